//! Phase 1, the partition: PT-Scotch on the coarse graph of block-local aggregates (or on
//! the dual graph itself).

use super::blocks::Blocks;
use super::comm::{blk, block_of, exchange, gathered_offsets, rank_size};
use super::graph::dual_graph;
use super::read::Phases;
use crate::error::RunError;
use crate::petsc;
use crate::petsc::{MPI_Comm, PInt};
use crate::tuning::{AGGREGATE_CELLS, COARSE_PER_PART, SCOTCH_IMBALANCE};
use mpi::datatype::PartitionMut;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

/// Phase 1: the rank of every cell of this block. PT-Scotch partitions the coarse graph of
/// [`aggregate`]'s aggregates (vertex weight: cells, edge weight: facets), which makes its
/// multilevel run far shorter (on the 557 k-cell Hertz disk: 35 k vertices instead of 557 k,
/// at a ~25 % larger edge cut); meshes with fewer than 2 × [`COARSE_PER_PART`] cells per part
/// partition the dual graph itself (as the whole-mesh path `partition::partition` does).
/// `-mat_partitioning_type` sends the dual graph through PETSc's MatPartitioning instead.
pub(super) fn partition_cells(
    world: &SimpleCommunicator,
    comm: MPI_Comm,
    b: &Blocks,
    phases: &mut Phases,
) -> Result<Vec<u32>, RunError> {
    let (_, size) = rank_size(world);
    if size == 1 {
        return Ok(vec![0; b.cell_tags.len()]);
    }
    let (xadj, adjncy) = dual_graph(world, b);
    phases.lap("dual_graph");
    let part: Vec<u32> = if petsc::options::has("-mat_partitioning_type")? {
        let p = petsc::partition_graph(comm, b.n_cells, &xadj, &adjncy, "ptscotch")?;
        phases.lap("scotch");
        p.iter().map(|&r| r as u32).collect()
    } else if aggregate_size(b.n_cells, size) == 1 {
        let p = petsc::scotch_partition(comm, &xadj, &adjncy, None, size, SCOTCH_IMBALANCE)?;
        phases.lap("scotch");
        p.iter().map(|&r| r as u32).collect()
    } else {
        let k = aggregate_size(b.n_cells, size);
        let lo = blk(b.n_cells, size, world.rank() as usize);
        let (agg, n_agg) = aggregate(lo, &xadj, &adjncy, k);
        let c = coarse_graph(world, b.n_cells, &xadj, &adjncy, &agg, n_agg);
        phases.lap("coarse_graph");
        let p = petsc::scotch_partition(
            comm,
            &c.xadj,
            &c.adjncy,
            Some((&c.vwgt, &c.ewgt)),
            size,
            SCOTCH_IMBALANCE,
        )?;
        phases.lap("scotch");
        agg.iter().map(|&a| p[a as usize] as u32).collect()
    };
    if phases.on {
        report_partition(world, b.n_cells, &xadj, &adjncy, &part);
    }
    Ok(part)
}

/// Cells per aggregate for `n_cells` cells on `size` parts: [`AGGREGATE_CELLS`], less where
/// that would leave fewer than [`COARSE_PER_PART`] coarse vertices per part (1: the dual
/// graph itself).
pub(super) fn aggregate_size(n_cells: usize, size: usize) -> usize {
    (n_cells / (size * COARSE_PER_PART)).clamp(1, AGGREGATE_CELLS)
}

/// Groups the cells of this block (first global index `lo`, dual-graph rows `xadj`/`adjncy`)
/// into aggregates of at most `k` cells: each grows breadth first from the lowest cell not yet
/// taken, over neighbours of the same block, so it is connected and compact. Returns every
/// cell's aggregate (local number, in the order of the seeds) and the number of aggregates.
/// Depends only on the block's rows: deterministic.
pub(super) fn aggregate(lo: usize, xadj: &[PInt], adjncy: &[PInt], k: usize) -> (Vec<u32>, usize) {
    let n = xadj.len() - 1;
    let mut agg = vec![u32::MAX; n];
    let mut queue: Vec<usize> = Vec::with_capacity(4 * k);
    let mut n_agg = 0u32;
    for seed in 0..n {
        if agg[seed] != u32::MAX {
            continue;
        }
        agg[seed] = n_agg;
        queue.clear();
        queue.push(seed);
        let (mut head, mut taken) = (0, 1);
        while head < queue.len() && taken < k {
            let i = queue[head];
            head += 1;
            for &j in &adjncy[xadj[i] as usize..xadj[i + 1] as usize] {
                let j = (j as usize).wrapping_sub(lo);
                if j < n && agg[j] == u32::MAX && taken < k {
                    agg[j] = n_agg;
                    queue.push(j);
                    taken += 1;
                }
            }
        }
        n_agg += 1;
    }
    (agg, n_agg as usize)
}

/// The coarse graph of the aggregates: this rank's rows (aggregates numbered in rank order),
/// vertex weight = cells, edge weight = facets between the two aggregates.
pub(super) struct CoarseGraph {
    pub(super) xadj: Vec<PInt>,
    pub(super) adjncy: Vec<PInt>,
    pub(super) vwgt: Vec<PInt>,
    pub(super) ewgt: Vec<PInt>,
}

/// Builds the coarse graph of [`aggregate`]'s aggregates from the dual-graph rows of this
/// block. One exchange: every cell with a neighbour in another block sends its global
/// aggregate to that block. Collective.
pub(super) fn coarse_graph(
    world: &SimpleCommunicator,
    n_cells: usize,
    xadj: &[PInt],
    adjncy: &[PInt],
    agg: &[u32],
    n_agg: usize,
) -> CoarseGraph {
    let (rank, size) = rank_size(world);
    let (lo, n) = (blk(n_cells, size, rank), agg.len());
    let first = gathered_offsets(world, n_agg)[rank] as u64;
    let recv = exchange(world, |p| {
        for i in 0..n {
            for &j in &adjncy[xadj[i] as usize..xadj[i + 1] as usize] {
                let j = j as usize;
                if j < lo || j >= lo + n {
                    p.to(block_of(j, n_cells, size))
                        .extend(&[(lo + i) as u64, first + agg[i] as u64]);
                }
            }
        }
    });
    // remote cell → its global aggregate, sorted by cell
    let mut remote: Vec<(u64, u64)> = recv.data.chunks_exact(2).map(|c| (c[0], c[1])).collect();
    drop(recv);
    remote.sort_unstable();
    remote.dedup();
    let global_agg = |j: usize| -> u64 {
        if j >= lo && j < lo + n {
            first + agg[j - lo] as u64
        } else {
            let at = remote.partition_point(|r| r.0 < j as u64);
            remote[at].1
        }
    };
    // (local aggregate, neighbour aggregate) of every facet between aggregates
    let mut pairs: Vec<(u32, u64)> = Vec::new();
    let mut vwgt = vec![0 as PInt; n_agg];
    for i in 0..n {
        let a = agg[i];
        vwgt[a as usize] += 1;
        for &j in &adjncy[xadj[i] as usize..xadj[i + 1] as usize] {
            let c = global_agg(j as usize);
            if c != first + a as u64 {
                pairs.push((a, c));
            }
        }
    }
    pairs.sort_unstable();
    let mut cx = Vec::with_capacity(n_agg + 1);
    let (mut adj, mut ewgt) = (Vec::new(), Vec::new());
    cx.push(0 as PInt);
    let mut k = 0;
    for a in 0..n_agg as u32 {
        while k < pairs.len() && pairs[k].0 == a {
            let c = pairs[k].1;
            let mut w = 0;
            while k < pairs.len() && pairs[k] == (a, c) {
                w += 1;
                k += 1;
            }
            adj.push(c as PInt);
            ewgt.push(w);
        }
        cx.push(adj.len() as PInt);
    }
    CoarseGraph {
        xadj: cx,
        adjncy: adj,
        vwgt,
        ewgt,
    }
}

/// Diagnostics (`SIGNORINI_DIST_PHASES`): rank 0 prints the edge cut of the dual graph (facets
/// between cells of different parts) and the cells per part. Collective; gathers the whole
/// partition, so only for benchmarks.
pub(super) fn report_partition(
    world: &SimpleCommunicator,
    n_cells: usize,
    xadj: &[PInt],
    adjncy: &[PInt],
    part: &[u32],
) {
    let (rank, size) = rank_size(world);
    let counts: Vec<i32> = (0..size)
        .map(|r| (blk(n_cells, size, r + 1) - blk(n_cells, size, r)) as i32)
        .collect();
    let displs: Vec<i32> = (0..size).map(|r| blk(n_cells, size, r) as i32).collect();
    let mut all = vec![0u32; n_cells];
    world.all_gather_varcount_into(part, &mut PartitionMut::new(&mut all[..], counts, displs));
    let lo = blk(n_cells, size, rank);
    let mut cut = 0u64;
    for (i, w) in xadj.windows(2).enumerate() {
        for &j in &adjncy[w[0] as usize..w[1] as usize] {
            cut += (all[lo + i] != all[j as usize]) as u64;
        }
    }
    let mut total = 0u64;
    world.all_reduce_into(&cut, &mut total, mpi::collective::SystemOperation::sum());
    if rank == 0 {
        let mut per = vec![0usize; size];
        for &p in &all {
            per[p as usize] += 1;
        }
        let max = per.iter().copied().max().unwrap_or(0) as f64;
        eprintln!(
            "dist partition edge cut {} facets, cells per part {per:?} (max/mean {:.4})",
            total / 2,
            max * size as f64 / n_cells.max(1) as f64
        );
    }
}
