//! What a query of an obstacle returns.

use super::vec3::{norm, scale};

/// Closest point, normal (unit, into the body) and initial gap g0 of a point x.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    pub closest: [f64; 3],
    pub normal: [f64; 3],
    pub gap: f64,
}

impl Projection {
    /// The apex `apex` of a tip whose unit axis `axis` points into the indenter as the
    /// nearest point of x = apex + d: g0 = |d|, n = d/|d|; at the apex itself (|d| = 0)
    /// g0 = 0, n = −a.
    pub(super) fn to_apex(apex: [f64; 3], axis: [f64; 3], d: [f64; 3]) -> Projection {
        let len = norm(d);
        let normal = if len == 0.0 {
            scale(-1.0, axis)
        } else {
            scale(1.0 / len, d)
        };
        Projection {
            closest: apex,
            normal,
            gap: len,
        }
    }
}
