//! The obstacle of a contact pair ([`Obstacle`]).

use super::axisymmetric::{Cone, Cylinder, Punch};
use super::body::BodyTarget;
use super::error::ObstacleError;
use super::plane_sphere::{Plane, Sphere};
use super::projection::Projection;
use super::pyramid::Pyramid;
use crate::contact::height::Height;
use crate::contact::surface::TriSurface;
use std::sync::Arc;

/// Any supported obstacle.
#[derive(Debug, Clone, PartialEq)]
pub enum Obstacle {
    Plane(Plane),
    Sphere(Sphere),
    Cylinder(Cylinder),
    Cone(Cone),
    Pyramid(Pyramid),
    Punch(Punch),
    /// Below the graph of an expression (docs/obstacles.md, "height").
    Height(Height),
    /// Inside a closed triangle surface (3D only; docs/obstacles.md, "surface"). The surface is
    /// read once per run and shared.
    Surface(Arc<TriSurface>),
    /// Another deformable body (dual mortar): its rows per slave node, not a shape
    /// ([`BodyTarget`]); [`Obstacle::project`] refuses it.
    Body(Arc<BodyTarget>),
}

impl Obstacle {
    pub fn dim(&self) -> usize {
        match self {
            Obstacle::Plane(p) => p.dim(),
            Obstacle::Sphere(s) => s.dim(),
            Obstacle::Cylinder(_) | Obstacle::Pyramid(_) => 3,
            Obstacle::Cone(c) => c.dim(),
            Obstacle::Punch(p) => p.dim(),
            Obstacle::Height(h) => h.dim(),
            Obstacle::Surface(_) => 3,
            Obstacle::Body(b) => b.dim,
        }
    }
    /// Closest point, normal (into the body) and initial gap g0(x) (3.3).
    pub fn project(&self, x: [f64; 3]) -> Result<Projection, ObstacleError> {
        match self {
            Obstacle::Plane(p) => Ok(p.project(x)),
            Obstacle::Sphere(s) => s.project(x),
            Obstacle::Cylinder(c) => c.project(x),
            Obstacle::Cone(c) => c.project(x),
            Obstacle::Pyramid(p) => p.project(x),
            Obstacle::Punch(p) => p.project(x),
            Obstacle::Height(h) => h.project(x),
            Obstacle::Surface(s) => {
                if x.iter().all(|v| v.is_finite()) {
                    Ok(s.project(x))
                } else {
                    Err(ObstacleError::NotFinite)
                }
            }
            Obstacle::Body(_) => Err(ObstacleError::NotRigid),
        }
    }
}
