//! Coulomb friction as the generalised Newton sees it (docs/friction.md): the threshold
//! b = μ max(0, −λ_n − c(u_n + g)) (F1), the rows (F5)/(F6) with settled slip in 2D, the
//! natural residual of (F3), the certificate's b_k = μ(−λ_n^k) and the capacity Σ_j μ_j N_j.
//! The pointwise law is `contact::coulomb`; the strategy of a solve is signorini/coulomb.rs.

use super::rules::{increment, slips_back, FloatingLoad, FrictionLaw};
use crate::contact::{self, CoulombRow, NodePoint};
use crate::signorini::boundary::{ContactNode, NodeResult};
use crate::signorini::force::ForceControl;

/// Coulomb (generalised Newton): the residual (F3) over all contact nodes must be below this
/// fraction of ‖λ‖₂ over all contact nodes, besides Algorithm 2's rule (no state changed,
/// |u^ℓ − u^{ℓ−1}| / |u^ℓ| < tol_u), before the iteration stops.
pub const COULOMB_RESIDUAL_TOL: f64 = 1e-9;

/// Coulomb: a residual (F3) below this fraction of ‖λ‖₂ is round-off: with no state changed
/// the iterate is a solution and the iteration stops at once (λ = f − A u holds by
/// construction, so (F3) = 0 is the whole problem), without the step that tests |Δu|.
pub const COULOMB_RESIDUAL_ZERO: f64 = 1e-12;

/// Coulomb: a residual that an exact step on unchanged states and an unchanged u (below
/// tol_u) no longer halves is what round-off leaves of (F3) — it grows with c and the
/// number of nodes (the floating Hertz disk at 344 620 unknowns stalls at 1.5e-9 of ‖λ‖₂, above
/// COULOMB_RESIDUAL_TOL, step after step with |Δu|/|u| ~ 1e-13) — and is accepted below this
/// fraction of ‖λ‖₂.
pub const COULOMB_RESIDUAL_STALL: f64 = 1e-6;

/// [`residual_floor`]: a residual (F3) within this many times ε c ‖u‖₂ (u on the contact
/// nodes) is round-off, however large c is. The arguments of (F3), λ_τ + c Δu_τ and the
/// threshold's c (u_n + g), carry c times u's rounding, about ε |u| per node: with c far above
/// its default that exceeds COULOMB_RESIDUAL_STALL · ‖λ‖₂. Measured: examples/cattaneo_mindlin.toml
/// at c = 1e9 (1e7 × its default) repeated one iterate with |Δu| = 0 and the residual at
/// 2.2e-10 (1.1e-6 ‖λ‖₂) for 100 steps, every load step failing after its cutbacks, though
/// its certificates held to 1e-13; the stalled residuals there and in tests/cases/punch_back.toml
/// at c = 1e12 (1.7e-3 ‖λ‖₂) are 0.25–0.49 ε c ‖u‖₂.
pub const COULOMB_ROUND_OFF_FACTOR: f64 = 10.0;

/// The residual (F3) that round-off alone leaves at an iterate whose contact nodes' ‖u‖₂ is
/// `contact_u`, with the complementarity parameter c: [`COULOMB_ROUND_OFF_FACTOR`] · ε c ‖u‖₂.
/// Pure.
pub fn residual_floor(c: f64, contact_u: f64) -> f64 {
    COULOMB_ROUND_OFF_FACTOR * f64::EPSILON * c * contact_u
}

/// Coulomb's law with each node's μ (`ContactNode::mu`: its pair's).
pub struct Coulomb;

impl FrictionLaw for Coulomb {
    /// (F5): stick, or slip with L̃, r̃ and the λ_n coupling q (F6). Local.
    fn row(&self, k: &ContactNode, r: &NodeResult, c: f64, dim: usize) -> CoulombRow<2> {
        let du_t = increment(r, k);
        contact::coulomb_row_dyn(dim, r.u_n, r.lambda_n, du_t, r.lambda_t, k.gap, k.mu, c).row
    }

    /// μ max(0, −λ_n − c(u_n + g)) (F1).
    fn threshold(&self, k: &ContactNode, r: &NodeResult, c: f64) -> f64 {
        contact::coulomb_threshold(r.u_n, r.lambda_n, k.gap, k.mu, c)
    }

    /// The natural residual of (F3), tangential part, squared.
    fn residual2(&self, k: &ContactNode, r: &NodeResult, c: f64) -> f64 {
        let p = NodePoint {
            u_n: r.u_n,
            lam_n: r.lambda_n,
            u_t: increment(r, k),
            lam_t: r.lambda_t,
        };
        contact::coulomb_residual(&p, k.gap, k.mu, c)
            .tangential
            .powi(2)
    }

    /// The row for the next step from the (F5) row `row` of node `k` at `r` and the row
    /// `prev` it was solved with, in 2D (docs/friction.md, "Settled slip"; `row` itself in 3D):
    /// - a node that slipped and slips on in the same direction (the sign of q kept) takes the
    ///   projection form's row [`contact::coulomb_row_projected`] λ_τ' = μ(−λ_n') ν: the (F5)
    ///   row at the slip solution, exact in 2D (the iteration is then piecewise linear there);
    /// - a node that slipped and whose increment now opposes its force (λ_τ Δu_τ < 0 with
    ///   |λ_τ| ≤ b: at a slip solution λ_τ = b sign Δu_τ) sticks.
    fn settled(
        &self,
        prev: Option<CoulombRow<2>>,
        row: CoulombRow<2>,
        k: &ContactNode,
        r: &NodeResult,
        c: f64,
        dim: usize,
    ) -> CoulombRow<2> {
        let (Some(CoulombRow::Slip { q: q0, .. }), CoulombRow::Slip { q: q1, .. }) = (prev, row)
        else {
            return row;
        };
        let b = self.threshold(k, r, c);
        if dim != 2 || !(b > 0.0 && q0[0] != 0.0 && q1[0] != 0.0) {
            return row;
        }
        if slips_back(r, k, b) {
            return CoulombRow::Stick;
        }
        let du = increment(r, k)[0];
        if q0[0] * q1[0] < 0.0 {
            return row;
        }
        let p = NodePoint {
            u_n: r.u_n,
            lam_n: r.lambda_n,
            u_t: [du],
            lam_t: [r.lambda_t[0]],
        };
        match contact::coulomb_row_projected(&p, k.gap, k.mu, c) {
            Some(CoulombRow::Slip { q, .. }) => CoulombRow::Slip {
                l: [[0.0; 2]; 2],
                q: [q[0], 0.0],
                r: [0.0; 2],
            },
            _ => row,
        }
    }

    /// b_k = μ(−λ_n^k) (F1) at the final state.
    fn judged_bound(&self, k: &ContactNode, r: &NodeResult) -> f64 {
        k.mu * (-r.lambda_n).max(0.0)
    }

    /// Σ_j μ_j N_j with N_j the pairs' normal forces ([`normal_forces`]); `None` where they
    /// are not known before the solve, or without friction or a normal load.
    fn capacity(&self, load: &FloatingLoad) -> Option<(f64, String)> {
        let normal = normal_forces(load.planes, load.rn, load.forces)?;
        let c: f64 = normal.iter().zip(load.mu).map(|(n, m)| n * m).sum();
        if c <= 0.0 {
            return None; // no friction, or no normal load: the balance test decides
        }
        let terms: Vec<String> = normal
            .iter()
            .zip(load.mu)
            .filter(|(n, _)| **n > 0.0)
            .map(|(n, m)| format!("{m} × {n:.6e}"))
            .collect();
        let what = if load.planes.len() == 1 {
            format!(
                "μ Σ_k (−λ_n^k) = μ × normal load = {} = {c:.6e}, Coulomb",
                terms.join("")
            )
        } else {
            format!(
                "Σ_j μ_j N_j over the pairs, N_j their normal forces = {} = {c:.6e}, Coulomb",
                terms.join(" + ")
            )
        };
        Some((c, what))
    }
}

/// The pairs' normal forces N_j ≥ 0 on a floating body between parallel planes (normals
/// `planes`, n_j = s_j n_0), from the load's normal resultant `rn` (along n_0) and the forces
/// under control: Σ_j s_j N_j + rn = 0, N_j = |F_j| on a pair pushed along its normal. `None`
/// if a force is not along its plane's normal, if more than one pair's force is unknown, or
/// if the balance asks for a pull (N < 0: the body leaves the plane, the balance test decides).
fn normal_forces(planes: &[[f64; 3]], rn: f64, forces: &[ForceControl]) -> Option<Vec<f64>> {
    let n0 = planes[0];
    let s: Vec<f64> = planes
        .iter()
        .map(|n| crate::geom::dot(*n, n0).signum())
        .collect();
    let mut normal = vec![f64::NAN; planes.len()];
    for fc in forces {
        let along = crate::geom::dot(fc.direction(), planes[fc.pair]);
        if along < 1.0 - 1e-12 {
            return None;
        }
        normal[fc.pair] = fc.magnitude();
    }
    let unknown: Vec<usize> = (0..planes.len()).filter(|&j| normal[j].is_nan()).collect();
    let known: f64 = (0..planes.len())
        .filter(|&j| !normal[j].is_nan())
        .map(|j| s[j] * normal[j])
        .sum();
    match unknown.as_slice() {
        [] => {}
        [u] => normal[*u] = -(rn + known) / s[*u],
        _ => return None,
    }
    normal.iter().all(|&n| n >= 0.0).then_some(normal)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pushed(pair: usize, force: [f64; 3]) -> ForceControl {
        ForceControl {
            force,
            start: 0.0,
            file: "case.toml".into(),
            pair,
            key: format!("contact[{pair}].force"),
        }
    }

    /// The normal forces of a body between a plate below (n = +y) and one above (n = −y).
    #[test]
    fn normal_forces_between_two_plates() {
        let plates = [[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]];
        // the top plate pushed down by 0.01, a body load of 0.002 downwards (rn = −0.002)
        let top = [pushed(1, [0.0, -0.01, 0.0])];
        let n = normal_forces(&plates, -0.002, &top).expect("known");
        assert!((n[0] - 0.012).abs() < 1e-15 && n[1] == 0.01, "{n:?}");
        // one plane, no force: N = −rn; a pull leaves it to the balance test
        assert_eq!(normal_forces(&plates[..1], -0.5, &[]), Some(vec![0.5]));
        assert_eq!(normal_forces(&plates[..1], 0.5, &[]), None);
        // two unknown normal forces, or a slanted force: not known before the solve
        assert_eq!(normal_forces(&plates, -0.002, &[]), None);
        let slanted = [pushed(1, [0.001, -0.01, 0.0])];
        assert_eq!(normal_forces(&plates, -0.002, &slanted), None);
    }
}
