//! The facets a rank integrates: its own slave facets, and the master facets within reach of
//! them gathered from the ranks that own them.

use super::MasterFixed;
use crate::contact::mortar::{MortarError, Orientation, Surface};
use crate::mesh::Mesh;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::setup::{group_facets, ContactSettings};
use std::collections::HashMap;

/// One facet's nodes (id, coordinates) for [`Surface::new`].
pub(super) type FacetNodes = Vec<(usize, [f64; 3])>;

/// A rank's slave facets of one pair: those of the pair's group with an owned node (their
/// cells are local: the rows of the owned slave nodes need every facet around them), as
/// (mesh node index, coordinates), with a point inside the body per facet (the cell's vertex
/// off the facet).
pub(super) struct SlaveFacets {
    pub facets: Vec<FacetNodes>,
    pub inside: Vec<[f64; 3]>,
}

impl SlaveFacets {
    /// Of boundary group `name`. Local.
    pub fn of(mesh: &Mesh, layout: &Layout, name: &str) -> SlaveFacets {
        let mut facets = Vec::new();
        let mut inside = Vec::new();
        for f in group_facets(mesh, name) {
            let nodes = mesh.facet(f);
            if !nodes.iter().any(|&v| layout.owns_node(v)) {
                continue;
            }
            let Some(p) = inside_point(mesh, layout, nodes) else {
                continue;
            };
            facets.push(nodes.iter().map(|&v| (v, mesh.coords[v])).collect());
            inside.push(p);
        }
        SlaveFacets { facets, inside }
    }
}

/// The vertex off the facet of a local cell that contains the facet `nodes`.
fn inside_point(mesh: &Mesh, layout: &Layout, nodes: &[usize]) -> Option<[f64; 3]> {
    for &c in layout.node_cells.of(nodes[0]) {
        let cell = mesh.cell(c);
        if nodes.iter().all(|v| cell.contains(v)) {
            let off = cell.iter().find(|v| !nodes.contains(v))?;
            return Some(mesh.coords[*off]);
        }
    }
    None
}

/// Per body pair: the search radius (the diagonal of the slave group's bounding box over all
/// ranks) and every rank's slave box widened by it.
pub(super) struct Reach {
    /// By pair index (0 for rigid pairs).
    pub radius: Vec<f64>,
    /// boxes[rank][pair] = (lower, upper) corner; an empty box where the rank has no slave
    /// facet of the pair.
    boxes: Vec<Vec<([f64; 3], [f64; 3])>>,
}

const EMPTY: ([f64; 3], [f64; 3]) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);

impl Reach {
    /// Collective.
    pub fn of(ctx: &Ctx, n: usize, slaves: &[(usize, SlaveFacets)]) -> Reach {
        let mut mine = vec![EMPTY; n];
        for (p, s) in slaves {
            let p = *p;
            for (_, x) in s.facets.iter().flatten() {
                for d in 0..3 {
                    mine[p].0[d] = mine[p].0[d].min(x[d]);
                    mine[p].1[d] = mine[p].1[d].max(x[d]);
                }
            }
        }
        let flat: Vec<f64> = mine
            .iter()
            .flat_map(|(a, b)| a.iter().chain(b))
            .copied()
            .collect();
        let all = ctx.all_gather_varcount(&flat);
        let boxes: Vec<Vec<([f64; 3], [f64; 3])>> = all
            .chunks_exact(6 * n)
            .map(|r| {
                r.chunks_exact(6)
                    .map(|b| ([b[0], b[1], b[2]], [b[3], b[4], b[5]]))
                    .collect()
            })
            .collect();
        let radius = (0..n)
            .map(|p| {
                let (mut lo, mut hi) = EMPTY;
                for b in &boxes {
                    for d in 0..3 {
                        lo[d] = lo[d].min(b[p].0[d]);
                        hi[d] = hi[d].max(b[p].1[d]);
                    }
                }
                let d2: f64 = (0..3).map(|d| (hi[d] - lo[d]).powi(2)).sum();
                if d2.is_finite() {
                    d2.sqrt()
                } else {
                    0.0
                }
            })
            .collect();
        Reach { radius, boxes }
    }

    /// True when the box (lo, hi) meets rank `r`'s slave box of pair `p` widened by the
    /// radius.
    fn meets(&self, r: usize, p: usize, (lo, hi): ([f64; 3], [f64; 3])) -> bool {
        let (a, b) = self.boxes[r][p];
        let w = self.radius[p];
        (0..3).all(|d| lo[d] <= b[d] + w && hi[d] >= a[d] - w)
    }
}

/// The master facets this rank integrates against, from every rank: per facet its pair, the
/// global node numbers, coordinates, a point inside the master body, the nodes'
/// Dirichlet-fixed components and the slot of the master body's rigid modes
/// ([`crate::mesh::BodyModes`]).
pub(super) struct MasterFacets {
    dim: usize,
    records: Vec<f64>,
}

impl MasterFacets {
    fn record_len(dim: usize) -> usize {
        1 + dim + 3 * dim + 3 + dim * dim + 1
    }

    /// Each rank sends the master facets whose node of smallest global number it owns to the
    /// ranks whose reach they meet, and to those only (one all-to-all-v); each keeps what it
    /// receives. Collective.
    pub fn exchange(
        ctx: &Ctx,
        mesh: &Mesh,
        layout: &Layout,
        settings: &ContactSettings,
        fixed: &[f64],
        reach: &Reach,
    ) -> MasterFacets {
        let dim = mesh.dim;
        // every facet to send, with the ranks it goes to
        let mut out: Vec<(Vec<f64>, Vec<usize>)> = Vec::new();
        for (p, pair) in settings.pairs.iter().enumerate() {
            let crate::contact::Obstacle::Body(t) = &pair.obstacle else {
                continue;
            };
            for f in group_facets(mesh, &t.group) {
                let nodes = mesh.facet(f);
                let first = *nodes
                    .iter()
                    .min_by_key(|&&v| layout.node_global[v])
                    .expect("a facet has nodes");
                if !layout.owns_node(first) {
                    continue;
                }
                let bb = bbox(nodes.iter().map(|&v| mesh.coords[v]));
                let to: Vec<usize> = (0..ctx.size).filter(|&r| reach.meets(r, p, bb)).collect();
                if to.is_empty() {
                    continue;
                }
                let Some(inside) = inside_point(mesh, layout, nodes) else {
                    continue;
                };
                let mut rec = vec![p as f64];
                rec.extend(nodes.iter().map(|&v| layout.node_global[v] as f64));
                for &v in nodes {
                    rec.extend_from_slice(&mesh.coords[v]);
                }
                rec.extend_from_slice(&inside);
                for &v in nodes {
                    for d in 0..dim {
                        rec.push(if fixed[v * dim + d].is_nan() {
                            0.0
                        } else {
                            1.0
                        });
                    }
                }
                rec.push(settings.modes.as_ref().map_or(0, |m| m.slot_of(first)) as f64);
                out.push((rec, to));
            }
        }
        let got = crate::dist::comm::exchange(ctx.world, |pk| {
            for (rec, to) in &out {
                for &r in to {
                    for &x in rec {
                        pk.to(r).push(x.to_bits());
                    }
                }
            }
        });
        let records = got.data.iter().map(|&b| f64::from_bits(b)).collect();
        MasterFacets { dim, records }
    }

    fn of_pair(&self, p: usize) -> impl Iterator<Item = &[f64]> {
        let n = Self::record_len(self.dim);
        self.records
            .chunks_exact(n)
            .filter(move |r| r[0] as usize == p)
    }

    /// The master surface of pair `p` (node ids: global node numbers); `None` when no master
    /// facet is within this rank's reach.
    pub fn surface(&self, p: usize, dim: usize) -> Result<Option<Surface>, MortarError> {
        let mut facets: Vec<FacetNodes> = Vec::new();
        let mut inside = Vec::new();
        for r in self.of_pair(p) {
            let x = |a: usize| [r[1 + dim + 3 * a], r[2 + dim + 3 * a], r[3 + dim + 3 * a]];
            facets.push((0..dim).map(|a| (r[1 + a] as usize, x(a))).collect());
            let i = 1 + dim + 3 * dim;
            inside.push([r[i], r[i + 1], r[i + 2]]);
        }
        if facets.is_empty() {
            return Ok(None);
        }
        Surface::new(dim, &facets, Orientation::InsidePoints(&inside)).map(Some)
    }

    /// The Dirichlet-fixed components of pair `p`'s master nodes, into `out`.
    pub fn fixed_of(&self, p: usize, out: &mut MasterFixed) {
        let dim = self.dim;
        for r in self.of_pair(p) {
            let base = 1 + dim + 3 * dim + 3;
            for a in 0..dim {
                let e = out.entry(r[1 + a] as usize).or_insert([false; 3]);
                for d in 0..dim {
                    e[d] |= r[base + a * dim + d] != 0.0;
                }
            }
        }
    }

    /// Pair `p`'s master nodes (global number) with the slot of their body's rigid modes
    /// ([`crate::mesh::NO_SLOT`]: a held body) and their coordinates.
    pub fn nodes_of(&self, p: usize) -> HashMap<usize, (u32, [f64; 3])> {
        let dim = self.dim;
        let n = Self::record_len(dim);
        let mut out = HashMap::new();
        for r in self.of_pair(p) {
            let slot = r[n - 1] as u32;
            for a in 0..dim {
                let x = [r[1 + dim + 3 * a], r[2 + dim + 3 * a], r[3 + dim + 3 * a]];
                out.insert(r[1 + a] as usize, (slot, x));
            }
        }
        out
    }
}

/// The bounding box of points.
fn bbox(xs: impl Iterator<Item = [f64; 3]>) -> ([f64; 3], [f64; 3]) {
    let (mut lo, mut hi) = EMPTY;
    for x in xs {
        for d in 0..3 {
            lo[d] = lo[d].min(x[d]);
            hi[d] = hi[d].max(x[d]);
        }
    }
    (lo, hi)
}
