//! The elastic half-space: its compliance between contact nodes (Boussinesq in 3D, Flamant in 2D)
//! with mirror images in the body's symmetry planes, built in column shares on every rank.

use crate::mesh::Mesh;
use crate::par::Ctx;
use std::f64::consts::PI;

/// The centre displacement of a uniformly loaded square of side s on a half-space is
/// SQUARE_SELF · F / (π E* s) (∫∫ dA / r over the square = 4 s ln(1 + √2)).
const SQUARE_SELF: f64 = 3.525_494_348_078_172;

/// An elastic half-space with the body's contact modulus, mirrored in its symmetry planes.
#[derive(Clone, Debug)]
pub struct HalfSpace {
    /// E* = E / (1 − ν²) in 3D and plane strain, E in plane stress.
    pub modulus: f64,
    pub dim: usize,
    /// 2D: the length L of the Flamant solution's ln(L / r) (the displacement of a half-plane
    /// is defined up to a constant: here relative to the distance L, twice the mesh extent).
    pub length: f64,
    /// Symmetry planes x_k = c (Dirichlet u_k = 0 alone on a plane group), at most 3.
    pub mirrors: Vec<(usize, f64)>,
}

impl HalfSpace {
    /// Normal displacement at x per unit normal force at y (Boussinesq: 1 / (π E* r); Flamant:
    /// 2 / (π E*) ln(L / r)).
    fn point(&self, r: f64) -> f64 {
        if self.dim == 3 {
            1.0 / (PI * self.modulus * r)
        } else {
            2.0 / (PI * self.modulus) * (self.length / r).ln()
        }
    }

    /// The displacement of a node under its own unit force spread uniformly over its lumped
    /// weight w (3D: a square of area w; 2D: a strip of width w, centre value).
    fn own(&self, w: f64) -> f64 {
        if self.dim == 3 {
            SQUARE_SELF / (PI * self.modulus * w.sqrt())
        } else {
            2.0 / (PI * self.modulus) * ((2.0 * self.length / w).ln() + 1.0)
        }
    }

    /// The images of y in the mirror planes (y itself first): 2^|mirrors| points.
    fn images(&self, y: &[f64; 3]) -> Vec<[f64; 3]> {
        let mut out = vec![*y];
        for &(k, c) in &self.mirrors {
            let n = out.len();
            for i in 0..n {
                let mut p = out[i];
                p[k] = 2.0 * c - p[k];
                out.push(p);
            }
        }
        out
    }

    /// Columns `cols` of the upper triangle of the model's compliance C (n × n, symmetric) of
    /// nodes at `x` with lumped weights `w`, packed: for each column j the entries i = 0..=j (C
    /// is symmetric: |x_i − image(x_j)| = |image(x_i) − x_j| in mirror planes), the
    /// displacement at node i per unit force at node j and at j's images. Images that fall on
    /// the node itself (a node on a symmetry plane) merge with it: m coincident copies make one
    /// node of weight m w and force m. Dense iterations read it as it is
    /// ([`CMatrix::Upper`](crate::signorini::dense::CMatrix)).
    pub fn columns(&self, x: &[[f64; 3]], w: &[f64], cols: std::ops::Range<usize>) -> Vec<f64> {
        let scale = x
            .iter()
            .flat_map(|p| p.iter())
            .fold(0.0f64, |a, v| a.max(v.abs()))
            .max(self.length);
        let tiny = 1e-9 * scale;
        let dist =
            |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
        let mut out = Vec::with_capacity(cols.clone().map(|j| j + 1).sum());
        for j in cols {
            let images = self.images(&x[j]);
            for xi in &x[..=j] {
                let mut v = 0.0;
                let mut own = 0usize;
                for y in &images {
                    let r = dist(xi, y);
                    if r <= tiny {
                        own += 1;
                    } else {
                        v += self.point(r);
                    }
                }
                if own > 0 {
                    v += own as f64 * self.own(own as f64 * w[j]);
                }
                out.push(v);
            }
        }
        out
    }
}

/// Rank `rank` of `size` builds the columns lo..hi of an n × n triangle: about equal shares
/// of its n (n + 1) / 2 entries (column j has j + 1).
pub(super) fn column_share(n: usize, rank: usize, size: usize) -> std::ops::Range<usize> {
    let at = |r: usize| ((n as f64) * (r as f64 / size as f64).sqrt()).round() as usize;
    at(rank).min(n)..at(rank + 1).min(n)
}

/// The symmetry planes of the Dirichlet data `fixed` (per local node and component, NaN =
/// free): for each axis k, the nodes whose only prescribed component is u_k = 0; a plane
/// x_k = c if there are at least 3 of them (all ranks) and they all have x_k = c. Collective.
pub fn mirror_planes(ctx: &Ctx, mesh: &Mesh, fixed: &[f64]) -> Vec<(usize, f64)> {
    let dim = mesh.dim;
    let mut local = Vec::with_capacity(3 * dim);
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut count = [0.0f64; 3];
    for (v, x) in mesh.coords.iter().enumerate() {
        let f = &fixed[v * dim..(v + 1) * dim];
        let set: Vec<usize> = (0..dim).filter(|&k| !f[k].is_nan()).collect();
        if let [k] = set[..] {
            if f[k] == 0.0 {
                count[k] += 1.0;
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
    }
    local.extend_from_slice(&count[..dim]);
    let n = ctx.sum_vec(&local);
    let extent = mesh.extent();
    let mut out = Vec::new();
    for k in 0..dim {
        let (a, b) = (ctx.min_f64(lo[k]), ctx.max_f64(hi[k]));
        if n[k] >= 3.0 && b - a <= 1e-9 * extent {
            out.push((k, 0.5 * (a + b)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signorini::dense::{CMatrix, Dense, End};
    use nalgebra::DMatrix;

    /// Every column of the model's packed triangle for nodes `x`, weights `w`.
    fn triangle(h: &HalfSpace, x: &[[f64; 3]], w: &[f64]) -> Vec<f64> {
        h.columns(x, w, 0..x.len())
    }

    fn hs3(mirrors: Vec<(usize, f64)>) -> HalfSpace {
        HalfSpace {
            modulus: 2.0,
            dim: 3,
            length: 1.0,
            mirrors,
        }
    }

    #[test]
    fn boussinesq_kernel_and_symmetry() {
        let h = hs3(vec![]);
        let x = vec![[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.2, 0.0]];
        let w = [0.01, 0.01, 0.01];
        let packed = triangle(&h, &x, &w);
        let c = CMatrix::Upper {
            n: 3,
            packed: &packed,
        };
        assert!((c.at(0, 1) - 1.0 / (PI * 2.0 * 0.1)).abs() < 1e-12);
        // symmetric: the nodes in the reverse order give the same entry from the other side
        let xr: Vec<[f64; 3]> = x.iter().rev().copied().collect();
        let packed_r = triangle(&h, &xr, &w);
        let cr = CMatrix::Upper {
            n: 3,
            packed: &packed_r,
        };
        assert!((c.at(1, 2) - cr.at(0, 1)).abs() <= 1e-15 * c.at(1, 2));
        // own term: the square of side 0.1
        assert!((c.at(0, 0) - SQUARE_SELF / (PI * 2.0 * 0.1)).abs() < 1e-12);
        assert!(
            c.at(0, 0) > c.at(0, 1),
            "the own displacement is the largest"
        );
    }

    #[test]
    fn a_mirror_plane_adds_the_image_and_merges_nodes_on_it() {
        let h = hs3(vec![(0, 0.0)]);
        let x = vec![[0.1, 0.0, 0.0], [0.0, 0.3, 0.0]];
        let w = [0.01, 0.005];
        let packed = triangle(&h, &x, &w);
        let c = CMatrix::Upper {
            n: 2,
            packed: &packed,
        };
        // node 0 and its image at (-0.1, 0, 0)
        let own0 = SQUARE_SELF / (PI * 2.0 * 0.1) + 1.0 / (PI * 2.0 * 0.2);
        assert!((c.at(0, 0) - own0).abs() < 1e-12);
        // node 1 lies on the plane: one node of twice the weight carrying twice the force
        let own1 = 2.0 * SQUARE_SELF / (PI * 2.0 * (0.01f64).sqrt());
        assert!((c.at(1, 1) - own1).abs() < 1e-12);
        let r = (0.1f64 * 0.1 + 0.09).sqrt();
        assert!((c.at(0, 1) - 2.0 / (PI * 2.0 * r)).abs() < 1e-12);
        // symmetric across the plane: node 1's column seen from node 0 and the reverse
        let xr = [x[1], x[0]];
        let packed_r = triangle(&h, &xr, &[w[1], w[0]]);
        let cr = CMatrix::Upper {
            n: 2,
            packed: &packed_r,
        };
        assert!((c.at(0, 1) - cr.at(0, 1)).abs() <= 1e-15 * c.at(0, 1));
    }

    #[test]
    fn column_shares_cover_the_triangle_once() {
        let h = hs3(vec![(0, 0.0)]);
        let x: Vec<[f64; 3]> = (0..23)
            .map(|i| [0.01 * i as f64, 0.003 * i as f64, 0.0])
            .collect();
        let w = vec![1e-4; 23];
        for size in 1..5 {
            let mut packed = Vec::new();
            let mut next = 0;
            for rank in 0..size {
                let cols = column_share(23, rank, size);
                assert_eq!(cols.start, next, "contiguous");
                next = cols.end;
                packed.extend(h.columns(&x, &w, cols));
            }
            assert_eq!(next, 23);
            assert_eq!(packed, triangle(&h, &x, &w));
        }
    }

    #[test]
    fn flamant_kernel_decreases_with_distance() {
        let h = HalfSpace {
            modulus: 1.0,
            dim: 2,
            length: 2.0,
            mirrors: vec![],
        };
        let x: Vec<[f64; 3]> = (0..5).map(|i| [0.1 * i as f64, 0.0, 0.0]).collect();
        let packed = triangle(&h, &x, &[0.1; 5]);
        let c = CMatrix::Upper {
            n: 5,
            packed: &packed,
        };
        for j in 1..4 {
            assert!(c.at(0, j) > c.at(0, j + 1) && c.at(0, j + 1) > 0.0);
        }
        assert!(c.at(0, 0) > c.at(0, 1));
    }

    /// The model reproduces Hertz: a paraboloid gap g = r² / (2R) on a half-space pressed by a
    /// free rigid translation with the load F gives a = (3 F R / (4 E*))^(1/3).

    #[test]
    fn the_model_reproduces_hertz_radius() {
        // OpenBLAS' threaded LU needs more stack than a test thread's 2 MiB (the binary's
        // main thread has the system's 8 MiB)
        std::thread::Builder::new()
            .stack_size(16 << 20)
            .spawn(hertz_radius)
            .expect("thread")
            .join()
            .expect("no panic");
    }

    fn hertz_radius() {
        let (rr, f, e): (f64, f64, f64) = (1.0, 0.003, 2.0);
        let a = (3.0 * f * rr / (4.0 * e)).powf(1.0 / 3.0);
        // a quarter grid (two mirror planes), spacing h
        let h = a / 20.0;
        let mut x = Vec::new();
        for i in 0..45 {
            for j in 0..45 {
                x.push([i as f64 * h, j as f64 * h, 0.0]);
            }
        }
        let w: Vec<f64> = x
            .iter()
            .map(|p| {
                let f = |v: f64| if v == 0.0 { 0.5 } else { 1.0 };
                h * h * f(p[0]) * f(p[1])
            })
            .collect();
        let model = hs3(vec![(0, 0.0), (1, 0.0)]);
        let packed = triangle(&model, &x, &w);
        let gap: Vec<f64> = x
            .iter()
            .map(|p| (p[0] * p[0] + p[1] * p[1]) / (2.0 * rr))
            .collect();
        let n = x.len();
        // one free mode (translation towards the plane: u_n = +α), the load F/4 on it
        let g = DMatrix::from_element(n, 1, -1.0);
        let dense = Dense {
            cmat: CMatrix::Upper { n, packed: &packed },
            d0: &vec![0.0; n],
            gap: &gap,
            g: &g,
            phi: &[f / 4.0],
            load_scale: f,
            c: 1.0,
            max_steps: 100,
            pins: None,
        };
        let run = dense.run_nested(vec![false; n], &x);
        assert_eq!(run.end, End::Converged);
        let rmax = x
            .iter()
            .zip(&run.active)
            .filter(|(_, &a)| a)
            .map(|(p, _)| (p[0] * p[0] + p[1] * p[1]).sqrt())
            .fold(0.0, f64::max);
        assert!(
            (rmax - a).abs() <= 1.5 * h,
            "contact radius {rmax} against Hertz {a} (h = {h})"
        );
        let total: f64 = -run.lambda.iter().sum::<f64>();
        assert!((total - f / 4.0).abs() <= 1e-9 * f, "force {total}");
    }
}
