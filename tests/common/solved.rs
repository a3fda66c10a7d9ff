//! One solver run on a case file (`mpirun -n np signorini-mpi CASE --set ... -o OUT`) and what
//! it wrote: summary.json, contact_nodes.csv and (through Debian's Python with h5py)
//! solution.h5.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use serde_json::Value;

use super::compare::floats;
use super::csv::{by_node_id, read_csv, Row};
use super::process::{
    binary, mpirun, python_json, repo, run_with_timeout, toml_path, write_case, Run,
};

/// Time limit of one solver run (the largest test run takes a few seconds).
pub const LIMIT: Duration = Duration::from_secs(180);

/// A test case of tests/cases/tresca.
pub fn case(name: &str) -> PathBuf {
    repo(&format!("tests/cases/tresca/{name}"))
}

/// `mpirun -n np --oversubscribe signorini-mpi CASE [--set s]... -o OUT`.
pub fn solver_command(np: usize, case: &Path, sets: &[&str], out: &Path) -> Command {
    let mut args = vec![case.display().to_string()];
    for s in sets {
        args.push("--set".into());
        args.push(s.to_string());
    }
    args.push("-o".into());
    args.push(out.display().to_string());
    mpirun(np, &binary(), &args)
}

/// The Hertz disk (refined level 4) held at its top arc by Dirichlet data — pushed down by 0.01
/// and sideways by 0.001, the Cattaneo setting — on a rigid plane, Coulomb with μ = 0.3, the
/// direct preset; `extra` TOML tables appended before `[output]`. Returns the case file in
/// `dir`.
pub fn held_disk(dir: &Path, extra: &str) -> PathBuf {
    let mesh = repo("cases/hertz/meshes/hertz_refined_L4.msh");
    write_case(
        &dir.join("held.toml"),
        &format!(
            "[mesh]\nfile = {}\n[material]\nyoung = 2.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\
             [[dirichlet]]\ngroup = \"load\"\nvalue = [0.001, -0.01]\n[contact]\n\
             group = \"contact\"\nobstacle = {{ type = \"plane\", point = [0.0, -1.0], \
             normal = [0.0, 1.0] }}\nfriction = {{ law = \"coulomb\", mu = 0.3 }}\n\
             [solver]\npreset = \"direct\"\n{extra}[output]\nfields = [\"displacement\", \"contact\"]\n",
            toml_path(&mesh)
        ),
    )
}

/// Runs the solver; returns the process result whatever its exit code.
pub fn run_solver(np: usize, case: &Path, sets: &[&str], out: &Path) -> Run {
    run_with_timeout(solver_command(np, case, sets, out), LIMIT)
}

/// Runs the solver into a fresh temporary directory; panics unless it exits with 0 and writes
/// a summary.
pub fn solve(np: usize, case: &Path, sets: &[&str]) -> Solved {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("out");
    let run = run_solver(np, case, sets, &dir);
    solved(run, tmp, dir)
}

/// [`solve`] with `env` added to the solver's environment (test-only limits) and the time
/// limit `limit`.
pub fn solve_env(
    np: usize,
    case: &Path,
    sets: &[&str],
    env: &[(&str, &str)],
    limit: Duration,
) -> Solved {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("out");
    let mut cmd = solver_command(np, case, sets, &dir);
    for (k, v) in env {
        cmd.env(k, v);
    }
    solved(run_with_timeout(cmd, limit), tmp, dir)
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

/// A successful solver run: its output directory, summary and log.
pub struct Solved {
    pub dir: PathBuf,
    pub summary: Value,
    pub run: Run,
    _tmp: tempfile::TempDir,
}

impl Solved {
    /// The load steps that took the previous step's factorisation (the log's line for each).
    pub fn kept_factorisations(&self) -> usize {
        self.run
            .stdout
            .matches("the previous load step's factorisation and compliance")
            .count()
    }

    /// max |u_self − u_other| / max |u_self| over all nodes (by node id); u = 0 is a failure
    /// (nothing would be tested).
    pub fn u_rel_diff(&self, other: &Solved) -> f64 {
        let (ua, ub) = (self.displacement(), other.displacement());
        assert_eq!(ua.len(), ub.len());
        let scale = ua.values().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(scale > 0.0, "u = 0: nothing tested");
        let (diff, _) = super::compare::max_diff(&ua, &ub);
        diff / scale
    }

    /// Asserts that this run ends on `reference`'s active nodes with u within `tol` of
    /// max |u| (`what` names the run in the messages).
    pub fn assert_same_answer(&self, reference: &Solved, tol: f64, what: &str) {
        assert_eq!(
            reference.active_node_ids(),
            self.active_node_ids(),
            "{what}: final active sets differ"
        );
        let d = reference.u_rel_diff(self);
        assert!(d <= tol, "{what}: |u - u_reference| / max|u| = {d:e}");
    }

    /// Node ids of the active contact nodes (contact_nodes.csv), ascending.
    pub fn active_node_ids(&self) -> Vec<u64> {
        self.contact_rows_by_id()
            .iter()
            .filter(|(_, r)| r.active())
            .map(|(id, _)| *id)
            .collect()
    }

    /// `summary[a][b]...` as f64 (panics with the path and the log if absent or not a number).
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

    /// |A_n| of every Newton step.
    pub fn active_history(&self) -> Vec<usize> {
        get(&self.summary, &["newton", "history"])
            .as_array()
            .expect("history array")
            .iter()
            .map(|h| h["active"].as_u64().expect("active count") as usize)
            .collect()
    }

    /// [S1, S2, S3, S4] of the final state, counted node by node from contact_nodes.csv (a
    /// path's history need not have per-step counts: the condensed path's dense steps have
    /// none).
    pub fn final_states(&self) -> [usize; 4] {
        let mut states = [0; 4];
        for r in self.contact_rows_by_id().values() {
            let slip = r.tangential() == "slip";
            states[2 * usize::from(r.active()) + usize::from(slip)] += 1;
        }
        states
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

    /// Rows of contact_nodes.csv, in file order.
    pub fn contact_rows(&self) -> Vec<Row> {
        read_csv(&self.dir.join("contact_nodes.csv"))
    }

    /// Rows of contact_nodes.csv, by node id.
    /// The ids of the active contact nodes that slip (contact_nodes.csv), ascending.
    pub fn slip_node_ids(&self) -> Vec<u64> {
        self.contact_rows_by_id()
            .iter()
            .filter(|(_, r)| r.active() && r.tangential() == "slip")
            .map(|(id, _)| *id)
            .collect()
    }

    pub fn contact_rows_by_id(&self) -> BTreeMap<u64, Row> {
        by_node_id(self.contact_rows())
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

/// Contact force −λ^k in global coordinates (solution.h5 /contact/contact_force), by
/// node id, the first `dim` components; the contact nodes only (the surface's nodes held by
/// Dirichlet data, state −1, have none).
pub fn contact_forces(s: &Solved, dim: usize) -> BTreeMap<u64, Vec<f64>> {
    let v = python_json(
        r#"
import sys, json, h5py
f = h5py.File(sys.argv[1], "r")
keep = f["contact/state"][:] != -1
print("RESULT " + json.dumps({"ids": f["contact/node_id"][:][keep].tolist(),
                          "force": f["contact/contact_force"][:][keep].tolist()}))
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

/// The displacement of load step `step` (from 1) by node id, from `dir`/solution.h5.
pub fn step_displacement(dir: &Path, step: usize) -> BTreeMap<u64, Vec<f64>> {
    let v = python_json(
        r#"
import sys, json, h5py
f = h5py.File(sys.argv[1], "r")
ids = f["mesh/node_id"][:].tolist()
u = f["step_" + sys.argv[2] + "/nodal/displacement"][:].tolist()
print("RESULT " + json.dumps({"ids": ids, "u": u}))
"#,
        &[&dir.join("solution.h5"), Path::new(&step.to_string())],
    );
    let (ids, u) = (v["ids"].as_array().unwrap(), v["u"].as_array().unwrap());
    ids.iter()
        .zip(u)
        .map(|(i, row)| (i.as_u64().unwrap(), floats(row)))
        .collect()
}

/// A load history `c` on `np` ranks ends where `reference` ends, step by step: u within
/// `tol` of max |u| at each of the `steps` load steps, and the same final active nodes.
pub fn same_steps(c: &Solved, reference: &Solved, steps: usize, tol: f64, np: usize) {
    for step in 1..=steps {
        let (du, su) = super::compare::max_diff(
            &step_displacement(&c.dir, step),
            &step_displacement(&reference.dir, step),
        );
        assert!(
            du <= tol * su,
            "{np} rank(s), step {step}: |Δu| {du:e} of {su:e}"
        );
    }
    assert_eq!(
        reference.active_node_ids(),
        c.active_node_ids(),
        "{np} rank(s)"
    );
}

/// The layered blocks' nodes (the body-pair patch tests).
impl Solved {
    /// Node coordinates of solution.h5 by node id, with the layer of the node: the integer
    /// part of the centroid height (last coordinate) of a cell through it (blocks stacked one
    /// unit high each: 0 the lowest).
    pub fn node_layers(&self) -> BTreeMap<u64, (Vec<f64>, usize)> {
        let v = python_json(
            r#"
import sys, json, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
x = f["mesh/geometry"][:]
cells = f["mesh/topology"][:]
dim = cells.shape[1] - 1
layer = np.zeros(len(x), dtype=int)
layer[cells.ravel()] = np.repeat(np.floor(x[cells, dim - 1].mean(axis=1)).astype(int), dim + 1)
print("RESULT " + json.dumps({"ids": f["mesh/node_id"][:].tolist(), "x": x.tolist(), "layer": layer.tolist()}))
"#,
            &[&self.dir.join("solution.h5")],
        );
        let ids = v["ids"].as_array().expect("ids");
        let xs = v["x"].as_array().expect("x");
        let up = v["layer"].as_array().expect("layer");
        ids.iter()
            .zip(xs.iter().zip(up))
            .map(|(i, (x, l))| {
                let layer = l.as_u64().expect("layer") as usize;
                (i.as_u64().expect("id"), (floats(x), layer))
            })
            .collect()
    }
}
