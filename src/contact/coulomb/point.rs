//! One node's Coulomb quantities in its frame: the iterate, the threshold (F1), the residual
//! and the conditions, the node's state, and the derivative of c_τ.

use crate::contact::complementarity::{c_n, c_tau, normal_active, tangential_slip, NodeState};
use crate::contact::linalg::{axpy, norm, scale};
use crate::contact::residual::{normal_residual, project_ball, tresca_conditions_hold};

/// One node's iterate in its frame: normal and tangential parts of u^k and λ^k.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodePoint<const M: usize> {
    pub u_n: f64,
    pub lam_n: f64,
    pub u_t: [f64; M],
    pub lam_t: [f64; M],
}

/// (F1) the Coulomb threshold b = μ max(0, −λ_n − c (u_n + g)) of the complementarity form.
pub fn coulomb_threshold(u_n: f64, lam_n: f64, g: f64, mu: f64, c: f64) -> f64 {
    mu * (-lam_n - c * (u_n + g)).max(0.0)
}

/// (3.31) with the threshold (F1): C_τ = max{b, |v|} λ_τ − b v, v = λ_τ + c u_τ (F2).
pub fn c_tau_coulomb<const M: usize>(p: &NodePoint<M>, g: f64, mu: f64, c: f64) -> [f64; M] {
    let b = coulomb_threshold(p.u_n, p.lam_n, g, mu, c);
    c_tau(&p.u_t, &p.lam_t, b, c)
}

/// Residual of Coulomb's law at one node (F3): C_n (3.21) and the natural residual
/// |λ_τ − P_b(λ_τ + c u_τ)| with b of (F1). Both vanish iff (3.14) holds and (3.18) holds with
/// b = μ(−λ_n), i.e. iff the node satisfies Coulomb's law (any c > 0, also where b = 0, where
/// C_τ itself has spurious roots, §3.4.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoulombResidual {
    /// C_n(u_n, λ_n) (3.21), unit of λ.
    pub normal: f64,
    /// |λ_τ − P_b(λ_τ + c u_τ)|, unit of λ.
    pub tangential: f64,
}

impl CoulombResidual {
    /// √(C_n² + tangential²).
    pub fn norm(&self) -> f64 {
        self.normal.hypot(self.tangential)
    }
}

/// (F3) the residual of Coulomb's law at one node, see [`CoulombResidual`].
pub fn coulomb_residual<const M: usize>(
    p: &NodePoint<M>,
    g: f64,
    mu: f64,
    c: f64,
) -> CoulombResidual {
    let b = coulomb_threshold(p.u_n, p.lam_n, g, mu, c);
    let v = axpy(&p.lam_t, c, &p.u_t);
    CoulombResidual {
        normal: c_n(p.u_n, p.lam_n, g, c),
        tangential: norm(&axpy(&p.lam_t, -1.0, &project_ball(&v, b))),
    }
}

/// Coulomb's law stated directly (no complementarity function): (3.14) and (3.18) with
/// b = μ(−λ_n), within `tol_force` (λ-valued defects) and `tol_disp` (u-valued defects):
/// u_n + g ≥ −tol_disp, λ_n ≤ tol_force, |λ_n| ≤ tol_force or |u_n + g| ≤ tol_disp; and u_τ = 0
/// with |λ_τ| ≤ b, or λ_τ = b u_τ/|u_τ|.
pub fn coulomb_conditions_hold<const M: usize>(
    p: &NodePoint<M>,
    g: f64,
    mu: f64,
    tol_force: f64,
    tol_disp: f64,
) -> bool {
    let r = normal_residual(p.u_n, p.lam_n, g);
    let normal = r.penetration <= tol_disp
        && r.tension <= tol_force
        && (p.lam_n.abs() <= tol_force || (p.u_n + g).abs() <= tol_disp);
    normal
        && tresca_conditions_hold(
            &p.u_t,
            &p.lam_t,
            mu * (-p.lam_n).max(0.0),
            tol_force,
            tol_disp,
        )
}

/// (3.23) and (3.33) with b of (F1): the node's state for the next Newton step. S2 (k ∉ A_n,
/// frictionless), S3 (stick) or S4 (slip); never S1.
pub fn coulomb_classify<const M: usize>(p: &NodePoint<M>, g: f64, mu: f64, c: f64) -> NodeState {
    let b = coulomb_threshold(p.u_n, p.lam_n, g, mu, c);
    NodeState::new(
        normal_active(p.u_n, p.lam_n, g, c),
        tangential_slip(&p.u_t, &p.lam_t, b, c),
    )
}

/// One element of the generalised derivative of C_τ (3.31) with b of (F1) (F4), the branch
/// chosen by the strict tests (3.23)/(3.33): ∂C_τ/∂u_n, ∂C_τ/∂λ_n ∈ R^M,
/// ∂C_τ/∂u_τ, ∂C_τ/∂λ_τ ∈ R^{M×M} (row i: component i of C_τ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoulombDerivative<const M: usize> {
    pub d_un: [f64; M],
    pub d_lam_n: [f64; M],
    pub d_ut: [[f64; M]; M],
    pub d_lam_t: [[f64; M]; M],
}

/// (F4) the generalised derivative of C_τ with the Coulomb threshold (F1). With ν = v/|v|,
/// s = −λ_n − c(u_n + g):
/// - slip (b > 0, |v| > b): ∂λ_τ = (|v| − b) I + λ_τ νᵀ, ∂u_τ = c (λ_τ νᵀ − b I),
///   ∂λ_n = μ v, ∂u_n = μ c v (from ∂C/∂b = −v, ∂b/∂λ_n = −μ, ∂b/∂u_n = −μ c);
/// - stick (b > 0, |v| ≤ b): C_τ = −b c u_τ: ∂u_τ = −b c I, ∂λ_n = μ c u_τ, ∂u_n = μ c² u_τ;
/// - s ≤ 0 (b = 0): C_τ = |v| λ_τ: ∂λ_τ = |v| I + λ_τ νᵀ, ∂u_τ = c λ_τ νᵀ (0 at v = 0).
pub fn c_tau_coulomb_derivative<const M: usize>(
    p: &NodePoint<M>,
    g: f64,
    mu: f64,
    c: f64,
) -> CoulombDerivative<M> {
    let b = coulomb_threshold(p.u_n, p.lam_n, g, mu, c);
    let v = axpy(&p.lam_t, c, &p.u_t);
    let nv = norm(&v);
    let nu = if nv > 0.0 {
        scale(1.0 / nv, &v)
    } else {
        [0.0; M]
    };
    let mut d = CoulombDerivative {
        d_un: [0.0; M],
        d_lam_n: [0.0; M],
        d_ut: [[0.0; M]; M],
        d_lam_t: [[0.0; M]; M],
    };
    let positive = b > 0.0;
    if positive && nv <= b {
        for i in 0..M {
            d.d_ut[i][i] = -b * c;
            d.d_lam_n[i] = mu * c * p.u_t[i];
            d.d_un[i] = mu * c * c * p.u_t[i];
        }
        return d;
    }
    let diag = if positive { nv - b } else { nv };
    let bb = if positive { b } else { 0.0 };
    for i in 0..M {
        for j in 0..M {
            d.d_lam_t[i][j] = p.lam_t[i] * nu[j];
            d.d_ut[i][j] = c * p.lam_t[i] * nu[j];
        }
        d.d_lam_t[i][i] += diag;
        d.d_ut[i][i] -= c * bb;
        if positive {
            d.d_lam_n[i] = mu * v[i];
            d.d_un[i] = mu * c * v[i];
        }
    }
    d
}
