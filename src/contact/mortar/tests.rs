//! Tests of the dual basis and of D, M, g̃ on matching, non-matching, offset, curved and
//! partially covered interfaces in 2D and 3D.

use super::assemble::MortarRow;
use super::dual::{eval, reference_coefficients, restricted_coefficients};
use super::test_util::*;

const XS7: [f64; 8] = [0.0, 0.1, 0.25, 0.3, 0.5, 0.62, 0.8, 1.0];
const XS3: [f64; 4] = [0.0, 0.37, 0.7, 1.0];

/// ∫_0^1 f over the reference segment/triangle by a rule exact for degree 2.
fn reference_integral(n: usize, f: &dyn Fn(&[f64; 3]) -> f64) -> f64 {
    if n == 2 {
        let g = 0.5 / 3f64.sqrt();
        return [0.5 - g, 0.5 + g]
            .iter()
            .map(|&s| 0.5 * f(&[1.0 - s, s, 0.0]))
            .sum();
    }
    (0..3)
        .map(|k| {
            let mut l = [1.0 / 6.0; 3];
            l[k] = 2.0 / 3.0;
            f(&l) / 6.0
        })
        .sum()
}

#[test]
fn dual_basis_is_biorthogonal() {
    for n in [2, 3] {
        let a = reference_coefficients(n);
        for i in 0..n {
            for j in 0..n {
                let ij = reference_integral(n, &|p| eval(n, &a, p)[i] * p[j]);
                let want = if i == j {
                    reference_integral(n, &|p| p[j])
                } else {
                    0.0
                };
                assert!((ij - want).abs() < 1e-15, "n={n} {i} {j}: {ij} {want}");
            }
        }
    }
    // Triangle: ψ_i = 4φ_i − 1; segment: ψ_1 = 2φ_1 − φ_2.
    let p = [0.2, 0.3, 0.5];
    let psi = eval(3, &reference_coefficients(3), &p);
    for i in 0..3 {
        assert!((psi[i] - (4.0 * p[i] - 1.0)).abs() < 1e-15);
    }
    let psi = eval(2, &reference_coefficients(2), &[0.3, 0.7, 0.0]);
    assert!((psi[0] - (0.6 - 0.7)).abs() < 1e-15 && (psi[1] - (1.4 - 0.3)).abs() < 1e-15);
    // On the whole facet the restricted basis is the reference one.
    for (n, g, m) in [
        (
            2,
            [[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0; 3]],
            [3.0, 3.0, 0.0],
        ),
        (
            3,
            [[2.0, 1.0, 1.0], [1.0, 2.0, 1.0], [1.0, 1.0, 2.0]],
            [4.0; 3],
        ),
    ] {
        let a = restricted_coefficients(n, &g, &m).unwrap();
        let r = reference_coefficients(n);
        for i in 0..n {
            for l in 0..n {
                assert!((a[i][l] - r[i][l]).abs() < 1e-14);
            }
        }
    }
}

/// Checks M_kj = D_kk δ_kj (master id = slave id + `shift`) and g̃ = 0.
fn check_matching(rows: &[MortarRow], shift: usize) {
    for row in rows {
        assert!(row.d > 0.0 && row.fully_covered);
        for &(j, v) in &row.m {
            let want = if j == row.id + shift { row.d } else { 0.0 };
            assert!(
                (v - want).abs() <= 1e-13 * row.d,
                "{} {j} {v} {want}",
                row.id
            );
        }
        assert!(row.gap.abs() <= 1e-13 * row.d, "{}", row.gap);
    }
}

#[test]
fn matching_meshes_2d() {
    let slave = line(&XS7, 0.0, 0, -1.0).surface(&id);
    // The master traversed the other way round: node order must not matter.
    let rev: Vec<f64> = XS7.iter().rev().copied().collect();
    let mut master_raw = line(&rev, 0.0, 100, 1.0);
    for f in &mut master_raw.facets {
        for e in f.iter_mut() {
            e.0 = 100 + XS7.iter().position(|&x| x == e.1[0]).unwrap();
        }
    }
    let master = master_raw.surface(&id);
    let mortar = couple(&slave, &master, 0.1);
    check_matching(&mortar.rows, 100);
    assert!((mortar.covered_measure() - 1.0).abs() < 1e-14);
    let h = |k: usize| XS7[k.min(7)] - XS7[k.saturating_sub(1)];
    for (k, row) in mortar.rows.iter().enumerate() {
        let lumped = 0.5 * (h(k) + h(k + 1));
        assert!((row.d - lumped).abs() < 1e-15, "{k}");
        assert_eq!(row.normal, [0.0, 1.0, 0.0]);
    }
}

#[test]
fn matching_meshes_3d() {
    let grid = square(4, 1.0, 1.0, 0.0, 0.3, 0, 7);
    let slave = grid.slave();
    let master = grid.master(1000);
    let mortar = couple(&slave, &master, 0.1);
    check_matching(&mortar.rows, 1000);
    assert!((mortar.covered_measure() - 1.0).abs() < 1e-14);
    let d: f64 = mortar.rows.iter().map(|r| r.d).sum();
    assert!((d - 1.0).abs() < 1e-14);
}

#[test]
fn non_matching_flat_2d() {
    let slave = line(&XS7, 0.0, 0, -1.0).surface(&id);
    let master = line(&XS3, 0.0, 100, 1.0).surface(&id);
    let mortar = couple(&slave, &master, 0.1);
    let n = check_reproduction(&mortar, &master, &|r| r.fully_covered, 1e-13);
    assert_eq!(n, 8);
    let d: f64 = mortar.rows.iter().map(|r| r.d).sum();
    assert!((d - 1.0).abs() < 1e-14);
    assert!(mortar.rows.iter().all(|r| r.gap.abs() < 1e-15));
    // Node 0.25 (facets [0.1, 0.3]) faces master segment [0, 0.37] only; node 0.3 two.
    assert_eq!(mortar.rows[2].master_facets, vec![0]);
    assert_eq!(mortar.rows[3].master_facets, vec![0, 1]);
}

#[test]
fn non_matching_flat_3d() {
    let slave = square(5, 1.0, 1.0, 0.0, 0.25, 0, 1).slave();
    let master = square(3, 1.0, 1.0, 0.0, 0.3, 1, 2).master(1000);
    let mortar = couple(&slave, &master, 0.1);
    assert_eq!(
        check_reproduction(&mortar, &master, &|r| r.fully_covered, 1e-13),
        36
    );
    let d: f64 = mortar.rows.iter().map(|r| r.d).sum();
    assert!((d - 1.0).abs() < 1e-14, "{d}");
    assert!(mortar.rows.iter().all(|r| r.gap.abs() < 1e-15));
}

#[test]
fn uniform_gap() {
    let delta = 0.0375;
    let slave = line(&XS7, 0.0, 0, -1.0).surface(&id);
    let master = line(&XS3, delta, 100, 1.0).surface(&id);
    let rows2 = couple(&slave, &master, 0.1).rows;
    let slave = square(5, 1.0, 1.0, 0.0, 0.25, 0, 1).slave();
    let master = square(3, 1.0, 1.0, delta, 0.3, 1, 2).master(1000);
    let rows3 = couple(&slave, &master, 0.1).rows;
    for row in rows2.iter().chain(&rows3) {
        assert!((row.gap - row.d * delta).abs() < 1e-14 * row.d, "{row:?}");
    }
    // Penetration: the master below the slave surface gives g̃ = −D δ.
    let slave = line(&XS7, 0.0, 0, -1.0).surface(&id);
    let master = line(&XS3, -delta, 100, 1.0).surface(&id);
    for row in couple(&slave, &master, 0.1).rows {
        assert!((row.gap + row.d * delta).abs() < 1e-14 * row.d);
    }
    // Beyond the search radius: nothing.
    let master = line(&XS3, 0.5, 100, 1.0).surface(&id);
    let far = couple(&slave, &master, 0.4);
    assert!(far.rows.iter().all(|r| r.d == 0.0 && r.m.is_empty()));
}

/// The lower arc of the circle of radius `r` centred at (0, r + h0), n segments over the
/// angles [−α, α]; body inside the circle.
fn arc(r: f64, h0: f64, alpha: f64, n: usize) -> Vec<[f64; 2]> {
    (0..=n)
        .map(|i| {
            let t = -alpha + 2.0 * alpha * i as f64 / n as f64;
            [r * t.sin(), r + h0 - r * t.cos()]
        })
        .collect()
}

#[test]
fn curved_slave_against_flat_master() {
    let (r, alpha) = (1.0, 0.5);
    for n in [16, 64] {
        let pts = arc(r, 0.0, alpha, n);
        let slave = polyline(&pts, 0, [0.0, 0.01]).surface(&id);
        let master = line(&[-1.0, -0.3, 0.2, 1.0], 0.0, 100, -1.0).surface(&id);
        let mortar = couple(&slave, &master, 0.5);
        let chords: f64 = (0..n).map(|f| slave.measure(f)).sum();
        let d: f64 = mortar.rows.iter().map(|r| r.d).sum();
        // Every slave segment is covered: Σ D = the polygon's length, 2αr to O(h²).
        assert!((d - chords).abs() < 1e-14, "{d} {chords}");
        let h = 2.0 * alpha / n as f64;
        assert!((d - 2.0 * alpha * r).abs() < 0.1 * h * h, "{d}");
        for (k, row) in mortar.rows.iter().enumerate() {
            assert!(row.gap >= -1e-15 && row.fully_covered);
            // g̃_k / D_kk: the distance y_k / cos t_k from node k along the circle's normal
            // to the master line, up to O(h²) inside, O(h) at the two end nodes (whose
            // normal is their one segment's).
            let t = -alpha + 2.0 * alpha * k as f64 / n as f64;
            let err = (row.gap / row.d - pts[k][1] / t.cos()).abs();
            let end = k == 0 || k == n;
            assert!(err <= if end { h } else { 0.01 * h * h }, "{k} {err}");
        }
        assert!(mortar.rows[n / 2].gap.abs() < 1e-15);
        // Pressed 0.01 into the master: the middle penetrates, g̃ < 0 there.
        let pts = arc(r, -0.01, alpha, n);
        let slave = polyline(&pts, 0, [0.0, 0.01]).surface(&id);
        let mortar = couple(&slave, &master, 0.5);
        assert!(mortar.rows[n / 2].gap < 0.0 && mortar.rows[0].gap > 0.0);
    }
}

#[test]
fn partial_coverage_2d() {
    let slave = line(&[0.0, 0.25, 0.5, 0.75, 1.0], 0.0, 0, -1.0).surface(&id);
    let master = line(&[0.0, 0.3, 0.6], 0.0, 100, 1.0).surface(&id);
    let mortar = couple(&slave, &master, 0.1);
    let rows = &mortar.rows;
    // Node 1.0: its facet [0.75, 1] is not covered: no entries.
    assert!(rows[4].d == 0.0 && rows[4].m.is_empty() && rows[4].master_facets.is_empty());
    assert!(rows[4].gap == 0.0 && !rows[4].fully_covered);
    // Node 0.75: D = ∫_0.5^0.6 φ_0.75 = 0.02 (covered part of [0.5, 0.75] only).
    assert!((rows[3].d - 0.02).abs() < 1e-15 && !rows[3].fully_covered);
    // Node 0.5: 0.125 from [0.25, 0.5] + ∫_0.5^0.6 φ_0.5 = 0.08.
    assert!((rows[2].d - 0.205).abs() < 1e-15 && !rows[2].fully_covered);
    assert!(rows[1].fully_covered && (rows[1].d - 0.25).abs() < 1e-15);
    // The dual basis built on the covered part: constants and linear fields reproduced at
    // every covered node, partial ones included, and g̃ = D δ there too.
    assert_eq!(
        check_reproduction(&mortar, &master, &|r| r.d > 0.0, 1e-13),
        4
    );
    let master = line(&[0.0, 0.3, 0.6], 0.02, 100, 1.0).surface(&id);
    let offset = couple(&slave, &master, 0.1);
    for (row, off) in rows.iter().zip(&offset.rows) {
        assert!(row.gap == 0.0 && (off.gap - 0.02 * off.d).abs() <= 1e-14 * off.d);
    }
    assert!((mortar.covered_measure() - 0.6).abs() < 1e-15);
}

#[test]
fn partial_coverage_3d() {
    let slave = square(5, 1.0, 1.0, 0.0, 0.2, 0, 3).slave();
    let master = square(3, 0.55, 1.0, 0.0, 0.3, 1, 4).master(1000);
    let mortar = couple(&slave, &master, 0.1);
    assert!((mortar.covered_measure() - 0.55).abs() < 1e-14);
    let covered = check_reproduction(&mortar, &master, &|r| r.d > 0.0, 1e-12);
    // Nodes with x > 0.8 (last column, x = 1) touch no covered facet.
    for row in &mortar.rows {
        if row.x[0] > 0.9 {
            assert!(row.d == 0.0 && row.m.is_empty() && row.master_facets.is_empty());
        } else if row.x[0] < 0.35 {
            assert!(row.fully_covered && row.d > 0.0);
        }
    }
    assert!((24..36).contains(&covered), "{covered}");
}

/// A spherical cap (radius 1) above the plane z = 0, touching it at the origin.
#[test]
fn curved_slave_3d() {
    let r = 1.0;
    for n in [8, 16] {
        let mut grid = square(n, 0.6, 0.6, 0.0, 0.0, 0, 0);
        for x in &mut grid.x {
            let (a, b) = (x[0] - 0.3, x[1] - 0.3);
            *x = [a, b, r - (r * r - a * a - b * b).sqrt()];
        }
        let mut raw = grid.raw(0, 1.0);
        raw.inside = vec![[0.0, 0.0, r]; raw.facets.len()];
        let slave = raw.surface(&id);
        let shift = |x: [f64; 3]| [x[0] - 0.5, x[1] - 0.5, x[2]];
        let master = square(5, 1.0, 1.0, 0.0, 0.1, 1, 3)
            .raw(1000, -1.0)
            .surface(&shift);
        let mortar = couple(&slave, &master, 0.5);
        let area: f64 = (0..slave.n_facets()).map(|f| slave.measure(f)).sum();
        let d: f64 = mortar.rows.iter().map(|r| r.d).sum();
        assert!((mortar.covered_measure() - area).abs() < 1e-13 && (d - area).abs() < 1e-13);
        let (mut inner, mut edge) = (0.0f64, 0.0f64);
        for row in &mortar.rows {
            assert!(row.gap >= -1e-15 && row.fully_covered);
            // The distance from the node along the sphere's normal to the plane z = 0.
            let want = row.x[2] * r / (r - row.x[2]);
            let err = (row.gap / row.d - want).abs();
            if row.x[0].abs().max(row.x[1].abs()) < 0.29 {
                inner = inner.max(err);
            } else {
                edge = edge.max(err);
            }
        }
        // First order in h = 0.6/n (area-weighted nodal normals of an unsymmetric
        // triangulation), small inside, larger on the cap's rim.
        let h = 0.6 / n as f64;
        assert!(inner < 1e-3 * h && edge < 0.05 * h, "{inner} {edge}");
    }
}
