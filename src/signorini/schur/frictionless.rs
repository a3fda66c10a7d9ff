//! Algorithm 1 on the contact unknowns alone (frictionless, direct preset): one factorisation
//! of the stiffness with every rigid mode that Dirichlet data leave free pinned, K_p, by MUMPS
//! directly, in the candidate contact nodes' frames (Qᵀ K_p Q, normal first) and with the Schur
//! complement S on the candidates' normal dofs alone (ICNTL(19)); K_p⁻¹ restricted to those dofs
//! is S⁻¹, so the compliance is C = Nᵀ K_p⁻¹ N = S⁻¹, one dense Cholesky and inversion (LAPACK)
//! of the size of the candidate set; every step of Algorithm 1 is then a dense solve of the
//! active nodes' block; at the end MUMPS' condensation and expansion solves give u.
//!
//! The step count: with newton.init = "auto" and no warm start, Algorithm 1 first runs on
//! coarse subsets of the candidates (nested iteration,
//! [`Dense::run_nested`](crate::signorini::dense::Dense::run_nested)), each level starting the
//! next; the steps on the candidates themselves are those counted.
//!
//! Why it is Algorithm 1: with u = w + ρ (ρ a rigid motion Dirichlet data leave free, zero in
//! K_p's pins) and K_p w = f − N λ_n, the reduced system (3.29) of a set A is, eliminated onto
//! the contact unknowns,
//!
//! ```text
//!   u_n = d₀ − C λ_n + G α        (d₀ = Nᵀ K_p⁻¹ f, G = Nᵀ R z: the free modes' normal parts)
//!   u_n,k = −g_k  (k ∈ A),  λ_n,k = 0  (k ∉ A),   Gᵀ λ_n = zᵀ Rᵀ f  (the pins carry nothing)
//! ```
//!
//! for the modes the set fixes; modes the set leaves free stay pinned (as the plain path pins
//! them) and the balance test of [`crate::signorini::rigid`] decides, as in the plain path. λ_n of (3.28)
//! and u_n come out of the same dense system, the set update is (3.23). The final set is
//! checked on the expanded u by the plain path's own recovery (3.28) and update (3.23): a
//! node that changes there sends the solve to the plain path.
//!
//! Collectives: the gathering of the candidates (one all-gather), MUMPS' factorisation and
//! three solve phases (the right-hand sides gathered on rank 0, the solution scattered back),
//! two broadcasts (S's definiteness, the dense result), one MatMult.

use super::candidates::Shape;
use super::candidates::{dirichlet_reach, hold, wide, Candidates, Compliance, Growth, Sticking};
use super::outcome::Stop;
use super::outcome::{fallback, fallback_stop, finish, keep_solved, Condensed, Expanded, Kept};
use super::round::{expand, factorise_round, judge, locate, refuse_floating_force};
use super::round::{reused, Expansion, Judged, Pass};
use super::start::{predicted_zone, prepare_base, splits_zones, start_set, PassPlan, SolveStart};
use super::summary::{tag_key, CondensedSummary};
use crate::case::NewtonInit;
use crate::error::RunError;
use crate::par::Ctx;
use crate::say;
use crate::signorini::kept::KeptFactor;
use crate::signorini::plain_path::{ContactProblem, NewtonSettings, StepInfo, WarmStart};
use crate::signorini::rigid::FreeModes;
use crate::signorini::session::Session;
use crate::signorini::step_system::ReducedSystem;
use crate::tuning::{BAND_FRACTION, DENSE_FLOOR_FLOPS, LOCATED_MARGIN, MAX_ROUNDS};
use std::time::Instant;

/// Runs Algorithm 1 condensed onto the contact unknowns (module note). `Fallback` when the
/// dense iteration cycles, does not converge within `max_steps`, or its final set changes on
/// the expanded u; an error only where the plain path would give the same one (no support).
/// Collective.
pub fn solve(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    s: &NewtonSettings,
    session: &mut Session,
    warm: Option<&WarmStart>,
) -> Result<Condensed, RunError> {
    solve_keeping(ctx, p, reduced, s, session, warm, Condensing::FRICTIONLESS).map(|(c, _)| c)
}

/// How one condensed solve runs ([`solve_keeping`]): the Schur variables per candidate (`per`:
/// 1 the normal dofs, the dimension every dof), whether the frictionless steps run (`steps`),
/// where friction needs it the zone held sticking (`stick`), and whether every node with a
/// Tresca threshold is a candidate (`thresholds`; else the nodes beyond the candidates carry
/// their friction as a load, schur/coulomb.rs).
#[derive(Clone, Copy)]
pub(crate) struct Condensing<'a> {
    pub per: usize,
    pub steps: bool,
    pub stick: Option<Sticking<'a>>,
    pub thresholds: bool,
}

impl Condensing<'_> {
    /// The candidates' normal dofs with the frictionless steps, no zone held sticking.
    pub const FRICTIONLESS: Condensing<'static> = Condensing {
        per: 1,
        steps: true,
        stick: None,
        thresholds: false,
    };
}

/// [`solve`] with `per` Schur variables per candidate (1: the normal dof; d: every dof, for
/// friction); with `per` > 1 a converged solve also returns what it [`Kept`] (with `per` = 1
/// it leaves it in `session.kept` for the next load step). A load step (`warm`) starts from
/// the previous step's factorisation where it holds ([`reused`]). Without `steps`
/// it stops after the first factorisation (`Factorised`; the start set and λ = 0 kept: a load
/// step of a friction solve starts from its warm start instead). With `stick` (friction,
/// `per` > 1) a zone too wide for every dof of its nodes has its interior held on the obstacle
/// and sticking (u_τ = u_ref), as a frictionless solve holds it on the obstacle, but for the
/// nodes it releases, which are candidates. Collective.
pub(crate) fn solve_keeping(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    s: &NewtonSettings,
    session: &mut Session,
    warm: Option<&WarmStart>,
    how: Condensing,
) -> Result<(Condensed, Option<Kept>), RunError> {
    let Condensing {
        per,
        steps,
        stick,
        thresholds,
    } = how;
    let (b, dim) = (p.boundary, p.mesh.dim);
    let summary = CondensedSummary::new(b.n_global);
    let free0 = FreeModes::new(ctx, p.mesh, p.layout, p.fixed, b, &reduced.f_local, s.rigid);
    refuse_floating_force(p, s, &free0)?;
    let start = start_set(p, s, &free0, warm);
    let located = locate(ctx, p, &mut session.located, s, &free0, warm)?;
    let key = located.as_ref().map(|(k, _)| k.as_slice());
    let n_rows = p.layout.node_offsets.last().copied().unwrap_or(0) * dim;
    let splits = splits_zones(&session.kept, s, warm, per, steps, stick.is_some());
    let sticking = stick.unwrap_or_default();
    // every contact node as the case starts (the zones' positions and order keys), gathered
    // once
    let all0 = splits.then(|| Candidates::gather(ctx, b, &free0, &start, key));
    // friction: a zone is held only where every dof of its nodes is too many for the dense
    // limits (below)
    let zone = match per {
        1 => predicted_zone(all0.as_ref(), &located, per),
        _ => sticking.zone.filter(|_| splits).map(<[bool]>::to_vec),
    };
    let passes = Passes {
        at: SolveStart {
            p,
            warm,
            free0: &free0,
            all0: all0.as_ref(),
            start: &start,
            located: &located,
            per,
            thresholds,
        },
        given: s,
        // a zone held sticking holds every rigid mode: no load is left for the contact to carry
        held_sticking: NewtonSettings {
            carried: None,
            ..*s
        },
        shape: Shape { dim, n_rows },
        nested: warm.is_none() && s.section.init == NewtonInit::Auto,
        splits,
        steps,
        sticking,
    };
    let factors = Factors {
        reduced,
        kept: &mut session.kept,
    };
    passes.run(ctx, factors, zone, summary)
}

/// What every pass of one condensed solve shares: its start, the settings asked for (and
/// those of a pass that holds a zone sticking), the shape of the system, whether its first
/// round runs nested, whether zones may be held, whether it runs the frictionless steps, and
/// the sticking zone's settings.
struct Passes<'a> {
    at: SolveStart<'a>,
    given: &'a NewtonSettings<'a>,
    held_sticking: NewtonSettings<'a>,
    shape: Shape,
    nested: bool,
    splits: bool,
    steps: bool,
    sticking: Sticking<'a>,
}

/// How a pass ends.
enum PassEnd {
    /// The solve's outcome, with what a friction solve keeps.
    Done(Box<(Condensed, Option<Kept>)>),
    /// A new pass holding a zone, with the node order of the pass before.
    Next(Vec<bool>, Option<Vec<usize>>, CondensedSummary),
    /// No rounds left.
    Exhausted(CondensedSummary),
}

/// How a round's dense steps end ([`Passes::dense_round`]).
enum RoundEnd {
    /// Another round on these candidates (the dense set asks it, or the candidates grew).
    Again,
    /// The condensed path stops for the plain path.
    Stop(Stop),
    Fall(String),
    /// The final set, with the expanded iterate and the candidates' multipliers.
    Settled(Box<Expanded>, Vec<f64>),
    /// A new pass holding this zone, with the node order of this one.
    Pass(Vec<bool>, Option<Vec<usize>>),
}

/// The rounds and the step history of a solve's passes so far.
#[derive(Default)]
struct Done {
    rounds: usize,
    history: Vec<StepInfo>,
}

/// The linear algebra of a solve's passes: the reduced system that K_p is written into, and
/// the factorisation kept across load steps (the previous step's, taken where it holds; this
/// solve's, left for the next).
struct Factors<'s> {
    reduced: &'s mut ReducedSystem,
    kept: &'s mut KeptFactor,
}

/// One round of a pass as [`Passes::dense_round`] runs it: its number in the pass, whether
/// its dense steps run nested (the solve's first round) and the zone the pass holds.
#[derive(Clone, Copy)]
struct Round<'z> {
    number: usize,
    first: bool,
    zone: Option<&'z Vec<bool>>,
}

impl Passes<'_> {
    /// The passes of a solve from the predicted `zone` (or none), each begun anew (K_p with
    /// its held zone, [`begin_pass`]) until one ends the solve; `factors`' kept factorisation:
    /// the previous load step's (taken where a load step starts), this solve's left for the
    /// next. Collective.
    fn run(
        &self,
        ctx: &Ctx,
        mut factors: Factors,
        mut zone: Option<Vec<bool>>,
        mut summary: CondensedSummary,
    ) -> Result<(Condensed, Option<Kept>), RunError> {
        let mut order = factors.kept.take_order(); // a load step after a held zone's
        let mut done = Done::default();
        loop {
            let plan = PassPlan {
                zone: zone.as_deref(),
                order: order.take(),
                sticking: self.sticking,
            };
            let pass = begin_pass(ctx, &self.at, &mut factors, plan, &mut summary)?;
            match self.rounds(ctx, &mut factors, pass, zone.as_ref(), &mut done, summary)? {
                PassEnd::Done(done) => return Ok(*done),
                PassEnd::Next(z, o, sm) => (zone, order, summary) = (Some(z), o, sm),
                PassEnd::Exhausted(sm) => {
                    let why = format!("no final set in {MAX_ROUNDS} rounds of candidates");
                    return Ok((fallback(ctx, sm, why), None));
                }
            }
        }
    }

    /// The Newton settings of a pass that holds `zone` (or none): the held sticking zone's
    /// where friction holds one, else those asked for.
    fn settings_of(&self, zone: Option<&Vec<bool>>) -> &NewtonSettings<'_> {
        match self.at.per > 1 && zone.is_some() {
            true => &self.held_sticking,
            false => self.given,
        }
    }

    /// The rounds of one pass holding `zone` (or none): factorise (the candidates grown), then
    /// the dense steps and their expansion ([`Passes::dense_round`]), until the pass ends.
    /// Collective.
    fn rounds(
        &self,
        ctx: &Ctx,
        factors: &mut Factors,
        mut pass: Pass,
        zone: Option<&Vec<bool>>,
        done: &mut Done,
        mut summary: CondensedSummary,
    ) -> Result<PassEnd, RunError> {
        let reduced = &mut *factors.reduced;
        let fall = |c: Condensed| Ok(PassEnd::Done(Box::new((c, None))));
        for round in 1..=MAX_ROUNDS {
            done.rounds += 1;
            if done.rounds > MAX_ROUNDS {
                break;
            }
            let grown = factorise_round(ctx, reduced, &mut pass, &mut summary, round, &self.shape);
            if let Err(stop) = grown {
                let to_hold = stop.too_wide && self.at.per > 1 && self.splits && zone.is_none();
                let active = &pass.growth.active;
                let instead = || hold_instead(ctx, &stop, &self.at, active);
                if let Some(z) = to_hold.then(instead).flatten() {
                    return Ok(PassEnd::Next(z, None, summary));
                }
                return fall(fallback_stop(ctx, summary, stop));
            }
            if !self.steps {
                summary.outcome = "factorised";
                let n = pass.cand.n;
                if !summary.factorisation_kept {
                    // (a kept one is said by the round)
                    summary.log_factorised(ctx, n);
                }
                let kept = pass.keep(vec![0.0; n], zone.cloned());
                let factorised = (Condensed::Factorised(summary), Some(kept));
                return Ok(PassEnd::Done(Box::new(factorised)));
            }
            let at = Round {
                number: round,
                first: self.nested && done.rounds == 1,
                zone,
            };
            let history = &mut done.history;
            match self.dense_round(ctx, reduced, &mut pass, at, &mut summary, history)? {
                RoundEnd::Again => {}
                RoundEnd::Stop(stop) => return fall(fallback_stop(ctx, summary, stop)),
                RoundEnd::Fall(why) => return fall(fallback(ctx, summary, why)),
                RoundEnd::Pass(z, order) => return Ok(PassEnd::Next(z, order, summary)),
                RoundEnd::Settled(ex, lambda) => {
                    let history = std::mem::take(&mut done.history);
                    let solved = finish(self.at.p, reduced, &pass.free, *ex, history, summary)?;
                    let keep = pass.keep(lambda, zone.cloned());
                    let done = keep_solved(factors.kept, solved, keep, self.at.per);
                    return Ok(PassEnd::Done(Box::new(done)));
                }
            }
        }
        Ok(PassEnd::Exhausted(summary))
    }

    /// A round's dense steps on the factorised candidates, their judgement, the expansion of
    /// the iterate and what the nodes that change on it ask: another round on more
    /// candidates, a new pass, or the plain path. Collective.
    fn dense_round(
        &self,
        ctx: &Ctx,
        reduced: &mut ReducedSystem,
        pass: &mut Pass,
        at: Round,
        summary: &mut CondensedSummary,
        history: &mut Vec<StepInfo>,
    ) -> Result<RoundEnd, RunError> {
        let Round {
            number: round,
            first,
            zone,
        } = at;
        let s = self.settings_of(zone);
        let on = self.at.located.as_ref().map(|(_, on)| *on);
        let on = on.filter(|_| zone.is_none());
        let run = pass.dense(ctx, s, first, on, summary, history);
        let lambda = pass.growth.take_dense(&pass.comp, &run);
        match judge(ctx, self.at.p, s, pass, &run)? {
            Judged::Expand => {}
            Judged::Again => return Ok(RoundEnd::Again),
            Judged::Stop(stop) => return Ok(RoundEnd::Stop(stop)),
        }
        let (cand, comp, free, growth) = (&pass.cand, &mut pass.comp, &pass.free, &mut pass.growth);
        let t = Instant::now();
        let active = growth.active.as_slice();
        let expansion = Expansion {
            s,
            free,
            comp,
            cand,
            f_root: &pass.f_root,
            n_local: pass.rhs0.len(),
        };
        let ex = match expand(
            ctx, self.at.p, reduced, expansion, &lambda, active, &run.alpha,
        )? {
            Ok(ex) => ex,
            Err(why) => return Ok(RoundEnd::Fall(why)),
        };
        summary.solves += 2;
        summary.expansion_seconds += t.elapsed().as_secs_f64();
        if ex.changed.is_empty() {
            let n_active = growth.active.iter().filter(|&&a| a).count();
            summary.log(ctx, cand.n, n_active);
            return Ok(RoundEnd::Settled(Box::new(ex), lambda));
        }
        let (max_flops, per) = (comp.max_flops, comp.per);
        if let Some(next) = growth.next_pass(ctx, &ex.changed, max_flops, per, self.splits) {
            let budget = (self.at.per > 1).then_some(self.sticking.factorisations);
            if budget.is_some_and(|b| b > 0 && summary.factorisations >= b) {
                let n = summary.factorisations;
                let why = format!("the held zone's set still changes after {n} factorisations");
                return Ok(RoundEnd::Fall(why));
            }
            return Ok(RoundEnd::Pass(next, comp.node_order.take()));
        }
        match growth.widen(ctx, &ex.changed, comp, round) {
            Ok(()) => Ok(RoundEnd::Again),
            Err(why) => Ok(RoundEnd::Fall(why)),
        }
    }
}

/// Friction, where every dof of the candidates is too many (`stop`): the zone to hold sticking
/// instead, the predicted one ([`predicted_zone`]) or else the set the candidates grew to
/// (`grown`), where it is [`wide`]. Local (on all-gathered data; said in the log).
fn hold_instead(ctx: &Ctx, stop: &Stop, at: &SolveStart, grown: &[bool]) -> Option<Vec<bool>> {
    let per = at.per;
    let zone = predicted_zone(at.all0, at.located, per).or_else(|| {
        let on = grown.iter().filter(|&&a| a).count();
        wide(on, per, DENSE_FLOOR_FLOPS).then(|| grown.to_vec())
    })?;
    say!(
        ctx,
        "newton: condensed: {}; the predicted zone's interior held sticking instead",
        stop.why
    );
    Some(zone)
}

/// A pass begun: the held nodes of the predicted `zone` ([`hold`] on `all0`, every contact
/// node as the case starts; none without a zone), K_p
/// written with them, its candidates (the zone's nodes not held start active; else the start
/// set `start`), the first candidates' count ([`first_growth`]), and a compliance on the
/// previous load step's factorisation where it holds ([`reused`], taken from `kept`) or a new
/// one with the kept node order `order`. Collective.
fn begin_pass(
    ctx: &Ctx,
    at: &SolveStart,
    factors: &mut Factors,
    plan: PassPlan,
    summary: &mut CondensedSummary,
) -> Result<Pass, RunError> {
    let (p, per) = (at.p, at.per);
    let sticking = plan.sticking;
    let released = |i: usize| sticking.release.get(i).copied().unwrap_or(false);
    let held = match (plan.zone, at.all0) {
        (Some(z), Some(all)) => {
            let kept_on: Vec<bool> = (0..z.len()).map(|i| z[i] && !released(i)).collect();
            hold(all, &kept_on, (BAND_FRACTION >> sticking.pass).max(1))
        }
        _ => Vec::new(),
    };
    let (free, rhs0) = prepare_base(ctx, p, factors.reduced, at.free0, &held, per > 1)?;
    let f_root = ctx.gather_to_root(&rhs0); // f for MUMPS' solve phases, once per pass
    let b = p.boundary;
    let pass_start: Vec<bool> = match plan.zone {
        Some(z) => (0..b.nodes.len())
            .map(|i| (z[b.offset + i] || released(b.offset + i)) && !held[b.offset + i])
            .collect(),
        None => (0..b.nodes.len())
            .map(|i| at.start[i] || released(b.offset + i))
            .collect(),
    };
    let key = at.located.as_ref().map(|(k, _)| k.as_slice());
    let cand = Candidates::gather(ctx, b, &free, &pass_start, key);
    let growth = first_growth(ctx, at, plan.zone, &cand, &held, summary);
    let t = Instant::now();
    let (kept, order_dropped) = match at.warm {
        Some(_) => reused(ctx, at, factors.kept.take(), &free, &cand, &f_root, &held),
        None => (None, None),
    };
    let mut comp = match kept {
        Some(comp) => {
            summary.factorisation_kept = true;
            comp
        }
        None => Compliance::new(cand.n, per),
    };
    if comp.node_order.is_none() {
        comp.node_order = plan.order.or(order_dropped);
    }
    Ok(Pass {
        free,
        rhs0,
        f_root,
        cand,
        growth,
        comp,
        condensation: t.elapsed().as_secs_f64(),
    })
}

/// A pass's first candidates ([`Growth::new`]): the zone's band and margin (`zone`, its
/// `held` nodes held), or the located zone's margin, and on a first solve with nothing
/// located the nodes within the Dirichlet data's reach ([`dirichlet_reach`]); the held nodes
/// into `summary` and the log. Collective (the reach's reduction, the log).
fn first_growth(
    ctx: &Ctx,
    at: &SolveStart,
    zone: Option<&[bool]>,
    cand: &Candidates,
    held: &[bool],
    summary: &mut CondensedSummary,
) -> Growth {
    let per = at.per;
    let count = |v: &[bool]| v.iter().filter(|&&a| a).count();
    let want = match zone {
        Some(z) => Some(count(z) - count(held) + count(z) / LOCATED_MARGIN),
        None => at.located.as_ref().map(|(_, on)| on + on / LOCATED_MARGIN),
    };
    // a first solve with nothing located: the nodes the Dirichlet data may press into contact
    let reach = match (zone, at.located, at.warm) {
        (None, None, None) => dirichlet_reach(ctx, at.p.fixed),
        _ => 0.0,
    };
    let growth = Growth::new(cand, per, want, held, reach, at.thresholds);
    if growth.reached > 0 {
        say!(
            ctx,
            "newton: condensed: the first candidates take the {} nodes whose gap is within the \
             Dirichlet data's reach {reach:.3e} (the largest prescribed displacement)",
            growth.reached,
        );
    }
    summary.held_nodes = growth.held_count;
    summary.held_key = (growth.held_count > 0).then(|| {
        let held = (0..cand.n).filter(|&i| growth.held[i]);
        tag_key(held.map(|i| cand.tag(i)))
    });
    if growth.held_count > 0 {
        say!(
            ctx,
            "newton: condensed: {} nodes inside the predicted contact zone ({} nodes) held on \
             the obstacle{} in K_p; the dense steps on the rest of it and beyond",
            growth.held_count,
            zone.map_or(0, count),
            if per > 1 { ", sticking," } else { "" }
        );
    }
    growth
}

#[cfg(test)]
mod tests {
    use crate::signorini::dense::{DenseRun, End};

    #[test]
    fn pack_round_trip() {
        let run = DenseRun {
            active: vec![true, false],
            lambda: vec![-1.0, 0.0],
            alpha: vec![0.5],
            u_n: vec![0.0, 0.3],
            steps: vec![(1, 0, 1, 0.1, 0.01), (2, 1, 0, 0.0, 0.02)],
            end: End::Fallback("cycling".into()),
            coarse: vec![(16, 3), (32, 2)],
        };
        let back = DenseRun::unpack(&run.pack(2, 1), 2, 1);
        assert_eq!(back.coarse, run.coarse);
        assert_eq!(back.active, run.active);
        assert_eq!(back.lambda, run.lambda);
        assert_eq!(back.alpha, run.alpha);
        assert_eq!(back.u_n, run.u_n);
        assert_eq!(back.steps, run.steps);
        assert_eq!(back.end, run.end);
    }
}
