//! Rank independence of Algorithm 2 (Tresca): the same case on 1, 2 and 3 MPI ranks gives the
//! same Newton history (|A_n| and the four state counts of every step), the same final state of
//! every contact node (matched by node id) and the same displacement up to round-off.
//!
//! Cases: block3d with a small diagonal drag (stick in the middle, slip outside: both
//! tangential states and 2×2 slip rows) and the Hertz disk with friction and a tangential load
//! (all four states along the iteration).

mod common;

use common::*;

fn same_on_all_ranks(case_file: &str, sets: &[&str]) {
    let runs: Vec<(usize, Solved)> = [1usize, 2, 3]
        .into_iter()
        .map(|np| (np, solve(np, &case(case_file), sets)))
        .collect();
    let (_, base) = &runs[0];
    base.assert_converged(case_file);
    let base_hist = base.state_history();
    let base_active: Vec<f64> = history_active(base);
    let base_rows = base.contact_rows_by_id();
    let base_u = base.displacement();
    let dim = csv_dim(&base_rows);
    let mut tangential_states = std::collections::BTreeSet::new();
    for r in base_rows.values() {
        tangential_states.insert(r.tangential().to_string());
    }
    assert!(
        tangential_states.contains("stick") && tangential_states.contains("slip"),
        "{case_file}: the case should have both stick and slip nodes: {tangential_states:?}"
    );
    for (np, s) in &runs[1..] {
        s.assert_converged(&format!("{case_file} on {np} ranks"));
        assert_eq!(s.f(&["ranks"]) as usize, *np, "summary ranks");
        assert_eq!(
            s.state_history(),
            base_hist,
            "{case_file}: state history on {np} ranks differs from 1 rank"
        );
        assert_eq!(history_active(s), base_active, "{case_file}: |A_n| history");
        let rows = s.contact_rows_by_id();
        assert_eq!(
            rows.keys().collect::<Vec<_>>(),
            base_rows.keys().collect::<Vec<_>>(),
            "{case_file}: contact node ids on {np} ranks"
        );
        for (id, r) in &rows {
            let b = &base_rows[id];
            assert_eq!(
                r.active(),
                b.active(),
                "node {id} on {np} ranks: contact state"
            );
            assert_eq!(
                r.tangential(),
                b.tangential(),
                "node {id} on {np} ranks: stick/slip"
            );
            assert!(
                (r.bound() - b.bound()).abs() <= 1e-14 * b.bound().abs().max(1e-300),
                "node {id}: b_k differs"
            );
        }
        let (du, su) = max_diff(&s.displacement(), &base_u);
        eprintln!("{case_file}: {np} ranks vs 1: max |Δu| = {du:.3e} (max |u| {su:.3e})");
        assert!(su > 0.0);
        assert!(
            du <= 1e-10 * su,
            "{case_file}: u on {np} ranks differs from 1 rank by {du:e} (max |u| {su:e})"
        );
        // λ_τ of every node (frame quantities, the frames are per node and rank independent).
        let keys: Vec<String> = (1..dim).map(|i| format!("lambda_t{i}")).collect();
        let keys: Vec<&str> = keys.iter().map(String::as_str).collect();
        let (dl, _) = max_diff(&columns(&rows, &keys), &columns(&base_rows, &keys));
        let bmax = base_rows.values().map(Row::bound).fold(0.0, f64::max);
        assert!(
            dl <= 1e-9 * bmax,
            "{case_file}: λ_τ on {np} ranks differs by {dl:e} (b scale {bmax:e})"
        );
    }
}

fn history_active(s: &Solved) -> Vec<f64> {
    get(&s.summary, &["newton", "history"])
        .as_array()
        .expect("history")
        .iter()
        .map(|h| h["active"].as_f64().expect("active"))
        .collect()
}

/// On the plain path (Algorithm 2 on the whole system, whose every step has its state counts;
/// the case's newton.init = "auto" would solve it on the contact unknowns, whose rank
/// independence tests/tresca_condensed.rs checks).
#[test]
fn block3d_small_diagonal_drag_on_1_2_3_ranks() {
    same_on_all_ranks(
        "block3d_tresca.toml",
        &[
            "dirichlet.0.value=[0.0007, 0.0007, \"free\"]",
            "solver.path=\"plain\"",
        ],
    );
}

#[test]
fn hertz_tresca_on_1_2_3_ranks() {
    same_on_all_ranks("hertz_tresca.toml", &[]);
}
