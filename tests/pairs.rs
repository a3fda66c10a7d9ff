//! Several contact pairs (`[[contact]]`, docs/obstacles.md "Several contact pairs"): a half
//! disk pressed between two plates, on a mesh that is exactly mirror-symmetric about y = 0
//! (cases/plates/disk_plates.py), against the model of the same problem by its symmetry (the
//! bottom quarter with one pair); force control of one pair and of both against their motions,
//! and of the top plate on a disk that only its plates hold (every path, with friction);
//! load steps; Tresca on one pair next to a frictionless one; a node on two pairs' groups
//! refused.

mod common;

use common::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// The top plate's motion: the disk is squeezed by 0.02 (its centre moves by −0.01).
const SQUEEZE: f64 = 0.02;

/// The half disk (and, with `quarter`, its bottom quarter with the same node ids) in `dir`.
fn disk_mesh(dir: &Path, quarter: bool) -> PathBuf {
    let out = dir.join(if quarter { "quarter.msh" } else { "half.msh" });
    let mut cmd = Command::new(PYTHON);
    cmd.arg(repo("cases/plates/disk_plates.py")).arg(&out);
    if quarter {
        cmd.arg("--quarter");
    }
    run_with_timeout(cmd, Duration::from_secs(120)).expect_code(0, "disk_plates.py");
    out
}

const MATERIAL: &str = "[material]\nyoung = 1.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\n\
                        [[dirichlet]]\ngroup = \"sym\"\nvalue = [0.0, \"free\"]\n\n";

const BOTTOM: &str = "[[contact]]\ngroup = \"bottom\"\n\
                      obstacle = { type = \"plane\", point = [0, -1], normal = [0, 1] }\n";

/// The top plate, moved by `top` (e.g. `motion = [0, -0.02]`).
fn top_pair(top: &str) -> String {
    format!(
        "[[contact]]\ngroup = \"top\"\n\
         obstacle = {{ type = \"plane\", point = [0, 1], normal = [0, -1] }}\n{top}\n"
    )
}

fn write(dir: &Path, name: &str, mesh: &Path, body: &str) -> PathBuf {
    write_case(
        &dir.join(name),
        &format!("[mesh]\nfile = {}\n\n{MATERIAL}{body}", toml_path(mesh)),
    )
}

fn pair(s: &Solved, i: usize) -> &serde_json::Value {
    &get(&s.summary, &["contact", "pairs"])[i]
}

fn pair_force(s: &Solved, i: usize) -> Vec<f64> {
    floats(&pair(s, i)["total_force"])
}

fn pair_active(s: &Solved, i: usize) -> u64 {
    pair(s, i)["active_count"].as_u64().expect("active_count")
}

/// The disk between a fixed bottom plate and a top plate moved down by 0.02 is the mirror
/// image of itself about y = 0 moved by −0.01: its bottom pair is the quarter model with
/// u_y = −0.01 on y = 0 — the same contact force, active set and pressures to round-off, on
/// 1, 2 and 3 ranks; the top pair carries the opposite force.
#[test]
fn two_plates_match_the_symmetric_quarter() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (half, quarter) = (disk_mesh(tmp.path(), false), disk_mesh(tmp.path(), true));
    let q = write(
        tmp.path(),
        "quarter.toml",
        &quarter,
        &format!(
            "[[dirichlet]]\ngroup = \"mid\"\nvalue = [\"free\", {}]\n\n{}",
            -SQUEEZE / 2.0,
            BOTTOM.replace("[[contact]]", "[contact]")
        ),
    );
    let model = solve(1, &q, &[]);
    model.assert_converged("quarter");
    let f_model = model.total_force()[1];
    assert!(f_model > 0.0, "the plate pushes the disk up: {f_model}");
    let p_model: std::collections::BTreeMap<u64, f64> = model
        .contact_rows_by_id()
        .iter()
        .map(|(id, r)| (*id, r.f("pressure")))
        .collect();
    let p_max = p_model.values().fold(0.0f64, |m, p| m.max(*p));
    let both = write(
        tmp.path(),
        "plates.toml",
        &half,
        &format!(
            "{BOTTOM}\n{}",
            top_pair(&format!("motion = [0, {}]", -SQUEEZE))
        ),
    );
    for np in [1, 2, 3] {
        let s = solve(np, &both, &[]);
        s.assert_converged("two plates");
        let (f0, f1) = (pair_force(&s, 0), pair_force(&s, 1));
        assert!(
            rel(f0[1], f_model) <= 1e-9,
            "{np} ranks: {f0:?} vs {f_model}"
        );
        assert!(rel(f1[1], -f_model) <= 1e-9, "{np} ranks: {f1:?}");
        let active = model.active_node_ids().len() as u64;
        assert!(active >= 3, "{active}");
        assert_eq!((pair_active(&s, 0), pair_active(&s, 1)), (active, active));
        assert_eq!(pair(&s, 1)["group"], "top");
        assert_eq!(
            floats(&pair(&s, 1)["obstacle_displacement"]),
            [0.0, -SQUEEZE]
        );
        // contact_nodes.csv: the pair of every node; the bottom pair's pressures are the model's
        let rows = s.contact_rows_by_id();
        assert_eq!(rows.len(), 2 * p_model.len());
        for (id, r) in &rows {
            match (r.s("pair"), p_model.get(id)) {
                ("1", Some(p)) => {
                    assert!((r.f("pressure") - p).abs() <= 1e-9 * p_max, "node {id}")
                }
                ("2", None) => {}
                (other, p) => panic!("node {id}: pair {other}, in the quarter: {p:?}"),
            }
        }
    }
}

/// The bottom plate's motion in the tests of a disk held on its side arc.
const LIFT: f64 = 0.01;

/// The top plate's motion in the tests of a disk held on its side arc.
const PRESS: f64 = 0.015;

/// The half disk held on its side arc (u = 0 there) between the bottom plate, moved or pushed
/// by `bottom` (e.g. `motion = [0, 0.01]`), and the top plate, by `top`.
fn held_disk(bottom: &str, top: &str) -> String {
    format!(
        "[[dirichlet]]\ngroup = \"side\"\nvalue = [0.0, 0.0]\n\n{BOTTOM}{bottom}\n\n{}",
        top_pair(top)
    )
}

/// The held disk with both plates moved (bottom up by LIFT, top down by PRESS), on 1 rank, and
/// each pair's force along y, the force that moves it (the body's force on the obstacle as
/// summary.json reports it).
fn held_disk_moved(dir: &Path, half: &Path) -> (Solved, [f64; 2]) {
    let moved = solve(
        1,
        &write(
            dir,
            "moved.toml",
            half,
            &held_disk(
                &format!("motion = [0, {LIFT}]"),
                &format!("motion = [0, {}]", -PRESS),
            ),
        ),
        &[],
    );
    moved.assert_converged("motions");
    let f = [pair_force(&moved, 0)[1], pair_force(&moved, 1)[1]];
    assert!(f[0] > 0.0 && f[1] < 0.0, "{f:?}");
    (moved, f)
}

/// The held disk with both plates under force control: the forces `f` along y.
fn held_disk_forced(f: [f64; 2]) -> String {
    held_disk(
        &format!("force = [0, {:.17e}]", f[0]),
        &format!("force = [0, {:.17e}]", f[1]),
    )
}

/// Force control on both pairs: the disk held on its side arc, the bottom plate under the force
/// that its motion up by LIFT takes and the top plate under the force that its motion down by
/// PRESS takes (both moved together): each pair's approach δ_j gives back its motion, and u,
/// the forces and the active set are the motions' solution — on the condensed path, the plain
/// path and the iterative preset (with the half-space predictor), on 1 to 3 ranks.
#[test]
fn force_on_two_pairs_returns_their_motions() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let half = disk_mesh(tmp.path(), false);
    let (moved, f) = held_disk_moved(tmp.path(), &half);
    let forced = write(tmp.path(), "forced.toml", &half, &held_disk_forced(f));
    let runs: [(usize, &[&str]); 6] = [
        (1, &["solver.preset=\"direct\""]),
        (2, &["solver.preset=\"direct\""]),
        (1, &["solver.preset=\"direct\"", "solver.reuse=\"never\""]),
        (3, &["solver.preset=\"direct\"", "solver.reuse=\"never\""]),
        (1, &["solver.preset=\"iterative\""]),
        (2, &["solver.preset=\"iterative\""]),
    ];
    for (np, sets) in runs {
        let s = solve(np, &forced, sets);
        s.assert_converged("force control on two pairs");
        let delta = [0, 1].map(|i| pair(&s, i)["approach"].as_f64().expect("approach"));
        eprintln!(
            "{np} ranks {sets:?}: {} steps, δ = {delta:?} (motions {LIFT}, {PRESS})",
            s.steps()
        );
        for (d, want) in delta.iter().zip([LIFT, PRESS]) {
            assert!(
                (d - want).abs() <= 1e-8 * want,
                "{np} {sets:?}: δ = {delta:?}"
            );
        }
        // each obstacle moved along its force: the bottom one up, the top one down
        let moved_by = |i: usize| floats(&pair(&s, i)["obstacle_displacement"]);
        assert!(rel(moved_by(0)[1], LIFT) <= 1e-8 && moved_by(0)[0] == 0.0);
        assert!(rel(moved_by(1)[1], -PRESS) <= 1e-8 && moved_by(1)[0] == 0.0);
        // one approach per pair: none for the section as a whole
        assert!(get(&s.summary, &["contact"]).get("approach").is_none());
        for i in [0, 1] {
            let (a, b) = (pair_force(&s, i)[1], f[i]);
            assert!(rel(a, b) <= 1e-8, "{np} {sets:?}: pair {i}: {a} vs {b}");
        }
        assert!(s.u_rel_diff(&moved) <= 1e-8, "{np} {sets:?}");
        assert_eq!(
            s.active_node_ids(),
            moved.active_node_ids(),
            "{np} {sets:?}"
        );
        assert!(pair_active(&s, 0) >= 3 && pair_active(&s, 1) >= 3);
    }
}

/// Force control on both pairs with the bottom plate 0.002 below the disk: its approach is
/// LIFT + 0.002 and the solution the motions' — on the plain path the first step has active
/// nodes on the top pair only, so the top pair takes its bordered step while the bottom plate
/// moves until its first node touches (said in the log); also condensed and iterative, 2 ranks.
#[test]
fn force_on_two_pairs_from_a_gap() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let half = disk_mesh(tmp.path(), false);
    let (moved, f) = held_disk_moved(tmp.path(), &half);
    let gap = 0.002;
    let text =
        held_disk_forced(f).replace("point = [0, -1]", &format!("point = [0, {}]", -1.0 - gap));
    assert!(text.contains("-1.002"), "{text}");
    let forced = write(tmp.path(), "gap.toml", &half, &text);
    for sets in [
        &[][..],
        &["solver.reuse=\"never\""][..],
        &["solver.preset=\"iterative\""][..],
    ] {
        let s = solve(2, &forced, sets);
        s.assert_converged("force control on two pairs from a gap");
        let delta = [0, 1].map(|i| pair(&s, i)["approach"].as_f64().expect("approach"));
        for (d, want) in delta.iter().zip([LIFT + gap, PRESS]) {
            assert!((d - want).abs() <= 1e-8 * want, "{sets:?}: δ = {delta:?}");
        }
        assert!(s.u_rel_diff(&moved) <= 1e-8, "{sets:?}");
        assert_eq!(s.active_node_ids(), moved.active_node_ids(), "{sets:?}");
        if sets.is_empty() {
            continue;
        }
        let log = s.run.output();
        let first: Vec<&str> = log
            .lines()
            .filter(|l| l.starts_with("force control (contact[") && l.contains(", step 1:"))
            .collect();
        assert_eq!(first.len(), 2, "{log}");
        assert!(
            first[0].contains("contact[0].force") && first[0].contains("touches"),
            "{first:?}"
        );
    }
}

/// Force control on both pairs through load steps: each step's forces are t·F_j
/// (history.csv's `pairp_force_y`); the last step gives back the motions whose forces F_j are;
/// the middle step's approaches, prescribed as motions, take the middle step's forces.
#[test]
fn force_on_two_pairs_through_load_steps() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let half = disk_mesh(tmp.path(), false);
    let (moved, f) = held_disk_moved(tmp.path(), &half);
    let case = write(
        tmp.path(),
        "steps.toml",
        &half,
        &format!("{}\n[load]\nfactors = [0.5, 1.0]\n", held_disk_forced(f)),
    );
    for sets in [&[][..], &["solver.reuse=\"never\""][..]] {
        let s = solve(2, &case, sets);
        s.assert_converged("force control in load steps");
        let rows = read_csv(&s.dir.join("history.csv"));
        assert_eq!(rows.len(), 2);
        for (r, t) in rows.iter().zip([0.5, 1.0]) {
            for (p, fp) in [(1, f[0]), (2, f[1])] {
                let fy = r.f(&format!("pair{p}_force_y"));
                assert!(rel(fy, t * fp) <= 1e-8, "{sets:?} t = {t}: pair {p}: {fy}");
            }
        }
        let obstacle = |r: &Row| [r.f("pair1_obstacle_y"), r.f("pair2_obstacle_y")];
        let (mid, last) = (obstacle(&rows[0]), obstacle(&rows[1]));
        assert!(
            rel(last[0], LIFT) <= 1e-8 && rel(last[1], -PRESS) <= 1e-8,
            "{last:?}"
        );
        assert!(0.0 < mid[0] && mid[0] < last[0], "{mid:?} {last:?}");
        assert!(last[1] < mid[1] && mid[1] < 0.0, "{mid:?} {last:?}");
        let (u_last, u_moved) = (step_displacement(&s.dir, 2), moved.displacement());
        let scale = u_moved
            .values()
            .flatten()
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let (diff, _) = max_diff(&u_last, &u_moved);
        assert!(
            scale > 0.0 && diff <= 1e-8 * scale,
            "{sets:?}: {diff} of {scale}"
        );
        // the middle step as a displacement-controlled solve
        let m = solve(
            1,
            &write(
                tmp.path(),
                "mid.toml",
                &half,
                &held_disk(
                    &format!("motion = [0, {:.17e}]", mid[0]),
                    &format!("motion = [0, {:.17e}]", mid[1]),
                ),
            ),
            &[],
        );
        m.assert_converged("the middle step's motions");
        for i in [0, 1] {
            let a = pair_force(&m, i)[1];
            assert!(
                rel(a, 0.5 * f[i]) <= 1e-8,
                "{sets:?}: pair {i}: {a} vs {}",
                0.5 * f[i]
            );
        }
    }
}

/// Tresca friction on both plates of the held disk, the top plate moved along a slanted
/// direction (its tangential part drags the stick nodes): prescribing each pair's force
/// component along its motion's direction gives back both motions as approaches, u, the active
/// and the slip nodes (Algorithm 2 on the plain path: 1 rank direct, 2 ranks iterative).
#[test]
fn tresca_force_on_two_pairs_returns_their_motions() {
    let tresca = "friction = { law = \"tresca\", threshold = 0.03 }\n";
    let runs: [(usize, &[&str]); 2] = [
        (1, &["solver.preset=\"direct\""]),
        (2, &["solver.preset=\"iterative\""]),
    ];
    friction_force_on_two_pairs(tresca, &runs);
}

/// Coulomb friction (μ = 0.3, the generalised Newton) on both plates of the held disk, as the
/// Tresca test: both pairs' forces prescribed give back both motions as approaches (1e-8), u,
/// the active and the slip nodes — the plain path from the frictionless force-controlled
/// solution on 1, 2 and 3 ranks (direct preset), and the iterative preset on 2.
#[test]
fn coulomb_force_on_two_pairs_returns_their_motions() {
    let coulomb = "friction = { law = \"coulomb\", mu = 0.3 }\n";
    let runs: [(usize, &[&str]); 4] = [
        (1, &["solver.preset=\"direct\""]),
        (2, &["solver.preset=\"direct\""]),
        (3, &["solver.preset=\"direct\""]),
        (2, &["solver.preset=\"iterative\""]),
    ];
    friction_force_on_two_pairs(coulomb, &runs);
}

/// Both plates of the held disk with `friction`, the top plate moved along a slanted direction,
/// then each pair's force component along its motion's direction prescribed on the `runs`:
/// the motions as approaches (1e-8), u (1e-8), the active and the slip nodes (some slip, some
/// stick).
fn friction_force_on_two_pairs(friction: &str, runs: &[(usize, &[&str])]) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let half = disk_mesh(tmp.path(), false);
    let motions = [[0.0, LIFT], [0.004, -PRESS]];
    let vector = |v: [f64; 2]| format!("[{:.17e}, {:.17e}]", v[0], v[1]);
    let moved = solve(
        1,
        &write(
            tmp.path(),
            "moved.toml",
            &half,
            &held_disk(
                &format!("motion = {}\n{friction}", vector(motions[0])),
                &format!("motion = {}\n{friction}", vector(motions[1])),
            ),
        ),
        &[],
    );
    moved.assert_converged("motions with friction");
    // the force along each motion's direction e_j, prescribed along e_j
    let length = motions.map(|m| m[0].hypot(m[1]));
    let dirs = [0, 1].map(|i| motions[i].map(|x| x / length[i]));
    let along_e = |s: &Solved, i: usize| {
        let f = pair_force(s, i);
        f[0] * dirs[i][0] + f[1] * dirs[i][1]
    };
    let along = [0, 1].map(|i| along_e(&moved, i));
    let forces = [0, 1].map(|i| dirs[i].map(|x| along[i] * x));
    let (slip, active) = (moved.slip_node_ids().len(), moved.active_node_ids().len());
    eprintln!("motions: slip {slip} of {active} active");
    assert!(slip > 0 && active > slip, "slip {slip} of {active} active");
    let forced = write(
        tmp.path(),
        "forced.toml",
        &half,
        &held_disk(
            &format!("force = {}\n{friction}", vector(forces[0])),
            &format!("force = {}\n{friction}", vector(forces[1])),
        ),
    );
    for &(np, sets) in runs {
        let s = solve(np, &forced, sets);
        s.assert_converged("force control on two pairs with friction");
        let delta = [0, 1].map(|i| pair(&s, i)["approach"].as_f64().expect("approach"));
        eprintln!(
            "{np} ranks {sets:?}: {} steps (motions: {}), δ = {delta:?} (|m| = {length:?})",
            s.steps(),
            moved.steps()
        );
        for (d, want) in delta.iter().zip(length) {
            assert!(
                (d - want).abs() <= 1e-8 * want,
                "{np} {sets:?}: δ = {delta:?}"
            );
        }
        for (i, want) in along.iter().enumerate() {
            let p = along_e(&s, i);
            assert!(
                (p - want).abs() <= 1e-9 * want.abs(),
                "{np} {sets:?}: pair {i}'s force along its e {p}, prescribed {want}"
            );
        }
        assert!(s.u_rel_diff(&moved) <= 1e-8, "{np} {sets:?}");
        assert_eq!(s.active_node_ids(), moved.active_node_ids());
        assert_eq!(s.slip_node_ids(), moved.slip_node_ids(), "{np} {sets:?}");
    }
}

/// Force control on every pair of a body that only its pairs hold (the disk without its side
/// arc held): the forces do not fix the disk's position, and the run is refused with exit code
/// 2 naming the first pair's force, on the condensed and the plain path; a force on the second
/// pair that pulls its obstacle away from the body is refused naming that pair's force.
#[test]
fn force_on_every_pair_of_a_floating_body_is_refused() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let half = disk_mesh(tmp.path(), false);
    let floating = write(
        tmp.path(),
        "floating.toml",
        &half,
        &format!(
            "{BOTTOM}force = [0, 0.001]\n\n{}",
            top_pair("force = [0, -0.001]")
        ),
    );
    for sets in [&[][..], &["solver.reuse=\"never\""][..]] {
        let out = tmp.path().join("refused");
        let run = run_solver(2, &floating, sets, &out);
        run.expect_code(2, "force control on every pair of a floating body");
        let text = run.output();
        assert!(
            text.contains("contact[0].force") && text.contains("every contact pair"),
            "{sets:?}: {text}"
        );
        assert!(!out.join("summary.json").exists());
    }
    let away = write(
        tmp.path(),
        "away.toml",
        &half,
        &held_disk("force = [0, 0.001]", "force = [0, 0.001]"),
    );
    for sets in [&[][..], &["solver.reuse=\"never\""][..]] {
        let out = tmp.path().join("away");
        let run = run_solver(1, &away, sets, &out);
        run.expect_code(2, "a force that pulls the obstacle away");
        let text = run.output();
        assert!(
            text.contains("contact[1].force") && text.contains("never reaches the body"),
            "{sets:?}: {text}"
        );
    }
}

/// The same squeeze of a disk held on its side arc: the top plate under the force that its
/// motion of 0.015 takes gives back the motion (δ) and the solution, on the condensed path,
/// the plain path and the iterative preset, on 1 to 3 ranks; the bottom pair's force and
/// motion stay.
#[test]
fn force_on_one_pair_returns_its_motion() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let half = disk_mesh(tmp.path(), false);
    let body = |top: &str| held_disk(&format!("motion = [0, {LIFT}]"), top);
    let moved = solve(
        1,
        &write(
            tmp.path(),
            "moved.toml",
            &half,
            &body(&format!("motion = [0, {}]", -PRESS)),
        ),
        &[],
    );
    moved.assert_converged("motion");
    let f = pair_force(&moved, 1);
    assert!(f[1] < 0.0, "{f:?}");
    let forced = write(
        tmp.path(),
        "forced.toml",
        &half,
        &body(&format!("force = [0, {:.17e}]", f[1])),
    );
    let runs: [(usize, &[&str]); 4] = [
        (1, &["solver.preset=\"direct\""]),
        (3, &["solver.preset=\"direct\""]),
        (2, &["solver.preset=\"direct\"", "solver.reuse=\"never\""]),
        (2, &["solver.preset=\"iterative\""]),
    ];
    for (np, sets) in runs {
        let s = solve(np, &forced, sets);
        s.assert_converged("force control");
        let delta = s.f(&["contact", "approach"]);
        assert!(
            (delta - 0.015).abs() <= 1e-8 * 0.015,
            "{np} {sets:?}: δ = {delta}"
        );
        assert_eq!(pair(&s, 1)["approach"].as_f64(), Some(delta));
        assert!(pair(&s, 0).get("approach").is_none());
        assert!(rel(pair_force(&s, 0)[1], pair_force(&moved, 0)[1]) <= 1e-8);
        assert!(s.u_rel_diff(&moved) <= 1e-8, "{np} {sets:?}");
        assert_eq!(
            s.active_node_ids(),
            moved.active_node_ids(),
            "{np} {sets:?}"
        );
    }
}

/// Load steps move each pair's obstacle with the factor; history.csv has every pair's columns.
#[test]
fn pairs_through_load_steps() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let half = disk_mesh(tmp.path(), false);
    let case = write(
        tmp.path(),
        "steps.toml",
        &half,
        &format!(
            "{BOTTOM}\n{}\n[load]\nfactors = [0.5, 1.0]\n",
            top_pair(&format!("motion = [0, {}]", -SQUEEZE))
        ),
    );
    let s = solve(2, &case, &[]);
    let rows = read_csv(&s.dir.join("history.csv"));
    assert_eq!(rows.len(), 2);
    for (r, t) in rows.iter().zip([0.5, 1.0]) {
        assert_eq!(r.f("pair2_obstacle_y"), -SQUEEZE * t);
        assert_eq!(r.f("pair1_obstacle_y"), 0.0);
        let (f1, f2) = (r.f("pair1_force_y"), r.f("pair2_force_y"));
        assert!(f1 > 0.0 && rel(f1, -f2) <= 1e-9, "{f1} {f2}");
        assert!(r.f("pair1_active") >= 1.0 && r.f("pair1_half_width") > 0.0);
    }
    // the second step presses harder
    assert!(rows[1].f("pair1_force_y") > rows[0].f("pair1_force_y"));
    // scripts/plot-history: one curve, of the moving pair, named by its group
    let png = s.dir.join("curve.png");
    let mut cmd = Command::new(repo("scripts/plot-history"));
    cmd.arg(&s.dir).arg("--out").arg(&png);
    let r = run_with_timeout(cmd, Duration::from_secs(120));
    r.expect_code(0, "plot-history");
    assert!(r.stdout.contains("pair 2 (top)"), "{}", r.stdout);
    assert!(!r.stdout.contains("pair 1"), "{}", r.stdout);
    assert!(png.metadata().is_ok_and(|m| m.len() > 1000));
}

/// The half disk with `friction` on its bottom pair, the top plate frictionless and moved down
/// by the squeeze, on 2 ranks: the run, its contact rows by node id and the largest |λ_n|.
fn friction_under_the_disk(friction: &str) -> (Solved, BTreeMap<u64, Row>, f64) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let half = disk_mesh(tmp.path(), false);
    let case = write(
        tmp.path(),
        "friction.toml",
        &half,
        &format!(
            "{BOTTOM}{friction}\n\n{}",
            top_pair(&format!("motion = [0, {}]", -SQUEEZE))
        ),
    );
    let s = solve(2, &case, &[]);
    s.assert_converged(friction);
    let rows = s.contact_rows_by_id();
    let scale = rows
        .values()
        .map(|r| r.f("lambda_n").abs())
        .fold(0.0, f64::max);
    (s, rows, scale)
}

/// Tresca on the bottom pair, frictionless on the top one: the top pair's nodes have no
/// tangential force (to round-off) and no friction bound; the bottom pair's respect theirs.
#[test]
fn tresca_next_to_a_frictionless_pair() {
    let g = 0.01;
    let (_, rows, scale) = friction_under_the_disk(&format!(
        "friction = {{ law = \"tresca\", threshold = {g} }}"
    ));
    let (mut stuck_or_slipping, mut top) = (0, 0);
    for r in rows.values() {
        let lt = r.lambda_t(2)[0].abs();
        if r.s("pair") == "2" {
            top += 1;
            // λ_τ recovered from f − A u (3.28): zero to round-off of the normal forces
            assert!(
                lt <= 1e-12 * scale && r.bound() == 0.0,
                "{lt} {}",
                r.bound()
            );
        } else {
            assert!(lt <= r.bound() * (1.0 + 1e-9), "{lt} > {}", r.bound());
            assert!((r.bound() - g * r.f("weight")).abs() <= 1e-12 * g);
            if r.active() && lt > 0.0 {
                stuck_or_slipping += 1;
            }
        }
    }
    assert!(
        top > 0 && stuck_or_slipping > 0,
        "{top} {stuck_or_slipping}"
    );
}

/// The side arc shares its end nodes with the top arc: contact on both is refused, naming the
/// second pair's group, with exit code 2 and nothing written.
#[test]
fn a_node_on_two_pairs_is_refused() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let half = disk_mesh(tmp.path(), false);
    let case = write(
        tmp.path(),
        "clash.toml",
        &half,
        &format!(
            "{}\n[[contact]]\ngroup = \"side\"\nobstacle = {{ type = \"plane\", point = [1.5, 0], normal = [-1, 0] }}\n",
            top_pair("")
        ),
    );
    let out = tmp.path().join("out");
    let run = run_solver(2, &case, &[], &out);
    run.expect_code(2, "a node on two pairs");
    let text = run.output();
    assert!(text.contains("contact[1].group"), "{text}");
    assert!(text.contains("two pairs"), "{text}");
    assert!(!out.join("summary.json").exists());
}

/// 3D: the unit cube between a fixed plate under it (y = 0) and one moved down by d on top,
/// frictionless, held only by the mirror planes x = 0 and z = 0 (u_x = 0, u_z = 0 there): it is
/// squeezed uniformly (uniaxial stress, which P1 represents exactly), so each plate carries
/// E d, every contact node is active, and the bottom stays where it is — on the condensed path,
/// the plain path and the iterative preset (with the half-space predictor), on 1 to 3 ranks.
#[test]
fn cube_between_two_plates() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = unit_mesh(tmp.path(), 3, 0.25);
    let d = 0.01;
    let case = write_case(
        &tmp.path().join("cube.toml"),
        &format!(
            "[mesh]\nfile = {}\n\n[material]\nyoung = 2.0\npoisson = 0.3\n\n\
             [[dirichlet]]\ngroup = \"left\"\nvalue = [0.0, \"free\", \"free\"]\n\n\
             [[dirichlet]]\ngroup = \"front\"\nvalue = [\"free\", \"free\", 0.0]\n\n\
             [[contact]]\ngroup = \"bottom\"\n\
             obstacle = {{ type = \"plane\", point = [0, 0, 0], normal = [0, 1, 0] }}\n\n\
             [[contact]]\ngroup = \"top\"\n\
             obstacle = {{ type = \"plane\", point = [0, 1, 0], normal = [0, -1, 0] }}\n\
             motion = [0, {}, 0]\n",
            toml_path(&mesh),
            -d
        ),
    );
    let runs: [(usize, &[&str]); 4] = [
        (1, &["solver.preset=\"direct\""]),
        (2, &["solver.preset=\"direct\"", "solver.reuse=\"never\""]),
        (2, &["solver.preset=\"iterative\""]),
        (3, &["solver.preset=\"direct\""]),
    ];
    for (np, sets) in runs {
        let s = solve(np, &case, sets);
        s.assert_converged("cube");
        let e_d = 2.0 * d;
        let (f0, f1) = (pair_force(&s, 0), pair_force(&s, 1));
        assert!(rel(f0[1], e_d) <= 1e-8, "{np} {sets:?}: {f0:?}");
        assert!(rel(f1[1], -e_d) <= 1e-8, "{np} {sets:?}: {f1:?}");
        // no tangential force: to round-off on a factorisation; the iterative run's reactions
        // carry its Krylov tolerance (rtol 1e-10 of ‖b‖, met from a warm start just below it:
        // measured 3.9e-12 against E d = 0.02)
        let iterative = sets.iter().any(|s| s.contains("iterative"));
        let tangential = if iterative { 1e-8 } else { 1e-10 };
        for (i, f) in [f0, f1].iter().enumerate() {
            assert!(
                f[0].abs() + f[2].abs() <= tangential * e_d,
                "{np} {sets:?} pair {i}: {f:?}"
            );
        }
        let nodes = |i: usize| pair(&s, i)["nodes"].as_u64().expect("nodes");
        assert_eq!(
            (pair_active(&s, 0), pair_active(&s, 1)),
            (nodes(0), nodes(1))
        );
        assert!(nodes(0) >= 25, "{}", nodes(0));
        let rows = s.contact_rows_by_id();
        // u_n = u·n: 0 on the fixed plate, d under the moved one (n = −e_y, u_y = −d)
        for (id, r) in &rows {
            let want = if r.s("pair") == "1" { 0.0 } else { d };
            assert!(
                (r.f("u_n") - want).abs() <= 1e-9 * d,
                "node {id}: {}",
                r.f("u_n")
            );
        }
    }
}

/// 3D: the unit cube clamped on its face x = 0, pressed from below and from above by two
/// force-controlled spheres (radius 0.5, touching the faces' centres) with the forces that
/// their motions (0.02 up, 0.04 down) take: both approaches give back the motions, and u and
/// the active set are the motions' — on the condensed path, the plain path and the iterative
/// preset (with the half-space predictor).
#[test]
fn force_on_two_pairs_in_3d() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = unit_mesh(tmp.path(), 3, 0.125);
    let (lift, press) = (0.02, 0.04);
    let case = |name: &str, bottom: &str, top: &str| {
        write_case(
            &tmp.path().join(name),
            &format!(
                "[mesh]\nfile = {}\n\n[material]\nyoung = 2.0\npoisson = 0.3\n\n\
                 [[dirichlet]]\ngroup = \"left\"\nvalue = [0.0, 0.0, 0.0]\n\n\
                 [[contact]]\ngroup = \"bottom\"\n\
                 obstacle = {{ type = \"sphere\", center = [0.5, -0.5, 0.5], radius = 0.5 }}\n{bottom}\n\n\
                 [[contact]]\ngroup = \"top\"\n\
                 obstacle = {{ type = \"sphere\", center = [0.5, 1.5, 0.5], radius = 0.5 }}\n{top}\n",
                toml_path(&mesh),
            ),
        )
    };
    let moved = solve(
        1,
        &case(
            "moved.toml",
            &format!("motion = [0, {lift}, 0]"),
            &format!("motion = [0, {}, 0]", -press),
        ),
        &[],
    );
    moved.assert_converged("motions, 3D");
    let f = [pair_force(&moved, 0)[1], pair_force(&moved, 1)[1]];
    assert!(f[0] > 0.0 && f[1] < 0.0, "{f:?}");
    let active = [pair_active(&moved, 0), pair_active(&moved, 1)];
    eprintln!("motions: {} steps, active {active:?}", moved.steps());
    assert!(active[0] >= 3 && active[1] >= 3, "{active:?}");
    let forced = case(
        "forced.toml",
        &format!("force = [0, {:.17e}, 0]", f[0]),
        &format!("force = [0, {:.17e}, 0]", f[1]),
    );
    let runs: [(usize, &[&str]); 3] = [
        (2, &["solver.preset=\"direct\""]),
        (1, &["solver.preset=\"direct\"", "solver.reuse=\"never\""]),
        (2, &["solver.preset=\"iterative\""]),
    ];
    for (np, sets) in runs {
        let s = solve(np, &forced, sets);
        s.assert_converged("force control on two pairs, 3D");
        let delta = [0, 1].map(|i| pair(&s, i)["approach"].as_f64().expect("approach"));
        eprintln!("{np} ranks {sets:?}: {} steps, δ = {delta:?}", s.steps());
        for (d, want) in delta.iter().zip([lift, press]) {
            assert!(
                (d - want).abs() <= 1e-8 * want,
                "{np} {sets:?}: δ = {delta:?}"
            );
        }
        assert!(s.u_rel_diff(&moved) <= 1e-8, "{np} {sets:?}");
        assert_eq!(
            s.active_node_ids(),
            moved.active_node_ids(),
            "{np} {sets:?}"
        );
    }
}

/// Coulomb pairs with their own μ: μ = 0.5 under the disk, frictionless (no friction key) on
/// top, the top plate moved down: the top pair carries no tangential force (to
/// round-off), the bottom pair's respects |λ_τ| ≤ μ (−λ_n) and carries some.
#[test]
fn coulomb_pairs_with_their_own_mu() {
    let mu = 0.5;
    let (_, rows, scale) =
        friction_under_the_disk(&format!("friction = {{ law = \"coulomb\", mu = {mu} }}"));
    let mut carrying = 0;
    for (id, r) in &rows {
        let (lt, ln) = (r.lambda_t(2)[0].abs(), -r.f("lambda_n"));
        if r.s("pair") == "2" {
            assert!(lt <= 1e-12 * scale, "top node {id}: λ_τ = {lt}");
        } else {
            assert!(
                lt <= mu * ln.max(0.0) * (1.0 + 1e-9) + 1e-12 * scale,
                "node {id}"
            );
            if r.active() && lt > 1e-6 * scale {
                carrying += 1;
            }
        }
    }
    assert!(carrying > 0, "no tangential force under the disk");
}

/// Coulomb friction (μ = 0.3) on both plates: the two-pair disk is again the mirror image of
/// itself, its bottom pair the quarter model with the same friction — force, λ_n and λ_τ of
/// every node to round-off.
#[test]
fn coulomb_plates_match_the_symmetric_quarter() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (half, quarter) = (disk_mesh(tmp.path(), false), disk_mesh(tmp.path(), true));
    let friction = "friction = { law = \"coulomb\", mu = 0.3 }\n";
    let q = write(
        tmp.path(),
        "quarter.toml",
        &quarter,
        &format!(
            "[[dirichlet]]\ngroup = \"mid\"\nvalue = [\"free\", {}]\n\n{}{friction}",
            -SQUEEZE / 2.0,
            BOTTOM.replace("[[contact]]", "[contact]")
        ),
    );
    let model = solve(2, &q, &[]);
    model.assert_converged("quarter");
    let both = write(
        tmp.path(),
        "plates.toml",
        &half,
        &format!(
            "{BOTTOM}{friction}\n{}{friction}",
            top_pair(&format!("motion = [0, {}]", -SQUEEZE))
        ),
    );
    let s = solve(2, &both, &[]);
    s.assert_converged("two plates, Coulomb");
    let f_model = model.total_force()[1];
    assert!(rel(pair_force(&s, 0)[1], f_model) <= 1e-9);
    let m = model.contact_rows_by_id();
    let scale = m
        .values()
        .map(|r| r.f("lambda_n").abs())
        .fold(0.0, f64::max);
    let mut tangential = 0.0f64;
    for (id, r) in s
        .contact_rows_by_id()
        .iter()
        .filter(|(_, r)| r.s("pair") == "1")
    {
        let q = &m[id];
        assert!(
            (r.f("lambda_n") - q.f("lambda_n")).abs() <= 1e-9 * scale,
            "node {id}"
        );
        let (a, b) = (r.lambda_t(2)[0], q.lambda_t(2)[0]);
        assert!((a - b).abs() <= 1e-9 * scale, "node {id}: {a} {b}");
        tangential = tangential.max(a.abs());
    }
    assert!(
        tangential > 1e-3 * scale,
        "friction carries nothing: {tangential}"
    );
}

/// The disk held only between its two plates (free vertically but for them: `sym` holds u_x
/// and with it the rotation), the top plate moved or pushed by `top`, `friction` on both
/// pairs (empty: frictionless).
fn floating_disk(top: &str, friction: &str) -> String {
    format!("{BOTTOM}{friction}\n{}{friction}\n", top_pair(top))
}

/// The top pair's approach δ of a run (summary.json's `contact.approach`).
fn approach(s: &Solved) -> f64 {
    s.f(&["contact", "approach"])
}

/// The floating disk, the top plate under the force that its motion of 0.02 takes: the
/// approach δ is one more free mode next to the disk's own rigid mode. The condensed path
/// (the direct preset's default) gives back δ = 0.02 and the motion's solution (1 and 3 ranks);
/// the plain path (`solver.reuse = "never"`, and `newton.init = "gap"`) gives the condensed
/// path's final active set, u within 1e-9 of max|u| and δ within 1e-9 (1, 2 and 3 ranks); the
/// iterative preset the same set, u and δ within its Krylov tolerance (1e-7; 1 and 2 ranks).
#[test]
fn force_on_a_body_held_only_by_its_pairs() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let half = disk_mesh(tmp.path(), false);
    let motion = format!("motion = [0, {}]", -SQUEEZE);
    let moved = solve(
        1,
        &write(tmp.path(), "moved.toml", &half, &floating_disk(&motion, "")),
        &[],
    );
    moved.assert_converged("motion");
    let f = pair_force(&moved, 1);
    let forced = write(
        tmp.path(),
        "forced.toml",
        &half,
        &floating_disk(&format!("force = [0, {:.17e}]", f[1]), ""),
    );
    let condensed = solve(1, &forced, &[]);
    let three = solve(3, &forced, &[]);
    for (np, s) in [(1, &condensed), (3, &three)] {
        s.assert_converged("force control, floating");
        let delta = approach(s);
        assert!(
            (delta - SQUEEZE).abs() <= 1e-8 * SQUEEZE,
            "{np} ranks: δ = {delta}"
        );
        assert!(s.u_rel_diff(&moved) <= 1e-8, "{np} ranks");
        assert_eq!(s.active_node_ids(), moved.active_node_ids());
    }
    let dc = approach(&condensed);
    let runs: [(usize, &[&str], f64); 6] = [
        (1, &["solver.reuse=\"never\""], 1e-9),
        (2, &["solver.reuse=\"never\""], 1e-9),
        (3, &["solver.reuse=\"never\""], 1e-9),
        (2, &["newton.init=\"gap\"", "solver.reuse=\"never\""], 1e-9),
        (1, &["solver.preset=\"iterative\""], 1e-7),
        (2, &["solver.preset=\"iterative\""], 1e-7),
    ];
    for (np, sets, tol) in runs {
        let s = solve(np, &forced, sets);
        s.assert_converged("force control, floating, off the condensed path");
        let (d, du) = (approach(&s), s.u_rel_diff(&condensed));
        eprintln!(
            "{np} ranks {sets:?}: {} steps (condensed: {}), δ = {d:.17e} (condensed \
             {dc:.17e}, rel {:.1e}), |Δu|/max|u| = {du:.1e}",
            s.steps(),
            condensed.steps(),
            rel(d, dc)
        );
        assert!(rel(d, dc) <= tol, "{np} {sets:?}: δ = {d} vs {dc}");
        assert!(du <= tol, "{np} {sets:?}: {du}");
        assert_eq!(
            s.active_node_ids(),
            condensed.active_node_ids(),
            "{np} {sets:?}"
        );
        assert!(rel(pair_force(&s, 1)[1], f[1]) <= tol, "{np} {sets:?}");
    }
}

/// The floating disk with friction `law` on both plates, the top plate under a force: the plain
/// path (Algorithm 2; for Coulomb the fixed point or the generalised Newton) finds an approach
/// δ, and the top plate's
/// motion by δ gives the same u (within `tol` of max|u|), the same force on the top plate, the
/// same active and slip nodes — on each run's ranks and settings (both runs), `tol` its own;
/// and the motion's run has slip nodes and stick nodes among its active ones.
fn friction_on_a_floating_disk(law: &str, runs: &[(usize, &[&str], f64)]) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let half = disk_mesh(tmp.path(), false);
    let friction = format!("friction = {law}\n");
    let force = -0.004;
    let forced = write(
        tmp.path(),
        "forced.toml",
        &half,
        &floating_disk(&format!("force = [0, {force}]"), &friction),
    );
    let (mut slip, mut active) = (0, 0);
    for &(np, sets, tol) in runs {
        let s = solve(np, &forced, sets);
        s.assert_converged(law);
        let delta = approach(&s);
        assert!(delta > 0.0, "{np} ranks: δ = {delta}");
        let moved = solve(
            np,
            &write(
                tmp.path(),
                "moved.toml",
                &half,
                &floating_disk(&format!("motion = [0, {:.17e}]", -delta), &friction),
            ),
            sets,
        );
        moved.assert_converged(law);
        let (du, fm) = (s.u_rel_diff(&moved), pair_force(&moved, 1)[1]);
        (slip, active) = (moved.slip_node_ids().len(), moved.active_node_ids().len());
        eprintln!(
            "{law}, {np} ranks {sets:?}: δ = {delta:.17e}, {} steps (the motion: {}), |Δu|/max|u| = \
             {du:.1e}, the motion's force {fm:.17e} (rel {:.1e}), slip {slip} of {} active",
            s.steps(),
            moved.steps(),
            rel(fm, force),
            active
        );
        assert!(du <= tol, "{law}, {np} {sets:?}: {du}");
        assert!(
            rel(fm, force) <= tol,
            "{law}, {np} {sets:?}: {fm} vs {force}"
        );
        assert!(rel(pair_force(&s, 1)[1], force) <= tol, "{np} {sets:?}");
        assert_eq!(
            s.active_node_ids(),
            moved.active_node_ids(),
            "{np} {sets:?}"
        );
        assert_eq!(s.slip_node_ids(), moved.slip_node_ids(), "{np} {sets:?}");
    }
    assert!(slip > 0 && active > slip, "slip {slip} of {active} active");
}

/// Tresca friction (threshold 0.01: half the active nodes slip) on both plates of the floating
/// disk under force control of the top plate: the plain path's δ, prescribed as the top
/// plate's motion, gives the same u (1e-8), force, active and slip nodes, on 1 and 2 ranks;
/// on the iterative preset to its Krylov tolerance (1e-7; 2 ranks).
#[test]
fn tresca_force_on_a_floating_disk() {
    let law = "{ law = \"tresca\", threshold = 0.01 }";
    let runs: [(usize, &[&str], f64); 3] = [
        (1, &[], 1e-8),
        (2, &[], 1e-8),
        (2, &["solver.preset=\"iterative\""], 1e-7),
    ];
    friction_on_a_floating_disk(law, &runs);
}

/// Coulomb friction by the fixed point (μ = 0.3) on both plates of the floating disk under
/// force control of the top plate: the δ found, prescribed as the top plate's motion, gives the
/// same u, force, active and slip nodes (1e-8: the fixed point stops when the thresholds
/// settle to 1e-9), on 1 and 2 ranks.
#[test]
fn coulomb_fixed_point_force_on_a_floating_disk() {
    let law = "{ law = \"coulomb\", mu = 0.3, algorithm = \"fixed-point\" }";
    let runs: [(usize, &[&str], f64); 2] = [(1, &[], 1e-8), (2, &[], 1e-8)];
    friction_on_a_floating_disk(law, &runs);
}

/// Coulomb friction by the generalised Newton (μ = 0.3) on both plates of the floating disk
/// under force control of the top plate (its approach coupled to the disk's free mode): the δ
/// found, prescribed as the top plate's motion, gives the same u, force, active and slip nodes
/// (1e-8), on 1 and 2 ranks and on the iterative preset.
#[test]
fn coulomb_newton_force_on_a_floating_disk() {
    let law = "{ law = \"coulomb\", mu = 0.3 }";
    let runs: [(usize, &[&str], f64); 3] = [
        (1, &[], 1e-8),
        (2, &[], 1e-8),
        (2, &["solver.preset=\"iterative\""], 1e-7),
    ];
    friction_on_a_floating_disk(law, &runs);
}

/// The floating disk with the bottom plate GAP below it, the top plate under a force: the
/// plain path first presses the disk against its pin (the set leaves the disk's mode, with the
/// top plate's approach coupled to it, free), finds that mode unbalanced by the prescribed
/// force and moves the disk with the top plate until the bottom plate's first node touches
/// (said in the log); the result is the condensed path's (the same set, u within 1e-9 of
/// max|u|, δ within 1e-9) and the approach is the one without the gap plus GAP — 1 and 2 ranks.
#[test]
fn force_on_a_floating_disk_from_a_gap() {
    const GAP: f64 = 0.05;
    let tmp = tempfile::tempdir().expect("tempdir");
    let half = disk_mesh(tmp.path(), false);
    let top = "force = [0, -0.004]";
    let touching = write(tmp.path(), "touching.toml", &half, &floating_disk(top, ""));
    let text =
        floating_disk(top, "").replace("point = [0, -1]", &format!("point = [0, {}]", -1.0 - GAP));
    let gap = write(tmp.path(), "gap.toml", &half, &text);
    let d0 = approach(&solve(1, &touching, &[]));
    let condensed = solve(1, &gap, &[]);
    condensed.assert_converged("condensed, from a gap");
    let dc = approach(&condensed);
    assert!(rel(dc, d0 + GAP) <= 1e-9, "{dc} vs {d0} + {GAP}");
    for np in [1, 2] {
        let s = solve(np, &gap, &["solver.reuse=\"never\""]);
        s.assert_converged("plain path, from a gap");
        let (d, du) = (approach(&s), s.u_rel_diff(&condensed));
        eprintln!(
            "{np} ranks: {} steps, δ = {d:.17e} (condensed {dc:.17e}), |Δu|/max|u| = {du:.1e}",
            s.steps()
        );
        assert!(rel(d, dc) <= 1e-9 && du <= 1e-9, "{np} ranks: {d} {du}");
        assert_eq!(s.active_node_ids(), condensed.active_node_ids());
        assert!(
            s.run.output().contains("the body moves until contact node"),
            "{}",
            s.run.output()
        );
    }
}
