//! Shared helpers of the tresca_* integration tests: running the signorini-mpi binary under
//! mpirun with a time limit, reading summary.json, contact_nodes.csv and (through Debian's
//! Python with h5py) solution.h5, and comparing fields node by node.
//!
//! Every tresca_* test file includes this module with `mod tresca_common;` and uses part of it.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use serde_json::Value;

/// Debian's Python (h5py and numpy installed); the `python3` on PATH may have neither.
pub const PYTHON: &str = "/usr/bin/python3";

/// Time limit of one solver run (the largest run here takes a few seconds).
pub const LIMIT: Duration = Duration::from_secs(180);

/// Absolute path of a file of the crate, e.g. `repo("tests/cases/tresca/hertz_tresca.toml")`.
pub fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// A test case of tests/cases/tresca.
pub fn case(name: &str) -> PathBuf {
    repo(&format!("tests/cases/tresca/{name}"))
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

/// A successful solver run: its output directory, summary and log.
pub struct Solved {
    pub dir: PathBuf,
    pub summary: Value,
    pub run: Run,
    _tmp: tempfile::TempDir,
}

/// Runs the solver into a fresh temporary directory; panics unless it exits with 0 and writes
/// a summary.
pub fn solve(np: usize, case: &Path, sets: &[&str]) -> Solved {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("out");
    let run = run_with_timeout(solver_command(np, case, sets, &dir), LIMIT);
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

impl Solved {
    /// `summary[a][b]...` as f64.
    pub fn f(&self, path: &[&str]) -> f64 {
        get(&self.summary, path)
            .as_f64()
            .unwrap_or_else(|| panic!("summary {path:?} is not a number: {}", self.run.output()))
    }

    pub fn steps(&self) -> usize {
        self.f(&["newton", "steps"]) as usize
    }

    pub fn converged(&self) -> bool {
        get(&self.summary, &["newton", "converged"]) == &Value::Bool(true)
    }

    /// Panics (with the log) unless Newton converged.
    pub fn assert_converged(&self, what: &str) {
        assert!(
            self.converged(),
            "{what}: Newton did not converge\n{}",
            self.run.output()
        );
    }

    /// contact.total_force = Σ_k (−λ^k), global coordinates.
    pub fn total_force(&self) -> Vec<f64> {
        floats(get(&self.summary, &["contact", "total_force"]))
    }

    /// [S1, S2, S3, S4] of every Newton step.
    pub fn state_history(&self) -> Vec<[usize; 4]> {
        get(&self.summary, &["newton", "history"])
            .as_array()
            .expect("history array")
            .iter()
            .map(|h| {
                let s = h["states"]
                    .as_array()
                    .unwrap_or_else(|| panic!("history entry without states: {h}"));
                assert_eq!(s.len(), 4, "states {s:?}");
                [0, 1, 2, 3].map(|i| s[i].as_u64().expect("state count") as usize)
            })
            .collect()
    }

    /// Rows of contact_nodes.csv, by node id.
    pub fn contact_rows(&self) -> BTreeMap<u64, Row> {
        read_csv(&self.dir.join("contact_nodes.csv"))
            .into_iter()
            .map(|r| (r.node_id(), r))
            .collect()
    }

    /// Nodal displacement from solution.h5, by node id (always 3 components).
    pub fn displacement(&self) -> BTreeMap<u64, Vec<f64>> {
        let v = python_json(
            r#"
import sys, json, h5py
f = h5py.File(sys.argv[1], "r")
ids = f["mesh/node_id"][:].tolist()
u = f["nodal/displacement"][:].tolist()
print("RESULT " + json.dumps({"ids": ids, "u": u}))
"#,
            &[&self.dir.join("solution.h5")],
        );
        let ids = v["ids"].as_array().expect("ids");
        let u = v["u"].as_array().expect("u");
        assert_eq!(ids.len(), u.len());
        ids.iter()
            .zip(u)
            .map(|(i, row)| (i.as_u64().expect("node id"), floats(row)))
            .collect()
    }
}

/// A JSON array of numbers as a vector.
pub fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("{v} is not an array"))
        .iter()
        .map(|x| x.as_f64().unwrap_or_else(|| panic!("{x} is not a number")))
        .collect()
}

/// One row of a CSV file, by column name.
#[derive(Debug, Clone)]
pub struct Row(pub BTreeMap<String, String>);

impl Row {
    pub fn s(&self, key: &str) -> &str {
        self.0
            .get(key)
            .unwrap_or_else(|| panic!("CSV has no column {key:?}: {:?}", self.0))
    }

    pub fn f(&self, key: &str) -> f64 {
        let s = self.s(key);
        s.parse()
            .unwrap_or_else(|e| panic!("CSV {key} = {s:?} is not a number: {e}"))
    }

    pub fn node_id(&self) -> u64 {
        self.s("node_id").parse().expect("node_id")
    }

    pub fn active(&self) -> bool {
        match self.s("state") {
            "active" => true,
            "inactive" => false,
            other => panic!("unknown contact state {other:?}"),
        }
    }

    /// "stick", "slip" or "-".
    pub fn tangential(&self) -> &str {
        self.s("tangential")
    }

    /// (u_t1[, u_t2]) of a CSV with `dim` spatial columns.
    pub fn u_t(&self, dim: usize) -> Vec<f64> {
        (1..dim).map(|i| self.f(&format!("u_t{i}"))).collect()
    }

    /// (λ_t1[, λ_t2]).
    pub fn lambda_t(&self, dim: usize) -> Vec<f64> {
        (1..dim).map(|i| self.f(&format!("lambda_t{i}"))).collect()
    }

    pub fn bound(&self) -> f64 {
        self.f("bound")
    }
}

/// Spatial dimension of a contact_nodes.csv (2 without a z column).
pub fn csv_dim(rows: &BTreeMap<u64, Row>) -> usize {
    let r = rows.values().next().expect("contact rows");
    if r.0.contains_key("z") {
        3
    } else {
        2
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
            assert_eq!(cells.len(), header.len(), "CSV row {l:?} vs {header:?}");
            Row(header
                .iter()
                .cloned()
                .zip(cells.iter().map(|c| c.trim().to_string()))
                .collect())
        })
        .collect()
}

/// Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// max_k |a_k − b_k| over the common node ids (both maps must hold the same ids) and
/// max_k |b_k|, i.e. (absolute difference, scale).
pub fn max_diff(a: &BTreeMap<u64, Vec<f64>>, b: &BTreeMap<u64, Vec<f64>>) -> (f64, f64) {
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "the two runs have different node ids"
    );
    let mut diff = 0.0f64;
    let mut scale = 0.0f64;
    for (k, va) in a {
        let vb = &b[k];
        assert_eq!(va.len(), vb.len());
        for (x, y) in va.iter().zip(vb) {
            diff = diff.max((x - y).abs());
            scale = scale.max(y.abs());
        }
    }
    (diff, scale)
}

/// Selected numeric CSV columns of each contact node, by node id.
pub fn columns(rows: &BTreeMap<u64, Row>, keys: &[&str]) -> BTreeMap<u64, Vec<f64>> {
    rows.iter()
        .map(|(k, r)| (*k, keys.iter().map(|c| r.f(c)).collect()))
        .collect()
}

/// Contact force −λ^k in global coordinates (solution.h5 /contact/contact_force), by node id.
pub fn contact_forces(s: &Solved, dim: usize) -> BTreeMap<u64, Vec<f64>> {
    let v = python_json(
        r#"
import sys, json, h5py
f = h5py.File(sys.argv[1], "r")
print("RESULT " + json.dumps({"ids": f["contact/node_id"][:].tolist(),
                              "force": f["contact/contact_force"][:].tolist()}))
"#,
        &[&s.dir.join("solution.h5")],
    );
    let ids = v["ids"].as_array().expect("ids");
    let force = v["force"].as_array().expect("force");
    ids.iter()
        .zip(force)
        .map(|(i, f)| (i.as_u64().expect("id"), floats(f)[..dim].to_vec()))
        .collect()
}
