//! Cell stresses of P1 solutions and equivalent (von Mises) stresses.

// Index loops mirror the tensor formulas (sums over i, j, a, b).
#![allow(clippy::needless_range_loop)]

use super::element::{tet_gradients, tri_gradients};
use super::{Material, Model};

/// Hooke's law sigma = lambda tr(eps) I + 2 mu eps (thesis ch. 1, with (1.25)) for the
/// constant strain of a P1 cell, returned as a full 3x3 tensor.
///
/// `x` holds dim+1 points (z ignored in 2D), `u` the (dim+1)*dim nodal displacements,
/// node-major. In 2D the in-plane block uses the model's Lamé parameters; sigma_zz is
/// lambda tr(eps) for plane strain (eps_zz = 0) and 0 for plane stress; sigma_xz = sigma_yz = 0.
/// A degenerate cell gives zero stress.
///
/// Panics if the slice lengths do not match the model's dimension (a programming error).
pub fn cell_stress(mat: &Material, x: &[[f64; 3]], u: &[f64]) -> [[f64; 3]; 3] {
    let dim = mat.model.dim();
    assert_eq!(x.len(), dim + 1, "cell_stress: expected {} points", dim + 1);
    assert_eq!(
        u.len(),
        (dim + 1) * dim,
        "cell_stress: wrong number of values"
    );
    let (lambda, mu) = mat.lame();
    // Displacement gradient H[i][j] = d u_i / d x_j.
    let mut h = [[0.0; 3]; 3];
    if dim == 2 {
        let xt = [[x[0][0], x[0][1]], [x[1][0], x[1][1]], [x[2][0], x[2][1]]];
        let (g, _) = tri_gradients(&xt);
        for (a, ga) in g.iter().enumerate() {
            for i in 0..2 {
                for j in 0..2 {
                    h[i][j] += u[2 * a + i] * ga[j];
                }
            }
        }
    } else {
        let xt = [x[0], x[1], x[2], x[3]];
        let (g, _) = tet_gradients(&xt);
        for (a, ga) in g.iter().enumerate() {
            for i in 0..3 {
                for j in 0..3 {
                    h[i][j] += u[3 * a + i] * ga[j];
                }
            }
        }
    }
    let mut s = [[0.0; 3]; 3];
    let tr = h[0][0] + h[1][1] + h[2][2];
    for i in 0..dim {
        for j in 0..dim {
            s[i][j] = mu * (h[i][j] + h[j][i]);
        }
        s[i][i] += lambda * tr;
    }
    if mat.model == Model::PlaneStrain {
        s[2][2] = lambda * tr;
    }
    s
}

/// Standard von Mises stress sqrt(3/2 s':s') of the full 3x3 tensor, s' = s - tr(s)/3 I.
/// Uniaxial stress s gives |s|, pure shear t gives sqrt(3)|t|.
pub fn von_mises(s: &[[f64; 3]; 3]) -> f64 {
    let p = (s[0][0] + s[1][1] + s[2][2]) / 3.0;
    let mut sum = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let d = s[i][j] - if i == j { p } else { 0.0 };
            sum += d * d;
        }
    }
    (1.5 * sum).sqrt()
}

/// (4.1): the thesis' effective stress sigma_eff^2 = sum_{i,j=1..d} |sigma_ij - delta_ij p|^2
/// with p = (1/d) sum_{i=1..d} sigma_ii, summed over the in-plane d x d block only
/// (d = `dim`; sigma_zz is ignored in 2D). Note the missing factor 3/2 of von Mises.
pub fn von_mises_thesis(s: &[[f64; 3]; 3], dim: usize) -> f64 {
    let d = dim.min(3);
    let mut p = 0.0;
    for (i, row) in s.iter().enumerate().take(d) {
        p += row[i];
    }
    p /= d as f64;
    let mut sum = 0.0;
    for i in 0..d {
        for j in 0..d {
            let v = s[i][j] - if i == j { p } else { 0.0 };
            sum += v * v;
        }
    }
    sum.sqrt()
}
