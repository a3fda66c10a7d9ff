//! A block pressed onto a rigid plane by a uniform pressure, its top dragged sideways by a
//! prescribed displacement, with Tresca friction g_R = 0.01 (a tenth of the pressure, so the
//! tilting moment of the friction keeps every bottom node in contact). Cases
//! tests/cases/tresca/block{2,3}d_tresca.toml.
//!
//! * Large drag: every contact node slips in the direction of the drag. At a slip node
//!   |λ_τ| = b_k and λ_τ ∥ u_τ (3.18), so the friction force −λ_τ opposes the motion and
//!   Σ_k |λ_τ^k| = Σ_k b_k. In 2D every node moves in +x, hence Σ_k (−λ_τ^k) = −Σ_k b_k e_x
//!   exactly. In 3D the lateral Poisson spread gives every node its own slip direction û_k, so
//!   the exact statement is Σ_k (−λ_τ^k) = −Σ_k b_k û_k; its component along the drag must
//!   still be close to −Σ b_k.
//! * Small drag: the middle of the bottom sticks (u_τ = 0, |λ_τ| < b_k), the rim slips.
//!
//! Everything is checked twice: in the frame quantities of contact_nodes.csv (u_t, λ_t, bound)
//! and in global coordinates (solution.h5: contact force −λ^k and nodal displacement).

mod common;

use std::collections::BTreeMap;

use common::*;

const G_R: f64 = 0.01;

/// In-plane contact force (−λ_τ, global) and in-plane displacement (u_τ, global) per contact
/// node. The obstacle normal is the last axis, so the in-plane part is the first dim − 1
/// components.
fn tangential_global(s: &Solved, dim: usize) -> BTreeMap<u64, (Vec<f64>, Vec<f64>)> {
    let forces = contact_forces(s, dim);
    let u = s.displacement();
    forces
        .into_iter()
        .map(|(id, f)| (id, (f[..dim - 1].to_vec(), u[&id][..dim - 1].to_vec())))
        .collect()
}

/// Area (length in 2D) of the bottom face of the block.
fn bottom_area(dim: usize) -> f64 {
    if dim == 2 {
        2.0
    } else {
        4.0
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Checks of a slip node: |λ_τ| = b_k, λ_τ ∥ u_τ with the same sense (CSV frame quantities).
fn check_slip_row(id: u64, r: &Row, dim: usize) {
    let b = r.bound();
    let lt = r.lambda_t(dim);
    let ut = r.u_t(dim);
    let nu = norm(&ut);
    assert!(nu > 0.0, "node {id}: slips with u_τ = 0");
    assert!(
        (norm(&lt) - b).abs() <= 1e-10 * b,
        "node {id}: slip with |λ_τ| = {:e} ≠ b_k = {b:e}",
        norm(&lt)
    );
    for (l, u) in lt.iter().zip(&ut) {
        assert!(
            (l - b * u / nu).abs() <= 1e-10 * b,
            "node {id}: λ_τ = {lt:?} not parallel to u_τ = {ut:?} (b_k = {b:e})"
        );
    }
}

/// Large drag `drag` (in-plane direction of the TOML value `drag_toml`): every node in contact
/// and slipping; the sums of the friction forces.
fn all_slip(case_file: &str, dim: usize, drag_toml: &str, drag: &[f64]) {
    let set = format!("dirichlet.0.value={drag_toml}");
    let s = solve(1, &case(case_file), &[&set]);
    s.assert_converged(case_file);
    assert_eq!(s.f(&["newton", "algorithm"]), 2.0);
    let rows = s.contact_rows_by_id();
    let n = rows.len();
    for (id, r) in &rows {
        assert!(r.active(), "node {id} lost contact (design: full contact)");
        assert_eq!(
            r.tangential(),
            "slip",
            "node {id} sticks under the large drag"
        );
        check_slip_row(*id, r, dim);
    }
    assert_eq!(s.final_states(), [0, 0, 0, n]);
    assert_eq!(s.f(&["contact", "friction", "slip_count"]) as usize, n);

    // b_k = g_R w_k and Σ w_k = area of the bottom.
    let sum_b: f64 = rows.values().map(Row::bound).sum();
    let want = G_R * bottom_area(dim);
    assert!(
        (sum_b - want).abs() <= 1e-12 * want,
        "Σ b_k = {sum_b:e}, expected g_R · area = {want:e}"
    );

    let dn = norm(drag);
    let dhat: Vec<f64> = drag.iter().map(|x| x / dn).collect();
    let tg = tangential_global(&s, dim);
    let mut total = vec![0.0; dim - 1];
    let mut total_dir = vec![0.0; dim - 1];
    let mut sum_abs = 0.0;
    for (id, (f, u)) in &tg {
        let b = rows[id].bound();
        let nu = norm(u);
        assert!(
            dot(u, &dhat) > 0.0,
            "node {id} moves against the drag: u_τ = {u:?}"
        );
        for i in 0..dim - 1 {
            // The force on the body opposes the motion: −λ_τ = −b_k û_k.
            assert!(
                (f[i] + b * u[i] / nu).abs() <= 1e-10 * b,
                "node {id}: force −λ_τ = {f:?} vs −b_k û = {:?}",
                u.iter().map(|x| -b * x / nu).collect::<Vec<_>>()
            );
            total[i] += f[i];
            total_dir[i] -= b * u[i] / nu;
        }
        sum_abs += norm(f);
    }
    assert!(
        (sum_abs - sum_b).abs() <= 1e-10 * sum_b,
        "Σ |λ_τ| = {sum_abs:e} vs Σ b_k = {sum_b:e}"
    );
    for i in 0..dim - 1 {
        assert!(
            (total[i] - total_dir[i]).abs() <= 1e-10 * sum_b,
            "Σ(−λ_τ) = {total:?} vs −Σ b_k û_k = {total_dir:?}"
        );
    }
    // The summary's total force agrees with the node-wise sum.
    let tf = s.total_force();
    for i in 0..dim - 1 {
        assert!(
            (tf[i] - total[i]).abs() <= 1e-12 * sum_b,
            "{tf:?} vs {total:?}"
        );
    }
    let along = dot(&total, &dhat);
    eprintln!(
        "{case_file} drag {drag_toml}: {n} nodes slip, Σ(−λ_τ) = {total:?}, along the drag \
         {along:.6e}, Σ b_k = {sum_b:.6e}"
    );
    if dim == 2 {
        // All nodes move in +x: the total friction force is exactly −Σ b_k e_x.
        assert!(
            (along + sum_b).abs() <= 1e-10 * sum_b,
            "2D: Σ(−λ_τ) = {along:e}, expected −Σ b_k = {:e}",
            -sum_b
        );
    } else {
        assert!(
            along <= -0.95 * sum_b,
            "3D: the friction force along the drag {along:e} is not close to −Σ b_k = {:e}",
            -sum_b
        );
    }
}

/// Small drag: the middle sticks with |λ_τ| < b_k and u_τ = 0, the rim slips.
fn inner_stick(case_file: &str, dim: usize, drag_toml: &str) {
    let set = format!("dirichlet.0.value={drag_toml}");
    let s = solve(1, &case(case_file), &[&set]);
    s.assert_converged(case_file);
    let rows = s.contact_rows_by_id();
    let umax = s
        .displacement()
        .values()
        .map(|u| norm(u))
        .fold(0.0, f64::max);
    let mut stick = 0;
    let mut sum_lt = 0.0;
    let mut sum_b = 0.0;
    for (id, r) in &rows {
        assert!(r.active(), "node {id} lost contact");
        let on_rim = (r.f("x").abs() - 1.0).abs() < 1e-9
            || (dim == 3 && (r.f("y").abs() - 1.0).abs() < 1e-9);
        let b = r.bound();
        let lt = norm(&r.lambda_t(dim));
        sum_lt += lt;
        sum_b += b;
        match r.tangential() {
            "stick" => {
                stick += 1;
                assert!(!on_rim, "node {id} on the rim sticks");
                assert!(
                    norm(&r.u_t(dim)) <= 1e-12 * umax,
                    "node {id}: stick with u_τ = {:?}",
                    r.u_t(dim)
                );
                assert!(
                    lt < (1.0 - 1e-6) * b,
                    "node {id}: stick with |λ_τ| = {lt:e} not below b_k = {b:e}"
                );
            }
            "slip" => check_slip_row(*id, r, dim),
            other => panic!("node {id}: tangential state {other:?}"),
        }
    }
    eprintln!(
        "{case_file} drag {drag_toml}: {stick} of {} nodes stick, Σ|λ_τ| = {sum_lt:.4e} < Σ b_k = \
         {sum_b:.4e}",
        rows.len()
    );
    assert!(stick > 0, "no node sticks under the small drag");
    assert!(stick < rows.len(), "no node slips under the small drag");
    assert!(sum_lt < sum_b);
    let last = s.final_states();
    assert_eq!(last, [0, 0, stick, rows.len() - stick]);
    assert_eq!(s.f(&["contact", "friction", "stick_count"]) as usize, stick);
    if dim == 2 {
        // The stick nodes form one interval of x in the middle of the bottom.
        let mut by_x: Vec<(f64, bool)> = rows
            .values()
            .map(|r| (r.f("x"), r.tangential() == "stick"))
            .collect();
        by_x.sort_by(|a, b| a.0.total_cmp(&b.0));
        let first = by_x.iter().position(|p| p.1).expect("stick");
        let last = by_x.iter().rposition(|p| p.1).expect("stick");
        assert!(
            by_x[first..=last].iter().all(|p| p.1),
            "stick nodes are not contiguous: {by_x:?}"
        );
    }
}

#[test]
fn block2d_large_drag_all_slip() {
    all_slip("block2d_tresca.toml", 2, "[0.05, \"free\"]", &[1.0]);
}

#[test]
fn block2d_small_drag_inner_stick() {
    inner_stick("block2d_tresca.toml", 2, "[0.001, \"free\"]");
}

#[test]
fn block3d_large_drag_x_all_slip() {
    all_slip(
        "block3d_tresca.toml",
        3,
        "[0.05, \"free\", \"free\"]",
        &[1.0, 0.0],
    );
}

#[test]
fn block3d_large_drag_diagonal_all_slip() {
    all_slip(
        "block3d_tresca.toml",
        3,
        "[0.04, 0.03, \"free\"]",
        &[0.8, 0.6],
    );
}

#[test]
fn block3d_small_drag_inner_stick() {
    inner_stick("block3d_tresca.toml", 3, "[0.0005, \"free\", \"free\"]");
}

#[test]
fn block3d_small_diagonal_drag_inner_stick() {
    inner_stick("block3d_tresca.toml", 3, "[0.0007, 0.0007, \"free\"]");
}
