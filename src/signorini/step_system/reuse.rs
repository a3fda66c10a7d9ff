//! How a step's system was solved (a factorisation, Krylov iterations, a reused
//! factorisation or preconditioner) and the rules that decide when to reuse one.

use super::rows::{Directions, Springs};
use crate::case::Reuse;
use crate::linsolve::{self};
use crate::petsc::{self, Ksp, SolveInfo, Vector};
use crate::tuning::{
    ALWAYS_BUDGET, AUTO_MARGIN, INEXACT_REDUCTION, ITERATION_PER_SOLVE, PREDICTOR_REDUCTION,
    RATE_MIN_DECADES, RATE_MIN_ITERATIONS, REBUILD_GROWTH, REUSE_BUDGET, SOLVE_FLOP_COST,
};
use std::time::Instant;

/// How a step's system was solved: a numeric factorisation of the new matrix (the symbolic
/// analysis is made once, in the first step), or Krylov iterations with a preconditioner
/// rebuilt for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SolveKind {
    Factorisation,
    Krylov,
    /// Krylov iterations preconditioned by an earlier step's preconditioner, set up for
    /// another matrix: the factorisation (direct preset) or the AMG hierarchy (iterative
    /// preset) of an earlier step (no new factorisation, no new PCSetUp).
    Reuse,
    /// A step of Algorithm 1 on the contact unknowns alone (signorini::condensed): a dense
    /// solve, no sparse one.
    Condensed,
}

/// What the reuse path did in one step (summary.json `newton.history[].reuse`; absent with
/// `solver.reuse = "never"` and with the iterative preset).
#[derive(Clone, Debug, serde::Serialize)]
pub struct ReuseStep {
    /// Bound on the rank of S_k − S_j, S_j the factored matrix: 2 per prescribed direction
    /// added or removed since, d − 1 per changed slip block (0 before the first factorisation).
    pub rank: usize,
    /// Krylov iterations allowed on S_j's factorisation (0: not tried).
    pub budget: usize,
    /// Krylov iterations made on S_j's factorisation (0: not tried).
    pub krylov_iterations: usize,
    /// The Krylov solve did not reach its tolerance within the budget: refactorised.
    pub fallback: bool,
    /// Seconds of this step's numeric factorisation (0 without one; a record only: no
    /// choice depends on it).
    pub factorisation_seconds: f64,
    /// The costs "auto" weighs ([`ReuseCosts`], in flops of the factorisation; recorded in
    /// every mode) of the factored matrix' numeric factorisation with its solve, and of one
    /// Krylov iteration on it (0: nothing factored yet, or no MUMPS statistics).
    pub cost_factorisation: f64,
    pub cost_iteration: f64,
}

/// One step's solve: the solver's report of the solve that produced u, how it was made, the
/// seconds (all of it, a failed reuse attempt included) and what the reuse path did.
pub struct StepSolve {
    pub info: SolveInfo,
    pub kind: SolveKind,
    pub seconds: f64,
    /// The plain path: seconds of the set-up alone (the numeric factorisation on the direct
    /// preset), before the solve.
    pub setup_seconds: Option<f64>,
    pub reuse: Option<ReuseStep>,
    pub amg: Option<AmgStep>,
}

/// What "auto" weighs, in flops of the numeric factorisation, from MUMPS' global statistics
/// of the last factorisation (the same on every rank): the factorisation (RINFOG(1)) and one
/// triangular solve pair (2 flops per factor entry and substitution: L and U once each, or
/// LDLᵀ's L twice), weighted by [`SOLVE_FLOP_COST`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReuseCosts {
    pub factorisation: f64,
    pub solve: f64,
}

impl ReuseCosts {
    /// From a factorisation's statistics; `None` without flops or entries.
    pub fn of(stats: &petsc::mumps::FactorStats) -> Option<ReuseCosts> {
        // INFOG(29) < 0: millions of entries
        let entries = match stats.factor_entries {
            e if e < 0 => -(e as f64) * 1e6,
            e => e as f64,
        };
        let per_entry = if stats.symmetric { 4.0 } else { 2.0 };
        (stats.flops > 0.0 && entries > 0.0).then_some(ReuseCosts {
            factorisation: stats.flops,
            solve: SOLVE_FLOP_COST * per_entry * entries,
        })
    }

    /// One Krylov iteration on the factorisation.
    pub fn iteration(&self) -> f64 {
        ITERATION_PER_SOLVE * self.solve
    }

    /// "auto"'s rule: reuse when the expected `rank` + 2 Krylov iterations (the first applies
    /// M⁻¹ to b; one per rank of S_k − S_j, as GMRES needs at most) cost at most
    /// [`AUTO_MARGIN`] of a factorisation step (the factorisation and its solve), with the
    /// budget of iterations that cost one such step (beyond it the reuse no longer pays), at
    /// most GMRES' restart. Counts only: the same choice on every run.
    pub fn plan(&self, rank: usize) -> Option<usize> {
        let step = self.factorisation + self.solve;
        let it = self.iteration();
        if it <= 0.0 || !step.is_finite() {
            return None;
        }
        // (budget + 1) iterations cost at most one factorisation step
        let budget = ((step / it).floor() as usize)
            .saturating_sub(1)
            .min(linsolve::REUSE_RESTART);
        let expected = (rank + 2) as f64 * it;
        (rank < budget && expected <= AUTO_MARGIN * step).then_some(budget)
    }
}

/// The reuse path of the direct preset: a GMRES solver on the shared factorisation, the
/// constraints of the factored matrix S_j and of the system written last, and S_j's costs
/// from MUMPS' counts (the same on every rank).
pub(super) struct Reuser {
    pub(super) mode: Reuse,
    pub(super) ksp: Ksp,
    /// Directions and this rank's slip blocks of the factored matrix (`None`: none factored).
    pub(super) factored: Option<(Directions, Springs)>,
    /// The same of the system written last.
    pub(super) current: (Directions, Springs),
    /// The costs of the factored matrix' factorisation (`None`: no MUMPS statistics, e.g.
    /// a preconditioner given by `solver.petsc_options`: "auto" then never reuses).
    pub(super) costs: Option<ReuseCosts>,
}

impl Reuser {
    /// Whether to try the reuse, and its budget: "always" whenever a factorisation exists;
    /// "auto" by [`ReuseCosts::plan`] on the factored matrix' counts.
    pub(super) fn plan(&self, rank: usize) -> Option<usize> {
        self.factored.as_ref()?;
        match self.mode {
            Reuse::Never => None,
            Reuse::Always => Some(ALWAYS_BUDGET),
            Reuse::Auto => self.costs?.plan(rank),
        }
    }
}

// tuning::INEXACT_REDUCTION: An inexact step of the iterative preset reduces the residual of its warm start by this
// factor (‖b − S u‖ ≤ INEXACT_REDUCTION ‖b − S u₀‖, never looser than the preset's own
// tolerance): while the active set still changes, a step only has to tell the next set, not
// the final u. Relative to the start rather than to ‖b‖: the start's residual comes from the
// nodes that changed, on the scale of the nodal contact forces, which shrink with the mesh
// while ‖b‖ does not. Measured on 3D Hertz, 2 ranks: a fixed 1e-4 ‖b‖ made the set chatter
// (79 k unknowns: ~150 nodes changing in every step, no convergence in 100 steps); a fixed
// 1e-6 ‖b‖ went through the plain path's sets at 79 k but not at 526 k (11 steps instead of
// 7, the last three exact after the set grew again).

/// What the iterative preset's reuse path did in one step (summary.json
/// `newton.history[].amg`; absent with `solver.reuse = "never"` and with the direct preset).
#[derive(Clone, Debug, serde::Serialize)]
pub struct AmgStep {
    /// The preconditioner was set up (PCSetUp) on this step's matrix before the solve: the
    /// first step, a rebuild asked for by the previous step ("auto"), or a fallback.
    pub pc_setup: bool,
    /// Seconds of the PCSetUp calls of this step (0 without one).
    pub pc_setup_seconds: f64,
    /// The relative tolerance of the solve (on ‖b‖): the preset's, or that of an inexact
    /// step ([`INEXACT_REDUCTION`] × `initial_residual`, not below the preset's).
    pub rtol: f64,
    /// An inexact step (frictionless, while the active set still changes).
    pub inexact: bool,
    /// ‖b − S x₀‖ / ‖b‖ of the start (the previous iterate with the prescribed components set
    /// exactly; 1 for the first step's zero start).
    pub initial_residual: f64,
    /// Krylov iterations per decade of residual reduction (0 when too few to tell).
    pub rate: f64,
    /// The Krylov solve on the reused preconditioner did not converge: set up anew and solved
    /// again from where it stopped (`iterations` counts both solves).
    pub fallback: bool,
    /// The free rigid modes were S's null space instead of pinned dofs
    /// ([`ReducedSystem::set_free_null_space`](super::system::ReducedSystem::set_free_null_space)).
    pub null_space: bool,
    /// The set-up also built GAMG's aggregates and prolongators anew instead of keeping the
    /// last ones (the step after the predictor's first solve).
    pub new_hierarchy: bool,
    /// No solve: the predictor's first solve of a floating body, u⁰ = 0
    /// ([`ReducedSystem::set_predictor_solve`](super::system::ReducedSystem::set_predictor_solve)).
    pub skipped: bool,
}

/// The iterative preset's reuse path (`solver.reuse` "auto" / "always"): warm starts, the
/// preconditioner kept from step to step, inexact early steps (set by the Newton loop).
pub(super) struct AmgReuser {
    pub(super) mode: Reuse,
    /// The configured relative tolerance and iteration limit (preset < case < command line).
    pub(super) rtol: f64,
    pub(super) max_it: usize,
    /// Iterations per decade of the solve right after the last PCSetUp.
    pub(super) fresh_rate: Option<f64>,
    /// A preconditioner has been set up.
    pub(super) built: bool,
    /// The next solve sets the preconditioner up anew ("auto": the rate grew).
    pub(super) rebuild: bool,
    /// That set-up also builds GAMG's aggregates and prolongators anew (after the predictor's
    /// first solve, whose matrix has no active node and the pins of every rigid mode: kept,
    /// its prolongators cost the exact steps after it half again as many iterations, the full
    /// ball at 57 k unknowns 36 and 35 against 22 and 19).
    pub(super) rebuild_hierarchy: bool,
    /// The last set-up did so.
    pub(super) new_hierarchy: bool,
    /// This step's solve may stop at [`INEXACT_REDUCTION`] of its start's residual.
    pub(super) inexact: bool,
    /// This step's solve is the predictor's first
    /// ([`ReducedSystem::set_predictor_solve`](super::system::ReducedSystem::set_predictor_solve)).
    pub(super) predictor: bool,
    /// ... and is skipped (u = 0, no setup).
    pub(super) skip: bool,
    /// The free rigid modes are S's null space
    /// ([`ReducedSystem::set_free_null_space`](super::system::ReducedSystem::set_free_null_space)).
    pub(super) null_space: bool,
    /// This rank's prescribed node components of the system written last: (first local row,
    /// projector P onto the free components, prescribed part ū).
    pub(super) prescribed: Vec<(usize, [[f64; 3]; 3], [f64; 3])>,
}

impl AmgReuser {
    /// The relative tolerance (on ‖b‖, the default test of a nonzero start) of this solve:
    /// the preset's, or for an inexact step [`INEXACT_REDUCTION`] (the predictor's first
    /// solve: [`PREDICTOR_REDUCTION`]) of the start's residual, never tighter than the preset's.
    pub(super) fn tolerance(&self, predictor: bool, r0: f64, bnorm: f64) -> f64 {
        let reduction = if predictor {
            PREDICTOR_REDUCTION
        } else {
            INEXACT_REDUCTION
        };
        if self.inexact && bnorm > 0.0 {
            (reduction * r0 / bnorm).max(self.rtol)
        } else {
            self.rtol
        }
    }

    /// The iteration limit: on a reused preconditioner [`REUSE_BUDGET`] times the iterations
    /// the rate after the last setup predicts (then it is set up anew), on a fresh one the
    /// configured limit.
    pub(super) fn budget(&self, setup: bool, r0: f64, rtol: f64, bnorm: f64) -> usize {
        match self.fresh_rate {
            Some(f) if !setup && r0 > 0.0 && bnorm > 0.0 => {
                let decades = (r0 / (rtol * bnorm)).log10().max(1.0);
                ((REUSE_BUDGET * f * decades).ceil() as usize + RATE_MIN_ITERATIONS)
                    .min(self.max_it)
            }
            _ => self.max_it,
        }
    }

    /// The Krylov solve, on a preconditioner set up for this matrix (`setup`) or the kept one;
    /// a solve on the kept one that does not converge sets up on this matrix and goes on from
    /// where it stopped. Returns (info, fallback, PCSetUp seconds). Collective.
    pub(super) fn krylov(
        &mut self,
        ksp: &mut Ksp,
        rhs: &Vector,
        u: &mut Vector,
        setup: bool,
    ) -> petsc::Result<(SolveInfo, bool, f64)> {
        let mut setup_seconds = 0.0;
        if setup {
            ksp.set_reuse_preconditioner(false)?;
            let hierarchy = std::mem::take(&mut self.rebuild_hierarchy);
            self.new_hierarchy = hierarchy;
            if hierarchy {
                ksp.set_gamg_reuse_interpolation(false)?;
            }
            let ts = Instant::now();
            ksp.set_up()?;
            setup_seconds += ts.elapsed().as_secs_f64();
            if hierarchy {
                ksp.set_gamg_reuse_interpolation(true)?;
            }
            self.built = true;
            self.rebuild = false;
        } else {
            ksp.set_reuse_preconditioner(true)?;
        }
        let mut info = ksp.solve(rhs, u)?;
        if info.converged() || setup {
            return Ok((info, false, setup_seconds));
        }
        let its = info.iterations;
        ksp.set_max_iterations(self.max_it)?;
        ksp.set_reuse_preconditioner(false)?;
        ksp.set_initial_guess_nonzero(true)?;
        let ts = Instant::now();
        ksp.set_up()?;
        setup_seconds += ts.elapsed().as_secs_f64();
        info = ksp.solve(rhs, u)?;
        info.iterations += its;
        Ok((info, true, setup_seconds))
    }

    /// The rate of this solve (iterations per decade, 0 when too few to tell) and what it
    /// decides for the next one: the reference rate after a setup, a rebuild ("auto") when it
    /// grew beyond [`REBUILD_GROWTH`] × the reference; after the predictor's first solve a
    /// rebuild on the next matrix ("auto"; "always" keeps this one).
    pub(super) fn learn(
        &mut self,
        predictor: bool,
        setup: bool,
        fallback: bool,
        r0: f64,
        r_end: f64,
        iterations: usize,
    ) -> f64 {
        let decades = if r_end > 0.0 && r0 > 0.0 {
            (r0 / r_end).log10()
        } else {
            0.0
        };
        let measured = decades >= RATE_MIN_DECADES && iterations >= RATE_MIN_ITERATIONS;
        let rate = if measured {
            iterations as f64 / decades
        } else {
            0.0
        };
        if predictor {
            self.rebuild = self.mode == Reuse::Auto;
            self.rebuild_hierarchy = self.rebuild;
        } else if measured && !fallback {
            // after a fallback the next measured solve on the new preconditioner is the reference
            if setup || self.fresh_rate.is_none() {
                self.fresh_rate = Some(rate);
            } else if self.mode == Reuse::Auto {
                self.rebuild = self.fresh_rate.is_some_and(|f| rate > REBUILD_GROWTH * f);
            }
        }
        if fallback {
            self.fresh_rate = None;
        }
        rate
    }

    /// The step's record for summary.json.
    pub(super) fn record(
        &self,
        pc_setup: bool,
        pc_setup_seconds: f64,
        rtol: f64,
        initial_residual: f64,
        rate: f64,
        fallback: bool,
    ) -> AmgStep {
        AmgStep {
            pc_setup,
            pc_setup_seconds,
            rtol,
            inexact: self.inexact,
            initial_residual,
            rate,
            fallback,
            null_space: self.null_space,
            new_hierarchy: pc_setup && self.new_hierarchy,
            skipped: false,
        }
    }
}

/// A slip block whose entries change by at most this fraction of the node's stiffness (the
/// mean diagonal of its rows of A) changed by round-off only: the regularised L̃ of (3.39) of a
/// node that slips with |λ_τ| = b_k is 0 or c · 1e-14 from one solve to the next, depending on
/// the last bit of |λ_τ| − b_k (measured on the Hertz disk, stiffness of order 1: ~500 such
/// blocks per step at 42 040 unknowns, ~2 900 at 171 602, the largest entry 1.3e-11 in steps
/// where nothing else changed; of the changes above 1e-12 all but a handful exceeded 1e-8,
/// most 1e-4).
pub const SLIP_BLOCK_ROUNDOFF: f64 = 1e-10;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_reuses_by_counts_alone() {
        use crate::petsc::mumps::FactorStats;
        let stats = |flops: f64, entries: i64, symmetric: bool| FactorStats {
            flops,
            factor_entries: entries,
            symmetric,
            ..FactorStats::default()
        };
        // 1e9 flops, 1e6 LDLᵀ entries: a solve pair weighs 4e6 × SOLVE_FLOP_COST
        let c = ReuseCosts::of(&stats(1e9, 1_000_000, true)).unwrap();
        assert_eq!(c.solve, 4e6 * SOLVE_FLOP_COST);
        assert_eq!(c, ReuseCosts::of(&stats(1e9, 1_000_000, true)).unwrap());
        // LU counts L and U: 2 flops per entry; INFOG(29) < 0 counts millions
        let lu = ReuseCosts::of(&stats(1e9, -2, false)).unwrap();
        assert_eq!(lu.solve, 2.0 * 2e6 * SOLVE_FLOP_COST);
        let step = c.factorisation + c.solve;
        let budget = ((step / c.iteration()).floor() as usize - 1).min(linsolve::REUSE_RESTART);
        assert!(budget > 2);
        assert_eq!(c.plan(0), Some(budget));
        assert_eq!(c.plan(1), c.plan(1), "the same counts, the same choice");
        // beyond the budget, or the expected iterations beyond the margin: refactorise
        assert_eq!(c.plan(budget), None);
        let most = (0..budget).filter(|&r| c.plan(r).is_some()).max().unwrap();
        assert!((most + 2) as f64 * c.iteration() <= AUTO_MARGIN * step);
        assert!((most + 3) as f64 * c.iteration() > AUTO_MARGIN * step || most + 1 == budget);
        // a factorisation as cheap as a few solves is never worth a Krylov solve
        let cheap = ReuseCosts::of(&stats(1e3 * SOLVE_FLOP_COST, 1000, true)).unwrap();
        assert_eq!(cheap.plan(0), None);
        // no statistics: no costs
        assert_eq!(ReuseCosts::of(&stats(0.0, 1000, true)), None);
        assert_eq!(ReuseCosts::of(&stats(1e9, 0, true)), None);
    }
}
