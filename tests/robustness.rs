//! Errors found on some ranks end every rank with the same message and exit code (no hang);
//! the output directory holds exactly what one run wrote; an unusable output directory is
//! refused before the solve (issue 11, items 1, 2, 5).

mod common;
use common::*;
use std::path::Path;

const SPHERE_AT_NODE: &str = "contact.obstacle={type=\"sphere\",center=[1.0,0.0],radius=0.5}";

#[test]
fn a_contact_node_at_the_sphere_centre_is_refused_on_every_rank_count() {
    let tmp = tempfile::tempdir().unwrap();
    let mut messages = Vec::new();
    for np in [1, 2, 3] {
        let out = tmp.path().join(format!("out{np}"));
        let r = run_solver(
            np,
            &repo("cases/blocks/block2d.toml"),
            &[SPHERE_AT_NODE],
            &out,
        );
        // A hang would end in the test's time limit (code None).
        r.expect_code(2, &format!("{np} ranks"));
        let line = error_line(&r);
        assert!(line.contains("centre of the sphere"), "{line}");
        assert!(line.contains("contact.obstacle"), "{line}");
        assert!(!out.exists(), "nothing written");
        messages.push(line);
    }
    assert!(messages.iter().all(|m| *m == messages[0]), "{messages:#?}");
}

/// The first `error:` line of a run's stderr (panics with the run's output if there is none).
fn error_line(r: &Run) -> String {
    r.stderr
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or_else(|| panic!("no error line:\n{}", r.output()))
        .to_string()
}

fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_reused_output_directory_holds_only_the_last_run() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("same");
    run_solver(1, &repo("cases/blocks/block2d.toml"), &[], &out).expect_code(0, "contact run");
    assert!(out.join("contact_nodes.csv").exists());
    run_solver(1, &repo("cases/plate/plate.toml"), &[], &out).expect_code(0, "linear run");
    assert_eq!(
        files(&out),
        ["solution.h5", "solution.xdmf", "summary.json"],
        "the contact table of the first run must be gone"
    );
    // No staging or set-aside directory is left next to it.
    assert_eq!(files(tmp.path()), ["same"]);
}

#[test]
fn an_unusable_output_directory_is_refused_before_the_solve() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("a_file");
    std::fs::write(&file, "x").unwrap();
    let out = file.join("sub");
    let r = run_solver(1, &repo("cases/blocks/block2d.toml"), &[], &out);
    r.expect_code(2, "output below a file");
    assert!(r.stderr.contains("output.dir"), "{}", r.output());
    assert!(
        !r.stdout.contains("newton"),
        "refused before the solve:\n{}",
        r.output()
    );

    // A directory with files this program did not write is not replaced.
    let foreign = tmp.path().join("mine");
    std::fs::create_dir(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "keep me").unwrap();
    let r = run_solver(2, &repo("cases/blocks/block2d.toml"), &[], &foreign);
    r.expect_code(2, "foreign file");
    assert!(r.stderr.contains("notes.txt"), "{}", r.output());
    assert_eq!(files(&foreign), ["notes.txt"]);
}

#[test]
fn a_failed_solve_leaves_the_previous_results() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("res");
    run_solver(1, &repo("cases/blocks/block2d.toml"), &[], &out).expect_code(0, "first run");
    let before = std::fs::read(out.join("summary.json")).unwrap();
    // One Newton step is not enough for this case.
    let r = run_solver(
        2,
        &repo("cases/hertz/hertz.toml"),
        &["newton.max_steps=1"],
        &out,
    );
    r.expect_code(1, "max_steps = 1");
    assert_eq!(std::fs::read(out.join("summary.json")).unwrap(), before);
    assert_eq!(files(tmp.path()), ["res"], "no staging directory left");
}

#[test]
fn a_tangential_load_beyond_the_friction_capacity_is_refused_before_newton() {
    let tmp = tempfile::tempdir().unwrap();
    for np in [1, 2] {
        let out = tmp.path().join(format!("out{np}"));
        let r = run_solver(
            np,
            &repo("tests/cases/tresca/hertz_tresca.toml"),
            &["neumann.1.traction=[0.05,0.0]"],
            &out,
        );
        r.expect_code(1, "beyond the friction capacity");
        assert!(r.stderr.contains("no equilibrium"), "{}", r.output());
        assert!(
            !r.stdout.contains("newton   1"),
            "refused before Newton:\n{}",
            r.output()
        );
        assert!(!out.exists());
    }
    // Within the capacity the same case converges.
    let s = solve(1, &repo("tests/cases/tresca/hertz_tresca.toml"), &[]);
    s.assert_converged("within the capacity");
}

/// A full disk (no Dirichlet data) between two plates, the top one under a force along its
/// normal (N = 0.01 on each plate), with a tangential traction on its free sides whose
/// resultant is 0.003: refused before Newton where the plates' capacity Σ_j μ_j N_j is
/// 0.1 × 0.01 + 0.1 × 0.01 (1 and 2 ranks; it used to end in "Newton cycling" after 44 steps);
/// solved where the top plate's μ is 0.3 (capacity 0.004), so each pair's own μ counts.
#[test]
fn a_tangential_load_beyond_the_friction_of_two_plates_is_refused_before_newton() {
    let tmp = tempfile::tempdir().unwrap();
    let case = |mu_top: f64| {
        format!(
            "[mesh]\nfile = {}\n[material]\nyoung = 1.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\
             [[neumann]]\ngroup = \"free\"\ntraction = [0.000764, 0.0]\n\
             [[contact]]\ngroup = \"contact\"\n\
             obstacle = {{ type = \"plane\", point = [0.0, -1.0], normal = [0.0, 1.0] }}\n\
             friction = {{ law = \"coulomb\", mu = 0.1 }}\n\
             [[contact]]\ngroup = \"load\"\n\
             obstacle = {{ type = \"plane\", point = [0.0, 1.0], normal = [0.0, -1.0] }}\n\
             friction = {{ law = \"coulomb\", mu = {mu_top} }}\nforce = [0.0, -0.01]\n",
            toml_path(&repo("cases/hertz/meshes/hertz_L3.msh"))
        )
    };
    let beyond = write_case(&tmp.path().join("beyond.toml"), &case(0.1));
    for np in [1, 2] {
        let out = tmp.path().join(format!("out{np}"));
        let r = run_solver(np, &beyond, &[], &out);
        r.expect_code(1, "beyond the plates' friction capacity");
        assert!(
            r.stderr.contains("no equilibrium") && r.stderr.contains("2.000000e-3"),
            "{}",
            r.output()
        );
        assert!(!r.stdout.contains("newton   1"), "{}", r.output());
        assert!(!out.exists());
    }
    let within = write_case(&tmp.path().join("within.toml"), &case(0.3));
    let s = solve(2, &within, &[]);
    s.assert_converged("within the capacity of the two plates");
}

/// The Hertz disk (no Dirichlet data) pressed onto a large circle (not a plane: its friction
/// capacity is not known before the solve) with a tangential traction twice what μ = 0.05
/// carries: the generalised Newton cannot converge, and the error says why it may not (exit
/// code 1, 2 ranks).
#[test]
fn a_floating_body_beyond_friction_on_a_curved_obstacle_is_told_why() {
    let tmp = tempfile::tempdir().unwrap();
    let text = format!(
        "[mesh]\nfile = {}\n[material]\nyoung = 2.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\
         [[neumann]]\ngroup = \"load\"\npressure = 0.02\n\
         [[neumann]]\ngroup = \"load\"\ntraction = [0.002, 0.0]\n\
         [contact]\ngroup = \"contact\"\n\
         obstacle = {{ type = \"sphere\", center = [0.0, -101.0], radius = 100.0 }}\n\
         friction = {{ law = \"coulomb\", mu = 0.05 }}\nrigid_modes = \"auto\"\n",
        toml_path(&repo("cases/hertz/meshes/hertz_L4.msh"))
    );
    let case = write_case(&tmp.path().join("curved.toml"), &text);
    let out = tmp.path().join("out");
    let r = run_solver(2, &case, &[], &out);
    r.expect_code(1, "beyond friction on a curved obstacle");
    assert!(
        r.stderr.contains("friction alone holds it tangentially"),
        "{}",
        r.output()
    );
    assert!(!out.exists());
}

#[test]
fn certificates_are_judged_by_the_problems_scales() {
    // The block lifted off the plane (all contact forces ~1e-17) and the iterative preset
    // (u_n ~1e-13 at an all-active bottom) used to warn about round-off.
    for (case, sets) in [
        (
            "tests/cases/block2d_pulled.toml",
            vec!["solver.preset=\"iterative\""],
        ),
        (
            "cases/blocks/block3d.toml",
            vec!["solver.preset=\"iterative\""],
        ),
    ] {
        let s = solve(1, &repo(case), &sets);
        assert!(
            !s.run.stdout.contains("warning"),
            "{case}:\n{}",
            s.run.output()
        );
        let kkt = get(&s.summary, &["contact", "kkt"]);
        let length = kkt["length_scale"].as_f64().unwrap();
        assert!(length > 1e-6, "{case}: length scale {length}");
    }
}

#[test]
fn nearly_incompressible_materials_are_warned_about() {
    let case = repo("cases/blocks/block2d.toml");
    let s = solve(1, &case, &["material.poisson=0.4999"]);
    assert!(
        s.run.stdout.contains("warning: poisson = 0.4999"),
        "{}",
        s.run.output()
    );
    let s = solve(1, &case, &["material.poisson=0.45"]);
    assert!(!s.run.stdout.contains("warning"), "{}", s.run.output());
    let s = solve(
        1,
        &case,
        &["material.poisson=0.4999", "material.model=\"plane_stress\""],
    );
    assert!(
        !s.run.stdout.contains("warning"),
        "plane stress does not lock"
    );
}

#[test]
fn an_obstacle_deep_inside_the_body_is_refused_naming_the_key() {
    // The Hertz disk (radius 1, resting on y = −1): a plane at y = +0.5 with its normal up (the
    // obstacle's side is below: the disk starts 1.5 deep inside, every node beyond) and a plane
    // at y = −0.75 (the lowest 0.25 of the disk inside, 12.5 % of its size 2): both refused before
    // Newton on 1 and 2 ranks, exit 2, naming contact.obstacle; nothing written.
    let tmp = tempfile::tempdir().unwrap();
    let plane =
        |y: f64| format!("contact.obstacle={{type=\"plane\",point=[0.0,{y}],normal=[0.0,1.0]}}");
    for (y, hint) in [(0.5, "normal"), (-0.75, "placed")] {
        for np in [1, 2] {
            let out = tmp.path().join(format!("out{np}"));
            let p = plane(y);
            let r = run_solver(np, &repo("cases/hertz/hertz.toml"), &[&p], &out);
            r.expect_code(2, "deep start");
            assert!(r.stderr.contains("contact.obstacle"), "{}", r.output());
            assert!(
                r.stderr.contains("deep inside the obstacle"),
                "{}",
                r.output()
            );
            assert!(r.stderr.contains(hint), "{}", r.output());
            assert!(!r.stdout.contains("newton   1"), "{}", r.output());
            assert!(!out.exists(), "nothing written");
        }
    }
    // An overlap of 1 % of the disk's size starts and converges.
    let s = solve(2, &repo("cases/hertz/hertz.toml"), &[&plane(-0.98)]);
    s.assert_converged("overlap of 0.02");
    assert!(s.f(&["contact", "active_count"]) > 0.0);
}

/// The fault-injection tests (here and tests/faults.rs) need the test-only feature: without it
/// the suite fails here instead of skipping them.
#[cfg(not(feature = "fault-injection"))]
#[test]
fn the_suite_is_built_with_fault_injection() {
    panic!("build the tests with `--features fault-injection` (scripts/test does)");
}

#[cfg(feature = "fault-injection")]
#[test]
fn a_failure_on_one_rank_ends_every_rank_alike() {
    // Test-only fault injection (src/fault.rs, SIGNORINI_TEST_FAULT=STAGE@RANK) in the stages
    // of a contact solve where one rank acts alone before a collective: rank 1 of 2 and of 3
    // fails; every rank ends with the same message, exit 1, within the time limit (no hang),
    // nothing written. The default Hertz case runs the condensed path (a failure in its
    // factorisation falls back to the plain path, whose factorisation fails the same way).
    let tmp = tempfile::tempdir().unwrap();
    for stage in ["mumps-rows", "nd-graph", "condensed-expand"] {
        for np in [2, 3] {
            let out = tmp.path().join(format!("{stage}-{np}"));
            let mut cmd = solver_command(np, &repo("cases/hertz/hertz.toml"), &[], &out);
            cmd.env("SIGNORINI_TEST_FAULT", format!("{stage}@1"));
            let r = run_with_timeout(cmd, std::time::Duration::from_secs(120));
            r.expect_code(1, stage);
            let msg = format!("injected fault at {stage} on rank 1");
            // every rank that prints an error prints this one: as many copies of the message
            // as error headers (counted, not matched line by line: the ranks' lines and
            // MPI_Abort's banner interleave on stderr)
            let headers = r.stderr.matches("error (rank").count()
                + r.stderr.lines().filter(|l| l.starts_with("error:")).count();
            assert!(headers >= 1, "{}", r.output());
            assert!(
                r.stderr.matches(&msg).count() >= headers,
                "{stage}, {np} ranks: {headers} error(s), not all with the same message\n{}",
                r.output()
            );
            assert!(!out.exists(), "{stage}, {np} ranks: output written");
        }
    }
}

#[cfg(feature = "fault-injection")]
#[test]
fn a_panic_in_rank_0s_dense_work_is_caught_and_every_rank_goes_on_alike() {
    // The dense steps of the condensed path and the predictor's model run on rank 0 while the
    // other ranks wait in a broadcast: a panic there (test-only fault injection) is caught,
    // broadcast as a failure, and every rank takes the same way on — the condensed path falls
    // back to the plain path, the iterative path goes on without a prediction — to the same
    // answer as without the fault, within the time limit.
    let case = repo("cases/hertz/hertz.toml");
    for (stage, sets) in [
        ("dense-steps", vec![]),
        ("predictor-model", vec!["solver.preset=\"iterative\""]),
    ] {
        let clean = solve(2, &case, &sets);
        clean.assert_converged(stage);
        for np in [2, 3] {
            let tmp = tempfile::tempdir().unwrap();
            let out = tmp.path().join("out");
            let mut cmd = solver_command(np, &case, &sets, &out);
            cmd.env("SIGNORINI_TEST_FAULT", format!("{stage}@0"));
            let r = solved(
                run_with_timeout(cmd, std::time::Duration::from_secs(120)),
                tmp,
                out,
            );
            r.assert_converged(&format!("{stage} on {np} ranks"));
            let msg = format!("injected fault at {stage} on rank 0");
            if stage == "dense-steps" {
                let cs = &r.summary["newton"]["condensed"];
                assert_eq!(cs["outcome"], "fallback", "{}", r.run.output());
                let why = cs["fallback_reason"].as_str().unwrap();
                assert!(why.contains(&msg), "{why}");
            } else {
                let p = &r.summary["newton"]["history"][0]["predictor"];
                assert_eq!(
                    p["outcome"], "the model failed on rank 0 (no prediction)",
                    "{p}"
                );
            }
            r.assert_same_answer(&clean, 1e-8, &format!("{stage}, {np} ranks"));
        }
    }
}

#[test]
fn a_floating_body_with_too_few_pins_is_told_which_keys_to_change() {
    // A unit square of four triangles around one interior node, its whole boundary the contact
    // group, resting on y = 0 under a pressure on top: three free rigid modes but only the
    // interior node's two dofs off the contact boundary to pin them. Every rank count ends with
    // the same message naming the keys that hold the body, exit 1, nothing written.
    let tmp = tempfile::tempdir().unwrap();
    let geo = tmp.path().join("sq.geo");
    std::fs::write(
        &geo,
        "Point(1) = {0, 0, 0, 2}; Point(2) = {1, 0, 0, 2}; Point(3) = {1, 1, 0, 2};\n\
         Point(4) = {0, 1, 0, 2};\n\
         Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};\n\
         Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};\n\
         Physical Curve(\"all\") = {1, 2, 3, 4}; Physical Curve(\"top\") = {3};\n\
         Physical Surface(\"body\") = {1};\n",
    )
    .unwrap();
    let msh = tmp.path().join("sq.msh");
    gmsh_file(&geo, 2, &[], &msh);
    let case = write_case(
        &tmp.path().join("sq.toml"),
        &format!(
            "[mesh]\nfile = {}\n[material]\nyoung = 1.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\
             [[neumann]]\ngroup = \"top\"\npressure = 0.01\n[contact]\ngroup = \"all\"\n\
             obstacle = {{ type = \"plane\", point = [0.0, 0.0], normal = [0.0, 1.0] }}\n\
             rigid_modes = \"auto\"\n",
            toml_path(&msh)
        ),
    );
    let mut lines = Vec::new();
    for np in [1, 2] {
        let out = tmp.path().join(format!("out{np}"));
        let r = run_solver(np, &case, &[], &out);
        r.expect_code(1, &format!("{np} ranks"));
        let line = error_line(&r);
        for want in [
            "3 free rigid mode(s) but only 2 dof(s)",
            "'dirichlet'",
            "'contact.group'",
            "'contact.rigid_modes'",
        ] {
            assert!(line.contains(want), "{want:?} missing: {line}");
        }
        assert!(!out.exists(), "nothing written");
        lines.push(line);
    }
    assert_eq!(lines[0], lines[1]);
}

#[test]
fn a_linear_solve_that_does_not_converge_names_the_solver_keys() {
    // The plate (a linear case) on the iterative preset with two GMRES iterations allowed:
    // exit 1 on 1 and 2 ranks, one message naming the case file and its solver keys, nothing
    // written.
    let tmp = tempfile::tempdir().unwrap();
    let case = repo("cases/plate/plate.toml");
    for np in [1, 2] {
        let out = tmp.path().join(format!("out{np}"));
        let mut cmd = solver_command(np, &case, &["solver.preset=\"iterative\""], &out);
        cmd.args(["--", "-ksp_max_it", "2"]);
        let r = run_with_timeout(cmd, std::time::Duration::from_secs(120));
        r.expect_code(1, &format!("{np} ranks"));
        let line = error_line(&r);
        for want in [
            "did not converge",
            "plate.toml",
            "'solver.preset' = \"iterative\"",
        ] {
            assert!(line.contains(want), "{want:?} missing: {line}");
        }
        assert!(!out.exists(), "nothing written");
    }
}
