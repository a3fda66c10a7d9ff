//! Contact algebra: obstacles, frames, complementarity functions, Tresca regularisation,
//! node states and residual certificates. Pure functions on small fixed-size arrays; no
//! MPI, no PETSc. Equation numbers refer to the thesis (docs/method.md).
//!
//! - [`obstacle`]: `Plane`, `Sphere`, `Cylinder`, `Cone`, `Pyramid`, `Punch`, `Height`
//!   ([`height`]), `Surface` ([`surface`]) (docs/obstacles.md),
//!   `Obstacle::project` → closest point, normal n (into
//!   the body), gap g0 (3.3).
//! - [`frame`]: orthonormal frames {n, τ_1 (, τ_2)}; 2D τ = (n_y, −n_x), 3D right-handed.
//! - [`complementarity`]: C_n (3.21), normal test (3.23), C_τ (3.31), slip test (3.33),
//!   node states S1..S4.
//! - [`tresca`]: slip rows −λ_τ + L̃ u_τ = r̃ (3.39) with the regularisation (3.40), the
//!   unregularised L, r (3.37)/(3.38), and the zero-threshold rule (§3.4.3).
//! - [`residual`]: residuals of (3.14) and (3.18) for a convergence certificate.
//! - [`coulomb`]: node-wise Coulomb friction for one generalised Newton (docs/friction.md):
//!   threshold b = μ max(0, −λ_n − c(u_n + g)), residual, states, derivative, slip rows with
//!   the λ_n coupling and their block data for the reduced system (runtime dimension:
//!   [`coulomb::coulomb_row_dyn`]).
//!
//! Tangential quantities are generic over M = d − 1 (`[f64; M]`, `[[f64; M]; M]`).
//! Callers with a runtime dimension may pass 2D tangential vectors zero-padded to
//! `[f64; 2]` (as [`frame::Frame::tangential_part`] returns them) to `c_tau`,
//! `tangential_slip`, `classify` and the residuals: the results equal the M = 1 ones.
//! NOT to `regularise`/`tangential_row`: use [`tresca::tangential_row_dyn`] there.

pub mod complementarity;
pub mod coulomb;
pub mod frame;
pub mod height;
mod linalg;
pub mod mortar;
pub mod obstacle;
pub mod residual;
pub mod surface;
pub mod tresca;

pub use complementarity::{
    c_n, c_tau, classify, inf_norm, normal_active, normal_active_or_tie, tangential_slip, ties,
    NodeState,
};
pub use coulomb::{
    c_tau_coulomb, c_tau_coulomb_derivative, coulomb_block, coulomb_classify,
    coulomb_conditions_hold, coulomb_residual, coulomb_row, coulomb_row_dyn, coulomb_row_projected,
    coulomb_row_unregularised, coulomb_threshold, CoulombBlock, CoulombDerivative, CoulombNewton,
    CoulombResidual, CoulombRow, NodePoint,
};
pub use frame::{tangent_2d, tangents_3d, Frame};
pub use obstacle::{Obstacle, ObstacleError, Plane, Projection, Sphere};
pub use residual::{
    normal_conditions_hold, normal_residual, tangential_residual, tresca_conditions_hold,
    tresca_natural_residual, NormalResidual, TangentialResidual,
};
pub use tresca::{
    regularise, tangential_row, tangential_row_dyn, unregularised, Regularisation, TangentialRow,
    Unregularised,
};
