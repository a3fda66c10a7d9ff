//! The distributed contact algorithm (MPI + PETSc): the contact boundary c_h, the sets and
//! iterates of Algorithms 1 and 2, the reduced systems (3.29)/(3.42), the free rigid modes,
//! the cycle guard, the Newton loop and the report of the final state. The pointwise contact
//! law it applies lives in `crate::contact` (pure, no MPI).
//!
//! Floors inside: `cycle`, `boundary` → `rigid`, `active_set`, `report` → `reduced` →
//! `newton` → this file's [`solve`].

pub mod active_set;
pub mod boundary;
pub mod cycle;
pub mod newton;
pub mod reduced;
pub mod report;
pub mod rigid;
pub mod snesvi;

use crate::assembly::System;
use crate::case::{self, Method, Preset, SolverSection};
use crate::contact::Obstacle;
use crate::error::RunError;
use crate::mesh::Mesh;
use crate::output::ContactResult;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::Vector;
use crate::say;
use crate::setup::ContactSettings;
use crate::solver;
use active_set::{ActiveSet, Iterate};
use boundary::ContactBoundary;
use newton::{ContactProblem, NewtonResult, NewtonSettings, StepInfo};
use reduced::ReducedSystem;
use report::{FrictionCertificate, Kkt, Scales};
use rigid::FreeModes;
use serde::Serialize;
use std::time::Instant;

/// summary.json's "newton" section.
#[derive(Debug, Clone, Serialize)]
pub struct NewtonSummary {
    /// "newton" (Algorithms 1/2) or "snesvi" (PETSc SNES VI).
    pub method: &'static str,
    /// 1 (frictionless) or 2 (Tresca).
    pub algorithm: u8,
    pub init: &'static str,
    pub c: f64,
    pub c_default: bool,
    pub steps: usize,
    /// Numeric factorisations of the run (each step of the direct preset is one).
    pub factorisations: usize,
    pub converged: bool,
    pub history: Vec<StepInfo>,
    pub rows_seconds: f64,
    pub lambda_seconds: f64,
    pub pinned_dofs: usize,
    pub on_cycle: &'static str,
    pub cycle_detected_at: Option<usize>,
}

/// summary.json's "contact" section.
#[derive(Debug, Clone, Serialize)]
pub struct ContactSummary {
    pub nodes: usize,
    pub excluded_dirichlet: usize,
    pub active_count: usize,
    pub max_pressure: f64,
    pub total_force: Vec<f64>,
    pub half_width: Option<f64>,
    pub kkt: Kkt,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<FrictionCertificate>,
}

/// summary.json's "linear_solver" section of a contact run.
#[derive(Debug, Clone, Serialize)]
pub struct PresetOnly {
    pub preset: &'static str,
}

/// What a contact solve reports in summary.json.
#[derive(Debug, Clone, Serialize)]
pub struct ContactReport {
    pub newton: NewtonSummary,
    pub contact: ContactSummary,
    pub linear_solver: PresetOnly,
}

/// A solved contact problem.
pub struct ContactSolution {
    pub u: Vector,
    /// The contact grid, its fields and the table, for the output layer.
    pub result: ContactResult,
    pub report: ContactReport,
}

/// Builds c_h, configures the solver, runs Algorithm 1 or 2 and reports the final state.
/// Collective; every rank returns the same `Ok` / `Err` kind.
#[allow(clippy::too_many_arguments)]
pub fn solve(
    ctx: &Ctx,
    settings: &ContactSettings,
    mesh: &Mesh,
    layout: &Layout,
    fixed: &[f64],
    sys: &System,
    solver_section: &SolverSection,
    previous: Option<&ContactSolution>,
) -> Result<ContactSolution, RunError> {
    let _ = previous;
    let dim = mesh.dim;
    let b = boundary::build(ctx, mesh, layout, settings, fixed)?;
    log_boundary(ctx, &b, &settings.group);
    check_friction_capacity(ctx, &b, fixed, sys, dim)?;
    let friction = settings.friction();
    solver::configure(
        solver_section.preset,
        solver_section.rtol,
        !friction,
        &solver_section.petsc_options,
    )?;
    let coords = solver::near_null_space_coordinates(ctx, mesh, layout, solver_section.preset)?;
    let c = match settings.newton.c {
        Some(c) => c,
        None => newton::default_c(ctx, &b, dim, settings.young),
    };
    say!(
        ctx,
        "newton: c = {c:.6e}{}",
        if settings.newton.c.is_none() {
            " (E / h_c)"
        } else {
            ""
        }
    );
    let problem = ContactProblem {
        mesh,
        layout,
        boundary: &b,
        fixed,
        sys,
    };
    let ns = NewtonSettings {
        section: &settings.newton,
        c,
        friction,
        rigid: settings.rigid_modes,
    };
    let nr = match solver_section.method {
        Method::Newton => {
            let reduced = ReducedSystem::new(ctx, sys, &b, coords.as_ref(), dim)?;
            newton::semismooth_newton(ctx, &problem, reduced, &ns)?
        }
        Method::SnesVi => {
            let f_local = sys.b.to_local_vec()?;
            snesvi_solve(ctx, &problem, &f_local, settings.rigid_modes)?
        }
    };
    if !nr.converged {
        return Err(RunError::NoConvergence(match solver_section.method {
            Method::Newton => format!(
                "Newton did not converge in newton.max_steps = {} steps (active set still \
                 changing: {} node(s) in the last step)",
                settings.newton.max_steps,
                nr.history.last().map(|h| h.changed).unwrap_or(0)
            ),
            Method::SnesVi => format!("SNES VI did not converge in {} steps", nr.steps),
        }));
    }
    let table = report::gather(ctx, &b, &nr.nodes, dim);
    let total_force = report::total_force(ctx, &nr.nodes);
    let half_width = table.half_width(&b.obstacle);
    let scales = problem_scales(ctx, sys, &nr.u)?;
    let kkt = table.kkt(!friction, &scales);
    let friction_certificate = friction.then(|| table.friction_certificate());
    check_certificates(ctx, &kkt, friction_certificate.as_ref(), &scales)?;
    say!(
        ctx,
        "contact: {} active, p_max = {:.6}, half width = {}, total force = {:?}",
        table.active_count(),
        table.max_pressure(),
        half_width
            .map(|b| format!("{b:.6}"))
            .unwrap_or_else(|| "n/a".into()),
        &total_force[..dim]
    );
    let report = ContactReport {
        newton: NewtonSummary {
            method: solver_section.method.name(),
            algorithm: if friction { 2 } else { 1 },
            init: settings.newton.init.name(),
            c,
            c_default: settings.newton.c.is_none(),
            steps: nr.steps,
            factorisations: match solver_section.method {
                Method::Newton => nr
                    .history
                    .iter()
                    .filter(|h| h.solve == reduced::SolveKind::Factorisation)
                    .count(),
                // rsls factors every reduced system of its steps with the direct preset
                Method::SnesVi if solver_section.preset == Preset::Direct => nr.steps,
                Method::SnesVi => 0,
            },
            converged: nr.converged,
            history: nr.history.clone(),
            rows_seconds: nr.rows_seconds,
            lambda_seconds: nr.lambda_seconds,
            pinned_dofs: nr.pinned_final.len(),
            on_cycle: settings.newton.on_cycle.name(),
            cycle_detected_at: nr.cycle_detected_at,
        },
        contact: ContactSummary {
            nodes: b.n_global,
            excluded_dirichlet: b.excluded_dirichlet,
            active_count: table.active_count(),
            max_pressure: table.max_pressure(),
            total_force: total_force[..dim].to_vec(),
            half_width,
            kkt,
            friction: friction_certificate,
        },
        linear_solver: PresetOnly {
            preset: solver_section.preset.name(),
        },
    };
    Ok(ContactSolution {
        result: report::contact_result(&b, &nr.nodes, dim, friction, &table),
        u: nr.u,
        report,
    })
}

/// The same discrete frictionless problem through PETSc's SNES VI (a baseline for Algorithm 1):
/// the rigid modes that the whole contact boundary cannot fix are pinned once; λ by (3.28).
fn snesvi_solve(
    ctx: &Ctx,
    p: &ContactProblem,
    f_local: &[f64],
    rigid: case::RigidModeHandling,
) -> Result<NewtonResult, RunError> {
    let (mesh, b, sys) = (p.mesh, p.boundary, p.sys);
    let dim = mesh.dim;
    let mut free = FreeModes::new(ctx, mesh, p.layout, p.fixed, b, f_local, rigid);
    let pins = free
        .update_for_whole_boundary(ctx, mesh, p.layout, b)?
        .to_vec();
    let pinned: Vec<usize> = pins.iter().map(|&(v, k)| v * dim + k).collect();
    let nodes: Vec<snesvi::SnesContactNode> = b
        .nodes
        .iter()
        .map(|k| snesvi::SnesContactNode {
            row: k.row,
            normal: k.frame.n,
            gap: k.gap,
        })
        .collect();
    let r = snesvi::solve_snesvi(ctx.comm(), dim, &sys.a, &sys.b, &nodes, &pinned)
        .map_err(|e| RunError::Failed(e.to_string()))?;
    say!(
        ctx,
        "snesvi: {} steps ({}), {} linear iterations, {} ({:.3} s)",
        r.steps,
        r.snes_type,
        r.linear_iterations,
        r.reason,
        r.seconds
    );
    // (3.28), and A_n = the nodes that touch the obstacle.
    let t = Instant::now();
    let mut au = sys.b.duplicate()?;
    sys.a.mult(&r.u, &mut au)?;
    let u_local = r.u.to_local_vec()?;
    let scale = ctx.max_f64(u_local.iter().fold(0.0f64, |m, x| m.max(x.abs())));
    let mut set = ActiveSet {
        normal: vec![false; b.nodes.len()],
        tangential: None,
    };
    let mut it = Iterate::new(b.nodes.len(), u_local.len(), false);
    it.recover(u_local.clone(), au.to_local_vec()?, f_local, b, &set, dim);
    for (i, (k, r)) in b.nodes.iter().zip(&it.nodes).enumerate() {
        set.normal[i] = r.u_n + k.gap <= 1e-9 * scale.max(k.gap.abs());
    }
    it.recover(u_local, au.to_local_vec()?, f_local, b, &set, dim);
    Ok(NewtonResult {
        u: r.u,
        nodes: it.nodes,
        history: Vec::new(),
        converged: r.converged,
        steps: r.steps,
        lambda_seconds: t.elapsed().as_secs_f64(),
        rows_seconds: r.setup_seconds,
        pinned_final: pins,
        cycle_detected_at: None,
    })
}

/// A floating body (no Dirichlet data) on a flat obstacle with Tresca friction has no
/// equilibrium when the tangential resultant of its load exceeds the total friction capacity
/// Σ_k b_k (3.18): said before the solve instead of after a long Newton run. Collective.
fn check_friction_capacity(
    ctx: &Ctx,
    b: &ContactBoundary,
    fixed: &[f64],
    sys: &System,
    dim: usize,
) -> Result<(), RunError> {
    let Obstacle::Plane(plane) = b.obstacle else {
        return Ok(());
    };
    // `fixed` holds every mesh dof on every rank: the same answer everywhere.
    let floating = fixed.iter().all(|x| x.is_nan());
    if !floating {
        return Ok(());
    }
    let capacity = ctx.sum_f64(b.nodes.iter().map(|k| k.bound).sum());
    if capacity == 0.0 {
        return Ok(()); // frictionless: the balance test of the free modes decides
    }
    let f = sys.b.to_local_vec()?;
    let mut local = [0.0; 3];
    for (i, x) in f.iter().enumerate() {
        local[i % dim] += x;
    }
    let r = ctx.sum_vec(&local);
    let n = plane.normal();
    let rn: f64 = (0..3).map(|k| r[k] * n[k]).sum();
    let rt = (0..3)
        .map(|k| (r[k] - rn * n[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    if rt > capacity * (1.0 + 1e-9) + 1e-14 * r.iter().map(|x| x.abs()).sum::<f64>() {
        return Err(RunError::Failed(format!(
            "no equilibrium: the body has no Dirichlet data and the tangential resultant of its \
             load ({rt:.6e}) exceeds the total friction capacity of the contact boundary \
             (Σ b_k = {capacity:.6e}, (3.18)): it would slide away"
        )));
    }
    Ok(())
}

/// |f|_∞ and |u|_∞ of the whole problem (two reductions); a non-finite u is an error.
fn problem_scales(ctx: &Ctx, sys: &System, u: &Vector) -> Result<Scales, RunError> {
    let inf = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let u_local = u.to_local_vec()?;
    let length = ctx.max_f64(if u_local.iter().all(|x| x.is_finite()) {
        inf(&u_local)
    } else {
        f64::INFINITY
    });
    if !length.is_finite() {
        return Err(RunError::Failed(
            "the final displacement is not finite (the reduced system was singular or the \
             iteration diverged)"
                .into(),
        ));
    }
    let force = ctx.max_f64(inf(&sys.b.to_local_vec()?));
    Ok(Scales { force, length })
}

/// The final state against (3.14) (and (3.18) with friction): beyond 1e-8 of the problem's
/// scales a warning (an inexact linear solve), beyond [`report::CERTIFICATE_TOL`] an error —
/// such a state is not a solution, whatever the iteration's stopping rule said.
fn check_certificates(
    ctx: &Ctx,
    kkt: &Kkt,
    friction: Option<&FrictionCertificate>,
    scales: &Scales,
) -> Result<(), RunError> {
    let fric_bad = |rel: f64| friction.is_some_and(|f| f.beyond(rel, scales));
    if kkt.beyond(report::CERTIFICATE_TOL) || fric_bad(report::CERTIFICATE_TOL) {
        return Err(RunError::Failed(format!(
            "the final state is not a solution: it violates {} beyond {:e} of the problem's \
             scales (force {:.3e}, length {:.3e}): KKT {}{} — the problem is probably ill-posed \
             (a load that contact and friction cannot carry) or the linear solves inexact",
            if fric_bad(report::CERTIFICATE_TOL) {
                "(3.18)"
            } else {
                "(3.14)"
            },
            report::CERTIFICATE_TOL,
            scales.force,
            scales.length,
            json(kkt),
            friction
                .map(|f| format!(", friction {}", json(f)))
                .unwrap_or_default()
        )));
    }
    if kkt.beyond(1e-8) || fric_bad(1e-8) {
        say!(
            ctx,
            "warning: the final state violates (3.14) beyond round-off: {}",
            json(kkt)
        );
    }
    Ok(())
}

/// Compact JSON of a certificate (sorted keys).
fn json<T: Serialize>(v: &T) -> String {
    serde_json::to_value(v).expect("plain data").to_string()
}

fn log_boundary(ctx: &Ctx, b: &ContactBoundary, group: &str) {
    say!(
        ctx,
        "contact: {} nodes on '{}'{}",
        b.n_global,
        group,
        if b.excluded_dirichlet > 0 {
            format!(
                " ({} more left to their Dirichlet data)",
                b.excluded_dirichlet
            )
        } else {
            String::new()
        }
    );
}
