//! The regular pyramid.

use super::error::ObstacleError;
pub use super::error::{MAX_FACES, MIN_FACES};
use super::projection::Projection;
use super::vec3::{
    add, axpy, check_axis_3d, finite, half_angle_sin_cos, norm, reference_direction, scale,
};
use crate::geom::{cross, dot, sub};
use std::f64::consts::{PI, TAU};

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
        let axis = check_axis_3d("pyramid", dim, &apex, &axis, &[half_angle, azimuth])?;
        let (sin, cos) = half_angle_sin_cos(half_angle)?;
        if !(MIN_FACES..=MAX_FACES).contains(&faces) {
            return Err(ObstacleError::BadFaces(faces));
        }
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
        let apex = Projection::to_apex(self.apex, self.axis, d);
        if apex.gap == 0.0 {
            return Ok(apex);
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
        let mut best = apex;
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
