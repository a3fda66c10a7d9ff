//! Coulomb friction between two elastic bodies (dual mortar, `obstacle = { type = "body" }`):
//! Cattaneo–Mindlin on cases/bodies/cattaneo_bodies.toml, two half disks of one material
//! (R = 1 each, E = 1, ν = 0.3) pressed by a held displacement of the upper one's flat side,
//! then dragged sideways by a ramped one, on level 2 of cases/bodies/cattaneo_bodies.geo
//! (about 4 200 cells, 25 / 17 active slave nodes on the upper / lower side).
//!
//! With one material the normal and tangential problems decouple, and Cattaneo's stick zone
//! is c/a = √(1 − Q/(μP)), centred. a and c are measured as in scripts/bench-bodies
//! (docs/bodies.md, "Validated"): least-squares fits of p² over the active nodes and of
//! (μp − |q|)² over the stick nodes by a parabola in x (both vanish at a square-root edge),
//! its half width between the roots and its centre at the vertex. Measured at this level:
//! c/a +1.2 % (upper side slave) and +1.3 % (lower side slave) from Cattaneo (+0.06 % and
//! −0.17 % on level 4), the stick zone's centre 0.2 % / 0.1 % of a off the axis.
//!
//! In 3D, Mindlin's stick zone c/a = (1 − Q/(μP))^(1/3) on cases/bodies/mindlin_bodies3d.toml
//! (a lens on a block of one material, half-symmetric).

mod common;

use common::*;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

const MU: f64 = 0.3;
const YOUNG: f64 = 1.0;
const POISSON: f64 = 0.3;
/// 1/R* = 1/R + 1/R.
const R_STAR: f64 = 0.5;
/// c/a against Cattaneo, relative (measured +1.2 % and +1.3 % at level 2).
const TOL_C: f64 = 0.05;
/// a of the fit against Hertz' a for the computed P, relative (measured −0.4 % and −0.8 %).
const TOL_A: f64 = 0.03;
/// The stick zone's centre off the axis, relative to a (measured 0.2 % and 0.1 %; 0.8 % and
/// 0.5 % with the slave normal as the frame, 19 % so with a 16 times wider zone: docs/bodies.md,
/// "The method").
const TOL_CENTRE: f64 = 0.03;

/// Level 2 of cases/bodies/cattaneo_bodies.geo, its contact size and uniform zone `k` times
/// the default (for a contact k times wider).
fn mesh(dir: &Path, k: f64) -> PathBuf {
    let out = dir.join(format!("cattaneo_bodies_L2_k{k}.msh"));
    let geo = repo("cases/bodies/cattaneo_bodies.geo");
    let (h0, z) = ((0.0016 * k).to_string(), (0.008 * k).to_string());
    let numbers = [
        "-setnumber",
        "L",
        "2",
        "-setnumber",
        "h0",
        &h0,
        "-setnumber",
        "Z",
        &z,
    ];
    gmsh_file(&geo, 2, &numbers, &out);
    out
}

/// The case on `mesh` with `slave` ("upper" or "lower") as the slave side, on `np` ranks,
/// and the `extra` settings.
fn run(np: usize, mesh: &Path, slave: &str, extra: &[String]) -> Solved {
    let master = if slave == "upper" { "lower" } else { "upper" };
    let mut sets = vec![
        format!("mesh.file={}", toml_path(mesh)),
        format!("contact.group=\"{slave}_contact\""),
        format!("contact.obstacle.group=\"{master}_contact\""),
    ];
    sets.extend_from_slice(extra);
    let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
    let s = solve(np, &repo("cases/bodies/cattaneo_bodies.toml"), &sets);
    s.assert_converged(&format!("{slave} side slave on {np} ranks"));
    assert_eq!(
        s.summary["load"]["completed"],
        true,
        "{slave} slave, {np} ranks:\n{}",
        s.run.output()
    );
    s
}

/// Half width (between the roots) and centre (the vertex) of the least-squares parabola
/// y = c0 + c1 x + c2 x² through `pts` (x, y).
fn parabola(pts: &[(f64, f64)]) -> (f64, f64) {
    assert!(pts.len() >= 4, "{} points to fit", pts.len());
    let mut m = [[0.0; 4]; 3];
    for &(x, y) in pts {
        let v = [1.0, x, x * x];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += v[i] * v[j];
            }
            m[i][3] += v[i] * y;
        }
    }
    for i in 0..3 {
        let pivot = m[i];
        for row in m.iter_mut().skip(i + 1) {
            let f = row[i] / pivot[i];
            for (x, p) in row.iter_mut().zip(pivot).skip(i) {
                *x -= f * p;
            }
        }
    }
    let mut c = [0.0; 3];
    for i in (0..3).rev() {
        c[i] = (m[i][3] - (i + 1..3).map(|j| m[i][j] * c[j]).sum::<f64>()) / m[i][i];
    }
    assert!(c[2] < 0.0, "the fit y = {c:?} opens upwards");
    let centre = -c[1] / (2.0 * c[2]);
    ((centre * centre - c[0] / c[2]).sqrt(), centre)
}

/// What one run gives: P, Q (the contact forces' totals), a and c of the fits, the stick
/// zone's centre, the ends of the stick zone by the node states (midpoints between the outermost
/// stick node and the next slip node), and the node spacing there.
#[derive(Debug)]
struct Zone {
    p: f64,
    q: f64,
    a: f64,
    c: f64,
    centre: f64,
    ends: (f64, f64),
    h: f64,
}

fn zone(s: &Solved) -> Zone {
    let force = s.total_force();
    let (p, q) = (force[1].abs(), force[0].abs());
    let mut rows = s.contact_rows();
    rows.sort_by(|a, b| a.f("x").total_cmp(&b.f("x")));
    let active: Vec<&csv::Row> = rows.iter().filter(|r| r.active()).collect();
    let pressure = |r: &csv::Row| -r.f("lambda_n") / r.f("weight");
    let (a, _) = parabola(
        &(active.iter())
            .map(|r| (r.f("x"), pressure(r).powi(2)))
            .collect::<Vec<_>>(),
    );
    let stick: Vec<usize> = (0..active.len())
        .filter(|&i| active[i].tangential() == "stick")
        .collect();
    let (first, last) = (stick[0], stick[stick.len() - 1]);
    assert_eq!(
        last - first + 1,
        stick.len(),
        "the stick nodes are one interval"
    );
    assert!(
        first > 0 && last + 1 < active.len(),
        "slip on both sides of the stick zone"
    );
    let reserve = |r: &csv::Row| MU * pressure(r) - r.f("lambda_t1").abs() / r.f("weight");
    let (c, centre) = parabola(
        &(stick.iter())
            .map(|&i| (active[i].f("x"), reserve(active[i]).powi(2)))
            .collect::<Vec<_>>(),
    );
    let x = |i: usize| active[i].f("x");
    let ends = (
        0.5 * (x(first - 1) + x(first)),
        0.5 * (x(last) + x(last + 1)),
    );
    let h = (x(first) - x(first - 1)).max(x(last + 1) - x(last));
    Zone {
        p,
        q,
        a,
        c,
        centre,
        ends,
        h,
    }
}

/// The stick zone's c/a within [`TOL_C`] of Cattaneo's `cattaneo` and its centre within
/// [`TOL_CENTRE`] of a.
fn assert_stick_zone(z: &Zone, cattaneo: f64, slave: &str) {
    assert!(
        ((z.c / z.a) / cattaneo - 1.0).abs() < TOL_C,
        "{slave}: c/a = {} against Cattaneo's {cattaneo}",
        z.c / z.a
    );
    assert!(
        z.centre.abs() < TOL_CENTRE * z.a,
        "{slave}: the stick zone's centre at {:e}, a = {:e}",
        z.centre,
        z.a
    );
}

/// Coulomb's law on the final step's nodes: |λ_t| = μ|λ_n| where a node slips, ≤ where it
/// sticks, the force along Q everywhere in contact (a monotone drag).
fn assert_coulomb(s: &Solved, what: &str) {
    let rows = s.contact_rows();
    let active: Vec<&csv::Row> = rows.iter().filter(|r| r.active()).collect();
    let q_sign = active
        .iter()
        .map(|r| r.f("lambda_t1"))
        .sum::<f64>()
        .signum();
    for r in active {
        let (n, t) = (r.f("lambda_n"), r.f("lambda_t1"));
        let bound = MU * n.abs();
        match r.tangential() {
            "slip" => assert!(
                (t.abs() - bound).abs() <= 1e-10 * bound,
                "{what}: slip node at x = {}: |λ_t| = {:e}, μ|λ_n| = {bound:e}",
                r.f("x"),
                t.abs()
            ),
            "stick" => assert!(
                t.abs() <= bound * (1.0 + 1e-12),
                "{what}: stick node at x = {}: |λ_t| = {:e} > μ|λ_n| = {bound:e}",
                r.f("x"),
                t.abs()
            ),
            other => panic!("{what}: active node at x = {} in state {other}", r.f("x")),
        }
        assert!(n < 0.0, "{what}: λ_n = {n:e} at x = {}", r.f("x"));
        assert_eq!(
            t.signum(),
            q_sign,
            "{what}: λ_t = {t:e} at x = {}",
            r.f("x")
        );
    }
}

/// The states (active, tangential) of every slave node by node id.
fn states(s: &Solved) -> Vec<(u64, bool, String)> {
    let mut v: Vec<(u64, bool, String)> = (s.contact_rows().iter())
        .map(|r| (r.node_id(), r.active(), r.tangential().to_string()))
        .collect();
    v.sort();
    v
}

/// The largest difference of λ_n, λ_t between two runs' slave nodes, relative to the largest
/// |λ_n|.
fn multiplier_diff(a: &Solved, b: &Solved) -> f64 {
    let (ra, rb) = (a.contact_rows_by_id(), b.contact_rows_by_id());
    assert_eq!(ra.len(), rb.len(), "slave node counts");
    let scale = ra
        .values()
        .map(|r| r.f("lambda_n").abs())
        .fold(0.0, f64::max);
    let mut d: f64 = 0.0;
    for (id, r) in &ra {
        for key in ["lambda_n", "lambda_t1"] {
            d = d.max((r.f(key) - rb[id].f(key)).abs());
        }
    }
    d / scale
}

/// Hertz' half width for the line force p between the two cylinders.
fn hertz_a(p: f64) -> f64 {
    let e_star = YOUNG / (2.0 * (1.0 - POISSON * POISSON));
    (4.0 * p * R_STAR / (PI * e_star)).sqrt()
}

#[test]
fn cattaneo_mindlin_between_two_cylinders_with_either_side_slave_on_1_and_2_ranks() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let m = mesh(tmp.path(), 1.0);
    let mut zones = Vec::new();
    for slave in ["upper", "lower"] {
        let s2 = run(2, &m, slave, &[]);
        let s1 = run(1, &m, slave, &[]);
        assert_eq!(states(&s1), states(&s2), "{slave} slave: 1 and 2 ranks");
        let d = multiplier_diff(&s1, &s2);
        assert!(
            d < 1e-9,
            "{slave} slave: λ on 1 and 2 ranks differs by {d:e}"
        );
        assert_coulomb(&s2, slave);
        let z = zone(&s2);
        let ratio = z.q / (MU * z.p);
        let cattaneo = (1.0 - ratio).sqrt();
        eprintln!(
            "{slave} slave: {z:?}, Q/(μP) {ratio:.4}, c/a {:.4}, Cattaneo {cattaneo:.4}",
            z.c / z.a
        );
        assert!((0.4..0.6).contains(&ratio), "{slave}: Q/(μP) = {ratio}");
        assert!(
            (z.a / hertz_a(z.p) - 1.0).abs() < TOL_A,
            "{slave}: a = {} against Hertz' {}",
            z.a,
            hertz_a(z.p)
        );
        assert_stick_zone(&z, cattaneo, slave);
        // the node states give the same zone within a node spacing, centred as well
        let half = 0.5 * (z.ends.1 - z.ends.0);
        assert!(
            (half - z.c).abs() < z.h && (z.ends.0 + z.ends.1).abs() < 2.0 * z.h,
            "{slave}: stick zone {:?} by the states, c = {} by the fit, spacing {}",
            z.ends,
            z.c,
            z.h
        );
        // one material: pressing does not change with the drag (P of the first and last step)
        let steps = s2.summary["load"]["steps"].as_array().expect("load.steps");
        let p0 = steps[0]["total_force"][1]
            .as_f64()
            .expect("total_force")
            .abs();
        assert!(
            (z.p / p0 - 1.0).abs() < 1e-3,
            "{slave}: P {} after the drag, {p0} before",
            z.p
        );
        zones.push(z);
    }
    // either side as slave: the same forces and the same zone within the coarser side's spacing
    let (u, l) = (&zones[0], &zones[1]);
    assert!(
        (u.p / l.p - 1.0).abs() < 1e-3 && (u.q / l.q - 1.0).abs() < 1e-3,
        "P, Q: {} {} (upper slave) against {} {} (lower slave)",
        u.p,
        u.q,
        l.p,
        l.q
    );
    let h = u.h.max(l.h);
    assert!(
        (u.ends.0 - l.ends.0).abs() <= h && (u.ends.1 - l.ends.1).abs() <= h,
        "stick zone {:?} (upper slave) against {:?} (lower slave), spacing {h}",
        u.ends,
        l.ends
    );
    assert!(
        (u.c / u.a - l.c / l.a).abs() < 0.02,
        "c/a {} (upper slave) against {} (lower slave)",
        u.c / u.a,
        l.c / l.a
    );
}

/// A contact 16 times wider (a/R = 0.12: the approach and the drag 256 times the case's, the
/// mesh's contact size and zone 16 times): the slave normals turn by up to 0.12 rad across
/// it. Pressed alone, no node slips but the outermost two (one material: no tangential force
/// in theory; along the slave normals alone 6 interior nodes slipped here, 12–18 on level 3);
/// dragged, the stick zone stays centred (19 % of a off the axis along the slave normals on
/// level 3; measured 0.15 % and 0.16 % here) and c/a agrees with Cattaneo (measured +0.1 % and
/// +1.3 %).
#[test]
fn a_wide_contact_does_not_slip_under_pressing_and_its_stick_zone_stays_centred() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let k = 16.0;
    let m = mesh(tmp.path(), k);
    let load = [
        format!("dirichlet.0.value=[\"free\", {:?}]", -1.5e-4 * k * k),
        format!("dirichlet.1.value=[{:?}, \"free\"]", 3.0e-5 * k * k),
    ];
    for slave in ["upper", "lower"] {
        let mut pressed = load.to_vec();
        pressed.push("load.factors=[0.0]".into());
        let s = run(2, &m, slave, &pressed);
        let mut rows = s.contact_rows();
        rows.retain(|r| r.active());
        rows.sort_by(|a, b| a.f("x").total_cmp(&b.f("x")));
        // but for the outermost nodes, which carry almost no force
        let slipping: Vec<f64> = (rows[1..rows.len() - 1].iter())
            .filter(|r| r.tangential() == "slip")
            .map(|r| r.f("x"))
            .collect();
        assert!(
            slipping.is_empty(),
            "{slave} slave, pressed alone: slip at x = {slipping:?}"
        );
        let s = run(2, &m, slave, &load);
        assert_coulomb(&s, slave);
        let z = zone(&s);
        let cattaneo = (1.0 - z.q / (MU * z.p)).sqrt();
        eprintln!(
            "{slave} slave: {z:?}, c/a {:.4}, Cattaneo {cattaneo:.4}",
            z.c / z.a
        );
        assert_stick_zone(&z, cattaneo, slave);
    }
}

/// The ball of tests/meshes/ball_on_block.geo resting under its weight on the block, whose
/// whole top is the slave side: its nodes beside the ball's silhouette are covered by the
/// master only in part, and their frame must be the slave's own normal (a "common normal"
/// from those couplings put such a node 1.6 deep inside the ball: the case was refused as a
/// misplaced obstacle). `friction` the [contact] friction value.
fn ball_on_block(dir: &Path, mesh: &Path, friction: &str) -> PathBuf {
    let case = dir.join(format!("ball_on_block_{}.toml", friction.len()));
    let text = format!(
        "[mesh]\nfile = {}\n\
         [[material]]\ngroup = \"ball\"\nyoung = 1.0\npoisson = 0.3\nmodel = \"3d\"\n\
         [[material]]\ngroup = \"block\"\nyoung = 5.0\npoisson = 0.25\nmodel = \"3d\"\n\
         [body_force]\nvalue = [0.0, 0.0, -0.01]\n\
         [[dirichlet]]\ngroup = \"block_bottom\"\nvalue = [0.0, 0.0, 0.0]\n\
         [contact]\ngroup = \"block_top\"\nobstacle = {{ type = \"body\", group = \"ball_surf\" }}\n\
         friction = {friction}\n\
         [output]\nfields = [\"displacement\", \"contact\"]\n",
        toml_path(mesh)
    );
    std::fs::write(&case, text).expect("case file");
    case
}

#[test]
fn a_slave_side_reaching_beyond_the_masters_silhouette_takes_friction() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = tmp.path().join("ball_on_block.msh");
    gmsh("ball_on_block.geo", 3, 0.1, &mesh);
    let frictionless = solve(2, &ball_on_block(tmp.path(), &mesh, "\"none\""), &[]);
    frictionless.assert_converged("frictionless");
    let gaps0 = columns(&frictionless.contact_rows_by_id(), &["gap0"]);
    let weight = frictionless.total_force()[2];
    assert!(
        weight < 0.0,
        "the ball's weight {weight:e} on the block top"
    );
    for (law, np) in [
        ("{ law = \"coulomb\", mu = 0.3 }", 2),
        ("{ law = \"coulomb\", mu = 0.3 }", 3),
        ("{ law = \"tresca\", threshold = 1e-4 }", 2),
    ] {
        let what = format!("{law} on {np} ranks");
        let s = solve(np, &ball_on_block(tmp.path(), &mesh, law), &[]);
        s.assert_converged(&what);
        let rows = s.contact_rows_by_id();
        assert_eq!(rows.len(), gaps0.len(), "{what}: slave nodes");
        // the ball rests on its pole: no slave node starts inside it
        for (id, r) in &rows {
            let g = r.f("gap0");
            assert!(
                g >= -1e-12,
                "{what}: node {id} starts {g:e} inside (frictionless {:e})",
                gaps0[id][0]
            );
        }
        let f = s.total_force();
        assert!(
            (f[2] - weight).abs() <= 1e-10 * weight.abs()
                && f[0].abs() + f[1].abs() <= 1e-10 * weight.abs(),
            "{what}: total force {f:?} against the weight {weight:e}"
        );
        assert!(s.active_node_ids().len() > 3, "{what}: active nodes");
    }
}

/// The zone's edge on a half model (y ≥ 0): in each of six 30° sectors around the axis, the
/// midpoint between the outermost node of `inside` and the innermost node of `outside` beyond
/// it, averaged over the sectors (scripts/bench-mindlin's "edge" measure).
fn half_disc_edge(rows: &[(f64, f64, bool, bool)]) -> f64 {
    let sectors = 6;
    let mut sum = 0.0;
    for k in 0..sectors {
        let (lo, hi) = (PI * k as f64 / 6.0, PI * (k + 1) as f64 / 6.0);
        let sec: Vec<_> = (rows.iter())
            .filter(|r| (lo..hi).contains(&r.1.atan2(r.0)))
            .collect();
        let r_in = (sec.iter())
            .filter(|r| r.2)
            .map(|r| r.0.hypot(r.1))
            .fold(0.0, f64::max);
        assert!(r_in > 0.0, "sector {k}: no node inside the zone");
        let r_out = (sec.iter())
            .filter(|r| r.3)
            .map(|r| r.0.hypot(r.1))
            .filter(|&r| r > r_in)
            .fold(f64::INFINITY, f64::min);
        sum += if r_out.is_finite() {
            0.5 * (r_in + r_out)
        } else {
            r_in
        };
    }
    sum / sectors as f64
}

/// Mindlin between two 3D bodies of one material (cases/bodies/mindlin_bodies3d.toml on level
/// 0 of its geometry: a lens of radius 10 on a block, half-symmetric, 15 411 unknowns): pressed
/// alone, the zone sticks but for its rim; dragged to Q/(μP) ≈ 0.81, the contact radius a is
/// Hertz' and the stick zone a centred disc of Mindlin's radius c = a (1 − Q/(μP))^(1/3).
/// Measured here: a −0.5 % from Hertz, c/a −2.3 % from Mindlin, the stick centre 0.01 c off
/// the axis; 7 of 124 nodes slip under the pressing (docs/numbers.md, "Mindlin between two
/// bodies").
#[test]
fn a_lens_dragged_on_a_block_has_mindlins_stick_zone() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = tmp.path().join("mindlin_bodies3d.msh");
    gmsh_file(
        &repo("cases/bodies/mindlin_bodies3d.geo"),
        3,
        &["-setnumber", "L", "0"],
        &mesh,
    );
    let set = format!("mesh.file={}", toml_path(&mesh));
    let s = solve(2, &repo("cases/bodies/mindlin_bodies3d.toml"), &[&set]);
    s.assert_converged("the lens on the block");
    let steps = s.summary["load"]["steps"].as_array().expect("load.steps");
    let count = |k: usize, key: &str| steps[k][key].as_u64().expect("stick / slip counts");
    let (stick0, slip0) = (count(0, "stick"), count(0, "slip"));
    assert!(
        slip0 * 10 <= stick0 + slip0,
        "pressed alone: {slip0} of {} nodes slip",
        stick0 + slip0
    );
    // the half model's forces: P and Q of the whole contact are twice these
    let f = s.total_force();
    let (p, q) = (2.0 * f[2].abs(), 2.0 * f[0].abs());
    let ratio = q / (MU * p);
    assert!((0.7..0.9).contains(&ratio), "Q/(μP) = {ratio}");
    let (young, nu, radius) = (1.0, 0.3, 10.0);
    let e_star = young / (2.0 * (1.0 - nu * nu));
    let hertz_a = (3.0 * p * radius / (4.0 * e_star)).cbrt();
    let rows: Vec<(f64, f64, bool, bool)> = (s.contact_rows().iter())
        .map(|r| {
            let active = r.active();
            let stick = active && r.tangential() == "stick";
            (r.f("x"), r.f("y"), active, stick)
        })
        .collect();
    let zone: Vec<_> = rows.iter().map(|r| (r.0, r.1, r.2, !r.2)).collect();
    let a = half_disc_edge(&zone);
    assert!(
        (a / hertz_a - 1.0).abs() < 0.03,
        "a = {a} against Hertz' {hertz_a}"
    );
    let sticking: Vec<_> = rows.iter().map(|r| (r.0, r.1, r.3, r.2 && !r.3)).collect();
    let c = half_disc_edge(&sticking);
    let mindlin = (1.0 - ratio).cbrt();
    assert!(
        (c / a / mindlin - 1.0).abs() < 0.05,
        "c/a = {} against Mindlin's {mindlin} (a = {a}, c = {c})",
        c / a
    );
    let xs: Vec<f64> = rows.iter().filter(|r| r.3).map(|r| r.0).collect();
    let centre = xs.iter().sum::<f64>() / xs.len() as f64;
    eprintln!(
        "a {a} (Hertz {hertz_a}), c/a {} (Mindlin {mindlin}), centre {centre}, Q/(μP) {ratio}",
        c / a
    );
    assert!(
        centre.abs() < 0.1 * c,
        "the stick zone's centre {centre} off the axis (c = {c})"
    );
}
