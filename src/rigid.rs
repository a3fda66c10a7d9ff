//! Rigid body modes that neither Dirichlet data nor the active contact set fixes
//! (THEORY.md §5; thesis 4.1, where V*_h removes only the tangential translation).
//!
//! Mechanism: the rigid modes r_1..r_m (m = 3 in 2D, 6 in 3D) are tested against the
//! constraint rows — every Dirichlet dof and the normal row nᵀ of every active contact node —
//! through the m×m Gram matrix G = Σ (C r)ᵀ (C r). Its null space is exactly the set of free
//! modes: no fewer are removed (the system would be singular) and no more (that would change
//! the answer). Each free mode is removed by pinning one dof (its row of the reduced system
//! becomes a_pp u_p = 0, on A's pattern). The pinned dofs are chosen from the whole mesh by a
//! pivoted Gram–Schmidt on the free modes' values, away from the contact boundary and the
//! Dirichlet data, identically on every rank (so the result does not depend on the number of
//! ranks). Pinning selects one member of the family u + Σ α_j r_j, which all have the same
//! strains, stresses and multipliers; if the load is not balanced in a free mode the pins carry
//! a reaction, and a converged state with such a reaction is reported as "no support".

use crate::mesh::Mesh;
use nalgebra::{DMatrix, SymmetricEigen};

/// The rigid modes of a mesh, in coordinates centred and scaled to O(1).
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

    /// Row vector of the constraint nᵀ u at a node at x.
    pub fn normal_row(&self, x: &[f64; 3], n: &[f64; 3]) -> [f64; 6] {
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

    /// Chooses one dof (node, component) per free mode: among the nodes allowed by
    /// `candidate`, greedily the dof whose free-mode values are largest after removing the
    /// directions already pinned (pivoted Gram–Schmidt). Same result on every rank.
    pub fn pins(
        &self,
        mesh: &Mesh,
        q: &DMatrix<f64>,
        candidate: impl Fn(usize) -> bool,
    ) -> Vec<(usize, usize)> {
        let mf = q.ncols();
        if mf == 0 {
            return Vec::new();
        }
        let dim = self.dim;
        // Values of the free modes at every candidate dof.
        let mut dofs: Vec<(usize, usize)> = Vec::new();
        let mut w: Vec<f64> = Vec::new();
        for v in 0..mesh.n_nodes() {
            if !candidate(v) {
                continue;
            }
            for k in 0..dim {
                let row = self.dof_row(&mesh.coords[v], k);
                dofs.push((v, k));
                for c in 0..mf {
                    w.push((0..self.m).map(|j| row[j] * q[(j, c)]).sum());
                }
            }
        }
        let mut chosen = Vec::new();
        for _ in 0..mf {
            let mut best = (0.0f64, usize::MAX);
            for i in 0..dofs.len() {
                let n2: f64 = w[i * mf..(i + 1) * mf].iter().map(|x| x * x).sum();
                if n2 > best.0 * (1.0 + 1e-12) {
                    best = (n2, i);
                }
            }
            if best.1 == usize::MAX || best.0 < 1e-20 {
                break;
            }
            let i = best.1;
            chosen.push(dofs[i]);
            let p: Vec<f64> = w[i * mf..(i + 1) * mf].to_vec();
            let pn = best.0.sqrt();
            let p: Vec<f64> = p.iter().map(|x| x / pn).collect();
            for r in 0..dofs.len() {
                let s: f64 = (0..mf).map(|c| w[r * mf + c] * p[c]).sum();
                for c in 0..mf {
                    w[r * mf + c] -= s * p[c];
                }
            }
        }
        chosen
    }
}
