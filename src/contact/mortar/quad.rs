//! Segment-to-segment (2D) and triangle-to-triangle (3D) overlaps of a slave facet with a
//! master facet projected along the slave facet normal, as quadrature points exact for
//! products of two linear functions (degree 2) on the overlap.

use super::geom::{barycentric, cross, cross2, dot, norm, polygon_area2, sub, unit};

/// Overlaps (and clip polygons) of measure ≤ this × the slave facet's measure are dropped.
pub const OVERLAP_TOL: f64 = 1e-14;

/// A quadrature point on a slave facet: weight `w` (length/area measure), the slave shape
/// function values `phi_s`, the master facet it projects onto and the master shape function
/// values `phi_m` there (entries past the facet's node count are 0).
#[derive(Debug, Clone, Copy)]
pub struct QuadPoint {
    pub w: f64,
    pub phi_s: [f64; 3],
    pub master: usize,
    pub phi_m: [f64; 3],
}

/// 2D: the master segment `xm` (index `master`) projected orthogonally onto the line of the
/// slave segment `xs`, clipped to the slave segment; 2-point Gauss on the overlap (exact:
/// the master coordinate is affine in the slave one, ψ φ is quadratic). Returns the
/// overlap length (0 when dropped: no overlap, length ≤ [`OVERLAP_TOL`] relative, or a
/// master segment perpendicular to the slave one).
pub fn segment_points(
    xs: &[[f64; 3]],
    xm: &[[f64; 3]],
    master: usize,
    out: &mut Vec<QuadPoint>,
) -> f64 {
    let t = sub(xs[1], xs[0]);
    let len = norm(t);
    let s = |p: [f64; 3]| dot(sub(p, xs[0]), t) / (len * len);
    let (s0, s1) = (s(xm[0]), s(xm[1]));
    if (s1 - s0).abs() <= OVERLAP_TOL {
        return 0.0;
    }
    let lo = s0.min(s1).max(0.0);
    let hi = s0.max(s1).min(1.0);
    if hi - lo <= OVERLAP_TOL {
        return 0.0;
    }
    let g = 0.5 / 3f64.sqrt();
    for q in [0.5 - g, 0.5 + g] {
        let sq = lo + q * (hi - lo);
        let eta = (sq - s0) / (s1 - s0);
        out.push(QuadPoint {
            w: 0.5 * (hi - lo) * len,
            phi_s: [1.0 - sq, sq, 0.0],
            master,
            phi_m: [1.0 - eta, eta, 0.0],
        });
    }
    (hi - lo) * len
}

/// 3D: the master triangle `xm` (index `master`) projected orthogonally into the plane of
/// the slave triangle `xs`, clipped to it (Sutherland–Hodgman against the convex slave
/// triangle), the clip polygon cut into a fan of triangles from its vertex average, each
/// integrated by the 3-point degree-2 rule (exact: both shape functions are affine in the
/// plane). Returns the clip polygon's area (0 when dropped: empty, area ≤ [`OVERLAP_TOL`]
/// relative, or a master triangle seen edge-on).
pub fn triangle_points(
    xs: &[[f64; 3]],
    xm: &[[f64; 3]],
    master: usize,
    out: &mut Vec<QuadPoint>,
) -> f64 {
    let e1 = unit(sub(xs[1], xs[0]));
    let g = cross(sub(xs[1], xs[0]), sub(xs[2], xs[0]));
    let slave_area = 0.5 * norm(g);
    let e2 = cross(unit(g), e1);
    let proj = |p: [f64; 3]| {
        let d = sub(p, xs[0]);
        [dot(d, e1), dot(d, e2)]
    };
    let st = [proj(xs[0]), proj(xs[1]), proj(xs[2])];
    let mt = [proj(xm[0]), proj(xm[1]), proj(xm[2])];
    let tol = OVERLAP_TOL * slave_area;
    if 0.5 * cross2(mt[0], mt[1], mt[2]).abs() <= tol || !boxes_overlap(&st, &mt) {
        return 0.0;
    }
    let poly = clip(mt.to_vec(), &st);
    let area = 0.5 * polygon_area2(&poly).abs();
    if poly.len() < 3 || area <= tol {
        return 0.0;
    }
    let inv = 1.0 / poly.len() as f64;
    let c = poly
        .iter()
        .fold([0.0; 2], |c, p| [c[0] + inv * p[0], c[1] + inv * p[1]]);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let a = 0.5 * cross2(c, p, q).abs();
        if a > 0.0 {
            fan_points(&[c, p, q], a, &st, &mt, master, out);
        }
    }
    area
}

/// The 3-point degree-2 rule (barycentric (2/3, 1/6, 1/6) and permutations, weights a/3)
/// on the plane triangle `t` of area `a`.
fn fan_points(
    t: &[[f64; 2]; 3],
    a: f64,
    st: &[[f64; 2]; 3],
    mt: &[[f64; 2]; 3],
    master: usize,
    out: &mut Vec<QuadPoint>,
) {
    for k in 0..3 {
        let mut l = [1.0 / 6.0; 3];
        l[k] = 2.0 / 3.0;
        let q = [
            l[0] * t[0][0] + l[1] * t[1][0] + l[2] * t[2][0],
            l[0] * t[0][1] + l[1] * t[1][1] + l[2] * t[2][1],
        ];
        out.push(QuadPoint {
            w: a / 3.0,
            phi_s: barycentric(st, q),
            master,
            phi_m: barycentric(mt, q),
        });
    }
}

/// Whether the bounding boxes of two plane triangles overlap.
fn boxes_overlap(a: &[[f64; 2]; 3], b: &[[f64; 2]; 3]) -> bool {
    (0..2).all(|d| {
        let lo = |t: &[[f64; 2]; 3]| t.iter().fold(f64::INFINITY, |m, p| m.min(p[d]));
        let hi = |t: &[[f64; 2]; 3]| t.iter().fold(f64::NEG_INFINITY, |m, p| m.max(p[d]));
        lo(a) <= hi(b) && lo(b) <= hi(a)
    })
}

/// Sutherland–Hodgman: the polygon `subject` (either orientation) clipped to the
/// counter-clockwise triangle `clipper` (kept: the left of each of its edges).
pub fn clip(subject: Vec<[f64; 2]>, clipper: &[[f64; 2]; 3]) -> Vec<[f64; 2]> {
    let mut out = subject;
    for e in 0..3 {
        let (c0, c1) = (clipper[e], clipper[(e + 1) % 3]);
        let input = std::mem::take(&mut out);
        for i in 0..input.len() {
            let (p, q) = (input[i], input[(i + 1) % input.len()]);
            let (dp, dq) = (cross2(c0, c1, p), cross2(c0, c1, q));
            if dp >= 0.0 {
                out.push(p);
            }
            if (dp >= 0.0) != (dq >= 0.0) {
                let s = dp / (dp - dq);
                out.push([p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])]);
            }
        }
    }
    out
}
