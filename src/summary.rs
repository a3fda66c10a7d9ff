//! summary.json: a typed record of the run (serde), the timings of its phases, and the
//! closing log line. The solve's own section (linear or contact) comes from the stage that
//! solved, flattened in.

use crate::par::{peak_memory_bytes, Ctx};
use crate::say;
use serde::Serialize;
use std::time::Instant;

/// Timings of the phases, seconds.
#[derive(Default, Clone, Copy, Debug, Serialize)]
pub struct Timings {
    pub read: f64,
    pub partition: f64,
    pub assembly: f64,
    pub solve: f64,
    pub post: f64,
    pub output: f64,
    pub total: f64,
}

/// The phases of a run, timed one after the other.
pub struct Clock {
    start: Instant,
    lap: Instant,
    pub t: Timings,
}

impl Clock {
    pub fn start() -> Clock {
        let now = Instant::now();
        Clock {
            start: now,
            lap: now,
            t: Timings::default(),
        }
    }

    /// Seconds since the last lap (or the start), and a new lap.
    pub fn lap(&mut self) -> f64 {
        let now = Instant::now();
        let s = (now - self.lap).as_secs_f64();
        self.lap = now;
        s
    }

    /// The timings with the total so far.
    pub fn finish(&mut self) -> Timings {
        self.t.total = self.start.elapsed().as_secs_f64();
        self.t
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct PartitionInfo {
    pub cells_per_rank: Vec<usize>,
    pub nodes_per_rank: Vec<usize>,
    pub cell_imbalance: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct AssemblyInfo {
    pub mallocs: f64,
    pub matrix_seconds_max: f64,
    /// Of the matrix: element rows summed into the CSR arrays (slowest rank).
    pub rows_seconds_max: f64,
    /// Of the matrix: PETSc's assembly of the handed-over arrays (slowest rank).
    pub petsc_seconds_max: f64,
}

/// `solver.preset` as asked and as used.
#[derive(Debug, Clone, Serialize)]
pub struct PresetChoice {
    pub asked: &'static str,
    pub used: &'static str,
    pub reason: String,
}

/// What summary.json holds. `S` is the solve's own section(s), flattened in.
#[derive(Debug, Clone, Serialize)]
pub struct Summary<S: Serialize> {
    pub case: String,
    pub mesh: String,
    pub dimension: usize,
    pub model: String,
    pub cells: usize,
    pub nodes: usize,
    pub dofs: usize,
    /// `mesh.refine` (absent when 0); cells, nodes and dofs are those of the refined mesh.
    #[serde(skip_serializing_if = "is_zero")]
    pub refine: usize,
    pub ranks: usize,
    /// The BLAS kernels (OpenBLAS' kernel set, [`crate::blas::kernels`]); absent for
    /// another BLAS.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blas: Option<String>,
    /// The OpenBLAS threads of rank 0's dense phases ([`crate::blas::NodeCores`]).
    pub dense_threads: usize,
    /// `solver.dense_threads` as asked: "auto" (one per CPU of the ranks on rank 0's node, as
    /// the launcher bound them) or the fixed count.
    pub dense_threads_asked: String,
    /// The mesh's separate bodies ([`crate::bodies`]).
    pub bodies: crate::bodies::Bodies,
    /// `solver.preset` as asked and as used (the "auto" choice).
    pub preset: PresetChoice,
    pub partition: PartitionInfo,
    pub assembly: AssemblyInfo,
    pub timings: Timings,
    pub peak_memory_bytes_per_rank: Vec<f64>,
    /// Runs that succeed but look wrong (docs/warnings.md); empty for a run without any.
    pub warnings: Vec<crate::warnings::Warning>,
    #[serde(flatten)]
    pub solve: S,
}

impl<S: Serialize> Summary<S> {
    /// Pretty JSON with the keys in alphabetical order, as every reader of it expects.
    pub fn to_json(&self) -> String {
        let v = serde_json::to_value(self).expect("a summary is plain data");
        serde_json::to_string_pretty(&v).expect("JSON") + "\n"
    }
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// Peak memory of every rank (one Allgather) and the closing timing line on rank 0.
pub fn peak_memory_and_log(ctx: &Ctx, t: &Timings) -> Vec<f64> {
    let mem = ctx.gather_f64(peak_memory_bytes());
    say!(
        ctx,
        "timings [s]: read {:.3}, partition {:.3}, assembly {:.3}, solve {:.3}, post {:.3}, \
         output {:.3}, total {:.3}; peak memory per rank {:.0} MB (max)",
        t.read,
        t.partition,
        t.assembly,
        t.solve,
        t.post,
        t.output,
        t.total,
        mem.iter().fold(0.0f64, |a, &b| a.max(b)) / 1e6
    );
    mem
}

/// max / mean of per-rank counts (1 for an empty list).
pub fn imbalance(v: &[usize]) -> f64 {
    let max = *v.iter().max().unwrap_or(&0) as f64;
    let mean = v.iter().sum::<usize>() as f64 / v.len().max(1) as f64;
    if mean > 0.0 {
        max / mean
    } else {
        1.0
    }
}
