//! Force control (`contact.force`, docs/obstacles.md "Force control"): the approach δ is an
//! unknown of the active-set iteration. Prescribing the force that a displacement-controlled
//! run reports gives back its motion and its solution (1, 2, 3 ranks, both presets; also with
//! Tresca friction and with Coulomb friction, by the generalised Newton and by the fixed
//! point, also through load steps); a ramped force from a gap touches first and ends where the
//! static solve does; bad input is refused with the key named and exit code 2.

mod common;

use common::*;
use std::path::PathBuf;

/// The block [-1,1] × [0,1] (2 025 nodes), clamped at its bottom, under the circle of radius
/// 0.5 centred at (0, 1.49): a gap of 0.01 at the top's centre.
fn case() -> PathBuf {
    repo("tests/cases/indent2d_sym.toml")
}

const AUTO: &str = "newton.init=\"auto\"";
/// The displacement-controlled run: the circle moved down by 0.03.
const DEPTH: f64 = 0.03;

fn total_force(s: &Solved) -> Vec<f64> {
    floats(get(&s.summary, &["contact", "total_force"]))
}

fn force_key(f: &[f64]) -> String {
    format!("contact.force=[{:.17e}, {:.17e}]", f[0], f[1])
}

/// The force F that moving the circle by 0.03 takes, prescribed: δ = 0.03 and the same u and
/// active set, to the solver's tolerance (1e-8 relative; the direct preset's result agrees to
/// ~1e-14, the iterative preset's — GMRES to rtol — to ~1e-10), on 1, 2 and 3 ranks, on the
/// condensed path (the default: one factorisation), the plain path and the iterative preset.
#[test]
fn force_control_inverts_displacement_control() {
    let moved = solve(1, &case(), &[AUTO, "contact.motion=[0.0, -0.03]"]);
    moved.assert_converged("displacement control");
    let f = total_force(&moved);
    assert!(f[1] < 0.0, "the circle pushes the block down: {f:?}");
    let active = moved.active_node_ids();
    assert!(active.len() > 10, "{active:?}");
    let direct = "solver.preset=\"direct\"";
    let runs: [(usize, &[&str]); 5] = [
        (1, &[direct]),
        (2, &[direct]),
        (3, &[direct]),
        (2, &[direct, "solver.reuse=\"never\""]),
        (2, &["solver.preset=\"iterative\""]),
    ];
    for (np, sets) in runs {
        let fk = force_key(&f);
        let mut all = vec![AUTO, fk.as_str()];
        all.extend_from_slice(sets);
        let forced = solve(np, &case(), &all);
        forced.assert_converged("force control");
        let delta = forced.f(&["contact", "approach"]);
        assert!(
            (delta - DEPTH).abs() <= 1e-8 * DEPTH,
            "{np} ranks, {sets:?}: δ = {delta}"
        );
        let d = floats(get(&forced.summary, &["contact", "obstacle_displacement"]));
        assert!(
            (d[1] + delta).abs() <= 1e-12 * delta && d[0].abs() <= 1e-12 * delta,
            "{d:?}"
        );
        let g = total_force(&forced);
        assert!(
            (g[1] - f[1]).abs() <= 1e-8 * f[1].abs(),
            "{g:?} against {f:?}"
        );
        let du = forced.u_rel_diff(&moved);
        assert!(du <= 1e-8, "{np} ranks, {sets:?}: |Δu|/|u| = {du:e}");
        assert_eq!(forced.active_node_ids(), active, "{np} ranks, {sets:?}");
        if sets == [direct] {
            // the condensed path: one factorisation for the whole iteration
            let fact = forced.f(&["newton", "factorisations"]);
            assert_eq!(fact, 1.0, "{np} ranks: {}", forced.run.output());
        }
    }
}

/// 3D: the sphere over the clamped block of tests/cases/sphere3d.toml (a gap of 0.05) moved
/// down by 0.1; the force's component along the motion, prescribed along it, gives back
/// δ = 0.1 and u (the lateral force components of the unstructured mesh are not prescribed:
/// force control holds the force along F/|F| only) — condensed and plain path, 1 and 2 ranks,
/// and the iterative preset (its first step predicts the set and δ by the half-space model).
#[test]
fn force_control_inverts_displacement_control_in_3d() {
    let case = repo("tests/cases/sphere3d.toml");
    let moved = solve(1, &case, &[AUTO, "contact.motion=[0.0, 0.0, -0.1]"]);
    moved.assert_converged("displacement control");
    let fz = total_force(&moved)[2];
    assert!(fz < 0.0, "{fz}");
    let fk = format!("contact.force=[0.0, 0.0, {fz:.17e}]");
    for (np, path) in [
        (1, "solver.reuse=\"auto\""),
        (2, "solver.reuse=\"auto\""),
        (2, "solver.reuse=\"never\""),
        (2, "solver.preset=\"iterative\""),
    ] {
        let forced = solve(np, &case, &[AUTO, &fk, path]);
        forced.assert_converged("force control");
        let delta = forced.f(&["contact", "approach"]);
        assert!(
            (delta - 0.1).abs() <= 1e-8 * 0.1,
            "{np} ranks, {path}: δ = {delta}"
        );
        let du = forced.u_rel_diff(&moved);
        assert!(du <= 1e-8, "{np} ranks, {path}: |Δu|/|u| = {du:e}");
        assert_eq!(forced.active_node_ids(), moved.active_node_ids());
    }
}

/// The circle raised to a gap of 0.11 and the force ramped over three load steps: the first
/// step moves the circle until a node touches (on the plain path its first solve has no node
/// active), every step carries
/// t·F (history.csv), the circle goes down step by step, and the last step is the static
/// solve's — on the condensed and on the plain path.
#[test]
fn a_ramped_force_from_a_gap_touches_first_and_ends_at_the_static_solution() {
    let raised = "contact.obstacle.center=[0.0, 1.6]";
    let f = [0.0, -0.05];
    let fk = force_key(&f);
    for path in ["solver.reuse=\"auto\"", "solver.reuse=\"never\""] {
        let stat = solve(2, &case(), &[AUTO, raised, &fk, path]);
        stat.assert_converged("static force control");
        let delta = stat.f(&["contact", "approach"]);
        assert!(
            delta > 0.11,
            "the circle must first close the gap of 0.11: δ = {delta}"
        );
        if path.contains("never") {
            // the plain path's first solve: no node active, then the touch
            let first = get(&stat.summary, &["newton", "history"])[0]["active"].as_f64();
            assert_eq!(first, Some(0.0), "{}", stat.run.output());
            assert!(
                stat.run.output().contains("touches"),
                "{}",
                stat.run.output()
            );
        }
        let ramp = solve(2, &case(), &[AUTO, raised, &fk, path, "load.steps=3"]);
        let h = read_csv(&ramp.dir.join("history.csv"));
        assert_eq!(h.len(), 3);
        let mut last = 0.0;
        for (i, r) in h.iter().enumerate() {
            let t = (i + 1) as f64 / 3.0;
            let fy = r.f("force_y");
            assert!(
                (fy - t * f[1]).abs() <= 1e-8 * f[1].abs(),
                "step {}: {fy}",
                i + 1
            );
            let y = r.f("obstacle_y");
            assert!(y < last, "the circle goes down: {h:?}");
            last = y;
        }
        assert!(
            (-last - delta).abs() <= 1e-8 * delta,
            "{path}: last step {} against the static {delta}",
            -last
        );
        let (u_ramp, u_stat) = (step_displacement(&ramp.dir, 3), stat.displacement());
        let (diff, scale) = max_diff(&u_ramp, &u_stat);
        assert!(scale > 0.0, "u = 0: nothing tested");
        assert!(
            diff <= 1e-8 * scale,
            "{path}: |Δu| = {diff:e}, |u| = {scale:e}"
        );
    }
}

/// Force control's bad input: with a motion, a zero force, SNES VI, a force
/// that pulls the circle away, a body that Dirichlet data leave free. Each is refused with
/// `contact.force` named, exit code 2 and no summary written.
#[test]
fn bad_force_input_is_refused() {
    let f = "contact.force=[0.0, -0.05]";
    let cases: [(&[&str], &str); 5] = [
        (&[f, "contact.motion=[0.0, -0.01]"], "instead of the motion"),
        (&["contact.force=[0.0, 0.0]"], "is zero"),
        (&[f, "solver.method=\"snesvi\""], "no force control"),
        (&["contact.force=[0.0, 0.05]"], "never reaches the body"),
        (
            &[
                f,
                "dirichlet.0.value=[\"free\", 0.0]",
                "contact.rigid_modes=\"auto\"",
            ],
            "Dirichlet data hold",
        ),
    ];
    for (sets, says) in cases {
        let tmp = tempfile::tempdir().expect("tempdir");
        let out = tmp.path().join("out");
        let run = run_solver(1, &case(), sets, &out);
        let text = run.output();
        assert_eq!(run.code, Some(2), "{sets:?}:\n{text}");
        assert!(text.contains("contact.force"), "{sets:?}:\n{text}");
        assert!(text.contains(says), "{sets:?}: expected {says:?}:\n{text}");
        assert!(!out.join("summary.json").exists(), "{sets:?}");
    }
}

/// The slanted direction of the friction tests, e = (0.3, −1) (not normalised), and the depth
/// of the displacement-controlled run along it.
const SLANT: [f64; 2] = [0.3, -1.0];
const SLANT_DEPTH: f64 = 0.03;

/// |e| and a force along e with |F| = `along`, as a `contact.force` key.
fn slanted_force_key(along: f64) -> String {
    let norm = SLANT[0].hypot(SLANT[1]);
    format!(
        "contact.force=[{:.17e}, {:.17e}]",
        along * SLANT[0] / norm,
        along * SLANT[1] / norm
    )
}

/// A run's contact force along e: F·e/|e|.
fn force_along_slant(s: &Solved) -> f64 {
    let f = total_force(s);
    (f[0] * SLANT[0] + f[1] * SLANT[1]) / SLANT[0].hypot(SLANT[1])
}

/// The circle pressed along the slanted direction e = (0.3, −1) by 0.03 with `friction`: a
/// displacement-controlled run, then the force it reports along e prescribed instead, on the
/// ranks and settings of `runs` — each run's approach, u, active and slip nodes against the
/// motion's (1e-8; some active nodes slip, some stick), its contact force along e against the
/// prescribed |F| (1e-9), its Coulomb algorithm the one `friction` names. Returns the force
/// key and the forced runs.
fn slanted_force_gives_back_the_motion(
    friction: &str,
    label: &str,
    runs: &[(usize, &[&str])],
) -> (String, Vec<Solved>) {
    let norm = SLANT[0].hypot(SLANT[1]);
    let depth = SLANT_DEPTH;
    let m = SLANT.map(|x| depth * x / norm);
    let motion = format!("contact.motion=[{:.17e}, {:.17e}]", m[0], m[1]);
    let moved = solve(1, &case(), &[AUTO, friction, &motion]);
    moved.assert_converged("displacement control");
    let along = force_along_slant(&moved);
    assert!(
        along > 0.0,
        "the circle pushes the block along its motion: {:?}",
        total_force(&moved)
    );
    // the force's component along e prescribed: |F| = F·e, direction e
    let fk = slanted_force_key(along);
    let (slip, active) = (moved.slip_node_ids().len(), moved.active_node_ids().len());
    assert!(slip > 0 && active > slip, "slip {slip} of {active} active");
    let mut out = Vec::new();
    for (np, sets) in runs {
        let mut all = vec![AUTO, friction, fk.as_str()];
        all.extend_from_slice(sets);
        let forced = solve(*np, &case(), &all);
        forced.assert_converged(label);
        let delta = forced.f(&["contact", "approach"]);
        let du = forced.u_rel_diff(&moved);
        let p = force_along_slant(&forced);
        eprintln!(
            "{label}, {np} ranks {sets:?}: δ = {delta:.17e}, |Δu|/|u| = {du:.2e}, force along \
             e {:.2e} off, {} steps (motion: {})",
            (p - along).abs() / along,
            forced.steps(),
            moved.steps()
        );
        assert!(
            (delta - depth).abs() <= 1e-8 * depth,
            "{np} ranks, {sets:?}: δ = {delta}"
        );
        assert!(du <= 1e-8, "{np} ranks, {sets:?}: {du}");
        assert!(
            (p - along).abs() <= 1e-9 * along,
            "{np} ranks, {sets:?}: force along e {p} against |F| = {along}"
        );
        assert_eq!(forced.active_node_ids(), moved.active_node_ids());
        assert_eq!(
            forced.slip_node_ids(),
            moved.slip_node_ids(),
            "{np} ranks, {sets:?}"
        );
        if friction.contains("coulomb") {
            let rec = get(&forced.summary, &["newton", "coulomb", "algorithm"]);
            let want = if friction.contains("fixed-point") {
                "fixed-point"
            } else {
                "newton"
            };
            assert_eq!(rec, want, "{np} ranks, {sets:?}");
        }
        out.push(forced);
    }
    (fk, out)
}

const ONE_TWO_ITERATIVE: [(usize, &[&str]); 3] = [
    (1, &["solver.preset=\"direct\""]),
    (2, &["solver.preset=\"direct\""]),
    (2, &["solver.preset=\"iterative\""]),
];

/// Tresca friction under force control: the circle pressed along a slanted force (its
/// tangential part drags the stick nodes, the slip nodes slide) — the force that a
/// displacement-controlled run along the same direction reports gives back its approach, u and
/// the normal and tangential states (1 and 2 ranks, direct and iterative presets).
#[test]
fn force_control_with_tresca_friction() {
    let tresca = "contact.friction={law=\"tresca\", threshold=0.02}";
    slanted_force_gives_back_the_motion(tresca, "force control with Tresca", &ONE_TWO_ITERATIVE);
}

const COULOMB_FIXED_POINT: &str =
    "contact.friction={law=\"coulomb\", mu=0.3, algorithm=\"fixed-point\"}";
const COULOMB_NEWTON: &str = "contact.friction={law=\"coulomb\", mu=0.3}";

/// Coulomb friction (μ = 0.3, the fixed point on Tresca thresholds) under force control: the
/// circle pressed along the slanted direction of the Tresca test — the force that a
/// displacement-controlled run along that direction reports gives back its approach, u and
/// the normal and tangential states to 1e-8 (the fixed point's thresholds stop at 1e-9 of the
/// largest; 1 and 2 ranks, direct and iterative presets).
#[test]
fn force_control_with_coulomb_fixed_point() {
    slanted_force_gives_back_the_motion(
        COULOMB_FIXED_POINT,
        "force control with Coulomb (fixed point)",
        &ONE_TWO_ITERATIVE,
    );
}

/// Coulomb friction (μ = 0.3) by the generalised Newton (the default algorithm) under force
/// control: the force that the slanted displacement-controlled run reports gives back its
/// approach, u, the active and the slip nodes (some slip, some stick) to 1e-8 and the force
/// along e to 1e-9 — on 1, 2 and 3 ranks on the contact unknowns (direct preset: the
/// frictionless force-controlled solution, then the dense generalised Newton with δ as one
/// more unknown, one factorisation), on 2 on the plain path from the touching nodes
/// (`solver.reuse = "never"`) and with the iterative preset; and the fixed point under the
/// same force finds the same δ (1e-8) in more linear solves.
#[test]
fn force_control_with_coulomb_newton() {
    let runs: [(usize, &[&str]); 5] = [
        (1, &["solver.preset=\"direct\""]),
        (2, &["solver.preset=\"direct\""]),
        (3, &["solver.preset=\"direct\""]),
        (2, &["solver.preset=\"direct\"", "solver.reuse=\"never\""]),
        (2, &["solver.preset=\"iterative\""]),
    ];
    let label = "force control with Coulomb (generalised Newton)";
    let (fk, newton) = slanted_force_gives_back_the_motion(COULOMB_NEWTON, label, &runs);
    // the direct preset solves on the contact unknowns with the approach as one more
    // unknown: one factorisation, the dense steps' history (1, 2 and 3 ranks)
    for (np, s) in newton.iter().enumerate().take(3) {
        let cs = &s.summary["newton"]["condensed"];
        assert_eq!(
            cs["coulomb"]["outcome"],
            "condensed",
            "{} rank(s): {cs}",
            np + 1
        );
        assert_eq!(
            s.f(&["newton", "factorisations"]),
            1.0,
            "{} rank(s)",
            np + 1
        );
    }
    let fixed = solve(1, &case(), &[AUTO, COULOMB_FIXED_POINT, &fk]);
    fixed.assert_converged("force control with Coulomb (fixed point)");
    let (a, b) = (
        newton[0].f(&["contact", "approach"]),
        fixed.f(&["contact", "approach"]),
    );
    let du = newton[0].u_rel_diff(&fixed);
    eprintln!(
        "generalised Newton {} steps, fixed point {} steps: δ {a:.17e} against {b:.17e} \
         ({:.2e} relative), |Δu|/|u| = {du:.2e}",
        newton[0].steps(),
        fixed.steps(),
        (a - b).abs() / b
    );
    assert!((a - b).abs() <= 1e-8 * b, "δ: Newton {a}, fixed point {b}");
    assert!(du <= 1e-8, "|Δu|/|u| = {du}");
    assert_eq!(newton[0].slip_node_ids(), fixed.slip_node_ids());
}

/// 3D: Coulomb's generalised Newton (μ = 0.3) under force control, the sphere of
/// tests/cases/sphere3d.toml pressed along e = m/|m|, m = (0.03, 0.01, −0.1) (the drag has
/// components along both tangents of the frames): the force along e that the motion m reports
/// gives back δ = |m|, u, the active and the slip nodes (1e-8; some slip, some stick) and the
/// force along e (1e-9), on 1 and 2 ranks.
#[test]
fn force_control_with_coulomb_newton_in_3d() {
    let case = repo("tests/cases/sphere3d.toml");
    let m = [0.03f64, 0.01, -0.1];
    let norm = m.iter().map(|x| x * x).sum::<f64>().sqrt();
    let motion = format!("contact.motion=[{}, {}, {}]", m[0], m[1], m[2]);
    let moved = solve(1, &case, &[AUTO, COULOMB_NEWTON, &motion]);
    moved.assert_converged("displacement control");
    let along_e = |s: &Solved| {
        let f = total_force(s);
        (0..3).map(|i| f[i] * m[i]).sum::<f64>() / norm
    };
    let along = along_e(&moved);
    let fk = format!(
        "contact.force=[{:.17e}, {:.17e}, {:.17e}]",
        along * m[0] / norm,
        along * m[1] / norm,
        along * m[2] / norm
    );
    let (slip, active) = (moved.slip_node_ids().len(), moved.active_node_ids().len());
    assert!(slip > 0 && active > slip, "slip {slip} of {active} active");
    for np in [1, 2] {
        let forced = solve(np, &case, &[AUTO, COULOMB_NEWTON, &fk]);
        forced.assert_converged("force control with Coulomb in 3D");
        let delta = forced.f(&["contact", "approach"]);
        let du = forced.u_rel_diff(&moved);
        let p = along_e(&forced);
        eprintln!(
            "3D, {np} ranks: δ = {delta:.17e} for {norm:.17e}, |Δu|/|u| = {du:.2e}, {} steps \
             (motion: {})",
            forced.steps(),
            moved.steps()
        );
        assert!(
            (delta - norm).abs() <= 1e-8 * norm,
            "{np} ranks: δ = {delta}"
        );
        assert!(du <= 1e-8, "{np} ranks: |Δu|/|u| = {du}");
        assert!(
            (p - along).abs() <= 1e-9 * along,
            "{np} ranks: {p} against {along}"
        );
        assert_eq!(forced.active_node_ids(), moved.active_node_ids());
        assert_eq!(forced.slip_node_ids(), moved.slip_node_ids(), "{np} ranks");
    }
}

/// Coulomb (μ = 0.3) under force control from a gap: the circle raised by 0.11 and pushed
/// along the slanted (0.3, −1). The frictionless start on the contact unknowns must close the
/// gap (its estimate lets the pins carry only the body's own modes, never the force: a start
/// with no active node used to be accepted, and the plain path then took 10 factorisations);
/// then the dense Coulomb iteration with δ: one factorisation, the plain path's δ, u and
/// active and slip nodes (1e-8), on 1 and 2 ranks.
#[test]
fn coulomb_force_from_a_gap_on_the_contact_unknowns() {
    let raised = "contact.obstacle.center=[0.0, 1.6]";
    let fk = slanted_force_key(0.05);
    let base = [AUTO, raised, COULOMB_NEWTON, fk.as_str()];
    let plain = solve(
        2,
        &case(),
        &[&base[..], &["solver.reuse=\"never\""]].concat(),
    );
    plain.assert_converged("the plain path from a gap");
    let dp = plain.f(&["contact", "approach"]);
    assert!(dp > 0.11, "the gap is closed first: δ = {dp}");
    for np in [1, 2] {
        let s = solve(np, &case(), &base);
        s.assert_converged("Coulomb force control from a gap");
        let start = s
            .run
            .stdout
            .lines()
            .find(|l| l.starts_with("coulomb: the frictionless solution"))
            .unwrap_or_else(|| panic!("{}", s.run.output()))
            .to_string();
        assert!(!start.ends_with(" 0 active nodes"), "{start}");
        let cs = &s.summary["newton"]["condensed"];
        assert_eq!(cs["coulomb"]["outcome"], "condensed", "{np} rank(s): {cs}");
        assert_eq!(s.f(&["newton", "factorisations"]), 1.0, "{np} rank(s)");
        let (d, du) = (s.f(&["contact", "approach"]), s.u_rel_diff(&plain));
        eprintln!("{np} rank(s): {start}; δ = {d:.17e} (plain {dp:.17e}), |Δu|/|u| = {du:.2e}");
        assert!(
            (d - dp).abs() <= 1e-8 * dp && du <= 1e-8,
            "{np}: δ {d}, {du}"
        );
        assert_eq!(s.active_node_ids(), plain.active_node_ids());
        assert_eq!(s.slip_node_ids(), plain.slip_node_ids());
    }
}

/// Coulomb's generalised Newton under force control through three load steps: the slanted
/// force ramped (each step's force along e is t·|F|, 1e-9), each step warm-started from the
/// previous one's approach and states; every step's approach and u agree with the fixed
/// point's through the same steps (the same incremental problems, 1e-8), on 1 and 2 ranks,
/// the steps after the first on the first one's factorisation (the approach an unknown of the
/// dense iteration); and displacement control through the approaches found (`load.factors` = δ_i/δ_3 of the
/// motion δ_3 e) takes the forces t·|F| (1e-9) and gives every step's u (1e-8).
#[test]
fn force_control_with_coulomb_newton_in_load_steps() {
    let along = 0.047;
    let fk = slanted_force_key(along);
    let fixed = solve(
        1,
        &case(),
        &[AUTO, COULOMB_FIXED_POINT, &fk, "load.steps=3"],
    );
    fixed.assert_converged("Coulomb fixed point in load steps");
    let hf = read_csv(&fixed.dir.join("history.csv"));
    assert_eq!(hf.len(), 3);
    for np in [1, 2] {
        let newton = solve(np, &case(), &[AUTO, COULOMB_NEWTON, &fk, "load.steps=3"]);
        newton.assert_converged("Coulomb generalised Newton in load steps");
        let (slip, active) = (newton.slip_node_ids().len(), newton.active_node_ids().len());
        assert!(slip > 0 && active > slip, "slip {slip} of {active} active");
        let h = read_csv(&newton.dir.join("history.csv"));
        assert_eq!(h.len(), 3);
        let norm = SLANT[0].hypot(SLANT[1]);
        for (i, (r, q)) in h.iter().zip(&hf).enumerate() {
            let t = (i + 1) as f64 / 3.0;
            let p = (r.f("force_x") * SLANT[0] + r.f("force_y") * SLANT[1]) / norm;
            assert!(
                (p - t * along).abs() <= 1e-9 * t * along,
                "{np} ranks, step {}: force along e {p}",
                i + 1
            );
            let d = [r.f("obstacle_x"), r.f("obstacle_y")];
            let dq = [q.f("obstacle_x"), q.f("obstacle_y")];
            let (delta, delta_fixed) = (d[0].hypot(d[1]), dq[0].hypot(dq[1]));
            let (u, uq) = (
                step_displacement(&newton.dir, i + 1),
                step_displacement(&fixed.dir, i + 1),
            );
            let (diff, scale) = max_diff(&u, &uq);
            eprintln!(
                "{np} ranks, step {}: δ = {delta:.17e} (fixed point {delta_fixed:.17e}), \
                 |Δu|/|u| = {:.2e}",
                i + 1,
                diff / scale
            );
            assert!(
                (delta - delta_fixed).abs() <= 1e-8 * delta_fixed,
                "{np} ranks, step {}: δ = {delta}, fixed point {delta_fixed}",
                i + 1
            );
            assert!(scale > 0.0 && diff <= 1e-8 * scale, "step {}", i + 1);
        }
        assert_eq!(newton.slip_node_ids(), fixed.slip_node_ids(), "{np} ranks");
        // on the contact unknowns, the approach one more unknown: the steps after the first
        // on the first step's factorisation (only d₀ is new)
        let kept = newton.kept_factorisations();
        assert_eq!(kept, 2, "{np} ranks: {}", newton.run.output());
        eprintln!(
            "{np} ranks: generalised Newton {} steps, fixed point {} steps (3 load steps)",
            newton.steps(),
            fixed.steps()
        );
        if np == 1 {
            motion_through_the_approaches(&newton, &h, along);
        }
    }
}

/// Displacement control through the approaches δ_i of the force-controlled load steps `h`
/// (their history.csv) of `forced`: each step's force along e is t_i·`along` (1e-9) and its u
/// the force-controlled one (1e-8).
fn motion_through_the_approaches(forced: &Solved, h: &[Row], along: f64) {
    let norm = SLANT[0].hypot(SLANT[1]);
    let delta: Vec<f64> = h
        .iter()
        .map(|r| (r.f("obstacle_x") * SLANT[0] + r.f("obstacle_y") * SLANT[1]) / norm)
        .collect();
    let last = delta[delta.len() - 1];
    let factors: Vec<String> = delta.iter().map(|d| format!("{:.17e}", d / last)).collect();
    let factors = format!("load.factors=[{}]", factors.join(", "));
    let m = SLANT.map(|x| last * x / norm);
    let motion = format!("contact.motion=[{:.17e}, {:.17e}]", m[0], m[1]);
    let moved = solve(1, &case(), &[AUTO, COULOMB_NEWTON, &motion, &factors]);
    moved.assert_converged("displacement control through the approaches");
    let hm = read_csv(&moved.dir.join("history.csv"));
    assert_eq!(hm.len(), h.len());
    for (i, r) in hm.iter().enumerate() {
        let t = (i + 1) as f64 / h.len() as f64;
        let p = (r.f("force_x") * SLANT[0] + r.f("force_y") * SLANT[1]) / norm;
        let (u, um) = (
            step_displacement(&forced.dir, i + 1),
            step_displacement(&moved.dir, i + 1),
        );
        let (diff, scale) = max_diff(&u, &um);
        eprintln!(
            "motion through the approaches, step {}: force along e {:.2e} off, |Δu|/|u| = {:.2e}",
            i + 1,
            (p - t * along).abs() / (t * along),
            diff / scale
        );
        assert!(
            (p - t * along).abs() <= 1e-9 * t * along,
            "step {}: force along e {p} against {}",
            i + 1,
            t * along
        );
        assert!(scale > 0.0 && diff <= 1e-8 * scale, "step {}", i + 1);
    }
    assert_eq!(moved.slip_node_ids(), forced.slip_node_ids());
}

/// The force history of the table test: loaded to 0.04 by the load factor 0.5, held to 0.75,
/// then unloaded part-way, to 0.02 at 1.
const FORCE_TABLE: &str = "contact.force={table=[[0.0, 0.0, 0.0], [0.5, 0.0, -0.04], \
                           [0.75, 0.0, -0.04], [1.0, 0.0, -0.02]]}";
const TABLE_FACTORS: [f64; 6] = [0.25, 0.5, 0.625, 0.75, 0.875, 1.0];

/// The table's y component at the load factor t (the rows of [`FORCE_TABLE`]).
fn force_table_y(t: f64) -> f64 {
    let rows = [(0.0, 0.0), (0.5, -0.04), (0.75, -0.04), (1.0, -0.02)];
    let i = rows.iter().position(|r| r.0 >= t).expect("covered").max(1);
    let ((t0, f0), (t1, f1)) = (rows[i - 1], rows[i]);
    f0 + (t - t0) / (t1 - t0) * (f1 - f0)
}

/// `contact.force = { table = ... }` with a kink (load, hold, unload part-way), the circle
/// from its gap of 0.01: every load step carries the table's interpolated force (history.csv,
/// to the force balance's 1e-8), the last one also in summary.json; the circle goes down
/// while loading, stays while the force is held, comes back up while unloading; frictionless,
/// the state depends on the force only, so the unloaded step at 0.02 is the loading one at
/// 0.02 (factor 0.25). 1 and 2 ranks agree.
#[test]
fn a_force_table_is_followed_step_by_step() {
    let factors = format!("load.factors={TABLE_FACTORS:?}");
    let mut first: Option<Vec<Row>> = None;
    for np in [1, 2] {
        let s = solve(np, &case(), &[AUTO, FORCE_TABLE, &factors]);
        s.assert_converged("force table");
        let h = read_csv(&s.dir.join("history.csv"));
        assert_eq!(h.len(), TABLE_FACTORS.len(), "{}", s.run.output());
        for (r, &t) in h.iter().zip(&TABLE_FACTORS) {
            let want = force_table_y(t);
            let fy = r.f("force_y");
            assert!(
                (fy - want).abs() <= 1e-8 * want.abs(),
                "{np} ranks, factor {t}: force_y {fy}, the table {want}"
            );
            assert_eq!(r.f("obstacle_x"), 0.0, "moved along the force only");
        }
        let y: Vec<f64> = h.iter().map(|r| r.f("obstacle_y")).collect();
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-8 * b.abs();
        assert!(y[0] < 0.0 && y[1] < y[0], "loading goes down: {y:?}");
        assert!(same(y[2], y[1]) && same(y[3], y[1]), "held: {y:?}");
        assert!(y[4] > y[3] && y[5] > y[4], "unloading goes up: {y:?}");
        assert!(same(y[5], y[0]), "0.02 unloaded is 0.02 loaded: {y:?}");
        let (u_first, u_last) = (step_displacement(&s.dir, 1), step_displacement(&s.dir, 6));
        let (diff, scale) = max_diff(&u_last, &u_first);
        assert!(scale > 0.0 && diff <= 1e-8 * scale, "|Δu| = {diff:e}");
        let f = total_force(&s);
        assert!((f[1] + 0.02).abs() <= 1e-8 * 0.02, "summary.json: {f:?}");
        match &first {
            None => first = Some(h),
            Some(h1) => {
                for (a, b) in h.iter().zip(h1) {
                    for k in ["force_y", "obstacle_y"] {
                        assert!(same(a.f(k), b.f(k)), "2 vs 1 rank, {k}");
                    }
                }
            }
        }
    }
}

/// A bad force table is an input error naming the key (and the row): exit 2, nothing
/// written — factors not increasing, rows of different lengths, a 3D row in 2D, a table
/// that stops before the run's last factor, a force zero at a factor of the run.
#[test]
fn a_bad_force_table_is_refused() {
    let factors = "load.factors=[0.5, 1.0]";
    let cases: [(&str, &str, &str); 5] = [
        (
            "contact.force={table=[[0, 0, 0], [0.5, 0, -0.04], [0.5, 0, -0.02]]}",
            "contact.force.table[2][0]",
            "must increase",
        ),
        (
            "contact.force={table=[[0, 0, -0.01], [1, 0, -0.02, 0]]}",
            "contact.force.table[1]",
            "like the first row",
        ),
        (
            "contact.force={table=[[0, 0, 0, -0.01], [1, 0, 0, -0.02]]}",
            "contact.force.table",
            "2D",
        ),
        (
            "contact.force={table=[[0, 0, 0], [0.5, 0, -0.04]]}",
            "contact.force.table",
            "not extrapolated",
        ),
        (
            "contact.force={table=[[0, 0, 0], [0.5, 0, -0.04], [1, 0, 0]]}",
            "contact.force.table",
            "zero force at the load factor 1",
        ),
    ];
    for (np, (set, key, says)) in [1, 2].into_iter().flat_map(|np| cases.map(|c| (np, c))) {
        let tmp = tempfile::tempdir().expect("tempdir");
        let out = tmp.path().join("out");
        let run = run_solver(np, &case(), &[AUTO, set, factors], &out);
        let text = run.output();
        assert_eq!(run.code, Some(2), "{np} ranks, {set}:\n{text}");
        assert!(text.contains(key), "{set}: expected {key}:\n{text}");
        assert!(text.contains(says), "{set}: expected {says:?}:\n{text}");
        assert!(!out.join("summary.json").exists(), "{set}");
    }
}
