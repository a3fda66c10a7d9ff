//! The reduced systems (3.29) / (3.42), written into a matrix that keeps A's nonzero pattern
//! (the symbolic part, made once) so that only values change from step to step (the numeric
//! part) and MUMPS reuses its analysis. Every prescribed direction (active normal, stick
//! tangent, pinned dof) is eliminated symmetrically: from the node's own rows and from the
//! columns, i.e. a mirror block in each unconstrained neighbour's rows (which may belong to
//! another rank: PETSc moves those entries at assembly). A Tresca slip row adds L̃ and r̃
//! (3.39) to the node's own block. Dirichlet data are eliminated earlier, per element, in
//! assembly.rs; this is the same elimination at matrix level.

use super::active_set::{ActiveSet, Iterate};
use super::boundary::ContactBoundary;
use super::rigid::Pin;
use crate::assembly::System;
use crate::case::Reuse;
use crate::contact::{coulomb_block, CoulombRow, Frame, TangentialRow};
use crate::linsolve::{self, LinearSetup, LinearSolver, SolverKind, SymbolicSchur};
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::mumps::NodeBases;
use crate::petsc::{self, Ksp, Matrix, PInt, SolveInfo, Vector};
use std::collections::HashMap;
use std::time::Instant;

/// A contact node's d rows of A (all with the same columns: A is assembled in d×d blocks).
#[derive(Clone, Debug)]
pub struct NodeRows {
    /// Global index of the node's first row.
    pub row: usize,
    pub cols: Vec<PInt>,
    /// vals[j] = row `row + j` of A on `cols`.
    pub vals: Vec<Vec<f64>>,
    /// Position of the node's own column `row + j` in `cols`.
    pub own: [usize; 3],
}

impl NodeRows {
    /// Copies the node's rows out of A (they do not change during the Newton iteration).
    pub fn read(a: &Matrix, row: usize, dim: usize) -> petsc::Result<NodeRows> {
        let mut cols: Vec<PInt> = Vec::new();
        let mut vals = Vec::with_capacity(dim);
        for j in 0..dim {
            let (c, v) = a.with_row(row + j, |c, v| (c.to_vec(), v.to_vec()))?;
            if j == 0 {
                cols = c;
            } else if c != cols {
                return Err(petsc::PetscError {
                    code: -1,
                    message: format!(
                        "rows {row}..{} of A do not share one pattern (internal error)",
                        row + dim
                    ),
                    location: format!("{}:{}", file!(), line!()),
                });
            }
            vals.push(v);
        }
        let mut own = [0usize; 3];
        for (j, o) in own.iter_mut().enumerate().take(dim) {
            *o = cols
                .binary_search(&((row + j) as PInt))
                .expect("the diagonal block is in A's pattern");
        }
        Ok(NodeRows {
            row,
            cols,
            vals,
            own,
        })
    }

    /// Row `row + j` of A times the local values: the diagonal entry a_jj.
    pub fn diag(&self, j: usize) -> f64 {
        self.vals[j][self.own[j]]
    }
}

/// Prescribed components of one node: orthonormal directions c with cᵀ u = value (an active
/// contact node: c = n, value = −g; a stick tangent: c = τ_i, value = 0; a pinned dof:
/// c = e_k, value = 0), and a slip row's spring. A node with no direction (a Tresca slip node
/// of an inactive contact node) is still rewritten by its owner.
#[derive(Clone, Debug, Default)]
pub struct NodeConstraint {
    pub dirs: Vec<([f64; 3], f64)>,
    /// Added to the node's own block (Tresca slip rows (3.39): Σ τ_i L̃_ij τ_jᵀ); only the
    /// owner of the node uses it.
    pub spring: [[f64; 3]; 3],
    /// Added to the node's right-hand side (Σ τ_i r̃_i).
    pub spring_rhs: [f64; 3],
    /// A Coulomb slip row's λ_n coupling E = Σ q_i τ_i nᵀ (F7): the node's rows are
    /// (P_k + E) A_kj P_j; zero otherwise. Only the owner of the node uses it.
    pub row_mix: Option<[[f64; 3]; 3]>,
}

impl NodeConstraint {
    /// P = I − Σ c cᵀ (projector onto the free components).
    pub fn projector(&self, dim: usize) -> [[f64; 3]; 3] {
        let mut p = [[0.0; 3]; 3];
        for (a, row) in p.iter_mut().enumerate().take(dim) {
            row[a] = 1.0;
        }
        for (c, _) in &self.dirs {
            for a in 0..dim {
                for b in 0..dim {
                    p[a][b] -= c[a] * c[b];
                }
            }
        }
        p
    }

    /// ū = Σ value · c (the prescribed part of u).
    pub fn known(&self) -> [f64; 3] {
        let mut u = [0.0; 3];
        for (c, v) in &self.dirs {
            for a in 0..3 {
                u[a] += v * c[a];
            }
        }
        u
    }
}

impl NodeConstraint {
    /// A slip row: Tresca's (3.39a) by [`Self::add_slip_spring`], Coulomb's (F7) with its
    /// coupling by `coulomb_block`.
    pub fn add_slip_row(&mut self, frame: &Frame, row: &CoulombRow<2>, dim: usize) {
        if !row.coupled() {
            self.add_slip_spring(&frame.t, &row.tresca_part(), dim);
            return;
        }
        let blk = coulomb_block(frame, row);
        for a in 0..dim {
            for b in 0..dim {
                self.spring[a][b] += blk.spring[a][b];
            }
            self.spring_rhs[a] += blk.spring_rhs[a];
        }
        self.row_mix = Some(blk.row_mix);
    }

    /// The slip row (3.39a) τᵀ(A u)_k + L̃ τᵀ u^k = τᵀ f_k + r̃: adds Σ τ_i L̃_ij τ_jᵀ to the node's
    /// block and Σ τ_i r̃_i to its right-hand side.
    pub fn add_slip_spring(&mut self, t: &[[f64; 3]; 2], row: &TangentialRow<2>, dim: usize) {
        let TangentialRow::Slip { l, r } = row else {
            return;
        };
        for a in 0..dim {
            for b in 0..dim {
                for (ii, ti) in t[..dim - 1].iter().enumerate() {
                    for (jj, tj) in t[..dim - 1].iter().enumerate() {
                        self.spring[a][b] += ti[a] * l[ii][jj] * tj[b];
                    }
                }
            }
            for (ii, ti) in t[..dim - 1].iter().enumerate() {
                self.spring_rhs[a] += ti[a] * r[ii];
            }
        }
    }
}

/// The constraints of every rewritten node (contact nodes with prescribed rows, pinned dofs) by
/// global node number, on every rank: a node's rows are rewritten by its owner, its columns in
/// every neighbour's rows.
pub struct ConstraintMap(HashMap<usize, NodeConstraint>);

impl ConstraintMap {
    /// One all-gather of the rewritten contact nodes' directions; the pins are known everywhere.
    /// Collective.
    pub fn gather(
        ctx: &Ctx,
        layout: &Layout,
        b: &ContactBoundary,
        set: &ActiveSet,
        pins: &[Pin],
        dim: usize,
    ) -> ConstraintMap {
        // Records (global node, c, value); a node rewritten without a direction sends value NaN.
        let mut mine: Vec<f64> = Vec::new();
        for (i, k) in b.nodes.iter().enumerate() {
            if let Some(p) = set.prescribed(b, i, dim) {
                let gk = layout.node_global[k.node] as f64;
                if p.dirs.is_empty() {
                    mine.extend_from_slice(&[gk, 0.0, 0.0, 0.0, f64::NAN]);
                }
                for (c, v) in &p.dirs {
                    mine.extend_from_slice(&[gk, c[0], c[1], c[2], *v]);
                }
            }
        }
        let all = ctx.all_gather_varcount(&mine);
        let mut map: HashMap<usize, NodeConstraint> = HashMap::new();
        for r in all.chunks_exact(5) {
            let e = map.entry(r[0] as usize).or_default();
            if !r[4].is_nan() {
                e.dirs.push(([r[1], r[2], r[3]], r[4]));
            }
        }
        for &(v, k) in pins {
            let mut e = [0.0; 3];
            e[k] = 1.0;
            map.entry(v) // pins name global nodes
                .or_default()
                .dirs
                .push((e, 0.0));
        }
        ConstraintMap(map)
    }

    pub fn get(&self, global_node: usize) -> Option<&NodeConstraint> {
        self.0.get(&global_node)
    }

    /// The prescribed directions of every rewritten node (the same on every rank): with the
    /// slip blocks, what the matrix S depends on (the values only reach the right-hand side).
    fn directions(&self) -> Directions {
        self.0
            .iter()
            .map(|(&k, c)| (k, c.dirs.iter().map(|(d, _)| *d).collect()))
            .collect()
    }
}

/// Prescribed directions by global node.
type Directions = HashMap<usize, Vec<[f64; 3]>>;

/// Slip blocks Σ τ_i L̃_ij τ_jᵀ of this rank's rewritten nodes, by first local row.
type Springs = HashMap<usize, [[f64; 3]; 3]>;

/// Prescribed directions added or removed between two systems, over all nodes. Each changes
/// the node's rows and columns by a term of rank ≤ 2 (S' − S = c wᵀ + w cᵀ for one direction c
/// of (3.29) applied symmetrically).
fn direction_changes(old: &Directions, new: &Directions) -> usize {
    let missing = |a: &Directions, b: &Directions| -> usize {
        a.iter()
            .map(|(k, dirs)| {
                let other = b.get(k).map(Vec::as_slice).unwrap_or(&[]);
                dirs.iter().filter(|d| !other.contains(d)).count()
            })
            .sum()
    };
    missing(old, new) + missing(new, old)
}

/// This rank's nodes whose slip block differs between two systems (each a change of rank
/// ≤ d − 1 in the node's own block).
fn spring_changes(old: &Springs, new: &Springs) -> usize {
    let zero = [[0.0; 3]; 3];
    let differs = |a: &Springs, b: &Springs| -> usize {
        a.iter()
            .filter(|(k, m)| b.get(k).unwrap_or(&zero) != *m)
            .count()
    };
    // a key in both maps that differs is counted twice: count the union once
    let both = old
        .iter()
        .filter(|(k, m)| new.get(k).is_some_and(|n| n != *m))
        .count();
    differs(old, new) + differs(new, old) - both
}

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

/// "always": Krylov iterations a reuse may make before the step refactorises (fixed, so that
/// runs and tests are reproducible; "auto" takes its budget from the factorisation's counts).
pub const ALWAYS_BUDGET: usize = 30;

/// "auto" reuses only if the expected Krylov solve costs at most this fraction of a
/// factorisation step: room for the estimate of one iteration.
pub const AUTO_MARGIN: f64 = 0.75;

/// The cost of one Krylov iteration on the factorisation as this multiple of one triangular
/// solve pair (MatSolve; plus MatMult and orthogonalisation).
pub const ITERATION_PER_SOLVE: f64 = 1.25;

/// The cost of one flop of a triangular solve pair (sparse, memory-bound, one vector) in flops
/// of the numeric factorisation (dense fronts, BLAS 3): a fixed ratio, so that "auto"'s choice
/// depends on the run's counts alone, never on its timings. Measured on the plain path of
/// the Hertz disk (docs/numbers.md, "solver.reuse = auto from counts").
pub const SOLVE_FLOP_COST: f64 = 4.0;

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
struct Reuser {
    mode: Reuse,
    ksp: Ksp,
    /// Directions and this rank's slip blocks of the factored matrix (`None`: none factored).
    factored: Option<(Directions, Springs)>,
    /// The same of the system written last.
    current: (Directions, Springs),
    /// The costs of the factored matrix' factorisation (`None`: no MUMPS statistics, e.g.
    /// a preconditioner given by `solver.petsc_options`: "auto" then never reuses).
    costs: Option<ReuseCosts>,
}

impl Reuser {
    /// Whether to try the reuse, and its budget: "always" whenever a factorisation exists;
    /// "auto" by [`ReuseCosts::plan`] on the factored matrix' counts.
    fn plan(&self, rank: usize) -> Option<usize> {
        self.factored.as_ref()?;
        match self.mode {
            Reuse::Never => None,
            Reuse::Always => Some(ALWAYS_BUDGET),
            Reuse::Auto => self.costs?.plan(rank),
        }
    }
}

/// An inexact step of the iterative preset reduces the residual of its warm start by this
/// factor (‖b − S u‖ ≤ INEXACT_REDUCTION ‖b − S u₀‖, never looser than the preset's own
/// tolerance): while the active set still changes, a step only has to tell the next set, not
/// the final u. Relative to the start rather than to ‖b‖: the start's residual comes from the
/// nodes that changed, on the scale of the nodal contact forces, which shrink with the mesh
/// while ‖b‖ does not. Measured on 3D Hertz, 2 ranks: a fixed 1e-4 ‖b‖ made the set chatter
/// (79 k unknowns: ~150 nodes changing in every step, no convergence in 100 steps); a fixed
/// 1e-6 ‖b‖ went through the plain path's sets at 79 k but not at 526 k (11 steps instead of
/// 7, the last three exact after the set grew again).
pub const INEXACT_REDUCTION: f64 = 1e-6;

/// The half-space predictor's first solve (no active node) only has to give the model the
/// normal displacements u⁰_n, a smooth field: it reduces its residual by this factor.
/// Measured at 527 k unknowns (3D Hertz, 2 ranks): 1e-3, 1e-2, 1e-1 took 7, 5, 4 iterations
/// and gave predicted sets of 1 579, 1 578, 1 578 nodes (final set 1 576).
pub const PREDICTOR_REDUCTION: f64 = 1e-2;

/// "auto" (iterative preset): the next step sets the preconditioner up anew (PCSetUp on its
/// matrix) when this step needed more than this multiple of the iterations per decade of
/// residual reduction that the solve right after the last setup needed.
pub const REBUILD_GROWTH: f64 = 1.3;

/// A solve on a reused preconditioner may make this multiple of the iterations that the rate
/// after the last setup predicts for it before it stops and the preconditioner is set up anew.
pub const REUSE_BUDGET: f64 = 4.0;

/// A solve must reduce the residual by at least this many decades and make this many
/// iterations before its rate (iterations per decade) is compared: a warm start that is
/// already nearly converged says nothing about the preconditioner.
const RATE_MIN_DECADES: f64 = 1.5;
const RATE_MIN_ITERATIONS: usize = 4;

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
    /// ([`ReducedSystem::set_free_null_space`]).
    pub null_space: bool,
    /// The set-up also built GAMG's aggregates and prolongators anew instead of keeping the
    /// last ones (the step after the predictor's first solve).
    pub new_hierarchy: bool,
    /// No solve: the predictor's first solve of a floating body, u⁰ = 0
    /// ([`ReducedSystem::set_predictor_solve`]).
    pub skipped: bool,
}

/// The iterative preset's reuse path (`solver.reuse` "auto" / "always"): warm starts, the
/// preconditioner kept from step to step, inexact early steps (set by the Newton loop).
struct AmgReuser {
    mode: Reuse,
    /// The configured relative tolerance and iteration limit (preset < case < command line).
    rtol: f64,
    max_it: usize,
    /// Iterations per decade of the solve right after the last PCSetUp.
    fresh_rate: Option<f64>,
    /// A preconditioner has been set up.
    built: bool,
    /// The next solve sets the preconditioner up anew ("auto": the rate grew).
    rebuild: bool,
    /// That set-up also builds GAMG's aggregates and prolongators anew (after the predictor's
    /// first solve, whose matrix has no active node and the pins of every rigid mode: kept,
    /// its prolongators cost the exact steps after it half again as many iterations, the full
    /// ball at 57 k unknowns 36 and 35 against 22 and 19).
    rebuild_hierarchy: bool,
    /// The last set-up did so.
    new_hierarchy: bool,
    /// This step's solve may stop at [`INEXACT_REDUCTION`] of its start's residual.
    inexact: bool,
    /// This step's solve is the predictor's first ([`ReducedSystem::set_predictor_solve`]).
    predictor: bool,
    /// ... and is skipped (u = 0, no setup).
    skip: bool,
    /// The free rigid modes are S's null space ([`ReducedSystem::set_free_null_space`]).
    null_space: bool,
    /// This rank's prescribed node components of the system written last: (first local row,
    /// projector P onto the free components, prescribed part ū).
    prescribed: Vec<(usize, [[f64; 3]; 3], [f64; 3])>,
}

impl AmgReuser {
    /// The relative tolerance (on ‖b‖, the default test of a nonzero start) of this solve:
    /// the preset's, or for an inexact step [`INEXACT_REDUCTION`] (the predictor's first
    /// solve: [`PREDICTOR_REDUCTION`]) of the start's residual, never tighter than the preset's.
    fn tolerance(&self, predictor: bool, r0: f64, bnorm: f64) -> f64 {
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
    fn budget(&self, setup: bool, r0: f64, rtol: f64, bnorm: f64) -> usize {
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
    fn krylov(
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
    fn learn(
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
    fn record(
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

/// The reduced system of one Newton step and its solver: the matrix S on A's pattern, the
/// right-hand side, the KSP, and the (constant) rows of A at the contact nodes and the pins.
pub struct ReducedSystem {
    s: Matrix,
    rhs: Vector,
    u: Vector,
    au: Vector,
    ls: LinearSolver,
    contact_rows: Vec<NodeRows>,
    pin_rows: Vec<(usize, NodeRows)>,
    /// This rank's rows of f.
    pub f_local: Vec<f64>,
    /// First global row of this rank.
    pub row_lo: usize,
    buf: Vec<f64>,
    /// Seconds spent writing the reduced systems, all steps.
    pub rows_seconds: f64,
    /// Seconds spent in λ recovery (MatMult + local work), all steps.
    pub lambda_seconds: f64,
    dim: usize,
    /// How the solver solves (known after the first solve).
    kind: Option<SolveKind>,
    /// The reuse path (direct preset, `solver.reuse` not "never").
    reuser: Option<Reuser>,
    /// The reuse path of the iterative preset (`solver.reuse` not "never").
    amg: Option<AmgReuser>,
    /// Force control: the last lift u¹ of each force-controlled pair, the next lift's start on
    /// the iterative preset (a lift depends on the set and F/|F| only, which change little
    /// from step to step).
    lifts: Vec<Option<Vector>>,
    /// With friction: the directions and this rank's slip blocks of the system written last,
    /// and how it differed from the one before ([`RowChange`]; `None` for the first).
    previous: Option<(Directions, ScaledSprings)>,
    change: Option<RowChange>,
    /// The iterative preset with Coulomb's (F7) rows: the matrix GAMG is built from, S without
    /// the row mix E (a scratch right-hand side with it), and whether this step uses it.
    amg_matrix: Option<(Matrix, Vector)>,
    unmixed: bool,
}

impl ReducedSystem {
    /// The symbolic part, made once: S with A's pattern, its KSP, the contact nodes' rows of A.
    pub fn new(
        ctx: &Ctx,
        sys: &System,
        b: &ContactBoundary,
        setup: &LinearSetup,
        dim: usize,
    ) -> petsc::Result<ReducedSystem> {
        let contact_rows = b
            .nodes
            .iter()
            .map(|k| NodeRows::read(&sys.a, k.row, dim))
            .collect::<Result<_, _>>()?;
        let f_local = sys.b.to_local_vec()?;
        let mut s = sys.a.duplicate()?;
        let ls = setup.solver(ctx.comm(), &mut s)?;
        let (row_lo, _) = sys.a.ownership_range()?;
        Ok(ReducedSystem {
            s,
            rhs: sys.b.duplicate()?,
            u: sys.b.duplicate()?,
            au: sys.b.duplicate()?,
            ls,
            contact_rows,
            pin_rows: Vec::new(),
            f_local,
            row_lo,
            buf: Vec::new(),
            rows_seconds: 0.0,
            lambda_seconds: 0.0,
            dim,
            kind: None,
            reuser: None,
            amg: None,
            lifts: Vec::new(),
            previous: None,
            change: None,
            amg_matrix: None,
            unmixed: false,
        })
    }

    /// Enables the reuse of factorisations across steps (`solver.reuse`): only if the solver
    /// factorises (direct preset). With friction (`friction`: a Tresca threshold or Coulomb's
    /// fixed point) "auto" stays on the plain path with the direct preset: a node on its
    /// stick/slip threshold to round-off may flip between steps, and the ~1e-10 that a reuse
    /// solve leaves in Δu (GMRES to 1e-13 on the preconditioned residual) then hides that the
    /// iterate no longer moves, so the recurring-set stop (|Δu|/|u| < tol_u) cannot apply and the
    /// run ends as cycling (seen on 2 ranks: tests/coulomb.rs, warm start of the fixed point,
    /// whenever the timings made "auto" reuse). "always" still reuses. Collective.
    pub fn enable_reuse(&mut self, ctx: &Ctx, mode: Reuse, friction: bool) -> petsc::Result<()> {
        let factorises = self.ls.kind().factorises();
        self.amg = None;
        if mode == Reuse::Never {
            self.reuser = None;
            return Ok(());
        }
        if !factorises {
            // Krylov with a preconditioner that is set up per matrix (GAMG and the like).
            self.reuser = None;
            let (rtol, max_it) = self.ls.ksp.tolerances()?;
            self.amg = Some(AmgReuser {
                mode,
                rtol,
                max_it,
                fresh_rate: None,
                built: false,
                rebuild: false,
                rebuild_hierarchy: false,
                new_hierarchy: false,
                inexact: false,
                predictor: false,
                skip: false,
                null_space: false,
                prescribed: Vec::new(),
            });
            return Ok(());
        }
        if friction && mode == Reuse::Auto {
            self.reuser = None;
            return Ok(());
        }
        let ksp = self.ls.reuse_solver(ctx.comm())?;
        self.reuser = Some(Reuser {
            mode,
            ksp,
            factored: None,
            current: (Directions::new(), Springs::new()),
            costs: None,
        });
        Ok(())
    }

    /// Reads the rows of A of the owned pinned nodes (for their symmetric elimination).
    pub fn set_pins(&mut self, sys: &System, layout: &Layout, pins: &[Pin]) -> petsc::Result<()> {
        let dim = self.dim;
        let mut owned: Vec<usize> = pins
            .iter()
            .map(|&(v, _)| v)
            .filter(|&v| (layout.node_range().0..layout.node_range().1).contains(&v))
            .collect();
        owned.sort_unstable();
        owned.dedup();
        self.pin_rows.clear();
        for v in owned {
            let r = NodeRows::read(&sys.a, v * dim, dim)?;
            self.pin_rows.push((v, r));
        }
        Ok(())
    }

    /// The numeric part of a step: S and its right-hand side for `set` and `pins` — (3.29)
    /// without friction, (3.42) with Tresca — applied symmetrically. Collective.
    pub fn write(
        &mut self,
        ctx: &Ctx,
        sys: &System,
        layout: &Layout,
        b: &ContactBoundary,
        set: &ActiveSet,
        pins: &[Pin],
    ) -> petsc::Result<()> {
        let t = Instant::now();
        let dim = self.dim;
        self.s.copy_values_from(&sys.a)?;
        self.rhs.copy_from(&sys.b)?;
        let cmap = ConstraintMap::gather(ctx, layout, b, set, pins, dim);
        let writes = rewrites(
            (&self.contact_rows, &self.pin_rows, self.row_lo),
            layout,
            b,
            set,
            &cmap,
            dim,
        );
        if let Some(re) = &mut self.reuser {
            let zero = [[0.0; 3]; 3];
            let springs = writes
                .iter()
                .filter(|(_, me, _)| me.spring != zero)
                .map(|(_, me, lr)| (*lr, me.spring))
                .collect();
            re.current = (cmap.directions(), springs);
        }
        if set.tangential.is_some() {
            let dirs = cmap.directions();
            let springs: ScaledSprings = writes
                .iter()
                .filter(|(_, me, _)| me.spring != [[0.0; 3]; 3])
                .map(|(r, me, lr)| {
                    let scale = (0..dim).map(|j| r.diag(j).abs()).sum::<f64>() / dim as f64;
                    (*lr, (me.spring, scale))
                })
                .collect();
            self.change = match &self.previous {
                Some((d0, s0)) => {
                    let (real, roundoff) = slip_block_changes(s0, &springs);
                    let g = ctx.sum_vec(&[real as f64, roundoff as f64]);
                    Some(RowChange {
                        directions: direction_changes(d0, &dirs),
                        slip_blocks: g[0].round() as usize,
                        slip_blocks_roundoff: g[1].round() as usize,
                    })
                }
                None => None,
            };
            self.previous = Some((dirs, springs));
        }
        if let Some(amg) = &mut self.amg {
            amg.prescribed = writes
                .iter()
                .filter(|(_, me, _)| !me.dirs.is_empty())
                .map(|(_, me, lr)| (*lr, me.projector(dim), me.known()))
                .collect();
        }
        write_rows(
            Some(&mut self.s),
            &mut self.rhs,
            (&writes, Some(&self.f_local)),
            &cmap,
            dim,
            &mut self.buf,
        )?;
        // the same solver on every rank: the reduction only on the iterative preset
        self.unmixed = !self.ls.kind().factorises()
            && ctx.any(writes.iter().any(|(_, me, _)| me.row_mix.is_some()));
        if self.unmixed {
            let made = &mut self.amg_matrix;
            write_unmixed(
                made,
                (&self.s, &self.rhs),
                sys,
                (&writes, &cmap),
                (dim, &mut self.buf),
            )?;
        }
        self.rows_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// Solves the step's system. Without the reuse path: one KSPSolve (a numeric
    /// factorisation of the direct preset, or Krylov iterations). With it (`allow_reuse`:
    /// Coulomb's unsymmetric (F7) rows stay on the plain path): Krylov iterations on S_k
    /// preconditioned by the factorisation of the last factored S_j when [`Reuser::plan`]
    /// says so, and a numeric refactorisation of S_k otherwise or when they do not reach
    /// their tolerance within the budget. Collective.
    pub fn solve(&mut self, ctx: &Ctx, allow_reuse: bool) -> petsc::Result<StepSolve> {
        if self.amg.is_some() {
            return self.solve_amg(ctx);
        }
        if self.reuser.is_none() {
            return self.solve_plain();
        }
        let t = Instant::now();
        let dim = self.dim;
        let re = self.reuser.as_mut().expect("checked");
        // One Allreduce: the slip blocks changed on every rank, so that every rank takes the
        // same path (the costs are MUMPS' global counts, the same on every rank).
        let (dirs, springs) = match &re.factored {
            Some((d, sp)) => (
                direction_changes(d, &re.current.0),
                spring_changes(sp, &re.current.1),
            ),
            None => (0, 0),
        };
        let g = ctx.sum_vec(&[springs as f64]);
        let rank = 2 * dirs + (dim - 1) * (g[0].round() as usize);
        let weighed = match (&re.factored, re.costs) {
            (Some(_), Some(c)) => (c.factorisation + c.solve, c.iteration()),
            _ => (0.0, 0.0),
        };
        let mut step = ReuseStep {
            rank,
            budget: 0,
            krylov_iterations: 0,
            fallback: false,
            factorisation_seconds: 0.0,
            cost_factorisation: weighed.0,
            cost_iteration: weighed.1,
        };
        let plan = if allow_reuse { re.plan(rank) } else { None };
        if let Some(budget) = plan {
            re.ksp.set_operator(&self.s)?;
            re.ksp.set_reuse_preconditioner(true)?;
            re.ksp.set_max_iterations(budget)?;
            let info = re.ksp.solve(&self.rhs, &mut self.u)?;
            step.budget = budget;
            step.krylov_iterations = info.iterations;
            if info.converged() {
                let secs = t.elapsed().as_secs_f64();
                return Ok(StepSolve {
                    info,
                    kind: SolveKind::Reuse,
                    seconds: secs,
                    setup_seconds: None,
                    reuse: Some(step),
                    amg: None,
                });
            }
            step.fallback = true;
        }
        // A numeric factorisation of S_k (the shared PC sets up anew: its operator changed),
        // timed apart from its solve.
        self.ls.ksp.set_reuse_preconditioner(false)?;
        self.ls.ksp.set_operator(&self.s)?;
        let tf = Instant::now();
        self.ls.ksp.set_up()?;
        step.factorisation_seconds = tf.elapsed().as_secs_f64();
        let info = self.ls.solve(&self.rhs, &mut self.u)?;
        re.costs =
            petsc::ndfactor::record(&self.ls.ksp)?.and_then(|(r, _)| ReuseCosts::of(&r.stats));
        re.factored = Some(re.current.clone());
        Ok(StepSolve {
            info,
            kind: SolveKind::Factorisation,
            seconds: t.elapsed().as_secs_f64(),
            setup_seconds: None,
            reuse: Some(step),
            amg: None,
        })
    }

    /// The free rigid modes as the null space of S instead of pins (`Some(fields)`, this
    /// rank's rows of each mode; `None` detaches it): the fields are orthonormalised and
    /// attached to S, and Krylov solves then leave their components alone (the solution is
    /// one member of the family u + Σ α_j r_j; the Newton loop moves it to the pinned one).
    /// The iterative preset's use: a mode held by one pinned dof is a point constraint, whose
    /// stiffness falls with the mesh size, and GMRES + GAMG then needs more iterations per
    /// decade than on the same body held along a surface. Collective.
    pub fn set_free_null_space(
        &mut self,
        ctx: &Ctx,
        fields: Option<Vec<Vec<f64>>>,
    ) -> petsc::Result<()> {
        let mut basis: Vec<Vector> = Vec::new();
        let mut done: Vec<Vec<f64>> = Vec::new();
        for mut f in fields.unwrap_or_default() {
            // Gram–Schmidt twice against the fields before (global dot products)
            for _ in 0..2 {
                let dots: Vec<f64> = done
                    .iter()
                    .map(|g| g.iter().zip(&f).map(|(a, b)| a * b).sum())
                    .collect();
                let dots = ctx.sum_vec(&dots);
                for (g, d) in done.iter().zip(&dots) {
                    f.iter_mut().zip(g).for_each(|(x, y)| *x -= d * y);
                }
            }
            let norm = ctx.sum_vec(&[f.iter().map(|x| x * x).sum::<f64>()])[0].sqrt();
            if norm == 0.0 {
                continue;
            }
            f.iter_mut().for_each(|x| *x /= norm);
            let mut v = self.u.duplicate()?;
            v.write(|x| x.copy_from_slice(&f))?;
            basis.push(v);
            done.push(f);
        }
        if let Some(amg) = &mut self.amg {
            amg.null_space = !basis.is_empty();
        }
        self.s.set_null_space(ctx.comm(), &basis)
    }

    /// This rank's first global row and row count.
    pub fn local_rows(&self) -> (usize, usize) {
        (self.row_lo, self.f_local.len())
    }

    /// Adds `delta` (this rank's rows) to the last solution.
    pub fn add_to_solution(&mut self, delta: &[f64]) -> petsc::Result<()> {
        self.u
            .write(|x| x.iter_mut().zip(delta).for_each(|(a, b)| *a += b))
    }

    /// How the system written last differs from the one before (friction; `None` for the
    /// first and without friction).
    pub fn change(&self) -> Option<RowChange> {
        self.change
    }

    /// Whether the solver may make inexact steps (the iterative preset's reuse path).
    pub fn inexact_available(&self) -> bool {
        self.amg.is_some()
    }

    /// Lets the next solve stop at [`INEXACT_REDUCTION`] of its start's residual (`true`) or
    /// at the configured tolerance.
    pub fn set_inexact(&mut self, inexact: bool) {
        if let Some(amg) = &mut self.amg {
            amg.inexact = inexact;
        }
    }

    /// The half-space predictor's first solve (predictor.rs): the next solve, inexact, stops
    /// at [`PREDICTOR_REDUCTION`] of its start's residual, and ("auto") the solve after it sets
    /// the preconditioner up on its own matrix (the first matrix has no active node, a poor
    /// preconditioner for the predicted set's: 30 instead of 13 iterations at 527 k unknowns,
    /// and an iterate whose set update flipped 115 edge nodes instead of 8).
    ///
    /// `skip`: no solve at all, u⁰ = 0 (a body that Dirichlet data leave free in a rigid mode:
    /// its pinned u⁰ is the load's deformation against arbitrary pins, and the model, whose free
    /// modes carry the load's resultant into contact, predicts as well from the gaps alone —
    /// measured on the full floating ball at 126 888 unknowns: the same 409 nodes, the same
    /// steps after, one GAMG setup fewer); the preconditioner is then set up by the next
    /// solve, on the predicted set's matrix.
    pub fn set_predictor_solve(&mut self, skip: bool) {
        if let Some(amg) = &mut self.amg {
            amg.predictor = true;
            amg.skip = skip;
        }
    }

    /// ‖rhs − S u‖₂ and ‖rhs‖₂. Collective.
    fn residual_norms(&mut self, ctx: &Ctx) -> petsc::Result<(f64, f64)> {
        self.s.mult(&self.u, &mut self.au)?;
        let (b, au) = (self.rhs.to_local_vec()?, self.au.to_local_vec()?);
        let (mut rr, mut bb) = (0.0, 0.0);
        for (x, y) in b.iter().zip(&au) {
            rr += (x - y) * (x - y);
            bb += x * x;
        }
        let g = ctx.sum_vec(&[rr, bb]);
        Ok((g[0].sqrt(), g[1].sqrt()))
    }

    /// The iterative preset's reuse path: the previous step's u as the start, its prescribed
    /// components set exactly (u_k ← P_k u_k + ū_k); the preconditioner set up in the first
    /// step and reused, set up anew when [`AmgReuser`]'s rule asks for it ("auto": the
    /// iterations per decade grew beyond [`REBUILD_GROWTH`] × those after the last setup) or
    /// when a solve on the reused one does not converge; the tolerance of an inexact step when
    /// the Newton loop says so. Every decision is taken from global quantities (iteration
    /// counts, norms), the same on every rank. Collective.
    fn solve_amg(&mut self, ctx: &Ctx) -> petsc::Result<StepSolve> {
        let t = Instant::now();
        let (r0, bnorm, zero_start) = self.warm_start(ctx)?;
        self.set_operators()?;
        let amg = self.amg.as_mut().expect("checked");
        let first = !amg.built;
        let skipped = std::mem::take(&mut amg.skip) && bnorm > 0.0;
        if (bnorm == 0.0 || skipped) && first {
            // No load yet (a body loaded only through the contact, the predictor's first
            // solve): u = 0 without a solve, and the preconditioner is set up by the first
            // solve that has a right-hand side, on its own matrix.
            amg.predictor = false;
            let info = SolveInfo {
                iterations: 0,
                reason: 2, // KSP_CONVERGED_RTOL_NORMAL's sign: converged
                reason_name: "zero right-hand side".into(),
            };
            let record = AmgStep {
                skipped,
                ..amg.record(false, 0.0, amg.rtol, 0.0, 0.0, false)
            };
            return Ok(StepSolve {
                info,
                kind: SolveKind::Krylov,
                seconds: t.elapsed().as_secs_f64(),
                setup_seconds: None,
                reuse: None,
                amg: Some(record),
            });
        }
        let setup = first || amg.rebuild;
        let predictor = std::mem::take(&mut amg.predictor);
        let rtol = amg.tolerance(predictor, r0, bnorm);
        let ksp = &mut self.ls.ksp;
        ksp.set_initial_guess_nonzero(!zero_start)?;
        ksp.set_rtol(rtol)?;
        ksp.set_max_iterations(amg.budget(setup, r0, rtol, bnorm))?;
        let (info, fallback, setup_seconds) = amg.krylov(ksp, &self.rhs, &mut self.u, setup)?;
        let r_end = ksp.residual_norm()?;
        let rate = amg.learn(predictor, setup, fallback, r0, r_end, info.iterations);
        let r0_rel = if bnorm > 0.0 { r0 / bnorm } else { 0.0 };
        let record = amg.record(
            setup || fallback,
            setup_seconds,
            rtol,
            r0_rel,
            rate,
            fallback,
        );
        Ok(StepSolve {
            info,
            kind: if setup || fallback {
                SolveKind::Krylov
            } else {
                SolveKind::Reuse
            },
            seconds: t.elapsed().as_secs_f64(),
            setup_seconds: None,
            reuse: None,
            amg: Some(record),
        })
    }

    /// The start of an iterative-preset solve: zero in the first solve, else the previous u
    /// with its prescribed components set exactly (u_k ← P_k u_k + ū_k) — or zero again if
    /// that start is worse than none. Returns (‖b − S u₀‖, ‖b‖, zero start). Collective.
    fn warm_start(&mut self, ctx: &Ctx) -> petsc::Result<(f64, f64, bool)> {
        let dim = self.dim;
        let amg = self.amg.as_ref().expect("checked");
        let first = !amg.built;
        if first {
            self.u.set_all(0.0)?;
        } else {
            let pres = &amg.prescribed;
            self.u.write(|x| {
                for (lr, p, known) in pres {
                    let mut v = [0.0; 3];
                    for a in 0..dim {
                        v[a] = (0..dim).map(|b| p[a][b] * x[lr + b]).sum::<f64>() + known[a];
                    }
                    x[*lr..*lr + dim].copy_from_slice(&v[..dim]);
                }
            })?;
        }
        let (r0, bnorm) = self.residual_norms(ctx)?;
        // A warm start worse than none (‖b − S u₀‖ ≥ ‖b‖: e.g. the rigid motion of a free body
        // that the previous step's pins allowed, measured on block2d at ν = 0.4999, where it
        // was > 1e5 ‖b‖ and GMRES stopped at once with DIVERGED_DTOL): start from zero.
        // The norms are global: every rank decides alike.
        if !first && r0 >= bnorm {
            self.u.set_all(0.0)?;
            return Ok((bnorm, bnorm, true));
        }
        Ok((r0, bnorm, first))
    }

    /// True when the solver factorises (its kind, decided once by [`LinearSetup`]). Local.
    pub fn factorises(&self) -> petsc::Result<bool> {
        Ok(self.kind().factorises())
    }

    /// What the steps' solver runs. Local.
    pub fn kind(&self) -> SolverKind {
        self.ls.kind()
    }

    /// The symbolic factorisation of the matrix written last with a Schur complement on
    /// `schur_rows`, by the steps' solver ([`LinearSolver::analyse_schur`]). Collective.
    pub fn analyse_schur(
        &self,
        ctx: &Ctx,
        (n, schur_rows): (usize, &[usize]),
        (order, bases): (Option<&[usize]>, &NodeBases),
    ) -> petsc::Result<SymbolicSchur> {
        let root = ctx.rank == 0;
        let ls = &self.ls;
        ls.analyse_schur(ctx.comm(), &self.s, (n, schur_rows), (order, bases), root)
    }

    /// The KSP and PC types of the steps' solver ([`Ksp::type_names`]). Local.
    pub fn solver_types(&self) -> petsc::Result<(String, String)> {
        self.ls.ksp.type_names()
    }

    /// The matrix written last (the condensed path hands K_p to MUMPS directly).
    pub fn matrix(&self) -> &Matrix {
        &self.s
    }

    /// This rank's rows of the right-hand side written last.
    pub fn rhs_local(&self) -> petsc::Result<Vec<f64>> {
        self.rhs.to_local_vec()
    }

    /// Entries of the last solution at global rows `idx` (any rank's), on every rank.
    /// Collective.
    pub fn solution_at(&self, idx: &[PInt]) -> petsc::Result<Vec<f64>> {
        self.u.gather(idx)
    }

    /// This rank's rows of the last solution.
    pub fn solution_local(&self) -> petsc::Result<Vec<f64>> {
        self.u.to_local_vec()
    }

    /// The lift of force control (force.rs): the step's system (3.29) with f = 0, no Dirichlet
    /// values and the values `b` and `set` prescribe (the active normals' u_n = −g_k), solved
    /// on the last solve's factorisation or preconditioner (S is unchanged since: no new
    /// factorisation or setup), to the preset's tolerance — on the iterative preset from the
    /// last lift of the same force-controlled pair (`slot`: its index among them), and in an
    /// inexact step to [`INEXACT_REDUCTION`] of its right-hand side. Returns this rank's rows
    /// of the solution u¹ and of A u¹. Not with the direct preset's reuse solver (GMRES on an
    /// earlier factorisation). Collective.
    #[allow(clippy::too_many_arguments)]
    pub fn solve_lift(
        &mut self,
        ctx: &Ctx,
        slot: usize,
        sys: &System,
        layout: &Layout,
        b: &ContactBoundary,
        set: &ActiveSet,
        pins: &[Pin],
    ) -> petsc::Result<(Vec<f64>, Vec<f64>)> {
        if self.reuser.is_some() {
            // the plain path's one reuse rule (signorini::plain_reuse) keeps this from happening
            return Err(petsc::PetscError {
                code: -1,
                message: "internal: the force-control lift on a reused factorisation (force \
                          control takes no reuse)"
                    .to_string(),
                location: format!("{}:{}", file!(), line!()),
            });
        }
        let t = Instant::now();
        let dim = self.dim;
        let cmap = ConstraintMap::gather(ctx, layout, b, set, pins, dim);
        let writes = rewrites(
            (&self.contact_rows, &self.pin_rows, self.row_lo),
            layout,
            b,
            set,
            &cmap,
            dim,
        );
        let mut rhs = self.rhs.duplicate()?;
        rhs.set_all(0.0)?;
        write_rows(None, &mut rhs, (&writes, None), &cmap, dim, &mut self.buf)?;
        self.rows_seconds += t.elapsed().as_secs_f64();
        if self.lifts.len() <= slot {
            self.lifts.resize_with(slot + 1, || None);
        }
        let warm = self.amg.is_some() && self.lifts[slot].is_some();
        let mut x = match self.lifts[slot].take() {
            Some(v) if warm => v,
            _ => {
                let mut v = self.u.duplicate()?;
                v.set_all(0.0)?;
                v
            }
        };
        if let Some(amg) = &self.amg {
            // An inexact step's lift is inexact alike, to INEXACT_REDUCTION of its right-hand
            // side (not of its start's residual: the lift's error enters u times the step's
            // change of δ only, so the last lift's start is kept to that accuracy for free).
            let rtol = if amg.inexact {
                INEXACT_REDUCTION.max(amg.rtol)
            } else {
                amg.rtol
            };
            let ksp = &mut self.ls.ksp;
            ksp.set_initial_guess_nonzero(warm)?;
            ksp.set_rtol(rtol)?;
            ksp.set_max_iterations(amg.max_it)?;
            ksp.set_reuse_preconditioner(true)?;
        }
        let info = self.ls.solve(&rhs, &mut x)?;
        if !info.converged() {
            return Err(petsc::PetscError {
                code: -1,
                message: format!(
                    "the force-control lift did not converge ({} iterations)",
                    info.iterations
                ),
                location: format!("{}:{}", file!(), line!()),
            });
        }
        sys.a.mult(&x, &mut self.au)?;
        let out = (x.to_local_vec()?, self.au.to_local_vec()?);
        self.lifts[slot] = Some(x);
        Ok(out)
    }

    /// Replaces this rank's rows of the solution (what `recover` and `solution` read).
    pub fn set_solution_local(&mut self, v: &[f64]) -> petsc::Result<()> {
        self.u.write(|x| x.copy_from_slice(v))
    }

    /// S as the operator, and as the preconditioner's matrix unless this step has one of its
    /// own ([`write_unmixed`]).
    fn set_operators(&mut self) -> petsc::Result<()> {
        match (&self.amg_matrix, self.unmixed) {
            (Some((p, _)), true) => self.ls.ksp.set_operators(&self.s, p),
            _ => self.ls.ksp.set_operator(&self.s),
        }
    }

    /// One KSPSolve on the step's matrix (the plain path).
    fn solve_plain(&mut self) -> petsc::Result<StepSolve> {
        let t = Instant::now();
        self.set_operators()?;
        // the set-up (a numeric factorisation on the direct preset) timed apart from the solve
        // that follows it; KSPSolve then finds the KSP set up
        self.ls.ksp.set_up()?;
        let setup_seconds = t.elapsed().as_secs_f64();
        let info = self.ls.solve(&self.rhs, &mut self.u)?;
        let kind = match self.kind {
            Some(k) => k,
            None => {
                // The solver's type does not change between steps: asked once.
                let k = if self.ls.kind().factorises() {
                    SolveKind::Factorisation
                } else {
                    SolveKind::Krylov
                };
                self.kind = Some(k);
                k
            }
        };
        Ok(StepSolve {
            info,
            kind,
            seconds: t.elapsed().as_secs_f64(),
            setup_seconds: Some(setup_seconds),
            reuse: None,
            amg: None,
        })
    }

    /// (3.28) for the last solution: λ = f − A u on the contact rows (one MatMult), into `it`.
    /// Collective.
    pub fn recover(
        &mut self,
        sys: &System,
        b: &ContactBoundary,
        set: &ActiveSet,
        it: &mut Iterate,
    ) -> petsc::Result<()> {
        let t = Instant::now();
        sys.a.mult(&self.u, &mut self.au)?;
        let u_local = self.u.to_local_vec()?;
        let au_local = self.au.to_local_vec()?;
        it.recover(u_local, au_local, &self.f_local, b, set, self.dim);
        self.lambda_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// A copy of the last solution (the system stays for further solves: the fixed point).
    pub fn solution(&self) -> petsc::Result<Vector> {
        let mut u = self.u.duplicate()?;
        u.copy_from(&self.u)?;
        Ok(u)
    }
}

/// A rewritten node: its rows of A, its constraint, its first local row.
type Rewrite<'r> = (&'r NodeRows, NodeConstraint, usize);

/// A slip block whose entries change by at most this fraction of the node's stiffness (the
/// mean diagonal of its rows of A) changed by round-off only: the regularised L̃ of (3.39) of a
/// node that slips with |λ_τ| = b_k is 0 or c · 1e-14 from one solve to the next, depending on
/// the last bit of |λ_τ| − b_k (measured on the Hertz disk, stiffness of order 1: ~500 such
/// blocks per step at 42 040 unknowns, ~2 900 at 171 602, the largest entry 1.3e-11 in steps
/// where nothing else changed; of the changes above 1e-12 all but a handful exceeded 1e-8,
/// most 1e-4).
pub const SLIP_BLOCK_ROUNDOFF: f64 = 1e-10;

/// How a friction step's matrix (3.42) differs from the previous step's: S_ℓ − S_{ℓ−1} has
/// rank at most 2 per direction added or removed plus d − 1 per changed slip block, the cost
/// of an exact low-rank update of the previous factorisation (summary.json
/// `newton.history[].change`; docs/numbers.md, "Tresca and the reuse of factorisations").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct RowChange {
    /// Prescribed directions (normal and stick rows) added or removed, over all nodes.
    pub directions: usize,
    /// Slip blocks Σ τ_i L̃_ij τ_jᵀ (3.39) added, removed or changed beyond
    /// [`SLIP_BLOCK_ROUNDOFF`] of the node's stiffness.
    pub slip_blocks: usize,
    /// Slip blocks that changed by round-off only.
    pub slip_blocks_roundoff: usize,
}

/// This rank's slip blocks by first local row, with the node's stiffness (mean diagonal of its
/// rows of A): what [`slip_block_changes`] compares.
type ScaledSprings = HashMap<usize, ([[f64; 3]; 3], f64)>;

/// Slip blocks of this rank that differ between two systems: (beyond round-off, round-off
/// only); a block present in one system only counts as beyond round-off unless all of its
/// entries are within round-off of 0.
fn slip_block_changes(old: &ScaledSprings, new: &ScaledSprings) -> (usize, usize) {
    let zero = [[0.0; 3]; 3];
    let (mut real, mut roundoff) = (0, 0);
    let mut seen = |k: &usize, a: &[[f64; 3]; 3], scale: f64, other: &ScaledSprings| {
        let b = other.get(k).map_or(&zero, |(m, _)| m);
        let d = (0..3)
            .flat_map(|i| (0..3).map(move |j| (a[i][j] - b[i][j]).abs()))
            .fold(0.0, f64::max);
        if d > SLIP_BLOCK_ROUNDOFF * scale {
            real += 1;
        } else if d > 0.0 {
            roundoff += 1;
        }
    };
    for (k, (a, scale)) in new {
        seen(k, a, *scale, old);
    }
    for (k, (a, scale)) in old {
        if !new.contains_key(k) {
            seen(k, a, *scale, new);
        }
    }
    (real, roundoff)
}

/// (rows of A, constraint, first local row) of every node this rank rewrites: the contact
/// nodes `set` prescribes (rows of inactive frictionless nodes stay as in A (3.29)) and the
/// owned pinned nodes. `rows` = (the contact nodes' rows, the pinned nodes' rows, first
/// global row of this rank).
fn rewrites<'r>(
    rows: (&'r [NodeRows], &'r [(usize, NodeRows)], usize),
    layout: &Layout,
    b: &ContactBoundary,
    set: &ActiveSet,
    cmap: &ConstraintMap,
    dim: usize,
) -> Vec<Rewrite<'r>> {
    let (contact_rows, pin_rows, row_lo) = rows;
    let mut writes = Vec::new();
    for (i, (k, r)) in b.nodes.iter().zip(contact_rows).enumerate() {
        let Some(p) = set.prescribed(b, i, dim) else {
            continue;
        };
        let mut me = cmap
            .get(layout.node_global[k.node])
            .expect("gathered")
            .clone();
        if let Some(row) = &p.slip {
            me.add_slip_row(&k.frame, row, dim);
        }
        writes.push((r, me, k.local_row));
    }
    for (v, r) in pin_rows {
        let me = cmap.get(*v).expect("pins are in the map").clone();
        writes.push((r, me, v * dim - row_lo));
    }
    writes
}

/// The rows `writes` of the reduced system (3.29) applied symmetrically
/// ([`write_symmetric_constraint`]): into `s` when given (then assembled), and into `rhs`
/// (whose other rows stay; the neighbours' corrections added in rank order: repeatable runs), with f
/// from `f_local` (this rank's rows) or f = 0. Collective.
fn write_rows(
    mut s: Option<&mut Matrix>,
    rhs: &mut Vector,
    (writes, f_local): (&[Rewrite], Option<&[f64]>),
    cmap: &ConstraintMap,
    dim: usize,
    buf: &mut Vec<f64>,
) -> petsc::Result<()> {
    let zero = [0.0; 3];
    let mut rhs_add: Vec<(PInt, f64)> = Vec::new();
    let mut rhs_updates: Vec<(usize, f64)> = Vec::new();
    for (r, me, lr) in writes {
        let fk = f_local.map_or(&zero[..dim], |f| &f[*lr..*lr + dim]);
        let rk = write_symmetric_constraint(
            s.as_deref_mut(),
            r,
            me,
            fk,
            dim,
            |j| cmap.get(j),
            &mut rhs_add,
            buf,
        )?;
        for (a, v) in rk.iter().enumerate().take(dim) {
            rhs_updates.push((lr + a, *v));
        }
    }
    let (idx, vals): (Vec<PInt>, Vec<f64>) = rhs_add.into_iter().unzip();
    crate::par::add_in_rank_order(rhs, &idx, &vals)?; // deterministic order: repeatable runs
    rhs.assemble()?;
    if let Some(s) = s {
        s.assemble()?;
    }
    rhs.write(|x| {
        for &(i, v) in &rhs_updates {
            x[i] = v;
        }
    })
}

/// The matrix GAMG is built from on the iterative preset with Coulomb's (F7) rows: S with
/// the slip nodes' rows P_k A_kj P_j (Tresca's form, symmetric up to the slip springs)
/// instead of (P_k + E) A_kj P_j. S differs from it by one row per slip node (rank ≤ |slip|),
/// which GMRES absorbs; measured on 2 ranks (GMRES iterations in all, with the Gram–Schmidt
/// refinement of the preset): the 3D block held and pushed into a sphere at 112 890 unknowns
/// 461 against 518 with GAMG built on S itself, the floating ball with a tangential traction
/// (12 129) 1 044 against 1 305; peak memory 379 against 350 MB per rank. Collective.
fn write_unmixed(
    made: &mut Option<(Matrix, Vector)>,
    (s, rhs): (&Matrix, &Vector),
    sys: &System,
    (writes, cmap): (&[Rewrite], &ConstraintMap),
    (dim, buf): (usize, &mut Vec<f64>),
) -> petsc::Result<()> {
    if made.is_none() {
        let mut p = s.duplicate()?;
        p.copy_near_null_space_from(s)?;
        *made = Some((p, rhs.duplicate()?));
    }
    let (p, scratch) = made.as_mut().expect("made above");
    p.copy_values_from(&sys.a)?;
    let plain: Vec<Rewrite> = writes
        .iter()
        .map(|(r, me, lr)| {
            let mut me = me.clone();
            me.row_mix = None;
            (*r, me, *lr)
        })
        .collect();
    write_rows(Some(p), scratch, (&plain, None), cmap, dim, buf)
}

fn matmul3(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3], dim: usize) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for i in 0..dim {
        for j in 0..dim {
            c[i][j] = (0..dim).map(|l| a[i][l] * b[l][j]).sum();
        }
    }
    c
}

/// The (3.29) constraints of one node, applied symmetrically. The node's rows become
/// P_k A_kj P_j (plus s_k Σ c cᵀ on its own block) and its right-hand side
/// P_k (f_k − Σ_j A_kj ū_j) + s_k ū_k; in every unconstrained neighbour row i the block A_ik
/// becomes A_ik P_k and A_ik ū_k moves to the right-hand side. This is (3.29) with the known
/// normal displacement eliminated from the columns too: the same solution, on A's pattern,
/// and symmetric (positive definite without friction), so CG/AMG and Cholesky apply.
/// `constrained(j)` gives the constraint of global node j, if any. Returns the node's
/// right-hand side; the neighbour corrections are appended to `rhs_add` (global row, value).
/// With `s` = None only the right-hand side is formed (S unchanged).
#[allow(clippy::too_many_arguments)]
pub fn write_symmetric_constraint<'c>(
    mut s: Option<&mut Matrix>,
    rows: &NodeRows,
    me: &NodeConstraint,
    f_k: &[f64],
    dim: usize,
    constrained: impl Fn(usize) -> Option<&'c NodeConstraint>,
    rhs_add: &mut Vec<(PInt, f64)>,
    buf: &mut Vec<f64>,
) -> petsc::Result<[f64; 3]> {
    let n = rows.cols.len();
    let node_k = rows.row / dim;
    let pk = me.projector(dim);
    // The left factor of the node's rows: P_k, plus E for a Coulomb slip row (F7).
    let left = match me.row_mix {
        None => pk,
        Some(e) => {
            let mut l = pk;
            for a in 0..dim {
                for b in 0..dim {
                    l[a][b] += e[a][b];
                }
            }
            l
        }
    };
    let uk = me.known();
    let sk = (0..dim).map(|j| rows.diag(j)).sum::<f64>() / dim as f64;
    let mut new_rows = vec![vec![0.0; n]; dim];
    let mut t = [0.0; 3]; // Σ_j A_kj ū_j
    let mut mirror_cols: [PInt; 3] = [0; 3];
    for c in 0..dim {
        mirror_cols[c] = (node_k * dim + c) as PInt;
    }
    let mut blk = [[0.0; 3]; 3];
    let mut m = 0;
    while m < n {
        let j = rows.cols[m] as usize / dim;
        for a in 0..dim {
            for b in 0..dim {
                blk[a][b] = rows.vals[a][m + b];
            }
        }
        let cj = if j == node_k {
            Some(me)
        } else {
            constrained(j)
        };
        let pj = match cj {
            Some(c) => c.projector(dim),
            None => NodeConstraint::default().projector(dim),
        };
        if let Some(c) = cj {
            let uj = c.known();
            for a in 0..dim {
                t[a] += (0..dim).map(|b| blk[a][b] * uj[b]).sum::<f64>();
            }
        }
        let mut nb = matmul3(&left, &matmul3(&blk, &pj, dim), dim);
        if j == node_k {
            for (cvec, _) in &me.dirs {
                for a in 0..dim {
                    for b in 0..dim {
                        nb[a][b] += sk * cvec[a] * cvec[b];
                    }
                }
            }
            for a in 0..dim {
                for b in 0..dim {
                    nb[a][b] += me.spring[a][b];
                }
            }
        }
        for a in 0..dim {
            for b in 0..dim {
                new_rows[a][m + b] = nb[a][b];
            }
        }
        if cj.is_none() {
            // Mirror block in the unconstrained neighbour's rows: A_jk P_k = (A_kj)ᵀ P_k.
            let mut mb = [[0.0; 3]; 3];
            for a in 0..dim {
                for b in 0..dim {
                    mb[a][b] = (0..dim).map(|l| blk[l][a] * pk[l][b]).sum();
                }
            }
            buf.clear();
            for row in mb.iter().take(dim) {
                buf.extend_from_slice(&row[..dim]);
            }
            let mrows: Vec<PInt> = (0..dim).map(|c| (j * dim + c) as PInt).collect();
            if let Some(s) = s.as_mut() {
                s.insert_values(&mrows, &mirror_cols[..dim], buf)?;
            }
            // rhs_j −= A_jk ū_k
            for a in 0..dim {
                let v: f64 = (0..dim).map(|l| blk[l][a] * uk[l]).sum();
                if v != 0.0 {
                    rhs_add.push(((j * dim + a) as PInt, -v));
                }
            }
        }
        m += dim;
    }
    if let Some(s) = s.as_mut() {
        for (a, row) in new_rows.iter().enumerate() {
            s.insert_values(&[(rows.row + a) as PInt], &rows.cols, row)?;
        }
    }
    let mut rhs = [0.0; 3];
    let mut ft = [0.0; 3];
    for a in 0..dim {
        ft[a] = f_k[a] - t[a];
    }
    for a in 0..dim {
        rhs[a] = (0..dim).map(|b| left[a][b] * ft[b]).sum::<f64>() + sk * uk[a] + me.spring_rhs[a];
    }
    Ok(rhs)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(l: f64) -> [[f64; 3]; 3] {
        let mut m = [[0.0; 3]; 3];
        m[0][0] = l;
        m[0][1] = 0.5 * l;
        m
    }

    #[test]
    fn slip_blocks_split_into_real_and_round_off_changes() {
        let scale = 2.0;
        let old: ScaledSprings = [
            (0, (block(1.0), scale)),   // unchanged
            (2, (block(1.0), scale)),   // changes by 1e-3: real
            (4, (block(3e-14), scale)), // round-off, then gone: round-off
            (6, (block(1.0), scale)),   // removed: real
            (8, (block(0.25), scale)),  // changes by 1e-13: round-off
            (10, (block(1e-9), scale)), // at 5e-10 of the stiffness: real
        ]
        .into_iter()
        .collect();
        let new: ScaledSprings = [
            (0, (block(1.0), scale)),
            (2, (block(1.0 + 1e-3), scale)),
            (8, (block(0.25 + 1e-13), scale)),
            (10, (block(0.0), scale)),
            (12, (block(4e-12), scale)), // appears at round-off
            (14, (block(0.1), scale)),   // appears: real
        ]
        .into_iter()
        .collect();
        assert_eq!(slip_block_changes(&old, &new), (4, 3));
        assert_eq!(slip_block_changes(&new, &old), (4, 3));
        assert_eq!(slip_block_changes(&new, &new), (0, 0));
    }

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
