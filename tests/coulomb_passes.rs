//! Coulomb on the condensed path where its iterates are hard: a load step's passes
//! (src/signorini/mod.rs `PassLoop`: where nodes beyond a pass' candidates change state on the
//! expanded u, the next pass takes them as candidates and keeps the pass' own, so that a zone
//! that moves, a floating body's that rolls, is not left for the plain path), and a dense step
//! whose settled slip rows leave the system singular (schur/coulomb_dense.rs `DenseIteration::run`: the
//! step again on the (F5) rows).

mod common;

use common::process::{gmsh_file, mesh_dir, repo};
use common::solved::{solve, solve_env, Solved};
use std::path::Path;

/// tests/meshes/ellipse_contact.geo (8 916 unknowns), floating: pressed onto the plane y = 0 by
/// a pressure of 0.02 on its upper half with a tangential traction of 0.001 that friction
/// alone holds (μ = 0.3), in the load steps 0.5 and 1. In the second step the body rolls: two
/// nodes beyond the first pass' candidates come into contact.
fn ellipse_case(dir: &Path) -> std::path::PathBuf {
    let mesh = dir.join("ellipse.msh");
    gmsh_file(&mesh_dir().join("ellipse_contact.geo"), 2, &[], &mesh);
    let case = dir.join("ellipse.toml");
    let text = format!(
        "[mesh]\nfile = {:?}\n[material]\nyoung = 2.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\
         [[neumann]]\ngroup = \"load\"\npressure = 0.02\n[[neumann]]\ngroup = \"load\"\n\
         traction = [0.001, 0.0]\n[contact]\ngroup = \"contact\"\n\
         obstacle = {{ type = \"plane\", point = [0.0, 0.0], normal = [0.0, 1.0] }}\n\
         friction = {{ law = \"coulomb\", mu = 0.3 }}\nrigid_modes = \"auto\"\n\
         [output]\nfields = [\"displacement\", \"contact\"]\n[load]\nfactors = [0.5, 1.0]\n",
        mesh.display().to_string()
    );
    std::fs::write(&case, text).expect("writing the case");
    case
}

/// Summary field of load step `k` (from 0).
fn step(s: &Solved, k: usize, key: &str) -> u64 {
    s.summary["load"]["steps"][k][key]
        .as_u64()
        .unwrap_or_else(|| panic!("load.steps[{k}].{key}: {}", s.run.output()))
}

#[test]
fn a_new_pass_keeps_the_candidates_of_the_pass_before() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let case = ellipse_case(tmp.path());
    let plain = solve(1, &case, &["newton.init=\"gap\""]);
    for np in [1, 2] {
        let s = solve(np, &case, &[]);
        let log = &s.run.stdout;
        assert!(
            log.contains("a new pass with them as candidates"),
            "{np} rank(s): the case needs a second pass\n{}",
            s.run.output()
        );
        assert!(
            !log.contains("plain path"),
            "{np} rank(s): the second pass solves the step\n{}",
            s.run.output()
        );
        let f = step(&s, 1, "factorisations");
        println!("{np} rank(s): load step 2 in {f} factorisations");
        assert!(f <= 2, "{np} rank(s): {f} factorisations in load step 2");
        for k in 0..2 {
            assert_eq!(step(&s, k, "active"), step(&plain, k, "active"), "step {k}");
            assert_eq!(step(&s, k, "slip"), step(&plain, k, "slip"), "step {k}");
        }
        assert_eq!(s.active_node_ids(), plain.active_node_ids(), "{np} rank(s)");
        assert_eq!(s.slip_node_ids(), plain.slip_node_ids(), "{np} rank(s)");
        let du = common::solved::step_displacement(&s.dir, 2);
        let du0 = common::solved::step_displacement(&plain.dir, 2);
        let scale = du0.values().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        let diff = common::compare::max_diff(&du, &du0).0 / scale;
        println!("{np} rank(s): u against the plain path {diff:.1e}");
        assert!(diff <= 1e-9, "{np} rank(s): u differs by {diff:.1e}");
    }
}

/// `s` (on `np` ranks) ends where `plain` ends: the same active and slipping nodes, u within
/// 1e-9 of its largest component.
fn ends_where(s: &Solved, plain: &Solved, np: usize) {
    assert_eq!(s.active_node_ids(), plain.active_node_ids(), "{np} rank(s)");
    assert_eq!(s.slip_node_ids(), plain.slip_node_ids(), "{np} rank(s)");
    let du = s.u_rel_diff(plain);
    println!("{np} rank(s): u against the plain path {du:.1e}");
    assert!(du <= 1e-9, "{np} rank(s): u differs by {du:.1e}");
}

/// The Hertz disk of the refined family (cases/hertz/meshes/hertz_refined_L4.msh, 12 618
/// unknowns) floating under the pressure 0.02 and a tangential traction of 0.004 that friction
/// alone holds (μ = 0.5): at the solution 30 of its 31 contact nodes slip. On the way an
/// iterate has every active node slipping, on settled rows: its dense system is singular.
fn rolling_disk_case(dir: &Path) -> std::path::PathBuf {
    let case = dir.join("disk.toml");
    let text = format!(
        "[mesh]\nfile = {:?}\n[material]\nyoung = 2.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\
         [[neumann]]\ngroup = \"load\"\npressure = 0.02\n[[neumann]]\ngroup = \"load\"\n\
         traction = [0.004, 0.0]\n[contact]\ngroup = \"contact\"\n\
         obstacle = {{ type = \"plane\", point = [0.0, -1.0], normal = [0.0, 1.0] }}\n\
         friction = {{ law = \"coulomb\", mu = 0.5 }}\nrigid_modes = \"auto\"\n\
         [output]\nfields = [\"displacement\", \"contact\"]\n",
        repo("cases/hertz/meshes/hertz_refined_L4.msh")
            .display()
            .to_string()
    );
    std::fs::write(&case, text).expect("writing the case");
    case
}

#[test]
fn a_singular_dense_step_on_settled_slip_rows_is_taken_on_the_f5_rows() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let case = rolling_disk_case(tmp.path());
    let plain = solve(1, &case, &["newton.init=\"gap\""]);
    plain.assert_converged("plain path");
    for np in [1, 2] {
        let s = solve(np, &case, &[]);
        s.assert_converged("default");
        assert!(
            !s.run.stdout.contains("plain path") && !s.run.stdout.contains("is singular"),
            "{np} rank(s): the dense iteration ends the solve\n{}",
            s.run.output()
        );
        let f = s.f(&["newton", "factorisations"]);
        // the path the test is named after: a dense step (of the fine iteration or of a coarse
        // level of the nested start) was singular on settled slip rows and taken on the (F5)
        // rows — in summary.json and in the log
        let cs = &s.summary["newton"]["condensed"]["coulomb"];
        println!(
            "{np} rank(s): the (F5) rows from dense step {}, on {} coarse level(s)",
            cs["f5_from"], cs["f5_coarse_levels"]
        );
        // (each key absent where it is none; measured: 3 coarse levels on 1, 2, 3 and 4 ranks)
        let fine = cs["f5_from"].as_u64();
        let coarse = cs["f5_coarse_levels"].as_u64().unwrap_or(0);
        assert!(
            fine.is_some_and(|k| k >= 1) || coarse >= 1,
            "{np} rank(s): no dense step on the (F5) rows: {cs}\n{}",
            s.run.output()
        );
        assert!(
            s.run
                .stdout
                .contains("settled slip rows left a dense system singular"),
            "{np} rank(s): {}",
            s.run.output()
        );
        println!(
            "{np} rank(s): {} Newton steps, {f} factorisation(s)",
            s.steps()
        );
        assert_eq!(f, 1.0, "{np} rank(s): one factorisation");
        assert!(!plain.slip_node_ids().is_empty());
        ends_where(&s, &plain, np);
    }
}

#[test]
fn a_second_pass_of_the_first_solve_starts_from_the_first_pass_states() {
    // The rolling disk of [`rolling_disk_case`] with the Schur limit lowered to 120 dofs (the
    // test-only limit MAX_SCHUR_DOFS): its first candidates are capped at 30 nodes, as the
    // floating disk at 698 352 unknowns is capped at 2 000 where its located zone asks for
    // 2 232 (docs/numbers.md). The frictionless solution (29 nodes) fits, Coulomb's (31) does
    // not: the check on the expanded u finds nodes beyond the candidates and a second pass
    // takes them. It factorises K_p alone, and its dense iteration starts from the first pass'
    // expanded iterate (no frictionless steps, no nested start) and ends where the plain path
    // from the touching node ends, on 1, 2 and 3 ranks.
    let tmp = tempfile::tempdir().expect("tempdir");
    let case = rolling_disk_case(tmp.path());
    let plain = solve(1, &case, &["newton.init=\"gap\""]);
    plain.assert_converged("plain path");
    let env = [("SIGNORINI_TEST_LIMIT_MAX_SCHUR_DOFS", "120")];
    for np in [1, 2, 3] {
        let s = solve_env(np, &case, &[], &env, std::time::Duration::from_secs(300));
        s.assert_converged("default, capped");
        let log = &s.run.stdout;
        assert!(
            log.contains("a new pass with them as candidates"),
            "{np} rank(s): the case needs a second pass\n{}",
            s.run.output()
        );
        assert!(
            !log.contains("plain path"),
            "{np} rank(s): {}",
            s.run.output()
        );
        // the frictionless steps and Coulomb's nested start in the first pass only; the second
        // factorises K_p alone
        let nested = log.matches("coulomb: condensed: nested start").count();
        let frictionless = log.matches("coulomb: the frictionless solution").count();
        let warm = log
            .matches("the friction iteration from its warm states")
            .count();
        let counts = (nested, frictionless, warm);
        assert_eq!(counts, (1, 1, 1), "{np} rank(s): {}", s.run.output());
        assert_eq!(s.f(&["newton", "factorisations"]), 2.0, "{np} rank(s)");
        ends_where(&s, &plain, np);
    }
}
