//! Two body-pair inputs whose geometry is decided by round-off or by the material:
//! - a master side that reaches 1e-12 into the slave's facets (two meshes' corners meeting to
//!   the last digits): the slave nodes it covers by such a sliver are no contact nodes, so the
//!   answer is the one of the meshes without the sliver, on every rank count (before, such a
//!   node carried a full contact force at a pressure of 1e19, u 2.8e-2 of max |u| away, and on
//!   a 3D pair the answer changed with the rank count: src/contact/mortar/assemble.rs
//!   `SLIVER_COVERAGE`);
//! - a pair between two groups of one body that face each other through its material is refused
//!   (exit 2, the key named) instead of solved as a penetration.

mod common;
use common::process::{gmsh_file, mesh_dir, run_with_timeout, solver, toml_path, write_case};
use common::solved::solve;
use std::path::Path;
use std::time::Duration;

/// The two blocks of tests/meshes/sliver_pair.geo (overhang `d`), the upper one pressed down
/// by its top's Dirichlet data onto the lower one; `pair`: the `[contact]` table's two groups.
fn case(dir: &Path, d: &str, pair: (&str, &str)) -> std::path::PathBuf {
    let mesh = dir.join(format!("sliver_{d}.msh"));
    if !mesh.exists() {
        let args = ["-setnumber", "h", "0.1", "-setnumber", "d", d];
        gmsh_file(&mesh_dir().join("sliver_pair.geo"), 2, &args, &mesh);
    }
    let text = format!(
        r#"[mesh]
file = {}
[[material]]
group = "lower"
young = 1.0
poisson = 0.3
model = "plane_strain"
[[material]]
group = "upper"
young = 2.0
poisson = 0.25
model = "plane_strain"
[[dirichlet]]
group = "lower_bottom"
value = [0.0, 0.0]
[[dirichlet]]
group = "upper_top"
value = [0.0, -0.005]
[contact]
group = "{}"
obstacle = {{ type = "body", group = "{}" }}
[output]
fields = ["displacement", "contact"]
"#,
        toml_path(&mesh),
        pair.0,
        pair.1
    );
    write_case(&dir.join(format!("sliver_{d}_{}.toml", pair.0)), &text)
}

#[test]
fn a_master_side_reaching_a_sliver_into_the_slave_facets_changes_nothing() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let pair = ("lower_top", "upper_bottom");
    let reference = solve(1, &case(tmp.path(), "0", pair), &[]);
    reference.assert_converged("no overhang");
    let p_max = reference.f(&["contact", "max_pressure"]);
    let sliver = case(tmp.path(), "1e-12", pair);
    for np in [1, 2] {
        let what = format!("overhang 1e-12, {np} rank(s)");
        let s = solve(np, &sliver, &[]);
        s.assert_converged(&what);
        s.assert_same_answer(&reference, 1e-9, &what);
        let p = s.f(&["contact", "max_pressure"]);
        assert!(
            (p - p_max).abs() <= 1e-9 * p_max,
            "{what}: p_max {p:e}, without it {p_max:e}"
        );
    }
}

#[test]
fn a_pair_facing_its_own_body_through_the_material_is_refused() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let c = case(tmp.path(), "0", ("lower_top", "lower_bottom"));
    for np in [1, 3] {
        let out = tmp.path().join(format!("out{np}"));
        let args = [
            c.display().to_string(),
            "-o".into(),
            out.display().to_string(),
        ];
        let run = run_with_timeout(solver(np, &args), Duration::from_secs(120));
        run.expect_code(2, &format!("{np} rank(s)"));
        let text = run.output();
        assert!(text.contains("obstacle.group'"), "{np} rank(s): {text}");
        assert!(
            text.contains("through the material"),
            "{np} rank(s): {text}"
        );
        assert_eq!(text.matches("error:").count(), 1, "{np} rank(s): {text}");
        assert!(!out.exists(), "{np} rank(s): output written");
    }
}
