//! Quasi-static load stepping: the solve stage of a run, one solve per load factor.
//!
//! Step s solves the problem with the Neumann data, the body force and the prescribed
//! displacements multiplied by its factor t_s (the obstacle stays). The assembled right-hand
//! side is linear in all three (the loads (3.8), −K_ij g_j of the eliminated Dirichlet columns
//! and A_jj g_j of their rows), so f(t) = t · f(1): the system is assembled once and its
//! right-hand side scaled per step. A Neumann load with `ramp = false` is held at its full
//! value: f(t) = t · f(1) + (1 − t) · f_held; so is a Dirichlet entry with `ramp = false` (its
//! prescribed values, and f_held holds their elimination terms). A contact step starts from the previous converged step
//! (`previous` of [`signorini::solve`]).
//!
//! Cutback: a step whose solve does not converge ([`RunError::NoConvergence`]) is retried at
//! the midpoint between the last converged factor and the failed one; after a success the
//! halved increment is kept until the planned factor is reached. A planned step may halve its
//! increment `max_cutbacks` times (so it becomes at most 2^max_cutbacks sub-steps); one more
//! failure ends the run. Any other error ends the run at once.
//!
//! Without `[load]` the run is one step at factor 1 without cutback, written as today's single
//! solution; with `[load]` every converged step (sub-steps of a cutback included) is a step of
//! the XDMF temporal collection and a row of `history.csv`.

use crate::assembly::System;
use crate::case::{Case, LoadSection, OutputField, SolverPath, SolverSection};
use crate::error::RunError;
use crate::fem::Materials;
use crate::mesh::Mesh;
use crate::mortar;
use crate::output::{ContactResult, ResultSet};
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::Vector;
use crate::post;
use crate::say;
use crate::setup::ContactSettings;
use crate::signorini::certificate::Certificate;
use crate::signorini::report::{FrictionCertificate, Kkt, PairSummary};
use crate::signorini::session::Session;
use crate::signorini::{self, ContactReport, ContactSolution};
use crate::solver::{self, LinearSummary};
use crate::warnings::{self, Warning};
use serde::Serialize;
use std::fmt::Write;
use std::time::Instant;

/// The solve's own summary section(s).
#[derive(Serialize)]
#[serde(untagged)]
pub enum SolveReport {
    Linear(LinearSummary),
    Contact(Box<ContactReport>),
}

/// One converged load step: a row of history.csv and an entry of summary.json's `load.steps`.
#[derive(Debug, Clone, Serialize)]
pub struct StepRecord {
    /// Converged steps so far, 1, 2, … (the XDMF time step).
    pub step: usize,
    /// The planned step (index into the case's factors, from 1) this one belongs to.
    pub planned: usize,
    /// The load factor t.
    pub factor: f64,
    /// The XDMF time of the step: the load factor while the history only loads; from the first
    /// unloading step on, the length of the load path Σ|Δt| (ParaView needs increasing times).
    pub time: f64,
    /// Halvings of the increment of the planned step when this step converged.
    pub cutbacks: usize,
    /// Newton steps (contact) — None for a linear case.
    pub newton_steps: Option<usize>,
    /// Numeric factorisations of the step (contact, direct preset; 0 where the step solved on
    /// the previous step's factorisation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub factorisations: Option<usize>,
    pub active: Option<usize>,
    /// Active nodes sticking / slipping (friction only).
    pub stick: Option<usize>,
    pub slip: Option<usize>,
    /// Σ of the contact forces −λ over the contact nodes.
    pub total_force: Option<Vec<f64>>,
    /// The obstacle's displacement d = t·m (`contact.motion`; 0 for an obstacle at rest).
    pub obstacle_displacement: Option<Vec<f64>>,
    pub max_pressure: Option<f64>,
    /// 2D: half width of the contact zone.
    pub half_width: Option<f64>,
    /// 3D: Σ w_k over the active nodes (the contact area).
    pub contact_area: Option<f64>,
    /// Several contact pairs: each pair's numbers (history.csv's `pairN_*` columns).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pairs: Option<Vec<PairSummary>>,
    /// The step's KKT certificate of (3.14) (checked at every step: beyond
    /// `report::CERTIFICATE_TOL` the step is an error).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kkt: Option<Kkt>,
    /// Its worst violation relative to its scale (`Kkt::worst`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kkt_violation: Option<f64>,
    /// The step's friction certificate of (3.18), on the increment of the step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<FrictionCertificate>,
    /// Its worst violation relative to its scale (`FrictionCertificate::worst`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_violation: Option<f64>,
    /// The step's certificate (signorini/certificate.rs): its stop rule, violations,
    /// equilibrium and force balance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub certificate: Option<Certificate>,
    /// The step's warnings (docs/warnings.md; `[]` for a step without any).
    pub warnings: Vec<Warning>,
    /// Seconds of the step (solve, post-processing, output).
    pub seconds: f64,
}

impl StepRecord {
    /// A step's record at `factor` (time = factor) with no contact data yet.
    fn new(step: usize, planned: usize, factor: f64, cutbacks: usize) -> StepRecord {
        StepRecord {
            step,
            planned,
            factor,
            time: factor,
            cutbacks,
            newton_steps: None,
            factorisations: None,
            active: None,
            stick: None,
            slip: None,
            total_force: None,
            obstacle_displacement: None,
            max_pressure: None,
            half_width: None,
            contact_area: None,
            pairs: None,
            kkt: None,
            kkt_violation: None,
            friction: None,
            friction_violation: None,
            certificate: None,
            warnings: Vec::new(),
            seconds: 0.0,
        }
    }
}

/// summary.json's `load` section (runs with `[load]`).
#[derive(Debug, Clone, Serialize)]
pub struct LoadReport {
    /// The planned factors of the case.
    pub factors: Vec<f64>,
    pub max_cutbacks: usize,
    /// Every step of the history reached the last factor.
    pub completed: bool,
    /// Failed attempts that were cut back, in all.
    pub cutbacks: usize,
    /// Why the run stopped before the last factor.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    pub steps: Vec<StepRecord>,
}

/// The solve stage's product: the last converged step and the record of all of them.
pub struct Stepped {
    pub report: SolveReport,
    /// The last step's contact table (contact_nodes.csv).
    pub contact_csv: Option<String>,
    /// None without `[load]`.
    pub load: Option<LoadReport>,
    /// history.csv (with `[load]`).
    pub history_csv: Option<String>,
    /// The error that ended the run after some steps converged (their output is written).
    pub failure: Option<RunError>,
    /// The run's warnings (docs/warnings.md); a series': every step's, each once.
    pub warnings: Vec<Warning>,
    pub solve_seconds: f64,
    pub post_seconds: f64,
    pub output_seconds: f64,
}

/// What the steps share: the case, its discretisation and the output being written.
pub struct Stepper<'a> {
    pub ctx: &'a Ctx<'a>,
    pub case: &'a Case,
    /// The case's `solver` section with its preset resolved.
    pub solver: &'a SolverSection,
    pub mesh: &'a Mesh,
    pub layout: &'a Layout,
    pub material: &'a Materials,
    /// Prescribed displacements at factor 1 (NaN = free dof).
    pub fixed: &'a [f64],
    /// Per dof: held at full value in every step (`ramp = false`); empty = none held.
    pub held_fixed: &'a [bool],
    /// The contact settings (`None`: a linear case).
    pub contact: Option<&'a ContactSettings>,
    /// The change of basis of the body pairs (crate::mortar): the contact solve runs on
    /// Qᵀ A Q (A in `run`'s system is that already) and Qᵀ (f − A c); `None` without them.
    pub mortar: Option<&'a mortar::Basis>,
    /// The body of every local node (0, 1, ... in the order of their first node tags).
    pub body_of: &'a [u32],
    pub out: &'a ResultSet,
}

/// One solved step before it is recorded.
struct Solved {
    /// The displacement of a linear solve, or of a contact solve with body pairs (u = Q w + c;
    /// the contact solve's own is w); `None`: the contact solve's.
    linear_u: Option<Vector>,
    report: SolveReport,
    contact: Option<ContactSolution>,
}

impl Solved {
    fn u(&self) -> &Vector {
        match (&self.contact, &self.linear_u) {
            (_, Some(u)) => u,
            (Some(c), None) => &c.u,
            (None, None) => unreachable!("a solved step has a displacement"),
        }
    }
}

/// The solve of a linear case or of the contact algorithm at one factor (its settings at the
/// factor, and the run's session).
enum Physics {
    Linear,
    Contact(Box<ContactSettings>, Box<Session>),
}

/// What a run of load steps carries from step to step.
struct Progress {
    /// The prescribed displacements at the current factor.
    fixed: Vec<f64>,
    /// The last converged step.
    last: Option<Solved>,
    records: Vec<StepRecord>,
    /// The XDMF times of the steps written.
    times: Vec<f64>,
    solve_s: f64,
    post_s: f64,
    output_s: f64,
    collected: warnings::Collected,
}

impl Progress {
    fn new(fixed: &[f64]) -> Progress {
        Progress {
            fixed: fixed.to_vec(),
            last: None,
            records: Vec::new(),
            times: Vec::new(),
            solve_s: 0.0,
            post_s: 0.0,
            output_s: 0.0,
            collected: warnings::Collected::default(),
        }
    }

    /// Logs converged step `rec` (with `[load]`: its progress line and its new warnings; the
    /// planned steps `of`) and keeps it with its warnings.
    fn push(&mut self, ctx: &Ctx, mut rec: StepRecord, warned: Vec<Warning>, of: Option<usize>) {
        if let Some(planned) = of {
            log_step(ctx, &rec, planned);
            let new = self.collected.add(rec.step, &warned);
            warnings::log(ctx, &new, &format!("load step {}: ", rec.planned));
        } else {
            warnings::log(ctx, &warned, "");
            self.collected.list = warned.clone();
        }
        rec.warnings = warned;
        self.records.push(rec);
    }
}

/// The error of a failed step that could not be cut back: with `[load]`, a non-converged
/// solve names the planned step `p`, its factor and the cutbacks made.
fn step_failure(
    e: RunError,
    series: bool,
    plan: &LoadSection,
    p: usize,
    factor: f64,
    halvings: usize,
) -> RunError {
    match e {
        RunError::NoConvergence(why) if series => RunError::Failed(format!(
            "load step {p}: factor {factor} did not converge after {halvings} \
             cutback(s) of its increment (load.max_cutbacks = {}): {why}",
            plan.max_cutbacks
        )),
        e => e,
    }
}

impl Stepper<'_> {
    /// Solves every load step (one at factor 1 without `[load]`), writing each converged one.
    /// An `Err` means nothing was written; a failure after some steps converged comes back in
    /// [`Stepped::failure`] with the converged steps written.
    pub fn run(&self, sys: &mut System) -> Result<Stepped, RunError> {
        let ctx = self.ctx;
        let series = self.case.load.is_some();
        let plan = self.case.load.clone().unwrap_or_else(LoadSection::single);
        let mut physics = match self.contact {
            None => Physics::Linear,
            // what the contact solves keep from one to the next: the linear solver, a condensed
            // factorisation (the matrix is assembled once; only the right-hand side is scaled)
            Some(c) => {
                let (mesh, layout) = (self.mesh, self.layout);
                let session = Session::new(ctx, mesh, layout, self.solver, c, &sys.a, self.mortar)?;
                if self.solver.path == SolverPath::Schur && !session.setup().kind().factorises() {
                    let why =
                        "needs a factorisation: solver.petsc_options make the solver iterative";
                    return Err(self.case.schur_path_refused(why).into());
                }
                Physics::Contact(Box::new(c.clone()), Box::new(session))
            }
        };
        // f(1), kept to scale from (only with [load]: a single step solves f(1) itself).
        let b_full = if series {
            Some(sys.b.duplicate().and_then(|mut v| {
                v.copy_from(&sys.b)?;
                Ok(v)
            })?)
        } else {
            None
        };
        let mut run = Progress::new(self.fixed);
        let mut failure = None;
        let mut schedule = Schedule::new(&plan);
        while let Some(factor) = schedule.next() {
            let t0 = Instant::now();
            let (p, halvings) = (schedule.planned(), schedule.halvings());
            self.prepare_step(sys, b_full.as_ref(), &mut physics, &mut run, factor)?;
            let previous = run.last.as_ref().and_then(|s| s.contact.as_ref());
            let solved = self.solve_once(&mut physics, &run.fixed, sys, previous);
            run.solve_s += t0.elapsed().as_secs_f64();
            let solved = match solved {
                Ok(s) => s,
                Err(RunError::NoConvergence(why)) if schedule.can_cut_back() => {
                    let retry = schedule.cut_back();
                    say!(
                        ctx,
                        "load step {p}: factor {factor} failed ({why}), cut back to {retry}"
                    );
                    continue;
                }
                Err(e) => {
                    let e = step_failure(e, series, &plan, p, factor, halvings);
                    if run.records.is_empty() {
                        return Err(e);
                    }
                    failure = Some(e);
                    break;
                }
            };
            if !series {
                // no later load step takes the condensed factorisation: its memory goes now
                if let Physics::Contact(_, session) = &mut physics {
                    session.release_factor();
                }
            }
            let step = run.records.len() + 1;
            let (warned, time) = self.write_step(&solved, &mut run, series, step, factor)?;
            let mut rec = self.record(&solved, step, p, factor, halvings);
            rec.time = time;
            rec.seconds = t0.elapsed().as_secs_f64();
            run.push(ctx, rec, warned, series.then_some(plan.factors.len()));
            schedule.converged(factor);
            run.last = Some(solved);
        }
        Ok(self.finish(run, &plan, series, schedule.cutbacks, failure))
    }

    /// Before the solve at `factor`: the loads and prescribed displacements scaled (with
    /// `[load]`), the contact settings at the factor, and the predictor of the previous step's
    /// solution (none at a corner of a motion / force table).
    fn prepare_step(
        &self,
        sys: &mut System,
        b_full: Option<&Vector>,
        physics: &mut Physics,
        run: &mut Progress,
        factor: f64,
    ) -> Result<(), RunError> {
        if let Some(b) = b_full {
            scale(sys, b, self.fixed, self.held_fixed, &mut run.fixed, factor)?;
        }
        if let Physics::Contact(settings, _) = physics {
            settings.at_factor(factor);
        }
        if let Some(c) = run.last.as_mut().and_then(|s| s.contact.as_mut()) {
            c.predict = predictor_ratio(&run.records, factor);
            // a corner of a motion / force table: the increments are not parallel
            if let (Physics::Contact(settings, _), [.., before, done]) =
                (&*physics, run.records.as_slice())
            {
                if !settings.increments_parallel(before.factor, done.factor, factor, c.predict) {
                    c.predict = 0.0;
                }
            }
        }
        Ok(())
    }

    /// The post-processing and output of converged step `step` at `factor`: returns its
    /// warnings and its XDMF time.
    fn write_step(
        &self,
        solved: &Solved,
        run: &mut Progress,
        series: bool,
        step: usize,
        factor: f64,
    ) -> Result<(Vec<Warning>, f64), RunError> {
        let (ctx, case) = (self.ctx, self.case);
        let t1 = Instant::now();
        let values = post::local_cell_values(self.mesh, self.layout, solved.u())?;
        let (mesh, layout, material) = (self.mesh, self.layout, self.material);
        let cells = post::cell_fields(mesh, layout, material, &values, &case.output, self.body_of);
        let mut warned = (solved.contact.as_ref())
            .map(|c| c.warnings.clone())
            .unwrap_or_default();
        warned.extend(post::deformation_warning(
            ctx,
            self.mesh,
            self.layout,
            &values,
        ));
        drop(values);
        let fields =
            post::solution_fields(self.mesh, self.layout, solved.u(), cells, &case.output)?;
        run.post_s += t1.elapsed().as_secs_f64();
        let grid = solved
            .contact
            .as_ref()
            .map(|c| &c.result)
            .filter(|_| case.output.wants(OutputField::Contact));
        let piece = fields.piece(grid);
        let time = step_time(&run.records, factor);
        run.output_s += if series {
            run.times.push(time);
            self.out.write_step(ctx, &piece, step, &run.times)?
        } else {
            self.out.write_solution(ctx, &piece)?
        };
        drop(fields);
        Ok((warned, time))
    }

    /// The solve stage's product from the steps run: the last converged step's report (with
    /// `[load]`, its certificate the worst over the steps), the tables and the load report.
    fn finish(
        &self,
        run: Progress,
        plan: &LoadSection,
        series: bool,
        cutbacks: usize,
        failure: Option<RunError>,
    ) -> Stepped {
        let Progress {
            last,
            records,
            solve_s,
            post_s,
            output_s,
            collected,
            ..
        } = run;
        let mut last = last.expect("a step converged, or the run returned its error");
        if let (true, SolveReport::Contact(r)) = (series, &mut last.report) {
            if let Some(worst) = worst_certificate(&records) {
                r.certificate = worst;
            }
        }
        let contact_csv = last.contact.as_ref().map(|c| c.result.csv.clone());
        let history_csv = series.then(|| history_csv(&records, self.mesh.dim));
        let load = series.then(|| LoadReport {
            factors: plan.factors.clone(),
            max_cutbacks: plan.max_cutbacks,
            completed: failure.is_none(),
            cutbacks,
            failure: failure.as_ref().map(|e| e.to_string()),
            steps: records,
        });
        Stepped {
            report: last.report,
            contact_csv,
            load,
            history_csv,
            failure,
            warnings: collected.list,
            solve_seconds: solve_s,
            post_seconds: post_s,
            output_seconds: output_s,
        }
    }

    /// One linear solve, or the contact algorithm from the previous step's state (and what
    /// the run's session keeps).
    fn solve_once(
        &self,
        physics: &mut Physics,
        fixed: &[f64],
        sys: &mut System,
        previous: Option<&ContactSolution>,
    ) -> Result<Solved, RunError> {
        let (ctx, case) = (self.ctx, self.case);
        match physics {
            Physics::Linear => {
                let (u, report) = solver::linear_solve(
                    ctx,
                    self.mesh,
                    self.layout,
                    sys,
                    self.solver,
                    &case.file,
                )?;
                Ok(Solved {
                    linear_u: Some(u),
                    report: SolveReport::Linear(report.summary(self.solver.preset)),
                    contact: None,
                })
            }
            Physics::Contact(settings, session) => {
                let mut in_w = (self.mortar)
                    .map(|m| m.rhs(self.layout, &sys.b, fixed))
                    .transpose()?;
                if let Some((f_hat, _)) = in_w.as_mut() {
                    std::mem::swap(&mut sys.b, f_hat);
                }
                let in_u = match (self.mortar, &in_w) {
                    (Some(basis), Some((f, c))) => Some(mortar::InU {
                        basis,
                        f,
                        c: c.as_ref(),
                    }),
                    _ => None,
                };
                let s = signorini::solve(
                    ctx,
                    settings,
                    self.mesh,
                    self.layout,
                    fixed,
                    sys,
                    self.solver,
                    session,
                    previous,
                    in_u.as_ref(),
                );
                if let Some((f_hat, _)) = in_w.as_mut() {
                    std::mem::swap(&mut sys.b, f_hat);
                }
                let s = s?;
                let body_u = match (self.mortar, &in_w) {
                    (Some(m), Some((_, c))) => Some(m.displacement(&s.u, c.as_ref())?),
                    _ => None,
                };
                // the report goes to the summary, the rest stays as the next step's start
                Ok(Solved {
                    linear_u: body_u,
                    report: SolveReport::Contact(Box::new(s.report.clone())),
                    contact: Some(s),
                })
            }
        }
    }

    /// The record of a converged step (contact counts summed over the ranks). Collective.
    fn record(
        &self,
        s: &Solved,
        step: usize,
        planned: usize,
        factor: f64,
        cutbacks: usize,
    ) -> StepRecord {
        let mut rec = StepRecord::new(step, planned, factor, cutbacks);
        let (Some(c), SolveReport::Contact(r)) = (&s.contact, &s.report) else {
            return rec;
        };
        rec.newton_steps = Some(r.newton.steps);
        rec.factorisations = Some(r.newton.factorisations);
        rec.active = Some(r.contact.active_count);
        rec.total_force = Some(r.contact.total_force.clone());
        if let [d] = c.obstacle_displacement.as_slice() {
            rec.obstacle_displacement = Some(d[..self.mesh.dim].to_vec());
        }
        rec.pairs = r.contact.pairs.clone();
        rec.max_pressure = Some(r.contact.max_pressure);
        rec.half_width = r.contact.half_width.filter(|_| self.mesh.dim == 2);
        rec.kkt = Some(r.contact.kkt);
        rec.kkt_violation = Some(r.contact.kkt.worst());
        rec.friction = r.contact.friction;
        rec.friction_violation = r.contact.friction.map(|f| f.worst(&r.contact.scales));
        rec.certificate = Some(r.certificate.clone());
        let (stick, slip, area) = contact_counts(&c.result);
        let sums = self.ctx.sum_vec(&[stick, slip, area]);
        if c.result.fields.iter().any(|f| f.name == "slip_state") {
            rec.stick = Some(sums[0] as usize);
            rec.slip = Some(sums[1] as usize);
        }
        if self.mesh.dim == 3 {
            rec.contact_area = Some(sums[2]);
        }
        rec
    }
}

/// The XDMF time of a step at `factor` after `done`: the factor while the history has only
/// loaded, else the previous time plus |Δ factor| (the length of the load path).
fn step_time(done: &[StepRecord], factor: f64) -> f64 {
    let Some(last) = done.last() else {
        return factor;
    };
    let loading = last.time == last.factor && factor > last.factor;
    if loading {
        factor
    } else {
        last.time + (factor - last.factor).abs()
    }
}

/// The predictor of a step at `factor` after the converged steps `done`: the ratio of its
/// load increment to the last step's, when the last step itself started from a converged step
/// (its increment is then parallel to this one's: f(t) = t f(1) + (1 − t) f_held) and the
/// load goes on in the same sense; 0 (no predictor) otherwise.
fn predictor_ratio(done: &[StepRecord], factor: f64) -> f64 {
    let [.., before, last] = done else {
        return 0.0;
    };
    let s = (factor - last.factor) / (last.factor - before.factor);
    if s.is_finite() && s > 0.0 {
        s
    } else {
        0.0
    }
}

/// A sub-step whose factor comes within this fraction of its increment of the planned factor
/// lands on it ([`Schedule::next`]): a sum of factors that misses it by round-off is not a
/// step of its own.
const LAND_RTOL: f64 = 1e-9;

/// The load factors to solve at, with cutbacks (no solves: the loop asks it what comes next).
pub struct Schedule<'p> {
    plan: &'p LoadSection,
    /// The planned step being worked on (index into the factors).
    planned: usize,
    /// The factor of the last converged step (0: the unloaded start).
    reached: f64,
    /// The current increment of the planned step.
    increment: f64,
    /// Halvings of the planned step's increment so far.
    halvings: usize,
    /// Cutbacks of the whole history.
    pub cutbacks: usize,
}

impl<'p> Schedule<'p> {
    pub fn new(plan: &'p LoadSection) -> Self {
        Schedule {
            plan,
            planned: 0,
            reached: 0.0,
            increment: plan.factors.first().copied().unwrap_or(0.0),
            halvings: 0,
            cutbacks: 0,
        }
    }

    /// The factor of the next solve; None once the last planned factor is reached.
    pub fn next(&self) -> Option<f64> {
        let target = *self.plan.factors.get(self.planned)?;
        let f = self.reached + self.increment;
        // the last sub-step lands exactly on the planned factor, also where reached +
        // increment misses it by round-off (1.0 + (0.3 − 1.0) = 0.30000000000000004)
        let near = LAND_RTOL * self.increment.abs();
        let beyond = (self.increment > 0.0 && f >= target - near)
            || (self.increment < 0.0 && f <= target + near);
        Some(if beyond { target } else { f })
    }

    /// The planned step being worked on, from 1.
    pub fn planned(&self) -> usize {
        self.planned + 1
    }

    /// Halvings of the planned step's increment so far.
    pub fn halvings(&self) -> usize {
        self.halvings
    }

    /// The solve at `f` (= [`Schedule::next`]) converged.
    pub fn converged(&mut self, f: f64) {
        self.reached = f;
        if Some(&f) == self.plan.factors.get(self.planned) {
            self.planned += 1;
            self.halvings = 0;
            if let Some(&t) = self.plan.factors.get(self.planned) {
                self.increment = t - f;
            }
        }
    }

    /// May the failed solve at [`Schedule::next`] be retried with half the increment? Not
    /// beyond `max_cutbacks` halvings of one planned step, nor when half the increment no
    /// longer changes the factor.
    pub fn can_cut_back(&self) -> bool {
        let half = self.reached + 0.5 * self.increment;
        self.halvings < self.plan.max_cutbacks && half != self.reached
    }

    /// Halves the increment; returns the factor to retry at (the midpoint between the last
    /// converged factor and the failed one).
    pub fn cut_back(&mut self) -> f64 {
        if let Some(failed) = self.next() {
            self.increment = failed - self.reached;
        }
        self.increment *= 0.5;
        self.halvings += 1;
        self.cutbacks += 1;
        self.reached + self.increment
    }
}

/// sys.b = t · f(1) and the prescribed displacements t · g(1).
fn scale(
    sys: &mut System,
    b_full: &Vector,
    fixed_full: &[f64],
    held: &[bool],
    fixed: &mut [f64],
    t: f64,
) -> Result<(), RunError> {
    sys.b.copy_from(b_full)?;
    sys.b.write(|b| b.iter_mut().for_each(|x| *x *= t))?;
    if let Some(h) = &sys.b_held {
        // f(t) = t f(1) + (1 − t) f_held: the held loads at full value in every step
        let h = h.to_local_vec()?;
        sys.b.write(|b| {
            for (x, hv) in b.iter_mut().zip(&h) {
                *x += (1.0 - t) * hv;
            }
        })?;
    }
    for (i, (g, &g1)) in fixed.iter_mut().zip(fixed_full).enumerate() {
        *g = if held.get(i) == Some(&true) {
            g1
        } else {
            t * g1
        };
    }
    Ok(())
}

/// This rank's active nodes that stick and slip, and their Σ w_k, from the contact surface's
/// fields `state` (1 in contact; report::STATE_CODES), `slip_state` (0 stick, 1 slip on nodes
/// in contact) and `weight`.
fn contact_counts(r: &ContactResult) -> (f64, f64, f64) {
    let field = |name: &str| r.fields.iter().find(|f| f.name == name);
    let (Some(state), weight) = (field("state"), field("weight")) else {
        return (0.0, 0.0, 0.0);
    };
    let slip = field("slip_state");
    let (mut n_stick, mut n_slip, mut area) = (0.0, 0.0, 0.0);
    for (k, &s) in state.data.iter().enumerate() {
        if s != 1.0 {
            continue;
        }
        if let Some(w) = weight {
            area += w.data[k];
        }
        match slip.map(|f| f.data[k]) {
            Some(1.0) => n_slip += 1.0,
            Some(_) => n_stick += 1.0,
            None => {}
        }
    }
    (n_stick, n_slip, area)
}

/// The progress line of a converged step.
fn log_step(ctx: &Ctx, r: &StepRecord, planned: usize) {
    let mut line = format!(
        "load step {}/{planned}: factor {} converged",
        r.planned, r.factor
    );
    if let Some(n) = r.newton_steps {
        let _ = write!(
            line,
            " in {n} Newton steps, {} active",
            r.active.unwrap_or(0)
        );
    }
    if let (Some(st), Some(sl)) = (r.stick, r.slip) {
        let _ = write!(line, " ({st} stick, {sl} slip)");
    }
    if let Some(p) = r.max_pressure {
        let _ = write!(line, ", p_max = {p:.6}");
    }
    if let Some(f) = &r.total_force {
        let _ = write!(line, ", total force = {f:?}");
    }
    if let Some(d) = r
        .obstacle_displacement
        .as_ref()
        .filter(|d| d.iter().any(|&x| x != 0.0))
    {
        let _ = write!(line, ", obstacle at {d:?}");
    }
    if r.cutbacks > 0 {
        let _ = write!(line, " ({} cutback(s))", r.cutbacks);
    }
    let _ = write!(line, " ({:.3} s)", r.seconds);
    say!(ctx, "{line}");
}

/// A load series' certificate block: every value's worst over the steps, the stop rule the
/// first loosened one, `worst_step` the step of the largest relative value. `None` without a
/// contact step. Pure.
fn worst_certificate(records: &[StepRecord]) -> Option<Certificate> {
    let mut steps = records
        .iter()
        .filter_map(|r| r.certificate.as_ref().map(|c| (r.step, c)));
    let (first, c) = steps.next()?;
    let mut block = c.clone();
    block.worst_step = Some(first);
    for (step, c) in steps {
        block.merge(c, step);
    }
    Some(block)
}

/// history.csv: one row per converged step; empty cells where a value does not apply.
pub fn history_csv(records: &[StepRecord], dim: usize) -> String {
    // several pairs: each pair's columns last
    let n_pairs = records
        .iter()
        .filter_map(|r| r.pairs.as_ref().map(Vec::len))
        .max()
        .unwrap_or(0);
    let mut out = history_header(dim, n_pairs);
    for r in records {
        history_row(&mut out, r, dim);
        for p in 0..n_pairs {
            pair_columns(&mut out, r.pairs.as_ref().and_then(|ps| ps.get(p)), dim);
        }
        out.push('\n');
    }
    out
}

/// history.csv's header line (with its newline): the step's columns, then `n_pairs` pairs'.
fn history_header(dim: usize, n_pairs: usize) -> String {
    let axes = ["x", "y", "z"];
    let mut out = String::from("step,planned,factor,time,cutbacks,newton_steps,active,stick,slip");
    for a in &axes[..dim] {
        let _ = write!(out, ",force_{a}");
    }
    for a in &axes[..dim] {
        let _ = write!(out, ",obstacle_{a}");
    }
    out.push_str(",max_pressure,half_width,contact_area");
    out.push_str(",kkt_penetration,kkt_positive_lambda_n,kkt_complementarity,kkt_violation");
    out.push_str(",friction_excess,friction_stick_motion,friction_slip_alignment");
    out.push_str(",friction_violation");
    out.push_str(",stop_rule,equilibrium_residual,equilibrium_relative,certificate_worst");
    for p in 1..=n_pairs {
        let _ = write!(out, ",pair{p}_active");
        for a in &axes[..dim] {
            let _ = write!(out, ",pair{p}_force_{a}");
        }
        for a in &axes[..dim] {
            let _ = write!(out, ",pair{p}_obstacle_{a}");
        }
        let _ = write!(
            out,
            ",pair{p}_max_pressure,pair{p}_half_width,pair{p}_contact_area"
        );
    }
    out.push('\n');
    out
}

/// A history.csv cell: the value, or empty.
fn csv_opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map(|x| x.to_string()).unwrap_or_default()
}

/// A history.csv number cell (17 significant digits), or empty.
fn csv_num(v: Option<f64>) -> String {
    v.map(|x| format!("{x:.17e}")).unwrap_or_default()
}

/// The step's columns of its history.csv row (without the pairs' columns and the newline).
fn history_row(out: &mut String, r: &StepRecord, dim: usize) {
    let _ = write!(
        out,
        "{},{},{:.17e},{:.17e},{},{},{},{},{}",
        r.step,
        r.planned,
        r.factor,
        r.time,
        r.cutbacks,
        csv_opt(r.newton_steps),
        csv_opt(r.active),
        csv_opt(r.stick),
        csv_opt(r.slip)
    );
    for k in 0..dim {
        let _ = write!(
            out,
            ",{}",
            csv_num(r.total_force.as_ref().and_then(|f| f.get(k).copied()))
        );
    }
    for k in 0..dim {
        let _ = write!(
            out,
            ",{}",
            csv_num(
                r.obstacle_displacement
                    .as_ref()
                    .and_then(|d| d.get(k).copied())
            )
        );
    }
    let _ = write!(
        out,
        ",{},{},{}",
        csv_num(r.max_pressure),
        csv_num(r.half_width),
        csv_num(r.contact_area)
    );
    let (k, f) = (r.kkt.as_ref(), r.friction.as_ref());
    let _ = write!(
        out,
        ",{},{},{},{},{},{},{},{}",
        csv_num(k.map(|k| k.max_penetration)),
        csv_num(k.map(|k| k.max_positive_lambda_n)),
        csv_num(k.map(|k| k.max_complementarity)),
        csv_num(r.kkt_violation),
        csv_num(f.map(|f| f.max_excess)),
        csv_num(f.map(|f| f.max_stick_motion)),
        csv_num(f.map(|f| f.max_slip_alignment_defect)),
        csv_num(r.friction_violation)
    );
    let c = r.certificate.as_ref();
    let _ = write!(
        out,
        ",{},{},{},{}",
        csv_opt(
            c.and_then(|c| serde_json::to_value(c.stop_rule).ok())
                .and_then(|v| v.as_str().map(str::to_string))
        ),
        csv_num(c.map(|c| c.equilibrium.residual_norm)),
        csv_num(c.map(|c| c.equilibrium.relative)),
        csv_num(c.map(|c| c.worst))
    );
}

/// One pair's columns of a history.csv row (empty cells for a pair the step does not have).
fn pair_columns(out: &mut String, s: Option<&PairSummary>, dim: usize) {
    let _ = write!(out, ",{}", csv_opt(s.map(|s| s.active_count)));
    for k in 0..dim {
        let _ = write!(
            out,
            ",{}",
            csv_num(s.and_then(|s| s.total_force.get(k).copied()))
        );
    }
    for k in 0..dim {
        let d = s.map(|s| {
            s.obstacle_displacement
                .as_ref()
                .map_or(0.0, |d| d.get(k).copied().unwrap_or(0.0))
        });
        let _ = write!(out, ",{}", csv_num(d));
    }
    let _ = write!(
        out,
        ",{},{},{}",
        csv_num(s.map(|s| s.max_pressure)),
        csv_num(s.and_then(|s| s.half_width)),
        csv_num(s.and_then(|s| s.contact_area))
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs a schedule against a solver that converges when the step from the last converged
    /// factor is at most `reach`; returns the converged factors, whether the plan was
    /// completed, and the cutbacks.
    fn walk(factors: &[f64], max_cutbacks: usize, reach: f64) -> (Vec<f64>, bool, usize) {
        let plan = LoadSection {
            factors: factors.to_vec(),
            max_cutbacks,
        };
        let mut s = Schedule::new(&plan);
        let (mut done, mut last, mut solves) = (Vec::new(), 0.0f64, 0);
        while let Some(f) = s.next() {
            solves += 1;
            assert!(solves < 1000, "runaway schedule");
            if (f - last).abs() <= reach + 1e-12 {
                s.converged(f);
                done.push(f);
                last = f;
            } else if s.can_cut_back() {
                let r = s.cut_back();
                assert!(
                    close(r, 0.5 * (last + f)),
                    "{r}: the midpoint of {last} and {f}"
                );
            } else {
                return (done, false, s.cutbacks);
            }
        }
        (done, true, s.cutbacks)
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-15
    }

    fn check(got: (Vec<f64>, bool, usize), factors: &[f64], completed: bool, cutbacks: usize) {
        let ok = got.0.len() == factors.len()
            && got.0.iter().zip(factors).all(|(x, y)| close(*x, *y))
            && got.1 == completed
            && got.2 == cutbacks;
        assert!(ok, "{got:?}, expected {factors:?} {completed} {cutbacks}");
    }

    fn at(factor: f64, time: f64) -> StepRecord {
        StepRecord {
            time,
            ..StepRecord::new(1, 1, factor, 0)
        }
    }

    #[test]
    fn predictor_only_while_the_load_goes_on() {
        let done = |fs: &[f64]| -> Vec<StepRecord> { fs.iter().map(|&f| at(f, f)).collect() };
        // the next increment over the last one
        assert_eq!(predictor_ratio(&done(&[0.25, 0.5]), 0.75), 1.0);
        assert_eq!(predictor_ratio(&done(&[0.0, 0.5]), 0.75), 0.5);
        // a held load: factor 0 first, then the ramp
        assert_eq!(predictor_ratio(&done(&[0.0, 0.25]), 0.5), 1.0);
        // the first step has no increment of its own to extrapolate (it started unloaded)
        assert_eq!(predictor_ratio(&done(&[0.25]), 0.5), 0.0);
        assert_eq!(predictor_ratio(&[], 0.5), 0.0);
        // unloading after loading (and back): no predictor
        assert_eq!(predictor_ratio(&done(&[0.5, 1.0]), 0.7), 0.0);
        assert_eq!(predictor_ratio(&done(&[1.0, 0.5]), 0.8), 0.0);
        // unloading on: extrapolated as well
        assert_eq!(predictor_ratio(&done(&[1.0, 0.5]), 0.25), 0.5);
    }

    #[test]
    fn times_increase_along_the_load_path() {
        let mut done: Vec<StepRecord> = Vec::new();
        let mut times = Vec::new();
        for f in [0.3, 0.7, 1.0, 0.5, 0.8] {
            let t = step_time(&done, f);
            times.push(t);
            done.push(at(f, t));
        }
        // the factors themselves while loading, then the path length
        assert_eq!(&times[..3], &[0.3, 0.7, 1.0]);
        assert!(
            (times[3] - 1.5).abs() < 1e-15 && (times[4] - 1.8).abs() < 1e-15,
            "{times:?}"
        );
    }

    #[test]
    fn a_sum_that_misses_the_planned_factor_by_round_off_lands_on_it() {
        // 1.0 + (0.3 − 1.0) = 0.30000000000000004: one step, at 0.3 itself
        for (factors, reach, want) in [
            (&[1.0, 0.3][..], 1.0, &[1.0, 0.3][..]),
            (&[1.0, 0.3][..], 0.4, &[0.25, 0.5, 0.75, 1.0, 0.65, 0.3][..]),
            (&[0.1, 0.7, 0.3][..], 1.0, &[0.1, 0.7, 0.3][..]),
        ] {
            let (got, completed, _) = walk(factors, 5, reach);
            assert!(completed && got == want, "{factors:?}: {got:?}");
        }
    }

    #[test]
    fn no_failure_walks_the_plan() {
        check(walk(&[0.25, 0.5, 1.0], 0, 1.0), &[0.25, 0.5, 1.0], true, 0);
        // unloading and overloading
        check(walk(&[1.0, 2.0, 0.5], 0, 2.0), &[1.0, 2.0, 0.5], true, 0);
    }

    #[test]
    fn cutback_halves_and_keeps_the_increment() {
        // steps of at most 0.3: 1.0 fails, 0.5 fails, 0.25 converges, then 0.5, 0.75, 1.0
        check(walk(&[1.0], 5, 0.3), &[0.25, 0.5, 0.75, 1.0], true, 2);
        // the next planned step starts with its full increment again
        check(walk(&[0.2, 1.0], 5, 0.5), &[0.2, 0.6, 1.0], true, 1);
        // unloading is cut back the same way
        check(
            walk(&[1.0, 0.0], 5, 0.4),
            &[0.25, 0.5, 0.75, 1.0, 0.75, 0.5, 0.25, 0.0],
            true,
            4,
        );
    }

    #[test]
    fn cutbacks_are_bounded() {
        // 1.0 → 0.5 → 0.25 allowed (2 halvings), 0.25 still too far: terminal
        check(walk(&[1.0], 2, 0.2), &[], false, 2);
        // halvings count per planned step, successes between them included: 0.5 fails, 0.25
        // converges, 0.5 converges, 0.75 fails and no halving is left
        check(walk(&[1.0], 2, 0.25), &[0.25, 0.5, 0.75, 1.0], true, 2);
        check(walk(&[0.2, 1.0], 1, 0.3), &[0.2], false, 1);
        check(walk(&[1.0], 0, 0.9), &[], false, 0);
    }
}
