//! Phases 7b to 10: node data, the global numbering, the local mesh and its layout.

use super::blocks::Blocks;
use super::cells::{Elems, Homes};
use super::comm::{block_of, counts_sum, exchange, gathered_offsets, rank_size};
use super::groups::NodeGroups;
use crate::mesh::{GlobalInfo, Group, Mesh};
use crate::partition::{morton_key, Layout, NodeCells};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

/// The bounding box of the whole mesh, from the coordinate blocks. Collective.
pub(super) fn global_bbox(world: &SimpleCommunicator, b: &Blocks) -> ([f64; 3], [f64; 3]) {
    let mut lohi = [f64::INFINITY; 6];
    for x in b.coords.chunks_exact(3) {
        for k in 0..3 {
            lohi[k] = lohi[k].min(x[k]);
            lohi[3 + k] = lohi[3 + k].min(-x[k]);
        }
    }
    let mut glohi = [0.0; 6];
    world.all_reduce_into(
        &lohi[..],
        &mut glohi[..],
        mpi::collective::SystemOperation::min(),
    );
    (
        [glohi[0], glohi[1], glohi[2]],
        [-glohi[3], -glohi[4], -glohi[5]],
    )
}

/// What is kept of the whole mesh once its blocks are dropped.
pub(super) struct WholeMesh {
    pub(super) dim: usize,
    pub(super) n_nodes: usize,
    pub(super) n_facets: usize,
    pub(super) groups: Vec<Group>,
    pub(super) group_sizes: Vec<usize>,
    pub(super) bbox: ([f64; 3], [f64; 3]),
}

/// The local nodes (mesh numbers `orig`, sorted) and their data.
pub(super) struct LocalNodes {
    pub(super) orig: Vec<u64>,
    pub(super) coords: Vec<[f64; 3]>,
    pub(super) tags: Vec<u64>,
    pub(super) owner: Vec<u32>,
    /// Groups of local node l: group_ids[group_ptr[l]..group_ptr[l + 1]].
    pub(super) group_ptr: Vec<usize>,
    pub(super) group_ids: Vec<u32>,
}

impl LocalNodes {
    /// The local index of mesh node v.
    pub(super) fn local(&self, v: u64) -> usize {
        self.orig.binary_search(&v).expect("local node")
    }
}

/// Phase 7b: the local nodes' data from their homes (two exchanges: the nodes asked, the
/// answers [owner, tag, x, y, z, n groups, groups] in the order asked, which in rank order
/// is the order of `orig`).
pub(super) fn node_data(
    world: &SimpleCommunicator,
    b: &Blocks,
    homes: &Homes,
    node_groups: &NodeGroups,
    orig: Vec<u64>,
) -> LocalNodes {
    let (_, size) = rank_size(world);
    let req = exchange(world, |p| {
        for &v in &orig {
            p.to(block_of(v as usize, b.n_nodes, size)).push(v);
        }
    });
    let reply = exchange(world, |p| {
        for r in 0..size {
            p.to(r);
            for &v in req.from(r) {
                let j = v as usize - homes.node_lo;
                let x = &b.coords[3 * j..3 * j + 3];
                let gs = node_groups.of(j);
                p.extend(&[
                    homes.owner(v),
                    b.node_tags[j],
                    x[0].to_bits(),
                    x[1].to_bits(),
                    x[2].to_bits(),
                    gs.len() as u64,
                ]);
                for &g in gs {
                    p.push(g as u64);
                }
            }
        }
    });
    drop(req);
    let nl = orig.len();
    let mut n = LocalNodes {
        coords: Vec::with_capacity(nl),
        tags: Vec::with_capacity(nl),
        owner: Vec::with_capacity(nl),
        group_ptr: Vec::with_capacity(nl + 1),
        group_ids: Vec::new(),
        orig,
    };
    n.group_ptr.push(0);
    let d = &reply.data;
    let mut i = 0;
    while i < d.len() {
        n.owner.push(d[i] as u32);
        n.tags.push(d[i + 1]);
        n.coords.push([
            f64::from_bits(d[i + 2]),
            f64::from_bits(d[i + 3]),
            f64::from_bits(d[i + 4]),
        ]);
        let ng = d[i + 5] as usize;
        n.group_ids
            .extend(d[i + 6..i + 6 + ng].iter().map(|&g| g as u32));
        n.group_ptr.push(n.group_ids.len());
        i += 6 + ng;
    }
    debug_assert_eq!(n.owner.len(), nl);
    n
}

/// The global node numbering.
pub(super) struct Numbering {
    /// Local indices of the owned nodes, in global order.
    pub(super) owned: Vec<usize>,
    pub(super) node_offsets: Vec<usize>,
    pub(super) node_global: Vec<usize>,
}

/// Phase 8: global numbering: the owned nodes along the Morton curve of the whole mesh (ties
/// by mesh order); the owners answer for the other local nodes (two exchanges, the answers
/// in the order asked). Collective.
pub(super) fn global_numbering(
    world: &SimpleCommunicator,
    n: &LocalNodes,
    whole: &WholeMesh,
) -> Numbering {
    let (rank, size) = rank_size(world);
    let (dim, bbox) = (whole.dim, &whole.bbox);
    let nl = n.orig.len();
    let extent = (0..dim)
        .map(|k| bbox.1[k] - bbox.0[k])
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut keyed: Vec<(u64, u64, usize)> = (0..nl)
        .filter(|&l| n.owner[l] as usize == rank)
        .map(|l| (morton_key(&n.coords[l], dim, &bbox.0, extent), n.orig[l], l))
        .collect();
    keyed.sort_unstable();
    let owned: Vec<usize> = keyed.into_iter().map(|k| k.2).collect();
    let node_offsets = gathered_offsets(world, owned.len());
    let mut node_global = vec![usize::MAX; nl];
    for (i, &l) in owned.iter().enumerate() {
        node_global[l] = node_offsets[rank] + i;
    }
    // a node no cell holds has no owner (u32::MAX) and no number
    let asked = |l: usize| n.owner[l] as usize != rank && (n.owner[l] as usize) < size;
    let req = exchange(world, |p| {
        for l in (0..nl).filter(|&l| asked(l)) {
            p.to(n.owner[l] as usize).push(n.orig[l]);
        }
    });
    let reply = exchange(world, |p| {
        for r in 0..size {
            p.to(r);
            for &v in req.from(r) {
                p.push(node_global[n.local(v)] as u64);
            }
        }
    });
    drop(req);
    let mut next = reply.offsets.clone();
    for l in (0..nl).filter(|&l| asked(l)) {
        let r = n.owner[l] as usize;
        node_global[l] = reply.data[next[r]] as usize;
        next[r] += 1;
    }
    Numbering {
        owned,
        node_offsets,
        node_global,
    }
}

/// Phase 9: the local mesh: own cells (global order), then ghosts (`cell_nodes`: their local
/// nodes); boundary elements; groups (cell groups hold own and ghost cells); the whole mesh's
/// counts. Takes the nodes' coordinates, tags and groups out of `n` (no copies). Collective
/// (one sum).
pub(super) fn local_mesh(
    world: &SimpleCommunicator,
    whole: &WholeMesh,
    n: &mut LocalNodes,
    cell_nodes: Vec<usize>,
    own: &Elems,
    ghosts: &Elems,
    bnd: &[Elems; 3],
) -> Mesh {
    let (rank, _) = rank_size(world);
    let dim = whole.dim;
    let n_own = own.len();
    let mut groups: Vec<Group> = whole
        .groups
        .iter()
        .map(|g| Group {
            elements: Vec::new(),
            ..g.clone()
        })
        .collect();
    // own cells first, then the ghosts (their materials are needed where they touch owned
    // nodes); every group's elements stay ascending
    for (ci, gs) in (0..n_own)
        .map(|ci| own.groups_of(ci))
        .chain((0..ghosts.len()).map(|i| ghosts.groups_of(i)))
        .enumerate()
    {
        for &g in gs {
            if groups[g as usize].dim == dim {
                groups[g as usize].elements.push(ci);
            }
        }
    }
    let cell_tags = own.tag.iter().chain(&ghosts.tag).copied().collect();
    let mut lists: [(Vec<usize>, Vec<u64>); 3] = Default::default();
    for (k, e) in bnd.iter().enumerate() {
        lists[k].0 = e.nodes.iter().map(|&v| n.local(v)).collect();
        lists[k].1 = e.tag.clone();
        for i in 0..e.len() {
            for &g in e.groups_of(i) {
                groups[g as usize].elements.push(i);
            }
        }
    }
    let [(facets, facet_tags), (edges, edge_tags), (points, point_tags)] = lists;
    let mut mesh = Mesh {
        dim,
        coords: std::mem::take(&mut n.coords),
        node_tags: std::mem::take(&mut n.tags),
        cells: cell_nodes,
        cell_tags,
        facets,
        facet_tags,
        edges,
        edge_tags,
        points,
        point_tags,
        groups,
        global: None,
    };
    let facet_checked: Vec<bool> = (0..mesh.n_facets())
        .map(|f| mesh.facet(f).iter().any(|&v| n.owner[v] as usize == rank))
        .collect();
    mesh.global = Some(Box::new(GlobalInfo {
        n_nodes: whole.n_nodes,
        n_cells: counts_sum(world, n_own),
        n_facets: whole.n_facets,
        group_sizes: whole.group_sizes.clone(),
        bbox: whole.bbox,
        node_group_ptr: std::mem::take(&mut n.group_ptr),
        node_group_ids: std::mem::take(&mut n.group_ids),
        facet_checked,
        n_own_cells: n_own,
    }));
    mesh
}

/// Phase 10: the layout: node ownership and numbering, own cells in the order of their lowest
/// global node (locality of the assembly loop; ties by global cell), cell offsets of the
/// output. Collective.
pub(super) fn local_layout(
    world: &SimpleCommunicator,
    mesh: &Mesh,
    n: LocalNodes,
    numbering: Numbering,
    own: &Elems,
    ghosts: &Elems,
) -> Layout {
    let (rank, size) = rank_size(world);
    let n_own = own.len();
    let node_global = numbering.node_global;
    // the keys computed once (a key per comparison would read scattered memory)
    let mut keyed: Vec<(usize, u64, usize)> = (0..n_own)
        .map(|c| {
            let first = mesh
                .cell(c)
                .iter()
                .map(|&v| node_global[v])
                .min()
                .unwrap_or(0);
            (first, own.id[c], c)
        })
        .collect();
    keyed.sort_unstable();
    let local_cells = keyed.into_iter().map(|k| k.2).collect();
    Layout {
        rank,
        size,
        cell_rank: own.rank.iter().chain(&ghosts.rank).copied().collect(),
        node_owner: n.owner,
        node_global,
        node_offsets: numbering.node_offsets,
        owned_nodes: numbering.owned,
        local_cells,
        cell_offsets: gathered_offsets(world, n_own),
        node_cells: NodeCells::new(mesh),
        node_orig: n.orig.iter().map(|&v| v as usize).collect(),
    }
}
