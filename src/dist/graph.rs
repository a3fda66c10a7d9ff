//! The dual graph of the cells without the whole mesh: facet keys hashed to a home rank.

use super::blocks::Blocks;
use super::comm::{blk, block_of, exchange, rank_size, Received};
use crate::petsc::PInt;
use mpi::topology::SimpleCommunicator;

/// The facet of `cell` without its corner `skip`: its nodes ascending (`u64::MAX` pads the
/// unused places).
pub(super) fn facet_key(cell: &[u64], skip: usize) -> [u64; 3] {
    let mut key = [u64::MAX; 3];
    let mut j = 0;
    for (a, &v) in cell.iter().enumerate() {
        if a != skip {
            key[j] = v;
            j += 1;
        }
    }
    key[..j].sort_unstable();
    key
}

/// A 64-bit hash of a facet key.
pub(super) fn facet_hash(key: &[u64; 3]) -> u64 {
    key.iter()
        .fold(0xcbf29ce484222325u64, |h, &k| {
            (h ^ k).wrapping_mul(0x100000001b3)
        })
        .wrapping_mul(0x9E3779B97F4A7C15)
}

/// A second, independent 24-bit hash of a facet key (with [`facet_hash`]: 88 bits).
pub(super) fn facet_check(key: &[u64; 3]) -> u64 {
    key.iter().fold(0x2545F4914F6CDD1Du64, |h, &k| {
        (h.rotate_left(23) ^ k).wrapping_mul(0xff51afd7ed558ccd)
    }) >> 40
}

/// The rank that matches the cells sharing a facet (a hash of its key).
pub(super) fn facet_home(key: &[u64; 3], size: usize) -> usize {
    ((facet_hash(key) >> 32) % size as u64) as usize
}

/// Calls `f` with every run of records with the same facet key (records sorted).
pub(super) fn facet_runs(recs: &[[u64; 4]], mut f: impl FnMut(&[[u64; 4]])) {
    let mut i = 0;
    while i < recs.len() {
        let mut j = i + 1;
        while j < recs.len() && recs[j][..3] == recs[i][..3] {
            j += 1;
        }
        f(&recs[i..j]);
        i = j;
    }
}

/// Dual-graph rows of this rank's block of cells (cells sharing a facet), CSR, global cell
/// indices, neighbours ascending. A facet of exactly two cells of the block is matched on the
/// block's rank (by an 88-bit hash of its key); every other facet (on the boundary, between blocks, or of more than two
/// cells) is sent to a home rank chosen by hashing its key, which sends every pair of cells
/// sharing it back to the readers of the cells. Two exchanges. (A facet of two cells of one
/// block and more of other blocks — not a valid mesh — loses the pairs across.)
pub(super) fn dual_graph(world: &SimpleCommunicator, b: &Blocks) -> (Vec<PInt>, Vec<PInt>) {
    let (rank, size) = rank_size(world);
    let lo = blk(b.n_cells, size, rank);
    let (local_pairs, remote) = block_facets(b, lo);
    let pairs = home_pairs(world, b, remote);
    csr_rows(lo, b.cell_tags.len(), local_pairs, pairs)
}

/// The facets of this block (first global cell `lo`) matched on this rank: the pairs
/// [a, c, c, a] of global cells sharing a facet of exactly two cells of the block, and the
/// records [facet key (padded), global cell] of every other facet, for the facets' homes.
fn block_facets(b: &Blocks, lo: usize) -> (Vec<u64>, Vec<[u64; 4]>) {
    let npc = b.dim + 1;
    let n_local = b.cell_tags.len();
    // (88-bit facet hash, cell · 4 + corner left out) of this block, sorted: 16-byte records,
    // equal facets next to each other. Two records of equal hash are taken as one facet of two
    // cells without comparing the keys (a false match, ~2^-88 per pair of facets, would only
    // add one edge to the partitioner's graph, never change the mesh); every other run of
    // equal hashes goes to the facets' homes, which match the keys exactly.
    let mut mine: Vec<u128> = Vec::with_capacity(n_local * npc);
    for (i, cell) in b.cells.chunks_exact(npc).enumerate() {
        for skip in 0..npc {
            let key = facet_key(cell, skip);
            mine.push(
                ((facet_hash(&key) as u128) << 64)
                    | ((facet_check(&key) as u128) << 40)
                    | (4 * i + skip) as u128,
            );
        }
    }
    mine.sort_unstable();
    let cell_of = |r: u128| ((r as u64 & ((1 << 40) - 1)) >> 2) as usize;
    let mut local_pairs: Vec<u64> = Vec::new();
    // [facet key (padded), cell] of the facets matched at their home rank
    let mut remote: Vec<[u64; 4]> = Vec::new();
    let mut i = 0;
    while i < mine.len() {
        let mut j = i + 1;
        while j < mine.len() && mine[j] >> 40 == mine[i] >> 40 {
            j += 1;
        }
        let (a, c) = (cell_of(mine[i]), cell_of(mine[j - 1]));
        if j - i == 2 && a != c {
            let (a, c) = ((lo + a) as u64, (lo + c) as u64);
            local_pairs.extend_from_slice(&[a, c, c, a]);
        } else {
            for &r in &mine[i..j] {
                let (c, skip) = (cell_of(r), (r as u64 & 3) as usize);
                let key = facet_key(&b.cells[c * npc..(c + 1) * npc], skip);
                remote.push([key[0], key[1], key[2], (lo + c) as u64]);
            }
        }
        i = j;
    }
    (local_pairs, remote)
}

/// The facets of `remote` matched at their home ranks (a hash of the key): every pair of
/// cells sharing a facet comes back to the reader of the first cell as [a, c]. Two exchanges.
fn home_pairs(world: &SimpleCommunicator, b: &Blocks, remote: Vec<[u64; 4]>) -> Received {
    let (_, size) = rank_size(world);
    let w = b.dim;
    let recv = exchange(world, |p| {
        for r in &remote {
            let key = [r[0], r[1], r[2]];
            p.to(facet_home(&key, size)).extend(&key[..w]);
            p.push(r[3]);
        }
    });
    drop(remote);
    // at the homes: the cells of a facet are neighbours
    let mut recs: Vec<[u64; 4]> = recv
        .data
        .chunks_exact(w + 1)
        .map(|c| {
            let mut r = [u64::MAX; 4];
            r[..w].copy_from_slice(&c[..w]);
            r[3] = c[w];
            r
        })
        .collect();
    drop(recv);
    recs.sort_unstable();
    exchange(world, |p| {
        facet_runs(&recs, |run| {
            for a in run {
                for c in run {
                    if a[3] != c[3] {
                        p.to(block_of(a[3] as usize, b.n_cells, size))
                            .extend(&[a[3], c[3]]);
                    }
                }
            }
        });
    })
}

/// The CSR rows of the `n_local` cells from `lo` on, from the pairs [cell, neighbour] found
/// on this rank and at the homes: a counting sort on the local cell, then every row sorted
/// and unique.
fn csr_rows(
    lo: usize,
    n_local: usize,
    local_pairs: Vec<u64>,
    pairs: Received,
) -> (Vec<PInt>, Vec<PInt>) {
    let all = || {
        local_pairs
            .chunks_exact(2)
            .chain(pairs.data.chunks_exact(2))
    };
    let mut start = vec![0usize; n_local + 1];
    for pr in all() {
        start[pr[0] as usize - lo + 1] += 1;
    }
    for i in 0..n_local {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut adjncy = vec![0 as PInt; start[n_local]];
    for pr in all() {
        let i = pr[0] as usize - lo;
        adjncy[fill[i]] = pr[1] as PInt;
        fill[i] += 1;
    }
    drop(pairs);
    drop(local_pairs);
    drop(fill);
    let mut xadj = Vec::with_capacity(n_local + 1);
    xadj.push(0 as PInt);
    let mut out = 0;
    for i in 0..n_local {
        adjncy[start[i]..start[i + 1]].sort_unstable();
        for k in start[i]..start[i + 1] {
            if k == start[i] || adjncy[k] != adjncy[k - 1] {
                adjncy[out] = adjncy[k];
                out += 1;
            }
        }
        xadj.push(out as PInt);
    }
    adjncy.truncate(out);
    (xadj, adjncy)
}
