//! The linear-solver seam (src/linsolve.rs): the solver's kind follows the PC its resolved
//! options run — the preset's, overridden by the case file's `solver.petsc_options` and by the
//! command line after `--` — and the solver's set-up writes nothing into PETSc's global options
//! database (`-options_left` finds only what the user gave, all of it used).

mod common;
use common::*;
use std::path::PathBuf;

const L0: &str = "mesh.file=meshes/hertz_L0.msh";

fn hertz() -> PathBuf {
    repo("cases/hertz/hertz.toml")
}

/// Solves the frictionless 2D Hertz case on 2 ranks with `sets` and the PETSc options `petsc`
/// after `--`.
fn run(sets: &[&str], petsc: &[&str]) -> Solved {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("out");
    let mut cmd = solver_command(2, &hertz(), sets, &dir);
    cmd.arg("--").args(petsc);
    let run = run_with_timeout(cmd, LIMIT);
    solved(run, tmp, dir)
}

fn types(s: &Solved) -> (String, String) {
    let ls = get(&s.summary, &["linear_solver"]);
    let t = |k: &str| ls[k].as_str().unwrap_or_default().to_string();
    (t("ksp_type"), t("pc_type"))
}

/// A factorisation asked for on the command line over the iterative preset is a direct kind:
/// MUMPS' Cholesky with the project's order and the condensed path of the direct preset. (A
/// factorisation without `-pc_factor_mat_solver_type mumps` is PETSc's own, still direct.)
#[test]
fn a_factorisation_on_the_command_line_makes_a_direct_kind() {
    let s = run(
        &[L0, "solver.preset=\"iterative\""],
        &[
            "-ksp_type",
            "preonly",
            "-pc_type",
            "cholesky",
            "-pc_factor_mat_solver_type",
            "mumps",
        ],
    );
    let out = s.run.output();
    assert_eq!(types(&s), ("preonly".into(), "cholesky-mumps-nd".into()));
    assert!(out.contains("newton: condensed:"), "{out}");
    let direct = run(&[L0], &[]);
    assert_eq!(types(&direct).1, "cholesky-mumps-nd");
    let active = |s: &Solved| get(&s.summary, &["contact"])["active_count"].clone();
    assert_eq!(active(&s), active(&direct));
}

/// GMRES + GAMG asked for in the case file over the direct preset is an iterative kind: the
/// plain path (no condensed solve), Krylov iterations in every step.
#[test]
fn amg_in_the_case_options_makes_an_iterative_kind() {
    let s = run(
        &[
            L0,
            "solver.petsc_options=\"-ksp_type gmres -pc_type gamg -ksp_rtol 1e-10\"",
        ],
        &[],
    );
    let out = s.run.output();
    assert_eq!(types(&s), ("gmres".into(), "gamg".into()));
    assert!(!out.contains("newton: condensed:"), "{out}");
}

/// The preset's and the case file's options stay in the solver's own database: PETSc's global
/// one holds the command line alone, and what the solver used of it counts as used.
#[test]
fn the_global_options_database_holds_the_command_line_alone() {
    let s = run(
        &[L0, "solver.petsc_options=\"-ksp_max_it 50\""],
        &["-ksp_type", "preonly", "-options_left"],
    );
    let out = s.run.output();
    assert!(out.contains("There are no unused options."), "{out}");
    assert!(!out.contains("Option left"), "{out}");
}

/// The warnings of `code` in summary.json.
fn warned<'a>(s: &'a Solved, code: &str) -> Vec<&'a serde_json::Value> {
    let list = get(&s.summary, &["warnings"]).as_array().expect("a list");
    list.iter().filter(|w| w["code"] == code).collect()
}

/// An option that nothing reads — misspelt in the case file or on the command line, or meant
/// for a solver the run does not use — is one warning naming it and where it came from; the
/// options the run read are not named. PETSc itself takes such options without a word.
#[test]
fn petsc_options_that_nothing_reads_are_warned_about() {
    let s = run(
        &[
            L0,
            "solver.petsc_options=\"-ksp_rtoll 1e-8 -ksp_type preonly -pc_gamg_threshold 0.1\"",
        ],
        &["-ksp_monitorr", "-pc_type", "cholesky"],
    );
    let out = s.run.output();
    let w = warned(&s, "unused_petsc_options");
    assert_eq!(w.len(), 1, "{out}");
    let message = w[0]["message"].as_str().unwrap();
    assert!(out.contains(&format!("warning: {message}")), "{out}");
    for named in ["-ksp_rtoll", "-pc_gamg_threshold", "-ksp_monitorr"] {
        assert!(message.contains(named), "{message}");
    }
    for read in ["-ksp_type", "-pc_type"] {
        assert!(!message.contains(read), "{message}");
    }
    assert_eq!(w[0]["key"], "solver.petsc_options");
    assert_eq!(w[0]["value"].as_f64(), Some(3.0));
    // options that are all read: no warning
    let quiet = run(
        &[L0, "solver.petsc_options=\"-ksp_type preonly\""],
        &["-pc_type", "cholesky"],
    );
    assert!(
        warned(&quiet, "unused_petsc_options").is_empty(),
        "{}",
        quiet.run.output()
    );
}

/// The user's MUMPS controls reach the project's own MUMPS instances (the condensed path's
/// Schur factorisation and the plain path's factorisations), as PETSc's MUMPS interface takes
/// them: MUMPS' own output (ICNTL(1–4)) appears in the log on both paths; a control that is not
/// a number is refused as input.
#[test]
fn mumps_controls_reach_the_projects_own_factorisations() {
    let verbose = "solver.petsc_options=\"-mat_mumps_icntl_1 6 -mat_mumps_icntl_2 6 \
                   -mat_mumps_icntl_3 6 -mat_mumps_icntl_4 2\"";
    for path in ["\"schur\"", "\"plain\""] {
        let set = format!("solver.path={path}");
        let quiet = run(&[L0, &set], &[]);
        assert!(
            !quiet.run.stdout.contains("Entering DMUMPS"),
            "{}",
            quiet.run.output()
        );
        let s = run(&[L0, &set, verbose], &[]);
        let out = s.run.output();
        assert!(s.run.stdout.contains("Entering DMUMPS"), "{path}: {out}");
        assert!(
            warned(&s, "unused_petsc_options").is_empty(),
            "{path}: {out}"
        );
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let sets = [L0, "solver.petsc_options=\"-mat_mumps_icntl_14 5x\""];
    let cmd = solver_command(2, &hertz(), &sets, &tmp.path().join("out"));
    let r = run_with_timeout(cmd, LIMIT);
    let out = r.output();
    assert_eq!(r.code, Some(2), "{out}");
    assert!(
        out.contains("solver.petsc_options") && out.contains("-mat_mumps_icntl_14"),
        "{out}"
    );
}
