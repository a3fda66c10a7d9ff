//! Shared helpers of the contact_* integration tests: running the signorini-mpi binary under
//! mpirun with a time limit, reading its summary.json and contact_nodes.csv, and running
//! Debian's Python (h5py, numpy) on solution.h5.
//!
//! Every contact_* test file includes this module with `mod common_contact;` and uses part of it.
#![allow(dead_code)]

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use serde_json::Value;

/// Debian's Python (h5py and numpy installed); the `python3` on PATH may have neither.
pub const PYTHON: &str = "/usr/bin/python3";

/// Time limit of one solver run (the largest contact test run takes a few seconds).
pub const LIMIT: Duration = Duration::from_secs(180);

/// Absolute path of a file of the crate, e.g. `repo("cases/hertz/hertz.toml")`.
pub fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

// Running processes with a time limit and the MPI environment: the shared test helpers.
#[path = "../common/mod.rs"]
mod base;
#[allow(unused_imports)] // each test file uses part of it
pub use base::{python_json, run_with_timeout, Run};

/// `mpirun -n np --oversubscribe signorini-mpi CASE [--set s]... -o OUT`.
pub fn solver_command(np: usize, case: &Path, sets: &[&str], out: &Path) -> Command {
    let mut cmd = Command::new("mpirun");
    cmd.args(["-n", &np.to_string(), "--oversubscribe"])
        .arg(env!("CARGO_BIN_EXE_signorini-mpi"))
        .arg(case);
    for s in sets {
        cmd.args(["--set", s]);
    }
    cmd.arg("-o").arg(out);
    base::mpi_env(&mut cmd);
    cmd
}

/// Runs the solver; returns the process result whatever its exit code.
pub fn run_solver(np: usize, case: &Path, sets: &[&str], out: &Path) -> Run {
    run_with_timeout(solver_command(np, case, sets, out), LIMIT)
}

/// A successful solver run: its output directory, summary and log.
pub struct Solved {
    pub dir: PathBuf,
    pub summary: Value,
    pub run: Run,
    _tmp: tempfile::TempDir,
}

impl Solved {
    /// Rows of contact_nodes.csv.
    pub fn contact_rows(&self) -> Vec<Row> {
        read_csv(&self.dir.join("contact_nodes.csv"))
    }

    /// `summary[a][b]...` as f64 (panics with the path if absent or not a number).
    pub fn f(&self, path: &[&str]) -> f64 {
        get(&self.summary, path)
            .as_f64()
            .unwrap_or_else(|| panic!("summary {path:?} is not a number"))
    }

    pub fn steps(&self) -> usize {
        self.f(&["newton", "steps"]) as usize
    }

    pub fn converged(&self) -> bool {
        get(&self.summary, &["newton", "converged"]) == &Value::Bool(true)
    }

    /// contact.total_force as a vector.
    pub fn total_force(&self) -> Vec<f64> {
        get(&self.summary, &["contact", "total_force"])
            .as_array()
            .expect("total_force array")
            .iter()
            .map(|v| v.as_f64().expect("number"))
            .collect()
    }

    /// |A_n| of every Newton step.
    pub fn active_history(&self) -> Vec<usize> {
        get(&self.summary, &["newton", "history"])
            .as_array()
            .expect("history array")
            .iter()
            .map(|h| h["active"].as_u64().expect("active count") as usize)
            .collect()
    }
}

/// `v[a][b]...`; panics with the path if absent.
pub fn get<'a>(v: &'a Value, path: &[&str]) -> &'a Value {
    let mut cur = v;
    for k in path {
        cur = cur
            .get(*k)
            .unwrap_or_else(|| panic!("summary has no {path:?} (missing {k:?})"));
    }
    cur
}

/// Runs the solver into a fresh temporary directory; panics unless it exits with 0 and writes
/// a summary.
pub fn solve(np: usize, case: &Path, sets: &[&str]) -> Solved {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("out");
    let run = run_solver(np, case, sets, &dir);
    solved(run, tmp, dir)
}

/// The [`Solved`] of a finished run that wrote into `dir` (inside `tmp`); panics unless it
/// exited with 0 and wrote a summary.
pub fn solved(run: Run, tmp: tempfile::TempDir, dir: PathBuf) -> Solved {
    assert_eq!(run.code, Some(0), "solver failed:\n{}", run.output());
    let text = std::fs::read_to_string(dir.join("summary.json"))
        .unwrap_or_else(|e| panic!("no summary.json ({e}):\n{}", run.output()));
    let summary: Value = serde_json::from_str(&text).expect("summary.json is JSON");
    Solved {
        dir,
        summary,
        run,
        _tmp: tmp,
    }
}

/// One row of a CSV file, by column name.
#[derive(Debug, Clone)]
pub struct Row(pub HashMap<String, String>);

impl Row {
    pub fn s(&self, key: &str) -> &str {
        self.0
            .get(key)
            .unwrap_or_else(|| panic!("CSV has no column {key:?}"))
    }

    pub fn f(&self, key: &str) -> f64 {
        let s = self.s(key);
        s.parse()
            .unwrap_or_else(|e| panic!("CSV {key} = {s:?} is not a number: {e}"))
    }

    pub fn active(&self) -> bool {
        match self.s("state") {
            "active" => true,
            "inactive" => false,
            other => panic!("unknown contact state {other:?}"),
        }
    }

    pub fn node_id(&self) -> u64 {
        self.s("node_id").parse().expect("node_id")
    }
}

/// Reads a header + rows CSV file without quoting.
pub fn read_csv(path: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .expect("CSV header")
        .split(',')
        .map(|s| s.trim().to_string())
        .collect();
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(
                cells.len(),
                header.len(),
                "CSV row {l:?} vs header {header:?}"
            );
            Row(header
                .iter()
                .cloned()
                .zip(cells.iter().map(|c| c.trim().to_string()))
                .collect())
        })
        .collect()
}

/// Relative difference |a − b| / |b|.
pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}
