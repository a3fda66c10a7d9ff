//! Every output of a solve opens with meshio as written — `meshio.read` on solution.xdmf and
//! contact.xdmf after a single solve, `meshio.xdmf.TimeSeriesReader` on both after load steps
//! — and what meshio reads is what h5py reads from solution.h5. The contact surface is made of
//! boundary facets of the mesh's cells, its nodes carry the documented codes (`state`,
//! `slip_state`: −1, 0, 1 as integers with a `codes` attribute), float fields are NaN exactly
//! on the nodes that are not contact nodes, `friction_ratio` is 0 on open nodes, and the
//! surface's contact nodes are the rows of contact_nodes.csv with the same pressure.
//! On 1 and 2 ranks, 2D and 3D, with friction (Tresca blocks).

mod common;

use common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};

const READ_PY: &str = r#"
import csv, json, os, sys
import xml.etree.ElementTree as ET
import numpy as np
import h5py, meshio

d, steps = sys.argv[1], int(sys.argv[2])
f = h5py.File(os.path.join(d, "solution.h5"), "r")
out = {}

def one_grid(fname, name, kind):
    dom = ET.parse(os.path.join(d, fname)).getroot().findall("Domain")
    assert len(dom) == 1
    gs = dom[0].findall("Grid")
    assert len(gs) == 1 and gs[0].get("Name") == name, fname
    assert gs[0].get("GridType") == kind, (fname, gs[0].attrib)

def same(a, b, what):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape, (what, a.shape, b.shape)
    assert a.dtype.kind == b.dtype.kind, (what, a.dtype, b.dtype)
    assert np.array_equal(a, b, equal_nan=(a.dtype.kind == "f")), what

def check_fields(pd, cd, nodal, cell, what):
    """meshio's point/cell data against the HDF5 groups (node_id, cell_id, facet_id are the
    grid's own datasets)."""
    own = {"node_id", "cell_id", "facet_id"}
    names = set(nodal.keys()) - own - {"geometry", "topology"}
    assert set(pd) - own == names, (what, sorted(pd), sorted(names))
    assert set(cd) - own == set(cell.keys() if cell is not None else []), (what, sorted(cd))
    for k in names:
        same(pd[k], nodal[k][:], what + "/" + k)
    for k in (cell.keys() if cell is not None else []):
        same(cd[k][0], cell[k][:], what + "/" + k)

mesh_ids = f["mesh/node_id"][:]
mesh_x = f["mesh/geometry"][:]
topo = f["mesh/topology"][:]
dim = topo.shape[1] - 1
c = f["contact"]
K, F = len(c["node_id"]), len(c["facet_id"])

if steps == 0:
    one_grid("solution.xdmf", "mesh", "Uniform")
    one_grid("contact.xdmf", "contact", "Uniform")
    m = meshio.read(os.path.join(d, "solution.xdmf"))
    same(m.points, mesh_x, "mesh points")
    assert len(m.cells) == 1
    same(m.cells[0].data, topo, "mesh cells")
    same(m.point_data["node_id"], mesh_ids, "node_id")
    same(m.cell_data["cell_id"][0], f["mesh/cell_id"][:], "cell_id")
    check_fields(m.point_data, m.cell_data, f["nodal"], f["cell"], "mesh")
    s = meshio.read(os.path.join(d, "contact.xdmf"))
    contact_steps = [(None, s.point_data, s.cell_data, c)]
    pts, cells = s.points, s.cells
    out["times"] = []
else:
    one_grid("solution.xdmf", "mesh", "Collection")
    one_grid("contact.xdmf", "contact", "Collection")
    with meshio.xdmf.TimeSeriesReader(os.path.join(d, "solution.xdmf")) as r:
        p, cl = r.read_points_cells()
        same(p, mesh_x, "mesh points")
        same(cl[0].data, topo, "mesh cells")
        assert r.num_steps == steps
        times = []
        for k in range(steps):
            t, pd, cd = r.read_data(k)
            times.append(t)
            g = f["step_%d" % (k + 1)]
            check_fields(pd, cd, g["nodal"], g["cell"], "mesh step %d" % (k + 1))
    contact_steps = []
    with meshio.xdmf.TimeSeriesReader(os.path.join(d, "contact.xdmf")) as r:
        pts, cells = r.read_points_cells()
        assert r.num_steps == steps
        for k in range(steps):
            t, pd, cd = r.read_data(k)
            assert t == times[k], (t, times[k])
            contact_steps.append((t, pd, cd, f["step_%d/contact" % (k + 1)]))
    out["times"] = times

# the contact surface: its own geometry and facets, made of boundary facets of the cells
same(pts, c["geometry"][:], "contact points")
assert len(cells) == 1 and cells[0].type == ("line" if dim == 2 else "triangle"), cells
fac = cells[0].data
same(fac, c["topology"][:], "contact facets")
assert fac.shape == (F, dim) and fac.min() >= 0 and fac.max() < K
ids = c["node_id"][:]
assert len(set(ids.tolist())) == K
where = {int(i): n for n, i in enumerate(mesh_ids)}
same(pts, mesh_x[[where[int(i)] for i in ids]], "contact points are mesh points")
faces = {}
for cell in topo:
    for drop in range(dim + 1):
        key = tuple(sorted(int(mesh_ids[v]) for j, v in enumerate(cell) if j != drop))
        faces[key] = faces.get(key, 0) + 1
for fa in fac:
    key = tuple(sorted(int(ids[v]) for v in fa))
    assert faces.get(key) == 1, ("not a boundary facet of the mesh", key)
assert sorted(set(fac.ravel().tolist())) == list(range(K)), "every surface node on a facet"

rows = list(csv.DictReader(open(os.path.join(d, "contact_nodes.csv"))))
codes = {}
for t, pd, cd, g in contact_steps:
    check_fields(pd, cd, g, None, "contact")
    same(cd["facet_id"][0], c["facet_id"][:], "facet_id")
    st = pd["state"]
    assert st.dtype == np.int64 and set(st.tolist()) <= {-1, 0, 1}, st
    codes["state"] = g["state"].attrs["codes"]
    floats = [k for k in pd if pd[k].dtype.kind == "f"]
    for k in floats:
        nan = np.isnan(pd[k]).reshape(K, -1)
        assert (nan.all(axis=1) == (st == -1)).all() and (nan.any(axis=1) == (st == -1)).all(), k
    if "slip_state" in pd:
        sl = pd["slip_state"]
        assert sl.dtype == np.int64 and set(sl.tolist()) <= {-1, 0, 1}
        assert ((sl == -1) == (st != 1)).all(), "slip_state −1 exactly off contact"
        codes["slip_state"] = g["slip_state"].attrs["codes"]
        fr = pd["friction_ratio"]
        assert (fr[st == 0] == 0).all(), "friction_ratio 0 on open nodes"
        assert (fr[st == 1] >= 0).all() and (fr[st == 1] <= 1 + 1e-6).all(), fr[st == 1]
        slip = pd["slip"].reshape(K, -1)
        assert (slip[(st == 0) | (sl == 0)] == 0).all(), "slip only on slip nodes"
        out["slip"] = int((sl == 1).sum())
        out["stick"] = int((sl == 0).sum())
    out["state"] = {str(v): int((st == v).sum()) for v in (-1, 0, 1)}
    # the last step's contact nodes are the rows of contact_nodes.csv
    if t is None or t == out["times"][-1]:
        mine = {int(i): (int(s), float(p)) for i, s, p in zip(ids, st, pd["pressure"]) if s != -1}
        table = {int(r["node_id"]): ("active" == r["state"], float(r["pressure"])) for r in rows}
        assert sorted(mine) == sorted(table), (sorted(mine), sorted(table))
        for i, (s, p) in mine.items():
            assert (s == 1) == table[i][0] and p == table[i][1], (i, mine[i], table[i])
text = open(os.path.join(d, "contact.xdmf")).read()
for k, v in codes.items():
    assert ("%s: %s" % (k, v)) in text, k
out.update({"nodes": K, "facets": F, "codes": codes,
            "surface": sorted(int(i) for i in ids),
            "facet_nodes": sorted(sorted(int(ids[v]) for v in fa) for fa in fac),
            "state_by_id": {str(int(i)): int(s) for i, s in zip(ids, contact_steps[-1][1]["state"])}})
print("RESULT " + json.dumps(out))
"#;

fn tresca(dim: usize) -> PathBuf {
    repo(&format!("tests/cases/tresca/block{dim}d_tresca.toml"))
}

/// block2d_tresca with the left side's displacement prescribed too, across the contact normal
/// as well (the bottom-left corner is then no contact node: a node whose Dirichlet data fix
/// its normal direction is left to its data).
fn tresca_with_held_corner(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(tresca(2)).expect("case");
    let mesh = repo("cases/blocks/block2d.msh");
    let text = text.replace(
        "file = \"../../../cases/blocks/block2d.msh\"",
        &format!("file = {}", toml_path(&mesh)),
    );
    let text = format!("{text}\n[[dirichlet]]\ngroup = \"left\"\nvalue = [0.05, 0.0]\n");
    write_case(&dir.join("held_corner.toml"), &text)
}

fn read(dir: &Path, steps: usize) -> Value {
    python_json(READ_PY, &[dir, Path::new(&steps.to_string())])
}

/// Reads the output of `case` with `sets` on 1 and 2 ranks; the two agree on the surface,
/// its facets and the state of every node.
fn one_and_two(case: &Path, sets: &[&str], steps: usize) -> Vec<Value> {
    let v: Vec<Value> = [1, 2]
        .iter()
        .map(|&np| {
            let s = solve(np, case, sets);
            s.assert_converged(&format!("{} on {np} rank(s)", case.display()));
            read(&s.dir, steps)
        })
        .collect();
    for k in [
        "nodes",
        "facets",
        "surface",
        "facet_nodes",
        "state_by_id",
        "codes",
    ] {
        assert_eq!(v[0][k], v[1][k], "{k}: 1 vs 2 ranks");
    }
    v
}

#[test]
fn single_solve_2d_and_3d_on_1_and_2_ranks() {
    let v = one_and_two(&tresca(2), &[], 0);
    let s = &v[1];
    assert!(s["facets"].as_u64().unwrap() > 0, "{s}");
    assert_eq!(
        s["facets"].as_u64().unwrap() + 1,
        s["nodes"].as_u64().unwrap()
    );
    assert!(s["state"]["1"].as_u64().unwrap() > 0, "{s}");
    assert_eq!(s["state"]["-1"], 0, "{s}");
    assert!(s["codes"]["state"]
        .as_str()
        .unwrap()
        .contains("1 in contact"));
    assert!(s["codes"]["slip_state"]
        .as_str()
        .unwrap()
        .contains("1 slip"));
    let v = one_and_two(&tresca(3), &[], 0);
    assert!(v[1]["facets"].as_u64().unwrap() > v[1]["nodes"].as_u64().unwrap());
}

#[test]
fn load_steps_on_1_and_2_ranks() {
    let v = one_and_two(&tresca(2), &["load.steps=3"], 3);
    for s in &v {
        let t: Vec<f64> = floats(&s["times"]);
        assert_eq!(t.len(), 3, "{s}");
        assert!(
            (t[2] - 1.0).abs() < 1e-15 && t[0] < t[1] && t[1] < t[2],
            "{t:?}"
        );
    }
}

#[test]
fn a_node_held_by_dirichlet_data_is_on_the_surface_with_code_minus_1() {
    let tmp = tempfile::tempdir().unwrap();
    let case = tresca_with_held_corner(tmp.path());
    let v = one_and_two(&case, &[], 0);
    assert_eq!(v[0]["state"]["-1"], 1, "{}", v[0]);
}

/// A distributed mesh (an HDF5 mesh: no rank holds the whole of it) writes the same contact
/// surface as the whole mesh read on one rank.
#[test]
fn distributed_mesh_writes_the_same_surface() {
    let tmp = tempfile::tempdir().unwrap();
    let msh = repo("cases/hertz/meshes/hertz_refined_L2.msh");
    let h5 = tmp.path().join("hertz.h5");
    convert(&msh, &h5);
    let hertz = repo("cases/hertz/hertz.toml");
    let v: Vec<Value> = [(1, &msh), (2, &h5)]
        .iter()
        .map(|&(np, mesh)| {
            let set = format!("mesh.file={}", toml_path(mesh));
            let s = solve(np, &hertz, &[&set, "solver.reuse=\"never\""]);
            read(&s.dir, 0)
        })
        .collect();
    for k in ["nodes", "facets", "surface", "facet_nodes", "state_by_id"] {
        assert_eq!(v[0][k], v[1][k], "{k}: whole mesh vs distributed");
    }
    assert!(v[1]["state"]["1"].as_u64().unwrap() > 0, "{}", v[1]);
}
