//! Phase 2, the physical groups of the elements and of the nodes.

use super::blocks::Blocks;
use super::comm::{blk, block_of, exchange, rank_size};
use mpi::topology::SimpleCommunicator;

/// The groups of this rank's block of elements of every kind, CSR over (element − first of
/// the block).
pub(super) struct ElemGroups {
    pub(super) ptr: [Vec<usize>; 4],
    pub(super) ids: [Vec<u32>; 4],
}

impl ElemGroups {
    /// The groups of element i (of this rank's block) of kind k.
    pub(super) fn of(&self, k: usize, i: usize) -> &[u32] {
        &self.ids[k][self.ptr[k][i]..self.ptr[k][i + 1]]
    }
}

/// Phase 2a: group memberships sent to the readers of the elements (one exchange of
/// [kind, element, group]); each element's groups in the file's order.
pub(super) fn element_groups(world: &SimpleCommunicator, b: &Blocks) -> ElemGroups {
    let (rank, size) = rank_size(world);
    let recv = exchange(world, |p| {
        for &(g, e) in &b.members {
            let k = b.kind(b.groups[g as usize].dim);
            p.to(block_of(e as usize, b.count(k), size))
                .extend(&[k as u64, e, g]);
        }
    });
    let lo: [usize; 4] = std::array::from_fn(|k| blk(b.count(k), size, rank));
    let mut ptr: [Vec<usize>; 4] =
        std::array::from_fn(|k| vec![0; blk(b.count(k), size, rank + 1) - lo[k] + 1]);
    for c in recv.data.chunks_exact(3) {
        let k = c[0] as usize;
        ptr[k][c[1] as usize - lo[k] + 1] += 1;
    }
    for p in ptr.iter_mut() {
        for i in 1..p.len() {
            p[i] += p[i - 1];
        }
    }
    let mut ids: [Vec<u32>; 4] = std::array::from_fn(|k| vec![0; *ptr[k].last().unwrap_or(&0)]);
    let mut fill = ptr.clone();
    for c in recv.data.chunks_exact(3) {
        let (k, i) = (c[0] as usize, c[1] as usize - lo[c[0] as usize]);
        ids[k][fill[k][i]] = c[2] as u32;
        fill[k][i] += 1;
    }
    ElemGroups { ptr, ids }
}

/// The groups of this rank's home nodes, CSR over (node − first home node): the groups of
/// every element containing the node, ascending, unique.
pub(super) struct NodeGroups {
    pub(super) ptr: Vec<usize>,
    pub(super) ids: Vec<u32>,
}

impl NodeGroups {
    pub(super) fn of(&self, j: usize) -> &[u32] {
        &self.ids[self.ptr[j]..self.ptr[j + 1]]
    }
}

/// Phase 2b: node-level memberships at the node homes: every rank sends the distinct
/// (node, group) pairs of its block's elements (one exchange, one u64 each).
pub(super) fn node_groups(world: &SimpleCommunicator, b: &Blocks, eg: &ElemGroups) -> NodeGroups {
    let (rank, size) = rank_size(world);
    let ng = b.groups.len().max(1) as u64;
    let mut codes: Vec<u64> = Vec::new();
    for k in 0..4 {
        let w = b.width(k);
        let list = if k == 0 { &b.cells } else { &b.bnd[k - 1] };
        for (i, nodes) in list.chunks_exact(w).enumerate() {
            for &g in eg.of(k, i) {
                codes.extend(nodes.iter().map(|&v| v * ng + g as u64));
            }
        }
    }
    codes.sort_unstable();
    codes.dedup();
    let recv = exchange(world, |p| {
        for &c in &codes {
            p.to(block_of((c / ng) as usize, b.n_nodes, size)).push(c);
        }
    });
    drop(codes);
    let mut got = recv.data;
    got.sort_unstable();
    got.dedup();
    let node_lo = blk(b.n_nodes, size, rank);
    let mut ptr = vec![0usize; b.node_tags.len() + 1];
    for &c in &got {
        ptr[(c / ng) as usize - node_lo + 1] += 1;
    }
    for i in 1..ptr.len() {
        ptr[i] += ptr[i - 1];
    }
    let ids = got.iter().map(|&c| (c % ng) as u32).collect();
    NodeGroups { ptr, ids }
}
