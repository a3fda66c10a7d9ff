//! Algorithm 1 on the contact unknowns alone (frictionless, direct preset): one factorisation
//! of the stiffness with every rigid mode that Dirichlet data leave free pinned, K_p, by MUMPS
//! directly, in the candidate contact nodes' frames (Qᵀ K_p Q, normal first) and with the Schur
//! complement S on the candidates' normal dofs alone (ICNTL(19)); K_p⁻¹ restricted to those dofs
//! is S⁻¹, so the compliance is C = Nᵀ K_p⁻¹ N = S⁻¹, one dense Cholesky and inversion (LAPACK)
//! of the size of the candidate set; every step of Algorithm 1 is then a dense solve of the
//! active nodes' block; at the end MUMPS' condensation and expansion solves give u.
//!
//! The step count: with newton.init = "auto" and no warm start, Algorithm 1 first runs on
//! coarse subsets of the candidates (nested iteration, [`Dense::run_nested`]), each level
//! starting the next; the steps on the candidates themselves are those counted.
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
//! Collectives: the gathering of the candidates (one all-gather), MUMPS' factorisation and
//! three solve phases (the right-hand sides gathered on rank 0, the solution scattered back),
//! two broadcasts (S's definiteness, the dense result), one MatMult.

use super::active_set::{ActiveSet, Iterate, Law};
use super::boundary::ContactBoundary;
use super::coulomb_condensed::CoulombCondensedSummary;
use super::dense::{guarded, Dense, DenseRun, End, Primal};
use super::halfspace::{self, Located};
use super::plain_path::{
    add_motion, ContactProblem, NewtonResult, NewtonSettings, StepInfo, WarmStart,
};
use super::rigid::{FreeModes, Motion, Pin};
use super::step_system::{ReducedSystem, SolveKind};
use crate::case::NewtonInit;
use crate::contact::Frame;
use crate::error::RunError;
use crate::linsolve::NumericSchur;
use crate::par::Ctx;
use crate::petsc::lapack::DenseCholesky;
use crate::petsc::mumps::NodeBases;
use crate::petsc::ndfactor::node_order;
use crate::petsc::PInt;
use crate::say;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use std::borrow::Cow;
use std::collections::HashSet;
use std::time::Instant;

/// More contact nodes than this and the condensed path is not tried (every rank holds a
/// record of 15 values per contact node).
pub const MAX_CONTACT_NODES: usize = 100_000;

/// More Schur variables (the candidates' normal dofs: one per candidate) than this and the
/// plain path takes over before anything is factorised: rank 0 holds S (then C) as one dense
/// matrix of their square (8 000: 512 MB), and the dense work grows as their cube (see also
/// DENSE_FLOOR_FLOPS).
pub const MAX_SCHUR_DOFS: usize = 8000;

/// [`MAX_SCHUR_DOFS`], or the test-only limit that replaces it (`crate::fault::limit`).
fn max_schur_dofs() -> usize {
    crate::fault::limit("MAX_SCHUR_DOFS", MAX_SCHUR_DOFS)
}

/// Dense work (n³ flops for the compliance of n candidates) always allowed: about 0.1 s of
/// LAPACK on one core. Beyond it the candidates must cost no more than the factorisation of
/// K_p (MUMPS' analysis estimate): else the plain path runs.
const DENSE_FLOOR_FLOPS: f64 = 1e9;

/// In 2D the dense work may be this many times the factorisation's flops: a dense flop costs
/// a fraction of one of MUMPS' on a 2D body (small fronts). Measured on the held Hertz disk at
/// 698 352 unknowns with Coulomb (2026-11-27), 2 ranks, OpenBLAS' AVX-512 kernels: K_p's
/// factorisation 1.1e10 flops, about 1.4 s per plain Newton step; the dense work on 2 000
/// candidates with every dof (n³ = 6.4e10) 1.6 s, about one factorisation's time (a ratio of
/// about 6). 8 lets the dense work cost up to about 1.4 factorisations: the path it saves
/// costs 10 or more (that case: 12 plain steps after the frictionless solution, 34.0 s in
/// all, against 9.7 s condensed). Earlier (LAPACK at 13.6 GFlop/s on one core against MUMPS'
/// 0.8 GFlop/s at 171 602 unknowns) it was 4. 3D fronts are dense enough for BLAS-3 rates:
/// there the ratio stays 1 (not measured beyond).
const DENSE_SPEEDUP_2D: f64 = 8.0;

/// The first candidate set: the 1/FIRST_FRACTION of the contact nodes with the smallest gaps.
const FIRST_FRACTION: usize = 8;

/// The first candidate set holds at least this many contact nodes (all if fewer).
const MIN_CANDIDATES: usize = 64;

/// Where the half-space model located the contact zone (halfspace::locate), the first
/// candidates hold at least (1 + 1/LOCATED_MARGIN) times the nodes it put in contact: its zone
/// is that of a coarse model without the load's own deformation (measured: the rolling Hertz
/// disk, 42 k to 345 k unknowns, 124 / 496 / 992 located, 124 / 495 / 991 in the final
/// Coulomb set; the floating Hertz disk at 345 k, 993 located, 969 frictionless and 947 with
/// Coulomb), and the dense compliance costs the cube of the candidates' dofs (with a fourth
/// more, the floating disk's Coulomb candidates at 345 k exceed what pays: the plain path).
const LOCATED_MARGIN: usize = 8;

/// Rounds of candidate growth before the plain path takes over.
const MAX_ROUNDS: usize = 8;

/// A predicted contact zone is wide where the dense compliance of its nodes and their margin
/// beyond (1/LOCATED_MARGIN more), `per` dofs each, would cost more than `max_flops`: before
/// anything is factorised the dense work always allowed (DENSE_FLOOR_FLOPS, from about 890
/// nodes with one dof each), after a
/// factorisation the dense work that pays against it ([`Compliance::grow`]). Its interior is
/// then held on the obstacle in the factorised matrix (u_n = −g there, as the plain path's
/// reduced system (3.29) writes an active node), and only its edge band and the nodes beyond
/// are Schur variables: the Schur complement's memory and the dense work grow with the zone's
/// edge, not its area.
fn wide(zone: usize, per: usize, max_flops: f64) -> bool {
    (((zone + zone / LOCATED_MARGIN) * per) as f64).powi(3) > max_flops
}

/// The edge band of a held zone: the 1/BAND_FRACTION of its nodes nearest to its edge (in 2D
/// 1/16 of the zone's width on either side, in 3D an annulus 6 % of a round zone's radius
/// wide); with the nodes beyond the zone (1/LOCATED_MARGIN of its count) they are the Schur
/// variables. The half-space model's zone edge was 2.3 % (its coarse levels) and 0.5 % of the
/// zone's width from the final one on the 2D Hertz disk at 10–50 × its load, 1.5 % of the
/// radius on the 3D ball; a held node that (3.23) releases, or a node beyond that comes into
/// contact, starts a new pass from the set (3.23) gives.
const BAND_FRACTION: usize = 8;

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
    /// Variables of the Schur complement (every dof of every candidate), last round.
    pub schur_dofs: usize,
    /// Numeric factorisations of K_p with the Schur complement (one per round of candidates).
    pub factorisations: usize,
    /// The fill-reducing order, MUMPS' analysis and numeric factorisation of K_p with the
    /// Schur complement [s].
    pub factorisation_seconds: f64,
    /// Of which the nested-dissection order of K_p's node graph (Scotch on rank 0) [s].
    pub ordering_seconds: f64,
    /// Handing K_p to MUMPS, the condensation of f, the dense factorisation of S, C and d₀ [s].
    pub schur_seconds: f64,
    /// Algorithm 1's steps on the dense system [s].
    pub dense_seconds: f64,
    /// The expansion solve, (3.28) and the check of the final set [s].
    pub expansion_seconds: f64,
    /// Solve phases with the factorisation (condensations, expansions).
    pub solves: usize,
    /// A load step on the previous load step's factorisation (`factorisations` 0).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub factorisation_kept: bool,
    /// The nested start (newton.init = "auto", no warm start): per coarse level, coarsest
    /// first, its nodes and Algorithm 1's steps on it (dense; not counted in newton.steps).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub coarse_levels: Vec<CoarseLevel>,
    /// Coulomb's generalised Newton on the same candidates (friction, held bodies).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coulomb: Option<CoulombCondensedSummary>,
    /// The fallback came from the dense limits (the candidates' Schur dofs, the dense work
    /// against the factorisation's): the contact zone is too wide for the dense compliance.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub too_wide: bool,
    /// The dense steps ran in the primal form on S (dense::Primal): C = S⁻¹ would have cost
    /// more than the factorisation.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub primal: bool,
    /// A wide zone's interior held on the obstacle in K_p (the last pass; 0: none).
    #[serde(skip_serializing_if = "is_zero")]
    pub held_nodes: usize,
    /// Which nodes: [`tag_key`] of their gmsh tags (the last pass; absent: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub held_key: Option<u64>,
    /// Which nodes were the candidates (the last round): [`tag_key`] of their gmsh tags.
    pub candidates_key: u64,
}

/// A key of a set of contact nodes that does not depend on the partition or on the order the
/// nodes come in: the wrapping sum of a mix (splitmix64's finaliser) of their gmsh tags. Two
/// runs that held or took different nodes differ in it (but for a 2⁻⁶⁴ chance). Local.
pub fn tag_key(tags: impl Iterator<Item = u64>) -> u64 {
    tags.map(|t| {
        let mut z = t.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    })
    .fold(0u64, u64::wrapping_add)
}

pub(super) fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// One coarse level of the nested start.
#[derive(Debug, Clone, Serialize)]
pub struct CoarseLevel {
    pub nodes: usize,
    pub steps: usize,
}

impl CondensedSummary {
    pub(super) fn new(candidates: usize) -> CondensedSummary {
        CondensedSummary {
            outcome: "condensed",
            fallback_reason: None,
            candidates,
            schur_dofs: 0,
            factorisations: 0,
            factorisation_seconds: 0.0,
            ordering_seconds: 0.0,
            schur_seconds: 0.0,
            dense_seconds: 0.0,
            expansion_seconds: 0.0,
            solves: 0,
            factorisation_kept: false,
            coarse_levels: Vec::new(),
            coulomb: None,
            too_wide: false,
            primal: false,
            held_nodes: 0,
            held_key: None,
            candidates_key: 0,
        }
    }

    /// A round's factorisation into the record: `seconds` of the round so far, of which
    /// `comp.factorisation_seconds` the ordering, analysis and factorisation.
    fn record_factorisation(&mut self, comp: &Compliance, cand: &Candidates, seconds: f64) {
        self.factorisations += 1;
        self.solves += 1;
        self.factorisation_seconds += comp.factorisation_seconds;
        self.ordering_seconds = self.ordering_seconds.max(comp.ordering_seconds);
        self.schur_seconds += seconds - comp.factorisation_seconds;
        self.candidates = comp.list.len();
        self.candidates_key = tag_key(comp.list.iter().map(|&i| cand.tag(i)));
        self.schur_dofs = comp.list.len() * comp.per;
    }

    /// A load step on the previous step's factorisation into the record and the log: one
    /// condensation (`seconds`), no factorisation.
    fn record_kept(&mut self, ctx: &Ctx, comp: &Compliance, cand: &Candidates, seconds: f64) {
        self.solves += 1;
        self.schur_seconds += seconds;
        self.candidates = comp.list.len();
        self.candidates_key = tag_key(comp.list.iter().map(|&i| cand.tag(i)));
        self.schur_dofs = comp.list.len() * comp.per;
        say!(
            ctx,
            "newton: condensed: the previous load step's factorisation and compliance on {} \
             candidates, d₀ of this step ({seconds:.3} s)",
            self.candidates
        );
    }

    /// The nested start's coarse levels of a dense round, into the record and the log.
    fn record_coarse(&mut self, ctx: &Ctx, run: &DenseRun) {
        if run.coarse.is_empty() {
            return;
        }
        let levels: Vec<String> = run
            .coarse
            .iter()
            .map(|c| format!("{} nodes {} steps", c.0, c.1))
            .collect();
        say!(
            ctx,
            "newton: condensed: nested start on coarse subsets of the candidates: {}",
            levels.join(", ")
        );
        self.coarse_levels.extend(
            run.coarse
                .iter()
                .map(|&(nodes, steps)| CoarseLevel { nodes, steps }),
        );
    }

    /// The closing log line of a converged condensed solve (`n` contact nodes).
    fn log(&self, ctx: &Ctx, n: usize, active: usize) {
        let factorisation = if self.factorisation_kept {
            "the previous load step's factorisation".to_string()
        } else {
            format!(
                "factorisation {:.3} s (ordering {:.3} s)",
                self.factorisation_seconds, self.ordering_seconds
            )
        };
        let form = if self.primal {
            " (primal form on S)"
        } else {
            ""
        };
        say!(
            ctx,
            "newton: condensed: {} of {n} contact nodes as candidates, {active} active, \
             {factorisation}, Schur complement {:.3} s, dense{form} {:.3} s, expansion {:.3} s",
            self.candidates,
            self.schur_seconds,
            self.dense_seconds,
            self.expansion_seconds
        );
    }
}

/// What the condensed path returns: the solution, or the reason to run the plain path.
pub enum Condensed {
    Solved(Box<NewtonResult>, CondensedSummary),
    Fallback(CondensedSummary),
    /// [`solve_keeping`] without the frictionless steps: K_p factorised with the first
    /// candidates' Schur complement, nothing solved.
    Factorised(CondensedSummary),
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
    solve_keeping(ctx, p, reduced, s, warm, (1, true, None)).map(|(c, _)| c)
}

/// What a converged condensed solve with every dof of the candidates in the Schur complement
/// (`per` = d) leaves for a friction solve on the same candidates: the compliance with its
/// factorisation, the candidates, f on rank 0, the free modes (K_p's pins) and the
/// frictionless set and λ_n
/// over every contact node (c_h's global order).
pub(super) struct Kept {
    pub(super) comp: Compliance,
    pub(super) cand: Candidates,
    pub(super) f_root: Vec<f64>,
    pub(super) n_local: usize,
    pub(super) free: FreeModes,
    pub(super) lambda: Vec<f64>,
    pub(super) active: Vec<bool>,
    /// The nodes K_p holds on the obstacle, sticking (c_h's global order; empty: none).
    pub(super) held: Vec<bool>,
    /// The zone they were held in (c_h's global order; empty: none).
    pub(super) zone: Vec<bool>,
}

impl Kept {
    /// The kept factorisation holds a step with free modes `free` and candidates `cand`: the
    /// same pins, `per` Schur variables per candidate, and the kept candidates' rows and node
    /// frames (K_p was factorised in them). Local (on all-gathered data).
    fn holds(&self, free: &FreeModes, cand: &Candidates, per: usize) -> bool {
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

/// A friction solve's zone held sticking in K_p where every dof of its nodes is too many for
/// the dense limits ([`solve_keeping`]).
#[derive(Clone, Copy, Default)]
pub(super) struct Sticking<'a> {
    /// The zone of a pass before (c_h's global order; `None`: predicted, where needed).
    pub zone: Option<&'a [bool]>,
    /// Nodes never held and always candidates (c_h's global order; may be empty): a pass
    /// before found them changing state beyond its candidates (a held node that slips or leaves
    /// the obstacle, a node beyond that touches), or a load step's nodes that slipped in the
    /// step before.
    pub release: &'a [bool],
    /// The pass (from 0): a band of 2ᵏ/[`BAND_FRACTION`] of the zone's held part is left free.
    pub pass: u32,
    /// At most this many factorisations in this call (0: no bound); beyond, the plain path.
    pub factorisations: usize,
}

/// [`solve`] with `per` Schur variables per candidate (1: the normal dof; d: every dof, for
/// friction); with `per` > 1 a converged solve also returns what it [`Kept`] (with `per` = 1
/// it leaves it in `p.kept` for the next load step). A load step (`warm`) starts from the
/// previous step's factorisation where it holds ([`reused`]). Without `steps`
/// it stops after the first factorisation (`Factorised`; the start set and λ = 0 kept: a load
/// step of a friction solve starts from its warm start instead). With `stick` (friction,
/// `per` > 1) a zone too wide for every dof of its nodes has its interior held on the obstacle
/// and sticking (u_τ = u_ref), as a frictionless solve holds it on the obstacle, but for the
/// nodes it releases, which are candidates. Collective.
pub(super) fn solve_keeping(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    s: &NewtonSettings,
    warm: Option<&WarmStart>,
    (per, steps, stick): (usize, bool, Option<Sticking>),
) -> Result<(Condensed, Option<Kept>), RunError> {
    let fall = |c: Condensed| Ok((c, None));
    let (b, dim) = (p.boundary, p.mesh.dim);
    let mut summary = CondensedSummary::new(b.n_global);
    let free0 = FreeModes::new(ctx, p.mesh, p.layout, p.fixed, b, &reduced.f_local, s.rigid);
    refuse_floating_force(p, s, &free0)?;
    let start = start_set(p, s, &free0, warm);
    let located = locate(ctx, p, s, &free0, warm)?;
    let key = located.as_ref().map(|(k, _)| k.as_slice());
    let n_rows = p.layout.node_offsets.last().copied().unwrap_or(0) * dim;
    let nested = warm.is_none() && s.section.init == NewtonInit::Auto;
    let splits = splits_zones(p, s, warm, (per, steps, stick.is_some()));
    let sticking = stick.unwrap_or_default();
    // every contact node as the case starts (the zones' positions and order keys), gathered
    // once
    let all0 = splits.then(|| Candidates::gather(ctx, b, &free0, &start, key));
    // friction: a zone is held only where every dof of its nodes is too many for the dense
    // limits (below)
    let mut zone = match per {
        1 => predicted_zone(all0.as_ref(), &located, per),
        _ => sticking.zone.filter(|_| splits).map(<[bool]>::to_vec),
    };
    // a zone held sticking holds every rigid mode: no load is left for the contact to carry
    let held_sticking = NewtonSettings {
        carried: None,
        ..*s
    };
    let given = s;
    let mut order_kept = p.kept.take_order(); // a load step after a held zone's
    let mut rounds = 0;
    let mut history: Vec<StepInfo> = Vec::new();
    'pass: loop {
        let s = match per > 1 && zone.is_some() {
            true => &held_sticking,
            false => given,
        };
        let zoned = zone.as_deref();
        let mut pass = begin_pass(
            ctx,
            (p, &mut *reduced, warm),
            (&free0, all0.as_ref()),
            (&start, &located, per),
            (zoned, order_kept.take(), sticking),
            &mut summary,
        )?;
        for round in 1..=MAX_ROUNDS {
            rounds += 1;
            if rounds > MAX_ROUNDS {
                break 'pass;
            }
            let Pass {
                cand,
                growth,
                comp,
                condensation,
                f_root,
                ..
            } = &mut pass;
            let grown = factorise_round(
                ctx,
                reduced,
                (cand, comp, growth),
                &mut summary,
                (round, *condensation),
                (dim, n_rows, f_root),
            );
            if let Err(stop) = grown {
                let to_hold = stop.too_wide && per > 1 && splits && zone.is_none();
                let all = all0.as_ref();
                let instead = || hold_instead(ctx, &stop, (all, &located, per), &growth.active);
                if let Some(z) = to_hold.then(instead).flatten() {
                    zone = Some(z);
                    continue 'pass;
                }
                return fall(fallback_stop(ctx, summary, stop));
            }
            if !steps {
                summary.outcome = "factorised";
                let n = pass.cand.n;
                let kept = pass.keep(vec![0.0; n], zone);
                return Ok((Condensed::Factorised(summary), Some(kept)));
            }

            let first = nested && rounds == 1;
            let on = located.as_ref().map(|(_, on)| *on);
            let on = on.filter(|_| zone.is_none());
            let run = pass.dense(ctx, s, (first, on), (&mut summary, &mut history));
            let (cand, comp, free, growth) =
                (&pass.cand, &mut pass.comp, &pass.free, &mut pass.growth);
            let lambda = growth.take_dense(comp, &run);
            match judge(ctx, p, s, (free, comp, cand.n), growth, &run)? {
                Judged::Expand => {}
                Judged::Again => continue,
                Judged::Stop(stop) => return fall(fallback_stop(ctx, summary, stop)),
            }

            let t = Instant::now();
            let set = (lambda.as_slice(), growth.active.as_slice());
            let ex = match expand(
                ctx,
                p,
                reduced,
                (s, free, comp, cand),
                (&pass.f_root, pass.rhs0.len()),
                set,
                &run.alpha,
            )? {
                Ok(ex) => ex,
                Err(why) => return fall(fallback(ctx, summary, why)),
            };
            summary.solves += 2;
            summary.expansion_seconds += t.elapsed().as_secs_f64();
            if ex.changed.is_empty() {
                let n_active = growth.active.iter().filter(|&&a| a).count();
                summary.log(ctx, cand.n, n_active);
                let solved = finish(p, reduced, free, ex, history, summary)?;
                return Ok(keep_solved(p, solved, pass.keep(lambda, zone), per));
            }
            if let Some(next) =
                growth.next_pass(ctx, &ex.changed, (comp.max_flops, comp.per), splits)
            {
                let budget = (per > 1).then_some(sticking.factorisations);
                if budget.is_some_and(|b| b > 0 && summary.factorisations >= b) {
                    let n = summary.factorisations;
                    let why = format!("the held zone's set still changes after {n} factorisations");
                    return fall(fallback(ctx, summary, why));
                }
                zone = Some(next);
                order_kept = comp.node_order.take();
                continue 'pass;
            }
            if let Err(why) = growth.widen(ctx, &ex.changed, comp, round) {
                return fall(fallback(ctx, summary, why));
            }
        }
        break;
    }
    let why = format!("no final set in {MAX_ROUNDS} rounds of candidates");
    fall(fallback(ctx, summary, why))
}

/// Whether a wide zone's interior may be held on the obstacle in the factorised matrix:
/// frictionless (with the frictionless steps; a load step only where the step before kept no
/// factorisation or one with a held zone), or for friction (`per` > 1) sticking as well where
/// `stick` asks (a load step without the frictionless steps: its dense iteration starts from
/// the warm states; a zone is held there only where the candidates grow too wide); not under
/// force control. Local.
fn splits_zones(
    p: &ContactProblem,
    s: &NewtonSettings,
    warm: Option<&WarmStart>,
    (per, steps, stick): (usize, bool, bool),
) -> bool {
    let kept_allows = warm.is_none() || p.kept.is_empty() || p.kept.holds_zone();
    s.force.is_empty()
        && if per == 1 {
            steps && kept_allows && !s.estimate && s.carried.is_none()
        } else {
            stick && (steps || warm.is_some())
        }
}

/// The predicted zone of [`first_zone`] on every contact node as the case starts (`all0`,
/// where zones may be held), with the located zone's node count. Local.
fn predicted_zone(all0: Option<&Candidates>, located: &Located, per: usize) -> Option<Vec<bool>> {
    all0.and_then(|all| first_zone(all, located.as_ref().map(|(_, on)| *on), per))
}

/// Friction, where every dof of the candidates is too many (`stop`): the zone to hold sticking
/// instead, the predicted one ([`predicted_zone`]) or else the set the candidates grew to
/// (`grown`), where it is [`wide`]. Local (on all-gathered data; said in the log).
fn hold_instead(
    ctx: &Ctx,
    stop: &Stop,
    (all0, located, per): (Option<&Candidates>, &Located, usize),
    grown: &[bool],
) -> Option<Vec<bool>> {
    let zone = predicted_zone(all0, located, per).or_else(|| {
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

/// A converged solve's result and what it keeps: with `per` > 1 the kept compliance for the
/// friction solve; else the factorisation for the next load step (`p.kept`). Local.
fn keep_solved(
    p: &ContactProblem,
    solved: Condensed,
    kept: Kept,
    per: usize,
) -> (Condensed, Option<Kept>) {
    match per > 1 {
        true => (solved, Some(kept)),
        false => {
            // for the next load step (a held zone's too: its rows' values are in f)
            p.kept.put(kept);
            (solved, None)
        }
    }
}

/// One pass of the condensed path: K_p's free modes and right-hand side (this rank's rows and
/// f on rank 0) with the pass' held nodes, the candidates, their growth (which knows the held
/// nodes) and compliance, and the seconds of a load step's condensation on a kept
/// factorisation.
struct Pass {
    free: FreeModes,
    rhs0: Vec<f64>,
    f_root: Vec<f64>,
    cand: Candidates,
    growth: Growth,
    comp: Compliance,
    condensation: f64,
}

impl Pass {
    /// A round's dense steps ([`dense_round`]; `first`: nested, `located`: the located zone's
    /// node count), recorded in `summary` and the step `history`. Collective.
    fn dense(
        &mut self,
        ctx: &Ctx,
        s: &NewtonSettings,
        (first, located): (bool, Option<usize>),
        (summary, history): (&mut CondensedSummary, &mut Vec<StepInfo>),
    ) -> DenseRun {
        let t = Instant::now();
        let (cand, comp, free) = (&self.cand, &mut self.comp, &self.free);
        let active = &self.growth.active;
        let (run, x_s) = dense_round(ctx, cand, comp, free, s, (active, first), located);
        comp.x_s = x_s;
        summary.dense_seconds += t.elapsed().as_secs_f64();
        summary.record_coarse(ctx, &run);
        let round = (comp.list.len(), free.pins().len());
        record_steps(ctx, history, &run.steps, ("C_n", "condensed"), round);
        run
    }

    /// What the pass keeps for a friction solve or the next load step, with the candidates'
    /// multipliers `lambda`.
    fn keep(self, lambda: Vec<f64>, zone: Option<Vec<bool>>) -> Kept {
        Kept {
            n_local: self.rhs0.len(),
            comp: self.comp,
            cand: self.cand,
            f_root: self.f_root,
            free: self.free,
            lambda,
            active: self.growth.active,
            held: self.growth.held,
            zone: zone.unwrap_or_default(),
        }
    }
}

/// A pass begun: the held nodes of the predicted `zone` ([`hold`] on `all0`, every contact
/// node as the case starts; none without a zone), K_p
/// written with them, its candidates (the zone's nodes not held start active; else the start
/// set `start`), the first candidates' count (the zone's band and margin, or the located
/// zone's margin), and a compliance on the previous load step's factorisation where it holds
/// ([`reused`]) or a new one with the kept node order `order`. Collective.
fn begin_pass(
    ctx: &Ctx,
    (p, reduced, warm): (&ContactProblem, &mut ReducedSystem, Option<&WarmStart>),
    (free0, all0): (&FreeModes, Option<&Candidates>),
    (start, located, per): (&[bool], &Located, usize),
    (zone, order, sticking): (Option<&[bool]>, Option<Vec<usize>>, Sticking),
    summary: &mut CondensedSummary,
) -> Result<Pass, RunError> {
    let b = p.boundary;
    let key = located.as_ref().map(|(k, _)| k.as_slice());
    let released = |i: usize| sticking.release.get(i).copied().unwrap_or(false);
    let held = match (zone, all0) {
        (Some(z), Some(all)) => {
            let kept_on: Vec<bool> = (0..z.len()).map(|i| z[i] && !released(i)).collect();
            hold(all, &kept_on, (BAND_FRACTION >> sticking.pass).max(1))
        }
        _ => Vec::new(),
    };
    let (free, rhs0) = prepare_base(ctx, (p, reduced), free0, (&held, per > 1))?;
    let f_root = ctx.gather_to_root(&rhs0); // f for MUMPS' solve phases, once per pass
    let pass_start: Vec<bool> = match zone {
        Some(z) => (0..b.nodes.len())
            .map(|i| (z[b.offset + i] || released(b.offset + i)) && !held[b.offset + i])
            .collect(),
        None => (0..b.nodes.len())
            .map(|i| start[i] || released(b.offset + i))
            .collect(),
    };
    let cand = Candidates::gather(ctx, b, &free, &pass_start, key);
    let count = |v: &[bool]| v.iter().filter(|&&a| a).count();
    let want = match zone {
        Some(z) => Some(count(z) - count(&held) + count(z) / LOCATED_MARGIN),
        None => located.as_ref().map(|(_, on)| on + on / LOCATED_MARGIN),
    };
    let growth = Growth::new(&cand, per, want, &held);
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
    let t = Instant::now();
    let (kept, order_dropped) = match warm {
        Some(_) => reused(ctx, p, (&free, &cand), &f_root, (per, &held)),
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
        comp.node_order = order.or(order_dropped);
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

/// The predicted contact zone a solve starts from, over every contact node (c_h's global
/// order), where it is [`wide`]: the nodes the
/// half-space model put in contact (`located`: the `on` nodes of smallest clearance), else
/// the start set. `None`: a narrower zone (every candidate a Schur variable). Local (on
/// all-gathered data).
fn first_zone(all: &Candidates, located: Option<usize>, per: usize) -> Option<Vec<bool>> {
    let zone: Vec<bool> = match located {
        Some(on) => {
            let mut by: Vec<usize> = (0..all.n).collect();
            by.sort_by(|&a, &b| all.by_key(a, b));
            let mut z = vec![false; all.n];
            for &i in by.iter().take(on) {
                z[i] = true;
            }
            z
        }
        None => (0..all.n).map(|i| all.start(i)).collect(),
    };
    wide(zone.iter().filter(|&&a| a).count(), per, DENSE_FLOOR_FLOPS).then_some(zone)
}

/// The nodes of a predicted contact zone (`zone`, every contact node in c_h's global order)
/// held on their obstacle in the factorised matrix: per contact pair, all of the pair's zone
/// but its 1/`band` (frictionless: 1/[`BAND_FRACTION`]) nodes nearest to a node of the pair
/// outside the zone (the zone's edge, where the prediction is uncertain; distance in space,
/// ties: the larger order key, then the gmsh tag), at least [`MIN_CANDIDATES`] of them. Local
/// (on all-gathered data).
fn hold(all: &Candidates, zone: &[bool], band: usize) -> Vec<bool> {
    let pairs = (0..all.n).map(|i| all.pair(i) + 1).max().unwrap_or(1);
    let mut held = vec![false; all.n];
    for pair in 0..pairs {
        let of_pair = |i: &usize| all.pair(*i) == pair;
        let outside: Vec<[f64; 3]> = (0..all.n)
            .filter(|i| of_pair(i) && !zone[*i])
            .map(|i| all.x(i))
            .collect();
        let tree = rstar::RTree::bulk_load(outside);
        let mut inside: Vec<(f64, usize)> = (0..all.n)
            .filter(|i| of_pair(i) && zone[*i])
            .map(|i| {
                let x = all.x(i);
                let depth = tree.nearest_neighbor(&x).map_or(f64::INFINITY, |y| {
                    (0..3).map(|a| (x[a] - y[a]).powi(2)).sum::<f64>()
                });
                (depth, i)
            })
            .collect();
        inside.sort_by(|a, b| {
            a.0.total_cmp(&b.0)
                .then(all.key(b.1).total_cmp(&all.key(a.1)))
                .then(all.tag(a.1).cmp(&all.tag(b.1)))
        });
        let band = inside
            .len()
            .div_ceil(band)
            .max(MIN_CANDIDATES)
            .min(inside.len());
        for &(_, i) in &inside[band..] {
            held[i] = true;
        }
    }
    held
}

/// A round's first phase: the nodes it adds (`Growth::next`) and K_p factorised with their
/// Schur complement (`Compliance::grow`), or the previous load step's factorisation where it
/// holds every candidate; recorded in `summary`. `Err`: why the condensed path stops.
/// Collective.
fn factorise_round(
    ctx: &Ctx,
    reduced: &ReducedSystem,
    (cand, comp, growth): (&Candidates, &mut Compliance, &Growth),
    summary: &mut CondensedSummary,
    (round, condensation): (usize, f64),
    (dim, n_rows, f_root): (usize, usize, &[f64]),
) -> Result<(), Stop> {
    let t = Instant::now();
    let new = growth.next(cand, comp, round)?;
    if new.is_empty() && comp.factor.is_some() {
        // the previous load step's factorisation holds every candidate of this one
        summary.record_kept(ctx, comp, cand, condensation + t.elapsed().as_secs_f64());
        return Ok(());
    }
    comp.grow(
        ctx,
        reduced,
        cand,
        &new,
        (dim, n_rows),
        (f_root, &growth.why),
    )?;
    summary.factorisation_kept = false;
    summary.primal = comp.primal;
    summary.record_factorisation(comp, cand, t.elapsed().as_secs_f64());
    Ok(())
}

/// What a dense round's end means for the condensed path.
enum Judged {
    /// Converged: expand and check on every contact node.
    Expand,
    /// No support among fewer candidates than contact nodes: every node a candidate, again.
    Again,
    Stop(Stop),
}

/// A round's dense end judged: no support on a body that nothing else can hold is the
/// case's error (force control: the obstacle never touches); a fallback of the primal form
/// means the zone is too wide even for it. Collective (force control's check).
fn judge(
    ctx: &Ctx,
    p: &ContactProblem,
    s: &NewtonSettings,
    (free, comp, n): (&FreeModes, &Compliance, usize),
    growth: &mut Growth,
    run: &DenseRun,
) -> Result<Judged, RunError> {
    match &run.end {
        End::Converged => Ok(Judged::Expand),
        End::NoSupport(_) if comp.list.len() < n => {
            // a node beyond the candidates may still carry the load: all of them
            growth.take_all();
            growth.why = format!(
                "no support among the {} candidates, so every contact node",
                comp.list.len()
            );
            Ok(Judged::Again)
        }
        End::NoSupport(reaction) => {
            // under force control: the pair whose obstacle never reaches the body, if one
            // does not; else no support as without force control
            if let Some(fc) = super::force::unreached(ctx, p.boundary, s.force) {
                return Err(super::force::never_touches(fc));
            }
            Err(free.no_support(run.active.iter().filter(|&&a| a).count(), *reaction))
        }
        // the primal form gives up where the zone is too wide even for it
        End::Fallback(why) if comp.primal => Ok(Judged::Stop(Stop::too_wide(why.clone()))),
        End::Fallback(why) => Ok(Judged::Stop(Stop::failed(why.clone()))),
    }
}

/// A floating body's contact zone located by the half-space model before anything is
/// factorised (the first solve of a case, `s.model` given): it may lie far from the smallest
/// gaps (the body rolls where friction alone holds a part of the load, `s.carried`) and be
/// wider than the dense limits. The clearance of this rank's contact nodes after the model's
/// rigid motion and the nodes it puts in contact ([`halfspace::locate`]), computed once per
/// solve (`p.located`). Collective.
fn locate(
    ctx: &Ctx,
    p: &ContactProblem,
    s: &NewtonSettings,
    free: &FreeModes,
    warm: Option<&WarmStart>,
) -> Result<Option<(Vec<f64>, usize)>, RunError> {
    match (s.model, warm) {
        (Some(hs), None) if free.floats() && free.dirichlet_free().ncols() > 0 => {
            if let Some(done) = p.located.borrow().as_ref() {
                return Ok(done.clone()); // the same body, load and model: located once
            }
            let phi = s.carried.map_or_else(|| free.free_load(), <[f64]>::to_vec);
            let zone =
                halfspace::locate(ctx, hs, p.boundary, free, &phi, (s.c, s.section.max_steps))?;
            *p.located.borrow_mut() = Some(zone.clone());
            Ok(zone)
        }
        _ => Ok(None),
    }
}

/// A floating body under force control: with one pair the load balance fixes the force;
/// with several, each approach is one more free mode next to the body's own (the dense
/// iteration's G has a column per mode), unless every pair is force-controlled (the
/// approaches and the body's position along them are then not determined). Local.
fn refuse_floating_force(
    p: &ContactProblem,
    s: &NewtonSettings,
    free: &FreeModes,
) -> Result<(), RunError> {
    if let (Some(fc), true) = (s.force.first(), free.floats()) {
        if p.boundary.n_pairs() == 1 {
            return Err(super::force::floating(fc));
        }
        if s.force.len() == p.boundary.n_pairs() {
            return Err(super::force::all_pairs_floating(fc));
        }
    }
    Ok(())
}

/// A load step's compliance on the previous step's factorisation ([`Kept`], `p.kept`): K_p
/// is the same matrix in every load step where it holds the same nodes (`held`; their rows'
/// values, this step's references and gaps, are in f), so where the pins, `per`, the held
/// nodes and the kept candidates' rows and frames are this step's, only d₀ is new (MUMPS'
/// condensation of this step's f, `f_root` on rank 0). `None`: nothing kept, or it does not
/// hold (it is dropped; its node order is returned). Collective (the decision is taken on
/// all-gathered data: the same on every rank).
fn reused(
    ctx: &Ctx,
    p: &ContactProblem,
    (free, cand): (&FreeModes, &Candidates),
    f_root: &[f64],
    (per, held): (usize, &[bool]),
) -> (Option<Compliance>, Option<Vec<usize>>) {
    let Some(kept) = p.kept.take() else {
        return (None, None);
    };
    let holding = |h: &[bool]| h.iter().any(|&x| x);
    let same_held = match (holding(&kept.held), holding(held)) {
        (false, false) => true,
        (true, true) => kept.held == held,
        _ => false,
    };
    if kept.comp.primal || !same_held || !kept.holds(free, cand, per) {
        return (None, kept.comp.node_order);
    }
    let mut comp = kept.comp;
    match comp.recondense(ctx, f_root) {
        Ok(()) => (Some(comp), None),
        Err(why) => {
            say!(ctx, "newton: condensed: {why}; a new factorisation");
            (None, comp.node_order.take())
        }
    }
}

/// Why a round of candidates stops the condensed path: the zone is too wide for the dense
/// limits (the plain path then starts from the half-space model's set, mod.rs), or something
/// failed.
struct Stop {
    why: String,
    too_wide: bool,
}

impl Stop {
    fn too_wide(why: String) -> Stop {
        Stop {
            why,
            too_wide: true,
        }
    }
    fn failed(why: String) -> Stop {
        Stop {
            why,
            too_wide: false,
        }
    }
}

/// The candidate set from round to round: the `take` contact nodes with the smallest gaps and
/// every node whose gap equals the largest of theirs (equal gaps are alike to this rule: a flat
/// face is taken whole, and when it exceeds the Schur limit the plain path runs before anything
/// is factorised), the nodes forced in (the start set, nodes (3.23) activated beyond the
/// candidates), and the current set of every contact node (c_h's global order). Growth doubles
/// `take`, a count, so it also grows where the gaps are ≤ 0 (bodies that start touching or
/// overlapping). Held nodes (K_p holds them on the obstacle) are never candidates and always
/// in the set.
struct Growth {
    /// Every contact node of each pair by increasing gap (ties: the gmsh tag), the held ones
    /// left out.
    by_gap: Vec<Vec<usize>>,
    /// How many of each pair's nodes by gap are candidates.
    take: Vec<usize>,
    forced: HashSet<usize>,
    active: Vec<bool>,
    /// The nodes K_p holds on the obstacle (empty: none).
    held: Vec<bool>,
    held_count: usize,
    /// Why the set has the size it has (for a fallback's reason).
    why: String,
}

impl Growth {
    /// The first candidates: of every contact pair the nodes with the smallest gaps (an
    /// eighth of the pair's nodes, at least MIN_CANDIDATES and `want` where given, all pairs
    /// together at most half the Schur limit) — per pair, since the pairs' gaps are not
    /// comparable (an obstacle moved into the body has the smallest gaps, the one that holds
    /// the body may have none below them) — and every node of the start set (the thesis'
    /// all-active start: all of them); `held` (or empty): the nodes K_p holds.
    fn new(cand: &Candidates, per: usize, want: Option<usize>, held: &[bool]) -> Growth {
        let n = cand.n;
        let is_held = |i: usize| held.get(i).copied().unwrap_or(false);
        let pairs = (0..n).map(|i| cand.pair(i) + 1).max().unwrap_or(1);
        let mut by_gap: Vec<Vec<usize>> = vec![Vec::new(); pairs];
        for i in (0..n).filter(|&i| !is_held(i)) {
            by_gap[cand.pair(i)].push(i);
        }
        for b in &mut by_gap {
            b.sort_by(|&a, &b| cand.by_key(a, b));
        }
        let limit = (max_schur_dofs() / (2 * per * pairs)).max(1);
        // a held zone's band and margin are what it wants
        let some_held = held.iter().any(|&h| h);
        let take: Vec<usize> = by_gap
            .iter()
            .map(|b| {
                (if some_held {
                    0
                } else {
                    b.len() / FIRST_FRACTION
                })
                .max(want.unwrap_or(0))
                .clamp(MIN_CANDIDATES.min(limit), limit)
                .min(b.len())
            })
            .collect();
        let first: usize = take.iter().sum();
        let active: Vec<bool> = (0..n).map(|i| cand.start(i) || is_held(i)).collect();
        let by = if want.is_some() {
            "clearances after the located rigid motion"
        } else {
            "gaps"
        };
        Growth {
            by_gap,
            take,
            forced: (0..n).filter(|&i| active[i] && !is_held(i)).collect(),
            active,
            held: (0..n).map(is_held).collect(),
            held_count: (0..n).filter(|&i| is_held(i)).count(),
            why: format!("the {first} nodes with the smallest {by} and the start set"),
        }
    }

    /// Where a new pass starts (`splits`: held zones allowed): the set (3.23) gives on the
    /// expanded u (the nodes `changed` turned over), where held nodes must change or that set
    /// is [`wide`] against the dense work that pays (`max_flops`). `None`: the pass goes on
    /// (more candidates). Collective (log).
    fn next_pass(
        &self,
        ctx: &Ctx,
        changed: &[u64],
        (max_flops, per): (f64, usize),
        splits: bool,
    ) -> Option<Vec<bool>> {
        // friction holds a zone only once every dof of the candidates is too many (the
        // candidates grow first, as without a zone: `widen`)
        if !splits || (per > 1 && self.held_count == 0) {
            return None;
        }
        let mut z = self.active.clone();
        for &i in changed {
            z[i as usize] = !z[i as usize];
        }
        let on = z.iter().filter(|&&a| a).count();
        if self.held_count == 0 && !wide(on, per, max_flops) {
            return None;
        }
        say!(
            ctx,
            "newton: condensed: {} node(s) change on the expanded u, {on} in contact: the \
             predicted zone again, a new factorisation",
            changed.len()
        );
        Some(z)
    }

    /// Every contact node a candidate.
    fn take_all(&mut self) {
        for (t, b) in self.take.iter_mut().zip(&self.by_gap) {
            *t = b.len();
        }
    }

    /// The nodes this round adds; `Err`: why the plain path takes over (none to add after the
    /// first round, or more Schur dofs than MAX_SCHUR_DOFS).
    fn next(&self, cand: &Candidates, comp: &Compliance, round: usize) -> Result<Vec<usize>, Stop> {
        // each pair's bound: the key (gap or clearance) of its last node taken
        let bound: Vec<f64> = self
            .by_gap
            .iter()
            .zip(&self.take)
            .map(|(b, &t)| {
                b.get(t.clamp(1, b.len().max(1)) - 1)
                    .map_or(f64::NEG_INFINITY, |&i| cand.key(i))
            })
            .collect();
        let mut new: Vec<usize> = (0..cand.n)
            .filter(|&i| {
                !comp.in_s[i]
                    && !self.held[i]
                    && (cand.key(i) <= bound[cand.pair(i)] || self.forced.contains(&i))
            })
            .collect();
        // by tag: the dense systems' order (C's rows, the nested start's coarsening, the
        // balance test's and the dense Coulomb iteration's ties) the same on every partition
        new.sort_by_key(|&i| cand.tag(i));
        if new.is_empty() && round > 1 {
            return Err(Stop::failed(
                "the candidate set cannot grow (internal)".to_string(),
            ));
        }
        let wanted = comp.list.len() + new.len();
        let max_dofs = max_schur_dofs();
        if wanted * comp.per > max_dofs {
            return Err(Stop::too_wide(format!(
                "{wanted} candidate contact nodes ({}) exceed the dense Schur complement's \
                 limit of {max_dofs} dofs ({} per node; a contact zone this wide costs \
                 less on the plain path)",
                self.why, comp.per,
            )));
        }
        Ok(new)
    }

    /// The dense round's set and λ_n over every contact node (0 and inactive off the
    /// candidates); the set is kept, λ_n returned.
    fn take_dense(&mut self, comp: &Compliance, run: &DenseRun) -> Vec<f64> {
        let mut lambda = vec![0.0; self.active.len()];
        self.active.copy_from_slice(&self.held);
        for (q, &i) in comp.list.iter().enumerate() {
            lambda[i] = run.lambda[q];
            self.active[i] = run.active[q];
        }
        lambda
    }

    /// Nodes beyond the candidates that (3.23) activates on the expanded u (`changed`) join
    /// the set and the candidates, and the number taken by gap doubles. `Err`: a candidate changed
    /// (round-off at the edge of the set) or the last round is spent. Collective (log).
    fn widen(
        &mut self,
        ctx: &Ctx,
        changed: &[u64],
        comp: &Compliance,
        round: usize,
    ) -> Result<(), String> {
        let inside = changed.iter().filter(|&&i| comp.in_s[i as usize]).count();
        if inside > 0 || round == MAX_ROUNDS {
            return Err(format!(
                "{} node(s) change on the expanded u ({inside} of them candidates: round-off at \
                 nodes on the edge of the set)",
                changed.len()
            ));
        }
        say!(
            ctx,
            "newton: condensed: {} node(s) beyond the {} candidates come into contact: more \
             candidates",
            changed.len(),
            comp.list.len()
        );
        for &i in changed {
            self.forced.insert(i as usize);
            self.active[i as usize] = true;
        }
        for t in &mut self.take {
            *t = (2 * *t).max(1);
        }
        self.why = format!(
            "{} node(s) beyond the candidates came into contact, so the {} nodes with the \
             smallest gaps",
            changed.len(),
            self.take.iter().sum::<usize>()
        );
        Ok(())
    }
}

/// The converged condensed solve as the plain path's result: u = w + ρ (λ and the set were
/// taken on w, as the plain path does). Collective.
fn finish(
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
        stop: super::certificate::StopRule::ActiveSet,
    };
    Ok(Condensed::Solved(Box::new(result), summary))
}

/// [`fallback`] for a round's [`Stop`] (marked in the summary where the zone is too wide).
fn fallback_stop(ctx: &Ctx, mut summary: CondensedSummary, stop: Stop) -> Condensed {
    summary.too_wide = stop.too_wide;
    fallback(ctx, summary, stop.why)
}

/// The plain path takes over: said in the log and in the summary.
fn fallback(ctx: &Ctx, mut summary: CondensedSummary, why: String) -> Condensed {
    let record = (&mut summary.outcome, &mut summary.fallback_reason);
    fall_back(
        ctx,
        ("newton: condensed path", "solving on the plain path"),
        record,
        why,
    );
    Condensed::Fallback(summary)
}

/// A condensed solve gives up for the plain path: said in the log (`what` gave up, `then`
/// where the plain path starts), its record's `outcome` "fallback" with the `reason` `why`.
/// Collective (log).
pub(super) fn fall_back(
    ctx: &Ctx,
    (what, then): (&str, &str),
    (outcome, reason): (&mut &'static str, &mut Option<String>),
    why: String,
) {
    say!(ctx, "{what}: {why}; {then}");
    *outcome = "fallback";
    *reason = Some(why);
}

/// K_p: A with every rigid mode that Dirichlet data and the held nodes (`held`: every
/// contact node in c_h's global order, or empty) leave free pinned, the held nodes' normal
/// rows written as the reduced system (3.29) writes an active node (u_n = −g) — with `stick`
/// their tangential rows too, as (3.42) writes a sticking node (u_τ = u_ref) — and no other
/// contact row, into the reduced system's matrix (factorised later, by MUMPS directly, with
/// the Schur complement). `free0`: the modes Dirichlet data leave free. Returns the free
/// modes (with K_p's pins) and this rank's rows of K_p's right-hand side. Collective.
fn prepare_base(
    ctx: &Ctx,
    (p, reduced): (&ContactProblem, &mut ReducedSystem),
    free0: &FreeModes,
    (held, stick): (&[bool], bool),
) -> Result<(FreeModes, Vec<f64>), RunError> {
    let (mesh, layout, b, sys) = (p.mesh, p.layout, p.boundary, p.sys);
    let mut free = free0.clone();
    let mine = match held.is_empty() {
        true => vec![false; b.nodes.len()],
        false => held[b.offset..b.offset + b.nodes.len()].to_vec(),
    };
    let set = ActiveSet::held(mine, stick);
    if held.iter().any(|&h| h) {
        let gram = set.summarise(ctx, b, free.modes(), mesh.dim).gram;
        free.hold_also(&gram);
    }
    free.update(ctx, mesh, layout, &[0.0; 36])?;
    reduced.set_pins(sys, layout, free.pins())?;
    reduced.write(ctx, sys, layout, b, &set, free.pins())?;
    Ok((free, reduced.rhs_local()?))
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
            let init = super::plain_path::auto_start(s.section.init, false, free);
            let (b, dim) = (p.boundary, p.mesh.dim);
            ActiveSet::initial(b, init, Law::Frictionless, s.c, p.mesh.extent(), dim).normal
        }
    }
}

/// Every contact node of c_h (all ranks', in c_h's global order) as the dense algorithm sees
/// it: first dof row, normal, gap, start flag, the free modes' normal parts G, position, the
/// reference tangential displacement u_τ^ref (friction).
pub(super) struct Candidates {
    all: Vec<f64>,
    pub(super) n: usize,
    mz: usize,
}

/// Values per candidate record: row, n (3), gap, start, G (6), x (3), u_τ^ref (2), pair, μ,
/// the order key, the gmsh tag (exact in f64 below 2⁵³).
const REC: usize = 21;

impl Candidates {
    /// One all-gather. `key`: what orders this rank's nodes for the first candidates (the
    /// clearance after a located rigid motion, [`super::halfspace::locate`]); `None`: the gap.
    /// Collective.
    fn gather(
        ctx: &Ctx,
        b: &ContactBoundary,
        free: &FreeModes,
        start: &[bool],
        key: Option<&[f64]>,
    ) -> Candidates {
        let mz = free.dirichlet_free().ncols();
        let mut mine = Vec::with_capacity(b.nodes.len() * REC);
        for (i, (k, &a)) in b.nodes.iter().zip(start).enumerate() {
            let gz = free.normal_parts(&k.x, &k.frame.n);
            let n = k.frame.n;
            let flag = if a { 1.0 } else { 0.0 };
            mine.extend_from_slice(&[k.row as f64, n[0], n[1], n[2], k.gap, flag]);
            mine.extend_from_slice(&gz);
            mine.extend_from_slice(&k.x);
            mine.extend_from_slice(&k.u_t_ref);
            mine.push(k.pair as f64);
            mine.push(k.mu);
            mine.push(key.map_or(k.gap, |key| key[i]));
            mine.push(k.tag as f64);
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
    pub(super) fn gap(&self, i: usize) -> f64 {
        self.rec(i)[4]
    }
    fn start(&self, i: usize) -> bool {
        self.rec(i)[5] != 0.0
    }
    fn g(&self, i: usize, c: usize) -> f64 {
        self.rec(i)[6 + c]
    }
    /// The node frame as an orthonormal basis, normal first (columns: n, t₁, t₂).
    fn basis(&self, i: usize, dim: usize) -> [[f64; 3]; 3] {
        let n = [self.normal(i, 0), self.normal(i, 1), self.normal(i, 2)];
        let mut q = [[0.0; 3]; 3];
        let Some(f) = Frame::new(n, dim) else {
            (0..3).for_each(|a| q[a][a] = 1.0);
            return q;
        };
        for (a, qa) in q.iter_mut().enumerate() {
            *qa = [f.n[a], f.t[0][a], f.t[1][a]];
        }
        q
    }
    pub(super) fn x(&self, i: usize) -> [f64; 3] {
        let r = self.rec(i);
        [r[12], r[13], r[14]]
    }
    pub(super) fn u_t_ref(&self, i: usize) -> [f64; 2] {
        let r = self.rec(i);
        [r[15], r[16]]
    }
    pub(super) fn n(&self, i: usize) -> [f64; 3] {
        [self.normal(i, 0), self.normal(i, 1), self.normal(i, 2)]
    }
    /// The candidate's contact pair.
    pub(super) fn pair(&self, i: usize) -> usize {
        self.rec(i)[17] as usize
    }
    /// The candidate's Coulomb μ.
    pub(super) fn mu(&self, i: usize) -> f64 {
        self.rec(i)[18]
    }
    /// What orders the nodes for the candidates: the gap, or the clearance after a located
    /// rigid motion.
    fn key(&self, i: usize) -> f64 {
        self.rec(i)[19]
    }
    /// The node's gmsh tag: what breaks ties between nodes, the same on every partition (c_h's
    /// global order is rank-major).
    pub(super) fn tag(&self, i: usize) -> u64 {
        self.rec(i)[20] as u64
    }
    /// `a` before `b` by the order key, ties by the gmsh tag. Local.
    fn by_key(&self, a: usize, b: usize) -> std::cmp::Ordering {
        self.key(a)
            .total_cmp(&self.key(b))
            .then(self.tag(a).cmp(&self.tag(b)))
    }
}

/// The compliance C = Nᵀ K_p⁻¹ N of a growing candidate set and d₀ = Nᵀ K_p⁻¹ f there. In the
/// candidates' node frames (Q, normal first) N becomes the unit columns of their normal dofs,
/// so with S the Schur complement of Qᵀ K_p Q on those dofs: C = S⁻¹ and d₀ = S⁻¹ r, r = f̃_s −
/// K̃_sr K̃_rr⁻¹ f̃_r (MUMPS' condensation of f̃ = Qᵀ f). The dense parts live on rank 0 only.
pub(super) struct Compliance {
    /// Schur variables per candidate: 1 (the normal dof) or d (every dof, in the node frame,
    /// normal first: C then holds the tangential compliance friction needs).
    pub(super) per: usize,
    pub(super) in_s: Vec<bool>,
    /// The candidates in the order of C's rows and columns (`per` rows each).
    pub(super) list: Vec<usize>,
    pub(super) cmat: DMatrix<f64>,
    pub(super) d0: Vec<f64>,
    /// The candidates' node frames (normal first): K_p is factorised as Qᵀ K_p Q.
    bases: NodeBases,
    factor: Option<NumericSchur>,
    /// Rank 0: the nested-dissection order of K_p's node graph (empty: MUMPS' own), made by
    /// the first `grow`.
    pub(super) node_order: Option<Vec<usize>>,
    /// The ordering, MUMPS' analysis and factorisation in the last `grow` [s].
    factorisation_seconds: f64,
    /// The nested-dissection ordering (graph gathered, Scotch) [s].
    ordering_seconds: f64,
    /// The primal form (frictionless, where C = S⁻¹ would cost more than the factorisation):
    /// rank 0 keeps S itself and r (MUMPS' condensation of f), `cmat` and `d0` stay empty,
    /// and the Schur variables' part of the expansion, S⁻¹ (r − λ) = u − G α, is the dense
    /// iteration's own (`x_s`).
    primal: bool,
    schur: DMatrix<f64>,
    r: Vec<f64>,
    x_s: Vec<f64>,
    /// The dense work that pays (flops): the dense compliance's or a primal step's bound.
    max_flops: f64,
}

impl Compliance {
    fn new(n: usize, per: usize) -> Compliance {
        Compliance {
            per,
            in_s: vec![false; n],
            list: Vec::new(),
            cmat: DMatrix::zeros(0, 0),
            d0: Vec::new(),
            bases: NodeBases::default(),
            factor: None,
            node_order: None,
            factorisation_seconds: 0.0,
            ordering_seconds: 0.0,
            primal: false,
            schur: DMatrix::zeros(0, 0),
            r: Vec::new(),
            x_s: Vec::new(),
            max_flops: 0.0,
        }
    }

    /// Adds the candidates `new` and factorises K_p (the reduced system's matrix, global size
    /// `n_rows`) anew in the candidates' frames with the Schur complement on their normal dofs;
    /// then C and d₀ (`f_root`: f on rank 0, empty elsewhere; `why`: how the set came about,
    /// for the log). `Err` (the same on every rank): why the condensed path gives up (MUMPS
    /// failed, the dense work would cost more than the factorisation, S not positive
    /// definite). Collective.
    fn grow(
        &mut self,
        ctx: &Ctx,
        reduced: &ReducedSystem,
        cand: &Candidates,
        new: &[usize],
        (dim, n_rows): (usize, usize),
        (f_root, why): (&[f64], &str),
    ) -> Result<(), Stop> {
        let root = ctx.rank == 0;
        for &i in new {
            self.in_s[i] = true;
        }
        self.list.extend_from_slice(new);
        for &i in new {
            self.bases.q.insert(cand.row(i) / dim, cand.basis(i, dim));
        }
        self.bases.dim = dim;
        // in the node frame the normal displacement is the node's first dof
        let per = self.per;
        let dofs: Vec<usize> = self
            .list
            .iter()
            .flat_map(|&i| (0..per).map(move |a| cand.row(i) + a))
            .collect();
        self.factor = None; // the old factorisation's memory first
        self.cmat = DMatrix::zeros(0, 0);
        self.schur = DMatrix::zeros(0, 0);
        let t = Instant::now();
        self.ordering_seconds = 0.0; // this factorisation's ordering (none where one is kept)
        if self.node_order.is_none() {
            // With a Schur complement MUMPS would order by AMD (2.4 × the flops of PORD on a 3D
            // block of 82 584 unknowns, measured): our nested-dissection order instead.
            // agreed before it may turn into a fallback (a failure on one rank alone ends
            // every rank instead)
            let order = ctx
                .agree_message(node_order(ctx.comm(), reduced.matrix(), dim))
                .map_err(Stop::failed)?;
            self.node_order = Some(order);
            self.ordering_seconds = t.elapsed().as_secs_f64();
        }
        let order = match &self.node_order {
            Some(o) if root && !o.is_empty() => Some(dof_order(o, &dofs, dim, n_rows)),
            _ => None,
        };
        let factor = reduced.analyse_schur(ctx, (n_rows, &dofs), (order.as_deref(), &self.bases));
        drop(order);
        let symbolic = ctx
            .agree_message(factor)
            .map_err(|e| Stop::failed(format!("MUMPS' analysis of K_p failed: {e}")))?;
        // the same numbers on every rank: the same decision
        let dense = (dofs.len() as f64).powi(3);
        let speedup = if dim == 2 { DENSE_SPEEDUP_2D } else { 1.0 };
        self.max_flops = DENSE_FLOOR_FLOPS.max(speedup * symbolic.flops());
        // frictionless: the primal form, whose steps solve for the inactive candidates alone
        self.primal = dense > self.max_flops && per == 1;
        if dense > self.max_flops && !self.primal {
            return Err(Stop::too_wide(format!(
                "{} candidate contact nodes ({} Schur dofs; {}): the dense compliance ({:.1e} \
                 flops) would cost more than the factorisation of K_p ({:.1e} flops); a contact zone this \
                 wide costs less on the plain path",
                self.list.len(),
                dofs.len(),
                why,
                dense,
                symbolic.flops()
            )));
        }
        let done = symbolic.factorise();
        self.factorisation_seconds = t.elapsed().as_secs_f64();
        let mut factor = ctx
            .agree_message(done)
            .map_err(|e| Stop::failed(format!("the Schur factorisation of K_p failed: {e}")))?;
        let r = ctx
            .agree_message(factor.condense(&self.rotated(f_root)))
            .map_err(|e| Stop::failed(format!("the condensation of f failed: {e}")))?;
        // S copied (primal) or inverted (dimension: the Schur dofs)
        let work = if self.primal { 0 } else { dofs.len() };
        let inverted = ctx.on_root_wide(work, || {
            if self.primal {
                // S itself (its lower triangle, column-major, as LAPACK's Cholesky reads it)
                let n = dofs.len();
                let mut s = DMatrix::from_vec(n, n, factor.take_schur());
                for j in 0..n {
                    for i in 0..j {
                        s[(i, j)] = s[(j, i)];
                    }
                }
                self.schur = s;
                self.r = r;
                return true;
            }
            // S's one copy, factorised and inverted in place: C = S⁻¹; with every dof of the
            // candidates (Coulomb) a copy of S and r too, for the primal form of its dense steps
            let sv = factor.take_schur();
            if per > 1 {
                self.schur = DMatrix::from_vec(dofs.len(), dofs.len(), sv.clone());
                self.r = r.clone();
            }
            let Some(ch) = DenseCholesky::factor_owned(dofs.len(), sv) else {
                return false;
            };
            self.cmat = ch.inverse();
            self.d0 = (&self.cmat * DVector::from_column_slice(&r))
                .as_slice()
                .to_vec();
            true
        });
        let mut ok = vec![if inverted == Some(false) { 0.0 } else { 1.0 }];
        ctx.broadcast_f64s(&mut ok);
        self.factor = Some(factor);
        if ok[0] == 0.0 {
            return Err(Stop::failed(format!(
                "the Schur complement of K_p on the {} candidates' dofs ({per} per node) is not \
                 positive definite",
                self.list.len()
            )));
        }
        Ok(())
    }

    /// C and d₀ on the candidates' normal dofs (the frictionless model): themselves for
    /// `per` = 1, else every `per`-th row and column (the compliance of the normal dofs with
    /// the tangential forces zero). Rank 0.
    fn normal_part(&self) -> (Cow<'_, DMatrix<f64>>, Cow<'_, [f64]>) {
        let (n, per) = (self.list.len(), self.per);
        if per == 1 {
            return (Cow::Borrowed(&self.cmat), Cow::Borrowed(&self.d0[..]));
        }
        let c = DMatrix::from_fn(n, n, |i, j| self.cmat[(i * per, j * per)]);
        let d = (0..n).map(|i| self.d0[i * per]).collect::<Vec<f64>>();
        (Cow::Owned(c), Cow::Owned(d))
    }

    /// d₀ = C r for a new f on the kept factorisation (`f_root`: f on rank 0), r MUMPS'
    /// condensation of Qᵀ f. `Err`: the solve phase failed. Collective.
    fn recondense(&mut self, ctx: &Ctx, f_root: &[f64]) -> Result<(), String> {
        let rhs = self.rotated(f_root);
        let factor = self.factor.as_mut().ok_or("no factorisation kept")?;
        let r = ctx
            .agree_message(factor.condense(&rhs))
            .map_err(|e| format!("the condensation of f failed: {e}"))?;
        if ctx.rank == 0 {
            self.d0 = (&self.cmat * DVector::from_column_slice(&r))
                .as_slice()
                .to_vec();
            if self.stiffness().is_some() {
                self.r = r;
            }
        }
        Ok(())
    }

    /// S itself and r (λ = r − S (u − G α) on the candidates' dofs) next to C = S⁻¹, where every
    /// dof of the candidates is a Schur variable (Coulomb; rank 0): the primal form of the
    /// dense Coulomb steps (coulomb_condensed.rs). `None` elsewhere.
    pub(super) fn stiffness(&self) -> Option<(&DMatrix<f64>, &[f64])> {
        let n = self.list.len() * self.per;
        (!self.primal && self.per > 1 && n > 0 && self.schur.nrows() == n)
            .then(|| (&self.schur, &self.r[..]))
    }

    /// w = K_p⁻¹ (f − N λ), this rank's rows (`n_local`), from MUMPS' condensation and
    /// expansion with the Schur variables' part S⁻¹ (r − λ) = d₀ − C λ; `lam`: on rank 0 the
    /// candidates' multipliers in C's order (`per` per node, node frame), empty elsewhere;
    /// `x_s`: the Schur variables' part where the caller has it (the primal form of the dense
    /// Coulomb steps), else empty; `f_root`: f on rank 0. `Err`: MUMPS' solve failed.
    /// Collective.
    pub(super) fn expand_u(
        &mut self,
        ctx: &Ctx,
        cand: &Candidates,
        (f_root, n_local): (&[f64], usize),
        (lam, x_s): (&[f64], &[f64]),
    ) -> Result<Vec<f64>, String> {
        let (rhs_root, x_s) = if ctx.rank == 0 {
            let mut rhs = self.rotated(f_root);
            for (q, &i) in self.list.iter().enumerate() {
                for a in 0..self.per {
                    rhs[cand.row(i) + a] -= lam[q * self.per + a];
                }
            }
            let x_s = if !x_s.is_empty() {
                x_s.to_vec()
            } else if self.primal {
                self.x_s.clone()
            } else {
                let d0 = DVector::from_column_slice(&self.d0);
                (d0 - &self.cmat * DVector::from_column_slice(lam))
                    .as_slice()
                    .to_vec()
            };
            (rhs, x_s)
        } else {
            (Vec::new(), Vec::new())
        };
        let factor = self.factor.as_mut().expect("factorised by grow");
        let mut w_root = ctx
            .agree_message(factor.expand(&rhs_root, &x_s))
            .map_err(|e| format!("the expansion solve failed: {e}"))?;
        self.bases.to_global(&mut w_root);
        Ok(ctx.scatter_from_root(&w_root, n_local))
    }

    /// Qᵀ x (x: a global vector on rank 0, empty elsewhere): the candidates' dofs in their
    /// node frames.
    fn rotated(&self, x: &[f64]) -> Vec<f64> {
        let mut y = x.to_vec();
        self.bases.to_local(&mut y);
        y
    }
}

/// The dof order for MUMPS from the node order: every node's dofs together, the Schur
/// variables (`schur`, all dofs of the candidates) last. order[i] = position of dof i.
fn dof_order(node_perm: &[usize], schur: &[usize], dim: usize, n_rows: usize) -> Vec<usize> {
    let mut in_schur = vec![false; n_rows];
    for &r in schur {
        in_schur[r] = true;
    }
    let mut by_position = vec![0usize; node_perm.len()];
    for (v, &p) in node_perm.iter().enumerate() {
        by_position[p] = v;
    }
    let mut order = vec![0usize; n_rows];
    let mut pos = 0;
    for &v in &by_position {
        for r in (v * dim..(v + 1) * dim).filter(|&r| !in_schur[r]) {
            order[r] = pos;
            pos += 1;
        }
    }
    for &r in schur {
        order[r] = pos;
        pos += 1;
    }
    order
}

/// Algorithm 1 on the candidates' dense system, from `active`, on rank 0; the outcome
/// broadcast to every rank. Collective.
fn dense_round(
    ctx: &Ctx,
    cand: &Candidates,
    comp: &Compliance,
    free: &FreeModes,
    s: &NewtonSettings,
    (active, nested): (&[bool], bool),
    located: Option<usize>,
) -> (DenseRun, Vec<f64>) {
    // force control: each approach δ_j is one more free mode, its normal parts −e_j·n on its
    // pair's candidates and its load |F_j| (force.rs)
    let force: Vec<_> = s
        .force
        .iter()
        .map(|fc| (fc.direction(), fc.magnitude(), fc.pair))
        .collect();
    let (ns, mz) = (comp.list.len(), cand.mz + force.len());
    let mut packed: Vec<f64> = Vec::new();
    // the primal form's Schur variables' part of the expansion, u − G α (rank 0)
    let mut x_s = Vec::new();
    let root = ctx.on_root_wide(ns + mz, || {
        let run = guarded("dense-steps", || {
            let (_, mut load_scale) = free.load();
            let mut phi = s.carried.map_or_else(|| free.free_load(), <[f64]>::to_vec);
            let list = &comp.list;
            let g = DMatrix::from_fn(ns, mz, |q, c| match force.get(c.wrapping_sub(cand.mz)) {
                Some(&(e, _, pair)) if c >= cand.mz => {
                    if cand.pair(list[q]) == pair {
                        -crate::geom::dot(cand.n(list[q]), e)
                    } else {
                        0.0 // another pair's obstacle stays
                    }
                }
                _ => cand.g(list[q], c),
            });
            for &(_, magnitude, _) in &force {
                phi.push(magnitude);
                load_scale = load_scale.max(magnitude);
            }
            let gap: Vec<f64> = list.iter().map(|&i| cand.gap(i)).collect();
            if comp.primal {
                // from as many candidates as the model put in contact, by clearance after the
                // located rigid motion; else from the start set where it has a candidate, else
                // from all of them (no inactive unknowns)
                let start = match located {
                    None if list.iter().any(|&i| active[i]) => {
                        list.iter().map(|&i| active[i]).collect()
                    }
                    Some(on) => {
                        let mut by: Vec<usize> = (0..ns).collect();
                        by.sort_by(|&a, &b| cand.by_key(list[a], list[b]));
                        let mut start = vec![false; ns];
                        for &q in by.iter().take(on) {
                            start[q] = true;
                        }
                        start
                    }
                    None => vec![true; ns],
                };
                let primal = Primal {
                    s: &comp.schur,
                    r: &comp.r,
                    gap: &gap,
                    g: &g,
                    phi: &phi,
                    load_scale,
                    c: s.c,
                    max_steps: s.section.max_steps,
                    max_flops: comp.max_flops,
                };
                let run = primal.run(start);
                if run.end == End::Converged {
                    let ga = &g * DVector::from_column_slice(&run.alpha);
                    x_s = (0..ns).map(|q| run.u_n[q] - ga[q]).collect();
                }
                return run;
            }
            let (cmat, d0) = comp.normal_part();
            let d0 = &d0[..];
            let start: Vec<bool> = list.iter().map(|&i| active[i]).collect();
            let dense = Dense {
                cmat: &cmat,
                d0,
                gap: &gap,
                g: &g,
                phi: &phi,
                load_scale,
                c: s.c,
                max_steps: s.section.max_steps,
                pins_carry: if s.estimate { cand.mz } else { 0 },
            };
            if nested {
                let x: Vec<[f64; 3]> = list.iter().map(|&i| cand.x(i)).collect();
                dense.run_nested(start, &x)
            } else {
                dense.run(start)
            }
        });
        run.unwrap_or_else(|why| DenseRun::failed(ns, mz, why))
            .pack(ns, mz)
    });
    if let Some(p) = root {
        packed = p;
    }
    ctx.broadcast_f64s(&mut packed);
    (DenseRun::unpack(&packed, ns, mz), x_s)
}

/// The dense steps of one round (`steps`: number, |A_n|, changed, residual, seconds) into the
/// history (numbered on) and the log, which names the residual and the path (`residual`,
/// `path`: "C_n", "condensed"; "C", "condensed Coulomb"). Collective (log).
pub(super) fn record_steps(
    ctx: &Ctx,
    history: &mut Vec<StepInfo>,
    steps: &[(usize, usize, usize, f64, f64)],
    (residual, path): (&str, &str),
    (candidates, pinned): (usize, usize),
) {
    let base = history.len();
    for h in steps {
        say!(
            ctx,
            "newton {:3}: |A_n| = {:6}  changed {:6}  |{residual}| = {:.3e}  {path}, \
             {candidates} candidates ({:.4} s)",
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
            predictor: None,
            change: None,
            factorisation_seconds: None,
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
    /// Force control: the approach δ_j of the round per force-controlled pair.
    approach: Vec<f64>,
}

/// Expansion: w = K_p⁻¹ (f − N λ_n) (MUMPS' condensation and expansion with the Schur
/// variables' part S⁻¹ (r − N_s λ_n) = x₀ − S⁻¹N_s λ_n; w goes into `reduced`),
/// ρ = R z α normalised at the pins the plain path chooses for the set (the modes the set
/// leaves free are balanced, else the dense iteration had not stopped), then (3.28) and (3.23)
/// on w with the gaps after ρ, as the plain path does, so that a large rigid motion does not
/// round λ. `(lambda, active)` of every contact node in c_h's global order. The inner `Err`:
/// MUMPS' solve failed (the plain path takes over). Collective.
fn expand(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    (s, free, comp, cand): (&NewtonSettings, &FreeModes, &mut Compliance, &Candidates),
    (f_root, n_local): (&[f64], usize),
    (lambda, active): (&[f64], &[bool]),
    alpha: &[f64],
) -> Result<Result<Expanded, String>, RunError> {
    let (mesh, layout, b, sys) = (p.mesh, p.layout, p.boundary, p.sys);
    let (dim, off) = (mesh.dim, b.offset);
    // On rank 0, in the candidates' frames: Qᵀ (f − N λ_n) (λ_n vanishes off the candidates:
    // it enters each candidate's normal dof) and the normal dofs' part d₀ − C λ_n.
    let lam: Vec<f64> = if ctx.rank == 0 {
        let per = comp.per;
        let mut lam = vec![0.0; comp.list.len() * per];
        for (q, &i) in comp.list.iter().enumerate() {
            lam[q * per] = lambda[i];
        }
        lam
    } else {
        Vec::new()
    };
    let w = match comp.expand_u(ctx, cand, (f_root, n_local), (&lam, &[])) {
        Ok(w) => w,
        Err(why) => return Ok(Err(why)),
    };
    // local (this rank's array): agreed before the collectives that follow
    let set = reduced.set_solution_local(&w).map_err(RunError::from);
    let set = set.and_then(
        |()| match crate::fault::injected("condensed-expand", ctx.rank) {
            Some(m) => Err(RunError::Failed(m)),
            None => Ok(()),
        },
    );
    ctx.agree(set)?;
    let z = free.dirichlet_free();
    let mut rho = [0.0; 6];
    for (j, r) in rho.iter_mut().enumerate().take(free.rigid_modes().m) {
        *r = (0..z.ncols()).map(|c| z[(j, c)] * alpha[c]).sum();
    }
    let set = ActiveSet::frictionless(active[off..off + b.nodes.len()].to_vec());
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
    // force control: the gaps to the obstacles moved by δ_j e_j (δ_j the free-mode
    // coefficients after the body's own)
    let approach: Vec<f64> = s
        .force
        .iter()
        .enumerate()
        .map(|(j, fc)| {
            let delta = alpha[z.ncols() + j];
            for k in shifted.nodes.iter_mut().filter(|k| k.pair == fc.pair) {
                k.gap -= delta * fc.weight(k);
            }
            delta
        })
        .collect();
    let mut it = Iterate::new(b.nodes.len(), n_local, false);
    reduced.recover(sys, &shifted, &set, &mut it)?; // (3.28)
    let update = set.update(&it, &shifted, Law::Frictionless, s.c, 0.0, dim); // (3.23)
    let changed_here: Vec<u64> = set
        .normal
        .iter()
        .zip(&update.next.normal)
        .enumerate()
        .filter(|(_, (a, b))| a != b)
        .map(|(i, _)| (off + i) as u64)
        .collect();
    Ok(Ok(Expanded {
        it,
        rho,
        pins: fin.pins().to_vec(),
        changed: ctx.all_gather_varcount(&changed_here),
        approach,
    }))
}

#[cfg(test)]
mod tests {
    use super::super::dense::{coarsen, COARSEST};
    use super::*;
    use crate::petsc::mumps::nested_dissection;

    /// A dense problem without free modes (c = 1, unit load scale).
    fn no_modes<'a>(
        cmat: &'a DMatrix<f64>,
        d0: &'a [f64],
        gap: &'a [f64],
        g: &'a DMatrix<f64>,
        max_steps: usize,
    ) -> Dense<'a> {
        Dense {
            cmat,
            d0,
            gap,
            g,
            phi: &[],
            load_scale: 1.0,
            c: 1.0,
            max_steps,
            pins_carry: 0,
        }
    }

    /// Two springs of compliance 1 under a load pressing both onto an obstacle at gap 0 and a
    /// third far away: the dense Algorithm 1 finds the set and λ by hand.
    #[test]
    fn dense_algorithm1_on_independent_springs() {
        // u_n = d0 − C λ; node 0 and 1 would penetrate (d0 < −g), node 2 not.
        let cmat = DMatrix::<f64>::identity(3, 3);
        let d0 = [-1.0, -0.5, 0.2];
        let gap = [0.0, 0.1, 0.0];
        let g = DMatrix::<f64>::zeros(3, 0);
        let dense = no_modes(&cmat, &d0, &gap, &g, 20);
        let run = dense.run(vec![false; 3]);
        assert_eq!(run.end, End::Converged);
        assert_eq!(run.active, vec![true, true, false]);
        // u_n = −g on A: λ = d0 + g (≤ 0, pressing)
        assert!((run.lambda[0] - -1.0).abs() < 1e-15);
        assert!((run.lambda[1] - -0.4).abs() < 1e-15);
        assert_eq!(run.lambda[2], 0.0);
        assert!((run.u_n[2] - 0.2).abs() < 1e-15);
    }

    /// A floating "body" of two uncoupled nodes (C = I, d₀ = 0) with one free translation along
    /// the normal, which moves both normal displacements equally, pressed by a load of 1
    /// (Gᵀ λ = φ = −1): the dense iteration from the empty set, the pins carrying the load in
    /// the first `pins_carry` modes.
    fn pressed_pair(gap: [f64; 2], pins_carry: usize) -> DenseRun {
        let cmat = DMatrix::<f64>::identity(2, 2);
        let g = DMatrix::from_row_slice(2, 1, &[1.0, 1.0]);
        let dense = Dense {
            cmat: &cmat,
            d0: &[0.0, 0.0],
            gap: &gap,
            g: &g,
            phi: &[-1.0],
            load_scale: 1.0,
            c: 1.0,
            max_steps: 20,
            pins_carry,
        };
        dense.run(vec![false; 2])
    }

    /// The pressed pair ([`pressed_pair`]): the load φ must be carried by the contact
    /// (Σ λ = φ); from the empty set the balance test activates the node that touches first,
    /// then the set converges.
    #[test]
    fn dense_algorithm1_floating_translation() {
        let gap = [0.0, 0.5];
        let run = pressed_pair(gap, 0);
        assert_eq!(run.end, End::Converged, "{run:?}");
        // node 0 alone carries λ = −1, u_n,0 = 0 = −λ + α → α = −1; node 1: u_n = α = −1 < −0.5
        // penetrates → both active: λ0 + λ1 = −1, −λ0 + α = 0, −λ1 + α = −0.5 → α = −0.75
        assert_eq!(run.active, vec![true, true]);
        let s: f64 = run.lambda.iter().sum();
        assert!((s - -1.0).abs() < 1e-14);
        assert!((run.alpha[0] - -0.75).abs() < 1e-14);
        assert!((run.u_n[0] + gap[0]).abs() < 1e-14 && (run.u_n[1] + gap[1]).abs() < 1e-14);
    }

    /// An estimate (the pins carry the load where the set leaves a mode free, Coulomb's
    /// frictionless start) from the empty set, with no node penetrating at d₀: the load still
    /// brings the body into contact (the balance test activates the node that touches first),
    /// instead of the pins carrying all of it with nothing in contact.
    #[test]
    fn an_estimate_from_the_empty_set_brings_the_pressed_body_into_contact() {
        let run = pressed_pair([0.1, 0.5], 1);
        assert_eq!(run.end, End::Converged, "{run:?}");
        assert_eq!(run.active, vec![true, true], "{run:?}");
        let s: f64 = run.lambda.iter().sum();
        assert!((s - -1.0).abs() < 1e-14, "{run:?}");
    }

    /// The primal form on S ends where the dual form on C = S⁻¹ ends (same set, λ, u, α): a
    /// line of 40 candidates with a coupled SPD S (a discrete Laplacian plus a diagonal), a
    /// curved gap, pressed down by a load held by the contact alone (one free translation)
    /// and, with the translation pinned, by a load through d₀.
    #[test]
    fn primal_form_on_s_equals_the_dual_form_on_its_inverse() {
        let n = 40;
        let mut sm = DMatrix::<f64>::zeros(n, n);
        for i in 0..n {
            sm[(i, i)] = 2.5;
            if i + 1 < n {
                sm[(i, i + 1)] = -1.0;
                sm[(i + 1, i)] = -1.0;
            }
        }
        let cmat = sm.clone().try_inverse().expect("SPD");
        let gap: Vec<f64> = (0..n)
            .map(|i| {
                let x = (i as f64 - 19.5) / 20.0;
                0.5 * x * x
            })
            .collect();
        for (mz, r) in [(1, vec![0.0; n]), (0, vec![-0.05; n])] {
            let g = DMatrix::from_element(n, mz, 1.0);
            let phi = vec![-0.4; mz];
            let d0 = (&cmat * DVector::from_column_slice(&r)).as_slice().to_vec();
            let dual = Dense {
                cmat: &cmat,
                d0: &d0,
                gap: &gap,
                g: &g,
                phi: &phi,
                load_scale: 1.0,
                c: 1.0,
                max_steps: 50,
                pins_carry: 0,
            }
            .run(vec![false; n]);
            let primal = Primal {
                s: &sm,
                r: &r,
                gap: &gap,
                g: &g,
                phi: &phi,
                load_scale: 1.0,
                c: 1.0,
                max_steps: 50,
                max_flops: 1e9,
            }
            .run(vec![true; n]);
            assert_eq!(dual.end, End::Converged, "{dual:?}");
            assert_eq!(primal.end, End::Converged, "{primal:?}");
            let on = primal.active.iter().filter(|&&a| a).count();
            assert!(on > 2 && on < n, "{mz} modes: {on} active");
            assert_eq!(primal.active, dual.active, "{mz} modes");
            for i in 0..n {
                assert!((primal.lambda[i] - dual.lambda[i]).abs() < 1e-12, "λ {i}");
                assert!((primal.u_n[i] - dual.u_n[i]).abs() < 1e-12, "u {i}");
            }
            for (a, b) in primal.alpha.iter().zip(&dual.alpha) {
                assert!((a - b).abs() < 1e-12, "α");
            }
        }
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
            pins_carry: 0,
        };
        let run = dense.run(vec![false]);
        assert!(matches!(run.end, End::NoSupport(_)), "{run:?}");
    }

    #[test]
    fn coarsening_of_a_line_halves_it_and_keeps_the_first_contact() {
        // 201 points at spacing 0.01 on a line, the smallest gap at point 137
        let x: Vec<[f64; 3]> = (0..201).map(|i| [0.01 * i as f64, 0.0, 0.0]).collect();
        let gap: Vec<f64> = (0..201).map(|i| (i as f64 - 137.0).abs()).collect();
        let levels = coarsen(&x, &gap);
        assert!(levels.len() >= 3, "{} levels", levels.len());
        let mut before = x.len();
        for (k, l) in levels.iter().enumerate() {
            assert!(l.contains(&137), "level {k} lost the first contact");
            assert!(l.len() >= COARSEST);
            assert!(
                l.len() * 4 <= before * 3,
                "level {k}: {} of {before}",
                l.len()
            );
            // spread: the kept points are 2^(k+1) spacings apart, so about n / 2^(k+1)
            let r = 0.01 * 0.99 * f64::powi(2.0, k as i32 + 1);
            for (a, &i) in l.iter().enumerate() {
                for &j in &l[..a] {
                    assert!((x[i][0] - x[j][0]).abs() >= r * (1.0 - 1e-12));
                }
            }
            assert!(
                l.len() <= 201 / (1 << (k + 1)) + 2,
                "level {k}: {}",
                l.len()
            );
            before = l.len();
        }
    }

    #[test]
    fn nested_run_ends_in_the_plain_runs_solution_in_fewer_fine_steps() {
        // A coupled line of 129 nodes pressed onto a flat obstacle: C_ij = exp(−|i−j| / 8)
        // (positive definite), d₀ a parabola deepest at the middle.
        let n = 129;
        let cmat = DMatrix::from_fn(n, n, |i, j| (-(i as f64 - j as f64).abs() / 8.0).exp());
        let d0: Vec<f64> = (0..n)
            .map(|i| {
                let t = (i as f64 - 64.0) / 64.0;
                -1.0 + 2.0 * t * t
            })
            .collect();
        let gap = vec![0.0; n];
        let x: Vec<[f64; 3]> = (0..n).map(|i| [i as f64, 0.0, 0.0]).collect();
        let g = DMatrix::<f64>::zeros(n, 0);
        let dense = no_modes(&cmat, &d0, &gap, &g, 50);
        let mut start = vec![false; n];
        start[64] = true;
        let plain = dense.run(start.clone());
        let nested = dense.run_nested(start, &x);
        assert_eq!(plain.end, End::Converged);
        assert_eq!(nested.end, End::Converged);
        assert_eq!(nested.active, plain.active);
        for i in 0..n {
            assert!((nested.lambda[i] - plain.lambda[i]).abs() <= 1e-12);
        }
        assert!(!nested.coarse.is_empty());
        assert!(
            nested.steps.len() < plain.steps.len(),
            "fine steps: nested {} plain {}",
            nested.steps.len(),
            plain.steps.len()
        );
    }

    #[test]
    fn dof_order_keeps_nodes_together_and_the_schur_dofs_last() {
        // 5 nodes, 2 dofs each; node order 4 2 0 3 1; Schur: nodes 2 and 0 (listed 2 first)
        let node_perm = [2, 4, 1, 3, 0];
        let schur = [4, 5, 0, 1];
        let order = dof_order(&node_perm, &schur, 2, 10);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..10).collect::<Vec<_>>(), "not a permutation");
        // the other nodes in Scotch's order 4, 3, 1, then the Schur dofs in their list order
        assert_eq!(order, vec![8, 9, 4, 5, 6, 7, 2, 3, 0, 1]);
    }

    #[test]
    fn nested_dissection_orders_a_grid() {
        // a 20 × 20 grid graph: a permutation, with the first separator (the last positions)
        // splitting the grid
        let (m, n) = (20usize, 400usize);
        let mut xadj = vec![0];
        let mut adj = Vec::new();
        for v in 0..n {
            let (i, j) = (v / m, v % m);
            for (di, dj) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                let (a, b) = (i as i64 + di, j as i64 + dj);
                if a >= 0 && b >= 0 && (a as usize) < m && (b as usize) < m {
                    adj.push(a as usize * m + b as usize);
                }
            }
            xadj.push(adj.len());
        }
        let perm = nested_dissection(&xadj, &adj).unwrap();
        let mut sorted = perm.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..n).collect::<Vec<_>>());
        // nested dissection eliminates a separator last: the last 20 positions do not hold a
        // connected corner block of the natural order (as a band order would)
        let last: Vec<usize> = (0..n).filter(|&v| perm[v] >= n - m).collect();
        assert!(last
            .iter()
            .any(|&v| v / m > 0 && v / m < m - 1 && v % m > 0 && v % m < m - 1));
        assert!(
            nested_dissection(&[0, 1], &[5]).is_err(),
            "malformed graph accepted"
        );
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
