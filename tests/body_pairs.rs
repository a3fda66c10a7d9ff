//! Contact between two deformable bodies (dual mortar, `obstacle = { type = "body" }`;
//! docs/bodies.md): the contact patch test on two blocks meshed independently (interface
//! sizes about 3 : 1), in 2D and 3D, with either side as slave, on 1, 2 and 3 ranks; and the
//! input errors of a body pair.
//!
//! The patch test: two materials, the lower block on a roller support (u_n = 0 at its bottom),
//! both blocks on symmetry planes, the upper block's top pushed down by δ. The exact solution is
//! the uniaxial stress σ_nn = −p in both blocks, p = δ / (H_1/E'_1 + H_2/E'_2), a linear
//! field that P1 elements reproduce; the dual mortar rows transmit it exactly on
//! non-matching meshes: every slave node active with pressure p, u the linear field.

mod common;

use common::*;
use std::path::{Path, PathBuf};

/// (E, ν) of the lower and the upper block.
const LOWER: (f64, f64) = (1.0, 0.45);
const UPPER: (f64, f64) = (3.0, 0.1);
const DELTA: f64 = 0.01;

/// The mesh of tests/meshes/stack{dim}d.geo with sizes hl (lower) and hu (upper).
fn stack_mesh(dir: &Path, dim: usize, hl: f64, hu: f64) -> PathBuf {
    let out = dir.join(format!("stack{dim}d.msh"));
    let (hl, hu) = (hl.to_string(), hu.to_string());
    gmsh_file(
        &mesh_dir().join(format!("stack{dim}d.geo")),
        dim,
        &["-setnumber", "hl", &hl, "-setnumber", "hu", &hu],
        &out,
    );
    out
}

/// The case of the patch test: `slave` against `master`.
fn stack_case(dir: &Path, mesh: &Path, dim: usize, (slave, master): (&str, &str)) -> PathBuf {
    let supports = if dim == 2 {
        r#"
[[dirichlet]]
group = "bottom"
value = ["free", 0.0]
[[dirichlet]]
group = "left"
value = [0.0, "free"]
[[dirichlet]]
group = "top"
value = ["free", -DELTA]
"#
    } else {
        r#"
[[dirichlet]]
group = "bottom"
value = ["free", "free", 0.0]
[[dirichlet]]
group = "x0"
value = [0.0, "free", "free"]
[[dirichlet]]
group = "y0"
value = ["free", 0.0, "free"]
[[dirichlet]]
group = "top"
value = ["free", "free", -DELTA]
"#
    };
    let model = if dim == 2 { "plane_strain" } else { "3d" };
    let text = format!(
        r#"[mesh]
file = {mesh}
[[material]]
group = "lower"
young = {:?}
poisson = {:?}
model = "{model}"
[[material]]
group = "upper"
young = {:?}
poisson = {:?}
model = "{model}"
{supports}
[contact]
group = "{slave}"
obstacle = {{ type = "body", group = "{master}" }}
friction = "none"
[output]
dir = "out"
fields = ["displacement", "contact"]
"#,
        LOWER.0,
        LOWER.1,
        UPPER.0,
        UPPER.1,
        mesh = toml_path(mesh),
        supports = supports.replace("DELTA", &format!("{DELTA:?}")),
    );
    write_case(&dir.join(format!("stack{dim}d_{slave}.toml")), &text)
}

/// The exact pressure and displacement at x of the patch test (blocks of height 1 each), x in
/// the upper block or not.
fn exact(dim: usize) -> (f64, impl Fn(&[f64], bool) -> Vec<f64>) {
    // the modulus along the load and the lateral strain per unit stress: plane strain
    // E' = E / (1 − ν²), ν (1 + ν) / E; 3D E, ν / E
    let moduli = |(e, nu): (f64, f64)| {
        if dim == 2 {
            (e / (1.0 - nu * nu), nu * (1.0 + nu) / e)
        } else {
            (e, nu / e)
        }
    };
    let (lo, up) = (moduli(LOWER), moduli(UPPER));
    let p = DELTA / (1.0 / lo.0 + 1.0 / up.0);
    let u = move |x: &[f64], upper: bool| {
        let lat = if upper { up.1 } else { lo.1 };
        let mut u: Vec<f64> = (0..dim - 1).map(|d| lat * p * x[d]).collect();
        let h = x[dim - 1];
        u.push(match upper {
            false => -p / lo.0 * h,
            true => -p / lo.0 - p / up.0 * (h - 1.0),
        });
        u
    };
    (p, u)
}

/// Node coordinates of solution.h5 by node id, with whether the node is the upper block's
/// (a node of a cell whose centroid lies above the interface).
fn coordinates(s: &Solved) -> std::collections::BTreeMap<u64, (Vec<f64>, bool)> {
    let v = python_json(
        r#"
import sys, json, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
x = f["mesh/geometry"][:]
cells = f["mesh/topology"][:]
dim = cells.shape[1] - 1
upper = np.zeros(len(x), dtype=bool)
for c in cells:
    if x[c, dim - 1].mean() > 1.0:
        upper[c] = True
print("RESULT " + json.dumps({"ids": f["mesh/node_id"][:].tolist(), "x": x.tolist(), "upper": upper.tolist()}))
"#,
        &[&s.dir.join("solution.h5")],
    );
    let ids = v["ids"].as_array().expect("ids");
    let xs = v["x"].as_array().expect("x");
    let up = v["upper"].as_array().expect("upper");
    ids.iter()
        .zip(xs.iter().zip(up))
        .map(|(i, (x, u))| {
            (
                i.as_u64().expect("id"),
                (floats(x), u.as_bool().expect("bool")),
            )
        })
        .collect()
}

/// Every slave node active with the pressure p to 1e-8, u the exact field to 1e-10 of its size.
fn check_patch(s: &Solved, dim: usize, what: &str) {
    s.assert_converged(what);
    let (p, u_exact) = exact(dim);
    let rows = s.contact_rows();
    assert!(rows.len() > 3, "{what}: {} contact nodes", rows.len());
    for r in &rows {
        assert!(r.active(), "{what}: node {} inactive", r.node_id());
        let pr = r.f("pressure");
        assert!(
            rel(pr, p) < 1e-8,
            "{what}: node {} pressure {pr:e}, exact {p:e}",
            r.node_id()
        );
    }
    let x = coordinates(s);
    let u = s.displacement();
    let scale = DELTA;
    let mut worst = 0.0f64;
    for (id, (xi, upper)) in &x {
        let ue = u_exact(xi, *upper);
        for d in 0..dim {
            worst = worst.max((u[id][d] - ue[d]).abs() / scale);
        }
    }
    assert!(
        worst < 1e-10,
        "{what}: u off the exact field by {worst:e} of δ"
    );
}

#[test]
fn two_blocks_meshed_apart_pass_the_patch_test_in_2d_with_either_side_slave() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = stack_mesh(tmp.path(), 2, 1.0 / 9.0, 1.0 / 3.0);
    let upper = stack_case(tmp.path(), &mesh, 2, ("upper_bottom", "lower_top"));
    let lower = stack_case(tmp.path(), &mesh, 2, ("lower_top", "upper_bottom"));
    for (case, np) in [(&upper, 1), (&upper, 3), (&lower, 1), (&lower, 2)] {
        let what = format!("{} on {np} rank(s)", case.display());
        check_patch(&solve(np, case, &[]), 2, &what);
    }
}

#[test]
fn two_boxes_meshed_apart_pass_the_patch_test_in_3d_with_either_side_slave() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = stack_mesh(tmp.path(), 3, 0.15, 0.45);
    let upper = stack_case(tmp.path(), &mesh, 3, ("upper_bottom", "lower_top"));
    let lower = stack_case(tmp.path(), &mesh, 3, ("lower_top", "upper_bottom"));
    for (case, np) in [(&upper, 2), (&lower, 1), (&lower, 3)] {
        let what = format!("{} on {np} rank(s)", case.display());
        check_patch(&solve(np, case, &[]), 3, &what);
    }
}

/// A body pair that cannot be set up: exit code 2, one message naming the key, no output.
fn refused(np: usize, case: &Path, key: &str, words: &str) {
    let out = case.parent().expect("dir").join("refused");
    let run = run_solver(np, case, &[], &out);
    run.expect_code(2, &format!("{}", case.display()));
    let text = run.output();
    assert!(text.contains(key), "the message names {key}:\n{text}");
    assert!(text.contains(words), "the message says {words:?}:\n{text}");
    assert!(
        !out.join("summary.json").exists(),
        "no output on an input error"
    );
}

#[test]
fn a_body_pair_that_cannot_be_set_up_is_refused_with_its_key() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = stack_mesh(tmp.path(), 2, 1.0 / 6.0, 1.0 / 3.0);
    let d = tmp.path();
    // no such group
    let c = stack_case(d, &mesh, 2, ("upper_bottom", "nowhere"));
    refused(
        2,
        &c,
        "contact.obstacle.group",
        "no boundary group \"nowhere\"",
    );
    // the pair's own group
    let c = stack_case(d, &mesh, 2, ("upper_bottom", "upper_bottom"));
    refused(1, &c, "contact.obstacle.group", "also its obstacle's group");
    // one body against itself: its two sides share the corner node (1, 1)
    let c = stack_case(d, &mesh, 2, ("lower_right", "lower_top"));
    refused(
        2,
        &c,
        "contact.obstacle.group",
        "one side of body contact only",
    );
    // a motion of its own
    let ok = stack_case(d, &mesh, 2, ("upper_bottom", "lower_top"));
    let m = std::fs::read_to_string(&ok).expect("case").replace(
        "friction = \"none\"",
        "friction = \"none\"\nmotion = [0.0, -0.01]",
    );
    let moved = write_case(&d.join("moved.toml"), &m);
    refused(1, &moved, "contact.motion", "no motion or force of its own");
    // two groups that do not face each other within the slave group's size
    let c = stack_case(d, &mesh, 2, ("lower_right", "top"));
    refused(1, &c, "contact.obstacle.group", "must face each other");
}
