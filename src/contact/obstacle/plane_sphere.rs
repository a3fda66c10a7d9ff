//! The smooth elementary obstacles: half-space and ball (disk).

use super::error::ObstacleError;
use super::projection::Projection;
use super::vec3::{check_dim, finite, flat};
use crate::geom::{dot, sub};

/// Half-space obstacle: the body lives on the side `normal` points to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    dim: usize,
    point: [f64; 3],
    normal: [f64; 3],
}

/// Rigid ball (3D) / disk (2D); the body stays outside it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    dim: usize,
    center: [f64; 3],
    radius: f64,
}

impl Plane {
    /// Plane through `point` with normal `normal` (any length > 0; it is normalised),
    /// pointing into the body side.
    pub fn new(point: [f64; 3], normal: [f64; 3], dim: usize) -> Result<Self, ObstacleError> {
        check_dim(dim)?;
        if !finite(&point) || !finite(&normal) {
            return Err(ObstacleError::NotFinite);
        }
        if dim == 2 && (point[2] != 0.0 || normal[2] != 0.0) {
            return Err(ObstacleError::NonZeroZ);
        }
        // Scale by the largest entry first so tiny or huge normals neither under- nor overflow.
        let big = normal.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        if big == 0.0 {
            return Err(ObstacleError::ZeroNormal);
        }
        let s = normal.map(|x| x / big);
        let len = dot(s, s).sqrt();
        Ok(Plane {
            dim,
            point,
            normal: s.map(|x| x / len),
        })
    }
    pub fn dim(&self) -> usize {
        self.dim
    }
    pub fn point(&self) -> [f64; 3] {
        self.point
    }
    /// The unit normal (into the body).
    pub fn normal(&self) -> [f64; 3] {
        self.normal
    }
    /// Closest point, normal and gap g0(x) = (x − p)·n.
    pub fn project(&self, x: [f64; 3]) -> Projection {
        let x = flat(self.dim, x);
        let g = dot(sub(x, self.point), self.normal);
        let n = self.normal;
        Projection {
            closest: [x[0] - g * n[0], x[1] - g * n[1], x[2] - g * n[2]],
            normal: n,
            gap: g,
        }
    }
}

impl Sphere {
    /// Ball (disk in 2D) with centre `center` and radius `radius` > 0.
    pub fn new(center: [f64; 3], radius: f64, dim: usize) -> Result<Self, ObstacleError> {
        check_dim(dim)?;
        if !finite(&center) || !radius.is_finite() {
            return Err(ObstacleError::NotFinite);
        }
        if dim == 2 && center[2] != 0.0 {
            return Err(ObstacleError::NonZeroZ);
        }
        if radius <= 0.0 {
            return Err(ObstacleError::NonPositiveRadius);
        }
        Ok(Sphere {
            dim,
            center,
            radius,
        })
    }
    pub fn dim(&self) -> usize {
        self.dim
    }
    pub fn center(&self) -> [f64; 3] {
        self.center
    }
    pub fn radius(&self) -> f64 {
        self.radius
    }
    /// Normal n = (x − c)/|x − c| (from the centre towards x), closest point c + R n and
    /// gap g0 = |x − c| − R. Error [`ObstacleError::AtCentre`] when |x − c| ≤ 1e-12·R.
    pub fn project(&self, x: [f64; 3]) -> Result<Projection, ObstacleError> {
        let x = flat(self.dim, x);
        if !finite(&x) {
            return Err(ObstacleError::NotFinite);
        }
        let d = sub(x, self.center);
        let dist = dot(d, d).sqrt();
        // finite: x, centre and radius are finite
        if dist <= 1e-12 * self.radius {
            return Err(ObstacleError::AtCentre);
        }
        let n = d.map(|v| v / dist);
        let c = self.center;
        let r = self.radius;
        Ok(Projection {
            closest: [c[0] + r * n[0], c[1] + r * n[1], c[2] + r * n[2]],
            normal: n,
            gap: dist - r,
        })
    }
}
