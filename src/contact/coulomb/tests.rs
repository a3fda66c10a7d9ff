//! Tests of the node-wise Coulomb rows: thresholds, residuals, derivatives and rows.

use super::point::*;
use super::row::*;
use crate::contact::complementarity::{normal_active, NodeState};
use crate::contact::frame::Frame;
use crate::contact::linalg::{axpy, matvec, norm, scale};
use crate::contact::linalg::{dot, identity, inverse, mat_lin, max_abs};
use crate::contact::residual::project_ball;
use crate::contact::tresca::tangential_row;
use crate::contact::tresca::{regularise, TangentialRow};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn rand_vec<const M: usize>(rng: &mut StdRng, r: f64) -> [f64; M] {
    [0.0; M].map(|_| rng.gen_range(-r..r))
}

fn pt<const M: usize>(u_n: f64, lam_n: f64, u_t: [f64; M], lam_t: [f64; M]) -> NodePoint<M> {
    NodePoint {
        u_n,
        lam_n,
        u_t,
        lam_t,
    }
}

/// Random iterates of every kind: free, pressing with stick / slip / at the limit, λ_τ
/// opposite to v, λ_τ = 0, penetrating, in tension, with |v| just above b.
fn samples<const M: usize>(seed: u64, n: usize) -> Vec<(NodePoint<M>, f64, f64, f64)> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let g = if rng.gen_bool(0.3) {
                0.0
            } else {
                rng.gen_range(0.0..0.5)
            };
            let mu: f64 = [0.05, 0.3, 1.0, 3.0][rng.gen_range(0..4)];
            let c: f64 = [0.01, 1.0, 10.0, 1e3][rng.gen_range(0..4)];
            let lam_n: f64 = -rng.gen_range(-0.5..3.0);
            let u_n = -g + rng.gen_range(-0.3..0.3) / c.sqrt();
            let b = mu * (-lam_n).max(0.0);
            let sc = b.max(0.1);
            let (u_t, lam_t) = match rng.gen_range(0..5) {
                0 => (
                    rand_vec(&mut rng, 3.0 * sc / c),
                    rand_vec(&mut rng, 3.0 * sc),
                ),
                1 => {
                    let lam = rand_vec::<M>(&mut rng, 2.0 * sc);
                    (scale(-rng.gen_range(1.05..20.0) / c, &lam), lam)
                }
                2 => (rand_vec(&mut rng, 3.0 * sc / c), [0.0; M]),
                3 => (
                    rand_vec(&mut rng, 0.2 * sc / c),
                    rand_vec(&mut rng, 0.5 * sc),
                ),
                _ => {
                    let lam = rand_vec::<M>(&mut rng, 2.0 * sc);
                    let dir = rand_vec::<M>(&mut rng, 1.0);
                    let t = sc * (1.0 + 10f64.powf(rng.gen_range(-8.0..-1.0)));
                    let v = scale(t / norm(&dir).max(1e-3), &dir);
                    (axpy(&v, -1.0, &lam).map(|x| x / c), lam)
                }
            };
            (pt(u_n, lam_n, u_t, lam_t), g, mu, c)
        })
        .collect()
}

/// μ = 0: every node gets the frictionless rows λ_τ' = 0 (S2 or S4 with l = q = r = 0), and
/// the block data vanish, so the node's rows are those of (3.29).
fn mu_zero_is_frictionless<const M: usize>(seed: u64) {
    let mut seen = [0usize; 4];
    for (p, g, _, c) in samples::<M>(seed, 2000) {
        let n = coulomb_row(&p, g, 0.0, c);
        assert_eq!(n.b, 0.0);
        assert!(matches!(n.state, NodeState::S2 | NodeState::S4));
        assert_eq!(n.state.normal_active(), normal_active(p.u_n, p.lam_n, g, c));
        seen[n.state.number() as usize - 1] += 1;
        let zero = CoulombRow::Slip {
            l: [[0.0; M]; M],
            q: [0.0; M],
            r: [0.0; M],
        };
        assert_eq!(n.row, zero);
    }
    assert!(seen[1] > 100 && seen[3] > 100, "{seen:?}");
    let f = Frame::new([0.3, 1.0, -0.2], M + 1).unwrap();
    let blk = coulomb_block(
        &f,
        &CoulombRow::Slip {
            l: [[0.0; 2]; 2],
            q: [0.0; 2],
            r: [0.0; 2],
        },
    );
    assert_eq!(blk.row_mix, [[0.0; 3]; 3]);
    assert_eq!(blk.spring, [[0.0; 3]; 3]);
    assert_eq!(blk.spring_rhs, [0.0; 3]);
}

#[test]
fn mu_zero_is_frictionless_2d() {
    mu_zero_is_frictionless::<1>(40);
}

#[test]
fn mu_zero_is_frictionless_3d() {
    mu_zero_is_frictionless::<2>(41);
}

/// With s' = λ_n' + c(u_n' + g) frozen at its previous value, the Coulomb rows are the Tresca
/// rows (3.39) with b = μ max(0, −s) (= μ(−λ_n) on a node with u_n = −g): the same state,
/// the same L̃, and r + q s = r̃.
fn frozen_normal_is_tresca<const M: usize>(seed: u64) {
    let mut slips = 0;
    for (p, g, mu, c) in samples::<M>(seed, 3000) {
        let s = p.lam_n + c * (p.u_n + g);
        let b = mu * (-s).max(0.0);
        let n = coulomb_row(&p, g, mu, c);
        assert_eq!(n.b, b);
        let want = tangential_row(&p.u_t, &p.lam_t, b, c);
        match (n.row.frozen(s), want) {
            (TangentialRow::Stick, TangentialRow::Stick) => {}
            (TangentialRow::Slip { l, r }, TangentialRow::Slip { l: l2, r: r2 }) => {
                assert_eq!(l, l2);
                let sc = b + norm(&r2) + norm(&p.lam_t);
                assert!(norm(&axpy(&r, -1.0, &r2)) <= 1e-12 * sc, "{r:?} {r2:?}");
                slips += 1;
            }
            other => panic!("state differs: {other:?}"),
        }
        // and on an active node (u_n = −g) with the Tresca threshold b = μ(−λ_n)
        let q = pt(-g, p.lam_n, p.u_t, p.lam_t);
        let b = mu * (-p.lam_n).max(0.0);
        let want = tangential_row(&p.u_t, &p.lam_t, b, c);
        assert_eq!(
            coulomb_row(&q, g, mu, c).row.frozen(p.lam_n).is_slip(),
            want.is_slip()
        );
    }
    assert!(slips > 1000);
}

#[test]
fn frozen_normal_is_tresca_2d() {
    frozen_normal_is_tresca::<1>(42);
}

#[test]
fn frozen_normal_is_tresca_3d() {
    frozen_normal_is_tresca::<2>(43);
}

/// 2D on an exact dyadic grid (every operation exact): the residual (F3) is exactly zero iff
/// Coulomb's law holds exactly, with both cases sampled often.
#[test]
fn residual_zero_iff_coulomb_exact_grid_2d() {
    let mut rng = StdRng::seed_from_u64(44);
    let mut counts = [0usize; 2];
    for _ in 0..40000 {
        let c = [0.5, 1.0, 2.0, 4.0][rng.gen_range(0..4)];
        let mu = [0.0, 0.25, 0.5, 1.0][rng.gen_range(0..4)];
        let g = rng.gen_range(0..=2) as f64 * 0.25;
        let lam_n = -(rng.gen_range(-1..=4) as f64) * 0.5;
        let u_n = -g + rng.gen_range(-1..=2) as f64 * 0.25;
        let lam_t = [rng.gen_range(-4..=4) as f64 * 0.25];
        let u_t = [rng.gen_range(-2..=2) as f64 * 0.25];
        let p = pt(u_n, lam_n, u_t, lam_t);
        let ok = coulomb_conditions_hold(&p, g, mu, 0.0, 0.0);
        let r = coulomb_residual(&p, g, mu, c);
        assert_eq!(r.norm() == 0.0, ok, "{p:?} g={g} mu={mu} c={c} {r:?}");
        counts[ok as usize] += 1;
    }
    assert!(counts[0] > 1000 && counts[1] > 1000, "{counts:?}");
}

/// 2D and 3D, continuous random samples: constructed points of each Coulomb state (free,
/// stick, at the limit, slip) give a zero residual (to rounding); the roots of the residual,
/// parametrised by λ_n = min(z, 0), u_n + g = max(z, 0)/c, λ_τ = P_b(y), u_τ = (y − λ_τ)/c,
/// satisfy the law; and each kind of violation gives a residual bounded away from 0.
fn residual_random<const M: usize>(seed: u64) {
    let mut rng = StdRng::seed_from_u64(seed);
    for _ in 0..3000 {
        let c = [0.01, 1.0, 10.0, 1e3][rng.gen_range(0..4)];
        let mu = rng.gen_range(0.0..2.0);
        let g = rng.gen_range(0.0..0.5);
        let pn = rng.gen_range(0.1..5.0); // −λ_n when pressing
        let b = mu * pn;
        let tol = 1e-12 * (1.0 + pn + b + c);
        let dir = rand_vec::<M>(&mut rng, 1.0);
        if norm(&dir) < 1e-2 {
            continue;
        }
        let e = scale(1.0 / norm(&dir), &dir);
        let free = pt(
            -g + rng.gen_range(1e-6..1.0),
            0.0,
            rand_vec(&mut rng, 1.0),
            [0.0; M],
        );
        let stick = pt(-g, -pn, [0.0; M], scale(b * rng.gen_range(0.0..1.0), &e));
        let limit = pt(-g, -pn, [0.0; M], scale(b, &e));
        let slip = pt(-g, -pn, scale(rng.gen_range(1e-3..2.0), &e), scale(b, &e));
        for p in [free, stick, limit, slip] {
            assert!(coulomb_conditions_hold(&p, g, mu, tol, 1e-14));
            assert!(coulomb_residual(&p, g, mu, c).norm() <= tol, "{p:?}");
        }
        // roots of the residual
        let z: f64 = rng.gen_range(-5.0..5.0);
        let (lam_n, un) = (z.min(0.0), z.max(0.0) / c - g);
        let y = rand_vec::<M>(&mut rng, 3.0 * (b + 0.1));
        let lam_t = project_ball(&y, mu * (-lam_n));
        let u_t = axpy(&y, -1.0, &lam_t).map(|x| x / c);
        let p = pt(un, lam_n, u_t, lam_t);
        let sc = 1e-12 * (1.0 + z.abs() + norm(&y));
        assert!(coulomb_residual(&p, g, mu, c).norm() <= sc);
        assert!(coulomb_conditions_hold(&p, g, mu, sc, sc));
        // violations (each with a defect ≥ 1e-3 relative): the residual is not zero
        let eps = rng.gen_range(1e-3..1.0);
        let bad = [
            pt(-g, -pn, [0.0; M], scale(b + eps * (1.0 + b), &e)), // |λ_τ| > μ|λ_n|
            pt(-g, -pn, scale(eps, &e), scale(-b, &e)),            // slips against λ_τ
            pt(-g, -pn, scale(eps, &e), scale(0.5 * b, &e)),       // slips below the limit
            pt(-g + eps, 0.0, [0.0; M], scale(eps, &e)),           // friction off contact
            pt(-g - eps, -pn, [0.0; M], [0.0; M]),                 // penetration
            pt(-g, eps, [0.0; M], [0.0; M]),                       // tension
        ];
        for (i, p) in bad.iter().enumerate() {
            if i == 2 && b == 0.0 {
                continue; // b = 0: λ_τ = 0 is the limit
            }
            assert!(!coulomb_conditions_hold(p, g, mu, 1e-9, 1e-9), "{i} {p:?}");
            let r = coulomb_residual(p, g, mu, c).norm();
            assert!(r > 1e-6 * eps.min(1.0) * eps.min(c * eps), "{i} {p:?} {r}");
        }
        if M == 2 {
            // |λ_τ| = μ|λ_n| but at 90° to the slip
            let mut perp = [0.0; M];
            perp[0] = -b * e[1];
            perp[1] = b * e[0];
            let p = pt(-g, -pn, scale(eps, &e), perp);
            if b > 1e-3 {
                assert!(coulomb_residual(&p, g, mu, c).norm() > 1e-9);
                assert!(!coulomb_conditions_hold(&p, g, mu, 1e-9, 1e-9));
            }
        }
    }
}

#[test]
fn residual_random_2d() {
    residual_random::<1>(45);
}

#[test]
fn residual_random_3d() {
    residual_random::<2>(46);
}

/// C_τ along the line x + t Δ (all four node unknowns move).
fn c_at<const M: usize>(
    p: &NodePoint<M>,
    dp: &NodePoint<M>,
    t: f64,
    g: f64,
    mu: f64,
    c: f64,
) -> [f64; M] {
    let q = pt(
        p.u_n + t * dp.u_n,
        p.lam_n + t * dp.lam_n,
        axpy(&p.u_t, t, &dp.u_t),
        axpy(&p.lam_t, t, &dp.lam_t),
    );
    c_tau_coulomb(&q, g, mu, c)
}

/// J Δ with the generalised derivative (F4).
fn jac_apply<const M: usize>(d: &CoulombDerivative<M>, dp: &NodePoint<M>) -> [f64; M] {
    let mut r = axpy(
        &matvec(&d.d_ut, &dp.u_t),
        1.0,
        &matvec(&d.d_lam_t, &dp.lam_t),
    );
    r = axpy(&r, dp.u_n, &d.d_un);
    axpy(&r, dp.lam_n, &d.d_lam_n)
}

/// Distance of p from the kinks of C_τ (s = 0 and |v| = b), relative.
fn kink_distance<const M: usize>(p: &NodePoint<M>, g: f64, mu: f64, c: f64) -> f64 {
    let s = -p.lam_n - c * (p.u_n + g);
    let b = mu * s.max(0.0);
    let nv = norm(&axpy(&p.lam_t, c, &p.u_t));
    let sc = 1.0 + p.lam_n.abs() + c * (p.u_n + g).abs();
    (s.abs() / sc).min(if b > 0.0 {
        (nv - b).abs() / (nv + b)
    } else {
        1.0
    })
}

/// (F4) against central finite differences of C_τ in random directions of all unknowns,
/// at points of every branch (away from the kinks, where C_τ is smooth).
fn derivative_vs_fd<const M: usize>(seed: u64) {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut branches = [0usize; 3];
    for (p, g, mu, c) in samples::<M>(seed, 4000) {
        if kink_distance(&p, g, mu, c) < 1e-3 {
            continue;
        }
        let d = c_tau_coulomb_derivative(&p, g, mu, c);
        let sc_u = 1.0 / c.max(1.0);
        let dp = pt(
            rng.gen_range(-1.0..1.0) * sc_u,
            rng.gen_range(-1.0..1.0),
            rand_vec(&mut rng, sc_u),
            rand_vec(&mut rng, 1.0),
        );
        let h =
            1e-6 * kink_distance(&p, g, mu, c).min(1.0) * (1.0 + p.lam_n.abs() + norm(&p.lam_t));
        let fd = axpy(
            &c_at(&p, &dp, h, g, mu, c),
            -1.0,
            &c_at(&p, &dp, -h, g, mu, c),
        )
        .map(|x| x / (2.0 * h));
        let an = jac_apply(&d, &dp);
        let scale_j =
            1.0 + max_abs(&d.d_ut) + max_abs(&d.d_lam_t) + norm(&d.d_un) + norm(&d.d_lam_n);
        assert!(
            norm(&axpy(&fd, -1.0, &an)) <= 1e-5 * scale_j,
            "{p:?} g={g} mu={mu} c={c}: fd {fd:?} an {an:?}"
        );
        let b = coulomb_threshold(p.u_n, p.lam_n, g, mu, c);
        let nv = norm(&axpy(&p.lam_t, c, &p.u_t));
        branches[if b <= 0.0 {
            0
        } else if nv <= b {
            1
        } else {
            2
        }] += 1;
    }
    assert!(branches.iter().all(|&n| n > 200), "{branches:?}");
}

#[test]
fn derivative_vs_fd_2d() {
    derivative_vs_fd::<1>(47);
}

#[test]
fn derivative_vs_fd_3d() {
    derivative_vs_fd::<2>(48);
}

/// The unregularised slip row (F5) IS the generalised Newton step on C_τ (F4): for any new
/// (u_n', λ_n', u_τ') and λ_τ' from the row, C_τ(x) + J (x' − x) = 0 (the row is that
/// equation divided by |v|). Also the stick row is the Newton step on C_τ / b (= −c u_τ on
/// I_τ: no λ_n coupling), and the S2 row the one on C_τ / |v| (= λ_τ).
fn row_is_newton_step<const M: usize>(seed: u64) {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut tested = [0usize; 3];
    for (p, g, mu, c) in samples::<M>(seed, 4000) {
        let nd = coulomb_row(&p, g, mu, c);
        let b = nd.b;
        let v = axpy(&p.lam_t, c, &p.u_t);
        let sc_u = 1.0 / c.max(1.0);
        let un2 = p.u_n + rng.gen_range(-1.0..1.0) * sc_u;
        let ln2 = p.lam_n + rng.gen_range(-1.0..1.0);
        let ut2 = axpy(&p.u_t, 1.0, &rand_vec::<M>(&mut rng, sc_u));
        match nd.state {
            NodeState::S4 if b > 0.0 => {
                let Some(CoulombRow::Slip { l, q, r }) = coulomb_row_unregularised(&p, g, mu, c)
                else {
                    continue; // I − M singular
                };
                if max_abs(&l) > 1e6 * c {
                    continue;
                }
                let s2 = ln2 + c * (un2 + g);
                // λ_τ' = l u_τ' − q s' − r
                let lt2 = axpy(&axpy(&matvec(&l, &ut2), -s2, &q), -1.0, &r);
                let dp = pt(
                    un2 - p.u_n,
                    ln2 - p.lam_n,
                    axpy(&ut2, -1.0, &p.u_t),
                    axpy(&lt2, -1.0, &p.lam_t),
                );
                let d = c_tau_coulomb_derivative(&p, g, mu, c);
                let res = axpy(&c_tau_coulomb(&p, g, mu, c), 1.0, &jac_apply(&d, &dp));
                let sc = norm(&v) * (norm(&p.lam_t) + norm(&lt2) + b + mu * s2.abs())
                    + (b + mu * norm(&v))
                        * (norm(&dp.lam_t) + c * norm(&dp.u_t) + dp.lam_n.abs() + c * dp.u_n.abs());
                assert!(norm(&res) <= 1e-10 * sc, "{res:?} scale {sc}");
                tested[2] += 1;
            }
            NodeState::S3 => {
                assert_eq!(nd.row, CoulombRow::Stick);
                // C_τ / b = −c u_τ here: its Newton step is u_τ' = 0 whatever λ_n' is
                let cb = c_tau_coulomb(&p, g, mu, c).map(|x| x / b);
                assert!(norm(&axpy(&cb, c, &p.u_t)) <= 1e-12 * (1.0 + c * norm(&p.u_t)));
                tested[1] += 1;
            }
            NodeState::S2 => {
                assert!(
                    matches!(nd.row, CoulombRow::Slip { q, r, .. } if q == [0.0; M] && r == [0.0; M])
                );
                let nv = norm(&v);
                if nv > 0.0 {
                    let cv = c_tau_coulomb(&p, g, mu, c).map(|x| x / nv);
                    assert!(norm(&axpy(&cv, -1.0, &p.lam_t)) <= 1e-12 * norm(&p.lam_t));
                }
                tested[0] += 1;
            }
            _ => {}
        }
    }
    assert!(tested.iter().all(|&n| n > 200), "{tested:?}");
}

#[test]
fn row_is_newton_step_2d() {
    row_is_newton_step::<1>(49);
}

#[test]
fn row_is_newton_step_3d() {
    row_is_newton_step::<2>(50);
}

/// Where the Tresca regularisation is inactive (|λ_τ| ≤ b, λ_τ·v ≥ 0) the regularised row
/// equals the exact Newton row, coupling included.
fn regularised_equals_exact_where_inactive<const M: usize>(seed: u64) {
    let mut n = 0;
    for (p, g, mu, c) in samples::<M>(seed, 4000) {
        let nd = coulomb_row(&p, g, mu, c);
        let v = axpy(&p.lam_t, c, &p.u_t);
        if nd.state != NodeState::S4 || norm(&p.lam_t) > nd.b || dot(&p.lam_t, &v) < 0.0 {
            continue;
        }
        let (
            CoulombRow::Slip { l, q, r },
            Some(CoulombRow::Slip {
                l: l2,
                q: q2,
                r: r2,
            }),
        ) = (nd.row, coulomb_row_unregularised(&p, g, mu, c))
        else {
            panic!("slip rows expected");
        };
        let s = 1.0 + max_abs(&l2) / c;
        let tol = 1e-11 * s * s;
        assert!(max_abs(&mat_lin(1.0, &l, -1.0, &l2)) <= tol * c);
        assert!(norm(&axpy(&q, -1.0, &q2)) <= tol * (1.0 + mu));
        assert!(norm(&axpy(&r, -1.0, &r2)) <= tol * (1.0 + nd.b));
        n += 1;
    }
    assert!(n > 200, "{n}");
}

#[test]
fn regularised_equals_exact_where_inactive_2d() {
    regularised_equals_exact_where_inactive::<1>(51);
}

#[test]
fn regularised_equals_exact_where_inactive_3d() {
    regularised_equals_exact_where_inactive::<2>(52);
}

/// At a slipping Coulomb solution (u_n = −g, |λ_τ| = μ|λ_n|, λ_τ ∥ u_τ): l = c e/(1−e)(I − ννᵀ),
/// q = μ ν, r = 0, so the row reads λ_τ' = l u_τ' + μ ν (−λ_n'): 2D λ_τ' = μ|λ_n'| sign(u_τ).
fn at_slip_solution<const M: usize>(seed: u64) {
    let mut rng = StdRng::seed_from_u64(seed);
    for _ in 0..500 {
        let (mu, c, g) = (
            rng.gen_range(0.05..2.0),
            [0.1, 1.0, 100.0][rng.gen_range(0..3)],
            0.1,
        );
        let pn = rng.gen_range(0.1..3.0);
        let dir = rand_vec::<M>(&mut rng, 1.0);
        if norm(&dir) < 1e-2 {
            continue;
        }
        let nu = scale(1.0 / norm(&dir), &dir);
        let u_t = scale(rng.gen_range(1e-2..2.0), &nu);
        let p = pt(-g, -pn, u_t, scale(mu * pn, &nu));
        let nd = coulomb_row(&p, g, mu, c);
        assert_eq!(nd.state, NodeState::S4);
        let CoulombRow::Slip { l, q, r } = nd.row else {
            unreachable!()
        };
        let e = mu * pn / (mu * pn + c * norm(&u_t));
        let mut want = mat_lin(c * e / (1.0 - e), &identity::<M>(), 0.0, &identity::<M>());
        for i in 0..M {
            for j in 0..M {
                want[i][j] -= c * e / (1.0 - e) * nu[i] * nu[j];
            }
        }
        assert!(max_abs(&mat_lin(1.0, &l, -1.0, &want)) <= 1e-10 * (1.0 + max_abs(&want)));
        assert!(norm(&axpy(&q, -mu, &nu)) <= 1e-12 * mu);
        assert!(norm(&r) <= 1e-12 * mu * pn);
    }
}

/// The projection form's row is the Newton step of C_τ = λ_τ − P_b(λ_τ + c u_τ) at an
/// active slip node: λ_τ' = b ν + e (I − ννᵀ)(v' − v) + ν (b' − b) for any new (λ_n', u_τ'),
/// with b' of (F1) at u_n' = −g; at a slip solution (λ_τ = b ν) it is the (F5) row.
fn projected_row_is_the_projection_forms_newton_step<const M: usize>(seed: u64) {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut tested = 0;
    for (mut p, g, mu, c) in samples::<M>(seed, 4000) {
        p.u_n = -g;
        let Some(CoulombRow::Slip { l, q, r }) = coulomb_row_projected(&p, g, mu, c) else {
            assert!(coulomb_classify(&p, g, mu, c) != NodeState::S4 || p.lam_n >= 0.0);
            continue;
        };
        assert_eq!(r, [0.0; M]);
        let b = coulomb_threshold(p.u_n, p.lam_n, g, mu, c);
        let v = axpy(&p.lam_t, c, &p.u_t);
        let nu = scale(1.0 / norm(&v), &v);
        let e = b / norm(&v);
        if e > 1.0 - 1e-6 {
            continue;
        }
        let (ln2, ut2) = (
            p.lam_n + rng.gen_range(-1.0..1.0),
            axpy(&p.u_t, 1.0, &rand_vec::<M>(&mut rng, 1.0 / c.max(1.0))),
        );
        let b2 = mu * (-ln2);
        // −λ_τ' + l u_τ' − q λ_n' = r on an active node (F6)
        let lt2 = axpy(&matvec(&l, &ut2), -ln2, &q);
        let dv = axpy(&axpy(&lt2, c, &ut2), -1.0, &v);
        let mut want = scale(b2, &nu);
        let along = dot(&nu, &dv);
        for i in 0..M {
            want[i] += e * (dv[i] - along * nu[i]);
        }
        let sc = norm(&lt2) + b.abs() + b2.abs() + e * norm(&dv);
        assert!(
            norm(&axpy(&lt2, -1.0, &want)) <= 1e-10 * sc,
            "{lt2:?} {want:?}"
        );
        if M == 1 {
            assert_eq!(l, [[0.0; M]; M]);
        }
        // at the slip solution with the same v the (F5) row is the same row
        let at_solution = pt(
            p.u_n,
            p.lam_n,
            axpy(&v, -b, &nu).map(|x| x / c),
            scale(b, &nu),
        );
        let Some(CoulombRow::Slip {
            l: l5,
            q: q5,
            r: r5,
        }) = coulomb_row_unregularised(&at_solution, g, mu, c)
        else {
            panic!("a slip solution has a slip row");
        };
        let s = 1.0 + max_abs(&l5) / c;
        assert!(max_abs(&mat_lin(1.0, &l, -1.0, &l5)) <= 1e-9 * s * c);
        assert!(norm(&axpy(&q, -1.0, &q5)) <= 1e-9 * s * mu);
        assert!(norm(&r5) <= 1e-9 * s * b);
        tested += 1;
    }
    assert!(tested > 200, "{tested}");
}

#[test]
fn projected_row_is_the_projection_forms_newton_step_2d() {
    projected_row_is_the_projection_forms_newton_step::<1>(61);
}

#[test]
fn projected_row_is_the_projection_forms_newton_step_3d() {
    projected_row_is_the_projection_forms_newton_step::<2>(62);
}

#[test]
fn at_slip_solution_2d() {
    at_slip_solution::<1>(53);
}

#[test]
fn at_slip_solution_3d() {
    at_slip_solution::<2>(54);
}

#[test]
fn dyn_wrapper_matches_generic() {
    let mut rng = StdRng::seed_from_u64(55);
    for (p, g, mu, c) in samples::<2>(56, 500) {
        let d3 = coulomb_row_dyn(3, p.u_n, p.lam_n, p.u_t, p.lam_t, g, mu, c);
        assert_eq!(d3, coulomb_row(&p, g, mu, c));
        let junk = rng.gen_range(-1.0..1.0);
        let d2 = coulomb_row_dyn(
            2,
            p.u_n,
            p.lam_n,
            [p.u_t[0], junk],
            [p.lam_t[0], junk],
            g,
            mu,
            c,
        );
        let p1 = pt(p.u_n, p.lam_n, [p.u_t[0]], [p.lam_t[0]]);
        let d1 = coulomb_row(&p1, g, mu, c);
        assert_eq!((d2.state, d2.b), (d1.state, d1.b));
        match (d2.row, d1.row) {
            (CoulombRow::Stick, CoulombRow::Stick) => {}
            (
                CoulombRow::Slip { l, q, r },
                CoulombRow::Slip {
                    l: l1,
                    q: q1,
                    r: r1,
                },
            ) => {
                assert_eq!(l, [[l1[0][0], 0.0], [0.0, 0.0]]);
                assert_eq!((q, r), ([q1[0], 0.0], [r1[0], 0.0]));
            }
            other => panic!("{other:?}"),
        }
    }
}

// ---- the rows in a (dense) reduced system ----

/// Dense Gaussian elimination with partial pivoting (tests only).
fn solve_dense(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for k in 0..n {
        let p = (k..n)
            .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
            .unwrap();
        a.swap(k, p);
        b.swap(k, p);
        assert!(a[k][k].abs() > 1e-13, "singular");
        for i in k + 1..n {
            let f = a[i][k] / a[k][k];
            for j in k..n {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|j| a[k][j] * x[j]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    x
}

/// The reduced system of [`reduced_system_rows`] written as the plain path writes it: each
/// node's rows left-multiplied by its projector (the slip node's by projector + row mix),
/// the prescribed directions' columns eliminated into the right-hand side, the scaled
/// identity on the prescribed directions and the slip block's spring. Returns (S, rhs).
#[allow(clippy::type_complexity)]
fn written_rows(
    (a, f): (&[Vec<f64>], &[f64]),
    (proj, known, left, dirs): (
        &[[[f64; 3]; 3]],
        &[[f64; 3]],
        &[[[f64; 3]; 3]],
        &[Vec<([f64; 3], f64)>],
    ),
    blk: &CoulombBlock,
    dim: usize,
) -> (Vec<Vec<f64>>, Vec<f64>) {
    let nn = proj.len();
    let nd = nn * dim;
    let mut s = vec![vec![0.0; nd]; nd];
    let mut rhs = vec![0.0; nd];
    for k in 0..nn {
        let sk = (0..dim).map(|x| a[k * dim + x][k * dim + x]).sum::<f64>() / dim as f64;
        let mut fk = [0.0; 3];
        for x in 0..dim {
            fk[x] = f[k * dim + x]
                - (0..nn)
                    .map(|j| {
                        (0..dim)
                            .map(|y| a[k * dim + x][j * dim + y] * known[j][y])
                            .sum::<f64>()
                    })
                    .sum::<f64>();
        }
        for x in 0..dim {
            rhs[k * dim + x] =
                (0..dim).map(|y| left[k][x][y] * fk[y]).sum::<f64>() + sk * known[k][x];
            if k == 0 {
                rhs[x] += blk.spring_rhs[x];
            }
            for j in 0..nn {
                for y in 0..dim {
                    // (left_k A_kj P_j)_{xy}
                    let mut v = 0.0;
                    for z in 0..dim {
                        for w in 0..dim {
                            v += left[k][x][z] * a[k * dim + z][j * dim + w] * proj[j][w][y];
                        }
                    }
                    if j == k {
                        for (cv, _) in &dirs[k] {
                            v += sk * cv[x] * cv[y];
                        }
                        if k == 0 {
                            v += blk.spring[x][y];
                        }
                    }
                    s[k * dim + x][j * dim + y] = v;
                }
            }
        }
    }
    (s, rhs)
}

/// The block data (F7) written as step_system/write.rs writes a node (symmetric elimination of the
/// prescribed directions, own-block spring) produce a system whose solution satisfies the
/// Newton rows: on a Coulomb slip node u_n = −g and −λ_τ' + l u_τ' − q λ_n' = r with
/// λ' = f − A u' (3.28); on a stick node u^k = −g n; free nodes are in equilibrium. The
/// matrix is unsymmetric exactly when q ≠ 0 (2D, l a scalar) — the λ_n coupling.
fn reduced_system_rows(dim: usize, seed: u64) {
    let mut rng = StdRng::seed_from_u64(seed);
    let nn = 4; // nodes: 0 slip, 1 stick, 2 and 3 free
    let nd = nn * dim;
    for trial in 0..200 {
        // A = Gᵀ G + I (SPD), f random
        let gm: Vec<Vec<f64>> = (0..nd)
            .map(|_| (0..nd).map(|_| rng.gen_range(-1.0..1.0)).collect())
            .collect();
        let mut a = vec![vec![0.0; nd]; nd];
        for i in 0..nd {
            for j in 0..nd {
                a[i][j] = (0..nd).map(|k| gm[k][i] * gm[k][j]).sum::<f64>();
            }
            a[i][i] += 1.0;
        }
        let f: Vec<f64> = (0..nd).map(|_| rng.gen_range(-1.0..1.0)).collect();
        let fr: Vec<Frame> = (0..2)
            .map(|_| {
                Frame::new(
                    [
                        rng.gen_range(-1.0..1.0),
                        rng.gen_range(0.5..1.0),
                        rng.gen_range(-1.0..1.0),
                    ],
                    dim,
                )
                .unwrap()
            })
            .collect();
        let g = [rng.gen_range(0.0..0.2), rng.gen_range(0.0..0.2)];
        let m = dim - 1;
        let mut l = [[0.0; 2]; 2];
        let mut q = [0.0; 2];
        let mut r = [0.0; 2];
        for i in 0..m {
            for j in 0..m {
                l[i][j] = rng.gen_range(0.0..2.0) * if i == j { 1.0 } else { 0.3 };
            }
            q[i] = if trial % 4 == 0 {
                0.0
            } else {
                rng.gen_range(-1.0..1.0)
            };
            r[i] = rng.gen_range(-1.0..1.0);
        }
        let row = CoulombRow::Slip { l, q, r };
        let blk = coulomb_block(&fr[0], &row);
        // projectors and known parts
        let mut proj = vec![[[0.0; 3]; 3]; nn];
        let mut known = vec![[0.0; 3]; nn];
        let mut dirs: Vec<Vec<([f64; 3], f64)>> = vec![Vec::new(); nn];
        dirs[0].push((fr[0].n, -g[0]));
        dirs[1].push((fr[1].n, -g[1]));
        for t in &fr[1].t[..m] {
            dirs[1].push((*t, 0.0));
        }
        for k in 0..nn {
            for x in 0..dim {
                proj[k][x][x] = 1.0;
            }
            for (cv, val) in &dirs[k] {
                for x in 0..dim {
                    known[k][x] += val * cv[x];
                    for y in 0..dim {
                        proj[k][x][y] -= cv[x] * cv[y];
                    }
                }
            }
        }
        let mut left = proj.clone(); // left factor of the node's rows
        for x in 0..dim {
            for y in 0..dim {
                left[0][x][y] += blk.row_mix[x][y];
            }
        }
        let (s, rhs) = written_rows((&a, &f), (&proj, &known, &left, &dirs), &blk, dim);
        let asym = (0..nd)
            .flat_map(|i| (0..nd).map(move |j| (i, j)))
            .fold(0.0_f64, |mx, (i, j)| mx.max((s[i][j] - s[j][i]).abs()));
        if q[..m].iter().all(|&x| x == 0.0) {
            if dim == 2 {
                assert!(asym <= 1e-12, "symmetric without the coupling: {asym}");
            }
        } else {
            assert!(asym > 1e-6, "the λ_n coupling makes S unsymmetric");
        }
        let u = solve_dense(s, rhs);
        // λ' = f − A u
        let lam: Vec<f64> = (0..nd)
            .map(|i| f[i] - (0..nd).map(|j| a[i][j] * u[j]).sum::<f64>())
            .collect();
        let part = |v: &[f64], k: usize| {
            [
                v[k * dim],
                v[k * dim + 1],
                if dim == 3 { v[k * dim + 2] } else { 0.0 },
            ]
        };
        let scale_u = 1.0 + u.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let tol = 1e-10 * scale_u * (1.0 + max_abs(&l));
        // slip node
        let (u0, l0) = (part(&u, 0), part(&lam, 0));
        assert!((fr[0].normal_part(&u0) + g[0]).abs() <= tol);
        let ut = fr[0].tangential_part(&u0);
        let lt = fr[0].tangential_part(&l0);
        let ln = fr[0].normal_part(&l0);
        for i in 0..m {
            let lu: f64 = (0..m).map(|j| l[i][j] * ut[j]).sum();
            let row_i = -lt[i] + lu - q[i] * ln;
            assert!(
                (row_i - r[i]).abs() <= tol,
                "slip row {i}: {row_i} vs {}",
                r[i]
            );
        }
        // stick node: u = −g n
        let u1 = part(&u, 1);
        for x in 0..dim {
            assert!((u1[x] + g[1] * fr[1].n[x]).abs() <= tol);
        }
        // free nodes: λ = 0
        for i in 2 * dim..nd {
            assert!(lam[i].abs() <= tol, "free node residual {}", lam[i]);
        }
    }
}

#[test]
fn reduced_system_rows_2d() {
    reduced_system_rows(2, 57);
}

#[test]
fn reduced_system_rows_3d() {
    reduced_system_rows(3, 58);
}

/// One contact node on a linear spring: λ = f − K u (the nodal form of (3.28), K SPD, d×d in
/// the node frame: index 0 normal, 1.. tangential), obstacle at gap g. The generalised Newton
/// (state by (3.23)/(3.33) with (F1), rows (F5)) converges to a point that satisfies
/// Coulomb's law (certificate (F3) and the direct check); the fixed point on Tresca
/// thresholds reaches the same point. Returns the Newton solves (sum, max) and the fixed-point solves (sum).
fn spring_node<const M: usize>(seed: u64) -> (usize, usize, usize) {
    let d = M + 1;
    let mut rng = StdRng::seed_from_u64(seed);
    let (mut newton_total, mut newton_max, mut fp_total) = (0, 0, 0);
    let mut slipped = 0;
    for _ in 0..300 {
        // K: diagonally dominant SPD with normal–tangential coupling
        let mut k = [[0.0; 3]; 3];
        let gm: [[f64; 3]; 3] = [[0.0; 3]; 3].map(|r| r.map(|_: f64| rng.gen_range(-0.4..0.4)));
        for i in 0..d {
            for j in 0..d {
                k[i][j] = (0..d).map(|l| gm[l][i] * gm[l][j]).sum::<f64>();
            }
            k[i][i] += 1.0;
        }
        let mut f = [0.0; 3];
        f[0] = -rng.gen_range(0.1..2.0); // pushes towards the obstacle
        for x in f.iter_mut().take(d).skip(1) {
            *x = rng.gen_range(-1.5..1.5);
        }
        let g = rng.gen_range(0.0..0.05);
        let mu = rng.gen_range(0.0..0.8);
        let c = [0.1, 1.0, 10.0][rng.gen_range(0..3)];
        let split = |u: &[f64; 3]| -> NodePoint<M> {
            let lam: Vec<f64> = (0..d)
                .map(|i| f[i] - (0..d).map(|j| k[i][j] * u[j]).sum::<f64>())
                .collect();
            let mut p = pt(u[0], lam[0], [0.0; M], [0.0; M]);
            p.u_t.copy_from_slice(&u[1..=M]);
            p.lam_t.copy_from_slice(&lam[1..=M]);
            p
        };
        // one linear solve with the normal row (active: u_n = −g, else λ_n = 0) and the
        // tangential rows `row` (q = 0: a Tresca row)
        let solve = |active: bool, row: &CoulombRow<M>| -> [f64; 3] {
            let mut a = vec![vec![0.0; d]; d];
            let mut rhs = vec![0.0; d];
            if active {
                a[0][0] = 1.0;
                rhs[0] = -g;
            } else {
                a[0][..d].copy_from_slice(&k[0][..d]);
                rhs[0] = f[0];
            }
            for i in 0..M {
                match *row {
                    CoulombRow::Stick => a[i + 1][i + 1] = 1.0,
                    CoulombRow::Slip { l, q, r } => {
                        // −(f − K u)_τ + l u_τ − q s' = r, s' = λ_n' + c(u_n' + g)
                        for j in 0..d {
                            a[i + 1][j] = k[i + 1][j];
                        }
                        for j in 0..M {
                            a[i + 1][j + 1] += l[i][j];
                        }
                        // − q s', s' = λ_n' + c(u_n' + g) = f_0 − K_0 u + c u_0 + c g
                        rhs[i + 1] = r[i] + f[i + 1] + q[i] * (f[0] + c * g);
                        for j in 0..d {
                            a[i + 1][j] += q[i] * k[0][j];
                        }
                        a[i + 1][0] -= q[i] * c;
                    }
                }
            }
            let x = solve_dense(a, rhs);
            let mut u = [0.0; 3];
            u[..d].copy_from_slice(&x);
            u
        };
        let converged = |u: &[f64; 3], u2: &[f64; 3], same: bool| {
            same && (0..d).map(|i| (u[i] - u2[i]).abs()).fold(0.0, f64::max) <= 1e-13
        };
        // generalised Newton from u = 0
        let mut u = [0.0; 3];
        let mut state = coulomb_classify(&split(&u), g, mu, c);
        let mut steps = 0;
        loop {
            steps += 1;
            assert!(steps <= 40, "Newton: no convergence (mu={mu}, c={c})");
            let nd = coulomb_row(&split(&u), g, mu, c);
            let u2 = solve(nd.state.normal_active(), &nd.row);
            let next = coulomb_classify(&split(&u2), g, mu, c);
            let done = converged(&u, &u2, next == state);
            u = u2;
            state = next;
            if done {
                break;
            }
        }
        newton_total += steps;
        newton_max = newton_max.max(steps);
        let p = split(&u);
        let sc = 1.0 + f.iter().map(|x| x.abs()).sum::<f64>();
        assert!(coulomb_residual(&p, g, mu, c).norm() <= 1e-11 * sc, "{p:?}");
        assert!(coulomb_conditions_hold(&p, g, mu, 1e-11 * sc, 1e-11 * sc));
        if state == NodeState::S4 && norm(&p.u_t) > 1e-6 {
            slipped += 1;
        }
        // fixed point on Tresca thresholds: outer b^{m+1} = μ(−λ_n^m), inner Algorithm 2
        // (normal set (3.23), Tresca rows (3.39) at the frozen b) to convergence
        let mut v = [0.0; 3];
        let mut b = 0.0;
        let mut solves = 0;
        for outer in 0.. {
            assert!(outer < 200, "fixed point: no convergence");
            let mut inner_state = None;
            loop {
                solves += 1;
                assert!(solves < 5000);
                let p = split(&v);
                let active = normal_active(p.u_n, p.lam_n, g, c);
                let row = match tangential_row(&p.u_t, &p.lam_t, b, c) {
                    TangentialRow::Stick => CoulombRow::Stick,
                    TangentialRow::Slip { l, r } => CoulombRow::Slip { l, q: [0.0; M], r },
                };
                let v2 = solve(active, &row);
                let st = (active, row.is_slip());
                let done = converged(&v, &v2, inner_state == Some(st));
                v = v2;
                inner_state = Some(st);
                if done {
                    break;
                }
            }
            let b2 = mu * (-split(&v).lam_n).max(0.0);
            if (b2 - b).abs() <= 1e-13 * sc {
                break;
            }
            b = b2;
        }
        fp_total += solves;
        let pv = split(&v);
        for i in 0..d {
            assert!(
                (u[i] - v[i]).abs() <= 1e-9 * sc,
                "Newton {u:?} vs fixed point {v:?}"
            );
        }
        assert!(coulomb_conditions_hold(&pv, g, mu, 1e-9 * sc, 1e-9 * sc));
    }
    assert!(slipped > 50, "slipping solutions sampled: {slipped}");
    (newton_total, newton_max, fp_total)
}

#[test]
fn spring_node_converges_2d() {
    let (n, n_max, fp) = spring_node::<1>(59);
    eprintln!("2D spring node, 300 cases: Newton {n} solves (max {n_max}), fixed point {fp}");
    assert!(n < fp);
}

#[test]
fn spring_node_converges_3d() {
    let (n, n_max, fp) = spring_node::<2>(60);
    eprintln!("3D spring node, 300 cases: Newton {n} solves (max {n_max}), fixed point {fp}");
    assert!(n < fp);
}

#[test]
fn coupling_uses_the_regularised_inverse() {
    // (I − βM̃)⁻¹ = I + L̃/c: the identity used for w̃
    for (p, g, mu, c) in samples::<2>(61, 2000) {
        let b = coulomb_threshold(p.u_n, p.lam_n, g, mu, c);
        let Some(reg) = regularise(&p.u_t, &p.lam_t, b, c) else {
            continue;
        };
        let a = mat_lin(1.0, &identity::<2>(), -reg.beta, &reg.m_tilde);
        let Some(inv) = inverse(&a, 1e-10) else {
            continue;
        };
        let want = mat_lin(1.0, &identity::<2>(), 1.0 / c, &reg.l_tilde);
        assert!(max_abs(&mat_lin(1.0, &inv, -1.0, &want)) <= 1e-8 * (1.0 + max_abs(&inv)));
    }
}
