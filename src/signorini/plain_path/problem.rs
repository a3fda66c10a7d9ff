//! What the plain path's Newton loop takes and gives: the settings of the case, the contact
//! problem, a warm start, and the per-step and final results.

use crate::assembly::System;
use crate::case::{self, NewtonSection};
use crate::mesh::Mesh;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::Vector;
use crate::signorini::active_set::Law;
use crate::signorini::boundary::{ContactBoundary, NodeResult};
use crate::signorini::dense::DenseLimits;
use crate::signorini::force::ForceControl;
use crate::signorini::halfspace::{HalfSpace, PredictorStep};
use crate::signorini::rigid::Pin;
use crate::signorini::step_system::{AmgStep, ReuseStep, RowChange, SolveKind};
#[cfg(doc)]
use crate::tuning::DEFAULT_C_FACTOR;

/// What the loop needs from the case.
pub struct NewtonSettings<'a> {
    pub section: &'a NewtonSection,
    /// The complementarity parameter c > 0 used.
    pub c: f64,
    pub law: Law,
    pub rigid: case::RigidModeHandling,
    /// The half-space model of the body for the first set of the iterative preset's reuse
    /// path (halfspace/); `None`: no prediction.
    pub halfspace: Option<&'a HalfSpace>,
    /// A frictionless estimate for a start (condensed path): the pins carry the load in the
    /// body's own modes the set leaves free instead of the balance test (never the prescribed
    /// forces of force control; [`crate::signorini::dense::Dense`]).
    pub estimate: bool,
    /// The frictionless estimate's load in the free modes where friction alone holds a part of
    /// the body's load: that part carried by a tangential force at the contact
    /// (`carried_at_contact` in mod.rs) instead of by the pins; `None`: the body's load φ.
    pub carried: Option<&'a [f64]>,
    /// The body's half-space model where the condensed path runs (direct preset): it locates
    /// the contact zone of a floating body before the factorisation
    /// ([`crate::signorini::halfspace::locate`]), and where that zone is too wide for the dense limits the
    /// plain path predicts its first set from it (as `halfspace`).
    pub model: Option<&'a HalfSpace>,
    /// Force control (`contact.force`, force.rs): one approach δ_j per force-controlled pair
    /// is an unknown of the loop (empty: no force control).
    pub force: &'a [ForceControl],
}

impl NewtonSettings<'_> {
    pub fn friction(&self) -> bool {
        self.law.friction()
    }

    /// c and newton.max_steps as the limits of a dense iteration.
    pub fn dense_limits(&self) -> DenseLimits {
        DenseLimits {
            c: self.c,
            max_steps: self.section.max_steps,
        }
    }
}
/// A warm start: the converged state of a previous solve on the same mesh and boundary
/// (the contact nodes' iterate with their final normal set in `active`, this rank's rows of u).
pub struct WarmStart<'a> {
    pub nodes: &'a [NodeResult],
    pub u_local: &'a [f64],
    /// A start within a load step other than the step's own warm start (the condensed Coulomb
    /// iteration's expanded iterate): the load step's, whose ‖u‖ and ‖λ‖ floor Algorithm 2's
    /// stopping rule ([`VANISHING`](super::iteration::VANISHING)); `None`: this start's own.
    /// Measured with the start's own: a stack of three bodies with Coulomb on every pair taken
    /// back to no load, on 2 ranks, started from an expanded iterate of 1e-12 and ran
    /// newton.max_steps = 100 steps on a residual of 7e-30 (tests/load_steps.rs).
    pub floors_from: Option<&'a WarmStart<'a>>,
}

/// One Newton step, for the history.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StepInfo {
    pub step: usize,
    /// |A_n^ℓ|: active nodes used in this step's solve.
    pub active: usize,
    /// Nodes whose state changed in the update after this solve.
    pub changed: usize,
    /// ‖C_n(u^ℓ, λ^ℓ)‖₂ over all contact nodes (3.21); with friction also C_τ (3.31).
    pub residual: f64,
    pub solve_seconds: f64,
    /// A numeric factorisation (direct preset), Krylov iterations (iterative preset), or
    /// Krylov iterations on an earlier step's factorisation (direct preset, reuse).
    pub solve: SolveKind,
    pub iterations: usize,
    /// The reuse path's record of the step (direct preset, `solver.reuse` not "never").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reuse: Option<ReuseStep>,
    /// The iterative preset's reuse path: PC setup or reuse, tolerance, warm start (iterative
    /// preset, `solver.reuse` not "never").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub amg: Option<AmgStep>,
    /// Number of rigid modes pinned in this step.
    pub pinned: usize,
    /// Tresca: nodes in S1..S4 (inactive/stick, inactive/slip, active/stick, active/slip) in
    /// this step's solve.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub states: Option<[usize; 4]>,
    /// Tresca: |u^ℓ − u^{ℓ−1}| / |u^ℓ|.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub du_rel: Option<f64>,
    /// The half-space predictor after this (first) step (iterative preset, frictionless).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub predictor: Option<PredictorStep>,
    /// Friction: how this step's matrix differs from the previous step's (absent in the
    /// first step).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub change: Option<RowChange>,
    /// A factorising step of the plain path: the seconds of the numeric factorisation alone
    /// (`solve_seconds` minus these: the solve with it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub factorisation_seconds: Option<f64>,
}

/// What Algorithms 1 and 2 return.
pub struct NewtonResult {
    pub u: Vector,
    pub nodes: Vec<NodeResult>,
    pub history: Vec<StepInfo>,
    pub converged: bool,
    /// Linear solves (Newton steps).
    pub steps: usize,
    /// Seconds spent in λ recovery (MatMult + local work), all steps.
    pub lambda_seconds: f64,
    /// Seconds spent writing the reduced systems, all steps.
    pub rows_seconds: f64,
    pub pinned_final: Vec<Pin>,
    /// Step after which a recurring set switched the iteration to least-index updates.
    pub cycle_detected_at: Option<usize>,
    /// Force control: the approach δ_j of the result per force-controlled pair, in pair order
    /// (its obstacle moved by δ_j F_j/|F_j|); empty without force control.
    pub approach: Vec<f64>,
    /// The rule that stopped the iteration (the exact criterion or a loosened acceptance).
    pub stop: crate::signorini::certificate::StopRule,
}

/// The nodal stiffness E h_c^(d−2) of the contact boundary (h_c the mean contact mesh size, the
/// mean of w_k^(1/(d−1)) over all contact nodes). The default c is κ times it
/// (κ = [`DEFAULT_C_FACTOR`]; 2D: κ E, 3D: κ E h_c), so that c u in (3.23) and (3.33) has the
/// unit of the nodal force λ it is added to, in every unit system. (The former E / h_c is a
/// stress per length: c u then weighed against λ with the unit of length to the power d − 1,
/// and a ball given in µm instead of m did not converge.) Collective (one reduction).
pub fn nodal_stiffness(ctx: &Ctx, b: &ContactBoundary, dim: usize, young: f64) -> f64 {
    let local: f64 = b
        .nodes
        .iter()
        .map(|k| k.weight.powf(1.0 / (dim - 1) as f64))
        .sum();
    let out = ctx.sum_vec(&[local, b.nodes.len() as f64]);
    if out[1] > 0.0 && out[0] > 0.0 {
        young * (out[0] / out[1]).powi(dim as i32 - 2)
    } else {
        // no contact node (every one held by Dirichlet data): c is never read
        young
    }
}

/// The data of a contact solve: the mesh and its partition, the contact boundary, the
/// Dirichlet values per dof (NaN = free), the assembled system (A, f).
pub struct ContactProblem<'a> {
    pub mesh: &'a Mesh,
    pub layout: &'a Layout,
    pub boundary: &'a ContactBoundary,
    pub fixed: &'a [f64],
    pub sys: &'a System,
}
