//! Force control (`contact.force`; docs/obstacles.md, "Force control"): the obstacle moves
//! along e = F/|F| by an approach δ that is an unknown of the active-set iteration, with the
//! one extra equation that the contact force along e equals |F|:
//!
//! ```text
//!     P(u) = Σ_k (−λ_k)·e = |F|,   λ = f − A u (3.28),   the gaps g_k(δ) = g0_k − δ w_k,
//!     w_k = n_k·e.
//! ```
//!
//! For a fixed active set the solution of (3.29) is affine in δ, u(δ) = u(δ_ℓ) + (δ − δ_ℓ) u¹,
//! where the lift u¹ solves the same reduced system with f = 0, no Dirichlet values and the
//! active nodes' normal values u¹_n = w_k. P is then affine too, P(δ) = P_ℓ + (δ − δ_ℓ) P¹ with
//! P¹ = Σ_k (A u¹)_k·e, and the bordered system [S, s; rᵀ, 0] of the step is solved exactly by
//! this block elimination: one factorisation (or preconditioner) and two solves on it. The set
//! update (3.23) then sees the iterate at the new δ; when it changes nothing, (u, λ, δ) solves
//! the problem. Frictionless or with Tresca friction: a stick node's u_τ = u_ref moves with the
//! obstacle, u_ref(δ) = u_ref + δ (τ_k·e), so the lift prescribes u¹_τ = τ_k·e there, and a
//! slip row −λ_τ + L (u_τ − u_ref) = r of the step is affine in δ alike (the lift keeps L,
//! drops r: [`ActiveSet::lift`]); the slip directions are the step's, so δ settles with the
//! sets. Coulomb friction by the fixed point is a sequence of such Tresca solves (mod.rs,
//! `fixed_point`). Coulomb's generalised Newton: a step's rows are affine in δ alike — a stick
//! row u_τ' = u_ref(δ), a slip row (F6) −λ_τ' + L (u_τ' − u_ref(δ)) − q λ_n' = r_C, the
//! normal rows u_n' = −g(δ) — so the lift keeps L and q, drops r_C, and solves with the step's
//! (nonsymmetric) Coulomb matrix; the bordered step is then the exact Newton step of the
//! system with δ (docs/obstacles.md, "With Coulomb friction"). On the contact unknowns
//! (schur/coulomb.rs, a held body) each δ_j is one more unknown of the dense system; on a
//! body that only its pairs hold the plain path starts from the frictionless force-controlled
//! solution (mod.rs, `coulomb_start`).
//!
//! Several force-controlled pairs j = 1..k: each has its own δ_j along e_j, moving only its
//! obstacle (a node belongs to one pair: g_k = g0_k − δ_j w_k with w_k = n_k·e_j of its pair),
//! and its own equation P_j = |F_j|. u is affine in all δ's, u(δ) = u_ℓ + Σ_j (δ_j − δ_j,ℓ) u¹_j
//! with one lift per pair, so the bordered system has k border rows and columns and its block
//! elimination solves k lifts on the step's factorisation and the k × k system
//! Σ_j P¹_ij Δδ_j = |F_i| − P_i, P¹_ij = Σ_{k ∈ pair i} (A u¹_j)_k·e_i ([`correct`]).
//!
//! A body that Dirichlet data leave free (several pairs, force control on some): the
//! approaches are more free modes next to the body's rigid modes ρ — the set's rows of pair j
//! hold under (ρ, δ_j) when cᵀρ(x_k) = δ_j (c·e_j) — so the pins are chosen for the modes that
//! the set leaves free with the δ's eliminated, and the balance test counts the prescribed
//! forces as their loads, ρᵀf + Σ_j |F_j| δ_j = 0 ([`Approach::couplings`],
//! [`super::rigid::FreeModes::couple`]; docs/obstacles.md, "On a body that only its pairs
//! hold"). With pins the lift is a deformation against them and the bordered step is as above.

use super::active_set::{ActiveSet, Iterate};
use super::boundary::{ContactBoundary, ContactNode};
use super::plain_path::ContactProblem;
use super::rigid::{ApproachCoupling, BodyModes, Pin};
use super::step_system::ReducedSystem;
use crate::error::{InputError, RunError};
use crate::geom::dot;
use crate::par::Ctx;
use std::path::Path;

/// The prescribed force of a solve.
#[derive(Clone, Debug)]
pub struct ForceControl {
    /// F (3 components, 0 beyond the mesh's dimension).
    pub force: [f64; 3],
    /// δ to start from (the previous load step's, else 0).
    pub start: f64,
    /// The case file (named in the diagnoses).
    pub file: std::path::PathBuf,
    /// The pair under force control: only its obstacle moves, only its nodes' forces count.
    pub pair: usize,
    /// Its `force` key (`contact.force` or `contact[i].force`), named in the diagnoses.
    pub key: String,
}

impl ForceControl {
    /// |F|.
    pub fn magnitude(&self) -> f64 {
        dot(self.force, self.force).sqrt()
    }

    /// e = F/|F|.
    pub fn direction(&self) -> [f64; 3] {
        let m = self.magnitude();
        self.force.map(|x| x / m)
    }

    /// (τ_k·e) for a node of the pair (its frame's tangents), 0 for the other pairs' nodes.
    pub fn tangential_weight(&self, k: &ContactNode) -> [f64; 2] {
        if k.pair == self.pair {
            let e = self.direction();
            [dot(k.frame.t[0], e), dot(k.frame.t[1], e)]
        } else {
            [0.0; 2]
        }
    }

    /// w_k = n_k·e for a node of the pair, 0 for the nodes of the other pairs (their obstacles
    /// do not move with δ).
    pub fn weight(&self, k: &ContactNode) -> f64 {
        if k.pair == self.pair {
            dot(k.frame.n, self.direction())
        } else {
            0.0
        }
    }
}

/// The force controls `fcs` starting from the approaches `deltas` (in pair order; a missing
/// one keeps its start). Pure.
pub fn starting_at(fcs: &[ForceControl], deltas: &[f64]) -> Vec<ForceControl> {
    let mut out = fcs.to_vec();
    for (fc, &d) in out.iter_mut().zip(deltas) {
        fc.start = d;
    }
    out
}

/// `b` with the obstacles of `fcs` placed at their starts ([`Approach::place`]); `b` itself
/// without force control. Local.
pub fn placed(b: &ContactBoundary, fcs: &[ForceControl]) -> ContactBoundary {
    let mut out = b.clone();
    if !fcs.is_empty() {
        Approach::new(b, fcs).place(&mut out);
    }
    out
}

/// One force-controlled pair's approach in the iteration.
#[derive(Clone, Debug)]
pub struct PairApproach {
    /// e = F/|F|.
    pub dir: [f64; 3],
    /// |F|.
    pub magnitude: f64,
    /// δ of the current iterate.
    pub delta: f64,
    /// The pair (its index among all pairs).
    pub pair: usize,
    /// Its `force` key, named in the diagnoses.
    key: String,
}

impl PairApproach {
    /// Its `force` key (`contact.force` or `contact[i].force`).
    pub fn key(&self) -> &str {
        &self.key
    }
}

/// The approaches δ_j of the iteration, one per force-controlled pair (in pair order), and
/// what their gaps are made of. Each contact node belongs to one pair, so its gap moves with
/// that pair's δ only: g_k = g0_k − δ_j(k) w_k.
pub struct Approach {
    /// The force-controlled pairs, in pair order.
    pub pairs: Vec<PairApproach>,
    /// The owned nodes' gaps to the obstacles at rest, g0_k.
    g0: Vec<f64>,
    /// w_k = n_k·e of the node's pair (0 off the force-controlled pairs).
    w: Vec<f64>,
    /// With friction: the tangential references u_ref of the obstacles at rest, and their
    /// change per unit approach, (τ_k·e) (0 off the force-controlled pairs): the obstacle
    /// drags the stick nodes along (docs/obstacles.md, "Moving obstacles").
    t0: Vec<[f64; 2]>,
    wt: Vec<[f64; 2]>,
    /// The index in `pairs` of the node's pair, `None` off the force-controlled pairs.
    slot: Vec<Option<usize>>,
    file: std::path::PathBuf,
}

/// Force control on a body that Dirichlet data leave free in a rigid mode with one contact
/// pair: the loads' balance fixes its contact force, which can then not be prescribed. (With
/// several pairs, a body held between obstacles, the approaches are more free modes next to
/// the body's: [`super::rigid::FreeModes::couple`], the condensed path's dense iteration.)
pub fn floating(fc: &ForceControl) -> RunError {
    let message = "force control needs a body that Dirichlet data hold: this body is free in a \
         rigid mode, where the balance of its loads decides the contact force (prescribe the \
         obstacle's motion instead, or hold the body)";
    RunError::Input(InputError::new(Path::new(&fc.file), message).with_key(fc.key.as_str()))
}

/// Force control on every pair of a body that Dirichlet data leave free in a rigid mode: the
/// balance of the loads fixes a combination of the prescribed forces and leaves the body's
/// position along it open, so the problem has no unique solution.
pub fn all_pairs_floating(fc: &ForceControl) -> RunError {
    RunError::Input(
        InputError::new(
            Path::new(&fc.file),
            "force control on every contact pair of a body that Dirichlet data leave free in a \
             rigid mode: the balance of its loads fixes the forces, not the body's position \
             (prescribe the motion of one pair's obstacle instead, or hold the body)",
        )
        .with_key(fc.key.as_str()),
    )
}

/// A force along which the obstacle never reaches the body.
pub fn never_touches(fc: &ForceControl) -> RunError {
    RunError::Input(InputError::new(Path::new(&fc.file), NEVER_TOUCHES).with_key(fc.key.as_str()))
}

/// The first force control among `fcs` whose obstacle never reaches the body: no contact
/// node of its pair on any rank has n·e > 0, so moving along e closes no gap. Collective.
pub fn unreached<'f>(
    ctx: &Ctx,
    b: &ContactBoundary,
    fcs: &'f [ForceControl],
) -> Option<&'f ForceControl> {
    if fcs.is_empty() {
        return None;
    }
    let local: Vec<f64> = fcs
        .iter()
        .map(|fc| f64::from(u8::from(b.nodes.iter().any(|k| fc.weight(k) > 0.0))))
        .collect();
    let reach = ctx.sum_vec(&local);
    reach.iter().position(|&r| r == 0.0).map(|j| &fcs[j])
}

const NEVER_TOUCHES: &str = "the obstacle, moving along the force, never reaches the body: no \
     contact node's normal has a part along the force (each points against it or lies \
     across it; the force must push the obstacle onto the body: along the normals n, from the \
     obstacle into the body)";

/// What a force step did to the approaches.
pub struct Correction {
    /// Some pair had active nodes: their δ's from the force balance of this step's set.
    pub bordered: bool,
    /// Per force-controlled pair (index in [`Approach::pairs`]) without an active node: the
    /// obstacle moved until the contact node with this tag touches (it joins the next set).
    pub touched: Vec<(usize, u64)>,
}

impl Approach {
    /// The approaches from `b` (the gaps to the obstacles at rest) at δ_j = `fcs[j].start`.
    pub fn new(b: &ContactBoundary, fcs: &[ForceControl]) -> Approach {
        let slot_of = |pair: usize| fcs.iter().position(|fc| fc.pair == pair);
        let of = |k: &ContactNode| slot_of(k.pair).map(|j| &fcs[j]);
        Approach {
            pairs: fcs
                .iter()
                .map(|fc| PairApproach {
                    dir: fc.direction(),
                    magnitude: fc.magnitude(),
                    delta: fc.start,
                    pair: fc.pair,
                    key: fc.key.clone(),
                })
                .collect(),
            g0: b.nodes.iter().map(|k| k.gap).collect(),
            w: b.nodes
                .iter()
                .map(|k| of(k).map_or(0.0, |fc| fc.weight(k)))
                .collect(),
            t0: b.nodes.iter().map(|k| k.u_t_ref).collect(),
            wt: b
                .nodes
                .iter()
                .map(|k| of(k).map_or([0.0; 2], |fc| fc.tangential_weight(k)))
                .collect(),
            slot: b.nodes.iter().map(|k| slot_of(k.pair)).collect(),
            file: fcs.first().map(|fc| fc.file.clone()).unwrap_or_default(),
        }
    }

    /// The approaches δ_j, in pair order.
    pub fn deltas(&self) -> Vec<f64> {
        self.pairs.iter().map(|a| a.delta).collect()
    }

    /// δ of a node's pair (0 off the force-controlled pairs).
    fn delta_at(&self, i: usize) -> f64 {
        self.slot[i].map_or(0.0, |j| self.pairs[j].delta)
    }

    /// The gaps g0_k − δ_j w_k of the obstacles moved by δ_j e_j, into `b`; with friction also
    /// the tangential references u_ref + δ_j (τ_k·e_j).
    pub fn place(&self, b: &mut ContactBoundary) {
        for (i, k) in b.nodes.iter_mut().enumerate() {
            let delta = self.delta_at(i);
            k.gap = self.g0[i] - delta * self.w[i];
            for j in 0..2 {
                k.u_t_ref[j] = self.t0[i][j] + delta * self.wt[i][j];
            }
        }
    }

    /// The lift's boundary for a unit approach of the pair `j` (the others at rest): gaps −w_k
    /// on its nodes (0 elsewhere), so that an active node prescribes u_n = w_k, and (friction)
    /// the references (τ_k·e), so that a stick node prescribes u_τ = τ_k·e and a slip row acts
    /// on u_τ − τ_k·e.
    fn unit(&self, b: &ContactBoundary, j: usize) -> ContactBoundary {
        let mut u = b.clone();
        for (i, k) in u.nodes.iter_mut().enumerate() {
            let mine = self.slot[i] == Some(j);
            k.gap = -(if mine { self.w[i] } else { 0.0 });
            k.u_t_ref = if mine { self.wt[i] } else { [0.0; 2] };
        }
        u
    }

    /// Each force-controlled pair's contact force along its e_j, Σ_k (−λ_k)·e_j over every
    /// rank's contact nodes of the pair. Collective.
    pub fn forces_along(&self, ctx: &Ctx, it: &Iterate) -> Vec<f64> {
        let local: Vec<f64> = (0..self.pairs.len())
            .map(|j| {
                let e = self.pairs[j].dir;
                it.nodes
                    .iter()
                    .zip(&self.slot)
                    .filter(|(_, s)| **s == Some(j))
                    .map(|(r, _)| -dot(r.lambda, e))
                    .sum()
            })
            .collect();
        ctx.sum_vec(&local)
    }

    /// The active nodes of each force-controlled pair (over all ranks). Collective.
    fn active_counts(&self, ctx: &Ctx, set: &ActiveSet) -> Vec<usize> {
        let mut local = vec![0.0; self.pairs.len()];
        for (a, s) in set.normal.iter().zip(&self.slot) {
            if let (true, Some(j)) = (*a, s) {
                local[*j] += 1.0;
            }
        }
        ctx.sum_vec(&local).iter().map(|&x| x as usize).collect()
    }

    /// Force control on a floating body: each force-controlled pair's approach tied to the
    /// rigid modes by the set's held rows on that pair ([`ApproachCoupling`]): b_j = Σ_rows
    /// (c·e_j) a_row and s_j = Σ_rows (c·e_j)² over every rank's rows (c the row's direction:
    /// an active node's normal, a held tangent), the pairs without such rows left out.
    /// Collective (one reduction).
    pub fn couplings(
        &self,
        ctx: &Ctx,
        b: &ContactBoundary,
        set: &ActiveSet,
        modes: &BodyModes,
        dim: usize,
    ) -> Vec<ApproachCoupling> {
        let n = self.pairs.len();
        let m = modes.count();
        let mut local = vec![0.0; n * (m + 1)];
        set.held_rows(b, dim, |i, c| {
            if let Some(j) = self.slot[i] {
                let w = dot(*c, self.pairs[j].dir);
                let k = &b.nodes[i];
                let a = modes.direction_row(k.node, &k.x, c);
                let at = j * (m + 1);
                for (x, y) in local[at..at + m].iter_mut().zip(a) {
                    *x += w * y;
                }
                local[at + m] += w * w;
            }
        });
        let all = ctx.sum_vec(&local);
        (0..n)
            .filter(|&j| all[j * (m + 1) + m] > 0.0)
            .map(|j| {
                let at = j * (m + 1);
                ApproachCoupling {
                    b: all[at..at + m].to_vec(),
                    s: all[at + m],
                    magnitude: self.pairs[j].magnitude,
                    dir: self.pairs[j].dir,
                    pair: self.pairs[j].pair,
                }
            })
            .collect()
    }

    /// The pair `j`'s force does not grow with its approach (dP/dδ = `slope` ≤ 0 with
    /// `active` active nodes): without friction the body is not held against the force (an
    /// input error); with friction the step's slip rows may do it to valid input, so the
    /// solve failed (a load step is cut back).
    fn unresisting(&self, j: usize, active: usize, slope: f64, friction: bool) -> RunError {
        if friction {
            return RunError::NoConvergence(format!(
                "force control ({}: key '{}'): with {active} active contact node(s) and the \
                 step's stick and slip rows the contact force along the force does not grow \
                 with the approach (dP/dδ = {slope:.3e}): no Newton step for the approach",
                self.file.display(),
                self.pairs[j].key
            ));
        }
        self.input_error(
            j,
            format!(
                "the body does not resist the obstacle's motion along the force: with {active} \
                 active contact node(s) the contact force along it does not grow with the \
                 approach (dP/dδ = {slope:.3e}): is the body held by Dirichlet data against the \
                 force?"
            ),
        )
    }

    fn input_error(&self, j: usize, message: String) -> RunError {
        RunError::Input(
            InputError::new(Path::new(&self.file), message).with_key(self.pairs[j].key.as_str()),
        )
    }

    /// No active node of the pair `j`: δ_j grows until the first of its contact nodes
    /// touches, the one whose gap g_k(δ) + u_n closes first along e_j (the smallest tag among
    /// equal distances). Returns the tag. Collective.
    fn touch(
        &mut self,
        ctx: &Ctx,
        b: &ContactBoundary,
        it: &Iterate,
        j: usize,
    ) -> Result<u64, RunError> {
        let mut best = (f64::INFINITY, u64::MAX);
        for (((k, r), w), s) in b.nodes.iter().zip(&it.nodes).zip(&self.w).zip(&self.slot) {
            if *s == Some(j) && *w > 0.0 {
                let d = (k.gap + r.u_n) / w;
                if d < best.0 || (d == best.0 && k.tag < best.1) {
                    best = (d, k.tag);
                }
            }
        }
        let d = ctx.min_f64(best.0);
        if !d.is_finite() {
            return Err(self.input_error(j, NEVER_TOUCHES.into()));
        }
        let tag = ctx.min_u64(if best.0 == d { best.1 } else { u64::MAX });
        self.pairs[j].delta += d;
        Ok(tag)
    }
}

/// Solves the small dense system K x = r by Gaussian elimination with partial pivoting (K is
/// the k × k derivative of the pairs' forces by their approaches, k the force-controlled pairs
/// with an active node); `None` if a pivot vanishes. With k = 1: x = r / K. Pure.
fn solve_small(mut k: Vec<Vec<f64>>, mut r: Vec<f64>) -> Option<Vec<f64>> {
    let n = r.len();
    for c in 0..n {
        let p = (c..n).max_by(|&a, &b| k[a][c].abs().total_cmp(&k[b][c].abs()))?;
        if k[p][c] == 0.0 || !k[p][c].is_finite() {
            return None;
        }
        k.swap(c, p);
        r.swap(c, p);
        for i in c + 1..n {
            let f = k[i][c] / k[c][c];
            for j in c..n {
                k[i][j] -= f * k[c][j];
            }
            r[i] -= f * r[c];
        }
    }
    let mut x = vec![0.0; n];
    for c in (0..n).rev() {
        let s: f64 = (c + 1..n).map(|j| k[c][j] * x[j]).sum();
        x[c] = (r[c] - s) / k[c][c];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// What a force step ([`correct`]) moves: the contact boundary (its gaps at the obstacles'
/// approaches), the approaches δ and the iterate.
pub struct Moved<'a> {
    pub boundary: &'a mut ContactBoundary,
    pub approach: &'a mut Approach,
    pub iterate: &'a mut Iterate,
}

/// The force step after the solve of `set` at δ_ℓ (`it` recovered from it), the bordered
/// system [S, s; rᵀ, 0] of (3.29) with one border row and column per force-controlled pair
/// that has an active node, solved by block elimination: the lift u¹_j of each such pair (one
/// more solve on the same factorisation each), the k × k system Σ_j P¹_ij Δδ_j = |F_i| − P_i
/// with P¹_ij = Σ_{k ∈ pair i} (A u¹_j)_k·e_i for the δ's, u ← u + Σ_j Δδ_j u¹_j in `reduced`,
/// λ recovered again (3.28). A pair without an active node instead moves to the touching δ.
/// `moved.boundary` gets the gaps at the new δ's (`p` gives the system, layout and dimension;
/// its own boundary is not read). `forces`: the iterate's contact forces along the e_j
/// ([`Approach::forces_along`]). Collective.
pub fn correct(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    set: &ActiveSet,
    pins: &[Pin],
    forces: &[f64],
    moved: Moved,
) -> Result<Correction, RunError> {
    let (sys, layout, dim) = (p.sys, p.layout, p.mesh.dim);
    let Moved {
        boundary: b,
        approach: ap,
        iterate: it,
    } = moved;
    let counts = ap.active_counts(ctx, set);
    let held: Vec<usize> = (0..ap.pairs.len()).filter(|&j| counts[j] > 0).collect();
    let mut c = Correction {
        bordered: !held.is_empty(),
        touched: Vec::new(),
    };
    if c.bordered {
        let mut lifts = Vec::with_capacity(held.len());
        let mut local = vec![0.0; held.len() * held.len()];
        for (q, &j) in held.iter().enumerate() {
            let unit = ap.unit(b, j);
            let (u1, au1) = reduced.solve_lift(ctx, j, sys, layout, &unit, &set.lift(), pins)?;
            // column q: the pairs' forces along their e_i per unit δ_j
            for (p, &i) in held.iter().enumerate() {
                let e = ap.pairs[i].dir;
                local[p * held.len() + q] = b
                    .nodes
                    .iter()
                    .zip(&ap.slot)
                    .filter(|(_, s)| **s == Some(i))
                    .map(|(k, _)| (0..dim).map(|d| au1[k.local_row + d] * e[d]).sum::<f64>())
                    .sum();
            }
            lifts.push(u1);
        }
        let all = ctx.sum_vec(&local);
        let n = held.len();
        let stiffness: Vec<Vec<f64>> = (0..n).map(|p| all[p * n..(p + 1) * n].to_vec()).collect();
        // frictionless, P¹_jj = u¹_jᵀ A u¹_j (A u¹_j vanishes off the active rows, where u¹_j
        // is prescribed): > 0 unless no active node of the pair has a normal component along
        // e_j; with friction the lift's tangential rows may make it ≤ 0 on valid input
        if let Some(p) = (0..n).find(|&p| stiffness[p][p].is_nan() || stiffness[p][p] <= 0.0) {
            let j = held[p];
            return Err(ap.unresisting(j, counts[j], stiffness[p][p], set.tangential.is_some()));
        }
        let rhs: Vec<f64> = held
            .iter()
            .map(|&j| ap.pairs[j].magnitude - forces[j])
            .collect();
        let Some(steps) = solve_small(stiffness, rhs) else {
            return Err(ap.input_error(
                held[0],
                "the forces of the force-controlled pairs do not grow independently with their \
                 approaches (the system for the approaches is singular): is the body held by \
                 Dirichlet data against the forces?"
                    .into(),
            ));
        };
        let mut u = reduced.solution_local()?;
        for (step, u1) in steps.iter().zip(&lifts) {
            for (x, y) in u.iter_mut().zip(u1) {
                *x += step * y;
            }
        }
        reduced.set_solution_local(&u)?;
        for (&j, step) in held.iter().zip(&steps) {
            ap.pairs[j].delta += step;
        }
        ap.place(b);
        reduced.recover(sys, b, set, it)?; // (3.28) at the new δ's
    }
    for j in (0..ap.pairs.len()).filter(|&j| counts[j] == 0) {
        let tag = ap.touch(ctx, b, it, j)?;
        c.touched.push((j, tag));
    }
    if !c.touched.is_empty() {
        ap.place(b);
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// dP/dδ ≤ 0: an input error without friction, a failed solve (exit 1) with it, each
    /// naming the pair's `force` key.
    #[test]
    fn unresisting_force_is_input_only_without_friction() {
        let b = ContactBoundary {
            nodes: Vec::new(),
            n_global: 0,
            offset: 0,
            on_contact_boundary: Vec::new(),
            excluded_dirichlet: 0,
            obstacles: Vec::new(),
            keys: Default::default(),
            modes: std::sync::Arc::new(crate::mesh::BodyModes::none(2)),
            stiffness: 0.0,
        };
        let fc = |pair: usize| ForceControl {
            force: [0.0, -1.0, 0.0],
            start: 0.0,
            file: "case.toml".into(),
            pair,
            key: format!("contact[{pair}].force"),
        };
        let ap = Approach::new(&b, &[fc(0), fc(2)]);
        let e = ap.unresisting(1, 3, -0.5, false);
        assert_eq!(e.exit_code(), 2, "{e}");
        assert!(e.to_string().contains("key 'contact[2].force'"), "{e}");
        let e = ap.unresisting(1, 3, -0.5, true);
        assert!(matches!(e, RunError::NoConvergence(_)), "{e}");
        assert_eq!(e.exit_code(), 1);
        assert!(e.to_string().contains("key 'contact[2].force'"), "{e}");
    }

    #[test]
    fn small_system() {
        assert_eq!(solve_small(vec![vec![4.0]], vec![2.0]), Some(vec![0.5]));
        let x = solve_small(vec![vec![1.0, 2.0], vec![3.0, 4.0]], vec![5.0, 6.0]).unwrap();
        assert!(
            (x[0] + 4.0).abs() < 1e-12 && (x[1] - 4.5).abs() < 1e-12,
            "{x:?}"
        );
        assert_eq!(
            solve_small(vec![vec![1.0, 2.0], vec![2.0, 4.0]], vec![1.0, 1.0]),
            None
        );
    }
}
