//! P1 (constant strain) element kernels: gradients of the barycentric shape functions and
//! element stiffness matrices. No heap allocation: everything lives in fixed arrays.

// Index loops mirror the tensor formulas (sums over i, j, a, b).
#![allow(clippy::needless_range_loop)]

use crate::geom::{cross, dot, sub};

/// Gradients of the three P1 shape functions of a triangle, and its SIGNED area
/// (positive when the nodes run counter-clockwise).
///
/// A degenerate triangle (area exactly 0) gives zero gradients and area 0; callers must
/// check the returned measure (the mesh reader rejects such cells).
#[inline]
pub fn tri_gradients(x: &[[f64; 2]; 3]) -> ([[f64; 2]; 3], f64) {
    let (x10, y10) = (x[1][0] - x[0][0], x[1][1] - x[0][1]);
    let (x20, y20) = (x[2][0] - x[0][0], x[2][1] - x[0][1]);
    let det = x10 * y20 - x20 * y10;
    if det == 0.0 {
        return ([[0.0; 2]; 3], 0.0);
    }
    let inv = 1.0 / det;
    // Rows of J^{-T}: grad phi_1 = (y20, -x20)/det, grad phi_2 = (-y10, x10)/det.
    let g1 = [y20 * inv, -x20 * inv];
    let g2 = [-y10 * inv, x10 * inv];
    let g0 = [-g1[0] - g2[0], -g1[1] - g2[1]];
    ([g0, g1, g2], 0.5 * det)
}

/// Gradients of the four P1 shape functions of a tetrahedron, and its SIGNED volume
/// (positive when (x1-x0, x2-x0, x3-x0) is a right-handed frame).
///
/// A degenerate tetrahedron (volume exactly 0) gives zero gradients and volume 0.
#[inline]
pub fn tet_gradients(x: &[[f64; 3]; 4]) -> ([[f64; 3]; 4], f64) {
    let e1 = sub(x[1], x[0]);
    let e2 = sub(x[2], x[0]);
    let e3 = sub(x[3], x[0]);
    let c23 = cross(e2, e3);
    let det = dot(e1, c23);
    if det == 0.0 {
        return ([[0.0; 3]; 4], 0.0);
    }
    let inv = 1.0 / det;
    // grad phi_k (k = 1, 2, 3) are the rows of J^{-1}, J = [e1 e2 e3]:
    // e2 x e3 / det, e3 x e1 / det, e1 x e2 / det.
    let c31 = cross(e3, e1);
    let c12 = cross(e1, e2);
    let mut g = [[0.0; 3]; 4];
    for i in 0..3 {
        g[1][i] = c23[i] * inv;
        g[2][i] = c31[i] * inv;
        g[3][i] = c12[i] * inv;
        g[0][i] = -(g[1][i] + g[2][i] + g[3][i]);
    }
    (g, det / 6.0)
}

/// Bilinear form a(u, v) = ∫ lambda div u div v + 2 mu eps(u):eps(v) (the stiffness of (3.8))
/// on a constant-gradient cell of measure `w`, the `D` rows of node `a` only:
/// rows[i][b D + j] = K[(a,i),(b,j)]
/// = w (lambda g_a[i] g_b[j] + mu g_a[j] g_b[i] + mu delta_ij g_a·g_b).
/// The full element matrix is these rows for a = 0..N, so both give the same numbers bit for
/// bit.
#[inline(always)]
pub fn p1_stiffness_rows<const D: usize, const N: usize>(
    g: &[[f64; D]; N],
    w: f64,
    lambda: f64,
    mu: f64,
    a: usize,
    rows: &mut [[f64; 12]; 3],
) {
    let wl = w * lambda;
    let wm = w * mu;
    for b in 0..N {
        let k = p1_stiffness_block::<D>(&g[a], &g[b], wl, wm);
        for i in 0..D {
            rows[i][b * D..b * D + D].copy_from_slice(&k[i]);
        }
    }
}

/// One D×D block of the stiffness of (3.8) on a constant-gradient cell, between nodes a and b
/// (gradients `ga`, `gb`; `wl` = w lambda, `wm` = w mu):
/// K[(a,i),(b,j)] = wl g_a[i] g_b[j] + wm g_a[j] g_b[i] + wm delta_ij g_a·g_b.
#[inline(always)]
pub fn p1_stiffness_block<const D: usize>(
    ga: &[f64; D],
    gb: &[f64; D],
    wl: f64,
    wm: f64,
) -> [[f64; D]; D] {
    let mut dot = 0.0;
    for i in 0..D {
        dot += ga[i] * gb[i];
    }
    let mut k = [[0.0; D]; D];
    for i in 0..D {
        for j in 0..D {
            let mut v = wl * ga[i] * gb[j] + wm * ga[j] * gb[i];
            if i == j {
                v += wm * dot;
            }
            k[i][j] = v;
        }
    }
    k
}

/// The full element matrix (row-major (N D)²) from [`p1_stiffness_rows`].
#[inline(always)]
fn p1_stiffness<const D: usize, const N: usize>(
    g: &[[f64; D]; N],
    w: f64,
    lambda: f64,
    mu: f64,
    k: &mut [f64],
) {
    let ndof = N * D;
    let k = &mut k[..ndof * ndof]; // fixed length: lets the compiler drop bounds checks
    let mut rows = [[0.0; 12]; 3];
    for a in 0..N {
        p1_stiffness_rows::<D, N>(g, w, lambda, mu, a, &mut rows);
        for i in 0..D {
            let row = (a * D + i) * ndof;
            k[row..row + ndof].copy_from_slice(&rows[i][..ndof]);
        }
    }
}

/// (3.8): P1 triangle stiffness matrix (row-major 6x6), dofs node-major
/// (x0, y0, x1, y1, x2, y2). Use the Lamé parameters of the model from
/// [`crate::fem::Material::lame`] (plane stress is the plane law with its own lambda).
/// Returns the signed area; the matrix uses its absolute value.
pub fn tri_stiffness(x: &[[f64; 2]; 3], lambda: f64, mu: f64, k: &mut [f64; 36]) -> f64 {
    let (g, area) = tri_gradients(x);
    p1_stiffness::<2, 3>(&g, area.abs(), lambda, mu, k);
    area
}

/// (3.8): P1 tetrahedron stiffness matrix (row-major 12x12), dofs node-major
/// (x0, y0, z0, x1, ...). Returns the signed volume; the matrix uses its absolute value.
pub fn tet_stiffness(x: &[[f64; 3]; 4], lambda: f64, mu: f64, k: &mut [f64; 144]) -> f64 {
    let (g, vol) = tet_gradients(x);
    p1_stiffness::<3, 4>(&g, vol.abs(), lambda, mu, k);
    vol
}
