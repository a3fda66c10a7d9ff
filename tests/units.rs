//! Results do not depend on the units of a case (docs/case-file.md, "Units"): the same case
//! with every length times s and every stress times f (forces per area; forces per length or
//! volume and forces accordingly) must give the displacements times s to round-off, the same
//! contact and slip state at every contact node and the same Newton steps and factorisations
//! in every load step. Each test solves one case in its own units and in others (the mesh
//! re-saved by gmsh with its coordinates scaled) and compares; each unit system is one in which
//! a constant with a unit hidden in the solver once changed the run. Magnitudes whose squares
//! leave double precision's range are refused before the solve, naming the key.

mod common;

use common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// A unit system against the case's own: lengths times `s`, stresses times `f`.
#[derive(Clone, Copy, Debug)]
struct Units {
    s: f64,
    f: f64,
}

/// The case's own units.
const OWN: Units = Units { s: 1.0, f: 1.0 };

/// Far above round-off (the runs agree to 1e-15–1e-12 where nothing depends on the units) and
/// far below what a changed path or mesh leaves (1e-4–1e-3 in the defects these tests guard).
const TOL: f64 = 1e-8;

/// `mesh` re-saved by gmsh (binary MSH 4.1) with its coordinates times `s` as `out`; the case's
/// own units go the same way (s = 1), so that both runs read files written alike. gmsh parses
/// `-string` through the file $HOME/.gmsh-tmp, which tests running at once shared: a mesh asked
/// for in the case's units came out scaled by another test's 1e-200. Each call has its own
/// HOME (the output's directory).
fn scaled_mesh(mesh: &Path, s: f64, out: &Path) -> PathBuf {
    let mut cmd = Command::new("gmsh");
    cmd.env("HOME", out.parent().expect("a file in a directory"))
        .arg(mesh)
        .args(["-save", "-format", "msh41", "-bin", "-string"])
        .arg(format!("Mesh.ScalingFactor={s:e};"))
        .arg("-o")
        .arg(out);
    run_with_timeout(cmd, Duration::from_secs(60)).expect_code(0, "gmsh -save");
    out.to_path_buf()
}

/// What one load step (or the single solve) gives: u by node id, and the contact state and
/// slip state by contact node id; with the Newton steps and factorisations of the step.
#[derive(Debug)]
struct Step {
    ids: Vec<u64>,
    u: Vec<Vec<f64>>,
    contact_ids: Vec<u64>,
    states: Vec<i64>,
    slip: Vec<i64>,
    newton: (u64, u64),
}

/// Every step of the run that wrote `dir` (solution.h5 and summary.json).
fn steps(dir: &Path) -> Vec<Step> {
    let v = python_json(
        r#"
import sys, json, h5py, numpy as np
f = h5py.File(sys.argv[1] + "/solution.h5", "r")
ids = f["mesh/node_id"][:]
o = np.argsort(ids)
cid = f["contact/node_id"][:] if "contact/node_id" in f else np.zeros(0, dtype=int)
co = np.argsort(cid)
names = sorted((k for k in f if k.startswith("step_")), key=lambda k: int(k[5:]))
out = []
for g in ([f[k] for k in names] if names else [f]):
    c = g["contact"] if "contact" in g else {}
    out.append({
        "u": g["nodal/displacement"][:][o].tolist(),
        "state": c["state"][:][co].tolist() if "state" in c else [],
        "slip": c["slip_state"][:][co].tolist() if "slip_state" in c else [],
    })
print("RESULT " + json.dumps({"ids": ids[o].tolist(), "cid": cid[co].tolist(), "steps": out}))
"#,
        &[dir],
    );
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).expect("summary"))
            .expect("summary.json is JSON");
    let n = |x: &Value| x.as_u64().unwrap_or(0);
    let newton: Vec<(u64, u64)> = match summary.get("load") {
        Some(load) => (load["steps"].as_array().expect("load steps").iter())
            .map(|s| (n(&s["newton_steps"]), n(&s["factorisations"])))
            .collect(),
        None => vec![(
            n(&summary["newton"]["steps"]),
            n(&summary["newton"]["factorisations"]),
        )],
    };
    let ints = |x: &Value| -> Vec<i64> {
        (x.as_array().expect("array").iter())
            .map(|v| v.as_i64().expect("int"))
            .collect()
    };
    let uints = |x: &Value| -> Vec<u64> {
        (x.as_array().expect("array").iter())
            .map(|v| v.as_u64().expect("id"))
            .collect()
    };
    let all = v["steps"].as_array().expect("steps");
    assert_eq!(
        all.len(),
        newton.len(),
        "steps in solution.h5 and summary.json"
    );
    all.iter()
        .zip(newton)
        .map(|(s, newton)| Step {
            ids: uints(&v["ids"]),
            u: (s["u"].as_array().expect("u").iter()).map(floats).collect(),
            contact_ids: uints(&v["cid"]),
            states: ints(&s["state"]),
            slip: ints(&s["slip"]),
            newton,
        })
        .collect()
}

/// Solves the case `text(units, mesh)` on `mesh` (re-saved in those units) in the case's own
/// units and in `units` on `np` ranks, and asserts the same answer: u / s within [`TOL`] of
/// max |u| and the same states and Newton steps and factorisations, step by step.
fn same_in(
    name: &str,
    mesh: &Path,
    text: impl Fn(Units, &Path) -> String,
    units: Units,
    np: usize,
) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mut runs = Vec::new();
    for (tag, un) in [("own", OWN), ("other", units)] {
        let m = scaled_mesh(mesh, un.s, &tmp.path().join(format!("{tag}.msh")));
        let case = write_case(&tmp.path().join(format!("{tag}.toml")), &text(un, &m));
        let out = tmp.path().join(format!("out_{tag}"));
        let run = run_solver(np, &case, &[], &out);
        run.expect_code(0, &format!("{name} in {un:?}"));
        runs.push((run, steps(&out)));
    }
    let (own, other) = (&runs[0].1, &runs[1].1);
    let what = format!("{name}: {units:?} against the case's own units, {np} rank(s)");
    let newton = |r: &[Step]| r.iter().map(|s| s.newton).collect::<Vec<_>>();
    assert_eq!(
        newton(own),
        newton(other),
        "{what}: Newton steps and factorisations per step\n{}\n{}",
        runs[0].0.stdout,
        runs[1].0.stdout
    );
    for (k, (a, b)) in own.iter().zip(other).enumerate() {
        assert_eq!(a.ids, b.ids, "{what}: node ids");
        assert_eq!(a.contact_ids, b.contact_ids, "{what}: contact node ids");
        assert_eq!(a.states, b.states, "{what}, step {}: contact states", k + 1);
        assert_eq!(a.slip, b.slip, "{what}, step {}: slip states", k + 1);
        let scale = a.u.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(scale > 0.0, "{what}: u = 0, nothing compared");
        let diff = (a.u.iter().flatten().zip(b.u.iter().flatten()))
            .fold(0.0f64, |m, (x, y)| m.max((y / units.s - x).abs()));
        println!(
            "{what}, step {}: |u/s − u| = {:.1e} of max |u|",
            k + 1,
            diff / scale
        );
        assert!(
            diff <= TOL * scale,
            "{what}, step {}: |u/s − u| = {:e} of max |u|",
            k + 1,
            diff / scale
        );
    }
}

/// A TOML number.
fn num(x: f64) -> String {
    format!("{x:e}")
}

/// A floating 3D block pressed onto a plane with the default complementarity parameter, in
/// micrometres: the former default c = E / h_c, a stress per length, weighed c u against the
/// nodal force λ with the unit of length squared; in µm the condensed path's dense iteration
/// did not converge and the plain path took 4 factorisations instead of 1.
#[test]
fn a_floating_block_in_micrometres() {
    let text = |u: Units, mesh: &Path| {
        format!(
            "[mesh]\nfile = {}\n[material]\nyoung = {}\npoisson = 0.3\nmodel = \"3d\"\n\
             [[neumann]]\ngroup = \"top\"\npressure = {}\n[contact]\ngroup = \"bottom\"\n\
             obstacle = {{ type = \"plane\", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\n\
             [output]\nfields = [\"displacement\", \"contact\"]\n",
            toml_path(mesh),
            num(2.0 * u.f),
            num(0.1 * u.f),
        )
    };
    let mesh = repo("cases/blocks/block3d.msh");
    same_in("floating block", &mesh, text, Units { s: 1e-6, f: 1.0 }, 2);
}

/// A 2D block dragged over a plane with Tresca friction, stresses in Pa instead of GPa: the
/// condensed Tresca iteration's check compared C_τ of (3.31), a force squared, with ‖λ‖, so in
/// Pa it refused the iterate it accepted in GPa (5 steps and 2 factorisations instead of 4
/// and 1). newton.c, a force per length, is a stress in 2D.
#[test]
fn a_tresca_block_in_pascal_and_in_gigapascal() {
    let text = |u: Units, mesh: &Path| {
        format!(
            "[mesh]\nfile = {}\n[material]\nyoung = {}\npoisson = 0.3\nmodel = \"plane_strain\"\n\
             [[neumann]]\ngroup = \"top\"\npressure = {}\n[[dirichlet]]\ngroup = \"top\"\n\
             value = [{}, \"free\"]\n[contact]\ngroup = \"bottom\"\n\
             obstacle = {{ type = \"plane\", point = [0.0, 0.0], normal = [0.0, 1.0] }}\n\
             friction = {{ law = \"tresca\", threshold = {} }}\n[newton]\nc = {}\n\
             [output]\nfields = [\"displacement\", \"contact\"]\n",
            toml_path(mesh),
            num(2.0 * u.f),
            num(0.1 * u.f),
            num(0.05 * u.s),
            num(0.01 * u.f),
            num(u.f),
        )
    };
    let mesh = repo("cases/blocks/block2d.msh");
    for np in [1, 2] {
        same_in("Tresca block", &mesh, text, Units { s: 1.0, f: 1e9 }, np);
    }
}

/// The Hertz disk (graded level 3) on the condensed path with a tiny unit of stress: MUMPS' LLᵀ
/// Schur complement came back wrong with matrix entries near 1e-18 (a unit of 1e-18: "the
/// final state is not a solution", exit 1); at the bottom of the admissible range (1e-140) it
/// is as exact as in the case's own units.
#[test]
fn the_hertz_disk_in_tiny_units_of_stress() {
    let text = |u: Units, mesh: &Path| {
        format!(
            "[mesh]\nfile = {}\n[material]\nyoung = {}\npoisson = 0.3\nmodel = \"plane_strain\"\n\
             [[neumann]]\ngroup = \"load\"\npressure = {}\n[contact]\ngroup = \"contact\"\n\
             obstacle = {{ type = \"plane\", point = [0.0, {}], normal = [0.0, 1.0] }}\n\
             [newton]\nc = {}\n[output]\nfields = [\"displacement\", \"contact\"]\n",
            toml_path(mesh),
            num(2.0 * u.f),
            num(0.02 * u.f),
            num(-u.s),
            num(u.f),
        )
    };
    let mesh = repo("cases/hertz/meshes/hertz_L3.msh");
    for f in [1e-18, 1e-140] {
        same_in("Hertz disk", &mesh, text, Units { s: 1.0, f }, 2);
    }
}

/// A cube refined once (`mesh.refine`) under a sphere, in km: where two diagonals of a
/// tetrahedron's octahedron are equal, the rounding of the coordinates chose the cut, so the
/// refined mesh in km was another than in m (u differed by 1.3e-3 of max |u|).
#[test]
fn a_refined_cube_in_kilometres() {
    let text = |u: Units, mesh: &Path| {
        format!(
            "[mesh]\nfile = {}\nrefine = 1\n[material]\nyoung = {}\npoisson = 0.3\nmodel = \"3d\"\n\
             [[dirichlet]]\ngroup = \"bottom\"\nvalue = [0.0, 0.0, 0.0]\n[contact]\ngroup = \"top\"\n\
             obstacle = {{ type = \"sphere\", center = [{}, {}, {}], radius = {} }}\n\
             motion = [0.0, {}, 0.0]\n[output]\nfields = [\"displacement\", \"contact\"]\n",
            toml_path(mesh),
            num(2.0 * u.f),
            num(0.5 * u.s),
            num(1.49 * u.s),
            num(0.5 * u.s),
            num(0.5 * u.s),
            num(-0.05 * u.s),
        )
    };
    let mesh = mesh_dir().join("cube_h0.25.msh");
    same_in("refined cube", &mesh, text, Units { s: 1e-3, f: 1.0 }, 2);
}

/// A block indented by a sphere on the iterative preset with a tiny unit of force: GMRES had
/// PETSc's absolute tolerance 1e-50, a residual in the case's unit of force, and stopped at
/// once where the loads are 1e-60 ("the final state is not a solution", exit 1).
#[test]
fn the_iterative_preset_in_a_tiny_unit_of_force() {
    let text = |u: Units, mesh: &Path| {
        format!(
            "[mesh]\nfile = {}\n[material]\nyoung = {}\npoisson = 0.3\nmodel = \"3d\"\n\
             [[dirichlet]]\ngroup = \"bottom\"\nvalue = [0.0, 0.0, 0.0]\n[contact]\ngroup = \"top\"\n\
             obstacle = {{ type = \"sphere\", center = [0.0, 0.0, {}], radius = {} }}\n\
             rigid_modes = \"none\"\n[newton]\ninit = \"gap\"\n[solver]\npreset = \"iterative\"\n\
             [output]\nfields = [\"displacement\", \"contact\"]\n",
            toml_path(mesh),
            num(2.0 * u.f),
            num(0.95 * u.s),
            num(0.5 * u.s),
        )
    };
    let mesh = repo("cases/blocks/block3d.msh");
    same_in(
        "iterative block",
        &mesh,
        text,
        Units { s: 1.0, f: 1e-60 },
        2,
    );
}

/// Cattaneo's load history (Coulomb, the obstacle pressed and then dragged) on the graded Hertz
/// disk in binary millimetres and megapascals (s = 2^10, f = 2^−20: every datum scaled
/// exactly): with the former default c = E / h_c load step 3 took 1 Newton step instead of 3.
#[test]
fn coulomb_load_steps_in_binary_millimetres() {
    let text = |u: Units, mesh: &Path| {
        let m = |x: f64| num(x * u.s);
        format!(
            "[mesh]\nfile = {}\n[material]\nyoung = {}\npoisson = 0.45\nmodel = \"plane_strain\"\n\
             [[dirichlet]]\ngroup = \"load\"\nvalue = [0.0, 0.0]\n[contact]\ngroup = \"contact\"\n\
             obstacle = {{ type = \"plane\", point = [0.0, {}], normal = [0.0, 1.0] }}\n\
             motion = {{ table = [[0.0, 0.0, 0.0], [0.5, 0.0, {}], [1.0, {}, {}]] }}\n\
             friction = {{ law = \"coulomb\", mu = 0.3 }}\nrigid_modes = \"none\"\n\
             [load]\nfactors = [0.25, 0.5, 0.625, 0.75, 0.875, 1.0]\n\
             [output]\nfields = [\"displacement\", \"contact\"]\n",
            toml_path(mesh),
            num(2.0 * u.f),
            m(-1.0),
            m(0.01),
            m(0.016),
            m(0.01),
        )
    };
    let mesh = repo("cases/hertz/meshes/hertz_L3.msh");
    let units = Units {
        s: 1024.0,
        f: 1.0 / 1_048_576.0,
    };
    same_in("Cattaneo", &mesh, text, units, 2);
}

/// Stresses and forces times 2^36 (lengths alike): u repeats bit for bit, with the same states
/// and steps, on a 3D block pushed by a force-controlled sphere with Coulomb friction — the
/// condensed path's dual form then has the obstacle's approach α among its unknowns. Before,
/// its rows mixed the units of C and of G, their equilibration took the largest entry of
/// either as the unit system decided, and u differed (4.7e-15 of max |u| at 2^26, 1.4e-10 and
/// one dense step fewer at 2^26 on the finer block of an earlier sweep); now the unknown is
/// c α. (A power of four: MUMPS' scaling of the matrix takes square roots.)
#[test]
fn force_controlled_coulomb_times_a_power_of_four_repeats_bit_for_bit() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mut runs = Vec::new();
    for (tag, f) in [("own", 1.0), ("scaled", 2f64.powi(36))] {
        let case = write_case(
            &tmp.path().join(format!("{tag}.toml")),
            &format!(
                "[mesh]\nfile = {}\n[material]\nyoung = {}\npoisson = 0.3\n\
                 [[dirichlet]]\ngroup = \"bottom\"\nvalue = [0.0, 0.0, 0.0]\n\
                 [contact]\ngroup = \"top\"\n\
                 obstacle = {{ type = \"sphere\", center = [0.2, -0.1, 1.1], radius = 0.5 }}\n\
                 force = [{}, 0.0, {}]\nfriction = {{ law = \"coulomb\", mu = 0.5 }}\n\
                 [output]\nfields = [\"displacement\", \"contact\"]\n",
                toml_path(&repo("cases/blocks/block3d.msh")),
                num(2.0 * f),
                num(0.002 * f),
                num(-0.05 * f),
            ),
        );
        let out = tmp.path().join(format!("out_{tag}"));
        run_solver(1, &case, &[], &out).expect_code(0, tag);
        runs.push(steps(&out));
    }
    let (a, b) = (&runs[0][0], &runs[1][0]);
    assert_eq!(a.newton, b.newton, "Newton steps and factorisations");
    assert_eq!(
        (&a.states, &a.slip),
        (&b.states, &b.slip),
        "contact and slip states"
    );
    assert!(
        a.u.iter().flatten().any(|x| *x != 0.0),
        "u = 0: nothing compared"
    );
    assert!(a.u == b.u, "u differs between the units");
}

/// Magnitudes whose squares leave double precision's range are refused before the solve
/// (exit code 2, one line naming the key; docs/case-file.md, "Units"): Young's moduli of 1e308
/// (MUMPS failed, exit 1) and 1e-300 (the run ended with exit 0 and infinite strains), and a
/// mesh in units where its coordinates are 1e-200 (refused as a degenerate cell); inside the
/// range, the same block at E = 1e140 with its loads and c scaled alike solves.
#[test]
fn magnitudes_beyond_double_precision_are_refused() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let block = |mesh: &Path, young: f64, load: f64| {
        format!(
            "[mesh]\nfile = {}\n[material]\nyoung = {}\npoisson = 0.3\nmodel = \"plane_strain\"\n\
             [[neumann]]\ngroup = \"top\"\npressure = {}\n[[dirichlet]]\ngroup = \"bottom\"\n\
             value = [0.0, 0.0]\n",
            toml_path(mesh),
            num(young),
            num(load),
        )
    };
    let own = repo("cases/blocks/block2d.msh");
    let refused = |text: &str, key: &str| {
        let case = write_case(&tmp.path().join("refused.toml"), text);
        let run = run_solver(2, &case, &[], &tmp.path().join("out_refused"));
        let line = run.the_error_line(key).to_string();
        println!("{line}");
        assert!(line.contains(&format!("key '{key}'")), "{line}");
        assert!(
            line.contains("outside the range this solver can represent"),
            "{line}"
        );
        assert!(!tmp.path().join("out_refused").exists(), "{line}");
    };
    refused(&block(&own, 1e308, 0.1), "material.young");
    refused(&block(&own, 1e-300, 0.1), "material.young");
    let tiny = scaled_mesh(&own, 1e-200, &tmp.path().join("tiny.msh"));
    refused(&block(&tiny, 2.0, 0.1), "mesh.file");
    // a load in range whose displacements are not: 1e-10 against E = 1e140 moves the block
    // by about 1e-150
    refused(&block(&own, 1e140, 1e-10), "neumann[0].pressure");
    let case = write_case(&tmp.path().join("inside.toml"), &block(&own, 2e140, 1e139));
    run_solver(2, &case, &[], &tmp.path().join("out_inside")).expect_code(0, "E = 2e140");
}
