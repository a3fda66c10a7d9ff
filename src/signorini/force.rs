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
//! sets. Coulomb friction is refused by the case reader.

use super::active_set::{ActiveSet, Iterate};
use super::boundary::{ContactBoundary, ContactNode};
use super::reduced::ReducedSystem;
use super::rigid::Pin;
use crate::assembly::System;
use crate::error::{InputError, RunError};
use crate::geom::dot;
use crate::par::Ctx;
use crate::partition::Layout;
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

/// The approach δ of the iteration and what its gaps are made of.
pub struct Approach {
    /// e = F/|F|.
    pub dir: [f64; 3],
    /// |F|.
    pub magnitude: f64,
    /// δ of the current iterate.
    pub delta: f64,
    /// The pair under force control.
    pub pair: usize,
    /// The owned nodes' gaps to the obstacle at rest, g0_k.
    g0: Vec<f64>,
    /// w_k = n_k·e (0 off the pair).
    w: Vec<f64>,
    /// With friction: the tangential references u_ref of the obstacle at rest, and their
    /// change per unit approach, (τ_k·e) (0 off the pair): the obstacle drags the stick
    /// nodes along (docs/obstacles.md, "Moving obstacles").
    t0: Vec<[f64; 2]>,
    wt: Vec<[f64; 2]>,
    /// The node belongs to the pair under force control.
    in_pair: Vec<bool>,
    file: std::path::PathBuf,
    key: String,
}

/// Force control on a body that Dirichlet data leave free in a rigid mode. With one contact
/// pair the loads' balance fixes its contact force, which can then not be prescribed; with
/// several (a body held between obstacles) the approach is solved on the condensed path as one
/// more free mode, and other paths (`several`) refuse it.
pub fn floating(fc: &ForceControl, several: bool) -> RunError {
    let message = if several {
        "force control of a body that only its contact pairs hold (Dirichlet data leave it free \
         in a rigid mode) is solved on the condensed path only — the direct preset, frictionless, \
         solver.reuse = \"auto\" — which did not take this case: prescribe the obstacle's \
         motion instead, or hold the body"
    } else {
        "force control needs a body that Dirichlet data hold: this body is free in a rigid \
         mode, where the balance of its loads decides the contact force (prescribe the \
         obstacle's motion instead, or hold the body)"
    };
    RunError::Input(InputError::new(Path::new(&fc.file), message).with_key(fc.key.as_str()))
}

/// A force along which the obstacle never reaches the body.
pub fn never_touches(fc: &ForceControl) -> RunError {
    RunError::Input(InputError::new(Path::new(&fc.file), NEVER_TOUCHES).with_key(fc.key.as_str()))
}

const NEVER_TOUCHES: &str = "the obstacle, moving along the force, never reaches the body: every \
     contact node's normal points against the force (the force must push the obstacle onto the \
     body: along the normals n, from the obstacle into the body)";

/// What a force step did to δ.
pub enum Correction {
    /// The bordered step: δ from the force balance of this step's set.
    Bordered,
    /// No node was active: the obstacle moved until the contact node with this tag touches
    /// (it joins the next set).
    Touch(u64),
}

impl Approach {
    /// The approach from `b` (the gaps to the obstacle at rest) at δ = `fc.start`.
    pub fn new(b: &ContactBoundary, fc: &ForceControl) -> Approach {
        let dir = fc.direction();
        Approach {
            dir,
            magnitude: fc.magnitude(),
            delta: fc.start,
            pair: fc.pair,
            g0: b.nodes.iter().map(|k| k.gap).collect(),
            w: b.nodes.iter().map(|k| fc.weight(k)).collect(),
            t0: b.nodes.iter().map(|k| k.u_t_ref).collect(),
            wt: b.nodes.iter().map(|k| fc.tangential_weight(k)).collect(),
            in_pair: b.nodes.iter().map(|k| k.pair == fc.pair).collect(),
            file: fc.file.clone(),
            key: fc.key.clone(),
        }
    }

    /// The gaps g0_k − δ w_k of the obstacle moved by δ e, into `b`; with friction also the
    /// tangential references u_ref + δ (τ_k·e).
    pub fn place(&self, b: &mut ContactBoundary) {
        for (i, k) in b.nodes.iter_mut().enumerate() {
            k.gap = self.g0[i] - self.delta * self.w[i];
            for j in 0..2 {
                k.u_t_ref[j] = self.t0[i][j] + self.delta * self.wt[i][j];
            }
        }
    }

    /// The obstacle's displacement δ e.
    pub fn displacement(&self) -> [f64; 3] {
        self.dir.map(|x| self.delta * x)
    }

    /// The lift's boundary: gaps −w_k, so that an active node prescribes u_n = w_k, and
    /// (friction) the references (τ_k·e), so that a stick node prescribes u_τ = τ_k·e and a
    /// slip row acts on u_τ − τ_k·e.
    fn unit(&self, b: &ContactBoundary) -> ContactBoundary {
        let mut u = b.clone();
        for (i, k) in u.nodes.iter_mut().enumerate() {
            k.gap = -self.w[i];
            k.u_t_ref = self.wt[i];
        }
        u
    }

    /// The contact force along e of an iterate, Σ_k (−λ_k)·e over every rank's contact nodes
    /// of the pair.
    /// Collective.
    pub fn force_along(&self, ctx: &Ctx, it: &Iterate) -> f64 {
        let local: f64 = it
            .nodes
            .iter()
            .zip(&self.in_pair)
            .filter(|(_, &mine)| mine)
            .map(|(r, _)| -dot(r.lambda, self.dir))
            .sum();
        ctx.sum_vec(&[local])[0]
    }

    fn input_error(&self, message: String) -> RunError {
        RunError::Input(InputError::new(Path::new(&self.file), message).with_key(self.key.as_str()))
    }

    /// No active node: δ grows until the first contact node touches, the one whose gap
    /// g_k(δ) + u_n closes first along e (the smallest tag among equal distances).
    fn touch(
        &mut self,
        ctx: &Ctx,
        b: &ContactBoundary,
        it: &Iterate,
    ) -> Result<Correction, RunError> {
        let mut best = (f64::INFINITY, u64::MAX);
        for ((k, r), w) in b.nodes.iter().zip(&it.nodes).zip(&self.w) {
            if *w > 0.0 {
                let d = (k.gap + r.u_n) / w;
                if d < best.0 || (d == best.0 && k.tag < best.1) {
                    best = (d, k.tag);
                }
            }
        }
        let d = ctx.min_f64(best.0);
        if !d.is_finite() {
            return Err(self.input_error(NEVER_TOUCHES.into()));
        }
        let tag = ctx.min_u64(if best.0 == d { best.1 } else { u64::MAX });
        self.delta += d;
        Ok(Correction::Touch(tag))
    }
}

/// The force step after the solve of `set` at δ_ℓ (`it` recovered from it): the bordered
/// system's δ by the lift u¹ (one more solve on the same factorisation), u ← u + Δδ u¹ in
/// `reduced`, λ recovered again (3.28); without an active node the touching δ instead. `b`
/// gets the gaps at the new δ. `force`: the iterate's contact force along e
/// ([`Approach::force_along`]). Collective.
#[allow(clippy::too_many_arguments)]
pub fn correct(
    ctx: &Ctx,
    (sys, layout, dim): (&System, &Layout, usize),
    reduced: &mut ReducedSystem,
    set: &ActiveSet,
    pins: &[Pin],
    (n_active, force): (usize, f64),
    b: &mut ContactBoundary,
    ap: &mut Approach,
    it: &mut Iterate,
) -> Result<Correction, RunError> {
    if n_active == 0 {
        let c = ap.touch(ctx, b, it)?;
        ap.place(b);
        return Ok(c);
    }
    let unit = ap.unit(b);
    let (u1, au1) = reduced.solve_lift(ctx, sys, layout, &unit, &set.lift(), pins)?;
    let local: f64 = b
        .nodes
        .iter()
        .zip(&ap.in_pair)
        .filter(|(_, &mine)| mine)
        .map(|(k, _)| {
            (0..dim)
                .map(|j| au1[k.local_row + j] * ap.dir[j])
                .sum::<f64>()
        })
        .sum();
    let stiffness = ctx.sum_vec(&[local])[0];
    // P¹ = u¹ᵀ A u¹ (A u¹ vanishes off the active normals, where u¹_n = w_k): > 0 unless no
    // active node's normal has a component along e
    if stiffness.is_nan() || stiffness <= 0.0 {
        return Err(ap.input_error(format!(
            "the body does not resist the obstacle's motion along the force: with {n_active} \
             active contact node(s) the contact force along it does not grow with the approach \
             (dP/dδ = {stiffness:.3e}): is the body held by Dirichlet data against the force?"
        )));
    }
    let step = (ap.magnitude - force) / stiffness;
    let mut u = reduced.solution_local()?;
    for (x, y) in u.iter_mut().zip(&u1) {
        *x += step * y;
    }
    reduced.set_solution_local(&u)?;
    ap.delta += step;
    ap.place(b);
    reduced.recover(sys, b, set, it)?; // (3.28) at the new δ
    Ok(Correction::Bordered)
}
