//! Tests of frame invariance, input checks, degenerate and edge-on facets, the normal
//! filter and a large surface pair.

use super::assemble::{assemble, assemble_with_normals, Mortar, MortarOptions};
use super::surface::{MortarError, Orientation, Surface};
use super::test_util::*;
use rand::rngs::StdRng;
use rand::SeedableRng;

/// The non-matching pair of the flat tests (master offset by `delta`) mapped by `tf`.
fn pair(dim: usize, delta: f64, tf: Map) -> (Surface, Surface) {
    if dim == 2 {
        let xs7 = [0.0, 0.1, 0.25, 0.3, 0.5, 0.62, 0.8, 1.0];
        let slave = line(&xs7, 0.0, 0, -1.0).surface(tf);
        let master = line(&[-0.1, 0.37, 0.7, 0.9], delta, 100, 1.0).surface(tf);
        return (slave, master);
    }
    let slave = square(5, 1.0, 1.0, 0.0, 0.25, 0, 1)
        .raw(0, -1.0)
        .surface(tf);
    let master = square(3, 0.9, 1.2, delta, 0.3, 1, 2)
        .raw(1000, 1.0)
        .surface(tf);
    (slave, master)
}

fn same(a: &Mortar, b: &Mortar, r: &[[f64; 3]; 3], tol: f64) {
    assert_eq!(a.rows.len(), b.rows.len());
    for (x, y) in a.rows.iter().zip(&b.rows) {
        assert_eq!((x.id, x.m.len()), (y.id, y.m.len()));
        assert_eq!(x.master_facets, y.master_facets);
        assert!(
            (x.d - y.d).abs() < tol && (x.gap - y.gap).abs() < tol,
            "{x:?} {y:?}"
        );
        for (p, q) in x.m.iter().zip(&y.m) {
            assert!(p.0 == q.0 && (p.1 - q.1).abs() < tol, "{p:?} {q:?}");
        }
        let rn = apply(r, [0.0; 3], x.normal);
        assert!((0..3).all(|c| (rn[c] - y.normal[c]).abs() < tol));
    }
}

#[test]
fn frame_invariance() {
    let mut rng = StdRng::seed_from_u64(11);
    for dim in [2, 3] {
        let (slave, master) = pair(dim, 0.03, &id);
        let base = couple(&slave, &master, 0.1);
        assert!(base.rows.iter().any(|r| !r.fully_covered && r.d > 0.0));
        for _ in 0..10 {
            let (r, t) = rigid(dim, &mut rng);
            let (slave, master) = pair(dim, 0.03, &|x| apply(&r, t, x));
            same(&base, &couple(&slave, &master, 0.1), &r, 1e-12);
        }
    }
}

#[test]
fn orientation_by_node_order() {
    let x = |a: f64, b: f64| [a, b, 0.0];
    let seg = [[(1, x(0.0, 0.0)), (2, x(1.0, 0.0))]];
    let s = Surface::new(2, &seg, Orientation::NodeOrder).unwrap();
    assert_eq!(s.normal(0), [0.0, -1.0, 0.0]);
    let tri = [[(1, x(0.0, 0.0)), (2, x(1.0, 0.0)), (3, x(0.0, 1.0))]];
    let s = Surface::new(3, &tri, Orientation::NodeOrder).unwrap();
    assert_eq!((s.normal(0), s.measure(0)), ([0.0, 0.0, 1.0], 0.5));
    let s = Surface::new(3, &tri, Orientation::InsidePoints(&[[0.1, 0.1, 1.0]])).unwrap();
    assert_eq!(s.normal(0), [0.0, 0.0, -1.0]);
    assert_eq!(s.nodal_normals(), vec![[0.0, 0.0, -1.0]; 3]);
}

#[test]
fn bad_input() {
    let x = |a: f64, b: f64, c: f64| [a, b, c];
    let new = |dim, f: &[Vec<(usize, [f64; 3])>]| Surface::new(dim, f, Orientation::NodeOrder);
    let seg = vec![(1, x(0.0, 0.0, 0.0)), (2, x(1.0, 0.0, 0.0))];
    assert_eq!(
        new(4, std::slice::from_ref(&seg)).unwrap_err(),
        MortarError::Dimension(4)
    );
    let bad = [
        (vec![seg[0], seg[0]], MortarError::FacetNodes { facet: 0 }),
        (vec![seg[0]], MortarError::FacetNodes { facet: 0 }),
        (
            vec![seg[0], (2, x(1.0, 0.0, 0.1))],
            MortarError::Coordinates { facet: 0 },
        ),
        (
            vec![seg[0], (2, x(f64::NAN, 0.0, 0.0))],
            MortarError::Coordinates { facet: 0 },
        ),
        (
            vec![seg[0], (2, x(0.0, 0.0, 0.0))],
            MortarError::Degenerate { facet: 0 },
        ),
    ];
    for (f, e) in bad {
        assert_eq!(new(2, &[f]).unwrap_err(), e);
        assert!(!e.to_string().is_empty());
    }
    let moved = vec![(2, x(1.0, 1e-9, 0.0)), (3, x(2.0, 0.0, 0.0))];
    let e = new(2, &[seg.clone(), moved]).unwrap_err();
    assert_eq!(e, MortarError::ConflictingCoordinates { id: 2 });
    let on = Surface::new(
        2,
        std::slice::from_ref(&seg),
        Orientation::InsidePoints(&[[3.0, 0.0, 0.0]]),
    );
    assert_eq!(on.unwrap_err(), MortarError::InsideOnFacet { facet: 0 });
    let few = Surface::new(
        2,
        std::slice::from_ref(&seg),
        Orientation::InsidePoints(&[]),
    );
    assert!(matches!(few, Err(MortarError::Length { .. })));
    let s2 = new(2, &[seg]).unwrap();
    let tri = vec![
        (1, x(0.0, 0.0, 0.0)),
        (2, x(1.0, 0.0, 0.0)),
        (3, x(0.0, 1.0, 0.0)),
    ];
    let s3 = new(3, &[tri]).unwrap();
    let opts = MortarOptions::new(0.1);
    assert_eq!(
        assemble(&s2, &s3, &opts),
        Err(MortarError::DimensionMismatch)
    );
    let neg = MortarOptions::new(-1.0);
    assert_eq!(assemble(&s2, &s2, &neg), Err(MortarError::SearchRadius));
    let e = assemble_with_normals(&s2, &s2, &[[0.0; 3]], &opts).unwrap_err();
    assert!(matches!(e, MortarError::Length { .. }));
    let e = assemble_with_normals(&s2, &s2, &[[0.0; 3], [0.0, 1.0, 0.0]], &opts);
    assert_eq!(e.unwrap_err(), MortarError::Normal { node: 0 });
}

#[test]
fn edge_on_touching_and_tangent_facets() {
    let x = |a: f64, b: f64, c: f64| [a, b, c];
    let slave = square(2, 1.0, 1.0, 0.0, 0.0, 0, 0).slave();
    let masters = [
        // Edge-on (vertical), touching at a vertex, touching along an edge, nearly tangent.
        vec![
            (10, x(0.2, 0.2, 0.0)),
            (11, x(0.8, 0.2, 0.0)),
            (12, x(0.5, 0.2, 0.5)),
        ],
        vec![
            (10, x(1.0, 1.0, 0.0)),
            (11, x(2.0, 1.0, 0.0)),
            (12, x(1.0, 2.0, 0.0)),
        ],
        vec![
            (10, x(1.0, 0.0, 0.0)),
            (11, x(2.0, 0.0, 0.0)),
            (12, x(1.0, 1.0, 0.0)),
        ],
        vec![
            (10, x(0.2, 0.2, 0.0)),
            (11, x(0.8, 0.2, 0.0)),
            (12, x(0.5, 0.2 + 1e-9, 0.5)),
        ],
    ];
    for (i, m) in masters.into_iter().enumerate() {
        let master = Surface::new(3, &[m], Orientation::NodeOrder).unwrap();
        let mortar = couple(&slave, &master, 1.0);
        let all_finite = mortar
            .rows
            .iter()
            .all(|r| r.d.is_finite() && r.gap.is_finite() && r.m.iter().all(|e| e.1.is_finite()));
        assert!(all_finite, "{i}");
        if i < 3 {
            assert_eq!(mortar.covered_measure(), 0.0, "{i}");
        } else {
            assert!(mortar.covered_measure() < 1e-9, "{i}");
        }
    }
    // 2D: a master segment perpendicular to the slave.
    let slave = line(&[0.0, 0.5, 1.0], 0.0, 0, -1.0).surface(&id);
    let seg = [[(10, x(0.3, 0.0, 0.0)), (11, x(0.3, 1.0, 0.0))]];
    let master = Surface::new(2, &seg, Orientation::NodeOrder).unwrap();
    assert_eq!(couple(&slave, &master, 1.0).covered_measure(), 0.0);
}

#[test]
fn normal_filter_skips_the_back_face() {
    let slave = square(4, 1.0, 1.0, 0.0, 0.2, 0, 5).slave();
    // The master body between z = 0.01 and z = 0.5: its lower face faces the slave, its
    // upper face looks away.
    let mut raw = square(3, 1.0, 1.0, 0.01, 0.2, 1, 6).raw(1000, 1.0);
    let top = square(3, 1.0, 1.0, 0.5, 0.2, 0, 7).raw(2000, -1.0);
    raw.facets.extend(top.facets);
    raw.inside.extend(top.inside);
    let master = raw.surface(&id);
    let both = couple(&slave, &master, 1.0);
    assert!((both.covered_measure() - 2.0).abs() < 1e-13);
    let mut opts = MortarOptions::new(1.0);
    opts.max_normal_dot = Some(0.0);
    let facing = assemble(&slave, &master, &opts).unwrap();
    assert!((facing.covered_measure() - 1.0).abs() < 1e-13);
    for row in &facing.rows {
        assert!(row.master_facets.iter().all(|&f| f < 18));
        assert!((row.gap - 0.01 * row.d).abs() < 1e-14);
    }
}

#[test]
fn large_surfaces_3d() {
    let slave = square(60, 1.0, 1.0, 0.0, 0.1, 0, 8).slave();
    let master = square(43, 1.0, 1.0, 0.0, 0.1, 1, 9).master(100_000);
    let mortar = couple(&slave, &master, 0.01);
    assert!((mortar.covered_measure() - 1.0).abs() < 1e-12);
    let n = check_reproduction(&mortar, &master, &|r| r.fully_covered, 1e-12);
    assert_eq!(n, 61 * 61);
    let most = mortar.rows.iter().map(|r| r.master_facets.len()).max();
    assert!(most.unwrap() <= 30);
}

#[test]
fn a_node_covered_by_a_sliver_is_no_contact_node() {
    // the slave 0 — 0.5 — 1 under a master from 1 − δ on: δ = 1e-12 covers the nodes at 0.5
    // and 1 by round-off of their coordinates (D_kk ≈ δ² and δ against ∫ φ_k = 0.5 and
    // 0.25): no rows; δ = 0.01 is geometry: rows whose master part reproduces the node's x
    let slave = line(&[0.0, 0.5, 1.0], 0.0, 0, -1.0).surface(&id);
    for (delta, kept) in [(1e-12, false), (1e-2, true)] {
        let master = line(&[1.0 - delta, 2.0], 0.0, 100, 1.0).surface(&id);
        let mortar = couple(&slave, &master, 0.1);
        assert_eq!(mortar.rows[0].d, 0.0, "δ = {delta:e}");
        for row in &mortar.rows[1..] {
            assert_eq!(row.d > 0.0, kept, "δ = {delta:e}: {row:?}");
            assert_eq!(row.m.is_empty(), !kept, "δ = {delta:e}: {row:?}");
            assert_eq!(
                row.master_facets.is_empty(),
                !kept,
                "δ = {delta:e}: {row:?}"
            );
        }
        // the sliver's measure itself is still counted as covered
        assert!(mortar.covered_measure() > 0.0, "δ = {delta:e}");
    }
}
