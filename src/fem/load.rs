//! Load vectors (the f of (3.8)): boundary tractions and body forces on P1 cells/facets,
//! lumped for constant data, by quadrature for variable data.

use crate::geom::{cross, dot, sub};

/// Unit normal and measure (length in 2D, area in 3D) of a boundary facet.
///
/// 2D: `x` = 2 points in the xy plane (z ignored); the normal is the tangent x1 - x0 turned
/// clockwise by 90°, i.e. it points to the RIGHT of the direction x0 -> x1. On the boundary
/// of a counter-clockwise oriented domain (positively oriented triangles, interior to the
/// left) this is the outward normal.
/// 3D: `x` = 3 points; the normal is (x1 - x0) x (x2 - x0) normalised (right-hand rule):
/// outward when the nodes run counter-clockwise seen from outside the body.
///
/// A degenerate facet gives the zero vector and measure 0.
/// Panics if `x` has neither 2 nor 3 points (a programming error).
pub fn facet_normal_measure(x: &[[f64; 3]]) -> ([f64; 3], f64) {
    match x.len() {
        2 => {
            let tx = x[1][0] - x[0][0];
            let ty = x[1][1] - x[0][1];
            let len = tx.hypot(ty);
            if len == 0.0 {
                return ([0.0; 3], 0.0);
            }
            ([ty / len, -tx / len, 0.0], len)
        }
        3 => {
            let c = cross(sub(x[1], x[0]), sub(x[2], x[0]));
            let n2 = dot(c, c).sqrt();
            if n2 == 0.0 {
                return ([0.0; 3], 0.0);
            }
            ([c[0] / n2, c[1] / n2, c[2] / n2], 0.5 * n2)
        }
        n => panic!("facet_normal_measure: a facet has 2 or 3 points, got {n}"),
    }
}

/// (3.8): consistent load of a CONSTANT traction on a P1 facet (exact): each of the `dim`
/// facet nodes gets traction * measure / dim. `out` (length dim*dim, node-major) is overwritten.
/// Only the first `dim` components of `traction` are used.
pub fn lumped_facet_load(measure: f64, traction: [f64; 3], dim: usize, out: &mut [f64]) {
    spread(measure / dim as f64, traction, dim, dim, out);
}

/// (3.8): consistent load of a CONSTANT body force on a P1 cell (exact): each of the dim+1 cell
/// nodes gets f * measure / (dim+1). `out` (length (dim+1)*dim, node-major) is overwritten.
pub fn body_force_load(measure: f64, f: [f64; 3], dim: usize, out: &mut [f64]) {
    spread(measure / (dim + 1) as f64, f, dim + 1, dim, out);
}

fn spread(w: f64, v: [f64; 3], nodes: usize, dim: usize, out: &mut [f64]) {
    assert_eq!(out.len(), nodes * dim, "load: wrong output length");
    for a in 0..nodes {
        for i in 0..dim {
            out[a * dim + i] = w * v[i];
        }
    }
}

/// Unsigned measure of a simplex given by its vertices: 2 points = length, 3 = area,
/// 4 = volume. In 2D (`dim` = 2) the z coordinates are ignored.
pub fn simplex_measure(x: &[[f64; 3]], dim: usize) -> f64 {
    let p = |k: usize| -> [f64; 3] {
        if dim == 2 {
            [x[k][0], x[k][1], 0.0]
        } else {
            x[k]
        }
    };
    match x.len() {
        2 => {
            let d = sub(p(1), p(0));
            dot(d, d).sqrt()
        }
        3 => {
            let c = cross(sub(p(1), p(0)), sub(p(2), p(0)));
            0.5 * dot(c, c).sqrt()
        }
        4 => {
            let c = cross(sub(p(2), p(0)), sub(p(3), p(0)));
            dot(sub(p(1), p(0)), c).abs() / 6.0
        }
        n => panic!("simplex_measure: 2, 3 or 4 points expected, got {n}"),
    }
}

/// A quadrature point on a simplex: barycentric coordinates (unused trailing entries 0) and
/// weight relative to the simplex measure (the weights of a rule sum to 1).
#[derive(Clone, Copy, Debug)]
pub struct QuadPoint {
    pub bary: [f64; 4],
    pub weight: f64,
}

// Two-point Gauss on a line: (1 ± 1/sqrt 3)/2, exact for degree 3.
const LINE_A: f64 = 0.788_675_134_594_812_9;
const LINE_B: f64 = 0.211_324_865_405_187_13;
static LINE_RULE: [QuadPoint; 2] = [
    QuadPoint {
        bary: [LINE_A, LINE_B, 0.0, 0.0],
        weight: 0.5,
    },
    QuadPoint {
        bary: [LINE_B, LINE_A, 0.0, 0.0],
        weight: 0.5,
    },
];

// Triangle, 3 interior points (2/3, 1/6, 1/6), exact for degree 2.
const TRI_A: f64 = 2.0 / 3.0;
const TRI_B: f64 = 1.0 / 6.0;
static TRI_RULE: [QuadPoint; 3] = [
    QuadPoint {
        bary: [TRI_A, TRI_B, TRI_B, 0.0],
        weight: 1.0 / 3.0,
    },
    QuadPoint {
        bary: [TRI_B, TRI_A, TRI_B, 0.0],
        weight: 1.0 / 3.0,
    },
    QuadPoint {
        bary: [TRI_B, TRI_B, TRI_A, 0.0],
        weight: 1.0 / 3.0,
    },
];

// Tetrahedron, 4 points (a, b, b, b), a = (5 + 3 sqrt 5)/20, b = (5 - sqrt 5)/20, exact for
// degree 2.
const TET_A: f64 = 0.585_410_196_624_968_5;
const TET_B: f64 = 0.138_196_601_125_010_5;
static TET_RULE: [QuadPoint; 4] = [
    QuadPoint {
        bary: [TET_A, TET_B, TET_B, TET_B],
        weight: 0.25,
    },
    QuadPoint {
        bary: [TET_B, TET_A, TET_B, TET_B],
        weight: 0.25,
    },
    QuadPoint {
        bary: [TET_B, TET_B, TET_A, TET_B],
        weight: 0.25,
    },
    QuadPoint {
        bary: [TET_B, TET_B, TET_B, TET_A],
        weight: 0.25,
    },
];

/// Quadrature rule exact for polynomials of degree 2 on a simplex with `nverts` vertices
/// (2 = line: 2-point Gauss, degree 3; 3 = triangle; 4 = tetrahedron).
/// Panics for other `nverts` (a programming error).
pub fn simplex_quadrature(nverts: usize) -> &'static [QuadPoint] {
    match nverts {
        2 => &LINE_RULE,
        3 => &TRI_RULE,
        4 => &TET_RULE,
        n => panic!("simplex_quadrature: 2, 3 or 4 vertices expected, got {n}"),
    }
}

/// (3.8): consistent load ∫ f phi_a of a variable vector field `f` over a P1 simplex:
/// a boundary facet (traction) or a cell (body force). `x` holds the simplex vertices
/// (2 = segment, 3 = triangle, 4 = tetrahedron; z ignored and set to 0 in 2D), `dim` is the
/// number of displacement components. `out` (length x.len()*dim, node-major) is overwritten.
///
/// The rule is exact for degree 2, so the load is exact for f linear (f phi_a quadratic) and
/// the total ∑_a out is exact for f quadratic.
pub fn cell_load_quadrature(
    x: &[[f64; 3]],
    dim: usize,
    f: &dyn Fn([f64; 3]) -> [f64; 3],
    out: &mut [f64],
) {
    let n = x.len();
    assert_eq!(
        out.len(),
        n * dim,
        "cell_load_quadrature: wrong output length"
    );
    let measure = simplex_measure(x, dim);
    out.iter_mut().for_each(|v| *v = 0.0);
    for q in simplex_quadrature(n) {
        let mut p = [0.0; 3];
        for (a, xa) in x.iter().enumerate() {
            for c in 0..3 {
                p[c] += q.bary[a] * xa[c];
            }
        }
        if dim == 2 {
            p[2] = 0.0;
        }
        let fv = f(p);
        let w = q.weight * measure;
        for a in 0..n {
            for i in 0..dim {
                out[a * dim + i] += w * q.bary[a] * fv[i];
            }
        }
    }
}
