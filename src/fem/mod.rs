//! P1 finite elements: material laws, element stiffness matrices, loads, stresses.
//!
//! Dofs are node-major (x0, y0, x1, y1, …); (1.25) gives the Lamé constants of each model.

mod element;
mod load;
mod stress;

#[cfg(test)]
mod tests;

pub use element::{
    p1_stiffness_block, p1_stiffness_rows, tet_gradients, tet_stiffness, tri_gradients,
    tri_stiffness,
};
pub use load::{
    body_force_load, cell_load_quadrature, facet_normal_measure, lumped_facet_load,
    simplex_measure, simplex_quadrature, QuadPoint,
};
pub use stress::{cell_stress, von_mises, von_mises_thesis};

/// Kinematic model of the body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// 2D, eps_zz = 0.
    PlaneStrain,
    /// 2D, sigma_zz = 0.
    PlaneStress,
    /// 3D.
    Solid,
}

impl Model {
    /// Spatial dimension of the model: 2 for plane strain / plane stress, 3 for solids.
    pub fn dim(self) -> usize {
        match self {
            Model::PlaneStrain | Model::PlaneStress => 2,
            Model::Solid => 3,
        }
    }
}

/// Isotropic linear-elastic material (Hooke's law, thesis ch. 1).
#[derive(Clone, Copy, Debug)]
pub struct Material {
    /// Young's modulus E.
    pub young: f64,
    /// Poisson's ratio nu.
    pub poisson: f64,
    pub model: Model,
}

impl Material {
    /// (1.25): Lamé parameters (lambda, mu) effective for the model.
    ///
    /// Plane strain and 3D: lambda = E nu / ((1+nu)(1-2nu)); plane stress:
    /// lambda = E nu / (1 - nu^2) (the in-plane law with sigma_zz = 0); mu = E / (2(1+nu)).
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.young, self.poisson);
        let mu = e / (2.0 * (1.0 + nu));
        let lambda = match self.model {
            Model::PlaneStrain | Model::Solid => e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            Model::PlaneStress => e * nu / (1.0 - nu * nu),
        };
        (lambda, mu)
    }

    /// The contact modulus E* = E / (1 − ν²) (3D, plane strain) or E (plane stress): the
    /// half-space model's.
    pub fn contact_modulus(&self) -> f64 {
        let (e, nu) = (self.young, self.poisson);
        match self.model {
            Model::PlaneStress => e,
            Model::PlaneStrain | Model::Solid => e / (1.0 - nu * nu),
        }
    }
}

/// The materials of a body: one or several (one per volume group of the mesh), all of one
/// model, and the material of every local cell. The Lamé constants (1.25) of each material
/// are computed once; a cell finds its own by a small index (no lookup by name).
#[derive(Clone, Debug)]
pub struct Materials {
    /// At least one; every entry has the model `model`.
    pub list: Vec<Material>,
    pub model: Model,
    /// Per local cell: its material's index into `list`; empty when there is one material.
    cell: std::sync::Arc<[u16]>,
    /// (λ, μ) of every entry of `list`.
    lame: Vec<(f64, f64)>,
    /// The entry whose modulus the single-modulus estimates use (the contact predictor's
    /// half-space model, the default Newton parameter c = 100 E h_c^(d−2)).
    pub reference: usize,
    /// The contact modulus of the half-space model: the reference entry's, or with contact
    /// between bodies the two sides' in series (crate::setup); `None`: the reference's.
    pub half_space: Option<f64>,
    /// With contact between bodies: the largest ratio of a pair's slave-side to master-side
    /// contact modulus (crate::setup); `None` without body pairs.
    pub slave_over_master: Option<f64>,
}

impl Materials {
    /// One material for every cell.
    pub fn single(m: Material) -> Materials {
        Materials {
            list: vec![m],
            model: m.model,
            cell: std::sync::Arc::from(Vec::new()),
            lame: vec![m.lame()],
            reference: 0,
            half_space: None,
            slave_over_master: None,
        }
    }

    /// Several materials, `cell[c]` the index of cell c's (every index < `list.len()`).
    pub fn per_cell(list: Vec<Material>, cell: Vec<u16>) -> Materials {
        debug_assert!(cell.iter().all(|&i| (i as usize) < list.len()));
        Materials {
            model: list[0].model,
            lame: list.iter().map(Material::lame).collect(),
            list,
            cell: std::sync::Arc::from(cell),
            reference: 0,
            half_space: None,
            slave_over_master: None,
        }
    }

    /// The index of cell c's material.
    #[inline]
    pub fn index(&self, c: usize) -> usize {
        if self.cell.is_empty() {
            0
        } else {
            self.cell[c] as usize
        }
    }

    /// Cell c's material.
    #[inline]
    pub fn of(&self, c: usize) -> &Material {
        &self.list[self.index(c)]
    }

    /// (1.25): cell c's Lamé constants (λ, μ).
    #[inline]
    pub fn lame_of(&self, c: usize) -> (f64, f64) {
        self.lame[self.index(c)]
    }

    /// (1.25): the Lamé constants of every material, by index.
    pub fn lame_table(&self) -> &[(f64, f64)] {
        &self.lame
    }

    /// The material of the single-modulus estimates ([`Materials::reference`]).
    pub fn reference_material(&self) -> &Material {
        &self.list[self.reference]
    }
}

/// Number of rigid-body modes in dimension `dim`: 3 in 2D, 6 in 3D (a test helper: the
/// solver's own rigid modes, centred and scaled, are in `signorini::rigid`).
#[cfg(test)]
pub fn n_rigid_modes(dim: usize) -> usize {
    if dim == 2 {
        3
    } else {
        6
    }
}

/// Rigid-body mode `k` (0-based, `k < n_rigid_modes(dim)`) evaluated at point `x`.
///
/// 2D: k = 0, 1 translations along x, y; k = 2 rotation (-y, x).
/// 3D: k = 0, 1, 2 translations; k = 3, 4, 5 rotations about the x, y, z axes
/// ((0, -z, y), (z, 0, -x), (-y, x, 0)). Unnormalised; the third component is 0 in 2D.
/// Useful as the near-null space of an AMG preconditioner.
#[cfg(test)]
pub fn rigid_mode(dim: usize, k: usize, x: [f64; 3]) -> [f64; 3] {
    let [px, py, pz] = x;
    if dim == 2 {
        match k {
            0 => [1.0, 0.0, 0.0],
            1 => [0.0, 1.0, 0.0],
            2 => [-py, px, 0.0],
            _ => panic!("rigid_mode: k = {k} out of range for dim 2"),
        }
    } else {
        match k {
            0 => [1.0, 0.0, 0.0],
            1 => [0.0, 1.0, 0.0],
            2 => [0.0, 0.0, 1.0],
            3 => [0.0, -pz, py],
            4 => [pz, 0.0, -px],
            5 => [-py, px, 0.0],
            _ => panic!("rigid_mode: k = {k} out of range for dim 3"),
        }
    }
}
