//! The separate bodies of a mesh: counted the same on every rank count (summary.json's
//! `bodies`); a body that its Dirichlet data leave free in a rigid motion beside another is held
//! by its contact, and refused before the solve where no contact group lies on it.

mod common;
use common::process::{gmsh, run_with_timeout, solver};
use common::solved::solve;
use std::path::Path;
use std::time::Duration;

/// The two squares of tests/meshes/two_squares.geo pressed down on their tops; `held`: the
/// Dirichlet groups (u = 0; a group with a trailing `/x`: u_x = 0 alone); `contact`: the group
/// on the plane y = 0 (`bottom`: both squares' bottoms, `bottom_a`: the first square's).
fn case(dir: &Path, held: &[&str], contact: Option<&str>) -> std::path::PathBuf {
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
    if let Some(g) = contact {
        text += &format!(
            "[contact]\ngroup = \"{g}\"\n\
             obstacle = {{ type = \"plane\", point = [0.0, 0.0], normal = [0.0, 1.0] }}\n"
        );
    }
    text += "[output]\nfields = [\"displacement\", \"contact\"]\n";
    let path = dir.join(format!(
        "two_{}_{}.toml",
        held.join("_").replace('/', ""),
        contact.unwrap_or("none")
    ));
    std::fs::write(&path, text).expect("writing the case");
    path
}

#[test]
fn two_squares_are_two_bodies_on_1_2_3_ranks() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let c = case(tmp.path(), &["left_a", "left_b"], None);
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
fn a_body_not_held_beside_another_is_refused_where_no_contact_group_lies_on_it() {
    let tmp = tempfile::tempdir().expect("tempdir");
    // the second square floats; the contact group is the first square's bottom alone
    let c = case(tmp.path(), &["left_a"], Some("bottom_a"));
    for np in [1, 2] {
        let dir = tmp.path().join(format!("out{np}"));
        let run = refused(np, &c, &dir, "a floating square without a contact group");
        let out = run.output();
        assert!(
            out.contains("2 separate bodies (parts that share no node)")
                && out.contains("no contact group on it"),
            "{out}"
        );
        assert!(
            out.contains("two_squares.msh"),
            "the mesh file named: {out}"
        );
        assert!(
            out.contains("two_left_a_bottom_a.toml") && out.contains("key 'dirichlet'"),
            "the case file and its key named: {out}"
        );
        assert!(!dir.exists(), "no output written: {}", dir.display());
    }
}

#[test]
fn bodies_that_dirichlet_data_leave_free_are_held_by_their_contact() {
    let tmp = tempfile::tempdir().expect("tempdir");
    // the second square floats on the plane (free sideways: pinned), the first is clamped;
    // then each held by u_x = 0 on its left side alone (free up and down, and in rotation)
    for (held, not_held) in [(&["left_a"][..], 1), (&["left_a/x", "left_b/x"][..], 2)] {
        let c = case(tmp.path(), held, Some("bottom"));
        for np in [1, 2] {
            let what = format!("{held:?} on {np} rank(s)");
            let s = solve(np, &c, &[]);
            s.assert_converged(&what);
            assert_eq!(s.summary["bodies"]["not_held"], not_held, "{what}");
            // the loads (0.01 on a unit width each) of the squares that float vertically go
            // through the plane; the clamped square's in part
            let f = s.summary["contact"]["total_force"][1]
                .as_f64()
                .expect("total force");
            match not_held {
                2 => assert!((f - 0.02).abs() < 1e-12, "{what}: total force {f}"),
                _ => assert!(f > 0.01 && f < 0.02, "{what}: total force {f}"),
            }
        }
    }
    // both bodies held, with contact: solved
    let c = case(tmp.path(), &["left_a", "left_b"], Some("bottom"));
    let s = solve(2, &c, &[]);
    assert_eq!(s.summary["bodies"]["not_held"], 0);
}
