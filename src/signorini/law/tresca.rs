//! Tresca friction (Algorithm 2): the nodal thresholds b_k of the contact boundary (3.18),
//! the rows (3.33)/(3.39) and the residual (3.31). The pointwise law is `contact::tresca`.

use super::rules::{increment, slips_back, FloatingLoad, FrictionLaw};
use crate::contact::{self, CoulombRow};
use crate::signorini::boundary::{ContactNode, NodeResult};

/// Tresca's law with the given thresholds b_k (`ContactNode::bound`).
pub struct Tresca;

impl FrictionLaw for Tresca {
    /// (3.33)/(3.39): stick, or slip with L̃, r̃. Local.
    fn row(&self, k: &ContactNode, r: &NodeResult, c: f64, dim: usize) -> CoulombRow<2> {
        contact::tangential_row_dyn(dim, increment(r, k), r.lambda_t, k.bound, c).into()
    }

    /// b_k (3.18).
    fn threshold(&self, k: &ContactNode, _r: &NodeResult, _c: f64) -> f64 {
        k.bound
    }

    /// The natural residual of (3.18), |λ_τ − P_b(λ_τ + c Δu_τ)|², squared: (3.31)'s C_τ
    /// divided by max(b_k, |λ_τ + c Δu_τ|). C_τ itself is a force squared, and its sum with
    /// C_n (a force) compared with ‖λ‖ would weigh the two by the unit of force (the condensed
    /// Tresca iteration's checks accepted a block's iterate in N and refused it in GN); the
    /// natural residual is a force, zero exactly where C_τ is (Satz 3.7).
    fn residual2(&self, k: &ContactNode, r: &NodeResult, c: f64) -> f64 {
        contact::tresca_natural_residual(&increment(r, k), &r.lambda_t, k.bound, c).powi(2)
    }

    /// The row for the next step from the (3.39) row `row` of node `k` at `r` and the row `prev`
    /// it was solved with, in 2D (docs/friction.md, "Settled slip"; `row` itself in 3D), as
    /// Coulomb's: a node that slipped and slips on in the same direction (its last row's
    /// −r̃ and v = λ_τ + c Δu_τ of one sign) takes λ_τ' = b_k sign v, the (3.39) row at a slip
    /// solution (F̃ = 1, M̃ = 0, L̃ = 0), exact in 2D, so that the condensed iteration is
    /// piecewise linear there; one whose increment now opposes its force (λ_τ Δu_τ < 0 with
    /// |λ_τ| ≤ b_k) sticks. Local.
    fn settled(
        &self,
        prev: Option<CoulombRow<2>>,
        row: CoulombRow<2>,
        k: &ContactNode,
        r: &NodeResult,
        c: f64,
        dim: usize,
    ) -> CoulombRow<2> {
        let (Some(CoulombRow::Slip { r: r0, .. }), CoulombRow::Slip { .. }) = (prev, row) else {
            return row;
        };
        let b = k.bound;
        if dim != 2 || !(b > 0.0 && r0[0] != 0.0) {
            return row;
        }
        if slips_back(r, k, b) {
            return CoulombRow::Stick;
        }
        let v = r.lambda_t[0] + c * increment(r, k)[0];
        if v == 0.0 || v.signum() != (-r0[0]).signum() {
            return row;
        }
        CoulombRow::Slip {
            l: [[0.0; 2]; 2],
            q: [0.0; 2],
            r: [-b * v.signum(), 0.0],
        }
    }

    /// Σ b_k over the contact boundary (3.18); `None` for b = 0 (frictionless: the balance
    /// test of the free modes decides).
    fn capacity(&self, load: &FloatingLoad) -> Option<(f64, String)> {
        let c: f64 = load.bounds.iter().sum();
        (c != 0.0).then(|| (c, format!("Σ b_k = {c:.6e}, (3.18)")))
    }
}
