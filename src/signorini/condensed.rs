//! Algorithm 1 on the contact unknowns alone (frictionless, direct preset): one factorisation
//! of the stiffness with every rigid mode that Dirichlet data leave free pinned, K_p; the
//! compliance of the candidate contact nodes C = Nᵀ K_p⁻¹ N from MUMPS' selected-inverse
//! solve (the entries of K_p⁻¹ between their dofs only); then every step of Algorithm 1 is a
//! dense solve of the active nodes' block; at the end one more solve with the factorisation
//! expands the multipliers into u.
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
//! them) and the balance test of [`super::rigid`] decides, as in the plain path. λ_n of (3.28)
//! and u_n come out of the same dense system, the set update is (3.23). The final set is
//! checked on the expanded u by the plain path's own recovery (3.28) and update (3.23): a
//! node that changes there sends the solve to the plain path.
//!
//! Collectives: the gathering of the candidates (one all-gather), the selected-inverse solve,
//! two triangular solves, one broadcast of the dense result, one MatMult.

use super::active_set::{ActiveSet, Iterate, Law};
use super::boundary::ContactBoundary;
use super::newton::{
    add_motion, ContactProblem, NewtonResult, NewtonSettings, StepInfo, WarmStart,
};
use super::reduced::{ReducedSystem, SolveKind};
use super::rigid::{FreeModes, Motion, Pin};
use crate::contact::{c_n, normal_active};
use crate::error::RunError;
use crate::par::Ctx;
use crate::petsc::{InverseRequest, PInt};
use crate::say;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use serde::Serialize;
use std::collections::HashSet;
use std::time::Instant;

/// More candidate contact nodes than this and the condensed path is not tried: the dense
/// compliance (8 n_c² bytes on rank 0) and its selected-inverse solve would not pay.
pub const MAX_CANDIDATES: usize = 8000;

/// The first candidate set: the 1/FIRST_FRACTION of the contact nodes with the smallest gaps.
const FIRST_FRACTION: usize = 8;

/// The first candidate set holds at least this many contact nodes (all if fewer).
const MIN_CANDIDATES: usize = 64;

/// Rounds of candidate growth before the plain path takes over.
const MAX_ROUNDS: usize = 8;

/// An unbalanced load in the set's free modes below this fraction of the load's scale is
/// balanced (as [`super::rigid`]'s balance test).
const BALANCE_RTOL: f64 = 1e-10;

/// summary.json's `newton.condensed`: what the condensed path did.
#[derive(Debug, Clone, Serialize)]
pub struct CondensedSummary {
    /// The path ran to the end ("condensed"), or handed the solve to the plain path
    /// ("fallback", with the reason).
    pub outcome: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fallback_reason: Option<String>,
    /// Candidate contact nodes (the dense system's size).
    pub candidates: usize,
    /// Entries of K_p⁻¹ computed by the selected-inverse solve.
    pub inverse_entries: usize,
    /// Analysis + numeric factorisation of K_p and the solve for d₀ [s].
    pub factorisation_seconds: f64,
    /// The selected-inverse solve and the assembly of C [s].
    pub inverse_seconds: f64,
    /// Algorithm 1's steps on the dense system [s].
    pub dense_seconds: f64,
    /// The expansion solve, (3.28) and the check of the final set [s].
    pub expansion_seconds: f64,
    /// Triangular solves with the factorisation (d₀, expansion).
    pub solves: usize,
}

impl CondensedSummary {
    fn new(candidates: usize) -> CondensedSummary {
        CondensedSummary {
            outcome: "condensed",
            fallback_reason: None,
            candidates,
            inverse_entries: 0,
            factorisation_seconds: 0.0,
            inverse_seconds: 0.0,
            dense_seconds: 0.0,
            expansion_seconds: 0.0,
            solves: 0,
        }
    }

    /// The closing log line of a converged condensed solve (`n` contact nodes).
    fn log(&self, ctx: &Ctx, n: usize, active: usize) {
        say!(
            ctx,
            "newton: condensed: {} of {n} contact nodes as candidates, {active} active, \
             factorisation {:.3} s, inverse {:.3} s, dense {:.3} s, expansion {:.3} s",
            self.candidates,
            self.factorisation_seconds,
            self.inverse_seconds,
            self.dense_seconds,
            self.expansion_seconds
        );
    }
}

/// What the condensed path returns: the solution, or the reason to run the plain path.
pub enum Condensed {
    Solved(Box<NewtonResult>, CondensedSummary),
    Fallback(CondensedSummary),
}

/// Runs Algorithm 1 condensed onto the contact unknowns (module note). `Fallback` when the
/// dense iteration cycles, does not converge within `max_steps`, or its final set changes on
/// the expanded u; an error only where the plain path would give the same one (no support).
/// Collective.
pub fn solve(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    s: &NewtonSettings,
    warm: Option<&WarmStart>,
) -> Result<Condensed, RunError> {
    let b = p.boundary;
    let dim = p.mesh.dim;
    let mut summary = CondensedSummary::new(b.n_global);
    let t = Instant::now();
    let (free, w0, rhs0) = factorise_base(ctx, p, reduced, s)?;
    summary.solves += 1;
    summary.factorisation_seconds = t.elapsed().as_secs_f64();

    let start = start_set(p, s, &free, warm);
    let cand = Candidates::gather(ctx, b, &free, &start, &w0, dim);
    let n = cand.n;
    let n_rows = p.layout.node_offsets.last().copied().unwrap_or(0) * dim;
    // The candidates: first the nodes with the smallest gaps (an eighth of c_h, at least
    // MIN_CANDIDATES), grown (the gap bound doubled, and every node that (3.23) activates on
    // the expanded u) until (3.23) changes no node outside them.
    let mut sorted: Vec<f64> = (0..n).map(|i| cand.gap(i)).collect();
    sorted.sort_by(|a, b| a.total_cmp(b));
    let mut bound = sorted[(n / FIRST_FRACTION).max(MIN_CANDIDATES).min(n) - 1];
    let mut comp = Compliance::new(n);
    let mut active: Vec<bool> = (0..n).map(|i| cand.start(i)).collect();
    // Every node of the start set is a candidate (the thesis' all-active start: all of them).
    let mut forced: HashSet<usize> = (0..n).filter(|&i| active[i]).collect();
    let mut history: Vec<StepInfo> = Vec::new();
    let mut last: Option<Expanded> = None;
    for round in 1..=MAX_ROUNDS {
        let t = Instant::now();
        let new: Vec<usize> = (0..n)
            .filter(|&i| !comp.in_s[i] && (cand.gap(i) <= bound || forced.contains(&i)))
            .collect();
        if new.is_empty() && round > 1 {
            let why = "the candidate set cannot grow (internal)".to_string();
            return Ok(fallback(ctx, summary, why));
        }
        summary.inverse_entries += comp.grow(ctx, reduced, &cand, &new, dim, n_rows)?;
        summary.inverse_seconds += t.elapsed().as_secs_f64();
        let ns = comp.list.len();
        summary.candidates = ns;

        let t = Instant::now();
        let run = dense_round(ctx, &cand, &comp, &free, s, &active);
        summary.dense_seconds += t.elapsed().as_secs_f64();
        record_steps(ctx, &mut history, &run, ns, free.pins().len());
        let mut lambda = vec![0.0; n];
        active = vec![false; n];
        for (q, &i) in comp.list.iter().enumerate() {
            lambda[i] = run.lambda[q];
            active[i] = run.active[q];
        }
        match run.end {
            End::Converged => {}
            End::NoSupport(_) if ns < n => {
                // a node beyond the candidates may still carry the load: all of them
                bound = f64::INFINITY;
                continue;
            }
            End::NoSupport(reaction) => {
                return Err(free.no_support(run.active.iter().filter(|&&a| a).count(), reaction))
            }
            End::Fallback(why) => return Ok(fallback(ctx, summary, why)),
        }

        let t = Instant::now();
        let ex = expand(
            ctx,
            p,
            reduced,
            s,
            &free,
            &rhs0,
            (&lambda, &active),
            &run.alpha,
        )?;
        summary.solves += 1;
        summary.expansion_seconds += t.elapsed().as_secs_f64();
        if ex.changed.is_empty() {
            last = Some(ex);
            break;
        }
        let inside = ex
            .changed
            .iter()
            .filter(|&&i| comp.in_s[i as usize])
            .count();
        if inside > 0 || round == MAX_ROUNDS {
            let why = format!(
                "{} node(s) change on the expanded u ({inside} of them candidates: round-off at \
                 nodes on the edge of the set)",
                ex.changed.len()
            );
            return Ok(fallback(ctx, summary, why));
        }
        say!(
            ctx,
            "newton: condensed: {} node(s) beyond the {ns} candidates come into contact: more \
             candidates",
            ex.changed.len()
        );
        for &i in &ex.changed {
            forced.insert(i as usize);
            active[i as usize] = true;
        }
        bound *= 2.0;
    }
    let Some(mut ex) = last else {
        let why = format!("no final set in {MAX_ROUNDS} rounds of candidates");
        return Ok(fallback(ctx, summary, why));
    };
    summary.log(ctx, n, active.iter().filter(|&&a| a).count());
    // u = w + ρ (λ and the set were taken on w, as the plain path does)
    let mut u = reduced.solution()?;
    add_motion(&free, &ex.rho, p, &mut u, &mut ex.it.nodes)?;
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
    };
    Ok(Condensed::Solved(Box::new(result), summary))
}

/// The plain path takes over: said in the log and in the summary.
fn fallback(ctx: &Ctx, mut summary: CondensedSummary, why: String) -> Condensed {
    say!(
        ctx,
        "newton: condensed path: {why}; solving on the plain path"
    );
    summary.outcome = "fallback";
    summary.fallback_reason = Some(why);
    Condensed::Fallback(summary)
}

/// K_p: A with every Dirichlet-free rigid mode pinned and no contact row, factorised, and
/// w₀ = K_p⁻¹ f. Returns the free modes (with K_p's pins), this rank's rows of w₀ and of
/// K_p's right-hand side. Collective.
fn factorise_base(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    s: &NewtonSettings,
) -> Result<(FreeModes, Vec<f64>, Vec<f64>), RunError> {
    let (mesh, layout, b, sys) = (p.mesh, p.layout, p.boundary, p.sys);
    let mut free = FreeModes::new(ctx, mesh, layout, p.fixed, b, &reduced.f_local, s.rigid);
    free.update(ctx, mesh, layout, &[0.0; 36])?;
    reduced.set_pins(sys, layout, free.pins())?;
    let empty = ActiveSet {
        normal: vec![false; b.nodes.len()],
        tangential: None,
    };
    reduced.write(ctx, sys, layout, b, &empty, free.pins())?;
    let solved = reduced.solve_current()?;
    if !solved.info.converged() {
        return Err(RunError::Failed(format!(
            "the factorisation of the stiffness for the condensed contact solve failed ({})",
            solved.info.reason_name
        )));
    }
    Ok((free, reduced.solution_local()?, reduced.rhs_local()?))
}

/// The start set of this rank's contact nodes: the warm start's final set, or the case's
/// start as the plain path forms it. Local.
fn start_set(
    p: &ContactProblem,
    s: &NewtonSettings,
    free: &FreeModes,
    warm: Option<&WarmStart>,
) -> Vec<bool> {
    match warm {
        Some(w) => w.nodes.iter().map(|r| r.active).collect(),
        None => {
            let init = super::newton::auto_start(s.section.init, false, free);
            let (b, dim) = (p.boundary, p.mesh.dim);
            ActiveSet::initial(b, init, Law::Frictionless, s.c, p.mesh.extent(), dim).normal
        }
    }
}

/// Every contact node of c_h (all ranks', in c_h's global order) as the dense algorithm sees
/// it: first dof row, normal, gap, d₀ = nᵀw₀, start flag, the free modes' normal parts G.
struct Candidates {
    all: Vec<f64>,
    n: usize,
    mz: usize,
}

/// Values per candidate record: row, n (3), gap, d₀, start, G (6).
const REC: usize = 13;

impl Candidates {
    /// One all-gather. Collective.
    fn gather(
        ctx: &Ctx,
        b: &ContactBoundary,
        free: &FreeModes,
        start: &[bool],
        w0: &[f64],
        dim: usize,
    ) -> Candidates {
        let (z, modes) = (free.dirichlet_free(), free.rigid_modes());
        let mz = z.ncols();
        let mut mine = Vec::with_capacity(b.nodes.len() * REC);
        for (k, &a) in b.nodes.iter().zip(start) {
            let d0: f64 = (0..dim).map(|j| k.frame.n[j] * w0[k.local_row + j]).sum();
            let row = modes.direction_row(&k.x, &k.frame.n);
            let mut gz = [0.0; 6];
            for (c, g) in gz.iter_mut().enumerate().take(mz) {
                *g = (0..modes.m).map(|j| row[j] * z[(j, c)]).sum();
            }
            let n = k.frame.n;
            let flag = if a { 1.0 } else { 0.0 };
            mine.extend_from_slice(&[k.row as f64, n[0], n[1], n[2], k.gap, d0, flag]);
            mine.extend_from_slice(&gz);
        }
        let all = ctx.all_gather_varcount(&mine);
        let n = all.len() / REC;
        Candidates { all, n, mz }
    }

    fn rec(&self, i: usize) -> &[f64] {
        &self.all[i * REC..(i + 1) * REC]
    }
    fn row(&self, i: usize) -> usize {
        self.rec(i)[0] as usize
    }
    fn normal(&self, i: usize, a: usize) -> f64 {
        self.rec(i)[1 + a]
    }
    fn gap(&self, i: usize) -> f64 {
        self.rec(i)[4]
    }
    fn d0(&self, i: usize) -> f64 {
        self.rec(i)[5]
    }
    fn start(&self, i: usize) -> bool {
        self.rec(i)[6] != 0.0
    }
    fn g(&self, i: usize, c: usize) -> f64 {
        self.rec(i)[7 + c]
    }
}

/// The compliance C = Nᵀ K_p⁻¹ N on a growing candidate set (the matrix on rank 0 only).
struct Compliance {
    in_s: Vec<bool>,
    /// The candidates in the order of C's rows and columns.
    list: Vec<usize>,
    cmat: DMatrix<f64>,
}

impl Compliance {
    fn new(n: usize) -> Compliance {
        Compliance {
            in_s: vec![false; n],
            list: Vec::new(),
            cmat: DMatrix::zeros(0, 0),
        }
    }

    /// Adds the candidates `new`: their columns of K_p⁻¹ (all rows of the grown set; of the
    /// new-new pairs only those on and below the diagonal, since K_p⁻¹ is symmetric and the
    /// fewer rows a column asks for, the more of its backward solve MUMPS prunes) from MUMPS'
    /// selected inverse. Returns the number of entries requested. Collective.
    fn grow(
        &mut self,
        ctx: &Ctx,
        reduced: &ReducedSystem,
        cand: &Candidates,
        new: &[usize],
        dim: usize,
        n_rows: usize,
    ) -> Result<usize, RunError> {
        let root = ctx.rank == 0;
        let old_len = self.list.len();
        for &i in new {
            self.in_s[i] = true;
        }
        self.list.extend_from_slice(new);
        let ns = self.list.len();
        // (position in the list, global row, normal component) of every candidate dof
        let dofs: Vec<(usize, usize, f64)> = self
            .list
            .iter()
            .enumerate()
            .flat_map(|(q, &i)| {
                (0..dim)
                    .filter(move |&a| cand.normal(i, a) != 0.0)
                    .map(move |a| (q, cand.row(i) + a, cand.normal(i, a)))
            })
            .collect();
        let new_dofs: Vec<&(usize, usize, f64)> = dofs.iter().filter(|d| d.0 >= old_len).collect();
        let old_rows: Vec<usize> = dofs.iter().filter(|d| d.0 < old_len).map(|d| d.1).collect();
        let request: InverseRequest = if root {
            new_dofs
                .iter()
                .map(|d| {
                    let mut r: Vec<usize> = old_rows.clone();
                    r.extend(new_dofs.iter().map(|e| e.1).filter(|&x| x >= d.1));
                    r.sort_unstable();
                    (d.1, r)
                })
                .collect()
        } else {
            Vec::new()
        };
        let entries = reduced
            .ksp()
            .mumps_inverse_entries(ctx.comm(), n_rows, root, &request)?;
        if root {
            let of_row: std::collections::HashMap<usize, (usize, f64)> =
                dofs.iter().map(|&(q, r, ni)| (r, (q, ni))).collect();
            let mut grown = DMatrix::<f64>::zeros(ns, ns);
            grown
                .view_mut((0, 0), (old_len, old_len))
                .copy_from(&self.cmat);
            for (col, &&(qj, _, nj)) in new_dofs.iter().enumerate() {
                let rj = request[col].0;
                for (&ri, &v) in request[col].1.iter().zip(&entries[col]) {
                    let (qi, ni) = of_row[&ri];
                    let x = ni * nj * v;
                    grown[(qi, qj)] += x;
                    if qi >= old_len && ri != rj {
                        grown[(qj, qi)] += x; // the mirror entry of a new-new pair
                    }
                }
            }
            for qj in old_len..ns {
                for qi in 0..old_len {
                    grown[(qj, qi)] = grown[(qi, qj)]; // K_p⁻¹ symmetric
                }
            }
            self.cmat = grown;
        }
        Ok(request.iter().map(|r| r.1.len()).sum())
    }
}

/// Algorithm 1 on the candidates' dense system, from `active`, on rank 0; the outcome
/// broadcast to every rank. Collective.
fn dense_round(
    ctx: &Ctx,
    cand: &Candidates,
    comp: &Compliance,
    free: &FreeModes,
    s: &NewtonSettings,
    active: &[bool],
) -> DenseRun {
    let (ns, mz) = (comp.list.len(), cand.mz);
    let mut packed: Vec<f64> = Vec::new();
    if ctx.rank == 0 {
        let (z, modes) = (free.dirichlet_free(), free.rigid_modes());
        let (load, load_scale) = free.load();
        let phi: Vec<f64> = (0..mz)
            .map(|c| (0..modes.m).map(|j| z[(j, c)] * load[j]).sum())
            .collect();
        let list = &comp.list;
        let g = DMatrix::from_fn(ns, mz, |q, c| cand.g(list[q], c));
        let d0: Vec<f64> = list.iter().map(|&i| cand.d0(i)).collect();
        let gap: Vec<f64> = list.iter().map(|&i| cand.gap(i)).collect();
        let start: Vec<bool> = list.iter().map(|&i| active[i]).collect();
        let dense = Dense {
            cmat: &comp.cmat,
            d0: &d0,
            gap: &gap,
            g: &g,
            phi: &phi,
            load_scale,
            c: s.c,
            max_steps: s.section.max_steps,
        };
        packed = dense.run(start).pack(ns, mz);
    }
    ctx.broadcast_f64s(&mut packed);
    DenseRun::unpack(&packed, ns, mz)
}

/// The dense steps of one round into the history (numbered on) and the log.
fn record_steps(
    ctx: &Ctx,
    history: &mut Vec<StepInfo>,
    run: &DenseRun,
    candidates: usize,
    pinned: usize,
) {
    let base = history.len();
    for h in &run.steps {
        say!(
            ctx,
            "newton {:3}: |A_n| = {:6}  changed {:6}  |C_n| = {:.3e}  condensed, {candidates} \
             candidates ({:.4} s)",
            base + h.0,
            h.1,
            h.2,
            h.3,
            h.4
        );
        history.push(StepInfo {
            step: base + h.0,
            active: h.1,
            changed: h.2,
            residual: h.3,
            solve_seconds: h.4,
            solve: SolveKind::Condensed,
            iterations: 0,
            reuse: None,
            amg: None,
            pinned,
            states: None,
            du_rel: None,
        });
    }
}

/// The expanded iterate of a round: (3.28) on w with the set, the rigid motion ρ that u = w + ρ
/// carries, the pins of the set's free modes, and the global indices of the nodes (3.23)
/// changes.
struct Expanded {
    it: Iterate,
    rho: Motion,
    pins: Vec<Pin>,
    changed: Vec<u64>,
}

/// Expansion: w = K_p⁻¹ (f − N λ_n) (one triangular solve; the solution stays in `reduced`),
/// ρ = R z α normalised at the pins the plain path chooses for the set (the modes the set
/// leaves free are balanced, else the dense iteration had not stopped), then (3.28) and (3.23)
/// on w with the gaps after ρ, as the plain path does, so that a large rigid motion does not
/// round λ. `(lambda, active)` of every contact node in c_h's global order. Collective.
#[allow(clippy::too_many_arguments)]
fn expand(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    s: &NewtonSettings,
    free: &FreeModes,
    rhs0: &[f64],
    (lambda, active): (&[f64], &[bool]),
    alpha: &[f64],
) -> Result<Expanded, RunError> {
    let (mesh, layout, b, sys) = (p.mesh, p.layout, p.boundary, p.sys);
    let (dim, off) = (mesh.dim, b.offset);
    let mut rhs = rhs0.to_vec();
    for (i, k) in b.nodes.iter().enumerate() {
        for j in 0..dim {
            rhs[k.local_row + j] -= k.frame.n[j] * lambda[off + i];
        }
    }
    reduced.set_rhs_local(&rhs)?;
    let solved = reduced.solve_current()?;
    if !solved.info.converged() {
        return Err(RunError::Failed(format!(
            "the expansion solve of the condensed contact solve failed ({})",
            solved.info.reason_name
        )));
    }
    let z = free.dirichlet_free();
    let mut rho = [0.0; 6];
    for (j, r) in rho.iter_mut().enumerate().take(free.rigid_modes().m) {
        *r = (0..z.ncols()).map(|c| z[(j, c)] * alpha[c]).sum();
    }
    let set = ActiveSet {
        normal: active[off..off + b.nodes.len()].to_vec(),
        tangential: None,
    };
    let gram = set.summarise(ctx, b, free.modes(), dim).gram;
    let mut fin = FreeModes::new(ctx, mesh, layout, p.fixed, b, &reduced.f_local, s.rigid);
    fin.update(ctx, mesh, layout, &gram)?;
    if !fin.pins().is_empty() {
        let idx: Vec<PInt> = fin
            .pins()
            .iter()
            .map(|&(v, k)| (v * dim + k) as PInt)
            .collect();
        let at = reduced.solution_at(&idx)?;
        let corr = fin.motion_to_zero_pins(&at, &rho);
        for (x, c) in rho.iter_mut().zip(corr) {
            *x += c;
        }
    }
    let mut shifted = b.clone();
    free.shift(b, &rho, &mut shifted);
    let mut it = Iterate::new(b.nodes.len(), rhs.len(), false);
    reduced.recover(sys, &shifted, &set, &mut it)?; // (3.28)
    let update = set.update(&it, &shifted, Law::Frictionless, s.c, dim); // (3.23)
    let changed_here: Vec<u64> = set
        .normal
        .iter()
        .zip(&update.next.normal)
        .enumerate()
        .filter(|(_, (a, b))| a != b)
        .map(|(i, _)| (off + i) as u64)
        .collect();
    Ok(Expanded {
        it,
        rho,
        pins: fin.pins().to_vec(),
        changed: ctx.all_gather_varcount(&changed_here),
    })
}

/// Algorithm 1 on the condensed system (module note): C (n × n), d₀, the gaps, the free
/// modes' normal parts G (n × m_z), the load in them φ = zᵀ Rᵀ f and its scale, c.
pub struct Dense<'a> {
    pub cmat: &'a DMatrix<f64>,
    pub d0: &'a [f64],
    pub gap: &'a [f64],
    pub g: &'a DMatrix<f64>,
    pub phi: &'a [f64],
    pub load_scale: f64,
    pub c: f64,
    pub max_steps: usize,
}

/// How the dense iteration ended.
#[derive(Debug, Clone, PartialEq)]
pub enum End {
    Converged,
    /// The load is unbalanced in a mode no contact node can fix (the unbalanced load).
    NoSupport(f64),
    Fallback(String),
}

/// The dense iteration's result: final set, λ_n, the free modes' coefficients α, u_n, and per
/// step (step, |A_n|, changed, ‖C_n‖, seconds).
#[derive(Debug, Clone)]
pub struct DenseRun {
    pub active: Vec<bool>,
    pub lambda: Vec<f64>,
    pub alpha: Vec<f64>,
    pub u_n: Vec<f64>,
    pub steps: Vec<(usize, usize, usize, f64, f64)>,
    pub end: End,
}

impl DenseRun {
    /// One flat vector for the broadcast.
    fn pack(&self, n: usize, mz: usize) -> Vec<f64> {
        let mut v = Vec::with_capacity(4 * n + mz + 5 * self.steps.len() + 3);
        let (code, x) = match &self.end {
            End::Converged => (0.0, 0.0),
            End::NoSupport(r) => (1.0, *r),
            End::Fallback(_) => (2.0, 0.0),
        };
        v.extend_from_slice(&[code, x, self.steps.len() as f64]);
        v.extend(self.active.iter().map(|&a| if a { 1.0 } else { 0.0 }));
        v.extend_from_slice(&self.lambda);
        v.extend_from_slice(&self.u_n);
        v.extend_from_slice(&self.alpha[..mz]);
        for s in &self.steps {
            v.extend_from_slice(&[s.0 as f64, s.1 as f64, s.2 as f64, s.3, s.4]);
        }
        if let End::Fallback(why) = &self.end {
            v.extend(why.bytes().map(f64::from));
        }
        v
    }

    fn unpack(v: &[f64], n: usize, mz: usize) -> DenseRun {
        let steps_n = v[2] as usize;
        let mut p = 3;
        let mut take = |len: usize| {
            let s = &v[p..p + len];
            p += len;
            s.to_vec()
        };
        let active = take(n).iter().map(|&x| x != 0.0).collect();
        let lambda = take(n);
        let u_n = take(n);
        let alpha = take(mz);
        let steps = (0..steps_n)
            .map(|_| {
                let s = take(5);
                (s[0] as usize, s[1] as usize, s[2] as usize, s[3], s[4])
            })
            .collect();
        let end = match v[0] as i32 {
            0 => End::Converged,
            1 => End::NoSupport(v[1]),
            _ => End::Fallback(
                v[p..]
                    .iter()
                    .map(|&b| char::from(b as u8))
                    .collect::<String>(),
            ),
        };
        DenseRun {
            active,
            lambda,
            alpha,
            u_n,
            steps,
            end,
        }
    }
}

impl Dense<'_> {
    /// Algorithm 1 from the set `active`: solve the set's dense system, λ_n and u_n of every
    /// candidate, update by (3.23); stop when no node changes (with the balance test of the
    /// modes the set leaves free, as the plain path). Local.
    pub fn run(&self, mut active: Vec<bool>) -> DenseRun {
        let n = self.d0.len();
        let mz = self.g.ncols();
        let mut seen: HashSet<Vec<bool>> = HashSet::new();
        seen.insert(active.clone());
        let mut steps = Vec::new();
        let out = |active: Vec<bool>, lambda, alpha, u_n, steps, end| DenseRun {
            active,
            lambda,
            alpha,
            u_n,
            steps,
            end,
        };
        for step in 1..=self.max_steps {
            let t = Instant::now();
            let (lambda, alpha, u_n, free_dirs) = match self.solve_set(&active) {
                Some(x) => x,
                None => {
                    return out(
                        active,
                        vec![0.0; n],
                        vec![0.0; mz],
                        vec![0.0; n],
                        steps,
                        End::Fallback(format!("the dense system of step {step} is singular")),
                    )
                }
            };
            let mut next = active.clone();
            let mut changed = 0;
            let mut res2 = 0.0;
            for i in 0..n {
                let cn = c_n(u_n[i], lambda[i], self.gap[i], self.c); // (3.21)
                res2 += cn * cn;
                next[i] = normal_active(u_n[i], lambda[i], self.gap[i], self.c); // (3.23)
                changed += usize::from(next[i] != active[i]);
            }
            let n_active = active.iter().filter(|&&a| a).count();
            steps.push((
                step,
                n_active,
                changed,
                res2.sqrt(),
                t.elapsed().as_secs_f64(),
            ));
            if changed == 0 {
                match self.balance(&active, &u_n, &free_dirs) {
                    None => return out(active, lambda, alpha, u_n, steps, End::Converged),
                    Some(Ok(i)) => next[i] = true,
                    Some(Err(r)) => {
                        return out(active, lambda, alpha, u_n, steps, End::NoSupport(r))
                    }
                }
            }
            if !seen.insert(next.clone()) {
                return out(
                    active,
                    lambda,
                    alpha,
                    u_n,
                    steps,
                    End::Fallback(format!("the set of step {} recurs (cycling)", step + 1)),
                );
            }
            active = next;
        }
        let n_active = active.iter().filter(|&&a| a).count();
        out(
            active,
            vec![0.0; n],
            vec![0.0; mz],
            vec![0.0; n],
            steps,
            End::Fallback(format!(
                "no convergence in newton.max_steps = {} dense steps ({n_active} active)",
                self.max_steps
            )),
        )
    }

    /// The system of set A: [C_AA, −H; −Hᵀ, 0] [λ_A; β] = [g_A + d₀_A; −V_fᵀ φ] with H = G_A V_f,
    /// V_f the modes A fixes (α = V_f β; the others stay pinned). Returns λ_n (0 off A), α,
    /// u_n = d₀ − C λ + G α, and V_u (the modes A leaves free, m_z × ·). `None` if singular.
    #[allow(clippy::type_complexity)]
    fn solve_set(&self, active: &[bool]) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>, DMatrix<f64>)> {
        let n = self.d0.len();
        let mz = self.g.ncols();
        let idx: Vec<usize> = (0..n).filter(|&i| active[i]).collect();
        let na = idx.len();
        let ga = DMatrix::from_fn(na, mz, |r, c| self.g[(idx[r], c)]);
        let (vf, vu) = split_modes(&(ga.transpose() * &ga), mz);
        let nf = vf.ncols();
        let h = &ga * &vf;
        let dimn = na + nf;
        let mut m = DMatrix::<f64>::zeros(dimn, dimn);
        let mut rhs = DVector::<f64>::zeros(dimn);
        for (r, &i) in idx.iter().enumerate() {
            for (q, &j) in idx.iter().enumerate() {
                m[(r, q)] = self.cmat[(i, j)];
            }
            for c in 0..nf {
                m[(r, na + c)] = -h[(r, c)];
                m[(na + c, r)] = -h[(r, c)];
            }
            rhs[r] = self.gap[i] + self.d0[i];
        }
        let phi = DVector::from_column_slice(self.phi);
        let pf = vf.transpose() * phi;
        for c in 0..nf {
            rhs[na + c] = -pf[c];
        }
        let x = if dimn == 0 {
            DVector::zeros(0)
        } else {
            let lu = m.lu();
            let x = lu.solve(&rhs)?;
            if !x.iter().all(|v| v.is_finite()) {
                return None;
            }
            x
        };
        let mut lambda = vec![0.0; n];
        for (r, &i) in idx.iter().enumerate() {
            lambda[i] = x[r];
        }
        let beta = DVector::from_iterator(nf, (0..nf).map(|c| x[na + c]));
        let alpha = &vf * beta;
        let la = DVector::from_column_slice(&lambda);
        let un = DVector::from_column_slice(self.d0) - self.cmat * la + self.g * &alpha;
        Some((
            lambda,
            alpha.as_slice().to_vec(),
            un.as_slice().to_vec(),
            vu,
        ))
    }

    /// The plain path's balance test on the modes the set leaves free (`vu`): `None` balanced;
    /// `Some(Ok(i))` the inactive node a rigid motion along the unbalanced load brings into
    /// contact first; `Some(Err(r))` no node approaches (no support, unbalanced load r).
    fn balance(
        &self,
        active: &[bool],
        u_n: &[f64],
        vu: &DMatrix<f64>,
    ) -> Option<Result<usize, f64>> {
        if vu.ncols() == 0 {
            return None;
        }
        let phi = DVector::from_column_slice(self.phi);
        let pu = vu.transpose() * phi;
        let norm = pu.norm();
        if norm <= BALANCE_RTOL * self.load_scale {
            return None;
        }
        let dir = vu * pu / norm; // motion per unit length, in z coordinates
        let mut best: Option<(f64, usize)> = None;
        for i in 0..active.len() {
            if active[i] {
                continue;
            }
            let speed = -(0..dir.len()).map(|c| self.g[(i, c)] * dir[c]).sum::<f64>();
            if speed <= 1e-12 {
                continue;
            }
            let a = (u_n[i] + self.gap[i]).max(0.0) / speed;
            if best.is_none_or(|(b, _)| a < b) {
                best = Some((a, i));
            }
        }
        Some(best.map(|(_, i)| i).ok_or(norm))
    }
}

/// The modes (columns of the m_z × m_z identity's eigenbasis of the Gram matrix `gram`) that
/// a set fixes (eigenvalue above 1e-9 of the largest, at least 1e-9) and those it leaves free.
fn split_modes(gram: &DMatrix<f64>, mz: usize) -> (DMatrix<f64>, DMatrix<f64>) {
    if mz == 0 {
        return (DMatrix::zeros(0, 0), DMatrix::zeros(0, 0));
    }
    let eig = SymmetricEigen::new(gram.clone());
    let lmax = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let tol = 1e-9 * lmax.max(1.0);
    let fixed: Vec<usize> = (0..mz).filter(|&i| eig.eigenvalues[i] >= tol).collect();
    let loose: Vec<usize> = (0..mz).filter(|&i| eig.eigenvalues[i] < tol).collect();
    let pick = |cols: &[usize]| {
        let mut q = DMatrix::zeros(mz, cols.len());
        for (c, &i) in cols.iter().enumerate() {
            q.set_column(c, &eig.eigenvectors.column(i));
        }
        q
    };
    (pick(&fixed), pick(&loose))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two springs of compliance 1 under a load pressing both onto an obstacle at gap 0 and a
    /// third far away: the dense Algorithm 1 finds the set and λ by hand.
    #[test]
    fn dense_algorithm1_on_independent_springs() {
        // u_n = d0 − C λ; node 0 and 1 would penetrate (d0 < −g), node 2 not.
        let cmat = DMatrix::<f64>::identity(3, 3);
        let d0 = [-1.0, -0.5, 0.2];
        let gap = [0.0, 0.1, 0.0];
        let g = DMatrix::<f64>::zeros(3, 0);
        let dense = Dense {
            cmat: &cmat,
            d0: &d0,
            gap: &gap,
            g: &g,
            phi: &[],
            load_scale: 1.0,
            c: 1.0,
            max_steps: 20,
        };
        let run = dense.run(vec![false; 3]);
        assert_eq!(run.end, End::Converged);
        assert_eq!(run.active, vec![true, true, false]);
        // u_n = −g on A: λ = d0 + g (≤ 0, pressing)
        assert!((run.lambda[0] - -1.0).abs() < 1e-15);
        assert!((run.lambda[1] - -0.4).abs() < 1e-15);
        assert_eq!(run.lambda[2], 0.0);
        assert!((run.u_n[2] - 0.2).abs() < 1e-15);
    }

    /// A floating "body" of two uncoupled nodes with one free translation along the normal: the
    /// load φ must be carried by the contact (Σ λ = φ); from the empty set the balance test
    /// activates the node that touches first, then the set converges.
    #[test]
    fn dense_algorithm1_floating_translation() {
        let cmat = DMatrix::<f64>::identity(2, 2);
        let d0 = [0.0, 0.0];
        let gap = [0.0, 0.5];
        // the translation moves both normal displacements equally
        let g = DMatrix::from_row_slice(2, 1, &[1.0, 1.0]);
        let phi = [-1.0]; // Gᵀ λ = φ: the load presses with 1
        let dense = Dense {
            cmat: &cmat,
            d0: &d0,
            gap: &gap,
            g: &g,
            phi: &phi,
            load_scale: 1.0,
            c: 1.0,
            max_steps: 20,
        };
        let run = dense.run(vec![false; 2]);
        assert_eq!(run.end, End::Converged, "{run:?}");
        // node 0 alone carries λ = −1, u_n,0 = 0 = −λ + α → α = −1; node 1: u_n = α = −1 < −0.5
        // penetrates → both active: λ0 + λ1 = −1, −λ0 + α = 0, −λ1 + α = −0.5 → α = −0.75
        assert_eq!(run.active, vec![true, true]);
        let s: f64 = run.lambda.iter().sum();
        assert!((s - -1.0).abs() < 1e-14);
        assert!((run.alpha[0] - -0.75).abs() < 1e-14);
        assert!((run.u_n[0] + gap[0]).abs() < 1e-14 && (run.u_n[1] + gap[1]).abs() < 1e-14);
    }

    #[test]
    fn dense_no_support_when_the_load_pulls_away() {
        let cmat = DMatrix::<f64>::identity(1, 1);
        let g = DMatrix::from_row_slice(1, 1, &[1.0]);
        let dense = Dense {
            cmat: &cmat,
            d0: &[0.0],
            gap: &[0.0],
            g: &g,
            phi: &[1.0],
            load_scale: 1.0,
            c: 1.0,
            max_steps: 20,
        };
        let run = dense.run(vec![false]);
        assert!(matches!(run.end, End::NoSupport(_)), "{run:?}");
    }

    #[test]
    fn pack_round_trip() {
        let run = DenseRun {
            active: vec![true, false],
            lambda: vec![-1.0, 0.0],
            alpha: vec![0.5],
            u_n: vec![0.0, 0.3],
            steps: vec![(1, 0, 1, 0.1, 0.01), (2, 1, 0, 0.0, 0.02)],
            end: End::Fallback("cycling".into()),
        };
        let back = DenseRun::unpack(&run.pack(2, 1), 2, 1);
        assert_eq!(back.active, run.active);
        assert_eq!(back.lambda, run.lambda);
        assert_eq!(back.alpha, run.alpha);
        assert_eq!(back.u_n, run.u_n);
        assert_eq!(back.steps, run.steps);
        assert_eq!(back.end, run.end);
    }
}
