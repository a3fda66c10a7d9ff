//! The example case files under examples/: every one is a valid case file (the reader accepts
//! it as written), and the 2D ones, whose meshes are committed, run to the end on 2 ranks.

mod common;

use common::*;
use signorini_mpi::case::Case;
use std::path::PathBuf;

fn example_cases() -> Vec<PathBuf> {
    let mut all: Vec<PathBuf> = std::fs::read_dir(repo("examples"))
        .expect("examples/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    all.sort();
    all
}

#[test]
fn every_example_case_file_is_valid() {
    let all = example_cases();
    assert!(all.len() >= 10, "{all:?}");
    for p in &all {
        // the reader alone: some examples' meshes are made by `scripts/mesh examples` (too
        // big to commit), and a fresh clone does not have them (Case::load would say so)
        let text = std::fs::read_to_string(p).expect("example case file");
        let case =
            Case::parse(&text, p, &[], None).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        assert!(
            case.mesh.file.is_absolute(),
            "{}: the mesh path is resolved against the case file",
            p.display()
        );
    }
}

/// The 2D examples (committed meshes) run to the end on 2 ranks: every step converged.
#[test]
fn the_2d_examples_run() {
    for name in [
        "disk_plates.toml",
        "hertz_steps.toml",
        "indent_height2d.toml",
        "indent_punch2d.toml",
        "indent_wedge2d.toml",
    ] {
        let s = solve(2, &repo(&format!("examples/{name}")), &[]);
        if let Some(load) = s.summary.get("load") {
            assert_eq!(load["completed"], true, "{name}: {}", s.run.output());
        } else {
            s.assert_converged(name);
        }
    }
}

/// Copies `from` (a directory of the repository) into `to`, only the files `keep` accepts.
fn copy_tree(
    from: &std::path::Path,
    to: &std::path::Path,
    keep: &dyn Fn(&std::path::Path) -> bool,
) {
    for e in std::fs::read_dir(from).expect("read_dir") {
        let p = e.expect("entry").path();
        let dst = to.join(p.file_name().expect("name"));
        if p.is_dir() {
            if p.file_name()
                .is_some_and(|n| n == "meshes" || n == "__pycache__")
                && !keep(&p)
            {
                continue;
            }
            copy_tree(&p, &dst, keep);
        } else if keep(&p) {
            std::fs::create_dir_all(to).expect("mkdir");
            std::fs::copy(&p, &dst).expect("copy");
        }
    }
}

/// Every example runs from a tree where its mesh is absent: `scripts/run EXAMPLE` makes the mesh
/// (checked with `--check`: the case and the mesh read, nothing solved), or, for the big meshes
/// of `scripts/mesh examples` (the message path, SIGNORINI_NO_MESH=1, kept quick), stops with a
/// message that names that command.
#[test]
fn every_example_makes_its_mesh_or_names_the_command() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let tree = tmp.path().join("clone");
    let all = |_: &std::path::Path| true;
    copy_tree(&repo("scripts"), &tree.join("scripts"), &all);
    copy_tree(&repo("examples"), &tree.join("examples"), &all);
    // the geometry and the mesh scripts, no mesh
    copy_tree(
        &repo("cases"),
        &tree.join("cases"),
        &|p: &std::path::Path| p.extension().is_some_and(|x| x == "geo" || x == "py"),
    );
    let mut made = 0;
    for case in example_cases() {
        let name = case.file_name().unwrap().to_string_lossy().to_string();
        let copy = tree.join("examples").join(&name);
        let text = std::fs::read_to_string(&copy).expect("example");
        let mesh = Case::parse(&text, &copy, &[], None)
            .expect("valid")
            .mesh
            .file;
        // examples share meshes: take away what an example before made
        let _ = std::fs::remove_file(&mesh);
        let mut cmd = std::process::Command::new(tree.join("scripts/mesh"));
        cmd.arg("for").arg(&mesh).arg("--print-command");
        let r = run_with_timeout(cmd, std::time::Duration::from_secs(60));
        r.expect_code(0, &format!("{name}: scripts/mesh knows {}", mesh.display()));
        let big = r.stdout.trim() == "scripts/mesh examples";
        let mut cmd = std::process::Command::new(tree.join("scripts/run"));
        cmd.arg(&copy).args(["-n", "1", "--check"]);
        cmd.env("SIGNORINI_BIN", binary()).current_dir(tmp.path());
        mpi_env(&mut cmd);
        if big {
            cmd.env("SIGNORINI_NO_MESH", "1");
        }
        let r = run_with_timeout(cmd, std::time::Duration::from_secs(300));
        if big {
            assert_eq!(r.code, Some(1), "{name}: {}", r.output());
            assert!(
                r.stderr.contains("make it with 'scripts/mesh examples'"),
                "{name}: {}",
                r.output()
            );
            assert!(!mesh.exists());
        } else {
            r.expect_code(0, &format!("{name}: scripts/run --check"));
            assert!(r.stderr.contains("making it"), "{name}: {}", r.output());
            assert!(r.stdout.contains("is valid"), "{name}: {}", r.output());
            assert!(mesh.exists(), "{name}: the mesh was made");
            made += 1;
        }
    }
    assert!(made >= 5, "{made}");
}
