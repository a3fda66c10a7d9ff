//! Bad output paths, options and command lines are input errors found before the solve (exit
//! code 2, one message naming the case file and the key, the same on 1, 2 and 3 ranks, nothing
//! written) — in `signorini-mpi check` too; an existing output directory is replaced only if it
//! holds this program's results (docs/output.md, "The output directory"). Also `convert`'s
//! output paths (docs/mesh-h5.md), the warning of a nearly incompressible material in
//! summary.json (docs/warnings.md) and clap's errors under mpirun.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The contact case of these tests (a block pressed onto a plane; a second or so).
fn block() -> PathBuf {
    repo("cases/blocks/block2d.toml")
}

/// `signorini-mpi [check] CASE [args]` on `np` ranks (0: without mpirun), in `cwd`.
fn run_in(cwd: &Path, np: usize, check: bool, case: &Path, args: &[&str]) -> Run {
    let mut all: Vec<String> = Vec::new();
    if check {
        all.push("check".into());
    }
    all.push(case.display().to_string());
    all.extend(args.iter().map(|s| s.to_string()));
    let mut cmd = solver(np, &all);
    cmd.current_dir(cwd);
    run_with_timeout(cmd, Duration::from_secs(180))
}

/// The one `error` line of a run that must be refused with exit code 2 before the solve;
/// panics unless there is exactly one and it holds every `expect`.
fn refused(r: &Run, expect: &[&str]) -> String {
    let error = r.the_error_line("refused");
    assert!(
        !r.stdout.contains("newton"),
        "refused before the solve:\n{}",
        r.output()
    );
    for e in expect {
        assert!(error.contains(e), "{e:?} not in {}", error);
    }
    error.to_string()
}

/// `check` and a run on 1, 2 and 3 ranks of `case` with `args` are refused alike, naming
/// `expect`; returns the message.
fn refused_everywhere(cwd: &Path, case: &Path, args: &[&str], expect: &[&str]) -> String {
    let m = refused(&run_in(cwd, 0, true, case, args), expect);
    let mut messages = Vec::new();
    for np in [1, 2, 3] {
        messages.push(refused(&run_in(cwd, np, false, case, args), expect));
    }
    assert!(messages.iter().all(|x| *x == messages[0]), "{messages:#?}");
    m
}

/// A user's own directory with result-file names is neither checked as valid nor replaced.
#[test]
fn a_directory_with_a_summary_of_its_own_is_refused_and_kept() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("r_look");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("summary.json"), "{\"my\": \"precious data\"}\n").unwrap();
    std::fs::write(out.join("history.csv"), "a,b\n").unwrap();
    let before = listing(&out);
    let o = out.display().to_string();
    let m = refused_everywhere(
        tmp.path(),
        &block(),
        &["-o", &o],
        &["block2d.toml", "output.dir", "did not write"],
    );
    println!("{m}");
    assert_eq!(listing(&out), before, "the user's files are kept");
    assert_eq!(file_names(tmp.path()), ["r_look"]);
    // history.csv alone, without a summary of this program
    std::fs::remove_file(out.join("summary.json")).unwrap();
    refused(
        &run_in(tmp.path(), 1, false, &block(), &["-o", &o]),
        &["output.dir", "history.csv"],
    );
    assert_eq!(file_names(&out), ["history.csv"]);
}

#[test]
fn a_directory_named_like_a_result_file_is_refused_and_kept() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("r_sub");
    std::fs::create_dir_all(out.join("solution.h5")).unwrap();
    std::fs::write(out.join("solution.h5/mine.txt"), "user file\n").unwrap();
    let o = out.display().to_string();
    refused_everywhere(
        tmp.path(),
        &block(),
        &["-o", &o],
        &["output.dir", "solution.h5", "not a regular file"],
    );
    assert_eq!(
        std::fs::read_to_string(out.join("solution.h5/mine.txt")).unwrap(),
        "user file\n"
    );
}

/// Results of this program, also of an earlier version (its summary.json with the keys every
/// version wrote), are replaced; the new results are recognised as well.
#[test]
fn results_of_this_program_and_of_earlier_versions_are_replaced() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("old");
    std::fs::create_dir(&out).unwrap();
    let first_version = r#"{"case": "cases/plate/plate.toml", "mesh": "plate.msh",
        "dimension": 2, "model": "PlaneStress", "cells": 10, "nodes": 8, "dofs": 16,
        "ranks": 1, "partition": {"cells_per_rank": [10]}, "timings": {"total": 1.0},
        "peak_memory_bytes_per_rank": [1.0]}"#;
    std::fs::write(out.join("summary.json"), first_version).unwrap();
    std::fs::write(out.join("solution.h5"), "old data").unwrap();
    std::fs::write(out.join("solution.xdmf"), "old grid").unwrap();
    let o = out.display().to_string();
    run_in(tmp.path(), 0, true, &block(), &["-o", &o]).expect_code(0, "check");
    run_in(tmp.path(), 2, false, &block(), &["-o", &o]).expect_code(0, "first run");
    assert!(out.join("contact_nodes.csv").exists());
    run_in(tmp.path(), 1, false, &block(), &["-o", &o]).expect_code(0, "second run");
    assert_eq!(file_names(tmp.path()), ["old"], "nothing left beside it");
}

/// `DIR/.` is DIR (missing or an existing results directory), in `-o` and in output.dir.
#[test]
fn an_output_path_ending_in_dot_is_its_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    for args in [
        vec!["-o", "od/fresh/."],
        vec!["--set", "output.dir=\"od2/fresh2/.\""],
        vec!["-o", "od/fresh/."], // now an existing results directory
    ] {
        run_in(cwd, 0, true, &block(), &args).expect_code(0, "check");
        let r = run_in(cwd, 2, false, &block(), &args);
        r.expect_code(0, &format!("{args:?}"));
    }
    assert!(cwd.join("od/fresh/summary.json").exists());
    assert!(cwd.join("od2/fresh2/summary.json").exists());
    assert_eq!(file_names(&cwd.join("od")), ["fresh"]);
}

/// Paths that cannot be a results directory are refused before the solve, in `check` too.
#[test]
fn a_dangling_link_or_a_path_without_a_name_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    std::os::unix::fs::symlink("/proc/nonexist", cwd.join("dangling")).unwrap();
    refused_everywhere(
        cwd,
        &block(),
        &["-o", "dangling"],
        &["output.dir", "symbolic link", "/proc/nonexist"],
    );
    std::fs::write(cwd.join("afile"), "x").unwrap();
    std::os::unix::fs::symlink("afile", cwd.join("flink")).unwrap();
    refused(
        &run_in(cwd, 1, false, &block(), &["-o", "flink"]),
        &["output.dir", "not a directory"],
    );
    for bad in [".", "sub/..", "/"] {
        refused(
            &run_in(cwd, 1, false, &block(), &["-o", bad]),
            &["output.dir", "no directory of its own"],
        );
    }
    let mut names = file_names(cwd);
    names.sort();
    assert_eq!(names, ["afile", "dangling", "flink"], "nothing written");
}

/// A link to a results directory: the results go there and the link stays.
#[test]
fn a_link_to_a_results_directory_is_followed() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    std::fs::create_dir(cwd.join("real")).unwrap();
    std::os::unix::fs::symlink("real", cwd.join("link")).unwrap();
    for np in [1, 2] {
        run_in(cwd, np, false, &block(), &["-o", "link"]).expect_code(0, "through a link");
        assert!(std::fs::symlink_metadata(cwd.join("link"))
            .unwrap()
            .file_type()
            .is_symlink());
        assert!(cwd.join("real/summary.json").exists());
    }
    assert_eq!(file_names(cwd), ["link", "real"]);
}

/// `convert`: an output that is the input, a directory, an .xdmf name or an unwritable place
/// is exit code 2 and writes nothing.
#[test]
fn convert_refuses_bad_outputs() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let msh = d.join("in.msh");
    std::fs::copy(mesh_dir().join("square_h0.25.msh"), &msh).unwrap();
    let original = std::fs::read(&msh).unwrap();
    std::os::unix::fs::symlink("in.msh", d.join("alias.h5")).unwrap();
    std::fs::create_dir(d.join("adir")).unwrap();
    let convert = |out: &Path| {
        let mut cmd = std::process::Command::new(binary());
        cmd.arg("convert").arg(&msh).arg(out).current_dir(d);
        run_with_timeout(cmd, Duration::from_secs(60))
    };
    for (out, expect) in [
        (msh.clone(), "input mesh"),
        (d.join("./in.msh"), "input mesh"),
        (d.join("alias.h5"), "input mesh"),
        (d.join("adir"), "is a directory"),
        (d.join("mesh.xdmf"), ".xdmf"),
        (PathBuf::from("/proc/x.h5"), "not writable"),
        (d.join("missing/x.h5"), "not an existing directory"),
    ] {
        let r = convert(&out);
        r.expect_code(2, &format!("convert to {}", out.display()));
        assert_eq!(r.stderr.trim().lines().count(), 1, "{}", r.output());
        assert!(r.stderr.contains(expect), "{expect:?}: {}", r.output());
    }
    assert_eq!(std::fs::read(&msh).unwrap(), original, "the input is kept");
    assert_eq!(file_names(d), ["adir", "alias.h5", "in.msh"]);
    assert!(file_names(&d.join("adir")).is_empty());
    convert(&d.join("out.h5")).expect_code(0, "a good output");
}

/// Every `warning:` line has its summary entry: the nearly incompressible material too; each
/// load step's list is there, empty where the step raised none.
#[test]
fn a_nearly_incompressible_material_is_in_the_summary_warnings() {
    let nu = "material.poisson=0.4999";
    for np in [1, 2] {
        let s = solve(np, &block(), &[nu, "load.steps=2"]);
        let lines: Vec<&str> = (s.run.stdout.lines())
            .filter(|l| l.starts_with("warning:"))
            .collect();
        let list = get(&s.summary, &["warnings"]).as_array().unwrap();
        assert_eq!(lines.len(), 1, "{}", s.run.output());
        assert_eq!(list.len(), 1, "{list:#?}");
        let w = &list[0];
        assert_eq!(w["code"], "nearly_incompressible");
        assert_eq!(w["key"], "material.poisson");
        assert_eq!(w["value"].as_f64(), Some(0.4999));
        assert_eq!(w["threshold"].as_f64(), Some(0.49));
        assert!(lines[0].ends_with(w["message"].as_str().unwrap()));
        for st in get(&s.summary, &["load", "steps"]).as_array().unwrap() {
            assert_eq!(st["warnings"], serde_json::json!([]), "{st:#?}");
        }
    }
}

/// Options PETSc refuses, in the case or after `--`: exit code 2 before the solve, one message
/// naming the key (or the command line), the same on every rank count; `check` finds it.
#[test]
fn refused_petsc_options_are_an_input_error() {
    let tmp = tempfile::tempdir().unwrap();
    let o = tmp.path().join("out").display().to_string();
    let set = "solver.petsc_options=\"-ksp_type nonsense\"";
    let m = refused_everywhere(
        tmp.path(),
        &block(),
        &["--set", set, "-o", &o],
        &["block2d.toml", "solver.petsc_options", "nonsense"],
    );
    println!("{m}");
    let m = refused_everywhere(
        tmp.path(),
        &block(),
        &["-o", &o, "--", "-ksp_type", "nonsense"],
        &["block2d.toml", "after --", "nonsense"],
    );
    println!("{m}");
    assert!(file_names(tmp.path()).is_empty(), "nothing written");
    // the command line wins over the case: a good one there makes the case's harmless
    run_in(
        tmp.path(),
        1,
        false,
        &block(),
        &["--set", set, "-o", &o, "--", "-ksp_type", "preonly"],
    )
    .expect_code(0, "overridden");
}

/// clap's errors (and help) under mpirun: printed by rank 0 alone, every rank exits 2.
#[test]
fn command_line_errors_are_printed_once_under_mpirun() {
    let tmp = tempfile::tempdir().unwrap();
    let case = block();
    for np in [2, 3] {
        let r = run_in(tmp.path(), np, false, &case, &["--bogus"]);
        r.expect_code(2, "--bogus");
        let errors = r.stderr.matches("unexpected argument '--bogus'").count();
        assert_eq!(errors, 1, "{}", r.output());
        assert_eq!(r.stderr.matches("Usage:").count(), 1, "{}", r.output());
    }
}
