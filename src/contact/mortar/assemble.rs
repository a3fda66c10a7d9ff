//! The mortar integrals D, M and the weighted gap g̃ of a slave surface against a master
//! surface (formulas: the module documentation).

use super::dual::{eval, restricted_coefficients, Coefficients};
use super::geom::{axpy, dot, norm, scale, sub};
use super::quad::{segment_points, triangle_points, QuadPoint};
use super::search::MasterTree;
use super::surface::{MortarError, Surface};

/// Options of [`assemble`].
#[derive(Debug, Clone, Copy)]
pub struct MortarOptions {
    /// Master facets whose bounding box is farther than this (in every coordinate) from a
    /// slave facet's box are not considered for it. Choose it larger than the largest gap
    /// (or penetration) of interest.
    pub search_radius: f64,
    /// When set, a master facet is skipped for a slave facet when n_master · n_slave of
    /// their oriented facet normals exceeds it (e.g. `Some(0.0)`: only facing facets).
    pub max_normal_dot: Option<f64>,
}

impl MortarOptions {
    /// The given search radius, no normal filter.
    pub fn new(search_radius: f64) -> Self {
        MortarOptions {
            search_radius,
            max_normal_dot: None,
        }
    }
}

/// The mortar row of one slave node k.
#[derive(Debug, Clone, PartialEq)]
pub struct MortarRow {
    /// The slave node id.
    pub id: usize,
    /// Its coordinates.
    pub x: [f64; 3],
    /// Its unit nodal normal n_k (outward from the slave body).
    pub normal: [f64; 3],
    /// D_kk = ∫ ψ_k φ_k = ∫ φ_k over the covered part of the slave facets around k.
    pub d: f64,
    /// (master node id, M_kj), sorted by id, no repeats: M_kj = ∫ ψ_k (φ_j ∘ π).
    pub m: Vec<(usize, f64)>,
    /// g̃_k = ∫ ψ_k n_k · (x_master ∘ π − x) = n_k · (Σ_j M_kj x_j − D_kk x_k); > 0 apart.
    pub gap: f64,
    /// The master facets (indices in the master surface's facet order, sorted) whose
    /// projection meets a slave facet around k.
    pub master_facets: Vec<usize>,
    /// Whether every slave facet around k is covered (to 1e-12 relative) by the master.
    pub fully_covered: bool,
}

/// The mortar coupling of a slave surface to a master surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Mortar {
    /// One row per slave node, in the slave surface's local node order. Nodes no master
    /// facet covers (or only a sliver of their support, [`SLIVER_COVERAGE`]) have d = 0, an
    /// empty m, gap 0 and no master facets.
    pub rows: Vec<MortarRow>,
    /// The covered measure of each slave facet (0 when dropped).
    pub facet_covered: Vec<f64>,
}

impl Mortar {
    /// The total covered measure Σ_f |covered part of f| (= Σ_k D_kk but for the rows of
    /// nodes covered by a sliver, [`SLIVER_COVERAGE`]).
    pub fn covered_measure(&self) -> f64 {
        self.facet_covered.iter().sum()
    }
}

/// The mortar coupling with the slave nodal normals of [`Surface::nodal_normals`].
pub fn assemble(
    slave: &Surface,
    master: &Surface,
    opts: &MortarOptions,
) -> Result<Mortar, MortarError> {
    assemble_with_normals(slave, master, &slave.nodal_normals(), opts)
}

/// The mortar coupling with given slave nodal normals (one per slave node in local order;
/// normalised here). Per slave facet: the master facets near it are projected onto it
/// along its normal and clipped; the dual basis is built on the covered part; D, M and g̃
/// are integrated exactly there (see the module documentation).
pub fn assemble_with_normals(
    slave: &Surface,
    master: &Surface,
    normals: &[[f64; 3]],
    opts: &MortarOptions,
) -> Result<Mortar, MortarError> {
    let normals = check_input(slave, master, normals, opts)?;
    let tree = MasterTree::new(master);
    let mut rows: Vec<MortarRow> = (0..slave.ids().len())
        .map(|k| MortarRow {
            id: slave.ids()[k],
            x: slave.coords()[k],
            normal: normals[k],
            d: 0.0,
            m: Vec::new(),
            gap: 0.0,
            master_facets: Vec::new(),
            fully_covered: false,
        })
        .collect();
    let mut facet_covered = vec![0.0; slave.n_facets()];
    let mut points = Vec::new();
    for (sf, covered) in facet_covered.iter_mut().enumerate() {
        points.clear();
        let (lo, hi) = slave.bbox(sf);
        let xs = slave.facet_coords(sf);
        for mf in tree.candidates(lo, hi, opts.search_radius) {
            let facing = dot(slave.normal(sf), master.normal(mf));
            if opts.max_normal_dot.is_some_and(|t| facing > t) {
                continue;
            }
            let xm = master.facet_coords(mf);
            *covered += if slave.dim() == 2 {
                segment_points(&xs, &xm, mf, &mut points)
            } else {
                triangle_points(&xs, &xm, mf, &mut points)
            };
        }
        if !add_facet(slave, master, sf, &points, &mut rows) {
            *covered = 0.0;
        }
    }
    finish_rows(slave, &facet_covered, &mut rows);
    Ok(Mortar {
        rows,
        facet_covered,
    })
}

/// Dimensions, lengths, the search radius and the normals (returned normalised).
fn check_input(
    slave: &Surface,
    master: &Surface,
    normals: &[[f64; 3]],
    opts: &MortarOptions,
) -> Result<Vec<[f64; 3]>, MortarError> {
    if slave.dim() != master.dim() {
        return Err(MortarError::DimensionMismatch);
    }
    if !(opts.search_radius >= 0.0 && opts.search_radius.is_finite()) {
        return Err(MortarError::SearchRadius);
    }
    if normals.len() != slave.ids().len() {
        return Err(MortarError::Length {
            what: "slave nodal normals",
            expected: slave.ids().len(),
            found: normals.len(),
        });
    }
    let planar = |n: &[f64; 3]| slave.dim() == 3 || n[2] == 0.0;
    normals
        .iter()
        .enumerate()
        .map(|(k, n)| {
            let l = norm(*n);
            if l > 0.0 && l.is_finite() && planar(n) {
                Ok(scale(1.0 / l, *n))
            } else {
                Err(MortarError::Normal { node: k })
            }
        })
        .collect()
}

/// The Gram matrix G_il = ∫ φ_i φ_l and m_i = ∫ φ_i over the quadrature points.
fn gram(n: usize, points: &[QuadPoint]) -> (Coefficients, [f64; 3]) {
    let mut g = [[0.0; 3]; 3];
    let mut m = [0.0; 3];
    for p in points {
        for i in 0..n {
            m[i] += p.w * p.phi_s[i];
            for l in 0..n {
                g[i][l] += p.w * p.phi_s[i] * p.phi_s[l];
            }
        }
    }
    (g, m)
}

/// Adds slave facet `sf`'s contributions (quadrature `points`, grouped by master facet) to
/// the rows of its nodes: D_kk += ∫ φ_k, M_kj += ∫ ψ_k φ_j, g̃_k += ∫ ψ_k n_k · (x_m − x_s),
/// with the dual basis biorthogonal on the covered part. False (nothing added) when the
/// covered part is empty or too thin for a dual basis.
fn add_facet(
    slave: &Surface,
    master: &Surface,
    sf: usize,
    points: &[QuadPoint],
    rows: &mut [MortarRow],
) -> bool {
    let n = slave.dim();
    let (g, lump) = gram(n, points);
    let Some(a) = (!points.is_empty())
        .then(|| restricted_coefficients(n, &g, &lump))
        .flatten()
    else {
        return false;
    };
    let nodes = slave.facet(sf);
    let xs = slave.facet_coords(sf);
    for i in 0..n {
        rows[nodes[i]].d += lump[i];
    }
    for piece in points.chunk_by(|p, q| p.master == q.master) {
        let mf = piece[0].master;
        let xm = master.facet_coords(mf);
        let mut mij = [[0.0; 3]; 3];
        let mut gap = [0.0; 3];
        for p in piece {
            let psi = eval(n, &a, &p.phi_s);
            let x_s = (0..n).fold([0.0; 3], |x, i| axpy(x, p.phi_s[i], xs[i]));
            let x_m = (0..n).fold([0.0; 3], |x, j| axpy(x, p.phi_m[j], xm[j]));
            for i in 0..n {
                gap[i] += p.w * psi[i] * dot(rows[nodes[i]].normal, sub(x_m, x_s));
                for j in 0..n {
                    mij[i][j] += p.w * psi[i] * p.phi_m[j];
                }
            }
        }
        for i in 0..n {
            let row = &mut rows[nodes[i]];
            row.gap += gap[i];
            row.master_facets.push(mf);
            for j in 0..n {
                row.m.push((master.ids()[master.facet(mf)[j]], mij[i][j]));
            }
        }
    }
    true
}

/// A slave node whose covered weight D_kk is below this part of its whole weight
/// ∫ φ_k (over every slave facet around it) faces the master by round-off of the meshes'
/// coordinates, not by geometry: its row is dropped (d = 0, the node no contact node). Such a
/// sliver — two meshes' corners that meet to 1e-12, one facet reaching 1e-12 over the master's
/// edge — gives D_kk of 1e-28…1e-24 against ∫ φ_k of 1e-3, and M_kj / D_kk, the node's
/// projection onto the master, is then a ratio of two roundings: it changed with the rank
/// count (u 5e-3 of max |u| apart between 1 and 2 ranks on a 3D pair, no warning), and the
/// node carried a full contact force at a pressure of 1e23. A row above this part holds
/// M_kj / D_kk to ε / 1e-6 ≈ 2e-10 relative.
pub const SLIVER_COVERAGE: f64 = 1e-6;

/// Merges repeated master ids in M, sorts and dedups the master facets, marks the
/// fully covered nodes and drops the rows of nodes covered by a sliver ([`SLIVER_COVERAGE`]).
fn finish_rows(slave: &Surface, facet_covered: &[f64], rows: &mut [MortarRow]) {
    let full: Vec<bool> = facet_covered
        .iter()
        .enumerate()
        .map(|(f, &c)| c >= (1.0 - 1e-12) * slave.measure(f))
        .collect();
    let per_node = slave.dim() as f64; // the nodes of a facet: ∫ φ_k = |f| / n on each
    for (k, fs) in slave.node_facets().iter().enumerate() {
        let row = &mut rows[k];
        let whole: f64 = fs.iter().map(|&f| slave.measure(f) / per_node).sum();
        if row.d > 0.0 && row.d < SLIVER_COVERAGE * whole {
            row.d = 0.0;
            row.gap = 0.0;
            row.m.clear();
            row.master_facets.clear();
            row.fully_covered = false;
            continue;
        }
        row.m.sort_by_key(|e| e.0);
        let mut merged: Vec<(usize, f64)> = Vec::with_capacity(row.m.len());
        for &(j, v) in &row.m {
            match merged.last_mut() {
                Some(last) if last.0 == j => last.1 += v,
                _ => merged.push((j, v)),
            }
        }
        row.m = merged;
        row.master_facets.sort_unstable();
        row.master_facets.dedup();
        row.fully_covered = fs.iter().all(|&f| full[f]);
    }
}
