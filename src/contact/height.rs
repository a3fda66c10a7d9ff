//! The `height` obstacle: the solid below the graph of a function, {y < h(x)} in 2D and
//! {z < h(x, y)} in 3D, the body above it (docs/obstacles.md, "height").
//!
//! h is an expression of the case file, parsed once ([`HeightExpr`], a [`crate::expr::Expr`])
//! and evaluated at the contact nodes. For a point x the nearest point of the graph is found by a safeguarded
//! Newton iteration on the squared distance, started at the vertical projection
//! ([`Height::project`]); the derivatives of h are central differences with steps scaled to
//! the point's size. g0 is the signed distance (positive above the graph), n the unit upward
//! normal of the graph at the nearest point: the gradient of g0 on both sides.

use super::obstacle::{ObstacleError, Projection};
use crate::expr::{quoted, Expr};
use std::sync::Arc;

pub use crate::expr::FUNCTIONS;

/// A parsed height expression h(x) (2D) or h(x, y) (3D): an [`Expr`] of the case file (its
/// syntax, functions and constants) whose variables are x (and y).
#[derive(Debug, PartialEq)]
pub struct HeightExpr(Expr);

impl HeightExpr {
    /// Parses `text`; the error is a sentence for the user (see [`Expr::parse`]).
    pub fn parse(text: &str) -> Result<Self, String> {
        Expr::parse(text).map(HeightExpr)
    }

    /// The expression as written.
    pub fn text(&self) -> &str {
        self.0.text()
    }

    /// The names of the variables the expression reads (sorted; without pi and e).
    pub fn variables(&self) -> &[String] {
        self.0.variables()
    }

    /// Ok when every variable is x (2D) or x or y (3D); else a message naming the others.
    pub fn check_variables(&self, dim: usize) -> Result<(), String> {
        let allowed: &[&str] = if dim == 2 { &["x"] } else { &["x", "y"] };
        let bad = self.0.unknown_variables(allowed);
        if bad.is_empty() {
            return Ok(());
        }
        let what = if dim == 2 {
            "in 2D the height is y = h(x): the only variable is x"
        } else {
            "in 3D the height is z = h(x, y): the only variables are x and y"
        };
        Err(format!(
            "unknown variable{} {}; {what}",
            if bad.len() > 1 { "s" } else { "" },
            quoted(&bad)
        ))
    }

    /// h(u) (u = [x, y]; y is ignored by 2D expressions). NaN where the evaluation fails or
    /// gives no number.
    pub fn eval(&self, u: [f64; 2]) -> f64 {
        self.0.eval([u[0], u[1], 0.0])
    }
}

/// The height obstacle of dimension `dim` (the parsed expression shared, not copied).
#[derive(Debug, Clone, PartialEq)]
pub struct Height {
    dim: usize,
    expr: Arc<HeightExpr>,
}

/// Most Newton iterations of a projection.
const MAX_ITER: usize = 60;
/// Convergence: a Newton step shorter than this times the point's scale.
const STEP_TOL: f64 = 1e-11;
/// A step this short (times the scale) is accepted even when the line search stalls on
/// round-off in the distance.
const STALL_TOL: f64 = 1e-8;
/// Newton steps this short (times the scale) are taken without line search.
const LOCAL_TOL: f64 = 1e-6;

/// h and its first and second derivatives at u by central differences: steps ε^(1/3) s for
/// the first, ε^(1/4) s for the second derivatives (s: the point's scale). Only the first
/// `n` parameters are used (n = 1 in 2D, 2 in 3D).
struct Local {
    h: f64,
    g: [f64; 2],
    hess: [[f64; 2]; 2],
}

impl Height {
    /// The obstacle below h for a mesh of dimension `dim` (2 or 3); the expression must use
    /// only x (2D) or x, y (3D).
    pub fn new(expr: Arc<HeightExpr>, dim: usize) -> Result<Self, ObstacleError> {
        if dim != 2 && dim != 3 {
            return Err(ObstacleError::BadDim(dim));
        }
        if expr.check_variables(dim).is_err() {
            return Err(ObstacleError::HeightVariables);
        }
        Ok(Height { dim, expr })
    }

    pub fn dim(&self) -> usize {
        self.dim
    }

    pub fn expr(&self) -> &HeightExpr {
        &self.expr
    }

    fn h(&self, u: [f64; 2]) -> f64 {
        self.expr.eval(u)
    }

    fn not_finite(&self, u: [f64; 2]) -> ObstacleError {
        ObstacleError::HeightNotFinite {
            x: u[0],
            y: (self.dim == 3).then_some(u[1]),
        }
    }

    fn local(&self, u: [f64; 2], s: f64) -> Result<Local, ObstacleError> {
        let n = self.dim - 1;
        let (d1, d2) = (f64::EPSILON.cbrt() * s, f64::EPSILON.powf(0.25) * s);
        let at = |i: usize, t: f64| {
            let mut v = u;
            v[i] += t;
            v
        };
        let h = self.h(u);
        let mut g = [0.0; 2];
        let mut hess = [[0.0; 2]; 2];
        for i in 0..n {
            g[i] = (self.h(at(i, d1)) - self.h(at(i, -d1))) / (2.0 * d1);
            hess[i][i] = (self.h(at(i, d2)) - 2.0 * h + self.h(at(i, -d2))) / (d2 * d2);
        }
        if n == 2 {
            let f = |a: f64, b: f64| self.h([u[0] + a, u[1] + b]);
            let c = (f(d2, d2) - f(d2, -d2) - f(-d2, d2) + f(-d2, -d2)) / (4.0 * d2 * d2);
            hess[0][1] = c;
            hess[1][0] = c;
        }
        let all = [h, g[0], g[1], hess[0][0], hess[0][1], hess[1][1]];
        if all.iter().all(|v| v.is_finite()) {
            Ok(Local { h, g, hess })
        } else {
            Err(self.not_finite(u))
        }
    }

    /// The one-sided slopes at the foot agree: a kink (a jump of the slope) or a step of h at
    /// the nearest point has no normal. With the step d = ε^(1/3) s the forward and backward
    /// differences of a C² function differ by d h'' (≤ 10⁻³ unless the radius of curvature is
    /// below s/170, where the differences lose their accuracy anyway).
    fn check_smooth(&self, u: [f64; 2], s: f64, l: &Local) -> Result<(), ObstacleError> {
        let d = f64::EPSILON.cbrt() * s;
        for i in 0..self.dim - 1 {
            let mut v = u;
            v[i] += d;
            let fwd = (self.h(v) - l.h) / d;
            v[i] = u[i] - d;
            let bwd = (l.h - self.h(v)) / d;
            let jump = (fwd - bwd).abs();
            if jump.is_nan() || jump > 1e-3 * (1.0 + l.g[i].abs()) {
                return Err(ObstacleError::HeightNotSmooth {
                    x: u[0],
                    y: (self.dim == 3).then_some(u[1]),
                });
            }
        }
        Ok(())
    }

    /// ½ |(u, h(u)) − x|² (NaN where h is not finite).
    fn phi(&self, u: [f64; 2], x: [f64; 3]) -> f64 {
        let n = self.dim - 1;
        let r = self.h(u) - x[n];
        let mut s = r * r;
        for i in 0..n {
            s += (u[i] - x[i]).powi(2);
        }
        0.5 * s
    }

    /// The nearest point of the graph to x: Newton on φ(u) = ½|(u, h(u)) − x|² from the
    /// vertical projection u = x', with the Gauss-Newton matrix I + ∇h∇hᵀ where the Hessian
    /// I + ∇h∇hᵀ + (h − z)∇²h is not positive definite, and a backtracking (Armijo) line
    /// search. Returns the parameters u of the foot point.
    fn foot(&self, x: [f64; 3], s: f64) -> Result<[f64; 2], ObstacleError> {
        let n = self.dim - 1;
        let mut u = [x[0], if n == 2 { x[1] } else { 0.0 }];
        let mut last = f64::INFINITY;
        for _ in 0..MAX_ITER {
            let l = self.local(u, s)?;
            let r = l.h - x[n];
            let mut grad = [0.0; 2];
            let mut newton = [[0.0; 2]; 2];
            let mut gn = [[0.0; 2]; 2];
            for i in 0..n {
                grad[i] = u[i] - x[i] + r * l.g[i];
                for j in 0..n {
                    let id = if i == j { 1.0 } else { 0.0 };
                    gn[i][j] = id + l.g[i] * l.g[j];
                    newton[i][j] = gn[i][j] + r * l.hess[i][j];
                }
            }
            let (step, pure) = match solve_spd(&newton, &grad, n) {
                Some(d) => (d, true),
                None => (
                    solve_spd(&gn, &grad, n).ok_or(ObstacleError::HeightNoConvergence)?,
                    false,
                ),
            };
            let len = step.iter().map(|v| v * v).sum::<f64>().sqrt();
            // Close to a minimum (positive definite Hessian, a short step) Newton converges
            // without safeguard; there the decrease of φ, of the order of the squared step, is
            // below its round-off and a line search could not judge it.
            // Converged when the steps stop shrinking there: the floor set by the round-off of
            // the differences (≈ 1e-10 s).
            if pure && len <= LOCAL_TOL * s {
                u = [u[0] + step[0], u[1] + step[1]];
                if len <= STEP_TOL * s || len > 0.5 * last {
                    return Ok(u);
                }
                last = len;
                continue;
            }
            last = len;
            let slope: f64 = (0..n).map(|i| grad[i] * step[i]).sum();
            let phi0 = 0.5 * ((0..n).map(|i| (u[i] - x[i]).powi(2)).sum::<f64>() + r * r);
            let mut t = 1.0;
            let mut next = None;
            for _ in 0..40 {
                let cand = [u[0] + t * step[0], u[1] + t * step[1]];
                let p = self.phi(cand, x);
                if p.is_finite() && p <= phi0 + 1e-4 * t * slope {
                    next = Some(cand);
                    break;
                }
                t *= 0.5;
            }
            match next {
                Some(v) => u = v,
                None if len <= STALL_TOL * s => return Ok(u),
                None => return Err(ObstacleError::HeightNoConvergence),
            }
            if t * len <= STEP_TOL * s {
                return Ok(u);
            }
        }
        Err(ObstacleError::HeightNoConvergence)
    }

    /// Closest point, normal (the graph's unit upward normal at the nearest point, into the
    /// body) and signed distance g0 (positive above the graph). Errors: h not finite near x,
    /// or the projection did not converge.
    pub fn project(&self, x: [f64; 3]) -> Result<Projection, ObstacleError> {
        let n = self.dim - 1;
        let x = if self.dim == 2 { [x[0], x[1], 0.0] } else { x };
        if x.iter().any(|v| !v.is_finite()) {
            return Err(ObstacleError::NotFinite);
        }
        let u0 = [x[0], if n == 2 { x[1] } else { 0.0 }];
        let h0 = self.h(u0);
        if !h0.is_finite() {
            return Err(self.not_finite(u0));
        }
        let s = x.iter().fold(h0.abs(), |m, v| m.max(v.abs()));
        let s = if s > 0.0 { s } else { 1.0 };
        let u = self.foot(x, s)?;
        let l = self.local(u, s)?;
        self.check_smooth(u, s, &l)?;
        // Upward unit normal (−∇h, 1)/√(1 + |∇h|²).
        let mut nv = [0.0; 3];
        let len = (1.0 + l.g[0] * l.g[0] + l.g[1] * l.g[1]).sqrt();
        for i in 0..n {
            nv[i] = -l.g[i] / len;
        }
        nv[n] = 1.0 / len;
        let mut foot = [0.0; 3];
        foot[..n].copy_from_slice(&u[..n]);
        foot[n] = l.h;
        let gap: f64 = (0..self.dim).map(|i| (x[i] - foot[i]) * nv[i]).sum();
        // A foot on the wrong side (x above the graph but below its tangent plane at the foot,
        // or the reverse) is a stationary point that is not the nearest one.
        let above = x[n] - h0;
        if above * gap < 0.0 && gap.abs() > 1e-9 * s {
            return Err(ObstacleError::HeightNoConvergence);
        }
        Ok(Projection {
            closest: [x[0] - gap * nv[0], x[1] - gap * nv[1], x[2] - gap * nv[2]],
            normal: nv,
            gap,
        })
    }
}

/// The solution of A d = −b for a symmetric positive definite n × n A (n = 1, 2), by
/// Cholesky; None when A is not (numerically) positive definite.
fn solve_spd(a: &[[f64; 2]; 2], b: &[f64; 2], n: usize) -> Option<[f64; 2]> {
    let l00 = a[0][0];
    if l00.is_nan() || l00 <= 0.0 {
        return None;
    }
    if n == 1 {
        return Some([-b[0] / l00, 0.0]);
    }
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    if det.is_nan() || det <= 1e-14 * a[0][0] * a[1][1] {
        return None;
    }
    Some([
        -(a[1][1] * b[0] - a[0][1] * b[1]) / det,
        -(a[0][0] * b[1] - a[1][0] * b[0]) / det,
    ])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::obstacle::{Obstacle, Plane};
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};
    use std::f64::consts::PI;

    fn height(text: &str, dim: usize) -> Height {
        let e = Arc::new(HeightExpr::parse(text).unwrap());
        Height::new(e, dim).unwrap()
    }

    fn norm(a: [f64; 3]) -> f64 {
        (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
    }

    /// x = closest + g n, |n| = 1, n upward, and the FD gradient of g equal to n.
    fn check_common(h: &Height, x: [f64; 3], q: &Projection, tol: f64) {
        let dim = h.dim();
        assert!((norm(q.normal) - 1.0).abs() < 1e-14);
        assert!(q.normal[dim - 1] > 0.0, "n points up: {:?}", q.normal);
        for k in 0..dim {
            assert!((x[k] - q.closest[k] - q.gap * q.normal[k]).abs() < 1e-12);
        }
        let e = 1e-6;
        for k in 0..dim {
            let (mut a, mut b) = (x, x);
            a[k] += e;
            b[k] -= e;
            let d = (h.project(a).unwrap().gap - h.project(b).unwrap().gap) / (2.0 * e);
            assert!(
                (d - q.normal[k]).abs() < tol,
                "dg/dx{k} = {d}, n = {:?}",
                q.normal
            );
        }
    }

    #[test]
    fn plane_heights_equal_the_plane() {
        let mut rng = StdRng::seed_from_u64(3);
        for (text, dim, normal, point) in [
            ("0.3*x + 0.1", 2, [-0.3, 1.0, 0.0], [0.0, 0.1, 0.0]),
            ("0.3*x - 0.2*y + 0.1", 3, [-0.3, 0.2, 1.0], [0.0, 0.0, 0.1]),
            ("-2", 3, [0.0, 0.0, 1.0], [0.0, 0.0, -2.0]),
        ] {
            let h = height(text, dim);
            let p = Obstacle::Plane(Plane::new(point, normal, dim).unwrap());
            for _ in 0..500 {
                let mut x: [f64; 3] = std::array::from_fn(|_| rng.gen_range(-5.0..5.0));
                if dim == 2 {
                    x[2] = 0.0;
                }
                let (q, r) = (h.project(x).unwrap(), p.project(x).unwrap());
                // Linear h: the differences are exact up to round-off of the O(5) coordinates.
                assert!(
                    (q.gap - r.gap).abs() < 1e-12,
                    "{text}: {} vs {}",
                    q.gap,
                    r.gap
                );
                for k in 0..3 {
                    assert!(
                        (q.normal[k] - r.normal[k]).abs() < 1e-10,
                        "{text}: {q:?} {r:?}"
                    );
                }
                check_common(&h, x, &q, 1e-6);
            }
        }
    }

    /// The cap h = c_y + √(R² − (x − c_x)²) (2D) or its 3D form against the analytic sphere:
    /// for points whose radial direction is within 35° of the vertical, the nearest point of
    /// the circle (sphere) lies on the cap, on both sides.
    #[test]
    fn circle_caps_equal_the_sphere() {
        let (r, c) = (0.7, [0.2, -0.3, 0.4]);
        let mut rng = StdRng::seed_from_u64(5);
        for dim in [2, 3] {
            let text = if dim == 2 {
                "-0.3 + sqrt(0.49 - (x - 0.2)^2)".to_string()
            } else {
                "0.4 + sqrt(0.49 - (x - 0.2)^2 - (y + 0.3)^2)".to_string()
            };
            let h = height(&text, dim);
            let mut below = 0;
            let (mut eg, mut en) = (0.0f64, 0.0f64);
            for _ in 0..500 {
                let (th, ph) = (rng.gen_range(-0.6..0.6f64), rng.gen_range(0.0..PI));
                let rad = if dim == 2 {
                    [th.sin(), th.cos(), 0.0]
                } else {
                    [th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()]
                };
                let rho = r * rng.gen_range(0.5..1.5);
                let mut x = [0.0; 3];
                for k in 0..dim {
                    let up = if k == dim - 1 {
                        rad[2 - (3 - dim)]
                    } else {
                        rad[k]
                    };
                    x[k] = c[k] + rho * up;
                }
                let rad = if dim == 2 { [rad[0], rad[1], 0.0] } else { rad };
                let q = h.project(x).unwrap();
                // The derivatives are central differences (steps ≈ 6e-6 and 1e-4 times the
                // O(1) coordinates): the normal carries their truncation and round-off error,
                // ≈ 1e-10 for this unit-size curvature (measured: < 1e-10); the gap only its
                // square, so round-off.
                assert!(
                    (q.gap - (rho - r)).abs() < 1e-13 * r,
                    "{text}: {} vs {}",
                    q.gap,
                    rho - r
                );
                for k in 0..3 {
                    assert!((q.normal[k] - rad[k]).abs() < 1e-9, "{q:?} vs {rad:?}");
                }
                check_common(&h, x, &q, 1e-6);
                below += usize::from(q.gap < 0.0);
                eg = eg.max((q.gap - (rho - r)).abs() / r);
                en = en.max(norm([
                    q.normal[0] - rad[0],
                    q.normal[1] - rad[1],
                    q.normal[2] - rad[2],
                ]));
            }
            println!("{dim}D cap: max |Δg|/R = {eg:.1e}, max |Δn| = {en:.1e}");
            assert!(below > 100 && below < 400, "{below} of 500 below");
        }
    }

    /// A parabola against the distance found by sampling: the minimum of |x − (u, h(u))| over
    /// a fine grid, refined by golden sections.
    #[test]
    fn parabola_against_sampling() {
        let h = height("0.5*x^2 - 0.2", 2);
        let f = |u: f64| 0.5 * u * u - 0.2;
        let mut rng = StdRng::seed_from_u64(9);
        for _ in 0..200 {
            let x = [rng.gen_range(-1.5..1.5), rng.gen_range(-1.0..1.5), 0.0];
            let d = |u: f64| ((u - x[0]).powi(2) + (f(u) - x[1]).powi(2)).sqrt();
            let span = (x[1] - f(x[0])).abs() + 1e-3;
            let m = 20000;
            let best = (0..=m)
                .map(|i| x[0] - span + 2.0 * span * i as f64 / m as f64)
                .min_by(|a, b| d(*a).total_cmp(&d(*b)))
                .unwrap();
            let (mut a, mut b) = (best - 2.0 * span / m as f64, best + 2.0 * span / m as f64);
            let gr = (5f64.sqrt() - 1.0) / 2.0;
            for _ in 0..80 {
                let (p, q) = (b - gr * (b - a), a + gr * (b - a));
                if d(p) < d(q) {
                    b = q;
                } else {
                    a = p;
                }
            }
            let dist = d(0.5 * (a + b));
            let q = h.project(x).unwrap();
            let sign = if x[1] > f(x[0]) { 1.0 } else { -1.0 };
            // The parabola's smallest radius of curvature is 1 (at the vertex); points closer
            // to the surface than that have one nearest point: the same one, to round-off.
            if dist < 0.9 {
                assert!(
                    (q.gap - sign * dist).abs() < 1e-10,
                    "{} vs {}",
                    q.gap,
                    sign * dist
                );
                check_common(&h, x, &q, 1e-6);
            }
            // Always: no farther than the vertical distance, and on the parabola.
            assert!(q.gap.abs() <= (x[1] - f(x[0])).abs() + 1e-14);
            let foot = [x[0] - q.gap * q.normal[0], x[1] - q.gap * q.normal[1]];
            assert!((foot[1] - f(foot[0])).abs() < 1e-9);
        }
    }

    #[test]
    fn syntax_variables_and_constants() {
        let e = HeightExpr::parse("pi + 2*e^0 - x*0 + 1/2").unwrap();
        assert!((e.eval([3.0, 4.0]) - (PI + 2.5)).abs() < 1e-15);
        // A leading minus applies to the power; scientific notation; the plain function names
        // and the math:: ones.
        let e = HeightExpr::parse("-x^2 + y + 1e-3 + exp(-x^2) - math::exp(-x^2)").unwrap();
        assert!((e.eval([3.0, 1.0]) - (-8.0 + 1e-3)).abs() < 1e-15);
        assert_eq!(e.variables(), ["x", "y"]);
        assert!(e.check_variables(3).is_ok());
        let m = e.check_variables(2).unwrap_err();
        assert!(m.contains("'y'") && m.contains("y = h(x)"), "{m}");
        let e = HeightExpr::parse("pow(x, 2) + hypot(x, y) + max(x, y) + sqrt(abs(-4))").unwrap();
        assert!((e.eval([3.0, 4.0]) - (9.0 + 5.0 + 4.0 + 2.0)).abs() < 1e-14);
        let m = HeightExpr::parse("z + x")
            .unwrap()
            .check_variables(3)
            .unwrap_err();
        assert!(m.contains("'z'"), "{m}");
        assert!(HeightExpr::parse("sin(x").is_err());
        assert!(HeightExpr::parse("  ").is_err());
        let m = HeightExpr::parse("foo(x)").unwrap_err();
        assert!(
            m.contains("unknown function 'foo'") && m.contains("sqrt"),
            "{m}"
        );
        assert!(HeightExpr::parse("x = 2")
            .unwrap_err()
            .contains("assignments"));
        assert!(HeightExpr::parse("x > 2")
            .unwrap_err()
            .contains("a boolean"));
        let e = Arc::new(HeightExpr::parse("y").unwrap());
        assert_eq!(Height::new(e, 2), Err(ObstacleError::HeightVariables));
    }

    #[test]
    fn not_finite_and_kinks_are_errors() {
        // sqrt of a negative number where the node is.
        let h = height("sqrt(x)", 2);
        assert!(matches!(
            h.project([-1.0, 0.0, 0.0]),
            Err(ObstacleError::HeightNotFinite { x, y: None }) if x == -1.0
        ));
        let h = height("1/(x - y)", 3);
        assert!(matches!(
            h.project([1.0, 1.0, 0.0]),
            Err(ObstacleError::HeightNotFinite { y: Some(_), .. })
        ));
        // Below the kink of a V, the nearest points are on both arms; the iteration ends at
        // the kink, which is refused.
        let h = height("abs(x)", 2);
        assert!(matches!(
            h.project([0.0, -1.0, 0.0]),
            Err(ObstacleError::HeightNotSmooth { .. })
        ));
        let h = height("floor(x) + 0.5*abs(y)", 3);
        assert!(h.project([0.3, 0.0, -1.0]).is_err());
        // A smooth part of the same V is fine.
        let h = height("abs(x)", 2);
        let q = h.project([2.0, 1.0, 0.0]).unwrap();
        assert!((q.gap - (-1.0 / 2f64.sqrt())).abs() < 1e-12, "{q:?}");
    }
}
