//! Verification driver of the linear-elastic solver, run under mpirun by tests/linear_patch.rs
//! and tests/linear_mms.rs. It uses the library directly (partition, assembly with Dirichlet
//! data given per dof by a closure, the direct linear solver) and measures errors against
//! exact solutions it knows in closed form.
//!
//! ```text
//! mpirun -n 2 target/release/examples/linear_check patch MODEL MESH...
//! mpirun -n 2 target/release/examples/linear_check mms MESH...
//! ```
//!
//! patch (MODEL = plane_strain | plane_stress | 3d): u(x) = a + B x imposed on every boundary
//!   node (boundary = nodes of cell faces that belong to one cell only, found from the cells,
//!   not from the mesh's facet groups); rank 0 prints one line `PATCH {json}` per mesh with the
//!   largest nodal error at interior / boundary nodes and the largest deviation of the cell
//!   stresses from sigma(B).
//! mms: a smooth manufactured solution (sin/cos products) with its body force written out by
//!   hand, Dirichlet data on the whole boundary; rank 0 prints `CHECK {json}` once (finite
//!   difference checks of the hand-written gradient and body force) and `MMS {json}` per mesh
//!   with the L2 and H1-seminorm errors (quadrature per cell, degree 2).

// Index loops mirror the tensor formulas.
#![allow(clippy::needless_range_loop)]

use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use mpi::traits::*;
use serde_json::json;
use signorini_mpi::assembly::{self, BodyForce, Problem};
use signorini_mpi::case::SolverSection;
use signorini_mpi::fem::{self, Material, Materials, Model};
use signorini_mpi::mesh::{self, Mesh};
use signorini_mpi::par::Ctx;
use signorini_mpi::partition::{self, Layout};
use signorini_mpi::petsc::{Petsc, Vector};
use signorini_mpi::{post, solver};

type Tensor = [[f64; 3]; 3];

// ---------------------------------------------------------------------------------------
// Material law, written out here independently of the library.

/// (lambda, mu) of the in-plane / 3D law: plane strain and 3D use the 3D Lamé parameters,
/// plane stress the reduced lambda* = E nu / (1 - nu^2).
fn lame(young: f64, nu: f64, model: Model) -> (f64, f64) {
    let mu = young / (2.0 * (1.0 + nu));
    let lambda = match model {
        Model::PlaneStress => young * nu / (1.0 - nu * nu),
        _ => young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
    };
    (lambda, mu)
}

/// Stress of a displacement gradient h (h[i][j] = d u_i / d x_j, only the dim x dim block
/// used), as a 3x3 tensor: plane strain sigma_zz = lambda tr eps, plane stress sigma_zz = 0.
fn hooke(young: f64, nu: f64, model: Model, h: &Tensor) -> Tensor {
    let dim = if model == Model::Solid { 3 } else { 2 };
    let (lambda, mu) = lame(young, nu, model);
    let mut eps = [[0.0; 3]; 3];
    for i in 0..dim {
        for j in 0..dim {
            eps[i][j] = 0.5 * (h[i][j] + h[j][i]);
        }
    }
    let tr: f64 = (0..dim).map(|i| eps[i][i]).sum();
    let mut s = [[0.0; 3]; 3];
    for i in 0..dim {
        for j in 0..dim {
            s[i][j] = 2.0 * mu * eps[i][j];
        }
        s[i][i] += lambda * tr;
    }
    if model == Model::PlaneStrain {
        s[2][2] = lambda * tr;
    }
    s
}

fn model_dim(model: Model) -> usize {
    if model == Model::Solid {
        3
    } else {
        2
    }
}

// ---------------------------------------------------------------------------------------
// Mesh helpers.

/// Nodes on the boundary: nodes of cell faces (dim nodes) shared by no other cell.
fn boundary_nodes(mesh: &Mesh) -> Vec<bool> {
    let npc = mesh.dim + 1;
    let mut count: HashMap<[usize; 3], u32> = HashMap::new();
    for c in 0..mesh.n_cells() {
        let cn = mesh.cell(c);
        for skip in 0..npc {
            let mut f = [usize::MAX; 3];
            let mut k = 0;
            for (a, &v) in cn.iter().enumerate() {
                if a != skip {
                    f[k] = v;
                    k += 1;
                }
            }
            f[..k].sort_unstable();
            *count.entry(f).or_insert(0) += 1;
        }
    }
    let mut on = vec![false; mesh.n_nodes()];
    for (f, n) in count {
        if n == 1 {
            for &v in f.iter().filter(|&&v| v != usize::MAX) {
                on[v] = true;
            }
        }
    }
    on
}

/// Longest edge of any cell.
fn h_max(mesh: &Mesh) -> f64 {
    let mut h: f64 = 0.0;
    for c in 0..mesh.n_cells() {
        let cn = mesh.cell(c);
        for a in 0..cn.len() {
            for b in a + 1..cn.len() {
                let (p, q) = (mesh.coords[cn[a]], mesh.coords[cn[b]]);
                let d =
                    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
                h = h.max(d);
            }
        }
    }
    h
}

/// Displacements of all nodes of this rank's cells: (sorted node list, dim values per node).
fn local_values(
    mesh: &Mesh,
    layout: &Layout,
    u: &Vector,
) -> Result<(Vec<usize>, Vec<f64>), String> {
    post::local_cell_values(mesh, layout, u).map_err(|e| e.to_string())
}

/// Partition, assemble with the given Dirichlet data and body force, solve (direct preset).
fn solve(
    ctx: &Ctx,
    mesh: &Mesh,
    material: Material,
    fixed: Vec<f64>,
    body_force: BodyForce,
) -> Result<(Layout, Vector), String> {
    let comm = ctx.petsc.comm();
    let layout =
        partition::partition(ctx.world, comm, mesh, "ptscotch").map_err(|e| e.to_string())?;
    let problem = Problem {
        mesh,
        held_fixed: Vec::new(),
        material: &Materials::single(material),
        fixed,
        facet_loads: Vec::new(),
        body_force,
    };
    let mut sys = assembly::assemble(comm, &layout, &problem).map_err(|e| e.to_string())?;
    let settings = SolverSection::default();
    let file = std::path::Path::new("examples/linear_check.rs");
    let (u, _) = solver::linear_solve(ctx, mesh, &layout, &mut sys, &settings, file)
        .map_err(|e| e.to_string())?;
    Ok((layout, u))
}

// ---------------------------------------------------------------------------------------
// Patch test.

const PATCH_E: f64 = 3.0;
const PATCH_NU: f64 = 0.3;
const PATCH_A: [f64; 3] = [0.1, -0.2, 0.3];
const PATCH_B: Tensor = [
    [0.011, 0.023, -0.031],
    [0.017, -0.013, 0.005],
    [-0.021, 0.007, 0.019],
];

fn patch_u(x: [f64; 3], dim: usize) -> [f64; 3] {
    let mut u = [0.0; 3];
    for i in 0..dim {
        u[i] = PATCH_A[i] + (0..dim).map(|j| PATCH_B[i][j] * x[j]).sum::<f64>();
    }
    u
}

fn patch(ctx: &Ctx, model: Model, file: &Path) -> Result<(), String> {
    let mesh = mesh::read_msh(file).map_err(|e| e.to_string())?;
    let dim = mesh.dim;
    if dim != model_dim(model) {
        return Err(format!(
            "{}: mesh is {dim}D, model {model:?}",
            file.display()
        ));
    }
    let on = boundary_nodes(&mesh);
    let mut fixed = vec![f64::NAN; mesh.n_nodes() * dim];
    for v in (0..mesh.n_nodes()).filter(|&v| on[v]) {
        let g = patch_u(mesh.coords[v], dim);
        fixed[v * dim..(v + 1) * dim].copy_from_slice(&g[..dim]);
    }
    let material = Material {
        young: PATCH_E,
        poisson: PATCH_NU,
        model,
    };
    let (layout, u) = solve(ctx, &mesh, material, fixed, BodyForce::None)?;

    let (nodes, vals) = local_values(&mesh, &layout, &u)?;
    let (mut err_in, mut err_bd, mut scale): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for (p, &v) in nodes.iter().enumerate() {
        let ex = patch_u(mesh.coords[v], dim);
        for k in 0..dim {
            let e = (vals[p * dim + k] - ex[k]).abs();
            scale = scale.max(ex[k].abs());
            if on[v] {
                err_bd = err_bd.max(e);
            } else {
                err_in = err_in.max(e);
            }
        }
    }
    let s_exact = hooke(PATCH_E, PATCH_NU, model, &PATCH_B);
    let s_scale = s_exact.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut s_err: f64 = 0.0;
    let mut x = [[0.0; 3]; 4];
    let mut ue = [0.0; 12];
    for &c in &layout.local_cells {
        for (a, &v) in mesh.cell(c).iter().enumerate() {
            x[a] = mesh.coords[v];
            let p = nodes.binary_search(&v).map_err(|_| "node not gathered")?;
            ue[a * dim..(a + 1) * dim].copy_from_slice(&vals[p * dim..(p + 1) * dim]);
        }
        let s = fem::cell_stress(&material, &x[..dim + 1], &ue[..(dim + 1) * dim]);
        for i in 0..3 {
            for j in 0..3 {
                s_err = s_err.max((s[i][j] - s_exact[i][j]).abs());
            }
        }
    }
    let err_in = ctx.max_f64(err_in);
    let err_bd = ctx.max_f64(err_bd);
    let scale = ctx.max_f64(scale);
    let s_err = ctx.max_f64(s_err);
    let n_interior = on.iter().filter(|&&b| !b).count();
    if ctx.rank == 0 {
        println!(
            "PATCH {}",
            json!({
                "mesh": file.display().to_string(), "model": format!("{model:?}"), "dim": dim,
                "ranks": ctx.size, "nodes": mesh.n_nodes(), "cells": mesh.n_cells(),
                "interior_nodes": n_interior,
                "max_err_interior": err_in, "max_err_boundary": err_bd, "u_scale": scale,
                "max_stress_err": s_err, "stress_scale": s_scale,
            })
        );
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Manufactured solutions.

const MMS_E: f64 = 1.0;
const MMS_NU: f64 = 0.3;

/// 2D: u = (sin(a x) sin(a y), cos(a x) cos(b y)), a = pi, b = 2 pi.
fn mms2_u(p: [f64; 3]) -> [f64; 3] {
    let (a, b) = (PI, 2.0 * PI);
    let (x, y) = (p[0], p[1]);
    [
        (a * x).sin() * (a * y).sin(),
        (a * x).cos() * (b * y).cos(),
        0.0,
    ]
}

/// 2D gradient h[i][j] = d u_i / d x_j, by hand.
fn mms2_grad(p: [f64; 3]) -> Tensor {
    let (a, b) = (PI, 2.0 * PI);
    let (x, y) = (p[0], p[1]);
    let (sax, cax, say, cay) = ((a * x).sin(), (a * x).cos(), (a * y).sin(), (a * y).cos());
    let (sby, cby) = ((b * y).sin(), (b * y).cos());
    [
        [a * cax * say, a * sax * cay, 0.0],
        [-a * sax * cby, -b * cax * sby, 0.0],
        [0.0; 3],
    ]
}

/// 2D body force f = -div sigma = -(lambda + mu) grad div u - mu lap u, by hand.
fn mms2_f(p: [f64; 3], lambda: f64, mu: f64) -> [f64; 3] {
    let (a, b) = (PI, 2.0 * PI);
    let (x, y) = (p[0], p[1]);
    let (sax, cax, say, cay) = ((a * x).sin(), (a * x).cos(), (a * y).sin(), (a * y).cos());
    let (sby, cby) = ((b * y).sin(), (b * y).cos());
    // grad div u
    let gdx = -a * a * sax * say + a * b * sax * sby;
    let gdy = a * a * cax * cay - b * b * cax * cby;
    // laplacian
    let l1 = -2.0 * a * a * sax * say;
    let l2 = -(a * a + b * b) * cax * cby;
    [
        -(lambda + mu) * gdx - mu * l1,
        -(lambda + mu) * gdy - mu * l2,
        0.0,
    ]
}

/// 3D: u = (sx sy sz, cx cy cz, sx cy sz), s* = sin(pi *), c* = cos(pi *).
fn mms3_u(p: [f64; 3]) -> [f64; 3] {
    let a = PI;
    let (sx, cx) = ((a * p[0]).sin(), (a * p[0]).cos());
    let (sy, cy) = ((a * p[1]).sin(), (a * p[1]).cos());
    let (sz, cz) = ((a * p[2]).sin(), (a * p[2]).cos());
    [sx * sy * sz, cx * cy * cz, sx * cy * sz]
}

fn mms3_grad(p: [f64; 3]) -> Tensor {
    let a = PI;
    let (sx, cx) = ((a * p[0]).sin(), (a * p[0]).cos());
    let (sy, cy) = ((a * p[1]).sin(), (a * p[1]).cos());
    let (sz, cz) = ((a * p[2]).sin(), (a * p[2]).cos());
    [
        [a * cx * sy * sz, a * sx * cy * sz, a * sx * sy * cz],
        [-a * sx * cy * cz, -a * cx * sy * cz, -a * cx * cy * sz],
        [a * cx * cy * sz, -a * sx * sy * sz, a * sx * cy * cz],
    ]
}

/// 3D body force: each component of u satisfies lap u_i = -3 a^2 u_i.
fn mms3_f(p: [f64; 3], lambda: f64, mu: f64) -> [f64; 3] {
    let a = PI;
    let (sx, cx) = ((a * p[0]).sin(), (a * p[0]).cos());
    let (sy, cy) = ((a * p[1]).sin(), (a * p[1]).cos());
    let (sz, cz) = ((a * p[2]).sin(), (a * p[2]).cos());
    let a2 = a * a;
    let gd = [
        a2 * (-sx * sy * sz + sx * sy * cz + cx * cy * cz),
        a2 * (cx * cy * sz - cx * cy * cz - sx * sy * cz),
        a2 * (cx * sy * cz + cx * sy * sz - sx * cy * sz),
    ];
    let u = [sx * sy * sz, cx * cy * cz, sx * cy * sz];
    let mut f = [0.0; 3];
    for i in 0..3 {
        f[i] = -(lambda + mu) * gd[i] + 3.0 * a2 * mu * u[i];
    }
    f
}

struct Mms {
    dim: usize,
    model: Model,
    u: fn([f64; 3]) -> [f64; 3],
    grad: fn([f64; 3]) -> Tensor,
    f: fn([f64; 3], f64, f64) -> [f64; 3],
}

impl Mms {
    fn new(dim: usize) -> Mms {
        if dim == 2 {
            Mms {
                dim,
                model: Model::PlaneStrain,
                u: mms2_u,
                grad: mms2_grad,
                f: mms2_f,
            }
        } else {
            Mms {
                dim,
                model: Model::Solid,
                u: mms3_u,
                grad: mms3_grad,
                f: mms3_f,
            }
        }
    }

    fn lame(&self) -> (f64, f64) {
        lame(MMS_E, MMS_NU, self.model)
    }

    /// Central-difference checks of the hand-written gradient (against u) and body force
    /// (against -div sigma(grad)) at a few points: largest relative deviations.
    fn fd_check(&self) -> (f64, f64) {
        let dim = self.dim;
        let (lambda, mu) = self.lame();
        let pts = [
            [0.13, 0.71, 0.37],
            [0.52, 0.29, 0.83],
            [0.91, 0.44, 0.06],
            [0.33, 0.97, 0.61],
        ];
        let d = 1e-5;
        let shift = |p: [f64; 3], j: usize, s: f64| {
            let mut q = p;
            q[j] += s;
            q
        };
        let (mut eg, mut ef): (f64, f64) = (0.0, 0.0);
        let (mut sg, mut sf): (f64, f64) = (0.0, 0.0);
        for &p in &pts {
            let g = (self.grad)(p);
            for i in 0..dim {
                for j in 0..dim {
                    let fd =
                        ((self.u)(shift(p, j, d))[i] - (self.u)(shift(p, j, -d))[i]) / (2.0 * d);
                    eg = eg.max((fd - g[i][j]).abs());
                    sg = sg.max(g[i][j].abs());
                }
            }
            let sigma = |q: [f64; 3]| hooke(MMS_E, MMS_NU, self.model, &(self.grad)(q));
            let f = (self.f)(p, lambda, mu);
            for i in 0..dim {
                let mut div = 0.0;
                for j in 0..dim {
                    div += (sigma(shift(p, j, d))[i][j] - sigma(shift(p, j, -d))[i][j]) / (2.0 * d);
                }
                ef = ef.max((-div - f[i]).abs());
                sf = sf.max(f[i].abs());
            }
        }
        (eg / sg, ef / sf)
    }
}

fn mms(ctx: &Ctx, file: &Path) -> Result<(), String> {
    let mesh = mesh::read_msh(file).map_err(|e| e.to_string())?;
    let dim = mesh.dim;
    let m = Mms::new(dim);
    let (lambda, mu) = m.lame();
    let on = boundary_nodes(&mesh);
    let mut fixed = vec![f64::NAN; mesh.n_nodes() * dim];
    for v in (0..mesh.n_nodes()).filter(|&v| on[v]) {
        let g = (m.u)(mesh.coords[v]);
        fixed[v * dim..(v + 1) * dim].copy_from_slice(&g[..dim]);
    }
    let material = Material {
        young: MMS_E,
        poisson: MMS_NU,
        model: m.model,
    };
    let ff = m.f;
    let body = BodyForce::Function(Box::new(move |p| ff(p, lambda, mu)));
    let (layout, u) = solve(ctx, &mesh, material, fixed, body)?;

    let (nodes, vals) = local_values(&mesh, &layout, &u)?;
    let (mut l2, mut h1, mut nl2, mut nh1) = (0.0, 0.0, 0.0, 0.0);
    let rule = fem::simplex_quadrature(dim + 1);
    let mut ue = [[0.0; 3]; 4];
    for &c in &layout.local_cells {
        let cn = mesh.cell(c);
        let xs: Vec<[f64; 3]> = cn.iter().map(|&v| mesh.coords[v]).collect();
        for (a, &v) in cn.iter().enumerate() {
            let p = nodes.binary_search(&v).map_err(|_| "node not gathered")?;
            ue[a] = [0.0; 3];
            ue[a][..dim].copy_from_slice(&vals[p * dim..(p + 1) * dim]);
        }
        // Gradients of the P1 shape functions and the cell measure.
        let mut grads = [[0.0; 3]; 4];
        let meas = if dim == 2 {
            let xt = [
                [xs[0][0], xs[0][1]],
                [xs[1][0], xs[1][1]],
                [xs[2][0], xs[2][1]],
            ];
            let (g, area) = fem::tri_gradients(&xt);
            for a in 0..3 {
                grads[a] = [g[a][0], g[a][1], 0.0];
            }
            area.abs()
        } else {
            let (g, vol) = fem::tet_gradients(&[xs[0], xs[1], xs[2], xs[3]]);
            grads = g;
            vol.abs()
        };
        let mut gh = [[0.0; 3]; 3];
        for a in 0..=dim {
            for i in 0..dim {
                for j in 0..dim {
                    gh[i][j] += ue[a][i] * grads[a][j];
                }
            }
        }
        for q in rule {
            let mut p = [0.0; 3];
            let mut uh = [0.0; 3];
            for a in 0..=dim {
                for k in 0..3 {
                    p[k] += q.bary[a] * xs[a][k];
                    uh[k] += q.bary[a] * ue[a][k];
                }
            }
            let w = q.weight * meas;
            let ex = (m.u)(p);
            let gx = (m.grad)(p);
            for i in 0..dim {
                l2 += w * (uh[i] - ex[i]).powi(2);
                nl2 += w * ex[i].powi(2);
                for j in 0..dim {
                    h1 += w * (gh[i][j] - gx[i][j]).powi(2);
                    nh1 += w * gx[i][j].powi(2);
                }
            }
        }
    }
    let l2 = ctx.sum_f64(l2).sqrt();
    let h1 = ctx.sum_f64(h1).sqrt();
    let nl2 = ctx.sum_f64(nl2).sqrt();
    let nh1 = ctx.sum_f64(nh1).sqrt();
    let volume: f64 = (0..mesh.n_cells()).map(|c| mesh.cell_measure(c)).sum();
    if ctx.rank == 0 {
        println!(
            "MMS {}",
            json!({
                "mesh": file.display().to_string(), "dim": dim, "ranks": ctx.size,
                "nodes": mesh.n_nodes(), "cells": mesh.n_cells(), "dofs": mesh.n_nodes() * dim,
                "h_max": h_max(&mesh),
                "h_eff": (volume / mesh.n_cells() as f64).powf(1.0 / dim as f64),
                "l2": l2, "h1": h1, "l2_norm_u": nl2, "h1_norm_u": nh1,
            })
        );
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------

fn run(ctx: &Ctx, args: &[String]) -> Result<(), String> {
    let usage = "usage: linear_check patch MODEL MESH... | linear_check mms MESH...";
    match args.first().map(String::as_str) {
        Some("patch") if args.len() >= 3 => {
            let model = match args[1].as_str() {
                "plane_strain" => Model::PlaneStrain,
                "plane_stress" => Model::PlaneStress,
                "3d" => Model::Solid,
                m => return Err(format!("unknown model {m}; {usage}")),
            };
            for f in &args[2..] {
                patch(ctx, model, &PathBuf::from(f))?;
            }
            Ok(())
        }
        Some("mms") if args.len() >= 2 => {
            let mut checked = [false; 4];
            for f in &args[1..] {
                let file = PathBuf::from(f);
                // The finite-difference check of the hand-written formulas, once per dimension.
                let dim = mesh::read_msh(&file).map_err(|e| e.to_string())?.dim;
                if !checked[dim] {
                    checked[dim] = true;
                    let (eg, ef) = Mms::new(dim).fd_check();
                    if ctx.rank == 0 {
                        println!(
                            "CHECK {}",
                            json!({"dim": dim, "grad_rel_err": eg, "f_rel_err": ef})
                        );
                    }
                }
                mms(ctx, &file)?;
            }
            Ok(())
        }
        _ => Err(usage.to_string()),
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(universe) = mpi::initialize() else {
        eprintln!("linear_check: MPI could not be initialised");
        return ExitCode::FAILURE;
    };
    let world = universe.world();
    let petsc = match Petsc::init(&[]) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("linear_check: PETSc: {e}");
            world.abort(1);
        }
    };
    let r = run(&Ctx::new(&world, &petsc), &args);
    if let Err(e) = r {
        eprintln!("linear_check (rank {}): {e}", world.rank());
        // Other ranks may be inside a collective call: end them all.
        world.abort(1);
    }
    drop(petsc);
    ExitCode::SUCCESS
}
