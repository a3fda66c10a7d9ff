//! Coulomb's generalised Newton (docs/friction.md (F1)–(F6)) on the contact unknowns alone
//! (direct preset): the frictionless condensed solve with every dof of its candidates in the
//! Schur complement (frictionless.rs, `per` = d) leaves the compliance C = Qᵀ K_p⁻¹ Q of the
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
//! Tresca (Algorithm 2, b_k fixed) runs the same way with its rows (3.33)/(3.39): every node with
//! a threshold is a candidate, and a node out of contact has λ_n = 0 and its stick row
//! (S1: u_τ = u_τ^ref) or slip row (S2: (3.39a)) (docs/friction.md, "Tresca on the contact
//! unknowns").
//!
//! (or the same step in the primal form on S = C⁻¹ itself where that has fewer unknowns,
//! [`Stiff`]) with the rows of `contact::coulomb_row_dyn` and the set update (3.23)/(F5) of the
//! plain path (`ActiveSet::update`, its stick band included), stopped by the same rule, first on
//! coarse subsets of the candidates (nested iteration, `DenseIteration::run_nested`). Nodes beyond
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

use super::coulomb_dense::DenseIteration;
use super::coulomb_dense::Stiff;
use super::coulomb_run::DenseCoulomb;
use super::outcome::fall_back;
use super::outcome::Kept;
use super::summary::record_steps;
use super::summary::{CoarseLevel, CoulombCondensedSummary};
use crate::contact::{CoulombRow, Frame};
use crate::error::RunError;
use crate::geom::dot;
use crate::par::Ctx;
use crate::say;
use crate::signorini::active_set::{threshold_scale, ActiveSet, Iterate, Law, StepTotals};
use crate::signorini::boundary::{ContactBoundary, ContactNode, NodeResult};
use crate::signorini::dense::guarded;
use crate::signorini::force::{self, ForceControl};
use crate::signorini::plain_path::{
    add_motion, ContactProblem, NewtonResult, NewtonSettings, StepInfo, WarmStart,
};
use crate::signorini::rigid::FreeModes;
use crate::signorini::step_system::ReducedSystem;
use nalgebra::DMatrix;
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
                bound: kept.cand.bound(i),
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
        modes: b.modes.clone(),
        stiffness: b.stiffness,
    }
}

/// G: the free modes' parts at the candidates, d rows per node (its frame: n, τ₁, τ₂), one
/// column per free mode, then (force control) one per force-controlled pair j: its obstacle
/// moved by δ_j e_j shifts the candidates' relative displacement by −δ_j (n·e_j, τ₁·e_j,
/// τ₂·e_j) on its nodes (gaps g0 − δ_j n·e_j, references u_τ^ref + δ_j τ·e_j, as
/// `force::Approach::place`), and its balance row is the pair's force along e_j (rank 0).
/// The free modes' parts come with the candidates' records (a slave node of a body pair
/// reads them through its mortar row, which only its own rank knows); `cb` is the candidate
/// boundary of [`candidate_boundary`], in the order of `kept.comp.list`.
fn mode_parts(
    kept: &Kept,
    force: &[ForceControl],
    cb: &ContactBoundary,
    dim: usize,
) -> DMatrix<f64> {
    let mz = kept.free.dirichlet_free().ncols();
    let mut g = DMatrix::zeros(cb.nodes.len() * dim, mz + force.len());
    for (q, (k, &i)) in cb.nodes.iter().zip(&kept.comp.list).enumerate() {
        let dirs = [k.frame.n, k.frame.t[0], k.frame.t[1]];
        for (a, dir) in dirs.iter().enumerate().take(dim) {
            for cz in 0..mz {
                g[(q * dim + a, cz)] = kept.cand.g_along(i, a, cz);
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

/// Coulomb with friction coefficient `mu` condensed onto the candidates that the frictionless
/// condensed solve `first` (its result) left in `kept` (module note). Tresca with nodes that
/// have a threshold beyond the candidates ([`Far`]): their friction is a load, found by rounds
/// of the dense iteration on the kept factorisation, each with the far nodes' λ_τ of the round
/// before, until the expanded iterate passes the check on every node. Collective.
pub(crate) fn solve(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    ns: &NewtonSettings,
    kept: &mut Kept,
    warm: Option<&WarmStart>,
) -> Result<CoulombCondensed, RunError> {
    let n = kept.comp.list.len();
    let mut summary = CoulombCondensedSummary {
        law: ns.law.name(),
        outcome: "condensed",
        reason: None,
        steps: 0,
        primal_steps: 0,
        dense_seconds: 0.0,
        expansion_seconds: 0.0,
        coarse_levels: Vec::new(),
        f5_from: None,
        f5_coarse_levels: 0,
        far_nodes: 0,
        far_rounds: 0,
    };
    let mut far = Far::of(ctx, p.boundary, kept, ns.law, warm);
    // f on rank 0: with far nodes each round's load replaces it for the round's solves, and it
    // is put back after
    let f0 = match far {
        Some(_) => std::mem::take(&mut kept.f_root),
        None => Vec::new(),
    };
    let at = Rounds {
        warm,
        f0: &f0,
        summary: &mut summary,
    };
    let ended = rounds(ctx, p, reduced, ns, kept, &mut far, at);
    if far.is_some() {
        kept.f_root = f0;
    }
    let (history, checked) = match ended? {
        Ok(done) => done,
        Err(why) => return Ok(give_up(ctx, summary, why)),
    };
    finish(ctx, reduced, (summary, history, n), checked)
}

/// What [`rounds`] starts from and records into: the warm start (a load step's), f on rank 0
/// where there are far nodes (`f0`; `kept.f_root` holds each round's load), the summary.
struct Rounds<'a> {
    warm: Option<&'a WarmStart<'a>>,
    f0: &'a [f64],
    summary: &'a mut CoulombCondensedSummary,
}

/// The dense iteration, its expansion and check: once, or with Tresca's far nodes ([`Far`])
/// round after round with their friction as a load (`kept.f_root` holds the load of the
/// round; the caller restores it). The inner `Err`: why the condensed solve gives up.
/// Collective.
fn rounds(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    ns: &NewtonSettings,
    kept: &mut Kept,
    far: &mut Option<Far>,
    at: Rounds,
) -> Result<Result<(Vec<StepInfo>, Checked), String>, RunError> {
    let Rounds { warm, f0, summary } = at;
    let (n, dim) = (kept.comp.list.len(), p.mesh.dim);
    let path = match ns.law {
        Law::Tresca => "condensed Tresca",
        _ => "condensed Coulomb",
    };
    let mut history = Vec::new();
    // the round before's iterate: the next round's start
    let mut before: Option<(Vec<NodeResult>, Vec<f64>)> = None;
    for round in 1.. {
        if let Some(fr) = far.as_ref() {
            let f = fr.loads(ctx, kept, f0, dim);
            let recondensed = kept.comp.recondense(ctx, &f);
            kept.f_root = f;
            if let Err(why) = recondensed {
                return Ok(Err(why));
            }
        }
        let start = before.as_ref().map(|(nodes, u)| WarmStart {
            nodes,
            u_local: u,
            floors_from: None,
        });
        let t = Instant::now();
        let run = dense_phase(ctx, p, ns, kept, start.as_ref().or(warm));
        summary.dense_seconds += t.elapsed().as_secs_f64();
        summary.steps += run.steps.len();
        summary.primal_steps += run.primal_steps;
        if round == 1 {
            record_coarse(ctx, &run, summary);
            record_f5(ctx, &run, summary);
        }
        record_steps(ctx, &mut history, &run.steps, "C", path, n, 0);
        if let Err(why) = &run.end {
            return Ok(Err(why.clone()));
        }
        let t = Instant::now();
        let w = match expand_run(ctx, kept, &run) {
            Ok(w) => w,
            Err(why) => return Ok(Err(why)),
        };
        let checked = check(ctx, p, reduced, ns, kept, &run, &w)?;
        summary.expansion_seconds += t.elapsed().as_secs_f64();
        let Some(fr) = far.as_mut() else {
            return Ok(Ok((history, checked)));
        };
        (summary.far_nodes, summary.far_rounds) = (fr.count, round);
        let moved = fr.update(ctx, p.boundary, &checked.it.nodes, ns.c);
        say!(
            ctx,
            "tresca: condensed: round {round}: {} dense steps, |C| = {:.3e} of |λ| = {:.3e} on \
             the expanded u, {} node(s) changed; the {} far nodes' friction moved by {:.3e}, \
             {} of them below their threshold",
            run.steps.len(),
            checked.totals.residual,
            checked.totals.lambda_norm,
            checked.totals.changed,
            fr.count,
            moved.change,
            moved.sticking
        );
        // accepted once the far nodes' friction is settled to round-off (or at the rounds'
        // limit); far nodes that stick after the first rounds, or the limit unaccepted: the
        // condensed solve gives up
        let settled = moved.change <= FAR_ROUND_OFF * fr.scale;
        if checked.accepted() && (settled || round >= MAX_FAR_ROUNDS) {
            return Ok(Ok((history, checked)));
        }
        if moved.sticking > 0 && round >= FAR_STICK_ROUNDS {
            let why = format!(
                "{} of the {} nodes beyond the candidates stick, which their friction as a load \
                 cannot hold",
                moved.sticking, fr.count
            );
            return Ok(Err(why));
        }
        if round >= MAX_FAR_ROUNDS {
            let why = format!("the far nodes' friction not settled in {MAX_FAR_ROUNDS} rounds");
            return Ok(Err(why));
        }
        let u = checked.u.to_local_vec()?;
        before = Some((checked.it.nodes, u));
    }
    unreachable!("the rounds end by return")
}

/// The rounds of the dense iteration with Tresca's far nodes' friction as a load at most
/// ([`rounds`]): each costs two solves with the kept factorisation (condensation and
/// expansion) and the dense steps from the round before's states. The far nodes' slip
/// directions converge linearly: 0.01–0.03 per round on the 3D block at g = 2.5e-4, 0.66 at
/// g = 5e-3, where the limit ends the rounds, the check accepting (docs/numbers.md, "Tresca's
/// far nodes"). Unaccepted at the limit the condensed solve gives up (the plain path).
const MAX_FAR_ROUNDS: usize = 30;

/// The far nodes' friction is settled where a round moves it by at most this part of the
/// largest threshold. Measured on the 3D block of 44 529 unknowns (1 692 far nodes): the
/// changes fall by 0.01–0.03 per round, 5e-10 of b in round 6, where the residual (F3) on the
/// expanded u is at round-off (4.5e-15 of ‖λ‖, the plain path's u to 2e-16); the check's own
/// bound (1e-8 of ‖λ‖) passed in round 4 with u 1.6e-10 off.
const FAR_ROUND_OFF: f64 = 1e-9;

/// From this round on a far node below its threshold or turned back (sticking) ends the rounds:
/// it needs its stick row, which only a candidate has. The first round starts from λ_τ = 0 at
/// the far nodes (or the load step before's), where a node may sit below its threshold only
/// until its neighbours' friction is found.
const FAR_STICK_ROUNDS: usize = 3;

/// Tresca's nodes with a threshold beyond the candidates (neither Schur variables nor held):
/// inactive nodes whose friction λ_τ, at its threshold, is a load on K_p (in the node frame;
/// this rank's contact nodes), updated between rounds by λ_τ ← b v/|v|, v = λ_τ + c Δu_τ, the
/// slip row (3.39) at its limit, or v itself below the threshold.
struct Far {
    /// c_h's global index of this rank's first contact node.
    offset: usize,
    far: Vec<bool>,
    lambda: Vec<[f64; 2]>,
    /// The far nodes of every rank.
    count: usize,
    /// Their largest threshold (every rank's).
    scale: f64,
}

/// What one update of the far nodes' friction did: its largest change and the nodes below
/// their threshold (every rank's).
struct Moved {
    change: f64,
    sticking: usize,
}

impl Far {
    /// The far nodes of `b` under Tresca (`None`: none, or another law), λ_τ from the warm
    /// start where there is one, else 0. Collective (two reductions).
    fn of(
        ctx: &Ctx,
        b: &ContactBoundary,
        kept: &Kept,
        law: Law,
        warm: Option<&WarmStart>,
    ) -> Option<Far> {
        // a body with free modes keeps the plain path (its load in them would need the far
        // friction's part; the rounds diverged on floating bodies: docs/friction.md)
        if law != Law::Tresca || kept.free.dirichlet_free().ncols() > 0 {
            return None;
        }
        let held = |g: usize| kept.held.get(g).copied().unwrap_or(false);
        let far: Vec<bool> = (b.nodes.iter().enumerate())
            .map(|(i, k)| {
                let g = b.offset + i;
                k.bound > 0.0 && !kept.comp.in_s[g] && !held(g)
            })
            .collect();
        let count = ctx.sum_usize(far.iter().filter(|&&f| f).count());
        if count == 0 {
            return None;
        }
        let lambda = (far.iter().enumerate())
            .map(|(i, &f)| match (f, warm) {
                (true, Some(w)) => w.nodes[i].lambda_t,
                _ => [0.0; 2],
            })
            .collect();
        let scale = (b.nodes.iter().zip(&far))
            .filter(|(_, &f)| f)
            .fold(0.0_f64, |m, (k, _)| m.max(k.bound));
        Some(Far {
            offset: b.offset,
            far,
            lambda,
            count,
            scale: ctx.max_f64(scale),
        })
    }

    /// The far nodes' friction as a load: f − N_τ λ_τ on rank 0 (global coordinates at their
    /// rows; `f0` is f there), empty elsewhere. (No free mode: [`Far::of`].) Collective (one
    /// gather).
    fn loads(&self, ctx: &Ctx, kept: &Kept, f0: &[f64], dim: usize) -> Vec<f64> {
        let mut mine = Vec::new();
        for (i, (&f, l)) in self.far.iter().zip(&self.lambda).enumerate() {
            if f {
                mine.extend_from_slice(&[(self.offset + i) as f64, l[0], l[1]]);
            }
        }
        let all = ctx.gather_to_root(&mine);
        if ctx.rank != 0 {
            return Vec::new();
        }
        let mut f = f0.to_vec();
        for e in all.chunks_exact(3) {
            let (i, l) = (e[0] as usize, [e[1], e[2]]);
            let (q, row) = (kept.cand.basis(i, dim), kept.cand.row(i));
            for a in 0..dim {
                f[row + a] -= (1..dim).map(|j| q[a][j] * l[j - 1]).sum::<f64>();
            }
        }
        f
    }

    /// λ_τ ← b v/|v| where |v| > b, else v (v = λ_τ + c Δu_τ on the expanded iterate `nodes`,
    /// this rank's contact nodes); below the threshold or turned back: sticking. Collective
    /// (two reductions).
    fn update(&mut self, ctx: &Ctx, b: &ContactBoundary, nodes: &[NodeResult], c: f64) -> Moved {
        let (mut change, mut sticking) = (0.0_f64, 0usize);
        for (i, k) in b.nodes.iter().enumerate().filter(|&(i, _)| self.far[i]) {
            let du = crate::signorini::law::increment(&nodes[i], k);
            let l = self.lambda[i];
            let v = [l[0] + c * du[0], l[1] + c * du[1]];
            let norm = v[0].hypot(v[1]);
            let below = norm <= k.bound;
            let next = match below {
                true => v,
                false => [k.bound * v[0] / norm, k.bound * v[1] / norm],
            };
            // turned back by more than a right angle: a node between two slip directions,
            // which a stick row holds (the update overshoots there: c is the Newton steps')
            let turned = next[0] * l[0] + next[1] * l[1] < 0.0;
            sticking += usize::from(below || turned);
            change = change.max((next[0] - l[0]).hypot(next[1] - l[1]));
            self.lambda[i] = next;
        }
        Moved {
            change: ctx.max_f64(change),
            sticking: ctx.sum_usize(sticking),
        }
    }
}

/// The nested start's coarse levels of `run`, logged and kept in `summary`.
fn record_coarse(ctx: &Ctx, run: &DenseCoulomb, summary: &mut CoulombCondensedSummary) {
    if run.coarse.is_empty() {
        return;
    }
    let levels: Vec<String> = run
        .coarse
        .iter()
        .map(|(nodes, steps)| format!("{nodes} nodes {steps} steps"))
        .collect();
    say!(
        ctx,
        "{}: condensed: nested start on coarse subsets of the candidates: {}",
        summary.law,
        levels.join(", ")
    );
    summary.coarse_levels = run
        .coarse
        .iter()
        .map(|&(nodes, steps)| CoarseLevel { nodes, steps })
        .collect();
}

/// Where the (F5) rows replaced settled slip rows in `run` (a singular dense system), logged
/// and kept in `summary`.
fn record_f5(ctx: &Ctx, run: &DenseCoulomb, summary: &mut CoulombCondensedSummary) {
    if run.f5_from == 0 && run.f5_coarse == 0 {
        return;
    }
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
        "{}: condensed: settled slip rows left a dense system singular (every active \
         node slipping); the (F5) rows instead: {}",
        summary.law,
        at.join("; ")
    );
}

/// w = K_p⁻¹ (f − Q λ): one expansion solve with the dense run's λ (and, from its primal
/// form, the Schur variables' part). `Err`: MUMPS' solve failed. Collective.
fn expand_run(ctx: &Ctx, kept: &mut Kept, run: &DenseCoulomb) -> Result<Vec<f64>, String> {
    let lam = if ctx.rank == 0 {
        run.lambda.clone()
    } else {
        Vec::new()
    };
    kept.comp
        .expand_u(ctx, &kept.cand, &kept.f_root, kept.n_local, &lam, &run.x_s)
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
            let g = mode_parts(kept, ns.force, &cb, dim);
            let mut phi = kept.free.free_load();
            phi.extend(ns.force.iter().map(|fc| fc.magnitude()));
            let stiff = kept.comp.stiffness().map(|(s, r)| {
                let sg = s.times_columns(&g);
                let gsg = g.transpose() * &sg;
                Stiff { s, r, sg, gsg }
            });
            let dense = DenseIteration {
                dim,
                cmat: kept.comp.c(),
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
                    let (start, u_prev) = warm_start(all, &kept.comp.list, &g, ns.force, dim);
                    dense.run(&start, u_prev)
                }
                None => {
                    let list = &kept.comp.list;
                    let active: Vec<bool> = list.iter().map(|&i| kept.active[i]).collect();
                    let lambda_n: Vec<f64> = list.iter().map(|&i| kept.lambda[i]).collect();
                    let (start, u_prev) = dense.frictionless_start(&active, &lambda_n);
                    // nested in 2D only: on surfaces (every fourth node a coarse one) it took
                    // as many fine steps or more (docs/numbers.md: the 3D block, 12 against 7
                    // and 8 against 8; the hemisphere, 14 against 13); not for Tresca, whose
                    // thresholds on a coarse subset need not hold the load (a floating disk's
                    // coarse levels ran to their step limit, docs/numbers.md); nor where more
                    // than one body's rigid modes are free: a coarse subset holds a body that
                    // has few nodes in it by too few rows (two disks stacked on a block: both
                    // levels diverged, 36–40 steps each, residuals up to 1e32; docs/friction.md)
                    let free = &kept.free;
                    let one_body = free.dirichlet_free().ncols() <= free.rigid_modes().per_body();
                    if dim == 2 && ns.law == Law::Coulomb && one_body {
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
    // (Tresca's plain path starts from its own start: coulomb.rs `coulomb_start`)
    let then = match summary.law == Law::Tresca.name() {
        true => "the plain path from its own start",
        false => "the plain path from the frictionless solution",
    };
    let what = format!("{}: condensed", summary.law);
    let (outcome, reason) = (&mut summary.outcome, &mut summary.reason);
    fall_back(ctx, &what, then, outcome, reason, why);
    CoulombCondensed::Fallback(summary)
}

/// The dense states on this rank's contact nodes, K_p's held nodes in contact and sticking (the
/// others inactive, λ = 0; a candidate that sticks out of contact, under Tresca, sticks).
/// Local.
fn local_set(kept: &Kept, b: &ContactBoundary, run: &DenseCoulomb, law: Law) -> ActiveSet {
    let mut pos = vec![usize::MAX; kept.cand.n];
    for (q, &i) in kept.comp.list.iter().enumerate() {
        pos[i] = q;
    }
    let zero = CoulombRow::Slip {
        l: [[0.0; 2]; 2],
        q: [0.0; 2],
        r: [0.0; 2],
    };
    let candidate = |i: usize| Some(pos[b.offset + i]).filter(|&q| q != usize::MAX);
    let on = |i: usize| candidate(i).filter(|&q| run.active[q]);
    // K_p's held nodes: in contact and sticking
    let held = |i: usize| kept.held.get(b.offset + i).copied().unwrap_or(false);
    ActiveSet {
        normal: (0..b.nodes.len())
            .map(|i| on(i).is_some() || held(i))
            .collect(),
        tangential: Some(
            (0..b.nodes.len())
                .map(|i| match candidate(i) {
                    Some(q) if !run.slip[q] && (run.active[q] || law == Law::Tresca) => {
                        CoulombRow::Stick
                    }
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
    /// ([`crate::signorini::final_state::coulomb_certificate_worst`]); not computed otherwise.
    certificate: Option<f64>,
    /// Force control: each force-controlled pair's approach δ_j.
    approach: Vec<f64>,
    /// Where no candidate changes state: the nodes beyond the candidates that do (c_h's global
    /// order, every rank's); else empty.
    beyond: Vec<usize>,
}

impl Checked {
    /// The result (no state changed, ‖R‖₂ ≤ DENSE_RESIDUAL_TOL ‖λ‖₂, every free mode held); a
    /// stalled dense iteration is accepted where its certificates hold to round-off (the bound
    /// beyond which the final check warns), as the plain path accepts a stall. The same on
    /// every rank.
    fn accepted(&self) -> bool {
        let totals = &self.totals;
        let residual_ok = totals.residual <= DENSE_RESIDUAL_TOL * totals.lambda_norm
            || self.certificate.is_some_and(|c| c <= CERTIFICATE_ROUND_OFF);
        totals.changed == 0 && residual_ok && !self.loose
    }
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
    let set = local_set(kept, b, run, ns.law);
    let mut it = Iterate::new(b.nodes.len(), w.len(), true);
    reduced.recover(p.sys, b, &set, &mut it)?; // (3.28) on w (A ρ = 0)
                                               // u = w + ρ, ρ = R z α: the free modes' motion
    let free = &kept.free;
    let z = free.dirichlet_free();
    let mut rho = free.no_motion();
    for (j, r) in rho.iter_mut().enumerate() {
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
        true => changed_beyond(ctx, kept, b, &set, &up.next),
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
        Some(crate::signorini::final_state::coulomb_certificate_worst(
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
    set: &ActiveSet,
    next: &ActiveSet,
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
    let accepted = checked.accepted();
    let Checked {
        it,
        u,
        totals,
        loose,
        certificate,
        approach,
        beyond,
    } = checked;
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
            crate::signorini::certificate::StopRule::ActiveSet
        } else {
            crate::signorini::certificate::StopRule::CondensedCoulombStall
        },
    };
    if accepted {
        let stalled = certificate.map_or(String::new(), |c| {
            format!(" (stalled; the certificates' worst {c:.3e} of the problem's scales)")
        });
        say!(
            ctx,
            "{}: condensed: {} dense steps ({} in the primal form) on {n} candidates \
             ({:.3} s), expansion and check {:.3} s: |C| = {:.3e} of |λ| = {:.3e}{stalled}",
            summary.law,
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
    say!(ctx, "{}: condensed: {why}", summary.law);
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
    g: &DMatrix<f64>,
    force: &[ForceControl],
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
