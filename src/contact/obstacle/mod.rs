//! Rigid obstacles Ψ (thesis ch. 1, (1.43d), (3.3)): closest point, frame normal and
//! initial gap g0 for a point x of the contact boundary.
//!
//! All points are `[f64; 3]` (mesh coordinates; z = 0 in 2D). An obstacle knows its
//! dimension: in 2D the z components of the obstacle data must be 0 (else an error) and
//! the z component of a queried point is ignored.
//!
//! Conventions (THEORY §1): the normal n at x is the obstacle's normal at the closest
//! point, pointing INTO the body; g0(x) = (x − closest)·n, the signed normal distance,
//! ≥ 0 when x is outside the obstacle (on the body side), < 0 when x penetrates it.
//!
//! The indenter shapes ([`Cylinder`], [`Cone`], [`Pyramid`], [`Punch`]) are solids whose g0 is
//! the exact signed distance to their surface (nearest surface point, outside positive) and
//! whose n is its gradient: the unit vector from the nearest surface point towards x outside,
//! the direction in which the penetration decreases fastest inside (x = closest + g0 n in
//! both cases). Their non-smooth places (apex, edges, and the interior points with several
//! nearest surface points) get the fixed choices documented on each type and in
//! docs/obstacles.md. [`Height`] (the solid below a graph, `contact::height`) and [`TriSurface`]
//! (inside a closed STL surface, `contact::surface`) follow the same conventions.
//!
//! By role and shape family: `error` (invalid data), `shape` (the [`Obstacle`] of a pair and
//! the [`Projection`] a query returns), `plane_sphere`, `axisymmetric` (cylinder, cone,
//! punch), `pyramid`, and `vec3` (the vector and axis helpers they share).

mod axisymmetric;
mod body;
mod error;
mod plane_sphere;
mod projection;
mod pyramid;
mod shape;
mod vec3;

#[cfg(test)]
mod tests;

pub use super::height::{Height, HeightExpr};
pub use super::surface::TriSurface;
pub use axisymmetric::{Cone, Cylinder, Punch};
pub use body::{BodyTarget, SlaveRow};
pub use error::ObstacleError;
pub use plane_sphere::{Plane, Sphere};
pub use projection::Projection;
pub use pyramid::{Pyramid, MAX_FACES, MIN_FACES};
pub use shape::Obstacle;
pub use vec3::reference_direction;
