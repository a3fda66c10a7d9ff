//! One Newton step of the plain path, decided before it runs and recorded after: its plan
//! (exact or inexact, reuse, the rules the loop reads), the rigid motion added back to the
//! solution, the stall rule of Coulomb's residual, and the step's progress lines.

use super::problem::{ContactProblem, StepInfo};
use crate::error::RunError;
use crate::par::Ctx;
use crate::petsc::{SolveInfo, Vector};
use crate::say;
use crate::signorini::active_set::StepTotals;
use crate::signorini::boundary::NodeResult;
use crate::signorini::law::coulomb::COULOMB_RESIDUAL_STALL;
use crate::signorini::rigid::{FreeModes, Motion};
use crate::signorini::step_system::SolveKind;

/// [`COULOMB_RESIDUAL_STALL`]: this step changed no state and left u unchanged (`still`), so did
/// the step before it (`last`: its residual), the residual did not halve, and it is below
/// COULOMB_RESIDUAL_STALL · ‖λ‖₂ or below `floor`, the round-off that c puts into the residual
/// ([`residual_floor`](crate::signorini::law::coulomb::residual_floor)). Pure.
pub(crate) fn stalled(
    still: bool,
    last: Option<f64>,
    residual: f64,
    lambda_norm: f64,
    floor: f64,
) -> bool {
    still
        && last.is_some_and(|r| residual >= 0.5 * r)
        && residual <= (COULOMB_RESIDUAL_STALL * lambda_norm).max(floor)
}

/// What a Newton step is, decided before it runs: the per-step record the loop's rules read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct StepPlan {
    /// Solved to the preset's tolerance (else inexact: frictionless, iterative preset's reuse
    /// path, the solve stops at `step_system::reuse::INEXACT_REDUCTION` of its start's residual).
    pub(super) exact: bool,
    /// The half-space model predicts the set after this step's solve (its first step).
    pub(super) predict: bool,
    /// The confirming step: the same sets factorised after a stop decided on a step solved by
    /// GMRES on an earlier factorisation (no reuse).
    pub(super) confirm: bool,
    /// The half-space model corrects the set update after this step's solve (`Loop::correct`):
    /// the exact steps from a predicted set on.
    pub(super) correct: bool,
    /// An exact step whose solve stops at `INEXACT_REDUCTION` of its start's residual all the
    /// same: the first step from a predicted set, where inexact solves exist. Its update is the model's to correct and an
    /// exact solve follows it (the same sets where it changes no node); the half-space model's
    /// corrections are what the earlier inexact steps from a predicted set lacked (they flipped
    /// edge nodes, `after_solve`). Measured (2 ranks, one run each, the same changes per step
    /// and final set): its GMRES iterations 22 → 14 on the full floating ball at 127 k and
    /// 396 k unknowns, 23 → 14 at 1.2 M (solve 32.2 → 28.5 s), 3D Hertz quarter ball 21 → 13
    /// at 315 k and 22 → 13 at 994 k.
    pub(super) loose: bool,
}

/// What follows a step: the same sets once more, or the set updated by (3.23)/(3.33); with
/// the next step's plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum After {
    Repeat(StepPlan),
    Update(StepPlan),
}

impl StepPlan {
    /// After the solve and the update (before the stop rule). `exact`: whether the next steps
    /// are exact as far as this step knows (its own plan, or the prediction's verdict: from a
    /// predicted set every step is exact — the inexact steps, a residual reduction of 1e-6,
    /// flip edge nodes whose λ_n or gap is near 0, 3D Hertz at 527 k unknowns: changes 18, 17,
    /// 0 and an exact step after them, exact: 6, 0 — unless the set reached the model's
    /// border). Inexact steps run while the set changes; the first that changes no node (or
    /// leads back to a set seen before, `recurs`) is repeated exactly on the same set, and from
    /// then on every step is exact, so the iteration ends as Algorithm 1 does: an exact solve
    /// whose update changes no node. An inexact step that changes at least as many nodes as
    /// the one before it (`last_changed`) makes no progress (the set chatters): exact from
    /// then on as well.
    pub(super) fn after_solve(
        self,
        exact: bool,
        changed: usize,
        recurs: bool,
        last_changed: &mut usize,
    ) -> After {
        // a confirming step keeps every later step factorised
        let next = StepPlan {
            exact,
            predict: false,
            confirm: self.confirm,
            // the exact steps from a predicted set on
            correct: (self.predict || self.correct) && exact,
            // the prediction's own step is inexact exactly where inexact solves exist (the
            // iterative preset's reuse path, frictionless); elsewhere every solve is exact
            loose: self.predict && exact && !self.exact,
        };
        if self.predict && !self.exact && changed == 0 {
            // The prediction's own solve was inexact, or skipped (a floating body: u⁰ = 0),
            // and the model keeps its set: that iterate is no final one either. Measured
            // before (three blocks of cases/blocks/tower2d.msh, the top pressed by Dirichlet
            // data, the middle one floating, iterative preset): the model found nothing
            // penetrating in u⁰ = 0, predicted no active node, and the run stopped on it
            // (exit 0, equilibrium residual 0.94 of its scale). The same sets, solved exactly.
            return After::Repeat(StepPlan {
                exact: true,
                loose: false,
                ..next
            });
        }
        if self.loose && (changed == 0 || recurs) {
            // a loose solve is no final iterate: the same sets once more, solved exactly
            return After::Repeat(StepPlan {
                loose: false,
                ..next
            });
        }
        if exact {
            return After::Update(next);
        }
        if changed == 0 || recurs {
            return After::Repeat(StepPlan {
                exact: true,
                ..next
            });
        }
        let exact = changed >= *last_changed;
        *last_changed = changed;
        After::Update(StepPlan { exact, ..next })
    }

    /// After the stop rule said stop: a stop decided on a step solved by GMRES on an earlier
    /// factorisation (`reused`, direct preset) carries the Krylov tolerance in u (~1e-10 of u
    /// where A is ill-conditioned, ν → ½; 7e-8 in λ_t measured on block2d at ν = 0.4999), so
    /// the same sets once more, factorised, and the final iterate is Algorithm 1's; else the
    /// end (`Update`).
    pub(super) fn after_stop(self, reused: bool) -> After {
        if reused && !self.confirm {
            After::Repeat(StepPlan {
                exact: true,
                predict: false,
                confirm: true,
                loose: false,
                correct: false,
            })
        } else {
            After::Update(self)
        }
    }
}

/// u = w + ρ: the rigid motion taken out of the solve, added back to the solution and to the
/// contact nodes' displacements. Collective when ρ ≠ 0 (the same ρ on every rank).
pub(crate) fn add_motion(
    free: &FreeModes,
    rho: &Motion,
    p: &ContactProblem,
    u: &mut Vector,
    nodes: &mut [NodeResult],
) -> Result<(), RunError> {
    if rho.iter().all(|&x| x == 0.0) {
        return Ok(());
    }
    let (mesh, layout, dim) = (p.mesh, p.layout, p.mesh.dim);
    let mut idx = Vec::with_capacity(layout.owned_nodes.len() * dim);
    let mut vals = Vec::with_capacity(idx.capacity());
    for &v in &layout.owned_nodes {
        for k in 0..dim {
            idx.push((layout.node_global[v] * dim + k) as crate::petsc::PInt);
            vals.push(free.motion_at(rho, v, &mesh.coords[v], k));
        }
    }
    u.set_values(&idx, &vals, true)?;
    u.assemble()?;
    for (k, r) in p.boundary.nodes.iter().zip(nodes.iter_mut()) {
        for c in 0..dim {
            r.u[c] += free.motion_at(rho, k.node, &k.x, c);
        }
        r.u_n = k.frame.normal_part(&r.u);
        r.u_t = k.frame.tangential_part(&r.u);
    }
    Ok(())
}

/// A linear solve that did not converge is an error naming the solver settings of the case.
pub(super) fn ensure_converged(
    step: usize,
    info: &SolveInfo,
    keys: &crate::signorini::boundary::CaseKeys,
) -> Result<(), RunError> {
    if info.converged() {
        return Ok(());
    }
    Err(RunError::Failed(format!(
        "Newton step {step}: the linear solver did not converge ({} after {} iterations); \
         {}: it is set by {} (and PETSc options after --)",
        info.reason_name,
        info.iterations,
        keys.file.display(),
        keys.solver
    )))
}

/// The rank-0 progress lines of a step.
pub(super) fn log_step(ctx: &Ctx, h: &StepInfo, t: &StepTotals) {
    let how = match (&h.reuse, &h.amg) {
        (Some(_), _) if h.solve == SolveKind::Reuse => format!("reuse, {} its", h.iterations),
        (Some(r), _) if r.fallback => format!("{} its, refactorised", r.krylov_iterations),
        (_, Some(a)) if a.skipped => {
            "no solve: a floating body, the model predicts from the gaps".to_string()
        }
        (_, Some(a)) if a.initial_residual == 0.0 && h.iterations == 0 && !a.pc_setup => {
            "no right-hand side, no solve".to_string()
        }
        (_, Some(a)) => format!(
            "{} its, {}{}{}, r0 {:.1e}",
            h.iterations,
            if a.fallback {
                "PC reused, failed, set up"
            } else if a.pc_setup {
                "PC set up"
            } else {
                "PC reused"
            },
            if a.inexact { ", inexact" } else { "" },
            if a.null_space {
                ", free modes as null space"
            } else {
                ""
            },
            a.initial_residual
        ),
        _ => format!("{} its", h.iterations),
    };
    say!(
        ctx,
        "newton {:3}: |A_n| = {:6}  changed {:6}  |C_n| = {:.3e}  pinned {}  solve {:.3} s ({how})",
        h.step,
        h.active,
        h.changed,
        h.residual,
        h.pinned,
        h.solve_seconds,
    );
    if let Some(s) = h.states {
        say!(
            ctx,
            "            S1 {} S2 {} S3 {} S4 {}  |du|/|u| = {:.3e}",
            s[0],
            s[1],
            s[2],
            s[3],
            t.du_rel
        );
    }
}
