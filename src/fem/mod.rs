//! P1 finite elements: material laws, element stiffness matrices, loads, stresses.
//!
//! INTERFACE (keep these names):
//!
//! ```ignore
//! #[derive(Clone, Copy, Debug, PartialEq, Eq)] pub enum Model { PlaneStrain, PlaneStress, Solid }
//! #[derive(Clone, Copy, Debug)] pub struct Material { pub young: f64, pub poisson: f64, pub model: Model }
//! impl Material { pub fn lame(&self) -> (f64, f64) }          // (1.25): (lambda, mu) for the model
//! /// P1 triangle stiffness, dofs node-major (x0,y0,x1,y1,x2,y2); returns the area.
//! pub fn tri_stiffness(x: &[[f64; 2]; 3], lambda: f64, mu: f64, k: &mut [f64; 36]) -> f64;
//! /// P1 tetrahedron stiffness, dofs node-major; returns the volume.
//! pub fn tet_stiffness(x: &[[f64; 3]; 4], lambda: f64, mu: f64, k: &mut [f64; 144]) -> f64;
//! /// Constant stress of a P1 cell as a full 3x3 tensor (plane strain: sigma_zz = lambda tr eps;
//! /// plane stress: sigma_zz = 0). `x` has dim+1 points (z ignored in 2D), `u` (dim+1)*dim values.
//! pub fn cell_stress(mat: &Material, x: &[[f64; 3]], u: &[f64]) -> [[f64; 3]; 3];
//! pub fn von_mises(s: &[[f64; 3]; 3]) -> f64;                 // standard, sqrt(3/2 s':s')
//! pub fn von_mises_thesis(s: &[[f64; 3]; 3], dim: usize) -> f64;   // thesis (4.1)
//! ```
//!
//! Additions beyond the interface above:
//!
//! ```ignore
//! impl Model { pub fn dim(self) -> usize }                       // 2, 2, 3
//! impl Material { pub fn validate(&self) -> Result<(), String> } // E > 0, -1 < nu < 1/2
//! pub fn tri_gradients(x: &[[f64; 2]; 3]) -> ([[f64; 2]; 3], f64);  // P1 gradients, signed area
//! pub fn tet_gradients(x: &[[f64; 3]; 4]) -> ([[f64; 3]; 4], f64);  // P1 gradients, signed volume
//! pub fn facet_normal_measure(x: &[[f64; 3]]) -> ([f64; 3], f64);
//! pub fn lumped_facet_load(measure: f64, traction: [f64; 3], dim: usize, out: &mut [f64]);
//! pub fn body_force_load(measure: f64, f: [f64; 3], dim: usize, out: &mut [f64]);
//! pub fn cell_load_quadrature(x: &[[f64; 3]], dim: usize, f: &dyn Fn([f64; 3]) -> [f64; 3], out: &mut [f64]);
//! pub fn simplex_measure(x: &[[f64; 3]], dim: usize) -> f64;
//! pub struct QuadPoint { pub bary: [f64; 4], pub weight: f64 }
//! pub fn simplex_quadrature(nverts: usize) -> &'static [QuadPoint]; // degree-2 exact rules
//! pub fn n_rigid_modes(dim: usize) -> usize;                    // 3 / 6
//! pub fn rigid_mode(dim: usize, k: usize, x: [f64; 3]) -> [f64; 3];
//! ```

mod element;
mod load;
mod stress;

#[cfg(test)]
mod tests;

pub use element::{tet_gradients, tet_stiffness, tri_gradients, tri_stiffness};
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

    /// Checks the parameters: E finite and > 0, nu finite with -1 < nu < 1/2.
    /// The message is meant to be wrapped into an `InputError` by the caller.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.young.is_finite() && self.young > 0.0) {
            return Err(format!(
                "Young's modulus must be finite and positive, got {}",
                self.young
            ));
        }
        if !(self.poisson.is_finite() && self.poisson > -1.0 && self.poisson < 0.5) {
            return Err(format!(
                "Poisson's ratio must satisfy -1 < nu < 0.5, got {}",
                self.poisson
            ));
        }
        Ok(())
    }
}

/// Number of rigid-body modes in dimension `dim`: 3 in 2D, 6 in 3D.
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
