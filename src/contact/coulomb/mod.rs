//! Node-wise Coulomb friction for ONE generalised semismooth Newton method in which λ_n and the
//! slip rows move together (docs/friction.md; equation labels (F1)–(F8) refer to it, the others
//! to the thesis). M = d − 1 tangential components, as in [`super::tresca`].
//!
//! Threshold (F1): b = μ max(0, −λ_n − c (u_n + g)); at a point with C_n = 0 (3.21) it equals
//! μ(−λ_n), the Coulomb threshold, and it is 0 off the contact.
//!
//! Node states of a Newton step (from the previous iterate, (3.23) and (3.33) with b of (F1)):
//! - S2, k ∉ A_n: b = 0, frictionless: λ_τ' = 0 (§3.4.3). (S1 cannot occur: b = 0 ⇒ slip.)
//! - S3, k ∈ A_n, |v| ≤ b: stick, u_τ' = 0 (3.34a).
//! - S4, k ∈ A_n, |v| > b: slip, the row (F5)
//!   −λ_τ' + L̃ u_τ' − q (λ_n' + c (u_n' + g)) = r,   q = μ w̃,  w̃ = (I − βM̃)⁻¹ v/|v|,
//!   r = r̃ + w̃ b, with L̃, r̃, M̃, β the Tresca quantities (3.39)/(3.40) at this b.
//!   On an active node u_n' = −g, so the coupling is −q λ_n' (F6).
//!
//! With μ = 0 every node is S2 or S4 with L̃ = 0, q = 0, r = 0: the frictionless rows (3.29).
//!
//! | module | role |
//! |---|---|
//! | `point` | a node's iterate, the threshold (F1), the residual, the states, c_τ's derivative |
//! | `row` | the node's Newton row of each state (F5)–(F7) and its block in the step system |

pub mod point;
pub mod row;
#[cfg(test)]
mod tests;

pub use point::{
    c_tau_coulomb, c_tau_coulomb_derivative, coulomb_classify, coulomb_conditions_hold,
    coulomb_residual, coulomb_threshold, CoulombDerivative, CoulombResidual, NodePoint,
};
pub use row::{
    coulomb_block, coulomb_row, coulomb_row_dyn, coulomb_row_projected, coulomb_row_unregularised,
    CoulombBlock, CoulombNewton, CoulombRow,
};
