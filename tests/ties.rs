//! Ties of the normal test (3.23): a contact node with (almost) no force at (almost) zero gap
//! keeps its state whatever sign round-off gives its test. A floating plate on a plane, pulled
//! up at one end against its weight, tips onto an edge where such a node sits; before, the
//! dense iteration dropped it in 2 of 8 runs on 3 ranks (its λ_n was −3.8e-15), the plate's
//! rotation about the edge was then free, and the run failed after the plain path's 100
//! steps. (The mechanism itself, deterministically: the unit test
//! `a_node_at_a_tie_keeps_its_state_whatever_the_sign_of_round_off` in src/signorini/dense.rs;
//! the plain path decides ties alike, plain_path/iteration.rs `tie_width`.)

mod common;
use common::*;

#[test]
fn a_plate_tipped_onto_an_edge_is_solved_alike_on_1_2_3_ranks() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mesh = dir.path().join("plate.msh");
    gmsh("tipped_plate.geo", 3, 0.02, &mesh);
    let case = write_case(
        &dir.path().join("plate.toml"),
        &format!(
            r#"[mesh]
file = {}
[material]
young = 1.0e4
poisson = 0.3
[body_force]
value = [0.0, 0.0, -1.0]
[[neumann]]
group = "end"
traction = [0.0, 0.0, 1.5]
[contact]
group = "bottom"
obstacle = {{ type = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}
"#,
            toml_path(&mesh)
        ),
    );
    // the plate's weight 0.3 less the pull 1.5 on its end face (area 0.1)
    let load = 0.3 - 0.15;
    let one = solve(1, &case, &[]);
    one.assert_converged("1 rank");
    let active = one.active_node_ids().len();
    assert!(
        active > 3 && active < 100,
        "{active} nodes in contact: not a plate tipped onto an edge"
    );
    // the plain path: the same ties in its update of the sets (the stop's confirming step
    // dropped an edge node by round-off, the rotation about the edge was then free, and the
    // run failed after its 100 steps on 1 and 2 ranks)
    for np in [1, 2] {
        let what = format!("plain path, {np} rank(s)");
        let s = solve(np, &case, &["solver.path=\"plain\""]);
        s.assert_converged(&what);
        s.assert_same_answer(&one, 1e-9, &what);
    }
    for np in [1, 2, 3] {
        // several runs: the failure was one of round-off, not of the rank count alone
        for run in 0..2 {
            let what = format!("{np} rank(s), run {run}");
            let s = solve(np, &case, &[]);
            s.assert_converged(&what);
            s.assert_same_answer(&one, 1e-9, &what);
            let f = s.total_force();
            assert!(
                (f[2] - load).abs() <= 1e-9 * load,
                "{what}: contact force {f:?}, load {load}"
            );
        }
    }
}
