//! The Schur path's candidates: the first zone and its held interior, the growth between
//! rounds, the candidates' records and the dense compliance on them.

use super::stop::Stop;
use crate::contact::Frame;
use crate::linsolve::{NumericSchur, SymbolicSchur};
use crate::par::Ctx;
use crate::petsc::lapack::DenseCholesky;
use crate::petsc::mumps::{FactorStats, NodeBases, SchurRequest};
use crate::petsc::ndfactor::node_order;
use crate::say;
use crate::signorini::boundary::ContactBoundary;
use crate::signorini::dense::{pack_upper, pack_upper_of_lower, CMatrix, DenseRun};
use crate::signorini::rigid::FreeModes;
use crate::signorini::step_system::ReducedSystem;
use crate::tuning::{
    CANDIDATE_GROWTH, DENSE_FLOOR_FLOPS, DENSE_SPEEDUP_2D, FIRST_FRACTION, FIRST_SCHUR_SHARE,
    LOCATED_MARGIN, MAX_ROUNDS, MAX_SCHUR_DOFS, MIN_CANDIDATES,
};
use nalgebra::{DMatrix, DVector};
use std::borrow::Cow;
use std::collections::HashSet;
use std::time::Instant;

/// The size of the system a solve condenses: the dimension and the global number of rows.
pub(super) struct Shape {
    pub(super) dim: usize,
    pub(super) n_rows: usize,
}

/// The candidates a round adds ([`Compliance::grow`]) and how the set came about (for the
/// log).
#[derive(Clone, Copy)]
pub(super) struct Added<'a> {
    pub(super) nodes: &'a [usize],
    pub(super) why: &'a str,
}

/// [`MAX_SCHUR_DOFS`], or the test-only limit that replaces it (`crate::fault::limit`).
pub(super) fn max_schur_dofs() -> usize {
    crate::fault::limit("MAX_SCHUR_DOFS", MAX_SCHUR_DOFS)
}

/// A predicted contact zone is wide where the dense compliance of its nodes and their margin
/// beyond (1/LOCATED_MARGIN more), `per` dofs each, would cost more than `max_flops`: before
/// anything is factorised the dense work always allowed (DENSE_FLOOR_FLOPS, from about 890
/// nodes with one dof each), after a
/// factorisation the dense work that pays against it ([`Compliance::grow`]). Its interior is
/// then held on the obstacle in the factorised matrix (u_n = −g there, as the plain path's
/// reduced system (3.29) writes an active node), and only its edge band and the nodes beyond
/// are Schur variables: the Schur complement's memory and the dense work grow with the zone's
/// edge, not its area.
pub(super) fn wide(zone: usize, per: usize, max_flops: f64) -> bool {
    (((zone + zone / LOCATED_MARGIN) * per) as f64).powi(3) > max_flops
}

// tuning::BAND_FRACTION: The edge band of a held zone: the 1/BAND_FRACTION of its nodes nearest to its edge (in 2D
// 1/16 of the zone's width on either side, in 3D an annulus 6 % of a round zone's radius
// wide); with the nodes beyond the zone (1/LOCATED_MARGIN of its count) they are the Schur
// variables. The half-space model's zone edge was 2.3 % (its coarse levels) and 0.5 % of the
// zone's width from the final one on the 2D Hertz disk at 10–50 × its load, 1.5 % of the
// radius on the 3D ball; a held node that (3.23) releases, or a node beyond that comes into
// contact, starts a new pass from the set (3.23) gives.

/// The most contact nodes of `per` Schur dofs each that are not [`wide`] against the dense work
/// always allowed ([`DENSE_FLOOR_FLOPS`]). Local.
pub(super) fn floor_nodes(per: usize) -> usize {
    let mut n = (DENSE_FLOOR_FLOPS.cbrt() as usize / per.max(1)).max(1);
    while n > 1 && wide(n, per, DENSE_FLOOR_FLOPS) {
        n -= 1;
    }
    n
}

/// The rigid approach the Dirichlet data impose on a contact pair, estimated by the largest
/// prescribed displacement |u_D| of the case (the same for every pair; an obstacle's own
/// motion is in the gaps already). A body the Dirichlet data press onto its obstacle touches
/// within about this reach (elastic deformation, for the usual convex shapes, only takes gap
/// back), which the half-space model, with no load to balance, cannot locate. Between two
/// bodies that Dirichlet data drive towards each other from both sides the approach may be up
/// to twice this: the nodes beyond that touch are then found by the exact check and taken in
/// a second round (every Schur variable more makes the factorisation dearer: the estimate
/// is not doubled). Collective.
pub(super) fn dirichlet_reach(ctx: &Ctx, fixed: &[f64]) -> f64 {
    let local = fixed
        .iter()
        .filter(|v| v.is_finite())
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    ctx.max_f64(local)
}

/// A friction solve's zone held sticking in K_p where every dof of its nodes is too many for
/// the dense limits ([`solve_keeping`]).
#[derive(Clone, Copy, Default)]
pub(crate) struct Sticking<'a> {
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

/// The predicted contact zone a solve starts from, over every contact node (c_h's global
/// order), where it is [`wide`]: the nodes the
/// half-space model put in contact (`located`: the `on` nodes of smallest clearance), else
/// the start set. `None`: a narrower zone (every candidate a Schur variable). Local (on
/// all-gathered data).
pub(super) fn first_zone(
    all: &Candidates,
    located: Option<usize>,
    per: usize,
) -> Option<Vec<bool>> {
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
pub(super) fn hold(all: &Candidates, zone: &[bool], band: usize) -> Vec<bool> {
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

/// The candidate set from round to round: the `take` contact nodes with the smallest gaps and
/// every node whose gap equals the largest of theirs (equal gaps are alike to this rule: a flat
/// face is taken whole, and when it exceeds the Schur limit the plain path runs before anything
/// is factorised), the nodes forced in (the start set, nodes (3.23) activated beyond the
/// candidates), and the current set of every contact node (c_h's global order). Growth doubles
/// `take`, a count, so it also grows where the gaps are ≤ 0 (bodies that start touching or
/// overlapping). Held nodes (K_p holds them on the obstacle) are never candidates and always
/// in the set.
pub(super) struct Growth {
    /// Every contact node of each pair by increasing gap (ties: the gmsh tag), the held ones
    /// left out.
    by_gap: Vec<Vec<usize>>,
    /// How many of each pair's nodes by gap are candidates.
    take: Vec<usize>,
    forced: HashSet<usize>,
    pub(super) active: Vec<bool>,
    /// The nodes K_p holds on the obstacle (empty: none).
    pub(super) held: Vec<bool>,
    pub(super) held_count: usize,
    /// Why the set has the size it has (for a fallback's reason).
    pub(super) why: String,
    /// The first candidates within the Dirichlet data's reach (all pairs).
    pub(super) reached: usize,
}

impl Growth {
    /// The first candidates: of every contact pair the nodes with the smallest gaps (an
    /// eighth of the pair's nodes, at least MIN_CANDIDATES and `want` where given, all pairs
    /// together at most half the Schur limit) — per pair, since the pairs' gaps are not
    /// comparable (an obstacle moved into the body has the smallest gaps, the one that holds
    /// the body may have none below them) — and every node of the start set (the thesis'
    /// all-active start: all of them) and, with every dof of the candidates condensed
    /// (friction) and `thresholds`, every node with a Tresca threshold b_k > 0 (it acts in
    /// contact or not, (3.18)); `held` (or empty): the nodes K_p holds. `reach` (0: none):
    /// the rigid approach of the Dirichlet data ([`dirichlet_reach`]); a pair's nodes whose gap
    /// is within it are taken as well, as many as the dense work always allowed
    /// ([`DENSE_FLOOR_FLOPS`]) holds.
    pub(super) fn new(
        cand: &Candidates,
        per: usize,
        want: Option<usize>,
        held: &[bool],
        reach: f64,
        thresholds: bool,
    ) -> Growth {
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
        let limit = (max_schur_dofs() / (FIRST_SCHUR_SHARE * per * pairs)).max(1);
        // a held zone's band and margin are what it wants
        let some_held = held.iter().any(|&h| h);
        // the nodes within the Dirichlet data's reach, as many as the dense floor allows (the
        // test-only limit REACH_NODES replaces that count: 0 takes none)
        let floor = crate::fault::limit("REACH_NODES", (floor_nodes(per) / pairs).max(1));
        // (no reach: none)
        let reached_in = |b: &[usize]| b.iter().filter(|&&i| cand.gap(i) <= reach).count();
        let within: Vec<usize> = (by_gap.iter())
            .map(|b| {
                if reach > 0.0 {
                    reached_in(b).min(floor)
                } else {
                    0
                }
            })
            .collect();
        let take: Vec<usize> = by_gap
            .iter()
            .zip(&within)
            .map(|(b, &within)| {
                (if some_held {
                    0
                } else {
                    b.len() / FIRST_FRACTION
                })
                .max(want.unwrap_or(0))
                .max(within)
                .clamp(MIN_CANDIDATES.min(limit), limit)
                .min(b.len())
            })
            .collect();
        let first: usize = take.iter().sum();
        let active: Vec<bool> = (0..n).map(|i| cand.start(i) || is_held(i)).collect();
        let reached: usize = within.iter().sum();
        let by = match (want.is_some(), reached > 0) {
            (true, _) => "clearances after the located rigid motion",
            (false, true) => "gaps (all within the Dirichlet data's reach among them)",
            (false, false) => "gaps",
        };
        Growth {
            by_gap,
            take,
            // Tresca's thresholds act on every node that has one, in contact or not (3.18):
            // with every dof in the Schur complement (friction) and `thresholds`, each such
            // node is a candidate
            forced: (0..n)
                .filter(|&i| {
                    let threshold = per > 1 && thresholds && cand.bound(i) > 0.0;
                    (active[i] || threshold) && !is_held(i)
                })
                .collect(),
            active,
            held: (0..n).map(is_held).collect(),
            held_count: (0..n).filter(|&i| is_held(i)).count(),
            why: format!("the {first} nodes with the smallest {by} and the start set"),
            reached,
        }
    }

    /// Where a new pass starts (`splits`: held zones allowed): the set (3.23) gives on the
    /// expanded u (the nodes `changed` turned over), where held nodes must change or that set
    /// is [`wide`] against the dense work that pays (`max_flops`). `None`: the pass goes on
    /// (more candidates). Collective (log).
    pub(super) fn next_pass(
        &self,
        ctx: &Ctx,
        changed: &[u64],
        max_flops: f64,
        per: usize,
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
    pub(super) fn take_all(&mut self) {
        for (t, b) in self.take.iter_mut().zip(&self.by_gap) {
            *t = b.len();
        }
    }

    /// The nodes this round adds; `Err`: why the plain path takes over (none to add after the
    /// first round, or more Schur dofs than MAX_SCHUR_DOFS).
    pub(super) fn next(
        &self,
        cand: &Candidates,
        comp: &Compliance,
        round: usize,
    ) -> Result<Vec<usize>, Stop> {
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
    pub(super) fn take_dense(&mut self, comp: &Compliance, run: &DenseRun) -> Vec<f64> {
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
    pub(super) fn widen(
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
            *t = (CANDIDATE_GROWTH * *t).max(1);
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

/// Every contact node of c_h (all ranks', in c_h's global order) as the dense algorithm sees
/// it: first dof row, normal, gap, start flag, position, the reference tangential displacement
/// u_τ^ref (friction), and the free modes' parts G of its rows along n, t₁ (, t₂).
pub(crate) struct Candidates {
    all: Vec<f64>,
    pub(crate) n: usize,
    pub(super) mz: usize,
    /// Values per record: [`HEAD`] + dim · m_z.
    rec: usize,
}

/// Values per candidate record before the free modes' parts: row, n (3), gap, start, x (3),
/// u_τ^ref (2), pair, μ, the order key, the gmsh tag (exact in f64 below 2⁵³), Tresca's b_k.
const HEAD: usize = 16;

impl Candidates {
    /// One all-gather. `key`: what orders this rank's nodes for the first candidates (the
    /// clearance after a located rigid motion, [`crate::signorini::halfspace::locate`]); `None`: the gap.
    /// Collective.
    pub(super) fn gather(
        ctx: &Ctx,
        b: &ContactBoundary,
        free: &FreeModes,
        start: &[bool],
        key: Option<&[f64]>,
    ) -> Candidates {
        let mz = free.dirichlet_free().ncols();
        let dim = free.rigid_modes().dim;
        let rec = HEAD + dim * mz;
        let mut mine = Vec::with_capacity(b.nodes.len() * rec);
        for (i, (k, &a)) in b.nodes.iter().zip(start).enumerate() {
            let n = k.frame.n;
            let flag = if a { 1.0 } else { 0.0 };
            mine.extend_from_slice(&[k.row as f64, n[0], n[1], n[2], k.gap, flag]);
            mine.extend_from_slice(&k.x);
            mine.extend_from_slice(&k.u_t_ref);
            mine.push(k.pair as f64);
            mine.push(k.mu);
            mine.push(key.map_or(k.gap, |key| key[i]));
            mine.push(k.tag as f64);
            mine.push(k.bound);
            for dir in [&k.frame.n, &k.frame.t[0], &k.frame.t[1]]
                .into_iter()
                .take(dim)
            {
                mine.extend(free.normal_parts(k, dir));
            }
        }
        let all = ctx.all_gather_varcount(&mine);
        let n = all.len() / rec;
        Candidates { all, n, mz, rec }
    }

    fn rec(&self, i: usize) -> &[f64] {
        &self.all[i * self.rec..(i + 1) * self.rec]
    }
    pub(super) fn row(&self, i: usize) -> usize {
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
    /// The free mode c's part of the normal row.
    pub(super) fn g(&self, i: usize, c: usize) -> f64 {
        self.rec(i)[HEAD + c]
    }
    /// The free mode c's part of the row along the frame's direction a (n, t₁, t₂).
    pub(super) fn g_along(&self, i: usize, a: usize, c: usize) -> f64 {
        self.rec(i)[HEAD + a * self.mz + c]
    }
    /// The node frame as an orthonormal basis, normal first (columns: n, t₁, t₂).
    pub(super) fn basis(&self, i: usize, dim: usize) -> [[f64; 3]; 3] {
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
        [r[6], r[7], r[8]]
    }
    pub(super) fn u_t_ref(&self, i: usize) -> [f64; 2] {
        let r = self.rec(i);
        [r[9], r[10]]
    }
    pub(super) fn n(&self, i: usize) -> [f64; 3] {
        [self.normal(i, 0), self.normal(i, 1), self.normal(i, 2)]
    }
    /// The candidate's contact pair.
    pub(super) fn pair(&self, i: usize) -> usize {
        self.rec(i)[11] as usize
    }
    /// The candidate's Coulomb μ.
    pub(super) fn mu(&self, i: usize) -> f64 {
        self.rec(i)[12]
    }
    /// What orders the nodes for the candidates: the gap, or the clearance after a located
    /// rigid motion.
    fn key(&self, i: usize) -> f64 {
        self.rec(i)[13]
    }
    /// The node's gmsh tag: what breaks ties between nodes, the same on every partition (c_h's
    /// global order is rank-major).
    pub(super) fn tag(&self, i: usize) -> u64 {
        self.rec(i)[14] as u64
    }
    /// The node's Tresca threshold b_k (3.18) (0: none).
    pub(super) fn bound(&self, i: usize) -> f64 {
        self.rec(i)[15]
    }
    /// `a` before `b` by the order key, ties by the gmsh tag. Local.
    pub(super) fn by_key(&self, a: usize, b: usize) -> std::cmp::Ordering {
        self.key(a)
            .total_cmp(&self.key(b))
            .then(self.tag(a).cmp(&self.tag(b)))
    }
}

/// The compliance C = Nᵀ K_p⁻¹ N of a growing candidate set and d₀ = Nᵀ K_p⁻¹ f there. In the
/// candidates' node frames (Q, normal first) N becomes the unit columns of their normal dofs,
/// so with S the Schur complement of Qᵀ K_p Q on those dofs: C = S⁻¹ and d₀ = S⁻¹ r, r = f̃_s −
/// K̃_sr K̃_rr⁻¹ f̃_r (MUMPS' condensation of f̃ = Qᵀ f). The dense parts live on rank 0 only.
pub(crate) struct Compliance {
    /// Schur variables per candidate: 1 (the normal dof) or d (every dof, in the node frame,
    /// normal first: C then holds the tangential compliance friction needs).
    pub(super) per: usize,
    pub(super) in_s: Vec<bool>,
    /// The candidates in the order of C's rows and columns (`per` rows each).
    pub(crate) list: Vec<usize>,
    /// C = S⁻¹, its upper triangle packed ([`Compliance::c`]; rank 0).
    cmat: Vec<f64>,
    pub(super) d0: Vec<f64>,
    /// The candidates' node frames (normal first): K_p is factorised as Qᵀ K_p Q.
    bases: NodeBases,
    pub(super) factor: Option<NumericSchur>,
    /// Rank 0: the nested-dissection order of K_p's node graph (empty: MUMPS' own), made by
    /// the first `grow`.
    pub(crate) node_order: Option<Vec<usize>>,
    /// The ordering, MUMPS' analysis and factorisation in the last `grow` [s].
    pub(super) factorisation_seconds: f64,
    /// The last factorisation's statistics (MUMPS' flops estimate, factor entries).
    pub(super) stats: FactorStats,
    /// The nested-dissection ordering (graph gathered, Scotch) [s].
    pub(super) ordering_seconds: f64,
    /// The primal form (frictionless, where C = S⁻¹ would cost more than the factorisation):
    /// rank 0 keeps S itself and r (MUMPS' condensation of f), `cmat` and `d0` stay empty,
    /// and the Schur variables' part of the expansion, S⁻¹ (r − λ) = u − G α, is the dense
    /// iteration's own (`x_s`).
    pub(super) primal: bool,
    pub(super) schur: DMatrix<f64>,
    /// S itself next to C where every dof of the candidates is a Schur variable (Coulomb's
    /// primal form), its upper triangle packed ([`Compliance::stiffness`]; rank 0).
    stiff: Vec<f64>,
    pub(super) r: Vec<f64>,
    pub(super) x_s: Vec<f64>,
    /// The dense work that pays (flops): the dense compliance's or a primal step's bound.
    pub(super) max_flops: f64,
}

impl Compliance {
    pub(super) fn new(n: usize, per: usize) -> Compliance {
        Compliance {
            per,
            in_s: vec![false; n],
            list: Vec::new(),
            cmat: Vec::new(),
            d0: Vec::new(),
            bases: NodeBases::default(),
            factor: None,
            node_order: None,
            factorisation_seconds: 0.0,
            stats: FactorStats::default(),
            ordering_seconds: 0.0,
            primal: false,
            schur: DMatrix::zeros(0, 0),
            stiff: Vec::new(),
            r: Vec::new(),
            x_s: Vec::new(),
            max_flops: 0.0,
        }
    }

    /// Adds the candidates `new` (their bases for MUMPS' node frames) and returns the Schur
    /// dofs: `per` dofs of every candidate, in the node frame the normal displacement first.
    /// Local.
    fn add_candidates(&mut self, cand: &Candidates, new: &[usize], dim: usize) -> Vec<usize> {
        for &i in new {
            self.in_s[i] = true;
        }
        self.list.extend_from_slice(new);
        for &i in new {
            self.bases.q.insert(cand.row(i) / dim, cand.basis(i, dim));
        }
        self.bases.dim = dim;
        let per = self.per;
        self.list
            .iter()
            .flat_map(|&i| (0..per).map(move |a| cand.row(i) + a))
            .collect()
    }

    /// The node order for MUMPS where none is kept: with a Schur complement MUMPS would order
    /// by AMD (2.4 × the flops of PORD on a 3D block of 82 584 unknowns, measured), our
    /// nested-dissection order instead; agreed before it may turn into a fallback (a failure
    /// on one rank alone ends every rank instead). Collective.
    fn order_nodes(
        &mut self,
        ctx: &Ctx,
        reduced: &ReducedSystem,
        dim: usize,
        t: Instant,
    ) -> Result<(), Stop> {
        if self.node_order.is_none() {
            let order = ctx
                .agree_message(node_order(ctx.comm(), reduced.matrix(), dim))
                .map_err(Stop::failed)?;
            self.node_order = Some(order);
            self.ordering_seconds = t.elapsed().as_secs_f64();
        }
        Ok(())
    }

    /// Adds the candidates `added` and factorises K_p (the reduced system's matrix, of
    /// `shape`) anew in the candidates' frames with the Schur complement on their normal dofs;
    /// then C and d₀ (`f_root`: f on rank 0, empty elsewhere). `Err` (the same on every rank): why the condensed path gives up (MUMPS
    /// failed, the dense work would cost more than the factorisation, S not positive
    /// definite). Collective.
    pub(super) fn grow(
        &mut self,
        ctx: &Ctx,
        reduced: &ReducedSystem,
        cand: &Candidates,
        added: Added,
        shape: &Shape,
        f_root: &[f64],
    ) -> Result<(), Stop> {
        let (new, why) = (added.nodes, added.why);
        let (dim, n_rows) = (shape.dim, shape.n_rows);
        let dofs = self.add_candidates(cand, new, dim);
        self.factor = None; // the old factorisation's memory first
        self.cmat = Vec::new();
        self.schur = DMatrix::zeros(0, 0);
        self.stiff = Vec::new();
        let t = Instant::now();
        let symbolic = self.analyse(ctx, reduced, &dofs, dim, n_rows, t)?;
        self.choose_form(dofs.len(), dim, &symbolic, why)?;
        let done = symbolic.factorise();
        self.factorisation_seconds = t.elapsed().as_secs_f64();
        let mut factor = ctx
            .agree_message(done)
            .map_err(|e| Stop::failed(format!("the Schur factorisation of K_p failed: {e}")))?;
        self.stats = factor.stats();
        let r = ctx
            .agree_message(factor.condense(&self.rotated(f_root)))
            .map_err(|e| Stop::failed(format!("the condensation of f failed: {e}")))?;
        // S copied (primal) or inverted (dimension: the Schur dofs)
        let work = if self.primal { 0 } else { dofs.len() };
        let inverted = ctx.on_root_wide(work, || self.keep_schur(&mut factor, r, dofs.len()));
        let mut ok = vec![if inverted == Some(false) { 0.0 } else { 1.0 }];
        ctx.broadcast_f64s(&mut ok);
        self.factor = Some(factor);
        if ok[0] == 0.0 {
            return Err(Stop::failed(format!(
                "the Schur complement of K_p on the {} candidates' dofs ({} per node) is not \
                 positive definite",
                self.list.len(),
                self.per
            )));
        }
        Ok(())
    }

    /// MUMPS' analysis of K_p with the Schur complement on `dofs`, in our node order (made
    /// here where none is kept; the ordering's seconds from `t`). Collective.
    fn analyse(
        &mut self,
        ctx: &Ctx,
        reduced: &ReducedSystem,
        dofs: &[usize],
        dim: usize,
        n_rows: usize,
        t: Instant,
    ) -> Result<SymbolicSchur, Stop> {
        self.ordering_seconds = 0.0; // this factorisation's ordering (none where one is kept)
        self.order_nodes(ctx, reduced, dim, t)?;
        let order = match &self.node_order {
            Some(o) if ctx.rank == 0 && !o.is_empty() => Some(dof_order(o, dofs, dim, n_rows)),
            _ => None,
        };
        let request = SchurRequest {
            n: n_rows,
            schur_rows: dofs,
            order: order.as_deref(),
            bases: &self.bases,
        };
        let factor = reduced.analyse_schur(ctx, &request);
        drop(order);
        ctx.agree_message(factor)
            .map_err(|e| Stop::failed(format!("MUMPS' analysis of K_p failed: {e}")))
    }

    /// The dense form of the compliance for `n_dofs` Schur dofs against the factorisation's
    /// flops (the same numbers on every rank: the same decision): the dual form C = S⁻¹, or
    /// the primal form (frictionless, whose steps solve for the inactive candidates alone)
    /// where C would cost more than the factorisation; `Err` where that form does not apply
    /// either (`why`: how the set came about, for the message).
    fn choose_form(
        &mut self,
        n_dofs: usize,
        dim: usize,
        symbolic: &SymbolicSchur,
        why: &str,
    ) -> Result<(), Stop> {
        let dense = (n_dofs as f64).powi(3);
        // (the test-only limit DENSE_SPEEDUP_2D replaces the 2D factor: what a wider dense
        // phase costs is measured with it)
        let speedup = match dim {
            2 => crate::fault::limit("DENSE_SPEEDUP_2D", DENSE_SPEEDUP_2D as usize) as f64,
            _ => 1.0,
        };
        self.max_flops = DENSE_FLOOR_FLOPS.max(speedup * symbolic.flops());
        self.primal = dense > self.max_flops && self.per == 1;
        if dense > self.max_flops && !self.primal {
            return Err(Stop::too_wide(format!(
                "{} candidate contact nodes ({} Schur dofs; {}): the dense compliance ({:.1e} \
                 flops) would cost more than the factorisation of K_p ({:.1e} flops); a contact zone this \
                 wide costs less on the plain path",
                self.list.len(),
                n_dofs,
                why,
                dense,
                symbolic.flops()
            )));
        }
        Ok(())
    }

    /// Rank 0: S from `factor` (n × n) and the condensed r kept for the chosen form; `false`
    /// where S, to be inverted, is not positive definite.
    fn keep_schur(&mut self, factor: &mut NumericSchur, r: Vec<f64>, n: usize) -> bool {
        if self.primal {
            // S itself (its lower triangle, column-major, as LAPACK's Cholesky reads it)
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
        // S's one copy, factorised and inverted in place: C = S⁻¹, kept packed (its upper
        // triangle, in the same memory); with every dof of the candidates (Coulomb) S packed
        // and r too, for the primal form of its dense steps. Rank 0 holds at most 1.5 n²
        // doubles here and n² after (docs/numbers.md, "Coulomb: later passes from the pass
        // before; C and S packed")
        let sv = factor.take_schur();
        if self.per > 1 {
            self.stiff = pack_upper_of_lower(&sv, n);
            self.r = r.clone();
        }
        let Some(ch) = DenseCholesky::factor_owned(n, sv) else {
            return false;
        };
        self.cmat = pack_upper(ch.inverse().data.into(), n);
        self.d0 = self
            .c()
            .times(&DVector::from_column_slice(&r))
            .as_slice()
            .to_vec();
        true
    }

    /// C = S⁻¹ on the candidates' dofs (rank 0). Local.
    pub(super) fn c(&self) -> CMatrix<'_> {
        CMatrix::Upper {
            n: self.list.len() * self.per,
            packed: &self.cmat,
        }
    }

    /// C and d₀ on the candidates' normal dofs (the frictionless model): themselves for
    /// `per` = 1 (`None`: [`Compliance::c`]), else every `per`-th row and column (the
    /// compliance of the normal dofs with the tangential forces zero). Rank 0.
    pub(super) fn normal_part(&self) -> (Option<DMatrix<f64>>, Cow<'_, [f64]>) {
        let (n, per) = (self.list.len(), self.per);
        if per == 1 {
            return (None, Cow::Borrowed(&self.d0[..]));
        }
        let normal: Vec<usize> = (0..n).map(|i| i * per).collect();
        let block = self.c().block(&normal);
        let d = (0..n).map(|i| self.d0[i * per]).collect::<Vec<f64>>();
        (Some(block), Cow::Owned(d))
    }

    /// d₀ = C r for a new f on the kept factorisation (`f_root`: f on rank 0), r MUMPS'
    /// condensation of Qᵀ f. `Err`: the solve phase failed. Collective.
    pub(super) fn recondense(&mut self, ctx: &Ctx, f_root: &[f64]) -> Result<(), String> {
        let rhs = self.rotated(f_root);
        let factor = self.factor.as_mut().ok_or("no factorisation kept")?;
        let r = ctx
            .agree_message(factor.condense(&rhs))
            .map_err(|e| format!("the condensation of f failed: {e}"))?;
        if ctx.rank == 0 {
            self.d0 = self
                .c()
                .times(&DVector::from_column_slice(&r))
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
    /// dense Coulomb steps (schur/coulomb.rs). `None` elsewhere.
    pub(super) fn stiffness(&self) -> Option<(CMatrix<'_>, &[f64])> {
        let n = self.list.len() * self.per;
        (!self.primal && self.per > 1 && n > 0 && self.stiff.len() == n * (n + 1) / 2).then(|| {
            let s = CMatrix::Upper {
                n,
                packed: &self.stiff,
            };
            (s, &self.r[..])
        })
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
        f_root: &[f64],
        n_local: usize,
        lam: &[f64],
        x_s: &[f64],
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
                (d0 - self.c().times(&DVector::from_column_slice(lam)))
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
pub(super) fn dof_order(
    node_perm: &[usize],
    schur: &[usize],
    dim: usize,
    n_rows: usize,
) -> Vec<usize> {
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

#[cfg(test)]
mod tests {
    use super::{floor_nodes, wide, Candidates, Growth, HEAD};
    use crate::tuning::{DENSE_FLOOR_FLOPS, FIRST_FRACTION};

    /// `n` contact nodes of one pair along a line, x in [−1, 1], gaps x²/2 (a unit disk over a
    /// plane), none in the start set.
    fn line(n: usize) -> Candidates {
        let mut all = Vec::with_capacity(n * HEAD);
        for i in 0..n {
            let x = -1.0 + 2.0 * i as f64 / (n - 1) as f64;
            let gap = 0.5 * x * x;
            let head = [
                i as f64, 0.0, 1.0, 0.0, gap, 0.0, x, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, gap, i as f64,
                0.0,
            ];
            all.extend_from_slice(&head);
        }
        Candidates {
            all,
            n,
            mz: 0,
            rec: HEAD,
        }
    }

    #[test]
    fn the_first_candidates_take_every_node_within_the_dirichlet_reach() {
        let cand = line(2001);
        // no reach: an eighth of the nodes
        let plain = Growth::new(&cand, 1, None, &[], 0.0, false);
        assert_eq!(plain.take, vec![2001 / FIRST_FRACTION]);
        // reach 0.08: |x| ≤ 0.4, about 800 nodes, more than an eighth
        let within = (0..cand.n).filter(|&i| cand.gap(i) <= 0.08).count();
        assert!((799..=801).contains(&within), "{within}");
        let reached = Growth::new(&cand, 1, None, &[], 0.08, false);
        assert_eq!(reached.take, vec![within]);
        assert!(reached.why.contains("reach"), "{}", reached.why);
        // a reach over every node: as many as the dense floor allows, per dof of a node
        for per in [1, 2, 3] {
            let all = Growth::new(&cand, per, None, &[], 10.0, false);
            let floor = floor_nodes(per);
            assert!(
                !wide(floor, per, DENSE_FLOOR_FLOPS) && wide(floor + 1, per, DENSE_FLOOR_FLOPS)
            );
            assert_eq!(all.take, vec![floor.clamp(2001 / FIRST_FRACTION, 2001)]);
        }
    }
}
