//! Quasi-static load stepping (`[load]`): the section's rejections, one step = the static run,
//! path independence of frictionless contact, linearity of a linear history, the temporal
//! XDMF collection and history.csv, cutback with the converged steps kept, 1 vs 2 ranks.

mod common;

use common::*;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn hertz() -> PathBuf {
    repo("cases/hertz/hertz.toml")
}

/// The small graded Hertz mesh (212 nodes; the contact zone grows from 1 to 3 active nodes
/// between load factors 0.5 and 0.75).
const HERTZ_L2: &str = "mesh.file=meshes/hertz_L2.msh";

/// Reads a load history's output: the times of both temporal collections (solution.xdmf's
/// "mesh", contact.xdmf's "contact") and, per step, the displacement by node id — through the
/// paths the XDMF names (so they must be right) and through meshio's time-series reader on
/// each file as written.
const SERIES_PY: &str = r#"
import sys, os, json
import xml.etree.ElementTree as ET
import h5py, meshio
d = sys.argv[1]
f = h5py.File(os.path.join(d, "solution.h5"), "r")
out = {"collections": {}, "steps": []}
for name, fname in [("mesh", "solution.xdmf"), ("contact", "contact.xdmf")]:
    path = os.path.join(d, fname)
    if not os.path.exists(path):
        continue
    dom = ET.parse(path).getroot().find("Domain")
    gs = dom.findall("Grid")
    assert len(gs) == 1 and gs[0].get("Name") == name, fname
    g = gs[0]
    assert g.get("GridType") == "Collection" and g.get("CollectionType") == "Temporal", g.attrib
    kids = g.findall("Grid")
    out["collections"][name] = [float(k.find("Time").get("Value")) for k in kids]
    if name == "mesh":
        ids = f["mesh/node_id"][:].tolist()
        for k in kids:
            a = [x for x in k.findall("Attribute") if x.get("Name") == "displacement"][0]
            path_u = a.find("DataItem").text.split(":", 1)[1]
            geo = k.find("Geometry").find("DataItem").text.split(":", 1)[1]
            assert geo == "/mesh/geometry", geo
            out["steps"].append({"path": path_u, "u": dict(zip(map(str, ids), f[path_u][:].tolist()))})
    with meshio.xdmf.TimeSeriesReader(path) as r:
        pts, cells = r.read_points_cells()
        times = []
        for k in range(r.num_steps):
            t, pd, cd = r.read_data(k)
            times.append(float(t))
            assert len(pd) > 0 and all(len(v) == len(pts) for v in pd.values()), list(pd)
    out["collections"][name + "_meshio"] = times
print("RESULT " + json.dumps(out))
"#;

/// What a history run wrote.
struct Series {
    times: BTreeMap<String, Vec<f64>>,
    /// Displacement of each step by node id.
    u: Vec<BTreeMap<u64, Vec<f64>>>,
}

fn series(dir: &Path) -> Series {
    let v = python_json(SERIES_PY, &[dir]);
    let times = v["collections"]
        .as_object()
        .expect("collections")
        .iter()
        .map(|(k, t)| (k.clone(), floats(t)))
        .collect();
    let u = v["steps"]
        .as_array()
        .expect("steps")
        .iter()
        .enumerate()
        .map(|(i, s)| {
            assert_eq!(
                s["path"].as_str().unwrap(),
                format!("/step_{}/nodal/displacement", i + 1)
            );
            s["u"]
                .as_object()
                .expect("u")
                .iter()
                .map(|(id, u)| (id.parse().expect("id"), floats(u)))
                .collect()
        })
        .collect();
    Series { times, u }
}

/// history.csv as rows of named cells (empty cells stay empty strings).
fn history(dir: &Path) -> Vec<BTreeMap<String, String>> {
    let text = std::fs::read_to_string(dir.join("history.csv")).expect("history.csv");
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().expect("header").split(',').collect();
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), head.len(), "{l}");
            head.iter()
                .zip(cells)
                .map(|(h, c)| (h.to_string(), c.to_string()))
                .collect()
        })
        .collect()
}

fn num(row: &BTreeMap<String, String>, key: &str) -> f64 {
    row[key]
        .parse()
        .unwrap_or_else(|e| panic!("history {key} = {:?}: {e}", row[key]))
}

/// max |a − b| over all nodes and components, and max |a|.
fn diff(a: &BTreeMap<u64, Vec<f64>>, b: &BTreeMap<u64, Vec<f64>>) -> (f64, f64) {
    assert_eq!(a.len(), b.len());
    let mut d = 0.0f64;
    let mut s = 0.0f64;
    for (id, x) in a {
        for (p, q) in x.iter().zip(&b[id]) {
            d = d.max((p - q).abs());
            s = s.max(p.abs());
        }
    }
    (d, s)
}

#[test]
fn load_section_rejected_with_its_key() {
    for (set, key, says) in [
        ("load.steps=0", "load.steps", "from 1"),
        ("load.factors=[0.5, 0.5]", "load.factors[1]", "equals"),
        ("load.factors=[0.5, -1.0]", "load.factors[1]", "≥ 0"),
        ("load.max_cutbacks=2", "load", "one of 'steps'"),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out");
        let run = run_solver(1, &hertz(), &[HERTZ_L2, set], &out);
        run.expect_code(2, set);
        assert!(
            run.stderr.contains(&format!("key '{key}'")) && run.stderr.contains(says),
            "{set}: {}",
            run.output()
        );
        assert!(!out.exists(), "{set}: nothing written");
    }
    // both keys: the second one is named
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let run = run_solver(
        1,
        &hertz(),
        &[HERTZ_L2, "load.steps=2", "load.factors=[1.0]"],
        &out,
    );
    run.expect_code(2, "steps and factors");
    assert!(run.stderr.contains("not both"), "{}", run.output());
}

#[test]
fn one_step_equals_the_static_run() {
    // The plain path: "auto" decides from wall-clock times, so two runs may differ in round-off.
    let never = "solver.reuse=\"never\"";
    let plain = solve(1, &hertz(), &[HERTZ_L2, never]);
    let one = solve(1, &hertz(), &[HERTZ_L2, never, "load.steps=1"]);
    // the static run writes what it always wrote
    assert!(plain.summary.get("load").is_none());
    assert!(!plain.dir.join("history.csv").exists());
    let u = plain.displacement();
    let s = series(&one.dir);
    assert_eq!(s.times["mesh"], vec![1.0]);
    assert_eq!(s.times["contact"], vec![1.0]);
    let (d, scale) = diff(&s.u[0], &u);
    assert!(
        d <= 1e-14 * scale,
        "steps = 1 vs no [load]: {d:e} (|u| {scale:e})"
    );
    assert_eq!(
        plain.f(&["contact", "max_pressure"]),
        one.f(&["contact", "max_pressure"])
    );
    assert_eq!(plain.steps(), one.steps());
    let steps = get(&one.summary, &["load", "steps"]).as_array().unwrap();
    assert_eq!(steps.len(), 1);
    assert_eq!(
        get(&one.summary, &["load", "completed"]),
        &Value::Bool(true)
    );
    assert_eq!(history(&one.dir).len(), 1);
}

#[test]
fn frictionless_history_ends_where_one_step_does() {
    let one = solve(1, &hertz(), &[HERTZ_L2]);
    let four = solve(1, &hertz(), &[HERTZ_L2, "load.steps=4"]);
    let s = series(&four.dir);
    let want = [0.25, 0.5, 0.75, 1.0];
    for k in ["mesh", "contact", "mesh_meshio", "contact_meshio"] {
        assert_eq!(s.times[k], want, "{k}");
    }
    // frictionless contact is path independent: the last step is the one-step solution
    let (d, scale) = diff(&s.u[3], &one.displacement());
    assert!(d <= 1e-10 * scale, "steps = 4 vs 1: {d:e} (|u| {scale:e})");
    // the steps differ (each is its own load)
    let (d01, _) = diff(&s.u[0], &s.u[3]);
    assert!(d01 > 0.1 * scale, "step 1 vs 4: {d01:e}");
    // history: one row per step, factors increasing; a floating body carries its whole load
    // through the contact, so the contact force scales with the factor
    let h = history(&four.dir);
    assert_eq!(h.len(), 4);
    let f_end = num(&h[3], "force_y");
    assert!(f_end > 0.0, "force_y {f_end}");
    for (i, row) in h.iter().enumerate() {
        assert_eq!(num(row, "factor"), want[i]);
        assert_eq!(num(row, "step") as usize, i + 1);
        let fy = num(row, "force_y");
        assert!(
            (fy - want[i] * f_end).abs() <= 1e-9 * f_end,
            "step {}: force_y {fy} vs {}",
            i + 1,
            want[i] * f_end
        );
        assert!(num(row, "newton_steps") >= 1.0 && num(row, "active") >= 1.0);
        assert!(num(row, "max_pressure") > 0.0);
        assert_eq!(row["stick"], "", "frictionless: no stick count");
    }
    // summary.json lists the same steps; its contact section is the last step's
    let steps = get(&four.summary, &["load", "steps"]).as_array().unwrap();
    assert_eq!(steps.len(), 4);
    assert_eq!(steps[3]["factor"].as_f64(), Some(1.0));
    assert_eq!(
        steps[3]["max_pressure"].as_f64(),
        Some(four.f(&["contact", "max_pressure"]))
    );
    let p1 = one.f(&["contact", "max_pressure"]);
    let p4 = four.f(&["contact", "max_pressure"]);
    assert!(rel(p1, p4) <= 1e-9, "p_max {p1} vs {p4}");
    assert!(four
        .run
        .stdout
        .contains("load step 4/4: factor 1 converged"));
}

/// A plate with a body force, a pressure and a prescribed displacement: every load scales
/// with the factor, so step 1 of 2 is half of step 2, and step 2 is the static solution.
#[test]
fn linear_history_scales_every_load() {
    let plate = repo("cases/plate/plate.toml");
    let sets = [
        "dirichlet.0.value=[0.001, -0.002]",
        "body_force.value=[0.0, -0.01]",
    ];
    let one = solve(1, &plate, &sets);
    let mut two_sets = sets.to_vec();
    two_sets.push("load.steps=2");
    let two = solve(1, &plate, &two_sets);
    let s = series(&two.dir);
    assert_eq!(s.times["mesh"], vec![0.5, 1.0]);
    let (d, scale) = diff(&s.u[1], &one.displacement());
    assert!(d <= 1e-12 * scale, "2 steps vs 1: {d:e} (|u| {scale:e})");
    let half: BTreeMap<u64, Vec<f64>> = s.u[1]
        .iter()
        .map(|(k, v)| (*k, v.iter().map(|x| 0.5 * x).collect()))
        .collect();
    let (d, _) = diff(&s.u[0], &half);
    assert!(d <= 1e-12 * scale, "step 1 vs half of step 2: {d:e}");
    let h = history(&two.dir);
    assert_eq!(h.len(), 2);
    assert_eq!(h[0]["newton_steps"], "", "linear: no Newton steps");
}

/// A pressure held with `ramp = false` while the body force and a prescribed displacement
/// ramp: factor 0 is the pressure alone, factor 1 the static solution; a non-boolean `ramp`
/// is an input error naming the key.
#[test]
fn held_load_does_not_ramp() {
    let plate = repo("cases/plate/plate.toml");
    let ramped = [
        "dirichlet.0.value=[0.001, -0.002]",
        "body_force.value=[0.0, -0.01]",
    ];
    let full = solve(1, &plate, &ramped);
    let alone = solve(1, &plate, &[]);
    let mut sets = ramped.to_vec();
    sets.extend(["neumann.0.ramp=false", "load.factors=[0.0, 1.0]"]);
    let held = solve(1, &plate, &sets);
    let s = series(&held.dir);
    assert_eq!(s.times["mesh"], vec![0.0, 1.0]);
    let (d, scale) = diff(&s.u[0], &alone.displacement());
    assert!(
        scale > 0.0 && d <= 1e-12 * scale,
        "factor 0 vs pressure alone: {d:e}"
    );
    let (d, scale) = diff(&s.u[1], &full.displacement());
    assert!(d <= 1e-12 * scale, "factor 1 vs static: {d:e}");
    let tmp = tempfile::tempdir().unwrap();
    let run = run_solver(
        1,
        &plate,
        &["neumann.0.ramp=\"no\""],
        &tmp.path().join("out"),
    );
    run.expect_code(2, "ramp");
    assert!(
        run.stderr.contains("neumann[0].ramp") || run.stderr.contains("neumann.0.ramp"),
        "{}",
        run.stderr
    );
}

/// Contact driven by a prescribed displacement (the top of a block pushed down): the history
/// ends at the one-step solution.
#[test]
fn prescribed_displacement_history() {
    let block = repo("tests/cases/block2d_pulled.toml");
    let down = "dirichlet.0.value=[0.0, -0.01]";
    let one = solve(1, &block, &[down]);
    let three = solve(1, &block, &[down, "load.steps=3"]);
    let s = series(&three.dir);
    assert_eq!(s.u.len(), 3);
    let (d, scale) = diff(&s.u[2], &one.displacement());
    assert!(scale > 0.0 && d <= 1e-10 * scale, "3 steps vs 1: {d:e}");
    let h = history(&three.dir);
    let f: Vec<f64> = h.iter().map(|r| num(r, "force_y")).collect();
    assert!(f[0] > 0.0 && f[0] < f[1] && f[1] < f[2], "{f:?}");
}

/// A history that takes its load back to nothing (tests/cases/punch_back.toml: the punch back
/// where it started) ends its last step at u = 0 in a few Newton steps on every rank count,
/// on the plain path (every step a factorisation) and on the default one. Its iterate used to
/// shrink by about 200 × per step while round-off flipped the states of the nodes at a zero
/// gap: 37, 14 and 24 plain steps on 1, 2 and 3 ranks, the log's residual down to 1e-157 and
/// NaN.
#[test]
fn a_step_back_to_no_load_ends_at_zero_in_a_few_steps() {
    let case = repo("tests/cases/punch_back.toml");
    for ranks in [1, 2, 3] {
        for plain in [true, false] {
            let sets: &[&str] = if plain {
                &["solver.reuse=\"never\""]
            } else {
                &[]
            };
            let s = solve(ranks, &case, sets);
            let h = history(&s.dir);
            assert_eq!(h.len(), 3, "{ranks} ranks: {} steps", h.len());
            let steps = num(&h[2], "newton_steps");
            assert!(
                steps <= 8.0,
                "{ranks} ranks, plain {plain}: {steps} Newton steps back to no load"
            );
            let series = series(&s.dir);
            let (_, before) = diff(&series.u[1], &series.u[1]);
            let (_, last) = diff(&series.u[2], &series.u[2]);
            assert!(
                before > 0.0 && last <= 1e-9 * before,
                "{ranks} ranks, plain {plain}: max |u| {last:e} at factor 0, {before:e} before"
            );
        }
    }
}

/// A prescribed displacement with `ramp = false` is held at its full value: every step of a
/// history equals the static solution (the only load), on 1 and 2 ranks.
#[test]
fn held_prescribed_displacement() {
    let block = repo("tests/cases/block2d_pulled.toml");
    let down = "dirichlet.0.value=[0.0, -0.01]";
    let one = solve(1, &block, &[down]);
    for np in [1, 2] {
        let held = solve(
            np,
            &block,
            &[down, "dirichlet.0.ramp=false", "load.factors=[0.5, 1.0]"],
        );
        let s = series(&held.dir);
        assert_eq!(s.u.len(), 2);
        for (i, u) in s.u.iter().enumerate() {
            let (d, scale) = diff(u, &one.displacement());
            assert!(
                scale > 0.0 && d <= 1e-10 * scale,
                "{np} ranks, step {}: {d:e}",
                i + 1
            );
        }
    }
}

/// newton.max_steps = 1 converges only where the initial active set (the touching node of
/// the "gap" start) is already right: below factor ~0.5 on this mesh, not at 0.75 or 1. So 1 fails, is cut back
/// to 0.5 (converges), 1 fails again, 0.75 fails with no cutback left: the run fails and
/// keeps the converged step.
#[test]
fn cutback_then_failure_keeps_the_converged_steps() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let sets = [
        HERTZ_L2,
        "newton.max_steps=1",
        "newton.init=\"gap\"",
        "load.factors=[1.0]",
        "load.max_cutbacks=2",
    ];
    let run = run_solver(1, &hertz(), &sets, &out);
    run.expect_code(1, "out of cutbacks");
    let o = run.output();
    assert!(
        run.stdout
            .contains("load step 1: factor 1 failed (Newton did not converge")
            && run.stdout.contains("cut back to 0.5\n")
            && run.stdout.contains("cut back to 0.75\n"),
        "{o}"
    );
    assert!(
        run.stderr
            .contains("load step 1: factor 0.75 did not converge after 2 cutback(s)"),
        "{o}"
    );
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["load"]["completed"], Value::Bool(false));
    assert_eq!(summary["load"]["cutbacks"].as_u64(), Some(2));
    assert!(summary["load"]["failure"]
        .as_str()
        .unwrap()
        .contains("0.75"));
    let h = history(&out);
    assert_eq!(h.len(), 1);
    assert_eq!(num(&h[0], "factor"), 0.5);
    assert_eq!(num(&h[0], "cutbacks"), 1.0);
    assert_eq!(series(&out).times["mesh"], vec![0.5]);

    // without [load] there is no cutback: the run fails as before and writes nothing
    let out2 = tmp.path().join("out2");
    let run = run_solver(1, &hertz(), &[HERTZ_L2, "newton.max_steps=1"], &out2);
    run.expect_code(1, "static run, no convergence");
    assert!(!run.stdout.contains("cut back"), "{}", run.output());
    assert!(!out2.exists());
}

#[test]
fn ranks_agree() {
    // The plain path: "auto" decides from wall-clock times, and a stop on a reuse step costs
    // one confirming step, so under load the step counts of two runs may differ by one.
    let sets = [
        HERTZ_L2,
        "load.factors=[0.4, 1.0, 0.7]",
        "solver.reuse=\"never\"",
    ];
    let a = solve(1, &hertz(), &sets);
    let b = solve(2, &hertz(), &sets);
    let (ha, hb) = (history(&a.dir), history(&b.dir));
    assert_eq!(ha.len(), 3);
    for (ra, rb) in ha.iter().zip(&hb) {
        for k in ["factor", "active", "newton_steps"] {
            assert_eq!(ra[k], rb[k], "{k}");
        }
        for k in ["force_y", "max_pressure"] {
            assert!(rel(num(ra, k), num(rb, k)) <= 1e-9, "{k}: {ra:?} vs {rb:?}");
        }
    }
    let (sa, sb) = (series(&a.dir), series(&b.dir));
    // unloading after 1.0: the XDMF time goes on along the load path (1.0 + 0.3)
    let t = &sa.times["mesh"];
    assert!(
        t.len() == 3 && t[0] == 0.4 && t[1] == 1.0 && (t[2] - 1.3).abs() < 1e-12,
        "{t:?}"
    );
    assert_eq!(num(&ha[2], "factor"), 0.7);
    assert_eq!(num(&ha[2], "time"), t[2]);
    for k in 0..3 {
        let (d, scale) = diff(&sa.u[k], &sb.u[k]);
        assert!(d <= 1e-10 * scale, "step {}: {d:e}", k + 1);
    }
}

/// The disk fills while step 2 is appended (step 1 of the default Hertz case, ~0.9 MB, fits
/// on 1.1 MB beside small previous results; step 2 adds ~0.3 MB): one error, exit 1, the
/// previous results untouched, no staging left — an output failure keeps nothing.
#[test]
fn a_full_disk_during_a_later_step_writes_nothing() {
    let disk = SmallDisk::mount("1100k");
    let out = disk.path.join("out");
    run_solver(1, &repo("cases/blocks/block2d.toml"), &[], &out).expect_code(0, "small run");
    let before = listing(&out);
    for np in [1, 2] {
        let r = run_solver(np, &hertz(), &["load.steps=2"], &out);
        r.expect_code(1, &format!("full disk, {np} rank(s)"));
        assert!(
            r.stdout.contains("load step 1/2: factor 0.5 converged"),
            "{}",
            r.output()
        );
        let what = format!("{np} rank(s)");
        let line = disk.assert_nothing_written(&r, &out, &before, &what);
        assert!(line.contains("cannot write results"), "{line}");
    }
}

/// A Tresca history whose obstacle lifts off in its last step (tests/meshes/mirror_block2d.geo,
/// the circle pressed in and taken back beyond the start): that step's forces vanish against
/// the steps before, and its final check judges it by their scales. On the iterative preset
/// (solves whose residual falls by rtol relative to the warm start's, of the step before's
/// size) the check took the vanishing step's own scale, and the run ended in "the final state
/// is not a solution" (λ_n = 1e-13 against a force scale of 1e-10, exit 1).
#[test]
fn an_obstacle_lifted_off_in_the_last_step_ends_the_history_on_either_preset() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = tmp.path().join("half.msh");
    gmsh("mirror_block2d.geo", 2, 0.08, &mesh);
    let case = write_case(
        &tmp.path().join("lift.toml"),
        &format!(
            "[mesh]\nfile = {}\n[material]\nyoung = 1.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\
             [[dirichlet]]\ngroup = \"bottom\"\nvalue = [0.0, 0.0]\n\
             [[dirichlet]]\ngroup = \"sym\"\nvalue = [0.0, \"free\"]\n\
             [contact]\ngroup = \"top\"\n\
             obstacle = {{ type = \"sphere\", center = [0.0, 2.0], radius = 1.0 }}\n\
             motion = {{ table = [[0.0, 0.0, 0.0], [1.0, 0.0, -0.006], [2.0, 0.0, 0.001]] }}\n\
             friction = {{ law = \"tresca\", threshold = 0.004 }}\n\
             [load]\nfactors = [0.5, 1.0, 1.5, 2.0]\n\
             [output]\nfields = [\"displacement\", \"contact\"]\n",
            toml_path(&mesh)
        ),
    );
    for preset in ["iterative", "direct"] {
        let set = format!("solver.preset=\"{preset}\"");
        let s = solve(2, &case, &[&set]);
        s.assert_converged(preset);
        let steps = s.summary["load"]["steps"].as_array().expect("load.steps");
        assert_eq!(steps.len(), 4, "{preset}: load steps");
        let active = |k: usize| steps[k]["active"].as_u64().expect("active");
        assert!(
            active(1) > 0,
            "{preset}: nothing in contact at the deepest step"
        );
        assert_eq!(active(3), 0, "{preset}: the lifted obstacle still touches");
    }
}

/// Three bodies of tests/meshes/stack3_sym.geo (a half model) on a rigid plane, Coulomb on
/// every pair, the disk's top pressed down and then taken back, without cutbacks: the last
/// step's solution vanishes. Its equilibrium is judged against the step before's reference as
/// its other scales (before, with the factors [1, 0] on 2 and 3 ranks: a residual of 2e-29
/// against its own reference of 1e-28, relative 0.023 and 0.098, the certificate's worst
/// value; with [0.5, 1, 0.5, 0] on 3 ranks 0.098). On 2 ranks with [0.5, 1, 0.5, 0] the
/// condensed Coulomb iteration handed an expanded iterate of 1e-12 to the plain path, whose
/// stopping rule took its floors from that start instead of the load step's warm start: 100
/// Newton steps on a residual of 7e-30, then "Newton did not converge" (exit 1); with that
/// fixed, the last step warned of a contact force pulling at 62 % among forces of 1e-29.
#[test]
fn a_stack_with_friction_taken_back_to_no_load_certifies_its_vanishing_step() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = tmp.path().join("stack3.msh");
    gmsh_file(&mesh_dir().join("stack3_sym.geo"), 2, &[], &mesh);
    let mut text = format!("[mesh]\nfile = {}\n", toml_path(&mesh));
    for (g, e, nu) in [
        ("block", 3.0, 0.25),
        ("plate", 10.0, 0.3),
        ("disk", 1.0, 0.4),
    ] {
        text += &format!(
            "[[material]]\ngroup = \"{g}\"\nyoung = {e:?}\npoisson = {nu:?}\n\
             model = \"plane_strain\"\n"
        );
    }
    text += "[[dirichlet]]\ngroup = \"sym\"\nvalue = [0.0, \"free\"]\n\
             [[dirichlet]]\ngroup = \"disk_top\"\nvalue = [\"free\", -0.005]\n\
             [[contact]]\ngroup = \"block_bottom\"\n\
             obstacle = { type = \"plane\", point = [0.0, 0.0], normal = [0.0, 1.0] }\n\
             friction = { law = \"coulomb\", mu = 0.6 }\n\
             [[contact]]\ngroup = \"plate_bottom\"\n\
             obstacle = { type = \"body\", group = \"block_top\" }\n\
             friction = { law = \"coulomb\", mu = 0.4 }\n\
             [[contact]]\ngroup = \"disk_arc\"\n\
             obstacle = { type = \"body\", group = \"plate_top\" }\n\
             friction = { law = \"coulomb\", mu = 0.3 }\n\
             [load]\nfactors = [0.5, 1.0, 0.5, 0.0]\nmax_cutbacks = 0\n\
             [output]\nfields = [\"displacement\", \"contact\"]\n";
    let case = write_case(&tmp.path().join("stack_back.toml"), &text);
    for ranks in [2, 3] {
        let s = solve(ranks, &case, &[]);
        s.assert_converged(&format!("{ranks} ranks"));
        let h = history(&s.dir);
        assert_eq!(h.len(), 4, "{ranks} ranks: {} steps", h.len());
        // the last step ends by the vanishing rule (not after 100 plain steps, exit 1). Its
        // Newton step count is no measure: the dense Coulomb iteration on its round-off forces
        // either stalls and is accepted (its steps, 72 in one run on 3 ranks, counted) or runs
        // to its limit and hands over to the plain path (4 steps counted), as the round-off of
        // MUMPS' parallel factorisation falls
        let rule = &s.summary["load"]["steps"][3]["certificate"]["stop_rule"];
        assert_eq!(
            rule, "vanishing",
            "{ranks} ranks: the last step's stop rule"
        );
        let worst = s.f(&["certificate", "worst"]);
        assert!(
            worst < 1e-6,
            "{ranks} ranks: the certificate's worst value {worst:e} ({})",
            get(&s.summary, &["certificate", "worst_of"])
        );
        // the vanishing step's forces are round-off: no warning reads their signs
        let warnings = s.summary["warnings"].as_array().expect("warnings");
        assert!(
            !warnings
                .iter()
                .any(|w| w["code"] == "pulling_contact_force"),
            "{ranks} ranks: {warnings:?}"
        );
    }
}
