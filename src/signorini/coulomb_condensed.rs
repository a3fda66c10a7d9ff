//! Coulomb's generalised Newton (docs/friction.md (F1)–(F6)) on the contact unknowns alone
//! (direct preset): the frictionless condensed solve with every dof of its candidates in the
//! Schur complement (condensed.rs, `per` = d) leaves the compliance C = Qᵀ K_p⁻¹ Q of the
//! candidates' dofs in their node frames (normal first) and d₀ = Qᵀ K_p⁻¹ f there. With λ the
//! candidates' multipliers (3.28), α the amplitudes of the rigid modes Dirichlet data leave free
//! (K_p pins them) and G their parts at the candidates, u = d₀ − C λ + G α, and every Newton
//! step of the plain path is, on the candidates, one dense system in the active nodes' λ and α
//! (with the balance Gᵀ λ = φ, the load in those modes):
//!
//! ```text
//!   k ∈ A_n:            u_n,k = −g_k
//!   stick (S3):         u_τ,k = u_τ^ref                                          (3.34a)
//!   slip (S4):          −λ_τ,k + L̃ (u_τ,k − u_τ^ref) − q λ_n,k = r̃      (F6), u_n,k + g_k = 0
//!   k ∉ A_n (S2):       λ_k = 0
//! ```
//!
//! (or the same step in the primal form on S = C⁻¹ itself where that has fewer unknowns,
//! [`Stiff`]) with the rows of `contact::coulomb_row_dyn` and the set update (3.23)/(F5) of the
//! plain path (`ActiveSet::update`, its stick band included), stopped by the same rule, first on
//! coarse subsets of the candidates (nested iteration, `Dense::run_nested`). Nodes beyond
//! the candidates stay inactive. At the end one expansion solve gives u = K_p⁻¹ (f − Q λ) +
//! R z α, and the plain path's recovery (3.28) and set update on every contact node check it:
//! no state may change, the residual (F3) must pass the plain path's tolerance (or, where the
//! dense steps stalled, the KKT and friction certificates hold to round-off) and the set must
//! hold every free mode. A check that fails hands the expanded iterate to the plain path as
//! its start.
//!
//! Force control (a held body): each approach δ_j is one more column of G (the relative
//! displacement of the pair's candidates, −δ_j (n·e_j, τ·e_j)) and one more balance row
//! (the pair's force along e_j equals |F_j|); the check reads the obstacles at the δ's found.
//!
//! Collectives: one broadcast (the dense result), the expansion solve, one MatMult, the
//! update's reduction and the certificates' all-gather.

use super::active_set::{
    threshold_scale, threshold_scale_local, ActiveSet, Iterate, Law, StepTotals, FIXED_POINT_SLACK,
};
use super::boundary::{ContactBoundary, ContactNode, NodeResult};
use super::condensed::{fall_back, is_zero, record_steps, CoarseLevel, Kept};
use super::dense::{coarsen, guarded};
use super::force::{self, ForceControl};
use super::plain_path::iteration::{
    COULOMB_RESIDUAL_STALL, COULOMB_RESIDUAL_TOL, COULOMB_RESIDUAL_ZERO,
};
use super::plain_path::{
    add_motion, stalled, ContactProblem, NewtonResult, NewtonSettings, StepInfo, WarmStart,
};
use super::rigid::FreeModes;
use super::step_system::ReducedSystem;
use crate::contact::{normal_active, CoulombRow, Frame};
use crate::error::RunError;
use crate::geom::dot;
use crate::par::Ctx;
use crate::petsc::lapack::DenseLu;
use crate::say;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use std::time::Instant;

/// What the condensed Coulomb solve returns.
pub enum CoulombCondensed {
    /// The checked solution (the dense steps are its history).
    Solved(Box<NewtonResult>, CoulombCondensedSummary),
    /// A start for the plain path: every contact node's record and this rank's rows of u; and
    /// where only nodes beyond the candidates change state on the expanded u, those nodes
    /// (c_h's global order; a new pass may take them as candidates).
    Start(
        Box<NewtonResult>,
        Vec<f64>,
        CoulombCondensedSummary,
        Vec<usize>,
    ),
    /// Nothing to start from (the frictionless start then applies).
    Fallback(CoulombCondensedSummary),
}

/// summary.json's `newton.condensed.coulomb`: what the dense Coulomb iteration did.
#[derive(Debug, Clone, Serialize)]
pub struct CoulombCondensedSummary {
    /// "condensed": the expanded iterate passed the check; "start": it became the plain
    /// path's start (`reason` says why); "fallback": the dense iteration gave up (`reason`).
    pub outcome: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// Steps of the dense generalised Newton.
    pub steps: usize,
    /// Of these, the steps solved in the primal form (on S itself; the others on C = S⁻¹).
    pub primal_steps: usize,
    pub dense_seconds: f64,
    /// The expansion solve, (3.28) and the check on every contact node [s].
    pub expansion_seconds: f64,
    /// The nested start (from the frictionless solution): per coarse level, coarsest first,
    /// its candidates and dense steps (not in `steps`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub coarse_levels: Vec<CoarseLevel>,
    /// The dense step whose settled slip rows left its system singular, from which the (F5)
    /// rows ran (docs/friction.md, "A singular dense step"); absent where none did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub f5_from: Option<usize>,
    /// The nested start's coarse levels on which the same happened.
    #[serde(skip_serializing_if = "is_zero")]
    pub f5_coarse_levels: usize,
}

/// The residual ‖R‖₂ (F3) of the expanded iterate accepted, relative to ‖λ‖₂ (the plain path:
/// `COULOMB_RESIDUAL_TOL` = 1e-9): the dense steps stall at the round-off of the compliance
/// C = S⁻¹ and of the dense solves, measured at 2e-9 / 5e-9 (the held / floating Hertz disk,
/// 171 602 unknowns) and 1.5e-8 (held, 344 620) of ‖λ‖₂; accepted at 2e-9 and 5e-9 the
/// friction certificate ends at 6e-10 and 5e-9 of its scale, within the 1e-8 asked of every
/// friction solve. Above it a stalled iteration is accepted where the certificates hold to
/// [`CERTIFICATE_ROUND_OFF`] (the Hertz disk at 344 620 unknowns, held and floating: u within
/// 2.8e-12 and 2.4e-11 of the plain path's); else one plain step from the expanded iterate
/// confirms.
const DENSE_RESIDUAL_TOL: f64 = 1e-8;

/// The certificates' worst violation, relative to the problem's scales, that a stalled dense
/// iterate may have to be accepted (the final check's warning level).
const CERTIFICATE_ROUND_OFF: f64 = 1e-8;

/// One dense step's record: step, |A_n|, changed, residual, seconds.
type DenseStep = (usize, usize, usize, f64, f64);

/// The dense generalised Newton on rank 0 and how it ended.
struct DenseCoulomb {
    /// λ of every candidate, d per node in C's order (node frame, normal first).
    lambda: Vec<f64>,
    /// The free modes' amplitudes α (u = w + R z α).
    alpha: Vec<f64>,
    /// Per candidate: in A_n, slipping.
    active: Vec<bool>,
    slip: Vec<bool>,
    /// Per step: step, |A_n|, changed, residual, seconds.
    steps: Vec<DenseStep>,
    /// `Err`: why the iteration gave up.
    end: Result<(), String>,
    /// It stopped by the stall rule (`plain_path::stalled`: the residual at the round-off of the
    /// dense compliance, above COULOMB_RESIDUAL_TOL).
    stalled: bool,
    /// The nested start's coarse levels, coarsest first: (nodes, dense steps).
    coarse: Vec<(usize, usize)>,
    /// Rank 0, where the last step was in the primal form: its u − G α at the candidates' dofs,
    /// the Schur variables' part of the expansion (else empty: d₀ − C λ). Not broadcast.
    x_s: Vec<f64>,
    /// Steps in the primal form ([`Stiff`]).
    primal_steps: usize,
    /// The step whose settled slip rows left the system singular, from which the (F5) rows
    /// ran (0: none).
    f5_from: usize,
    /// The nested start's coarse levels on which that happened.
    f5_coarse: usize,
}

impl DenseCoulomb {
    fn failed(n: usize, dim: usize, mz: usize, why: String) -> DenseCoulomb {
        DenseCoulomb {
            lambda: vec![0.0; n * dim],
            alpha: vec![0.0; mz],
            active: vec![false; n],
            slip: vec![false; n],
            steps: Vec::new(),
            end: Err(why),
            stalled: false,
            coarse: Vec::new(),
            x_s: Vec::new(),
            primal_steps: 0,
            f5_from: 0,
            f5_coarse: 0,
        }
    }

    /// All fields as one f64 vector (the broadcast); the reason travels as UTF-8 bytes.
    fn pack(&self) -> Vec<f64> {
        let mut v = self.lambda.clone();
        v.extend_from_slice(&self.alpha);
        v.extend(self.active.iter().map(|&a| a as u8 as f64));
        v.extend(self.slip.iter().map(|&a| a as u8 as f64));
        v.push(self.steps.len() as f64);
        for s in &self.steps {
            v.extend([s.0 as f64, s.1 as f64, s.2 as f64, s.3, s.4]);
        }
        let why = self.end.as_ref().err().map_or(&[][..], |w| w.as_bytes());
        v.push(if self.end.is_ok() { 1.0 } else { 0.0 });
        v.push(if self.stalled { 1.0 } else { 0.0 });
        v.push(self.primal_steps as f64);
        v.push(self.f5_from as f64);
        v.push(self.f5_coarse as f64);
        v.push(self.coarse.len() as f64);
        for &(nodes, steps) in &self.coarse {
            v.extend([nodes as f64, steps as f64]);
        }
        v.push(why.len() as f64);
        v.extend(why.iter().map(|&b| b as f64));
        v
    }

    fn unpack(v: &[f64], n: usize, dim: usize, mz: usize) -> DenseCoulomb {
        let lambda = v[..n * dim].to_vec();
        let alpha = v[n * dim..n * dim + mz].to_vec();
        let nl = n * dim + mz;
        let active = v[nl..nl + n].iter().map(|&x| x != 0.0).collect();
        let slip = v[nl + n..nl + 2 * n].iter().map(|&x| x != 0.0).collect();
        let mut at = nl + 2 * n;
        let ns = v[at] as usize;
        at += 1;
        let steps = (0..ns)
            .map(|i| {
                let s = &v[at + 5 * i..at + 5 * i + 5];
                (s[0] as usize, s[1] as usize, s[2] as usize, s[3], s[4])
            })
            .collect();
        at += 5 * ns;
        let ok = v[at] != 0.0;
        let stalled = v[at + 1] != 0.0;
        let primal_steps = v[at + 2] as usize;
        let f5_from = v[at + 3] as usize;
        let f5_coarse = v[at + 4] as usize;
        let nc = v[at + 5] as usize;
        let coarse = (0..nc)
            .map(|i| (v[at + 6 + 2 * i] as usize, v[at + 7 + 2 * i] as usize))
            .collect();
        at += 6 + 2 * nc;
        let len = v[at] as usize;
        let bytes: Vec<u8> = v[at + 1..at + 1 + len].iter().map(|&b| b as u8).collect();
        let end = if ok {
            Ok(())
        } else {
            Err(String::from_utf8_lossy(&bytes).into_owned())
        };
        DenseCoulomb {
            lambda,
            alpha,
            active,
            slip,
            steps,
            end,
            stalled,
            coarse,
            x_s: Vec::new(),
            primal_steps,
            f5_from,
            f5_coarse,
        }
    }
}

/// The candidates as contact nodes of their own boundary (rank 0): frames, gaps, references.
fn candidate_boundary(kept: &Kept, b: &ContactBoundary, dim: usize) -> ContactBoundary {
    let nodes = kept
        .comp
        .list
        .iter()
        .map(|&i| {
            let n = kept.cand.n(i);
            ContactNode {
                node: 0,
                pair: kept.cand.pair(i),
                mu: kept.cand.mu(i),
                tag: kept.cand.tag(i),
                row: 0,
                local_row: 0,
                x: kept.cand.x(i),
                frame: Frame::new(n, dim).expect("obstacle normals are unit vectors"),
                gap: kept.cand.gap(i),
                weight: 0.0,
                bound: 0.0,
                u_t_ref: kept.cand.u_t_ref(i),
            }
        })
        .collect();
    ContactBoundary {
        nodes,
        n_global: kept.comp.list.len(),
        offset: 0,
        on_contact_boundary: Vec::new(),
        excluded_dirichlet: 0,
        obstacles: b.obstacles.clone(),
        keys: b.keys.clone(),
    }
}

/// G: the free modes' parts at the candidates, d rows per node (its frame: n, τ₁, τ₂), one
/// column per free mode, then (force control) one per force-controlled pair j: its obstacle
/// moved by δ_j e_j shifts the candidates' relative displacement by −δ_j (n·e_j, τ₁·e_j,
/// τ₂·e_j) on its nodes (gaps g0 − δ_j n·e_j, references u_τ^ref + δ_j τ·e_j, as
/// `force::Approach::place`), and its balance row is the pair's force along e_j (rank 0).
fn mode_parts(
    free: &FreeModes,
    force: &[ForceControl],
    cb: &ContactBoundary,
    dim: usize,
) -> DMatrix<f64> {
    let mz = free.dirichlet_free().ncols();
    let mut g = DMatrix::zeros(cb.nodes.len() * dim, mz + force.len());
    for (q, k) in cb.nodes.iter().enumerate() {
        let dirs = [k.frame.n, k.frame.t[0], k.frame.t[1]];
        for (a, dir) in dirs.iter().enumerate().take(dim) {
            let parts = free.normal_parts(&k.x, dir);
            for cz in 0..mz {
                g[(q * dim + a, cz)] = parts[cz];
            }
            for (j, fc) in force.iter().enumerate() {
                if k.pair == fc.pair {
                    g[(q * dim + a, mz + j)] = -dot(*dir, fc.direction());
                }
            }
        }
    }
    g
}

/// One step's dense system (module note), its rows equilibrated.
struct System {
    /// The rows as columns (row ri of the system is column ri).
    a: DMatrix<f64>,
    rhs: DVector<f64>,
    /// The first unknowns: the active nodes' λ (the primal form: the free displacements' dofs);
    /// α follow.
    cols: Vec<Unknown>,
    /// The primal form ([`Stiff`]): u at every candidate dof, NaN where it is an unknown;
    /// `None`: the dual form.
    known: Option<Vec<f64>>,
}

/// S itself next to C = S⁻¹ (rank 0; condensed.rs `Compliance::stiffness`): λ = r − S (u − G α)
/// on the candidates' dofs, with S G and Gᵀ S G. A step's system in the primal form has the
/// displacements the set leaves free as unknowns — every dof of an inactive candidate, the
/// tangential dofs of a slipping one — with the rows λ = 0 and the slip rows (F6) in λ
/// (module note), and the balance Gᵀ λ = φ: where the zone fills the candidates that is far
/// fewer unknowns than the dual form's λ of every active node.
struct Stiff<'a> {
    s: &'a DMatrix<f64>,
    r: &'a [f64],
    sg: DMatrix<f64>,
    gsg: DMatrix<f64>,
}

/// One λ unknown of the dense system: λ at the candidates' dof `dof`, and, where a 2D slip row
/// ties the node's λ_τ to its λ_n (`tied`: λ_τ's dof and factor), λ_τ with it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Unknown {
    dof: usize,
    tied: Option<(usize, f64)>,
}

impl Unknown {
    /// Σ over the λ dofs this unknown stands for of its factor times `at(dof)`.
    fn of(&self, at: impl Fn(usize) -> f64) -> f64 {
        at(self.dof) + self.tied.map_or(0.0, |(t, f)| f * at(t))
    }
}

/// The tie λ_τ = −q λ_n of a 2D slip row without spring and right-hand side (the settled row of
/// `active_set::settled`, −λ_τ' − q λ_n' = 0): λ_τ's dof and −q. Such a node's λ_τ is no unknown
/// of the dense system, and its tangential row no row (exact).
fn tie(row: CoulombRow<2>, dof_n: usize, d: usize) -> Option<(usize, f64)> {
    match row {
        CoulombRow::Slip { l, q, r }
            if d == 2 && l == [[0.0; 2]; 2] && r == [0.0; 2] && q[0] != 0.0 =>
        {
            Some((dof_n + 1, -q[0]))
        }
        _ => None,
    }
}

/// Each row (a column of `a`) and its right-hand side scaled to max |row| = 1: the rows are in
/// displacement (normal, stick) and force (slip, balance) units, the columns in force (λ) and
/// displacement (α) units (measured on the Hertz disk at 171 602 unknowns: the residual floor
/// of the dense steps 10 × lower).
fn equilibrate(a: &mut DMatrix<f64>, rhs: &mut DVector<f64>) {
    for (mut row, b) in a.column_iter_mut().zip(rhs.iter_mut()) {
        let s = row.iter().fold(0.0_f64, |x, v| x.max(v.abs()));
        if s > 0.0 {
            row.scale_mut(1.0 / s);
            *b /= s;
        }
    }
}

/// max |R (M x − b)| of a system at x, its rows R-equilibrated as built.
fn residual_at(sys: &System, x: &[f64]) -> f64 {
    sys.a
        .column_iter()
        .zip(sys.rhs.iter())
        .map(|(row, b)| (row.iter().zip(x).map(|(r, xi)| r * xi).sum::<f64>() - b).abs())
        .fold(0.0, f64::max)
}

/// The system's solution by LU (LAPACK), its columns equilibrated. `None`: singular (e.g. a
/// free mode that the set does not hold).
fn solve_system(sys: &System) -> Option<Vec<f64>> {
    let n = sys.rhs.len();
    let mut cmax = vec![0.0_f64; n];
    for row in sys.a.column_iter() {
        for (c, v) in cmax.iter_mut().zip(row.iter()) {
            *c = c.max(v.abs());
        }
    }
    let cs: Vec<f64> = cmax
        .iter()
        .map(|&s| if s > 0.0 { 1.0 / s } else { 1.0 })
        .collect();
    // the system column-major (the transpose of the rows-as-columns), columns scaled
    let mut at = sys.a.transpose();
    for (mut col, c) in at.column_iter_mut().zip(&cs) {
        col.scale_mut(*c);
    }
    let mut x = DenseLu::factor_owned(n, at.data.into())?.solve(&sys.rhs);
    for (xj, cj) in x.iter_mut().zip(&cs) {
        *xj *= cj;
    }
    if x.iter().any(|v| !v.is_finite()) {
        return None;
    }
    Some(x.as_slice().to_vec())
}

/// The system `next` holds at `x` to the round-off of the solve that gave x (`own`: its
/// residual in its own system, [`residual_at`]): within FIXED_POINT_SLACK × max(own, ε |b|∞).
/// Measured on the Hertz disks of 42 k–345 k unknowns: at a fixed point the next residual
/// equalled `own` (1e-18–3e-16, |b|∞ = 1.5e-2), elsewhere it was 1.5e-7–1.3e-5. Pure.
fn fixed_point(next: &System, x: &[f64], own: f64) -> bool {
    let b = next.rhs.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    residual_at(next, x) <= FIXED_POINT_SLACK * own.max(f64::EPSILON * b)
}

/// The generalised Newton of docs/friction.md on the candidates' dense system (module note).
struct Dense<'a> {
    dim: usize,
    cmat: &'a DMatrix<f64>,
    /// Cᵀ (C's rows as contiguous columns, for the rows of the dense system).
    cmat_t: &'a DMatrix<f64>,
    d0: &'a [f64],
    /// The free modes' parts at the candidates (d rows per node, frame components; mz columns)
    /// and the load in them, φ = zᵀ Rᵀ f: u = d₀ − C λ + G α, Gᵀ λ = φ.
    g: &'a DMatrix<f64>,
    phi: &'a [f64],
    cb: &'a ContactBoundary,
    law: Law,
    c: f64,
    max_steps: usize,
    tol_u: f64,
    /// The rows of settled slip (`ActiveSet::update_with`; production: true).
    settle: bool,
    /// S itself: each step in the form with fewer unknowns (`None`: the dual form always).
    stiff: Option<&'a Stiff<'a>>,
}

impl Dense<'_> {
    /// The start from the frictionless solution (`active`, λ_n per candidate, u = d₀ − C λ_n):
    /// every active node sticks (Δu_τ = 0, λ_τ = 0), so the first step gives the all-stick λ_τ
    /// and (F5) lets slip where |λ_τ| exceeds μ(−λ_n). Returns the records and u (d per node).
    fn frictionless_start(&self, active: &[bool], lambda_n: &[f64]) -> (Vec<NodeResult>, Vec<f64>) {
        let (d, n) = (self.dim, self.cb.nodes.len());
        let mut u_prev = self.d0.to_vec();
        for (q, &l) in lambda_n.iter().enumerate() {
            if l != 0.0 {
                for (ui, ci) in u_prev.iter_mut().zip(self.cmat.column(q * d).iter()) {
                    *ui -= ci * l;
                }
            }
        }
        // u_n = −g on the frictionless set (its rigid motion G α is not in u_prev), never a
        // penetration off it: b of (F1) is μ(−λ_n) on the set and 0 elsewhere
        let start: Vec<NodeResult> = (0..n)
            .map(|q| NodeResult {
                u_n: if active[q] {
                    -self.cb.nodes[q].gap
                } else {
                    u_prev[q * d].max(-self.cb.nodes[q].gap)
                },
                u_t: self.cb.nodes[q].u_t_ref,
                lambda_n: lambda_n[q],
                active: active[q],
                ..NodeResult::default()
            })
            .collect();
        (start, u_prev)
    }

    /// The iteration from `start` (per candidate; `u_prev`: its u, d per node).
    fn run(&self, start: &[NodeResult], mut u_prev: Vec<f64>) -> DenseCoulomb {
        let (d, n) = (self.dim, self.cb.nodes.len());
        let (law, c) = (self.law, self.c);
        let scale = threshold_scale_local(self.cb, start, law, c);
        let mut set = ActiveSet::warm(self.cb, start, law, c, scale, d);
        let mut it = Iterate::new(n, 0, true);
        let mut last_still = None;
        let mut steps = Vec::new();
        let mut sys = self.system(&set);
        let mut primal = 0;
        // the set the last iterate was solved on, for a step whose settled rows leave the
        // system singular (below); from then on the (F5) rows alone, as the plain path has them
        let mut before: Option<ActiveSet> = None;
        let mut settle = self.settle;
        let mut f5_from = 0;
        for step in 1..=self.max_steps {
            let t = Instant::now();
            let mut solved = sys.and_then(|sk| Some((solve_system(&sk)?, sk)));
            if solved.is_none() {
                // Settled slip rows (λ_τ = μ(−λ_n) ν, docs/friction.md) give a slipping
                // node's tangential displacement no stiffness of its own: where every active
                // node of a floating body slips, its tangential rigid motion is free and the
                // system singular (an iterate of the way, e.g. a rolling disk whose one sticking
                // node slips for a step). The (F5) rows keep their spring L̃: the step again on
                // them, and the iteration on them to its end.
                // (`it` holds the last iterate until this step's records)
                let unsettled = before.take().map(|b| {
                    let scale = threshold_scale_local(self.cb, &it.nodes, law, c);
                    b.update_with(&it, self.cb, law, c, scale, d, false).next
                });
                if let Some(alt) = unsettled.filter(|alt| *alt != set) {
                    settle = false;
                    f5_from = step;
                    set = alt;
                    solved = self
                        .system(&set)
                        .and_then(|sk| Some((solve_system(&sk)?, sk)));
                }
            }
            primal += solved.as_ref().is_some_and(|(_, s)| s.known.is_some()) as usize;
            let Some((x, sys_k)) = solved else {
                let why = format!("the dense Coulomb system of step {step} is singular");
                return self.end(
                    &set,
                    (vec![0.0; n * d], Vec::new()),
                    (steps, primal),
                    Err(why),
                );
            };
            let (lam, u, alpha) = self.unknowns(&sys_k, &x);
            self.records(&set, &lam, &u, &mut it.nodes);
            let scale = threshold_scale_local(self.cb, &it.nodes, law, c);
            let up = set.update_with(&it, self.cb, law, c, scale, d, settle); // (3.23) / (F5)
            let (residual, lambda_norm) = (up.residual2.sqrt(), up.lambda2.sqrt());
            let du: f64 = u.iter().zip(&u_prev).map(|(a, b)| (a - b).powi(2)).sum();
            let uu: f64 = u.iter().map(|a| a * a).sum();
            let du_rel = if uu > 0.0 { (du / uu).sqrt() } else { 0.0 };
            let n_active = set.local_active();
            steps.push((
                step,
                n_active,
                up.changed,
                residual,
                t.elapsed().as_secs_f64(),
            ));
            // The stall rule without |Δu| < tol_u: on a floating body the dense u carries the
            // round-off of α, |Δu|/|u| stays above tol_u while the residual sits at its
            // round-off (measured: the floating Hertz disk at 171 602 unknowns, |C| ~ 3e-11 of
            // |λ| ~ 8e-4 for 90 steps); the expanded iterate is checked on every node anyway.
            let unchanged = up.changed == 0;
            let stall = stalled(unchanged, last_still, residual, lambda_norm);
            last_still = unchanged.then_some(residual);
            let zero = residual <= COULOMB_RESIDUAL_ZERO * lambda_norm;
            let small = residual <= COULOMB_RESIDUAL_TOL * lambda_norm;
            if unchanged && (zero || stall || (du_rel < self.tol_u && small)) {
                let x_s = self.primal_x_s(&sys_k, &u, &alpha);
                let mut run = self.end(&set, (lam, alpha), (steps, primal), Ok(()));
                run.stalled = residual > COULOMB_RESIDUAL_TOL * lambda_norm;
                run.x_s = x_s;
                run.f5_from = f5_from;
                return run;
            }
            // The next step's system holds at this iterate as well as its own did (states
            // unchanged, and the rows that changed hold at it to round-off): the next step would
            // return the same iterate, so it is not taken
            let next = self.system(&up.next);
            let fixed = unchanged
                && residual <= COULOMB_RESIDUAL_STALL * lambda_norm
                && next.as_ref().is_some_and(|sn| {
                    sn.cols == sys_k.cols
                        && sn.known.is_some() == sys_k.known.is_some()
                        && fixed_point(sn, &x, residual_at(&sys_k, &x))
                });
            if fixed {
                let x_s = self.primal_x_s(&sys_k, &u, &alpha);
                let mut run = self.end(&set, (lam, alpha), (steps, primal), Ok(()));
                run.stalled = residual > COULOMB_RESIDUAL_TOL * lambda_norm;
                run.x_s = x_s;
                run.f5_from = f5_from;
                return run;
            }
            let solved_on = std::mem::replace(&mut set, up.next);
            before = settle.then_some(solved_on);
            u_prev = u;
            sys = next;
        }
        let why = format!(
            "the dense Coulomb iteration did not converge in {} steps",
            self.max_steps
        );
        self.end(
            &set,
            (vec![0.0; n * d], Vec::new()),
            (steps, primal),
            Err(why),
        )
    }

    fn end(
        &self,
        set: &ActiveSet,
        (lambda, mut alpha): (Vec<f64>, Vec<f64>),
        (steps, primal_steps): (Vec<DenseStep>, usize),
        end: Result<(), String>,
    ) -> DenseCoulomb {
        let n = self.cb.nodes.len();
        alpha.resize(self.g.ncols(), 0.0);
        DenseCoulomb {
            lambda,
            alpha,
            active: set.normal.clone(),
            slip: (0..n).map(|q| set.slip(q)).collect(),
            steps,
            end,
            stalled: false,
            coarse: Vec::new(),
            x_s: Vec::new(),
            primal_steps,
            f5_from: 0,
            f5_coarse: 0,
        }
    }

    /// Nested iteration (as the frictionless [`super::dense::Dense::run_nested`]; used in 2D):
    /// the dense generalised Newton first on coarse subsets of the candidates (`coarsen`, coarsest
    /// first; each subset's problem holds the contact conditions at its nodes only, with the
    /// exact compliance C between them), each level's solution starting the next finer one
    /// through (3.23) and (F5) evaluated at every candidate (λ = 0 off the subset,
    /// u = d₀ − C λ + G α); then the iteration on all candidates from there. The result's
    /// `steps` are the fine ones, `coarse` (nodes, steps) per level. A coarse level that does
    /// not converge leaves the start as it was. Local.
    fn run_nested(&self, start: &[NodeResult], u_prev: Vec<f64>) -> DenseCoulomb {
        let d = self.dim;
        let x: Vec<[f64; 3]> = self.cb.nodes.iter().map(|k| k.x).collect();
        let gap: Vec<f64> = self.cb.nodes.iter().map(|k| k.gap).collect();
        let (mut start, mut u_prev) = (start.to_vec(), u_prev);
        let mut coarse = Vec::new();
        let mut f5_coarse = 0;
        for idx in coarsen(&x, &gap).iter().rev() {
            let dofs: Vec<usize> = idx
                .iter()
                .flat_map(|&q| (0..d).map(move |a| q * d + a))
                .collect();
            let sub_c =
                DMatrix::from_fn(dofs.len(), dofs.len(), |r, q| self.cmat[(dofs[r], dofs[q])]);
            let sub_ct = sub_c.transpose();
            let sub_g = DMatrix::from_fn(dofs.len(), self.g.ncols(), |r, c| self.g[(dofs[r], c)]);
            let pick = |v: &[f64]| dofs.iter().map(|&i| v[i]).collect::<Vec<f64>>();
            let d0 = pick(self.d0);
            let cb = ContactBoundary {
                nodes: idx.iter().map(|&q| self.cb.nodes[q].clone()).collect(),
                n_global: idx.len(),
                offset: 0,
                on_contact_boundary: Vec::new(),
                excluded_dirichlet: 0,
                obstacles: self.cb.obstacles.clone(),
                keys: self.cb.keys.clone(),
            };
            let sub = Dense {
                cmat: &sub_c,
                cmat_t: &sub_ct,
                d0: &d0,
                g: &sub_g,
                cb: &cb,
                stiff: None,
                ..*self
            };
            let sub_start: Vec<NodeResult> = idx.iter().map(|&q| start[q]).collect();
            let run = sub.run(&sub_start, pick(&u_prev));
            coarse.push((idx.len(), run.steps.len()));
            f5_coarse += usize::from(run.f5_from > 0);
            if run.end.is_err() {
                continue;
            }
            let mut lam = vec![0.0; self.d0.len()];
            for (r, &i) in dofs.iter().enumerate() {
                lam[i] = run.lambda[r];
            }
            let u = self.u_of(&lam, &run.alpha);
            let normal = (0..self.cb.nodes.len())
                .map(|q| normal_active(u[q * d], lam[q * d], self.cb.nodes[q].gap, self.c)) // (3.23)
                .collect();
            let set = ActiveSet {
                normal,
                tangential: None,
                spring_floor: 0.0,
                stick_active: false,
            };
            self.records(&set, &lam, &u, &mut start);
            u_prev = u;
        }
        let mut run = self.run(&start, u_prev);
        run.coarse = coarse;
        run.f5_coarse = f5_coarse;
        run
    }

    /// u = d₀ − C λ + G α at every candidate (d per node).
    fn u_of(&self, lam: &[f64], alpha: &[f64]) -> Vec<f64> {
        let mut u = self.d0.to_vec();
        for (col, &l) in lam.iter().enumerate() {
            if l != 0.0 {
                for (ui, ci) in u.iter_mut().zip(self.cmat.column(col).iter()) {
                    *ui -= ci * l;
                }
            }
        }
        for (cz, &al) in alpha.iter().enumerate() {
            for (ui, gi) in u.iter_mut().zip(self.g.column(cz).iter()) {
                *ui += gi * al;
            }
        }
        u
    }

    /// The step's dense system in the form with fewer unknowns: the dual form
    /// ([`Dense::system_dual`]) or, with S at hand, the primal one ([`Dense::system_primal`]).
    /// Both give the same Newton step. `None` without tangential rows.
    fn system(&self, set: &ActiveSet) -> Option<System> {
        let rows = set.tangential.as_ref()?;
        let Some(st) = self.stiff else {
            return self.system_dual(set);
        };
        let d = self.dim;
        let (mut dual, mut primal) = (0, 0);
        for (q, row) in rows.iter().enumerate() {
            if !set.normal[q] {
                primal += d;
            } else {
                dual += if tie(*row, q * d, d).is_some() { 1 } else { d };
                if row.is_slip() {
                    primal += d - 1;
                }
            }
        }
        if primal < dual {
            Some(self.system_primal(set, rows, st))
        } else {
            self.system_dual(set)
        }
    }

    /// The step's dense system in the primal form ([`Stiff`]): the unknowns u at the dofs the
    /// set leaves free and α; rows λ = 0 (inactive), (F6) −λ_τ + L̃ u_τ − q λ_n = r̃ + L̃ u_τ^ref
    /// (slip), Gᵀ λ = φ, with λ = r − S (u − G α) and u = −g, u_τ^ref where the set prescribes
    /// it; rows equilibrated as the dual form's.
    fn system_primal(&self, set: &ActiveSet, rows: &[CoulombRow<2>], st: &Stiff) -> System {
        let (d, n, mz) = (self.dim, self.cb.nodes.len(), self.g.ncols());
        let mut known = vec![f64::NAN; n * d];
        let mut cols: Vec<Unknown> = Vec::new();
        let mut at = vec![usize::MAX; n];
        let free = |dof: usize| Unknown { dof, tied: None };
        for (q, k) in self.cb.nodes.iter().enumerate() {
            at[q] = cols.len();
            if !set.normal[q] {
                cols.extend((0..d).map(|a| free(q * d + a)));
                continue;
            }
            known[q * d] = -k.gap;
            if rows[q].is_slip() {
                cols.extend((1..d).map(|a| free(q * d + a)));
            } else {
                known[q * d + 1..q * d + d].copy_from_slice(&k.u_t_ref[..d - 1]);
            }
        }
        let m = cols.len();
        // λ at u_F = 0, α = 0: r − S u_K
        let mut base = st.r.to_vec();
        for (j, &uj) in known.iter().enumerate() {
            if uj.is_finite() && uj != 0.0 {
                for (b, sij) in base.iter_mut().zip(st.s.column(j).iter()) {
                    *b -= sij * uj;
                }
            }
        }
        let mut a = DMatrix::<f64>::zeros(m + mz, m + mz);
        let mut rhs = DVector::<f64>::zeros(m + mz);
        // row `ri` += Σ_t coef_t λ(dof_t); returns its constant part Σ_t coef_t base(dof_t)
        // (S symmetric: S's row `dof` is its column)
        let put_lam = |a: &mut DMatrix<f64>, ri: usize, terms: &[(usize, f64)]| -> f64 {
            let mut row = a.column_mut(ri);
            for &(dof, f) in terms {
                let s_row = st.s.column(dof);
                for (jc, u) in cols.iter().enumerate() {
                    row[jc] -= f * s_row[u.dof];
                }
                for cz in 0..mz {
                    row[m + cz] += f * st.sg[(dof, cz)];
                }
            }
            terms.iter().map(|&(dof, f)| f * base[dof]).sum::<f64>()
        };
        let mut ri = 0;
        for (q, k) in self.cb.nodes.iter().enumerate() {
            if !set.normal[q] {
                // λ = 0
                for b in 0..d {
                    rhs[ri] = -put_lam(&mut a, ri, &[(q * d + b, 1.0)]);
                    ri += 1;
                }
                continue;
            }
            let CoulombRow::Slip { l, q: qc, r } = rows[q].with_reference(&k.u_t_ref) else {
                continue; // stick: no unknown, no row
            };
            // (F6): −λ_τ − q λ_n + L̃ u_τ = r̃ (+ L̃ u_τ^ref, in r)
            for i in 0..d - 1 {
                let c0 = put_lam(&mut a, ri, &[(q * d + 1 + i, -1.0), (q * d, -qc[i])]);
                for j in 0..d - 1 {
                    a[(at[q] + j, ri)] += l[i][j];
                }
                rhs[ri] = r[i] - c0;
                ri += 1;
            }
        }
        debug_assert_eq!(ri, m);
        // the balance of the free modes: Gᵀ λ = φ, λ = base − S u_F + S G α
        for cz in 0..mz {
            let mut row = a.column_mut(m + cz);
            for (jc, u) in cols.iter().enumerate() {
                row[jc] = -st.sg[(u.dof, cz)];
            }
            for c2 in 0..mz {
                row[m + c2] = st.gsg[(cz, c2)];
            }
            let gb: f64 = self
                .g
                .column(cz)
                .iter()
                .zip(&base)
                .map(|(g, b)| g * b)
                .sum();
            rhs[m + cz] = self.phi[cz] - gb;
        }
        equilibrate(&mut a, &mut rhs);
        System {
            a,
            rhs,
            cols,
            known: Some(known),
        }
    }

    /// The step's dense system in the active nodes' λ and the free modes' α (module note;
    /// bordered by the balance Gᵀ λ = φ where Dirichlet data leave rigid modes free), its rows
    /// equilibrated. `None` without tangential rows.
    fn system_dual(&self, set: &ActiveSet) -> Option<System> {
        let (d, n, mz) = (self.dim, self.cb.nodes.len(), self.g.ncols());
        let (cmt, g, w) = (self.cmat_t, self.g, self.d0);
        let rows = set.tangential.as_ref()?;
        // the unknowns: per active node λ_n, then λ_τ unless its row ties it to λ_n; `at`: the
        // position of each active node's λ_n
        let mut cols: Vec<Unknown> = Vec::new();
        let mut at = vec![usize::MAX; n];
        for q in (0..n).filter(|&q| set.normal[q]) {
            at[q] = cols.len();
            let tied = tie(rows[q], q * d, d);
            cols.push(Unknown { dof: q * d, tied });
            if tied.is_none() {
                cols.extend((1..d).map(|b| Unknown {
                    dof: q * d + b,
                    tied: None,
                }));
            }
        }
        let m = cols.len();
        // built as its transpose: row ri of the system is column ri here (contiguous, as Cᵀ's
        // column dof is C's row dof; measured on the floating Hertz disk at 344 620 unknowns,
        // 1 875 dense unknowns: 0.15 s a step against 0.18 s built row by row)
        let mut a = DMatrix::<f64>::zeros(m + mz, m + mz);
        let mut rhs = DVector::<f64>::zeros(m + mz);
        // row `ri` := Σ_j coef_j · u_(dof_j) (+ constants on the right): u = w − C λ + G α
        let put_u = |a: &mut DMatrix<f64>, ri: usize, terms: &[(usize, f64)]| -> f64 {
            let mut row = a.column_mut(ri);
            for &(dof, f) in terms {
                let c_row = cmt.column(dof);
                for (jc, u) in cols.iter().enumerate() {
                    row[jc] -= f * u.of(|col| c_row[col]);
                }
                for cz in 0..mz {
                    row[m + cz] += f * g[(dof, cz)];
                }
            }
            terms.iter().map(|&(dof, f)| f * w[dof]).sum::<f64>()
        };
        for p in (0..n).filter(|&q| set.normal[q]) {
            let k = &self.cb.nodes[p];
            let (r0, pn) = (at[p], p * d);
            // u_n = −g
            rhs[r0] = -k.gap - put_u(&mut a, r0, &[(pn, 1.0)]);
            match rows[p] {
                _ if cols[r0].tied.is_some() => {} // λ_τ = −q λ_n: its row is the tie
                CoulombRow::Stick => {
                    // u_τ = u_τ^ref (3.34a)
                    for i in 0..d - 1 {
                        let wi = put_u(&mut a, r0 + 1 + i, &[(pn + 1 + i, 1.0)]);
                        rhs[r0 + 1 + i] = k.u_t_ref[i] - wi;
                    }
                }
                row => {
                    // (F6) on an active node: −λ_τ + L̃ u_τ − q λ_n = r̃ + L̃ u_τ^ref. Its term
                    // q c (u_n + g) vanishes by the normal row; kept, it would carry that row's
                    // round-off times c (u_n = d₀ − C λ cancels to −g) into λ_τ (measured on the
                    // held disk at c = 1e7: u 2.1e-9 off the plain path's with it, 1.5e-14 without)
                    let CoulombRow::Slip { l, q, r } = row.with_reference(&k.u_t_ref) else {
                        unreachable!("a slip row stays a slip row")
                    };
                    for i in 0..d - 1 {
                        let ri = r0 + 1 + i;
                        let terms: Vec<(usize, f64)> =
                            (0..d - 1).map(|j| (pn + 1 + j, l[i][j])).collect();
                        let wi = put_u(&mut a, ri, &terms);
                        a[(r0 + 1 + i, ri)] -= 1.0;
                        a[(r0, ri)] -= q[i];
                        rhs[ri] = r[i] - wi;
                    }
                }
            }
        }
        // the balance of the free modes: Gᵀ λ = φ (the pins carry nothing)
        for cz in 0..mz {
            for (jc, u) in cols.iter().enumerate() {
                a[(jc, m + cz)] = u.of(|col| g[(col, cz)]);
            }
            rhs[m + cz] = self.phi[cz];
        }
        equilibrate(&mut a, &mut rhs);
        Some(System {
            a,
            rhs,
            cols,
            known: None,
        })
    }

    /// λ (every candidate, d per node), u = d₀ − C λ + G α and α from a system's solution.
    #[allow(clippy::type_complexity)]
    fn unknowns(&self, sys: &System, x: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        if let (Some(known), Some(st)) = (&sys.known, self.stiff) {
            return self.unknowns_primal(sys, known, st, x);
        }
        let (d, n, m) = (self.dim, self.cb.nodes.len(), sys.cols.len());
        let mut lam = vec![0.0; n * d];
        for (u, &xj) in sys.cols.iter().zip(x) {
            lam[u.dof] = xj;
            if let Some((t, f)) = u.tied {
                lam[t] = f * xj;
            }
        }
        let alpha: Vec<f64> = x[m..].to_vec();
        let u = self.u_of(&lam, &alpha);
        (lam, u, alpha)
    }

    /// u − G α at the candidates' dofs where `sys` is in the primal form (empty otherwise): the
    /// Schur variables' part of the expansion, from the step's own unknowns (d₀ − C λ would
    /// carry λ's round-off through C = S⁻¹: measured on the rolling Hertz disk at 344 620
    /// unknowns, the expanded residual 1.5e-9 of ‖λ‖ instead of round-off).
    fn primal_x_s(&self, sys: &System, u: &[f64], alpha: &[f64]) -> Vec<f64> {
        if sys.known.is_none() {
            return Vec::new();
        }
        (DVector::from_column_slice(u) - self.g * DVector::from_column_slice(alpha))
            .as_slice()
            .to_vec()
    }

    /// [`Dense::unknowns`] of the primal form: u (`known` where the set prescribes it), α, and
    /// λ = r − S (u − G α), exactly 0 at the inactive candidates (their rows).
    #[allow(clippy::type_complexity)]
    fn unknowns_primal(
        &self,
        sys: &System,
        known: &[f64],
        st: &Stiff,
        x: &[f64],
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let (d, m) = (self.dim, sys.cols.len());
        let mut u = known.to_vec();
        for (c, &xj) in sys.cols.iter().zip(x) {
            u[c.dof] = xj;
        }
        let alpha: Vec<f64> = x[m..].to_vec();
        let w = DVector::from_column_slice(&u) - self.g * DVector::from_column_slice(&alpha);
        let mut lam = (DVector::from_column_slice(st.r) - st.s * w)
            .as_slice()
            .to_vec();
        for (q, l) in lam.chunks_mut(d).enumerate() {
            if known[q * d].is_nan() {
                l.fill(0.0);
            }
        }
        (lam, u, alpha)
    }

    /// The iterate's per-node records (frame and global components) from λ and u.
    fn records(&self, set: &ActiveSet, lam: &[f64], u: &[f64], out: &mut [NodeResult]) {
        let d = self.dim;
        for (q, (k, r)) in self.cb.nodes.iter().zip(out.iter_mut()).enumerate() {
            let f = &k.frame;
            let (uq, lq) = (&u[q * d..q * d + d], &lam[q * d..q * d + d]);
            let mut ug = [0.0; 3];
            let mut lg = [0.0; 3];
            for a in 0..3 {
                ug[a] = f.n[a] * uq[0];
                lg[a] = f.n[a] * lq[0];
                for i in 0..d - 1 {
                    ug[a] += f.t[i][a] * uq[1 + i];
                    lg[a] += f.t[i][a] * lq[1 + i];
                }
            }
            let mut u_t = [0.0; 2];
            let mut lambda_t = [0.0; 2];
            u_t[..d - 1].copy_from_slice(&uq[1..d]);
            lambda_t[..d - 1].copy_from_slice(&lq[1..d]);
            *r = NodeResult {
                u: ug,
                lambda: lg,
                u_n: uq[0],
                u_t,
                lambda_n: lq[0],
                lambda_t,
                active: set.normal[q],
                slip: set.slip(q),
            };
        }
    }
}

/// Coulomb with friction coefficient `mu` condensed onto the candidates that the frictionless
/// condensed solve `first` (its result) left in `kept` (module note). Collective.
pub(super) fn solve(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    ns: &NewtonSettings,
    kept: &mut Kept,
    warm: Option<&WarmStart>,
) -> Result<CoulombCondensed, RunError> {
    let n = kept.comp.list.len();
    let mut summary = CoulombCondensedSummary {
        outcome: "condensed",
        reason: None,
        steps: 0,
        primal_steps: 0,
        dense_seconds: 0.0,
        expansion_seconds: 0.0,
        coarse_levels: Vec::new(),
        f5_from: None,
        f5_coarse_levels: 0,
    };
    let t = Instant::now();
    let run = dense_phase(ctx, p, ns, kept, warm);
    summary.dense_seconds = t.elapsed().as_secs_f64();
    summary.steps = run.steps.len();
    summary.primal_steps = run.primal_steps;
    if !run.coarse.is_empty() {
        let levels: Vec<String> = run
            .coarse
            .iter()
            .map(|(nodes, steps)| format!("{nodes} nodes {steps} steps"))
            .collect();
        say!(
            ctx,
            "coulomb: condensed: nested start on coarse subsets of the candidates: {}",
            levels.join(", ")
        );
        summary.coarse_levels = run
            .coarse
            .iter()
            .map(|&(nodes, steps)| CoarseLevel { nodes, steps })
            .collect();
    }
    let mut history = Vec::new();
    record_steps(
        ctx,
        &mut history,
        &run.steps,
        ("C", "condensed Coulomb"),
        (n, 0),
    );
    if run.f5_from > 0 || run.f5_coarse > 0 {
        summary.f5_from = (run.f5_from > 0).then_some(run.f5_from);
        summary.f5_coarse_levels = run.f5_coarse;
        let mut at = Vec::new();
        if run.f5_from > 0 {
            at.push(format!("from dense step {} on", run.f5_from));
        }
        if run.f5_coarse > 0 {
            at.push(format!(
                "on {} coarse level(s) of the nested start",
                run.f5_coarse
            ));
        }
        say!(
            ctx,
            "coulomb: condensed: settled slip rows left a dense system singular (every active \
             node slipping); the (F5) rows instead: {}",
            at.join("; ")
        );
    }
    if let Err(why) = &run.end {
        return Ok(give_up(ctx, summary, why.clone()));
    }
    // w = K_p⁻¹ (f − Q λ): one expansion solve
    let t = Instant::now();
    let lam = if ctx.rank == 0 {
        run.lambda.clone()
    } else {
        Vec::new()
    };
    let w = match kept.comp.expand_u(
        ctx,
        &kept.cand,
        (&kept.f_root, kept.n_local),
        (&lam, &run.x_s),
    ) {
        Ok(w) => w,
        Err(why) => return Ok(give_up(ctx, summary, why)),
    };
    let checked = check(ctx, p, reduced, ns, kept, &run, &w)?;
    summary.expansion_seconds = t.elapsed().as_secs_f64();
    finish(ctx, reduced, (summary, history, n), checked)
}

/// The dense generalised Newton on rank 0 (from the warm records of a load step, or the
/// frictionless solution), its outcome broadcast to every rank. Collective.
fn dense_phase(
    ctx: &Ctx,
    p: &ContactProblem,
    ns: &NewtonSettings,
    kept: &Kept,
    warm: Option<&WarmStart>,
) -> DenseCoulomb {
    let (b, dim) = (p.boundary, p.mesh.dim);
    let n = kept.comp.list.len();
    let mz = kept.free.dirichlet_free().ncols() + ns.force.len();
    let warm_records = warm.map(|w| gather_records(ctx, w.nodes));
    let root = ctx.on_root_wide(n * dim + mz, || {
        let run = guarded("coulomb-dense-steps", || {
            let cb = candidate_boundary(kept, b, dim);
            let g = mode_parts(&kept.free, ns.force, &cb, dim);
            let mut phi = kept.free.free_load();
            phi.extend(ns.force.iter().map(|fc| fc.magnitude()));
            let cmat_t = kept.comp.cmat.transpose();
            let stiff = kept.comp.stiffness().map(|(s, r)| {
                let sg = s * &g;
                let gsg = g.transpose() * &sg;
                Stiff { s, r, sg, gsg }
            });
            let dense = Dense {
                dim,
                cmat: &kept.comp.cmat,
                cmat_t: &cmat_t,
                d0: &kept.comp.d0,
                g: &g,
                phi: &phi,
                cb: &cb,
                law: ns.law,
                c: ns.c,
                max_steps: ns.section.max_steps,
                tol_u: ns.section.tol_u,
                settle: true,
                stiff: stiff.as_ref(),
            };
            match &warm_records {
                Some(all) => {
                    let (start, u_prev) = warm_start(all, &kept.comp.list, (&g, ns.force), dim);
                    dense.run(&start, u_prev)
                }
                None => {
                    let list = &kept.comp.list;
                    let active: Vec<bool> = list.iter().map(|&i| kept.active[i]).collect();
                    let lambda_n: Vec<f64> = list.iter().map(|&i| kept.lambda[i]).collect();
                    let (start, u_prev) = dense.frictionless_start(&active, &lambda_n);
                    // nested in 2D only: on surfaces (every fourth node a coarse one) it took
                    // as many fine steps or more (docs/numbers.md: the 3D block, 12 against 7
                    // and 8 against 8; the hemisphere, 14 against 13)
                    if dim == 2 {
                        dense.run_nested(&start, u_prev)
                    } else {
                        dense.run(&start, u_prev)
                    }
                }
            }
        });
        let mut run = run.unwrap_or_else(|why| DenseCoulomb::failed(n, dim, mz, why));
        (run.pack(), std::mem::take(&mut run.x_s))
    });
    let (mut packed, x_s) = root.unwrap_or_default();
    ctx.broadcast_f64s(&mut packed);
    let mut run = DenseCoulomb::unpack(&packed, n, dim, mz);
    run.x_s = x_s;
    run
}

/// The condensed solve stops: said in the log, the plain path from the frictionless solution.
fn give_up(ctx: &Ctx, mut summary: CoulombCondensedSummary, why: String) -> CoulombCondensed {
    let then = "the plain path from the frictionless solution";
    let record = (&mut summary.outcome, &mut summary.reason);
    fall_back(ctx, ("coulomb: condensed", then), record, why);
    CoulombCondensed::Fallback(summary)
}

/// The dense states on this rank's contact nodes, K_p's held nodes in contact and sticking (the
/// others inactive, λ = 0). Local.
fn local_set(kept: &Kept, b: &ContactBoundary, run: &DenseCoulomb) -> ActiveSet {
    let mut pos = vec![usize::MAX; kept.cand.n];
    for (q, &i) in kept.comp.list.iter().enumerate() {
        pos[i] = q;
    }
    let zero = CoulombRow::Slip {
        l: [[0.0; 2]; 2],
        q: [0.0; 2],
        r: [0.0; 2],
    };
    let on = |i: usize| {
        let q = pos[b.offset + i];
        (q != usize::MAX && run.active[q]).then_some(q)
    };
    // K_p's held nodes: in contact and sticking
    let held = |i: usize| kept.held.get(b.offset + i).copied().unwrap_or(false);
    ActiveSet {
        normal: (0..b.nodes.len())
            .map(|i| on(i).is_some() || held(i))
            .collect(),
        tangential: Some(
            (0..b.nodes.len())
                .map(|i| match on(i) {
                    Some(q) if !run.slip[q] => CoulombRow::Stick,
                    None if held(i) => CoulombRow::Stick,
                    _ => zero,
                })
                .collect(),
        ),
        spring_floor: 0.0,
        stick_active: false,
    }
}

/// An expanded iterate checked on every contact node.
struct Checked {
    it: Iterate,
    u: crate::petsc::Vector,
    totals: StepTotals,
    /// The final set leaves a free rigid mode free (the plain path pins it: not unique).
    loose: bool,
    /// Where the dense steps stalled with no state changed above DENSE_RESIDUAL_TOL: the worst
    /// violation of (3.14)/(3.18) relative to the problem's scales
    /// ([`super::final_state::coulomb_certificate_worst`]); not computed otherwise.
    certificate: Option<f64>,
    /// Force control: each force-controlled pair's approach δ_j.
    approach: Vec<f64>,
    /// Where no candidate changes state: the nodes beyond the candidates that do (c_h's global
    /// order, every rank's); else empty.
    beyond: Vec<usize>,
}

/// u = w + R z α from this rank's rows `w`, (3.28) and the set update (3.23)/(F5) with the
/// dense states on every contact node, and whether the set holds every free mode. Collective.
fn check(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    ns: &NewtonSettings,
    kept: &Kept,
    run: &DenseCoulomb,
    w: &[f64],
) -> Result<Checked, RunError> {
    let dim = p.mesh.dim;
    // under force control the obstacles at the approaches found (the gaps and references of
    // the plain path's iterate)
    let approach = approaches(kept, run);
    let placed = force::placed(p.boundary, &force::starting_at(ns.force, &approach));
    let b = &placed;
    ctx.agree(reduced.set_solution_local(w).map_err(RunError::from))?;
    let set = local_set(kept, b, run);
    let mut it = Iterate::new(b.nodes.len(), w.len(), true);
    reduced.recover(p.sys, b, &set, &mut it)?; // (3.28) on w (A ρ = 0)
                                               // u = w + ρ, ρ = R z α: the free modes' motion
    let free = &kept.free;
    let z = free.dirichlet_free();
    let mut rho = [0.0; 6];
    for (j, r) in rho.iter_mut().enumerate().take(free.rigid_modes().m) {
        *r = (0..z.ncols()).map(|c| z[(j, c)] * run.alpha[c]).sum();
    }
    let mut u = reduced.solution()?;
    add_motion(free, &rho, p, &mut u, &mut it.nodes)?;
    let scale = threshold_scale(ctx, b, &it.nodes, ns.law, ns.c);
    let up = set.update(&it, b, ns.law, ns.c, scale, dim); // (3.23) / (F5)
    let totals = up.reduce(ctx, b, free.modes(), dim);
    // the nodes beyond the candidates that change state: a new pass takes them as candidates
    // (gathered only where a state changed; the same on every rank)
    let beyond = match totals.changed > 0 {
        true => changed_beyond(ctx, kept, b, (&set, &up.next)),
        false => Vec::new(),
    };
    let loose = if z.ncols() > 0 {
        let gram = set.summarise(ctx, b, free.modes(), dim).gram;
        let mut fin = FreeModes::new(
            ctx,
            p.mesh,
            p.layout,
            p.fixed,
            b,
            &reduced.f_local,
            ns.rigid,
        );
        fin.update(ctx, p.mesh, p.layout, &gram)?;
        !fin.pins().is_empty()
    } else {
        false
    };
    // the same on every rank: the totals are reduced, the run broadcast
    let judged = totals.changed == 0
        && run.stalled
        && totals.residual > DENSE_RESIDUAL_TOL * totals.lambda_norm;
    let certificate = if judged {
        Some(super::final_state::coulomb_certificate_worst(
            ctx, p.sys, b, &it.nodes, &u, dim,
        )?)
    } else {
        None
    };
    Ok(Checked {
        it,
        u,
        totals,
        loose,
        certificate,
        approach,
        beyond,
    })
}

/// The nodes whose state changes from `set` to `next` where no candidate's does: every rank's,
/// in c_h's global order (empty where a candidate changes). Collective.
fn changed_beyond(
    ctx: &Ctx,
    kept: &Kept,
    b: &ContactBoundary,
    (set, next): (&ActiveSet, &ActiveSet),
) -> Vec<usize> {
    let mut mine = Vec::new();
    let mut inside = 0usize;
    for i in 0..b.nodes.len() {
        if set.state(i) != next.state(i) {
            let g = b.offset + i;
            match kept.comp.in_s[g] {
                true => inside += 1,
                false => mine.push(g as f64),
            }
        }
    }
    if ctx.sum_usize(inside) > 0 {
        return Vec::new();
    }
    ctx.all_gather_varcount(&mine)
        .iter()
        .map(|&g| g as usize)
        .collect()
}

/// The force-controlled pairs' approaches δ_j of a dense run (the amplitudes after the free
/// modes'; empty without force control).
fn approaches(kept: &Kept, run: &DenseCoulomb) -> Vec<f64> {
    run.alpha[kept.free.dirichlet_free().ncols()..].to_vec()
}

/// The checked iterate as the result (no state changed, ‖R‖₂ ≤ DENSE_RESIDUAL_TOL ‖λ‖₂, every
/// free mode held), else as the plain path's start — where the dense steps stalled above the
/// bound, the plain path confirms from it in one LU step to round-off. Collective (log).
fn finish(
    ctx: &Ctx,
    reduced: &ReducedSystem,
    (mut summary, history, n): (CoulombCondensedSummary, Vec<StepInfo>, usize),
    checked: Checked,
) -> Result<CoulombCondensed, RunError> {
    let Checked {
        it,
        u,
        totals,
        loose,
        certificate,
        approach,
        beyond,
    } = checked;
    // a stalled dense iteration is accepted where its certificates hold to round-off (the
    // bound beyond which the final check warns), as the plain path accepts a stall
    let residual_ok = totals.residual <= DENSE_RESIDUAL_TOL * totals.lambda_norm
        || certificate.is_some_and(|c| c <= CERTIFICATE_ROUND_OFF);
    let u_local = u.to_local_vec()?;
    let result = NewtonResult {
        u,
        nodes: it.nodes,
        steps: history.len(),
        history,
        converged: true,
        lambda_seconds: reduced.lambda_seconds,
        rows_seconds: reduced.rows_seconds,
        pinned_final: Vec::new(),
        cycle_detected_at: None,
        approach,
        // accepted by its certificates alone above DENSE_RESIDUAL_TOL: loosened
        stop: if totals.residual <= DENSE_RESIDUAL_TOL * totals.lambda_norm {
            super::certificate::StopRule::ActiveSet
        } else {
            super::certificate::StopRule::CondensedCoulombStall
        },
    };
    if totals.changed == 0 && residual_ok && !loose {
        let stalled = certificate.map_or(String::new(), |c| {
            format!(" (stalled; the certificates' worst {c:.3e} of the problem's scales)")
        });
        say!(
            ctx,
            "coulomb: condensed: {} dense steps ({} in the primal form) on {n} candidates \
             ({:.3} s), expansion and check {:.3} s: |C| = {:.3e} of |λ| = {:.3e}{stalled}",
            summary.steps,
            summary.primal_steps,
            summary.dense_seconds,
            summary.expansion_seconds,
            totals.residual,
            totals.lambda_norm
        );
        return Ok(CoulombCondensed::Solved(Box::new(result), summary));
    }
    let why = if loose {
        "the final set leaves a rigid mode free".to_string()
    } else if let Some(c) = certificate {
        format!(
            "the dense steps stalled at |C| = {:.3e} of |λ| = {:.3e} on the expanded u, above \
             {DENSE_RESIDUAL_TOL:e} of it, the certificates' worst {c:.3e} of the problem's \
             scales: one plain step confirms",
            totals.residual, totals.lambda_norm
        )
    } else {
        format!(
            "on the expanded u {} node(s) change state, |C| = {:.3e} of |λ| = {:.3e}",
            totals.changed, totals.residual, totals.lambda_norm
        )
    };
    say!(ctx, "coulomb: condensed: {why}");
    summary.outcome = "start";
    summary.reason = Some(why);
    Ok(CoulombCondensed::Start(
        Box::new(result),
        u_local,
        summary,
        beyond,
    ))
}

/// Values per node of a gathered warm record: u_n, u_τ (2), λ_n, λ_τ (2), active, slip.
const WARM_REC: usize = 8;

/// Every rank's warm-start records in c_h's global order (one all-gather). Collective.
fn gather_records(ctx: &Ctx, nodes: &[NodeResult]) -> Vec<f64> {
    let mut mine = Vec::with_capacity(nodes.len() * WARM_REC);
    for r in nodes {
        mine.extend_from_slice(&[r.u_n, r.u_t[0], r.u_t[1], r.lambda_n]);
        mine.extend_from_slice(&[r.lambda_t[0], r.lambda_t[1]]);
        mine.extend_from_slice(&[r.active as u8 as f64, r.slip as u8 as f64]);
    }
    ctx.all_gather_varcount(&mine)
}

/// The dense iteration's start from a load step's warm records (`all`, gathered) at the
/// candidates `list`: their states and values, u (d per node). Under force control u is
/// taken relative to the obstacles at their starting approaches δ_j (the dense unknowns are
/// relative: u = d₀ − C λ + G α, G's last columns the approaches', `g`).
fn warm_start(
    all: &[f64],
    list: &[usize],
    (g, force): (&DMatrix<f64>, &[ForceControl]),
    dim: usize,
) -> (Vec<NodeResult>, Vec<f64>) {
    let mut u = vec![0.0; list.len() * dim];
    let first = g.ncols() - force.len();
    let start = list
        .iter()
        .enumerate()
        .map(|(q, &i)| {
            let mut r = [0.0; WARM_REC];
            r.copy_from_slice(&all[i * WARM_REC..(i + 1) * WARM_REC]);
            for (j, fc) in force.iter().enumerate() {
                for a in 0..dim {
                    r[a] += fc.start * g[(q * dim + a, first + j)];
                }
            }
            u[q * dim] = r[0];
            u[q * dim + 1..(q + 1) * dim].copy_from_slice(&r[1..dim]);
            NodeResult {
                u_n: r[0],
                u_t: [r[1], r[2]],
                lambda_n: r[3],
                lambda_t: [r[4], r[5]],
                active: r[6] != 0.0,
                slip: r[7] != 0.0,
                ..NodeResult::default()
            }
        })
        .collect();
    (start, u)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A coupled line of `n` candidates (2D) pressed onto a flat obstacle and pushed sideways:
    /// normal and tangential compliances C_ij = exp(−|i−j| / 8) (positive definite, uncoupled
    /// between the directions), d₀ a parabola deepest at the middle along the normal and a
    /// uniform sideways push `push`; μ = 0.3. The middle sticks, the edges slip (Cattaneo).
    fn pushed_line(n: usize, push: f64) -> (DMatrix<f64>, Vec<f64>, ContactBoundary) {
        let k = |i: usize, j: usize| (-(i as f64 - j as f64).abs() / 8.0).exp();
        let cmat = DMatrix::from_fn(2 * n, 2 * n, |r, q| {
            if r % 2 == q % 2 {
                k(r / 2, q / 2)
            } else {
                0.0
            }
        });
        let mid = (n / 2) as f64;
        let d0: Vec<f64> = (0..2 * n)
            .map(|r| {
                let t = ((r / 2) as f64 - mid) / mid;
                if r % 2 == 0 {
                    -1.0 + 2.0 * t * t
                } else {
                    push
                }
            })
            .collect();
        let nodes = (0..n)
            .map(|i| ContactNode {
                node: i,
                pair: 0,
                mu: 0.3,
                tag: i as u64,
                row: 0,
                local_row: 0,
                x: [i as f64, 0.0, 0.0],
                frame: Frame::new([0.0, 1.0, 0.0], 2).expect("unit normal"),
                gap: 0.0,
                weight: 0.0,
                bound: 0.0,
                u_t_ref: [0.0; 2],
            })
            .collect();
        let cb = ContactBoundary {
            nodes,
            n_global: n,
            offset: 0,
            on_contact_boundary: Vec::new(),
            excluded_dirichlet: 0,
            obstacles: Vec::new(),
            keys: Default::default(),
        };
        (cmat, d0, cb)
    }

    /// The pushed line ([`pushed_line`]) with Cᵀ and no free modes.
    struct Line {
        cmat: DMatrix<f64>,
        cmat_t: DMatrix<f64>,
        d0: Vec<f64>,
        g: DMatrix<f64>,
        cb: ContactBoundary,
    }

    impl Line {
        fn new(n: usize, push: f64) -> Line {
            let (cmat, d0, cb) = pushed_line(n, push);
            Line {
                cmat_t: cmat.transpose(),
                cmat,
                d0,
                g: DMatrix::zeros(2 * n, 0),
                cb,
            }
        }

        /// Its dense Coulomb iteration (μ = 0.3) with c, the settled rows on.
        fn dense(&self, c: f64) -> Dense<'_> {
            Dense {
                dim: 2,
                cmat: &self.cmat,
                cmat_t: &self.cmat_t,
                d0: &self.d0,
                g: &self.g,
                phi: &[],
                cb: &self.cb,
                law: Law::Coulomb,
                c,
                max_steps: 100,
                tol_u: 1e-10,
                settle: true,
                stiff: None,
            }
        }
    }

    /// Runs `f` on a thread with a stack of its own: a multithreaded BLAS may take more than a
    /// test thread's 2 MB.
    fn on_big_stack(f: impl FnOnce() + Send + 'static) {
        std::thread::Builder::new()
            .stack_size(64 << 20)
            .spawn(f)
            .expect("thread")
            .join()
            .expect("the test");
    }

    #[test]
    fn nested_coulomb_ends_in_the_plain_runs_solution_in_fewer_fine_steps() {
        on_big_stack(nested_against_plain);
    }

    /// A 2D slip row without spring and right-hand side ties λ_τ = −q λ_n: the node keeps one
    /// unknown and one row, and the solution still satisfies every row of the set.
    #[test]
    fn a_settled_slip_nodes_tangential_force_is_tied_to_its_normal_force() {
        on_big_stack(|| {
            let n = 9;
            let line = Line::new(n, 0.1);
            let (dense, cb) = (line.dense(1.0), &line.cb);
            // the outer four nodes slip outwards (settled rows), the middle five stick
            let coef = |q: usize| if q < 2 { -0.3 } else { 0.3 };
            let row = |q: usize| {
                if q < 2 || q >= n - 2 {
                    CoulombRow::Slip {
                        l: [[0.0; 2]; 2],
                        q: [coef(q), 0.0],
                        r: [0.0; 2],
                    }
                } else {
                    CoulombRow::Stick
                }
            };
            let set = ActiveSet {
                normal: vec![true; n],
                tangential: Some((0..n).map(row).collect()),
                spring_floor: 0.0,
                stick_active: false,
            };
            let sys = dense.system(&set).expect("rows");
            assert_eq!(sys.cols.len(), 4 + 2 * 5);
            let x = solve_system(&sys).expect("regular");
            let (lam, u, _) = dense.unknowns(&sys, &x);
            let (su, sl) = (
                u.iter().fold(0.0_f64, |m, v| m.max(v.abs())),
                lam.iter().fold(0.0_f64, |m, v| m.max(v.abs())),
            );
            for q in 0..n {
                assert!(
                    (u[2 * q] + cb.nodes[q].gap).abs() <= 1e-12 * su,
                    "u_n of {q}"
                );
                if set.slip(q) {
                    let tied = lam[2 * q + 1] + coef(q) * lam[2 * q];
                    assert!(tied.abs() <= 1e-12 * sl, "λ_τ of {q}: {tied}");
                    assert!(lam[2 * q + 1] != 0.0);
                } else {
                    assert!(u[2 * q + 1].abs() <= 1e-12 * su, "u_τ of {q}");
                }
            }
        });
    }

    /// The primal form (on S = C⁻¹ itself) against the dual form on C, on the pushed line
    /// pressed in everywhere (every node active: the primal form has the slipping nodes'
    /// tangential displacements alone as unknowns): the same final states and λ.
    #[test]
    fn the_primal_form_ends_where_the_dual_form_ends() {
        on_big_stack(|| {
            let n = 65;
            let mut line = Line::new(n, 0.0);
            let mid = (n / 2) as f64;
            for q in 0..n {
                let t = (q as f64 - mid) / mid;
                line.d0[2 * q] = -1.0 - 0.5 * t * t;
                line.d0[2 * q + 1] = 0.6 * t;
            }
            let s = line.cmat.clone().try_inverse().expect("SPD");
            let r = (&s * DVector::from_column_slice(&line.d0))
                .as_slice()
                .to_vec();
            let sg = &s * &line.g;
            let gsg = line.g.transpose() * &sg;
            let st = Stiff {
                s: &s,
                r: &r,
                sg,
                gsg,
            };
            let dual = line.dense(100.0);
            let primal = Dense {
                stiff: Some(&st),
                ..dual
            };
            let (start, u_prev) = dual.frictionless_start(&vec![true; n], &vec![0.0; n]);
            let a = dual.run(&start, u_prev.clone());
            let b = primal.run(&start, u_prev);
            assert!(a.end.is_ok() && b.end.is_ok(), "{:?} {:?}", a.end, b.end);
            assert_eq!((a.primal_steps, b.primal_steps), (0, b.steps.len()));
            let slips = (0..n).filter(|&q| b.active[q] && b.slip[q]).count();
            let sticks = (0..n).filter(|&q| b.active[q] && !b.slip[q]).count();
            assert!(slips > 5 && sticks > 5, "{slips} slip, {sticks} stick");
            assert_eq!((a.active.clone(), a.slip.clone()), (b.active, b.slip));
            let scale = a.lambda.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            for (x, y) in a.lambda.iter().zip(&b.lambda) {
                assert!((x - y).abs() <= 1e-10 * scale, "{x} {y}");
            }
            // the primal iterate's own u − G α: the dual's d₀ − C λ
            let w = DVector::from_column_slice(&line.d0)
                - &line.cmat * DVector::from_column_slice(&a.lambda);
            let wmax = w.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            for (x, y) in w.iter().zip(&b.x_s) {
                assert!((x - y).abs() <= 1e-10 * wmax, "{x} {y}");
            }
        });
    }

    #[test]
    fn a_system_that_holds_at_the_iterate_is_a_fixed_point() {
        // rows as columns: [[2, 1], [0, 4]] x = [3, 4] ⇒ x = (1, 1)
        let sys = |a: [[f64; 2]; 2], b: [f64; 2]| System {
            a: DMatrix::from_fn(2, 2, |j, i| a[i][j]),
            rhs: DVector::from_row_slice(&b),
            cols: vec![Unknown { dof: 0, tied: None }],
            known: None,
        };
        let own = sys([[2.0, 1.0], [0.0, 4.0]], [3.0, 4.0]);
        let x = [1.0, 1.0 + 2.0 * f64::EPSILON];
        let r = residual_at(&own, &x);
        assert!(r > 0.0 && r < 1e-14, "{r}");
        // the same rows: a fixed point; one row scaled: still (it holds at x)
        assert!(fixed_point(&own, &x, r));
        assert!(fixed_point(
            &sys([[2.0, 1.0], [0.0, 8.0]], [3.0, 8.0]),
            &x,
            r
        ));
        // a row that changed beyond round-off at x: not
        assert!(!fixed_point(
            &sys([[2.0, 1.0], [0.0, 4.0]], [3.0, 4.0 + 1e-9]),
            &x,
            r
        ));
        assert!(!fixed_point(
            &sys([[2.0, 1.1], [0.0, 4.0]], [3.0, 4.0]),
            &x,
            r
        ));
    }

    /// The settled rows (docs/friction.md, "Settled slip") against the (F5) rows throughout, on
    /// the pushed line with c = 100 and a push under which every active node but one slips far
    /// beyond its threshold: the same solution, in fewer fine steps after the nested start.
    #[test]
    fn settled_rows_end_a_wide_slip_in_fewer_steps() {
        on_big_stack(|| {
            let n = 129;
            let line = Line::new(n, 0.3);
            let settled = line.dense(100.0);
            let f5 = Dense {
                settle: false,
                ..settled
            };
            let active: Vec<bool> = (0..n).map(|i| i == n / 2).collect();
            let (start, u_prev) = settled.frictionless_start(&active, &vec![0.0; n]);
            let a = settled.run_nested(&start, u_prev.clone());
            let b = f5.run_nested(&start, u_prev);
            assert!(a.end.is_ok() && b.end.is_ok(), "{:?} {:?}", a.end, b.end);
            let slips = (0..n).filter(|&q| a.active[q] && a.slip[q]).count();
            assert!(slips > 50, "{slips} slipping");
            let scale = b.lambda.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            // A node on its stick/slip threshold to round-off (|λ_τ| = μ|λ_n|) solves the
            // problem in either state, so its state is decided by the BLAS kernels' round-off
            // (measured: the middle node sticks with OpenBLAS' Prescott and Haswell kernels and
            // slips with SkylakeX and Nehalem): its state is not compared, its λ is.
            let at_limit = |r: &DenseCoulomb, q: usize| {
                (r.lambda[2 * q + 1].abs() - 0.3 * r.lambda[2 * q].abs()).abs() <= 1e-8 * scale
            };
            for q in 0..n {
                assert_eq!(a.active[q], b.active[q], "node {q}");
                if !(at_limit(&a, q) && at_limit(&b, q)) {
                    assert_eq!(a.slip[q], b.slip[q], "node {q}");
                }
            }
            for (x, y) in a.lambda.iter().zip(&b.lambda) {
                assert!((x - y).abs() <= 1e-10 * scale, "{x} {y}");
            }
            assert!(
                a.steps.len() < b.steps.len(),
                "fine steps: settled {}, (F5) rows {}",
                a.steps.len(),
                b.steps.len()
            );
        });
    }

    fn nested_against_plain() {
        let n = 129;
        let line = Line::new(n, 0.1);
        let dense = line.dense(1.0);
        // the frictionless start: the middle node touching, λ = 0
        let active: Vec<bool> = (0..n).map(|i| i == n / 2).collect();
        let (start, u_prev) = dense.frictionless_start(&active, &vec![0.0; n]);
        let plain = dense.run(&start, u_prev.clone());
        let nested = dense.run_nested(&start, u_prev);
        assert!(
            plain.end.is_ok() && nested.end.is_ok(),
            "{:?} {:?}",
            plain.end,
            nested.end
        );
        let (slips, sticks) = (0..n)
            .filter(|&q| plain.active[q])
            .fold((0, 0), |(s, k), q| {
                if plain.slip[q] {
                    (s + 1, k)
                } else {
                    (s, k + 1)
                }
            });
        assert!(
            slips > 0 && sticks > 0,
            "partial slip: {slips} slip, {sticks} stick"
        );
        let scale = plain.lambda.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for (a, b) in nested.lambda.iter().zip(&plain.lambda) {
            assert!((a - b).abs() <= 1e-10 * scale, "{a} {b}");
        }
        assert!(!nested.coarse.is_empty());
        assert!(
            nested.steps.len() < plain.steps.len(),
            "fine steps: nested {} plain {}",
            nested.steps.len(),
            plain.steps.len()
        );
    }
}
