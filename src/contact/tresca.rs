//! Tresca slip rows of the semismooth Newton method (thesis §3.4.1–§3.4.3,
//! (3.33)–(3.40)) for one contact node, M = d − 1 tangential components (M = 1: 2D
//! scalars, M = 2: 3D 2×2 matrices).
//!
//! Inputs are the previous iterate (u_τ, λ_τ), the threshold b = b_k ≥ 0 and c > 0;
//! v = λ_τ + c u_τ. A slip node (k ∈ A_τ) gets the row  −λ_τ' + L̃ u_τ' = r̃  (3.39a) for
//! the new iterate (u_τ', λ_τ'); a stick node the row u_τ' = 0 (3.34a).
//!
//! Degenerate inputs (§3.4.3, and how they are handled here):
//! - b ≤ 0 (frictionless node): always slip with L̃ = 0, r̃ = 0, i.e. λ_τ' = 0, whatever
//!   u_τ and λ_τ are (also for v = 0 or λ_τ = 0).
//! - b > 0 and |v| ≤ b: stick by (3.33); no slip row is formed, so v = 0 never divides.
//! - b > 0, |v| > b, λ_τ = 0: nothing divides by zero either. F̃ = 0, M̃ = e I and
//!   α δ = λ_τ·v / (|v| max(b, |λ_τ|)) = 0, so β = 1 and L̃ = c e/(1−e) I, r̃ = 0: the exact
//!   Newton row (3.34b). This node is NOT forced to λ_τ' = 0: doing so would make
//!   (λ_τ = 0, c|u_τ| > b) a fixed point of Algorithm 2 that violates (3.18). α is
//!   reported as 0 there (it is undefined; only the product α δ = 0 enters).

use super::complementarity::tangential_slip;
use super::linalg::{axpy, dot, identity, inverse, mat_lin, matvec, norm, outer};

/// All quantities of the regularised slip row (3.35)–(3.40) of one slip node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Regularisation<const M: usize> {
    /// v = λ_τ + c u_τ
    pub v: [f64; M],
    /// e = b / |v| ∈ (0, 1)  (3.35)
    pub e: f64,
    /// α = λ_τ·v / (|λ_τ| |v|) ∈ [−1, 1]; 0 when λ_τ = 0
    pub alpha: f64,
    /// δ = min(|λ_τ| / b, 1) ∈ [0, 1]
    pub delta: f64,
    /// β = 1/(1 − α δ) if α < 0, else 1; β ∈ [1/2, 1]
    pub beta: f64,
    /// F̃ = λ_τ vᵀ / (max(b, |λ_τ|) |v|)  (3.40)
    pub f_tilde: [[f64; M]; M],
    /// M̃ = e (I − F̃)
    pub m_tilde: [[f64; M]; M],
    /// h̃ = e F̃ v  (= b λ_τ / max(b, |λ_τ|))
    pub h_tilde: [f64; M],
    /// L̃ = c ((I − β M̃)⁻¹ − I)  (3.39b)
    pub l_tilde: [[f64; M]; M],
    /// r̃ = −(I − β M̃)⁻¹ h̃  (3.39c)
    pub r_tilde: [f64; M],
}

/// (3.35), (3.39), (3.40): the regularised slip row of a node with b > 0 and
/// |v| > b (k ∈ A_τ by (3.33)). `None` if b ≤ 0, |v| ≤ b or inputs are not finite.
///
/// I − β M̃ = (1 − βe) I + βe F̃ has the eigenvalues 1 − βe(1 − αδ) (eigenvector λ_τ)
/// and 1 − βe (2D: only the first), both in (0, 1]. L̃ and r̃ are formed in closed form
/// in a basis aligned with λ_τ (see the code), which keeps them accurate as e → 1.
pub fn regularise<const M: usize>(
    u_t: &[f64; M],
    lam_t: &[f64; M],
    b: f64,
    c: f64,
) -> Option<Regularisation<M>> {
    let v = axpy(lam_t, c, u_t);
    let nv = norm(&v);
    let nl = norm(lam_t);
    if !(nv.is_finite() && nl.is_finite() && c.is_finite()) || b.is_nan() || b <= 0.0 || nv <= b {
        return None;
    }
    let e = b / nv;
    let mx = b.max(nl);
    let id = identity::<M>();
    let f_tilde = mat_lin(1.0 / (mx * nv), &outer(lam_t, &v), 0.0, &id);
    let m_tilde = mat_lin(-e, &f_tilde, e, &id);
    let h_tilde = matvec(&f_tilde, &v).map(|x| e * x);
    let (alpha, delta) = if nl > 0.0 {
        (
            (dot(lam_t, &v) / (nl * nv)).clamp(-1.0, 1.0),
            (nl / b).min(1.0),
        )
    } else {
        (0.0, 0.0)
    };
    // α δ = trace F̃, computed without dividing by |λ_τ|.
    let ad = (dot(lam_t, &v) / (mx * nv)).clamp(-1.0, 1.0);
    let beta = if alpha < 0.0 { 1.0 / (1.0 - ad) } else { 1.0 };
    let be = beta * e;
    // I − βM̃ = a0 I + βe F̃ with a0 = 1 − βe; λ_τ is an eigenvector, eigenvalue
    // γ1 = a0 + βe αδ. Both are formed from 1 − e = (|v| − b)/|v| without cancellation:
    // α < 0: a0 = (1 − e − αδ)/(1 − αδ), γ1 = 1 − e;  α ≥ 0: a0 = 1 − e, γ1 = 1 − e + e αδ.
    let ome = (nv - b) / nv;
    let (a0, gamma1) = if alpha < 0.0 {
        ((ome - ad) / (1.0 - ad), ome)
    } else {
        (ome, ome + e * ad.max(0.0))
    };
    // In the orthonormal basis q0 = λ_τ/|λ_τ|, q1 = q0 turned by 90° (3D only), with
    // F̃ = λ_τ wᵀ, w = v/(max(b,|λ_τ|)|v|), I − βM̃ is upper triangular:
    //   [[γ1, βe|λ_τ| w·q1], [0, a0]],
    // so (using 1 − γ1 = βe(1 − αδ), 1 − a0 = βe)
    //   L̃ = c [[βe(1 − αδ)/γ1, −βe|λ_τ|(w·q1)/(γ1 a0)], [0, βe/a0]],   r̃ = −h̃/γ1.
    // This avoids the cancellation of the textbook formula when 1 − e is small.
    let mut l_tilde = [[0.0; M]; M];
    let r_tilde;
    if nl > 0.0 {
        let q0 = lam_t.map(|x| x / nl);
        let mut l = mat_lin(c * be * (1.0 - ad) / gamma1, &outer(&q0, &q0), 0.0, &id);
        if M == 2 {
            let mut q1 = [0.0; M];
            q1[0] = -q0[1];
            q1[1] = q0[0];
            let w1 = dot(&v, &q1) / (mx * nv);
            l = mat_lin(1.0, &l, c * be / a0, &outer(&q1, &q1));
            l = mat_lin(1.0, &l, -c * be * nl * w1 / (gamma1 * a0), &outer(&q0, &q1));
        }
        l_tilde = l;
        r_tilde = h_tilde.map(|x| -x / gamma1);
    } else {
        for (i, row) in l_tilde.iter_mut().enumerate() {
            row[i] = c * be / a0;
        }
        r_tilde = [0.0; M];
    }
    Some(Regularisation {
        v,
        e,
        alpha,
        delta,
        beta,
        f_tilde,
        m_tilde,
        h_tilde,
        l_tilde,
        r_tilde,
    })
}

/// The unregularised quantities (3.35)–(3.38) of a slip node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unregularised<const M: usize> {
    /// e = b / |v|  (3.35)
    pub e: f64,
    /// F = λ_τ vᵀ / (b |v|)  (3.35)
    pub f: [[f64; M]; M],
    /// M = e (I − F)
    pub m: [[f64; M]; M],
    /// h = e F v (= λ_τ)  (3.36)
    pub h: [f64; M],
    /// L = c ((I − M)⁻¹ − I)  (3.38a)
    pub l: [[f64; M]; M],
    /// r = −(I − M)⁻¹ h  (3.38b)
    pub r: [f64; M],
}

/// (3.35)–(3.38) for b > 0, v ≠ 0. `None` if b ≤ 0, v = 0 or I − M is numerically
/// singular (which does happen during the iteration: the reason for (3.39)).
pub fn unregularised<const M: usize>(
    u_t: &[f64; M],
    lam_t: &[f64; M],
    b: f64,
    c: f64,
) -> Option<Unregularised<M>> {
    let v = axpy(lam_t, c, u_t);
    let nv = norm(&v);
    if !nv.is_finite() || b.is_nan() || b <= 0.0 || nv <= 0.0 {
        return None;
    }
    let e = b / nv;
    let id = identity::<M>();
    let f = mat_lin(1.0 / (b * nv), &outer(lam_t, &v), 0.0, &id);
    let m = mat_lin(-e, &f, e, &id);
    let h = matvec(&f, &v).map(|x| e * x);
    let inv = inverse(&mat_lin(1.0, &id, -1.0, &m), 1e-12)?;
    let l = mat_lin(c, &inv, -c, &id);
    let r = matvec(&inv, &h).map(|x| -x);
    Some(Unregularised { e, f, m, h, l, r })
}

/// The tangential rows of one node for the next Newton step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TangentialRow<const M: usize> {
    /// k ∈ I_τ: u_τ' = 0  (3.34a)
    Stick,
    /// k ∈ A_τ: −λ_τ' + l u_τ' = r  (3.39a); l = 0, r = 0 for b = 0 (§3.4.3)
    Slip { l: [[f64; M]; M], r: [f64; M] },
}

impl<const M: usize> TangentialRow<M> {
    pub fn is_slip(&self) -> bool {
        matches!(self, TangentialRow::Slip { .. })
    }
}

/// (3.33), (3.34a), (3.39), §3.4.3: stick or slip, and the slip row's L̃, r̃, from the
/// previous iterate (u_τ, λ_τ) of a node with threshold b ≥ 0 (b ≤ 0: frictionless).
pub fn tangential_row<const M: usize>(
    u_t: &[f64; M],
    lam_t: &[f64; M],
    b: f64,
    c: f64,
) -> TangentialRow<M> {
    if !tangential_slip(u_t, lam_t, b, c) {
        return TangentialRow::Stick;
    }
    match regularise(u_t, lam_t, b, c) {
        Some(reg) => TangentialRow::Slip {
            l: reg.l_tilde,
            r: reg.r_tilde,
        },
        // b ≤ 0 (or non-finite input): frictionless, λ_τ' = 0.
        None => TangentialRow::Slip {
            l: [[0.0; M]; M],
            r: [0.0; M],
        },
    }
}

/// [`tangential_row`] for a runtime dimension `dim` (2 or 3), with tangential vectors
/// padded to length 2 (second entry ignored in 2D). In 2D the 1×1 row sits in
/// `l[0][0]`, `r[0]`; the other entries are 0.
pub fn tangential_row_dyn(
    dim: usize,
    u_t: [f64; 2],
    lam_t: [f64; 2],
    b: f64,
    c: f64,
) -> TangentialRow<2> {
    if dim == 3 {
        return tangential_row(&u_t, &lam_t, b, c);
    }
    match tangential_row(&[u_t[0]], &[lam_t[0]], b, c) {
        TangentialRow::Stick => TangentialRow::Stick,
        TangentialRow::Slip { l, r } => TangentialRow::Slip {
            l: [[l[0][0], 0.0], [0.0, 0.0]],
            r: [r[0], 0.0],
        },
    }
}

#[cfg(test)]
mod tests {
    use super::super::complementarity::c_tau;
    use super::super::linalg::{eig2, matmul, max_abs, scale};
    use super::super::residual::tangential_residual;
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    fn rand_vec<const M: usize>(rng: &mut StdRng, r: f64) -> [f64; M] {
        [0.0; M].map(|_| rng.gen_range(-r..r))
    }

    /// Random previous iterates that are slip nodes (|v| > b), from several families:
    /// generic, λ_τ far outside the disc, λ_τ opposite to v, λ_τ ⊥ v, λ_τ = 0, and |v|
    /// just above b (e → 1).
    fn slip_samples<const M: usize>(seed: u64, n: usize) -> Vec<([f64; M], [f64; M], f64, f64)> {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut out = Vec::new();
        while out.len() < n {
            let b = rng.gen_range(0.05..5.0);
            let c = [0.01, 1.0, 10.0, 1e3][rng.gen_range(0..4)];
            let kind = rng.gen_range(0..6);
            let (u, lam): ([f64; M], [f64; M]) = match kind {
                0 => (rand_vec(&mut rng, 3.0 * b / c), rand_vec(&mut rng, 3.0 * b)),
                1 => (rand_vec(&mut rng, b / c), rand_vec(&mut rng, 30.0 * b)),
                2 => {
                    // v = λ + c u points against λ
                    let lam = rand_vec(&mut rng, 2.0 * b);
                    let s = rng.gen_range(1.05..20.0);
                    (scale(-s / c, &lam), lam)
                }
                3 => {
                    let lam: [f64; M] = rand_vec(&mut rng, 2.0 * b);
                    let mut u = rand_vec::<M>(&mut rng, 3.0 * b / c);
                    if M == 2 {
                        // make v ⊥ λ: v = λ + c u, remove the λ-part of v
                        let v = axpy(&lam, c, &u);
                        let p = dot(&v, &lam) / dot(&lam, &lam);
                        let vp = axpy(&v, -p, &lam);
                        u = axpy(&vp, -1.0, &lam).map(|x| x / c);
                    }
                    (u, lam)
                }
                4 => (rand_vec(&mut rng, 3.0 * b / c), [0.0; M]),
                _ => {
                    let lam: [f64; M] = rand_vec(&mut rng, 2.0 * b);
                    let v = rand_vec::<M>(&mut rng, 1.0);
                    let nv = norm(&v);
                    if nv < 1e-3 {
                        continue;
                    }
                    let target = b * (1.0 + 10f64.powf(rng.gen_range(-12.0..-1.0)));
                    let v = scale(target / nv, &v);
                    (axpy(&v, -1.0, &lam).map(|x| x / c), lam)
                }
            };
            if norm(&axpy(&lam, c, &u)) > b {
                out.push((u, lam, b, c));
            }
        }
        out
    }

    /// Thesis §3.4.2, 2D: 1 − βM̃ ∈ (0, 1] for every slip node, so L̃ ≥ 0 exists.
    #[test]
    fn regularised_scalar_in_0_1_2d() {
        for (u, lam, b, c) in slip_samples::<1>(20, 5000) {
            let reg = regularise(&u, &lam, b, c).expect("slip node");
            let a = 1.0 - reg.beta * reg.m_tilde[0][0];
            assert!(a > 0.0 && a <= 1.0 + 1e-15, "1-βM̃ = {a}");
            assert!(reg.l_tilde[0][0] >= -1e-12 * c && reg.l_tilde[0][0].is_finite());
            assert!(reg.e > 0.0 && reg.e < 1.0);
            assert!(reg.beta >= 0.5 && reg.beta <= 1.0);
        }
    }

    /// Thesis §3.4.2, 3D (d−1 = 2). The thesis states (citing [9]): the eigenvalues of F̃
    /// are αδ and 0; those of M̃ are e(1 − αδ) ∈ [0, 2) and e ∈ (0, 1) (using
    /// 0 < e < 1 on slip nodes, −1 ≤ α ≤ 1, 0 ≤ δ ≤ 1); with β = 1/(1 − αδ) for α < 0 the
    /// eigenvalues of I − βM̃ are positive and ≤ 1, so I − βM̃ is regular. Checked here:
    /// the eigenvalues computed from the matrix entries are real and equal the stated
    /// formulas (to √ε: F̃ can be nilpotent, whose eigenvalues are that sensitive), the
    /// formulas lie in the stated ranges, and the eigenvalues of L̃ = c((I − βM̃)⁻¹ − I)
    /// are real and ≥ 0 (L̃ itself is not symmetric in general).
    #[test]
    fn regularised_eigenvalues_3d() {
        let close = |got: [(f64, f64); 2], want: [f64; 2], sc: f64| {
            let (lo, hi) = (want[0].min(want[1]), want[0].max(want[1]));
            let tol = 1e-7 * sc;
            got[0].1.abs() <= tol
                && got[1].1.abs() <= tol
                && (got[0].0 - lo).abs() <= tol
                && (got[1].0 - hi).abs() <= tol
        };
        for (u, lam, b, c) in slip_samples::<2>(21, 5000) {
            let reg = regularise(&u, &lam, b, c).expect("slip node");
            // α, δ, e, β recomputed here from their definitions
            let v = axpy(&lam, c, &u);
            let e = b / norm(&v);
            let (alpha, delta) = if norm(&lam) > 0.0 {
                (
                    dot(&lam, &v) / (norm(&lam) * norm(&v)),
                    (norm(&lam) / b).min(1.0),
                )
            } else {
                (0.0, 0.0)
            };
            assert!((alpha - reg.alpha).abs() < 1e-12 && (delta - reg.delta).abs() < 1e-12);
            assert!((e - reg.e).abs() < 1e-15 && e > 0.0 && e < 1.0);
            assert!(alpha.abs() <= 1.0 + 1e-15 && (0.0..=1.0).contains(&delta));
            let ad = alpha.clamp(-1.0, 1.0) * delta;
            let beta = if alpha < 0.0 { 1.0 / (1.0 - ad) } else { 1.0 };
            assert!((beta - reg.beta).abs() < 1e-12);
            let sf = 1.0 + max_abs(&reg.f_tilde);
            assert!(
                close(eig2(&reg.f_tilde), [ad, 0.0], sf),
                "F̃ {:?}",
                eig2(&reg.f_tilde)
            );
            let want_m = [e * (1.0 - ad), e];
            assert!(close(eig2(&reg.m_tilde), want_m, sf));
            assert!((0.0..2.0).contains(&want_m[0]) && want_m[1] > 0.0 && want_m[1] < 1.0);
            let a = mat_lin(1.0, &identity::<2>(), -reg.beta, &reg.m_tilde);
            let want_a = [1.0 - beta * want_m[0], 1.0 - beta * want_m[1]];
            assert!(close(eig2(&a), want_a, sf), "{:?} {want_a:?}", eig2(&a));
            assert!(want_a.iter().all(|&x| x > 0.0 && x <= 1.0), "{want_a:?}");
            let sl = 1.0 + max_abs(&reg.l_tilde);
            for (re, im) in eig2(&reg.l_tilde) {
                assert!(im.abs() <= 1e-7 * sl && re >= -1e-7 * sl, "L̃ eig {re} {im}");
            }
        }
    }

    /// The closed-form inverse agrees with the definitions (3.39b), (3.39c) evaluated with
    /// a general 2×2 / 1×1 inverse, and h̃ = b λ_τ / max(b, |λ_τ|) (THEORY §4).
    fn closed_form_matches_definition<const M: usize>(seed: u64) {
        for (u, lam, b, c) in slip_samples::<M>(seed, 3000) {
            let reg = regularise(&u, &lam, b, c).unwrap();
            let a = mat_lin(1.0, &identity::<M>(), -reg.beta, &reg.m_tilde);
            let inv = inverse(&a, 1e-15).expect("regular");
            let l = mat_lin(c, &inv, -c, &identity::<M>());
            let r = matvec(&inv, &reg.h_tilde).map(|x| -x);
            // The reference forms I − βM̃ with cancellation: relative accuracy ~ ε·|A⁻¹|.
            let s = max_abs(&inv);
            let tol = 1e-12 * s * s;
            assert!(
                max_abs(&mat_lin(1.0, &l, -1.0, &reg.l_tilde)) <= tol * c,
                "{l:?} {reg:?}"
            );
            assert!(norm(&axpy(&r, -1.0, &reg.r_tilde)) <= tol * b);
            let h = scale(b / b.max(norm(&lam)), &lam);
            assert!(norm(&axpy(&h, -1.0, &reg.h_tilde)) <= 1e-12 * b);
        }
    }

    #[test]
    fn closed_form_matches_definition_2d() {
        closed_form_matches_definition::<1>(22);
    }

    #[test]
    fn closed_form_matches_definition_3d() {
        closed_form_matches_definition::<2>(23);
    }

    /// The unregularised row (3.34b)/(3.37) is the semismooth Newton linearisation of
    /// C_τ (3.31) at a slip node: for any (u', λ') on the row −λ' + L u' = r,
    /// C_τ(u, λ) + D C_τ(u, λ)(u' − u, λ' − λ) = 0 with the derivative of §3.4.1.
    fn newton_consistency<const M: usize>(seed: u64) {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut tested = 0;
        for (u, lam, b, c) in slip_samples::<M>(seed, 2000) {
            let Some(un) = unregularised(&u, &lam, b, c) else {
                continue;
            };
            if max_abs(&un.l) > 1e6 * c {
                continue; // nearly singular I − M: skip the ill-conditioned samples
            }
            tested += 1;
            let u2 = rand_vec::<M>(&mut rng, b / c);
            let lam2 = axpy(&matvec(&un.l, &u2), -1.0, &un.r);
            let v = axpy(&lam, c, &u);
            let nv = norm(&v);
            let dl = axpy(&lam2, -1.0, &lam);
            let du = axpy(&u2, -1.0, &u);
            let dv = axpy(&dl, c, &du);
            // D C_τ(Δ) = |v| Δλ + λ vᵀ Δv / |v| − b Δv   (k ∈ A_τ)
            let d = axpy(&axpy(&scale(nv, &dl), dot(&v, &dv) / nv, &lam), -b, &dv);
            let res = axpy(&c_tau(&u, &lam, b, c), 1.0, &d);
            let sc = nv * (norm(&lam) + norm(&lam2) + b) + b * norm(&dv);
            assert!(norm(&res) <= 1e-10 * sc, "{res:?} scale {sc}");
            // and h = λ (3.36)
            assert!(norm(&axpy(&un.h, -1.0, &lam)) <= 1e-12 * (b + norm(&lam)));
        }
        assert!(tested > 1000);
    }

    #[test]
    fn newton_consistency_2d() {
        newton_consistency::<1>(24);
    }

    #[test]
    fn newton_consistency_3d() {
        newton_consistency::<2>(25);
    }

    /// Where the regularisation is inactive (|λ_τ| ≤ b and λ_τ·v ≥ 0) L̃ = L and r̃ = r.
    fn inactive_regularisation_is_exact<const M: usize>(seed: u64) {
        let mut n = 0;
        for (u, lam, b, c) in slip_samples::<M>(seed, 3000) {
            if norm(&lam) > b || dot(&lam, &axpy(&lam, c, &u)) < 0.0 {
                continue;
            }
            let reg = regularise(&u, &lam, b, c).unwrap();
            assert_eq!(reg.beta, 1.0);
            let Some(un) = unregularised(&u, &lam, b, c) else {
                panic!("I - M must be regular here")
            };
            let s = 1.0 + max_abs(&un.l) / c;
            let tol = 1e-12 * s * s;
            assert!(
                max_abs(&mat_lin(1.0, &un.l, -1.0, &reg.l_tilde)) <= tol * c,
                "{un:?} {reg:?}"
            );
            assert!(norm(&axpy(&un.r, -1.0, &reg.r_tilde)) <= tol * b);
            n += 1;
        }
        assert!(n > 200);
    }

    #[test]
    fn inactive_regularisation_is_exact_2d() {
        inactive_regularisation_is_exact::<1>(26);
    }

    #[test]
    fn inactive_regularisation_is_exact_3d() {
        inactive_regularisation_is_exact::<2>(27);
    }

    /// At a slipping solution of (3.18) (|λ_τ| = b, λ_τ = γ u_τ, γ > 0): the node is in
    /// A_τ, L̃ = L, r̃ = r = −λ_τ, the slip row holds for (u_τ, λ_τ) itself, and near the
    /// solution L̃ − L, r̃ − r = O(distance) (the regularisation fades out).
    fn at_solution<const M: usize>(seed: u64) {
        let mut rng = StdRng::seed_from_u64(seed);
        for _ in 0..500 {
            let b = rng.gen_range(0.05..5.0);
            let c = [0.01, 1.0, 10.0, 1e3][rng.gen_range(0..4)];
            let d = rand_vec::<M>(&mut rng, 1.0);
            if norm(&d) < 1e-2 {
                continue;
            }
            let lam = scale(b / norm(&d), &d);
            let gamma = 10f64.powf(rng.gen_range(-2.0..2.0));
            let u = scale(1.0 / gamma, &lam);
            assert!(tangential_slip(&u, &lam, b, c));
            let reg = regularise(&u, &lam, b, c).unwrap();
            let un = unregularised(&u, &lam, b, c).unwrap();
            assert!((reg.beta - 1.0).abs() < 1e-15 && (reg.alpha - 1.0).abs() < 1e-12);
            let sl = c * (1.0 + 1.0 / (1.0 - reg.e));
            assert!(max_abs(&mat_lin(1.0, &un.l, -1.0, &reg.l_tilde)) <= 1e-9 * sl);
            assert!(norm(&axpy(&un.r, -1.0, &reg.r_tilde)) <= 1e-9 * b);
            assert!(norm(&axpy(&reg.r_tilde, 1.0, &lam)) <= 1e-12 * b);
            // slip row satisfied by the solution
            let row = axpy(&matvec(&reg.l_tilde, &u), -1.0, &lam);
            assert!(norm(&axpy(&row, -1.0, &reg.r_tilde)) <= 1e-10 * (b + sl * norm(&u)));
            // approach the solution (generic direction, so |λ| > b and F̃ ≠ F happen):
            // the differences L̃ − L, r̃ − r shrink linearly with the distance
            // p: outward (|λ| > b, so F̃ ≠ F) plus a random part
            let p = axpy(&scale(1.0 / b, &lam), 0.5, &rand_vec::<M>(&mut rng, 1.0));
            let q = rand_vec::<M>(&mut rng, 1.0);
            let base = 0.1 * (c / gamma).min(1.0); // stay in A_τ: |v| − b = b c/γ
            let mut diffs = Vec::new();
            for k in 0..4 {
                let eps = base * 10f64.powi(-2 * k);
                let lp = axpy(&lam, eps * b, &p);
                let up = axpy(&u, eps * norm(&u), &q);
                let rg = regularise(&up, &lp, b, c).expect("still slip");
                let ug = unregularised(&up, &lp, b, c).expect("I - M regular near solution");
                let dl = max_abs(&mat_lin(1.0, &ug.l, -1.0, &rg.l_tilde)) / sl;
                let dr = norm(&axpy(&ug.r, -1.0, &rg.r_tilde)) / b;
                diffs.push(dl + dr);
            }
            for k in 1..4 {
                assert!(diffs[k] <= 0.05 * diffs[k - 1] + 1e-11, "{diffs:?}");
            }
            assert!(diffs[3] <= 1e-6, "{diffs:?}");
        }
    }

    #[test]
    fn at_solution_2d() {
        at_solution::<1>(28);
    }

    #[test]
    fn at_solution_3d() {
        at_solution::<2>(29);
    }

    /// Zero-threshold and zero-norm rules (§3.4.3, see the module doc).
    #[test]
    fn degenerate_cases() {
        let mut rng = StdRng::seed_from_u64(30);
        for _ in 0..500 {
            let u = rand_vec::<2>(&mut rng, 1.0);
            let lam = rand_vec::<2>(&mut rng, 1.0);
            let c = rng.gen_range(0.1..10.0);
            // b = 0: frictionless slip row, λ_τ' = 0, for any input, including v = 0, λ = 0
            for (uu, ll) in [
                (u, lam),
                ([0.0; 2], [0.0; 2]),
                (u, [0.0; 2]),
                (scale(-1.0 / c, &lam), lam),
            ] {
                let want = TangentialRow::Slip {
                    l: [[0.0; 2]; 2],
                    r: [0.0; 2],
                };
                assert_eq!(tangential_row(&uu, &ll, 0.0, c), want);
                assert_eq!(tangential_row_dyn(3, uu, ll, 0.0, c), want);
                assert_eq!(tangential_row_dyn(2, uu, ll, 0.0, c), want);
            }
            // b > 0, v = 0: stick
            let b = rng.gen_range(0.1..2.0);
            assert_eq!(
                tangential_row(&scale(-1.0 / c, &lam), &lam, b, c),
                TangentialRow::Stick
            );
            assert!(regularise(&scale(-1.0 / c, &lam), &lam, b, c).is_none());
            // b > 0, λ = 0, c|u| > b: the exact Newton row L̃ = c e/(1−e) I, r̃ = 0
            let uu = scale(2.0 * b / (c * norm(&u).max(1e-3)), &u);
            let reg = regularise(&uu, &[0.0; 2], b, c).unwrap();
            assert_eq!((reg.alpha, reg.delta, reg.beta), (0.0, 0.0, 1.0));
            let k = c * reg.e / (1.0 - reg.e);
            assert!(max_abs(&mat_lin(1.0, &reg.l_tilde, -k, &identity::<2>())) <= 1e-12 * k);
            assert_eq!(reg.r_tilde, [0.0; 2]);
            let un = unregularised(&uu, &[0.0; 2], b, c).unwrap();
            assert!(max_abs(&mat_lin(1.0, &reg.l_tilde, -1.0, &un.l)) <= 1e-12 * k);
            // the new λ' = L̃ u is not 0
            assert!(norm(&matvec(&reg.l_tilde, &uu)) > b);
        }
        // no slip row for |v| ≤ b; |v| = b is stick (3.33b)
        assert!(regularise(&[0.5], &[0.5], 1.0, 1.0).is_none());
        assert_eq!(
            tangential_row(&[0.5], &[0.5], 1.0, 1.0),
            TangentialRow::Stick
        );
        assert!(unregularised(&[0.0], &[0.0], 1.0, 1.0).is_none());
        assert!(!TangentialRow::<1>::Stick.is_slip());
        // 2D, b = 1, c = 1, λ = −2, u = 3.5: v = 1.5, e = 2/3, F = −2, M = 2, so I − M = −1
        // is regular but negative and the unregularised L = c(1/(1 − M) − 1) = −2 < 0,
        // which the regularisation prevents.
        let un = unregularised(&[3.5], &[-2.0], 1.0, 1.0).unwrap();
        assert!((un.m[0][0] - 2.0).abs() < 1e-14 && (un.l[0][0] + 2.0).abs() < 1e-13);
        let reg = regularise(&[3.5], &[-2.0], 1.0, 1.0).unwrap();
        assert!(reg.l_tilde[0][0] > 0.0);
        // exactly singular: 1 − e(1 − F) = 0 with λ = −1, c = 1, b = 1, u = 3: v = 2,
        // e = 1/2, F = −1, M = 1.
        assert!(unregularised(&[3.0], &[-1.0], 1.0, 1.0).is_none());
        assert!(regularise(&[3.0], &[-1.0], 1.0, 1.0).is_some());
    }

    /// The rows do not depend on the choice of tangent basis: for an orthogonal Q
    /// (rotation or reflection) L̃(Qu, Qλ) = Q L̃ Qᵀ and r̃(Qu, Qλ) = Q r̃.
    #[test]
    fn equivariant_under_tangent_basis_change() {
        let mut rng = StdRng::seed_from_u64(31);
        for (u, lam, b, c) in slip_samples::<2>(32, 2000) {
            let th: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
            let s = if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
            let q = [[th.cos(), -th.sin()], [s * th.sin(), s * th.cos()]];
            let qt = [[q[0][0], q[1][0]], [q[0][1], q[1][1]]];
            let r1 = regularise(&u, &lam, b, c).unwrap();
            let Some(r2) = regularise(&matvec(&q, &u), &matvec(&q, &lam), b, c) else {
                continue; // |v| = b up to rounding after the rotation
            };
            let l1 = matmul(&matmul(&q, &r1.l_tilde), &qt);
            let sc = 1.0 + max_abs(&l1);
            // rounding in the rotated v changes |v| − b by ~ε|v|: relative effect ε/(1 − e)
            let tol = 1e-12 + 1e-14 / (1.0 - r1.e);
            assert!(max_abs(&mat_lin(1.0, &l1, -1.0, &r2.l_tilde)) <= tol * sc);
            let rr = matvec(&q, &r1.r_tilde);
            assert!(norm(&axpy(&rr, -1.0, &r2.r_tilde)) <= tol * (b + norm(&rr)));
        }
    }

    /// One node in a linear spring: λ_τ = f − K u_τ (the nodal form of (3.28), K SPD).
    /// Algorithm 2's tangential part — state by (3.33), rows (3.34a)/(3.39a) — converges
    /// to the solution of (3.18): u = 0 if |f| ≤ b, else |λ| = b, λ = α² u.
    fn spring_node<const M: usize>(seed: u64, start_frictionless: bool) {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut steps_max = 0;
        for _ in 0..400 {
            let mut k = [[0.0; M]; M];
            let g: [[f64; M]; M] = [[0.0; M]; M].map(|_| rand_vec(&mut rng, 1.0));
            for i in 0..M {
                for j in 0..M {
                    k[i][j] = (0..M).map(|l| g[l][i] * g[l][j]).sum::<f64>();
                }
                k[i][i] += 0.2;
            }
            let f = rand_vec::<M>(&mut rng, 3.0);
            let b = rng.gen_range(0.1..2.0);
            let c = [0.1, 1.0, 10.0][rng.gen_range(0..3)];
            let kinv = inverse(&k, 1e-14).unwrap();
            let (mut u, mut lam) = if start_frictionless {
                (matvec(&kinv, &f), [0.0; M])
            } else {
                ([0.0; M], [0.0; M])
            };
            let mut done = false;
            for step in 1..=60 {
                let (u2, lam2) = match tangential_row(&u, &lam, b, c) {
                    TangentialRow::Stick => ([0.0; M], f),
                    TangentialRow::Slip { l, r } => {
                        // −(f − K u) + L̃ u = r̃  ⇒  (K + L̃) u = r̃ + f
                        let a = mat_lin(1.0, &k, 1.0, &l);
                        let u2 = matvec(&inverse(&a, 1e-14).unwrap(), &axpy(&r, 1.0, &f));
                        (u2, axpy(&f, -1.0, &matvec(&k, &u2)))
                    }
                };
                let change = norm(&axpy(&u2, -1.0, &u)) + norm(&axpy(&lam2, -1.0, &lam));
                u = u2;
                lam = lam2;
                if change <= 1e-13 * (1.0 + norm(&f)) {
                    steps_max = steps_max.max(step);
                    done = true;
                    break;
                }
            }
            assert!(done, "no convergence: f={f:?} b={b} c={c}");
            let slip = norm(&f) > b;
            let res = tangential_residual(&u, &lam, b, slip);
            assert!(res.excess <= 1e-10 && res.stick_motion <= 1e-12);
            assert!(res.slip_alignment <= 1e-9, "{res:?}");
            assert_eq!(norm(&u) > 0.0, slip);
            // (3.18) holds (the certificate above) and the problem is strictly convex, so
            // this is the solution. In 2D compare with the closed form as well.
            if !slip {
                assert_eq!(lam, f);
            } else if M == 1 {
                let want = (f[0] - b * f[0].signum()) / k[0][0];
                assert!((u[0] - want).abs() <= 1e-12 * (1.0 + want.abs()));
            }
        }
        assert!(steps_max <= 25, "max steps {steps_max}");
    }

    #[test]
    fn spring_node_converges_2d() {
        spring_node::<1>(33, false);
        spring_node::<1>(34, true);
    }

    #[test]
    fn spring_node_converges_3d() {
        spring_node::<2>(35, false);
        spring_node::<2>(36, true);
    }

    #[test]
    fn dyn_wrapper_matches_generic() {
        let mut rng = StdRng::seed_from_u64(37);
        for _ in 0..200 {
            let u = rand_vec::<2>(&mut rng, 1.0);
            let lam = rand_vec::<2>(&mut rng, 2.0);
            let (b, c) = (rng.gen_range(0.1..1.0), 1.0);
            match (
                tangential_row(&[u[0]], &[lam[0]], b, c),
                tangential_row_dyn(2, u, lam, b, c),
            ) {
                (TangentialRow::Stick, TangentialRow::Stick) => {}
                (TangentialRow::Slip { l, r }, TangentialRow::Slip { l: l2, r: r2 }) => {
                    assert_eq!(l2, [[l[0][0], 0.0], [0.0, 0.0]]);
                    assert_eq!(r2, [r[0], 0.0]);
                }
                other => panic!("mismatch {other:?}"),
            }
            assert_eq!(
                tangential_row_dyn(3, u, lam, b, c),
                tangential_row(&u, &lam, b, c)
            );
        }
    }
}
