//! Small 3-vector helpers shared by the element, mesh and contact code (2D points carry z = 0).

/// a − b.
#[inline(always)]
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// a · b.
#[inline(always)]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a × b.
#[inline(always)]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// |a|².
#[inline(always)]
pub fn norm2(a: [f64; 3]) -> f64 {
    dot(a, a)
}

/// Key of a point on the Morton (Z-order) curve of the box from `lo` of size `extent`:
/// coordinates scaled to 21-bit integers (clamped to the box), bits interleaved. Used to order
/// nodes (partition, dist) and cells (`convert`) along space.
pub fn morton_key(x: &[f64; 3], dim: usize, lo: &[f64; 3], extent: f64) -> u64 {
    let scale = ((1u64 << 21) - 1) as f64 / extent;
    let mut q = [0u64; 3];
    for k in 0..dim {
        q[k] = (((x[k] - lo[k]) * scale).max(0.0) as u64).min((1 << 21) - 1);
    }
    let mut key = 0u64;
    for bit in (0..21).rev() {
        for qk in &q[..dim] {
            key = (key << 1) | ((qk >> bit) & 1);
        }
    }
    key
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn right_handed() {
        assert_eq!(cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        assert_eq!(
            dot(sub([3.0, 2.0, 1.0], [1.0, 1.0, 1.0]), [1.0, 1.0, 1.0]),
            3.0
        );
        assert_eq!(norm2([3.0, 4.0, 0.0]), 25.0);
    }
}
