//! The rigid modes of a mesh (3 in 2D, 6 in 3D), in coordinates centred on the whole mesh's
//! bounding box and scaled to O(1): their values at a point, the rows of constraints on them and
//! the Gram matrices of such rows (the contact solver's free modes, signorini/rigid.rs; the
//! bodies of a mesh, bodies.rs).

use super::Mesh;
use nalgebra::{DMatrix, SymmetricEigen};

/// The rigid modes of a mesh, in coordinates centred and scaled to O(1).
#[derive(Clone)]
pub struct RigidModes {
    pub dim: usize,
    pub m: usize,
    center: [f64; 3],
    scale: f64,
}

impl RigidModes {
    pub fn new(mesh: &Mesh) -> RigidModes {
        let dim = mesh.dim;
        let (lo, hi) = mesh.bounding_box();
        let center = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
        let scale = mesh.extent();
        RigidModes {
            dim,
            m: if dim == 2 { 3 } else { 6 },
            center,
            scale,
        }
    }

    /// Value of mode j at point x, component k.
    #[inline]
    pub fn value(&self, j: usize, x: &[f64; 3], k: usize) -> f64 {
        let y = [0, 1, 2].map(|i| (x[i] - self.center[i]) / self.scale);
        if j < self.dim {
            return if j == k { 1.0 } else { 0.0 };
        }
        if self.dim == 2 {
            // rotation (−y, x)
            return match k {
                0 => -y[1],
                1 => y[0],
                _ => 0.0,
            };
        }
        // 3D rotations e_a × y for a = j − 3
        let a = j - 3;
        let e = [0, 1, 2].map(|i| if i == a { 1.0 } else { 0.0 });
        let c = [
            e[1] * y[2] - e[2] * y[1],
            e[2] * y[0] - e[0] * y[2],
            e[0] * y[1] - e[1] * y[0],
        ];
        c[k]
    }

    /// Row vector (over modes) of the constraint "component k of node at x".
    pub fn dof_row(&self, x: &[f64; 3], k: usize) -> [f64; 6] {
        let mut r = [0.0; 6];
        for (j, rj) in r.iter_mut().enumerate().take(self.m) {
            *rj = self.value(j, x, k);
        }
        r
    }

    /// Row vector of the constraint cᵀ u at a node at x (c a normal or a tangent).
    pub fn direction_row(&self, x: &[f64; 3], n: &[f64; 3]) -> [f64; 6] {
        let mut r = [0.0; 6];
        for (j, rj) in r.iter_mut().enumerate().take(self.m) {
            *rj = (0..self.dim).map(|k| n[k] * self.value(j, x, k)).sum();
        }
        r
    }

    /// Adds rowᵀ row to the packed m×m Gram matrix `g` (row-major, 36 entries).
    pub fn add_outer(&self, g: &mut [f64], row: &[f64; 6]) {
        for a in 0..self.m {
            for b in 0..self.m {
                g[a * self.m + b] += row[a] * row[b];
            }
        }
    }

    /// Free modes from the global Gram matrix: an m × m_f basis (columns, orthonormal).
    pub fn free_modes(&self, g: &[f64]) -> DMatrix<f64> {
        let m = self.m;
        let gm = DMatrix::from_row_slice(m, m, &g[..m * m]);
        let eig = SymmetricEigen::new(gm);
        let lmax = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        let tol = 1e-9 * lmax.max(1.0);
        let cols: Vec<usize> = (0..m).filter(|&i| eig.eigenvalues[i] < tol).collect();
        let mut q = DMatrix::zeros(m, cols.len());
        for (c, &i) in cols.iter().enumerate() {
            q.set_column(c, &eig.eigenvectors.column(i));
        }
        q
    }
}
