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

pub use super::height::{Height, HeightExpr};
pub use super::surface::TriSurface;
use crate::error::InputError;
use crate::geom::{cross, dot, sub};
use std::f64::consts::{FRAC_1_SQRT_2, PI, TAU};
use std::fmt;
use std::path::Path;
use std::sync::Arc;

/// Invalid obstacle data, or a query point without a defined normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ObstacleError {
    /// A coordinate or the radius is NaN or infinite.
    NotFinite,
    /// The plane's normal is the zero vector.
    ZeroNormal,
    /// The sphere's radius is ≤ 0.
    NonPositiveRadius,
    /// A 2D obstacle has a non-zero z component (point, normal or centre).
    NonZeroZ,
    /// Dimension other than 2 or 3.
    BadDim(usize),
    /// Sphere query at its centre: no defined normal.
    AtCentre,
    /// The axis of a cylinder, cone, pyramid or punch is the zero vector.
    ZeroAxis,
    /// The radius of a cylinder or punch is ≤ 0.
    BadRadius,
    /// A cone's or pyramid's half angle is not in (0, 90) degrees.
    BadHalfAngle,
    /// A pyramid's number of faces is not in [`MIN_FACES`, `MAX_FACES`].
    BadFaces(usize),
    /// A punch's edge radius is not in [0, radius].
    BadEdgeRadius,
    /// A shape that exists in 3D only (its name) asked for in 2D.
    Only3D(&'static str),
    /// Cylinder query on its axis: no defined normal.
    OnAxis,
    /// A height expression with variables other than x (2D) or x, y (3D).
    HeightVariables,
    /// The height h is not a finite number at (x) or (x, y) near a queried point.
    HeightNotFinite { x: f64, y: Option<f64> },
    /// The nearest point of a height surface was not found.
    HeightNoConvergence,
    /// The slope of h jumps at the nearest point (x) or (x, y): a kink or a step.
    HeightNotSmooth { x: f64, y: Option<f64> },
}

impl fmt::Display for ObstacleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ObstacleError::NotFinite => write!(f, "obstacle data must be finite numbers"),
            ObstacleError::ZeroNormal => write!(f, "the plane normal must not be the zero vector"),
            ObstacleError::NonPositiveRadius => write!(f, "the sphere radius must be > 0"),
            ObstacleError::NonZeroZ => {
                write!(
                    f,
                    "a 2D obstacle must have z = 0 in its point, normal and centre"
                )
            }
            ObstacleError::BadDim(d) => write!(f, "dimension must be 2 or 3, got {d}"),
            ObstacleError::AtCentre => write!(
                f,
                "a contact node lies at the centre of the sphere obstacle: no normal is defined"
            ),
            ObstacleError::ZeroAxis => write!(f, "the axis must not be the zero vector"),
            ObstacleError::BadRadius => write!(f, "the radius must be > 0"),
            ObstacleError::BadHalfAngle => {
                write!(f, "the half angle must lie in (0, 90) degrees")
            }
            ObstacleError::BadFaces(n) => write!(
                f,
                "a pyramid needs {MIN_FACES} to {MAX_FACES} faces, got {n}"
            ),
            ObstacleError::BadEdgeRadius => {
                write!(f, "the edge radius must lie in [0, radius]")
            }
            ObstacleError::Only3D(name) => {
                write!(f, "a {name} obstacle exists in 3D only")
            }
            ObstacleError::OnAxis => write!(
                f,
                "a contact node lies on the axis of the cylinder obstacle: no normal is defined"
            ),
            ObstacleError::HeightVariables => write!(
                f,
                "the height expression 'expr' may use only x (2D) or x and y (3D)"
            ),
            ObstacleError::HeightNotFinite { x, y } => {
                let at = match y {
                    Some(y) => format!("(x, y) = ({x}, {y})"),
                    None => format!("x = {x}"),
                };
                write!(
                    f,
                    "the height expression 'expr' is not a finite number at \
                     {at}, near the node (the obstacle's surface must be defined and smooth \
                     under the contact boundary)"
                )
            }
            ObstacleError::HeightNotSmooth { x, y } => {
                let at = match y {
                    Some(y) => format!("(x, y) = ({x}, {y})"),
                    None => format!("x = {x}"),
                };
                write!(
                    f,
                    "the height surface 'expr' has a kink or a step at {at}, \
                     the nearest point to the node (its slope jumps there): the surface must be \
                     smooth (C¹) near the body"
                )
            }
            ObstacleError::HeightNoConvergence => write!(
                f,
                "the nearest point on the height surface 'expr' was not found \
                 (the projection did not converge): the surface must be smooth (C¹) near the \
                 body, without kinks or steps"
            ),
        }
    }
}

impl std::error::Error for ObstacleError {}

impl ObstacleError {
    /// Wrap as a user-facing [`InputError`] for the case file `file`, key `key`.
    pub fn into_input_error(self, file: &Path, key: &str) -> InputError {
        InputError::new(file, self.to_string()).with_key(key)
    }

    /// The key of the obstacle's table the error is about: `obstacle.expr` for the height
    /// expression, else `obstacle`.
    pub fn key_in_pair(&self) -> &'static str {
        match self {
            ObstacleError::HeightVariables
            | ObstacleError::HeightNotFinite { .. }
            | ObstacleError::HeightNotSmooth { .. }
            | ObstacleError::HeightNoConvergence => "obstacle.expr",
            _ => "obstacle",
        }
    }
}

/// Closest point, normal (unit, into the body) and initial gap g0 of a point x.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    pub closest: [f64; 3],
    pub normal: [f64; 3],
    pub gap: f64,
}

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
}

fn check_dim(dim: usize) -> Result<(), ObstacleError> {
    if dim == 2 || dim == 3 {
        Ok(())
    } else {
        Err(ObstacleError::BadDim(dim))
    }
}

fn finite(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn flat(dim: usize, x: [f64; 3]) -> [f64; 3] {
    if dim == 2 {
        [x[0], x[1], 0.0]
    } else {
        x
    }
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

/// Fewest faces of a [`Pyramid`].
pub const MIN_FACES: usize = 3;
/// Most faces of a [`Pyramid`] (a pyramid with many more faces is a [`Cone`]; the queries cost
/// O(faces)).
pub const MAX_FACES: usize = 64;

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn scale(s: f64, a: [f64; 3]) -> [f64; 3] {
    a.map(|v| s * v)
}

/// a + s b.
fn axpy(a: [f64; 3], s: f64, b: [f64; 3]) -> [f64; 3] {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// The unit vector along `v` (scaled by its largest entry first, so that tiny or huge
/// vectors neither under- nor overflow); `None` for the zero vector.
fn unit(v: [f64; 3]) -> Option<[f64; 3]> {
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
fn check_axis(
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
fn meridian(d: [f64; 3], a: [f64; 3], r0: [f64; 3]) -> (f64, f64, [f64; 3]) {
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
        check_dim(dim)?;
        if dim == 2 {
            return Err(ObstacleError::Only3D("cylinder"));
        }
        let axis = check_axis(dim, &point, &axis, &[radius])?;
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
        if !(half_angle > 0.0 && half_angle < 90.0) {
            return Err(ObstacleError::BadHalfAngle);
        }
        let (sin, cos) = half_angle.to_radians().sin_cos();
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
        let x = flat(self.dim, x);
        if !finite(&x) {
            return Err(ObstacleError::NotFinite);
        }
        let a = self.axis;
        let d = sub(x, self.apex);
        let len = norm(d);
        if len == 0.0 {
            return Ok(Projection {
                closest: self.apex,
                normal: scale(-1.0, a),
                gap: 0.0,
            });
        }
        let (t, rho, e) = meridian(d, a, self.r0);
        let l = t * self.cos + rho * self.sin;
        if l < 0.0 {
            return Ok(Projection {
                closest: self.apex,
                normal: scale(1.0 / len, d),
                gap: len,
            });
        }
        let generator = add(scale(self.cos, a), scale(self.sin, e));
        Ok(Projection {
            closest: axpy(self.apex, l, generator),
            normal: add(scale(-self.sin, a), scale(self.cos, e)),
            gap: rho * self.cos - t * self.sin,
        })
    }
}

/// Regular pyramid (3D only): the intersection of the `faces` half-spaces
/// {x : (x − apex)·m_k ≤ 0}, k = 0 .. N − 1, each face through the apex at the angle β (the
/// half angle) to the axis a, which points from the tip into the indenter.
///
/// Face k's outward normal is m_k = cos β u_k − sin β a with the horizontal direction
/// u_k = cos φ_k r0 + sin φ_k (a × r0), φ_k = azimuth + 360° k / N, r0 the
/// [`reference_direction`] of a: at azimuth 0, face 0 faces r0 (x for a vertical axis).
/// The edge between faces k and k + 1 lies at φ_k + 180°/N.
///
/// Inside (max_k d·m_k ≤ 0, d = x − apex): g0 = max_k d·m_k, n = m_k of the first face
/// attaining it. Outside: the nearest of the candidate surface points (feet on the faces that
/// lie on their face, feet on the edge rays, the apex): g0 its distance, n the unit vector
/// from it to x (m_k for a face). At the apex itself: g0 = 0, n = −a.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pyramid {
    apex: [f64; 3],
    axis: [f64; 3],
    half_angle: f64,
    faces: usize,
    azimuth: f64,
    cos: f64,
    sin: f64,
    r0: [f64; 3],
    r1: [f64; 3],
}

impl Pyramid {
    /// Pyramid with its tip at `apex`, axis `axis` (any length > 0; normalised), face-to-axis
    /// angle `half_angle` in degrees (0, 90) (Berkovich: 3 faces at 65.27°, Vickers: 4 at
    /// 68°), `faces` in [`MIN_FACES`, `MAX_FACES`], `azimuth` in degrees (any finite value).
    pub fn new(
        apex: [f64; 3],
        axis: [f64; 3],
        half_angle: f64,
        faces: usize,
        azimuth: f64,
        dim: usize,
    ) -> Result<Self, ObstacleError> {
        check_dim(dim)?;
        if dim == 2 {
            return Err(ObstacleError::Only3D("pyramid"));
        }
        let axis = check_axis(dim, &apex, &axis, &[half_angle, azimuth])?;
        if !(half_angle > 0.0 && half_angle < 90.0) {
            return Err(ObstacleError::BadHalfAngle);
        }
        if !(MIN_FACES..=MAX_FACES).contains(&faces) {
            return Err(ObstacleError::BadFaces(faces));
        }
        let (sin, cos) = half_angle.to_radians().sin_cos();
        let r0 = reference_direction(axis);
        Ok(Pyramid {
            apex,
            axis,
            half_angle,
            faces,
            azimuth,
            cos,
            sin,
            r0,
            r1: cross(axis, r0),
        })
    }
    pub fn apex(&self) -> [f64; 3] {
        self.apex
    }
    /// The unit axis.
    pub fn axis(&self) -> [f64; 3] {
        self.axis
    }
    /// The face-to-axis angle in degrees.
    pub fn half_angle(&self) -> f64 {
        self.half_angle
    }
    pub fn faces(&self) -> usize {
        self.faces
    }
    /// The azimuth of face 0 in degrees.
    pub fn azimuth(&self) -> f64 {
        self.azimuth
    }
    /// The horizontal unit vector at the angle φ (radians) from r0, right-handed about a.
    fn horizontal(&self, phi: f64) -> [f64; 3] {
        let (s, c) = phi.sin_cos();
        add(scale(c, self.r0), scale(s, self.r1))
    }
    fn phi(&self, k: usize) -> f64 {
        self.azimuth.to_radians() + TAU * k as f64 / self.faces as f64
    }
    /// The outward unit normal m_k of face k.
    pub fn face_normal(&self, k: usize) -> [f64; 3] {
        let u = self.horizontal(self.phi(k));
        add(scale(self.cos, u), scale(-self.sin, self.axis))
    }
    /// The unit direction of the edge between faces k and k + 1 (mod N), from the apex into
    /// the indenter: (cos β cos(π/N) a + sin β v)/|·|, v horizontal at φ_k + π/N.
    pub fn edge(&self, k: usize) -> [f64; 3] {
        let half = PI / self.faces as f64;
        let v = self.horizontal(self.phi(k) + half);
        let c = self.cos * half.cos();
        let h = c.hypot(self.sin);
        add(scale(c / h, self.axis), scale(self.sin / h, v))
    }
    /// Closest point, normal and gap (see the type's documentation).
    pub fn project(&self, x: [f64; 3]) -> Result<Projection, ObstacleError> {
        if !finite(&x) {
            return Err(ObstacleError::NotFinite);
        }
        let d = sub(x, self.apex);
        let len = norm(d);
        if len == 0.0 {
            return Ok(Projection {
                closest: self.apex,
                normal: scale(-1.0, self.axis),
                gap: 0.0,
            });
        }
        let nf = self.faces;
        let mut m = [[0.0; 3]; MAX_FACES];
        let mut s = [0.0; MAX_FACES];
        let mut first = 0;
        for k in 0..nf {
            m[k] = self.face_normal(k);
            s[k] = dot(d, m[k]);
            if s[k] > s[first] {
                first = k;
            }
        }
        if s[first] <= 0.0 {
            // Inside (or on the surface): the nearest face plane.
            let n = m[first];
            return Ok(Projection {
                closest: axpy(x, -s[first], n),
                normal: n,
                gap: s[first],
            });
        }
        // Outside: the nearest surface point is the apex, on an edge ray or on a face.
        let mut best = Projection {
            closest: self.apex,
            normal: scale(1.0 / len, d),
            gap: len,
        };
        for k in 0..nf {
            if s[k] > 0.0 && s[k] < best.gap {
                let foot = axpy(d, -s[k], m[k]);
                let (prev, next) = ((k + nf - 1) % nf, (k + 1) % nf);
                if dot(foot, m[prev]) <= 0.0 && dot(foot, m[next]) <= 0.0 {
                    best = Projection {
                        closest: add(self.apex, foot),
                        normal: m[k],
                        gap: s[k],
                    };
                }
            }
        }
        for k in 0..nf {
            let e = self.edge(k);
            let l = dot(d, e);
            if l > 0.0 {
                let w = axpy(d, -l, e);
                let dist = norm(w);
                if dist > 0.0 && dist < best.gap {
                    best = Projection {
                        closest: axpy(self.apex, l, e),
                        normal: scale(1.0 / dist, w),
                        gap: dist,
                    };
                }
            }
        }
        Ok(best)
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
        let x = flat(self.dim, x);
        if !finite(&x) {
            return Err(ObstacleError::NotFinite);
        }
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
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
        let d = sub(*a, *b);
        dot(d, d).sqrt()
    }

    /// The thesis' benchmark: plane y = -1 below the unit disk, n = (0, 1).
    #[test]
    fn hertz_plane_2d() {
        let p = Plane::new([0.0, -1.0, 0.0], [0.0, 3.0, 0.0], 2).unwrap();
        assert_eq!(p.normal(), [0.0, 1.0, 0.0]);
        // Lowest point of the unit disk touches: gap 0.
        let q = p.project([0.0, -1.0, 0.0]);
        assert_eq!(q.gap, 0.0);
        // A point of the circle at angle 5π/4: gap = 1 − sin(π/4).
        let a = 5.0 * std::f64::consts::PI / 4.0;
        let q = p.project([a.cos(), a.sin(), 0.0]);
        assert!(close(q.gap, 1.0 - (0.5f64).sqrt(), 1e-15));
        assert!(close(q.closest[0], a.cos(), 1e-15) && close(q.closest[1], -1.0, 1e-15));
        // z of the query is ignored in 2D.
        let q2 = p.project([a.cos(), a.sin(), 7.0]);
        assert_eq!(q, q2);
        // Below the plane: negative gap.
        assert!(close(p.project([0.3, -1.5, 0.0]).gap, -0.5, 1e-15));
    }

    #[test]
    fn plane_random_3d() {
        let mut rng = StdRng::seed_from_u64(1);
        for _ in 0..200 {
            let pt = [0.0; 3].map(|_: f64| rng.gen_range(-2.0..2.0));
            let nr = [0.0; 3].map(|_: f64| rng.gen_range(-1.0..1.0));
            if dot(nr, nr) < 1e-4 {
                continue;
            }
            let p = Plane::new(pt, nr, 3).unwrap();
            let n = p.normal();
            assert!(close(dot(n, n), 1.0, 1e-14));
            assert!(dot(n, nr) > 0.0, "orientation kept");
            let x = [0.0; 3].map(|_: f64| rng.gen_range(-3.0..3.0));
            let q = p.project(x);
            // closest point lies on the plane
            assert!(dot(sub(q.closest, pt), n).abs() < 1e-13);
            // x = closest + g n
            for i in 0..3 {
                assert!(close(x[i], q.closest[i] + q.gap * n[i], 1e-13));
            }
            // |g| is the distance to the plane, and no other point of the plane is closer
            assert!(close(q.gap.abs(), dist(&x, &q.closest), 1e-13));
            let other = [
                q.closest[0] + 0.1 * n[1],
                q.closest[1] - 0.1 * n[0],
                q.closest[2],
            ];
            assert!(dist(&x, &other) >= q.gap.abs() - 1e-13);
            // sign: moving along +n increases the gap by the step
            let x2 = [x[0] + 0.5 * n[0], x[1] + 0.5 * n[1], x[2] + 0.5 * n[2]];
            assert!(close(p.project(x2).gap, q.gap + 0.5, 1e-13));
        }
    }

    #[test]
    fn sphere_2d_and_3d() {
        // 2D disk of radius 2 at (1, 1): point (4, 5) is at distance 5, gap 3, n = (0.6, 0.8).
        let s = Sphere::new([1.0, 1.0, 0.0], 2.0, 2).unwrap();
        let q = s.project([4.0, 5.0, 0.0]).unwrap();
        assert!(close(q.gap, 3.0, 1e-15));
        assert!(close(q.normal[0], 0.6, 1e-15) && close(q.normal[1], 0.8, 1e-15));
        assert_eq!(q.normal[2], 0.0);
        assert!(close(q.closest[0], 2.2, 1e-15) && close(q.closest[1], 2.6, 1e-15));
        // inside: negative gap, normal still from centre to x
        let q = s.project([1.0, 0.0, 0.0]).unwrap();
        assert!(close(q.gap, -1.0, 1e-15));
        assert_eq!(q.normal, [0.0, -1.0, 0.0]);
        assert_eq!(s.project([1.0, 1.0, 0.0]), Err(ObstacleError::AtCentre));

        let mut rng = StdRng::seed_from_u64(2);
        for _ in 0..200 {
            let c = [0.0; 3].map(|_: f64| rng.gen_range(-2.0..2.0));
            let r = rng.gen_range(0.1..3.0);
            let s = Sphere::new(c, r, 3).unwrap();
            let x = [0.0; 3].map(|_: f64| rng.gen_range(-5.0..5.0));
            let q = s.project(x).unwrap();
            assert!(close(dot(q.normal, q.normal), 1.0, 1e-14));
            assert!(close(dist(&q.closest, &c), r, 1e-13));
            assert!(close(q.gap, dist(&x, &c) - r, 1e-13));
            // x = closest + g n; n points from centre to x
            for ((xi, pi), ni) in x.iter().zip(&q.closest).zip(&q.normal) {
                assert!(close(*xi, pi + q.gap * ni, 1e-12));
            }
            assert!(dot(q.normal, sub(x, c)) > 0.0);
            // the closest point really is closest among sampled sphere points
            for _ in 0..5 {
                let d = [0.0; 3].map(|_: f64| rng.gen_range(-1.0..1.0));
                let l = dot(d, d).sqrt();
                if l < 1e-3 {
                    continue;
                }
                let y = [
                    c[0] + r * d[0] / l,
                    c[1] + r * d[1] / l,
                    c[2] + r * d[2] / l,
                ];
                assert!(dist(&x, &y) >= q.gap.abs() - 1e-12);
            }
        }
    }

    #[test]
    fn invalid_data() {
        assert_eq!(
            Plane::new([0.0; 3], [0.0; 3], 3),
            Err(ObstacleError::ZeroNormal)
        );
        assert_eq!(
            Plane::new([0.0; 3], [0.0, 1.0, 0.5], 2),
            Err(ObstacleError::NonZeroZ)
        );
        assert_eq!(
            Plane::new([0.0, f64::NAN, 0.0], [0.0, 1.0, 0.0], 2),
            Err(ObstacleError::NotFinite)
        );
        assert_eq!(
            Sphere::new([0.0; 3], 0.0, 3),
            Err(ObstacleError::NonPositiveRadius)
        );
        assert_eq!(
            Sphere::new([0.0; 3], -1.0, 3),
            Err(ObstacleError::NonPositiveRadius)
        );
        assert_eq!(
            Sphere::new([0.0, 0.0, 1.0], 1.0, 2),
            Err(ObstacleError::NonZeroZ)
        );
        assert_eq!(Sphere::new([0.0; 3], 1.0, 4), Err(ObstacleError::BadDim(4)));
        let e = ObstacleError::AtCentre.into_input_error(Path::new("case.toml"), "obstacle");
        assert_eq!(e.key.as_deref(), Some("obstacle"));
        assert!(e.to_string().starts_with("case.toml: key 'obstacle': "));
        let o = Obstacle::Sphere(Sphere::new([0.0; 3], 1.0, 3).unwrap());
        assert_eq!(o.project([0.0; 3]), Err(ObstacleError::AtCentre));
        assert_eq!(o.dim(), 3);
    }

    // ---- the indenter shapes -------------------------------------------------------------

    fn rand_vec(rng: &mut StdRng, lo: f64, hi: f64, dim: usize) -> [f64; 3] {
        let mut v = [0.0; 3].map(|_: f64| rng.gen_range(lo..hi));
        if dim == 2 {
            v[2] = 0.0;
        }
        v
    }

    fn rand_unit(rng: &mut StdRng, dim: usize) -> [f64; 3] {
        loop {
            let v = rand_vec(rng, -1.0, 1.0, dim);
            let l = dot(v, v).sqrt();
            if l > 0.2 {
                return v.map(|x| x / l);
            }
        }
    }

    fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }

    /// Rodrigues: v rotated by the angle φ about the unit axis k.
    fn rotate(v: [f64; 3], k: [f64; 3], phi: f64) -> [f64; 3] {
        let (s, c) = phi.sin_cos();
        let kv = cross3(k, v);
        let kd = dot(k, v);
        [0, 1, 2].map(|i| v[i] * c + kv[i] * s + k[i] * kd * (1.0 - c))
    }

    /// Unit normal, x = closest + g n, and the finite-difference gradient of the gap equal to
    /// n (central differences with step h; `smooth` false skips the gradient check).
    fn check_common(o: &Obstacle, x: [f64; 3], q: &Projection, smooth: bool, what: &str) {
        let dim = o.dim();
        let n = q.normal;
        assert!(close(dot(n, n), 1.0, 1e-13), "{what}: |n| at {x:?}: {n:?}");
        for i in 0..dim {
            assert!(
                close(x[i], q.closest[i] + q.gap * n[i], 1e-12),
                "{what}: x = closest + g n at {x:?}: {q:?}"
            );
        }
        if dim == 2 {
            assert_eq!((n[2], q.closest[2]), (0.0, 0.0), "{what}");
        }
        if smooth {
            let h = 1e-7;
            for i in 0..dim {
                let (mut xp, mut xm) = (x, x);
                xp[i] += h;
                xm[i] -= h;
                let g = (o.project(xp).unwrap().gap - o.project(xm).unwrap().gap) / (2.0 * h);
                assert!(
                    close(g, n[i], 1e-6),
                    "{what}: d gap / dx_{i} = {g} but n = {n:?} at {x:?}"
                );
            }
        }
    }

    #[test]
    fn reference_direction_is_unit_and_perpendicular() {
        assert_eq!(reference_direction([0.0, 0.0, 1.0]), [1.0, 0.0, 0.0]);
        assert_eq!(reference_direction([0.0, 0.0, -1.0]), [1.0, 0.0, 0.0]);
        assert_eq!(reference_direction([0.0, 1.0, 0.0]), [1.0, 0.0, 0.0]);
        assert_eq!(reference_direction([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]);
        let mut rng = StdRng::seed_from_u64(10);
        for dim in [2, 3] {
            for _ in 0..200 {
                let a = rand_unit(&mut rng, dim);
                let r = reference_direction(a);
                assert!(close(dot(r, r), 1.0, 1e-14) && dot(r, a).abs() < 1e-14);
                if dim == 2 {
                    assert_eq!(r[2], 0.0);
                }
            }
        }
    }

    #[test]
    fn cylinder_random_points() {
        let mut rng = StdRng::seed_from_u64(11);
        for _ in 0..300 {
            let p = rand_vec(&mut rng, -2.0, 2.0, 3);
            let a = rand_unit(&mut rng, 3);
            let r = rng.gen_range(0.1..2.0);
            let c = Cylinder::new(p, a.map(|x| 3.0 * x), r, 3).unwrap();
            assert!(close(dot(c.axis(), a), 1.0, 1e-14));
            let o = Obstacle::Cylinder(c);
            // Points both sides, some close to the surface.
            let x = if rng.gen_bool(0.5) {
                rand_vec(&mut rng, -4.0, 4.0, 3)
            } else {
                let y = add(p, scale(rng.gen_range(-3.0..3.0), a));
                let w = cross3(a, rand_unit(&mut rng, 3));
                let w = scale(1.0 / norm(w), w);
                axpy(y, r + rng.gen_range(-1e-3..1e-3), w)
            };
            let q = o.project(x).unwrap();
            // Independent: the distance to the axis line is |(x − p) × a|.
            let rho = norm(cross3(sub(x, p), a));
            assert!(close(q.gap, rho - r, 1e-12), "{} vs {}", q.gap, rho - r);
            assert!(dot(q.normal, a).abs() < 1e-12);
            assert!(close(norm(cross3(sub(q.closest, p), a)), r, 1e-12));
            check_common(&o, x, &q, rho > 1e-3, "cylinder");
        }
        let c = Cylinder::new([0.0; 3], [0.0, 0.0, 1.0], 1.0, 3).unwrap();
        assert_eq!(c.project([0.0, 0.0, 5.0]), Err(ObstacleError::OnAxis));
        let q = c.project([0.0, 2.0, 7.0]).unwrap();
        assert_eq!(
            (q.gap, q.normal, q.closest),
            (1.0, [0.0, 1.0, 0.0], [0.0, 1.0, 7.0])
        );
    }

    /// Independent signed distance of the cone through the angle θ between x − apex and the
    /// axis: inside (θ ≤ α) −|d| sin(α − θ); outside |d| sin(θ − α) while θ − α ≤ 90°,
    /// else |d| (the apex).
    fn cone_gap_by_angle(apex: [f64; 3], a: [f64; 3], alpha: f64, x: [f64; 3]) -> f64 {
        let d = sub(x, apex);
        let len = norm(d);
        let theta = norm(cross3(d, a)).atan2(dot(d, a));
        if theta <= alpha {
            -len * (alpha - theta).sin()
        } else if theta - alpha <= std::f64::consts::FRAC_PI_2 {
            len * (theta - alpha).sin()
        } else {
            len
        }
    }

    #[test]
    fn cone_random_points_2d_and_3d() {
        let mut rng = StdRng::seed_from_u64(12);
        for dim in [2, 3] {
            for _ in 0..400 {
                let apex = rand_vec(&mut rng, -1.0, 1.0, dim);
                let a = rand_unit(&mut rng, dim);
                let deg = rng.gen_range(5.0..85.0);
                let alpha = f64::to_radians(deg);
                let c = Cone::new(apex, a.map(|x| 0.5 * x), deg, dim).unwrap();
                let o = Obstacle::Cone(c);
                assert_eq!(o.dim(), dim);
                let x = match rng.gen_range(0..3) {
                    0 => rand_vec(&mut rng, -3.0, 3.0, dim),
                    // near the apex
                    1 => axpy(apex, 1e-3, rand_vec(&mut rng, -1.0, 1.0, dim)),
                    // near the surface: a generator point moved off it by ±1e-4
                    _ => {
                        let w = cross3(a, rand_unit(&mut rng, dim));
                        let w = if dim == 2 {
                            [-a[1], a[0], 0.0]
                        } else {
                            scale(1.0 / norm(w), w)
                        };
                        let gen = add(scale(alpha.cos(), a), scale(alpha.sin(), w));
                        let y = axpy(apex, rng.gen_range(0.0..2.0), gen);
                        axpy(y, 1e-4, rand_vec(&mut rng, -1.0, 1.0, dim))
                    }
                };
                let q = o.project(x).unwrap();
                let want = cone_gap_by_angle(apex, a, alpha, x);
                assert!(close(q.gap, want, 1e-12), "{dim}D: {} vs {want}", q.gap);
                // The closest point lies on the surface: the apex or at the angle α.
                let y = sub(q.closest, apex);
                if norm(y) > 1e-9 {
                    let th = norm(cross3(y, a)).atan2(dot(y, a));
                    assert!(close(th, alpha, 1e-9), "{th} vs {alpha}");
                }
                // Smooth away from the axis and the apex.
                let d = sub(x, apex);
                let smooth = norm(d) > 1e-3 && norm(cross3(d, a)) > 1e-3;
                check_common(&o, x, &q, smooth, "cone");
            }
        }
    }

    #[test]
    fn cone_apex_axis_and_known_values() {
        // 2D wedge, tip at the origin, axis +y, half angle 45°.
        let c = Cone::new([0.0; 3], [0.0, 2.0, 0.0], 45.0, 2).unwrap();
        let s = 0.5f64.sqrt();
        // At the apex: g = 0, n = −axis.
        let q = c.project([0.0, 0.0, 3.0]).unwrap();
        assert_eq!(
            (q.gap, q.normal, q.closest),
            (0.0, [0.0, -1.0, 0.0], [0.0; 3])
        );
        // Below the tip on the axis: the apex is nearest, n = −axis.
        let q = c.project([0.0, -2.0, 0.0]).unwrap();
        assert_eq!((q.gap, q.normal), (2.0, [0.0, -1.0, 0.0]));
        // Beside the wedge: the face x = y is nearest.
        let q = c.project([1.0, 0.0, 0.0]).unwrap();
        assert!(close(q.gap, s, 1e-15) && close(q.normal[0], s, 1e-15));
        assert!(close(q.normal[1], -s, 1e-15));
        assert!(close(q.closest[0], 0.5, 1e-15) && close(q.closest[1], 0.5, 1e-15));
        // Inside on the axis: both faces are nearest, the one towards r0 = +x is taken.
        let q = c.project([0.0, 1.0, 0.0]).unwrap();
        assert!(close(q.gap, -s, 1e-15));
        assert!(close(q.normal[0], s, 1e-15) && close(q.normal[1], -s, 1e-15));
        // 3D, axis +z: inside on the axis also takes r0 = x.
        let c = Cone::new([0.0, 0.0, 1.0], [0.0, 0.0, 1.0], 60.0, 3).unwrap();
        let q = c.project([0.0, 0.0, 3.0]).unwrap();
        let (sa, ca) = 60f64.to_radians().sin_cos();
        assert!(close(q.gap, -2.0 * sa, 1e-15));
        assert!(close(q.normal[0], ca, 1e-15) && close(q.normal[2], -sa, 1e-15));
        assert_eq!(q.normal[1], 0.0);
    }

    #[test]
    fn pyramid_face_conventions() {
        // Vickers: 4 faces at 68°, axis +z, azimuth 0: faces towards +x, +y, −x, −y.
        let b = 68f64.to_radians();
        let p = Pyramid::new([0.0; 3], [0.0, 0.0, 1.0], 68.0, 4, 0.0, 3).unwrap();
        let want = [
            [b.cos(), 0.0, -b.sin()],
            [0.0, b.cos(), -b.sin()],
            [-b.cos(), 0.0, -b.sin()],
            [0.0, -b.cos(), -b.sin()],
        ];
        for (k, w) in want.iter().enumerate() {
            let m = p.face_normal(k);
            for i in 0..3 {
                assert!(close(m[i], w[i], 1e-15), "face {k}: {m:?}");
            }
        }
        // Its edges lie on the diagonals; the face-to-axis angle is 68°.
        let e = p.edge(0);
        assert!(close(e[0], e[1], 1e-15) && e[0] > 0.0 && e[2] > 0.0);
        // A point above face 0 (off its centre line) projects onto face 0 along m_0.
        let x = [1.0, 0.1, 0.2];
        let q = p.project(x).unwrap();
        assert!(close(q.gap, dot(x, want[0]), 1e-15) && q.normal == p.face_normal(0));
        // Berkovich, azimuth 90°: face 0 faces +y, the others at 210° and 330°.
        let b = 65.27f64.to_radians();
        let p = Pyramid::new([0.0; 3], [0.0, 0.0, 1.0], 65.27, 3, 90.0, 3).unwrap();
        for (k, phi) in [90.0f64, 210.0, 330.0].iter().enumerate() {
            let m = p.face_normal(k);
            let (s, c) = phi.to_radians().sin_cos();
            let w = [b.cos() * c, b.cos() * s, -b.sin()];
            for i in 0..3 {
                assert!(close(m[i], w[i], 1e-15), "face {k}: {m:?} vs {w:?}");
            }
        }
        // At the apex: n = −axis; straight below it, too.
        let q = p.project([0.0; 3]).unwrap();
        assert_eq!((q.gap, q.normal), (0.0, [0.0, 0.0, -1.0]));
        let q = p.project([0.0, 0.0, -0.5]).unwrap();
        assert_eq!(
            (q.gap, q.normal, q.closest),
            (0.5, [0.0, 0.0, -1.0], [0.0; 3])
        );
        // Inside on the axis: the first face is taken.
        let q = p.project([0.0, 0.0, 1.0]).unwrap();
        assert!(close(q.gap, -b.sin(), 1e-15) && q.normal == p.face_normal(0));
    }

    #[test]
    fn pyramid_random_points() {
        let mut rng = StdRng::seed_from_u64(13);
        for _ in 0..400 {
            let apex = rand_vec(&mut rng, -1.0, 1.0, 3);
            let a = rand_unit(&mut rng, 3);
            let deg = rng.gen_range(10.0..85.0);
            let nf = rng.gen_range(3..9);
            let az = rng.gen_range(-400.0..400.0);
            let p = Pyramid::new(apex, a.map(|x| 2.0 * x), deg, nf, az, 3).unwrap();
            let o = Obstacle::Pyramid(p);
            // Independent face normals: m_0 rotated about the axis by 360° k / N.
            let m0 = p.face_normal(0);
            assert!(close(dot(m0, a), -f64::to_radians(deg).sin(), 1e-14));
            let ms: Vec<[f64; 3]> = (0..nf)
                .map(|k| rotate(m0, a, std::f64::consts::TAU * k as f64 / nf as f64))
                .collect();
            for (k, m) in ms.iter().enumerate() {
                let mk = p.face_normal(k);
                assert!((0..3).all(|i| close(mk[i], m[i], 1e-13)), "face {k}");
            }
            // Independent edges: m_k × m_{k+1}, oriented into the indenter.
            let es: Vec<[f64; 3]> = (0..nf)
                .map(|k| {
                    let e = cross3(ms[k], ms[(k + 1) % nf]);
                    let e = scale(1.0 / norm(e), e);
                    if dot(e, a) < 0.0 {
                        scale(-1.0, e)
                    } else {
                        e
                    }
                })
                .collect();
            for (k, e) in es.iter().enumerate() {
                let ek = p.edge(k);
                assert!((0..3).all(|i| close(ek[i], e[i], 1e-13)), "edge {k}");
            }
            let x = match rng.gen_range(0..3) {
                0 => rand_vec(&mut rng, -3.0, 3.0, 3),
                1 => axpy(apex, 1e-3, rand_vec(&mut rng, -1.0, 1.0, 3)),
                // near an edge
                _ => {
                    let y = axpy(apex, rng.gen_range(0.0..2.0), es[rng.gen_range(0..nf)]);
                    axpy(y, 1e-4, rand_vec(&mut rng, -1.0, 1.0, 3))
                }
            };
            let q = o.project(x).unwrap();
            let d = sub(x, apex);
            let y = sub(q.closest, apex);
            let smax = ms.iter().map(|m| dot(d, *m)).fold(f64::MIN, f64::max);
            // The closest point is on the surface.
            let ymax = ms.iter().map(|m| dot(y, *m)).fold(f64::MIN, f64::max);
            assert!(ymax.abs() < 1e-12, "{ymax}");
            let smooth = if smax <= 0.0 {
                // Inside: the distance to the nearest face plane.
                assert!(close(q.gap, smax, 1e-13), "{} vs {smax}", q.gap);
                let mut s: Vec<f64> = ms.iter().map(|m| dot(d, *m)).collect();
                s.sort_by(|u, v| v.total_cmp(u));
                s[0] - s[1] > 1e-4
            } else {
                // Outside: y is the projection onto the convex cone K (Moreau): y ∈ K,
                // (d − y)·y = 0 and d − y in the polar cone, i.e. (d − y)·e_k ≤ 0 for the
                // generators e_k of K.
                let w = sub(d, y);
                assert!(close(q.gap, norm(w), 1e-12) && q.gap > 0.0);
                assert!(dot(w, y).abs() < 1e-12, "{}", dot(w, y));
                for e in &es {
                    assert!(dot(w, *e) < 1e-12, "{}", dot(w, *e));
                }
                // The distance to a convex set is smooth outside it (its Hessian ~ 1/gap).
                q.gap > 1e-3
            };
            check_common(&o, x, &q, smooth, "pyramid");
        }
    }

    /// Independent signed distance of the punch from its meridian profile: the flat segment
    /// t = 0, ρ ≤ R − r_e, the quarter arc of radius r_e about (r_e, R − r_e) and the side
    /// ρ = R, t ≥ r_e; negative inside.
    fn punch_gap_by_profile(t: f64, rho: f64, r: f64, h: f64) -> f64 {
        let rp = r - h;
        let seg = |p: (f64, f64), a: (f64, f64), b: (f64, f64)| {
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let l2 = dx * dx + dy * dy;
            let s = if l2 > 0.0 {
                (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p.0 - a.0 - s * dx).hypot(p.1 - a.1 - s * dy)
        };
        let flat = seg((t, rho), (0.0, 0.0), (0.0, rp));
        let side = if t >= h {
            (rho - r).abs()
        } else {
            (t - h).hypot(rho - r)
        };
        let arc = if t <= h && rho >= rp {
            ((t - h).hypot(rho - rp) - h).abs()
        } else {
            t.hypot(rho - rp).min((t - h).hypot(rho - r))
        };
        let dist = flat.min(side).min(arc);
        let inside = t >= 0.0 && rho <= r && !(t < h && rho > rp && (t - h).hypot(rho - rp) > h);
        if inside {
            -dist
        } else {
            dist
        }
    }

    #[test]
    fn punch_random_points_2d_and_3d() {
        let mut rng = StdRng::seed_from_u64(14);
        for dim in [2, 3] {
            for case in 0..450 {
                let c0 = rand_vec(&mut rng, -1.0, 1.0, dim);
                let a = rand_unit(&mut rng, dim);
                let r = rng.gen_range(0.2..2.0);
                // sharp, round-nosed and in between
                let h = match case % 3 {
                    0 => 0.0,
                    1 => r,
                    _ => rng.gen_range(0.0..r),
                };
                let p = Punch::new(c0, a.map(|x| 4.0 * x), r, h, dim).unwrap();
                let o = Obstacle::Punch(p);
                assert_eq!(o.dim(), dim);
                let x = match rng.gen_range(0..3) {
                    0 => axpy(c0, 1.5 * r, rand_vec(&mut rng, -1.0, 1.0, dim)),
                    // near the edge
                    1 => {
                        let w = if dim == 2 {
                            [-a[1], a[0], 0.0]
                        } else {
                            let w = cross3(a, rand_unit(&mut rng, 3));
                            scale(1.0 / norm(w), w)
                        };
                        let y = add(c0, scale(r, w));
                        axpy(y, 1e-3 * r + h, rand_vec(&mut rng, -1.0, 1.0, dim))
                    }
                    // near the face centre, and on the axis
                    _ => axpy(c0, rng.gen_range(-0.5..1.5) * r, a),
                };
                let q = o.project(x).unwrap();
                let d = sub(x, c0);
                let t = dot(d, a);
                let rho = norm(cross3(d, a));
                let want = punch_gap_by_profile(t, rho, r, h);
                assert!(
                    close(q.gap, want, 1e-12),
                    "{dim}D R {r} r_e {h}: {} vs {want} at t {t} rho {rho}",
                    q.gap
                );
                // Smooth away from the axis (ρ = 0 is a symmetry line), the sharp corner, the
                // face-side ties inside (t − r_e = R − r_e − ρ) and their extension.
                let (u, v) = (h - t, rho - (r - h));
                let smooth = rho > 1e-3
                    && (u.abs() > 1e-3 || v.abs() > 1e-3)
                    && !(u <= 1e-3 && v <= 1e-3 && (u - v).abs() < 1e-3);
                check_common(&o, x, &q, smooth, "punch");
            }
        }
    }

    #[test]
    fn punch_known_values() {
        // 3D punch, face centred at the origin, axis +z, R = 1, r_e = 0.2.
        let p = Punch::new([0.0; 3], [0.0, 0.0, 1.0], 1.0, 0.2, 3).unwrap();
        // Below the face: the flat face is nearest, n = −axis.
        let q = p.project([0.3, 0.0, -0.5]).unwrap();
        assert_eq!((q.gap, q.normal), (0.5, [0.0, 0.0, -1.0]));
        assert!(close(q.closest[0], 0.3, 1e-15) && q.closest[2] == 0.0);
        // Beside the side: n radial.
        let q = p.project([0.0, 1.5, 2.0]).unwrap();
        assert_eq!((q.gap, q.normal), (0.5, [0.0, 1.0, 0.0]));
        // Diagonally off the rounded edge: centre of the edge circle (t, ρ) = (0.2, 0.8).
        let q = p.project([1.1, 0.0, -0.2]).unwrap();
        assert!(close(q.gap, 0.5 - 0.2, 1e-15), "{}", q.gap);
        assert!(close(q.normal[0], 0.6, 1e-15) && close(q.normal[2], -0.8, 1e-15));
        // Inside, nearer the face than the side: depth along −axis; a tie goes to the face.
        let q = p.project([0.0, 0.0, 0.1]).unwrap();
        assert_eq!((q.gap, q.normal), (-0.1, [0.0, 0.0, -1.0]));
        let q = p.project([0.6, 0.0, 0.4]).unwrap();
        assert!(close(q.gap, -0.4, 1e-15) && q.normal == [0.0, 0.0, -1.0]);
        // Deep inside on the axis: the side towards r0 = +x.
        let q = p.project([0.0, 0.0, 3.0]).unwrap();
        assert_eq!((q.gap, q.normal), (-1.0, [1.0, 0.0, 0.0]));
        // 2D strip, sharp corners: a point off the corner (1, 0) at (2, −1).
        let p = Punch::new([0.0; 3], [0.0, 1.0, 0.0], 1.0, 0.0, 2).unwrap();
        let q = p.project([2.0, -1.0, 5.0]).unwrap();
        let s = 0.5f64.sqrt();
        assert!(close(q.gap, 2f64.sqrt(), 1e-15));
        assert!(close(q.normal[0], s, 1e-15) && close(q.normal[1], -s, 1e-15));
        assert!(close(q.closest[0], 1.0, 1e-15) && close(q.closest[1], 0.0, 1e-15));
    }

    #[test]
    fn invalid_indenter_data() {
        let z = [0.0, 0.0, 1.0];
        assert_eq!(
            Cylinder::new([0.0; 3], [0.0, 1.0, 0.0], 1.0, 2),
            Err(ObstacleError::Only3D("cylinder"))
        );
        assert_eq!(
            Cylinder::new([0.0; 3], [0.0; 3], 1.0, 3),
            Err(ObstacleError::ZeroAxis)
        );
        assert_eq!(
            Cylinder::new([0.0; 3], z, 0.0, 3),
            Err(ObstacleError::BadRadius)
        );
        assert_eq!(
            Cylinder::new([0.0; 3], z, f64::INFINITY, 3),
            Err(ObstacleError::NotFinite)
        );
        for bad in [0.0, 90.0, -5.0, 120.0] {
            assert_eq!(
                Cone::new([0.0; 3], z, bad, 3),
                Err(ObstacleError::BadHalfAngle)
            );
            assert_eq!(
                Pyramid::new([0.0; 3], z, bad, 4, 0.0, 3),
                Err(ObstacleError::BadHalfAngle)
            );
        }
        assert_eq!(
            Cone::new([0.0; 3], [0.0, 1.0, 1.0], 30.0, 2),
            Err(ObstacleError::NonZeroZ)
        );
        assert_eq!(
            Cone::new([0.0; 3], z, f64::NAN, 3),
            Err(ObstacleError::NotFinite)
        );
        assert_eq!(
            Pyramid::new([0.0; 3], [0.0, 1.0, 0.0], 60.0, 4, 0.0, 2),
            Err(ObstacleError::Only3D("pyramid"))
        );
        for n in [0, 2, MAX_FACES + 1] {
            assert_eq!(
                Pyramid::new([0.0; 3], z, 60.0, n, 0.0, 3),
                Err(ObstacleError::BadFaces(n))
            );
        }
        assert!(Pyramid::new([0.0; 3], z, 60.0, MAX_FACES, 0.0, 3).is_ok());
        assert_eq!(
            Pyramid::new([0.0; 3], z, 60.0, 3, f64::INFINITY, 3),
            Err(ObstacleError::NotFinite)
        );
        assert_eq!(
            Punch::new([0.0; 3], z, 1.0, 1.5, 3),
            Err(ObstacleError::BadEdgeRadius)
        );
        assert_eq!(
            Punch::new([0.0; 3], z, 1.0, -0.1, 3),
            Err(ObstacleError::BadEdgeRadius)
        );
        assert_eq!(
            Punch::new([0.0; 3], z, -1.0, 0.0, 3),
            Err(ObstacleError::BadRadius)
        );
        assert!(Punch::new([0.0; 3], z, 1.0, 1.0, 3).is_ok());
        let c = Cone::new([0.0; 3], z, 30.0, 3).unwrap();
        assert_eq!(
            c.project([f64::NAN, 0.0, 0.0]),
            Err(ObstacleError::NotFinite)
        );
        assert!(ObstacleError::Only3D("cylinder")
            .to_string()
            .contains("cylinder"));
        assert!(ObstacleError::BadFaces(2).to_string().contains("got 2"));
    }
}
