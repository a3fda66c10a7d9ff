//! What the algorithm asks of a tangential law ([`FrictionLaw`]), and the pieces every law
//! shares: the increment friction acts on and the stick band of (3.33).

use crate::contact::CoulombRow;
use crate::signorini::boundary::{ContactNode, NodeResult};
use crate::signorini::force::ForceControl;

/// A tangential law: the pointwise rules the set update, the stop rule, the certificate and
/// the checks before the solve take from it. Every method is local (one node, or data
/// already reduced).
pub trait FrictionLaw: Sync {
    /// The law has tangential states (rows, thresholds); `false`: Algorithm 1.
    fn friction(&self) -> bool {
        true
    }

    /// The tangential rows of node `k` at the iterate `r` (increment u_τ − u_ref): stick, or
    /// slip with L̃, r̃ (and Coulomb's λ_n coupling q).
    fn row(&self, k: &ContactNode, r: &NodeResult, c: f64, dim: usize) -> CoulombRow<2>;

    /// The threshold b of node `k` at `r`.
    fn threshold(&self, k: &ContactNode, r: &NodeResult, c: f64) -> f64;

    /// The squared tangential residual of node `k` at `r` (C_n is added by the caller).
    fn residual2(&self, k: &ContactNode, r: &NodeResult, c: f64) -> f64;

    /// The row of settled slip from `row` and the row `prev` it was solved with (the condensed
    /// iteration's update, docs/friction.md, "Settled slip"); `row` itself unless the law
    /// settles.
    fn settled(
        &self,
        _prev: Option<CoulombRow<2>>,
        row: CoulombRow<2>,
        _k: &ContactNode,
        _r: &NodeResult,
        _c: f64,
        _dim: usize,
    ) -> CoulombRow<2> {
        row
    }

    /// A stick node stays stick while |v| ≤ b + [`STICK_TOL`] · max(b, `scale`), b > 0,
    /// v = λ_τ + c Δu_τ, with `scale` the largest threshold on the whole boundary
    /// (`active_set::threshold_scale`): the hysteresis of (3.33) that keeps a node at the
    /// stick/slip limit (|λ_τ| = b, Δu_τ = 0: every slip node of a warm start from its own
    /// solution) from flipping on round-off. The band is measured against the problem's
    /// threshold scale, not against the node's own b: a node with a small b (the edge of the
    /// contact zone) sees the same round-off in λ_τ as every other node, and a fixed point on
    /// Tresca thresholds leaves b within 1e-9 · max b of μ(−λ_n), not within 1e-9 · b.
    fn stays_stuck(&self, k: &ContactNode, r: &NodeResult, c: f64, scale: f64) -> bool {
        let du_t = increment(r, k);
        let v = [r.lambda_t[0] + c * du_t[0], r.lambda_t[1] + c * du_t[1]];
        let b = self.threshold(k, r, c);
        b > 0.0 && v[0].hypot(v[1]) <= b + STICK_TOL * b.max(scale)
    }

    /// The threshold b_k by which the friction certificate (3.18) and the output judge node
    /// `k`'s final state `r`: the boundary's b_k unless the law says otherwise.
    fn judged_bound(&self, k: &ContactNode, _r: &NodeResult) -> f64 {
        k.bound
    }

    /// The total friction capacity of a floating body against parallel planes and what it is
    /// (for the message), or `None` where it is not known before the solve (or there is no
    /// friction): the balance test and the iteration decide.
    fn capacity(&self, load: &FloatingLoad) -> Option<(f64, String)>;
}

/// A floating body against parallel planes, as the capacity check sees it (all reduced): the
/// planes' normals (into the body), the load's normal resultant along the first, force
/// control, and per pair the largest μ and Σ b_k over its nodes.
pub struct FloatingLoad<'a> {
    pub planes: &'a [[f64; 3]],
    pub rn: f64,
    pub forces: &'a [ForceControl],
    pub mu: &'a [f64],
    pub bounds: &'a [f64],
}

/// Relative tolerance of the stick → slip test (3.33) for a node that sticks (a law's
/// `stays_stuck`): a stick node may end with |λ_τ| ≤ b + STICK_TOL · max_k b_k,
/// at the warning level of the friction certificate (1e-8 of the problem's scales) at most.
pub const STICK_TOL: f64 = 1e-8;

/// A 2D node that slipped and whose increment now opposes its force: λ_τ Δu_τ < 0 with
/// |λ_τ| ≤ b (at a slip solution λ_τ = b sign Δu_τ); the laws' settled rows make it stick.
pub fn slips_back(r: &NodeResult, k: &ContactNode, b: f64) -> bool {
    let du = increment(r, k)[0];
    r.lambda_t[0] * du < 0.0 && r.lambda_t[0].abs() <= b
}

/// u_τ − u_ref: the tangential increment friction acts on (u_τ itself for u_ref = 0).
pub fn increment(r: &NodeResult, k: &ContactNode) -> [f64; 2] {
    if k.u_t_ref == [0.0; 2] {
        return r.u_t;
    }
    [r.u_t[0] - k.u_t_ref[0], r.u_t[1] - k.u_t_ref[1]]
}
