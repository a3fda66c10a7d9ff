//! Warnings for runs that succeed but look wrong (issue 50, item 1; docs/warnings.md): one log
//! line `warning: ...` each, summary.json's `warnings` list, exit 0 — the same warnings on 1, 2
//! and 3 ranks; a body that the contact cannot hold is "no support", not "Newton cycling".
//! The cases: tests/cases/warnings/*.toml (the 2D and 3D blocks of cases/blocks) and
//! cases/blocks, cases/hertz, tests/cases/sphere3d.toml. Each warning also in 3D, on the second
//! of two contact pairs (2D and 3D), and under force control (a forced pair always ends in
//! contact: no pressed_without_contact for it).

mod common;
use common::*;
use serde_json::Value;

fn warnings_case(name: &str) -> std::path::PathBuf {
    repo(&format!("tests/cases/warnings/{name}"))
}

/// summary.json's `warnings` list (present also when empty).
fn warnings(s: &Solved) -> Vec<Value> {
    get(&s.summary, &["warnings"])
        .as_array()
        .unwrap_or_else(|| panic!("warnings is not a list: {}", s.run.output()))
        .clone()
}

fn text<'a>(w: &'a Value, key: &str) -> &'a str {
    w.get(key).and_then(Value::as_str).unwrap_or("")
}

/// Solves `case` on 1, 2 and 3 ranks; each run exits 0 with the warnings `codes` (in order),
/// each logged on one `warning:` line; returns each run's warning of `codes[0]`, which names
/// `key`. The same codes, keys, pairs and (to 1e-6) values on every rank count.
fn warned_alike(
    case: &std::path::Path,
    sets: &[&str],
    codes: &[&str],
    key: Option<&str>,
) -> Vec<Value> {
    let mut runs: Vec<Vec<Value>> = Vec::new();
    for np in [1, 2, 3] {
        let s = solve(np, case, sets);
        let list = warnings(&s);
        let got: Vec<&str> = list.iter().map(|w| text(w, "code")).collect();
        assert_eq!(got, codes, "{np} ranks: {list:#?}\n{}", s.run.output());
        let lines: Vec<&str> = (s.run.stdout.lines())
            .filter(|l| l.starts_with("warning:"))
            .collect();
        assert_eq!(lines.len(), list.len(), "{}", s.run.output());
        for (w, line) in list.iter().zip(&lines) {
            assert!(line.contains(text(w, "message")), "{line}");
            let (value, threshold) = (
                w["value"].as_f64().unwrap(),
                w["threshold"].as_f64().unwrap(),
            );
            assert!(value > threshold, "{w:#?}");
        }
        assert_eq!(list[0].get("key").and_then(Value::as_str), key, "{list:#?}");
        runs.push(list);
    }
    for list in &runs[1..] {
        for (w, w0) in list.iter().zip(&runs[0]) {
            for k in ["code", "key", "pair"] {
                assert_eq!(w.get(k), w0.get(k), "{runs:#?}");
            }
            let (a, b) = (w["value"].as_f64().unwrap(), w0["value"].as_f64().unwrap());
            assert!((a - b).abs() <= 1e-6 * b.abs(), "{runs:#?}");
        }
    }
    runs.into_iter().map(|mut l| l.remove(0)).collect()
}

#[test]
fn a_pressed_plate_that_touches_nothing_is_warned_about() {
    // The plate's normal the wrong way: its motion down moves it away as the contact sees it.
    let seen = warned_alike(
        &warnings_case("plate_pressed.toml"),
        &[],
        &["pressed_without_contact"],
        Some("contact.obstacle"),
    );
    for w in &seen {
        assert_eq!(text(w, "pair"), "contact");
        // every top node ends the motion's 0.01 beyond the plate (the block is held, unloaded)
        assert!(text(w, "message").contains("1.0000e-2"), "{w:#?}");
        let x = w["at"]["x"].as_array().unwrap();
        assert_eq!(x[1].as_f64(), Some(0.5), "a node of the top face: {w:#?}");
    }
}

/// A block pressed down onto a plane with its left side as the contact group: the side's
/// corner touches, the bottom goes through the plane unseen (0.0118 deep on the block of
/// cases/blocks) — `boundary_through_obstacle`, the same on 1, 2 and 3 ranks and on the plain
/// path. Before, no warning of it, and a `pulling_contact_force` on the corner decided by the
/// sign of round-off (on 2 ranks, not on 1 or 3; on the plain path on 1 and 2). Held at the
/// bottom by Dirichlet data that push it into the plane: the same warning, naming them; with
/// the bottom as the group: none.
#[test]
fn boundary_nodes_outside_the_group_that_go_through_the_obstacle_are_warned_about() {
    let dir = tempfile::tempdir().expect("tempdir");
    let case = write_case(
        &dir.path().join("block.toml"),
        &format!(
            r#"[mesh]
file = {}
[material]
young = 1.0
poisson = 0.3
model = "plane_strain"
[[dirichlet]]
group = "top"
value = [0.0, -0.01]
[contact]
group = "bottom"
obstacle = {{ type = "plane", point = [0.0, 0.0], normal = [0.0, 1.0] }}
"#,
            toml_path(&repo("cases/blocks/block2d.msh"))
        ),
    );
    let side = "contact.group=\"left\"";
    for path in ["solver.path=\"auto\"", "solver.path=\"plain\""] {
        let seen = warned_alike(
            &case,
            &[side, path],
            &["boundary_through_obstacle"],
            Some("contact.group"),
        );
        for w in &seen {
            // a node of the bottom, which starts on the plane
            let x = w["at"]["x"].as_array().unwrap();
            assert_eq!(x[1].as_f64(), Some(0.0), "{w:#?}");
            assert!(text(w, "message").contains("in no contact group"), "{w:#?}");
        }
    }
    let held = warned_alike(
        &case,
        &["dirichlet.0.group=\"bottom\""],
        &["boundary_through_obstacle"],
        Some("contact.group"),
    );
    for w in &held {
        assert!(
            text(w, "message").contains("held by Dirichlet data"),
            "{w:#?}"
        );
        assert!(
            (w["value"].as_f64().unwrap() - 0.005).abs() < 1e-12,
            "{w:#?}"
        );
    }
    let quiet = solve(1, &case, &[]);
    assert!(warnings(&quiet).is_empty(), "{}", quiet.run.output());
}

/// Two `[[dirichlet]]` entries on different groups that prescribe a shared node's component
/// differently (the corner of `left` = [0, 0] and `bottom` = [0.01, 0]): the later entry's
/// value holds, and `dirichlet_overridden` says so (before: silently), on 1, 2 and 3 ranks. A
/// later entry on the same group overrides on purpose (examples/sphere_drag.toml): no warning;
/// nor where the entries agree at the corner.
#[test]
fn a_dirichlet_entry_that_overrides_another_at_a_shared_node_is_warned_about() {
    let dir = tempfile::tempdir().expect("tempdir");
    let case = |name: &str, entries: &[(&str, &str)]| {
        let mut text = format!(
            "[mesh]\nfile = {}\n[material]\nyoung = 1.0\npoisson = 0.3\n\
             model = \"plane_strain\"\n",
            toml_path(&repo("cases/blocks/block2d.msh"))
        );
        for (group, rest) in entries {
            text += &format!("[[dirichlet]]\ngroup = \"{group}\"\n{rest}\n");
        }
        write_case(&dir.path().join(name), &text)
    };
    let clamped = ("left", "value = [0.0, 0.0]");
    let over = case("over.toml", &[clamped, ("bottom", "value = [0.001, 0.0]")]);
    let seen = warned_alike(
        &over,
        &[],
        &["dirichlet_overridden"],
        Some("dirichlet[1].value"),
    );
    for w in &seen {
        // the corner (−1, 0), once
        assert_eq!(w["value"].as_f64(), Some(1.0), "{w:#?}");
        let x = w["at"]["x"].as_array().unwrap();
        assert_eq!(
            (x[0].as_f64(), x[1].as_f64()),
            (Some(-1.0), Some(0.0)),
            "{w:#?}"
        );
        assert!(text(w, "message").contains("0.001 instead of 0"), "{w:#?}");
    }
    // the same value, held at the right side and ramped on the top: two histories
    let held = case(
        "held.toml",
        &[
            ("left", "value = [\"free\", 0.0]"),
            ("right", "value = [0.001, \"free\"]\nramp = false"),
            ("top", "value = [0.001, \"free\"]"),
        ],
    );
    let seen = warned_alike(
        &held,
        &[],
        &["dirichlet_overridden"],
        Some("dirichlet[2].value"),
    );
    assert!(
        text(&seen[0], "message").contains("0.001 instead of 0.001 held (ramp = false)"),
        "{seen:#?}"
    );
    for quiet in [
        case(
            "same_group.toml",
            &[clamped, ("left", "value = [0.001, \"free\"]")],
        ),
        case(
            "agree.toml",
            &[clamped, ("bottom", "value = [\"free\", 0.0]")],
        ),
    ] {
        let s = solve(1, &quiet, &[]);
        assert!(warnings(&s).is_empty(), "{}", s.run.output());
    }
}

#[test]
fn a_contact_force_that_lifts_the_surface_is_warned_about() {
    let seen = warned_alike(
        &warnings_case("plate_pulling.toml"),
        &[],
        &["pulling_contact_force"],
        Some("contact.obstacle"),
    );
    // every active node pulls: the whole normal force
    assert!(
        seen.iter().all(|w| w["value"].as_f64() == Some(1.0)),
        "{seen:#?}"
    );
}

#[test]
fn a_start_on_the_obstacles_far_side_is_warned_about() {
    // the issue's plate, normal the wrong way, 0.005 inside: the top face is lifted as well
    let seen = warned_alike(
        &warnings_case("plate_inside.toml"),
        &[],
        &["start_inside_obstacle", "pulling_contact_force"],
        Some("contact.obstacle"),
    );
    // 0.005 of the block's size 2, on the far side
    for w in &seen {
        let v = w["value"].as_f64().unwrap();
        assert!((v - 0.0025).abs() < 1e-9, "{w:#?}");
        assert!(text(w, "message").contains("far side"), "{w:#?}");
    }
}

#[test]
fn a_start_deeper_than_a_small_overlap_is_warned_about() {
    // cases/blocks/indent2d.toml (the ball 0.01 into the block: an overlap that prescribes
    // the indentation, no warning) with the ball 0.06 into it, 3 % of the block's size 2
    let ball = "contact.obstacle={type=\"sphere\",center=[0.0,1.44],radius=0.5}";
    let case = repo("cases/blocks/indent2d.toml");
    let quiet = solve(1, &case, &[]);
    assert!(warnings(&quiet).is_empty(), "{}", quiet.run.output());
    let seen = warned_alike(
        &case,
        &[ball],
        &["start_inside_obstacle", "large_deformation"],
        Some("contact.obstacle"),
    );
    for w in &seen {
        let v = w["value"].as_f64().unwrap();
        assert!((v - 0.03).abs() < 1e-9, "{w:#?}");
        assert!(text(w, "message").contains("small overlap"), "{w:#?}");
    }
}

#[test]
fn a_strain_beyond_small_deformations_is_warned_about() {
    // cases/blocks/block2d.toml under a pressure of 5 E: the exact strain (1 − ν²) p / E = 4.55
    let seen = warned_alike(
        &repo("cases/blocks/block2d.toml"),
        &["neumann.0.pressure=10.0"],
        &["large_deformation"],
        None,
    );
    for w in &seen {
        let v = w["value"].as_f64().unwrap();
        assert!((v - 4.55).abs() < 1e-6, "{w:#?}");
        assert!(w["at"]["cell"].as_u64().is_some(), "{w:#?}");
        assert_eq!(w["at"]["x"].as_array().map(Vec::len), Some(2), "{w:#?}");
    }
}

#[test]
fn a_load_series_warns_per_step_and_collects_once() {
    let s = solve(2, &warnings_case("plate_pressed.toml"), &["load.steps=2"]);
    let top = warnings(&s);
    assert_eq!(top.len(), 1, "{top:#?}");
    assert_eq!(text(&top[0], "code"), "pressed_without_contact");
    assert_eq!(top[0]["steps"], serde_json::json!([1, 2]), "{top:#?}");
    let steps = get(&s.summary, &["load", "steps"]).as_array().unwrap();
    for st in steps {
        let list = st["warnings"].as_array().unwrap();
        assert_eq!(list.len(), 1, "{st:#?}");
        assert_eq!(text(&list[0], "code"), "pressed_without_contact");
    }
    // logged once, at the step that first raised it
    let lines: Vec<&str> = (s.run.stdout.lines())
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert_eq!(lines.len(), 1, "{}", s.run.output());
    assert!(
        lines[0].starts_with("warning: load step 1: "),
        "{}",
        lines[0]
    );
}

#[test]
fn a_normal_run_has_no_warning() {
    for np in [1, 2] {
        let s = solve(np, &repo("cases/hertz/hertz.toml"), &[]);
        assert!(warnings(&s).is_empty(), "{np} ranks: {}", s.run.output());
        assert!(!s.run.stdout.contains("warning"), "{}", s.run.output());
    }
}

#[test]
fn a_body_that_nothing_holds_is_no_support_not_cycling() {
    let tmp = tempfile::tempdir().unwrap();
    let mut lines = Vec::new();
    for np in [1, 2, 3] {
        let out = tmp.path().join(format!("out{np}"));
        let r = run_solver(np, &warnings_case("plate_unheld.toml"), &[], &out);
        r.expect_code(1, &format!("{np} ranks"));
        let line = (r.stderr.lines())
            .find(|l| l.starts_with("error:"))
            .unwrap_or_else(|| panic!("no error line:\n{}", r.output()))
            .to_string();
        assert!(line.contains("no support"), "{line}");
        assert!(!line.contains("cycling"), "{line}");
        assert!(line.contains("'dirichlet'"), "{line}");
        lines.push(line);
    }
    assert!(lines.iter().all(|l| *l == lines[0]), "{lines:#?}");
}

/// Each warning in 3D (the box of cases/blocks/block3d.msh): the plate of plate_pressed.toml
/// pressed down (pressed_without_contact, the top nodes 0.01 = 0.5 % of the size 2 beyond it),
/// moved up (pulling_contact_force, all of it) and placed 0.005 inside the box (a start on the
/// far side); tests/cases/sphere3d.toml, its sphere 0.0483 into the box at its deepest node
/// (2.4 % of 2: start_inside_obstacle, and large_deformation at 0.15); cases/blocks/
/// block3d.toml under a pressure of E/2: the uniaxial strain p/E = 0.5, exact for P1.
#[test]
fn each_warning_in_3d() {
    let plate = warnings_case("plate3d_pressed.toml");
    for w in warned_alike(
        &plate,
        &[],
        &["pressed_without_contact"],
        Some("contact.obstacle"),
    ) {
        assert!(
            (w["value"].as_f64().unwrap() - 0.005).abs() < 1e-9,
            "{w:#?}"
        );
        let x = w["at"]["x"].as_array().unwrap();
        assert_eq!(x.len(), 3, "{w:#?}");
        assert_eq!(x[2].as_f64(), Some(0.5), "a node of the top face: {w:#?}");
    }
    let up = "contact.motion=[0.0, 0.0, 0.01]";
    for w in warned_alike(
        &plate,
        &[up],
        &["pulling_contact_force"],
        Some("contact.obstacle"),
    ) {
        assert_eq!(w["value"].as_f64(), Some(1.0), "{w:#?}");
    }
    let inside = [
        "contact.obstacle.point=[0.0, 0.0, 0.505]",
        "contact.motion=[0.0, 0.0, 0.0]",
    ];
    for w in warned_alike(
        &plate,
        &inside,
        &["start_inside_obstacle", "pulling_contact_force"],
        Some("contact.obstacle"),
    ) {
        assert!(
            (w["value"].as_f64().unwrap() - 0.0025).abs() < 1e-9,
            "{w:#?}"
        );
        assert!(text(&w, "message").contains("far side"), "{w:#?}");
    }
    for w in warned_alike(
        &repo("tests/cases/sphere3d.toml"),
        &[],
        &["start_inside_obstacle", "large_deformation"],
        Some("contact.obstacle"),
    ) {
        let v = w["value"].as_f64().unwrap();
        assert!(v > 0.02 && v < 0.025, "{w:#?}");
        assert!(text(&w, "message").contains("small overlap"), "{w:#?}");
    }
    for w in warned_alike(
        &repo("cases/blocks/block3d.toml"),
        &["neumann.0.pressure=1.0"],
        &["large_deformation"],
        None,
    ) {
        assert!((w["value"].as_f64().unwrap() - 0.5).abs() < 1e-6, "{w:#?}");
        assert_eq!(w["at"]["x"].as_array().map(Vec::len), Some(3), "{w:#?}");
    }
}

/// The active nodes of pair `i` in summary.json.
fn pair_active(s: &Solved, i: usize) -> u64 {
    get(&s.summary, &["contact", "pairs"])[i]["active_count"]
        .as_u64()
        .expect("active_count")
}

/// Two pairs, 2D (the top plate under force control) and 3D (both plates moved): each
/// contact warning is the second pair's — its code, `contact[1]`, `contact[1].obstacle` —
/// never the first's, which presses the body as it should (active nodes; in 2D its force
/// the prescribed one). The wrong-way plate under the bottom moved up: pressed_without_contact;
/// moved down: pulling_contact_force; placed inside: start_inside_obstacle (far side).
#[test]
fn each_contact_warning_on_the_second_of_two_pairs() {
    let key = Some("contact[1].obstacle");
    for (case, up, down, inside) in [
        (
            "two_plates.toml",
            "contact.1.motion=[0.0, 0.01]",
            "contact.1.motion=[0.0, -0.005]",
            [
                "contact.1.motion=[0.0, 0.0]",
                "contact.1.obstacle.point=[0.0, -0.005]",
            ],
        ),
        (
            "two_plates3d.toml",
            "contact.1.motion=[0.0, 0.0, 0.005]",
            "contact.1.motion=[0.0, 0.0, -0.005]",
            [
                "contact.1.motion=[0.0, 0.0, 0.0]",
                "contact.1.obstacle.point=[0.0, 0.0, -0.005]",
            ],
        ),
    ] {
        let path = warnings_case(case);
        for (sets, codes) in [
            (vec![up], &["pressed_without_contact"][..]),
            (vec![down], &["pulling_contact_force"][..]),
            (
                inside.to_vec(),
                &["start_inside_obstacle", "pulling_contact_force"][..],
            ),
        ] {
            for w in warned_alike(&path, &sets, codes, key) {
                assert_eq!(text(&w, "pair"), "contact[1]", "{case} {sets:?}: {w:#?}");
                assert!(text(&w, "message").starts_with("contact[1]: "), "{w:#?}");
            }
            let s = solve(2, &path, &sets);
            for w in warnings(&s) {
                assert_eq!(text(&w, "pair"), "contact[1]", "{case} {sets:?}: {w:#?}");
            }
            assert!(pair_active(&s, 0) > 0, "{case} {sets:?}");
            if case == "two_plates.toml" {
                let f = floats(&get(&s.summary, &["contact", "pairs"])[0]["total_force"]);
                assert!((f[1] + 0.01).abs() <= 1e-8 * 0.01, "{f:?}");
            }
        }
    }
}

/// Force control: the force balance of a forced pair needs active nodes, so a forced pair
/// cannot end with none (no pressed_without_contact for it: tests/cases/warnings/two_plates.toml
/// raises it for its pair under motion, next to the forced one); the plate of plate_forced.toml,
/// its normal the wrong way, forced along that normal, ends with every top node active and
/// pulling (pulling_contact_force); forced the other way it never reaches the body: exit 2.
#[test]
fn force_control_ends_in_contact_and_warns_of_a_pulling_force() {
    let case = warnings_case("plate_forced.toml");
    for w in warned_alike(
        &case,
        &[],
        &["pulling_contact_force"],
        Some("contact.obstacle"),
    ) {
        assert_eq!(w["value"].as_f64(), Some(1.0), "{w:#?}");
    }
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let r = run_solver(2, &case, &["contact.force=[0.0, -0.01]"], &out);
    r.expect_code(2, "the force away from the body");
    assert!(
        r.stderr.contains("never reaches the body"),
        "{}",
        r.output()
    );
    assert!(r.stderr.contains("'contact.force'"), "{}", r.output());
}

#[test]
fn an_inexact_final_state_is_warned_about_and_names_the_solver_keys() {
    // cases/hertz/hertz.toml on the iterative preset: at solver.rtol = 1e-7 the final state's
    // worst certificate violation is 0.9–1.7e-7 of the problem's scales (1, 2, 3 ranks), above
    // round-off (1e-8) and below the acceptance tolerance (1e-6): a warning with the
    // equation it violates and the solver keys, in the log and in summary.json; at the
    // preset's own rtol (1e-10: 0.7–1.9e-10) none. The value is the Krylov solve's, so it is
    // judged by its range, not compared between rank counts.
    let case = repo("cases/hertz/hertz.toml");
    for np in [1, 2, 3] {
        let s = solve(
            np,
            &case,
            &["solver.preset=\"iterative\"", "solver.rtol=1e-7"],
        );
        s.assert_converged("rtol 1e-7");
        let list = warnings(&s);
        let codes: Vec<&str> = list.iter().map(|w| text(w, "code")).collect();
        assert_eq!(codes, ["inexact_final_state"], "{np} ranks: {list:#?}");
        let w = &list[0];
        let (value, threshold) = (
            w["value"].as_f64().unwrap(),
            w["threshold"].as_f64().unwrap(),
        );
        assert_eq!(threshold, 1e-8, "{w:#?}");
        assert!(value > threshold && value < 1e-6, "{np} ranks: {w:#?}");
        let message = text(w, "message");
        for part in ["violates (3.14)", "'solver.rtol' = 1e-7", "inexact"] {
            assert!(message.contains(part), "{np} ranks: {message}");
        }
        let lines: Vec<&str> = (s.run.stdout.lines())
            .filter(|l| l.starts_with("warning:"))
            .collect();
        assert_eq!(lines, [format!("warning: {message}")], "{}", s.run.output());
        let tight = solve(np, &case, &["solver.preset=\"iterative\""]);
        tight.assert_converged("the preset's rtol");
        assert!(
            warnings(&tight).is_empty(),
            "{np} ranks: {}",
            tight.run.output()
        );
    }
}

/// Two squares (cubes) side by side, meshed apart and never joined, both held at their bottom:
/// two bodies where the picture shows one. The warning `unjoined_nodes` names the mesh, the
/// number of coincident pairs and the first pair by Gmsh tags, the same on 1, 2 and 3 ranks; the
/// same geometry made conformal (`joined = 1`) gives none.
#[test]
fn parts_meshed_apart_and_never_joined_are_warned_about() {
    let tmp = tempfile::tempdir().expect("tempdir");
    for dim in [2usize, 3] {
        let geo = mesh_dir().join(format!("unjoined{dim}d.geo"));
        let (h, bottom, load) = if dim == 2 {
            ("0.1", "[0.0, 0.0]", "[0.001, -0.001]")
        } else {
            ("0.25", "[0.0, 0.0, 0.0]", "[0.001, 0.0, -0.001]")
        };
        let mut seen = Vec::new();
        for joined in [0, 1] {
            let msh = tmp.path().join(format!("u{dim}_{joined}.msh"));
            let j = joined.to_string();
            gmsh_file(
                &geo,
                dim,
                &["-setnumber", "h", h, "-setnumber", "joined", &j],
                &msh,
            );
            let case = tmp.path().join(format!("u{dim}_{joined}.toml"));
            let model = if dim == 2 {
                "model = \"plane_strain\"\n"
            } else {
                ""
            };
            std::fs::write(
                &case,
                format!(
                    "[mesh]\nfile = \"{}\"\n[material]\nyoung = 1.0\npoisson = 0.3\n{model}\
                     [[dirichlet]]\ngroup = \"bottom\"\nvalue = {bottom}\n\
                     [[neumann]]\ngroup = \"top\"\ntraction = {load}\n",
                    msh.file_name().unwrap().to_str().unwrap()
                ),
            )
            .unwrap();
            for np in [1, 2, 3] {
                let s = solve(np, &case, &[]);
                let list = warnings(&s);
                let unjoined: Vec<&Value> = list
                    .iter()
                    .filter(|w| text(w, "code") == "unjoined_nodes")
                    .collect();
                if joined == 1 {
                    assert!(unjoined.is_empty(), "{dim}D joined, {np} ranks: {list:#?}");
                    assert_eq!(get(&s.summary, &["bodies"])["count"], 1);
                    continue;
                }
                assert_eq!(unjoined.len(), 1, "{dim}D, {np} ranks: {list:#?}");
                let w = unjoined[0];
                let message = text(w, "message");
                assert!(s.run.stdout.contains(&format!("warning: {message}")));
                assert!(message.contains("never joined") && message.contains(".msh"));
                assert_eq!(text(w, "key"), "mesh.file");
                assert_eq!(get(&s.summary, &["bodies"])["count"], 2);
                // at least the shared side's corners, at most its nodes on either part
                let pairs = w["value"].as_f64().unwrap();
                assert!(pairs >= f64::from(1 << (dim - 1)), "{w:#?}");
                let x = w["at"]["x"].as_array().unwrap();
                assert_eq!(x[0].as_f64(), Some(1.0), "{w:#?}");
                seen.push((pairs, w["at"].clone(), message.to_string()));
            }
        }
        assert!(seen.windows(2).all(|p| p[0] == p[1]), "{dim}D: {seen:#?}");
    }
}
