//! The condensed path (issue 9, item 1; signorini::condensed): Algorithm 1 on the contact
//! unknowns, one factorisation, the contact compliance from MUMPS' Schur complement. Its final
//! iterate must be the plain path's (every step a factorisation of (3.29)): the same active
//! nodes, u within 1e-10 of max|u|, on 1, 2 and 3 ranks, for a floating body (Hertz: free rigid
//! modes pinned, balance test), a clamped 3D body under a sphere (normals off the axes, every
//! dof component in C) and a Hertz zone wider than the first candidate set (it must grow). The
//! record: one factorisation per round of candidates, every step "condensed",
//! newton.condensed filled in.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::time::Duration;

fn hertz(level: usize) -> (PathBuf, String) {
    let mesh = repo(&format!("cases/hertz/meshes/hertz_refined_L{level}.msh"));
    (
        repo("cases/hertz/hertz.toml"),
        format!("mesh.file={}", toml_path(&mesh)),
    )
}

/// Solves `case` on the plain path (1 rank) and condensed on `ranks`; checks the answer and
/// the record; returns the condensed runs.
fn same_as_plain(case: &Path, sets: &[&str], ranks: &[usize]) -> Vec<Solved> {
    same_as_plain_env(case, sets, ranks, &[])
}

/// [`same_as_plain`] with the condensed runs' environment `env` (test-only limits).
fn same_as_plain_env(
    case: &Path,
    sets: &[&str],
    ranks: &[usize],
    env: &[(&str, &str)],
) -> Vec<Solved> {
    let with = |m: &str| {
        let mut v: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        v.push(format!("solver.reuse=\"{m}\""));
        v
    };
    let plain_sets = with("never");
    let plain = solve(
        1,
        case,
        &plain_sets.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    plain.assert_converged("plain path");
    assert!(plain.summary["newton"]["condensed"].is_null());
    let mut out = Vec::new();
    for &np in ranks {
        let c_sets = with("condensed");
        let c_sets: Vec<&str> = c_sets.iter().map(String::as_str).collect();
        let c = solve_env(np, case, &c_sets, env, Duration::from_secs(300));
        c.assert_converged("condensed");
        let cs = &c.summary["newton"]["condensed"];
        assert_eq!(cs["outcome"], "condensed", "{}", c.run.output());
        // one factorisation (with the Schur complement) per round of candidates; (that
        // newton.factorisations equals it is how the summary adds the counts up, not checked:
        // that no step factorised on the plain path is the history's "condensed" below)
        let rounds = c.f(&["newton", "condensed", "factorisations"]);
        assert!(rounds >= 1.0);
        let h = c.summary["newton"]["history"].as_array().unwrap();
        assert_eq!(h.len(), c.steps());
        assert!(h.iter().all(|e| e["solve"] == "condensed"), "{h:?}");
        assert!(cs["candidates"].as_u64().unwrap() >= 1);
        assert!(cs["solves"].as_u64().unwrap() >= 3 * rounds as u64);
        assert_eq!(plain.active_node_ids(), c.active_node_ids(), "{np} rank(s)");
        assert!(!c.active_node_ids().is_empty());
        let d = plain.u_rel_diff(&c);
        assert!(
            d <= 1e-10,
            "{} on {np} rank(s): |u - u_plain| / max|u| = {d:e}\n{}",
            case.display(),
            c.run.output()
        );
        out.push(c);
    }
    out
}

#[test]
fn floating_hertz_disk_equals_the_plain_path_on_1_2_3_ranks() {
    let (case, mesh) = hertz(3);
    let runs = same_as_plain(&case, &[&mesh], &[1, 2, 3]);
    for r in &runs {
        assert_eq!(r.f(&["newton", "factorisations"]), 1.0);
    }
    // The dense steps do not depend on the rank count.
    let steps: Vec<usize> = runs.iter().map(|r| r.steps()).collect();
    assert!(steps.iter().all(|&s| s == steps[0]), "{steps:?}");
}

#[test]
fn sphere_on_clamped_block_3d_equals_the_plain_path() {
    same_as_plain(&repo("tests/cases/sphere3d.toml"), &[], &[1, 2]);
}

/// The Hertz L4 disk held at its load arc and pushed down by 0.1 (its contact zone: ~75 of
/// 257 nodes).
fn pushed_hertz() -> (PathBuf, [String; 3]) {
    let (case, mesh) = hertz(4);
    let held = [
        mesh,
        "dirichlet=[{group=\"load\", value=[0.0, -0.1]}]".to_string(),
        "neumann=[]".to_string(),
    ];
    (case, held)
}

#[test]
fn a_wide_contact_zone_grows_the_candidates() {
    // The pushed disk's zone is wider than the first candidate set where the nodes within the
    // Dirichlet data's reach are not taken (the test-only limit REACH_NODES = 0): the 64 nodes
    // with the smallest gaps; so nodes beyond them come into contact on the expanded u and the
    // set must grow (two expansion solves at least).
    let (case, held) = pushed_hertz();
    let held: Vec<&str> = held.iter().map(String::as_str).collect();
    let env = [("SIGNORINI_TEST_LIMIT_REACH_NODES", "0")];
    let runs = same_as_plain_env(&case, &held, &[1, 2], &env);
    for r in &runs {
        let cand = r.f(&["newton", "condensed", "candidates"]);
        let active = r.f(&["contact", "active_count"]);
        assert!(active > 64.0, "zone not wider than the first set: {active}");
        // the first set (64 nodes) grew: by the nodes that came into contact and the doubled
        // count of smallest gaps
        assert!(cand >= 2.0 * 64.0, "candidates {cand}");
        assert!(
            r.run.stdout.contains("come into contact: more candidates"),
            "{}",
            r.run.output()
        );
        assert!(
            r.f(&["newton", "condensed", "factorisations"]) >= 2.0,
            "no growth round\n{}",
            r.run.output()
        );
    }
}

#[test]
fn a_pushed_bodys_zone_within_the_dirichlet_reach_takes_one_factorisation() {
    // The same disk with the nodes whose gap is within the largest prescribed displacement
    // (0.1) taken first: every node of the zone is a candidate of the first factorisation.
    let (case, held) = pushed_hertz();
    let held: Vec<&str> = held.iter().map(String::as_str).collect();
    for r in same_as_plain(&case, &held, &[1, 2]) {
        let cand = r.f(&["newton", "condensed", "candidates"]);
        let active = r.f(&["contact", "active_count"]);
        assert!(
            active > 64.0 && cand >= active,
            "{cand} candidates, {active} active"
        );
        assert!(
            r.run.stdout.contains("Dirichlet data's reach"),
            "{}",
            r.run.output()
        );
        assert!(!r.run.stdout.contains("come into contact: more candidates"));
        assert_eq!(r.f(&["newton", "condensed", "factorisations"]), 1.0);
    }
}

#[test]
fn a_floating_bodys_wide_zone_is_located_before_the_factorisation() {
    // The floating Hertz L4 disk with E / 10: its zone (~96 of 257 nodes) is wider than the
    // eighth of the nodes with the smallest gaps; the half-space model locates it before
    // anything is factorised, the candidates hold it: one factorisation, no growth round.
    let (case, mesh) = hertz(4);
    let runs = same_as_plain(&case, &[&mesh, "material.young=0.2"], &[1, 2]);
    for r in &runs {
        let active = r.f(&["contact", "active_count"]);
        assert!(active > 64.0, "zone not wider than 64 nodes: {active}");
        assert!(
            r.run
                .stdout
                .contains("the contact zone located by the half-space model"),
            "{}",
            r.run.output()
        );
        assert_eq!(r.f(&["newton", "condensed", "factorisations"]), 1.0);
    }
}

#[test]
fn plain_path_stays_selectable() {
    let (case, mesh) = hertz(2);
    let plain = solve(1, &case, &[&mesh, "solver.reuse=\"never\""]);
    plain.assert_converged("plain");
    let h = plain.summary["newton"]["history"].as_array().unwrap();
    assert!(h.iter().all(|e| e["solve"] == "factorisation"));
    assert!(plain.summary["newton"]["condensed"].is_null());
    // (newton.factorisations = steps is how the summary counts a plain run, not checked)
    // its answer is the condensed path's: the same active nodes, u within 1e-10
    let condensed = solve(1, &case, &[&mesh]);
    condensed.assert_converged("condensed");
    assert_eq!(
        condensed.summary["newton"]["condensed"]["outcome"],
        "condensed"
    );
    assert_eq!(plain.active_node_ids(), condensed.active_node_ids());
    let d = plain.u_rel_diff(&condensed);
    assert!(d <= 1e-10, "|u_plain - u_condensed| / max|u| = {d:e}");
}

/// Nodes on the top of the strip of [`strip_case`]: more than the dual form's dense compliance
/// pays for where the factorisation is as cheap as a strip's (n³ = 4.7e10 flops of dense work
/// against ~1e7 for K_p).
const STRIP_TOP_NODES: usize = 3601;

/// A strip [0, 4] × [0, 0.02] (a structured gmsh mesh: `top` nodes on the top, 4 layers,
/// 8 (top − 1) triangles) in `dir`, clamped at the bottom, its top pressed by a rigid plane
/// through (2, 0.02 − 0.002) with the normal `normal` (pointing down, into the strip); `extra`
/// TOML tables appended. Returns the case file.
fn strip_case(dir: &Path, (top, normal): (usize, &str), extra: &str) -> PathBuf {
    let mesh = strip_mesh(dir, top);
    write_case(
        &dir.join("strip.toml"),
        &format!(
            "[mesh]\nfile = {}\n[material]\nyoung = 2.0\npoisson = 0.3\n\
             model = \"plane_strain\"\n[[dirichlet]]\ngroup = \"bottom\"\n\
             value = [0.0, 0.0]\n[contact]\ngroup = \"top\"\nobstacle = {{ type = \"plane\", \
             point = [2.0, 0.018], normal = {normal} }}\nfriction = \"none\"\n\
             rigid_modes = \"none\"\n{extra}[output]\nfields = [\"displacement\"]\n",
            toml_path(&mesh)
        ),
    )
}

/// The strip's answer on the condensed path (`sets`) against the plain path's, on 1 and 2
/// ranks: the same active nodes, u within 1e-10 of max|u|. Returns the condensed runs.
fn strip_against_plain(case: &Path, sets: &[&str]) -> Vec<Solved> {
    let mut plain_sets = sets.to_vec();
    plain_sets.push("solver.reuse=\"never\"");
    let plain = solve(2, case, &plain_sets);
    plain.assert_converged("plain");
    let mut out = Vec::new();
    for np in [1, 2] {
        let r = solve(np, case, sets);
        r.assert_converged("strip");
        assert_eq!(plain.active_node_ids(), r.active_node_ids(), "{np} rank(s)");
        assert!(!r.active_node_ids().is_empty());
        let d = plain.u_rel_diff(&r);
        assert!(
            d <= 1e-10,
            "{np} rank(s): |u - u_plain| / max|u| = {d:e}\n{}",
            r.run.output()
        );
        out.push(r);
    }
    out
}

#[test]
fn a_flat_punch_too_wide_for_the_dense_compliance_holds_the_zones_interior() {
    // The strip's top pressed flat: every node has the same gap and starts active, a zone whose
    // dense compliance would cost far more than the strip's factorisation. Its interior is held
    // on the obstacle in K_p and only an eighth of it is a Schur variable: one factorisation,
    // the plain path's answer.
    let tmp = tempfile::tempdir().unwrap();
    let case = strip_case(tmp.path(), (STRIP_TOP_NODES, "[0.0, -1.0]"), "");
    for r in strip_against_plain(&case, &["solver.preset=\"direct\""]) {
        let nodes = r.f(&["contact", "nodes"]);
        assert_eq!(nodes as usize, STRIP_TOP_NODES);
        let cs = &r.summary["newton"]["condensed"];
        assert_eq!(cs["outcome"], "condensed", "{}", r.run.output());
        assert_eq!(cs["factorisations"], 1, "{cs}");
        let (held, cands) = (
            cs["held_nodes"].as_f64().unwrap(),
            r.f(&["newton", "condensed", "candidates"]),
        );
        assert!(held >= 0.8 * nodes && cands <= 0.2 * nodes, "{cs}");
        // (held + candidates = nodes is how the summary splits the nodes, not checked; the
        // held nodes' state is: every node of the top presses, below)
        assert_eq!(
            r.f(&["contact", "active_count"]),
            nodes,
            "the whole top presses"
        );
    }
}

#[test]
fn a_set_grown_wide_goes_on_with_its_interior_held() {
    // The strip pressed by a slightly tilted plane (every top node 0.001–0.003 inside),
    // started with no active node: the first candidates are the eighth with the smallest
    // gaps; on the expanded u every other node comes into contact, a zone too wide for the
    // dense compliance, so a second pass holds its interior and iterates on its edge.
    let tmp = tempfile::tempdir().unwrap();
    let extra = "[newton]\ninit = \"all_inactive\"\n[solver]\npreset = \"direct\"\n";
    let case = strip_case(tmp.path(), (STRIP_TOP_NODES, "[0.0005, -1.0]"), extra);
    for r in strip_against_plain(&case, &[]) {
        let cs = &r.summary["newton"]["condensed"];
        assert_eq!(cs["outcome"], "condensed", "{}", r.run.output());
        assert_eq!(cs["factorisations"], 2, "{cs}");
        assert!(cs["held_nodes"].as_f64().unwrap() > 0.0, "{cs}");
        assert!(
            r.run.stdout.contains("the predicted zone again"),
            "{}",
            r.run.output()
        );
    }
}

#[test]
fn a_wide_zone_whose_band_exceeds_the_dual_forms_limit_runs_in_the_primal_form() {
    // A strip with 13 001 top nodes pressed by the tilted plane with the default start: every
    // top node penetrates and starts active. Its interior is held; its band (an eighth,
    // 1 626 nodes) would still cost more than the dense work allowed for the strip's cheap
    // factorisation, so the dense steps run on the Schur complement itself: one
    // factorisation, the plain path's answer. (With 8 401 top nodes the band's dual form
    // fits the dense work allowed since 2D may spend 8 × the factorisation's flops.)
    let tmp = tempfile::tempdir().unwrap();
    let extra = "[solver]\npreset = \"direct\"\n";
    let case = strip_case(tmp.path(), (13001, "[0.0005, -1.0]"), extra);
    for r in strip_against_plain(&case, &[]) {
        let cs = &r.summary["newton"]["condensed"];
        assert_eq!(cs["outcome"], "condensed", "{}", r.run.output());
        assert_eq!(cs["primal"], true, "{cs}");
        assert_eq!(cs["factorisations"], 1, "{cs}");
        assert!(cs["held_nodes"].as_f64().unwrap() > 7000.0, "{cs}");
    }
}

#[test]
fn a_floating_strip_whose_zone_the_half_space_model_misses_is_solved_in_passes() {
    // A thin floating strip (4 × 0.1, 3 601 bottom nodes) pressed onto a rigid cylinder of
    // radius 20: it wraps the cylinder over most of its length, while the half-space model
    // (a half-space does not bend) puts a third of it in contact. Each pass starts from the
    // set (3.23) gives on the last expanded u, its interior held: the plain path's answer.
    let tmp = tempfile::tempdir().unwrap();
    let (case, [mesh, load]) = floating_strip_case(tmp.path(), 0.01);
    let sets = ["solver.preset=\"direct\"", mesh.as_str(), load.as_str()];
    let mut runs = strip_against_plain(&case, &sets);
    // and on 3 ranks
    let three = solve(3, &case, &sets);
    three.assert_converged("3 ranks");
    assert_eq!(
        runs[0].active_node_ids(),
        three.active_node_ids(),
        "3 ranks"
    );
    let d = runs[0].u_rel_diff(&three);
    assert!(d <= 1e-10, "3 ranks against 1: {d:e}");
    runs.push(three);
    for r in runs {
        let cs = &r.summary["newton"]["condensed"];
        assert_eq!(cs["outcome"], "condensed", "{}", r.run.output());
        assert!(cs["factorisations"].as_f64().unwrap() >= 2.0, "{cs}");
        assert!(cs["held_nodes"].as_f64().unwrap() > 0.0, "{cs}");
        assert!(
            r.f(&["contact", "active_count"]) > 3000.0,
            "{}",
            r.run.output()
        );
    }
}

#[test]
fn load_steps_on_a_wide_zone_hold_its_interior_in_every_step() {
    // The floating strip on the cylinder pressed in three load steps: the first step holds its
    // wide zone's interior, and each later step holds the interior of the step before's set
    // (its warm start; the kept factorisation only where it held the same nodes) — and ends
    // where the plain path ends, step by step, on 1 and 2 ranks.
    let tmp = tempfile::tempdir().unwrap();
    let (case, [mesh, load]) = floating_strip_case(tmp.path(), 0.01);
    let sets = ["solver.preset=\"direct\"", "load.steps=3", &mesh, &load];
    let plain = solve(1, &case, &[&sets[..], &["solver.reuse=\"never\""]].concat());
    plain.assert_converged("plain path");
    for np in [1, 2] {
        let c = solve(np, &case, &sets);
        c.assert_converged("condensed");
        let held = c.run.stdout.matches("held on the obstacle").count();
        assert!(held >= 3, "{np} rank(s): {}", c.run.output());
        let cs = &c.summary["newton"]["condensed"];
        assert_eq!(cs["outcome"], "condensed", "{cs}");
        assert!(cs["held_nodes"].as_f64().unwrap() > 0.0, "{cs}");
        same_steps(&c, &plain, 3, 1e-10, np);
    }
}

#[test]
fn a_wide_zone_in_3d_holds_its_interior() {
    // The block of cases/blocks/block3d.geo (meshed with h = 0.06: 1 434 top nodes), clamped at
    // the bottom, its top pressed by a slightly tilted plane 0.001 inside it: every top node
    // starts in contact, a zone too wide for the dense compliance, so its interior is held
    // (the distance to its edge in 3D) and about a thousand nodes stay in contact: one
    // factorisation, the plain path's answer on 1 and 2 ranks.
    let tmp = tempfile::tempdir().unwrap();
    let case = pressed_block_case(
        tmp.path(),
        "[0.0, 0.0, 0.499], normal = [0.002, 0.001, -1.0]",
        "",
    );
    for r in strip_against_plain(&case, &[]) {
        let cs = &r.summary["newton"]["condensed"];
        assert_eq!(cs["outcome"], "condensed", "{}", r.run.output());
        assert_eq!(cs["factorisations"], 1, "{cs}");
        let held = cs["held_nodes"].as_f64().unwrap();
        let active = r.f(&["contact", "active_count"]);
        assert!(held > 0.5 * active && active < 1434.0, "{cs}");
    }
}

#[test]
fn load_steps_that_hold_the_same_nodes_reuse_the_held_zones_factorisation() {
    // The block of the test above, its top touched by a level plane that moves 0.003 into it
    // in three load steps: the whole top stays in contact, every step holds the same interior
    // nodes, and K_p with them is the same matrix in every step (the held rows' values are in
    // f). The steps after the first solve on its factorisation (only d₀ is new) and end where
    // the plain path ends, step by step, on 1 and 2 ranks.
    let tmp = tempfile::tempdir().unwrap();
    let plane = "[0.0, 0.0, 0.5], normal = [0.0, 0.0, -1.0]";
    let more = "motion = [0.0, 0.0, -0.003]\n[load]\nsteps = 3\n";
    let case = pressed_block_case(tmp.path(), plane, more);
    let plain = solve(2, &case, &["solver.reuse=\"never\""]);
    plain.assert_converged("plain path");
    for np in [1, 2] {
        let c = solve(np, &case, &[]);
        c.assert_converged("condensed");
        let held = c.run.stdout.matches("held on the obstacle in K_p").count();
        assert!(held >= 3, "{np} rank(s): {}", c.run.output());
        assert_eq!(
            c.kept_factorisations(),
            2,
            "{np} rank(s): {}",
            c.run.output()
        );
        same_steps(&c, &plain, 3, 1e-10, np);
    }
}

/// The block of cases/blocks/block3d.geo meshed into `dir` with h = 0.06 (1 434 top nodes),
/// clamped at the bottom, its top the contact boundary under a rigid plane (`plane`: its point
/// and normal), frictionless, on the direct preset; `more`: further keys of [contact] and
/// further sections.
fn pressed_block_case(dir: &Path, plane: &str, more: &str) -> PathBuf {
    let mesh = dir.join("block.msh");
    gmsh_file(
        &repo("cases/blocks/block3d.geo"),
        3,
        &["-setnumber", "h", "0.06"],
        &mesh,
    );
    write_case(
        &dir.join("block.toml"),
        &format!(
            "[mesh]\nfile = {}\n[material]\nyoung = 2.0\npoisson = 0.3\nmodel = \"3d\"\n\
             [[dirichlet]]\ngroup = \"bottom\"\nvalue = [0.0, 0.0, 0.0]\n[contact]\n\
             group = \"top\"\nobstacle = {{ type = \"plane\", point = {plane} }}\n\
             friction = \"none\"\nrigid_modes = \"none\"\n{more}\
             [solver]\npreset = \"direct\"\n[output]\nfields = [\"displacement\"]\n",
            toml_path(&mesh)
        ),
    )
}

/// The floating strip of cases/strip (4 × 0.1, 3 601 bottom nodes, 8 layers; meshed into
/// `dir`), its top pressed by `pressure` onto a rigid cylinder through (2, −20) of radius 20.
/// Returns the case file and the settings that point it at the mesh and the pressure.
fn floating_strip_case(dir: &Path, pressure: f64) -> (PathBuf, [String; 2]) {
    let mesh = dir.join("strip.msh");
    gmsh_file(&repo("cases/strip/strip.geo"), 2, &[], &mesh);
    (
        repo("cases/strip/strip.toml"),
        [
            format!("mesh.file={}", toml_path(&mesh)),
            format!("neumann.0.pressure={pressure}"),
        ],
    )
}

#[test]
fn a_body_that_starts_inside_the_obstacle_equals_the_plain_path() {
    // Hertz L4 with the plane 0.02 above the disk's lowest point: the nodes of the lowest arc
    // start with negative gaps (the growth of the candidates must not depend on a positive
    // bound); the answer is the plain path's on 1 and 2 ranks.
    let (case, mesh) = hertz(4);
    let p = "contact.obstacle={type=\"plane\",point=[0.0,-0.98],normal=[0.0,1.0]}";
    let runs = same_as_plain(&case, &[&mesh, p], &[1, 2]);
    for r in &runs {
        assert!(r.f(&["contact", "active_count"]) > 1.0);
    }
}

#[test]
fn load_steps_keep_the_factorisation() {
    // The floating Hertz disk pressed in four load steps: K_p (with the pins of its free rigid
    // modes) is the same in every step, so the steps after the first solve on the first step's
    // factorisation and compliance (only d₀ is new) — and end where the plain path ends, step
    // by step, on 1 and 2 ranks.
    let (case, mesh) = hertz(4);
    let plain = solve(1, &case, &[&mesh, "load.steps=4", "solver.reuse=\"never\""]);
    plain.assert_converged("plain path");
    for np in [1, 2] {
        let c = solve(np, &case, &[&mesh, "load.steps=4"]);
        c.assert_converged("condensed");
        let kept = c.kept_factorisations();
        assert_eq!(kept, 3, "{np} rank(s): {}", c.run.output());
        let cs = &c.summary["newton"]["condensed"];
        assert_eq!(cs["factorisation_kept"], true, "{cs}");
        assert_eq!(c.f(&["newton", "factorisations"]), 0.0, "{np} rank(s)");
        same_steps(&c, &plain, 4, 1e-10, np);
    }
}
