//! The parallel context of a run and the few collective patterns every stage uses: agreement on
//! an error found on some ranks, all-gathers of variable length, prefix sums, small reductions.
//!
//! The rule that keeps ranks from hanging: every rank enters the same collectives in the same
//! order on every path. A check that may fail on some ranks only therefore collects its result
//! locally, lets the collectives of the stage run, and then calls [`Ctx::agree`], which gives
//! every rank the same `Err` (the lowest failing rank's message and kind).

use crate::error::{InputError, RunError};
use crate::petsc::{MPI_Comm, Petsc};
use mpi::collective::SystemOperation;
use mpi::datatype::{Equivalence, PartitionMut};
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
}

impl<'a> Ctx<'a> {
    pub fn new(world: &'a SimpleCommunicator, petsc: &'a Petsc) -> Self {
        Ctx {
            world,
            petsc,
            rank: world.rank() as usize,
            size: world.size() as usize,
        }
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
        let mut out = vec![0.0f64; local.len()];
        self.world
            .all_reduce_into(local, &mut out[..], SystemOperation::sum());
        out
    }

    /// One value per rank, on every rank.
    pub fn gather_f64(&self, v: f64) -> Vec<f64> {
        self.gather(v)
    }

    /// One value per rank, on every rank (one Allgather).
    pub fn gather<T: Equivalence + Default + Clone>(&self, v: T) -> Vec<T> {
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

    /// Every rank gets `Err` if any rank has one: the lowest failing rank's error, with its kind
    /// (input: exit code 2; anything else: exit code 1) and message. Collective.
    pub fn agree<T>(&self, local: Result<T, RunError>) -> Result<T, RunError> {
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
