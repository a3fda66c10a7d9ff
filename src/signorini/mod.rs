//! The distributed contact algorithm (MPI + PETSc): the contact boundary c_h, the sets and
//! iterates of Algorithms 1 and 2, the reduced systems (3.29)/(3.42), the free rigid modes,
//! the cycle guard, the Newton loop and the report of the final state. The pointwise contact
//! law it applies lives in `crate::contact` (pure, no MPI).
//!
//! Floors inside: `cycle`, `boundary` → `rigid`, `active_set`, `report` → `reduced` →
//! `newton` → this file's [`solve`].

pub mod active_set;
pub mod boundary;
pub mod certificate;
pub mod condensed;
pub mod coulomb_condensed;
pub mod cycle;
pub mod dense;
pub mod force;
pub mod newton;
pub mod predictor;
pub mod reduced;
pub mod report;
pub mod rigid;
pub mod snesvi;
pub mod warn;

use crate::assembly::System;
use crate::case::{self, CoulombAlgorithm, Method, Preset, Reuse, SolverSection};
use crate::contact::Obstacle;
use crate::error::RunError;
use crate::linsolve::{LinearSetup, SolverKind};
use crate::mesh::Mesh;
use crate::output::ContactResult;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::Vector;
use crate::say;
use crate::setup::ContactSettings;
use crate::solver;
use crate::warnings::Warning;
use active_set::{ActiveSet, Iterate, Law};
use boundary::{ContactBoundary, NodeResult};
use newton::{ContactProblem, NewtonResult, NewtonSettings, StepInfo, WarmStart};
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
    pub condensed: Option<condensed::CondensedSummary>,
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

/// summary.json's "contact" section.
#[derive(Debug, Clone, Serialize)]
pub struct ContactSummary {
    pub nodes: usize,
    pub excluded_dirichlet: usize,
    pub active_count: usize,
    pub max_pressure: f64,
    pub total_force: Vec<f64>,
    /// A moving obstacle (`contact.motion`): its displacement d in this solve.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub obstacle_displacement: Option<Vec<f64>>,
    /// Force control (`contact.force`): the approach δ solved for (the obstacle moved by
    /// δ F/|F|).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub approach: Option<f64>,
    pub half_width: Option<f64>,
    /// Several contact pairs: each pair's numbers (the fields above are over all pairs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pairs: Option<Vec<report::PairSummary>>,
    pub kkt: Kkt,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<FrictionCertificate>,
    /// The problem's scales the certificates were judged by (not written).
    #[serde(skip)]
    pub scales: Scales,
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
    /// The condensed solve's factorisation, compliance and candidates, for the next load step
    /// (taken by it).
    kept: KeptFactor,
    /// The warnings of this solve (docs/warnings.md; the same on every rank, not logged yet).
    pub warnings: Vec<Warning>,
}

/// A condensed solve's factorisation of K_p with its Schur complement, compliance and
/// candidates ([`condensed::Kept`]; frictionless or Coulomb), handed from one load step to the
/// next: K_p does not change between load steps, so the next step reuses it where the
/// candidates' frames and the pins are the same (`Kept::holds`). Empty unless the last step
/// was solved on the contact unknowns.
#[derive(Default)]
pub struct KeptFactor {
    kept: std::cell::RefCell<Option<condensed::Kept>>,
    /// Rank 0: the nested-dissection order of K_p's node graph (the same graph in every load
    /// step), where the step kept no factorisation with it (a frictionless step that held a
    /// wide zone, or a held zone's pass before).
    order: std::cell::RefCell<Option<Vec<usize>>>,
}

/// A located contact zone (predictor::locate): this rank's clearances and the nodes the model
/// puts in contact; `None` where the model did not converge.
pub(crate) type Located = Option<(Vec<f64>, usize)>;

impl ContactSolution {
    /// Drops the factorisation kept for a next load step (none follows).
    pub fn release_factor(&self) {
        drop(self.kept.take());
    }
}

impl KeptFactor {
    fn take(&self) -> Option<condensed::Kept> {
        self.kept.borrow_mut().take()
    }

    fn put(&self, kept: condensed::Kept) {
        *self.kept.borrow_mut() = Some(kept);
    }

    /// No factorisation is kept (the previous load step ran the plain path, or there was
    /// none).
    fn is_empty(&self) -> bool {
        self.kept.borrow().is_none()
    }

    /// The kept factorisation holds a wide zone's interior (friction: sticking).
    fn holds_zone(&self) -> bool {
        let kept = self.kept.borrow();
        kept.as_ref().is_some_and(|k| k.held.iter().any(|&h| h))
    }

    fn take_order(&self) -> Option<Vec<usize>> {
        self.order.borrow_mut().take()
    }

    fn put_order(&self, order: Option<Vec<usize>>) {
        *self.order.borrow_mut() = order;
    }
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
    (nodes, displacement): (&[NodeResult], &[[f64; 3]]),
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
    let dim = mesh.dim;
    let law = law_of(settings);
    let friction = settings.friction();
    let (mut b, mut warned) = contact_boundary(ctx, settings, mesh, layout, fixed)?;
    b.keys.solver = solver_keys(solver_section);
    let force_control = force_control(settings, previous);
    check_friction_capacity(ctx, &b, (fixed, sys, dim), law, &force_control)?;
    let displacements = settings.displacements();
    let prev_u = (previous.map(|prev| take_reference(ctx, &mut b, prev, friction, &displacements)))
        .transpose()?;
    let setup = LinearSetup::for_section(
        ctx,
        (mesh, layout),
        solver_section,
        symmetric_rows(settings, dim),
        solver::matrix_scale(ctx, &sys.a)?,
    )?;
    let c = complementarity_parameter(ctx, settings, &b, dim);
    // the start: the previous step's solution, or its extrapolation along its own increment
    // (under force control against the obstacles where the previous step left them)
    let at_start = (!force_control.is_empty()).then(|| {
        let mut placed = b.clone();
        force::Approach::new(&b, &force_control).place(&mut placed);
        placed
    });
    let start = previous
        .zip(prev_u.clone())
        .map(|(prev, u)| prev.start(at_start.as_ref().unwrap_or(&b), u, c));
    let warm = previous
        .zip(start.as_ref())
        .map(|(prev, (nodes, u))| WarmStart {
            nodes: nodes.as_deref().unwrap_or(&prev.nodes),
            u_local: u,
        });
    let kept = KeptFactor {
        kept: std::cell::RefCell::new(previous.and_then(|p| p.kept.take())),
        order: std::cell::RefCell::new(previous.and_then(|p| p.kept.take_order())),
    };
    let located = std::cell::RefCell::new(None);
    let problem = ContactProblem {
        mesh,
        layout,
        boundary: &b,
        fixed,
        sys,
        kept: &kept,
        located: &located,
    };
    // the body's half-space model: the predictor's on the iterative preset (frictionless,
    // newton.rs), else the condensed path's (locating a floating body's zone; the plain path's
    // first set where the zone is too wide for the dense limits)
    let iterative = setup.kind() == SolverKind::Iterative;
    let model = predictor::HalfSpace {
        modulus: settings.contact_modulus,
        dim,
        length: 2.0 * mesh.extent(),
        mirrors: predictor::mirror_planes(ctx, mesh, fixed),
    };
    let ns = NewtonSettings {
        section: &settings.newton,
        c,
        law,
        rigid: settings.rigid_modes,
        halfspace: (!friction && iterative).then_some(&model),
        estimate: false,
        carried: None,
        model: (!iterative).then_some(&model),
        force: &force_control,
    };
    // a failure of a frictional body that only its contact holds says what may be the cause
    let sliding = friction && !held_anywhere(ctx, fixed);
    let mut types = None;
    let (mut nr, outer_steps, condensed_summary) = run_method(
        ctx,
        &problem,
        &ns,
        (settings, solver_section),
        (&setup, warm.as_ref()),
        &mut types,
    )
    .map_err(|e| why_sliding(e, sliding))?;
    if law == Law::Coulomb {
        // The certificate and the output judge Coulomb's law with b_k = μ(−λ_n^k).
        coulomb_bounds(&mut b, &nr.nodes);
    }
    let (displacement, approaches) =
        place_at_approaches(&mut b, settings, (&force_control, &nr.approach), friction);
    let floor = vanishing_floor(previous); // the step before's scales, for a vanishing step
    let (mut contact, table) = final_state(ctx, sys, &b, &nr, (friction, dim), floor)?;
    report::per_pair(
        ctx,
        settings,
        &b,
        &nr.nodes,
        &table,
        (&displacement, &approaches),
        &mut contact,
    );
    let certificate = certify(
        ctx,
        (settings, mesh, layout, fixed, sys),
        (&b, &table, &contact),
        &nr,
        &force_control,
    )?;
    let mut newton = newton_summary(settings, solver_section, c, &mut nr, outer_steps, previous);
    if let Some(cs) = condensed_summary {
        // K_p's with the Schur complement, one per round of candidates (the dense steps
        // factorise nothing sparse)
        newton.factorisations += cs.factorisations;
        newton.condensed = Some(cs);
    }
    warned.extend(warn::contact_warnings(
        ctx,
        (mesh, layout, settings),
        &b,
        &nr.nodes,
        &displacement,
    ));
    let delta = match previous.zip(prev_u) {
        Some((prev, u_prev)) => Some(step_delta(
            prev,
            (&nr.nodes, &displacement),
            &nr.u.to_local_vec()?,
            &u_prev,
        )),
        None => None,
    };
    Ok(ContactSolution {
        result: report::contact_result(
            ctx,
            (mesh, layout, settings),
            &b,
            &nr.nodes,
            friction,
            &table,
        ),
        u: nr.u,
        report: ContactReport {
            newton,
            contact,
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
        obstacle_displacement: displacement,
        kept,
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
    let (b, warned) = boundary::build(ctx, mesh, layout, settings, fixed)?;
    log_boundary(ctx, &b, settings, mesh.dim);
    // the approaches' starts do not matter here: only the forces' directions
    if let Some(fc) = force::unreached(ctx, &b, &force_control(settings, None)) {
        return Err(force::never_touches(fc));
    }
    Ok((b, warned))
}

/// The linear solver's keys of a case with their values, for the diagnoses.
fn solver_keys(s: &SolverSection) -> String {
    let mut keys = vec![format!("'solver.preset' = \"{}\"", s.preset.name())];
    if s.preset == Preset::Iterative {
        keys.push(format!("'solver.rtol' = {:e}", s.rtol));
    }
    if !s.petsc_options.trim().is_empty() {
        keys.push(format!(
            "'solver.petsc_options' = {:?}",
            s.petsc_options.trim()
        ));
    }
    keys.join(", ")
}

/// Force control's result on the boundary: every force-controlled pair's obstacle where its
/// approach δ put it (the gaps g0 − δ e·n and, with friction, the tangential references moved
/// along), for the certificates and the output. Returns every pair's obstacle displacement
/// and approach (`None` off force control). Local.
fn place_at_approaches(
    b: &mut ContactBoundary,
    settings: &ContactSettings,
    (force_control, approach): (&[force::ForceControl], &[f64]),
    friction: bool,
) -> (Vec<[f64; 3]>, Vec<Option<f64>>) {
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
    (displacement, approaches)
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

/// The complementarity parameter c: the case's, or E / h_c; said in the log. Collective.
fn complementarity_parameter(
    ctx: &Ctx,
    settings: &ContactSettings,
    b: &ContactBoundary,
    dim: usize,
) -> f64 {
    let c = match settings.newton.c {
        Some(c) => c,
        None => newton::default_c(ctx, b, dim, settings.young),
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
    c
}

/// The plain path's reuse of factorisations, one rule for every branch that enters it: force
/// control solves its lift on the step's own factorisation (force.rs), so a factorising
/// solver never reuses one under force control; the iterative preset's reuse of
/// preconditioners stays. Local.
fn plain_reuse(
    ns: &NewtonSettings,
    section: &SolverSection,
    reduced: &ReducedSystem,
) -> Result<Reuse, RunError> {
    Ok(if !ns.force.is_empty() && reduced.factorises()? {
        Reuse::Never
    } else {
        section.reuse
    })
}

/// Runs the method of the case (Algorithm 1/2 or Coulomb's generalised Newton, the fixed
/// point on Tresca thresholds, or SNES VI) to convergence; a run that does not converge is
/// [`RunError::NoConvergence`]. Returns the result and the fixed point's outer steps;
/// `types`: the Newton steps' KSP and PC types. Collective.
fn run_method(
    ctx: &Ctx,
    problem: &ContactProblem,
    ns: &NewtonSettings,
    (settings, solver_section): (&ContactSettings, &SolverSection),
    (setup, warm): (&LinearSetup, Option<&WarmStart>),
    types: &mut Option<(String, String)>,
) -> Result<
    (
        NewtonResult,
        Option<usize>,
        Option<condensed::CondensedSummary>,
    ),
    RunError,
> {
    let (sys, b, dim) = (problem.sys, problem.boundary, problem.mesh.dim);
    let mut outer_steps = None;
    let mut condensed_summary = None;
    let nr = match solver_section.method {
        Method::Newton => {
            let mut reduced = ReducedSystem::new(ctx, sys, b, setup, dim)?;
            *types = Some(reduced.solver_types()?);
            let friction = settings.friction();
            let condense = !friction
                && solver_section.reuse == Reuse::Auto
                && b.n_global > 0
                && b.n_global <= condensed::MAX_CONTACT_NODES
                && reduced.factorises()?;
            if condense {
                match condensed::solve(ctx, problem, &mut reduced, ns, warm)? {
                    condensed::Condensed::Solved(nr, s) => {
                        return Ok((*nr, None, Some(s)));
                    }
                    condensed::Condensed::Fallback(s) if s.too_wide => {
                        // a zone too wide for the dense compliance: the plain path from the
                        // half-space model's set, the model correcting each exact step's update
                        condensed_summary = Some(s);
                        let wide = NewtonSettings {
                            halfspace: ns.model,
                            ..*ns
                        };
                        let reuse = plain_reuse(ns, solver_section, &reduced)?;
                        reduced.enable_reuse(ctx, reuse, false)?;
                        let nr =
                            newton::semismooth_newton(ctx, problem, &mut reduced, &wide, warm)?;
                        return Ok((nr, None, condensed_summary));
                    }
                    condensed::Condensed::Fallback(s) | condensed::Condensed::Factorised(s) => {
                        condensed_summary = Some(s)
                    }
                }
            }
            let coulomb_newton = matches!(settings.coulomb, Some((_, CoulombAlgorithm::Newton)));
            if coulomb_newton && solver_section.reuse == Reuse::Always && reduced.factorises()? {
                say!(
                    ctx,
                    "newton: solver.reuse = \"always\" with Coulomb: its rows change the matrix \
                     in every step, so every Newton step factorises (\"auto\": Coulomb on the \
                     contact unknowns after one factorisation)"
                );
            }
            let start = if coulomb_newton && ns.section.init == case::NewtonInit::Auto {
                let (start, cs) =
                    coulomb_start(ctx, problem, &mut reduced, ns, solver_section, warm)?;
                condensed_summary = cs;
                start
            } else {
                Begin::Touching
            };
            if let Begin::Solved(nr) = start {
                return Ok((nr, None, condensed_summary));
            }
            let reuse = plain_reuse(ns, solver_section, &reduced)?;
            reduced.enable_reuse(ctx, reuse, friction)?;
            match settings.coulomb {
                Some((_, CoulombAlgorithm::FixedPoint)) => {
                    let (nr, outer) = fixed_point(ctx, problem, &mut reduced, ns, warm)?;
                    outer_steps = Some(outer);
                    nr
                }
                _ => match start {
                    Begin::Start(first, u) => {
                        let w = WarmStart {
                            nodes: &first.nodes,
                            u_local: &u,
                        };
                        // under force control from the start's approaches
                        let force = force::starting_at(ns.force, &first.approach);
                        let ns = NewtonSettings {
                            force: &force,
                            ..*ns
                        };
                        let mut nr =
                            newton::semismooth_newton(ctx, problem, &mut reduced, &ns, Some(&w))?;
                        // the start's steps first in the record (and their factorisations)
                        after(first.history, &mut nr);
                        nr
                    }
                    _ => newton::semismooth_newton(ctx, problem, &mut reduced, ns, warm)?,
                },
            }
        }
        Method::SnesVi => {
            let f_local = sys.b.to_local_vec()?;
            setup.scoped(|| snesvi_solve(ctx, problem, &f_local, settings.rigid_modes))??
        }
    };
    if !nr.converged {
        return Err(RunError::NoConvergence(match solver_section.method {
            Method::Newton => format!(
                "Newton did not converge in newton.max_steps = {} steps ({})",
                settings.newton.max_steps,
                last_step_state(nr.history.last(), settings.newton.tol_u)
            ),
            Method::SnesVi => format!("SNES VI did not converge in {} steps", nr.steps),
        }));
    }
    Ok((nr, outer_steps, condensed_summary))
}

/// The floor of the scales the final check judges a load step by: a step whose solution
/// vanishes against the step before's (its load taken back to nothing) is judged against
/// [`newton::VANISHING`] of that step's scales, as its stopping rule is. Local.
fn vanishing_floor(previous: Option<&ContactSolution>) -> Scales {
    previous.map_or(Scales::default(), |p| {
        let s = p.report.contact.scales;
        Scales {
            force: newton::VANISHING * s.force,
            length: newton::VANISHING * s.length,
        }
    })
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

/// The final state: the contact table, the KKT and friction certificates (an error if they
/// fail), the contact line of the log and summary.json's "contact" section. Collective.
fn final_state(
    ctx: &Ctx,
    sys: &System,
    b: &ContactBoundary,
    nr: &NewtonResult,
    (friction, dim): (bool, usize),
    floor: Scales,
) -> Result<(ContactSummary, report::Table), RunError> {
    let table = report::gather(ctx, b, &nr.nodes, dim);
    let total_force = report::total_force(ctx, &nr.nodes);
    let half_width = match b.obstacles.as_slice() {
        [one] => table.half_width(one, None),
        _ => None,
    };
    let (scales, kkt, friction_certificate) =
        certificates(ctx, sys, &table, &nr.u, friction, floor)?;
    check_certificates(ctx, &kkt, friction_certificate.as_ref(), &scales, &b.keys)?;
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
    let contact = ContactSummary {
        nodes: b.n_global,
        excluded_dirichlet: b.excluded_dirichlet,
        active_count: table.active_count(),
        max_pressure: table.max_pressure(),
        total_force: total_force[..dim].to_vec(),
        obstacle_displacement: None,
        approach: None,
        half_width,
        pairs: None,
        kkt,
        friction: friction_certificate,
        scales,
    };
    Ok((contact, table))
}

/// The final state's certificate (certificate.rs): the stop rule, (3.14), (3.18), the global
/// equilibrium and each force-controlled pair's balance, said in one log line; with
/// `newton.strict` an error where the rule is loosened or a relative value above
/// [`certificate::STRICT_TOL`]. Collective.
fn certify(
    ctx: &Ctx,
    (settings, mesh, layout, fixed, sys): (&ContactSettings, &Mesh, &Layout, &[f64], &System),
    (b, table, contact): (&ContactBoundary, &report::Table, &ContactSummary),
    nr: &NewtonResult,
    force_control: &[force::ForceControl],
) -> Result<certificate::Certificate, RunError> {
    let (equilibrium, lambdas) = certificate::equilibrium(
        ctx,
        (mesh, layout, &settings.material),
        fixed,
        sys,
        b,
        &nr.u,
    )?;
    let force_balance = (!force_control.is_empty())
        .then(|| certificate::force_balance(ctx, b, &lambdas, force_control));
    let cert = certificate::Certificate::new(certificate::Parts {
        stop: nr.stop,
        strict: settings.newton.strict,
        kkt: &contact.kkt,
        friction: contact.friction.as_ref(),
        scales: &contact.scales,
        mesh_size: table.mesh_size(),
        equilibrium,
        force_balance,
    });
    say!(ctx, "{}", cert.line());
    match cert.strict_failure().filter(|_| cert.strict) {
        Some(why) => Err(RunError::Failed(why)),
        None => Ok(cert),
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
            .filter(|h| h.solve == reduced::SolveKind::Factorisation)
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

/// The reduced systems of the case are symmetric: frictionless (3.29) and, in 2D, Tresca's
/// (3.42) (also the fixed point's inner Tresca solves), both applied symmetrically — a 2D slip
/// row adds the scalar spring L̃ ≥ 0 of (3.39b) to its node's own tangential diagonal. Not
/// Coulomb's generalised Newton (its row mix (F7)) nor 3D Tresca (a 2 × 2 L̃ that is not
/// symmetric). The direct preset then factorises by LDLᵀ instead of LU.
fn symmetric_rows(settings: &ContactSettings, dim: usize) -> bool {
    match settings.coulomb {
        Some((_, CoulombAlgorithm::Newton)) => false,
        _ => !settings.friction() || dim == 2,
    }
}

/// The tangential law of the settings (the fixed point's inner solves are Tresca solves).
fn law_of(settings: &ContactSettings) -> Law {
    match (settings.tresca, settings.coulomb) {
        (true, _) => Law::Tresca,
        (false, Some(_)) => Law::Coulomb,
        (false, None) => Law::Frictionless,
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

/// Coulomb by the fixed point on Tresca thresholds (docs/friction.md (a)):
/// b^{m+1}_k = μ max(0, −λ_n^{k,m}), every outer step a Tresca solve (Algorithm 2) warm-started
/// from the previous one (b^0 from the warm start's λ_n, else ‖f‖₁: all stick); stop when
/// max_k |b^{m+1} − b^m| ≤ [`FIXED_POINT_TOL`] · max_k b^{m+1}. Under force control every
/// Tresca solve is force-controlled (force.rs), from the previous one's approaches. Returns
/// the last Tresca result with the history and step count of all outer steps, and the number
/// of outer steps. Collective.
fn fixed_point(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    ns: &NewtonSettings,
    warm: Option<&WarmStart>,
) -> Result<(NewtonResult, usize), RunError> {
    // under force control each Tresca solve starts from the approaches of the previous one
    let mut force = ns.force.to_vec();
    let mut b = p.boundary.clone();
    let mut state: Option<(Vec<NodeResult>, Vec<f64>)> =
        warm.map(|w| (w.nodes.to_vec(), w.u_local.to_vec()));
    // each node's μ: its pair's
    let threshold = |k: &boundary::ContactNode, r: &NodeResult| k.mu * (-r.lambda_n).max(0.0);
    // b^0 without a warm start: ‖f‖₁, beyond any nodal friction force, so the first solve
    // sticks (b^0 = 0 would leave a free body with a tangential load without support).
    let stick_all = ctx.sum_f64(reduced.f_local.iter().map(|x| x.abs()).sum());
    for (i, k) in b.nodes.iter_mut().enumerate() {
        k.bound = state
            .as_ref()
            .map_or(stick_all, |(n, _)| threshold(&*k, &n[i]));
    }
    let mut history: Vec<StepInfo> = Vec::new();
    let mut stop = certificate::StopRule::ActiveSet;
    for outer in 1..=ns.section.max_steps {
        let pm = ContactProblem { boundary: &b, ..*p };
        let start = state
            .as_ref()
            .map(|(nodes, u)| WarmStart { nodes, u_local: u });
        let tresca = NewtonSettings {
            law: Law::Tresca,
            force: &force,
            ..*ns
        };
        let mut nr = newton::semismooth_newton(ctx, &pm, reduced, &tresca, start.as_ref())?;
        stop = stop.worse(nr.stop);
        nr.stop = stop;
        for (fc, &delta) in force.iter_mut().zip(&nr.approach) {
            fc.start = delta;
        }
        for h in &nr.history {
            let mut h = h.clone();
            h.step = history.len() + 1;
            history.push(h);
        }
        let (mut change, mut scale) = (0.0f64, 0.0f64);
        for (k, r) in b.nodes.iter_mut().zip(&nr.nodes) {
            let next = threshold(&*k, r);
            change = change.max((next - k.bound).abs());
            scale = scale.max(next);
            k.bound = next;
        }
        let (change, scale) = (ctx.max_f64(change), ctx.max_f64(scale));
        say!(
            ctx,
            "fixed point {outer:3}: {} Newton steps, max |b^(m+1) - b^m| = {change:.3e} \
             (max b = {scale:.3e})",
            nr.steps
        );
        let done = change <= FIXED_POINT_TOL * scale;
        if !nr.converged || done {
            nr.converged &= done;
            nr.steps = history.len();
            nr.history = history;
            return Ok((nr, outer));
        }
        let u = nr.u.to_local_vec()?;
        state = Some((nr.nodes, u));
    }
    Err(RunError::NoConvergence(format!(
        "the fixed point on Tresca thresholds did not converge in newton.max_steps = {} outer \
         steps",
        ns.section.max_steps
    )))
}

/// `r`'s steps after `first` in its record (numbered on). Local.
fn after(first: Vec<StepInfo>, r: &mut NewtonResult) {
    let mut history = first;
    for mut h in std::mem::take(&mut r.history) {
        h.step += history.len();
        history.push(h);
    }
    r.steps = history.len();
    r.history = history;
}

/// How Coulomb's generalised Newton begins (`coulomb_start`).
enum Begin {
    /// Solved on the contact unknowns and checked on every contact node (coulomb_condensed).
    Solved(NewtonResult),
    /// A start for the plain path: the records of every contact node, this rank's rows of u.
    Start(NewtonResult, Vec<f64>),
    /// The touching nodes (`ActiveSet::initial`), or the warm start of a load step.
    Touching,
}

/// The start of Coulomb's generalised Newton under newton.init = "auto" (no warm start) where
/// the condensed path applies (direct preset): the frictionless solution of the same case by
/// the condensed path (about one factorisation; the pins carry a load in the modes only
/// friction can hold, e.g. a tangential load on a floating body). For a body that Dirichlet
/// data hold, the Schur complement takes every dof of the candidates and Coulomb's iteration
/// runs on them (coulomb_condensed): its checked result, or its expanded iterate as the plain
/// path's start. Else (or if that gives up) the frictionless active set and λ_n give the
/// thresholds b = μ(−λ_n) of (F1), every active node sticking — instead of a start from the
/// touching nodes, where the whole load first hangs on them and the set needs many steps to
/// shrink. Where friction alone holds a part of the load (the body rolls), the frictionless
/// estimate carries that part by a tangential force at the contact and the half-space model
/// locates the zone the candidates are taken from (`Unheld`, docs/friction.md). `Touching`
/// (said in the log) where the condensed path does not find a frictionless set; where it does
/// not apply (the iterative preset), [`iterative_start`]. A load step (`warm`) tries the
/// condensed iteration alone (the frictionless set from the warm one; references u_τ^ref of
/// the previous step) and otherwise keeps its warm start.
/// Under force control the dense Coulomb iteration takes the approaches as unknowns (a held
/// body); on a body that only its pairs hold the start is the frictionless force-controlled
/// solution, every active node sticking, at its approaches (the `approach` of the returned
/// start), and a load step keeps its warm start.
/// Returns the beginning and the condensed path's record. Collective.
fn coulomb_start(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &mut ReducedSystem,
    ns: &NewtonSettings,
    solver_section: &SolverSection,
    warm: Option<&WarmStart>,
) -> Result<(Begin, Option<condensed::CondensedSummary>), RunError> {
    let fl = NewtonSettings {
        law: Law::Frictionless,
        halfspace: None,
        estimate: true,
        ..*ns
    };
    let b = problem.boundary;
    let condense = solver_section.reuse == Reuse::Auto
        && b.n_global > 0
        && b.n_global <= condensed::MAX_CONTACT_NODES
        && reduced.factorises()?;
    if !condense {
        return iterative_start(ctx, problem, reduced, ns, warm);
    }
    let from = if warm.is_some() {
        "the previous load step"
    } else {
        "the touching nodes"
    };
    // the body's free modes (one construction: both tests below read them)
    let free = free_modes(ctx, problem, reduced, ns);
    // a load that friction alone holds: the frictionless estimate carries it at the contact
    let carried = Unheld::of(ctx, b, &free).map(|un| {
        say!(
            ctx,
            "coulomb: {}; the frictionless estimate carries it by a tangential force at the \
             contact",
            un.why()
        );
        un.carried_at_contact(ctx, b, &free)
    });
    let fl = NewtonSettings {
        carried: carried.as_deref(),
        ..fl
    };
    // force control on a body that only its pairs hold: the plain path (the dense Coulomb
    // iteration takes the approaches as unknowns next to a held body's contact unknowns)
    let forced = !ns.force.is_empty() && free.floats();
    if forced {
        say!(
            ctx,
            "coulomb: force control on a body that only its pairs hold: the plain path"
        );
    }
    if let Some(w) = warm {
        if forced {
            drop(problem.kept.take()); // no Coulomb step uses a kept factorisation here
            return Ok((Begin::Touching, None));
        }
        return coulomb_load_step(ctx, problem, reduced, (ns, &fl), w);
    }
    let (mut nr, summary) = match coulomb_passes(ctx, problem, reduced, (ns, &fl), (forced, from))?
    {
        Passes::Done(begin, summary) => return Ok((begin, summary)),
        Passes::Frictionless(nr, summary) => (nr, summary),
    };
    say!(
        ctx,
        "coulomb: start from the frictionless solution, every active node sticking"
    );
    let u = nr.u.to_local_vec()?;
    // under force control the references where the frictionless approaches put the obstacles
    let placed = force::placed(b, &force::starting_at(ns.force, &nr.approach));
    sticking(&mut nr.nodes, &placed);
    Ok((Begin::Start(nr, u), Some(summary)))
}

/// What the condensed passes of a Coulomb start end in.
enum Passes {
    /// The start's outcome: solved, a start for the plain path, or none (the touching nodes).
    Done(Begin, Option<condensed::CondensedSummary>),
    /// The frictionless solution (the condensed Coulomb iteration does not apply or gave up).
    Frictionless(NewtonResult, condensed::CondensedSummary),
}

/// [`coulomb_start`] on the condensed path: the frictionless solution by the condensed path
/// (`fl`; every dof of the candidates in the Schur complement, or, where the zone is too wide
/// for that, its interior held sticking in K_p), then Coulomb's iteration on its candidates
/// (coulomb_condensed). Where a held zone's check finds nodes beyond the candidates changing
/// state, a new pass takes them as candidates (at most [`MAX_STICK_FACTORISATIONS`]
/// factorisations in all, while fewer change each pass). `forced`: force control on a body
/// that only its pairs hold (the frictionless solution alone); `from`: the start said where
/// there is none. Collective.
fn coulomb_passes(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &mut ReducedSystem,
    (ns, fl): (&NewtonSettings, &NewtonSettings),
    (forced, from): (bool, &str),
) -> Result<Passes, RunError> {
    let dim = problem.mesh.dim;
    // errors are agreed: every rank takes the same branch
    // the Coulomb iteration on the candidates needs every dof of them, the plain path none
    let per = if forced { 1 } else { dim };
    let too_wide = |t: &Result<_, RunError>| {
        let fell = |s: &condensed::CondensedSummary| s.factorisations == 0;
        matches!(t, Ok((condensed::Condensed::Fallback(s), _)) if fell(s))
    };
    // where the zone is too wide for every dof of its nodes: the nodes a held zone releases
    let mut passes = PassLoop::new(Vec::new(), Vec::new());
    // the expanded iterate of the last pass: the plain path's start where the next one fails
    let mut last: Option<(NewtonResult, Vec<f64>, condensed::CoulombCondensedSummary)> = None;
    loop {
        // too many candidates' dofs for the dense tangential compliance: the predicted zone's
        // interior held sticking, the dense steps on its edge and beyond (condensed.rs)
        let held = (per > 1).then(|| {
            passes.sticking(match passes.pass {
                0 => FIRST_STICK_FACTORISATIONS,
                _ => MAX_STICK_FACTORISATIONS
                    .saturating_sub(passes.earlier)
                    .max(1),
            })
        });
        let mut tried =
            condensed::solve_keeping(ctx, problem, reduced, fl, None, (per, true, held));
        if let Some((r, u, cs)) = last.take() {
            // a later pass: its own frictionless solution, or the plain path from the pass
            // before
            let fell = match &tried {
                Ok((condensed::Condensed::Fallback(s), _))
                | Ok((condensed::Condensed::Factorised(s), _)) => Some(s.clone()),
                Err(RunError::Failed(_)) => Some(condensed::CondensedSummary::new(0)),
                _ => None, // solved, or an error every rank returns (below)
            };
            if let Some(mut summary) = fell {
                drop(problem.kept.take());
                summary.factorisations += passes.earlier;
                summary.coulomb = Some(cs);
                say!(
                    ctx,
                    "coulomb: the plain path from the last pass' expanded iterate"
                );
                return Ok(Passes::Done(Begin::Start(r, u), Some(summary)));
            }
        }
        if per > 1 && too_wide(&tried) {
            // no zone to hold: the candidates' normal dofs alone
            say!(
                ctx,
                "coulomb: the candidates' normal dofs alone in the Schur complement"
            );
            tried = condensed::solve_keeping(ctx, problem, reduced, fl, None, (1, true, None));
        }
        // a frictionless solve on the normal dofs alone keeps its factorisation for a next
        // load step, which no Coulomb step can use
        drop(problem.kept.take());
        let (mut nr, mut summary, kept) = match tried {
            Ok((condensed::Condensed::Solved(nr, s), kept)) => (*nr, s, kept),
            Ok((condensed::Condensed::Fallback(s), _))
            | Ok((condensed::Condensed::Factorised(s), _)) => {
                say!(ctx, "coulomb: no frictionless start; starting from {from}");
                return Ok(Passes::Done(Begin::Touching, Some(s)));
            }
            Err(RunError::Failed(why)) => {
                say!(
                    ctx,
                    "coulomb: no frictionless start ({why}); starting from {from}"
                );
                return Ok(Passes::Done(Begin::Touching, None));
            }
            Err(e) => return Err(e),
        };
        summary.factorisations += passes.earlier;
        let active = ctx.sum_usize(nr.nodes.iter().filter(|r| r.active).count());
        say!(
            ctx,
            "coulomb: the frictionless solution: {} steps, {active} active nodes",
            nr.steps
        );
        let Some(mut kept) = kept.filter(|_| !forced) else {
            return Ok(Passes::Frictionless(nr, summary));
        };
        let first = std::mem::take(&mut nr.history);
        let joined = |mut r: NewtonResult| {
            after(first.clone(), &mut r);
            r
        };
        match coulomb_condensed::solve(ctx, problem, reduced, ns, &mut kept, None)? {
            coulomb_condensed::CoulombCondensed::Solved(r, cs) => {
                summary.coulomb = Some(cs);
                // for the next load step (a held zone's too: its rows' values are in f)
                problem.kept.put(kept);
                return Ok(Passes::Done(Begin::Solved(joined(*r)), Some(summary)));
            }
            coulomb_condensed::CoulombCondensed::Start(r, u, cs, beyond) => {
                if passes.goes_on(&beyond, summary.factorisations) {
                    passes.next(ctx, problem, &mut kept, &beyond, summary.factorisations);
                    last = Some((joined(*r), u, cs));
                    continue;
                }
                say!(ctx, "coulomb: the plain path from the expanded iterate");
                summary.coulomb = Some(cs);
                return Ok(Passes::Done(Begin::Start(joined(*r), u), Some(summary)));
            }
            coulomb_condensed::CoulombCondensed::Fallback(cs) => {
                summary.coulomb = Some(cs);
                nr.history = first;
                return Ok(Passes::Frictionless(nr, summary));
            }
        }
    }
}

/// Every node of a frictionless solution starts sticking (Δu_τ = 0, λ_τ = 0 against the
/// references of `b`): the first Coulomb step gives the all-stick λ_τ, and (3.33) lets slip
/// where |λ_τ| exceeds μ(−λ_n). Local.
fn sticking(nodes: &mut [NodeResult], b: &ContactBoundary) {
    for (k, r) in b.nodes.iter().zip(nodes.iter_mut()) {
        r.u_t = k.u_t_ref;
        r.lambda_t = [0.0; 2];
        r.slip = false;
    }
}

/// The start of Coulomb's generalised Newton where no factorisation is there to condense on
/// (the iterative preset): Algorithm 1's frictionless solution on the same Krylov solver,
/// every active node sticking — for a body that Dirichlet data hold, without force control or
/// a warm start; else the touching nodes. Measured on the 3D block held and pushed into a
/// sphere (μ = 0.3, 2 ranks; Newton steps with the frictionless ones, GMRES iterations in all)
/// at 7 071 / 44 529 / 112 890 unknowns: 11 / 12 / 14 steps, 146 / 223 / 461 iterations,
/// against 12 / 13 / 16 steps, 173 / 312 / 513 iterations from the touching nodes (the solve
/// times within 5 %; docs/numbers.md, "Coulomb on the iterative preset"). Collective.
fn iterative_start(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &mut ReducedSystem,
    ns: &NewtonSettings,
    warm: Option<&WarmStart>,
) -> Result<(Begin, Option<condensed::CondensedSummary>), RunError> {
    let plain = warm.is_some()
        || !ns.force.is_empty()
        || problem.boundary.n_global == 0
        || reduced.factorises()?
        || free_modes(ctx, problem, reduced, ns).floats();
    if plain {
        return Ok((Begin::Touching, None));
    }
    let fl = NewtonSettings {
        law: Law::Frictionless,
        halfspace: None,
        ..*ns
    };
    let mut nr = match newton::semismooth_newton(ctx, problem, reduced, &fl, None) {
        Ok(nr) => nr,
        Err(RunError::Failed(why)) => {
            say!(
                ctx,
                "coulomb: no frictionless start ({why}); starting from the touching nodes"
            );
            return Ok((Begin::Touching, None));
        }
        Err(e) => return Err(e),
    };
    let active = ctx.sum_usize(nr.nodes.iter().filter(|r| r.active).count());
    say!(
        ctx,
        "coulomb: the frictionless solution: {} steps, {active} active nodes; every active \
         node starts sticking",
        nr.steps
    );
    let u = nr.u.to_local_vec()?;
    sticking(&mut nr.nodes, problem.boundary);
    Ok((Begin::Start(nr, u), None))
}

/// A load step of Coulomb's generalised Newton (`warm`: the previous step's solution, or its
/// extrapolation) on the contact unknowns: the previous step's factorisation where it still
/// holds (only d₀ is new; grown by a new one where the warm set reaches beyond its
/// candidates), else one factorisation with the Schur complement on every dof of the
/// candidates (the nodes with the smallest gaps and the warm set); where that is too wide for
/// the dense limits, the warm set's interior held sticking in K_p but for the nodes that
/// slipped in the step before (which are candidates), and a new pass for the nodes its check
/// finds changing beyond the candidates, as in [`coulomb_passes`]. The dense iteration from
/// the warm states (no frictionless steps), the check on every contact node; if it gives up,
/// the plain path from the warm start or from the last pass' expanded iterate. Collective.
fn coulomb_load_step(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &mut ReducedSystem,
    (ns, fl): (&NewtonSettings, &NewtonSettings),
    warm: &WarmStart,
) -> Result<(Begin, Option<condensed::CondensedSummary>), RunError> {
    let dim = problem.mesh.dim;
    // the nodes that slipped in the step before are never held sticking (c_h's global order)
    let release = gathered(ctx, warm.nodes.iter().map(|r| r.active && r.slip));
    // where the step before held a zone, this step holds the warm set's (its factorisation
    // is reused where the held nodes are the same)
    let zone: Vec<bool> = match problem.kept.holds_zone() {
        true => gathered(ctx, warm.nodes.iter().map(|r| r.active)),
        false => Vec::new(),
    };
    let mut passes = PassLoop::new(zone, release);
    // the expanded iterate of the last pass: the plain path's start where the next one fails
    let mut last: Option<(NewtonResult, Vec<f64>)> = None;
    loop {
        let held = passes.sticking(0);
        // the previous step's factorisation where it holds (condensed::reused), else a new one
        let tried = condensed::solve_keeping(
            ctx,
            problem,
            reduced,
            fl,
            Some(warm),
            (dim, false, Some(held)),
        );
        let (mut summary, mut kept) = match tried {
            Ok((condensed::Condensed::Factorised(s), Some(kept))) => (s, kept),
            Ok((condensed::Condensed::Fallback(mut s), _))
            | Ok((condensed::Condensed::Factorised(mut s), None))
            | Ok((condensed::Condensed::Solved(_, mut s), _)) => {
                s.factorisations += passes.earlier;
                return Ok((begin_from(ctx, last), Some(s)));
            }
            Err(RunError::Failed(why)) => {
                say!(
                    ctx,
                    "coulomb: not condensed ({why}); starting from the previous load step"
                );
                return Ok((begin_from(ctx, last), None));
            }
            Err(e) => return Err(e),
        };
        summary.factorisations += passes.earlier;
        let begin =
            match coulomb_condensed::solve(ctx, problem, reduced, ns, &mut kept, Some(warm))? {
                coulomb_condensed::CoulombCondensed::Solved(r, cs) => {
                    summary.coulomb = Some(cs);
                    problem.kept.put(kept); // for the next load step (a held zone's too)
                    Begin::Solved(*r)
                }
                coulomb_condensed::CoulombCondensed::Start(r, u, cs, beyond) => {
                    summary.coulomb = Some(cs);
                    // a held zone: at most WARM_STICK_FACTORISATIONS (where the warm set's
                    // stick core is no prediction of this step's, a rolling body's, further
                    // passes cost what the plain path's steps cost)
                    let held_missed = kept.held.iter().any(|&h| h)
                        && summary.factorisations >= WARM_STICK_FACTORISATIONS;
                    if !held_missed && passes.goes_on(&beyond, summary.factorisations) {
                        passes.next(ctx, problem, &mut kept, &beyond, summary.factorisations);
                        last = Some((*r, u));
                        continue;
                    }
                    say!(ctx, "coulomb: the plain path from the expanded iterate");
                    Begin::Start(*r, u)
                }
                coulomb_condensed::CoulombCondensed::Fallback(cs) => {
                    summary.coulomb = Some(cs);
                    begin_from(ctx, last)
                }
            };
        return Ok((begin, Some(summary)));
    }
}

/// The state of a Coulomb solve's condensed passes ([`coulomb_passes`], [`coulomb_load_step`]):
/// the held zone and the released nodes (c_h's global order; empty: none), the pass, the
/// factorisations of the passes before and the count of nodes that changed in the last one.
struct PassLoop {
    zone: Vec<bool>,
    release: Vec<bool>,
    pass: u32,
    earlier: usize,
    changed_before: usize,
}

impl PassLoop {
    fn new(zone: Vec<bool>, release: Vec<bool>) -> PassLoop {
        PassLoop {
            zone,
            release,
            pass: 0,
            earlier: 0,
            changed_before: usize::MAX,
        }
    }

    /// The next pass' held zone, released nodes and band, with at most `factorisations`.
    fn sticking(&self, factorisations: usize) -> condensed::Sticking<'_> {
        condensed::Sticking {
            zone: (!self.zone.is_empty()).then_some(self.zone.as_slice()),
            release: &self.release,
            pass: self.pass,
            factorisations,
        }
    }

    /// A new pass follows where nodes beyond the candidates change state (`beyond`), fewer
    /// than in the pass before, within [`MAX_STICK_FACTORISATIONS`] (`done` so far).
    fn goes_on(&self, beyond: &[usize], done: usize) -> bool {
        !beyond.is_empty() && beyond.len() < self.changed_before && done < MAX_STICK_FACTORISATIONS
    }

    /// The next pass from the nodes the check found changing beyond the candidates (c_h's
    /// global order): a node of the held zone (held, or in its band) that slips or leaves the
    /// obstacle is released (a candidate, never held); a node outside the zone that comes into
    /// contact widens the zone (its edge band moves out with it, so that a zone that grows with
    /// the load keeps its interior held); without a zone every such node is released, and so
    /// is every candidate of this pass (the next pass picks its first candidates anew, by gap:
    /// where the zone has moved, a rolling body's, the gaps alone would drop candidates that
    /// this pass needed). The pass's factorisation leaves its node order for the next (the
    /// same graph). Collective (log).
    fn next(
        &mut self,
        ctx: &Ctx,
        problem: &ContactProblem,
        kept: &mut condensed::Kept,
        beyond: &[usize],
        done: usize,
    ) {
        let held = beyond.iter().filter(|&&g| kept.held.get(g) == Some(&true));
        say!(
            ctx,
            "coulomb: condensed: {} node(s) beyond the candidates change state on the expanded \
             u, {} of them held: a new pass with them as candidates",
            beyond.len(),
            held.count()
        );
        self.zone = std::mem::take(&mut kept.zone); // empty: none held
        self.release.resize(kept.cand.n, false);
        if self.zone.is_empty() {
            for &g in &kept.comp.list {
                self.release[g] = true;
            }
        }
        for &g in beyond {
            match self.zone.get(g) {
                Some(false) => self.zone[g] = true,
                _ => self.release[g] = true,
            }
        }
        self.earlier = done;
        self.changed_before = beyond.len();
        self.pass += 1;
        problem.kept.put_order(kept.comp.node_order.take());
    }
}

/// This rank's flags of its contact nodes, all-gathered in c_h's global order. Collective.
fn gathered(ctx: &Ctx, mine: impl Iterator<Item = bool>) -> Vec<bool> {
    let mine: Vec<f64> = mine.map(|f| f64::from(u8::from(f))).collect();
    let all = ctx.all_gather_varcount(&mine);
    all.iter().map(|&f| f > 0.0).collect()
}

/// Where a load step's condensed pass gives up: the plain path from the last pass' expanded
/// iterate, or from the warm start where there was none. Collective (log).
fn begin_from(ctx: &Ctx, last: Option<(NewtonResult, Vec<f64>)>) -> Begin {
    match last {
        Some((r, u)) => {
            say!(
                ctx,
                "coulomb: the plain path from the last pass' expanded iterate"
            );
            Begin::Start(r, u)
        }
        None => Begin::Touching,
    }
}

/// The body's free rigid modes (those Dirichlet data leave free; none with the rigid-mode
/// handling off) and their load. Collective (reductions).
fn free_modes(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &ReducedSystem,
    ns: &NewtonSettings,
) -> FreeModes {
    let (mesh, b) = (problem.mesh, problem.boundary);
    FreeModes::new(
        ctx,
        mesh,
        problem.layout,
        problem.fixed,
        b,
        &reduced.f_local,
        ns.rigid,
    )
}

/// The part of the body's load that friction alone holds: the load φ = Zᵀ Rᵀ f in the rigid
/// modes that Dirichlet data leave free and that move no contact node along its normal (e.g. a
/// tangential load on a floating body pressed onto a plane).
struct Unheld {
    /// An orthonormal basis of those modes (m_z × count, in the coordinates of Z's columns).
    basis: nalgebra::DMatrix<f64>,
    /// |Uᵀ φ| and the load's scale.
    load: f64,
    scale: f64,
}

impl Unheld {
    /// The body's unheld load on the boundary `b`; `None`: the body is held, or that part is
    /// below [`dense::BALANCE_RTOL`] of the load's scale. Collective (one reduction).
    fn of(ctx: &Ctx, b: &ContactBoundary, free: &FreeModes) -> Option<Unheld> {
        let mz = free.dirichlet_free().ncols();
        if !free.floats() || mz == 0 {
            return None;
        }
        // Σ_k g_k g_kᵀ over every contact node (g_k: the free modes' normal parts at k)
        let mut gram = vec![0.0; mz * mz];
        for k in &b.nodes {
            let g = free.normal_parts(&k.x, &k.frame.n);
            for i in 0..mz {
                for j in 0..mz {
                    gram[i * mz + j] += g[i] * g[j];
                }
            }
        }
        let gram = nalgebra::DMatrix::from_row_slice(mz, mz, &ctx.sum_vec(&gram));
        let eig = gram.symmetric_eigen();
        let top = eig.eigenvalues.iter().fold(0.0_f64, |m, &e| m.max(e));
        let cols: Vec<_> = (0..mz)
            .filter(|&i| eig.eigenvalues[i] <= 1e-12 * top)
            .map(|i| eig.eigenvectors.column(i).into_owned())
            .collect();
        if cols.is_empty() {
            return None;
        }
        let basis = nalgebra::DMatrix::from_columns(&cols);
        let phi = nalgebra::DVector::from_vec(free.free_load());
        let (_, scale) = free.load();
        let load = (basis.transpose() * phi).norm();
        (load > dense::BALANCE_RTOL * scale).then_some(Unheld { basis, load, scale })
    }

    /// Why the frictionless problem cannot carry the load.
    fn why(&self) -> String {
        format!(
            "a load of {:.3e} (of {:.3e}) in rigid modes no contact normal holds: friction \
             alone carries it",
            self.load, self.scale
        )
    }

    /// The load of Coulomb's frictionless estimate: φ' = φ + P T s, the part only friction
    /// holds carried by one tangential force T s at the contact node with the smallest gap
    /// (ties: the smallest gmsh tag; P: the free modes' motion there, T its tangents), s the
    /// least-squares solution of Uᵀ φ' = 0 — where the pins would carry it off the contact and tip the body. Friction
    /// acts in the contact zone, and the moment of a force along a plane does not depend on
    /// where on the plane it acts: the estimate's moment balance is the friction's (to first
    /// order on a curved obstacle). What one force cannot carry (a torsion about the normal
    /// in 3D) the pins carry: it is left out of φ'. Collective (one all-gather).
    fn carried_at_contact(&self, ctx: &Ctx, b: &ContactBoundary, free: &FreeModes) -> Vec<f64> {
        let mz = free.dirichlet_free().ncols();
        let mut phi = free.free_load();
        // this rank's node with the smallest gap (ties: the smallest gmsh tag): gap, tag, then
        // the free modes' motion along its tangents (2 × 6)
        let mut mine = vec![f64::INFINITY; 14];
        let nearest = b
            .nodes
            .iter()
            .min_by(|a, c| a.gap.total_cmp(&c.gap).then(a.tag.cmp(&c.tag)));
        if let Some(k) = nearest {
            mine[0] = k.gap;
            mine[1] = k.tag as f64;
            for (i, t) in k.frame.t.iter().enumerate() {
                mine[2 + 6 * i..8 + 6 * i].copy_from_slice(&free.normal_parts(&k.x, t));
            }
        }
        let all = ctx.all_gather_varcount(&mine);
        // the smallest gap of all ranks (ties: the smallest tag, on every partition)
        let Some(best) = all
            .chunks(14)
            .filter(|r| r[0].is_finite())
            .min_by(|a, c| a[0].total_cmp(&c[0]).then(a[1].total_cmp(&c[1])))
        else {
            return phi;
        };
        let tangents = nalgebra::DMatrix::from_fn(mz, 2, |c, i| best[2 + 6 * i + c]);
        let a = self.basis.transpose() * &tangents;
        let rhs = -(self.basis.transpose() * nalgebra::DVector::from_column_slice(&phi));
        let svd = a.svd(true, true);
        let Ok(s) = svd.solve(&rhs, 1e-12 * svd.singular_values.max()) else {
            return phi;
        };
        let moved = tangents * s;
        for (p, m) in phi.iter_mut().zip(moved.iter()) {
            *p += m;
        }
        // what one force cannot carry is left to the pins: out of φ'
        let phi = nalgebra::DVector::from_vec(phi);
        let rest = &self.basis * (self.basis.transpose() * &phi);
        (phi - rest).as_slice().to_vec()
    }
}

/// The fixed point's stopping tolerance on the thresholds, relative to max_k b_k.
pub const FIXED_POINT_TOL: f64 = 1e-9;

/// Factorisations of K_p at most in a Coulomb start whose zone's interior is held sticking
/// (each pass takes the nodes that changed state beyond the candidates as candidates, as long
/// as fewer change than in the pass before); then the plain path from the last expanded
/// iterate. Below what the plain path costs: 9–19 LU steps on the wide zones of
/// docs/numbers.md ("Wide zones with friction").
const MAX_STICK_FACTORISATIONS: usize = 8;

/// Factorisations at most in a held zone's first pass (the attempt with every candidate
/// condensed, then the held zone and one pass where its frictionless set moves): a zone whose
/// frictionless set keeps moving under the held interior goes to the plain path instead.
const FIRST_STICK_FACTORISATIONS: usize = 3;

/// Factorisations at most in a Coulomb load step whose warm set's interior is held sticking
/// (the pass on the warm set and one more); then the plain path from the last expanded
/// iterate. Measured on the wide zones of docs/numbers.md ("Load steps on wide zones"): where
/// the warm set predicts the step (a punch pressed or dragged, a held disk pushed deeper) one
/// pass solves it; a floating disk rolling under a large traction took 5 passes with the
/// changes falling 304, 86, 21, 1, 3, about what its 12 plain steps cost.
const WARM_STICK_FACTORISATIONS: usize = 2;

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

/// A floating body (no Dirichlet data) against planes that share one normal direction (a plane,
/// or a body between parallel plates) has no equilibrium when the tangential resultant of its
/// load exceeds the total friction capacity of its pairs: Tresca Σ_k b_k (3.18); Coulomb
/// Σ_j μ_j N_j with N_j the pair's normal force, μ (−λ_n^k) summed over the pair's nodes. N_j is
/// known where the pair is under a force along its normal (N_j = |F_j|) or is the one pair left
/// to balance the load's normal resultant. Said before the solve instead of after a long (or
/// cycling) Newton run; other settings (tilted planes, curved obstacles, slanted forces, two
/// pairs with unknown normal forces) are left to the iteration. Collective.
fn check_friction_capacity(
    ctx: &Ctx,
    b: &ContactBoundary,
    (fixed, sys, dim): (&[f64], &System, usize),
    law: Law,
    forces: &[force::ForceControl],
) -> Result<(), RunError> {
    let Some(planes) = parallel_planes(&b.obstacles) else {
        return Ok(());
    };
    if law == Law::Frictionless || held_anywhere(ctx, fixed) {
        return Ok(());
    }
    let np = planes.len();
    // per pair: max μ (Coulomb) and Σ b_k (Tresca) over its nodes
    let mut local = vec![0.0; 2 * np];
    for k in &b.nodes {
        local[2 * k.pair] = f64::max(local[2 * k.pair], k.mu);
        local[2 * k.pair + 1] += k.bound;
    }
    let mu: Vec<f64> = (0..np).map(|j| ctx.max_f64(local[2 * j])).collect();
    let bounds = ctx.sum_vec(
        &local
            .iter()
            .skip(1)
            .step_by(2)
            .copied()
            .collect::<Vec<f64>>(),
    );
    let f = sys.b.to_local_vec()?;
    let mut local = [0.0; 3];
    for (i, x) in f.iter().enumerate() {
        local[i % dim] += x;
    }
    let r = ctx.sum_vec(&local);
    let n0 = planes[0];
    let rn = (0..3).map(|k| r[k] * n0[k]).sum::<f64>();
    let rt = (0..3)
        .map(|k| (r[k] - rn * n0[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    let (capacity, what) = if law == Law::Tresca {
        let c: f64 = bounds.iter().sum();
        if c == 0.0 {
            return Ok(()); // frictionless: the balance test of the free modes decides
        }
        (c, format!("Σ b_k = {c:.6e}, (3.18)"))
    } else {
        let Some(normal) = normal_forces(&planes, rn, forces) else {
            return Ok(());
        };
        let c: f64 = normal.iter().zip(&mu).map(|(n, m)| n * m).sum();
        if c <= 0.0 {
            return Ok(()); // no friction, or no normal load: the balance test decides
        }
        let terms: Vec<String> = normal
            .iter()
            .zip(&mu)
            .filter(|(n, _)| **n > 0.0)
            .map(|(n, m)| format!("{m} × {n:.6e}"))
            .collect();
        let what = if np == 1 {
            format!(
                "μ Σ_k (−λ_n^k) = μ × normal load = {} = {c:.6e}, Coulomb",
                terms.join("")
            )
        } else {
            format!(
                "Σ_j μ_j N_j over the pairs, N_j their normal forces = {} = {c:.6e}, Coulomb",
                terms.join(" + ")
            )
        };
        (c, what)
    };
    if rt > capacity * (1.0 + 1e-9) + 1e-14 * r.iter().map(|x| x.abs()).sum::<f64>() {
        return Err(RunError::Failed(format!(
            "no equilibrium: the body has no Dirichlet data and the tangential resultant of its \
             load ({rt:.6e}) exceeds the total friction capacity of the contact boundary \
             ({what}): it would slide away"
        )));
    }
    Ok(())
}

/// A failed iteration (`NoConvergence`) of a frictional body without Dirichlet data
/// (`sliding`) says what may be the cause; other errors as they are.
fn why_sliding(e: RunError, sliding: bool) -> RunError {
    match e {
        RunError::NoConvergence(why) if sliding => RunError::NoConvergence(format!(
            "{why}; the body has no Dirichlet data, so friction alone holds it tangentially: \
             beyond the friction capacity of its contact (not known before the solve on curved \
             or non-parallel obstacles) it has no equilibrium"
        )),
        e => e,
    }
}

/// Some dof of the mesh has Dirichlet data (`fixed` covers each rank's local mesh: agreed by
/// one reduction). Collective.
fn held_anywhere(ctx: &Ctx, fixed: &[f64]) -> bool {
    let here = if fixed.iter().any(|x| !x.is_nan()) {
        1.0
    } else {
        0.0
    };
    ctx.max_f64(here) > 0.0
}

/// The normals (into the body) of the pairs' obstacles if every one is a plane and all are
/// parallel (n_j = ±n_0).
fn parallel_planes(obstacles: &[Obstacle]) -> Option<Vec<[f64; 3]>> {
    let normals: Vec<[f64; 3]> = obstacles
        .iter()
        .map(|o| match o {
            Obstacle::Plane(p) => Some(p.normal()),
            _ => None,
        })
        .collect::<Option<_>>()?;
    let n0 = *normals.first()?;
    normals
        .iter()
        .all(|n| crate::geom::dot(*n, n0).abs() >= 1.0 - 1e-12)
        .then_some(normals)
}

/// The pairs' normal forces N_j ≥ 0 on a floating body between parallel planes (normals
/// `planes`, n_j = s_j n_0), from the load's normal resultant `rn` (along n_0) and the forces
/// under control: Σ_j s_j N_j + rn = 0, N_j = |F_j| on a pair pushed along its normal. `None`
/// if a force is not along its plane's normal, if more than one pair's force is unknown, or
/// if the balance asks for a pull (N < 0: the body leaves the plane, the balance test decides).
fn normal_forces(planes: &[[f64; 3]], rn: f64, forces: &[force::ForceControl]) -> Option<Vec<f64>> {
    let n0 = planes[0];
    let s: Vec<f64> = planes
        .iter()
        .map(|n| crate::geom::dot(*n, n0).signum())
        .collect();
    let mut normal = vec![f64::NAN; planes.len()];
    for fc in forces {
        let along = crate::geom::dot(fc.direction(), planes[fc.pair]);
        if along < 1.0 - 1e-12 {
            return None;
        }
        normal[fc.pair] = fc.magnitude();
    }
    let unknown: Vec<usize> = (0..planes.len()).filter(|&j| normal[j].is_nan()).collect();
    let known: f64 = (0..planes.len())
        .filter(|&j| !normal[j].is_nan())
        .map(|j| s[j] * normal[j])
        .sum();
    match unknown.as_slice() {
        [] => {}
        [u] => normal[*u] = -(rn + known) / s[*u],
        _ => return None,
    }
    normal.iter().all(|&n| n >= 0.0).then_some(normal)
}

/// The worst violation of (3.14) and of Coulomb's (3.18) with b_k = μ(−λ_n^k) by a state
/// (`nodes`, `u`) relative to the problem's scales, as [`final_state`] judges the final one (it
/// warns beyond 1e-8). Collective (one all-gather, two reductions).
pub(super) fn coulomb_certificate_worst(
    ctx: &Ctx,
    sys: &System,
    b: &ContactBoundary,
    nodes: &[NodeResult],
    u: &Vector,
    dim: usize,
) -> Result<f64, RunError> {
    let mut judged = b.clone();
    coulomb_bounds(&mut judged, nodes);
    let table = report::gather(ctx, &judged, nodes, dim);
    let (scales, kkt, friction) = certificates(ctx, sys, &table, u, true, Scales::default())?;
    let friction = friction.map_or(0.0, |f| f.worst(&scales));
    Ok(kkt.worst().max(friction))
}

/// Coulomb's thresholds b_k = μ(−λ_n^k) (F1) at the state `nodes`, by which the certificates
/// and the output judge Coulomb's law. Local.
fn coulomb_bounds(b: &mut ContactBoundary, nodes: &[NodeResult]) {
    for (k, r) in b.nodes.iter_mut().zip(nodes) {
        k.bound = k.mu * (-r.lambda_n).max(0.0);
    }
}

/// The problem's scales, at least `floor`, the KKT certificate of (3.14) and, with friction,
/// the friction certificate of (3.18) of a gathered contact table at u. Collective (two
/// reductions).
fn certificates(
    ctx: &Ctx,
    sys: &System,
    table: &report::Table,
    u: &Vector,
    friction: bool,
    floor: Scales,
) -> Result<(Scales, report::Kkt, Option<report::FrictionCertificate>), RunError> {
    let scales = problem_scales(ctx, sys, u)?;
    let mut kkt = table.kkt(!friction, &scales);
    kkt.force_scale = kkt.force_scale.max(floor.force);
    kkt.length_scale = kkt.length_scale.max(floor.length);
    // without a load (a body moved by its Dirichlet data or by the obstacle alone) the force
    // scale is the contact's own, as the KKT certificate takes it: friction with μ = 0 or
    // g_R = 0 (b = 0) is judged by it too, not by a zero scale
    let scales = Scales {
        force: kkt.force_scale,
        length: scales.length.max(floor.length),
    };
    Ok((scales, kkt, friction.then(|| table.friction_certificate())))
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
    keys: &boundary::CaseKeys,
) -> Result<(), RunError> {
    let fric_bad = |rel: f64| friction.is_some_and(|f| f.beyond(rel, scales));
    if kkt.beyond(report::CERTIFICATE_TOL) || fric_bad(report::CERTIFICATE_TOL) {
        return Err(RunError::Failed(format!(
            "the final state is not a solution: it violates {} beyond {:e} of the problem's \
             scales (force {:.3e}, length {:.3e}): KKT {}{} — the problem is probably ill-posed \
             (a load that contact and friction cannot carry, or a mesh of several bodies that \
             Dirichlet data do not hold: {}) or the linear solves inexact ({})",
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
                .unwrap_or_default(),
            keys.named(&["dirichlet", "neumann", ".obstacle", ".friction"]),
            keys.solver
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

#[cfg(test)]
mod tests {
    use super::*;

    fn pushed(pair: usize, force: [f64; 3]) -> force::ForceControl {
        force::ForceControl {
            force,
            start: 0.0,
            file: "case.toml".into(),
            pair,
            key: format!("contact[{pair}].force"),
        }
    }

    /// The normal forces of a body between a plate below (n = +y) and one above (n = −y).
    #[test]
    fn normal_forces_between_two_plates() {
        let plates = [[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]];
        // the top plate pushed down by 0.01, a body load of 0.002 downwards (rn = −0.002)
        let top = [pushed(1, [0.0, -0.01, 0.0])];
        let n = normal_forces(&plates, -0.002, &top).expect("known");
        assert!((n[0] - 0.012).abs() < 1e-15 && n[1] == 0.01, "{n:?}");
        // one plane, no force: N = −rn; a pull leaves it to the balance test
        assert_eq!(normal_forces(&plates[..1], -0.5, &[]), Some(vec![0.5]));
        assert_eq!(normal_forces(&plates[..1], 0.5, &[]), None);
        // two unknown normal forces, or a slanted force: not known before the solve
        assert_eq!(normal_forces(&plates, -0.002, &[]), None);
        let slanted = [pushed(1, [0.001, -0.01, 0.0])];
        assert_eq!(normal_forces(&plates, -0.002, &slanted), None);
    }

    #[test]
    fn only_parallel_planes_have_a_capacity_before_the_solve() {
        let plane = |n: [f64; 3]| {
            Obstacle::Plane(crate::contact::Plane::new([0.0; 3], n, 2).expect("plane"))
        };
        let two = [plane([0.0, 1.0, 0.0]), plane([0.0, -1.0, 0.0])];
        assert_eq!(parallel_planes(&two).map(|v| v.len()), Some(2));
        let tilted = [plane([0.0, 1.0, 0.0]), plane([0.6, -0.8, 0.0])];
        assert_eq!(parallel_planes(&tilted), None);
    }
}
