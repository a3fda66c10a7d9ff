//! Contact validation on blocks (cases/blocks, tests/cases): a block pressed flat onto a
//! frictionless plane (uniform contact pressure, 2D and 3D), a block pulled off the plane
//! (no contact, λ = 0) and a block indented by a rigid circle (a symmetric contact zone).

mod common;

use common::*;
use std::path::{Path, PathBuf};

/// E, ν and the top pressure p of cases/blocks/block{2,3}d.toml, read from the case file so
/// that the exact solution follows the case.
fn material_and_pressure(case: &Path) -> (f64, f64, f64) {
    let text = std::fs::read_to_string(case).expect("case file");
    let t: toml::Table = toml::from_str(&text).expect("case TOML");
    let e = t["material"]["young"].as_float().expect("young");
    let nu = t["material"]["poisson"].as_float().expect("poisson");
    let p = t["neumann"][0]["pressure"].as_float().expect("pressure");
    (e, nu, p)
}

/// Block of cases/blocks pressed onto z = 0 (3D) / y = 0 (2D) by the uniform pressure p on
/// its top: every bottom node active with pressure p, Σ −λ = p · area, KKT at round-off, and
/// the displacement is the exact linear field (P1 reproduces it): σ_nn = −p, the rest 0.
/// The solve's round-off in the multipliers, relative to the force scale (see `block_on_plane`).
const ROUND_OFF: f64 = 1e-10;

fn block_on_plane(dim: usize, np: usize) {
    let case: PathBuf = repo(&format!("cases/blocks/block{dim}d.toml"));
    let (e, nu, p) = material_and_pressure(&case);
    let s = solve(np, &case, &[]);
    let what = format!("block{dim}d on {np} rank(s)");
    assert!(s.converged(), "{what}:\n{}", s.run.output());
    let rows = s.contact_rows();
    assert!(!rows.is_empty());
    assert_eq!(
        s.f(&["contact", "active_count"]) as usize,
        rows.len(),
        "{what}: not all active"
    );
    for r in &rows {
        assert!(r.active(), "{what}: node {} inactive", r.node_id());
        let pr = r.f("pressure");
        assert!(
            rel(pr, p) < 1e-10,
            "{what}: node {} pressure {pr:.17e} ≠ {p}",
            r.node_id()
        );
        assert!(
            r.f("gap").abs() <= 1e-12,
            "{what}: node {} gap {:e}",
            r.node_id(),
            r.f("gap")
        );
    }
    // bottom area: 2 (2D, unit depth) or 2 × 2 (3D)
    let area = if dim == 2 { 2.0 } else { 4.0 };
    let f = s.total_force();
    assert_eq!(f.len(), dim);
    assert!(
        rel(f[dim - 1], p * area) < 1e-10,
        "{what}: Σ −λ = {f:?}, load {}",
        p * area
    );
    for fi in &f[..dim - 1] {
        assert!(
            fi.abs() < 1e-10 * p * area,
            "{what}: tangential Σ −λ = {f:?}"
        );
    }
    let k = |key: &str| s.f(&["contact", "kkt", key]);
    // λ = f − A u carries the solve's round-off, ~ ε κ(K) times the force scale: measured on
    // block3d 7.2e-13 (OpenBLAS' Prescott and SkylakeX kernels) and 1.15e-12 (Haswell) of the
    // force scale; 1e-10 keeps the check far below any real tangential force (μ ~ 0.1) without
    // deciding it by the CPU's BLAS kernels.
    let round_off = ROUND_OFF * k("force_scale");
    assert!(
        k("max_positive_lambda_n") <= round_off,
        "{what}: λ_n = {:e} > 0",
        k("max_positive_lambda_n")
    );
    assert!(
        k("max_abs_lambda_t") <= round_off,
        "{what}: λ_t = {:e} ≠ 0",
        k("max_abs_lambda_t")
    );
    assert!(
        k("max_penetration") <= 1e-12,
        "{what}: penetration {:e}",
        k("max_penetration")
    );

    // u = ε·x + rigid translation along the plane: strains of the exact solution.
    let (exx, enn) = if dim == 2 {
        // plane strain
        (nu * (1.0 + nu) * p / e, -(1.0 - nu * nu) * p / e)
    } else {
        (nu * p / e, -p / e)
    };
    let res = python_json(LINEAR_FIT_PY, &[&s.dir.join("solution.h5")]);
    let grad: Vec<Vec<f64>> = serde_json::from_value(res["grad"].clone()).expect("grad");
    assert_eq!(grad.len(), dim, "{what}: gradient {grad:?}");
    let off: Vec<f64> = serde_json::from_value(res["offset"].clone()).expect("offset");
    let resid = res["residual"].as_f64().expect("residual");
    let scale = enn.abs();
    assert!(
        resid <= 1e-10 * scale,
        "{what}: u is not linear (residual {resid:e})"
    );
    for (i, row) in grad.iter().enumerate() {
        for (j, &g) in row.iter().enumerate() {
            let want = if i != j {
                0.0
            } else if i == dim - 1 {
                enn
            } else {
                exx
            };
            assert!(
                (g - want).abs() <= 1e-10 * scale,
                "{what}: ∂u_{i}/∂x_{j} = {g:e}, exact {want:e}"
            );
        }
    }
    // the bottom stays on the plane: no normal translation
    assert!(
        off[dim - 1].abs() <= 1e-12,
        "{what}: normal offset {:e}",
        off[dim - 1]
    );
}

/// Least-squares fit u ≈ G x + c over all mesh nodes of solution.h5.
const LINEAR_FIT_PY: &str = r#"
import sys, json, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
x = f["mesh/geometry"][:]
u = f["nodal/displacement"][:]
d = 3 if np.ptp(x[:, 2]) > 0 else 2
x, u = x[:, :d], u[:, :d]
A = np.hstack([x, np.ones((len(x), 1))])
coef, *_ = np.linalg.lstsq(A, u, rcond=None)
res = np.abs(A @ coef - u).max()
print("RESULT " + json.dumps({"grad": coef[:d].T.tolist(), "offset": coef[d].tolist(), "residual": float(res)}))
"#;

#[test]
fn block2d_uniform_pressure_on_plane() {
    block_on_plane(2, 1);
    block_on_plane(2, 2);
}

#[test]
fn block3d_uniform_pressure_on_plane() {
    block_on_plane(3, 1);
    block_on_plane(3, 2);
}

#[test]
fn block_pulled_off_the_plane_has_no_contact() {
    // tests/cases/block2d_pulled.toml: top held at u = (0, 0.01), no load: the block translates
    // rigidly up by 0.01, every contact node lifts off and carries no force.
    let case = repo("tests/cases/block2d_pulled.toml");
    let lift = 0.01;
    // λ scale: the force of straining the block by its lift, E · lift · width
    let fscale = 2.0 * lift * 2.0;
    for (np, init) in [(1, "all_active"), (1, "auto"), (2, "all_active")] {
        let init_set = format!("newton.init={init}");
        let s = solve(np, &case, &[&init_set]);
        let what = format!("pulled block, init {init}, {np} rank(s)");
        assert!(s.converged(), "{what}:\n{}", s.run.output());
        assert_eq!(
            s.f(&["contact", "active_count"]),
            0.0,
            "{what}: active nodes"
        );
        let rows = s.contact_rows();
        assert_eq!(rows.len(), 21, "{what}: contact nodes of block2d.msh");
        for r in &rows {
            assert!(!r.active(), "{what}: node {} active", r.node_id());
            for key in ["lambda_n", "lambda_t1", "pressure"] {
                assert!(
                    r.f(key).abs() <= 1e-12 * fscale,
                    "{what}: node {} {key} = {:e}",
                    r.node_id(),
                    r.f(key)
                );
            }
            assert!(
                rel(r.f("u_n"), lift) < 1e-10,
                "{what}: node {} u_n = {:e}",
                r.node_id(),
                r.f("u_n")
            );
            assert!(
                rel(r.f("gap"), lift) < 1e-10,
                "{what}: node {} gap = {:e}",
                r.node_id(),
                r.f("gap")
            );
        }
        for fi in s.total_force() {
            assert!(
                fi.abs() <= 1e-12 * fscale,
                "{what}: Σ −λ = {:?}",
                s.total_force()
            );
        }
        assert!(s.f(&["contact", "max_pressure"]).abs() <= 1e-12 * fscale);
    }
}

/// Mirror comparison of solution.h5 about x = 0: nodes matched by coordinates (rounded to
/// 1e-9), u_x odd and u_y even; contact pressure and state even.
const MIRROR_PY: &str = r#"
import sys, json, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
x = f["mesh/geometry"][:, :2]; u = f["nodal/displacement"][:, :2]
key = lambda a, b: (round(a, 9) + 0.0, round(b, 9) + 0.0)
idx = {key(*p): i for i, p in enumerate(x)}
mir = [idx.get(key(-p[0], p[1])) for p in x]
if any(m is None for m in mir):
    print("RESULT " + json.dumps({"symmetric_mesh": False})); sys.exit(0)
mir = np.array(mir)
du = max(np.abs(u[:, 0] + u[mir, 0]).max(), np.abs(u[:, 1] - u[mir, 1]).max())
c = f["contact/geometry"][:, :2]; p = f["contact/pressure"][:]; st = f["contact/state"][:]
cidx = {key(*q): i for i, q in enumerate(c)}
cm = np.array([cidx[key(-q[0], q[1])] for q in c])
print("RESULT " + json.dumps({"symmetric_mesh": True, "du": float(du), "umax": float(np.abs(u).max()),
    "dp": float(np.abs(p - p[cm]).max()), "pmax": float(p.max()),
    "state_symmetric": bool((st == st[cm]).all())}))
"#;

#[test]
fn indentation_by_circle_is_symmetric() {
    // Mirror-symmetric mesh (tests/cases/indent2d_sym.geo): exact symmetry to round-off.
    let s = solve(1, &repo("tests/cases/indent2d_sym.toml"), &[]);
    assert!(s.converged(), "indent2d_sym:\n{}", s.run.output());
    let m = python_json(MIRROR_PY, &[&s.dir.join("solution.h5")]);
    assert_eq!(
        m["symmetric_mesh"], true,
        "indent2d_sym.msh is not mirror-symmetric"
    );
    let g = |k: &str| m[k].as_f64().unwrap();
    assert!(
        m["state_symmetric"] == true,
        "active set not symmetric: {m}"
    );
    assert!(g("dp") <= 1e-10 * g("pmax"), "pressure not symmetric: {m}");
    assert!(
        g("du") <= 1e-10 * g("umax"),
        "displacement not symmetric: {m}"
    );
    let rows = s.contact_rows();
    let active: Vec<&Row> = rows.iter().filter(|r| r.active()).collect();
    assert!(
        active.len() >= 9,
        "only {} active nodes: the zone is not resolved",
        active.len()
    );
    // The zone is one interval around x = 0, odd in count (centre node + mirrored pairs).
    assert_eq!(active.len() % 2, 1, "even active count on a symmetric mesh");
    let xa = active.iter().map(|r| r.f("x").abs()).fold(0.0, f64::max);
    for r in &rows {
        assert_eq!(
            r.active(),
            r.f("x").abs() <= xa,
            "active set is not an interval: {r:?}"
        );
    }
    // The centre node (gap0 = −δ = −0.01) is pushed down onto the circle: u_n = 0.01 along
    // the circle's outward normal (0, −1), i.e. u_y = −0.01, and gap = gap0 + u_n = 0.
    let centre = rows
        .iter()
        .find(|r| r.f("x") == 0.0)
        .expect("node at x = 0");
    assert!(centre.active(), "centre node inactive");
    assert!(
        rel(centre.f("gap0"), -0.01) < 1e-10,
        "centre gap0 {}",
        centre.f("gap0")
    );
    assert!(
        rel(centre.f("u_n"), 0.01) < 1e-10,
        "centre u_n {}",
        centre.f("u_n")
    );
    assert!(
        centre.f("gap").abs() <= 1e-14,
        "centre gap {}",
        centre.f("gap")
    );
    let f = s.total_force();
    assert!(
        f[0].abs() <= 1e-10 * f[1].abs(),
        "Σ −λ = {f:?} not vertical"
    );
    let k = |key: &str| s.f(&["contact", "kkt", key]);
    let (fs, ls) = (k("force_scale"), k("length_scale"));
    assert!(
        k("max_penetration") <= 1e-12 * ls,
        "penetration {:e}",
        k("max_penetration")
    );
    assert!(k("max_positive_lambda_n") <= 1e-12 * fs);
    assert!(k("max_complementarity") <= 1e-12 * fs * ls);

    // The committed cases/blocks/indent2d (an unstructured mesh, not symmetric): the same
    // problem, so symmetric up to the mesh size hf = 0.01 near the zone, and close to the
    // symmetric-mesh result.
    let u = solve(1, &repo("cases/blocks/indent2d.toml"), &[]);
    assert!(u.converged(), "indent2d:\n{}", u.run.output());
    let ur = u.contact_rows();
    let xs: Vec<f64> = ur.iter().filter(|r| r.active()).map(|r| r.f("x")).collect();
    let (lo, hi) = xs
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(
        (hi + lo).abs() <= 0.02,
        "indent2d: active zone [{lo}, {hi}] not symmetric within 2 hf"
    );
    assert!(
        (hi - lo - 2.0 * xa).abs() <= 0.03,
        "indent2d: zone width {} vs {} on the symmetric mesh",
        hi - lo,
        2.0 * xa
    );
    let fu = u.total_force();
    assert!(
        fu[0].abs() <= 1e-3 * fu[1].abs(),
        "indent2d: Σ −λ = {fu:?} not vertical"
    );
    assert!(
        rel(fu[1], f[1]) < 0.02,
        "indent2d: force {} vs {} on the symmetric mesh",
        fu[1],
        f[1]
    );
}

#[test]
fn symmetry_row_on_a_contact_node_equals_the_full_mesh() {
    // The right half of indent2d_sym with u_x = 0 on x = 0 (indent2d_half.geo meshes it as
    // the full mesh's right half): the node (0, 1) is on the contact boundary and on the
    // symmetry line; it keeps its contact row, and the half solution is the full one.
    let full = solve(1, &repo("tests/cases/indent2d_sym.toml"), &[]);
    for np in [1, 2] {
        let half = solve(np, &repo("tests/cases/indent2d_half.toml"), &[]);
        assert!(half.converged(), "indent2d_half:\n{}", half.run.output());
        assert!(
            !half.run.output().contains("left to their Dirichlet data"),
            "the symmetry node was dropped from the contact boundary:\n{}",
            half.run.output()
        );
        let key = |r: &Row| (r.f("x").to_bits(), r.f("y").to_bits());
        let by_x: std::collections::BTreeMap<_, Row> = full
            .contact_rows()
            .into_iter()
            .map(|r| (key(&r), r))
            .collect();
        let rows = half.contact_rows();
        let centre = rows.iter().find(|r| r.f("x") == 0.0).expect("node (0, 1)");
        assert!(centre.active(), "node (0, 1) not active: {centre:?}");
        let pmax = rows
            .iter()
            .map(|r| r.f("pressure").abs())
            .fold(0.0, f64::max);
        let mut n_active = 0;
        for r in &rows {
            let f = by_x
                .get(&key(r))
                .unwrap_or_else(|| panic!("no full node at {r:?}"));
            assert_eq!(r.active(), f.active(), "state differs at {r:?}");
            n_active += usize::from(r.active());
            // the half node (0, 1) has half the weight and half the force; p is the same
            assert!(
                (r.f("pressure") - f.f("pressure")).abs() <= 1e-9 * pmax,
                "{np} rank(s): pressure {} vs full {} at x = {}",
                r.f("pressure"),
                f.f("pressure"),
                r.f("x")
            );
            assert!(
                (r.f("u_n") - f.f("u_n")).abs() <= 1e-9 * 0.01,
                "{np} rank(s): u_n {} vs full {} at x = {}",
                r.f("u_n"),
                f.f("u_n"),
                r.f("x")
            );
        }
        let full_active = by_x.values().filter(|r| r.active()).count();
        assert_eq!(2 * n_active - 1, full_active, "active counts half vs full");
    }
}
