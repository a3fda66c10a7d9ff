//! The auto preset for 3D Tresca where its condensed path does not apply: a held block whose
//! whole top (more nodes with a threshold than the condensed path takes) is pushed sideways
//! into a rigid sphere runs on the iterative preset (GMRES + GAMG for every Newton step of the
//! plain path) on 1, 2 and 3 ranks, and ends in the direct preset's contact and slip state on
//! every node, u within the iterative solver's tolerance; asking for the Schur path keeps the
//! direct preset.

mod common;

use common::*;

const TRESCA: &str = r#"contact.friction={law="tresca", threshold=2.5e-4}"#;

#[test]
fn wide_tresca_on_a_held_block_runs_on_the_iterative_preset_with_the_direct_answer() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = tmp.path().join("block.msh");
    // h = 0.08: about 14 000 unknowns (the auto preset's iterative size is 10 000), the top's
    // nodes several hundred (3D Tresca condenses at most 333)
    gmsh_file(
        &repo("cases/blocks/block3d.geo"),
        3,
        &["-setnumber", "h", "0.08"],
        &mesh,
    );
    let case = repo("cases/bench/friction_block_held.toml");
    let file = format!("mesh.file=\"{}\"", mesh.display());
    let auto = [file.as_str(), TRESCA, r#"solver.preset="auto""#];
    let schur = [auto[0], auto[1], auto[2], r#"solver.path="schur""#];
    let direct = solve(2, &case, &schur);
    direct.assert_converged("Tresca, Schur path asked for");
    assert_eq!(
        get(&direct.summary, &["preset", "used"]).as_str(),
        Some("direct"),
        "solver.path = \"schur\" needs the direct preset"
    );
    let states = direct.final_states();
    assert!(
        states[3] > 0 && states[1] > 0,
        "slipping nodes in and out of contact expected: {states:?}"
    );
    let reference = direct.contact_rows_by_id();
    for np in [1, 2, 3] {
        let s = solve(np, &case, &auto);
        let what = format!("Tresca, auto preset, {np} rank(s)");
        s.assert_converged(&what);
        assert_eq!(
            get(&s.summary, &["preset", "used"]).as_str(),
            Some("iterative"),
            "{what}: {}",
            get(&s.summary, &["preset", "reason"])
        );
        let rows = s.contact_rows_by_id();
        assert_eq!(rows.len(), reference.len(), "{what}: contact nodes");
        for (id, r) in &rows {
            let b = &reference[id];
            assert_eq!(r.active(), b.active(), "{what}: node {id} in contact");
            assert_eq!(
                r.tangential(),
                b.tangential(),
                "{what}: node {id} stick/slip"
            );
        }
        // the iterative solves' tolerance, not round-off
        s.assert_same_answer(&direct, 1e-6, &what);
    }
}
