//! PETSc SNES VI (src/snesvi.rs) against Algorithm 1 (src/newton.rs) on the same assembled
//! system: the displacements agree to 1e-8 of max |u| on 1 and 2 ranks, on a block pressed
//! onto a plane (2D and 3D, rigid modes fixed only by contact and pins), a clamped block
//! indented by a circle (non-axis normals, initial penetration) and a box under a sphere (3D,
//! non-axis normals); with vinewtonrsls (default) and vinewtonssls.
//!
//! The library is called directly: the test re-runs its own executable under mpirun, with
//! SNESVI_CHILD set, on the test `child`, which initialises MPI and PETSc as src/main.rs does,
//! solves every case in SNESVI_CASES both ways and prints one "RESULT {json}" line per case.

mod common;

use common::*;
use mpi::collective::SystemOperation;
use mpi::traits::*;
use signorini_mpi::assembly;
use signorini_mpi::case::{Case, Preset};
use signorini_mpi::contact_set;
use signorini_mpi::newton;
use signorini_mpi::partition;
use signorini_mpi::petsc::Petsc;
use signorini_mpi::rigid::RigidModes;
use signorini_mpi::run::{self, Ctx};
use signorini_mpi::snesvi::{solve_snesvi, SnesContactNode};
use signorini_mpi::solver;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const CHILD: &str = "SNESVI_CHILD";

fn case_path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Global dofs that pin the rigid modes fixed neither by Dirichlet data nor by the whole
/// contact boundary (every contact normal counted): the same list on every rank.
fn pins_for_snes(
    world: &mpi::topology::SimpleCommunicator,
    mesh: &signorini_mpi::mesh::Mesh,
    layout: &partition::Layout,
    fixed: &[f64],
    cs: &contact_set::ContactSet,
) -> Vec<usize> {
    let dim = mesh.dim;
    let modes = RigidModes::new(mesh);
    let mut g = vec![0.0; 36];
    // Dirichlet dofs: every rank knows all of them (the same sum everywhere).
    for v in 0..mesh.n_nodes() {
        for k in 0..dim {
            if !fixed[v * dim + k].is_nan() {
                modes.add_outer(&mut g, &modes.dof_row(&mesh.coords[v], k));
            }
        }
    }
    let mut gc = vec![0.0; 36];
    for k in &cs.nodes {
        modes.add_outer(&mut gc, &modes.normal_row(&k.x, &k.frame.n));
    }
    let mut gc_all = vec![0.0; 36];
    world.all_reduce_into(&gc[..], &mut gc_all[..], SystemOperation::sum());
    for (a, b) in g.iter_mut().zip(&gc_all) {
        *a += b;
    }
    let q = modes.free_modes(&g);
    let candidate =
        |v: usize| !cs.on_contact_boundary[v] && (0..dim).all(|k| fixed[v * dim + k].is_nan());
    let pins = modes.pins(mesh, &q, candidate);
    assert_eq!(pins.len(), q.ncols(), "every free mode gets a pin");
    pins.iter()
        .map(|&(v, k)| layout.node_global[v] * dim + k)
        .collect()
}

/// Solves one case with Algorithm 1 and with SNES VI; returns the comparison (rank 0's copy
/// is printed; the numbers are global).
fn compare(ctx: &Ctx, case_file: &Path, overrides: &[String]) -> serde_json::Value {
    let world = ctx.world;
    let comm = ctx.petsc.comm();
    let case = Case::load(case_file, overrides, None).expect("case loads");
    let (mesh, material) = run::read_input(&case).expect("input");
    let dim = mesh.dim;
    let layout = partition::partition(world, comm, &mesh, "ptscotch").expect("partition");
    let problem = run::problem_from_case(&case, &mesh, material);
    let mut sys = assembly::assemble(comm, &layout, &problem).expect("assembly");
    let cc = case.contact.as_ref().expect("a contact case");
    let cs = contact_set::build(world, &mesh, &layout, cc, &problem.fixed, &case.file)
        .expect("contact set");
    solver::configure(Preset::Direct, case.solver.rtol, true, "").expect("options");

    let t = Instant::now();
    let nr = newton::semismooth_newton(
        ctx,
        &mesh,
        &layout,
        &mut sys,
        &problem.fixed,
        &cs,
        &case.newton,
        cc.rigid_modes,
        None,
        false,
        material.young,
    )
    .expect("Algorithm 1");
    let newton_seconds = t.elapsed().as_secs_f64();
    assert!(
        nr.converged,
        "{}: Algorithm 1 did not converge",
        case_file.display()
    );

    let t = Instant::now();
    let pins = pins_for_snes(world, &mesh, &layout, &problem.fixed, &cs);
    let nodes: Vec<SnesContactNode> = cs
        .nodes
        .iter()
        .map(|k| SnesContactNode {
            row: k.row,
            normal: k.frame.n,
            gap: k.gap,
        })
        .collect();
    let sr = solve_snesvi(comm, dim, &sys.a, &sys.b, &nodes, &pins).expect("SNES VI");
    let snes_seconds = t.elapsed().as_secs_f64();

    let un = nr.u.to_local_vec().unwrap();
    let us = sr.u.to_local_vec().unwrap();
    let local_max = un.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let local_diff = un
        .iter()
        .zip(&us)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    // Constraint check of the SNES answer in the original frame: n·u_k + g_k ≥ 0.
    let local_pen = cs.nodes.iter().fold(0.0f64, |m, k| {
        let lr = k.local_row;
        let un_k: f64 = (0..dim).map(|j| k.frame.n[j] * us[lr + j]).sum();
        m.max(-(un_k + k.gap))
    });
    let mut out = [0.0f64; 3];
    world.all_reduce_into(
        &[local_max, local_diff, local_pen][..],
        &mut out[..],
        SystemOperation::max(),
    );
    let active: usize = nr.nodes.iter().filter(|n| n.active).count();
    let mut active_all = 0u64;
    world.all_reduce_into(&(active as u64), &mut active_all, SystemOperation::sum());
    serde_json::json!({
        "case": case_file.display().to_string(),
        "mesh": case.mesh.file.display().to_string(),
        "ranks": ctx.size,
        "dofs": mesh.n_nodes() * dim,
        "contact_nodes": cs.n_global,
        "active": active_all,
        "pins": pins.len(),
        "u_max": out[0],
        "max_abs_diff": out[1],
        "rel_diff": out[1] / out[0],
        "snes_max_penetration": out[2],
        "newton_steps": nr.steps,
        "newton_seconds": newton_seconds,
        "snes_type": sr.snes_type,
        "snes_steps": sr.steps,
        "snes_linear_iterations": sr.linear_iterations,
        "snes_function_evals": sr.function_evals,
        "snes_converged": sr.converged,
        "snes_reason": sr.reason,
        "snes_setup_seconds": sr.setup_seconds,
        "snes_solve_seconds": sr.solve_seconds,
        "snes_seconds_with_pins": snes_seconds,
    })
}

/// The MPI side: runs only under mpirun from `run_child` (SNESVI_CHILD set).
#[test]
fn child() {
    if std::env::var_os(CHILD).is_none() {
        return;
    }
    let cases = std::env::var("SNESVI_CASES").expect("SNESVI_CASES");
    let petsc_args: Vec<String> = std::env::var("SNESVI_PETSC")
        .unwrap_or_default()
        .split_whitespace()
        .map(String::from)
        .collect();
    let universe = mpi::initialize().expect("MPI");
    let world = universe.world();
    let petsc = Petsc::init(&petsc_args).expect("PETSc");
    {
        let ctx = Ctx::new(&world, &petsc);
        // Case-key overrides (--set), ';'-separated.
        let overrides: Vec<String> = std::env::var("SNESVI_SET")
            .unwrap_or_default()
            .split(';')
            .filter(|s| !s.is_empty())
            .map(String::from)
            .collect();
        for c in cases.split(',') {
            let res = compare(&ctx, &case_path(c), &overrides);
            if ctx.rank == 0 {
                println!("RESULT {res}");
            }
        }
    }
    drop(petsc);
}

/// Runs `child` on `np` ranks for the given cases; returns one result per case.
fn run_child(np: usize, cases: &[&str], petsc: &str, limit: u64) -> Vec<serde_json::Value> {
    let exe = std::env::current_exe().expect("test executable");
    let args: Vec<String> = ["child", "--exact", "--nocapture", "--test-threads=1"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let mut cmd = mpirun(np, &exe, &args);
    cmd.env(CHILD, "1")
        .env("SNESVI_CASES", cases.join(","))
        .env("SNESVI_PETSC", petsc);
    let run = run_with_timeout(cmd, Duration::from_secs(limit));
    run.expect_code(0, &format!("SNES VI vs Algorithm 1 on {np} rank(s)"));
    let res = json_lines(&run.stdout, "RESULT ");
    assert_eq!(res.len(), cases.len(), "{}", run.output());
    res
}

fn check_agreement(res: &[serde_json::Value]) {
    for r in res {
        println!("{r}");
        let f = |k: &str| r[k].as_f64().unwrap_or(f64::NAN);
        assert!(r["snes_converged"].as_bool() == Some(true), "SNES VI: {r}");
        assert!(f("u_max") > 0.0, "no displacement: {r}");
        assert!(
            f("rel_diff") <= 1e-8,
            "SNES VI and Algorithm 1 differ by {:e} of max |u|: {r}",
            f("rel_diff")
        );
        assert!(
            f("snes_max_penetration") <= 1e-10 * f("u_max"),
            "SNES VI answer penetrates: {r}"
        );
    }
}

const CASES: &[&str] = &[
    "cases/blocks/block2d.toml",
    "cases/blocks/indent2d.toml",
    "cases/blocks/block3d.toml",
    "tests/cases/sphere3d.toml",
];

#[test]
fn snesvi_matches_algorithm_1_one_rank() {
    check_agreement(&run_child(1, CASES, "", 300));
}

#[test]
fn snesvi_matches_algorithm_1_two_ranks() {
    check_agreement(&run_child(2, CASES, "", 300));
}

/// vinewtonssls through the options database (the Cholesky preset becomes LU inside SNES:
/// the semismooth Jacobian is not symmetric).
#[test]
fn snesvi_ssls_matches_algorithm_1() {
    let res = run_child(2, CASES, "-snes_type vinewtonssls", 300);
    for r in &res {
        assert_eq!(r["snes_type"], "vinewtonssls", "{r}");
    }
    check_agreement(&res);
}

/// The Hertz measurement of the report (refined level 4): `cargo test --release --test snesvi
/// -- --ignored --nocapture`. SNESVI_HERTZ_NP sets the rank count (default 2).
#[test]
#[ignore]
fn hertz_measurement() {
    let np = std::env::var("SNESVI_HERTZ_NP")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2);
    let petsc = std::env::var("SNESVI_PETSC").unwrap_or_default();
    check_agreement(&run_child(np, &["cases/hertz/hertz.toml"], &petsc, 1200));
}
