//! The parallel context of a run and the few collective patterns every stage uses: agreement on
//! an error found on some ranks, all-gathers of variable length, prefix sums, small reductions.
//!
//! The rule that keeps ranks from hanging: every rank enters the same collectives in the same
//! order on every path. A check that may fail on some ranks only therefore collects its result
//! locally, lets the collectives of the stage run, and then calls [`Ctx::agree`], which gives
//! every rank the same `Err` (the lowest failing rank's message and kind). A failure that no
//! agreement covers ends every rank at this rank's next collective ([`crate::abort`]).

use crate::error::{InputError, RunError};
use crate::petsc::{self, MPI_Comm, PInt, Petsc, Vector};
use mpi::collective::SystemOperation;
use mpi::datatype::{Equivalence, Partition, PartitionMut};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use serde_json::{json, Value};

/// Rank-0 log line. Its arguments are evaluated on rank 0 only: never put a collective call in them.
#[macro_export]
macro_rules! say {
    ($ctx:expr, $($arg:tt)*) => {
        if $ctx.rank == 0 {
            println!($($arg)*);
        }
    };
}

/// The parallel context of a run.
pub struct Ctx<'a> {
    pub world: &'a SimpleCommunicator,
    pub petsc: &'a Petsc,
    pub rank: usize,
    pub size: usize,
    /// The cores rank 0's dense work may use ([`Ctx::on_root_wide`]).
    pub cores: crate::blas::NodeCores,
}

impl<'a> Ctx<'a> {
    /// Collective (the CPUs of rank 0's node, [`crate::blas::NodeCores::of_root_node`]).
    pub fn new(world: &'a SimpleCommunicator, petsc: &'a Petsc) -> Self {
        Ctx {
            world,
            petsc,
            rank: world.rank() as usize,
            size: world.size() as usize,
            cores: crate::blas::NodeCores::of_root_node(world),
        }
    }

    /// This context with the case's `solver.dense_threads` for rank 0's dense phases. Local.
    pub fn with_dense_threads(&self, threads: crate::case::DenseThreads) -> Ctx<'a> {
        Ctx {
            cores: self.cores.with(threads),
            ..*self
        }
    }

    /// `work` on rank 0 alone (`Some` there, `None` elsewhere), for rank 0's dense phases
    /// whose result a broadcast then shares; `dim`: the largest dimension of its dense
    /// matrices. From [`crate::tuning::WIDE_MIN_DIM`] on, rank 0's BLAS threads get the cores of
    /// the ranks beside it ([`crate::blas::NodeCores`]), and the other ranks wait in a barrier
    /// that they test and sleep on instead of spinning. Collective.
    pub fn on_root_wide<T>(&self, dim: usize, work: impl FnOnce() -> T) -> Option<T> {
        let out = (self.rank == 0).then(|| self.cores.run(dim, work));
        if self.size > 1 && dim >= crate::tuning::WIDE_MIN_DIM {
            crate::abort::before_collective();
            let mut req = self.world.immediate_barrier();
            if self.rank == 0 {
                req.wait();
            } else {
                // about 0.1 ms late at most after rank 0 ends, against dense phases of
                // milliseconds to seconds
                loop {
                    match req.test() {
                        Ok(_) => break,
                        Err(r) => req = r,
                    }
                    std::thread::sleep(std::time::Duration::from_micros(100));
                }
            }
        }
        out
    }

    /// PETSc's communicator (the same as `world`).
    pub fn comm(&self) -> MPI_Comm {
        self.petsc.comm()
    }

    /// True on every rank if it is true on any rank (one Allreduce).
    pub fn any(&self, flag: bool) -> bool {
        self.reduce(flag as i32, SystemOperation::max()) != 0
    }

    /// One value reduced over all ranks by `op` (one Allreduce).
    fn reduce<T: Equivalence + Default>(&self, v: T, op: SystemOperation) -> T {
        crate::abort::before_collective();
        let mut out = T::default();
        self.world.all_reduce_into(&v, &mut out, op);
        out
    }

    pub fn sum_f64(&self, v: f64) -> f64 {
        self.reduce(v, SystemOperation::sum())
    }

    pub fn max_f64(&self, v: f64) -> f64 {
        self.reduce(v, SystemOperation::max())
    }

    pub fn min_f64(&self, v: f64) -> f64 {
        self.reduce(v, SystemOperation::min())
    }

    pub fn min_u64(&self, v: u64) -> u64 {
        self.reduce(v, SystemOperation::min())
    }

    pub fn sum_usize(&self, v: usize) -> usize {
        self.reduce(v as u64, SystemOperation::sum()) as usize
    }

    /// Element-wise sum over ranks of a packed vector (one Allreduce).
    pub fn sum_vec(&self, local: &[f64]) -> Vec<f64> {
        crate::abort::before_collective();
        let mut out = vec![0.0f64; local.len()];
        self.world
            .all_reduce_into(local, &mut out[..], SystemOperation::sum());
        out
    }

    /// One value per rank, on every rank.
    /// The fields (this rank's rows of distributed vectors) made orthonormal by Gram–Schmidt
    /// twice against those before, with global dot products; a field that vanishes against
    /// them is dropped. Collective.
    pub fn orthonormalised(&self, fields: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
        let mut done: Vec<Vec<f64>> = Vec::new();
        for mut f in fields {
            for _ in 0..2 {
                let dots: Vec<f64> = done
                    .iter()
                    .map(|g| g.iter().zip(&f).map(|(a, b)| a * b).sum())
                    .collect();
                let dots = self.sum_vec(&dots);
                for (g, d) in done.iter().zip(&dots) {
                    f.iter_mut().zip(g).for_each(|(x, y)| *x -= d * y);
                }
            }
            let norm = self.sum_f64(f.iter().map(|x| x * x).sum::<f64>()).sqrt();
            if norm == 0.0 {
                continue;
            }
            f.iter_mut().for_each(|x| *x /= norm);
            done.push(f);
        }
        done
    }

    pub fn gather_f64(&self, v: f64) -> Vec<f64> {
        self.gather(v)
    }

    /// One value per rank, on every rank (one Allgather).
    pub fn gather<T: Equivalence + Default + Clone>(&self, v: T) -> Vec<T> {
        crate::abort::before_collective();
        let mut out = vec![T::default(); self.size];
        self.world.all_gather_into(&v, &mut out[..]);
        out
    }

    /// The concatenation of every rank's slice, in rank order, on every rank.
    pub fn all_gather_varcount<T: Equivalence + Default + Clone>(&self, mine: &[T]) -> Vec<T> {
        let counts: Vec<i32> = self.gather(mine.len() as i32);
        let displs: Vec<i32> = offsets(&counts.iter().map(|&c| c as usize).collect::<Vec<_>>())
            .iter()
            .map(|&d| d as i32)
            .collect();
        let total = counts.iter().map(|&c| c as usize).sum::<usize>();
        let mut all = vec![T::default(); total];
        {
            let mut part = PartitionMut::new(&mut all[..], counts, displs);
            self.world.all_gather_varcount_into(mine, &mut part);
        }
        all
    }

    /// Every rank's count `n` gathered on rank 0, with the offsets: `Some((counts,
    /// displacements))` there, `None` elsewhere (one Gather). Collective.
    fn counts_at_root(&self, n: usize) -> Option<(Vec<i32>, Vec<i32>)> {
        crate::abort::before_collective();
        let root = self.world.process_at_rank(0);
        let n = n as i32;
        if self.rank != 0 {
            root.gather_into(&n);
            return None;
        }
        let mut counts = vec![0i32; self.size];
        root.gather_into_root(&n, &mut counts[..]);
        let displs = offsets(&counts.iter().map(|&c| c as usize).collect::<Vec<_>>())
            .iter()
            .map(|&d| d as i32)
            .collect();
        Some((counts, displs))
    }

    /// The concatenation of every rank's slice, in rank order, on rank 0 (empty elsewhere;
    /// one Gather of the counts, one Gatherv). Collective.
    pub fn gather_to_root<T: Equivalence + Default + Clone>(&self, mine: &[T]) -> Vec<T> {
        let root = self.world.process_at_rank(0);
        let Some((counts, displs)) = self.counts_at_root(mine.len()) else {
            root.gather_varcount_into(mine);
            return Vec::new();
        };
        let mut all = vec![T::default(); counts.iter().map(|&c| c as usize).sum()];
        {
            let mut part = PartitionMut::new(&mut all[..], counts, displs);
            root.gather_varcount_into_root(mine, &mut part);
        }
        all
    }

    /// The inverse of [`Ctx::gather_to_root`]: rank 0's vector cut into consecutive pieces
    /// of `mine` entries each (every rank's own count). Collective.
    pub fn scatter_from_root(&self, all: &[f64], mine: usize) -> Vec<f64> {
        let root = self.world.process_at_rank(0);
        let mut out = vec![0.0; mine];
        let Some((counts, displs)) = self.counts_at_root(mine) else {
            root.scatter_varcount_into(&mut out[..]);
            return out;
        };
        let part = Partition::new(all, counts, displs);
        root.scatter_varcount_into_root(&part, &mut out[..]);
        out
    }

    /// Rank 0's vector on every rank (two broadcasts: the length, the values). Collective.
    pub fn broadcast_f64s(&self, v: &mut Vec<f64>) {
        crate::abort::before_collective();
        let root = self.world.process_at_rank(0);
        let mut len = v.len() as u64;
        root.broadcast_into(&mut len);
        v.resize(len as usize, 0.0);
        root.broadcast_into(&mut v[..]);
    }

    /// Rank 0's path on every rank (its bytes, as they are). Collective.
    pub fn broadcast_path(&self, p: &mut std::path::PathBuf) {
        use std::os::unix::ffi::{OsStrExt, OsStringExt};
        crate::abort::before_collective();
        let root = self.world.process_at_rank(0);
        let mut bytes = p.as_os_str().as_bytes().to_vec();
        let mut len = bytes.len() as u64;
        root.broadcast_into(&mut len);
        bytes.resize(len as usize, 0);
        root.broadcast_into(&mut bytes[..]);
        *p = std::ffi::OsString::from_vec(bytes).into();
    }

    /// Every rank gets `Err` (the lowest failing rank's message) if any rank has one: the
    /// agreement that must come before a local failure turns into a fallback. Collective.
    pub fn agree_message<T, E: std::fmt::Display>(&self, local: Result<T, E>) -> Result<T, String> {
        let mine = local.as_ref().err().map(|e| e.to_string());
        match first_error(self.world, mine) {
            None => local.map_err(|e| e.to_string()),
            Some((_, text)) => Err(text),
        }
    }

    /// [`Ctx::agree`] after rank 0's irreversible last step (the results put in place): shares
    /// rank 0's outcome; no fault is injected here (nothing else can fail on a rank at this
    /// point). Collective.
    pub fn agree_after_commit(&self, local: Result<(), RunError>) -> Result<(), RunError> {
        self.agree_counted(local, false)
    }

    /// Every rank gets `Err` if any rank has one: the lowest failing rank's error, with its kind
    /// (input: exit code 2; anything else: exit code 1) and message. Collective.
    pub fn agree<T>(&self, local: Result<T, RunError>) -> Result<T, RunError> {
        self.agree_counted(local, true)
    }

    /// [`Ctx::agree`] on the error of smallest `key` over all ranks (the Gmsh tag of the node
    /// or element it names): each rank checks its own part of the mesh, and the message must
    /// not depend on how the mesh is partitioned. Collective.
    pub fn agree_smallest(&self, local: Option<(u64, RunError)>) -> Result<(), RunError> {
        let smallest = self.min_u64(local.as_ref().map_or(u64::MAX, |l| l.0));
        self.agree(match local {
            Some((key, e)) if key == smallest => Err(e),
            _ => Ok(()),
        })
    }

    /// [`Ctx::agree`]; `inject`: a test-only fault may strike here (`crate::fault`).
    fn agree_counted<T>(&self, local: Result<T, RunError>, inject: bool) -> Result<T, RunError> {
        let fault = if inject {
            crate::fault::counted("agree", || self.rank)
        } else {
            None
        };
        let local = match fault {
            None => local,
            Some((m, crate::fault::Kind::Panic)) => panic!("{m}"),
            Some((m, crate::fault::Kind::Error)) => Err(RunError::Failed(m)),
            Some((m, crate::fault::Kind::Petsc)) => Err(petsc::raised_error(m).into()),
        };
        let mine = match &local {
            Ok(_) => None,
            Err(e) => Some(encode(e)),
        };
        match first_error(self.world, mine) {
            None => local,
            // The failing rank keeps its own error value; the others rebuild it.
            Some((first, _)) if first == self.rank => local,
            Some((_, text)) => Err(decode(&text)),
        }
    }
}

/// The lowest failing rank and its message, on every rank; `None` if no rank failed.
/// Collective over `comm`: every rank must call it, with `Some` where it failed.
pub fn first_error<C: Communicator>(comm: &C, local: Option<String>) -> Option<(usize, String)> {
    let size = comm.size();
    let mine = if local.is_some() { comm.rank() } else { size };
    let mut first = size;
    comm.all_reduce_into(&mine, &mut first, SystemOperation::min());
    // every rank now knows whether one failed: nothing of this rank's is pending alone
    crate::abort::covered();
    if first == size {
        return None;
    }
    let text = broadcast_string(comm, first, local.as_deref().unwrap_or_default());
    Some((first as usize, text))
}

/// `s` of rank `root`, on every rank. Collective.
pub fn broadcast_string<C: Communicator>(comm: &C, root: i32, s: &str) -> String {
    let root = comm.process_at_rank(root);
    let mut bytes = s.as_bytes().to_vec();
    let mut len = bytes.len() as u64;
    root.broadcast_into(&mut len);
    bytes.resize(len as usize, 0);
    root.broadcast_into(&mut bytes[..]);
    String::from_utf8_lossy(&bytes).into_owned()
}

fn encode(e: &RunError) -> String {
    let v = match e {
        RunError::Input(i) => json!({
            "kind": "input",
            "file": i.file.to_string_lossy(),
            "line": i.line,
            "key": i.key,
            "message": i.message,
        }),
        other => json!({ "kind": "failed", "message": other.to_string() }),
    };
    v.to_string()
}

fn decode(text: &str) -> RunError {
    let v: Value = serde_json::from_str(text).unwrap_or(Value::Null);
    let s = |k: &str| v[k].as_str().map(str::to_string);
    let message = s("message").unwrap_or_else(|| text.to_string());
    if v["kind"] == "input" {
        let mut e = InputError::new(
            std::path::Path::new(&s("file").unwrap_or_default()),
            message,
        )
        .with_line(v["line"].as_u64().map(|l| l as usize));
        e.key = s("key");
        RunError::Input(e)
    } else {
        RunError::Failed(message)
    }
}

/// Adds `vals` at the global rows `idx` of the distributed vector `v` (negative rows are
/// skipped) in an order that does not depend on message arrival: the entries owned elsewhere
/// travel in one all-to-all-v; every rank adds its own entries in the order given, then the
/// other ranks' entries in rank order. Replaces `set_values(.., add)` + `assemble`, whose
/// VecAssembly adds received entries in the order the messages arrive — a run-to-run
/// round-off difference where a row gets entries from two or more other ranks. On one rank
/// the same additions in the same order as `set_values`. Collective over MPI_COMM_WORLD
/// (PETSc's communicator).
pub fn add_in_rank_order(v: &mut Vector, idx: &[PInt], vals: &[f64]) -> petsc::Result<()> {
    let world = SimpleCommunicator::world();
    let (rank, size) = (world.rank() as usize, world.size() as usize);
    let (lo, hi) = v.ownership_range()?;
    let mut starts = vec![0u64; size];
    world.all_gather_into(&(lo as u64), &mut starts[..]);
    let owner = |i: usize| starts.partition_point(|&s| s as usize <= i) - 1;
    let rows = || {
        idx.iter()
            .zip(vals)
            .filter(|(&i, _)| i >= 0)
            .map(|(&i, &x)| (i as usize, x))
    };
    let mut counts = vec![0usize; size];
    for (i, _) in rows().filter(|&(i, _)| !(lo..hi).contains(&i)) {
        counts[owner(i)] += 2;
    }
    let displs = offsets(&counts);
    let mut fill = displs.clone();
    let mut send = vec![0u64; counts.iter().sum()];
    for (i, x) in rows().filter(|&(i, _)| !(lo..hi).contains(&i)) {
        let r = owner(i);
        send[fill[r]] = i as u64;
        send[fill[r] + 1] = x.to_bits();
        fill[r] += 2;
    }
    let to_i32 = |c: &[usize]| c.iter().map(|&c| c as i32).collect::<Vec<i32>>();
    let counts = to_i32(&counts);
    let mut rcounts = vec![0i32; size];
    world.all_to_all_into(&counts[..], &mut rcounts[..]);
    let rc: Vec<usize> = rcounts.iter().map(|&c| c as usize).collect();
    let rdispls = offsets(&rc);
    let mut recv = vec![0u64; rc.iter().sum()];
    {
        let sp = Partition::new(&send[..], counts, to_i32(&displs));
        let mut rp = PartitionMut::new(&mut recv[..], rcounts, to_i32(&rdispls));
        world.all_to_all_varcount_into(&sp, &mut rp);
    }
    debug_assert!(rc[rank] == 0);
    v.write(|x| {
        for (i, val) in rows().filter(|&(i, _)| (lo..hi).contains(&i)) {
            x[i - lo] += val;
        }
        for p in recv.chunks_exact(2) {
            x[p[0] as usize - lo] += f64::from_bits(p[1]);
        }
    })
}

/// The number of ranks of MPI_COMM_WORLD (PETSc's communicator).
pub fn world_size() -> usize {
    SimpleCommunicator::world().size() as usize
}

/// Prefix sums: `offsets(&[2, 3, 1]) = [0, 2, 5]` (the first index of every block).
pub fn offsets(counts: &[usize]) -> Vec<usize> {
    counts
        .iter()
        .scan(0usize, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect()
}

/// Peak resident memory of this process in bytes (VmHWM), 0 if unknown.
pub fn peak_memory_bytes() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<f64>().ok())
        })
        .map(|kb| kb * 1024.0)
        .unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn offsets_are_prefix_sums() {
        assert_eq!(offsets(&[2, 3, 1]), vec![0, 2, 5]);
        assert!(offsets(&[]).is_empty());
    }

    #[test]
    fn errors_travel_with_their_kind() {
        let e = InputError::new(Path::new("a/b.toml"), "bad value")
            .with_key("contact.obstacle")
            .with_line(Some(7));
        let back = decode(&encode(&RunError::Input(e.clone())));
        match back {
            RunError::Input(b) => assert_eq!(b, e),
            other => panic!("kind lost: {other:?}"),
        }
        let back = decode(&encode(&RunError::Failed("no support".into())));
        assert!(matches!(back, RunError::Failed(ref s) if s == "no support"));
        assert_eq!(back.exit_code(), 1);
    }
}
