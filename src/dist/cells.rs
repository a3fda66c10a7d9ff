//! Phases 3 to 7a: the cells to their ranks, node holders and owners, ghost cells, boundary
//! elements, the local node list.

use super::blocks::Blocks;
use super::comm::{blk, block_of, exchange, rank_size, Packer};
use super::groups::ElemGroups;
use mpi::topology::SimpleCommunicator;

/// Migrated elements of one width (cells, or boundary elements of one kind) as flat arrays:
/// global element number, rank (cells: the rank that owns the cell), tag, nodes (mesh
/// numbers), groups (CSR).
pub(super) struct Elems {
    pub(super) width: usize,
    pub(super) id: Vec<u64>,
    pub(super) rank: Vec<u32>,
    pub(super) tag: Vec<u64>,
    pub(super) nodes: Vec<u64>,
    pub(super) gptr: Vec<usize>,
    pub(super) gids: Vec<u32>,
}

impl Elems {
    pub(super) fn new(width: usize) -> Elems {
        Elems {
            width,
            id: Vec::new(),
            rank: Vec::new(),
            tag: Vec::new(),
            nodes: Vec::new(),
            gptr: vec![0],
            gids: Vec::new(),
        }
    }

    pub(super) fn len(&self) -> usize {
        self.id.len()
    }

    pub(super) fn nodes_of(&self, i: usize) -> &[u64] {
        &self.nodes[i * self.width..(i + 1) * self.width]
    }

    pub(super) fn groups_of(&self, i: usize) -> &[u32] {
        &self.gids[self.gptr[i]..self.gptr[i + 1]]
    }

    /// Writes element i as the record [id, tag, nodes (width), n groups, groups].
    pub(super) fn pack(&self, i: usize, p: &mut Packer) {
        p.extend(&[self.id[i], self.tag[i]]);
        p.extend(self.nodes_of(i));
        let gs = self.groups_of(i);
        p.push(gs.len() as u64);
        for &g in gs {
            p.push(g as u64);
        }
    }

    /// Appends the record at the start of `rec` (as [`Elems::pack`] writes it) with the rank
    /// `rank`; returns its length.
    pub(super) fn push_record(&mut self, rec: &[u64], rank: u32) -> usize {
        let w = self.width;
        self.id.push(rec[0]);
        self.tag.push(rec[1]);
        self.rank.push(rank);
        self.nodes.extend_from_slice(&rec[2..2 + w]);
        let ng = rec[2 + w] as usize;
        self.gids
            .extend(rec[3 + w..3 + w + ng].iter().map(|&g| g as u32));
        self.gptr.push(self.gids.len());
        3 + w + ng
    }

    /// Appends every record of `data`, with the rank `rank`.
    pub(super) fn push_all(&mut self, data: &[u64], rank: u32) {
        let mut i = 0;
        while i < data.len() {
            i += self.push_record(&data[i..], rank);
        }
    }

    /// Sorted by element number; an element received more than once is kept once.
    pub(super) fn sorted(self) -> Elems {
        if self.id.windows(2).all(|p| p[0] < p[1]) {
            return self;
        }
        let mut order: Vec<(u64, u32)> = self
            .id
            .iter()
            .enumerate()
            .map(|(i, &e)| (e, i as u32))
            .collect();
        order.sort_unstable();
        order.dedup_by_key(|p| p.0);
        let mut out = Elems::new(self.width);
        for &(_, i) in &order {
            let i = i as usize;
            out.id.push(self.id[i]);
            out.tag.push(self.tag[i]);
            out.rank.push(self.rank[i]);
            out.nodes.extend_from_slice(self.nodes_of(i));
            out.gids.extend_from_slice(self.groups_of(i));
            out.gptr.push(out.gids.len());
        }
        out
    }
}

/// Phase 3: the cells to their ranks (one exchange): this rank's own cells, in global order
/// (the blocks are in rank order, so they arrive sorted).
pub(super) fn own_cells(
    world: &SimpleCommunicator,
    b: &Blocks,
    part: &[u32],
    eg: &ElemGroups,
) -> Elems {
    let (rank, size) = rank_size(world);
    let npc = b.dim + 1;
    let cell_lo = blk(b.n_cells, size, rank);
    let recv = exchange(world, |p| {
        for (i, cell) in b.cells.chunks_exact(npc).enumerate() {
            p.to(part[i] as usize)
                .extend(&[(cell_lo + i) as u64, b.cell_tags[i]]);
            p.extend(cell);
            let gs = eg.of(0, i);
            p.push(gs.len() as u64);
            for &g in gs {
                p.push(g as u64);
            }
        }
    });
    let mut own = Elems::new(npc);
    own.push_all(&recv.data, rank as u32);
    own.sorted()
}

/// The distinct values of `list` (ascending) and the index of every entry of `list` in them
/// (one sort of (value, position) pairs: no search per entry).
pub(super) fn number_nodes(list: &[u64]) -> (Vec<u64>, Vec<u32>) {
    let mut pairs: Vec<(u64, u32)> = list
        .iter()
        .enumerate()
        .map(|(i, &v)| (v, i as u32))
        .collect();
    pairs.sort_unstable();
    let mut uniq: Vec<u64> = Vec::new();
    let mut index = vec![0u32; list.len()];
    for &(v, i) in &pairs {
        if uniq.last() != Some(&v) {
            uniq.push(v);
        }
        index[i as usize] = (uniq.len() - 1) as u32;
    }
    (uniq, index)
}

/// What the home rank of a block of nodes knows of them: the ranks holding each (ascending;
/// the first, the lowest, owns it), CSR over (node − first home node).
pub(super) struct Homes {
    pub(super) node_lo: usize,
    pub(super) ptr: Vec<usize>,
    pub(super) ranks: Vec<u32>,
}

impl Homes {
    pub(super) fn holders_of(&self, v: u64) -> &[u32] {
        let j = v as usize - self.node_lo;
        &self.ranks[self.ptr[j]..self.ptr[j + 1]]
    }

    /// The owner of home node v (u64::MAX if no cell holds it).
    pub(super) fn owner(&self, v: u64) -> u64 {
        self.holders_of(v).first().map_or(u64::MAX, |&r| r as u64)
    }
}

/// Phase 4: holders and owners: every rank tells the homes which nodes its cells hold; the homes
/// answer with the owners (two exchanges). Returns the homes' knowledge and the owner of
/// every own node (in the order of `own_nodes`, ascending).
pub(super) fn node_homes(
    world: &SimpleCommunicator,
    b: &Blocks,
    own_nodes: &[u64],
) -> (Homes, Vec<u32>) {
    let (rank, size) = rank_size(world);
    let node_lo = blk(b.n_nodes, size, rank);
    let recv = exchange(world, |p| {
        for &v in own_nodes {
            p.to(block_of(v as usize, b.n_nodes, size)).push(v);
        }
    });
    // a counting sort on the node, ranks in ascending order
    let mut ptr = vec![0usize; b.node_tags.len() + 1];
    for &v in &recv.data {
        ptr[v as usize - node_lo + 1] += 1;
    }
    for i in 1..ptr.len() {
        ptr[i] += ptr[i - 1];
    }
    let mut fill = ptr.clone();
    let mut ranks = vec![0u32; recv.data.len()];
    for r in 0..size {
        for &v in recv.from(r) {
            let j = v as usize - node_lo;
            ranks[fill[j]] = r as u32;
            fill[j] += 1;
        }
    }
    drop(fill);
    let homes = Homes {
        node_lo,
        ptr,
        ranks,
    };
    // The answers in the order asked: in rank order they follow `own_nodes` (sorted, and
    // the homes' blocks are in rank order).
    let reply = exchange(world, |p| {
        for r in 0..size {
            p.to(r);
            for &v in recv.from(r) {
                p.push(homes.owner(v));
            }
        }
    });
    let owner = reply.data.iter().map(|&o| o as u32).collect();
    (homes, owner)
}

/// Phase 5: ghost cells: every own cell to the owners of its nodes (one exchange); sorted by
/// global cell.
pub(super) fn ghost_cells(
    world: &SimpleCommunicator,
    own: &Elems,
    own_index: &[u32],
    own_owner: &[u32],
) -> Elems {
    let (rank, size) = rank_size(world);
    let npc = own.width;
    let recv = exchange(world, |p| {
        for c in 0..own.len() {
            let mut to = [u32::MAX; 4];
            let mut n = 0;
            for &i in &own_index[c * npc..(c + 1) * npc] {
                let r = own_owner[i as usize];
                if r as usize != rank && !to[..n].contains(&r) {
                    to[n] = r;
                    n += 1;
                }
            }
            to[..n].sort_unstable();
            for &r in &to[..n] {
                own.pack(c, p.to(r as usize));
            }
        }
    });
    let mut ghosts = Elems::new(npc);
    for r in 0..size {
        ghosts.push_all(recv.from(r), r as u32);
    }
    ghosts.sorted()
}

/// Phase 6: boundary elements to every rank holding one of their nodes, through the homes (two
/// exchanges of [kind, element, tag, nodes (width), n groups, groups]): kind − 1 → elements
/// sorted by number.
pub(super) fn boundary_elements(
    world: &SimpleCommunicator,
    b: &Blocks,
    eg: &ElemGroups,
    homes: &Homes,
) -> [Elems; 3] {
    let (rank, size) = rank_size(world);
    let recv = exchange(world, |p| {
        for k in 1..4 {
            let w = b.width(k);
            let lo = blk(b.count(k), size, rank);
            for (i, nodes) in b.bnd[k - 1].chunks_exact(w).enumerate() {
                let mut to = [usize::MAX; 3];
                let mut n = 0;
                for &v in nodes {
                    let h = block_of(v as usize, b.n_nodes, size);
                    if !to[..n].contains(&h) {
                        to[n] = h;
                        n += 1;
                    }
                }
                to[..n].sort_unstable();
                let gs = eg.of(k, i);
                for &h in &to[..n] {
                    p.to(h)
                        .extend(&[k as u64, (lo + i) as u64, b.bnd_tags[k - 1][i]]);
                    p.extend(nodes);
                    p.push(gs.len() as u64);
                    for &g in gs {
                        p.push(g as u64);
                    }
                }
            }
        }
    });
    // the length of the record at the start of `rec`
    let len = |rec: &[u64]| {
        let w = b.width(rec[0] as usize);
        4 + w + rec[3 + w] as usize
    };
    // at the homes: each record to the holders of its home nodes
    let mut to: Vec<u32> = Vec::new();
    let fwd = exchange(world, |p| {
        let mut i = 0;
        while i < recv.data.len() {
            let rec = &recv.data[i..];
            let (k, n) = (rec[0] as usize, len(rec));
            to.clear();
            for &v in &rec[3..3 + b.width(k)] {
                if block_of(v as usize, b.n_nodes, size) == rank {
                    to.extend_from_slice(homes.holders_of(v));
                }
            }
            to.sort_unstable();
            to.dedup();
            for &r in &to {
                p.to(r as usize).extend(&rec[..n]);
            }
            i += n;
        }
    });
    drop(recv);
    let mut bnd: [Elems; 3] = std::array::from_fn(|k| Elems::new(b.width(k + 1)));
    let mut i = 0;
    while i < fwd.data.len() {
        let k = fwd.data[i] as usize;
        i += 1 + bnd[k - 1].push_record(&fwd.data[i + 1..], 0);
    }
    bnd.map(Elems::sorted)
}

/// Phase 7a: the local nodes (mesh numbers, ascending): the own nodes merged with those of the
/// ghosts and the boundary elements; and the local index of every own node.
pub(super) fn local_node_list(
    own_nodes: Vec<u64>,
    ghosts: &Elems,
    bnd: &[Elems; 3],
) -> (Vec<u64>, Vec<u32>) {
    let mut extra: Vec<u64> = ghosts
        .nodes
        .iter()
        .chain(bnd.iter().flat_map(|e| e.nodes.iter()))
        .copied()
        .filter(|v| own_nodes.binary_search(v).is_err())
        .collect();
    extra.sort_unstable();
    extra.dedup();
    let mut orig = Vec::with_capacity(own_nodes.len() + extra.len());
    let mut own_local = Vec::with_capacity(own_nodes.len());
    let mut e = extra.iter().peekable();
    for &v in &own_nodes {
        while let Some(&&x) = e.peek() {
            if x > v {
                break;
            }
            orig.push(x);
            e.next();
        }
        own_local.push(orig.len() as u32);
        orig.push(v);
    }
    orig.extend(e);
    (orig, own_local)
}
