//! Builders and checks shared by the mortar tests.

use super::assemble::{assemble, Mortar, MortarOptions};
use super::surface::{Orientation, Surface};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::collections::HashMap;

/// A map of points (a rigid motion in the tests).
pub type Map<'a> = &'a dyn Fn([f64; 3]) -> [f64; 3];

/// The identity map.
pub fn id(x: [f64; 3]) -> [f64; 3] {
    x
}

/// Facets as (id, coordinates) lists and one inside point per facet.
pub struct Raw {
    pub dim: usize,
    pub facets: Vec<Vec<(usize, [f64; 3])>>,
    pub inside: Vec<[f64; 3]>,
}

impl Raw {
    /// The surface of the facets mapped by `tf`, oriented by the mapped inside points.
    pub fn surface(&self, tf: Map) -> Surface {
        let facets: Vec<Vec<(usize, [f64; 3])>> = self
            .facets
            .iter()
            .map(|f| f.iter().map(|&(i, x)| (i, tf(x))).collect())
            .collect();
        let inside: Vec<[f64; 3]> = self.inside.iter().map(|&x| tf(x)).collect();
        Surface::new(self.dim, &facets, Orientation::InsidePoints(&inside)).unwrap()
    }
}

/// A 2D polyline through `pts` (ids from `id0`), the body on the side of `inside_dir`
/// (a direction added to each segment's midpoint).
pub fn polyline(pts: &[[f64; 2]], id0: usize, inside_dir: [f64; 2]) -> Raw {
    let p = |i: usize| [pts[i][0], pts[i][1], 0.0];
    let facets = (0..pts.len() - 1)
        .map(|i| vec![(id0 + i, p(i)), (id0 + i + 1, p(i + 1))])
        .collect();
    let inside = (0..pts.len() - 1)
        .map(|i| {
            let m = [0.5 * (p(i)[0] + p(i + 1)[0]), 0.5 * (p(i)[1] + p(i + 1)[1])];
            [m[0] + inside_dir[0], m[1] + inside_dir[1], 0.0]
        })
        .collect();
    Raw {
        dim: 2,
        facets,
        inside,
    }
}

/// A flat 2D line y = `y` through the abscissae `xs`, body on the side `side` (±1) in y.
pub fn line(xs: &[f64], y: f64, id0: usize, side: f64) -> Raw {
    let pts: Vec<[f64; 2]> = xs.iter().map(|&x| [x, y]).collect();
    polyline(&pts, id0, [0.0, side])
}

/// The rectangle [0, lx] × [0, ly] at height z in an n × n grid of triangles (the
/// diagonal of each cell alternating with `pattern`), interior nodes moved randomly (seed
/// `seed`) by up to `jitter` cell sizes (≤ 0.1 keeps every triangle valid; the larger
/// values in the tests are for seeds checked to give the total area 1).
pub fn square(n: usize, lx: f64, ly: f64, z: f64, jitter: f64, pattern: usize, seed: u64) -> Grid {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut x = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let inner = i > 0 && i < n && j > 0 && j < n;
            let mut dx = [0.0; 2];
            if inner {
                dx = [0, 1].map(|_| rng.gen_range(-jitter..=jitter));
            }
            let h = [lx / n as f64, ly / n as f64];
            x.push([(i as f64 + dx[0]) * h[0], (j as f64 + dx[1]) * h[1], z]);
        }
    }
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let v = |a: usize, b: usize| (j + b) * (n + 1) + i + a;
            if (i + j + pattern) % 2 == 0 {
                tris.push([v(0, 0), v(1, 0), v(1, 1)]);
                tris.push([v(0, 0), v(1, 1), v(0, 1)]);
            } else {
                tris.push([v(0, 0), v(1, 0), v(0, 1)]);
                tris.push([v(1, 0), v(1, 1), v(0, 1)]);
            }
        }
    }
    Grid { x, tris }
}

/// Nodes and triangles of a planar grid.
pub struct Grid {
    pub x: Vec<[f64; 3]>,
    pub tris: Vec<[usize; 3]>,
}

impl Grid {
    /// The facets with ids from `id0`, body on the side `side` (±1) in z.
    pub fn raw(&self, id0: usize, side: f64) -> Raw {
        let facets = self
            .tris
            .iter()
            .map(|t| t.iter().map(|&v| (id0 + v, self.x[v])).collect())
            .collect();
        let inside = self
            .tris
            .iter()
            .map(|t| {
                let c = |a: usize| t.iter().map(|&v| self.x[v][a]).sum::<f64>() / 3.0;
                [c(0), c(1), c(2) + side]
            })
            .collect();
        Raw {
            dim: 3,
            facets,
            inside,
        }
    }

    /// The grid as a slave surface: ids from 0, the body below it.
    pub fn slave(&self) -> Surface {
        self.raw(0, -1.0).surface(&id)
    }

    /// The grid as a master surface: ids from `id0`, the body above it.
    pub fn master(&self, id0: usize) -> Surface {
        self.raw(id0, 1.0).surface(&id)
    }
}

/// The coupling with search radius `r`.
pub fn couple(slave: &Surface, master: &Surface, r: f64) -> Mortar {
    assemble(slave, master, &MortarOptions::new(r)).unwrap()
}

/// Master coordinates by id.
pub fn master_x(master: &Surface) -> HashMap<usize, [f64; 3]> {
    master
        .ids()
        .iter()
        .copied()
        .zip(master.coords().iter().copied())
        .collect()
}

/// For the rows selected by `pick`: Σ_j M_kj = D_kk and Σ_j M_kj x_j = D_kk x_k to `tol`
/// (relative to D_kk); returns how many rows were checked.
pub fn check_reproduction(
    mortar: &Mortar,
    master: &Surface,
    pick: &dyn Fn(&super::assemble::MortarRow) -> bool,
    tol: f64,
) -> usize {
    let xm = master_x(master);
    let mut n = 0;
    for row in mortar.rows.iter().filter(|r| pick(r)) {
        let sum: f64 = row.m.iter().map(|e| e.1).sum();
        assert!(
            (sum - row.d).abs() <= tol * row.d,
            "{} {sum} {}",
            row.id,
            row.d
        );
        for a in 0..3 {
            let lin: f64 = row.m.iter().map(|&(j, v)| v * xm[&j][a]).sum();
            let want = row.d * row.x[a];
            assert!(
                (lin - want).abs() <= tol * row.d,
                "{} {a} {lin} {want}",
                row.id
            );
        }
        n += 1;
    }
    n
}

/// A random rotation (a random unit quaternion; about z only in 2D) and translation.
pub fn rigid(dim: usize, rng: &mut StdRng) -> ([[f64; 3]; 3], [f64; 3]) {
    let mut q = [0.0; 4].map(|_| rng.gen_range(-1.0..1.0f64));
    if dim == 2 {
        q[1] = 0.0;
        q[2] = 0.0;
    }
    let l = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    let [w, x, y, z] = q.map(|v| v / l);
    let r = [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ];
    let mut t = [0.0; 3].map(|_| rng.gen_range(-10.0..10.0));
    if dim == 2 {
        t[2] = 0.0;
    }
    (r, t)
}

/// R x + t.
pub fn apply(r: &[[f64; 3]; 3], t: [f64; 3], x: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|a| r[a][0] * x[0] + r[a][1] * x[1] + r[a][2] * x[2] + t[a])
}
