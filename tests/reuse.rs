//! `solver.reuse` (issue 9, item 1): Newton steps of the direct preset that solve their reduced
//! system by GMRES preconditioned with an earlier step's factorisation end in the same iterate
//! as the plain path (every step refactorised): the same active sets step by step, the same
//! final active nodes and u within 1e-10 of max|u|, on 1 and 2 ranks, frictionless (2D, 3D)
//! and Tresca. "always" is used to force the reuse (its choice does not depend on timings);
//! where its budget is too small it must refactorise and still give the same answer.
//! summary.json records every step's solve consistently.

mod common;
use common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn history(s: &Solved) -> Vec<Value> {
    get(&s.summary, &["newton", "history"])
        .as_array()
        .expect("history array")
        .clone()
}

/// Steps solved by [kind] and the fallbacks, after checking the history's consistency:
/// factorisations + reuses = steps = newton.steps, newton.factorisations counts the
/// factorisations, a reuse made 1..=budget Krylov iterations, a fallback reached its budget
/// (or broke down) and refactorised, and `reuse` is recorded exactly when `with_reuse`.
fn check_history(s: &Solved, with_reuse: bool) -> (usize, usize, usize) {
    let h = history(s);
    assert_eq!(h.len(), s.steps(), "{}", s.run.output());
    let (mut fact, mut reuse, mut fallback) = (0, 0, 0);
    for (i, e) in h.iter().enumerate() {
        let kind = e["solve"].as_str().expect("solve kind");
        let r = &e["reuse"];
        assert_eq!(!r.is_null(), with_reuse, "step {}: {e}", i + 1);
        match kind {
            "factorisation" => fact += 1,
            "reuse" => {
                reuse += 1;
                assert!(i > 0, "the first step has nothing to reuse: {e}");
                let its = e["iterations"].as_u64().unwrap();
                assert_eq!(r["krylov_iterations"].as_u64(), Some(its), "{e}");
                assert!(its >= 1 && its <= r["budget"].as_u64().unwrap(), "{e}");
                assert_eq!(r["fallback"], Value::Bool(false), "{e}");
                assert_eq!(r["factorisation_seconds"].as_f64(), Some(0.0), "{e}");
            }
            other => panic!("unexpected solve kind {other} on the direct preset: {e}"),
        }
        if with_reuse && r["fallback"] == Value::Bool(true) {
            fallback += 1;
            assert_eq!(kind, "factorisation", "{e}");
            let its = r["krylov_iterations"].as_u64().unwrap();
            assert!(its >= 1 && its <= r["budget"].as_u64().unwrap(), "{e}");
        }
    }
    assert_eq!(fact + reuse, s.steps());
    assert_eq!(s.f(&["newton", "factorisations"]) as usize, fact);
    assert_eq!(h[0]["solve"], "factorisation");
    // The final iterate is a factorised one: a stop decided on a reuse step is confirmed by
    // one more step on the same sets, factorised (plain_path/iteration.rs).
    assert_eq!(
        h[h.len() - 1]["solve"],
        "factorisation",
        "the last step is not factorised: {}",
        s.run.output()
    );
    (fact, reuse, fallback)
}

/// Runs `case` with reuse "never" and `mode`: the same steps, active sets and active nodes, u
/// within 1e-10; returns (reuses, fallbacks) of the `mode` run.
fn same_as_plain(np: usize, case: &Path, sets: &[&str], mode: &str) -> (usize, usize) {
    let with = |m: &str| {
        let mut v: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        v.push(format!("solver.reuse=\"{m}\""));
        v
    };
    let plain_sets = with("never");
    let plain = solve(
        np,
        case,
        &plain_sets.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    plain.assert_converged("plain path");
    let reuse_sets = with(mode);
    let reuse = solve(
        np,
        case,
        &reuse_sets.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    reuse.assert_converged(mode);
    let (pf, pr, _) = check_history(&plain, false);
    assert_eq!((pf, pr), (plain.steps(), 0));
    let (_, reuses, fallbacks) = check_history(&reuse, true);
    // A stop decided on a reuse step is checked by one more step on the same sets, factorised
    // (plain_path/iteration.rs): then the history is the plain one plus that step.
    let (ph, mut rh) = (plain.active_history(), reuse.active_history());
    if rh.len() == ph.len() + 1 {
        let h = reuse.summary["newton"]["history"].as_array().unwrap();
        let n = h.len();
        assert_eq!(
            h[n - 2]["solve"],
            "reuse",
            "final check after a reuse step only"
        );
        assert_eq!(
            h[n - 1]["solve"],
            "factorisation",
            "the final check factorises"
        );
        assert_eq!(
            rh[rh.len() - 1],
            rh[rh.len() - 2],
            "the final check keeps the sets"
        );
        rh.pop();
    }
    assert_eq!(ph, rh);
    assert_eq!(plain.active_node_ids(), reuse.active_node_ids());
    assert!(!plain.active_node_ids().is_empty());
    let d = plain.u_rel_diff(&reuse);
    assert!(
        d <= 1e-10,
        "{} on {np} rank(s), reuse = {mode}: |u - u_plain| / max|u| = {d:e}\n{}",
        case.display(),
        reuse.run.output()
    );
    (reuses, fallbacks)
}

fn hertz(level: usize) -> (PathBuf, String) {
    let mesh = repo(&format!("cases/hertz/meshes/hertz_refined_L{level}.msh"));
    (
        repo("cases/hertz/hertz.toml"),
        format!("mesh.file={}", toml_path(&mesh)),
    )
}

#[test]
fn frictionless_2d_reuse_and_fallback_agree_with_plain() {
    // Hertz refined L3 (4 134 dofs, 7 steps, a free rigid mode pinned): the second step
    // changes 32 nodes (rank ~66 > the 30 iterations "always" allows), so it must fall back;
    // later steps change few nodes and reuse.
    let (case, mesh) = hertz(3);
    for np in [1, 2] {
        let (reuses, fallbacks) = same_as_plain(np, &case, &[&mesh], "always");
        assert!(reuses >= 1, "{np} rank(s): no step reused");
        assert!(fallbacks >= 1, "{np} rank(s): no step fell back");
    }
    let (reuses, _) = same_as_plain(2, &repo("cases/blocks/indent2d.toml"), &[], "always");
    assert!(reuses >= 1);
}

#[test]
fn tresca_reuse_agrees_with_plain() {
    for np in [1, 2] {
        let (reuses, _) = same_as_plain(
            np,
            &repo("tests/cases/tresca/hertz_tresca.toml"),
            &[],
            "always",
        );
        assert!(reuses >= 1, "{np} rank(s): no step reused");
    }
    let (reuses, _) = same_as_plain(
        1,
        &repo("tests/cases/tresca/block3d_tresca.toml"),
        &[],
        "always",
    );
    assert!(reuses >= 1);
}

#[test]
fn frictionless_3d_reuse_agrees_with_plain() {
    for np in [1, 2] {
        let (reuses, _) = same_as_plain(
            np,
            &repo("tests/cases/sphere3d.toml"),
            &["newton.init=\"auto\""],
            "always",
        );
        assert!(reuses >= 1, "{np} rank(s): no step reused");
    }
}

#[test]
fn coulomb_and_iterative_preset_stay_plain() {
    // Coulomb's unsymmetric (F7) rows: every step refactorises even with "always".
    let s = solve(
        1,
        &repo("tests/cases/tresca/block2d_tresca.toml"),
        &[
            "contact.friction={law=\"coulomb\", mu=0.3, algorithm=\"newton\"}",
            "solver.reuse=\"always\"",
        ],
    );
    s.assert_converged("Coulomb");
    let (fact, reuse, fallback) = check_history(&s, true);
    assert_eq!((fact, reuse, fallback), (s.steps(), 0, 0));
    // The iterative preset has no factorisation to reuse: no factorisation reuse record (its
    // own reuse path, tests/reuse_iterative.rs, records under "amg"); with "never" it is the
    // plain path, every step a Krylov solve on a preconditioner set up for it.
    for mode in ["always", "never"] {
        let s = solve(
            1,
            &repo("cases/blocks/indent2d.toml"),
            &[
                "solver.preset=\"iterative\"",
                &format!("solver.reuse=\"{mode}\""),
            ],
        );
        s.assert_converged("iterative");
        for e in history(&s) {
            assert!(e["reuse"].is_null(), "{e}");
            assert_eq!(e["amg"].is_null(), mode == "never", "{e}");
            if mode == "never" {
                assert_eq!(e["solve"], "krylov", "{e}");
            }
        }
    }
}

#[test]
fn bad_reuse_value_is_an_input_error() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let r = run_solver(
        1,
        &repo("cases/blocks/indent2d.toml"),
        &["solver.reuse=\"sometimes\""],
        &out,
    );
    r.expect_code(2, "solver.reuse = sometimes");
    assert!(
        r.stderr.contains("solver.reuse") && r.stderr.contains("\"never\""),
        "{}",
        r.output()
    );
    assert!(!out.exists(), "nothing written");
}

/// Runs `case` with "auto" on the plain path after the condensed path fell back (a zone too
/// wide for the test-only limit of 8 Schur dofs), started with no node active, on 1 rank, and
/// checks that its choice to reuse comes from MUMPS' counts of the factored matrix, never from
/// timings: two runs take the same path step by step (the kinds of solve, the ranks, budgets,
/// Krylov iterations and costs recorded), every choice follows the recorded costs by the
/// documented rule (reuse when rank < budget and (rank + 2) iterations cost at most 3/4 of a
/// factorisation step, the budget the iterations that one step costs, minus one, at most 200),
/// and the answer is the plain path's ("never"). Returns (steps where the rule chose to try
/// GMRES on the kept factorisation, steps solved that way).
#[cfg(feature = "fault-injection")]
fn auto_decides_from_counts(case: &Path, sets: &[&str]) -> (usize, usize) {
    let run = |reuse: &str| {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out");
        let reuse = format!("solver.reuse=\"{reuse}\"");
        let mut all: Vec<&str> = sets.to_vec();
        all.extend(["newton.init=\"all_inactive\"", reuse.as_str()]);
        let mut cmd = solver_command(1, case, &all, &out);
        cmd.env("SIGNORINI_TEST_LIMIT_MAX_SCHUR_DOFS", "8");
        let s = solved(run_with_timeout(cmd, LIMIT), tmp, out);
        s.assert_converged(&reuse);
        s
    };
    let (a, b, plain) = (run("auto"), run("auto"), run("never"));
    let cs = &a.summary["newton"]["condensed"];
    assert_eq!(
        cs["too_wide"], true,
        "the plain path after the fallback: {cs}"
    );
    let record = |s: &Solved| -> Vec<Value> {
        history(s)
            .iter()
            .map(|e| {
                let r = &e["reuse"];
                serde_json::json!([
                    e["solve"],
                    e["iterations"],
                    r["rank"],
                    r["budget"],
                    r["krylov_iterations"],
                    r["fallback"],
                    r["cost_factorisation"],
                    r["cost_iteration"]
                ])
            })
            .collect()
    };
    assert_eq!(record(&a), record(&b), "two runs, two paths");
    let (mut tried, mut reused) = (0, 0);
    let h = history(&a);
    for (i, e) in h.iter().enumerate() {
        let r = &e["reuse"];
        if i > 0 && h[i - 1]["solve"] == "reuse" && h[i - 1]["changed"] == 0 {
            // a stop reached by GMRES on a kept factorisation is confirmed by a factorisation
            assert_eq!(e["solve"], "factorisation", "step {}: {e}", i + 1);
            assert_eq!(i + 1, h.len(), "the confirmation is the last step: {e}");
            continue;
        }
        let num = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("reuse.{k}: {e}"));
        let (step, it) = (num("cost_factorisation"), num("cost_iteration"));
        if i == 0 {
            assert_eq!(
                (step, it),
                (0.0, 0.0),
                "nothing factored before step 1: {e}"
            );
            continue;
        }
        assert!(step > 0.0 && it > 0.0, "step {}: costs {e}", i + 1);
        let budget = (((step / it).floor() as usize).saturating_sub(1)).min(200);
        let rank = num("rank") as usize;
        let pays = rank < budget && (rank + 2) as f64 * it <= 0.75 * step;
        let took = num("budget") as usize;
        assert_eq!(took > 0, pays, "step {}: {e}", i + 1);
        if pays {
            assert_eq!(took, budget, "step {}: {e}", i + 1);
            tried += 1;
        }
        reused += usize::from(e["solve"] == "reuse");
    }
    assert_eq!(plain.active_node_ids(), a.active_node_ids());
    let d = plain.u_rel_diff(&a);
    assert!(d <= 1e-10, "|u - u_plain| / max|u| = {d:e}");
    (tried, reused)
}

/// 2D, Hertz refined L4 (12 618 dofs): a factorisation costs about six Krylov iterations here
/// (MUMPS' counts; measured: the rule refactorises every step); 3D, the quarter ball at h = 0.015 (about
/// 6 900 unknowns): a factorisation costs about 22 iterations and the late steps, which change
/// few nodes, are solved by GMRES on the kept factorisation.
#[cfg(feature = "fault-injection")]
#[test]
fn auto_after_a_condensed_fallback_decides_from_counts() {
    let (case, mesh) = hertz(4);
    auto_decides_from_counts(&case, &[&mesh]);
    let tmp = tempfile::tempdir().unwrap();
    let msh = tmp.path().join("hertz3d_h0.015.msh");
    gmsh_file(
        &repo("cases/hertz3d/hertz3d.geo"),
        3,
        &["-setnumber", "h", "0.015"],
        &msh,
    );
    let m = format!("mesh.file={}", toml_path(&msh));
    let (tried, reused) = auto_decides_from_counts(
        &repo("cases/hertz3d/hertz3d.toml"),
        &[&m, "solver.preset=\"direct\""],
    );
    assert!(
        tried >= 1 && reused >= 1,
        "3D: tried {tried}, reused {reused}"
    );
}

/// `solver.path` chooses the algorithm, `solver.reuse` only how the plain path carries a
/// factorisation: on a frictionless direct case `path = "plain"` with reuse "never" is the run
/// that reuse "never" alone gives (it implies the plain path), `path = "plain"` alone (reuse
/// "auto") ends in its active sets and u, and `path = "schur"` is the default's run;
/// summary.json's `newton.path` names the path taken.
#[test]
fn solver_path_plain_is_reuse_never_and_schur_the_default() {
    let (case, mesh) = hertz(3);
    let run = |sets: &[&str]| {
        let mut all = vec![mesh.as_str(), "solver.preset=\"direct\""];
        all.extend_from_slice(sets);
        let s = solve(1, &case, &all);
        s.assert_converged(&all.join(" "));
        s
    };
    let path = |s: &Solved| s.summary["newton"]["path"].as_str().map(str::to_string);
    let never = run(&["solver.reuse=\"never\""]);
    let plain_never = run(&["solver.path=\"plain\"", "solver.reuse=\"never\""]);
    let plain = run(&["solver.path=\"plain\""]);
    let default = run(&[]);
    let schur = run(&["solver.path=\"schur\""]);
    for s in [&never, &plain_never, &plain] {
        assert_eq!(path(s).as_deref(), Some("plain"), "{}", s.run.output());
        assert!(
            s.summary["newton"]["condensed"].is_null(),
            "no Schur path tried"
        );
    }
    for s in [&default, &schur] {
        assert_eq!(path(s).as_deref(), Some("schur"), "{}", s.run.output());
        assert!(!s.summary["newton"]["condensed"].is_null());
    }
    for (a, b, what) in [
        (&never, &plain_never, "path = plain, reuse = never"),
        (&default, &schur, "path = schur"),
    ] {
        assert_eq!(a.steps(), b.steps(), "{what}");
        assert_eq!(a.active_history(), b.active_history(), "{what}");
        assert_eq!(a.u_rel_diff(b), 0.0, "{what}: u differs");
    }
    assert_eq!(never.active_node_ids(), plain.active_node_ids());
    let d = never.u_rel_diff(&plain);
    assert!(
        d <= 1e-10,
        "path = plain (reuse auto): |u - u_never| / max|u| = {d:e}"
    );
}
