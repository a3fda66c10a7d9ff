//! Mirror planes with friction: a part of a symmetric body with mirror-plane Dirichlet data
//! (u·e = 0 on the plane, e its normal) must give the whole body's answer on the part. A
//! contact node on a mirror plane is a contact node as any other (a symmetry row: its fixed
//! component is orthogonal to its contact normal); with friction such nodes were once left to
//! their Dirichlet data alone, and penetrated the obstacle (a half block under a circle:
//! p_max +36 %, the node on the mirror line 3.4 % of the indentation inside).
//!
//! Each test meshes the part with gmsh, mirrors it node for node into the whole body
//! (tests/meshes/mirror.py), solves the same case on both and compares u at the part's nodes
//! (matched by their coordinates).

mod common;

use common::*;
use std::path::{Path, PathBuf};

/// The part's mesh from `geo` (tests/meshes, `h` its size) and the whole body's, mirrored at
/// the planes `axes` ("x": x = 0, "xy": x = 0 and y = 0) with the boundary groups `keep`.
fn part_and_whole(
    dir: &Path,
    geo: &str,
    dim: usize,
    h: f64,
    axes: &str,
    keep: &str,
) -> [PathBuf; 2] {
    let part = dir.join("part.msh");
    let whole = dir.join("whole.msh");
    gmsh(geo, dim, h, &part);
    let mut cmd = std::process::Command::new(PYTHON);
    cmd.arg(mesh_dir().join("mirror.py"))
        .arg(&part)
        .arg(&whole)
        .args([axes, keep]);
    run_with_timeout(cmd, std::time::Duration::from_secs(120)).expect_code(0, "mirror.py");
    [part, whole]
}

/// max |u_part − u_whole| / max |u_whole| over the part's nodes (matched by coordinates; the
/// last load step's), the
/// smallest gap of the part's contact nodes, and how many of them lie on a mirror plane
/// (`axes`).
fn compare(part: &Solved, whole: &Solved, axes: &str) -> (f64, f64, usize) {
    let v = python_json(
        r#"
import sys, csv, json, h5py
def nodal(d):
    f = h5py.File(d + "/solution.h5", "r")
    steps = sorted((k for k in f if k.startswith("step_")), key=lambda k: int(k[5:]))
    x = f["mesh/geometry"][:]
    u = (f[steps[-1]] if steps else f)["nodal/displacement"][:]
    return {tuple(round(c, 9) for c in p): q for p, q in zip(x.tolist(), u.tolist())}
part, whole = nodal(sys.argv[1]), nodal(sys.argv[2])
scale = max(abs(c) for q in whole.values() for c in q)
diff = max(abs(a - b) for p, q in part.items() for a, b in zip(q, whole[p]))
axes = [ord(a) - ord("x") for a in sys.argv[3]]
rows = list(csv.DictReader(open(sys.argv[1] + "/contact_nodes.csv")))
gap = min(float(r["gap"]) for r in rows)
on = sum(1 for r in rows if any(abs(float(r["xyz"[a]])) < 1e-12 for a in axes))
print("RESULT " + json.dumps([diff / scale, gap, on]))
"#,
        &[&part.dir, &whole.dir, Path::new(axes)],
    );
    let v = v.as_array().expect("result");
    let f = |i: usize| v[i].as_f64().expect("number");
    (f(0), f(1), f(2) as usize)
}

/// Solves `case` on the part (its mirror-plane Dirichlet data included) and on the whole
/// (`whole_dirichlet`: the case's Dirichlet tables without the mirror planes) with the extra
/// settings `sets`, and asserts the same u on the part to `tol`, no penetration, and contact
/// nodes on the mirror planes.
#[allow(clippy::too_many_arguments)]
fn assert_symmetric(
    case: &Path,
    meshes: &[PathBuf; 2],
    whole_dirichlet: &str,
    axes: &str,
    sets: &[&str],
    ranks: &[usize],
    tol: f64,
    what: &str,
) {
    let mesh = |m: &Path| format!("mesh.file={}", toml_path(m));
    let (part_mesh, whole_mesh) = (mesh(&meshes[0]), mesh(&meshes[1]));
    let dirichlet = format!("dirichlet={whole_dirichlet}");
    let mut w: Vec<&str> = vec![&whole_mesh, &dirichlet];
    w.extend(sets);
    let whole = solve(2, case, &w);
    whole.assert_converged(&format!("{what}, the whole body"));
    for &np in ranks {
        let mut p: Vec<&str> = vec![&part_mesh];
        p.extend(sets);
        let part = solve(np, case, &p);
        let label = format!("{what}, the part on {np} rank(s)");
        part.assert_converged(&label);
        let (d, gap, on) = compare(&part, &whole, axes);
        eprintln!("{label}: |u − u_whole| / max|u| = {d:e}, smallest gap {gap:e}, {on} contact nodes on mirror planes");
        assert!(d <= tol, "{label}: |u − u_whole| / max|u| = {d:e}");
        assert!(
            gap >= -1e-12,
            "{label}: a contact node {gap:e} inside the obstacle"
        );
        assert!(on > 0, "{label}: no contact node on a mirror plane");
    }
}

#[test]
fn a_half_block_under_a_circle_with_friction_is_the_whole_blocks_half() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let meshes = part_and_whole(tmp.path(), "mirror_block2d.geo", 2, 0.08, "x", "bottom,top");
    let case = write_case(
        &tmp.path().join("half.toml"),
        "[mesh]\nfile = \"part.msh\"\n[material]\nyoung = 1.0\npoisson = 0.3\n\
         model = \"plane_strain\"\n\
         [[dirichlet]]\ngroup = \"bottom\"\nvalue = [0.0, 0.0]\n\
         [[dirichlet]]\ngroup = \"sym\"\nvalue = [0.0, \"free\"]\n\
         [contact]\ngroup = \"top\"\n\
         obstacle = { type = \"sphere\", center = [0.0, 1.995], radius = 1.0 }\n\
         friction = { law = \"coulomb\", mu = 0.3 }\n\
         [output]\nfields = [\"displacement\", \"contact\"]\n",
    );
    let whole = "[{group=\"bottom\", value=[0.0, 0.0]}]";
    let tresca = "contact.friction={law=\"tresca\", threshold=0.002}";
    let plain = "solver.path=\"plain\"";
    let moving = ["contact.motion=[0.0, -0.003]", "load.steps=2"];
    assert_symmetric(
        &case,
        &meshes,
        whole,
        "x",
        &[],
        &[1, 2, 3],
        1e-10,
        "Coulomb",
    );
    assert_symmetric(
        &case,
        &meshes,
        whole,
        "x",
        &[plain],
        &[2],
        1e-10,
        "Coulomb, plain path",
    );
    assert_symmetric(&case, &meshes, whole, "x", &[tresca], &[2], 1e-10, "Tresca");
    assert_symmetric(
        &case,
        &meshes,
        whole,
        "x",
        &[tresca, plain],
        &[2],
        1e-10,
        "Tresca, plain path",
    );
    assert_symmetric(
        &case,
        &meshes,
        whole,
        "x",
        &moving,
        &[2],
        1e-10,
        "Coulomb, moving circle",
    );
}

#[test]
fn a_quarter_block_under_a_sphere_with_friction_is_the_whole_blocks_quarter() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let meshes = part_and_whole(tmp.path(), "mirror_block3d.geo", 3, 0.2, "xy", "bottom,top");
    let case = write_case(
        &tmp.path().join("quarter.toml"),
        "[mesh]\nfile = \"part.msh\"\n[material]\nyoung = 1.0\npoisson = 0.3\nmodel = \"3d\"\n\
         [[dirichlet]]\ngroup = \"bottom\"\nvalue = [0.0, 0.0, 0.0]\n\
         [[dirichlet]]\ngroup = \"symx\"\nvalue = [0.0, \"free\", \"free\"]\n\
         [[dirichlet]]\ngroup = \"symy\"\nvalue = [\"free\", 0.0, \"free\"]\n\
         [contact]\ngroup = \"top\"\n\
         obstacle = { type = \"sphere\", center = [0.0, 0.0, 2.0], radius = 2.0 }\n\
         motion = [0.0, 0.0, -0.01]\n\
         friction = { law = \"coulomb\", mu = 0.3 }\n\
         [output]\nfields = [\"displacement\", \"contact\"]\n",
    );
    let whole = "[{group=\"bottom\", value=[0.0, 0.0, 0.0]}]";
    let tresca = "contact.friction={law=\"tresca\", threshold=0.0005}";
    assert_symmetric(&case, &meshes, whole, "xy", &[], &[2, 3], 1e-10, "Coulomb");
    assert_symmetric(
        &case,
        &meshes,
        whole,
        "xy",
        &[tresca],
        &[2],
        1e-10,
        "Tresca",
    );
}

/// A body pair on a mirror plane: the lens of cases/bodies/mindlin_bodies3d.toml (coarse), its
/// mirror-plane slave nodes contact nodes with the common normal in the plane (the master's
/// nodal normals there, whose facets lie on one side, turned into it as the slave's are).
#[test]
fn a_half_lens_dragged_on_a_half_block_is_the_whole_pairs_half() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let part = tmp.path().join("part.msh");
    let whole = tmp.path().join("whole.msh");
    gmsh_file(
        &repo("cases/bodies/mindlin_bodies3d.geo"),
        3,
        &[
            "-setnumber",
            "L",
            "0",
            "-setnumber",
            "h0",
            "0.06",
            "-setnumber",
            "Z",
            "0.25",
        ],
        &part,
    );
    let mut cmd = std::process::Command::new(PYTHON);
    cmd.arg(mesh_dir().join("mirror.py"))
        .arg(&part)
        .arg(&whole)
        .args(["y", "lens_top,lens_contact,block_contact,block_bottom"]);
    run_with_timeout(cmd, std::time::Duration::from_secs(120)).expect_code(0, "mirror.py");
    let whole_dirichlet =
        "[{group=\"lens_top\", value=[\"free\", \"free\", -0.00225], ramp=false}, \
         {group=\"lens_top\", value=[0.0006, \"free\", \"free\"]}, \
         {group=\"block_bottom\", value=[0.0, 0.0, 0.0]}]";
    let steps = "load.factors=[0.0, 0.5, 1.0]";
    assert_symmetric(
        &repo("cases/bodies/mindlin_bodies3d.toml"),
        &[part, whole],
        whole_dirichlet,
        "y",
        &[steps],
        &[2],
        1e-10,
        "a body pair with Coulomb",
    );
}

/// A contact node whose tangential displacement Dirichlet data prescribe to a value other
/// than 0 (the bottom-left corner of tests/cases/tresca/block2d_tresca.toml with the left
/// side's x prescribed to 0.05): its friction would contradict its data (the slip row's force
/// in the Dirichlet row moved the corner to x = 0.0497, the equilibrium residual 0.1 of the
/// load), so it keeps its normal condition without friction; its data hold exactly.
#[test]
fn a_contact_node_with_a_prescribed_tangential_value_keeps_it() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let text =
        std::fs::read_to_string(repo("tests/cases/tresca/block2d_tresca.toml")).expect("case");
    let text = text.replace(
        "file = \"../../../cases/blocks/block2d.msh\"",
        &format!("file = {}", toml_path(&repo("cases/blocks/block2d.msh"))),
    );
    let case = write_case(
        &tmp.path().join("corner.toml"),
        &format!("{text}\n[[dirichlet]]\ngroup = \"left\"\nvalue = [0.05, \"free\"]\n"),
    );
    for np in [1, 2] {
        let s = solve(np, &case, &[]);
        s.assert_converged("the block with its left side moved");
        let rows = s.contact_rows();
        let corner = (rows.iter())
            .min_by(|a, b| a.f("x").total_cmp(&b.f("x")))
            .expect("contact nodes");
        assert!(
            corner.active(),
            "{np} rank(s): the corner is not in contact"
        );
        assert!(
            (corner.f("u_t1").abs() - 0.05).abs() < 1e-12,
            "{np} rank(s): the corner's tangential displacement {} against its prescribed 0.05",
            corner.f("u_t1")
        );
        assert_eq!(
            corner.f("lambda_t1"),
            0.0,
            "{np} rank(s): friction at the corner"
        );
        let worst = get(&s.summary, &["certificate", "worst"])
            .as_f64()
            .expect("certificate.worst");
        assert!(worst < 1e-10, "{np} rank(s): certificate {worst:e}");
    }
}
