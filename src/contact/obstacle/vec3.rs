//! Small vector helpers and the axis/meridian geometry shared by the shapes.

use super::error::ObstacleError;
use crate::geom::dot;
use std::f64::consts::FRAC_1_SQRT_2;

pub(super) fn check_dim(dim: usize) -> Result<(), ObstacleError> {
    if dim == 2 || dim == 3 {
        Ok(())
    } else {
        Err(ObstacleError::BadDim(dim))
    }
}

pub(super) fn finite(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

pub(super) fn flat(dim: usize, x: [f64; 3]) -> [f64; 3] {
    if dim == 2 {
        [x[0], x[1], 0.0]
    } else {
        x
    }
}

pub(super) fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub(super) fn scale(s: f64, a: [f64; 3]) -> [f64; 3] {
    a.map(|v| s * v)
}

/// a + s b.
pub(super) fn axpy(a: [f64; 3], s: f64, b: [f64; 3]) -> [f64; 3] {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}

pub(super) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// The unit vector along `v` (scaled by its largest entry first, so that tiny or huge
/// vectors neither under- nor overflow); `None` for the zero vector.
pub(super) fn unit(v: [f64; 3]) -> Option<[f64; 3]> {
    let big = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if big == 0.0 {
        return None;
    }
    let s = v.map(|x| x / big);
    let len = norm(s);
    Some(s.map(|x| x / len))
}

/// Checks the common data of an axisymmetric shape (finite point and axis, z = 0 in 2D) and
/// returns the unit axis.
pub(super) fn check_axis(
    dim: usize,
    point: &[f64; 3],
    axis: &[f64; 3],
    scalars: &[f64],
) -> Result<[f64; 3], ObstacleError> {
    check_dim(dim)?;
    if !finite(point) || !finite(axis) || scalars.iter().any(|x| !x.is_finite()) {
        return Err(ObstacleError::NotFinite);
    }
    if dim == 2 && (point[2] != 0.0 || axis[2] != 0.0) {
        return Err(ObstacleError::NonZeroZ);
    }
    unit(*axis).ok_or(ObstacleError::ZeroAxis)
}

/// [`check_axis`] for a shape that exists in 3D only (`name`: the shape in the error,
/// [`ObstacleError::Only3D`] in 2D).
pub(super) fn check_axis_3d(
    name: &'static str,
    dim: usize,
    point: &[f64; 3],
    axis: &[f64; 3],
    scalars: &[f64],
) -> Result<[f64; 3], ObstacleError> {
    check_dim(dim)?;
    if dim == 2 {
        return Err(ObstacleError::Only3D(name));
    }
    check_axis(dim, point, axis, scalars)
}

/// sin β and cos β of a half angle β given in degrees, 0 < β < 90 (else
/// [`ObstacleError::BadHalfAngle`]).
pub(super) fn half_angle_sin_cos(half_angle: f64) -> Result<(f64, f64), ObstacleError> {
    if !(half_angle > 0.0 && half_angle < 90.0) {
        return Err(ObstacleError::BadHalfAngle);
    }
    Ok(half_angle.to_radians().sin_cos())
}

/// `x` in the plane of a 2D shape (z = 0; [`flat`]); [`ObstacleError::NotFinite`] unless
/// it is finite.
pub(super) fn finite_point(dim: usize, x: [f64; 3]) -> Result<[f64; 3], ObstacleError> {
    let x = flat(dim, x);
    if !finite(&x) {
        return Err(ObstacleError::NotFinite);
    }
    Ok(x)
}

/// The reference direction r0 of a unit axis a: a unit vector ⊥ a, the x axis projected onto
/// the plane normal to a, or the y axis projected so when a makes an angle < 45° with x
/// (|a_x| > 1/√2). In 2D (a in the xy plane) r0 lies in the xy plane; for a = ±z it is x.
/// It fixes a pyramid's azimuth 0 and the radial direction chosen on an axis.
pub fn reference_direction(a: [f64; 3]) -> [f64; 3] {
    let e = if a[0].abs() <= FRAC_1_SQRT_2 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let p = axpy(e, -dot(e, a), a);
    scale(1.0 / norm(p), p)
}

/// d split along the unit axis a: axial coordinate t = d·a, radial distance ρ = |d − t a| and
/// the radial unit vector (d − t a)/ρ, or `r0` when ρ = 0.
pub(super) fn meridian(d: [f64; 3], a: [f64; 3], r0: [f64; 3]) -> (f64, f64, [f64; 3]) {
    let t = dot(d, a);
    let perp = axpy(d, -t, a);
    let rho = norm(perp);
    let e = if rho > 0.0 {
        scale(1.0 / rho, perp)
    } else {
        r0
    };
    (t, rho, e)
}
