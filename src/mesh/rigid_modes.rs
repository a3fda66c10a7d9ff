//! The rigid modes of a mesh (3 in 2D, 6 in 3D), in coordinates centred on the whole mesh's
//! bounding box and scaled to O(1): their values at a point, the rows of constraints on them and
//! the Gram matrices of such rows (the contact solver's free modes, signorini/rigid.rs; the
//! bodies of a mesh, bodies.rs).

use super::Mesh;
use nalgebra::{DMatrix, SymmetricEigen};

/// The rigid modes of a mesh, in coordinates centred and scaled to O(1).
#[derive(Clone, Debug)]
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
        self.weighted_value(j, 1.0, x, k)
    }

    /// Σ_i s_i r_j(x_i), component k, from s = Σ_i s_i and the moment X = Σ_i s_i x_i (r_j is
    /// affine); s = 1, X = x gives the value at x.
    #[inline]
    pub fn weighted_value(&self, j: usize, s: f64, moment: &[f64; 3], k: usize) -> f64 {
        if j < self.dim {
            return if j == k { s } else { 0.0 };
        }
        let y = [0, 1, 2].map(|i| (moment[i] - s * self.center[i]) / self.scale);
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
        null_space(self.m, g)
    }
}

/// The null space of the n × n symmetric positive semidefinite `g` (row-major): the
/// eigenvectors of eigenvalues below 1e-9 of the largest (or of 1), as orthonormal columns.
fn null_space(n: usize, g: &[f64]) -> DMatrix<f64> {
    if n == 0 {
        return DMatrix::zeros(0, 0);
    }
    let gm = DMatrix::from_row_slice(n, n, &g[..n * n]);
    let eig = SymmetricEigen::new(gm);
    let lmax = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let tol = 1e-9 * lmax.max(1.0);
    let cols: Vec<usize> = (0..n).filter(|&i| eig.eigenvalues[i] < tol).collect();
    let mut q = DMatrix::zeros(n, cols.len());
    for (c, &i) in cols.iter().enumerate() {
        q.set_column(c, &eig.eigenvectors.column(i));
    }
    q
}

/// A body's slot in [`BodyModes`] where the body has none: its Dirichlet data hold it, or the
/// node lies in no local cell.
pub const NO_SLOT: u32 = u32::MAX;

/// The master side a slave node of a body pair faces, one per body there: the sum of the
/// mortar weights s = Σ_j m_kj over that body's master nodes j and their moment
/// X = Σ_j m_kj x_j. A rigid mode r of that body moves the master side by Σ_j m_kj r(x_j),
/// which s and X give (r is affine).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Part {
    pub slot: u32,
    pub weight: f64,
    pub moment: [f64; 3],
}

/// The rigid modes of the bodies that Dirichlet data leave free in some mode (m per body, in
/// the order of the bodies' first node tags: the same on every rank), as the contact solver's
/// unknowns see them. A body's mode moves its nodes rigidly (in coordinates centred on the
/// body's bounding box and scaled to O(1)); in the unknowns of a body pair's slave node,
/// w_k = u_k − Σ_j m_kj u_j (crate::mortar), a mode of the master body moves w_k by
/// −Σ_j m_kj r(x_j). Mode i = slot · m + j is mode j of the body in `slot`.
#[derive(Clone, Debug)]
pub struct BodyModes {
    pub dim: usize,
    /// Modes per body: 3 in 2D, 6 in 3D.
    pub m: usize,
    /// Per slot: the body's centre and scale.
    shapes: Vec<RigidModes>,
    /// Per body: its slot, or [`NO_SLOT`] (held by its Dirichlet data).
    slot_of_body: Vec<u32>,
    /// Per local mesh node: its body (`u32::MAX`: none), held or not.
    body: Vec<u32>,
    /// Per local slave node of a body pair (mesh node index): the master side it faces.
    faces: std::collections::HashMap<usize, Vec<Part>>,
}

impl BodyModes {
    /// The whole mesh as one body in slot 0 (a mesh without a body survey).
    pub fn whole(mesh: &Mesh) -> BodyModes {
        let shape = RigidModes::new(mesh);
        BodyModes {
            dim: shape.dim,
            m: shape.m,
            shapes: vec![shape],
            slot_of_body: vec![0],
            body: vec![0; mesh.n_nodes()],
            faces: Default::default(),
        }
    }

    /// No modes (every body held), in `dim` dimensions.
    pub fn none(dim: usize) -> BodyModes {
        BodyModes {
            dim,
            m: if dim == 2 { 3 } else { 6 },
            shapes: Vec::new(),
            slot_of_body: Vec::new(),
            body: Vec::new(),
            faces: Default::default(),
        }
    }

    /// Slots for the bodies with `boxes[b] = Some((lo, hi))` (their bounding boxes), `None`
    /// for held bodies; `body_of[v]` the body of local node v (`u32::MAX`: none). Local.
    pub fn new(mesh: &Mesh, body_of: &[u32], boxes: &[Option<([f64; 3], [f64; 3])>]) -> BodyModes {
        let dim = mesh.dim;
        let mut slot_of_body = vec![NO_SLOT; boxes.len()];
        let mut shapes = Vec::new();
        for (b, bx) in boxes.iter().enumerate() {
            if let Some((lo, hi)) = bx {
                slot_of_body[b] = shapes.len() as u32;
                let scale = (0..dim)
                    .map(|k| hi[k] - lo[k])
                    .fold(0.0f64, f64::max)
                    .max(f64::MIN_POSITIVE);
                shapes.push(RigidModes {
                    dim,
                    m: if dim == 2 { 3 } else { 6 },
                    center: [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k])),
                    scale,
                });
            }
        }
        BodyModes {
            dim,
            m: if dim == 2 { 3 } else { 6 },
            shapes,
            slot_of_body,
            body: body_of.to_vec(),
            faces: Default::default(),
        }
    }

    /// The number of modes, m per slot.
    pub fn count(&self) -> usize {
        self.m * self.shapes.len()
    }

    /// The rigid modes of one body (3 in 2D, 6 in 3D).
    pub fn per_body(&self) -> usize {
        self.m
    }

    /// The slots (bodies with modes).
    pub fn slots(&self) -> usize {
        self.shapes.len()
    }

    /// The number of bodies (held or not).
    pub fn bodies(&self) -> usize {
        self.slot_of_body.len()
    }

    /// The body of local node v (`u32::MAX`: none).
    pub fn body_of(&self, v: usize) -> u32 {
        self.body.get(v).copied().unwrap_or(u32::MAX)
    }

    /// The slot of local node v.
    pub fn slot_of(&self, v: usize) -> u32 {
        let body = self.body_of(v) as usize;
        self.slot_of_body.get(body).copied().unwrap_or(NO_SLOT)
    }

    /// Records the master side that slave node v faces.
    pub fn set_faces(&mut self, v: usize, parts: Vec<Part>) {
        if parts.is_empty() {
            self.faces.remove(&v);
        } else {
            self.faces.insert(v, parts);
        }
    }

    /// The master side that local node v faces (empty off body pairs).
    pub fn faces(&self, v: usize) -> &[Part] {
        self.faces.get(&v).map_or(&[], Vec::as_slice)
    }

    /// `out[i] += cᵀ Σ_l s_l r_i(x_l)` for the modes i of `slot`, from s = Σ_l s_l and the
    /// moment X = Σ_l s_l x_l ([`RigidModes::weighted_value`]).
    fn add_at(&self, slot: u32, s: f64, moment: &[f64; 3], c: &[f64; 3], out: &mut [f64]) {
        let Some(shape) = self.shapes.get(slot as usize) else {
            return;
        };
        let base = slot as usize * self.m;
        for j in 0..self.m {
            out[base + j] += (0..self.dim)
                .map(|k| c[k] * shape.weighted_value(j, s, moment, k))
                .sum::<f64>();
        }
    }

    /// Row vector (over all modes) of the constraint cᵀ w at local node v at x (c a
    /// direction: a normal, a tangent or a unit vector).
    pub fn direction_row(&self, v: usize, x: &[f64; 3], c: &[f64; 3]) -> Vec<f64> {
        let mut r = self.row_of_slot(self.slot_of(v), x, c);
        for p in self.faces(v) {
            self.add_at(p.slot, -p.weight, &p.moment.map(|x| -x), c, &mut r);
        }
        r
    }

    /// Row vector of the constraint cᵀ u at a point x of the body in `slot` (off body pairs'
    /// slave nodes).
    pub fn row_of_slot(&self, slot: u32, x: &[f64; 3], c: &[f64; 3]) -> Vec<f64> {
        let mut r = vec![0.0; self.count()];
        self.add_at(slot, 1.0, x, c, &mut r);
        r
    }

    /// Row vector of the constraint "component k of local node v at x".
    pub fn dof_row(&self, v: usize, x: &[f64; 3], k: usize) -> Vec<f64> {
        let mut e = [0.0; 3];
        e[k] = 1.0;
        self.direction_row(v, x, &e)
    }

    /// Component k of the motion with mode coefficients `rho` at local node v at x.
    pub fn motion_at(&self, rho: &[f64], v: usize, x: &[f64; 3], k: usize) -> f64 {
        let row = self.dof_row(v, x, k);
        row.iter().zip(rho).map(|(a, b)| a * b).sum()
    }

    /// Zeroes the rotation entries of a vector over the modes, keeping each body's
    /// translations.
    pub fn keep_translations(&self, v: &mut [f64]) {
        for (i, x) in v.iter_mut().enumerate() {
            if i % self.m >= self.dim {
                *x = 0.0;
            }
        }
    }

    /// Adds rowᵀ row to the M × M Gram matrix `g` (row-major), over the row's nonzeros.
    pub fn add_outer(&self, g: &mut [f64], row: &[f64]) {
        let n = self.count();
        let nz: Vec<usize> = (0..n).filter(|&i| row[i] != 0.0).collect();
        for &a in &nz {
            for &b in &nz {
                g[a * n + b] += row[a] * row[b];
            }
        }
    }

    /// A zero Gram matrix.
    pub fn zero_gram(&self) -> Vec<f64> {
        vec![0.0; self.count() * self.count()]
    }

    /// Free modes from the global Gram matrix: an M × m_f basis (columns, orthonormal).
    pub fn free_modes(&self, g: &[f64]) -> DMatrix<f64> {
        null_space(self.count(), g)
    }
}
