//! Patch test (issue acceptance criterion 1): a linear displacement field u(x) = a + B x,
//! imposed as Dirichlet data on every boundary node of an unstructured mesh, must be
//! reproduced at every interior node to 1e-10, and every cell stress must equal the analytic
//! sigma(B) (Hooke's law written out in the example, independently of the library) to 1e-10
//! relative. 2D plane strain, 2D plane stress and 3D, on 1 and 2 ranks.
//!
//! The work is done by examples/linear_check.rs (`patch` mode) under mpirun: the library is
//! called directly with a closure-built Dirichlet vector (general a, B; not expressible with
//! per-group constants in a case file).

mod common;

use common::*;
use std::path::PathBuf;
use std::time::Duration;

fn run_patch(np: usize, model: &str, meshes: &[PathBuf]) -> Vec<serde_json::Value> {
    let mut args = vec!["patch".to_string(), model.to_string()];
    args.extend(meshes.iter().map(|m| m.display().to_string()));
    let r = run_with_timeout(
        mpirun(np, &example("linear_check"), &args),
        Duration::from_secs(180),
    );
    r.expect_code(0, &format!("linear_check patch {model} on {np} ranks"));
    let rows = json_lines(&r.stdout, "PATCH ");
    assert_eq!(
        rows.len(),
        meshes.len(),
        "one PATCH line per mesh:\n{}",
        r.stdout
    );
    rows
}

fn check(rows: &[serde_json::Value], np: usize, min_interior: u64) {
    for row in rows {
        let f = |k: &str| {
            row[k]
                .as_f64()
                .unwrap_or_else(|| panic!("{k} missing in {row}"))
        };
        let what = format!("{} ({} ranks)", row["mesh"], np);
        assert_eq!(row["ranks"].as_u64(), Some(np as u64), "{what}");
        assert!(
            row["interior_nodes"].as_u64().unwrap() >= min_interior,
            "{what}: too few interior nodes for a meaningful patch test: {row}"
        );
        assert!(f("u_scale") > 0.1, "{what}: {row}");
        assert!(
            f("max_err_interior") <= 1e-10,
            "{what}: interior nodes do not reproduce the linear field: {row}"
        );
        assert!(
            f("max_err_boundary") <= 1e-12,
            "{what}: boundary values not imposed exactly: {row}"
        );
        assert!(f("stress_scale") > 0.01, "{what}: {row}");
        assert!(
            f("max_stress_err") <= 1e-10 * f("stress_scale"),
            "{what}: cell stresses differ from sigma(B): {row}"
        );
    }
}

#[test]
fn patch_2d_plane_strain_1_and_2_ranks() {
    let tmp = tempfile::tempdir().unwrap();
    let meshes = vec![
        unit_mesh(tmp.path(), 2, 0.1),
        mesh_dir().join("square_h0.25.msh"),
        mesh_dir().join("square_h0.25_bin.msh"),
    ];
    for np in [1, 2] {
        check(&run_patch(np, "plane_strain", &meshes), np, 5);
    }
}

#[test]
fn patch_2d_plane_stress_2_ranks() {
    let tmp = tempfile::tempdir().unwrap();
    let meshes = vec![unit_mesh(tmp.path(), 2, 0.1)];
    check(&run_patch(2, "plane_stress", &meshes), 2, 50);
}

#[test]
fn patch_3d_1_and_2_ranks() {
    let tmp = tempfile::tempdir().unwrap();
    let meshes = vec![
        unit_mesh(tmp.path(), 3, 0.15),
        mesh_dir().join("cube_h0.25.msh"),
    ];
    for np in [1, 2] {
        check(&run_patch(np, "3d", &meshes), np, 10);
    }
}
