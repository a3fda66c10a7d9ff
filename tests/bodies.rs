//! The separate bodies of a mesh: counted the same on every rank count (summary.json's
//! `bodies`), and a case with contact in which one of several bodies has a rigid motion that
//! its Dirichlet data leave free is refused before the solve.

mod common;
use common::process::{gmsh, run_with_timeout, solver};
use common::solved::solve;
use std::path::Path;
use std::time::Duration;

/// The two squares of tests/meshes/two_squares.geo pressed down on their tops; `held`: the
/// Dirichlet groups (u = 0; a group with a trailing `/x`: u_x = 0 alone); `contact`: their
/// bottoms on the plane y = 0.
fn case(dir: &Path, held: &[&str], contact: bool) -> std::path::PathBuf {
    let mesh = dir.join("two_squares.msh");
    if !mesh.exists() {
        gmsh("two_squares.geo", 2, 0.1, &mesh);
    }
    let mut text = format!(
        "[mesh]\nfile = {:?}\n[material]\nyoung = 1.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\
         [[neumann]]\ngroup = \"top\"\npressure = 0.01\n",
        mesh.display().to_string()
    );
    for g in held {
        let (g, value) = match g.strip_suffix("/x") {
            Some(g) => (g, "[0.0, \"free\"]"),
            None => (*g, "[0.0, 0.0]"),
        };
        text += &format!("[[dirichlet]]\ngroup = \"{g}\"\nvalue = {value}\n");
    }
    if contact {
        text += "[contact]\ngroup = \"bottom\"\n\
                 obstacle = { type = \"plane\", point = [0.0, 0.0], normal = [0.0, 1.0] }\n";
    }
    text += "[output]\nfields = [\"displacement\"]\n";
    let path = dir.join(format!(
        "two_{}_{contact}.toml",
        held.join("_").replace('/', "")
    ));
    std::fs::write(&path, text).expect("writing the case");
    path
}

#[test]
fn two_squares_are_two_bodies_on_1_2_3_ranks() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let c = case(tmp.path(), &["left_a", "left_b"], false);
    for np in 1..=3 {
        let s = solve(np, &c, &[]);
        assert_eq!(
            s.summary["bodies"]["count"],
            2,
            "{np} ranks: {}",
            s.run.output()
        );
        assert_eq!(s.summary["bodies"]["not_held"], 0, "{np} ranks");
        // the log line driver.rs writes for a mesh of several bodies, with the count of those
        // its Dirichlet data leave free: none here (each square clamped on its left side)
        let out = s.run.output();
        assert!(
            out.contains(
                "mesh: 2 separate bodies (parts that share no node), 0 of them with a rigid \
                 motion their Dirichlet data leave free"
            ),
            "{out}"
        );
    }
}

/// Runs `case` on `np` ranks into `dir` and expects the refusal (exit code 2).
fn refused(np: usize, case: &Path, dir: &Path, what: &str) -> common::process::Run {
    let args = [
        case.display().to_string(),
        "-o".into(),
        dir.display().to_string(),
    ];
    let run = run_with_timeout(solver(np, &args), Duration::from_secs(300));
    run.expect_code(2, what);
    run
}

#[test]
fn a_body_not_held_beside_another_is_refused_with_contact() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let c = case(tmp.path(), &["left_a"], true);
    for np in [1, 2] {
        let dir = tmp.path().join(format!("out{np}"));
        let run = refused(
            np,
            &c,
            &dir,
            "two bodies, one without Dirichlet data, with contact",
        );
        let out = run.output();
        assert!(
            out.contains(
                "2 separate bodies (parts that share no node), 1 of them with a rigid motion their Dirichlet data leave free"
            ),
            "{out}"
        );
        assert!(
            out.contains("two_squares.msh"),
            "the mesh file named: {out}"
        );
        assert!(
            out.contains("two_left_a_true.toml") && out.contains("key 'dirichlet'"),
            "the case file and its key named: {out}"
        );
        assert!(!dir.exists(), "no output written: {}", dir.display());
    }
    // each square held by u_x = 0 on its left side alone: their rigid motions up and down
    // (and the rotations) are free, each its own
    let c = case(tmp.path(), &["left_a/x", "left_b/x"], true);
    let run = refused(2, &c, &tmp.path().join("o"), "two bodies held by u_x alone");
    assert!(
        run.output()
            .contains("2 of them with a rigid motion their Dirichlet data leave free"),
        "{}",
        run.output()
    );
    // both bodies held, with contact: solved
    let c = case(tmp.path(), &["left_a", "left_b"], true);
    let s = solve(2, &c, &[]);
    assert_eq!(s.summary["bodies"]["not_held"], 0);
}
