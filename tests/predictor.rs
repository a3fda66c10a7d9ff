//! The half-space predictor of the iterative preset's reuse path (issue 9, item 3;
//! src/signorini/halfspace/): after a first solve without active nodes, Algorithm 1 on a
//! dense half-space model (Boussinesq / Flamant, mirrored in the symmetry planes) gives the set
//! the second Newton step starts from. The final iterate stays Algorithm 1's: the same final
//! active nodes as the plain path and u within 1e-8 of max |u|; summary.json records the
//! prediction in the first step; no other path predicts.

mod common;
use common::*;
use serde_json::Value;
use std::path::Path;

fn predictor(s: &Solved) -> Value {
    get(&s.summary, &["newton", "history"])[0]["predictor"].clone()
}

fn iterative(sets: &[&str], reuse: &str) -> Vec<String> {
    let mut v: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    v.push("solver.preset=\"iterative\"".into());
    v.push(format!("solver.reuse=\"{reuse}\""));
    v
}

fn run(np: usize, case: &Path, sets: &[String]) -> Solved {
    let s = solve(
        np,
        case,
        &sets.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    s.assert_converged(&format!("{} {sets:?}", case.display()));
    s
}

/// Runs the plain path and the default reuse path; checks the prediction's record and the
/// final iterate; returns (plain, predicted) runs.
fn predicted_against_plain(
    np: usize,
    case: &Path,
    sets: &[&str],
    mirrors: u64,
) -> (Solved, Solved) {
    let plain = run(np, case, &iterative(sets, "never"));
    let auto = run(np, case, &iterative(sets, "auto"));
    assert!(
        predictor(&plain).is_null(),
        "the plain path does not predict"
    );
    let p = predictor(&auto);
    assert_eq!(p["outcome"], "predicted", "{p}\n{}", auto.run.output());
    assert_eq!(p["mirror_planes"].as_u64(), Some(mirrors), "{p}");
    let predicted = p["predicted_active"].as_u64().unwrap() as f64;
    let fin = auto.active_node_ids().len() as f64;
    assert!(fin > 0.0);
    assert!(
        (predicted - fin).abs() <= 0.15 * fin + 1.0,
        "predicted {predicted} active nodes, {fin} at the end: {p}"
    );
    assert!(p["model_nodes"].as_u64().unwrap() as f64 >= predicted);
    // the second step solves with the predicted set
    let h = get(&auto.summary, &["newton", "history"]);
    assert_eq!(h[1]["active"].as_u64(), Some(predicted as u64), "{}", h[1]);
    // the last step is an exact solve whose update changes no node (Algorithm 1's stop)
    let steps = h.as_array().unwrap();
    let last = &steps[steps.len() - 1];
    assert_eq!(last["changed"].as_u64(), Some(0), "{last}");
    assert_eq!(last["amg"]["inexact"], Value::Bool(false), "{last}");
    assert!(last["iterations"].as_u64().unwrap() >= 1, "{last}");
    assert_eq!(
        plain.active_node_ids(),
        auto.active_node_ids(),
        "{}: final active sets differ",
        case.display()
    );
    let d = plain.u_rel_diff(&auto);
    assert!(
        d <= 1e-8,
        "{}: |u - u_plain| / max|u| = {d:e}",
        case.display()
    );
    (plain, auto)
}

#[test]
fn hertz_cylinder_2d_starts_near_the_final_set_and_saves_steps() {
    let (plain, auto) = predicted_against_plain(2, &repo("cases/hertz/hertz.toml"), &[], 0);
    assert!(
        auto.steps() < plain.steps(),
        "predicted: {} steps, plain: {}",
        auto.steps(),
        plain.steps()
    );
}

/// The full floating ball of cases/ball3d (no Dirichlet data, no symmetry plane): its first
/// solve is skipped (the model, whose free modes carry the load into contact, predicts from
/// the gaps; GAMG is set up once, on the predicted set's matrix); after the prediction its
/// tangential rigid modes are free, the reuse path removes them as the null space of the
/// step's matrix instead of pinning a dof each, and the final iterate is still the pinned
/// plain path's (same active nodes, u within 1e-8), on 1 and 2 ranks.
#[test]
fn full_ball_3d_takes_its_free_modes_as_null_space_and_ends_on_the_pinned_answer() {
    for np in [1, 2] {
        let (plain, auto) = predicted_against_plain(np, &repo("cases/ball3d/ball3d.toml"), &[], 0);
        let h = get(&auto.summary, &["newton", "history"]);
        let steps = h.as_array().unwrap();
        assert_eq!(
            steps[0]["amg"]["null_space"],
            Value::Bool(false),
            "{}",
            steps[0]
        );
        // no first solve: the predicted set's step sets GAMG up, the only setup
        assert_eq!(
            steps[0]["amg"]["skipped"],
            Value::Bool(true),
            "{}",
            steps[0]
        );
        assert_eq!(steps[0]["iterations"].as_u64(), Some(0), "{}", steps[0]);
        assert_eq!(
            steps[0]["amg"]["pc_setup"],
            Value::Bool(false),
            "{}",
            steps[0]
        );
        assert_eq!(
            steps[1]["amg"]["pc_setup"],
            Value::Bool(true),
            "{}",
            steps[1]
        );
        for st in &steps[2..] {
            assert_eq!(st["amg"]["pc_setup"], Value::Bool(false), "{st}");
        }
        for st in &steps[1..] {
            assert_eq!(st["pinned"].as_u64(), Some(3), "{st}");
            assert_eq!(st["amg"]["null_space"], Value::Bool(true), "{st}");
        }
        // the first step from the predicted set is solved loosely, every later one exactly
        // (the last, which ends the iteration, above all)
        assert_eq!(
            steps[1]["amg"]["inexact"],
            Value::Bool(true),
            "{}",
            steps[1]
        );
        assert!(steps.len() > 2, "a loose step is never the last");
        for st in &steps[2..] {
            assert_eq!(st["amg"]["inexact"], Value::Bool(false), "{st}");
        }
        for st in get(&plain.summary, &["newton", "history"])
            .as_array()
            .unwrap()
        {
            assert_ne!(st["amg"]["null_space"], Value::Bool(true), "{st}");
        }
    }
}

/// The full ball pressed by 0.01 (106 nodes in contact at the end) with the model's size
/// lowered by the test-only limit MAX_MODEL_NODES, so that the model is coarser than the mesh
/// (52 model nodes for 256): at 60 the refinement at the edge does not fit and the coarse
/// model predicts alone; at 200 the nodes at the coarse prediction's edge get a model node
/// each (more model nodes than the coarse ones, fewer than represented) and the prediction
/// lands closer to the final set (measured: 3 nodes off against 10). Both end on the plain
/// path's answer.
#[test]
fn a_coarse_model_is_refined_at_the_contact_edge() {
    let case = repo("cases/ball3d/ball3d.toml");
    let sets = ["neumann.0.pressure=0.01"];
    let plain = run(2, &case, &iterative(&sets, "never"));
    let fin = plain.active_node_ids().len() as i64;
    let miss = |limit: &str| {
        let all = iterative(&sets, "auto");
        let all: Vec<&str> = all.iter().map(String::as_str).collect();
        let env = [("SIGNORINI_TEST_LIMIT_MAX_MODEL_NODES", limit)];
        let s = solve_env(2, &case, &all, &env, LIMIT);
        s.assert_converged(limit);
        s.assert_same_answer(&plain, 1e-8, &format!("limit {limit}"));
        let p = predictor(&s);
        assert_eq!(p["outcome"], "predicted", "{p}");
        let (m, n) = (
            p["model_nodes"].as_u64().unwrap(),
            p["represented"].as_u64().unwrap(),
        );
        assert!(m < n, "limit {limit}: a coarsened model: {p}");
        (m, (p["predicted_active"].as_i64().unwrap() - fin).abs())
    };
    let (coarse, coarse_miss) = miss("60");
    let (refined, refined_miss) = miss("200");
    assert!(refined > coarse, "{refined} model nodes against {coarse}");
    assert!(
        refined_miss < coarse_miss,
        "the refined model misses {refined_miss} nodes, the coarse one {coarse_miss}"
    );
}

/// Corrections where the model of every node would be coarser than the mesh: the committed
/// ball pressed by 0.05 with the model's size lowered by the test-only limit MAX_MODEL_NODES to
/// 300. An exact update that changes nodes is corrected by a model of its edge band alone
/// (fewer model nodes than contact nodes, every contact node represented, at most the limit);
/// the run ends on the plain path's answer in no more steps than the plain path (measured: 5
/// against 9; the band corrects the third step's update).
#[test]
fn a_coarse_zone_is_corrected_on_the_edge_band_of_each_exact_update() {
    let case = repo("cases/ball3d/ball3d.toml");
    let sets = ["neumann.0.pressure=0.05"];
    let plain = run(2, &case, &iterative(&sets, "never"));
    let all = iterative(&sets, "auto");
    let all: Vec<&str> = all.iter().map(String::as_str).collect();
    let env = [("SIGNORINI_TEST_LIMIT_MAX_MODEL_NODES", "300")];
    let s = solve_env(2, &case, &all, &env, LIMIT);
    s.assert_converged("limit 300");
    s.assert_same_answer(&plain, 1e-8, "limit 300");
    assert!(s.run.output().contains("edge band"), "{}", s.run.output());
    let h = get(&s.summary, &["newton", "history"]).as_array().unwrap();
    let corrected: Vec<&Value> = h[1..]
        .iter()
        .filter(|st| !st["predictor"].is_null())
        .collect();
    assert!(!corrected.is_empty(), "{h:?}");
    for st in corrected {
        let p = &st["predictor"];
        let (m, n) = (p["model_nodes"].as_u64(), p["represented"].as_u64());
        assert!(m < n && m <= Some(300), "{p}");
    }
    assert!(
        h.len() <= plain.steps(),
        "{} against {}",
        h.len(),
        plain.steps()
    );
}

/// A node at the edge of its state that the Krylov solver's error decides: the committed ball
/// pressed by 0.01 on the iterative preset with the loose solver.rtol = 1e-4. The solves are
/// tightened 1 000 × before the iteration goes on, and the run ends on the plain path's active
/// set (at the default rtol) instead of being called cycling or failing the final check (as the
/// binary before the tightening did). Two ways lead there: the model's correction keeps the set
/// that (3.23) changes (measured: at step 3), or, with the model capped at 60 nodes (test-only
/// limit; no correction fits), the set recurs (measured: at step 7). Either message is accepted
/// in either run: which step's round-off flips the node is not the test's business.
#[test]
fn an_edge_node_within_the_solver_error_tightens_the_krylov_solves() {
    let case = repo("cases/ball3d/ball3d.toml");
    let plain = run(2, &case, &iterative(&["neumann.0.pressure=0.01"], "never"));
    let sets = iterative(&["neumann.0.pressure=0.01", "solver.rtol=1e-4"], "auto");
    let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
    for limit in ["3000", "60"] {
        let env = [("SIGNORINI_TEST_LIMIT_MAX_MODEL_NODES", limit)];
        let loose = solve_env(2, &case, &sets, &env, LIMIT);
        loose.assert_converged(limit);
        let out = loose.run.output();
        assert!(
            (out.contains("recurs on Krylov solves to rtol 1e-4")
                || out.contains(
                    "kept by the model where (3.23) changes it on Krylov solves to rtol 1e-4"
                ))
                && out.contains("the steps from here solve to 1e-7"),
            "limit {limit}: {out}"
        );
        assert!(!out.contains("cycling detected"), "limit {limit}: {out}");
        loose.assert_same_answer(&plain, 1e-5, &format!("rtol 1e-4, limit {limit}"));
    }
}

/// The manufactured strip (a contact zone wide against the body's height: the half-space
/// model is rough, its first set has 24 of the final 57 nodes at level 3). From the predicted
/// set on, every exact step whose update (3.23) changes nodes has it corrected by the model
/// anchored at that step's solution; the iteration still ends as Algorithm 1 does (an exact
/// step that changes nothing), on the plain path's answer, in no more steps than it.
#[test]
fn manufactured_strip_2d_corrects_each_exact_update_by_the_anchored_model() {
    let case = repo("cases/manufactured/contact2d.toml");
    let sets = ["mesh.refine=3"];
    for np in [1, 2] {
        let plain = run(np, &case, &iterative(&sets, "never"));
        let auto = run(np, &case, &iterative(&sets, "auto"));
        assert_eq!(plain.active_node_ids(), auto.active_node_ids());
        let d = plain.u_rel_diff(&auto);
        assert!(d <= 1e-8, "|u - u_plain| / max|u| = {d:e}");
        let h = get(&auto.summary, &["newton", "history"]);
        let steps = h.as_array().unwrap();
        assert!(steps.len() >= 3, "{h}");
        assert!(
            auto.steps() <= plain.steps(),
            "{} > {}",
            auto.steps(),
            plain.steps()
        );
        for st in &steps[1..steps.len() - 1] {
            assert!(st["changed"].as_u64().unwrap() > 0, "{st}");
            assert_eq!(st["predictor"]["outcome"], "predicted", "{st}");
        }
        let last = &steps[steps.len() - 1];
        assert_eq!(last["changed"].as_u64(), Some(0), "{last}");
        assert!(last["predictor"].is_null(), "{last}");
    }
}

#[test]
fn quarter_ball_3d_mirrors_in_its_two_symmetry_planes() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = tmp.path().join("hertz3d.msh");
    let mut cmd = std::process::Command::new("gmsh");
    cmd.arg("-3")
        .arg(repo("cases/hertz3d/hertz3d.geo"))
        .args(["-setnumber", "h", "0.025", "-format", "msh41", "-o"])
        .arg(&mesh);
    run_with_timeout(cmd, std::time::Duration::from_secs(120)).expect_code(0, "gmsh hertz3d");
    let m = format!("mesh.file={}", toml_path(&mesh));
    for np in [1, 2] {
        predicted_against_plain(np, &repo("cases/hertz3d/hertz3d.toml"), &[&m], 2);
    }
}

#[test]
fn half_indentation_mirrors_in_one_plane_and_skips_the_unloaded_first_solve() {
    // a clamped block loaded only through the contact (the obstacle overlaps it): the first
    // solve has no right-hand side, u⁰ = 0, no solve and no preconditioner setup
    let case = repo("tests/cases/indent2d_half.toml");
    let init = "newton.init=\"auto\"";
    let (_, auto) = predicted_against_plain(2, &case, &[init], 1);
    let h0 = &get(&auto.summary, &["newton", "history"])[0];
    assert_eq!(h0["iterations"].as_u64(), Some(0), "{h0}");
    assert_eq!(h0["amg"]["pc_setup"], Value::Bool(false), "{h0}");
}

#[test]
fn only_the_iterative_reuse_path_without_friction_predicts() {
    let case = repo("cases/hertz/hertz.toml");
    for sets in [
        // an explicit start is the user's
        iterative(&["newton.init=\"all_inactive\""], "auto"),
        // the direct preset condenses instead
        vec!["solver.preset=\"direct\"".to_string()],
    ] {
        let s = run(2, &case, &sets);
        assert!(predictor(&s).is_null(), "{sets:?}: {}", predictor(&s));
        assert!(!s.run.output().contains("predictor:"), "{sets:?}");
    }
    // Tresca: Algorithm 2 without inexact steps
    let tresca = repo("tests/cases/tresca/hertz_tresca.toml");
    let sets = iterative(&[], "auto");
    let s = run(2, &tresca, &sets);
    assert!(predictor(&s).is_null(), "Tresca: {}", predictor(&s));
    assert!(!s.run.output().contains("predictor:"), "Tresca");
}

/// The three blocks of cases/blocks/tower2d.msh, the top pressed down by Dirichlet data and the
/// middle block held by contact alone: the predictor's first solve is skipped (a floating
/// body, u⁰ = 0), nothing penetrates in u⁰ and the model keeps the empty set. That iterate is
/// no answer; before, the run stopped on it (0 active nodes, equilibrium residual 0.94 of its
/// scale, exit 0).
#[test]
fn a_skipped_first_solve_whose_prediction_changes_nothing_is_no_answer() {
    let tmp = tempfile::tempdir().unwrap();
    let mut text = format!(
        "[mesh]\nfile = {}\n",
        toml_path(&repo("cases/blocks/tower2d.msh"))
    );
    for (g, e, nu) in [
        ("lower", 1.0, 0.45),
        ("middle", 3.0, 0.1),
        ("upper", 2.0, 0.3),
    ] {
        text += &format!(
            "[[material]]\ngroup = \"{g}\"\nyoung = {e:?}\npoisson = {nu:?}\n\
             model = \"plane_strain\"\n"
        );
    }
    text += "[[dirichlet]]\ngroup = \"bottom\"\nvalue = [\"free\", 0.0]\n\
             [[dirichlet]]\ngroup = \"left\"\nvalue = [0.0, \"free\"]\n\
             [[dirichlet]]\ngroup = \"top\"\nvalue = [\"free\", -0.005]\n\
             [[contact]]\ngroup = \"middle_bottom\"\n\
             obstacle = { type = \"body\", group = \"lower_top\" }\n\
             [[contact]]\ngroup = \"middle_top\"\n\
             obstacle = { type = \"body\", group = \"upper_bottom\" }\n\
             [output]\ndir = \"out\"\n";
    let case = write_case(&tmp.path().join("tower_pressed.toml"), &text);
    let direct = run(2, &case, &[]);
    assert_eq!(direct.active_node_ids().len(), 8, "{}", direct.run.output());
    for np in [1, 2] {
        let it = run(np, &case, &iterative(&[], "auto"));
        let h0 = &get(&it.summary, &["newton", "history"])[0];
        assert_eq!(h0["amg"]["skipped"], Value::Bool(true), "{h0}");
        let worst = it.f(&["certificate", "worst"]);
        assert!(worst < 1e-6, "{np} rank(s): certificate {worst:e}");
        it.assert_same_answer(&direct, 1e-8, &format!("iterative on {np} rank(s)"));
    }
}
