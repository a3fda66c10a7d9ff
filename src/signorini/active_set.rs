//! The sets of Algorithms 1 and 2 on this rank's contact nodes, an iterate's multipliers (3.28)
//! and the set update (3.23)/(3.33) with its one reduction per Newton step.

use super::boundary::{ContactBoundary, ContactNode, NodeResult};
use super::rigid::{BodyModes, Gram};
use crate::case::NewtonInit;
use crate::contact::{self, CoulombRow, NodeState};
use crate::par::Ctx;

use super::law::increment;
/// The law of a solve (law/: one type per law).
pub use super::law::Law;

/// The largest threshold b over every rank's contact nodes at the iterate `nodes` (Tresca: the
/// given b_k; Coulomb: (F1)): the scale of the stick band of each law's `stays_stuck`
/// (law/rules.rs). 0 without friction. Collective (one reduction) with friction.
pub fn threshold_scale(
    ctx: &Ctx,
    b: &ContactBoundary,
    nodes: &[NodeResult],
    law: Law,
    c: f64,
) -> f64 {
    if !law.friction() {
        return 0.0;
    }
    ctx.max_f64(threshold_scale_local(b, nodes, law, c))
}

/// [`threshold_scale`] over the nodes of `b` alone. Local.
pub fn threshold_scale_local(b: &ContactBoundary, nodes: &[NodeResult], law: Law, c: f64) -> f64 {
    b.nodes
        .iter()
        .zip(nodes)
        .map(|(k, r)| law.rules().threshold(k, r, c))
        .filter(|x| x.is_finite())
        .fold(0.0, f64::max)
}

/// A slip row whose spring L̃ is at most this fraction of c holds no rigid mode (`holds_tangent`):
/// L̃ ≈ c b/|v| of a node slipping far beyond its threshold rounds to 1e-16 c (measured on the
/// Tresca Hertz disk, every node slipping in step 4), and a mode held by such springs alone
/// makes the system singular to round-off: the pins take it instead. The spring stays in the
/// row (the Newton linearisation is unchanged). Against the body's stiffness, not against a c
/// larger than the default ([`spring_floor`]).
pub const SPRING_TOL: f64 = 1e-10;

/// The springs up to which a slip row holds no rigid mode: [`SPRING_TOL`] × c, c at most the
/// default c of the boundary's nodal stiffness (the system's scale: a spring is round-off
/// against the matrix, not against c). With c = 1e10 on the Tresca block of
/// tests/cases/tresca (E = 2; 10¹⁰ × its default) the floor 1e-10 c = 1 exceeded the slip
/// rows' springs L̃ ≈ b/|Δu_τ| ≈ 6e-3, the free tangential mode was pinned and kept a load
/// of 2.7e-3 of the applied one. Pure.
pub fn spring_floor(b: &ContactBoundary, c: f64) -> f64 {
    let scale = match b.stiffness > 0.0 {
        true => c.min(crate::tuning::DEFAULT_C_FACTOR * b.stiffness),
        false => c,
    };
    SPRING_TOL * scale
}

/// A_n (and, with friction, the tangential row of every node: stick, or slip with L̃, r̃ (3.39)
/// and, for Coulomb, the λ_n coupling q (F6)) on this rank's contact nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct ActiveSet {
    /// k ∈ A_n.
    pub normal: Vec<bool>,
    /// With friction: the tangential row of each node; `None` without friction (no
    /// tangential state is formed or tested).
    pub tangential: Option<Vec<CoulombRow<2>>>,
    /// [`SPRING_TOL`] · c: springs up to this hold no rigid mode.
    pub spring_floor: f64,
    /// Every node of A_n also sticks (u_τ = u_ref), without friction rows elsewhere: the
    /// interior of a wide zone held in the factorised matrix of a friction solve
    /// ([`ActiveSet::held`]).
    pub stick_active: bool,
}

/// What one node's rows prescribe: directions c with cᵀu^k = value.
#[derive(Clone, Debug, PartialEq)]
pub struct Prescribed {
    pub dirs: Vec<([f64; 3], f64)>,
    /// A slip row (3.39) / (F6) for the increment: L̃, r̃ go to the node's own block, a
    /// Coulomb coupling q to its rows (step_system/).
    pub slip: Option<CoulombRow<2>>,
}

/// A set as all ranks see it: |A_n|, two fingerprints, the Gram matrix of its constraint rows
/// against the rigid modes.
#[derive(Clone, Debug, PartialEq)]
pub struct SetSummary {
    pub n_active: usize,
    pub fingerprint: (f64, f64),
    pub gram: Gram,
}

/// Two fingerprints of a node state that do not depend on the partition (hashes of gmsh tags,
/// exact in f64 when summed).
fn node_hash(tag: u64) -> (f64, f64) {
    let mut x = tag.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 29;
    let mut y = tag.wrapping_mul(0xC2B2_AE3D_27D4_EB4F) ^ 0x1656_67B1_9E37_79F9;
    y ^= y >> 31;
    ((x >> 44) as f64, (y >> 44) as f64)
}

/// Does a tangential row hold u_τ (stick, or slip with a spring L̃ beyond `floor`)?
fn holds_tangent(r: &CoulombRow<2>, floor: f64) -> bool {
    match r {
        CoulombRow::Stick => true,
        CoulombRow::Slip { l, .. } => l.iter().flatten().any(|&x| x.abs() > floor),
    }
}

impl ActiveSet {
    /// The first set A_n^1 (and, with friction, the rows from u = 0, λ = 0: Tresca: stick where
    /// b_k > 0 (3.33), slip with λ_τ = 0 where b_k = 0 (§3.4.3); Coulomb: b of (F1) is 0 unless
    /// the node penetrates, so mostly λ_τ = 0).
    pub fn initial(
        b: &ContactBoundary,
        init: NewtonInit,
        law: Law,
        c: f64,
        scale: f64,
        dim: usize,
    ) -> ActiveSet {
        let touching = |g: f64| g <= 1e-9 * scale;
        let normal = b
            .nodes
            .iter()
            .map(|k| match init {
                NewtonInit::AllActive => true,
                NewtonInit::AllInactive => false,
                // "gap" and our default "auto": the initially touching nodes (empty if none
                // touches, which is the all-inactive start). Fewer steps than the thesis'
                // all-active start at every Hertz level measured (README).
                NewtonInit::Gap | NewtonInit::Auto => touching(k.gap),
            })
            .collect();
        let tangential = law.friction().then(|| {
            b.nodes
                .iter()
                .map(|k| {
                    let zero = NodeResult {
                        u_t: k.u_t_ref,
                        ..NodeResult::default()
                    };
                    law.rules().row(k, &zero, c, dim)
                })
                .collect()
        });
        ActiveSet {
            normal,
            tangential,
            spring_floor: spring_floor(b, c),
            stick_active: false,
        }
    }

    /// A frictionless set with the normal states `normal`.
    pub fn frictionless(normal: Vec<bool>) -> ActiveSet {
        ActiveSet {
            normal,
            tangential: None,
            spring_floor: 0.0,
            stick_active: false,
        }
    }

    /// The nodes `held` (this rank's) fixed in the factorised matrix: on the obstacle
    /// (nᵀu = −g), and with `stick` also sticking (τᵀu = u_ref, (3.34a)); every other node's
    /// rows as in A. Local.
    pub fn held(held: Vec<bool>, stick: bool) -> ActiveSet {
        ActiveSet {
            stick_active: stick,
            ..ActiveSet::frictionless(held)
        }
    }

    /// A warm start (a previous load step): A_n of the solve that produced `nodes`, the
    /// tangential rows from that iterate (its increment is 0 where u_ref is its own u_τ);
    /// `scale` = [`threshold_scale`] of `nodes`. Local.
    pub fn warm(
        b: &ContactBoundary,
        nodes: &[NodeResult],
        law: Law,
        c: f64,
        scale: f64,
        dim: usize,
    ) -> ActiveSet {
        let tangential = law.friction().then(|| {
            b.nodes
                .iter()
                .zip(nodes)
                .map(|(k, r)| {
                    // Δu_τ = 0: a node at the slip limit starts as stick (the first solve then
                    // tells whether the new load makes it slip, with a well-defined direction).
                    let row = law.rules().row(k, r, c, dim);
                    if row.is_slip() && law.rules().stays_stuck(k, r, c, scale) {
                        CoulombRow::Stick
                    } else {
                        row
                    }
                })
                .collect()
        });
        ActiveSet {
            normal: nodes.iter().map(|r| r.active).collect(),
            tangential,
            spring_floor: spring_floor(b, c),
            stick_active: false,
        }
    }

    pub fn friction(&self) -> bool {
        self.tangential.is_some()
    }

    /// k ∈ A_τ (friction only).
    pub fn slip(&self, i: usize) -> bool {
        self.tangential.as_ref().is_some_and(|t| t[i].is_slip())
    }

    /// The node state S1..S4 (thesis, after (3.41)).
    pub fn state(&self, i: usize) -> NodeState {
        NodeState::new(self.normal[i], self.slip(i))
    }

    /// This rank's |A_n|.
    pub fn local_active(&self) -> usize {
        self.normal.iter().filter(|&&a| a).count()
    }

    /// What node i's rows prescribe in the reduced system (3.29)/(3.42): the active normal
    /// (nᵀu = −g), stick tangents (τᵀu = 0), a slip row; `None` if the node's rows stay as in A
    /// (an inactive node without friction).
    pub fn prescribed(&self, b: &ContactBoundary, i: usize, dim: usize) -> Option<Prescribed> {
        let k = &b.nodes[i];
        let row = self.tangential.as_ref().map(|t| t[i]);
        if !self.normal[i] && row.is_none() {
            return None;
        }
        let mut dirs = Vec::new();
        if self.normal[i] {
            dirs.push((k.frame.n, -k.gap));
        }
        if matches!(row, Some(CoulombRow::Stick)) || (self.stick_active && self.normal[i]) {
            // u_τ' = u_ref (3.34a) for the increment
            for (t, v) in k.frame.t[..dim - 1].iter().zip(k.u_t_ref) {
                dirs.push((*t, v));
            }
        }
        Some(Prescribed {
            dirs,
            slip: row
                .filter(|r| r.is_slip())
                .map(|r| r.with_reference(&k.u_t_ref)),
        })
    }

    /// The set of a force-control lift (force.rs): the same rows with the slip rows'
    /// constants dropped (Tresca −λ_τ + L (u_τ − u_ref) = 0, Coulomb (F6)
    /// −λ_τ + L (u_τ − u_ref) − q λ_n = 0 with its coupling q kept: the lift has no loads, its
    /// u_ref is the obstacle's tangential motion per unit approach).
    pub fn lift(&self) -> ActiveSet {
        let mut s = self.clone();
        if let Some(t) = s.tangential.as_mut() {
            for row in t.iter_mut() {
                if let CoulombRow::Slip { r, .. } = row {
                    *r = [0.0; 2];
                }
            }
        }
        s
    }

    /// Local sums of the per-node hashes of the states (partition-independent when summed).
    fn fingerprint(&self, b: &ContactBoundary) -> (f64, f64) {
        let mut h = (0.0, 0.0);
        for (i, k) in b.nodes.iter().enumerate() {
            let state = self.normal[i] as u64 + 2 * self.slip(i) as u64;
            if state != 0 {
                let (x, y) = node_hash(k.tag.wrapping_mul(4).wrapping_add(state));
                h.0 += x;
                h.1 += y;
            }
        }
        h
    }

    /// Local Gram matrix of the set's constraint rows against the rigid modes: nᵀ at active
    /// nodes; with friction also τᵀ where the tangential row holds u_τ. Zero without `modes`.
    fn gram(&self, b: &ContactBoundary, modes: Option<&BodyModes>, dim: usize) -> Gram {
        let Some(modes) = modes else {
            return Vec::new();
        };
        let mut g = modes.zero_gram();
        self.held_rows(b, dim, |i, c| {
            let k = &b.nodes[i];
            modes.add_outer(&mut g, &modes.direction_row(k.node, &k.x, c))
        });
        g
    }

    /// Calls `row(i, c)` for every constraint row cᵀ u_i of the set at this rank's node i: the
    /// normal n of an active node; with friction also the tangents τ where the tangential row
    /// holds u_τ (stick, or a slip row with a spring). Local.
    pub fn held_rows(
        &self,
        b: &ContactBoundary,
        dim: usize,
        mut row: impl FnMut(usize, &[f64; 3]),
    ) {
        for (i, k) in b.nodes.iter().enumerate() {
            if self.normal[i] {
                row(i, &k.frame.n);
            }
            let sticks = self.stick_active && self.normal[i];
            if sticks
                || self
                    .tangential
                    .as_ref()
                    .is_some_and(|t| holds_tangent(&t[i], self.spring_floor))
            {
                for t in &k.frame.t[..dim - 1] {
                    row(i, t);
                }
            }
        }
    }

    /// Local part of the summary, packed: |A_n|, fingerprints, Gram.
    fn pack_summary(&self, b: &ContactBoundary, modes: Option<&BodyModes>, dim: usize) -> Vec<f64> {
        let (h1, h2) = self.fingerprint(b);
        let mut v = vec![self.local_active() as f64, h1, h2];
        v.extend(self.gram(b, modes, dim));
        v
    }

    /// The set as all ranks see it (one Allreduce).
    pub fn summarise(
        &self,
        ctx: &Ctx,
        b: &ContactBoundary,
        modes: Option<&BodyModes>,
        dim: usize,
    ) -> SetSummary {
        unpack_summary(
            &ctx.sum_vec(&self.pack_summary(b, modes, dim)),
            grams(modes),
        )
    }

    /// (3.23) and, with friction, (3.33) (Tresca) or (F1)/(F5) (Coulomb) with the newest
    /// iterate (THEORY §4 erratum): the next sets, and what changed; `scale` =
    /// [`threshold_scale`] of the iterate (friction; unused without). Local.
    pub fn update(
        &self,
        it: &Iterate,
        b: &ContactBoundary,
        law: Law,
        c: f64,
        scale: f64,
        dim: usize,
    ) -> SetUpdate {
        self.update_with(it, b, law, c, scale, dim, false, 0.0)
    }

    /// [`ActiveSet::update`], with `settle` the rows of settled slip (the law's `settled`, 2D
    /// Coulomb): the condensed Coulomb iteration's update (docs/friction.md, "Settled slip");
    /// and `tie` > 0 the width within which a node's (3.23) test is a tie and keeps its state
    /// ([`contact::ties`]; 0: the test's sign alone). Local.
    #[allow(clippy::too_many_arguments)]
    pub fn update_with(
        &self,
        it: &Iterate,
        b: &ContactBoundary,
        law: Law,
        c: f64,
        scale: f64,
        dim: usize,
        settle: bool,
        tie: f64,
    ) -> SetUpdate {
        let mut next = self.clone();
        let mut changed = 0usize;
        let mut residual2 = 0.0;
        let mut lambda2 = 0.0;
        let mut u2 = 0.0;
        let mut states = [0usize; 4];
        let mut rows2 = [0.0; 2];
        let rules = law.rules();
        for (i, (k, r)) in b.nodes.iter().zip(&it.nodes).enumerate() {
            states[self.state(i).number() as usize - 1] += 1;
            next.normal[i] = if tie > 0.0 {
                contact::normal_active_or_tie(r.u_n, r.lambda_n, k.gap, c, tie, self.normal[i])
            } else {
                contact::normal_active(r.u_n, r.lambda_n, k.gap, c)
            };
            let mut flip = next.normal[i] != self.normal[i];
            let cn = contact::c_n(r.u_n, r.lambda_n, k.gap, c);
            residual2 += cn * cn;
            if let Some(t) = next.tangential.as_mut() {
                t[i] = rules.row(k, r, c, dim);
                if t[i].is_slip() && !self.slip(i) && rules.stays_stuck(k, r, c, scale) {
                    t[i] = CoulombRow::Stick;
                }
                if settle {
                    let prev = self.tangential.as_ref().map(|p| p[i]);
                    t[i] = rules.settled(prev, t[i], k, r, c, dim);
                }
                flip |= t[i].is_slip() != self.slip(i);
                if let (Some(own), true) = (self.tangential.as_ref(), t[i] != CoulombRow::Stick) {
                    rows2[0] += row_residual2(&own[i], k, r, c);
                    rows2[1] += row_residual2(&t[i], k, r, c);
                }
                residual2 += rules.residual2(k, r, c);
                lambda2 += r.lambda.iter().map(|x| x * x).sum::<f64>();
                u2 += r.u.iter().map(|x| x * x).sum::<f64>();
            }
            if flip {
                changed += 1;
            }
        }
        SetUpdate {
            next,
            changed,
            residual2,
            lambda2,
            u2,
            states,
            du2: it.du2,
            uu: it.uu,
            rows2,
        }
    }
}

/// The Gram matrix's entries in a packed summary: M² (none without modes).
fn grams(modes: Option<&BodyModes>) -> usize {
    modes.map_or(0, |m| m.count() * m.count())
}

fn unpack_summary(v: &[f64], grams: usize) -> SetSummary {
    SetSummary {
        n_active: v[0] as usize,
        fingerprint: (v[1], v[2]),
        gram: v[3..3 + grams].to_vec(),
    }
}

/// One iterate on this rank's contact nodes: u and λ per node (3.28), and with friction the
/// norms of Algorithm 2's stopping rule.
pub struct Iterate {
    pub nodes: Vec<NodeResult>,
    /// This rank's rows of u and of A u.
    pub u_local: Vec<f64>,
    pub au_local: Vec<f64>,
    /// Friction: the previous u (for |u^ℓ − u^{ℓ−1}|), ‖u^ℓ − u^{ℓ−1}‖², ‖u^ℓ‖² (local).
    u_prev: Option<Vec<f64>>,
    du2: f64,
    uu: f64,
}

impl Iterate {
    pub fn new(n_contact: usize, n_local_rows: usize, friction: bool) -> Iterate {
        Iterate {
            nodes: vec![NodeResult::default(); n_contact],
            u_local: Vec::new(),
            au_local: Vec::new(),
            u_prev: friction.then(|| vec![0.0; n_local_rows]),
            du2: 0.0,
            uu: 0.0,
        }
    }

    /// A warm start: u^0 = `u_local` (this rank's rows) for |u^1 − u^0| and `nodes` as the
    /// iterate the first set was formed from.
    pub fn warm(&mut self, u_local: &[f64], nodes: &[NodeResult]) {
        if let Some(prev) = self.u_prev.as_mut() {
            prev.copy_from_slice(u_local);
        }
        self.nodes.copy_from_slice(nodes);
    }

    /// (3.28): λ = f − A u on the contact rows, in the node frames; the states of `set` (the
    /// set this iterate was solved with) are recorded per node. Local.
    pub fn recover(
        &mut self,
        u_local: Vec<f64>,
        au_local: Vec<f64>,
        f_local: &[f64],
        b: &ContactBoundary,
        set: &ActiveSet,
        dim: usize,
    ) {
        for (i, k) in b.nodes.iter().enumerate() {
            let mut uk = [0.0; 3];
            let mut lk = [0.0; 3];
            for j in 0..dim {
                uk[j] = u_local[k.local_row + j];
                lk[j] = f_local[k.local_row + j] - au_local[k.local_row + j];
            }
            self.nodes[i] = NodeResult {
                u: uk,
                lambda: lk,
                u_n: k.frame.normal_part(&uk),
                u_t: k.frame.tangential_part(&uk),
                lambda_n: k.frame.normal_part(&lk),
                lambda_t: k.frame.tangential_part(&lk),
                active: set.normal[i],
                slip: set.slip(i),
            };
        }
        if let Some(prev) = self.u_prev.as_mut() {
            let (mut du2, mut uu) = (0.0, 0.0);
            for (x, y) in u_local.iter().zip(prev.iter()) {
                du2 += (x - y) * (x - y);
                uu += x * x;
            }
            prev.copy_from_slice(&u_local);
            self.du2 = du2;
            self.uu = uu;
        }
        self.u_local = u_local;
        self.au_local = au_local;
    }
}

/// The update of one step on this rank.
pub struct SetUpdate {
    pub next: ActiveSet,
    /// Nodes whose state changed.
    pub changed: usize,
    /// ‖C_n‖² (+ ‖C_τ‖² (3.31) with Tresca, + the tangential (F3) with Coulomb) (3.21).
    pub residual2: f64,
    /// ‖λ‖² on the contact nodes (friction: the scale of the residual).
    pub lambda2: f64,
    /// ‖u‖² on the contact nodes (friction: c times its round-off is the residual's floor).
    pub u2: f64,
    /// Nodes in S1..S4 in the solve of this step.
    pub states: [usize; 4],
    pub du2: f64,
    pub uu: f64,
    /// Σ over the slip rows of the next set: each row's residual² at this iterate, in this
    /// step's row (the solve's round-off) and in the next step's ([`row_residual2`]).
    pub rows2: [f64; 2],
}

impl SetUpdate {
    /// Replaces the next normal set (frictionless) by `normal` (a prediction), counting the
    /// changes against `current`. Local.
    pub fn replace_normal(&mut self, current: &ActiveSet, normal: Vec<bool>) {
        self.changed = normal
            .iter()
            .zip(&current.normal)
            .filter(|(a, b)| a != b)
            .count();
        self.next.normal = normal;
    }
}

/// A system (rows, or the dense Coulomb system) holds at an iterate as well as the one it was
/// solved with where its residual there is within this factor of that one's (or of the
/// round-off floor): the iterate is its fixed point, no further step is taken
/// (plain_path/iteration.rs `rows_hold`, schur/coulomb_dense.rs `fixed_point`).
pub const FIXED_POINT_SLACK: f64 = 16.0;

/// The residual² of the tangential row `row` (3.39) / (F6), −λ_τ + L̃ Δu_τ − q (λ_n + c (u_n +
/// g)) − r̃, at the iterate `r` of node `k` (0 for a stick row, which does not depend on the
/// iterate). Pure.
fn row_residual2(row: &CoulombRow<2>, k: &ContactNode, r: &NodeResult, c: f64) -> f64 {
    let CoulombRow::Slip { l, q, r: rhs } = row else {
        return 0.0;
    };
    let du = increment(r, k);
    let s = r.lambda_n + c * (r.u_n + k.gap);
    (0..2)
        .map(|i| {
            let v = -r.lambda_t[i] + l[i][0] * du[0] + l[i][1] * du[1] - q[i] * s - rhs[i];
            v * v
        })
        .sum()
}

/// A step's update as all ranks see it.
#[derive(Clone, Debug)]
pub struct StepTotals {
    pub changed: usize,
    /// The next set.
    pub next: SetSummary,
    /// ‖C(u^ℓ, λ^ℓ)‖₂ over all contact nodes.
    pub residual: f64,
    /// ‖λ^ℓ‖₂ over all contact nodes (friction; 0 without).
    pub lambda_norm: f64,
    /// ‖u^ℓ‖₂ over all contact nodes (friction; 0 without).
    pub contact_u: f64,
    pub states: [usize; 4],
    /// |u^ℓ − u^{ℓ−1}| / |u^ℓ| (friction; 0 when u = 0).
    pub du_rel: f64,
    /// ‖u^ℓ‖².
    pub u_norm2: f64,
    /// The slip rows' residuals at u^ℓ over all contact nodes, (this step's rows, the next
    /// step's) ([`SetUpdate::rows2`]).
    pub rows: (f64, f64),
}

impl SetUpdate {
    /// The one Allreduce of a Newton step: changes, |A_n|, fingerprints and Gram matrix of the
    /// next set, residual², state counts, ‖Δu‖², ‖u‖².
    pub fn reduce(
        &self,
        ctx: &Ctx,
        b: &ContactBoundary,
        modes: Option<&BodyModes>,
        dim: usize,
    ) -> StepTotals {
        let mut local = vec![self.changed as f64, self.residual2, self.du2, self.uu];
        local.extend(self.states.map(|s| s as f64));
        local.extend(self.next.pack_summary(b, modes, dim));
        local.push(self.lambda2);
        local.push(self.u2);
        local.extend(self.rows2);
        let g = ctx.sum_vec(&local);
        let n = g.len();
        StepTotals {
            changed: g[0] as usize,
            residual: g[1].sqrt(),
            du_rel: if g[3] > 0.0 {
                (g[2] / g[3]).sqrt()
            } else {
                0.0
            },
            u_norm2: g[3],
            states: [0, 1, 2, 3].map(|j| g[4 + j] as usize),
            next: unpack_summary(&g[8..], grams(modes)),
            lambda_norm: g[n - 4].sqrt(),
            contact_u: g[n - 3].sqrt(),
            rows: (g[n - 2].sqrt(), g[n - 1].sqrt()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signorini::law::{Coulomb, FrictionLaw, Tresca};

    use crate::contact::Frame;

    fn node(bound: f64, u_t_ref: [f64; 2]) -> ContactNode {
        ContactNode {
            node: 0,
            pair: 0,
            mu: 0.1,
            tag: 7,
            row: 0,
            local_row: 0,
            x: [0.0; 3],
            frame: Frame::new([0.0, 1.0, 0.0], 2).expect("frame"),
            gap: 0.0,
            weight: 1.0,
            bound,
            u_t_ref,
        }
    }

    fn at(u_t: f64, lambda_n: f64, lambda_t: f64) -> NodeResult {
        NodeResult {
            u_n: 0.0,
            u_t: [u_t, 0.0],
            lambda_n,
            lambda_t: [lambda_t, 0.0],
            active: true,
            ..NodeResult::default()
        }
    }

    /// A held node's rows (schur/frictionless.rs' held zones): on the obstacle, and with `stick` at its
    /// reference u_τ as well; its constraint rows then hold the tangent too. Other nodes keep
    /// A's rows.
    #[test]
    fn a_held_node_sticks_only_where_asked() {
        let mut k = node(0.0, [0.3, 0.0]);
        k.gap = 0.02;
        let b = ContactBoundary {
            nodes: vec![k.clone(), k],
            n_global: 2,
            offset: 0,
            on_contact_boundary: vec![true, true],
            excluded_dirichlet: 0,
            obstacles: Vec::new(),
            keys: Default::default(),
            modes: std::sync::Arc::new(crate::mesh::BodyModes::none(2)),
            stiffness: 0.0,
        };
        for stick in [false, true] {
            let set = ActiveSet::held(vec![true, false], stick);
            assert!(!set.friction(), "no friction rows");
            let p = set.prescribed(&b, 0, 2).expect("held");
            let dirs: Vec<_> = p.dirs.iter().map(|(c, v)| (c[0], c[1], *v)).collect();
            let mut want = vec![(0.0, 1.0, -0.02)];
            if stick {
                // the first tangent, (±1, 0), at u_ref's first component
                want.push((b.nodes[0].frame.t[0][0], 0.0, 0.3));
            }
            assert_eq!(dirs, want, "stick {stick}");
            assert!(p.slip.is_none());
            assert!(set.prescribed(&b, 1, 2).is_none(), "not held: A's rows");
            let mut rows = 0;
            set.held_rows(&b, 2, |i, _| {
                assert_eq!(i, 0);
                rows += 1;
            });
            assert_eq!(rows, 1 + stick as usize);
        }
    }

    #[test]
    fn friction_acts_on_the_increment() {
        let k = node(0.1, [0.3, 0.0]);
        // u_τ = u_ref: no increment, |λ_τ| < b: stick (the row of u_τ itself would slip)
        let r = at(0.3, -1.0, 0.05);
        assert_eq!(increment(&r, &k), [0.0, 0.0]);
        assert_eq!(Tresca.row(&k, &r, 1.0, 2), CoulombRow::Stick);
        assert!(Tresca.row(&node(0.1, [0.0; 2]), &r, 1.0, 2).is_slip());
        assert_eq!(Coulomb.row(&k, &r, 1.0, 2), CoulombRow::Stick);
        // the stick row prescribes u_τ' = u_ref
        let set = ActiveSet {
            normal: vec![true],
            tangential: Some(vec![CoulombRow::Stick]),
            spring_floor: 0.0,
            stick_active: false,
        };
        let b = ContactBoundary {
            nodes: vec![k.clone()],
            n_global: 1,
            offset: 0,
            on_contact_boundary: vec![true],
            excluded_dirichlet: 0,
            obstacles: vec![crate::contact::Obstacle::Plane(
                crate::contact::Plane::new([0.0; 3], [0.0, 1.0, 0.0], 2).expect("plane"),
            )],
            keys: Default::default(),
            modes: std::sync::Arc::new(crate::mesh::BodyModes::none(2)),
            stiffness: 0.0,
        };
        let p = set.prescribed(&b, 0, 2).expect("rewritten");
        assert_eq!(p.dirs.len(), 2);
        assert_eq!(p.dirs[1].1, 0.3);
        // a slip row moves l u_ref to its right-hand side; with u_ref = 0 it is unchanged
        let row = CoulombRow::Slip {
            l: [[2.0, 0.0], [0.0, 0.0]],
            q: [0.5, 0.0],
            r: [1.0, 0.0],
        };
        assert_eq!(
            row.with_reference(&[0.3, 0.0]),
            CoulombRow::Slip {
                l: [[2.0, 0.0], [0.0, 0.0]],
                q: [0.5, 0.0],
                r: [1.6, 0.0],
            }
        );
        assert_eq!(row.with_reference(&[0.0; 2]), row);
    }

    #[test]
    fn a_settled_slip_node_takes_the_projection_row_and_one_slipping_back_sticks() {
        // μ = 0.1, λ_n = −1: b = 0.1; the node slipped in +τ (its last row's q > 0)
        let k = node(0.0, [0.0; 2]);
        let c = 10.0;
        let prev = Coulomb.row(&k, &at(1.0, -1.0, 0.1), c, 2);
        assert!(prev.coupled());
        // it slips on in +τ, λ_τ still short of b: the (F5) row has a spring and a right-hand
        // side, the settled row λ_τ' = μ(−λ_n') only
        let r = at(0.5, -1.0, 0.08);
        let row = Coulomb.row(&k, &r, c, 2);
        let CoulombRow::Slip { l, r: rhs, .. } = row else {
            panic!("slips");
        };
        assert!(l[0][0] > 0.0 && rhs[0] != 0.0);
        let want = CoulombRow::Slip {
            l: [[0.0; 2]; 2],
            q: [0.1, 0.0],
            r: [0.0; 2],
        };
        assert_eq!(Coulomb.settled(Some(prev), row, &k, &r, c, 2), want);
        // it now moves against its force (|λ_τ| ≤ b): stick
        let back = at(-0.5, -1.0, 0.08);
        let row = Coulomb.row(&k, &back, c, 2);
        assert!(row.is_slip());
        assert_eq!(
            Coulomb.settled(Some(prev), row, &k, &back, c, 2),
            CoulombRow::Stick
        );
        // a node that stuck before, or a 3D node, keeps its (F5) row
        let row = Coulomb.row(&k, &r, c, 2);
        assert_eq!(
            Coulomb.settled(Some(CoulombRow::Stick), row, &k, &r, c, 2),
            row
        );
        assert_eq!(Coulomb.settled(Some(prev), row, &k, &r, c, 3), row);
        // and so does one whose slip and force turned round together (a new direction)
        let turned = at(-0.5, -1.0, -0.09);
        let row = Coulomb.row(&k, &turned, c, 2);
        assert_eq!(Coulomb.settled(Some(prev), row, &k, &turned, c, 2), row);
    }

    #[test]
    fn a_stuck_node_at_the_limit_stays_stuck() {
        let k = node(0.1, [0.0; 2]);
        let c = 1.0;
        // |λ_τ| = b (1 + 1e-12), no motion: slips by (3.33), stays stuck with the tolerance
        let r = at(0.0, -1.0, 0.1 * (1.0 + 1e-12));
        assert!(Tresca.row(&k, &r, c, 2).is_slip());
        assert!(Tresca.stays_stuck(&k, &r, c, 0.1));
        let coulomb = Coulomb;
        assert!(coulomb.stays_stuck(&k, &r, c, 0.1));
        // clearly beyond the limit: slips
        let r = at(0.0, -1.0, 0.1 * (1.0 + 1e-6));
        assert!(!Tresca.stays_stuck(&k, &r, c, 0.1));
        assert!(!coulomb.stays_stuck(&k, &r, c, 0.1));
        // b = 0 (Coulomb, free node): never stuck
        let r = at(0.0, 0.0, 0.0);
        assert!(!coulomb.stays_stuck(&k, &r, c, 1.0));
        // a small threshold (b = 1e-4 · the boundary's largest, 10): the band is that of the
        // scale, so λ_τ exceeding b by 1e-9 · 10 (1e-4 of b) is round-off; by 1e-6 · 10 not
        let small = node(1e-3, [0.0; 2]);
        let r = at(0.0, -1.0, 1e-3 + 1e-8);
        assert!(!Tresca.stays_stuck(&small, &r, c, 0.0));
        assert!(Tresca.stays_stuck(&small, &r, c, 10.0));
        let r = at(0.0, -1.0, 1e-3 + 1e-5);
        assert!(!Tresca.stays_stuck(&small, &r, c, 10.0));
        // in the set update: a stick node at the limit keeps its state, a slip node does not
        // go back for it
        let b = ContactBoundary {
            nodes: vec![k.clone(), k.clone()],
            n_global: 2,
            offset: 0,
            on_contact_boundary: vec![true],
            excluded_dirichlet: 0,
            obstacles: vec![crate::contact::Obstacle::Plane(
                crate::contact::Plane::new([0.0; 3], [0.0, 1.0, 0.0], 2).expect("plane"),
            )],
            keys: Default::default(),
            modes: std::sync::Arc::new(crate::mesh::BodyModes::none(2)),
            stiffness: 0.0,
        };
        let mut it = Iterate::new(2, 4, true);
        let limit = at(0.0, -1.0, 0.1 * (1.0 + 1e-12));
        it.nodes = vec![limit, limit];
        let zero = CoulombRow::Slip {
            l: [[0.0; 2]; 2],
            q: [0.0; 2],
            r: [0.0; 2],
        };
        let set = ActiveSet {
            normal: vec![true, true],
            tangential: Some(vec![CoulombRow::Stick, zero]),
            spring_floor: 0.0,
            stick_active: false,
        };
        let up = set.update(&it, &b, Law::Tresca, c, 0.1, 2);
        let t = up.next.tangential.expect("friction");
        assert_eq!(t[0], CoulombRow::Stick);
        assert!(t[1].is_slip());
        assert_eq!(up.changed, 0);
        // the warm start puts both at the limit to stick
        let w = ActiveSet::warm(&b, &it.nodes, Law::Tresca, c, 0.1, 2);
        assert_eq!(
            w.tangential.expect("friction"),
            vec![CoulombRow::Stick, CoulombRow::Stick]
        );
        assert_eq!(w.normal, vec![true, true]);
    }

    #[test]
    fn round_off_springs_hold_nothing() {
        let c = 2.0;
        let floor = SPRING_TOL * c;
        // slipping far beyond a tiny threshold: L̃ ≈ c b/|v| = 2e-12 c, round-off: holds nothing
        let r = at(1.0, -1.0, 0.0);
        let tiny = Tresca.row(&node(2e-12, [0.0; 2]), &r, c, 2);
        assert!(tiny.is_slip());
        assert!(holds_tangent(&tiny, 0.0) && !holds_tangent(&tiny, floor));
        // a real spring (b/|v| = 0.05) holds u_τ
        let real = Tresca.row(&node(0.1, [0.0; 2]), &r, c, 2);
        assert!(real.is_slip() && holds_tangent(&real, floor));
        assert!(holds_tangent(&CoulombRow::Stick, floor));
    }

    #[test]
    fn coulomb_rows_carry_the_coupling() {
        let k = ContactNode {
            mu: 0.3,
            ..node(0.0, [0.0; 2])
        };
        // pressed (λ_n = −1), slipping fast: S4 with q ≠ 0; free node: zero row
        let r = at(0.5, -1.0, 0.3);
        let row = Coulomb.row(&k, &r, 1.0, 2);
        assert!(row.is_slip() && row.coupled());
        let free = NodeResult {
            u_n: 0.2,
            ..NodeResult::default()
        };
        let row = Coulomb.row(&k, &free, 1.0, 2);
        assert!(row.is_slip() && !row.coupled());
        // Tresca rows never couple
        let t = Tresca.row(&node(0.1, [0.0; 2]), &r, 1.0, 2);
        assert!(!t.coupled());
    }

    #[test]
    fn hashes_are_exact_in_f64_sums() {
        let (x, y) = node_hash(12345);
        assert!(x < (1u64 << 20) as f64 && y < (1u64 << 20) as f64);
        assert_ne!(node_hash(1), node_hash(2));
    }

    #[test]
    fn a_row_holds_at_the_iterate_it_was_formed_from_where_it_has_settled() {
        // a 2D Tresca slip row formed at a slip solution (|λ_τ| = b): λ_τ' = ±b, which that
        // iterate satisfies; a row formed where λ_τ is not yet b does not hold there
        let k = node(0.1, [0.0; 2]);
        let at = |lt: f64, ut: f64| NodeResult {
            u_t: [ut, 0.0],
            lambda_t: [lt, 0.0],
            ..NodeResult::default()
        };
        let settled = at(0.1, 0.3);
        let row = Tresca.row(&k, &settled, 1.0, 2);
        assert!(row.is_slip());
        assert!(row_residual2(&row, &k, &settled, 1.0) < 1e-30);
        let moving = at(0.05, 0.3);
        let row = Tresca.row(&k, &moving, 1.0, 2);
        assert!(row.is_slip());
        assert!(row_residual2(&row, &k, &moving, 1.0) > 1e-6);
        assert_eq!(row_residual2(&CoulombRow::Stick, &k, &moving, 1.0), 0.0);
    }
}
