//! The partitioner under repetition: the 3D block case on 4 and 5 ranks (oversubscribed),
//! several runs each. Every run must end (a hang is caught by the time limit) with exit code 0,
//! and every run on the same rank count must give the same partition (cells per rank and the
//! rank of every cell, exactly), the same Newton history (active sets, changes, pins, Krylov
//! iterations exactly; residuals to 1e-8) and the same displacement to 1e-10 of its size.
//! (Not bit for bit: with the partition fixed, u still varies by ~1e-16 between runs because
//! MUMPS schedules its factorisation dynamically and PETSc adds the off-process contributions
//! of the assembly in the order their messages arrive.)
//!
//! Before PT-Scotch ran under a deterministic single-thread context, 4-rank runs hung or
//! crashed inside PT-Scotch now and then, and no two runs gave the same partition.
//! The full-size version is `scripts/stress-partition`.

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

/// Runs per rank count (the first one is the reference).
const RUNS: usize = 3;
/// Far above a run's duration on a busy machine (about a second); only a hang reaches it.
const LIMIT: Duration = Duration::from_secs(120);

/// What must repeat from run to run.
#[derive(Debug)]
struct Fingerprint {
    cells_per_rank: Vec<u64>,
    /// (gmsh cell tag, rank) sorted by tag.
    cell_rank: Vec<(u64, usize)>,
    /// Newton history without timings and residuals: step, active, changed, pinned, its.
    history: Vec<(u64, u64, u64, u64, u64)>,
    residuals: Vec<f64>,
    u: Vec<f64>,
}

fn case() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/blocks/block3d.toml")
}

fn run(np: usize, out: &Path) -> Fingerprint {
    let args = vec![
        case().display().to_string(),
        // the plain path: whether "auto" reuses a factorisation follows the run's timings
        "--set".into(),
        "solver.reuse=\"never\"".into(),
        "-o".into(),
        out.display().to_string(),
    ];
    let r = common::run_with_timeout(common::solver(np, &args), LIMIT);
    r.expect_code(0, &format!("block3d on {np} ranks"));

    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    let s: serde_json::Value = serde_json::from_str(&text).expect("summary.json is JSON");
    let cells_per_rank: Vec<u64> = s["partition"]["cells_per_rank"]
        .as_array()
        .expect("partition.cells_per_rank")
        .iter()
        .map(|v| v.as_u64().expect("a cell count"))
        .collect();
    let steps = s["newton"]["history"].as_array().expect("newton.history");
    let history = steps
        .iter()
        .map(|h| {
            let n = |k: &str| h[k].as_u64().unwrap_or_else(|| panic!("history {k}"));
            (
                n("step"),
                n("active"),
                n("changed"),
                n("pinned"),
                n("iterations"),
            )
        })
        .collect();
    let residuals = steps
        .iter()
        .map(|h| h["residual"].as_f64().expect("history residual"))
        .collect();

    let file = hdf5::File::open(out.join("solution.h5")).expect("solution.h5");
    let cell_id: Vec<u64> = file
        .dataset("mesh/cell_id")
        .and_then(|d| d.read_raw::<u64>())
        .expect("/mesh/cell_id");
    let u: Vec<f64> = file
        .dataset("nodal/displacement")
        .and_then(|d| d.read_raw::<f64>())
        .expect("/nodal/displacement");
    // Cells are written rank after rank.
    assert_eq!(cells_per_rank.len(), np, "one cell count per rank");
    assert_eq!(
        cells_per_rank.iter().sum::<u64>() as usize,
        cell_id.len(),
        "cells per rank add up to the cells written"
    );
    let mut cell_rank: Vec<(u64, usize)> = cells_per_rank
        .iter()
        .enumerate()
        .flat_map(|(r, &n)| std::iter::repeat_n(r, n as usize))
        .zip(&cell_id)
        .map(|(r, &c)| (c, r))
        .collect();
    cell_rank.sort_unstable();
    Fingerprint {
        cells_per_rank,
        cell_rank,
        history,
        residuals,
        u,
    }
}

/// One rank count at a time: the machine has few cores.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn repeats_on(np: usize) {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().expect("tempdir");
    let first = run(np, &dir.path().join("run0"));
    assert!(
        first.cells_per_rank.iter().all(|&n| n > 0),
        "every rank gets cells: {:?}",
        first.cells_per_rank
    );
    let max = *first.cells_per_rank.iter().max().unwrap() as f64;
    let mean = first.cells_per_rank.iter().sum::<u64>() as f64 / np as f64;
    assert!(
        max / mean < 1.1,
        "balanced partition: {:?}",
        first.cells_per_rank
    );
    for i in 1..RUNS {
        let again = run(np, &dir.path().join(format!("run{i}")));
        assert_eq!(
            again.cells_per_rank, first.cells_per_rank,
            "run {i} on {np} ranks: cells per rank differ from run 0"
        );
        let moved = again
            .cell_rank
            .iter()
            .zip(&first.cell_rank)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(
            moved, 0,
            "run {i} on {np} ranks: {moved} cells on another rank than in run 0"
        );
        assert_eq!(
            again.history, first.history,
            "run {i} on {np} ranks: Newton history differs from run 0"
        );
        let close = |a: &[f64], b: &[f64], tol: f64| {
            let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol * scale)
        };
        assert!(
            close(&again.residuals, &first.residuals, 1e-8),
            "run {i} on {np} ranks: Newton residuals differ from run 0: {:?} vs {:?}",
            again.residuals,
            first.residuals
        );
        assert!(
            close(&again.u, &first.u, 1e-10),
            "run {i} on {np} ranks: displacement differs from run 0"
        );
    }
}

#[test]
fn four_ranks_end_and_repeat() {
    repeats_on(4);
}

#[test]
fn five_ranks_end_and_repeat() {
    repeats_on(5);
}
