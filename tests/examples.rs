//! The example case files under examples/: every one is a valid case file (the reader accepts
//! it as written), and the 2D ones, whose meshes are committed, run to the end on 2 ranks.

mod common;

use common::*;
use signorini_mpi::case::Case;
use std::path::PathBuf;

fn example_cases() -> Vec<PathBuf> {
    let mut all: Vec<PathBuf> = std::fs::read_dir(repo("examples"))
        .expect("examples/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    all.sort();
    all
}

#[test]
fn every_example_case_file_is_valid() {
    let all = example_cases();
    assert!(all.len() >= 10, "{all:?}");
    for p in &all {
        // the reader alone: some examples' meshes are made by `scripts/mesh examples` (too
        // big to commit), and a fresh clone does not have them (Case::load would say so)
        let text = std::fs::read_to_string(p).expect("example case file");
        let case =
            Case::parse(&text, p, &[], None).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        assert!(
            case.mesh.file.is_absolute(),
            "{}: the mesh path is resolved against the case file",
            p.display()
        );
    }
}

/// The 2D examples (committed meshes) run to the end on 2 ranks, every step converged, and each
/// gives the physics its comment promises, checked against references computed here: Hertz's
/// line contact, the geometry of the rigid indenters, mirror symmetry, the load's resultant,
/// and the global force balance of summary.json's certificate.
#[test]
fn the_2d_examples_run() {
    for name in [
        "disk_plates.toml",
        "hertz_steps.toml",
        "indent_height2d.toml",
        "indent_punch2d.toml",
        "indent_wedge2d.toml",
        "stacked_blocks.toml",
    ] {
        let s = solve(2, &repo(&format!("examples/{name}")), &[]);
        if let Some(load) = s.summary.get("load") {
            assert_eq!(load["completed"], true, "{name}: {}", s.run.output());
        } else {
            s.assert_converged(name);
        }
        // Σ applied + Σ contact + Σ reactions = 0 (round-off is ~1e-15 of the force through
        // the body)
        let eq = s.f(&["certificate", "equilibrium", "relative"]);
        assert!(eq <= 1e-8, "{name}: equilibrium defect {eq:e}");
        match name {
            "disk_plates.toml" => disk_plates(&s),
            "hertz_steps.toml" => hertz_steps(&s),
            "indent_height2d.toml" => height2d(&s),
            "indent_punch2d.toml" => punch2d(&s),
            "indent_wedge2d.toml" => wedge2d(&s),
            "stacked_blocks.toml" => stacked_blocks(&s),
            _ => unreachable!(),
        }
    }
}

/// stacked_blocks: the two body pairs each carry the load p = 0.005 (unit width) and the top
/// moves down by p Σ (1 − ν_i²) / E_i, the exact uniform-stress solution, to 1e-10.
fn stacked_blocks(s: &Solved) {
    let p = 0.005;
    let pairs = s.summary["contact"]["pairs"].as_array().expect("pairs");
    assert_eq!(pairs.len(), 2);
    for pair in pairs {
        let f = floats(&pair["total_force"]);
        assert!((f[1].abs() - p).abs() < 1e-10 * p, "pair force {f:?}");
    }
    let compliance: f64 = [(1.0, 0.45), (3.0, 0.1), (2.0, 0.3)]
        .iter()
        .map(|(e, nu): &(f64, f64)| (1.0 - nu * nu) / e)
        .sum();
    let top = -p * compliance;
    let u = s.displacement();
    let lowest = u.values().map(|v| v[1]).fold(f64::INFINITY, f64::min);
    assert!(
        (lowest - top).abs() < 1e-10 * top.abs(),
        "the top moves by {lowest:e}, exact {top:e}"
    );
}

/// Copies `from` (a directory of the repository) into `to`, only the files `keep` accepts.
fn copy_tree(
    from: &std::path::Path,
    to: &std::path::Path,
    keep: &dyn Fn(&std::path::Path) -> bool,
) {
    for e in std::fs::read_dir(from).expect("read_dir") {
        let p = e.expect("entry").path();
        let dst = to.join(p.file_name().expect("name"));
        if p.is_dir() {
            if p.file_name()
                .is_some_and(|n| n == "meshes" || n == "__pycache__")
                && !keep(&p)
            {
                continue;
            }
            copy_tree(&p, &dst, keep);
        } else if keep(&p) {
            std::fs::create_dir_all(to).expect("mkdir");
            std::fs::copy(&p, &dst).expect("copy");
        }
    }
}

/// Every example runs from a tree where its mesh is absent: `scripts/run EXAMPLE` makes the mesh
/// (checked with `--check`: the case and the mesh read, nothing solved), or, for the big meshes
/// of `scripts/mesh examples` (the message path, SIGNORINI_NO_MESH=1, kept quick), stops with a
/// message that names that command.
#[test]
fn every_example_makes_its_mesh_or_names_the_command() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let tree = tmp.path().join("clone");
    let all = |_: &std::path::Path| true;
    copy_tree(&repo("scripts"), &tree.join("scripts"), &all);
    copy_tree(&repo("examples"), &tree.join("examples"), &all);
    // the geometry and the mesh scripts, no mesh
    copy_tree(
        &repo("cases"),
        &tree.join("cases"),
        &|p: &std::path::Path| p.extension().is_some_and(|x| x == "geo" || x == "py"),
    );
    let mut made = 0;
    for case in example_cases() {
        let name = case.file_name().unwrap().to_string_lossy().to_string();
        let copy = tree.join("examples").join(&name);
        let text = std::fs::read_to_string(&copy).expect("example");
        let mesh = Case::parse(&text, &copy, &[], None)
            .expect("valid")
            .mesh
            .file;
        // examples share meshes: take away what an example before made
        let _ = std::fs::remove_file(&mesh);
        let mut cmd = std::process::Command::new(tree.join("scripts/mesh"));
        cmd.arg("for").arg(&mesh).arg("--print-command");
        let r = run_with_timeout(cmd, std::time::Duration::from_secs(60));
        r.expect_code(0, &format!("{name}: scripts/mesh knows {}", mesh.display()));
        let big = r.stdout.trim() == "scripts/mesh examples";
        let mut cmd = std::process::Command::new(tree.join("scripts/run"));
        cmd.arg(&copy).args(["-n", "1", "--check"]);
        cmd.env("SIGNORINI_BIN", binary()).current_dir(tmp.path());
        mpi_env(&mut cmd);
        if big {
            cmd.env("SIGNORINI_NO_MESH", "1");
        }
        let r = run_with_timeout(cmd, std::time::Duration::from_secs(300));
        if big {
            assert_eq!(r.code, Some(1), "{name}: {}", r.output());
            assert!(
                r.stderr.contains("make it with 'scripts/mesh examples'"),
                "{name}: {}",
                r.output()
            );
            assert!(!mesh.exists());
        } else {
            r.expect_code(0, &format!("{name}: scripts/run --check"));
            assert!(r.stderr.contains("making it"), "{name}: {}", r.output());
            assert!(r.stdout.contains("is valid"), "{name}: {}", r.output());
            assert!(mesh.exists(), "{name}: the mesh was made");
            made += 1;
        }
    }
    assert!(made >= 5, "{made}");
}

/// Hertz's line contact of a cylinder (radius `r`) on a rigid plane under the force `p` per
/// unit thickness, plane strain (Johnson, Contact Mechanics, 4.3): the half width
/// a = √(4 p r / (π E*)), E* = E / (1 − ν²), and the peak pressure 2 p / (π a).
fn hertz_line(p: f64, r: f64, young: f64, poisson: f64) -> (f64, f64) {
    let e_star = young / (1.0 - poisson * poisson);
    let a = (4.0 * p * r / (std::f64::consts::PI * e_star)).sqrt();
    (a, 2.0 * p / (std::f64::consts::PI * a))
}

/// The largest distance between neighbouring contact nodes (by x) with |x| ≤ `within` and y
/// on the side `below` (y < 0) or above: the resolution of a contact width.
fn spacing(s: &Solved, within: f64, below: Option<bool>) -> f64 {
    let mut xs: Vec<f64> = s
        .contact_rows()
        .iter()
        .filter(|r| below.is_none_or(|b| (r.f("y") < 0.0) == b))
        .map(|r| r.f("x"))
        .filter(|x| x.abs() <= within)
        .collect();
    xs.sort_by(f64::total_cmp);
    assert!(xs.len() >= 3, "contact nodes near the centre: {xs:?}");
    xs.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max)
}

/// The active contact nodes: (x, y, u_x, u_y), u from solution.h5.
fn active_nodes(s: &Solved) -> Vec<[f64; 4]> {
    let u = s.displacement();
    s.contact_rows()
        .iter()
        .filter(|r| r.active())
        .map(|r| {
            let ui = &u[&r.node_id()];
            [r.f("x"), r.f("y"), ui[0], ui[1]]
        })
        .collect()
}

/// The half disk (R = 1, E = 1, ν = 0.3) between two plates: the plates carry opposite forces
/// and, the mesh being mirror-symmetric about y = 0, the same contact; each contact is Hertz's
/// (the full disk's force, twice the half's) to within the contact nodes' spacing.
fn disk_plates(s: &Solved) {
    let pairs = get(&s.summary, &["contact", "pairs"])
        .as_array()
        .expect("pairs");
    assert_eq!(pairs.len(), 2);
    let force = |i: usize| pairs[i]["total_force"][1].as_f64().unwrap();
    let (bottom, top) = (force(0), force(1));
    assert!(bottom > 0.0, "the bottom plate pushes up: {bottom}");
    assert!(
        rel(bottom, -top) <= 1e-8,
        "plate forces {bottom:e}, {top:e}"
    );
    let width = |i: usize| pairs[i]["half_width"].as_f64().unwrap();
    assert!(rel(width(0), width(1)) <= 1e-8, "{pairs:?}");
    assert_eq!(pairs[0]["active_count"], pairs[1]["active_count"]);
    let (a, _) = hertz_line(2.0 * bottom, 1.0, 1.0, 0.3);
    let h = spacing(s, 0.3, Some(true));
    println!(
        "disk_plates: half width {} against Hertz {a} (spacing {h})",
        width(0)
    );
    assert!((width(0) - a).abs() <= h, "half width {} vs {a}", width(0));
}

/// The Hertz disk (R = 1, E = 2, ν = 0.3) under a pressure of 0.02 × the factor on the chords of
/// its top eighth: the contact force is the load's resultant, 0.02 × factor × 2 sin(π/8) (the
/// chords span 2 sin(π/8)); half width and peak pressure are Hertz's (within the nodes' spacing
/// and 10 %); frictionless, the last step (0.5) ends where the second (0.5) ended.
fn hertz_steps(s: &Solved) {
    let rows = read_csv(&s.dir.join("history.csv"));
    assert_eq!(rows.len(), 5);
    let h = spacing(s, 0.3, Some(true));
    for r in &rows {
        let factor = r.f("factor");
        let p = 0.02 * factor * 2.0 * (std::f64::consts::PI / 8.0).sin();
        let fy = r.f("force_y");
        assert!(
            rel(fy, p) <= 1e-8,
            "factor {factor}: force {fy:e}, load {p:e}"
        );
        let (a, p0) = hertz_line(p, 1.0, 2.0, 0.3);
        let (w, pm) = (r.f("half_width"), r.f("max_pressure"));
        println!("hertz_steps, factor {factor}: a {w} (Hertz {a}), p_max {pm} (Hertz {p0})");
        assert!((w - a).abs() <= h, "factor {factor}: half width {w} vs {a}");
        assert!(
            (pm - p0).abs() <= 0.1 * p0,
            "factor {factor}: p_max {pm} vs {p0}"
        );
    }
    let (u2, u5) = (step_displacement(&s.dir, 2), step_displacement(&s.dir, 5));
    let (d, scale) = max_diff(&u5, &u2);
    assert!(
        scale > 0.0 && d <= 1e-8 * scale,
        "step 5 against 2: {d:e} of {scale:e}"
    );
}

/// The block on the wavy foundation h(x) = 0.005 cos(4πx) − 0.004: five contact zones, each
/// around a crest (x = 0, ±0.5, ±1; the troughs at ±0.25, ±0.75 stay free), the deformed
/// bottom on the foundation there, the highest pressure on a crest.
fn height2d(s: &Solved) {
    let crest = |x: f64| (x - 0.5 * (x / 0.5).round()).abs();
    let mut xs = Vec::new();
    for [x, y, ux, uy] in active_nodes(s) {
        assert!(
            crest(x) <= 0.1,
            "an active node at x = {x}, away from the crests"
        );
        let h = 0.005 * (4.0 * std::f64::consts::PI * (x + ux)).cos() - 0.004;
        // the contact condition holds along the foundation's normal; vertically to second
        // order in its slope (measured ~4e-6 of the 0.009 relief)
        assert!(
            (y + uy - h).abs() <= 1e-2 * 0.009,
            "x = {x}: {} off h",
            y + uy - h
        );
        xs.push(x);
    }
    xs.sort_by(f64::total_cmp);
    let zones = 1 + xs.windows(2).filter(|w| w[1] - w[0] > 0.2).count();
    assert_eq!(zones, 5, "active x: {xs:?}");
    let rows = s.contact_rows();
    let peak = rows
        .iter()
        .max_by(|a, b| a.f("pressure").total_cmp(&b.f("pressure")))
        .expect("rows");
    assert!(
        crest(peak.f("x")) <= 0.05,
        "peak pressure at x = {}",
        peak.f("x")
    );
}

/// The flat punch (half width 0.1, corners rounded with radius 0.02, flat for |x| ≤ 0.08) 0.005
/// into the block: its flat part in contact, the deformed top on it (y + u_y = 0.995), nothing
/// beyond its footprint, the zone symmetric about x = 0 to the nodes' spacing.
fn punch2d(s: &Solved) {
    let active = active_nodes(s);
    for &[x, y, _, uy] in &active {
        assert!(
            x.abs() <= 0.1,
            "an active node at x = {x}, beyond the punch"
        );
        if x.abs() <= 0.08 {
            assert!(
                (y + uy - 0.995).abs() <= 1e-9,
                "x = {x}: y + u_y = {}",
                y + uy
            );
        }
    }
    let free: Vec<f64> = s
        .contact_rows()
        .iter()
        .filter(|r| !r.active() && r.f("x").abs() <= 0.07)
        .map(|r| r.f("x"))
        .collect();
    assert!(
        free.is_empty(),
        "nodes under the flat part not in contact: {free:?}"
    );
    symmetric_zone(s, &active, "punch");
}

/// The wedge (tip 0.02 below the top centre, faces rising at 10°): the deformed top on its faces,
/// y + u_y = 0.98 + |x + u_x| tan 10°, at every active node; the zone symmetric about x = 0 to
/// the nodes' spacing.
fn wedge2d(s: &Solved) {
    let active = active_nodes(s);
    let slope = 10f64.to_radians().tan();
    for &[x, y, ux, uy] in &active {
        let face = 0.98 + (x + ux).abs() * slope;
        assert!(
            (y + uy - face).abs() <= 1e-9,
            "x = {x}: {} off the face",
            y + uy - face
        );
    }
    symmetric_zone(s, &active, "wedge");
}

fn symmetric_zone(s: &Solved, active: &[[f64; 4]], what: &str) {
    assert!(!active.is_empty(), "{what}: nothing in contact");
    let lo = active.iter().map(|a| a[0]).fold(f64::INFINITY, f64::min);
    let hi = active
        .iter()
        .map(|a| a[0])
        .fold(f64::NEG_INFINITY, f64::max);
    let h = spacing(s, 0.2, None);
    assert!(lo < 0.0 && hi > 0.0, "{what}: zone [{lo}, {hi}]");
    assert!(
        (lo + hi).abs() <= h,
        "{what}: zone [{lo}, {hi}], spacing {h}"
    );
}
