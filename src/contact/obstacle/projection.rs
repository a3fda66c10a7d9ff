//! What a query of an obstacle returns.

/// Closest point, normal (unit, into the body) and initial gap g0 of a point x.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    pub closest: [f64; 3],
    pub normal: [f64; 3],
    pub gap: f64,
}
