//! `mesh.refine = k` and `[[mesh.project]]` (issue 10, item 3): the refined mesh reproduces a
//! linear field (patch test, 2D and 3D, 1–3 ranks), keeps every physical group with the right
//! number of children, is the same mesh (node ids and coordinates) on every rank count, gives
//! the same contact solution on 1 and 2 ranks, puts the new arc nodes on the circle, and bad
//! values are rejected with exit code 2 naming the key.

mod common;

use common::*;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const E: f64 = 2.0;
const NU: f64 = 0.3;

/// Diagonal stress of the patch test: tractions on right (x), top (y), back (z).
const SIGMA: [f64; 3] = [0.03, -0.02, 0.01];

/// The exact strain of the uniform stress SIGMA (plane strain in 2D: σ_zz = ν (σ_xx + σ_yy)).
fn exact_strain(dim: usize) -> [f64; 3] {
    let mut s = SIGMA;
    if dim == 2 {
        s[2] = NU * (s[0] + s[1]);
    }
    std::array::from_fn(|i| (s[i] - NU * (s[(i + 1) % 3] + s[(i + 2) % 3])) / E)
}

/// A case on the unit square / cube (groups left, right, bottom, top[, front, back], body):
/// symmetry conditions on left, bottom (and front), tractions SIGMA on the opposite sides;
/// the exact solution is u_i = ε_ii x_i.
fn patch_case(dir: &Path, dim: usize, mesh: &Path, refine: usize) -> PathBuf {
    let (model, dirichlet, neumann) = if dim == 2 {
        (
            "model = \"plane_strain\"",
            [("left", "[0.0, \"free\"]"), ("bottom", "[\"free\", 0.0]")].to_vec(),
            vec![
                ("right", format!("[{}, 0.0]", SIGMA[0])),
                ("top", format!("[0.0, {}]", SIGMA[1])),
            ],
        )
    } else {
        (
            "",
            [
                ("left", "[0.0, \"free\", \"free\"]"),
                ("bottom", "[\"free\", 0.0, \"free\"]"),
                ("front", "[\"free\", \"free\", 0.0]"),
            ]
            .to_vec(),
            vec![
                ("right", format!("[{}, 0.0, 0.0]", SIGMA[0])),
                ("top", format!("[0.0, {}, 0.0]", SIGMA[1])),
                ("back", format!("[0.0, 0.0, {}]", SIGMA[2])),
            ],
        )
    };
    let mut text = format!(
        "[mesh]\nfile = {}\nrefine = {refine}\n\n[material]\nyoung = {E}\npoisson = {NU}\n{model}\n",
        toml_path(mesh)
    );
    for (g, v) in dirichlet {
        text += &format!("\n[[dirichlet]]\ngroup = \"{g}\"\nvalue = {v}\n");
    }
    for (g, t) in neumann {
        text += &format!("\n[[neumann]]\ngroup = \"{g}\"\ntraction = {t}\n");
    }
    text += "\n[output]\nfields = [\"displacement\"]\n";
    write_case(&dir.join(format!("patch{dim}d_r{refine}.toml")), &text)
}

/// Node id → (coordinates, displacement).
type Nodes = BTreeMap<u64, (Vec<f64>, Vec<f64>)>;

/// The nodes of solution.h5.
fn nodes(s: &Solved) -> Nodes {
    let v = python_json(
        r#"
import sys, json, h5py
f = h5py.File(sys.argv[1], "r")
print("RESULT " + json.dumps({"ids": f["mesh/node_id"][:].tolist(),
      "x": f["mesh/geometry"][:].tolist(), "u": f["nodal/displacement"][:].tolist()}))
"#,
        &[&s.dir.join("solution.h5")],
    );
    let col = |k: &str| v[k].as_array().expect("array").clone();
    let (ids, x, u) = (col("ids"), col("x"), col("u"));
    ids.iter()
        .zip(x.iter().zip(&u))
        .map(|(i, (x, u))| (i.as_u64().expect("id"), (floats(x), floats(u))))
        .collect()
}

/// The patch test on `mesh` refined `refine` times on 1, 2 and 3 ranks: the linear field to
/// round-off, and the same nodes (ids and coordinates, bit for bit) on every rank count.
fn patch(dim: usize, mesh: &Path, refine: usize, cells_read: usize) {
    let tmp = tempfile::tempdir().unwrap();
    let case = patch_case(tmp.path(), dim, mesh, refine);
    let eps = exact_strain(dim);
    let mut first: Option<Nodes> = None;
    for np in 1..=3 {
        let s = solve(np, &case, &[]);
        let what = format!("{dim}D patch, refine {refine}, {np} rank(s)");
        assert_eq!(s.f(&["refine"]) as usize, refine, "{what}");
        let factor = if dim == 2 { 4usize } else { 8 };
        assert_eq!(
            s.f(&["cells"]) as usize,
            cells_read * factor.pow(refine as u32),
            "{what}"
        );
        let n = nodes(&s);
        assert_eq!(n.len(), s.f(&["nodes"]) as usize, "{what}");
        let (mut err, mut scale) = (0.0f64, 0.0f64);
        for (x, u) in n.values() {
            for i in 0..dim {
                let ex = eps[i] * x[i];
                err = err.max((u[i] - ex).abs());
                scale = scale.max(ex.abs());
            }
        }
        println!(
            "{what}: {} nodes, max |u - u_exact| = {err:.2e} (max |u| {scale:.2e})",
            n.len()
        );
        assert!(scale > 1e-3, "{what}: no deformation?");
        assert!(
            err <= 1e-10 * scale,
            "{what}: the linear field is not reproduced: error {err:e}, scale {scale:e}\n{}",
            s.run.output()
        );
        match &first {
            None => first = Some(n),
            Some(f) => {
                assert_eq!(
                    f.keys().collect::<Vec<_>>(),
                    n.keys().collect::<Vec<_>>(),
                    "{what}: node ids differ from 1 rank"
                );
                for (id, (x, _)) in &n {
                    assert_eq!(&f[id].0, x, "{what}: node {id} moved");
                }
            }
        }
    }
}

#[test]
fn patch_2d_refined_twice_1_2_3_ranks() {
    patch(
        2,
        &mesh_dir().join("square_h0.25.msh"),
        2,
        cells_of("square_h0.25.msh"),
    );
}

#[test]
fn patch_3d_refined_twice_1_2_3_ranks() {
    patch(
        3,
        &mesh_dir().join("cube_h0.5.msh"),
        2,
        cells_of("cube_h0.5.msh"),
    );
}

/// The cells of a mesh of tests/meshes as read (refine = 0), from the solver's log.
fn cells_of(name: &str) -> usize {
    let mesh = mesh_dir().join(name);
    let dim = if name.starts_with("cube") { 3 } else { 2 };
    let tmp = tempfile::tempdir().unwrap();
    let case = patch_case(tmp.path(), dim, &mesh, 0);
    let s = solve(1, &case, &[]);
    assert!(
        s.summary.get("refine").is_none(),
        "refine = 0 is not written"
    );
    s.f(&["cells"]) as usize
}

/// The counts of the solver's mesh line: (nodes, cells, boundary facets, group → size).
fn mesh_line(run: &Run) -> (usize, usize, usize, BTreeMap<String, usize>) {
    let line = run
        .stdout
        .lines()
        .find(|l| l.starts_with("mesh ") && l.contains("groups:"))
        .unwrap_or_else(|| panic!("no mesh line:\n{}", run.output()));
    let (head, groups) = line.split_once("groups: ").expect("groups");
    let num = |what: &str| -> usize {
        let before = head.split(what).next().expect("count");
        before
            .rsplit(' ')
            .find(|w| !w.is_empty())
            .and_then(|w| w.parse().ok())
            .unwrap_or_else(|| panic!("no count before {what:?} in {line}"))
    };
    let mut g = BTreeMap::new();
    for item in groups.split("), ") {
        let (name, rest) = item.split_once(" (").expect("name (dim, n)");
        let n = rest
            .trim_end_matches(')')
            .rsplit(", ")
            .next()
            .and_then(|w| w.parse().ok())
            .expect("group size");
        g.insert(name.to_string(), n);
    }
    (num(" nodes,"), num(" cells,"), num(" boundary facets"), g)
}

/// A box with a physical group of every dimension: volume, faces, an edge and a corner point.
const BOX_GEO: &str = r#"
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 0.7, 0.5};
Mesh.MeshSizeMax = 0.35;
Physical Volume("body") = {1};
Physical Surface("left") = {1};
Physical Surface("right") = {2};
Physical Curve("edge") = {1};
Physical Point("corner") = {1};
"#;

#[test]
fn counts_every_group_kept_2d_and_3d() {
    let tmp = tempfile::tempdir().unwrap();
    // 2D: the square; the new nodes are one per edge (Euler: E = V + C - 1 on a disk)
    let sq = mesh_dir().join("square_h0.25.msh");
    let runs: Vec<Run> = (0..2)
        .map(|k| {
            let case = patch_case(tmp.path(), 2, &sq, k);
            run_solver(2, &case, &[], &tmp.path().join(format!("o2_{k}")))
        })
        .collect();
    for r in &runs {
        r.expect_code(0, "square");
    }
    let (n0, c0, f0, g0) = mesh_line(&runs[0]);
    let (n1, c1, f1, g1) = mesh_line(&runs[1]);
    assert_eq!(c1, 4 * c0);
    assert_eq!(f1, 2 * f0);
    assert_eq!(n1, n0 + (n0 + c0 - 1), "one new node per edge");
    assert_eq!(g0.keys().collect::<Vec<_>>(), g1.keys().collect::<Vec<_>>());
    for (name, &n) in &g0 {
        let f = if name == "body" { 4 } else { 2 };
        assert_eq!(g1[name], f * n, "2D group {name}");
    }
    // 3D: a box with groups of every dimension
    let geo = tmp.path().join("box.geo");
    std::fs::write(&geo, BOX_GEO).unwrap();
    let msh = tmp.path().join("box.msh");
    let mut cmd = std::process::Command::new("gmsh");
    cmd.arg("-3")
        .arg(&geo)
        .args(["-format", "msh41", "-o"])
        .arg(&msh);
    run_with_timeout(cmd, std::time::Duration::from_secs(120)).expect_code(0, "gmsh box");
    let runs: Vec<Run> = (0..2)
        .map(|k| {
            let case = write_case(
                &tmp.path().join(format!("box{k}.toml")),
                &format!(
                    "[mesh]\nfile = {}\nrefine = {k}\n\n[material]\nyoung = 1.0\npoisson = 0.3\n\n\
                     [[dirichlet]]\ngroup = \"left\"\nvalue = [0.0, 0.0, 0.0]\n\n\
                     [[neumann]]\ngroup = \"right\"\ntraction = [0.1, 0.0, 0.0]\n",
                    toml_path(&msh)
                ),
            );
            run_solver(2, &case, &[], &tmp.path().join(format!("o3_{k}")))
        })
        .collect();
    for r in &runs {
        r.expect_code(0, "box");
    }
    let (n0, c0, f0, g0) = mesh_line(&runs[0]);
    let (n1, c1, f1, g1) = mesh_line(&runs[1]);
    println!("box: {n0} -> {n1} nodes, {c0} -> {c1} cells, {f0} -> {f1} facets, {g0:?} -> {g1:?}");
    assert_eq!(c1, 8 * c0);
    assert_eq!(f1, 4 * f0);
    assert!(n1 > n0);
    assert_eq!(g0.len(), 5, "{g0:?}");
    assert_eq!(g0.keys().collect::<Vec<_>>(), g1.keys().collect::<Vec<_>>());
    for (name, &n) in &g0 {
        let f = match name.as_str() {
            "body" => 8,
            "left" | "right" => 4,
            "edge" => 2,
            _ => 1, // the corner keeps its node
        };
        assert!(n > 0, "group {name} empty");
        assert_eq!(g1[name], f * n, "3D group {name}");
    }
}

/// The Hertz disk at level `level` refined once, every arc projected onto the unit circle.
fn hertz_refined(dir: &Path, level: usize) -> PathBuf {
    let mesh = repo(&format!("cases/hertz/meshes/hertz_L{level}.msh"));
    let mut text = std::fs::read_to_string(repo("cases/hertz/hertz.toml")).unwrap();
    let start = text.find("[mesh]").unwrap();
    let end = start + text[start..].find("\n\n").unwrap();
    let mut mesh_section = format!("[mesh]\nfile = {}\nrefine = 1\n", toml_path(&mesh));
    for g in ["contact", "load", "free"] {
        mesh_section += &format!(
            "\n[[mesh.project]]\ngroup = \"{g}\"\nshape = {{ type = \"sphere\", center = [0.0, 0.0], radius = 1.0 }}\n"
        );
    }
    text.replace_range(start..end, &mesh_section);
    write_case(&dir.join(format!("hertz_L{level}_r1.toml")), &text)
}

/// solution.h5 of a contact run by node id: displacement, and the contact nodes' coordinates
/// and states.
const CONTACT_PY: &str = r#"
import sys, json, h5py
f = h5py.File(sys.argv[1], "r")
print("RESULT " + json.dumps({"ids": f["mesh/node_id"][:].tolist(),
      "u": f["nodal/displacement"][:].tolist(),
      "cids": f["contact/node_id"][:].tolist(), "cx": f["contact/geometry"][:].tolist(),
      "state": f["contact/state"][:].tolist()}))
"#;

#[test]
fn hertz_refined_same_on_1_and_2_ranks_arc_on_circle() {
    let tmp = tempfile::tempdir().unwrap();
    let case = hertz_refined(tmp.path(), 2);
    let runs: Vec<Solved> = (1..=2).map(|np| solve(np, &case, &[])).collect();
    let data: Vec<Value> = runs
        .iter()
        .map(|s| {
            s.assert_converged("refined Hertz L2");
            python_json(CONTACT_PY, &[&s.dir.join("solution.h5")])
        })
        .collect();
    let by_id = |v: &Value, ids: &str, vals: &str| -> BTreeMap<u64, Vec<f64>> {
        v[ids]
            .as_array()
            .unwrap()
            .iter()
            .zip(v[vals].as_array().unwrap())
            .map(|(i, x)| {
                let x = match x {
                    Value::Array(_) => floats(x),
                    _ => vec![x.as_f64().unwrap()],
                };
                (i.as_u64().unwrap(), x)
            })
            .collect()
    };
    let (u1, u2) = (by_id(&data[0], "ids", "u"), by_id(&data[1], "ids", "u"));
    let (du, scale) = max_diff(&u2, &u1);
    println!("refined Hertz L2: 1 vs 2 ranks |du| = {du:.2e}, max |u| = {scale:.2e}");
    assert!(du <= 1e-10 * scale, "u differs: {du:e} vs {scale:e}");
    assert_eq!(
        by_id(&data[0], "cids", "state"),
        by_id(&data[1], "cids", "state"),
        "contact states differ"
    );
    // L2 has 16 contact segments: 17 nodes, 33 after one refinement, all on the circle
    let cx = by_id(&data[0], "cids", "cx");
    assert_eq!(cx.len(), 33);
    for (id, x) in &cx {
        let r = (x[0] * x[0] + x[1] * x[1]).sqrt();
        assert!((r - 1.0).abs() < 1e-14, "contact node {id} at radius {r}");
    }
    // the same peak pressure
    let p_max: Vec<f64> = runs
        .iter()
        .map(|s| s.f(&["contact", "max_pressure"]))
        .collect();
    assert!(rel(p_max[1], p_max[0]) < 1e-10, "{p_max:?}");
}

#[test]
fn bad_refine_values_exit_2_naming_the_key() {
    let tmp = tempfile::tempdir().unwrap();
    let case = hertz_refined(tmp.path(), 0);
    for (np, set, key) in [
        (1, "mesh.refine=-1", "mesh.refine"),
        (1, "mesh.refine=1.5", "mesh.refine"),
        (1, "mesh.refine=\"2\"", "mesh.refine"),
        (
            2,
            "mesh.project.1.group=\"nowhere\"",
            "mesh.project[1].group",
        ),
        (2, "mesh.project.0.group=\"body\"", "mesh.project[0].group"),
        (
            1,
            "mesh.project.0.shape={type=\"torus\"}",
            "mesh.project[0].shape.type",
        ),
        (
            2,
            "mesh.project.2.shape={type=\"plane\",point=[0,0,0],normal=[0,1,0]}",
            "mesh.project[2].shape.point",
        ),
        // a circle of half the disk's radius: the new contact nodes invert their cells
        (
            2,
            "mesh.project.0.shape={type=\"sphere\",center=[0,0],radius=0.5}",
            "mesh.project",
        ),
    ] {
        let out = tmp.path().join("out");
        let r = run_solver(np, &case, &[set], &out);
        r.expect_code(2, set);
        assert!(
            r.stderr.contains(&format!("'{key}'")),
            "{set}: the message does not name {key}:\n{}",
            r.output()
        );
        assert!(!r.stderr.contains("panicked"), "{}", r.output());
        assert!(!out.exists(), "{set}: output written");
    }
}

/// The lower half of the unit ball: flat face "flat" (clamped), curved face "curved".
const HEMI_GEO: &str = r#"
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 1, -Pi/2, 0};
Mesh.MeshSizeMax = 0.4;
flat() = Surface In BoundingBox{-2, -2, -1e-6, 2, 2, 1e-6};
curved() = Surface{:};
curved() -= flat();
Physical Surface("flat") = {flat()};
Physical Surface("curved") = {curved()};
Physical Volume("body") = {1};
"#;

#[test]
fn sphere_projection_3d_puts_new_surface_nodes_on_the_sphere() {
    let tmp = tempfile::tempdir().unwrap();
    let geo = tmp.path().join("hemi.geo");
    std::fs::write(&geo, HEMI_GEO).unwrap();
    let msh = tmp.path().join("hemi.msh");
    let mut cmd = std::process::Command::new("gmsh");
    cmd.arg("-3")
        .arg(&geo)
        .args(["-format", "msh41", "-o"])
        .arg(&msh);
    run_with_timeout(cmd, std::time::Duration::from_secs(120)).expect_code(0, "gmsh hemi");
    // the curved face is the contact group (its nodes are written with their coordinates);
    // the plane lies below the body, so nothing touches
    let radii = |project: bool| -> (usize, f64) {
        let text = format!(
            "[mesh]\nfile = {}\nrefine = 1\n{}\n[material]\nyoung = 1.0\npoisson = 0.3\n\n\
             [[dirichlet]]\ngroup = \"flat\"\nvalue = [0.0, 0.0, 0.0]\n\n\
             [body_force]\nvalue = [0.0, 0.0, -0.01]\n\n[contact]\ngroup = \"curved\"\n\
             obstacle = {{ type = \"plane\", point = [0.0, 0.0, -1.5], normal = [0.0, 0.0, 1.0] }}\n",
            toml_path(&msh),
            if project {
                "\n[[mesh.project]]\ngroup = \"curved\"\n\
                 shape = { type = \"sphere\", center = [0.0, 0.0, 0.0], radius = 1.0 }\n"
            } else {
                ""
            }
        );
        let case = write_case(&tmp.path().join(format!("hemi_{project}.toml")), &text);
        let s = solve(2, &case, &[]);
        s.assert_converged("hemisphere");
        let v = python_json(CONTACT_PY, &[&s.dir.join("solution.h5")]);
        let xs = v["cx"].as_array().unwrap();
        let dev = xs
            .iter()
            .map(|x| {
                let x = floats(x);
                ((x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() - 1.0).abs()
            })
            .fold(0.0f64, f64::max);
        (xs.len(), dev)
    };
    let (n, dev) = radii(true);
    println!("projected: {n} contact nodes, max ||x| - 1| = {dev:.1e}");
    assert!(n > 100, "{n}");
    assert!(dev < 1e-12, "a surface node is off the sphere by {dev:e}");
    let (n2, dev2) = radii(false);
    println!("not projected: {n2} contact nodes, max ||x| - 1| = {dev2:.1e}");
    assert_eq!(n, n2);
    assert!(
        dev2 > 1e-3,
        "without projection the new nodes stay on the flat facets"
    );
}
