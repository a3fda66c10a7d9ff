//! Small vector helpers on `[f64; 3]` and `[f64; 2]`, facet measures and normals, and
//! barycentric coordinates in a plane.

/// a − b.
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// a + s b.
pub fn axpy(a: [f64; 3], s: f64, b: [f64; 3]) -> [f64; 3] {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}

/// s a.
pub fn scale(s: f64, a: [f64; 3]) -> [f64; 3] {
    [s * a[0], s * a[1], s * a[2]]
}

/// a · b.
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a × b.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// |a|.
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// a / |a| (a ≠ 0).
pub fn unit(a: [f64; 3]) -> [f64; 3] {
    scale(1.0 / norm(a), a)
}

/// The measure (length in 2D, area in 3D) and the unit normal of a facet whose orientation
/// is given by its node order: 2D segment a→b: n = (t_y, −t_x) for the unit tangent t (the
/// right of the travel direction, outward for a body traversed counter-clockwise); 3D
/// triangle a, b, c: n = (b − a) × (c − a) / |·| (outward when the nodes turn
/// counter-clockwise seen from outside). A degenerate facet gives measure 0 and n = 0.
pub fn facet_measure_normal(x: &[[f64; 3]]) -> (f64, [f64; 3]) {
    if x.len() == 2 {
        let t = sub(x[1], x[0]);
        let len = norm(t);
        let n = [t[1], -t[0], 0.0];
        return (len, if len > 0.0 { scale(1.0 / len, n) } else { n });
    }
    let g = cross(sub(x[1], x[0]), sub(x[2], x[0]));
    let twice = norm(g);
    (
        0.5 * twice,
        if twice > 0.0 {
            scale(1.0 / twice, g)
        } else {
            g
        },
    )
}

/// Twice the signed area of the plane triangle (a, b, c) (positive counter-clockwise).
pub fn cross2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// The barycentric coordinates of `p` in the plane triangle `t` (non-degenerate): the
/// values at `p` of the three linear shape functions of `t`.
pub fn barycentric(t: &[[f64; 2]; 3], p: [f64; 2]) -> [f64; 3] {
    let det = cross2(t[0], t[1], t[2]);
    let l1 = cross2(t[0], p, t[2]) / det;
    let l2 = cross2(t[0], t[1], p) / det;
    [1.0 - l1 - l2, l1, l2]
}

/// Twice the signed area of a plane polygon (shoelace formula).
pub fn polygon_area2(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum()
}
