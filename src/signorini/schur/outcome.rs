//! How a pass of the Schur path ends: solved, factorised (kept for the next load step) or
//! fallen back to the plain path, with the reason.

use super::candidates::{Candidates, Compliance};
pub(super) use super::stop::Stop;
use super::summary::CondensedSummary;
use crate::error::RunError;
use crate::par::Ctx;
use crate::say;
use crate::signorini::active_set::Iterate;
use crate::signorini::kept::KeptFactor;
use crate::signorini::plain_path::{add_motion, ContactProblem, NewtonResult, StepInfo};
use crate::signorini::rigid::{FreeModes, Motion, Pin};
use crate::signorini::step_system::ReducedSystem;

/// What the condensed path returns: the solution, or the reason to run the plain path.
pub enum Condensed {
    Solved(Box<NewtonResult>, CondensedSummary),
    Fallback(CondensedSummary),
    /// [`solve_keeping`](super::frictionless::solve_keeping) without the frictionless steps: K_p
    /// factorised with the first candidates' Schur complement, nothing solved.
    Factorised(CondensedSummary),
}

/// What a converged condensed solve with every dof of the candidates in the Schur complement
/// (`per` = d) leaves for a friction solve on the same candidates: the compliance with its
/// factorisation, the candidates, f on rank 0, the free modes (K_p's pins) and the
/// frictionless set and λ_n
/// over every contact node (c_h's global order).
pub struct Kept {
    pub(crate) comp: Compliance,
    pub(crate) cand: Candidates,
    pub(crate) f_root: Vec<f64>,
    pub(crate) n_local: usize,
    pub(crate) free: FreeModes,
    pub(crate) lambda: Vec<f64>,
    pub(crate) active: Vec<bool>,
    /// The nodes K_p holds on the obstacle, sticking (c_h's global order; empty: none).
    pub(crate) held: Vec<bool>,
    /// The zone they were held in (c_h's global order; empty: none).
    pub(crate) zone: Vec<bool>,
}

impl Kept {
    /// The kept factorisation holds a step with free modes `free` and candidates `cand`: the
    /// same pins, `per` Schur variables per candidate, and the kept candidates' rows and node
    /// frames (K_p was factorised in them). Local (on all-gathered data).
    pub(super) fn holds(&self, free: &FreeModes, cand: &Candidates, per: usize) -> bool {
        self.comp.per == per
            && free.pins() == self.free.pins()
            && self.cand.n == cand.n
            && self
                .comp
                .list
                .iter()
                .all(|&i| cand.row(i) == self.cand.row(i) && cand.n(i) == self.cand.n(i))
    }
}

/// A converged solve's result and what it keeps: with `per` > 1 the kept compliance for the
/// friction solve; else the factorisation for the next load step (`store`). Local.
pub(super) fn keep_solved(
    store: &mut KeptFactor,
    solved: Condensed,
    kept: Kept,
    per: usize,
) -> (Condensed, Option<Kept>) {
    match per > 1 {
        true => (solved, Some(kept)),
        false => {
            // for the next load step (a held zone's too: its rows' values are in f)
            store.put(kept);
            (solved, None)
        }
    }
}

/// The expanded iterate of a round: (3.28) on w with the set, the rigid motion ρ that u = w + ρ
/// carries, the pins of the set's free modes, and the global indices of the nodes (3.23)
/// changes.
pub(super) struct Expanded {
    pub(super) it: Iterate,
    pub(super) rho: Motion,
    pub(super) pins: Vec<Pin>,
    pub(super) changed: Vec<u64>,
    /// Force control: the approach δ_j of the round per force-controlled pair.
    pub(super) approach: Vec<f64>,
}

/// The converged condensed solve as the plain path's result: u = w + ρ (λ and the set were
/// taken on w, as the plain path does). Collective.
pub(super) fn finish(
    p: &ContactProblem,
    reduced: &ReducedSystem,
    free: &FreeModes,
    mut ex: Expanded,
    history: Vec<StepInfo>,
    summary: CondensedSummary,
) -> Result<Condensed, RunError> {
    let mut u = reduced.solution()?;
    add_motion(free, &ex.rho, p, &mut u, &mut ex.it.nodes)?;
    let result = NewtonResult {
        u,
        nodes: ex.it.nodes,
        steps: history.len(),
        history,
        converged: true,
        lambda_seconds: reduced.lambda_seconds,
        rows_seconds: reduced.rows_seconds,
        pinned_final: ex.pins,
        cycle_detected_at: None,
        approach: ex.approach,
        stop: crate::signorini::certificate::StopRule::ActiveSet,
    };
    Ok(Condensed::Solved(Box::new(result), summary))
}

/// [`fallback`] for a round's [`Stop`] (marked in the summary where the zone is too wide).
pub(super) fn fallback_stop(ctx: &Ctx, mut summary: CondensedSummary, stop: Stop) -> Condensed {
    summary.too_wide = stop.too_wide;
    fallback(ctx, summary, stop.why)
}

/// The plain path takes over: said in the log and in the summary.
pub(super) fn fallback(ctx: &Ctx, mut summary: CondensedSummary, why: String) -> Condensed {
    let (outcome, reason) = (&mut summary.outcome, &mut summary.fallback_reason);
    let (what, then) = ("newton: condensed path", "solving on the plain path");
    fall_back(ctx, what, then, outcome, reason, why);
    Condensed::Fallback(summary)
}

/// A condensed solve gives up for the plain path: said in the log (`what` gave up, `then`
/// where the plain path starts), its record's `outcome` "fallback" with the `reason` `why`.
/// Collective (log).
pub(crate) fn fall_back(
    ctx: &Ctx,
    what: &str,
    then: &str,
    outcome: &mut &'static str,
    reason: &mut Option<String>,
    why: String,
) {
    say!(ctx, "{what}: {why}; {then}");
    *outcome = "fallback";
    *reason = Some(why);
}
