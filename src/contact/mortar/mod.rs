//! Dual (biorthogonal) mortar coupling of two deformable bodies: the geometric and
//! integration core, for P1 segments (2D) and P1 triangles (3D). Pure functions; no MPI,
//! no PETSc.
//!
//! References: B. I. Wohlmuth, "A mortar finite element method using dual spaces for the
//! Lagrange multiplier", SIAM J. Numer. Anal. 38 (2000); S. Hüeber & B. I. Wohlmuth, "A
//! primal–dual active set strategy for non-linear multibody contact problems", Comput.
//! Methods Appl. Mech. Engrg. 194 (2005); A. Popp, M. Gitterle, M. W. Gee & W. A. Wall,
//! "A dual mortar approach for 3D finite deformation contact with consistent
//! linearization", Int. J. Numer. Methods Engrg. 83 (2010) (projection into the slave
//! facet's plane, polygon clipping, triangulation of the clip polygon); T. Cichosz &
//! M. Bischoff, "Consistent treatment of boundaries with mortar contact formulations
//! using dual Lagrange multipliers", Comput. Methods Appl. Mech. Engrg. 200 (2011) (the
//! dual basis on partially covered slave facets).
//!
//! Notation: slave surface Γs with P1 shape functions φ_k (slave node k), master surface
//! with P1 shape functions φ_j (master node j); π maps a slave point to the master point
//! it faces.
//!
//! - Projection π: per slave facet, along that facet's (constant) unit normal: the
//!   master facet is projected orthogonally onto the slave segment's line (2D) or the slave
//!   triangle's plane (3D), then clipped to the slave facet ([`quad`]). φ_j ∘ π is then
//!   affine on each clipped piece, so all integrands below are quadratic and the rules
//!   used (2-point Gauss per interval; the 3-point degree-2 rule on a fan of triangles
//!   from the clip polygon's vertex average) are exact.
//! - Dual basis ψ_k ([`dual`]): on each slave facet ψ_i = Σ_l A_il φ_l, biorthogonal on
//!   the covered part Ω of the facet: ∫_Ω ψ_i φ_l = δ_il ∫_Ω φ_l, i.e. A = diag(∫_Ω φ_i)
//!   G⁻¹ with the Gram matrix G_il = ∫_Ω φ_i φ_l. On a fully covered facet this is the
//!   usual dual basis, the same on every facet in reference coordinates: segment
//!   ψ_1 = 2φ_1 − φ_2, ψ_2 = 2φ_2 − φ_1; triangle ψ_i = 4φ_i − 1 (= 3φ_i − Σ_{l≠i} φ_l).
//!   On a partially covered facet (the edge of the contact zone) it keeps D positive and
//!   constants and linear fields reproduced exactly (Cichosz & Bischoff 2011).
//! - D_kk = ∫_Ω ψ_k φ_k ds = ∫_Ω φ_k ds (lumped; > 0 for every covered node), summed over
//!   the slave facets around k, Ω their covered parts. Only covered parts are integrated:
//!   a slave node whose facets no master facet covers has D_kk = 0 and no M entries.
//! - M_kj = ∫_Ω ψ_k (φ_j ∘ π) ds; Σ_j M_kj = D_kk always, and Σ_j M_kj x_j = D_kk x_k when
//!   slave and master facets lie in one line/plane.
//! - g̃_k = ∫_Ω ψ_k n_k · (x_master ∘ π − x) ds = n_k · (Σ_j M_kj x_j − D_kk x_k) (the two
//!   agree by biorthogonality on Ω), n_k the unit slave nodal normal (outward from the slave
//!   body; by default the area-weighted average of the facet normals,
//!   [`Surface::nodal_normals`]). Sign: g̃_k > 0 when the bodies are apart, < 0 when they
//!   penetrate; a uniform gap δ gives g̃_k = D_kk δ.
//!
//! Robustness: master facets are found with an R-tree of their bounding boxes
//! ([`search`], O(n log n)); overlaps of measure ≤ 1e-14 × the slave facet's measure and
//! master facets seen edge-on are dropped; a covered part too thin for a dual basis
//! (scaled Gram determinant < 1e-10) is dropped with its facet. The master surface should
//! not fold over itself as seen from a slave facet (its projections must not overlap).

pub mod assemble;
pub mod dual;
pub mod geom;
pub mod quad;
pub mod search;
pub mod surface;
#[cfg(test)]
mod test_util;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_more;

pub use assemble::{assemble, assemble_with_normals, Mortar, MortarOptions, MortarRow};
pub use surface::{MortarError, Orientation, Surface};
