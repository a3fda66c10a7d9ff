//! A failure on one rank ends every rank — no hang, the message said, nothing written — on every
//! path: faults injected (test-only feature `fault-injection`, src/fault.rs) at the N-th
//! agreement of a run (every guarded stage ends in one) and at the N-th checked PETSc call (a
//! PETSc error on one rank at an arbitrary place), as a stage error, a PETSc error raised on
//! that rank alone, or a panic, on rank 0 and on the last rank of 2 and 3 ranks. A fault that an
//! agreed fallback absorbs must end in a converged run that says so.
//!
//! Also the crash on valid input the parallel rule once let through: force control on a contact
//! zone too wide for the dense compliance (the limit lowered for the test).

#![cfg(feature = "fault-injection")]

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// What one injected run must show; returns whether the fault fired.
fn check_run(np: usize, case: &Path, sets: &[&str], spec: &str) -> bool {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let mut cmd = solver_command(np, case, sets, &out);
    cmd.env("SIGNORINI_TEST_FAULT", spec);
    let t = Instant::now();
    let r = run_with_timeout(cmd, Duration::from_secs(90));
    let secs = t.elapsed().as_secs_f64();
    let (stage, _) = spec.split_once('@').unwrap();
    let msg = format!("injected fault at {stage} on rank");
    let what = format!(
        "{} on {np} ranks, {sets:?}, {spec} ({secs:.1} s)",
        case.display()
    );
    let fired = r.stdout.contains(&msg) || r.stderr.contains(&msg);
    match r.code {
        None => panic!("{what}: no exit (hang or signal)\n{}", r.output()),
        Some(0) => {
            // never reached, or absorbed by an agreed fallback: a complete, converged result
            let s = solved(r, tmp, out);
            s.assert_converged(&what);
        }
        Some(code) => {
            assert!(
                fired,
                "{what}: exit {code} without the injected message\n{}",
                r.output()
            );
            let expected = if spec.ends_with(":panic") {
                [101, 101]
            } else {
                [1, 2]
            };
            assert!(
                expected.contains(&code),
                "{what}: exit code {code}\n{}",
                r.output()
            );
            if spec.ends_with(":panic") {
                assert!(
                    r.stderr.contains("internal error"),
                    "{what}\n{}",
                    r.output()
                );
            }
            if out.exists() {
                // a load history whose later step failed keeps the steps that converged
                // (docs/load_steps.md): then a complete summary says so
                let text = std::fs::read_to_string(out.join("summary.json"))
                    .unwrap_or_else(|e| panic!("{what}: output without summary.json: {e}"));
                let v: serde_json::Value = serde_json::from_str(&text).expect("summary.json");
                assert!(
                    v["load"]["completed"] == false
                        && v["load"]["failure"]
                            .as_str()
                            .is_some_and(|m| m.contains(&msg))
                        && r.stderr.contains("the steps that converged are written"),
                    "{what}: output written\n{}",
                    r.output()
                );
            }
        }
    }
    fired
}

/// Sweeps the counted stage `stage` over its passes 1, 2, 3, 5, 8, … of the run until a pass
/// past the run's last one; kinds, failing rank (0 or the last) and rank count (2, 3) rotate.
/// Returns the number of runs in which the fault fired.
fn sweep(case: &Path, sets: &[&str], stage: &str, kinds: &[&str]) -> usize {
    let (mut a, mut b) = (1usize, 2usize);
    let mut fired = 0;
    for i in 0.. {
        let np = 2 + (i / 2) % 2;
        let rank = if i % 2 == 0 { 0 } else { np - 1 };
        let kind = kinds[i % kinds.len()];
        let spec = format!("{stage}#{a}@{rank}{kind}");
        if check_run(np, case, sets, &spec) {
            fired += 1;
        } else if !kind.ends_with("panic") && rank == 0 {
            // rank 0 passes every counted stage the others pass: past the end of the run
            break;
        }
        (a, b) = (b, a + b);
        assert!(i < 40, "{stage}: no end of the run found");
    }
    fired
}

const KINDS: [&str; 3] = ["", ":petsc", ":panic"];

fn hertz() -> PathBuf {
    repo("cases/hertz/hertz.toml")
}

#[test]
fn frictionless_condensed_and_plain_paths() {
    assert!(sweep(&hertz(), &[], "agree", &KINDS) >= 5);
    assert!(sweep(&hertz(), &["solver.reuse=\"never\""], "agree", &KINDS) >= 5);
    assert!(sweep(&hertz(), &[], "petsc-call", &["", ":panic"]) >= 5);
}

#[test]
fn iterative_preset_and_load_steps() {
    assert!(sweep(&hertz(), &["solver.preset=\"iterative\""], "agree", &KINDS) >= 5);
    assert!(sweep(&hertz(), &["load.steps=3"], "agree", &KINDS) >= 5);
    assert!(
        sweep(
            &hertz(),
            &["solver.preset=\"iterative\""],
            "petsc-call",
            &[""]
        ) >= 5
    );
}

#[test]
fn tresca_and_coulomb() {
    let tresca = case("hertz_tresca.toml");
    assert!(sweep(&tresca, &[], "agree", &KINDS) >= 5);
    let block = case("block2d_tresca.toml");
    let coulomb = "contact.friction={law=\"coulomb\", mu=0.3}";
    assert!(sweep(&block, &[coulomb], "agree", &KINDS) >= 5);
    assert!(sweep(&block, &[coulomb], "petsc-call", &[""]) >= 5);
}

/// Two bodies in one mesh (tests/meshes/two_squares.geo), each held at its left side, pressed
/// onto the plane y = 0: the bodies' count and their Dirichlet Gram matrices are agreed stages.
#[test]
fn two_bodies() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = tmp.path().join("two_squares.msh");
    common::process::gmsh("two_squares.geo", 2, 0.1, &mesh);
    let text = format!(
        "[mesh]\nfile = {:?}\n[material]\nyoung = 1.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\
         [[neumann]]\ngroup = \"top\"\npressure = 0.01\n\
         [[dirichlet]]\ngroup = \"left_a\"\nvalue = [0.0, 0.0]\n\
         [[dirichlet]]\ngroup = \"left_b\"\nvalue = [0.0, 0.0]\n\
         [contact]\ngroup = \"bottom\"\n\
         obstacle = {{ type = \"plane\", point = [0.0, 0.0], normal = [0.0, 1.0] }}\n",
        mesh.display().to_string()
    );
    let case = common::process::write_case(&tmp.path().join("two.toml"), &text);
    assert!(sweep(&case, &[], "agree", &KINDS) >= 5);
}

/// The block under the circle of tests/cases/indent2d_sym.toml, pushed by the force that a
/// motion of 0.03 takes (measured by a run first).
fn force_sets() -> (PathBuf, String) {
    let case = repo("tests/cases/indent2d_sym.toml");
    let moved = solve(
        1,
        &case,
        &["newton.init=\"auto\"", "contact.motion=[0.0, -0.03]"],
    );
    moved.assert_converged("displacement control");
    let f = floats(get(&moved.summary, &["contact", "total_force"]));
    (
        case,
        format!("contact.force=[{:.17e}, {:.17e}]", f[0], f[1]),
    )
}

#[test]
fn force_control() {
    let (case, force) = force_sets();
    let sets = ["newton.init=\"auto\"", force.as_str()];
    assert!(sweep(&case, &sets, "agree", &KINDS) >= 5);
}

/// Force control, direct preset, a contact zone wider than the dense Schur complement's limit
/// (lowered to 8 dofs by the test-only `SIGNORINI_TEST_LIMIT_MAX_SCHUR_DOFS`): the plain path
/// takes over without reusing a factorisation (force control solves its lift on the step's own
/// one) and gives back the displacement-controlled solution, on 1 and 2 ranks.
#[test]
fn force_control_on_a_zone_too_wide_for_the_dense_compliance() {
    let (case, force) = force_sets();
    let moved = solve(
        1,
        &case,
        &["newton.init=\"auto\"", "contact.motion=[0.0, -0.03]"],
    );
    for np in [1, 2] {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out");
        let sets = [
            "newton.init=\"auto\"",
            force.as_str(),
            "solver.preset=\"direct\"",
        ];
        let mut cmd = solver_command(np, &case, &sets, &out);
        cmd.env("SIGNORINI_TEST_LIMIT_MAX_SCHUR_DOFS", "8");
        let s = solved(run_with_timeout(cmd, Duration::from_secs(90)), tmp, out);
        s.assert_converged("force control, too wide");
        let log = s.run.output();
        assert!(log.contains("limit of 8 dofs"), "{log}");
        assert_eq!(s.summary["newton"]["condensed"]["too_wide"], true, "{log}");
        let delta = s.f(&["contact", "approach"]);
        assert!(
            (delta - 0.03).abs() <= 1e-8 * 0.03,
            "{np} ranks: δ = {delta}"
        );
        let du = s.u_rel_diff(&moved);
        assert!(du <= 1e-8, "{np} ranks: |Δu|/|u| = {du:e}");
    }
}
