//! Orthonormal contact frames {n, τ_1 (, τ_2)} (thesis §3.1, (3.4)–(3.7), §3.4.1):
//! u_n = u·n, u_τ = (u·τ_1, u·τ_2) ∈ R^(d−1).
//!
//! Conventions:
//! - 2D: τ = (n_y, −n_x), i.e. n turned clockwise by 90°. Then (τ, n) is positively
//!   oriented (det[τ n] = 1) like (e_x, e_y); for the Hertz plane n = (0, 1): τ = (1, 0).
//! - 3D: τ_1 = normalised projection of the coordinate axis e_i with the smallest |n_i|
//!   (ties: lowest index) onto the plane ⊥ n; τ_2 = n × τ_1. Then (τ_1, τ_2, n) is
//!   right-handed (τ_1 × τ_2 = n); for n = e_z: τ_1 = e_x, τ_2 = e_y.
//!   The choice is deterministic and continuous in n except where the index of the
//!   smallest |n_i| changes (a continuous global choice cannot exist on the sphere).
//!   That is harmless: the Tresca algebra is equivariant under a rotation of the tangent
//!   basis (tested in `tresca`), so the solution does not depend on it.

use crate::geom::{cross, dot};

/// 2D tangent τ = (n_y, −n_x) of a unit normal n.
pub fn tangent_2d(n: [f64; 2]) -> [f64; 2] {
    [n[1], -n[0]]
}

/// 3D tangents (τ_1, τ_2) of a unit normal n, see the module doc for the rule.
pub fn tangents_3d(n: [f64; 3]) -> [[f64; 3]; 2] {
    let mut i = 0;
    for k in 1..3 {
        if n[k].abs() < n[i].abs() {
            i = k;
        }
    }
    // e_i − n_i n
    let mut t = n.map(|x| -n[i] * x);
    t[i] += 1.0;
    let len = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
    let t1 = t.map(|x| x / len);
    let t2 = cross(n, t1);
    [t1, t2]
}

/// The frame of one contact node. Vectors are `[f64; 3]` (z = 0 in 2D); tangential
/// coefficient vectors are `[f64; 2]` with the second entry 0 in 2D.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub dim: usize,
    /// Unit normal, into the body.
    pub n: [f64; 3],
    /// Tangents; `t[1]` is the zero vector in 2D.
    pub t: [[f64; 3]; 2],
}

impl Frame {
    /// Frame of the normal `n` (normalised here; `None` if n is zero or not finite, or if
    /// `dim` is not 2 or 3). In 2D the z component of n is ignored.
    pub fn new(n: [f64; 3], dim: usize) -> Option<Frame> {
        let n = match dim {
            2 => [n[0], n[1], 0.0],
            3 => n,
            _ => return None,
        };
        let big = n.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        if !big.is_finite() || big <= 0.0 {
            return None;
        }
        let s = n.map(|x| x / big);
        let len = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
        let n = s.map(|x| x / len);
        let t = if dim == 2 {
            let t = tangent_2d([n[0], n[1]]);
            [[t[0], t[1], 0.0], [0.0; 3]]
        } else {
            tangents_3d(n)
        };
        Some(Frame { dim, n, t })
    }

    /// v_n = v·n
    pub fn normal_part(&self, v: &[f64; 3]) -> f64 {
        dot(*v, self.n)
    }

    /// v_τ = (v·τ_1, v·τ_2); second entry 0 in 2D.
    pub fn tangential_part(&self, v: &[f64; 3]) -> [f64; 2] {
        if self.dim == 2 {
            [dot(*v, self.t[0]), 0.0]
        } else {
            [dot(*v, self.t[0]), dot(*v, self.t[1])]
        }
    }

    /// v = v_n n + Σ v_τ,i τ_i (inverse of the two projections).
    pub fn to_global(&self, v_n: f64, v_t: [f64; 2]) -> [f64; 3] {
        let mut r = self.n.map(|x| v_n * x);
        for (i, ti) in self.t.iter().enumerate().take(self.dim - 1) {
            for k in 0..3 {
                r[k] += v_t[i] * ti[k];
            }
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    #[test]
    fn hertz_tangent() {
        assert_eq!(tangent_2d([0.0, 1.0]), [1.0, 0.0]);
        let f = Frame::new([0.0, 2.0, 0.0], 2).unwrap();
        assert_eq!(f.n, [0.0, 1.0, 0.0]);
        assert_eq!(f.t[0], [1.0, 0.0, 0.0]);
        assert_eq!(f.tangential_part(&[0.3, -0.7, 0.0]), [0.3, 0.0]);
        assert_eq!(f.normal_part(&[0.3, -0.7, 0.0]), -0.7);
        let f3 = Frame::new([0.0, 0.0, 1.0], 3).unwrap();
        assert_eq!(f3.t, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        assert!(Frame::new([0.0; 3], 3).is_none());
        assert!(Frame::new([0.0, 0.0, 1.0], 2).is_none());
        assert!(Frame::new([1.0, 0.0, 0.0], 1).is_none());
    }

    #[test]
    fn random_frames_orthonormal_right_handed() {
        let mut rng = StdRng::seed_from_u64(3);
        for dim in [2usize, 3] {
            for _ in 0..500 {
                let mut n = [0.0; 3].map(|_: f64| rng.gen_range(-1.0..1.0));
                if dim == 2 {
                    n[2] = 0.0;
                }
                let f = match Frame::new(n, dim) {
                    Some(f) => f,
                    None => continue,
                };
                let basis: Vec<[f64; 3]> = std::iter::once(f.n)
                    .chain(f.t.iter().copied().take(dim - 1))
                    .collect();
                for (a, x) in basis.iter().enumerate() {
                    for (b, y) in basis.iter().enumerate() {
                        let want = if a == b { 1.0 } else { 0.0 };
                        assert!((dot(*x, *y) - want).abs() < 1e-14);
                    }
                }
                if dim == 2 {
                    assert_eq!(f.t[1], [0.0; 3]);
                    assert_eq!(f.t[0][2], 0.0);
                    // det[τ n] = +1
                    let det = f.t[0][0] * f.n[1] - f.t[0][1] * f.n[0];
                    assert!((det - 1.0).abs() < 1e-14);
                } else {
                    let c = cross(f.t[0], f.t[1]);
                    for (ck, nk) in c.iter().zip(&f.n) {
                        assert!((ck - nk).abs() < 1e-14);
                    }
                }
                // projections and their inverse
                let v = [0.0; 3].map(|_: f64| rng.gen_range(-1.0..1.0));
                let v = if dim == 2 { [v[0], v[1], 0.0] } else { v };
                let back = f.to_global(f.normal_part(&v), f.tangential_part(&v));
                for k in 0..3 {
                    assert!((back[k] - v[k]).abs() < 1e-14);
                }
                // deterministic
                assert_eq!(Frame::new(n, dim), Some(f));
            }
        }
    }

    /// Small changes of n give small changes of the tangents (away from switch points).
    #[test]
    fn tangents_continuous_locally() {
        let mut rng = StdRng::seed_from_u64(4);
        for _ in 0..300 {
            let n = [0.0; 3].map(|_: f64| rng.gen_range(-1.0..1.0));
            let a = n.map(f64::abs);
            let mut s = a;
            s.sort_by(f64::total_cmp);
            if s[1] - s[0] < 1e-3 || s[2] < 1e-2 {
                continue; // near a switch of the smallest component, or degenerate
            }
            let f = Frame::new(n, 3).unwrap();
            let m = n.map(|x| x + 1e-7 * rng.gen_range(-1.0..1.0));
            let g = Frame::new(m, 3).unwrap();
            for i in 0..2 {
                for k in 0..3 {
                    assert!((f.t[i][k] - g.t[i][k]).abs() < 1e-4);
                }
            }
        }
    }
}
