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

use crate::error::InputError;
use crate::geom::{dot, sub};
use std::fmt;
use std::path::Path;

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
        }
    }
}

impl std::error::Error for ObstacleError {}

impl ObstacleError {
    /// Wrap as a user-facing [`InputError`] for the case file `file`, key `key`.
    pub fn into_input_error(self, file: &Path, key: &str) -> InputError {
        InputError::new(file, self.to_string()).with_key(key)
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
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Obstacle {
    Plane(Plane),
    Sphere(Sphere),
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

impl Obstacle {
    pub fn dim(&self) -> usize {
        match self {
            Obstacle::Plane(p) => p.dim(),
            Obstacle::Sphere(s) => s.dim(),
        }
    }
    /// Closest point, normal (into the body) and initial gap g0(x) (3.3).
    pub fn project(&self, x: [f64; 3]) -> Result<Projection, ObstacleError> {
        match self {
            Obstacle::Plane(p) => Ok(p.project(x)),
            Obstacle::Sphere(s) => s.project(x),
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
}
