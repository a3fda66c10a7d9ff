//! Friction between two elastic bodies (dual mortar, `obstacle = { type = "body" }`): the
//! Tresca patch test, a stiff master against the rigid plane with Tresca and Coulomb, and the
//! rank independence of a Tresca body pair (docs/bodies.md, docs/numbers.md "Friction between
//! bodies: Tresca and the stiff master").
//!
//! The patch test: two blocks of cases/bodies/tresca_patch{2,3}d.geo (lower E 1, ν 0.45; upper
//! E 3, ν 0.1) meshed independently (interface sizes 0.095 against 0.3 in 2D: 11 against 4
//! segments, no node in common but the ends; 0.15 against 0.45 in 3D), the lower one clamped
//! at its bottom, the upper one held by contact alone under the traction (q, −p) on its top,
//! Tresca's threshold g_R > q. The exact solution is affine in each block: the clamp makes
//! ε_xx (= ε_yy in 3D) = 0 in the lower block, and a sticking interface carries it into the
//! upper one, so with λ, μ each block's Lamé constants (plane strain in 2D)
//!
//!   ε_zz = −p/(λ + 2μ),  γ_xz = q/μ,  σ_zz = −p,  σ_xz = q,  σ_xx (= σ_yy) = λ ε_zz,
//!   u = (γ_L z, 0, ε_L z) below,  u = (γ_L + γ_U (z − 1), 0, ε_L + ε_U (z − 1)) above
//!
//! (z the vertical coordinate, y in 2D): the upper block moved rigidly by the lower one's top
//! displacement plus its own strain, the tangential jump zero (stick). The blocks' sides carry
//! the tractions σ·n of that state. Every slave node is active and sticks, its contact force
//! divided by its weight D_kk is (∓q, ±p) to round-off, its threshold b_k = g_R D_kk, and u is
//! the exact field. With g_R < q nothing holds the upper block tangentially: no equilibrium.

mod common;

use common::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// (E, ν) of the patch test's lower and upper block.
const LOWER: (f64, f64) = (1.0, 0.45);
const UPPER: (f64, f64) = (3.0, 0.1);
/// The traction on the upper block's top: pressure p, shear q along x.
const P: f64 = 0.01;
const Q: f64 = 0.004;
/// Tresca's threshold of the patch test: g_R > q (every node sticks).
const G_STICK: f64 = 0.006;

/// The mesh of cases/bodies/tresca_patch{dim}d.geo with sizes hl (lower) and hu (upper).
fn patch_mesh(dir: &Path, dim: usize, hl: f64, hu: f64) -> PathBuf {
    let out = dir.join(format!("patch{dim}d_{hl}_{hu}.msh"));
    let (hl, hu) = (hl.to_string(), hu.to_string());
    gmsh_file(
        &repo(&format!("cases/bodies/tresca_patch{dim}d.geo")),
        dim,
        &["-setnumber", "hl", &hl, "-setnumber", "hu", &hu],
        &out,
    );
    out
}

/// A vector of `dim` components from (x, y, z) with y the 3D-only component: (x, z) in 2D.
fn vec_of(dim: usize, v: [f64; 3]) -> Vec<f64> {
    if dim == 2 {
        vec![v[0], v[2]]
    } else {
        v.to_vec()
    }
}

/// A TOML vector.
fn toml_vec(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
    format!("[{}]", parts.join(", "))
}

/// Lamé's λ and μ of (E, ν) (plane strain uses the 3D constants).
fn lame((e, nu): (f64, f64)) -> (f64, f64) {
    (
        e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        e / (2.0 * (1.0 + nu)),
    )
}

/// The uniform state of a block of `material` under σ_zz = −p, σ_xz = q with ε_xx (= ε_yy) = 0:
/// (ε_zz, γ_xz, σ_xx).
fn uniform_state(material: (f64, f64), p: f64, q: f64) -> (f64, f64, f64) {
    let (l, m) = lame(material);
    let ez = -p / (l + 2.0 * m);
    (ez, q / m, l * ez)
}

/// The exact displacement of the patch test at x in block `layer` (0 lower, 1 upper).
fn exact_u(dim: usize, x: &[f64], layer: usize) -> Vec<f64> {
    let (el, gl, _) = uniform_state(LOWER, P, Q);
    let (eu, gu, _) = uniform_state(UPPER, P, Q);
    let z = x[dim - 1];
    let u = match layer {
        0 => [gl * z, 0.0, el * z],
        _ => [gl + gu * (z - 1.0), 0.0, el + eu * (z - 1.0)],
    };
    vec_of(dim, u)
}

/// The Neumann tables of the patch test: (q, −p) on the top, σ·n of the uniform state on
/// every side of both blocks.
fn patch_loads(dim: usize) -> String {
    let mut text = format!(
        "[[neumann]]\ngroup = \"top\"\ntraction = {}\n",
        toml_vec(&vec_of(dim, [Q, 0.0, -P]))
    );
    for (block, material) in [("lower", LOWER), ("upper", UPPER)] {
        let (_, _, sx) = uniform_state(material, P, Q);
        let mut sides = vec![("x1", [sx, 0.0, Q]), ("x0", [-sx, 0.0, -Q])];
        if dim == 3 {
            sides.extend([("y1", [0.0, sx, 0.0]), ("y0", [0.0, -sx, 0.0])]);
        }
        for (side, t) in sides {
            text += &format!(
                "[[neumann]]\ngroup = \"{block}_{side}\"\ntraction = {}\n",
                toml_vec(&vec_of(dim, t))
            );
        }
    }
    text
}

/// A case on `mesh`: the two blocks of `materials` (lower, upper), the lower one clamped at
/// its bottom, the Neumann tables `loads`, the contact table `contact`.
fn case_text(
    mesh: &Path,
    dim: usize,
    materials: [(f64, f64); 2],
    loads: &str,
    contact: &str,
) -> String {
    let model = if dim == 2 { "plane_strain" } else { "3d" };
    let mut text = format!("[mesh]\nfile = {}\n", toml_path(mesh));
    for (group, (e, nu)) in ["lower", "upper"].iter().zip(materials) {
        text += &format!(
            "[[material]]\ngroup = \"{group}\"\nyoung = {e:?}\npoisson = {nu:?}\nmodel = \"{model}\"\n"
        );
    }
    text += &format!(
        "[[dirichlet]]\ngroup = \"bottom\"\nvalue = {}\n",
        toml_vec(&vec![0.0; dim])
    );
    text += loads;
    text += contact;
    text += "[output]\ndir = \"out\"\nfields = [\"displacement\", \"contact\"]\n";
    text
}

/// A body pair's contact table, `slave` against `master`, friction `friction`.
fn body_pair(slave: &str, master: &str, friction: &str) -> String {
    format!(
        "[contact]\ngroup = \"{slave}\"\nobstacle = {{ type = \"body\", group = \"{master}\" }}\n\
         friction = {friction}\n"
    )
}

fn tresca(g: f64) -> String {
    format!("{{ law = \"tresca\", threshold = {g:?} }}")
}

/// The slave side (and its master) with the upper block as slave or not.
fn sides(upper_slave: bool) -> (&'static str, &'static str) {
    match upper_slave {
        true => ("upper_bottom", "lower_top"),
        false => ("lower_top", "upper_bottom"),
    }
}

/// The patch test's case with threshold `g`.
fn patch_case(dir: &Path, mesh: &Path, dim: usize, upper_slave: bool, g: f64) -> PathBuf {
    let (slave, master) = sides(upper_slave);
    let text = case_text(
        mesh,
        dim,
        [LOWER, UPPER],
        &patch_loads(dim),
        &body_pair(slave, master, &tresca(g)),
    );
    write_case(&dir.join(format!("patch{dim}d_{slave}_{g}.toml")), &text)
}

/// The patch test's checks on a converged run (slave side `upper_slave`, threshold `g`).
fn check_patch(s: &Solved, dim: usize, upper_slave: bool, g: f64, what: &str) {
    s.assert_converged(what);
    let rows = s.contact_rows_by_id();
    assert!(rows.len() > 3, "{what}: {} contact nodes", rows.len());
    let forces = contact_forces(s, dim);
    assert_eq!(
        forces.len(),
        rows.len(),
        "{what}: forces of every contact node"
    );
    // the force on a slave node of the upper block: (−q, p); of the lower block: (q, −p)
    let sign = if upper_slave { 1.0 } else { -1.0 };
    let traction = vec_of(dim, [-sign * Q, 0.0, sign * P]);
    let mut worst_t = 0.0f64;
    for (id, r) in &rows {
        assert!(r.active(), "{what}: node {id} inactive");
        assert_eq!(r.tangential(), "stick", "{what}: node {id}");
        let w = r.f("weight");
        let t: Vec<f64> = forces[id].iter().map(|f| f / w).collect();
        let off = t
            .iter()
            .zip(&traction)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        worst_t = worst_t.max(off / P);
        assert!(
            off < 1e-8 * P,
            "{what}: node {id} traction {t:?}, exact {traction:?}"
        );
        assert!(
            rel(r.f("pressure"), P) < 1e-8,
            "{what}: node {id} pressure {}",
            r.f("pressure")
        );
        assert!(
            rel(norm(&r.lambda_t(dim)) / w, Q) < 1e-8,
            "{what}: node {id} |λ_τ|/D_kk = {:e}, q = {Q:e}",
            norm(&r.lambda_t(dim)) / w
        );
        assert!(
            rel(r.bound(), g * w) < 1e-12,
            "{what}: node {id} b_k {:e}, g_R D_kk {:e}",
            r.bound(),
            g * w
        );
        // the tangential jump: zero (stick)
        assert!(
            norm(&r.u_t(dim)) < 1e-10 * P,
            "{what}: node {id} jump u_τ {:?}",
            r.u_t(dim)
        );
    }
    let u = s.displacement();
    let exact: BTreeMap<u64, Vec<f64>> = s
        .node_layers()
        .into_iter()
        .map(|(id, (x, layer))| (id, exact_u(dim, &x, layer)))
        .collect();
    let worst = exact
        .iter()
        .flat_map(|(id, ue)| ue.iter().zip(&u[id]).map(|(a, b)| (a - b).abs()))
        .fold(0.0, f64::max);
    let scale = exact.values().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    println!(
        "{what}: {} slave nodes, traction off by {worst_t:.1e} of p, u by {:.1e} of its size",
        rows.len(),
        worst / scale
    );
    assert!(
        worst < 1e-10 * scale,
        "{what}: u off the exact field by {:e} of its size {scale:e}",
        worst / scale
    );
}

#[test]
fn tresca_between_bodies_passes_the_patch_test_in_2d_with_either_side_slave() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = patch_mesh(tmp.path(), 2, 0.095, 0.3);
    for (upper_slave, np) in [(true, 1), (true, 3), (false, 1), (false, 2)] {
        let case = patch_case(tmp.path(), &mesh, 2, upper_slave, G_STICK);
        let what = format!("{} on {np} rank(s)", case.display());
        let s = solve(np, &case, &[]);
        assert_eq!(s.summary["bodies"]["not_held"], 1, "{what}");
        check_patch(&s, 2, upper_slave, G_STICK, &what);
    }
}

#[test]
fn tresca_between_bodies_passes_the_patch_test_in_3d_with_either_side_slave() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = patch_mesh(tmp.path(), 3, 0.15, 0.45);
    for (upper_slave, np) in [(true, 2), (false, 1), (false, 3)] {
        let case = patch_case(tmp.path(), &mesh, 3, upper_slave, G_STICK);
        let what = format!("{} on {np} rank(s)", case.display());
        let s = solve(np, &case, &[]);
        assert_eq!(s.summary["bodies"]["not_held"], 1, "{what}");
        check_patch(&s, 3, upper_slave, G_STICK, &what);
    }
}

/// A slave node's state: "open", or "stick" / "slip".
fn state(r: &Row) -> String {
    match r.active() {
        true => r.tangential().to_string(),
        false => "open".to_string(),
    }
}

/// The two runs' slave nodes in the same states (the nodes where they differ).
fn state_changes(a: &Solved, b: &Solved) -> Vec<(u64, String, String)> {
    let (ra, rb) = (a.contact_rows_by_id(), b.contact_rows_by_id());
    assert_eq!(
        ra.keys().collect::<Vec<_>>(),
        rb.keys().collect::<Vec<_>>(),
        "the same contact nodes"
    );
    ra.iter()
        .map(|(id, r)| (*id, state(r), state(&rb[id])))
        .filter(|(_, x, y)| x != y)
        .collect()
}

/// max |Δ| / max |b| of the contact forces (global components) and of u, a against b.
fn differences(a: &Solved, b: &Solved, dim: usize) -> (f64, f64) {
    let (df, sf) = max_diff(&contact_forces(a, dim), &contact_forces(b, dim));
    let (du, su) = max_diff(&a.displacement(), &b.displacement());
    (df / sf, du / su)
}

/// (E, ν) of the soft body and of the stiff master (E2/E1 = 1e6).
const SOFT: (f64, f64) = (1.0, 0.3);
const STIFF: (f64, f64) = (1.0e6, 0.3);
/// The traction (q, −p) on the soft block's top in the stiff-master comparison.
const P_STIFF: f64 = 0.01;
const Q_STIFF: f64 = 0.002;
/// Relative difference of forces and u between a stiff master and the rigid plane: the
/// master's compliance is 1e-6 of the soft body's, the differences measured 1e-6 … 1e-5
/// (docs/numbers.md); a threshold changed by 1 % moves them by 1e-3 or more.
const TOL_STIFF: f64 = 1e-4;

/// The soft upper block on the stiff lower one (body pair, the soft block as slave) or on the
/// rigid plane z = 1 (the lower block then unloaded), the top loaded by (q, −p), its sides
/// free, held by contact alone; friction `friction`.
fn stiff_case(dir: &Path, mesh: &Path, dim: usize, rigid: bool, friction: &str) -> PathBuf {
    let loads = format!(
        "[[neumann]]\ngroup = \"top\"\ntraction = {}\n",
        toml_vec(&vec_of(dim, [Q_STIFF, 0.0, -P_STIFF]))
    );
    let contact = match rigid {
        false => body_pair("upper_bottom", "lower_top", friction),
        true => format!(
            "[contact]\ngroup = \"upper_bottom\"\nobstacle = {{ type = \"plane\", point = {}, \
             normal = {} }}\nfriction = {friction}\n",
            toml_vec(&vec_of(dim, [0.0, 0.0, 1.0])),
            toml_vec(&vec_of(dim, [0.0, 0.0, 1.0]))
        ),
    };
    let text = case_text(mesh, dim, [STIFF, SOFT], &loads, &contact);
    let name = format!("stiff{dim}d_{rigid}_{}.toml", friction.len());
    write_case(&dir.join(name), &text)
}

/// A stiff master against the rigid plane on `mesh` with `friction` (and the rigid plane with
/// `perturbed`, which the comparison must tell apart), on `np` ranks: the same states on every
/// slave node, forces and u within [`TOL_STIFF`]. Returns the measured differences.
fn stiff_against_rigid(
    dir: &Path,
    mesh: &Path,
    dim: usize,
    (friction, perturbed): (&str, &str),
    np: usize,
) -> (f64, f64) {
    let what = format!("{dim}D, {friction}");
    let stiff = solve(np, &stiff_case(dir, mesh, dim, false, friction), &[]);
    let rigid = solve(np, &stiff_case(dir, mesh, dim, true, friction), &[]);
    stiff.assert_converged(&what);
    rigid.assert_converged(&what);
    let rows = rigid.contact_rows();
    let count = |s: &str| rows.iter().filter(|r| r.active() && state(r) == s).count();
    let (stick, slip) = (count("stick"), count("slip"));
    assert!(stick > 0 && slip > 0, "{what}: {stick} stick, {slip} slip");
    let changed = state_changes(&stiff, &rigid);
    assert!(changed.is_empty(), "{what}: states differ at {changed:?}");
    let (df, du) = differences(&stiff, &rigid, dim);
    println!(
        "{what}: {} slave nodes, {stick} stick, {slip} slip; forces {df:.2e}, u {du:.2e}",
        rows.len()
    );
    assert!(
        df < TOL_STIFF && du < TOL_STIFF,
        "{what}: forces {df:e}, u {du:e} off the rigid plane's"
    );
    // the tolerance tells a threshold 1 % off
    let other = solve(np, &stiff_case(dir, mesh, dim, true, perturbed), &[]);
    let (pf, pu) = differences(&stiff, &other, dim);
    println!("{what}, against {perturbed}: forces {pf:.2e}, u {pu:.2e}");
    assert!(
        pf.max(pu) > 10.0 * TOL_STIFF,
        "{what}: {perturbed} is only {pf:e}, {pu:e} off"
    );
    (df, du)
}

#[test]
fn a_stiff_master_acts_as_the_rigid_plane_with_tresca_and_coulomb() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mu = 0.3;
    let coulomb = |mu: f64| format!("{{ law = \"coulomb\", mu = {mu:?} }}");
    let coulomb_pair = (coulomb(mu), coulomb(1.01 * mu));
    // g_R: some nodes stick, some slip
    for (dim, hl, hu, g, np) in [(2, 0.15, 0.05, 0.0025, 2), (3, 0.3, 0.15, 0.004, 2)] {
        let tresca_pair = (tresca(g), tresca(1.01 * g));
        let mesh = patch_mesh(tmp.path(), dim, hl, hu);
        for (friction, perturbed) in [&tresca_pair, &coulomb_pair] {
            stiff_against_rigid(tmp.path(), &mesh, dim, (friction, perturbed), np);
        }
    }
}

/// The patch test's load with g_R < q: nothing holds the floating upper block tangentially
/// (Σ b_k = g_R < q, the tangential load), so there is no equilibrium. The run ends with exit
/// code 1 and writes no output: in 2D with "no support" after two Newton steps (every node
/// slips at the limit, its spring L̃ = 0, the body's tangential motion is pinned and the load
/// in it is unbalanced); in 3D after newton.max_steps (the slip rows at the limit keep a
/// spring across the slip direction, so no mode is found free; docs/bodies.md, "Limitations"),
/// with the hint that friction alone holds the body tangentially.
#[test]
fn a_floating_block_beyond_its_tresca_capacity_ends_in_an_error() {
    let tmp = tempfile::tempdir().expect("tempdir");
    for (dim, hl, hu, words) in [
        (2, 0.095, 0.3, "no support"),
        (3, 0.15, 0.45, "friction alone holds it tangentially"),
    ] {
        let mesh = patch_mesh(tmp.path(), dim, hl, hu);
        let case = patch_case(tmp.path(), &mesh, dim, true, 0.5 * Q);
        for np in [1, 2] {
            let what = format!("{} on {np} rank(s)", case.display());
            let out = tmp.path().join(format!("out{dim}_{np}"));
            let run = run_solver(np, &case, &[], &out);
            run.expect_code(1, &what);
            let text = run.output();
            assert!(text.contains(words), "{what}: says {words:?}\n{text}");
            assert!(!text.contains("panicked"), "{what}\n{text}");
            assert!(!out.exists(), "{what}: no output after the error");
        }
    }
}

/// A Tresca body pair with stick and slip nodes: the blocks of the patch test (their lateral
/// strains differ, so the interface shears most at its ends) under the traction (q/4, −p) on
/// the top, sides free, the lower block as slave, g_R below the shear at the ends.
fn mixed_case(dir: &Path, mesh: &Path, dim: usize, g: f64) -> PathBuf {
    let loads = format!(
        "[[neumann]]\ngroup = \"top\"\ntraction = {}\n",
        toml_vec(&vec_of(dim, [Q / 4.0, 0.0, -P]))
    );
    let contact = body_pair("lower_top", "upper_bottom", &tresca(g));
    let text = case_text(mesh, dim, [LOWER, UPPER], &loads, &contact);
    write_case(&dir.join(format!("mixed{dim}d.toml")), &text)
}

#[test]
fn a_tresca_body_pair_is_rank_independent() {
    let tmp = tempfile::tempdir().expect("tempdir");
    for (dim, hl, hu, g) in [(2, 0.05, 0.15, 0.004), (3, 0.15, 0.3, 0.004)] {
        let mesh = patch_mesh(tmp.path(), dim, hl, hu);
        let case = mixed_case(tmp.path(), &mesh, dim, g);
        let one = solve(1, &case, &[]);
        one.assert_converged("1 rank");
        let rows = one.contact_rows();
        let count = |s: &str| rows.iter().filter(|r| r.active() && state(r) == s).count();
        let (stick, slip) = (count("stick"), count("slip"));
        println!("{dim}D: {} nodes, {stick} stick, {slip} slip", rows.len());
        assert!(stick > 0 && slip > 0, "{dim}D: {stick} stick, {slip} slip");
        for np in [2, 3] {
            let s = solve(np, &case, &[]);
            let what = format!("{dim}D on {np} ranks");
            s.assert_converged(&what);
            let changed = state_changes(&s, &one);
            assert!(changed.is_empty(), "{what}: states differ at {changed:?}");
            let (df, du) = differences(&s, &one, dim);
            println!("{what}: forces {df:.2e}, u {du:.2e} off 1 rank's");
            assert!(df < 1e-10 && du < 1e-10, "{what}: forces {df:e}, u {du:e}");
        }
    }
}
