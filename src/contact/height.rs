//! The `height` obstacle: the solid below the graph of a function, {y < h(x)} in 2D and
//! {z < h(x, y)} in 3D, the body above it (docs/obstacles.md, "height").
//!
//! h is an expression of the case file, parsed once by `exmex` ([`HeightExpr`]) and evaluated
//! at the contact nodes. For a point x the nearest point of the graph is found by a safeguarded
//! Newton iteration on the squared distance, started at the vertical projection
//! ([`Height::project`]); the derivatives of h are central differences with steps scaled to
//! the point's size. g0 is the signed distance (positive above the graph), n the unit upward
//! normal of the graph at the nearest point: the gradient of g0 on both sides.

use super::obstacle::{ObstacleError, Projection};
use exmex::{Express, FlatEx, FloatOpsFactory, MakeOperators, Operator};
use std::f64::consts::PI;
use std::fmt;

/// The operators of a height expression: exmex's float operators (`^`, `sin`, `cos`, `tan`,
/// `sqrt`, `exp`, `ln`, `abs`, `min`, `max`, … and the constants `PI`/`π`, `E`/`e`, `TAU`/`τ`)
/// and the constant `pi`.
#[derive(Clone, Debug)]
pub struct HeightOps;

impl MakeOperators<f64> for HeightOps {
    fn make<'a>() -> Vec<Operator<'a, f64>> {
        let mut ops = FloatOpsFactory::<f64>::make();
        ops.push(Operator::make_constant("pi", PI));
        ops
    }
}

/// A parsed height expression h(x) (2D) or h(x, y) (3D).
pub struct HeightExpr {
    text: String,
    expr: FlatEx<f64, HeightOps>,
    /// For each variable of `expr` (exmex's alphabetical order): 0 for x, 1 for y, 2 for
    /// anything else (rejected by [`HeightExpr::check_variables`]).
    slots: Vec<usize>,
}

impl fmt::Debug for HeightExpr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "HeightExpr({:?})", self.text)
    }
}

impl PartialEq for HeightExpr {
    fn eq(&self, other: &Self) -> bool {
        self.text == other.text
    }
}

impl HeightExpr {
    /// Parses `text`; the error is exmex's message.
    pub fn parse(text: &str) -> Result<Self, String> {
        if text.trim().is_empty() {
            return Err("the expression is empty".into());
        }
        let expr = FlatEx::<f64, HeightOps>::parse(text).map_err(|e| e.to_string())?;
        let slots = expr
            .var_names()
            .iter()
            .map(|v| match v.as_str() {
                "x" => 0,
                "y" => 1,
                _ => 2,
            })
            .collect();
        Ok(HeightExpr {
            text: text.to_string(),
            expr,
            slots,
        })
    }

    /// The expression as written.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The names of the variables the expression uses (alphabetical).
    pub fn variables(&self) -> &[String] {
        self.expr.var_names()
    }

    /// Ok when every variable is x (2D) or x or y (3D); else a message naming the others.
    pub fn check_variables(&self, dim: usize) -> Result<(), String> {
        let allowed: &[&str] = if dim == 2 { &["x"] } else { &["x", "y"] };
        let bad: Vec<&str> = self
            .variables()
            .iter()
            .map(String::as_str)
            .filter(|v| !allowed.contains(v))
            .collect();
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
            bad.iter()
                .map(|v| format!("'{v}'"))
                .collect::<Vec<_>>()
                .join(", ")
        ))
    }

    /// h(u) (u = [x, y]; y is ignored in 2D expressions). NaN where exmex reports an error.
    pub fn eval(&self, u: [f64; 2]) -> f64 {
        let vals: Vec<f64> = self
            .slots
            .iter()
            .map(|&s| if s < 2 { u[s] } else { f64::NAN })
            .collect();
        self.expr.eval(&vals).unwrap_or(f64::NAN)
    }
}

/// The height obstacle of dimension `dim` (Copy: the expression is shared for the run).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Height {
    dim: usize,
    expr: &'static HeightExpr,
}

/// Most Newton iterations of a projection.
const MAX_ITER: usize = 60;
/// Convergence: a Newton step shorter than this times the point's scale.
const STEP_TOL: f64 = 1e-11;
/// A step this short (times the scale) is accepted even when the line search stalls on
/// round-off in the distance.
const STALL_TOL: f64 = 1e-8;

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
    pub fn new(expr: &'static HeightExpr, dim: usize) -> Result<Self, ObstacleError> {
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

    pub fn expr(&self) -> &'static HeightExpr {
        self.expr
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
            let step = solve_spd(&newton, &grad, n)
                .or_else(|| solve_spd(&gn, &grad, n))
                .ok_or(ObstacleError::HeightNoConvergence)?;
            let len = step.iter().map(|v| v * v).sum::<f64>().sqrt();
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
