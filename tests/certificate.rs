//! The certificate (summary.json's `certificate`, the log's `certificate:` line,
//! docs/method.md "The certificate"): present with finite values on frictionless Hertz, Tresca,
//! Coulomb and force control, on 1 and 2 ranks, with a small global equilibrium residual and
//! force balance; per load step in a series with the worst in the block; `newton.strict`
//! makes a loosened acceptance or a value above 1e-8 an error (exit 1) that names it.

mod common;

use common::*;
use serde_json::Value;
use std::path::PathBuf;

/// Far from round-off (measured: 1e-14 … 4e-14), far below a wrong balance.
const SMALL: f64 = 1e-6;

fn indent() -> PathBuf {
    repo("tests/cases/indent2d_sym.toml")
}

const PRESS: &str = "contact.motion=[0.01, -0.03]";
const TRESCA: &str = "contact.friction={law=\"tresca\", threshold=0.02}";
const COULOMB: &str = "contact.friction={law=\"coulomb\", mu=0.3}";

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// Every number of the block is finite; the values a rule needs are there, the others not.
fn check_block(c: &Value, friction: bool, what: &str) {
    fn finite(v: &Value, at: &str) {
        match v {
            Value::Number(n) => assert!(n.as_f64().unwrap().is_finite(), "{at}: {v}"),
            Value::Array(a) => a.iter().for_each(|x| finite(x, at)),
            Value::Object(o) => o.iter().for_each(|(k, x)| finite(x, &format!("{at}.{k}"))),
            _ => {}
        }
    }
    finite(c, what);
    for k in [
        "penetration",
        "penetration_per_mesh_size",
        "mesh_size",
        "positive_lambda_n",
        "complementarity",
        "worst",
    ] {
        assert!(num(&c[k]) >= 0.0, "{what}: {k} = {}", c[k]);
    }
    assert!(num(&c["mesh_size"]) > 0.0, "{what}");
    assert_eq!(c["friction"].is_object(), friction, "{what}: {c}");
    assert_eq!(c["tangential_force"].is_number(), !friction, "{what}: {c}");
    let eq = &c["equilibrium"];
    assert!(num(&eq["reference"]) >= 0.0, "{what}: {eq}");
    assert!(num(&eq["relative"]) < SMALL, "{what}: {eq}");
    // the residual is the sum of the three parts
    for i in 0..2 {
        let sum: f64 = ["applied", "contact", "reactions"]
            .iter()
            .map(|k| num(&eq[k][i]))
            .sum();
        assert!(
            (sum - num(&eq["residual"][i])).abs() <= 1e-12 * num(&eq["reference"]),
            "{what}: {eq}"
        );
    }
    assert!(num(&c["worst"]) < SMALL, "{what}: {c}");
}

fn certificate_of(s: &Solved, friction: bool, what: &str) -> Value {
    let c = s.summary["certificate"].clone();
    assert!(c.is_object(), "{what}: no certificate block");
    check_block(&c, friction, what);
    // a loaded body: something flows through it
    assert!(num(&c["equilibrium"]["reference"]) > 0.0, "{what}: {c}");
    assert!(
        s.run.stdout.lines().any(|l| l.starts_with("certificate: ")),
        "{what}: no log line:\n{}",
        s.run.output()
    );
    c
}

#[test]
fn frictionless_hertz_on_one_and_two_ranks() {
    let mut all = Vec::new();
    for np in [1, 2] {
        let s = solve(np, &repo("cases/hertz/hertz.toml"), &[]);
        let c = certificate_of(&s, false, &format!("hertz, {np} rank(s)"));
        assert_eq!(c["stop_rule"], "active_set");
        assert_eq!(c["loosened"], false);
        assert!(c.get("force_balance").is_none(), "{c}");
        // a floating disk: no Dirichlet node, the contact carries the whole load
        let eq = &c["equilibrium"];
        assert_eq!(eq["reactions"], serde_json::json!([0.0, 0.0]));
        let load = s.total_force();
        assert!(rel(num(&eq["contact"][1]), load[1]) < SMALL, "{eq}");
        all.push(c);
    }
    // the same numbers on any rank count, up to round-off
    let ap = |c: &Value| num(&c["equilibrium"]["applied"][1]);
    assert!(rel(ap(&all[0]), ap(&all[1])) < 1e-12);
}

#[test]
fn tresca_and_coulomb_on_one_and_two_ranks() {
    for (law, name) in [(TRESCA, "tresca"), (COULOMB, "coulomb")] {
        let mut reactions = Vec::new();
        for np in [1, 2] {
            let s = solve(np, &indent(), &[PRESS, law]);
            let c = certificate_of(&s, true, &format!("{name}, {np} rank(s)"));
            assert_eq!(c["stop_rule"], "active_set", "{name}");
            // the block is clamped at its bottom: the support carries the indenter's force
            let eq = &c["equilibrium"];
            let r = [num(&eq["reactions"][0]), num(&eq["reactions"][1])];
            let f = s.total_force();
            assert!(
                r[1] > 0.0 && rel(r[1], -f[1]) < SMALL,
                "{name}: {eq}, {f:?}"
            );
            reactions.push(r);
        }
        assert!(
            rel(reactions[0][1], reactions[1][1]) < 1e-10,
            "{reactions:?}"
        );
    }
}

#[test]
fn force_control_balances_each_pair() {
    for np in [1, 2] {
        for law in ["contact.friction=\"none\"", COULOMB] {
            let s = solve(
                np,
                &indent(),
                &["contact.force=[0.0, -0.05]", "newton.init=\"auto\"", law],
            );
            let what = format!("{law}, {np} rank(s)");
            let c = certificate_of(&s, law == COULOMB, &what);
            let fb = c["force_balance"].as_array().expect("force_balance");
            assert_eq!(fb.len(), 1, "{what}");
            assert_eq!(fb[0]["key"], "contact.force");
            assert!((num(&fb[0]["force"]) - 0.05).abs() < 1e-15, "{what}");
            assert!(num(&fb[0]["relative"]) < SMALL, "{what}: {fb:?}");
            assert!(rel(num(&fb[0]["carried"]), 0.05) < SMALL, "{what}: {fb:?}");
        }
    }
}

#[test]
fn a_load_series_has_one_per_step_and_the_worst_in_the_block() {
    let s = solve(2, &repo("tests/cases/punch_back.toml"), &[]);
    let steps = s.summary["load"]["steps"].as_array().expect("steps");
    assert!(steps.len() >= 3);
    let mut worst: f64 = 0.0;
    for st in steps {
        let c = &st["certificate"];
        check_block(c, true, &format!("step {}", st["step"]));
        // the step taken back to no load: nothing flows through the body, a zero residual
        let eq = &c["equilibrium"];
        if num(&st["factor"]) == 0.0 {
            assert_eq!(num(&eq["residual_norm"]), 0.0, "{eq}");
        } else {
            assert!(num(&eq["reference"]) > 0.0, "{eq}");
        }
        worst = worst.max(num(&c["worst"]));
    }
    let block = &s.summary["certificate"];
    assert_eq!(num(&block["worst"]), worst);
    let at = block["worst_step"].as_u64().expect("worst_step") as usize;
    assert_eq!(num(&steps[at - 1]["certificate"]["worst"]), worst);
    let csv = std::fs::read_to_string(s.dir.join("history.csv")).expect("history.csv");
    let head = csv.lines().next().unwrap();
    for k in ["stop_rule", "equilibrium_relative", "certificate_worst"] {
        assert!(head.split(',').any(|h| h == k), "{head}");
    }
}

/// The Hertz disk held at its top arc by Dirichlet data, Coulomb with μ = 0.3, and c = 1e7
/// (far above the default 100 E): the condensed Coulomb iteration stalls above 1e-8 ‖λ‖ and is
/// accepted by its certificates alone — a loosened acceptance.
#[test]
fn strict_refuses_a_loosened_acceptance() {
    let tmp = tempfile::tempdir().expect("tmp");
    let case = held_disk(tmp.path(), "[newton]\nc = 1e7\n");
    // without newton.strict: exit 0, the rule said
    let s = solve(1, &case, &[]);
    let c = &s.summary["certificate"];
    assert_eq!(c["stop_rule"], "condensed_coulomb_stall", "{c}");
    assert_eq!(c["loosened"], true);
    assert!(s.run.stdout.contains("(loosened)"), "{}", s.run.output());
    // with it: exit 1, the rule named
    for np in [1, 2] {
        let out = tmp.path().join(format!("strict{np}"));
        let run = run_solver(np, &case, &["newton.strict=true"], &out);
        run.expect_code(1, "newton.strict with a loosened acceptance");
        let text = run.output();
        assert!(
            text.contains("newton.strict") && text.contains("condensed_coulomb_stall"),
            "{text}"
        );
    }
}

#[test]
fn strict_refuses_an_inexact_equilibrium() {
    // GMRES to rtol = 1e-8: (3.14) holds to 1e-7 of its scales (accepted, with a warning),
    // but the global equilibrium is off by more than 1e-8 of the force through the body
    let sets = [
        "contact.motion=[0.0, -0.03]",
        "solver.preset=\"iterative\"",
        "solver.rtol=1e-8",
    ];
    let s = solve(1, &indent(), &sets);
    let eq = num(&s.summary["certificate"]["equilibrium"]["relative"]);
    assert!(eq > 1e-8, "the test needs an inexact solve: {eq:e}");
    let tmp = tempfile::tempdir().expect("tmp");
    let mut strict = sets.to_vec();
    strict.push("newton.strict=true");
    let run = run_solver(1, &indent(), &strict, &tmp.path().join("out"));
    run.expect_code(1, "newton.strict with an inexact equilibrium");
    let text = run.output();
    assert!(
        text.contains("newton.strict") && text.contains("equilibrium"),
        "{text}"
    );
}
