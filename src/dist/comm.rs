//! The communication pattern of the distributed read: row blocks of the ranks and one
//! all-to-all-v of flat u64 records per exchange.

use mpi::datatype::{Partition, PartitionMut};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

/// First row of rank r's block of n rows (the same blocks as the partitioner's).
pub fn blk(n: usize, size: usize, r: usize) -> usize {
    ((r as u128 * n as u128) / size as u128) as usize
}

/// The rank whose block holds row i.
pub(super) fn block_of(i: usize, n: usize, size: usize) -> usize {
    let mut lo = 0;
    let mut hi = size; // blk(lo) <= i < blk(hi)
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if blk(n, size, mid) <= i {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The records of one all-to-all-v, written by the same closure in two passes: the first
/// counts the u64 sent to every rank, the second writes them into one contiguous buffer at
/// their rank's place. No vector per item or per rank.
pub(crate) struct Packer {
    pub(super) filling: bool,
    pub(super) dest: usize,
    pub(super) counts: Vec<usize>,
    pub(super) fill: Vec<usize>,
    pub(super) buf: Vec<u64>,
}

impl Packer {
    /// The next values go to rank r.
    pub(crate) fn to(&mut self, r: usize) -> &mut Packer {
        self.dest = r;
        self
    }

    pub(crate) fn push(&mut self, x: u64) {
        if self.filling {
            self.buf[self.fill[self.dest]] = x;
            self.fill[self.dest] += 1;
        } else {
            self.counts[self.dest] += 1;
        }
    }

    pub(crate) fn extend(&mut self, xs: &[u64]) {
        if self.filling {
            let f = self.fill[self.dest];
            self.buf[f..f + xs.len()].copy_from_slice(xs);
            self.fill[self.dest] += xs.len();
        } else {
            self.counts[self.dest] += xs.len();
        }
    }
}

/// What one all-to-all-v brought: every rank's records, concatenated in rank order.
pub(crate) struct Received {
    pub(crate) data: Vec<u64>,
    /// Rank r's records are data[offsets[r]..offsets[r + 1]].
    pub(crate) offsets: Vec<usize>,
}

impl Received {
    pub(crate) fn from(&self, r: usize) -> &[u64] {
        &self.data[self.offsets[r]..self.offsets[r + 1]]
    }
}

/// One all-to-all-v of u64 records (and one all-to-all of the counts): `pack` writes every
/// record with its destination; it is called twice (count, fill) and must write the same
/// records both times. Collective.
pub(crate) fn exchange(world: &SimpleCommunicator, mut pack: impl FnMut(&mut Packer)) -> Received {
    let size = world.size() as usize;
    let mut p = Packer {
        filling: false,
        dest: 0,
        counts: vec![0; size],
        fill: Vec::new(),
        buf: Vec::new(),
    };
    pack(&mut p);
    let displs = crate::par::offsets(&p.counts);
    let total: usize = p.counts.iter().sum();
    p.fill = displs.clone();
    p.buf = vec![0u64; total];
    p.filling = true;
    pack(&mut p);
    debug_assert!((0..size).all(|r| p.fill[r] == displs[r] + p.counts[r]));
    let to_i32 = |v: &[usize]| -> Vec<i32> {
        v.iter()
            .map(|&c| i32::try_from(c).expect("fewer than 2^31 values per message"))
            .collect()
    };
    let counts = to_i32(&p.counts);
    let mut rcounts = vec![0i32; size];
    world.all_to_all_into(&counts[..], &mut rcounts[..]);
    let rc: Vec<usize> = rcounts.iter().map(|&c| c as usize).collect();
    let mut offsets = crate::par::offsets(&rc);
    let rtotal: usize = rc.iter().sum();
    let mut data = vec![0u64; rtotal];
    {
        let sp = Partition::new(&p.buf[..], counts, to_i32(&displs));
        let mut rp = PartitionMut::new(&mut data[..], rcounts, to_i32(&offsets));
        world.all_to_all_varcount_into(&sp, &mut rp);
    }
    offsets.push(rtotal);
    Received { data, offsets }
}

/// This rank and the number of ranks.
pub(super) fn rank_size(world: &SimpleCommunicator) -> (usize, usize) {
    (world.rank() as usize, world.size() as usize)
}

/// Offsets of the ranks' blocks of `n` items each (all-gathered), with the total at the end.
pub(super) fn gathered_offsets(world: &SimpleCommunicator, n: usize) -> Vec<usize> {
    let (_, size) = rank_size(world);
    let mut counts = vec![0u64; size];
    world.all_gather_into(&(n as u64), &mut counts[..]);
    let mut offsets = vec![0usize; size + 1];
    for r in 0..size {
        offsets[r + 1] = offsets[r] + counts[r] as usize;
    }
    offsets
}

pub(super) fn counts_sum(world: &SimpleCommunicator, n: usize) -> usize {
    let mut s = 0u64;
    world.all_reduce_into(&(n as u64), &mut s, mpi::collective::SystemOperation::sum());
    s as usize
}
