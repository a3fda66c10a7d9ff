//! Output check with meshio (issue acceptance criterion 4): the binary's solution.xdmf opens
//! with meshio (Debian's /usr/bin/python3), has the mesh's point and cell counts, exactly the
//! arrays listed in output.fields (plus the node_id / cell_id identifiers), displacement with 3
//! components (z = 0 in 2D), stress with 9, von_mises equal to the standard formula of the
//! stress tensor, rank in 0..ranks. The Python side also recomputes every cell stress from the
//! written displacement and connectivity with Hooke's law, so cell data order, connectivity and
//! nodal data must all agree.

mod common;

use common::*;
use std::path::Path;
use std::time::Duration;

const CHECK_PY: &str = r#"
import json, os, shutil, sys
import numpy as np
import meshio

d, msh, model, E, nu, ranks = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4]), float(sys.argv[5]), int(sys.argv[6])
fields = json.loads(sys.argv[7])
dim = 3 if model == "3d" else 2
ctype = "tetra" if dim == 3 else "triangle"

# The input mesh, read independently: body cells and the nodes they use.
src = meshio.read(msh)
conn_src = np.concatenate([c.data for c in src.cells if c.type == ctype])
used = np.unique(conn_src)
n_points, n_cells = len(used), len(conn_src)

# The XDMF must stay readable when the directory moves (relative HDF5 path).
moved = d + "_moved"
shutil.copytree(d, moved)
m = meshio.read(os.path.join(moved, "solution.xdmf"))
assert len(m.points) == n_points, (len(m.points), n_points)
assert m.points.shape[1] == 3
assert len(m.cells) == 1 and m.cells[0].type == ctype, [c.type for c in m.cells]
conn = m.cells[0].data
assert conn.shape == (n_cells, dim + 1), conn.shape
assert conn.min() >= 0 and conn.max() < n_points
# Same point set as the input mesh (sorted lexicographically).
a = src.points[used]
b = m.points.copy()
if dim == 2:
    assert np.all(b[:, 2] == 0.0)
key = lambda p: np.lexsort((p[:, 2], p[:, 1], p[:, 0]))
assert np.allclose(a[key(a)], b[key(b)], rtol=0, atol=1e-12), "points differ from the mesh"

expect_point = {"node_id"} | ({"displacement"} if "displacement" in fields else set())
expect_cell = {"cell_id"} | (set(fields) & {"stress", "von_mises", "von_mises_thesis", "rank"})
pd = dict(m.point_data)
cd = {k: v[0] for k, v in m.cell_data.items()}
assert set(pd) == expect_point, ("point data", sorted(pd), sorted(expect_point))
assert set(cd) == expect_cell, ("cell data", sorted(cd), sorted(expect_cell))
assert len(np.unique(pd["node_id"])) == n_points
assert len(np.unique(cd["cell_id"])) == n_cells

out = {"points": int(n_points), "cells": int(n_cells), "point_data": sorted(pd), "cell_data": sorted(cd)}

mu = E / (2 * (1 + nu))
lam = E * nu / (1 - nu * nu) if model == "plane_stress" else E * nu / ((1 + nu) * (1 - 2 * nu))

def hooke(H):
    eps = np.zeros((len(H), 3, 3))
    eps[:, :dim, :dim] = 0.5 * (H + np.transpose(H, (0, 2, 1)))
    tr = np.trace(eps, axis1=1, axis2=2)
    s = 2 * mu * eps
    for i in range(dim):
        s[:, i, i] += lam * tr
    if model == "plane_strain":
        s[:, 2, 2] = lam * tr
    return s

if "displacement" in pd:
    u = pd["displacement"]
    assert u.shape == (n_points, 3), u.shape
    if dim == 2:
        assert np.all(u[:, 2] == 0.0), "2D displacement must have z = 0"
    assert np.abs(u).max() > 0
    out["u_max"] = float(np.abs(u).max())
    # Cell stresses recomputed from the written displacement and connectivity.
    X = m.points[conn][:, :, :dim]          # cells x (dim+1) x dim
    U = u[conn][:, :, :dim]
    J = np.transpose(X[:, 1:, :] - X[:, :1, :], (0, 2, 1))    # columns x_a - x_0
    D = np.transpose(U[:, 1:, :] - U[:, :1, :], (0, 2, 1))
    H = D @ np.linalg.inv(J)                 # displacement gradient, du_i/dx_j
    s_expect = hooke(H)
else:
    s_expect = None

if "stress" in cd:
    s = cd["stress"]
    assert s.shape == (n_cells, 9), s.shape
    S = s.reshape(-1, 3, 3)
    scale = np.abs(S).max()
    assert scale > 0
    assert np.allclose(S, np.transpose(S, (0, 2, 1)), rtol=0, atol=1e-12 * scale), "stress not symmetric"
    if dim == 2:
        assert np.all(S[:, 0, 2] == 0) and np.all(S[:, 1, 2] == 0)
        if model == "plane_strain":   # eps_zz = 0: sigma_zz = nu (sigma_xx + sigma_yy)
            assert np.allclose(S[:, 2, 2], nu * (S[:, 0, 0] + S[:, 1, 1]), rtol=0, atol=1e-10 * scale)
        else:                          # plane stress
            assert np.all(S[:, 2, 2] == 0)
    if s_expect is not None:
        err = np.abs(S - s_expect).max() / scale
        out["stress_vs_displacement"] = float(err)
        assert err < 1e-9, err
else:
    S = s_expect

if "von_mises" in cd:
    vm = cd["von_mises"]
    assert vm.shape == (n_cells,), vm.shape
    assert S is not None
    ref = np.sqrt(0.5 * ((S[:, 0, 0] - S[:, 1, 1]) ** 2 + (S[:, 1, 1] - S[:, 2, 2]) ** 2
                         + (S[:, 2, 2] - S[:, 0, 0]) ** 2)
                  + 3 * (S[:, 0, 1] ** 2 + S[:, 1, 2] ** 2 + S[:, 2, 0] ** 2))
    err = np.abs(vm - ref).max() / np.abs(ref).max()
    out["von_mises_err"] = float(err)
    assert err < 1e-9, err

if "rank" in cd:
    r = cd["rank"]
    assert r.shape == (n_cells,)
    assert np.all(r == np.rint(r))
    out["ranks_seen"] = sorted(set(int(x) for x in r))
    assert out["ranks_seen"] == list(range(ranks)), out["ranks_seen"]
print("RESULT " + json.dumps(out))
"#;

/// Writes the case, runs the binary on `np` ranks and checks the output with meshio.
fn check_output(dim: usize, model: &str, h: f64, np: usize, fields: &[&str]) -> serde_json::Value {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = unit_mesh(tmp.path(), dim, h);
    let (e, nu) = (50.0, 0.3);
    let fields_toml = format!("{fields:?}");
    let text = if dim == 2 {
        format!(
            r#"
[mesh]
file = {mesh}
[material]
young = {e}
poisson = {nu}
model = "{model}"
[[dirichlet]]
group = "left"
value = [0.0, 0.0]
[[neumann]]
group = "right"
traction = [1.0, -0.5]
[[neumann]]
group = "top"
pressure = 0.2
[output]
fields = {fields_toml}
"#,
            mesh = toml_path(&mesh)
        )
    } else {
        format!(
            r#"
[mesh]
file = {mesh}
[material]
young = {e}
poisson = {nu}
[[dirichlet]]
group = "bottom"
value = [0.0, 0.0, 0.0]
[[neumann]]
group = "top"
traction = [0.5, -1.0, 0.3]
[body_force]
value = [0.0, -2.0, 0.0]
[output]
fields = {fields_toml}
"#,
            mesh = toml_path(&mesh)
        )
    };
    let case = write_case(&tmp.path().join("case.toml"), &text);
    let out = tmp.path().join("out");
    let args = vec![
        case.display().to_string(),
        "-o".into(),
        out.display().to_string(),
    ];
    run_with_timeout(solver(np, &args), Duration::from_secs(180))
        .expect_code(0, &format!("{dim}D {model} on {np} ranks"));
    let fields_json = serde_json::to_string(fields).unwrap();
    let args: Vec<String> = vec![
        out.display().to_string(),
        mesh.display().to_string(),
        model.to_string(),
        e.to_string(),
        nu.to_string(),
        np.to_string(),
        fields_json,
    ];
    let res = json_after(&python(CHECK_PY, &args), "RESULT ");
    println!("{dim}D {model} {np} ranks: {res}");
    check_files(&out);
    res
}

/// Exactly the three result files, no staging directory left next to them.
fn check_files(out: &Path) {
    let mut names: Vec<String> = std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["solution.h5", "solution.xdmf", "summary.json"]);
    let parent = out.parent().unwrap();
    for e in std::fs::read_dir(parent).unwrap() {
        let n = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            !n.ends_with(".partial"),
            "staging directory {n} left behind"
        );
    }
}

#[test]
fn plane_strain_all_cell_fields_2_ranks() {
    let r = check_output(
        2,
        "plane_strain",
        0.1,
        2,
        &["displacement", "stress", "von_mises", "rank"],
    );
    assert!(r["stress_vs_displacement"].is_number(), "{r}");
    assert!(r["von_mises_err"].is_number(), "{r}");
    assert_eq!(r["ranks_seen"], serde_json::json!([0, 1]));
}

#[test]
fn solid_3_ranks_without_rank_field() {
    let r = check_output(3, "3d", 0.25, 3, &["displacement", "stress", "von_mises"]);
    assert_eq!(
        r["cell_data"],
        serde_json::json!(["cell_id", "stress", "von_mises"])
    );
    assert!(r["stress_vs_displacement"].is_number(), "{r}");
}

#[test]
fn plane_stress_only_displacement_and_von_mises() {
    // stress and rank are not listed: absent; von_mises is checked against the stress
    // recomputed from the displacement.
    let r = check_output(2, "plane_stress", 0.1, 1, &["displacement", "von_mises"]);
    assert_eq!(
        r["point_data"],
        serde_json::json!(["displacement", "node_id"])
    );
    assert_eq!(r["cell_data"], serde_json::json!(["cell_id", "von_mises"]));
    assert!(r["von_mises_err"].is_number(), "{r}");
}

#[test]
fn no_displacement_when_not_listed() {
    let r = check_output(2, "plane_strain", 0.2, 2, &["stress"]);
    assert_eq!(r["point_data"], serde_json::json!(["node_id"]));
    assert_eq!(r["cell_data"], serde_json::json!(["cell_id", "stress"]));
}
