//! Moving obstacles (`contact.motion`, docs/obstacles.md "Moving obstacles"): moving the
//! obstacle by d is moving the body by −d (frictionless, Tresca and Coulomb, loading and
//! unloading), the sign of the motion, a held motion, the obstacle's displacement in
//! history.csv and summary.json, 1 against 2 ranks, and scripts/plot-history on the curve.

mod common;

use common::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The block [-1,1] × [0,0.25] of cases/blocks/block2d resting on the plane y = 0 (its bottom
/// is the contact boundary), held by Dirichlet data on its top.
fn block() -> PathBuf {
    repo("tests/cases/block2d_pulled.toml")
}

/// The motion m of the obstacle (up into the block and sideways) and its mirror image −m as
/// a prescribed displacement of the block's top.
const M: [f64; 2] = [0.004, 0.01];
const MOVE: &str = "contact.motion=[0.004, 0.01]";
const TOP_AT_REST: &str = "dirichlet.0.value=[0.0, 0.0]";
const TOP_MOVED: &str = "dirichlet.0.value=[-0.004, -0.01]";
/// Loading, beyond, and back.
const FACTORS: &str = "load.factors=[0.5, 1.0, 0.7]";
const T: [f64; 3] = [0.5, 1.0, 0.7];

fn history(dir: &Path) -> Vec<Row> {
    read_csv(&dir.join("history.csv"))
}

/// max |a − (b + shift)| over all nodes, and max |a|.
fn shifted_diff(
    a: &BTreeMap<u64, Vec<f64>>,
    b: &BTreeMap<u64, Vec<f64>>,
    shift: [f64; 2],
) -> (f64, f64) {
    assert_eq!(a.len(), b.len());
    let (mut d, mut s) = (0.0f64, 0.0f64);
    for (id, x) in a {
        for k in 0..2 {
            d = d.max((x[k] - (b[id][k] + shift[k])).abs());
            s = s.max(x[k].abs());
        }
    }
    (d, s)
}

/// A rigid translation changes no strain: the block clamped at rest under an obstacle moved by
/// t·m solves the same problem as the block whose top is moved by −t·m under the obstacle at
/// rest, shifted by t·m — the gaps (g0 − d·n, exact for a plane) and, with friction, the slip
/// relative to the obstacle (u_τ − d_τ) included. Every step of a loading and unloading history
/// agrees to the solver's tolerance; the forces are the same and the Coulomb history slips.
#[test]
fn moving_the_obstacle_is_moving_the_body() {
    for law in [
        "contact.friction=\"none\"",
        "contact.friction={law=\"tresca\", threshold=0.01}",
        "contact.friction={law=\"coulomb\", mu=0.3}",
    ] {
        let moved = solve(1, &block(), &[TOP_AT_REST, MOVE, law, FACTORS]);
        let body = solve(1, &block(), &[TOP_MOVED, law, FACTORS]);
        let (hm, hb) = (history(&moved.dir), history(&body.dir));
        assert_eq!((hm.len(), hb.len()), (3, 3), "{law}");
        let f_scale = hb.iter().map(|r| r.f("force_y").abs()).fold(0.0, f64::max);
        assert!(f_scale > 0.0, "{law}: the block is pressed");
        for (s, t) in T.iter().enumerate() {
            let (rm, rb) = (&hm[s], &hb[s]);
            for k in ["force_x", "force_y"] {
                assert!(
                    (rm.f(k) - rb.f(k)).abs() <= 1e-9 * f_scale,
                    "{law}, step {}: {k} {} vs {}",
                    s + 1,
                    rm.f(k),
                    rb.f(k)
                );
            }
            // the obstacle's displacement t·m in the history; none for the obstacle at rest
            for (k, m) in ["obstacle_x", "obstacle_y"].iter().zip(M) {
                assert!((rm.f(k) - t * m).abs() <= 1e-15, "{k}: {}", rm.f(k));
                assert_eq!(rb.f(k), 0.0, "{k}");
            }
            let (d, scale) = shifted_diff(
                &step_displacement(&moved.dir, s + 1),
                &step_displacement(&body.dir, s + 1),
                [t * M[0], t * M[1]],
            );
            assert!(
                scale > 0.0 && d <= 1e-9 * scale,
                "{law}, step {}: u − t·m against the moved body: {d:e} (|u| {scale:e})",
                s + 1
            );
        }
        if law.contains("coulomb") {
            let slip: f64 = hm.iter().map(|r| r.f("slip")).sum();
            assert!(slip > 0.0, "the drag makes some nodes slip: {hm:?}");
        }
    }
}

/// n points from the obstacle into the body: a motion with m·n > 0 closes the gap, one with
/// m·n < 0 opens it. The plane starts 0.001 below the block: at 5 % of the motion 0.01 up it
/// has not reached it yet, then it presses harder with every step; moved down it never
/// touches.
#[test]
fn motion_along_the_normal_closes_the_gap() {
    let below = "contact.obstacle={type=\"plane\", point=[0.0, -0.001], normal=[0.0, 1.0]}";
    let factors = "load.factors=[0.05, 0.5, 1.0]";
    let up = solve(
        1,
        &block(),
        &[TOP_AT_REST, below, "contact.motion=[0.0, 0.01]", factors],
    );
    let h = history(&up.dir);
    let f: Vec<f64> = h.iter().map(|r| r.f("force_y")).collect();
    assert_eq!(h[0].f("active"), 0.0, "{h:?}");
    // the force on the body points along n (into the body) and grows with the motion
    assert!(f[1] > 0.0 && f[2] > f[1], "{f:?}");
    // no node touches: λ = f − A u of the free rows, zero up to round-off
    assert!(f[0].abs() <= 1e-12 * f[2], "{f:?}");
    assert!(h[2].f("active") > 0.0);
    let down = solve(
        1,
        &block(),
        &[TOP_AT_REST, below, "contact.motion=[0.0, -0.01]", factors],
    );
    for r in history(&down.dir) {
        assert_eq!(r.f("active"), 0.0, "{r:?}");
        assert!(r.f("force_y").abs() <= 1e-12 * f[2], "{r:?}");
    }
}

/// `ramp = false` holds the obstacle at m in every step: each step of a history is the static
/// solution with the motion; a run without [load] is the problem at factor 1 and reports the
/// obstacle's displacement in summary.json (and no such key without a motion).
#[test]
fn held_motion_and_the_single_step_summary() {
    let stat = solve(1, &block(), &[TOP_AT_REST, MOVE]);
    let d = floats(get(&stat.summary, &["contact", "obstacle_displacement"]));
    assert_eq!(d, M.to_vec());
    assert!(
        stat.run.stdout.contains("obstacle moved by [0.004, 0.01]"),
        "{}",
        stat.run.stdout
    );
    let held = solve(
        1,
        &block(),
        &[
            TOP_AT_REST,
            "contact.motion={value=[0.004, 0.01], ramp=false}",
            "load.factors=[0.5, 1.0]",
        ],
    );
    let u = stat.displacement();
    for s in 1..=2 {
        let (d, scale) = shifted_diff(&step_displacement(&held.dir, s), &u, [0.0, 0.0]);
        assert!(scale > 0.0 && d <= 1e-10 * scale, "step {s}: {d:e}");
        let r = &history(&held.dir)[s - 1];
        assert_eq!((r.f("obstacle_x"), r.f("obstacle_y")), (M[0], M[1]));
    }
    let at_rest = solve(1, &block(), &[TOP_MOVED]);
    assert!(at_rest.summary["contact"]
        .get("obstacle_displacement")
        .is_none());
}

/// Coulomb friction against a moving obstacle, loading and unloading: 1 and 2 ranks give the
/// same history and displacements.
#[test]
fn ranks_agree_on_a_moving_obstacle() {
    let sets = [
        TOP_AT_REST,
        MOVE,
        "contact.friction={law=\"coulomb\", mu=0.3}",
        FACTORS,
    ];
    let a = solve(1, &block(), &sets);
    let b = solve(2, &block(), &sets);
    let (ha, hb) = (history(&a.dir), history(&b.dir));
    assert_eq!(ha.len(), hb.len());
    let f_scale = ha.iter().map(|r| r.f("force_y").abs()).fold(0.0, f64::max);
    for (ra, rb) in ha.iter().zip(&hb) {
        for k in ["force_x", "force_y", "obstacle_x", "obstacle_y"] {
            assert!(
                (ra.f(k) - rb.f(k)).abs() <= 1e-9 * f_scale.max(1e-2),
                "{k}: {ra:?} vs {rb:?}"
            );
        }
    }
    for s in 1..=ha.len() {
        let (d, scale) = shifted_diff(
            &step_displacement(&a.dir, s),
            &step_displacement(&b.dir, s),
            [0.0, 0.0],
        );
        assert!(scale > 0.0 && d <= 1e-9 * scale, "step {s}: {d:e}");
    }
}

/// scripts/plot-history draws the curve of a history to a PNG and prints the numbers it drew:
/// the force along the motion against the obstacle's displacement along it.
#[test]
fn plot_history_draws_the_curve() {
    let run = solve(1, &block(), &[TOP_AT_REST, MOVE, "load.factors=[0.5, 1.0]"]);
    let png = run.dir.join("curve.png");
    let mut cmd = std::process::Command::new(repo("scripts/plot-history"));
    cmd.arg(&run.dir).arg("--out").arg(&png);
    let r = run_with_timeout(cmd, std::time::Duration::from_secs(120));
    r.expect_code(0, "plot-history");
    let bytes = std::fs::read(&png).expect("the PNG");
    assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "not a PNG");
    // the printed table: s = d·e = t |m|, P = F·e from history.csv
    let h = history(&run.dir);
    let norm = M[0].hypot(M[1]);
    let rows: Vec<Vec<f64>> = r
        .stdout
        .lines()
        .filter_map(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .filter_map(|w| w.parse().ok())
                .collect();
            (v.len() == 5).then_some(v)
        })
        .collect();
    assert_eq!(rows.len(), 2, "{}", r.stdout);
    for (row, (hr, t)) in rows.iter().zip(h.iter().zip([0.5, 1.0])) {
        let p = (hr.f("force_x") * M[0] + hr.f("force_y") * M[1]) / norm;
        assert!(rel(row[2], t * norm) <= 1e-9, "{row:?}");
        assert!(p > 0.0 && rel(row[3], p) <= 1e-9, "{row:?} vs {p}");
    }
    // a history without contact forces is refused with one message
    let mut cmd = std::process::Command::new(repo("scripts/plot-history"));
    cmd.arg(run.dir.join("nowhere"));
    let r = run_with_timeout(cmd, std::time::Duration::from_secs(60));
    assert_ne!(r.code, Some(0));
    assert!(r.stderr.contains("history.csv"), "{}", r.stderr);
}

/// `motion = { table = [[0, 0, 0], [1, m]] }` is the ramped motion m: the same steps to the
/// bit; a table with a corner (indent, then slide) puts the obstacle at its interpolation.
#[test]
fn a_motion_table_is_piecewise_linear_in_the_factor() {
    let law = "contact.friction={law=\"coulomb\", mu=0.3}";
    let ramped = solve(1, &block(), &[TOP_AT_REST, MOVE, FACTORS, law]);
    let table = solve(
        1,
        &block(),
        &[
            TOP_AT_REST,
            "contact.motion={table=[[0.0, 0.0, 0.0], [1.2, 0.0048, 0.012]]}",
            FACTORS,
            law,
        ],
    );
    let (a, b) = (history(&ramped.dir), history(&table.dir));
    for (ra, rb) in a.iter().zip(&b) {
        for k in [
            "obstacle_x",
            "obstacle_y",
            "force_x",
            "force_y",
            "stick",
            "slip",
        ] {
            let (x, y) = (ra.f(k), rb.f(k));
            assert!((x - y).abs() <= 1e-15 + 1e-12 * x.abs(), "{k}: {x} vs {y}");
        }
    }
    // a corner at 0.5: up by 0.01, then sideways by 0.004 with the height held
    let corner = solve(
        1,
        &block(),
        &[
            TOP_AT_REST,
            "contact.motion={table=[[0, 0, 0], [0.5, 0, 0.01], [1, 0.004, 0.01]]}",
            "load.factors=[0.25, 0.5, 0.75, 1.0]",
            law,
        ],
    );
    let expected = [[0.0, 0.005], [0.0, 0.01], [0.002, 0.01], [0.004, 0.01]];
    let h = history(&corner.dir);
    assert_eq!(h.len(), 4);
    for (r, [x, y]) in h.iter().zip(expected) {
        assert!(
            (r.f("obstacle_x") - x).abs() < 1e-15,
            "{}",
            r.f("obstacle_x")
        );
        assert!(
            (r.f("obstacle_y") - y).abs() < 1e-15,
            "{}",
            r.f("obstacle_y")
        );
    }
    // the slide after the corner pulls the block sideways: Q grows, P stays nearly
    assert!(h[3].f("force_x") > h[2].f("force_x") && h[2].f("force_x") > h[1].f("force_x"));
}

/// scripts/plot-history writes its PNG beside the result folder (DIR.force_displacement.png),
/// so the next run into DIR is not refused; with --analytic it says why nothing is overlaid
/// in 2D, and overlays Hertz' sphere in 3D (the printed numbers are the formula's).
#[test]
fn plot_history_beside_the_folder_with_the_analytic_curve() {
    let sets = [TOP_AT_REST, MOVE, "load.factors=[0.5, 1.0]"];
    let run = solve(1, &block(), &sets);
    let mut cmd = std::process::Command::new(repo("scripts/plot-history"));
    cmd.arg(&run.dir)
        .arg("--analytic")
        .arg("--case")
        .arg(block());
    let r = run_with_timeout(cmd, std::time::Duration::from_secs(120));
    r.expect_code(0, "plot-history");
    let png = PathBuf::from(format!("{}.force_displacement.png", run.dir.display()));
    assert!(png.metadata().is_ok_and(|m| m.len() > 1000), "{}", r.stdout);
    assert!(
        r.stdout.contains(&png.display().to_string()),
        "{}",
        r.stdout
    );
    assert!(r.stdout.contains("none overlaid in 2D"), "{}", r.stdout);
    // the same run into the same folder again: nothing foreign in it
    run_solver(1, &block(), &sets, &run.dir).expect_code(0, "a second run into the folder");

    // 3D: a sphere (R = 1, E* = 2/(1 − 0.09)) touching the top of block3d, moved down
    let tmp = tempfile::tempdir().expect("tempdir");
    let case = write_case(
        &tmp.path().join("sphere.toml"),
        &format!(
            "[mesh]\nfile = {}\n[material]\nyoung = 2.0\npoisson = 0.3\nmodel = \"3d\"\n\
             [[dirichlet]]\ngroup = \"bottom\"\nvalue = [0.0, 0.0, 0.0]\n[contact]\n\
             group = \"top\"\nobstacle = {{ type = \"sphere\", center = [0.0, 0.0, 1.5], radius = 1.0 }}\n\
             motion = {{ table = [[0, 0, 0, 0], [1, 0, 0, -0.01]] }}\nfriction = \"none\"\n\
             [load]\nsteps = 2\n",
            toml_path(&repo("cases/blocks/block3d.msh"))
        ),
    );
    let out = tmp.path().join("out");
    run_solver(1, &case, &[], &out).expect_code(0, "the sphere");
    let mut cmd = std::process::Command::new(repo("scripts/plot-history"));
    cmd.arg(&out)
        .arg("--analytic")
        .arg("--case")
        .arg(&case)
        .arg("--fraction")
        .arg("0.5");
    let r = run_with_timeout(cmd, std::time::Duration::from_secs(120));
    r.expect_code(0, "plot-history --analytic");
    let estar = 2.0 / (1.0 - 0.09);
    let lines: Vec<&str> = r.stdout.lines().filter(|l| l.contains(" h = ")).collect();
    assert_eq!(lines.len(), 2, "{}", r.stdout);
    for (l, h) in lines.iter().zip([0.005f64, 0.01]) {
        let analytic: f64 = l.rsplit(' ').next().unwrap().parse().expect("a number");
        let p = 0.5 * 4.0 / 3.0 * estar * h.powf(1.5);
        assert!(rel(analytic, p) < 1e-5, "{l}: {p}");
    }
    assert!(tmp.path().join("out.force_displacement.png").exists());
}
