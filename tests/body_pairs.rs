//! Contact between two deformable bodies (dual mortar, `obstacle = { type = "body" }`;
//! docs/bodies.md): the contact patch test on two blocks meshed independently (interface
//! sizes about 3 : 1), in 2D and 3D, with either side as slave, on 1, 2 and 3 ranks, the upper
//! block pushed down by a prescribed displacement or held by contact alone under a pressure;
//! three blocks stacked, the upper two held by contact alone; and the input errors of a body
//! pair.
//!
//! The patch test: two materials, the lower block on a roller support (u_n = 0 at its bottom),
//! both blocks on symmetry planes, the upper block's top pushed down by δ (or pressed by p). The
//! exact solution is the uniaxial stress σ_nn = −p in both blocks, p = δ / (H_1/E'_1 +
//! H_2/E'_2), a linear field that P1 elements reproduce; the dual mortar rows transmit it
//! exactly on non-matching meshes: every slave node active with pressure p, u the linear field.
//! Pressed, the upper block's rigid motion along the load is free of Dirichlet data: the
//! contact holds it (its rigid modes, signorini/rigid.rs).

mod common;

use common::*;
use std::path::{Path, PathBuf};

/// (E, ν) of the lower and the upper block (and of the third block of the tower).
const LOWER: (f64, f64) = (1.0, 0.45);
const UPPER: (f64, f64) = (3.0, 0.1);
const THIRD: (f64, f64) = (2.0, 0.3);
const DELTA: f64 = 0.01;

/// How the upper block is loaded: its top displaced by −δ, pressed by the exact p, or pushed
/// down by δ by a rigid plane moving in three load steps (the last two: held by contact alone
/// along the load).
#[derive(Clone, Copy, PartialEq)]
enum Load {
    Displaced,
    Pressed,
    MovingPlane,
}

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

/// The case of the patch test: `slave` against `master`, displaced.
fn stack_case(dir: &Path, mesh: &Path, dim: usize, pair: (&str, &str)) -> PathBuf {
    loaded_stack_case(dir, mesh, dim, pair, Load::Displaced)
}

/// The case of the patch test: `slave` against `master`, loaded by `load`.
fn loaded_stack_case(
    dir: &Path,
    mesh: &Path,
    dim: usize,
    (slave, master): (&str, &str),
    load: Load,
) -> PathBuf {
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
    let (p, _) = exact(dim, &[LOWER, UPPER]);
    let supports = match load {
        Load::Displaced => supports.replace("DELTA", &format!("{DELTA:?}")),
        Load::Pressed => pressed(supports, p),
        Load::MovingPlane => supports
            .split_once("[[dirichlet]]\ngroup = \"top\"")
            .expect("the top's Dirichlet data last")
            .0
            .to_string(),
    };
    // the rigid plane on the top (z or y = 2) moving down by δ
    let plane = match load {
        Load::MovingPlane => {
            let (point, normal, motion) = match dim {
                2 => ("[0.0, 2.0]", "[0.0, -1.0]", format!("[0.0, {:?}]", -DELTA)),
                _ => (
                    "[0.0, 0.0, 2.0]",
                    "[0.0, 0.0, -1.0]",
                    format!("[0.0, 0.0, {:?}]", -DELTA),
                ),
            };
            format!(
                "[[contact]]\ngroup = \"top\"\nobstacle = {{ type = \"plane\", point = {point}, \
                 normal = {normal} }}\nmotion = {motion}\nfriction = \"none\"\n[load]\nsteps = 3\n"
            )
        }
        _ => String::new(),
    };
    let contact = if plane.is_empty() {
        "[contact]"
    } else {
        "[[contact]]"
    };
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
{contact}
group = "{slave}"
obstacle = {{ type = "body", group = "{master}" }}
friction = "none"
{plane}[output]
dir = "out"
fields = ["displacement", "contact"]
"#,
        LOWER.0,
        LOWER.1,
        UPPER.0,
        UPPER.1,
        mesh = toml_path(mesh),
    );
    let name = match load {
        Load::Displaced => format!("stack{dim}d_{slave}.toml"),
        Load::Pressed => format!("stack{dim}d_{slave}_pressed.toml"),
        Load::MovingPlane => format!("stack{dim}d_{slave}_plane.toml"),
    };
    write_case(&dir.join(name), &text)
}

/// The supports with the top's prescribed displacement replaced by the pressure p.
fn pressed(supports: &str, p: f64) -> String {
    let (held, top) = supports
        .split_once("[[dirichlet]]\ngroup = \"top\"")
        .expect("the top's Dirichlet data last");
    assert!(top.contains("-DELTA"), "{top}");
    format!("{held}[[neumann]]\ngroup = \"top\"\npressure = {p:?}\n")
}

/// The exact pressure and displacement at x of a stack of blocks of height 1 each, of the
/// materials `layers` from the bottom up, whose top is pushed down by δ; x in the block
/// `layer`.
fn exact(dim: usize, layers: &[(f64, f64)]) -> (f64, impl Fn(&[f64], usize) -> Vec<f64>) {
    // the modulus along the load and the lateral strain per unit stress: plane strain
    // E' = E / (1 − ν²), ν (1 + ν) / E; 3D E, ν / E
    let moduli: Vec<(f64, f64)> = (layers.iter())
        .map(|&(e, nu)| {
            if dim == 2 {
                (e / (1.0 - nu * nu), nu * (1.0 + nu) / e)
            } else {
                (e, nu / e)
            }
        })
        .collect();
    let p = DELTA / moduli.iter().map(|m| 1.0 / m.0).sum::<f64>();
    let u = move |x: &[f64], layer: usize| {
        let (e, lat) = moduli[layer];
        let mut u: Vec<f64> = (0..dim - 1).map(|d| lat * p * x[d]).collect();
        let below: f64 = moduli[..layer].iter().map(|m| p / m.0).sum();
        u.push(-below - p / e * (x[dim - 1] - layer as f64));
        u
    };
    (p, u)
}

/// Every slave node active with the pressure p to 1e-8, u the exact field to 1e-10 of its size.
fn check_patch(s: &Solved, dim: usize, what: &str) {
    check_stack(s, dim, &[LOWER, UPPER], what);
}

/// [`check_patch`] for the stack of blocks of the materials `layers`.
fn check_stack(s: &Solved, dim: usize, layers: &[(f64, f64)], what: &str) {
    check_stack_u(s, dim, layers, &s.displacement(), what);
}

/// [`check_stack`] with the displacement `u` (by node id; a load step's).
fn check_stack_u(
    s: &Solved,
    dim: usize,
    layers: &[(f64, f64)],
    u: &std::collections::BTreeMap<u64, Vec<f64>>,
    what: &str,
) {
    s.assert_converged(what);
    let (p, u_exact) = exact(dim, layers);
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
    let x = s.node_layers();
    let scale = DELTA;
    let mut worst = 0.0f64;
    for (id, (xi, layer)) in &x {
        let ue = u_exact(xi, *layer);
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

#[test]
fn a_pressed_block_held_by_contact_alone_passes_the_patch_test_in_2d_and_3d() {
    let tmp = tempfile::tempdir().expect("tempdir");
    for (dim, hl, hu, runs) in [
        (2, 1.0 / 9.0, 1.0 / 3.0, [(true, 1), (true, 3), (false, 2)]),
        (3, 0.15, 0.45, [(true, 2), (false, 1), (false, 3)]),
    ] {
        let dir = tmp.path().join(format!("{dim}d"));
        std::fs::create_dir_all(&dir).expect("dir");
        let mesh = stack_mesh(&dir, dim, hl, hu);
        for (upper_slave, np) in runs {
            let pair = match upper_slave {
                true => ("upper_bottom", "lower_top"),
                false => ("lower_top", "upper_bottom"),
            };
            let case = loaded_stack_case(&dir, &mesh, dim, pair, Load::Pressed);
            let what = format!("{} on {np} rank(s)", case.display());
            let s = solve(np, &case, &[]);
            assert_eq!(s.summary["bodies"]["not_held"], 1, "{what}");
            check_patch(&s, dim, &what);
        }
    }
}

#[test]
fn a_block_between_a_moving_plane_and_another_body_passes_the_patch_test_in_load_steps() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = stack_mesh(tmp.path(), 2, 1.0 / 9.0, 1.0 / 3.0);
    for (pair, np) in [
        (("upper_bottom", "lower_top"), 1),
        (("lower_top", "upper_bottom"), 2),
    ] {
        let case = loaded_stack_case(tmp.path(), &mesh, 2, pair, Load::MovingPlane);
        let what = format!("{} on {np} rank(s)", case.display());
        let s = solve(np, &case, &[]);
        assert_eq!(s.summary["bodies"]["not_held"], 1, "{what}");
        // the last step: the plane moved by δ, the body pair and the plane pair both at p
        let u = step_displacement(&s.dir, 3);
        check_stack_u(&s, 2, &[LOWER, UPPER], &u, &what);
    }
}

/// Three blocks of cases/blocks/tower2d.geo (sizes 1/7, 1/3, 1/5) of three materials, the
/// lowest on a roller support, all on the symmetry line x = 0, the top pressed by p: the
/// middle block against the lowest and the upper one, held by contact alone.
fn tower_case(dir: &Path, middle_slave: bool) -> PathBuf {
    let mesh = dir.join("tower2d.msh");
    gmsh_file(&repo("cases/blocks/tower2d.geo"), 2, &[], &mesh);
    let (p, _) = exact(2, &[LOWER, UPPER, THIRD]);
    let pairs = match middle_slave {
        true => [
            ("middle_bottom", "lower_top"),
            ("middle_top", "upper_bottom"),
        ],
        false => [
            ("lower_top", "middle_bottom"),
            ("upper_bottom", "middle_top"),
        ],
    };
    let mut text = format!("[mesh]\nfile = {}\n", toml_path(&mesh));
    for (g, (e, nu)) in ["lower", "middle", "upper"]
        .iter()
        .zip([LOWER, UPPER, THIRD])
    {
        text += &format!(
            "[[material]]\ngroup = \"{g}\"\nyoung = {e:?}\npoisson = {nu:?}\n\
             model = \"plane_strain\"\n"
        );
    }
    text += &format!(
        "[[dirichlet]]\ngroup = \"bottom\"\nvalue = [\"free\", 0.0]\n\
         [[dirichlet]]\ngroup = \"left\"\nvalue = [0.0, \"free\"]\n\
         [[neumann]]\ngroup = \"top\"\npressure = {p:?}\n"
    );
    for (slave, master) in pairs {
        text += &format!(
            "[[contact]]\ngroup = \"{slave}\"\n\
             obstacle = {{ type = \"body\", group = \"{master}\" }}\nfriction = \"none\"\n"
        );
    }
    text += "[output]\ndir = \"out\"\nfields = [\"displacement\", \"contact\", \"body\"]\n";
    write_case(&dir.join(format!("tower_{middle_slave}.toml")), &text)
}

#[test]
fn three_stacked_blocks_held_by_contact_alone_carry_the_load() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (p, _) = exact(2, &[LOWER, UPPER, THIRD]);
    for (middle_slave, np) in [(true, 1), (true, 3), (false, 2)] {
        let case = tower_case(tmp.path(), middle_slave);
        let what = format!("{} on {np} rank(s)", case.display());
        let s = solve(np, &case, &[]);
        assert_eq!(s.summary["bodies"]["not_held"], 2, "{what}");
        check_stack(&s, 2, &[LOWER, UPPER, THIRD], &what);
        // the cell field `body`: the blocks from the bottom up (their first node tags)
        let v = python_json(
            r#"
import sys, json, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
x = f["mesh/geometry"][:]
cells = f["mesh/topology"][:]
layer = np.floor(x[cells, 1].mean(axis=1)).astype(int)
print("RESULT " + json.dumps({"wrong": int((f["cell/body"][:] != layer + 1).sum()), "n": len(cells)}))
"#,
            &[&s.dir.join("solution.h5")],
        );
        assert_eq!(v["wrong"], 0, "{what}: cells of a wrong body in {v}");
        // each interface carries the load p (unit width): the pairs' total forces
        let pairs = s.summary["contact"]["pairs"].as_array().expect("pairs");
        for (j, pair) in pairs.iter().enumerate() {
            let f = floats(&pair["total_force"]);
            assert!(
                (f[1].abs() - p).abs() < 1e-10 * p && f[0].abs() < 1e-10 * p,
                "{what}: pair {j} carries {f:?}, the load {p:e}"
            );
        }
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
        "physical group \"nowhere\" is not in the mesh",
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
    // facing, but every slave node held along the normal by Dirichlet data: that is the reason
    let held = std::fs::read_to_string(&ok).expect("case")
        + "\n[[dirichlet]]\ngroup = \"upper_bottom\"\nvalue = [0.0, 0.0]\n";
    let held = write_case(&d.join("held.toml"), &held);
    refused(
        3,
        &held,
        "contact.group",
        "held along the contact normal by Dirichlet data",
    );
}

#[test]
fn the_3d_patch_tests_hold_on_the_iterative_preset() {
    // the body pair's preconditioner in u (step_system/mortar_pc.rs): pushed down and held
    // by contact alone, either side as slave
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = stack_mesh(tmp.path(), 3, 0.15, 0.45);
    let iterative = ["solver.preset=iterative", "solver.rtol=1e-12"];
    for (load, pair, np) in [
        (Load::Displaced, ("upper_bottom", "lower_top"), 1),
        (Load::Displaced, ("lower_top", "upper_bottom"), 3),
        (Load::Pressed, ("upper_bottom", "lower_top"), 2),
        (Load::Pressed, ("lower_top", "upper_bottom"), 3),
    ] {
        let case = loaded_stack_case(tmp.path(), &mesh, 3, pair, load);
        let what = format!("{} on {np} rank(s), iterative", case.display());
        let s = solve(np, &case, &iterative);
        assert_eq!(s.summary["linear_solver"]["pc_type"], "shell", "{what}");
        check_patch(&s, 3, &what);
    }
}

#[test]
fn the_step_operator_gives_the_assembled_step_matrix_answer() {
    // body pairs on the iterative preset solve with S = L A P + D as an operator
    // (step_system/matrix_free.rs); the test-only limit MATRIX_FREE = 0 writes S into a matrix
    // as every other path does: the same states and u, with Coulomb's row mix and slip
    // springs and with Tresca's, on 2 and 3 ranks; in two load steps, whose second holds the
    // sticking nodes at the first's u_τ (held rows with known values)
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = stack_mesh(tmp.path(), 3, 0.15, 0.45);
    let case = stack_case(tmp.path(), &mesh, 3, ("upper_bottom", "lower_top"));
    let limit = std::time::Duration::from_secs(300);
    for (friction, np) in [
        ("contact.friction={law=\"coulomb\", mu=0.3}", 2),
        ("contact.friction={law=\"tresca\", threshold=2e-3}", 3),
    ] {
        let sets = [
            "solver.preset=iterative",
            "solver.rtol=1e-12",
            "load.steps=2",
            friction,
        ];
        let what = format!("{friction} on {np} ranks");
        let free = solve_env(np, &case, &sets, &[], limit);
        let env = [("SIGNORINI_TEST_LIMIT_MATRIX_FREE", "0")];
        let assembled = solve_env(np, &case, &sets, &env, limit);
        free.assert_converged(&what);
        assert_eq!(free.summary["linear_solver"]["pc_type"], "shell", "{what}");
        let slip = free.slip_node_ids();
        assert!(
            !slip.is_empty(),
            "{what}: no node slips, the slip rows untested"
        );
        assert_eq!(slip, assembled.slip_node_ids(), "{what}: slip nodes");
        same_steps(&free, &assembled, 2, 1e-9, np);
    }
}

#[test]
fn a_slave_side_far_stiffer_than_its_master_takes_the_direct_preset() {
    // the iterative preset's preconditioner corrects held slave nodes on the slave side: a
    // slave side STIFF_SLAVE_RATIO × as stiff as its master or more goes to the direct preset
    // (solver.rs choose_preset); the other side as slave keeps the size rule
    let tmp = tempfile::tempdir().expect("tempdir");
    let mesh = stack_mesh(tmp.path(), 3, 0.15, 0.45);
    let stiff_upper = "material.1.young=1e4";
    for (pair, used, why) in [
        (("upper_bottom", "lower_top"), "direct", "slave side"),
        (("lower_top", "upper_bottom"), "direct", "unknowns <"),
    ] {
        let case = stack_case(tmp.path(), &mesh, 3, pair);
        let s = solve(2, &case, &[stiff_upper]);
        s.assert_converged(pair.0);
        let reason = s.summary["preset"]["reason"].as_str().expect("a reason");
        assert_eq!(s.summary["preset"]["used"], used, "{pair:?}: {reason}");
        assert!(reason.contains(why), "{pair:?}: {reason}");
    }
}

/// The two disks of tests/meshes/disk_stack2d.geo on the block under their weight (a body
/// force), disk 1 against the block and disk 2 against disk 1: two bodies held by contact
/// alone (frictionless: their sideways motion and rotation free, with no load in them).
/// `shared`: the geo's option that makes d1_top share d1_bottom's end nodes; `friction` both
/// pairs' friction value.
fn disk_stack_case(dir: &Path, shared: bool, friction: &str) -> PathBuf {
    let mesh = dir.join(format!("disk_stack2d_{shared}.msh"));
    let flag = if shared { "1" } else { "0" };
    gmsh_file(
        &mesh_dir().join("disk_stack2d.geo"),
        2,
        &["-setnumber", "shared", flag],
        &mesh,
    );
    let mut text = format!("[mesh]\nfile = {}\n", toml_path(&mesh));
    for (g, (e, nu)) in
        ["block", "disk1", "disk2"]
            .iter()
            .zip([(10.0, 0.3), (1.0, 0.3), (2.0, 0.25)])
    {
        text += &format!(
            "[[material]]\ngroup = \"{g}\"\nyoung = {e:?}\npoisson = {nu:?}\n\
             model = \"plane_strain\"\n"
        );
    }
    text += "[body_force]\nvalue = [0.0, -0.01]\n\
             [[dirichlet]]\ngroup = \"block_bottom\"\nvalue = [0.0, 0.0]\n";
    for (slave, master) in [("d1_bottom", "block_top"), ("d2_bottom", "d1_top")] {
        text += &format!(
            "[[contact]]\ngroup = \"{slave}\"\n\
             obstacle = {{ type = \"body\", group = \"{master}\" }}\nfriction = {friction}\n"
        );
    }
    text += "[output]\nfields = [\"displacement\", \"contact\"]\n";
    let name = format!("disk_stack_{shared}_{}.toml", friction.len());
    write_case(&dir.join(name), &text)
}

#[test]
fn two_disks_stacked_on_a_block_carry_their_weight_and_a_shared_node_is_refused_on_every_rank_count(
) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let case = disk_stack_case(tmp.path(), false, "\"none\"");
    let mut first: Option<(Vec<u64>, Vec<Vec<f64>>)> = None;
    for np in [1, 2, 3] {
        let what = format!("the disk stack on {np} rank(s)");
        let s = solve(np, &case, &[]);
        s.assert_converged(&what);
        assert_eq!(s.summary["bodies"]["not_held"], 2, "{what}");
        let pairs = s.summary["contact"]["pairs"].as_array().expect("pairs");
        let forces: Vec<Vec<f64>> = pairs.iter().map(|p| floats(&p["total_force"])).collect();
        // the block carries both disks, disk 1 carries disk 2: equal disks of equal weight
        let (lower, upper) = (forces[0][1], forces[1][1]);
        assert!(upper > 0.0, "{what}: disk 2 rests on disk 1 with {upper:e}");
        assert!(
            (lower / upper - 2.0).abs() < 1e-2,
            "{what}: the block carries {lower:e}, disk 1 carries {upper:e}"
        );
        for f in &forces {
            assert!(f[0].abs() < 1e-9 * lower, "{what}: a sideways force {f:?}");
        }
        let active = s.active_node_ids();
        match &first {
            None => first = Some((active, forces)),
            Some((a, f)) => {
                assert_eq!(&active, a, "{what}: the active nodes of 1 rank");
                for (x, y) in forces.iter().zip(f) {
                    assert!(
                        (x[1] - y[1]).abs() < 1e-10 * lower,
                        "{what}: {x:?} against {y:?} on 1 rank"
                    );
                }
            }
        }
    }
    // d1_top sharing d1_bottom's end nodes: the same node named on every rank count (the
    // check looked at the master facets a rank received, which come within each pair's
    // reach only: it passed on some rank counts)
    let shared = disk_stack_case(tmp.path(), true, "\"none\"");
    let mut said: Option<String> = None;
    for np in [1, 2, 3] {
        let out = tmp.path().join(format!("refused{np}"));
        let run = run_solver(np, &shared, &[], &out);
        run.expect_code(2, &format!("the shared node on {np} rank(s)"));
        let text = run.output();
        let line = (text.lines())
            .find(|l| l.contains("one side of body contact only"))
            .unwrap_or_else(|| panic!("{np} rank(s): no overlap message:\n{text}"))
            .to_string();
        assert!(
            line.contains("contact[1].obstacle.group"),
            "{np} rank(s): {line}"
        );
        assert!(!out.join("summary.json").exists(), "no output");
        match &said {
            None => said = Some(line),
            Some(l) => assert_eq!(&line, l, "{np} rank(s) against 1 rank"),
        }
    }
}

/// The states (active, tangential) of every slave node by node id.
fn node_states(s: &Solved) -> Vec<(u64, bool, String)> {
    let mut v: Vec<(u64, bool, String)> = (s.contact_rows().iter())
        .map(|r| (r.node_id(), r.active(), r.tangential().to_string()))
        .collect();
    v.sort();
    v
}

#[test]
fn two_stacked_disks_with_friction_are_solved_on_one_factorisation() {
    // Coulomb's and Tresca's start on the contact unknowns is a frictionless estimate whose
    // pins carry the load that only friction holds; they carried the upper disk's weight as
    // well (disk 1 touching the block sufficed), so that the upper disk touched nothing and
    // the dense iteration held its motion by no row: 100 steps, then the plain path
    let tmp = tempfile::tempdir().expect("tempdir");
    for (law, ranks) in [
        ("{ law = \"coulomb\", mu = 0.3 }", &[1, 2, 3][..]),
        ("{ law = \"tresca\", threshold = 1e-3 }", &[2][..]),
    ] {
        let case = disk_stack_case(tmp.path(), false, law);
        let plain = solve(2, &case, &["solver.path=\"plain\""]);
        plain.assert_converged(&format!("{law}, the plain path"));
        let scale = plain.total_force()[1];
        for &np in ranks {
            let what = format!("{law} on {np} rank(s)");
            let s = solve(np, &case, &[]);
            s.assert_converged(&what);
            let condensed = &s.summary["newton"]["condensed"]["coulomb"];
            assert_eq!(
                condensed["outcome"],
                "condensed",
                "{what}: {condensed}\n{}",
                s.run.output()
            );
            assert_eq!(s.summary["newton"]["factorisations"], 1, "{what}");
            // no nested start on coarse subsets with two floating bodies (they diverged)
            // (summary.json leaves the key out where there is none)
            let coarse = &condensed["coarse_levels"];
            assert!(
                coarse.as_array().is_none_or(|a| a.is_empty()),
                "{what}: coarse levels {coarse}"
            );
            assert_eq!(
                node_states(&s),
                node_states(&plain),
                "{what}: the plain path's states"
            );
            let (a, b) = (s.contact_rows_by_id(), plain.contact_rows_by_id());
            for (id, r) in &a {
                for key in ["lambda_n", "lambda_t1"] {
                    let d = (r.f(key) - b[id].f(key)).abs();
                    assert!(d < 1e-9 * scale, "{what}: node {id} {key} off by {d:e}");
                }
            }
        }
    }
}

#[test]
fn a_sideways_load_on_frictionless_stacked_disks_names_its_likely_cause() {
    // frictionless, a sideways body force has no equilibrium on the block's flat top: every
    // balance step brings another node into contact and the sets recur; the cycling error
    // says what that likely means and which keys to look at
    let tmp = tempfile::tempdir().expect("tempdir");
    let case = disk_stack_case(tmp.path(), false, "\"none\"");
    let out = tmp.path().join("sideways");
    let run = run_solver(2, &case, &["body_force.value=[0.002, -0.01]"], &out);
    run.expect_code(1, "a sideways load on frictionless stacked disks");
    let text = run.output();
    for words in [
        "Newton cycling",
        "may have no equilibrium",
        "'contact[1].obstacle'",
    ] {
        assert!(text.contains(words), "the message says {words:?}:\n{text}");
    }
    assert!(!out.join("summary.json").exists(), "no output");
}
