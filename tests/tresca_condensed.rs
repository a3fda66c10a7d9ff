//! Tresca (Algorithm 2) on the contact unknowns (src/signorini/mod.rs `run_method`, the Schur
//! path): one factorisation with every dof of every node that has a threshold b_k in the Schur
//! complement (Tresca acts on them in contact or not, (3.18)), the iteration (3.33)/(3.39) on
//! their dense system (schur/coulomb_dense.rs, with Tresca's settled slip rows in 2D), the
//! expanded iterate checked on every contact node. It must end where Algorithm 2 on the whole
//! system (`solver.path = "plain"`) ends: the same contact and slip states node by node and u
//! within 1e-10 of its largest component, on 1, 2 and 3 ranks.

mod common;

use common::process::repo;
use common::solved::{solve, Solved};

/// `s` (on `np` ranks) ends where `plain` ends (module note).
fn ends_where(s: &Solved, plain: &Solved, what: &str) {
    assert_eq!(s.active_node_ids(), plain.active_node_ids(), "{what}");
    assert_eq!(s.slip_node_ids(), plain.slip_node_ids(), "{what}");
    let du = s.u_rel_diff(plain);
    println!("{what}: u against the plain path {du:.1e}");
    assert!(du <= 1e-10, "{what}: u differs by {du:.1e}");
}

/// The case on the Schur path (one factorisation, the dense iteration accepted) on 1, 2 and 3
/// ranks against the plain path on one, which takes more than one factorisation; the run on
/// 3 ranks.
fn condensed_against_plain(case: &str, sets: &[&str]) -> Solved {
    let case = repo(case);
    let mut plain_sets = sets.to_vec();
    plain_sets.push("solver.path=\"plain\"");
    let plain = solve(1, &case, &plain_sets);
    plain.assert_converged("plain path");
    let plain_factorisations = plain.f(&["newton", "factorisations"]);
    assert!(plain_factorisations > 1.0, "{plain_factorisations}");
    assert!(
        !plain.slip_node_ids().is_empty(),
        "the case should have slipping nodes"
    );
    let mut last = None;
    for np in [1, 2, 3] {
        let what = format!("{} on {np} rank(s)", case.display());
        let s = solve(np, &case, sets);
        s.assert_converged(&what);
        let condensed = &s.summary["newton"]["condensed"];
        assert_eq!(s.summary["newton"]["path"], "schur", "{what}");
        assert_eq!(condensed["coulomb"]["outcome"], "condensed", "{what}");
        assert_eq!(s.f(&["newton", "factorisations"]), 1.0, "{what}");
        println!(
            "{what}: {} dense steps, 1 factorisation (the plain path: {plain_factorisations})",
            condensed["coulomb"]["steps"]
        );
        ends_where(&s, &plain, &what);
        last = Some(s);
    }
    last.expect("three runs")
}

const TRESCA: &str = "contact.friction={law=\"tresca\", threshold=5e-3}";
const CONTACT_OUT: &str = "output.fields=[\"displacement\", \"contact\"]";

/// The Hertz disk held at its load arc and pushed down and sideways (the Cattaneo setting):
/// a stick core inside the contact zone, slip bands on either side of it out of contact, then
/// nodes that stick, and slip again at the ends of the arc.
#[test]
fn a_held_disk_ends_where_the_plain_path_ends() {
    condensed_against_plain(
        "cases/bench/friction_disk_held.toml",
        &[TRESCA, CONTACT_OUT, "dirichlet.0.value=[0.001, -0.01]"],
    );
}

/// The floating Hertz disk (cases/hertz/meshes/hertz_L5.msh) under a pressure and a tangential
/// traction that friction alone holds: all but a few contact nodes slip, most of them out of
/// contact; on the way every node slips on its bound and the dense system holds the disk's
/// sideways motion by no row (a step with the free modes pinned).
#[test]
fn a_floating_disk_ends_where_the_plain_path_ends() {
    condensed_against_plain(
        "cases/bench/friction_disk_floating.toml",
        &[
            TRESCA,
            CONTACT_OUT,
            "mesh.file=\"../hertz/meshes/hertz_L5.msh\"",
        ],
    );
}

/// The 2D block of tests/cases/tresca dragged sideways on its whole face (newton.init =
/// "auto").
#[test]
fn a_dragged_block_ends_where_the_plain_path_ends() {
    condensed_against_plain("tests/cases/tresca/block2d_tresca.toml", &[]);
}

/// The 3D block held at its bottom and pushed sideways into a rigid sphere.
const BLOCK: &str = "cases/bench/friction_block_held.toml";

/// The settings of [`BLOCK`] on the block of `cases/blocks/block3d.geo` with tetrahedra of size
/// 0.1 (441 nodes on its top, made in `dir`), Tresca's `threshold` on its top, the contact
/// output.
fn block_sets(dir: &std::path::Path, threshold: f64) -> Vec<String> {
    let mesh = dir.join("block.msh");
    common::process::gmsh_file(
        &repo("cases/blocks/block3d.geo"),
        3,
        &["-setnumber", "h", "0.1"],
        &mesh,
    );
    vec![
        format!("mesh.file=\"{}\"", mesh.display()),
        format!("contact.friction={{law=\"tresca\", threshold={threshold:e}}}"),
        CONTACT_OUT.to_string(),
    ]
}

/// [`BLOCK`] with Tresca's threshold on every node of its top (several hundred: more than the
/// condensed path takes with every dof of each): the candidates by their gaps, the nodes
/// beyond them carrying their friction as a load, found in rounds on the one factorisation
/// (schur/coulomb.rs `Far`).
#[test]
fn a_3d_block_with_far_nodes_ends_where_the_plain_path_ends() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let owned = block_sets(tmp.path(), 2.5e-4);
    let sets: Vec<&str> = owned.iter().map(String::as_str).collect();
    let s = condensed_against_plain(BLOCK, &sets);
    let coulomb = &s.summary["newton"]["condensed"]["coulomb"];
    let far = coulomb["far_nodes"].as_u64().unwrap_or(0);
    let candidates = s.f(&["newton", "condensed", "candidates"]) as u64;
    assert!(far > 0, "nodes beyond the candidates expected: {coulomb}");
    assert!(
        far > candidates,
        "most of the top beyond the candidates: {far} against {candidates}"
    );
    assert!(
        coulomb["far_rounds"].as_u64().unwrap_or(0) >= 2,
        "{coulomb}"
    );
}

/// The same block with a threshold 80 × larger: many nodes beyond the candidates stick, which
/// their friction as a load cannot hold. The condensed solve says so and gives up; the plain
/// path from its own start ends where the plain path alone ends.
#[test]
fn far_nodes_that_stick_leave_the_3d_block_to_the_plain_path() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let owned = block_sets(tmp.path(), 2e-2);
    let sets: Vec<&str> = owned.iter().map(String::as_str).collect();
    let case = repo(BLOCK);
    let s = solve(2, &case, &sets);
    s.assert_converged("far nodes that stick");
    let coulomb = &s.summary["newton"]["condensed"]["coulomb"];
    assert_eq!(coulomb["outcome"], "fallback", "{coulomb}");
    let why = coulomb["reason"].as_str().unwrap_or("");
    assert!(why.contains("stick"), "{why}");
    let mut plain_sets = sets.to_vec();
    plain_sets.push("solver.path=\"plain\"");
    let plain = solve(2, &case, &plain_sets);
    plain.assert_converged("plain path");
    let stick = plain.final_states();
    assert!(
        stick[0] > 0,
        "nodes that stick out of contact expected: {stick:?}"
    );
    ends_where(&s, &plain, "far nodes that stick");
}
