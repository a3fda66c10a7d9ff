//! The indenters with an axis of revolution: cylinder, cone, flat punch.

use super::error::ObstacleError;
use super::projection::Projection;
use super::vec3::{
    add, axpy, check_axis, check_axis_3d, finite, finite_point, half_angle_sin_cos, meridian, norm,
    reference_direction, scale,
};
use crate::geom::{dot, sub};

/// Infinite circular cylinder (3D only) of radius `radius` around the line through `point`
/// along `axis`; the body stays outside it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    point: [f64; 3],
    axis: [f64; 3],
    radius: f64,
}

impl Cylinder {
    /// Cylinder around the line through `point` along `axis` (any length > 0; normalised).
    /// [`ObstacleError::Only3D`] in 2D (a circle there is a [`Sphere`]).
    pub fn new(
        point: [f64; 3],
        axis: [f64; 3],
        radius: f64,
        dim: usize,
    ) -> Result<Self, ObstacleError> {
        let axis = check_axis_3d("cylinder", dim, &point, &axis, &[radius])?;
        if radius <= 0.0 {
            return Err(ObstacleError::BadRadius);
        }
        Ok(Cylinder {
            point,
            axis,
            radius,
        })
    }
    pub fn point(&self) -> [f64; 3] {
        self.point
    }
    /// The unit axis.
    pub fn axis(&self) -> [f64; 3] {
        self.axis
    }
    pub fn radius(&self) -> f64 {
        self.radius
    }
    /// With d = x − p, t = d·a and ρ = |d − t a|: n = (d − t a)/ρ (from the axis towards x),
    /// g0 = ρ − R, closest point p + t a + R n. Error [`ObstacleError::OnAxis`] when
    /// ρ ≤ 1e-12·R (as a sphere at its centre).
    pub fn project(&self, x: [f64; 3]) -> Result<Projection, ObstacleError> {
        if !finite(&x) {
            return Err(ObstacleError::NotFinite);
        }
        let d = sub(x, self.point);
        let t = dot(d, self.axis);
        let perp = axpy(d, -t, self.axis);
        let rho = norm(perp);
        if rho <= 1e-12 * self.radius {
            return Err(ObstacleError::OnAxis);
        }
        let n = scale(1.0 / rho, perp);
        let foot = axpy(self.point, t, self.axis);
        Ok(Projection {
            closest: axpy(foot, self.radius, n),
            normal: n,
            gap: rho - self.radius,
        })
    }
}

/// Solid circular cone (3D) or wedge (2D) {x : ∠(x − apex, axis) ≤ α}: the axis points from
/// the tip into the indenter; the body stays outside.
///
/// With d = x − apex, t = d·a, ρ = |d − t a| and e the radial unit vector (module
/// [`reference_direction`] r0 when ρ = 0), in the meridian half-plane (t, ρ) the surface is
/// the ray l (cos α, sin α), l ≥ 0. If l = t cos α + ρ sin α ≥ 0 the nearest surface point
/// is on that ray: g0 = ρ cos α − t sin α, n = −sin α a + cos α e; otherwise it is the apex:
/// g0 = |d|, n = d/|d|. At the apex itself (|d| = 0): g0 = 0, n = −a. Inside on the axis
/// (ρ = 0, t > 0) every generator is nearest: the one towards r0 is taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cone {
    dim: usize,
    apex: [f64; 3],
    axis: [f64; 3],
    half_angle: f64,
    cos: f64,
    sin: f64,
    r0: [f64; 3],
}

impl Cone {
    /// Cone with its tip at `apex`, axis `axis` (any length > 0; normalised) pointing into the
    /// indenter and the half angle `half_angle` in degrees, 0 < half_angle < 90.
    pub fn new(
        apex: [f64; 3],
        axis: [f64; 3],
        half_angle: f64,
        dim: usize,
    ) -> Result<Self, ObstacleError> {
        let axis = check_axis(dim, &apex, &axis, &[half_angle])?;
        let (sin, cos) = half_angle_sin_cos(half_angle)?;
        Ok(Cone {
            dim,
            apex,
            axis,
            half_angle,
            cos,
            sin,
            r0: reference_direction(axis),
        })
    }
    pub fn dim(&self) -> usize {
        self.dim
    }
    pub fn apex(&self) -> [f64; 3] {
        self.apex
    }
    /// The unit axis.
    pub fn axis(&self) -> [f64; 3] {
        self.axis
    }
    /// The half angle in degrees.
    pub fn half_angle(&self) -> f64 {
        self.half_angle
    }
    /// Closest point, normal and gap (see the type's documentation).
    pub fn project(&self, x: [f64; 3]) -> Result<Projection, ObstacleError> {
        let x = finite_point(self.dim, x)?;
        let a = self.axis;
        let d = sub(x, self.apex);
        if norm(d) == 0.0 {
            return Ok(Projection::to_apex(self.apex, a, d));
        }
        let (t, rho, e) = meridian(d, a, self.r0);
        let l = t * self.cos + rho * self.sin;
        if l < 0.0 {
            return Ok(Projection::to_apex(self.apex, a, d));
        }
        let generator = add(scale(self.cos, a), scale(self.sin, e));
        Ok(Projection {
            closest: axpy(self.apex, l, generator),
            normal: add(scale(-self.sin, a), scale(self.cos, e)),
            gap: rho * self.cos - t * self.sin,
        })
    }
}

/// Flat-ended cylindrical punch (3D) or flat strip (2D) of radius (half-width) R whose end
/// face is centred at `center` with the outward normal −a (a points from the face into the
/// indenter), the edge between the face and the side rounded with the radius r_e, 0 ≤ r_e ≤ R.
///
/// The solid is the set of points within r_e of the convex set K = {t ≥ r_e, ρ ≤ R − r_e}
/// (d = x − center, t = d·a, ρ = |d − t a|), so g0 = sdf_K − r_e with, for u = r_e − t and
/// v = ρ − (R − r_e): sdf_K = √(u² + v²), n = −u/√· a + v/√· e when u > 0 and v > 0 (the
/// rounded edge, or the sharp corner when r_e = 0); else sdf_K = u, n = −a when u ≥ v (the flat
/// face; ties go to it); else sdf_K = v, n = e (the side). e is the radial unit vector, the
/// [`reference_direction`] r0 on the axis (ρ = 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Punch {
    dim: usize,
    center: [f64; 3],
    axis: [f64; 3],
    radius: f64,
    edge_radius: f64,
    r0: [f64; 3],
}

impl Punch {
    /// Punch with its end face centred at `center`, axis `axis` (any length > 0; normalised)
    /// into the indenter, radius `radius` > 0 and edge radius 0 ≤ `edge_radius` ≤ `radius`.
    pub fn new(
        center: [f64; 3],
        axis: [f64; 3],
        radius: f64,
        edge_radius: f64,
        dim: usize,
    ) -> Result<Self, ObstacleError> {
        let axis = check_axis(dim, &center, &axis, &[radius, edge_radius])?;
        if radius <= 0.0 {
            return Err(ObstacleError::BadRadius);
        }
        if !(0.0..=radius).contains(&edge_radius) {
            return Err(ObstacleError::BadEdgeRadius);
        }
        Ok(Punch {
            dim,
            center,
            axis,
            radius,
            edge_radius,
            r0: reference_direction(axis),
        })
    }
    pub fn dim(&self) -> usize {
        self.dim
    }
    pub fn center(&self) -> [f64; 3] {
        self.center
    }
    /// The unit axis.
    pub fn axis(&self) -> [f64; 3] {
        self.axis
    }
    pub fn radius(&self) -> f64 {
        self.radius
    }
    pub fn edge_radius(&self) -> f64 {
        self.edge_radius
    }
    /// Closest point, normal and gap (see the type's documentation).
    pub fn project(&self, x: [f64; 3]) -> Result<Projection, ObstacleError> {
        let x = finite_point(self.dim, x)?;
        let a = self.axis;
        let h = self.edge_radius;
        let (t, rho, e) = meridian(sub(x, self.center), a, self.r0);
        let u = h - t;
        let v = rho - (self.radius - h);
        // g0 = sdf_K − r_e, written per piece without the subtraction where it cancels.
        let (gap, nt, nr) = if u > 0.0 && v > 0.0 {
            let q = u.hypot(v);
            (q - h, -u / q, v / q)
        } else if u >= v {
            (-t, -1.0, 0.0)
        } else {
            (rho - self.radius, 0.0, 1.0)
        };
        let n = add(scale(nt, a), scale(nr, e));
        Ok(Projection {
            closest: axpy(x, -gap, n),
            normal: n,
            gap,
        })
    }
}
