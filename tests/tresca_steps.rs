//! What each Tresca step changes in the matrix of (3.42) (summary.json
//! `newton.history[].change`, the measure behind docs/numbers.md, "Tresca and the reuse of
//! factorisations"): on the Hertz disk held at its top arc (no rigid mode free, so no pins),
//! every node whose state flips in the update after step ℓ adds or removes one or two
//! prescribed directions (its normal, its stick row) in the matrix of step ℓ + 1, and no other
//! node does; the record is the same on 1 and 3 ranks; every step of the plain path is one
//! factorisation, timed apart from its solve.

mod common;

use common::*;
use serde_json::Value;

/// The Hertz disk (refined level 4) held at its top arc, pushed down by 0.01 and sideways by
/// 0.001, Tresca with g_R = 0.005 on the whole contact boundary (the bench's held case), on the
/// plain path (by default it is solved on the contact unknowns, tests/tresca_condensed.rs).
fn held_tresca(dir: &std::path::Path) -> std::path::PathBuf {
    let mesh = repo("cases/hertz/meshes/hertz_refined_L4.msh");
    write_case(
        &dir.join("held-tresca.toml"),
        &format!(
            "[mesh]\nfile = {}\n[material]\nyoung = 2.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\
             [[dirichlet]]\ngroup = \"load\"\nvalue = [0.001, -0.01]\n[contact]\n\
             group = \"contact\"\nobstacle = {{ type = \"plane\", point = [0.0, -1.0], \
             normal = [0.0, 1.0] }}\nfriction = {{ law = \"tresca\", threshold = 0.005 }}\n\
             [solver]\npreset = \"direct\"\npath = \"plain\"\n\
             [output]\nfields = [\"displacement\"]\n",
            toml_path(&mesh)
        ),
    )
}

fn history(s: &Solved) -> Vec<Value> {
    get(&s.summary, &["newton", "history"])
        .as_array()
        .expect("history array")
        .clone()
}

fn count(h: &Value, key: &str) -> usize {
    h[key].as_u64().unwrap_or_else(|| panic!("{key} in {h}")) as usize
}

#[test]
fn each_flipped_node_changes_one_or_two_directions_of_the_next_matrix() {
    let tmp = tempfile::tempdir().expect("tmp");
    let case = held_tresca(tmp.path());
    let runs: Vec<(usize, Solved)> = [1usize, 3]
        .into_iter()
        .map(|np| (np, solve(np, &case, &[])))
        .collect();
    let mut directions_by_ranks = Vec::new();
    for (np, s) in &runs {
        s.assert_converged(&format!("held Tresca disk on {np} ranks"));
        let hist = history(s);
        assert!(hist.len() >= 3, "too few steps to test: {}", hist.len());
        assert!(
            hist[0].get("change").is_none(),
            "the first step has no previous matrix: {}",
            hist[0]
        );
        let states = s.state_history();
        let mut directions = Vec::new();
        for (i, h) in hist.iter().enumerate() {
            assert_eq!(count(h, "pinned"), 0, "no pins on the held disk");
            assert_eq!(h["solve"], "factorisation", "step {}: {h}", i + 1);
            let f = h["factorisation_seconds"]
                .as_f64()
                .unwrap_or_else(|| panic!("step {}: factorisation_seconds: {h}", i + 1));
            let total = h["solve_seconds"].as_f64().expect("solve_seconds");
            assert!(
                f > 0.0 && f <= total,
                "step {}: factorisation {f} s of {total} s",
                i + 1
            );
            if i == 0 {
                continue;
            }
            let c = &h["change"];
            let flipped = count(&hist[i - 1], "changed");
            let d = count(c, "directions");
            assert!(
                flipped <= d && d <= 2 * flipped,
                "step {}: {flipped} nodes flipped after step {i}, but {d} directions changed",
                i + 1
            );
            // a changed slip block belongs to a node slipping in this step or the one before
            let slipping = |k: usize| states[k][1] + states[k][3];
            let blocks = count(c, "slip_blocks") + count(c, "slip_blocks_roundoff");
            assert!(
                blocks <= slipping(i) + slipping(i - 1),
                "step {}: {blocks} slip blocks changed, {} + {} slipping nodes",
                i + 1,
                slipping(i),
                slipping(i - 1)
            );
            directions.push(d);
        }
        assert!(
            directions.iter().any(|&d| d > 0),
            "no direction ever changed: nothing tested"
        );
        directions_by_ranks.push(directions);
    }
    assert_eq!(
        directions_by_ranks[0], directions_by_ranks[1],
        "directions changed per step: 1 rank vs 3 ranks"
    );
}
