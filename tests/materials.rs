//! Several materials, one per volume group (`[[material]]`).
//!
//! A bar of two materials in series ("soft" for x < 1, "hard" for x > 1), pushed at its end
//! x = 2 by a uniform pressure p on sliding (symmetry) supports: the stress is uniaxial,
//! σ_xx = −p in both parts, and with the two materials chosen so that their lateral strains
//! agree (ν(1 + ν)/E in plane strain, ν/E in 3D) the exact displacement is piecewise linear,
//! continuous at the interface, which P1 elements on a conforming mesh reproduce to round-off:
//! u_x = ε_soft x (x ≤ 1), ε_soft + ε_hard (x − 1) (x ≥ 1), lateral u = ε_lat · y (and z).
//! Every cell's stress is computed with its own material (σ_zz = ν σ_xx in plane strain).
//! On 1 and 2 ranks, from the Gmsh file and from the distributed .h5 input; then each input
//! error of `[[material]]`: exit code 2, one message naming the key, nothing written.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The pressure at the end x = 2.
const P: f64 = 0.01;
/// (E, ν) of the two parts. 2D plane strain: ν(1 + ν)/E equal (0.3125).
const SOFT_2D: (f64, f64) = (1.0, 0.25);
const HARD_2D: (f64, f64) = (1.248, 0.3);
/// 3D: ν/E equal (0.2).
const SOFT_3D: (f64, f64) = (1.0, 0.2);
const HARD_3D: (f64, f64) = (1.5, 0.3);

/// The bar meshed by gmsh from tests/meshes into `dir`.
fn bar_mesh(dir: &Path, dim: usize) -> PathBuf {
    let (geo, h) = if dim == 2 {
        ("bimaterial_bar.geo", 0.2)
    } else {
        ("bimaterial_bar3d.geo", 0.4)
    };
    let out = dir.join(format!("bar{dim}d.msh"));
    gmsh(geo, dim, h, &out);
    out
}

/// The case of the bar: `[[material]]` soft and hard, sliding supports, pressure P.
fn bar_case(mesh: &Path, dim: usize) -> String {
    let mut s = format!("[mesh]\nfile = {}\n", toml_path(mesh));
    let (soft, hard) = if dim == 2 {
        (SOFT_2D, HARD_2D)
    } else {
        (SOFT_3D, HARD_3D)
    };
    let model = if dim == 2 { "plane_strain" } else { "3d" };
    for (group, (e, nu)) in [("soft", soft), ("hard", hard)] {
        s += &format!(
            "\n[[material]]\ngroup = \"{group}\"\nyoung = {e}\npoisson = {nu}\nmodel = \"{model}\"\n"
        );
    }
    let supports: &[(&str, usize)] = if dim == 2 {
        &[("start", 0), ("bottom", 1)]
    } else {
        &[("start", 0), ("bottom", 1), ("front", 2)]
    };
    for &(group, k) in supports {
        let value: Vec<String> = (0..dim)
            .map(|j| {
                if j == k {
                    "0.0".into()
                } else {
                    "\"free\"".into()
                }
            })
            .collect();
        s += &format!(
            "\n[[dirichlet]]\ngroup = \"{group}\"\nvalue = [{}]\n",
            value.join(", ")
        );
    }
    s += &format!(
        "\n[[neumann]]\ngroup = \"end\"\npressure = {P}\n\n[output]\nfields = [\"displacement\", \"stress\"]\n"
    );
    s
}

/// The strains of one part under σ_xx = −p alone: (axial, lateral).
fn strains((e, nu): (f64, f64), dim: usize) -> (f64, f64) {
    if dim == 2 {
        (-P * (1.0 - nu * nu) / e, P * nu * (1.0 + nu) / e)
    } else {
        (-P / e, P * nu / e)
    }
}

/// Runs `case` on `np` ranks into `out`; exit code 0.
fn run_case(dir: &Path, case: &str, np: usize, out: &Path) -> Run {
    let path = write_case(&dir.join(format!("case_{np}.toml")), case);
    let args = vec![
        path.display().to_string(),
        "-o".into(),
        out.display().to_string(),
    ];
    let r = run_with_timeout(solver(np, &args), Duration::from_secs(180));
    r.expect_code(0, &format!("the bar on {np} rank(s)"));
    r
}

/// max |u − u_exact| / max |u|, and max |σ − σ_exact| / p over the cells (σ by the cell's
/// centroid's part), from `out`/solution.h5.
fn errors(out: &Path, dim: usize) -> (f64, f64) {
    let (soft, hard) = if dim == 2 {
        (SOFT_2D, HARD_2D)
    } else {
        (SOFT_3D, HARD_3D)
    };
    let ((ea, ela), (eb, elb)) = (strains(soft, dim), strains(hard, dim));
    assert!((ela - elb).abs() < 1e-15, "the lateral strains must agree");
    // plane strain: σ_zz = ν σ_xx
    let (sza, szb) = if dim == 2 {
        (-P * soft.1, -P * hard.1)
    } else {
        (0.0, 0.0)
    };
    let script = r#"
import sys, json, h5py
import numpy as np
f = h5py.File(sys.argv[1], "r")
dim, p = int(sys.argv[2]), float(sys.argv[3])
ea, eb, el, sza, szb = (float(a) for a in sys.argv[4:9])
x = f["mesh/geometry"][:]
u = f["nodal/displacement"][:]
ux = np.where(x[:, 0] <= 1.0, ea * x[:, 0], ea + eb * (x[:, 0] - 1.0))
exact = np.zeros_like(u)
exact[:, 0] = ux
for k in range(1, dim):
    exact[:, k] = el * x[:, k]
eu = float(abs(u - exact).max() / abs(u).max())
centroid = x[f["mesh/topology"][:]].mean(axis=1)
s = f["cell/stress"][:].reshape(-1, 3, 3)
soft = centroid[:, 0] < 1.0
want = np.zeros_like(s)
want[:, 0, 0] = -p
want[:, 2, 2] = np.where(soft, sza, szb)
es = float(abs(s - want).max() / p)
print("RESULT " + json.dumps({"u": eu, "stress": es, "soft": int(soft.sum()), "hard": int((~soft).sum())}))
"#;
    let args: Vec<String> = [dim as f64, P, ea, eb, ela, sza, szb]
        .iter()
        .map(|v| v.to_string())
        .collect();
    let mut all = vec![out.join("solution.h5").display().to_string()];
    all.extend(args);
    let paths: Vec<PathBuf> = all.iter().map(PathBuf::from).collect();
    let refs: Vec<&Path> = paths.iter().map(|p| p.as_path()).collect();
    let v = python_json(script, &refs);
    assert!(v["soft"].as_u64().unwrap() > 0 && v["hard"].as_u64().unwrap() > 0);
    (v["u"].as_f64().unwrap(), v["stress"].as_f64().unwrap())
}

/// The bar from the Gmsh file on 1 and 2 ranks and from its .h5 conversion on 2 ranks:
/// u exact to 1e-10, every cell's stress by its own material.
fn bar_exact(dim: usize) {
    let tmp = tempfile::tempdir().unwrap();
    let msh = bar_mesh(tmp.path(), dim);
    let h5 = tmp.path().join(format!("bar{dim}d.h5"));
    convert(&msh, &h5);
    for (np, mesh) in [(1, &msh), (2, &msh), (2, &h5)] {
        let out = tmp
            .path()
            .join(format!("out_{np}_{}", mesh.display()).replace('/', "_"));
        run_case(tmp.path(), &bar_case(mesh, dim), np, &out);
        let (eu, es) = errors(&out, dim);
        println!(
            "{dim}D, {np} rank(s), {}: u {eu:e}, stress {es:e}",
            mesh.display()
        );
        assert!(
            eu <= 1e-10,
            "{dim}D {np} rank(s) {}: u off by {eu:e}",
            mesh.display()
        );
        assert!(
            es <= 1e-10,
            "{dim}D {np} rank(s) {}: stress off by {es:e}",
            mesh.display()
        );
    }
}

#[test]
fn bar_of_two_materials_2d_is_exact() {
    bar_exact(2);
}

#[test]
fn bar_of_two_materials_3d_is_exact() {
    bar_exact(3);
}

/// The bar case with one edit; must be refused: exit code 2, one error line containing every
/// `expect`, nothing but the case file in the directory.
fn refused(np: usize, edit: impl Fn(String) -> String, expect: &[&str]) {
    refused_on(np, false, edit, expect)
}

/// [`refused`], with `h5`: on the bar's distributed .h5 input (`signorini-mpi convert`).
fn refused_on(np: usize, h5: bool, edit: impl Fn(String) -> String, expect: &[&str]) {
    let tmp = tempfile::tempdir().unwrap();
    let mut mesh = bar_mesh(tmp.path(), 2);
    if h5 {
        let out = mesh.with_extension("h5");
        convert(&mesh, &out);
        mesh = out;
    }
    let case_dir = tmp.path().join("case");
    std::fs::create_dir(&case_dir).unwrap();
    let text = edit(bar_case(&mesh, 2));
    let path = write_case(&case_dir.join("case.toml"), &text);
    let args = vec![
        path.display().to_string(),
        "-o".into(),
        case_dir.join("out").display().to_string(),
    ];
    let r = run_with_timeout(solver(np, &args), Duration::from_secs(120));
    r.expect_code(2, "a bad [[material]]");
    let errors: Vec<&str> = r
        .stderr
        .lines()
        .filter(|l| l.starts_with("error"))
        .collect();
    assert_eq!(errors.len(), 1, "one error message:\n{}", r.output());
    println!("refused ({np} rank(s)): {}", errors[0]);
    for e in expect {
        assert!(errors[0].contains(e), "message lacks {e:?}: {}", errors[0]);
    }
    assert!(
        errors[0].contains("case.toml"),
        "names the file: {}",
        errors[0]
    );
    let left: Vec<_> = std::fs::read_dir(&case_dir).unwrap().collect();
    assert_eq!(left.len(), 1, "something was written: {left:?}");
}

/// Replaces the first `from` (which must occur) by `to`.
fn replace(from: &'static str, to: &'static str) -> impl Fn(String) -> String {
    move |s| {
        assert!(s.contains(from), "{from:?} not in the case");
        s.replacen(from, to, 1)
    }
}

#[test]
fn a_group_that_is_missing_or_not_a_volume_group_is_refused() {
    refused(
        0,
        replace("group = \"hard\"", "group = \"nope\""),
        &["material[1].group", "\"nope\" is not in the mesh"],
    );
    refused(
        0,
        replace("group = \"hard\"", "group = \"end\""),
        &["material[1].group", "volume group"],
    );
}

#[test]
fn two_models_are_refused() {
    refused(
        0,
        |s| {
            let i = s.rfind("plane_strain").unwrap();
            format!("{}plane_stress{}", &s[..i], &s[i + "plane_strain".len()..])
        },
        &["material[1].model", "material[0].model"],
    );
}

#[test]
fn a_cell_without_material_is_refused_on_1_and_2_ranks() {
    for (np, h5) in [(0, false), (2, false), (2, true)] {
        // the hard part has no material: every one of its cells is named by count
        refused_on(
            np,
            h5,
            |s| {
                let i = s.find("[[material]]\ngroup = \"hard\"").unwrap();
                let j = i + s[i..].find("model").unwrap();
                let j = j + s[j..].find('\n').unwrap() + 1;
                format!("{}{}", &s[..i], &s[j..])
            },
            &["material", "in no [[material]] group", "Gmsh element tag"],
        );
    }
}

#[test]
fn a_cell_in_two_materials_is_refused_on_1_and_2_ranks() {
    for np in [0, 2] {
        refused(
            np,
            replace("group = \"hard\"", "group = \"bar\""),
            &[
                "material[1].group",
                "a cell has one material",
                "\"soft\"",
                "\"bar\"",
            ],
        );
    }
    refused(
        0,
        replace("group = \"hard\"", "group = \"soft\""),
        &["material[1].group", "already has a material"],
    );
}

#[test]
fn material_and_materials_together_are_refused() {
    refused(
        0,
        |s| format!("{s}\n[material]\nyoung = 1.0\npoisson = 0.3\nmodel = \"plane_strain\"\n"),
        &["material"],
    );
}

/// examples/coated_block.toml runs on 2 ranks, every step converged and in equilibrium, and
/// the stiff coating takes a larger force than the homogeneous block (the coating's E set to
/// the substrate's) on a narrower contact.
#[test]
fn the_coated_block_example_runs() {
    let case = repo("examples/coated_block.toml");
    let coated = solve(2, &case, &[]);
    let plain = solve(2, &case, &["material.0.young=1.0"]);
    for (s, what) in [(&coated, "coated"), (&plain, "homogeneous")] {
        assert_eq!(
            s.summary["load"]["completed"],
            true,
            "{what}: {}",
            s.run.output()
        );
        let eq = s.f(&["certificate", "equilibrium", "relative"]);
        assert!(eq <= 1e-8, "{what}: equilibrium defect {eq:e}");
    }
    let force = |s: &Solved| s.total_force()[1].abs();
    let active = |s: &Solved| s.active_node_ids().len();
    assert!(
        force(&coated) > 1.2 * force(&plain),
        "{} vs {}",
        force(&coated),
        force(&plain)
    );
    assert!(active(&coated) < active(&plain) && active(&coated) > 0);
}

/// A nearly incompressible entry is warned about by its key (P1 locking); the others not.
#[test]
fn a_nearly_incompressible_material_is_named_in_the_warning() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = bar_mesh(tmp.path(), 2);
    let case = bar_case(&mesh, 2).replacen("poisson = 0.3", "poisson = 0.495", 1);
    let r = run_case(tmp.path(), &case, 1, &tmp.path().join("out"));
    let warned: Vec<&str> = r
        .stdout
        .lines()
        .filter(|l| l.contains("close to 1/2"))
        .collect();
    assert_eq!(warned.len(), 1, "{}", r.output());
    assert!(
        warned[0].contains("material[1]: poisson = 0.495"),
        "{}",
        warned[0]
    );
}
