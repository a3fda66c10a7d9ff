//! No friction (Algorithm 1): no tangential state; the set update forms no tangential rows.

use super::rules::{increment, FloatingLoad, FrictionLaw};
use crate::contact::{self, CoulombRow};
use crate::signorini::boundary::{ContactNode, NodeResult};

/// The frictionless law: λ_τ = 0 (a free slip with b = 0, never asked for by the set update).
pub struct Frictionless;

impl FrictionLaw for Frictionless {
    fn friction(&self) -> bool {
        false
    }

    /// (3.39) with b = 0: λ_τ = 0.
    fn row(&self, k: &ContactNode, r: &NodeResult, c: f64, dim: usize) -> CoulombRow<2> {
        contact::tangential_row_dyn(dim, increment(r, k), r.lambda_t, 0.0, c).into()
    }

    fn threshold(&self, _k: &ContactNode, _r: &NodeResult, _c: f64) -> f64 {
        0.0
    }

    fn residual2(&self, _k: &ContactNode, _r: &NodeResult, _c: f64) -> f64 {
        0.0
    }

    fn capacity(&self, _load: &FloatingLoad) -> Option<(f64, String)> {
        None
    }
}
