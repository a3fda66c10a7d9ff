//! Complementarity functions and active-set tests of the semismooth Newton method
//! (thesis §3.3.2, §3.4.1): C_n (3.21) with the normal test (3.23), C_τ (3.31) with the
//! slip test (3.33), and the four Tresca node states S1..S4 (after (3.41)).
//!
//! Arguments per node: normal displacement `u_n`, multiplier `lam_n` (≤ 0 when pressing),
//! gap `g` = g_h^k, tangential coefficient vectors `u_t`, `lam_t` ∈ R^M with M = d − 1,
//! threshold `b` = b_k ≥ 0, parameter `c` > 0.

use super::linalg::{axpy, norm};

/// (3.21) C_n(u_n, λ_n) = λ_n + max{0, −λ_n − c (u_n + g)}.
/// Zero iff (3.14) holds (Satz 3.6).
pub fn c_n(u_n: f64, lam_n: f64, g: f64, c: f64) -> f64 {
    lam_n + (-lam_n - c * (u_n + g)).max(0.0)
}

/// (3.23) normal active test: k ∈ A_n ⇔ −λ_n − c (u_n + g) > 0.
pub fn normal_active(u_n: f64, lam_n: f64, g: f64, c: f64) -> bool {
    -lam_n - c * (u_n + g) > 0.0
}

/// A node's (3.23) test −λ_n − c (u_n + g) within this fraction of its round-off scale (see
/// [`ties`]) of zero is a tie: the node carries (almost) no force at (almost) zero gap, and
/// either state is a solution to round-off. Without it the sign of round-off decided: a
/// floating plate tipped on an edge of 9 nodes dropped one whose λ_n was −3.8e-15 (test
/// −8.3e-13 against a scale of 4.2e3), leaving its rotation about the edge free; the next step's
/// |C_n| was 2.3e4 and the run failed in 2 of 8 runs on 3 ranks. About 1 000 times the machine
/// epsilon; a tie decided wrongly violates (3.14) by at most this fraction of the scale, which
/// the final certificate on every node measures.
pub const SET_ROUND_OFF: f64 = 1e-13;

/// The largest magnitude of `v` (0 if empty).
pub fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// The tie width of the (3.23) test: [`SET_ROUND_OFF`] × (‖λ_n‖∞ + c max(‖u_n‖∞, ‖g‖∞)), the
/// magnitudes the test is computed from, over the nodes decided together.
pub fn ties(lambda_inf: f64, length_inf: f64, c: f64) -> f64 {
    SET_ROUND_OFF * (lambda_inf + c * length_inf)
}

/// (3.23) with ties: a node whose test is within `tie` of zero keeps its state `was`.
pub fn normal_active_or_tie(u_n: f64, lam_n: f64, g: f64, c: f64, tie: f64, was: bool) -> bool {
    let test = -lam_n - c * (u_n + g);
    if test.abs() <= tie {
        was
    } else {
        test > 0.0
    }
}

/// (3.31) C_τ(u_τ, λ_τ) = max{b, |v|} λ_τ − b v with v = λ_τ + c u_τ.
/// For b > 0 zero iff (3.18) holds (Satz 3.7). (For b = 0 it is |v| λ_τ, which also
/// vanishes for λ_τ ≠ 0 if v = 0: the thesis' reason (§3.4.3) to treat b = 0 apart.)
pub fn c_tau<const M: usize>(u_t: &[f64; M], lam_t: &[f64; M], b: f64, c: f64) -> [f64; M] {
    let v = axpy(lam_t, c, u_t);
    let m = b.max(norm(&v));
    let mut r = [0.0; M];
    for i in 0..M {
        r[i] = m * lam_t[i] - b * v[i];
    }
    r
}

/// (3.33) slip test: k ∈ A_τ ⇔ |λ_τ + c u_τ| − b > 0; and (§3.4.3) every node with
/// b ≤ 0 is in A_τ (frictionless: its slip row gives λ_τ = 0).
pub fn tangential_slip<const M: usize>(u_t: &[f64; M], lam_t: &[f64; M], b: f64, c: f64) -> bool {
    if b.is_nan() || b <= 0.0 {
        return true;
    }
    norm(&axpy(lam_t, c, u_t)) - b > 0.0
}

/// Tresca node state of one Newton step (thesis, after (3.41)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NodeState {
    /// I_n ∩ I_τ: no contact, stick.
    S1,
    /// I_n ∩ A_τ: no contact, slip.
    S2,
    /// A_n ∩ I_τ: contact, stick.
    S3,
    /// A_n ∩ A_τ: contact, slip.
    S4,
}

impl NodeState {
    /// State from the two set memberships.
    pub fn new(normal_active: bool, slip: bool) -> NodeState {
        match (normal_active, slip) {
            (false, false) => NodeState::S1,
            (false, true) => NodeState::S2,
            (true, false) => NodeState::S3,
            (true, true) => NodeState::S4,
        }
    }
    /// k ∈ A_n (normal row nᵀu^k = −g^k).
    pub fn normal_active(self) -> bool {
        matches!(self, NodeState::S3 | NodeState::S4)
    }
    /// k ∈ A_τ (slip row (3.39a)); otherwise stick row u_τ^k = 0 (3.34a).
    pub fn slip(self) -> bool {
        matches!(self, NodeState::S2 | NodeState::S4)
    }
    /// 1..=4, as in the thesis' S_i.
    pub fn number(self) -> u8 {
        match self {
            NodeState::S1 => 1,
            NodeState::S2 => 2,
            NodeState::S3 => 3,
            NodeState::S4 => 4,
        }
    }
}

/// (3.23) + (3.33): state of a node for the next Newton step from the current iterate.
#[allow(clippy::too_many_arguments)]
pub fn classify<const M: usize>(
    u_n: f64,
    lam_n: f64,
    g: f64,
    u_t: &[f64; M],
    lam_t: &[f64; M],
    b: f64,
    c: f64,
) -> NodeState {
    NodeState::new(
        normal_active(u_n, lam_n, g, c),
        tangential_slip(u_t, lam_t, b, c),
    )
}

#[cfg(test)]
mod tests {
    use super::super::residual::{normal_conditions_hold, project_ball, tresca_conditions_hold};
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    const CS: [f64; 4] = [0.01, 1.0, 3.0, 1e3];

    /// Satz 3.6 on a grid of dyadic values where the arithmetic is exact: C_n = 0 exactly
    /// iff (3.14) holds exactly. Covers the boundary cases λ_n = 0, u_n + g = 0.
    #[test]
    fn c_n_zero_iff_3_14_on_exact_grid() {
        let mut rng = StdRng::seed_from_u64(5);
        let mut counts = [0usize; 2];
        for &c in &[0.25, 1.0, 4.0, 64.0] {
            for _ in 0..2000 {
                let lam = rng.gen_range(-4..=4) as f64 * 0.5;
                let s = rng.gen_range(-4..=4) as f64 * 0.25; // u_n + g
                let g = rng.gen_range(0..=8) as f64 * 0.125;
                let u = s - g;
                let ok = normal_conditions_hold(u, lam, g, 0.0);
                assert_eq!(c_n(u, lam, g, c) == 0.0, ok, "u={u} lam={lam} g={g} c={c}");
                counts[ok as usize] += 1;
            }
        }
        assert!(
            counts[0] > 100 && counts[1] > 100,
            "both cases sampled: {counts:?}"
        );
    }

    /// Satz 3.6 on continuous random samples: constructed solutions of (3.14) give
    /// C_n = 0; every root of C_n (parametrised as λ_n = min(z, 0),
    /// u_n + g = max(z, 0)/c) satisfies (3.14); violations give C_n ≠ 0.
    #[test]
    fn c_n_random_samples() {
        let mut rng = StdRng::seed_from_u64(6);
        for &c in &CS {
            for _ in 0..1000 {
                let g = rng.gen_range(0.0..1.0);
                // contact: u_n = −g, λ_n ≤ 0
                let lam = -rng.gen_range(0.0..10.0);
                assert_eq!(c_n(-g, lam, g, c), 0.0);
                assert!(normal_active(-g, lam, g, c) == (lam < 0.0));
                // free: u_n > −g, λ_n = 0
                let u = -g + rng.gen_range(1e-9..2.0);
                assert_eq!(c_n(u, 0.0, g, c), 0.0);
                assert!(!normal_active(u, 0.0, g, c));
                // roots of C_n satisfy (3.14)
                let z: f64 = rng.gen_range(-5.0..5.0);
                let (lam, s) = (z.min(0.0), z.max(0.0) / c);
                assert!(c_n(s - g, lam, g, c).abs() <= 1e-12 * (1.0 + z.abs()));
                assert!(normal_conditions_hold(
                    s - g,
                    lam,
                    g,
                    1e-12 * (1.0 + z.abs())
                ));
                // violations
                let eps = rng.gen_range(1e-3..1.0);
                assert!(c_n(-g, eps, g, c) != 0.0); // tension
                assert!(c_n(-g - eps, 0.0, g, c) != 0.0); // penetration
                assert!(c_n(-g - eps, -1.0, g, c) != 0.0); // penetration while pressing
                assert!(c_n(-g + eps, -eps, g, c) != 0.0); // pressing while free
            }
        }
    }

    /// Satz 3.7 in 2D (M = 1) on an exact dyadic grid: C_τ = 0 exactly iff (3.18).
    #[test]
    fn c_tau_zero_iff_3_18_on_exact_grid_2d() {
        let mut rng = StdRng::seed_from_u64(7);
        let mut counts = [0usize; 2];
        for &c in &[0.5, 1.0, 2.0, 8.0] {
            for _ in 0..3000 {
                let b = rng.gen_range(1..=4) as f64 * 0.5;
                let lam = [rng.gen_range(-6..=6) as f64 * 0.5];
                let u = [rng.gen_range(-2..=2) as f64 * 0.5];
                let ok = tresca_conditions_hold(&u, &lam, b, 0.0, 0.0);
                let z = c_tau(&u, &lam, b, c)[0] == 0.0;
                assert_eq!(z, ok, "u={u:?} lam={lam:?} b={b} c={c}");
                counts[ok as usize] += 1;
            }
        }
        assert!(
            counts[0] > 100 && counts[1] > 100,
            "both cases sampled: {counts:?}"
        );
    }

    fn rand_vec<const M: usize>(rng: &mut StdRng, r: f64) -> [f64; M] {
        [0.0; M].map(|_| rng.gen_range(-r..r))
    }

    fn satz_3_7_random<const M: usize>(seed: u64) {
        let mut rng = StdRng::seed_from_u64(seed);
        for &c in &CS {
            for _ in 0..1000 {
                let b = rng.gen_range(0.1..5.0);
                let tol = 1e-12 * b * (b + 10.0 + 10.0 * c);
                // stick: |λ| < b, u = 0
                let mut lam = rand_vec::<M>(&mut rng, b);
                if norm(&lam) >= b {
                    lam = lam.map(|x| 0.5 * x);
                }
                let zero = [0.0; M];
                assert!(norm(&c_tau(&zero, &lam, b, c)) <= tol);
                // slip: |λ| = b, λ = γ u, γ > 0
                let dir = rand_vec::<M>(&mut rng, 1.0);
                if norm(&dir) < 1e-3 {
                    continue;
                }
                let lam = dir.map(|x| b * x / norm(&dir));
                let gamma = rng.gen_range(0.01..100.0);
                let u = lam.map(|x| x / gamma);
                assert!(norm(&c_tau(&u, &lam, b, c)) <= tol * (1.0 + c / gamma));
                // roots of C_τ: λ = P_b(v), u = (v − λ)/c for any v; they satisfy (3.18)
                let v = rand_vec::<M>(&mut rng, 3.0 * b);
                let lam = project_ball(&v, b);
                let u = axpy(&v, -1.0, &lam).map(|x| x / c);
                assert!(norm(&c_tau(&u, &lam, b, c)) <= tol);
                assert!(tresca_conditions_hold(&u, &lam, b, 1e-12 * b, 0.0));
                // violations: |λ| > b; stick that moves; slip against u; slip too short
                let big = dir.map(|x| 1.5 * b * x / norm(&dir));
                assert!(norm(&c_tau(&zero, &big, b, c)) > 1e-6 * b);
                let small = dir.map(|x| 0.5 * b * x / norm(&dir));
                let du = small.map(|x| 0.1 * x / b);
                assert!(norm(&c_tau(&du, &small, b, c)) > 1e-6 * b * b);
                let against = dir.map(|x| -b * x / norm(&dir));
                let along = dir.map(|x| x / norm(&dir));
                assert!(norm(&c_tau(&along, &against, b, c)) > 1e-6 * b * b);
                assert!(!tresca_conditions_hold(&along, &against, b, 1e-6 * b, 1e-6));
                if M == 2 {
                    // |λ| = b but at 90° to u
                    let mut perp = [0.0; M];
                    perp[0] = -b * dir[1] / norm(&dir);
                    perp[1] = b * dir[0] / norm(&dir);
                    assert!(norm(&c_tau(&along, &perp, b, c)) > 1e-6 * b * b);
                    assert!(!tresca_conditions_hold(&along, &perp, b, 1e-6 * b, 1e-6));
                }
            }
        }
    }

    /// Satz 3.7, 2D: constructed solutions of (3.18) give C_τ = 0, roots of C_τ satisfy
    /// (3.18), violations give C_τ ≠ 0.
    #[test]
    fn c_tau_random_samples_2d() {
        satz_3_7_random::<1>(8);
    }

    /// Satz 3.7, 3D (M = 2), including |λ_τ| = b at an angle to u_τ.
    #[test]
    fn c_tau_random_samples_3d() {
        satz_3_7_random::<2>(9);
    }

    /// Zero-padded 2D vectors in the M = 2 functions give the M = 1 results.
    #[test]
    fn padded_2d_equals_scalar() {
        let mut rng = StdRng::seed_from_u64(10);
        for _ in 0..500 {
            let (u, l) = (rng.gen_range(-1.0..1.0), rng.gen_range(-2.0..2.0));
            let (b, c) = (rng.gen_range(0.0..1.5), rng.gen_range(0.1..3.0));
            let (up, lp) = ([u, 0.0], [l, 0.0]);
            assert_eq!(c_tau(&up, &lp, b, c), [c_tau(&[u], &[l], b, c)[0], 0.0]);
            assert_eq!(
                tangential_slip(&up, &lp, b, c),
                tangential_slip(&[u], &[l], b, c)
            );
            assert_eq!(
                classify(0.0, -1.0, 0.0, &up, &lp, b, c),
                classify(0.0, -1.0, 0.0, &[u], &[l], b, c)
            );
        }
    }

    #[test]
    fn states_and_classification() {
        for na in [false, true] {
            for sl in [false, true] {
                let s = NodeState::new(na, sl);
                assert_eq!((s.normal_active(), s.slip()), (na, sl));
            }
        }
        assert_eq!(NodeState::S3.number(), 3);
        // pressing, sticking
        let s = classify(-0.1, -1.0, 0.1, &[0.0, 0.0], &[0.2, 0.0], 1.0, 1.0);
        assert_eq!(s, NodeState::S3);
        // pressing, slipping
        let s = classify(-0.1, -1.0, 0.1, &[2.0, 0.0], &[0.2, 0.0], 1.0, 1.0);
        assert_eq!(s, NodeState::S4);
        // free (u_n + g > 0, λ_n = 0), stick: the thesis' fourth state S1
        let s = classify(0.5, 0.0, 0.1, &[0.0], &[0.0], 1.0, 1.0);
        assert_eq!(s, NodeState::S1);
        // b = 0: always slip (§3.4.3), even with v = 0
        let s = classify(0.5, 0.0, 0.1, &[0.0], &[0.0], 0.0, 1.0);
        assert_eq!(s, NodeState::S2);
        // the boundary |v| = b is stick (3.33b)
        assert!(!tangential_slip(&[0.5], &[0.5], 1.0, 1.0));
        // larger c makes the stick test stricter
        assert!(!tangential_slip(&[0.1], &[0.5], 1.0, 1.0));
        assert!(tangential_slip(&[0.1], &[0.5], 1.0, 10.0));
    }
}
