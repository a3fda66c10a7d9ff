//! Nodes of the mesh's surface that lie where another node lies without being that node: parts
//! of a mesh whose shared surface was meshed twice and never joined (two Gmsh volumes without
//! BooleanFragments or Coherence, a mesh written with duplicate nodes). Such parts are separate
//! bodies, or a body with a crack, though the picture shows one: a silent wrong answer unless a
//! contact pair joins them.
//!
//! Every rank takes its owned nodes on the surface of its cells (a facet of one local cell
//! alone) and sends each to the rank that owns its cell of a fine grid (by a hash of the cell),
//! and to the neighbouring cells' ranks where it lies within the tolerance of a cell's border.
//! A rank compares the nodes of each grid cell it receives: O(surface nodes) sent once, never
//! the mesh on one rank.

use crate::bodies::Survey;
use crate::dist::comm::exchange;
use crate::mesh::Mesh;
use crate::par::Ctx;
use crate::partition::Layout;
use std::collections::HashMap;

/// Two nodes are one point when they are this fraction of the mesh's extent apart or closer:
/// far below any element (a mesh of 10⁶ elements along its extent has them 10⁻⁶ apart), far
/// above the round-off of coordinates written with 16 digits.
pub const COINCIDENT_FRACTION: f64 = 1e-10;

/// The grid's cell side over the tolerance: each node lies within the tolerance of its cell's
/// border (and goes to a neighbour too) in a fraction 2 / this of each direction.
const GRID_OVER_TOL: f64 = 1e4;

/// What [`unjoined`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct Unjoined {
    /// Pairs of distinct surface nodes at one point, not both in a contact group.
    pub pairs: usize,
    /// The pair whose smaller Gmsh node tag is smallest: its two tags (the smaller first), the
    /// point (of the smaller), the bodies (indices into the survey's list) of its nodes.
    pub first: (u64, u64),
    pub at: [f64; 3],
    pub bodies: (usize, usize),
}

/// Per local node of `mesh`: whether it lies on the surface of the local cells (on a facet of
/// one local cell alone). Exact for owned nodes: every cell touching one is local. A facet
/// through v is named by its other nodes; it is on the surface where one cell at v alone has
/// it. Local.
fn on_surface(mesh: &Mesh, layout: &Layout) -> Vec<bool> {
    let mut on = vec![false; mesh.n_nodes()];
    let mut keys: Vec<(usize, usize)> = Vec::new();
    for &v in &layout.owned_nodes {
        keys.clear();
        for &c in layout.node_cells.of(v) {
            let others: Vec<usize> = mesh.cell(c).iter().copied().filter(|&w| w != v).collect();
            // the facets of c through v: v with all of c's other nodes but one
            for skip in 0..others.len() {
                let mut rest = (0..others.len()).filter(|&k| k != skip).map(|k| others[k]);
                let a = rest.next().unwrap_or(usize::MAX);
                let b = rest.next().unwrap_or(usize::MAX);
                keys.push((a.min(b), a.max(b)));
            }
        }
        keys.sort_unstable();
        let mut i = 0;
        while i < keys.len() {
            let mut j = i + 1;
            while j < keys.len() && keys[j] == keys[i] {
                j += 1;
            }
            if j - i == 1 {
                on[v] = true;
                break;
            }
            i = j;
        }
    }
    on
}

/// The surface nodes of the distributed `mesh` that lie where another node lies (within
/// [`COINCIDENT_FRACTION`] of its extent), but for pairs whose nodes both lie in a contact
/// pair's group (`in_pair`, per local node: a body pair's two surfaces may start touching).
/// `None` where there are none. Collective; every rank returns the same.
pub fn unjoined(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    survey: &Survey,
    in_pair: &[bool],
) -> Option<Unjoined> {
    let tol = COINCIDENT_FRACTION * mesh.extent();
    let side = GRID_OVER_TOL * tol;
    let dim = mesh.dim;
    let surface = on_surface(mesh, layout);
    let nodes: Vec<usize> = (layout.owned_nodes.iter().copied())
        .filter(|&v| surface[v])
        .collect();
    let size = ctx.size;
    // a grid cell's owner: a hash of its integer coordinates
    let owner = |key: &[i64; 3]| -> usize {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for &k in key {
            h ^= k as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
            h ^= h >> 29;
        }
        (h % size as u64) as usize
    };
    // the grid cells a node goes to: its own first, then those within tol of it
    let cells_of = |x: &[f64; 3]| -> Vec<[i64; 3]> {
        let mut out: Vec<[i64; 3]> = vec![[0; 3]];
        for i in 0..dim {
            let k = (x[i] / side).floor();
            let mut ks = vec![k as i64];
            if x[i] - k * side < tol {
                ks.push(k as i64 - 1);
            }
            if (k + 1.0) * side - x[i] < tol {
                ks.push(k as i64 + 1);
            }
            out = out
                .iter()
                .flat_map(|c| {
                    ks.iter().map(move |&kk| {
                        let mut c = *c;
                        c[i] = kk;
                        c
                    })
                })
                .collect();
        }
        out
    };
    // record: key (3), global node, tag, x (3 as bits), body, flags (1: in a pair's group, 2:
    // the node's own cell)
    const REC: usize = 10;
    let received = exchange(ctx.world, |p| {
        for &v in &nodes {
            let x = mesh.coords[v];
            for (i, key) in cells_of(&x).iter().enumerate() {
                p.to(owner(key)).extend(&[
                    key[0] as u64,
                    key[1] as u64,
                    key[2] as u64,
                    layout.node_global[v] as u64,
                    mesh.node_tags[v],
                    x[0].to_bits(),
                    x[1].to_bits(),
                    x[2].to_bits(),
                    u64::from(survey.body_of[v]),
                    u64::from(in_pair[v]) | if i == 0 { 2 } else { 0 },
                ]);
            }
        }
    });
    let mut buckets: HashMap<[u64; 3], Vec<&[u64]>> = HashMap::new();
    for rec in received.data.chunks_exact(REC) {
        buckets
            .entry([rec[0], rec[1], rec[2]])
            .or_default()
            .push(rec);
    }
    // (the smaller tag, the other tag, x, their bodies)
    let mut pairs = 0usize;
    let mut first: Option<(u64, u64, [f64; 3], u64, u64)> = None;
    let point = |r: &[u64]| {
        [
            f64::from_bits(r[5]),
            f64::from_bits(r[6]),
            f64::from_bits(r[7]),
        ]
    };
    for recs in buckets.values() {
        for (i, a) in recs.iter().enumerate() {
            for b in &recs[i + 1..] {
                if a[3] == b[3] {
                    continue;
                }
                // by Gmsh tag, not by the global numbering (which the partition chooses)
                let (lo, hi) = if (a[4], a[3]) < (b[4], b[3]) {
                    (a, b)
                } else {
                    (b, a)
                };
                // counted once: in the smaller node's own cell
                if lo[9] & 2 == 0 {
                    continue;
                }
                if lo[9] & 1 == 1 && hi[9] & 1 == 1 {
                    continue;
                }
                let (p, q) = (point(lo), point(hi));
                let d2: f64 = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum();
                if d2.sqrt() > tol {
                    continue;
                }
                pairs += 1;
                if first.is_none_or(|f| (lo[4], hi[4]) < (f.0, f.1)) {
                    first = Some((lo[4], hi[4], p, lo[8], hi[8]));
                }
            }
        }
    }
    let total = ctx.sum_usize(pairs);
    if total == 0 {
        return None;
    }
    // the smallest first pair over the ranks
    // (tags as f64: exact below 2^53)
    let mine = match first {
        Some((ta, tb, p, ba, bb)) => {
            vec![ta as f64, tb as f64, p[0], p[1], p[2], ba as f64, bb as f64]
        }
        None => vec![f64::INFINITY; 7],
    };
    let all = ctx.all_gather_varcount(&mine);
    let best = all
        .chunks_exact(7)
        .min_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])))
        .expect("one rank at least");
    Some(Unjoined {
        pairs: total,
        first: (best[0] as u64, best[1] as u64),
        at: [best[2], best[3], best[4]],
        bodies: (best[5] as usize, best[6] as usize),
    })
}
