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
