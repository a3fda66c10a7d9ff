//! The distributed contact algorithm (MPI + PETSc): the contact boundary c_h, the sets and
//! iterates of Algorithms 1 and 2, the reduced systems (3.29)/(3.42), the free rigid modes,
//! the cycle guard, the Newton loop and the report of the final state. The pointwise contact
//! law it applies lives in `crate::contact` (pure, no MPI); the tangential laws as the
//! algorithm sees them in `law` (one file per law), Coulomb's strategy in `coulomb`.
//!
//! Floors inside: `cycle`, `boundary` → `rigid`, `law`, `active_set`, `report` →
//! `step_system` → `plain_path` → `schur` → `coulomb` → this file's [`solve`] (the
//! phases of a solve; the checks before it in `capacity`, the judged final state in
//! `final_state`).

pub mod active_set;
pub mod boundary;
pub mod capacity;
pub mod certificate;
pub mod coulomb;
pub mod cycle;
pub mod dense;
pub mod final_state;
pub mod force;
pub mod halfspace;
pub mod kept;
pub mod law;
pub mod plain_path;
pub mod report;
pub mod rigid;
pub mod schur;
pub mod session;
pub mod snesvi;
pub mod step_system;
pub mod warn;

use crate::assembly::System;
use crate::case::{self, CoulombAlgorithm, Method, NewtonInit, Preset, SolverPath, SolverSection};
use crate::error::RunError;
use crate::linsolve::SolverKind;
use crate::mesh::Mesh;
use crate::mortar::InU;
use crate::output::ContactResult;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::Vector;
use crate::say;
use crate::setup::ContactSettings;
use crate::solver;
use crate::tuning::DEFAULT_C_FACTOR;
use crate::warnings::Warning;
use active_set::{ActiveSet, Iterate, Law};
use boundary::{ContactBoundary, NodeResult};
use coulomb::Outcome;
use plain_path::{ContactProblem, NewtonResult, NewtonSettings, StepInfo, WarmStart};
use report::{ContactSummary, Scales};
use rigid::FreeModes;
use serde::Serialize;
use session::Session;
use std::time::Instant;
use step_system::ReducedSystem;

/// summary.json's "newton" section.
#[derive(Debug, Clone, Serialize)]
pub struct NewtonSummary {
    /// "newton" (Algorithms 1/2) or "snesvi" (PETSc SNES VI).
    pub method: &'static str,
    /// Method "newton": the path the solve took first, "schur" (the Schur path; `condensed`
    /// says whether it fell back to the plain path) or "plain" (`solver.path`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path: Option<&'static str>,
    /// 1 (frictionless) or 2 (Tresca).
    pub algorithm: u8,
    pub init: &'static str,
    pub c: f64,
    pub c_default: bool,
    pub steps: usize,
    /// Numeric factorisations of the run (each step of the direct preset is one).
    pub factorisations: usize,
    /// Iterative preset with `solver.reuse` not "never": preconditioner setups (PCSetUp) of
    /// the run; the plain path sets up once per step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pc_setups: Option<usize>,
    pub converged: bool,
    pub history: Vec<StepInfo>,
    pub rows_seconds: f64,
    pub lambda_seconds: f64,
    pub pinned_dofs: usize,
    pub on_cycle: &'static str,
    pub cycle_detected_at: Option<usize>,
    /// Coulomb friction only: the law, μ, the algorithm and (fixed point) its outer steps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coulomb: Option<CoulombSummary>,
    /// The condensed path (frictionless, direct preset), when it was tried.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub condensed: Option<schur::CondensedSummary>,
}

/// summary.json's "newton"."coulomb": how Coulomb friction was solved. `steps` of the
/// newton section counts every Newton step (linear solve), over all outer steps.
#[derive(Debug, Clone, Serialize)]
pub struct CoulombSummary {
    pub mu: f64,
    /// "newton" (one generalised Newton) or "fixed-point" (Tresca solves).
    pub algorithm: &'static str,
    /// Fixed point: the number of Tresca solves (outer steps); `None` for "newton".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outer_steps: Option<usize>,
    /// Whether the solve started from a previous load step (friction on the increment).
    pub warm_start: bool,
}

/// summary.json's "linear_solver" section of a contact run: the preset, and the Newton steps'
/// KSP and PC types as PETSc has them after the options (the project's MUMPS factorisation
/// with its nested-dissection order: "cholesky-mumps-nd" or "lu-mumps-nd"; absent for SNES VI).
#[derive(Debug, Clone, Serialize)]
pub struct PresetOnly {
    pub preset: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ksp_type: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pc_type: Option<String>,
}

/// What a contact solve reports in summary.json.
#[derive(Debug, Clone, Serialize)]
pub struct ContactReport {
    pub newton: NewtonSummary,
    pub contact: ContactSummary,
    pub linear_solver: PresetOnly,
    /// The final state's certificate (a load series: the worst over its steps).
    pub certificate: certificate::Certificate,
}

/// A solved contact problem.
pub struct ContactSolution {
    pub u: Vector,
    /// The contact grid, its fields and the table, for the output layer.
    pub result: ContactResult,
    pub report: ContactReport,
    /// This rank's contact nodes (in the order of c_h) at the solution: u, λ in their frames,
    /// the final normal set (`active`) and tangential state (`slip`). A later load step on
    /// the same mesh and boundary starts from it and measures the slip from its u_τ.
    pub nodes: Vec<NodeResult>,
    /// A warm-started solve: its change since the previous load step (the predictor of the
    /// next step).
    pub delta: Option<StepDelta>,
    /// Set by the load stepping before the next step starts from this solution: the ratio of
    /// the next load increment to this step's, s > 0: the next solve starts from the linear
    /// extrapolation `self + s · delta` (0: from this solution itself).
    pub predict: f64,
    /// Each pair's obstacle displacement d in this solve (friction in the next step acts on
    /// the slip relative to the obstacle's increment since).
    pub obstacle_displacement: Vec<[f64; 3]>,
    /// The warnings of this solve (docs/warnings.md; the same on every rank, not logged yet).
    pub warnings: Vec<Warning>,
}

/// A load step's change of the contact nodes' values (u, λ in both forms) and of this rank's
/// rows of u since the previous step.
pub struct StepDelta {
    pub nodes: Vec<NodeResult>,
    pub u_local: Vec<f64>,
    /// Each pair's obstacle displacement since the previous step.
    pub obstacle: Vec<[f64; 3]>,
}

impl ContactSolution {
    /// The start of the next load step: this solution, or with `predict` > 0 and a `delta`
    /// the linear extrapolation x + s Δx of every contact node's u, λ and of u (the
    /// increment of the next step predicted from this one's: the load increments of a history
    /// are all parallel, f(t) = t f(1) + (1 − t) f_held), the normal set from the predicted
    /// values by (3.23). `u_local`: this rank's rows of u. Local.
    fn start(
        &self,
        b: &ContactBoundary,
        u_local: Vec<f64>,
        c: f64,
    ) -> (Option<Vec<NodeResult>>, Vec<f64>) {
        let s = self.predict;
        let Some(d) = self.delta.as_ref().filter(|_| s > 0.0 && s.is_finite()) else {
            return (None, u_local);
        };
        let lin = |x: f64, dx: f64| x + s * dx;
        let nodes = self
            .nodes
            .iter()
            .zip(&d.nodes)
            .zip(&b.nodes)
            .map(|((r, dr), k)| {
                let mut p = *r;
                for j in 0..3 {
                    p.u[j] = lin(r.u[j], dr.u[j]);
                    p.lambda[j] = lin(r.lambda[j], dr.lambda[j]);
                }
                for j in 0..2 {
                    p.u_t[j] = lin(r.u_t[j], dr.u_t[j]);
                    p.lambda_t[j] = lin(r.lambda_t[j], dr.lambda_t[j]);
                }
                p.u_n = lin(r.u_n, dr.u_n);
                p.lambda_n = lin(r.lambda_n, dr.lambda_n);
                p.active = crate::contact::normal_active(p.u_n, p.lambda_n, k.gap, c);
                p
            })
            .collect();
        let u = u_local
            .iter()
            .zip(&d.u_local)
            .map(|(x, dx)| lin(*x, *dx))
            .collect();
        (Some(nodes), u)
    }
}

/// This solve's change since `prev` (same mesh and boundary). Local.
fn step_delta(
    prev: &ContactSolution,
    nodes: &[NodeResult],
    displacement: &[[f64; 3]],
    u: &[f64],
    u_prev: &[f64],
) -> StepDelta {
    let sub3 = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let sub2 = |a: [f64; 2], b: [f64; 2]| [a[0] - b[0], a[1] - b[1]];
    StepDelta {
        nodes: nodes
            .iter()
            .zip(&prev.nodes)
            .map(|(r, p)| NodeResult {
                u: sub3(r.u, p.u),
                lambda: sub3(r.lambda, p.lambda),
                u_n: r.u_n - p.u_n,
                u_t: sub2(r.u_t, p.u_t),
                lambda_n: r.lambda_n - p.lambda_n,
                lambda_t: sub2(r.lambda_t, p.lambda_t),
                active: r.active,
                slip: r.slip,
            })
            .collect(),
        u_local: u.iter().zip(u_prev).map(|(a, b)| a - b).collect(),
        obstacle: displacement
            .iter()
            .zip(&prev.obstacle_displacement)
            .map(|(d, p)| crate::geom::sub(*d, *p))
            .collect(),
    }
}

/// Builds c_h, configures the solver, runs Algorithm 1, Algorithm 2 (Tresca) or Coulomb (the
/// generalised Newton or the fixed point on Tresca thresholds) and reports the final state.
/// `previous`: the converged solution of the previous load step on the same mesh and boundary;
/// with it the Newton starts from its sets and iterate, and friction acts on the tangential
/// increment u_τ − u_τ^prev (docs/friction.md, "Load steps"). `None`: one static solve.
/// `session`: the run's linear solver and what the previous solve kept (its factorisation,
/// taken where it holds; this solve's left in it; after a failed solve, nothing). Collective;
/// every rank returns the same `Ok` / `Err` kind.
#[allow(clippy::too_many_arguments)]
pub fn solve(
    ctx: &Ctx,
    settings: &ContactSettings,
    mesh: &Mesh,
    layout: &Layout,
    fixed: &[f64],
    sys: &System,
    solver_section: &SolverSection,
    session: &mut Session,
    previous: Option<&ContactSolution>,
    in_u: Option<&InU>,
) -> Result<ContactSolution, RunError> {
    let dim = mesh.dim;
    let law = Law::of(settings);
    let friction = settings.friction();
    let (mut b, warned) = contact_boundary(ctx, settings, mesh, layout, fixed)?;
    b.keys.solver = solver::solver_keys(solver_section);
    let force_control = force_control(settings, previous);
    let within = capacity::check_friction_capacity(ctx, &b, fixed, sys, dim, law, &force_control)?;
    let displacements = settings.displacements();
    let prev_u = (previous.map(|prev| take_reference(ctx, &mut b, prev, friction, &displacements)))
        .transpose()?;
    b.stiffness = plain_path::nodal_stiffness(ctx, &b, dim, settings.young);
    let c = complementarity_parameter(ctx, settings, &b, dim);
    let start = warm_start(previous, prev_u.as_deref(), &b, &force_control, c);
    let warm = previous
        .zip(start.as_ref())
        .map(|(prev, (nodes, u))| WarmStart {
            nodes: nodes.as_deref().unwrap_or(&prev.nodes),
            u_local: u,
            floors_from: None,
        });
    session.located = None; // located anew in every solve
    let problem = ContactProblem {
        mesh,
        layout,
        boundary: &b,
        fixed,
        sys,
    };
    // the body's half-space model: the predictor's on the iterative preset (frictionless,
    // plain_path/), else the condensed path's (locating a floating body's zone; the plain path's
    // first set where the zone is too wide for the dense limits)
    let model = halfspace::HalfSpace {
        modulus: settings.contact_modulus,
        dim,
        length: 2.0 * mesh.extent(),
        mirrors: halfspace::mirror_planes(ctx, mesh, fixed),
    };
    let iterative = session.setup().kind() == SolverKind::Iterative;
    let choice = MethodChoice {
        settings,
        section: solver_section,
        path: chosen_path(settings, solver_section, &b, session.setup().kind()),
    };
    let ns = newton_settings(settings, c, law, &model, iterative, &force_control);
    // a failure of a frictional case with a body that only its contact holds in some rigid
    // mode (a slot of the body modes: the survey gives one to each such body) says what may be
    // the cause
    let sliding = friction && b.modes.slots() > 0;
    let mut types = None;
    let ran = run_method(
        ctx,
        &problem,
        &ns,
        &choice,
        session,
        warm.as_ref(),
        &mut types,
    )
    .map_err(|e| capacity::why_sliding(e, sliding, within))
    .map_err(|e| capacity::why_stiff_slave(e, settings.material.slave_over_master));
    let ran = forget_on_error(session, ran)?;
    let solved = Solved {
        law,
        c,
        ran,
        types,
        warned,
        previous,
        prev_u,
        in_u,
        force_control: &force_control,
    };
    let solution = report_solution(ctx, &choice, &problem, solved);
    forget_on_error(session, solution)
}

/// A solve that fails after it took the previous load step's factorisation leaves nothing
/// kept: the retry of a cut-back step starts without one. Local.
fn forget_on_error<T>(session: &mut Session, r: Result<T, RunError>) -> Result<T, RunError> {
    if r.is_err() {
        session.kept.clear();
    }
    r
}

/// The Newton loop's settings of a solve: the half-space `model` as the iterative preset's
/// predictor (frictionless) or, on the direct preset, as the condensed path's. Local.
fn newton_settings<'a>(
    settings: &'a ContactSettings,
    c: f64,
    law: Law,
    model: &'a halfspace::HalfSpace,
    iterative: bool,
    force: &'a [force::ForceControl],
) -> NewtonSettings<'a> {
    NewtonSettings {
        section: &settings.newton,
        c,
        law,
        rigid: settings.rigid_modes,
        halfspace: (!settings.friction() && iterative).then_some(model),
        estimate: false,
        carried: None,
        model: (!iterative).then_some(model),
        force,
    }
}

/// The start of a load step (`previous`, its u's local rows `prev_u`): the previous step's
/// solution, or its extrapolation along its own increment ([`ContactSolution::start`]; under
/// force control against the obstacles where the previous step left them). Local.
fn warm_start(
    previous: Option<&ContactSolution>,
    prev_u: Option<&[f64]>,
    b: &ContactBoundary,
    force_control: &[force::ForceControl],
    c: f64,
) -> Option<(Option<Vec<NodeResult>>, Vec<f64>)> {
    let at_start = (!force_control.is_empty()).then(|| {
        let mut placed = b.clone();
        force::Approach::new(b, force_control).place(&mut placed);
        placed
    });
    previous
        .zip(prev_u)
        .map(|(prev, u)| prev.start(at_start.as_ref().unwrap_or(b), u.to_vec(), c))
}

/// How a solve runs: the case's contact settings, its solver section (the method, the
/// preset) and the path a Newton solve takes first ([`chosen_path`]; `None`: SNES VI).
struct MethodChoice<'a> {
    settings: &'a ContactSettings,
    section: &'a SolverSection,
    path: Option<SolverPath>,
}

/// What [`solve`] hands its report: the law, c, the method's result, the Newton steps' KSP
/// and PC types, the warnings of the start, the previous load step's solution and u (local
/// rows), the body pairs' change of basis and force control.
struct Solved<'a> {
    law: Law,
    c: f64,
    ran: Ran,
    types: Option<(String, String)>,
    warned: Vec<Warning>,
    previous: Option<&'a ContactSolution>,
    prev_u: Option<Vec<f64>>,
    in_u: Option<&'a InU<'a>>,
    force_control: &'a [force::ForceControl],
}

/// The solution of a solve and its report: the final state judged (Coulomb by b_k =
/// μ(−λ_n^k)), the obstacles placed at their approaches, the certificate, summary.json's
/// sections, the warnings and the change since the previous load step; `problem`'s boundary
/// as the solve saw it (copied, judged and placed here). Collective.
fn report_solution(
    ctx: &Ctx,
    choice: &MethodChoice,
    problem: &ContactProblem,
    solved: Solved,
) -> Result<ContactSolution, RunError> {
    let MethodChoice {
        settings,
        section: solver_section,
        path,
    } = *choice;
    let (mesh, layout) = (problem.mesh, problem.layout);
    let (dim, friction) = (mesh.dim, settings.friction());
    let Solved {
        law,
        c,
        ran: (mut nr, outer_steps, condensed_summary),
        types,
        mut warned,
        previous,
        prev_u,
        in_u,
        force_control,
    } = solved;
    // the certificate and the output judge Coulomb's law with b_k = μ(−λ_n^k)
    let mut b = problem.boundary.clone();
    final_state::judged_bounds(law.rules(), &mut b, &nr.nodes);
    let placed = place_at_approaches(&mut b, settings, force_control, &nr.approach, friction);
    let displacement = &placed.displacement;
    let floor = vanishing_floor(previous); // the step before's scales, for a vanishing step
    let mut state = final_state::final_state(ctx, problem.sys, &b, &nr, friction, dim, floor)?;
    report::per_pair(
        ctx,
        settings,
        &b,
        &nr.nodes,
        &state.table,
        &placed,
        &mut state.contact,
    );
    let judged = ContactProblem {
        boundary: &b,
        ..*problem
    };
    // the step before's equilibrium reference, as its scales (`vanishing_floor`)
    state.equilibrium_floor = previous.map_or(0.0, |p| p.report.certificate.equilibrium.reference);
    let certificate =
        final_state::certify(ctx, settings, &judged, &state, &nr, in_u, force_control)?;
    // forces that do not balance: an error, or a warning if (3.14)/(3.18) raised none
    let unbalanced = final_state::check_balance(&certificate, &b.keys, c)?;
    state.warning = state.warning.or(unbalanced);
    let mut newton = newton_summary(settings, solver_section, c, &mut nr, outer_steps, previous);
    newton.path = path.map(SolverPath::name);
    if let Some(cs) = condensed_summary {
        // K_p's with the Schur complement, one per round of candidates (the dense steps
        // factorise nothing sparse)
        newton.factorisations += cs.factorisations;
        newton.condensed = Some(cs);
    }
    warned.extend(state.warning.take());
    let u_local = nr.u.to_local_vec()?;
    let vanishing = nr.stop == certificate::StopRule::Vanishing;
    warned.extend(warn::solution_warnings(
        ctx,
        &judged,
        settings,
        (&nr.nodes, &u_local),
        displacement,
        vanishing,
    ));
    let delta = match previous.zip(prev_u) {
        Some((prev, u_prev)) => Some(step_delta(prev, &nr.nodes, displacement, &u_local, &u_prev)),
        None => None,
    };
    Ok(ContactSolution {
        result: report::contact_result(ctx, mesh, layout, settings, &b, &nr.nodes, &state.table),
        u: nr.u,
        report: ContactReport {
            newton,
            contact: state.contact,
            linear_solver: PresetOnly {
                preset: solver_section.preset.name(),
                ksp_type: types.as_ref().map(|t| t.0.clone()),
                pc_type: types.map(|t| t.1),
            },
            certificate,
        },
        nodes: nr.nodes,
        delta,
        predict: 0.0,
        obstacle_displacement: placed.displacement,
        warnings: warned,
    })
}

/// The contact boundary of a solve, logged, with the checks that come before the solve (every
/// node projected, the depth of the start, a force that never reaches the body) and the
/// warnings of its start (not logged). Collective; every rank returns the same `Ok` / `Err`
/// kind.
pub fn contact_boundary(
    ctx: &Ctx,
    settings: &ContactSettings,
    mesh: &Mesh,
    layout: &Layout,
    fixed: &[f64],
) -> Result<(ContactBoundary, Vec<Warning>), RunError> {
    let start =
        |nodes: &[boundary::ContactNode]| warn::start_warnings(ctx, mesh, layout, settings, nodes);
    let (b, warned) = boundary::build(ctx, mesh, layout, settings, fixed, start)?;
    log_boundary(ctx, &b, settings, mesh.dim);
    // the approaches' starts do not matter here: only the forces' directions
    if let Some(fc) = force::unreached(ctx, &b, &force_control(settings, None)) {
        return Err(force::never_touches(fc));
    }
    Ok((b, warned))
}

/// Force control's result on the boundary: every force-controlled pair's obstacle where its
/// approach δ put it (the gaps g0 − δ e·n and, with friction, the tangential references moved
/// along), for the certificates and the output. Returns every pair's obstacle displacement
/// and approach (`None` off force control). Local.
fn place_at_approaches(
    b: &mut ContactBoundary,
    settings: &ContactSettings,
    force_control: &[force::ForceControl],
    approach: &[f64],
    friction: bool,
) -> report::Placement {
    let mut displacement = settings.displacements();
    let mut approaches = vec![None; settings.pairs.len()];
    for (&delta, fc) in approach.iter().zip(force_control) {
        displacement[fc.pair] = fc.direction().map(|x| delta * x);
        approaches[fc.pair] = Some(delta);
        for k in b.nodes.iter_mut().filter(|k| k.pair == fc.pair) {
            k.gap -= delta * fc.weight(k);
            if friction {
                let wt = fc.tangential_weight(k);
                for j in 0..2 {
                    k.u_t_ref[j] += delta * wt[j];
                }
            }
        }
    }
    report::Placement {
        displacement,
        approach: approaches,
    }
}

/// Force control of this solve (`contact.force`), one per force-controlled pair in pair
/// order: the force at this load factor, δ from the previous load step's obstacle
/// displacement (its component along the force; extrapolated along that step's increment as
/// the rest of its start, [`ContactSolution::start`]), else 0. Empty without force control.
fn force_control(
    settings: &ContactSettings,
    previous: Option<&ContactSolution>,
) -> Vec<force::ForceControl> {
    settings
        .force_pairs()
        .map(|(p, pair)| {
            let mut fc = force::ForceControl {
                force: pair.force_now,
                start: 0.0,
                file: settings.file.clone(),
                pair: p,
                key: pair.key("force"),
            };
            if let Some(prev) = previous {
                let mut d = prev.obstacle_displacement[p];
                if let Some(delta) = prev.delta.as_ref().filter(|_| prev.predict > 0.0) {
                    for (x, dx) in d.iter_mut().zip(delta.obstacle[p]) {
                        *x += prev.predict * dx;
                    }
                }
                fc.start = crate::geom::dot(d, fc.direction());
            }
            fc
        })
        .collect()
}

/// The complementarity parameter c: the case's, or κ E h_c^(d−2) (κ = [`DEFAULT_C_FACTOR`],
/// `b.stiffness` from [`plain_path::nodal_stiffness`]); said in the log.
fn complementarity_parameter(
    ctx: &Ctx,
    settings: &ContactSettings,
    b: &ContactBoundary,
    dim: usize,
) -> f64 {
    let c = match settings.newton.c {
        Some(c) => c,
        None => DEFAULT_C_FACTOR * b.stiffness,
    };
    say!(
        ctx,
        "newton: c = {c:.6e}{}",
        match (settings.newton.c, dim) {
            (Some(_), _) => String::new(),
            (None, 2) => format!(" ({DEFAULT_C_FACTOR} E)"),
            (None, _) => format!(" ({DEFAULT_C_FACTOR} E h_c)"),
        }
    );
    c
}

/// Runs the method of the case (Algorithm 1/2, Coulomb's generalised Newton or the fixed
/// point on Tresca thresholds (coulomb.rs), or SNES VI) to convergence; a run that does not
/// converge is [`RunError::NoConvergence`]. Returns the result, the fixed point's outer steps
/// and the condensed path's record; `types`: the Newton steps' KSP and PC types. Collective.
fn run_method(
    ctx: &Ctx,
    problem: &ContactProblem,
    ns: &NewtonSettings,
    choice: &MethodChoice,
    session: &mut Session,
    warm: Option<&WarmStart>,
    types: &mut Option<(String, String)>,
) -> Result<Ran, RunError> {
    let (settings, solver_section) = (choice.settings, choice.section);
    let (sys, b, dim) = (problem.sys, problem.boundary, problem.mesh.dim);
    let (nr, outer_steps, condensed_summary) = match solver_section.method {
        Method::Newton => {
            let mortar = session.mortar_pc.as_ref();
            let mut reduced = ReducedSystem::new(ctx, sys, b, session.setup(), dim, mortar)?;
            *types = Some(reduced.solver_types()?);
            // Tresca on the Schur path: Coulomb's generalised Newton on the contact unknowns
            // with the thresholds b_k fixed (docs/friction.md)
            let tresca_condensed = settings.tresca && choice.path == Some(SolverPath::Schur);
            let coulomb_algorithm = match settings.coulomb {
                Some((_, algorithm)) => Some(algorithm),
                None => tresca_condensed.then_some(CoulombAlgorithm::Newton),
            };
            let outcome = match coulomb_algorithm {
                Some(algorithm) => coulomb::solve(
                    ctx,
                    problem,
                    &mut reduced,
                    ns,
                    coulomb::CoulombMethod {
                        algorithm,
                        section: solver_section,
                    },
                    session,
                    warm,
                )?,
                None => normal_and_tresca(ctx, problem, &mut reduced, ns, choice, session, warm)?,
            };
            match outcome {
                Outcome::Checked(nr, cs) => return Ok((nr, None, cs)),
                Outcome::Iterated(nr, outer, cs) => (nr, outer, cs),
            }
        }
        Method::SnesVi => {
            let f_local = sys.b.to_local_vec()?;
            let nr = session
                .setup()
                .scoped(|| snesvi_solve(ctx, problem, &f_local, settings.rigid_modes))??;
            (nr, None, None)
        }
    };
    if !nr.converged {
        return Err(RunError::NoConvergence(match solver_section.method {
            Method::Newton => format!(
                "Newton did not converge in newton.max_steps = {} steps ({}){}",
                settings.newton.max_steps,
                last_step_state(nr.history.last(), settings.newton.tol_u),
                if solver_section.preset == crate::case::Preset::Iterative {
                    // a Tresca strip at c = 1e9 on the iterative preset: the sets kept changing
                    // for 100 steps where the direct preset (and solver.rtol = 1e-13) converged
                    // in 8
                    format!(
                        "; the iterative preset's inexact steps can keep the sets from settling \
                         (solver.rtol = {:e}): a tighter solver.rtol or solver.preset = \
                         \"direct\" may converge",
                        solver_section.rtol
                    )
                } else {
                    String::new()
                }
            ),
            Method::SnesVi => format!("SNES VI did not converge in {} steps", nr.steps),
        }));
    }
    Ok((nr, outer_steps, condensed_summary))
}

/// The path a Newton solve takes first (`None`: SNES VI): the Schur path where `solver.path`
/// allows it (not "plain"), the solver factorises and the contact boundary has 1 to
/// [`MAX_CONTACT_NODES`](crate::tuning::MAX_CONTACT_NODES) nodes, for frictionless contact,
/// Coulomb's generalised Newton and Tresca from newton.init = "auto" (coulomb.rs decides the
/// same, and sends Tresca beyond the dense limits to the plain path); else the plain path
/// (Coulomb's fixed point, another newton.init). The case reader refuses `solver.path =
/// "schur"` where the case file says it cannot run. Local.
fn chosen_path(
    settings: &ContactSettings,
    section: &SolverSection,
    b: &ContactBoundary,
    kind: SolverKind,
) -> Option<SolverPath> {
    let applies = match settings.coulomb {
        Some((_, algorithm)) => {
            algorithm == CoulombAlgorithm::Newton && settings.newton.init == NewtonInit::Auto
        }
        None if settings.tresca => settings.newton.init == NewtonInit::Auto,
        None => true,
    };
    let schur = applies
        && section.path.allows_schur()
        && b.n_global > 0
        && b.n_global <= crate::tuning::MAX_CONTACT_NODES
        && kind.factorises();
    match section.method {
        Method::SnesVi => None,
        Method::Newton if schur => Some(SolverPath::Schur),
        Method::Newton => Some(SolverPath::Plain),
    }
}

/// What [`run_method`] returns: the result, the fixed point's outer steps and the condensed
/// path's record.
type Ran = (NewtonResult, Option<usize>, Option<schur::CondensedSummary>);

/// Algorithm 1 (frictionless: on the contact unknowns where the dispatch chose the Schur
/// path, [`chosen_path`]) or Algorithm 2 (Tresca) on the plain path (where the dispatch did
/// not choose the Schur path for it: that one runs in coulomb.rs). Collective.
fn normal_and_tresca(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &mut ReducedSystem,
    ns: &NewtonSettings,
    choice: &MethodChoice,
    session: &mut Session,
    warm: Option<&WarmStart>,
) -> Result<Outcome, RunError> {
    let (friction, solver_section) = (choice.settings.friction(), choice.section);
    let mut condensed_summary = None;
    if choice.path == Some(SolverPath::Schur) {
        match schur::frictionless::solve(ctx, problem, reduced, ns, session, warm)? {
            schur::Condensed::Solved(nr, s) => {
                return Ok(Outcome::Checked(*nr, Some(s)));
            }
            schur::Condensed::Fallback(s) if s.too_wide => {
                // a zone too wide for the dense compliance: the plain path from the
                // half-space model's set, the model correcting each exact step's update
                let wide = NewtonSettings {
                    halfspace: ns.model,
                    ..*ns
                };
                plain_path::enable_reuse(ctx, ns, solver_section, reduced, false)?;
                let nr = plain_path::semismooth_newton(ctx, problem, reduced, &wide, warm)?;
                return Ok(Outcome::Checked(nr, Some(s)));
            }
            schur::Condensed::Fallback(s) | schur::Condensed::Factorised(s) => {
                condensed_summary = Some(s)
            }
        }
    }
    plain_path::enable_reuse(ctx, ns, solver_section, reduced, friction)?;
    let nr = plain_path::semismooth_newton(ctx, problem, reduced, ns, warm)?;
    Ok(Outcome::Iterated(nr, None, condensed_summary))
}

/// The floor of the scales the final check judges a load step by: the step before's. A step
/// whose solution vanishes against the step before's (its load or the obstacle taken back to
/// nothing) is computed from that step's state — a warm start, and on the iterative preset
/// solves whose residual falls by `solver.rtol` relative to that start's — so its violations
/// are of the step before's size times round-off or rtol, not of its own vanishing forces.
/// Judged by `VANISHING` (1e-6) of the step before's scales (the stopping rule's
/// floor), an obstacle lifted off a Tresca block on the iterative preset failed the check
/// with λ_n = 1.1e-13 against a force scale of 6.7e-11 (the step before's forces 1e-3), and
/// the direct preset warned at 4e-8. Local.
fn vanishing_floor(previous: Option<&ContactSolution>) -> Scales {
    previous.map_or(Scales::default(), |p| p.report.contact.scales)
}

/// What kept the last step of an unconverged iteration from stopping: nodes that changed
/// state, or (friction, no state changed) |Δu|/|u| at or above tol_u, or the residual. Local.
fn last_step_state(last: Option<&StepInfo>, tol_u: f64) -> String {
    match last {
        None => "no step".into(),
        Some(h) if h.changed > 0 => format!(
            "the sets still changing: {} node(s) in the last step",
            h.changed
        ),
        Some(h) => match h.du_rel {
            Some(du) if du >= tol_u => format!(
                "no state changed in the last step, but |Δu|/|u| = {du:.1e} ≥ newton.tol_u = \
                 {tol_u:e}"
            ),
            _ => format!(
                "no state changed in the last step, but the residual {:.1e} had not reached \
                 its tolerance",
                h.residual
            ),
        },
    }
}

/// summary.json's "newton" section; takes the step history out of `nr`.
fn newton_summary(
    settings: &ContactSettings,
    solver_section: &SolverSection,
    c: f64,
    nr: &mut NewtonResult,
    outer_steps: Option<usize>,
    previous: Option<&ContactSolution>,
) -> NewtonSummary {
    let factorisations = match solver_section.method {
        Method::Newton => nr
            .history
            .iter()
            .filter(|h| h.solve == step_system::SolveKind::Factorisation)
            .count(),
        // rsls factors every reduced system of its steps with the direct preset
        Method::SnesVi if solver_section.preset == Preset::Direct => nr.steps,
        Method::SnesVi => 0,
    };
    let pc_setups = nr.history.iter().any(|h| h.amg.is_some()).then(|| {
        nr.history
            .iter()
            .filter_map(|h| h.amg.as_ref())
            .map(|a| usize::from(a.pc_setup))
            .sum()
    });
    NewtonSummary {
        method: solver_section.method.name(),
        path: None,
        algorithm: if settings.friction() { 2 } else { 1 },
        init: settings.newton.init.name(),
        c,
        c_default: settings.newton.c.is_none(),
        steps: nr.steps,
        factorisations,
        pc_setups,
        converged: nr.converged,
        history: std::mem::take(&mut nr.history),
        rows_seconds: nr.rows_seconds,
        lambda_seconds: nr.lambda_seconds,
        pinned_dofs: nr.pinned_final.len(),
        on_cycle: settings.newton.on_cycle.name(),
        cycle_detected_at: nr.cycle_detected_at,
        condensed: None,
        coulomb: settings.coulomb.map(|(mu, algorithm)| CoulombSummary {
            mu,
            algorithm: algorithm.name(),
            outer_steps,
            warm_start: previous.is_some(),
        }),
    }
}

/// A warm start from the previous load step: its u_τ becomes every contact node's reference
/// (friction acts on the increment), moved along with the obstacle's tangential displacement
/// since then (`displacement` = each pair's d of this solve; the slip is relative to the obstacle:
/// u_τ − u_τ^prev − (d − d_prev)_τ); returns
/// this rank's rows of its u. The previous solution must be of the same mesh and boundary.
/// Collective.
fn take_reference(
    ctx: &Ctx,
    b: &mut ContactBoundary,
    prev: &ContactSolution,
    friction: bool,
    displacement: &[[f64; 3]],
) -> Result<Vec<f64>, RunError> {
    let u = prev.u.to_local_vec()?;
    let same = prev.nodes.len() == b.nodes.len()
        && b.nodes
            .last()
            .is_none_or(|k| k.local_row + k.frame.dim <= u.len());
    ctx.agree(if same {
        Ok(())
    } else {
        Err(RunError::Failed(format!(
            "internal error: the previous load step's solution has {} contact nodes on this \
             rank, the boundary {} (not the same mesh and boundary)",
            prev.nodes.len(),
            b.nodes.len()
        )))
    })?;
    if friction {
        for (k, r) in b.nodes.iter_mut().zip(&prev.nodes) {
            let dd = crate::geom::sub(displacement[k.pair], prev.obstacle_displacement[k.pair]);
            let t = &k.frame.t;
            k.u_t_ref = [
                r.u_t[0] + crate::geom::dot(dd, t[0]),
                r.u_t[1] + crate::geom::dot(dd, t[1]),
            ];
        }
    }
    Ok(u)
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
    let mut set = ActiveSet::frictionless(vec![false; b.nodes.len()]);
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
        approach: Vec::new(),
        stop: certificate::StopRule::SnesVi,
    })
}

fn log_boundary(ctx: &Ctx, b: &ContactBoundary, settings: &ContactSettings, dim: usize) {
    let several = settings.pairs.len() > 1;
    if several {
        say!(
            ctx,
            "contact: {} nodes in {} pairs{}",
            b.n_global,
            settings.pairs.len(),
            excluded_note(b)
        );
    }
    for (p, pair) in settings.pairs.iter().enumerate() {
        let nodes = if several {
            ctx.sum_usize(b.nodes.iter().filter(|k| k.pair == p).count())
        } else {
            b.n_global
        };
        say!(
            ctx,
            "contact{}: {nodes} nodes on '{}'{}{}",
            if several {
                format!(" ({})", pair.key)
            } else {
                String::new()
            },
            pair.group,
            if several {
                String::new()
            } else {
                excluded_note(b)
            },
            match (&pair.motion, &pair.force) {
                (Some(_), _) => format!(", obstacle moved by {:?}", &pair.displacement[..dim]),
                (_, Some(_)) => format!(", obstacle pressed by {:?}", &pair.force_now[..dim]),
                _ => String::new(),
            }
        );
    }
}

/// " (n more left to their Dirichlet data)", or nothing.
fn excluded_note(b: &ContactBoundary) -> String {
    if b.excluded_dirichlet > 0 {
        format!(
            " ({} more left to their Dirichlet data)",
            b.excluded_dirichlet
        )
    } else {
        String::new()
    }
}
