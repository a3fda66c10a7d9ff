//! A contact surface: facets (2D segments, 3D triangles) on nodes named by an id, with facet
//! measures, oriented facet normals and area-weighted nodal normals.

use super::geom::{axpy, dot, facet_measure_normal, norm, scale, sub};
use std::collections::HashMap;
use std::fmt;

/// How the facet normals of a [`Surface`] are oriented.
#[derive(Debug, Clone, Copy)]
pub enum Orientation<'a> {
    /// By the node order (see [`Surface::new`]).
    NodeOrder,
    /// One point per facet inside the body (e.g. the vertex of the boundary cell opposite
    /// the facet): the normal is turned to point away from it.
    InsidePoints(&'a [[f64; 3]]),
}

/// Bad input to [`Surface::new`] or to the mortar assembly.
#[derive(Debug, Clone, PartialEq)]
pub enum MortarError {
    /// The dimension is not 2 or 3.
    Dimension(usize),
    /// A facet does not have `dim` nodes, or names a node twice.
    FacetNodes { facet: usize },
    /// A coordinate is not finite, or a 2D node has z ≠ 0.
    Coordinates { facet: usize },
    /// Two facets give one node id different coordinates.
    ConflictingCoordinates { id: usize },
    /// A facet of zero (relative to its size: < 1e-14) measure.
    Degenerate { facet: usize },
    /// The inside point of a facet lies in the facet's line/plane.
    InsideOnFacet { facet: usize },
    /// A list (inside points, nodal normals) of the wrong length.
    Length {
        what: &'static str,
        expected: usize,
        found: usize,
    },
    /// A given nodal normal that is not a finite non-zero vector (in the xy plane in 2D).
    Normal { node: usize },
    /// Slave and master surfaces of different dimensions.
    DimensionMismatch,
    /// A search radius that is negative or not finite.
    SearchRadius,
}

impl fmt::Display for MortarError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Dimension(d) => write!(f, "mortar: dimension {d} (expected 2 or 3)"),
            Self::FacetNodes { facet } => {
                write!(
                    f,
                    "mortar: facet {facet}: wrong number of nodes or a repeated node"
                )
            }
            Self::Coordinates { facet } => {
                write!(
                    f,
                    "mortar: facet {facet}: non-finite coordinate (or z ≠ 0 in 2D)"
                )
            }
            Self::ConflictingCoordinates { id } => {
                write!(f, "mortar: node {id} given with different coordinates")
            }
            Self::Degenerate { facet } => write!(f, "mortar: facet {facet} is degenerate"),
            Self::InsideOnFacet { facet } => {
                write!(
                    f,
                    "mortar: facet {facet}: the inside point lies on the facet"
                )
            }
            Self::Length {
                what,
                expected,
                found,
            } => {
                write!(f, "mortar: {found} {what} given, {expected} expected")
            }
            Self::Normal { node } => write!(f, "mortar: bad nodal normal at slave node {node}"),
            Self::DimensionMismatch => write!(f, "mortar: slave and master dimensions differ"),
            Self::SearchRadius => write!(f, "mortar: search radius must be finite and ≥ 0"),
        }
    }
}

impl std::error::Error for MortarError {}

/// A contact surface of dimension `dim` (2: segments, 3: triangles). Nodes are numbered
/// locally 0.. in order of first appearance; facets keep their input order.
#[derive(Debug, Clone)]
pub struct Surface {
    dim: usize,
    ids: Vec<usize>,
    coords: Vec<[f64; 3]>,
    facets: Vec<[usize; 3]>,
    measures: Vec<f64>,
    normals: Vec<[f64; 3]>,
}

impl Surface {
    /// A surface from its facets, each a list of `dim` nodes (id, coordinates; z = 0 in
    /// 2D). Normals by the node order: 2D segment a→b: n = (t_y, −t_x) (outward for a body
    /// whose boundary runs counter-clockwise); 3D: n ∥ (b − a) × (c − a) (outward when the
    /// nodes turn counter-clockwise seen from outside); or turned away from the inside points.
    pub fn new<F: AsRef<[(usize, [f64; 3])]>>(
        dim: usize,
        facets: &[F],
        orientation: Orientation,
    ) -> Result<Self, MortarError> {
        if dim != 2 && dim != 3 {
            return Err(MortarError::Dimension(dim));
        }
        let mut s = Surface {
            dim,
            ids: Vec::new(),
            coords: Vec::new(),
            facets: Vec::with_capacity(facets.len()),
            measures: Vec::with_capacity(facets.len()),
            normals: Vec::with_capacity(facets.len()),
        };
        let mut local: HashMap<usize, usize> = HashMap::new();
        for (f, facet) in facets.iter().enumerate() {
            let nodes = facet.as_ref();
            let mut idx = [usize::MAX; 3];
            check_facet_nodes(dim, f, nodes)?;
            for (a, &(id, x)) in nodes.iter().enumerate() {
                idx[a] = s.node_index(&mut local, id, x)?;
            }
            let x = s.facet_coords_of(&idx[..dim]);
            let (measure, normal) = facet_measure_normal(&x);
            let h = x
                .iter()
                .flat_map(|a| x.iter().map(move |b| norm(sub(*a, *b))))
                .fold(0.0f64, f64::max);
            if measure <= 1e-14 * h.powi(dim as i32 - 1) || h == 0.0 {
                return Err(MortarError::Degenerate { facet: f });
            }
            s.facets.push(idx);
            s.measures.push(measure);
            s.normals.push(normal);
        }
        if let Orientation::InsidePoints(inside) = orientation {
            s.orient(inside)?;
        }
        Ok(s)
    }

    fn node_index(
        &mut self,
        local: &mut HashMap<usize, usize>,
        id: usize,
        x: [f64; 3],
    ) -> Result<usize, MortarError> {
        if let Some(&i) = local.get(&id) {
            if self.coords[i] != x {
                return Err(MortarError::ConflictingCoordinates { id });
            }
            return Ok(i);
        }
        local.insert(id, self.ids.len());
        self.ids.push(id);
        self.coords.push(x);
        Ok(self.ids.len() - 1)
    }

    fn orient(&mut self, inside: &[[f64; 3]]) -> Result<(), MortarError> {
        if inside.len() != self.facets.len() {
            return Err(MortarError::Length {
                what: "inside points",
                expected: self.facets.len(),
                found: inside.len(),
            });
        }
        for f in 0..self.facets.len() {
            let c = self.facet_centroid(f);
            let side = dot(self.normals[f], sub(c, inside[f]));
            let reach = norm(sub(c, inside[f]));
            if side.is_nan() || side.abs() <= 1e-12 * reach {
                return Err(MortarError::InsideOnFacet { facet: f });
            }
            if side < 0.0 {
                self.normals[f] = scale(-1.0, self.normals[f]);
            }
        }
        Ok(())
    }

    fn facet_coords_of(&self, idx: &[usize]) -> Vec<[f64; 3]> {
        idx.iter().map(|&i| self.coords[i]).collect()
    }

    /// The dimension (2 or 3).
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The node ids, by local node index.
    pub fn ids(&self) -> &[usize] {
        &self.ids
    }

    /// The node coordinates, by local node index.
    pub fn coords(&self) -> &[[f64; 3]] {
        &self.coords
    }

    /// The number of facets.
    pub fn n_facets(&self) -> usize {
        self.facets.len()
    }

    /// The local node indices of facet `f` (`dim` of them).
    pub fn facet(&self, f: usize) -> &[usize] {
        &self.facets[f][..self.dim]
    }

    /// The node coordinates of facet `f` (`dim` of them).
    pub fn facet_coords(&self, f: usize) -> Vec<[f64; 3]> {
        self.facet_coords_of(self.facet(f))
    }

    /// The measure (length in 2D, area in 3D) of facet `f`.
    pub fn measure(&self, f: usize) -> f64 {
        self.measures[f]
    }

    /// The oriented unit normal of facet `f`.
    pub fn normal(&self, f: usize) -> [f64; 3] {
        self.normals[f]
    }

    /// The centroid of facet `f`.
    pub fn facet_centroid(&self, f: usize) -> [f64; 3] {
        let x = self.facet_coords(f);
        let w = 1.0 / x.len() as f64;
        x.iter().fold([0.0; 3], |c, &y| axpy(c, w, y))
    }

    /// The axis-aligned bounding box (lower, upper corner) of facet `f`.
    pub fn bbox(&self, f: usize) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for y in self.facet_coords(f) {
            for a in 0..3 {
                lo[a] = lo[a].min(y[a]);
                hi[a] = hi[a].max(y[a]);
            }
        }
        (lo, hi)
    }

    /// The facets around each node (by local node index).
    pub fn node_facets(&self) -> Vec<Vec<usize>> {
        let mut adj = vec![Vec::new(); self.ids.len()];
        for f in 0..self.facets.len() {
            for &i in self.facet(f) {
                adj[i].push(f);
            }
        }
        adj
    }

    /// The nodal normals: n_k = Σ_f |f| n_f / |Σ_f |f| n_f| over the facets f around node k
    /// (area-weighted average of the oriented facet normals). A node whose weighted sum
    /// vanishes (a fold back onto itself) gets the normal of its first facet.
    pub fn nodal_normals(&self) -> Vec<[f64; 3]> {
        let mut sum = vec![[0.0; 3]; self.ids.len()];
        for f in 0..self.facets.len() {
            for &i in self.facet(f) {
                sum[i] = axpy(sum[i], self.measures[f], self.normals[f]);
            }
        }
        let adj = self.node_facets();
        sum.iter()
            .zip(&adj)
            .map(|(&v, fs)| {
                let l = norm(v);
                let size: f64 = fs.iter().map(|&f| self.measures[f]).sum();
                if l > 1e-12 * size {
                    scale(1.0 / l, v)
                } else {
                    self.normals[fs[0]]
                }
            })
            .collect()
    }
}

/// `dim` nodes, no id twice, finite coordinates, z = 0 in 2D.
fn check_facet_nodes(dim: usize, f: usize, nodes: &[(usize, [f64; 3])]) -> Result<(), MortarError> {
    if nodes.len() != dim || (1..dim).any(|a| (0..a).any(|b| nodes[a].0 == nodes[b].0)) {
        return Err(MortarError::FacetNodes { facet: f });
    }
    let bad = |x: &[f64; 3]| x.iter().any(|v| !v.is_finite()) || (dim == 2 && x[2] != 0.0);
    if nodes.iter().any(|(_, x)| bad(x)) {
        return Err(MortarError::Coordinates { facet: f });
    }
    Ok(())
}
