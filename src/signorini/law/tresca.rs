//! Tresca friction (Algorithm 2): the nodal thresholds b_k of the contact boundary (3.18),
//! the rows (3.33)/(3.39) and the residual (3.31). The pointwise law is `contact::tresca`.

use super::rules::{increment, FloatingLoad, FrictionLaw};
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

    /// ‖C_τ‖² (3.31).
    fn residual2(&self, k: &ContactNode, r: &NodeResult, c: f64) -> f64 {
        let ct = contact::c_tau(&increment(r, k), &r.lambda_t, k.bound, c);
        ct[0] * ct[0] + ct[1] * ct[1]
    }

    /// Σ b_k over the contact boundary (3.18); `None` for b = 0 (frictionless: the balance
    /// test of the free modes decides).
    fn capacity(&self, load: &FloatingLoad) -> Option<(f64, String)> {
        let c: f64 = load.bounds.iter().sum();
        (c != 0.0).then(|| (c, format!("Σ b_k = {c:.6e}, (3.18)")))
    }
}
