//! The auto preset falls back on the direct preset where its iterative solve fails: a thin
//! floating plate (1 × 1 × 0.01, one layer of cells) pressed onto a large sphere. GMRES with
//! the multigrid preconditioner needs 170–300 iterations a Newton step there, and the final
//! state's frictionless rows kept tangential forces beyond 1e-6 of the force scale (the
//! certificate: "not a solution", exit 1); the direct preset solves it at once. With the auto
//! preset the run now ends at exit 0 with the direct preset's answer, says so in its log and in
//! summary.json's `preset`, and writes nothing of the failed attempt (driver.rs `falls_back`).

mod common;
use common::*;

#[test]
fn a_thin_plate_that_the_iterative_preset_fails_is_solved_on_the_direct_preset() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mesh = dir.path().join("plate.msh");
    gmsh("thin_plate.geo", 3, 0.02, &mesh);
    let case = write_case(
        &dir.path().join("plate.toml"),
        &format!(
            r#"[mesh]
file = {}
[material]
young = 1.0e3
poisson = 0.3
[[neumann]]
group = "top"
traction = [0.0, 0.0, -1.0]
[contact]
group = "bottom"
obstacle = {{ type = "sphere", center = [0.0, 0.0, -2.5], radius = 2.5 }}
"#,
            toml_path(&mesh)
        ),
    );
    let direct = solve(1, &case, &["solver.preset=\"direct\""]);
    direct.assert_converged("direct preset");
    let auto = solve(2, &case, &[]);
    auto.assert_converged("auto preset, 2 ranks");
    let preset = get(&auto.summary, &["preset"]);
    assert!(
        get(preset, &["asked"]) == "auto" && get(preset, &["used"]) == "direct",
        "preset {preset}"
    );
    let reason = get(preset, &["reason"]).as_str().unwrap_or_default();
    assert!(
        reason.contains("the iterative preset failed"),
        "the reason does not say why: {reason}"
    );
    assert!(
        auto.run
            .stdout
            .contains("the auto preset solves the case again on the direct preset"),
        "no log line:\n{}",
        auto.run.stdout
    );
    // the plate's load (pressure 1 on 1 × 1) is carried by the sphere
    let f = auto.total_force();
    assert!((f[2] - 1.0).abs() <= 1e-9, "contact force {f:?}");
    auto.assert_same_answer(
        &direct,
        1e-9,
        "auto (fallen back) against the direct preset",
    );
}
