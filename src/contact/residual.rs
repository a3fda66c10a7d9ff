//! Node-wise residuals of the discrete contact conditions (3.14) and (3.18): a
//! certificate that a computed (u, λ) solves the contact problem, independent of the
//! complementarity functions and of c.
//!
//! Sign convention (THEORY §2): λ_n ≤ 0 where the node presses on the obstacle; −λ is the
//! contact force on the body. (3.18): |λ_τ| ≤ b; |λ_τ| < b ⇒ u_τ = 0;
//! |λ_τ| = b ⇒ λ_τ = α² u_τ, i.e. λ_τ is parallel to u_τ with the SAME orientation
//! (the friction force −λ_τ on the body opposes the slip u_τ). Equivalently (proof of
//! Lemma 3.3): |λ_τ| ≤ b and λ_τ·u_τ = b |u_τ|; so on a slipping node (u_τ ≠ 0)
//! λ_τ = b u_τ/|u_τ|. |λ_τ| = b with u_τ = 0 is admissible (a node at the stick limit).

use super::linalg::{axpy, norm, scale};

/// Residuals of (3.14) at one node. All are ≥ 0 and all vanish iff (3.14) holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormalResidual {
    /// max(−(u_n + g), 0): penetration into the obstacle.
    pub penetration: f64,
    /// max(λ_n, 0): the obstacle pulling on the body (adhesion), forbidden.
    pub tension: f64,
    /// |λ_n (u_n + g)|: force on a node that is not touching (unit force × length).
    pub complementarity: f64,
}

/// (3.14) residuals for one node with normal displacement `u_n`, multiplier `lam_n`
/// and gap `g`.
pub fn normal_residual(u_n: f64, lam_n: f64, g: f64) -> NormalResidual {
    let s = u_n + g;
    NormalResidual {
        penetration: (-s).max(0.0),
        tension: lam_n.max(0.0),
        complementarity: (lam_n * s).abs(),
    }
}

/// Does (3.14) hold within `tol`? (|·| of each residual ≤ tol; tol = 0 is exact.)
pub fn normal_conditions_hold(u_n: f64, lam_n: f64, g: f64, tol: f64) -> bool {
    let r = normal_residual(u_n, lam_n, g);
    r.penetration <= tol && r.tension <= tol && r.complementarity <= tol
}

/// Residuals of the Tresca conditions (3.18) at one node, given the node's tangential
/// state as used by the solver (stick: I_τ, slip: A_τ). Force-valued fields have the
/// unit of λ, `stick_motion` the unit of u.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TangentialResidual {
    /// max(|λ_τ| − b, 0): the friction force exceeds the threshold (any state).
    pub excess: f64,
    /// Stick nodes: |u_τ| (must be 0). Slip nodes: 0.
    pub stick_motion: f64,
    /// Slip nodes with u_τ ≠ 0: |λ_τ − b u_τ/|u_τ||, the defect of λ_τ = α² u_τ with
    /// |λ_τ| = b (covers both the length and the direction). Slip nodes with u_τ = 0:
    /// `excess` (such a node is at rest, which (3.18) allows for |λ_τ| ≤ b).
    /// Stick nodes: 0.
    pub slip_alignment: f64,
}

/// (3.18) residuals for one node with tangential displacement `u_t`, multiplier `lam_t`,
/// threshold `b` ≥ 0 and state `slip` (true: A_τ, false: I_τ).
pub fn tangential_residual<const M: usize>(
    u_t: &[f64; M],
    lam_t: &[f64; M],
    b: f64,
    slip: bool,
) -> TangentialResidual {
    let excess = (norm(lam_t) - b).max(0.0);
    if !slip {
        return TangentialResidual {
            excess,
            stick_motion: norm(u_t),
            slip_alignment: 0.0,
        };
    }
    let nu = norm(u_t);
    let slip_alignment = if nu > 0.0 {
        norm(&axpy(lam_t, -b / nu, u_t))
    } else {
        excess
    };
    TangentialResidual {
        excess,
        stick_motion: 0.0,
        slip_alignment,
    }
}

/// Does (3.18) hold within `tol_force` (for λ-valued defects) and `tol_disp` (for u)?
/// State-free: holds if u_τ = 0 and |λ_τ| ≤ b, or u_τ ≠ 0 and λ_τ = b u_τ/|u_τ|.
pub fn tresca_conditions_hold<const M: usize>(
    u_t: &[f64; M],
    lam_t: &[f64; M],
    b: f64,
    tol_force: f64,
    tol_disp: f64,
) -> bool {
    let stick = tangential_residual(u_t, lam_t, b, false);
    if stick.excess <= tol_force && stick.stick_motion <= tol_disp {
        return true;
    }
    let slip = tangential_residual(u_t, lam_t, b, true);
    norm(u_t) > 0.0 && slip.slip_alignment <= tol_force
}

/// Euclidean projection of `v` onto the closed ball of radius `b` ≥ 0.
pub fn project_ball<const M: usize>(v: &[f64; M], b: f64) -> [f64; M] {
    let nv = norm(v);
    if nv <= b {
        *v
    } else {
        scale(b / nv, v)
    }
}

/// Natural residual |λ_τ − P_b(λ_τ + c u_τ)| of (3.18) (unit of λ). It equals
/// |C_τ| / max(b, |λ_τ + c u_τ|) for b > 0 (3.31), and is zero iff (3.18) holds
/// (Satz 3.7, any c > 0). Unlike C_τ it also covers b = 0: P_0 = 0, so it is |λ_τ|.
pub fn tresca_natural_residual<const M: usize>(
    u_t: &[f64; M],
    lam_t: &[f64; M],
    b: f64,
    c: f64,
) -> f64 {
    let v = axpy(lam_t, c, u_t);
    norm(&axpy(lam_t, -1.0, &project_ball(&v, b)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_residual_cases() {
        // touching and pressing: fine
        assert!(normal_conditions_hold(-0.5, -3.0, 0.5, 0.0));
        // free, no force: fine
        assert!(normal_conditions_hold(0.1, 0.0, 0.5, 0.0));
        // penetration 0.25
        let r = normal_residual(-0.75, -1.0, 0.5);
        assert_eq!(r.penetration, 0.25);
        assert_eq!(r.complementarity, 0.25);
        assert_eq!(r.tension, 0.0);
        // tension
        let r = normal_residual(-0.5, 2.0, 0.5);
        assert_eq!(r.tension, 2.0);
        assert_eq!(r.penetration, 0.0);
        assert!(!normal_conditions_hold(-0.5, 2.0, 0.5, 1e-12));
        // pressing while free
        let r = normal_residual(0.5, -2.0, 0.5);
        assert_eq!(r.complementarity, 2.0);
    }

    #[test]
    fn tangential_residual_cases() {
        let b = 2.0;
        // stick inside the disc
        assert!(tresca_conditions_hold(
            &[0.0, 0.0],
            &[1.0, -1.0],
            b,
            0.0,
            0.0
        ));
        let r = tangential_residual(&[0.0, 0.0], &[1.0, -1.0], b, false);
        assert_eq!(
            (r.excess, r.stick_motion, r.slip_alignment),
            (0.0, 0.0, 0.0)
        );
        // slip aligned: λ = b u/|u|
        let r = tangential_residual(&[3.0, 4.0], &[1.2, 1.6], b, true);
        assert!(r.slip_alignment < 1e-15 && r.excess == 0.0);
        assert!(tresca_conditions_hold(
            &[3.0, 4.0],
            &[1.2, 1.6],
            b,
            1e-14,
            0.0
        ));
        // opposite orientation: defect 2b
        let r = tangential_residual(&[3.0, 4.0], &[-1.2, -1.6], b, true);
        assert!((r.slip_alignment - 4.0).abs() < 1e-14);
        assert!(!tresca_conditions_hold(
            &[3.0, 4.0],
            &[-1.2, -1.6],
            b,
            1e-8,
            1e-8
        ));
        // too short on a slipping node
        let r = tangential_residual(&[3.0], &[1.0], b, true);
        assert!((r.slip_alignment - 1.0).abs() < 1e-15);
        // stick node that moves
        let r = tangential_residual(&[0.5], &[3.0], b, false);
        assert_eq!((r.excess, r.stick_motion), (1.0, 0.5));
        // b = 0, slip: λ must vanish
        let r = tangential_residual(&[1.0, 0.0], &[0.0, 0.3], 0.0, true);
        assert!((r.slip_alignment - 0.3).abs() < 1e-15);
        // natural residual
        assert_eq!(tresca_natural_residual(&[0.0], &[1.0], b, 1.0), 0.0);
        assert!(tresca_natural_residual(&[1.0], &[2.0], b, 1.0) < 1e-15);
        // v = −1 lies in the disc: λ − P(v) = −2 − (−1)
        assert!((tresca_natural_residual(&[1.0], &[-2.0], b, 1.0) - 1.0).abs() < 1e-15);
        assert!((tresca_natural_residual(&[3.0], &[-2.0], b, 1.0) - 3.0).abs() < 1e-15);
        assert!((tresca_natural_residual(&[1.0, 0.0], &[0.0, 0.3], 0.0, 1.0) - 0.3).abs() < 1e-15);
    }
}
