//! The plain path's Newton loop on the full step system: the state carried from step to step,
//! the step itself (pins, system, solve, λ, set update, reduction, log) and its stopping rules.

use crate::case::NewtonInit;
use crate::error::RunError;
use crate::par::Ctx;
use crate::say;
use crate::signorini::active_set::{
    threshold_scale, ActiveSet, Iterate, Law, SetSummary, SetUpdate, StepTotals,
};
use crate::signorini::boundary::{ContactBoundary, NodeResult};
use crate::signorini::cycle::{decide, CycleGuard, Decision, Seen, SetKey};
use crate::signorini::force::{self, Approach};
use crate::signorini::halfspace::{self, HalfSpace, PredictorStep};
use crate::signorini::law::coulomb::{residual_floor, COULOMB_RESIDUAL_TOL, COULOMB_RESIDUAL_ZERO};
use crate::signorini::rigid::{Balance, FreeModes, Motion};
use crate::signorini::step_system::{ReducedSystem, RowChange, SolveKind, StepSolve};

use super::problem::{ContactProblem, NewtonResult, NewtonSettings, StepInfo, WarmStart};
use super::step::{add_motion, ensure_converged, log_step, stalled, After, StepPlan};
/// See [`Loop::fixed_point`] (as the condensed Coulomb iteration's step not taken).
use crate::signorini::active_set::FIXED_POINT_SLACK;
use crate::tuning::{TIGHTEN_ON_RECURRENCE, TIGHTEST_RTOL};

/// The next step's tangential rows hold at the iterate as well as this step's did: `rows` =
/// (‖this step's rows' residuals‖, ‖the next step's‖) at the iterate, `floor` the round-off of
/// a row. Pure.
fn rows_hold((own, next): (f64, f64), floor: f64) -> bool {
    next <= FIXED_POINT_SLACK * own.max(floor)
}

/// The state the loop carries from step to step.
struct Loop<'a> {
    ctx: &'a Ctx<'a>,
    p: &'a ContactProblem<'a>,
    s: &'a NewtonSettings<'a>,
    set: ActiveSet,
    summary: SetSummary,
    free: FreeModes,
    guard: CycleGuard,
    it: Iterate,
    /// Without friction: the rigid motion ρ taken out of the solve (u = ρ + w; the solve, the
    /// set update and the balance test see w and the gaps after ρ, `shifted`).
    rho: Motion,
    shifted: ContactBoundary,
    /// The residual of the last step that changed no state and left u unchanged (below
    /// tol_u), for [`COULOMB_RESIDUAL_STALL`].
    last_still_residual: Option<f64>,
    /// Force control: the approaches δ_j and the gaps they move.
    approach: Option<Approach>,
    /// The free modes are S's null space instead of pinned ([`Loop::free_modes_by_null_space`]).
    null_space: bool,
    /// The changes of the last step the model corrected, and whether the corrections stopped
    /// for good ([`Loop::correct`], [`Loop::corrected`]).
    corrections: (Option<usize>, bool),
    /// A load step's warm start, with friction: [`VANISHING`] · (‖u⁰‖, ‖λ⁰‖) over every rank,
    /// the floors of the norms Algorithm 2's stopping rule divides by ([`Loop::floored`]); 0
    /// without.
    floors: (f64, f64),
    /// The rule of the last stop decided ([`Loop::next`]).
    stop: crate::signorini::certificate::StopRule,
    /// Krylov solves (no factorisation): a recurring set first tightens their tolerance
    /// ([`Loop::new_sets`]); `Some(step)` once that happened after `step`, and the solver is
    /// to be tightened before the next solve while `tighten` is set.
    krylov: bool,
    tightened: Option<usize>,
    tighten: bool,
    /// The Krylov tolerance before it was tightened: given back when the solve ends.
    restore_rtol: Option<f64>,
    /// The model kept the step's set where (3.23) changed nodes, on Krylov solves not yet
    /// tightened ([`Loop::correct`]): the same set is solved once more, tighter.
    resolve: bool,
}

/// A load step whose solution vanishes against its warm start's (the load and the obstacle's
/// motion taken back to zero: u = 0) judges |u^ℓ − u^{ℓ−1}| and Coulomb's residual against
/// this fraction of the warm start's ‖u‖ and ‖λ‖ where its own are smaller, and ends where
/// all three are below it ([`Loop::vanished`]). Measured without it (tests/cases/punch_back.toml,
/// the plain path): the iterate shrank by about 200 × per step while round-off flipped the
/// states of the nodes at a zero gap, |Δu|/|u| stayed at 200, and the last step took 37, 14
/// and 24 Newton steps on 1, 2 and 3 ranks (|C_n| down to 1e-157, then NaN in the log); 2 now.
pub(crate) const VANISHING: f64 = 1e-6;

/// The start "auto": the initially touching nodes (the "gap" start), except for a
/// frictionless body that Dirichlet data leave floating, which starts with no active node:
/// its first solve then places the body by a pin away from the contact and the balance
/// shift ([`crate::signorini::rigid`]) instead of hanging the whole load on the touching point, whose
/// point support inflates the first penetration (3D Hertz: 6 instead of 20 Newton steps;
/// 2D Hertz: 1–2 steps fewer, README).
pub(crate) fn auto_start(init: NewtonInit, friction: bool, free: &FreeModes) -> NewtonInit {
    if init == NewtonInit::Auto && !friction && free.floats() {
        NewtonInit::AllInactive
    } else {
        init
    }
}

/// Algorithm 1 (frictionless, (3.29)), with friction Algorithm 2 (Tresca, (3.42)) or the
/// generalised Newton for Coulomb (docs/friction.md (b), rows (F7)) on the assembled system
/// `sys` (A, f), from the start `s.section.init` or from a previous state `warm`.
pub fn semismooth_newton(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    s: &NewtonSettings,
    warm: Option<&WarmStart>,
) -> Result<NewtonResult, RunError> {
    let (mesh, sys) = (p.mesh, p.sys);
    let dim = mesh.dim;
    let (mut lp, predicting) = Loop::begin(ctx, p, reduced, s, warm)?;
    let mut history = Vec::new();
    let mut converged = false;
    let mut plan = StepPlan {
        exact: !(reduced.inexact_available() && s.law == Law::Frictionless),
        predict: s.halfspace.is_some() && predicting,
        confirm: false,
        correct: false,
        loose: false,
    };
    let mut last_changed = usize::MAX;
    // GMRES on an earlier step's factorisation counts as factorised for the step not taken
    // (a stop there is confirmed by a factorised step, `StepPlan::after_stop`)
    let direct = reduced.kind().factorises();
    for step in 1..=s.section.max_steps {
        let solved = lp.write_and_solve(ctx, p, reduced, s, plan, step)?;
        let reused = solved.reuse.is_some() && solved.kind == SolveKind::Reuse;
        reduced.recover(sys, &lp.shifted, &lp.set, &mut lp.it)?; // (3.28)
        let touch = lp.bordered_step(reduced, step)?;
        let bs = &lp.shifted;
        let scale = threshold_scale(ctx, bs, &lp.it.nodes, s.law, s.c);
        let tie = tie_width(ctx, bs, &lp.it.nodes, s.c);
        let mut update = lp
            .set
            .update_with(&lp.it, bs, s.law, s.c, scale, dim, false, tie); // (3.23) / (3.33) / (F5)
        for tag in touch {
            lp.touch(tag, &mut update);
        }
        let mut predicted = None;
        let mut exact_from_prediction = None;
        if let Some(hs) = s.halfspace.filter(|_| plan.predict) {
            let (rec, exact) = lp.predict(hs, &mut update)?;
            exact_from_prediction = exact;
            predicted = Some(rec);
        } else if let Some(hs) = s.halfspace.filter(|_| plan.correct) {
            predicted = lp.correct(hs, &mut update)?;
        }
        let totals = update.reduce(ctx, &lp.shifted, lp.free.modes(), dim);
        if plan.correct && predicted.is_some() {
            lp.corrected(totals.changed);
        }
        let factorised =
            solved.kind == SolveKind::Factorisation || (solved.kind == SolveKind::Reuse && direct);
        history.push(lp.step_info(step, &totals, solved, reduced.change()));
        history.last_mut().expect("pushed").predictor = predicted;
        log_step(ctx, history.last().expect("pushed"), &totals);
        if std::mem::take(&mut lp.resolve) {
            if plan.loose {
                // the loose solve's error may decide the edge: the same sets, solved exactly
                plan.loose = false;
                continue;
            }
            lp.tightened = Some(step);
            lp.tighten_solver(reduced, "is kept by the model where (3.23) changes it")?;
            continue; // the same sets, solved tighter
        }
        let done = plan;
        let exact_now = exact_from_prediction.unwrap_or(done.exact);
        // Identical on every rank: `totals` and the guard's keys are global.
        let recurs =
            !exact_now && totals.changed > 0 && lp.guard.has_seen(lp.key(&totals.next, &totals));
        plan = match done.after_solve(exact_now, totals.changed, recurs, &mut last_changed) {
            After::Repeat(next) => {
                plan = next;
                continue; // the same sets
            }
            After::Update(next) => next,
        };
        let totals = lp.fixed_point(totals, factorised, scale);
        let stopped = lp.next(step, update.next, &totals)?;
        if std::mem::take(&mut lp.tighten) {
            lp.tighten_solver(reduced, "recurs")?;
        }
        if stopped {
            match done.after_stop(reused) {
                After::Repeat(next) => {
                    plan = next;
                    continue;
                }
                After::Update(_) => {
                    converged = true;
                    break;
                }
            }
        }
    }
    if let Some(rtol) = lp.restore_rtol.take() {
        reduced.set_krylov_rtol(rtol)?; // the next solve (load step, pass) at the case's
    }
    lp.finish(reduced, history, converged)
}

impl Loop<'_> {
    /// A step's first phase: the free rigid modes' pins (or a null space), the rigid motion
    /// taken out of a frictionless solve, the gaps at the approach, and the step system
    /// (3.29) / (3.42) written and solved as `plan` says. Collective.
    fn write_and_solve(
        &mut self,
        ctx: &Ctx,
        p: &ContactProblem,
        reduced: &mut ReducedSystem,
        s: &NewtonSettings,
        plan: StepPlan,
        step: usize,
    ) -> Result<StepSolve, RunError> {
        let (mesh, layout, b, sys) = (p.mesh, p.layout, p.boundary, p.sys);
        let gram = self.set_gram();
        let modes_changed = self.free.update(ctx, mesh, layout, &gram)?;
        let null_space = self.free_modes_by_null_space(reduced, modes_changed)?;
        if !s.friction() && self.approach.is_none() {
            // Friction reads u_τ itself (stick rows, slip rows), so only the frictionless
            // solve can leave the rigid motion out.
            self.rho = self
                .free
                .fit_motion(ctx, b, &self.set.normal, &self.summary.gram, mesh);
            self.free.shift(b, &self.rho, &mut self.shifted);
        }
        if let Some(ap) = &self.approach {
            ap.place(&mut self.shifted); // the gaps at δ_ℓ
        }
        let bs = &self.shifted;
        let pins = if null_space {
            &[][..]
        } else {
            self.free.pins()
        };
        reduced.write(ctx, sys, layout, bs, &self.set, pins)?; // (3.29) / (3.42)
        reduced.set_inexact(!plan.exact || plan.loose);
        if plan.predict {
            // a floating body: the model predicts from the gaps alone (no first solve)
            reduced.set_predictor_solve(self.free.floats() && self.approach.is_none());
        }
        let allow_reuse = s.law != Law::Coulomb && !plan.confirm;
        let solved = reduced.solve(ctx, allow_reuse)?;
        ensure_converged(step, &solved.info, &b.keys)?;
        if null_space {
            self.zero_pins(reduced)?;
        }
        Ok(solved)
    }
}

impl<'a> Loop<'a> {
    /// The loop's start: the free modes (and force control's approach), the first set — the
    /// warm one, the case's start, or all inactive for the half-space predictor — and the
    /// iterate. Returns the loop and whether the first step predicts. Collective.
    fn begin(
        ctx: &'a Ctx<'a>,
        p: &'a ContactProblem<'a>,
        reduced: &mut ReducedSystem,
        s: &'a NewtonSettings<'a>,
        warm: Option<&WarmStart>,
    ) -> Result<(Loop<'a>, bool), RunError> {
        let (mesh, layout, b, fixed, sys) = (p.mesh, p.layout, p.boundary, p.fixed, p.sys);
        let dim = mesh.dim;
        let free = FreeModes::new(ctx, mesh, layout, fixed, b, &reduced.f_local, s.rigid);
        let approach = match s.force {
            [] => None,
            [fc, ..] if free.floats() && s.force.len() == b.n_pairs() && b.n_pairs() > 1 => {
                return Err(force::all_pairs_floating(fc));
            }
            [fc, ..] if free.floats() && b.n_pairs() == 1 => {
                return Err(force::floating(fc));
            }
            fcs => Some(Approach::new(b, fcs)),
        };
        let mut placed = b.clone();
        if let Some(ap) = &approach {
            ap.place(&mut placed); // the gaps at the start's δ
        }
        reduced.set_pins(sys, layout, free.pins())?; // none yet (the system may be reused)
                                                     // The half-space predictor (iterative preset's reuse path, frictionless, the "auto"
                                                     // start, no warm start): the first solve has no active node (u⁰ = K_p⁻¹ f, the model's
                                                     // d₀), also where the "gap" start would clamp the initially touching nodes.
                                                     // the iterative preset's reuse path; on the direct preset `halfspace` is given only
                                                     // where the condensed path found the zone too wide for the dense limits (mod.rs)
        let predicting = s.halfspace.is_some()
            && (reduced.inexact_available() || reduced.kind().factorises())
            && s.law == Law::Frictionless
            && warm.is_none()
            && s.section.init == NewtonInit::Auto;
        let init = if predicting {
            NewtonInit::AllInactive
        } else {
            auto_start(s.section.init, s.friction(), &free)
        };
        // a warm start's rows against the obstacles at the start's approaches (force control:
        // Coulomb's threshold (F1) reads the gaps, the increments the moved references)
        let set = match warm {
            None => ActiveSet::initial(&placed, init, s.law, s.c, mesh.extent(), dim),
            Some(w) => {
                let scale = threshold_scale(ctx, &placed, w.nodes, s.law, s.c);
                ActiveSet::warm(&placed, w.nodes, s.law, s.c, scale, dim)
            }
        };
        let summary = set.summarise(ctx, b, free.modes(), dim);
        let guard = CycleGuard::new(
            s.section.on_cycle,
            s.friction(),
            SetKey::new(summary.n_active, summary.fingerprint, None),
        );
        let mut it = Iterate::new(b.nodes.len(), reduced.f_local.len(), s.friction());
        let mut floors = (0.0, 0.0);
        if let Some(w) = warm {
            it.warm(w.u_local, w.nodes);
        }
        // Algorithm 2's stopping rule (friction) reads ‖u‖, ‖u − u_prev‖ and ‖λ‖; without
        // friction the iteration ends when no state changes, and these are not measured
        if let Some(w) = warm.filter(|_| s.friction()) {
            let w = w.floors_from.unwrap_or(w);
            let uu: f64 = w.u_local.iter().map(|x| x * x).sum();
            let ll: f64 = (w.nodes.iter()).flat_map(|r| r.lambda).map(|x| x * x).sum();
            let g = ctx.sum_vec(&[uu, ll]);
            floors = (VANISHING * g[0].sqrt(), VANISHING * g[1].sqrt());
        }
        let rho = free.no_motion();
        let lp = Loop {
            ctx,
            p,
            s,
            set,
            summary,
            free,
            guard,
            it,
            rho,
            shifted: placed,
            last_still_residual: None,
            stop: crate::signorini::certificate::StopRule::ActiveSet,
            approach,
            null_space: false,
            corrections: (None, false),
            floors,
            krylov: !reduced.kind().factorises(),
            tightened: None,
            tighten: false,
            restore_rtol: None,
            resolve: false,
        };
        reduced.set_free_null_space(ctx, None)?; // none left from an earlier solve
        Ok((lp, predicting))
    }

    /// The Gram matrix of the set's rows that the free modes are read from: the set's own, or,
    /// under force control of a floating body, the one with the approaches eliminated
    /// ([`FreeModes::couple`]): a rigid motion that the force-controlled obstacles follow is
    /// free, its balance includes the prescribed forces. Collective under force control of a
    /// floating body (one reduction).
    fn set_gram(&mut self) -> crate::signorini::rigid::Gram {
        let (Some(ap), Some(modes), true) = (&self.approach, self.free.modes(), self.free.floats())
        else {
            return self.summary.gram.clone();
        };
        let b = &self.p.boundary;
        let coupling = ap.couplings(self.ctx, b, &self.set, modes, self.p.mesh.dim);
        self.free.couple(&self.summary.gram, coupling)
    }

    /// Force control's first touch: the node `tag` joins the next set (counted as a change).
    /// Local.
    fn touch(&self, tag: u64, update: &mut SetUpdate) {
        for (k, a) in self.shifted.nodes.iter().zip(update.next.normal.iter_mut()) {
            if k.tag == tag && !*a {
                *a = true;
                update.changed += 1;
            }
        }
    }

    /// The half-space predictor after the first solve: the predicted set replaces the next
    /// one (and, under force control, δ moves to the predicted approach). Returns the record
    /// and whether the next step is exact (a prediction that reaches the model's border is
    /// not). Collective.
    fn predict(
        &mut self,
        hs: &HalfSpace,
        update: &mut SetUpdate,
    ) -> Result<(PredictorStep, Option<bool>), RunError> {
        let s = self.s;
        let force: Vec<_> = self.approach.as_ref().map_or(Vec::new(), |a| {
            a.pairs
                .iter()
                .map(|p| (p.dir, p.magnitude, p.pair))
                .collect()
        });
        let limits = s.dense_limits();
        let (set, rec) = halfspace::predict(
            self.ctx,
            hs,
            &self.shifted,
            &self.it,
            &self.free,
            limits,
            &force,
        )?;
        let mut exact = None;
        if let Some(normal) = set {
            update.replace_normal(&self.set, normal);
            exact = Some(!rec.truncated);
        }
        if let (Some(ap), Some(d)) = (self.approach.as_mut(), rec.approach_change.as_ref()) {
            for (p, d) in ap.pairs.iter_mut().zip(d) {
                p.delta += d; // the next step solves at the predicted approach
            }
        }
        Ok((rec, exact))
    }

    /// The model's correction of an exact step's set update ([`halfspace::correct`]; not
    /// under force control): when (3.23) changes nodes, the next set is the model's, unless the
    /// model keeps the step's own set, where (3.23)'s update stays (so a correction never stops
    /// the iteration, which ends on an exact step whose update changes nothing). A node that
    /// (3.23) changes but the model does not is left to the next exact step: (3.23) from a set
    /// short of the final one also takes nodes that the growing zone lifts off again (measured:
    /// the full ball at 396 k unknowns pressed by 0.02: keeping every such change took 5 steps,
    /// changes 124, 19, 1, 0; the model's set 4, changes 107, 7, 0). The model's record, or
    /// `None` when (3.23) changes nothing, the corrections have stopped ([`Loop::corrected`]) or
    /// the model's edge band does not fit ([`halfspace::correct`]). Collective.
    fn correct(
        &mut self,
        hs: &HalfSpace,
        update: &mut SetUpdate,
    ) -> Result<Option<PredictorStep>, RunError> {
        let ctx = self.ctx;
        if self.approach.is_some() || self.corrections.1 || ctx.sum_usize(update.changed) == 0 {
            return Ok(None);
        }
        let (b, it, active) = (&self.shifted, &self.it, self.set.normal.as_slice());
        let limits = self.s.dense_limits();
        let Some((set, rec)) = halfspace::correct(ctx, hs, b, it, active, &self.free, limits)?
        else {
            return Ok(None);
        };
        if let Some(model) = set.filter(|_| !rec.truncated) {
            let moved = model
                .iter()
                .zip(&self.set.normal)
                .filter(|(m, now)| m != now);
            if ctx.sum_usize(moved.count()) > 0 {
                update.replace_normal(&self.set, model);
            } else if self.krylov && self.tightened.is_none() {
                // the model and (3.23) disagree on nodes at the edge of their state: the
                // solver's error may decide them
                self.resolve = true;
            }
        }
        Ok(Some(rec))
    }

    /// A set recurred on Krylov solves ([`Loop::new_sets`]), or the model kept a set that
    /// (3.23) changes ([`Loop::correct`]; `what` says which): the solver's relative tolerance
    /// divided by [`TIGHTEN_ON_RECURRENCE`] (not below [`TIGHTEST_RTOL`]) for the steps from
    /// here to the end of this solve; said in the log. Collective.
    fn tighten_solver(&mut self, reduced: &mut ReducedSystem, what: &str) -> Result<(), RunError> {
        let step = self.tightened.unwrap_or(0);
        match reduced.tighten_krylov(TIGHTEN_ON_RECURRENCE, TIGHTEST_RTOL)? {
            Some((from, to)) => {
                self.restore_rtol = Some(from);
                say!(
                    self.ctx,
                    "newton: the set of step {step} {what} on Krylov solves to rtol {from:.0e}: \
                     a node at the edge of its state may flip on the solver's error; the steps \
                     from here solve to {to:.0e}"
                )
            }
            None => say!(
                self.ctx,
                "newton: the set of step {step} {what}; the Krylov solves are at their tightest \
                 tolerance already"
            ),
        }
        Ok(())
    }

    /// After a corrected step's update (`changed` nodes, global): the corrections stop for good
    /// when a corrected step changes no fewer nodes than the one before it (the model does not
    /// converge on this body; (3.23) alone goes on, as without a model). Local.
    fn corrected(&mut self, changed: usize) {
        let (last, _) = self.corrections;
        let stop = last.is_some_and(|l| changed >= l);
        self.corrections = (Some(changed), stop);
    }

    /// The result: u = w + ρ (the rigid motion added back), the final iterate and the record.
    /// Collective.
    fn finish(
        self,
        reduced: &ReducedSystem,
        history: Vec<StepInfo>,
        converged: bool,
    ) -> Result<NewtonResult, RunError> {
        let mut u = reduced.solution()?;
        let mut nodes = self.it.nodes;
        add_motion(&self.free, &self.rho, self.p, &mut u, &mut nodes)?;
        Ok(NewtonResult {
            nodes,
            steps: history.len(),
            history,
            converged,
            lambda_seconds: reduced.lambda_seconds,
            rows_seconds: reduced.rows_seconds,
            pinned_final: self.free.pins().to_vec(),
            cycle_detected_at: self.guard.detected_at,
            approach: self.approach.map_or(Vec::new(), |a| a.deltas()),
            stop: self.stop,
            u,
        })
    }
}

impl Loop<'_> {
    /// Whether this step removes the free rigid modes by S's null space instead of pins, and
    /// the null space attached or detached accordingly: on the iterative preset's reuse path,
    /// frictionless, without force control, when the load is balanced in every free mode (the
    /// pins would carry nothing; an unbalanced load keeps them: the predictor's first solve,
    /// the body moved until it touches). The pins' rows are read anew when the modes or this
    /// choice changed (none with the null space). Collective when it changes.
    fn free_modes_by_null_space(
        &mut self,
        reduced: &mut ReducedSystem,
        modes_changed: bool,
    ) -> Result<bool, RunError> {
        let use_it = reduced.inexact_available()
            && !self.s.friction()
            && self.approach.is_none()
            && !self.free.pins().is_empty()
            && self.free.balanced();
        let (mesh, layout) = (self.p.mesh, self.p.layout);
        if use_it != self.null_space || modes_changed {
            let pins = if use_it { &[][..] } else { self.free.pins() };
            reduced.set_pins(self.p.sys, layout, pins)?;
        }
        if use_it != self.null_space || (use_it && modes_changed) {
            let (row_lo, n_local) = reduced.local_rows();
            let fields = use_it.then(|| self.free.free_fields(mesh, layout, row_lo, n_local));
            reduced.set_free_null_space(self.ctx, fields)?;
            self.null_space = use_it;
        }
        Ok(use_it)
    }

    /// After a solve with the free modes as S's null space: the solution moved by the free
    /// rigid motion that makes it vanish at the pins, the member of u + Σ α_j r_j that the
    /// pinned solve gives. Collective.
    fn zero_pins(&self, reduced: &mut ReducedSystem) -> Result<(), RunError> {
        let (mesh, layout, dim) = (self.p.mesh, self.p.layout, self.p.mesh.dim);
        let idx: Vec<crate::petsc::PInt> = (self.free.pins().iter())
            .map(|&(v, k)| (v * dim + k) as crate::petsc::PInt)
            .collect();
        let at = reduced.solution_at(&idx)?;
        let rho = self.free.motion_to_zero_pins(&at, &self.free.no_motion());
        let (row_lo, n_local) = reduced.local_rows();
        let mut delta = vec![0.0; n_local];
        for &v in &layout.owned_nodes {
            for k in 0..dim {
                delta[layout.node_global[v] * dim + k - row_lo] =
                    self.free.motion_at(&rho, v, &mesh.coords[v], k);
            }
        }
        reduced.add_to_solution(&delta)?;
        Ok(())
    }

    fn step_info(
        &self,
        step: usize,
        t: &StepTotals,
        solved: StepSolve,
        change: Option<RowChange>,
    ) -> StepInfo {
        let factorisation_seconds = solved
            .setup_seconds
            .filter(|_| solved.kind == SolveKind::Factorisation);
        StepInfo {
            step,
            active: self.summary.n_active,
            changed: t.changed,
            residual: t.residual,
            solve_seconds: solved.seconds,
            solve: solved.kind,
            iterations: solved.info.iterations,
            reuse: solved.reuse,
            amg: solved.amg,
            pinned: self.free.pins().len(),
            states: self.s.friction().then_some(t.states),
            du_rel: self.s.friction().then_some(t.du_rel),
            predictor: None,
            change,
            factorisation_seconds,
        }
    }

    fn key(&self, summary: &SetSummary, t: &StepTotals) -> SetKey {
        SetKey::new(
            summary.n_active,
            summary.fingerprint,
            self.s.friction().then_some(t.u_norm2),
        )
    }

    /// Algorithm 2's step that tests |u^ℓ − u^{ℓ−1}| is not taken where it would return u^ℓ:
    /// no state changed, u^ℓ came from a factorisation (direct preset), and the next step's
    /// rows (3.39) / (F6) hold at u^ℓ as well as this step's did (within [`FIXED_POINT_SLACK`]
    /// × their residual at u^ℓ, or ε × the largest threshold `scale` per row), so the next
    /// system is this one to round-off. Its |Δu|/|u| is then counted 0 (the 2D slip row is
    /// λ_τ = ±b once settled: measured on the held Hertz disk at 171 602 unknowns, Tresca, the
    /// last step repeated the sets of the one before with the residual unchanged, 9.3e-15).
    /// Not under force control, whose approach moves the gaps between steps. Local (`t` is
    /// global).
    fn fixed_point(&self, mut t: StepTotals, factorised: bool, scale: f64) -> StepTotals {
        let n = self.p.boundary.n_global.max(1) as f64;
        let floor = f64::EPSILON * scale * n.sqrt();
        let plain = factorised && self.s.friction() && self.approach.is_none();
        if plain && t.changed == 0 && rows_hold(t.rows, floor) {
            t.du_rel = 0.0;
        }
        t
    }

    /// The iterate and its change, u, u − u_prev and λ, are all below the warm start's floors
    /// ([`VANISHING`]): the step's solution is zero to that fraction of the step before's,
    /// and the states of its nodes (gaps, forces and motions of round-off size) are
    /// round-off too — they flip from step to step, so only this ends the iteration. Local.
    fn vanished(&self, t: &StepTotals) -> bool {
        let (fu, fl) = self.floors;
        let u = t.u_norm2.sqrt();
        fu > 0.0 && u < fu && t.du_rel * u < fu && t.lambda_norm < fl
    }

    /// The step's totals with |Δu|/|u| and ‖λ‖ taken against the warm start's floors
    /// ([`VANISHING`]) where u and λ are below them. Local.
    fn floored(&self, t: &StepTotals) -> StepTotals {
        let (fu, fl) = self.floors;
        let u = t.u_norm2.sqrt();
        let mut t = t.clone();
        if u < fu {
            t.du_rel *= u / fu;
        }
        t.lambda_norm = t.lambda_norm.max(fl);
        t
    }

    /// The decision after step `step` and the sets of the next step; `Ok(true)` = converged.
    fn next(&mut self, step: usize, mut next: ActiveSet, t: &StepTotals) -> Result<bool, RunError> {
        if self.vanished(t) {
            say!(
                self.ctx,
                "newton: u and λ below {VANISHING:e} of the warm start's: the step's solution \
                 vanishes (its states are round-off)"
            );
            self.stop = crate::signorini::certificate::StopRule::Vanishing;
            return Ok(true);
        }
        let t = &self.floored(t);
        let pins = !self.free.pins().is_empty();
        let rows_move = t.changed == 0 && self.s.friction() && t.du_rel >= self.s.section.tol_u;
        if pins && rows_move && t.next.gram != self.summary.gram {
            // No state changed, but a slip row begins or stops holding u_τ (Coulomb: b turns
            // positive after a frictionless first step): the pins change with the next rows, so
            // neither the balance test nor the stop applies yet.
            self.set.tangential = next.tangential;
            self.summary = t.next.clone();
            return Ok(false);
        }
        let residual = self.residual_acceptance(t);
        let mut decision = self.decision(t, pins, residual);
        if decision == Decision::TestBalance {
            match self.balance_test(next, t, residual)? {
                Ok((balanced, kept)) => (decision, next) = (balanced, kept),
                Err(done) => return Ok(done),
            }
        }
        match decision {
            Decision::Converged => {
                self.stop = self.stop_rule(t);
                Ok(true)
            }
            Decision::SameSets => {
                // Same sets, but the slip rows are a linearisation: iterate on with the new rows.
                // A slip row may start or stop holding u_τ (L̃ ≠ 0, e.g. Coulomb's b turning
                // positive) without a state change: the Gram matrix (the pins) follows it.
                self.set.tangential = next.tangential;
                self.summary = t.next.clone();
                Ok(false)
            }
            Decision::TestBalance => unreachable!("the balance test was made above"),
            Decision::NewSets => self.new_sets(step, next, t),
        }
    }

    /// Whether Coulomb's residual lets the iteration stop (its tolerance, or a stall at
    /// round-off: [`stalled`]) and whether it is round-off at once; (true, false) for the other
    /// laws. Records this step's residual for the next step's stall test. Local.
    fn residual_acceptance(&mut self, t: &StepTotals) -> (bool, bool) {
        let still = t.changed == 0 && t.du_rel < self.s.section.tol_u;
        let floor = residual_floor(self.s.c, t.contact_u);
        let stalled = stalled(
            still,
            self.last_still_residual,
            t.residual,
            t.lambda_norm,
            floor,
        );
        self.last_still_residual = still.then_some(t.residual);
        match self.s.law {
            Law::Coulomb => (
                t.residual <= COULOMB_RESIDUAL_TOL * t.lambda_norm || stalled,
                t.residual <= COULOMB_RESIDUAL_ZERO * t.lambda_norm,
            ),
            _ => (true, false),
        }
    }

    /// Algorithm 1/2's decision after a step ([`decide`]) with `pins` free rigid modes pinned
    /// and the residual's acceptance `residual` ([`Loop::residual_acceptance`]). Local.
    fn decision(&self, t: &StepTotals, pins: bool, residual: (bool, bool)) -> Decision {
        decide(
            t.changed,
            pins,
            self.s.friction(),
            t.du_rel,
            self.s.section.tol_u,
            residual.0,
            residual.1,
        )
    }

    /// The balance test of the free rigid modes: a free mode is harmless only if the load is
    /// balanced in it (the pins then carry no reaction). Balanced: `Ok(Ok)` with the decision
    /// without pins and `next` as it was. If not, the body moves along the unbalanced load
    /// until a contact node touches: that node is activated and the next sets taken
    /// (`Ok(Err(false))`: not converged); where no node approaches the obstacle there is no
    /// equilibrium (the error). Collective where the load is unbalanced.
    fn balance_test(
        &mut self,
        mut next: ActiveSet,
        t: &StepTotals,
        residual: (bool, bool),
    ) -> Result<Result<(Decision, ActiveSet), bool>, RunError> {
        let (ctx, dim, b) = (self.ctx, self.p.mesh.dim, &self.shifted);
        match self.free.balance(ctx, b, &self.it.nodes, &self.set.normal) {
            Balance::Balanced => Ok(Ok((self.decision(t, false, residual), next))),
            Balance::Touch(tag) => {
                for (k, a) in b.nodes.iter().zip(next.normal.iter_mut()) {
                    if k.tag == tag {
                        *a = true;
                    }
                }
                say!(
                    ctx,
                    "newton: the load is not balanced in a free rigid mode: the body moves \
                     until contact node {tag} touches (activated)"
                );
                let summary = next.summarise(ctx, b, self.free.modes(), dim);
                self.guard.record(self.key(&summary, t));
                self.take(next, summary);
                Ok(Err(false))
            }
            Balance::NoSupport(reaction) => {
                Err(self.free.no_support(self.summary.n_active, reaction))
            }
        }
    }

    /// How a converged iteration stopped: Coulomb accepted by the stall rule alone is a
    /// loosened acceptance. Local.
    fn stop_rule(&self, t: &StepTotals) -> crate::signorini::certificate::StopRule {
        let loose = self.s.law == Law::Coulomb && t.residual > COULOMB_RESIDUAL_TOL * t.lambda_norm;
        match loose {
            true => crate::signorini::certificate::StopRule::CoulombStall,
            false => crate::signorini::certificate::StopRule::ActiveSet,
        }
    }

    /// New sets after step `step`: the cycle guard's check (a recurring set while the iterate
    /// no longer moves stops a friction solve; cycling switches to single-node updates), then
    /// the next step's sets taken; `Ok(true)` = stopped. Collective (the guard's keys and the
    /// least-index pick are global).
    fn new_sets(
        &mut self,
        step: usize,
        mut next: ActiveSet,
        t: &StepTotals,
    ) -> Result<bool, RunError> {
        let (ctx, dim) = (self.ctx, self.p.mesh.dim);
        let b = &self.shifted;
        let mut summary = t.next.clone();
        let mut key = self.key(&summary, t);
        if self.krylov && self.tightened.is_none() && self.guard.has_seen(key) {
            // A recurring set on Krylov solves: a node at the edge of its state may flip on
            // the solver's error alone; the next solves are tighter (the main loop), and the
            // set is taken again before anything is called cycling
            self.tightened = Some(step + 1);
            self.tighten = true;
            self.guard.record(key);
            self.take(next, summary);
            return Ok(false);
        }
        let seen = match self.guard.check(step, key) {
            Err(_) if self.s.friction() && t.du_rel < self.s.section.tol_u => {
                // A recurring set while the iterate no longer moves: the nodes that
                // flip sit on the stick/slip threshold to round-off (both states hold
                // the same u and λ; several ranks' solver round-off differs from run
                // to run). Stop here; the KKT and friction certificates that follow
                // decide whether this iterate is a solution.
                say!(
                    ctx,
                    "newton: the set of step {} recurs while |Δu|/|u| = {:.1e} < tol_u: nodes on the \
                     stick/slip threshold to round-off; stopping",
                    step + 1,
                    t.du_rel
                );
                self.stop = crate::signorini::certificate::StopRule::RecurringSet;
                return Ok(true);
            }
            Err(e) => return Err(self.cycle_error(e)),
            Ok(seen) => seen,
        };
        if let Seen::SwitchToLeastIndex { prev } = seen {
            say!(
                ctx,
                "newton: cycling detected (the set of step {prev} recurs at step {}): \
                 continuing with single-node updates (penetrating nodes first, least \
                 index first)",
                step + 1
            );
        }
        if self.guard.least_index() {
            least_index_step(ctx, b, &self.set, &mut next);
            summary = next.summarise(ctx, b, self.free.modes(), dim);
            key = self.key(&summary, t);
            if let Err(e) = self.guard.check_safeguarded(step, key) {
                return Err(self.cycle_error(e));
            }
        }
        self.guard.record(key);
        self.take(next, summary);
        Ok(false)
    }

    /// A cycle of a frictionless body that the contact cannot hold
    /// ([`FreeModes::unpressable`]) is reported as its "no support"; any other cycle as it
    /// is. Collective (every rank meets the same cycle).
    fn cycle_error(&self, e: RunError) -> RunError {
        if !self.s.friction() && self.free.unpressable(self.ctx, self.p.boundary) {
            return self.free.no_support_unpressed();
        }
        let e = match (&e, self.s.friction(), self.free.cycle_hint()) {
            (RunError::NoConvergence(m), false, Some(hint)) => {
                RunError::NoConvergence(format!("{m}{hint}"))
            }
            _ => e,
        };
        match e {
            // Krylov steps are inexact (solver.rtol, tightened on a recurrence): their sets
            // can cycle where exact ones do not (floating blocks stacked on each other, body
            // pairs, 2 and 3 ranks: a balanced load the direct preset solves exactly)
            RunError::NoConvergence(m) if self.krylov => RunError::NoConvergence(format!(
                "{m}; the steps' linear solves were iterative (GMRES to solver.rtol), whose \
                 inexact steps can cycle where exact ones converge: try solver.preset = \
                 \"direct\""
            )),
            e => e,
        }
    }

    /// Force control: the step's δ's from the force balance (force.rs), u and λ moved with
    /// them and the gaps placed; the tags of the nodes that touch for the pairs without an
    /// active node. Logs each pair's δ and contact force along F before the step. Collective.
    fn bordered_step(
        &mut self,
        reduced: &mut ReducedSystem,
        step: usize,
    ) -> Result<Vec<u64>, RunError> {
        let Some(ap) = self.approach.as_mut() else {
            return Ok(Vec::new());
        };
        let deltas = ap.deltas();
        let forces = ap.forces_along(self.ctx, &self.it);
        let moved = force::Moved {
            boundary: &mut self.shifted,
            approach: ap,
            iterate: &mut self.it,
        };
        let c = force::correct(
            self.ctx,
            self.p,
            reduced,
            &self.set,
            self.free.pins(),
            &forces,
            moved,
        )?;
        let several = ap.pairs.len() > 1;
        for (j, p) in ap.pairs.iter().enumerate() {
            let how = match c.touched.iter().find(|(q, _)| *q == j) {
                Some((_, tag)) => format!("until contact node {tag} touches"),
                None => "from the force balance".to_string(),
            };
            let which = if several {
                format!(" ({})", p.key())
            } else {
                String::new()
            };
            say!(
                self.ctx,
                "force control{which}, step {step}: at δ = {:.6e} the contact force along F is \
                 {:.6e} (|F| = {:.6e}); δ → {:.6e} {how}",
                deltas[j],
                forces[j],
                p.magnitude,
                p.delta
            );
        }
        Ok(c.touched.into_iter().map(|(_, tag)| tag).collect())
    }

    fn take(&mut self, set: ActiveSet, summary: SetSummary) {
        self.set = set;
        self.summary = summary;
    }
}

/// Single-node update: activate the penetrating node with the smallest tag; only if none
/// penetrates, release the node in tension with the smallest tag (a least-index rule in the
/// spirit of Murty's, biased towards sets that hold the body, since sets that leave rigid
/// modes to the pins are not LCP pivots). Collective.
fn least_index_step(ctx: &Ctx, b: &ContactBoundary, old: &ActiveSet, next: &mut ActiveSet) {
    let pick = |want_activate: bool| -> u64 {
        let my_min = b
            .nodes
            .iter()
            .zip(old.normal.iter().zip(&next.normal))
            .filter(|(_, (a, n))| a != n && **n == want_activate)
            .map(|(k, _)| k.tag)
            .min()
            .unwrap_or(u64::MAX);
        ctx.min_u64(my_min)
    };
    let mut tag = pick(true);
    if tag == u64::MAX {
        tag = pick(false);
    }
    for ((k, a), n) in b.nodes.iter().zip(&old.normal).zip(next.normal.iter_mut()) {
        *n = if k.tag == tag { !*a } else { *a };
    }
}

/// The width within which a node's (3.23) test is a tie ([`crate::contact::ties`]) over every
/// contact node: such a node carries no force at zero gap to round-off and keeps its state, as
/// in the dense iteration. Without it a floating plate tipped onto an edge of 9 nodes dropped
/// one of them by the sign of round-off (|C_n| 2.9e-11) in the step that confirmed the stop,
/// the plate's rotation about the edge was free in the next, every node came back into contact
/// and the plain path failed after its 100 steps (tests/ties.rs). Collective (two reductions).
fn tie_width(ctx: &Ctx, b: &ContactBoundary, nodes: &[NodeResult], c: f64) -> f64 {
    let (mut lambda, mut length) = (0.0_f64, 0.0_f64);
    for (k, r) in b.nodes.iter().zip(nodes) {
        lambda = lambda.max(r.lambda_n.abs());
        length = length.max(r.u_n.abs()).max(k.gap.abs());
    }
    let (lambda, length) = (ctx.max_f64(lambda), ctx.max_f64(length));
    if lambda <= crate::contact::complementarity::SET_ROUND_OFF * c * length {
        // every force is itself round-off (a body that nothing holds, an unloaded step):
        // no node carries a force to keep, and the test's sign decides as written
        return 0.0;
    }
    crate::contact::ties(lambda, length, c)
}

#[cfg(test)]
mod tests;
