//! `solver.method = "snesvi"`: PETSc's SNES VI on the same discrete frictionless problem agrees
//! with Algorithm 1 (issue 9, item 4), on 1 and 2 ranks; bad combinations are refused.

mod common;
use common::*;
use std::path::Path;

/// max |u_a − u_b| / max |u_a| over all nodes (by node id) of two solution.h5 files.
const U_DIFF: &str = r#"
import sys, json, h5py, numpy as np
def u(d):
    with h5py.File(d + "/solution.h5", "r") as f:
        ids = f["mesh/node_id"][:]
        return ids, f["nodal/displacement"][:]
ia, ua = u(sys.argv[1]); ib, ub = u(sys.argv[2])
ua = ua[np.argsort(ia)]; ub = ub[np.argsort(ib)]
print("RESULT " + json.dumps({"diff": float(np.abs(ua - ub).max()), "scale": float(np.abs(ua).max())}))
"#;

fn compare(np: usize, case: &Path, sets: &[&str]) {
    let newton = solve(np, case, sets);
    newton.assert_converged("Algorithm 1");
    let mut sv = sets.to_vec();
    sv.push("solver.method=\"snesvi\"");
    let snes = solve(np, case, &sv);
    assert_eq!(get(&snes.summary, &["newton", "method"]), "snesvi");
    assert!(snes.converged(), "SNES VI:\n{}", snes.run.output());
    assert!(snes.steps() >= 1);
    let r = python_json(U_DIFF, &[&newton.dir, &snes.dir]);
    let (diff, scale) = (r["diff"].as_f64().unwrap(), r["scale"].as_f64().unwrap());
    assert!(scale > 0.0);
    assert!(
        diff <= 1e-8 * scale,
        "{}: |u_snes − u_newton| = {diff:e} against max|u| = {scale:e}",
        case.display()
    );
    // Same contact force and the same active nodes.
    let (fa, fb) = (newton.total_force(), snes.total_force());
    for (a, b) in fa.iter().zip(&fb) {
        assert!((a - b).abs() <= 1e-8 * norm(&fa), "{fa:?} vs {fb:?}");
    }
    assert_eq!(
        newton.f(&["contact", "active_count"]),
        snes.f(&["contact", "active_count"])
    );
}

#[test]
fn agrees_with_algorithm_1_in_2d() {
    compare(1, &repo("cases/blocks/block2d.toml"), &[]);
    compare(2, &repo("cases/blocks/indent2d.toml"), &[]);
}

#[test]
fn agrees_with_algorithm_1_in_3d_and_off_axis_normals() {
    compare(1, &repo("cases/blocks/block3d.toml"), &[]);
    compare(2, &repo("tests/cases/sphere3d.toml"), &[]);
}

#[test]
fn agrees_on_hertz_with_a_free_rigid_mode() {
    let mesh = repo("cases/hertz/meshes/hertz_refined_L2.msh");
    let set = format!("mesh.file={}", toml_path(&mesh));
    compare(2, &repo("cases/hertz/hertz.toml"), &[&set]);
}

#[test]
fn refuses_friction_and_linear_cases() {
    let tmp = tempfile::tempdir().unwrap();
    for (case, preset, want) in [
        (
            "tests/cases/tresca/block2d_tresca.toml",
            "auto",
            "frictionless contact only",
        ),
        (
            "cases/plate/plate.toml",
            "auto",
            "needs a [contact] section",
        ),
        // GMRES + GAMG does not converge on its reduced systems (solver.rs choose_preset)
        (
            "cases/blocks/block3d.toml",
            "iterative",
            "not preset = \"iterative\"",
        ),
    ] {
        let out = tmp.path().join("out");
        let preset = format!("solver.preset=\"{preset}\"");
        let r = run_solver(1, &repo(case), &["solver.method=\"snesvi\"", &preset], &out);
        r.expect_code(2, case);
        assert!(
            r.stderr.contains("solver.method") && r.stderr.contains(want),
            "{}",
            r.output()
        );
        assert!(!out.exists(), "nothing written");
    }
}
