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
