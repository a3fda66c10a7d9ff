//! The same path on every rank count: the condensed path's frictionless and Coulomb solves of
//! small cases with exact ties (equal gaps: a flat punch, a block on a plane, a mirror-symmetric
//! indentation) on 1, 2 and 3 ranks give the same record in summary.json — per step |A_n|, the
//! nodes that change, the kind of solve; the candidates and the held nodes (by a key of their
//! gmsh tags), the factorisations, the solves, the coarse levels, the outcome and any fallback
//! — and the same final state: the same active (and slipping) nodes by node id, u within 1e-8
//! of max |u| (round-off of the partition is ~1e-13; a different admissible Coulomb state or a
//! different held band would differ by far more).
//!
//! Ties between contact nodes are broken by their gmsh tags, not by c_h's global order (which
//! is rank-major and changes with the partition).

mod common;

use common::*;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// The decisions of a run, from summary.json: everything but timings and values of round-off.
fn record(s: &Solved) -> Value {
    let nw = get(&s.summary, &["newton"]);
    let steps: Vec<Value> = get(nw, &["history"])
        .as_array()
        .expect("history")
        .iter()
        .map(|h| {
            json!({
                "active": h["active"],
                "changed": h["changed"],
                "solve": h["solve"],
                "pinned": h["pinned"],
                "states": h["states"],
            })
        })
        .collect();
    let c = &nw["condensed"];
    let cc = &c["coulomb"];
    json!({
        "steps": nw["steps"],
        "converged": nw["converged"],
        "factorisations": nw["factorisations"],
        "cycle": nw["cycle_detected_at"],
        "history": steps,
        "condensed": {
            "outcome": c["outcome"],
            "fallback_reason": c["fallback_reason"],
            "candidates": c["candidates"],
            "candidates_key": c["candidates_key"],
            "held_nodes": c["held_nodes"],
            "held_key": c["held_key"],
            "factorisations": c["factorisations"],
            "solves": c["solves"],
            "coarse_levels": c["coarse_levels"],
            "primal": c["primal"],
            "too_wide": c["too_wide"],
        },
        "coulomb": {
            "outcome": cc["outcome"],
            "reason": cc["reason"],
            "steps": cc["steps"],
            "primal_steps": cc["primal_steps"],
            "coarse_levels": cc["coarse_levels"],
            "f5_from": cc["f5_from"],
            "f5_coarse_levels": cc["f5_coarse_levels"],
        },
    })
}

/// Solves `case` (`sets`) on 1, 2 and 3 ranks; asserts the same record and final state as on
/// 1 rank, and that the condensed path ran (`want`: the outcome on 1 rank). Returns 1 rank's.
fn same_path(what: &str, case: &Path, sets: &[&str], want: &str) -> Solved {
    let one = solve(1, case, sets);
    one.assert_converged(what);
    let rec = record(&one);
    assert_eq!(
        rec["condensed"]["outcome"],
        want,
        "{what}: {rec:#}\n{}",
        one.run.output()
    );
    let active = one.active_node_ids();
    assert!(!active.is_empty(), "{what}: nothing in contact");
    for np in [2, 3] {
        let other = solve(np, case, sets);
        other.assert_converged(what);
        let r = record(&other);
        assert_eq!(
            rec, r,
            "{what}: the path on {np} ranks differs from 1 rank's:\n1: {rec:#}\n{np}: {r:#}"
        );
        assert_eq!(active, other.active_node_ids(), "{what}: {np} ranks' set");
        assert_eq!(
            one.slip_node_ids(),
            other.slip_node_ids(),
            "{what}: {np} ranks' slip set"
        );
        let d = one.u_rel_diff(&other);
        eprintln!("{what}: {np} ranks vs 1: |Δu| / max|u| = {d:.2e}");
        assert!(d <= 1e-8, "{what}: {np} ranks: |Δu| / max|u| = {d:e}");
    }
    one
}

/// A strip [0, 4] × [0, 0.02] (`top` nodes on its top, 4 layers), clamped at the bottom, its
/// top pressed flat 0.002 deep: every contact node has the same gap.
fn flat_punch(dir: &Path, top: usize) -> PathBuf {
    let mesh = strip_mesh(dir, top);
    write_case(
        &dir.join("punch.toml"),
        &format!(
            "[mesh]\nfile = {}\n[material]\nyoung = 2.0\npoisson = 0.3\n\
             model = \"plane_strain\"\n[[dirichlet]]\ngroup = \"bottom\"\n\
             value = [0.0, 0.0]\n[contact]\ngroup = \"top\"\nobstacle = {{ type = \"plane\", \
             point = [2.0, 0.018], normal = [0.0, -1.0] }}\nfriction = \"none\"\n\
             rigid_modes = \"none\"\n[solver]\npreset = \"direct\"\n\
             [output]\nfields = [\"displacement\", \"contact\"]\n",
            toml_path(&mesh)
        ),
    )
}

#[test]
fn a_flat_punch_holds_the_same_nodes_on_every_rank_count() {
    // 1 201 top nodes, all in contact with the same gap: a zone too wide for the dense
    // compliance, whose interior is held; which nodes form the band (no node lies outside the
    // zone) is a choice among equal gaps.
    let tmp = tempfile::tempdir().unwrap();
    let case = flat_punch(tmp.path(), 1201);
    let one = same_path("flat punch", &case, &[], "condensed");
    assert!(one.f(&["newton", "condensed", "held_nodes"]) > 0.0);
}

fn coulomb(mu: f64) -> String {
    format!("contact.friction={{law=\"coulomb\", mu={mu:e}, algorithm=\"newton\"}}")
}

#[test]
fn a_dragged_block_on_a_plane_takes_the_same_coulomb_path_on_every_rank_count() {
    // block2d on the plane y = 0 (every bottom node at gap 0), pressed and dragged 0.002:
    // stick in the middle, slip at the rim (tests/coulomb.rs, ranks_agree).
    let case = case("block2d_tresca.toml");
    let mu = coulomb(0.3);
    let sets = [mu.as_str(), "dirichlet.0.value=[2e-3, \"free\"]"];
    let one = same_path("dragged block", &case, &sets, "condensed");
    let slip = one.slip_node_ids().len();
    assert!(slip > 0 && slip < one.contact_rows().len(), "{slip} slip");
}

#[test]
fn a_floating_block_that_friction_holds_takes_the_same_path_on_every_rank_count() {
    // A floating block pressed onto the plane and pushed sideways (tests/coulomb.rs'
    // floating case, μ = 0.3): the frictionless start carries the push by a tangential force
    // at the node with the smallest gap, every bottom node's gap being 0.
    let tmp = tempfile::tempdir().unwrap();
    let mesh = repo("cases/blocks/block2d.msh");
    let case = write_case(
        &tmp.path().join("floating.toml"),
        &format!(
            "[mesh]\nfile = {}\n[material]\nyoung = 2.0\npoisson = 0.3\n\
             model = \"plane_strain\"\n[[neumann]]\ngroup = \"top\"\npressure = 0.1\n\
             [[neumann]]\ngroup = \"left\"\ntraction = [0.05, 0.0]\n[contact]\n\
             group = \"bottom\"\nobstacle = {{ type = \"plane\", point = [0.0, 0.0], \
             normal = [0.0, 1.0] }}\nfriction = {{ law = \"coulomb\", mu = 0.3 }}\n\
             [newton]\nc = 1.0\n[output]\nfields = [\"displacement\", \"contact\"]\n",
            toml_path(&mesh)
        ),
    );
    same_path("floating block", &case, &[], "condensed");
}

#[test]
fn a_symmetric_indentation_takes_the_same_path_on_every_rank_count() {
    // The mirror-symmetric 2D indentation (mirrored nodes have equal gaps), frictionless with
    // the nested start, and with Coulomb friction.
    let case = repo("tests/cases/indent2d_sym.toml");
    same_path(
        "symmetric indentation",
        &case,
        &["newton.init=\"auto\""],
        "condensed",
    );
    let mu = coulomb(0.3);
    let sets = [mu.as_str(), "newton.init=\"auto\""];
    same_path("symmetric indentation, Coulomb", &case, &sets, "condensed");
}

#[test]
fn a_flat_punch_in_3d_holds_the_same_nodes_on_every_rank_count() {
    // The block of cases/blocks/block3d.geo (h = 0.06: 1 434 top nodes), clamped at the bottom, its top pressed
    // flat 0.001 deep: every top node has the same gap and starts in contact, a zone too wide
    // for the dense compliance with no node outside it. The ranks split the top face into
    // regions, so c_h's rank-major order is not the order of one rank.
    let tmp = tempfile::tempdir().unwrap();
    let mesh = tmp.path().join("block.msh");
    gmsh_file(
        &repo("cases/blocks/block3d.geo"),
        3,
        &["-setnumber", "h", "0.06"],
        &mesh,
    );
    let case = write_case(
        &tmp.path().join("block.toml"),
        &format!(
            "[mesh]\nfile = {}\n[material]\nyoung = 2.0\npoisson = 0.3\nmodel = \"3d\"\n\
             [[dirichlet]]\ngroup = \"bottom\"\nvalue = [0.0, 0.0, 0.0]\n[contact]\n\
             group = \"top\"\nobstacle = {{ type = \"plane\", point = [0.0, 0.0, 0.499], \
             normal = [0.0, 0.0, -1.0] }}\nfriction = \"none\"\nrigid_modes = \"none\"\n\
             [solver]\npreset = \"direct\"\n[output]\nfields = [\"displacement\", \
             \"contact\"]\n",
            toml_path(&mesh)
        ),
    );
    let one = same_path("3D flat punch", &case, &[], "condensed");
    assert!(one.f(&["newton", "condensed", "held_nodes"]) > 0.0);
}
