//! Tiny dense linear algebra on `[f64; M]` / `[[f64; M]; M]` (M = d−1 = 1 or 2, but
//! written for any M). Matrices are row-major: `a[i][j]` is row i, column j.

/// Euclidean inner product.
pub fn dot<const M: usize>(a: &[f64; M], b: &[f64; M]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Euclidean norm.
pub fn norm<const M: usize>(a: &[f64; M]) -> f64 {
    dot(a, a).sqrt()
}

/// a + s·b
pub fn axpy<const M: usize>(a: &[f64; M], s: f64, b: &[f64; M]) -> [f64; M] {
    let mut r = *a;
    for (ri, bi) in r.iter_mut().zip(b) {
        *ri += s * bi;
    }
    r
}

/// s·a
pub fn scale<const M: usize>(s: f64, a: &[f64; M]) -> [f64; M] {
    a.map(|x| s * x)
}

/// The M×M identity.
pub fn identity<const M: usize>() -> [[f64; M]; M] {
    let mut r = [[0.0; M]; M];
    for (i, row) in r.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    r
}

/// a bᵀ
pub fn outer<const M: usize>(a: &[f64; M], b: &[f64; M]) -> [[f64; M]; M] {
    let mut r = [[0.0; M]; M];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = a[i] * b[j];
        }
    }
    r
}

/// A x
pub fn matvec<const M: usize>(a: &[[f64; M]; M], x: &[f64; M]) -> [f64; M] {
    let mut r = [0.0; M];
    for (ri, row) in r.iter_mut().zip(a) {
        *ri = dot(row, x);
    }
    r
}

/// A B
#[cfg(test)]
pub fn matmul<const M: usize>(a: &[[f64; M]; M], b: &[[f64; M]; M]) -> [[f64; M]; M] {
    let mut r = [[0.0; M]; M];
    for i in 0..M {
        for j in 0..M {
            r[i][j] = (0..M).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    r
}

/// s_a·A + s_b·B
pub fn mat_lin<const M: usize>(
    sa: f64,
    a: &[[f64; M]; M],
    sb: f64,
    b: &[[f64; M]; M],
) -> [[f64; M]; M] {
    let mut r = [[0.0; M]; M];
    for i in 0..M {
        for j in 0..M {
            r[i][j] = sa * a[i][j] + sb * b[i][j];
        }
    }
    r
}

/// Largest absolute entry.
pub fn max_abs<const M: usize>(a: &[[f64; M]; M]) -> f64 {
    a.iter()
        .flat_map(|r| r.iter())
        .fold(0.0_f64, |m, x| m.max(x.abs()))
}

/// Inverse by Gauss–Jordan elimination with partial pivoting. `None` when a pivot is
/// below `rel_tol` times the largest entry of `a` (numerically singular) or not finite.
pub fn inverse<const M: usize>(a: &[[f64; M]; M], rel_tol: f64) -> Option<[[f64; M]; M]> {
    let scale = max_abs(a);
    if !scale.is_finite() || scale == 0.0 {
        return None;
    }
    let mut w = *a;
    let mut inv = identity::<M>();
    for col in 0..M {
        let piv = (col..M).max_by(|&i, &j| w[i][col].abs().total_cmp(&w[j][col].abs()))?;
        let pv = w[piv][col].abs();
        if pv.is_nan() || pv <= rel_tol * scale {
            return None;
        }
        w.swap(col, piv);
        inv.swap(col, piv);
        let p = w[col][col];
        for j in 0..M {
            w[col][j] /= p;
            inv[col][j] /= p;
        }
        for i in 0..M {
            if i != col {
                let f = w[i][col];
                if f != 0.0 {
                    for j in 0..M {
                        w[i][j] -= f * w[col][j];
                        inv[i][j] -= f * inv[col][j];
                    }
                }
            }
        }
    }
    Some(inv)
}

/// Eigenvalues of a real 2×2 matrix as (re, im) pairs, from trace and determinant.
#[cfg(test)]
pub fn eig2(a: &[[f64; 2]; 2]) -> [(f64, f64); 2] {
    let t = a[0][0] + a[1][1];
    let d = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    let disc = t * t / 4.0 - d;
    if disc >= 0.0 {
        let s = disc.sqrt();
        [(t / 2.0 - s, 0.0), (t / 2.0 + s, 0.0)]
    } else {
        let s = (-disc).sqrt();
        [(t / 2.0, -s), (t / 2.0, s)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    #[test]
    fn inverse_times_matrix_is_identity() {
        let mut rng = StdRng::seed_from_u64(11);
        for _ in 0..200 {
            let a: [[f64; 2]; 2] = [
                [rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0)],
                [rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0)],
            ];
            let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            if det.abs() < 1e-3 {
                continue;
            }
            let inv = inverse(&a, 1e-13).expect("regular");
            let p = matmul(&a, &inv);
            let id = identity::<2>();
            assert!(max_abs(&mat_lin(1.0, &p, -1.0, &id)) < 1e-10);
            // compare with the explicit 2x2 formula
            assert!((inv[0][0] - a[1][1] / det).abs() < 1e-9 * (1.0 + inv[0][0].abs()));
        }
        assert!(inverse(&[[1.0, 2.0], [2.0, 4.0]], 1e-13).is_none());
        assert!(inverse(&[[0.0]], 1e-13).is_none());
        assert_eq!(inverse(&[[4.0]], 1e-13), Some([[0.25]]));
    }

    #[test]
    fn eig2_of_triangular_and_rotation() {
        let e = eig2(&[[2.0, 5.0], [0.0, -1.0]]);
        assert_eq!(e, [(-1.0, 0.0), (2.0, 0.0)]);
        let e = eig2(&[[0.0, -1.0], [1.0, 0.0]]);
        assert!((e[0].1 + 1.0).abs() < 1e-15 && (e[1].1 - 1.0).abs() < 1e-15);
    }
}
