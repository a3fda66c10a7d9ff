//! Warnings for runs that succeed but look wrong (issue 50, item 1; docs/warnings.md): one log
//! line `warning: ...` each, summary.json's `warnings` list, exit 0 — the same warnings on 1, 2
//! and 3 ranks; a body that the contact cannot hold is "no support", not "Newton cycling".
//! The cases: tests/cases/warnings/*.toml (the 2D block of cases/blocks) and cases/blocks,
//! cases/hertz.

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
    // the plate, normal the wrong way, 0.005 inside: the top face is lifted as well
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
