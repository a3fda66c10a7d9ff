//! The node's Newton row of each Coulomb state (F5)–(F7), regularised, unregularised or
//! projected, and its d×d block in the step system (3.42).

use super::point::{coulomb_classify, coulomb_threshold, NodePoint};
use crate::contact::complementarity::NodeState;
use crate::contact::frame::Frame;
use crate::contact::linalg::{axpy, matvec, norm, scale};
use crate::contact::tresca::{regularise, unregularised, TangentialRow};
/// The tangential rows of one node for the next Newton step (F5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CoulombRow<const M: usize> {
    /// S3 (k ∈ A_n, stick): u_τ' = 0 (3.34a).
    Stick,
    /// S2 / S4: −λ_τ' + l u_τ' − q (λ_n' + c (u_n' + g)) = r. S2 and μ = 0: l = 0, q = 0,
    /// r = 0 (λ_τ' = 0). On an active node (u_n' = −g) the coupling is −q λ_n' (F6).
    Slip {
        l: [[f64; M]; M],
        q: [f64; M],
        r: [f64; M],
    },
}

impl<const M: usize> From<TangentialRow<M>> for CoulombRow<M> {
    /// A Tresca row (3.39a) is a Coulomb row without the λ_n coupling (q = 0).
    fn from(t: TangentialRow<M>) -> Self {
        match t {
            TangentialRow::Stick => CoulombRow::Stick,
            TangentialRow::Slip { l, r } => CoulombRow::Slip { l, q: [0.0; M], r },
        }
    }
}

impl<const M: usize> CoulombRow<M> {
    pub fn is_slip(&self) -> bool {
        matches!(self, CoulombRow::Slip { .. })
    }

    /// A slip row with a λ_n coupling (q ≠ 0): Coulomb's S4 row (F6), not a Tresca row.
    pub fn coupled(&self) -> bool {
        matches!(self, CoulombRow::Slip { q, .. } if q.iter().any(|&x| x != 0.0))
    }

    /// The row for the tangential increment u_τ − u_ref (load steps, docs/friction.md): the
    /// slip row −λ_τ' + l (u_τ' − u_ref) = r moves l u_ref to the right-hand side. Unchanged
    /// for u_ref = 0 (bit for bit).
    pub fn with_reference(&self, u_ref: &[f64; M]) -> Self {
        match *self {
            CoulombRow::Slip { l, q, r } if u_ref.iter().any(|&x| x != 0.0) => CoulombRow::Slip {
                l,
                q,
                r: axpy(&r, 1.0, &matvec(&l, u_ref)),
            },
            row => row,
        }
    }

    /// The Tresca part (l, r) of the row, the coupling q dropped.
    pub fn tresca_part(&self) -> TangentialRow<M> {
        match *self {
            CoulombRow::Stick => TangentialRow::Stick,
            CoulombRow::Slip { l, r, .. } => TangentialRow::Slip { l, r },
        }
    }

    /// The Tresca row (3.39a) this row becomes when s' = λ_n' + c (u_n' + g) is frozen at `s`
    /// (a Tresca solve with the threshold b = −μ s): −λ_τ' + l u_τ' = r + q s.
    pub fn frozen(&self, s: f64) -> TangentialRow<M> {
        match *self {
            CoulombRow::Stick => TangentialRow::Stick,
            CoulombRow::Slip { l, q, r } => TangentialRow::Slip {
                l,
                r: axpy(&r, s, &q),
            },
        }
    }
}

/// A node's Newton data: state, threshold b (F1) at the previous iterate, rows (F5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoulombNewton<const M: usize> {
    pub state: NodeState,
    pub b: f64,
    pub row: CoulombRow<M>,
}

/// (F5), regularised as (3.39)/(3.40): the state and the tangential rows of one node from the
/// previous iterate `p`. Slip: l = L̃, q = μ w̃, r = r̃ + w̃ b with w̃ = (I − βM̃)⁻¹ ν
/// = ν + L̃ ν / c. Degenerate cases as in Tresca (§3.4.3): b = 0 (k ∉ A_n, or μ = 0) gives the
/// frictionless row; |v| ≤ b is stick, so |v| ≥ b > 0 wherever ν is formed.
pub fn coulomb_row<const M: usize>(p: &NodePoint<M>, g: f64, mu: f64, c: f64) -> CoulombNewton<M> {
    let b = coulomb_threshold(p.u_n, p.lam_n, g, mu, c);
    let state = coulomb_classify(p, g, mu, c);
    let zero = CoulombRow::Slip {
        l: [[0.0; M]; M],
        q: [0.0; M],
        r: [0.0; M],
    };
    let row = if !state.slip() {
        CoulombRow::Stick
    } else {
        match regularise(&p.u_t, &p.lam_t, b, c) {
            Some(reg) => {
                let nu = scale(1.0 / norm(&reg.v), &reg.v);
                let w = axpy(&nu, 1.0 / c, &matvec(&reg.l_tilde, &nu));
                CoulombRow::Slip {
                    l: reg.l_tilde,
                    q: scale(mu, &w),
                    r: axpy(&reg.r_tilde, b, &w),
                }
            }
            // b ≤ 0 (or non-finite input): frictionless, λ_τ' = 0.
            None => zero,
        }
    };
    CoulombNewton { state, b, row }
}

/// (F5) without the regularisation: the exact Newton row of a slip node (S4) from (3.37)/(3.38)
/// plus the coupling w = (I − M)⁻¹ ν = ν + L ν / c. `None` unless the node is S4 with I − M
/// regular.
pub fn coulomb_row_unregularised<const M: usize>(
    p: &NodePoint<M>,
    g: f64,
    mu: f64,
    c: f64,
) -> Option<CoulombRow<M>> {
    let b = coulomb_threshold(p.u_n, p.lam_n, g, mu, c);
    if coulomb_classify(p, g, mu, c) != NodeState::S4 || b <= 0.0 {
        return None;
    }
    let un = unregularised(&p.u_t, &p.lam_t, b, c)?;
    let v = axpy(&p.lam_t, c, &p.u_t);
    let nu = scale(1.0 / norm(&v), &v);
    let w = axpy(&nu, 1.0 / c, &matvec(&un.l, &nu));
    Some(CoulombRow::Slip {
        l: un.l,
        q: scale(mu, &w),
        r: axpy(&un.r, b, &w),
    })
}

/// The Newton row of the projection form C_τ = λ_τ − P_b(λ_τ + c u_τ) (F3) at a slip node
/// (b > 0, |v| > b), for a node that slipped in the previous step as well (docs/friction.md,
/// "Settled slip"): with ν = v/|v|, e = b/|v|, the linearisation of P_b(v) = b ν is
/// e (I − ννᵀ) dv + ν db, so λ_τ' = L u_τ' + ν b' with L = c e/(1 − e) (I − ννᵀ):
/// l = L, q = μ ν, r = 0. It is the (F5) row evaluated as at a slipping solution (λ_τ = b ν);
/// in 2D L = 0 and the row λ_τ' = μ(−λ_n') ν depends on the direction alone, so the
/// iteration is piecewise linear. `None` unless b > 0 and |v| > b.
pub fn coulomb_row_projected<const M: usize>(
    p: &NodePoint<M>,
    g: f64,
    mu: f64,
    c: f64,
) -> Option<CoulombRow<M>> {
    let b = coulomb_threshold(p.u_n, p.lam_n, g, mu, c);
    let v = axpy(&p.lam_t, c, &p.u_t);
    let nv = norm(&v);
    if !(b > 0.0 && nv > b && nv.is_finite()) {
        return None;
    }
    // 2D: ν = sign v exactly, so that the row repeats bit for bit while the direction holds
    let nu = if M == 1 {
        v.map(f64::signum)
    } else {
        scale(1.0 / nv, &v)
    };
    // c e/(1 − e) = c b/(|v| − b), without the cancellation of 1 − e
    let k = c * b / (nv - b);
    let mut l = [[0.0; M]; M];
    if M > 1 {
        for (i, row) in l.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                let delta = if i == j { 1.0 } else { 0.0 };
                *x = k * (delta - nu[i] * nu[j]);
            }
        }
    }
    Some(CoulombRow::Slip {
        l,
        q: scale(mu, &nu),
        r: [0.0; M],
    })
}

/// [`coulomb_row`] for a runtime dimension `dim` (2 or 3) with tangential vectors padded to
/// length 2 (second entry ignored in 2D; the 2D row sits in `l[0][0]`, `q[0]`, `r[0]`).
#[allow(clippy::too_many_arguments)]
pub fn coulomb_row_dyn(
    dim: usize,
    u_n: f64,
    lam_n: f64,
    u_t: [f64; 2],
    lam_t: [f64; 2],
    g: f64,
    mu: f64,
    c: f64,
) -> CoulombNewton<2> {
    if dim == 3 {
        let p = NodePoint {
            u_n,
            lam_n,
            u_t,
            lam_t,
        };
        return coulomb_row(&p, g, mu, c);
    }
    let p = NodePoint {
        u_n,
        lam_n,
        u_t: [u_t[0]],
        lam_t: [lam_t[0]],
    };
    let n = coulomb_row(&p, g, mu, c);
    let row = match n.row {
        CoulombRow::Stick => CoulombRow::Stick,
        CoulombRow::Slip { l, q, r } => CoulombRow::Slip {
            l: [[l[0][0], 0.0], [0.0, 0.0]],
            q: [q[0], 0.0],
            r: [r[0], 0.0],
        },
    };
    CoulombNewton {
        state: n.state,
        b: n.b,
        row,
    }
}

/// What a Coulomb slip row (F5) puts into the reduced system, in global components (3×3,
/// only the leading d×d used), for an ACTIVE node whose normal is eliminated (u_n = −g) as in
/// step_system/write.rs (F7). With P_k = Σ τ_i τ_iᵀ the node's rows become `(P_k + E) A_kj P_j` for
/// every column block j of the node's rows of A, plus `s_k n nᵀ + S` on the node's own block,
/// and its right-hand side `(P_k + E)(f_k − Σ_j A_kj ū_j) + s_k ū_k + ρ`.
///
/// E = Σ_i q_i τ_i nᵀ is the λ_n coupling (λ_n' = nᵀ(f − A u)_k is the node's normal row of A);
/// S = Σ τ_i l_ij τ_jᵀ and ρ = Σ τ_i r_i are the Tresca spring and right-hand side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoulombBlock {
    /// E: left factor added to the node's projector P_k, applied to ALL its blocks of A and
    /// to its f_k (not only the own block: λ_n involves the neighbours).
    pub row_mix: [[f64; 3]; 3],
    /// S: added to the node's own block (as `NodeConstraint::add_slip_spring`).
    pub spring: [[f64; 3]; 3],
    /// ρ: added to the node's right-hand side.
    pub spring_rhs: [f64; 3],
}

/// (F7) the block data of a node's Coulomb row in its frame; zero for a stick row.
pub fn coulomb_block(frame: &Frame, row: &CoulombRow<2>) -> CoulombBlock {
    let mut blk = CoulombBlock {
        row_mix: [[0.0; 3]; 3],
        spring: [[0.0; 3]; 3],
        spring_rhs: [0.0; 3],
    };
    let CoulombRow::Slip { l, q, r } = row else {
        return blk;
    };
    let m = frame.dim - 1;
    let n = frame.n;
    for (i, ti) in frame.t[..m].iter().enumerate() {
        for a in 0..3 {
            for b in 0..3 {
                blk.row_mix[a][b] += q[i] * ti[a] * n[b];
                for (j, tj) in frame.t[..m].iter().enumerate() {
                    blk.spring[a][b] += ti[a] * l[i][j] * tj[b];
                }
            }
            blk.spring_rhs[a] += ti[a] * r[i];
        }
    }
    blk
}
