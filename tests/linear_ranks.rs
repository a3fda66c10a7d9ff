//! Rank independence (issue acceptance criterion 3): the binary on 1, 2 and 3 ranks (3 with
//! --oversubscribe on this 2-core machine) gives the same displacement to 1e-10 relative, on a
//! 2D and a 3D case with every kind of load (clamp, a Dirichlet condition with a free
//! component, traction, pressure, body force). solution.h5 is read with h5py and nodes are
//! matched by /mesh/node_id.

mod common;

use common::*;
use std::path::Path;
use std::time::Duration;

const COMPARE_PY: &str = r#"
import json, sys
import h5py, numpy as np

def load(d):
    with h5py.File(d + "/solution.h5", "r") as f:
        ids = f["/mesh/node_id"][...].ravel()
        x = f["/mesh/geometry"][...]
        u = f["/nodal/displacement"][...]
        rank = f["/cell/rank"][...].ravel()
    o = np.argsort(ids, kind="stable")
    assert len(np.unique(ids)) == len(ids), "node ids repeat"
    return ids[o], x[o], u[o], rank

ref = load(sys.argv[1])
out = {"nodes": int(len(ref[0])), "u_max": float(np.abs(ref[2]).max()), "runs": []}
for d in sys.argv[1:]:
    ids, x, u, rank = load(d)
    assert np.array_equal(ids, ref[0]), "different node ids"
    assert np.array_equal(x, ref[1]), "different coordinates for the same node id"
    out["runs"].append({
        "dir": d,
        "max_abs_diff": float(np.abs(u - ref[2]).max()),
        "ranks_seen": sorted(set(int(r) for r in rank)),
    })
print("RESULT " + json.dumps(out))
"#;

fn case_text(dim: usize, mesh: &Path) -> String {
    let mesh = toml_path(mesh);
    if dim == 2 {
        format!(
            r#"
[mesh]
file = {mesh}
[material]
young = 200.0
poisson = 0.3
model = "plane_strain"
[[dirichlet]]
group = "left"
value = [0.0, 0.0]
[[dirichlet]]
group = "bottom"
value = ["free", 0.0]
[[neumann]]
group = "right"
traction = [1.5, -0.5]
[[neumann]]
group = "top"
pressure = 0.7
[body_force]
value = [0.3, -2.0]
[output]
fields = ["displacement", "rank"]
"#
        )
    } else {
        format!(
            r#"
[mesh]
file = {mesh}
[material]
young = 70.0
poisson = 0.25
[[dirichlet]]
group = "left"
value = [0.0, 0.0, 0.0]
[[dirichlet]]
group = "front"
value = ["free", "free", 0.0]
[[neumann]]
group = "right"
traction = [0.5, 0.2, -0.1]
[[neumann]]
group = "top"
pressure = 0.3
[body_force]
value = [0.0, -1.0, 0.2]
[output]
fields = ["displacement", "rank"]
"#
        )
    }
}

/// Runs the case once per entry of `runs` (ranks, extra --set, allowed relative difference
/// from the first run) and compares the displacements.
fn ranks_agree(dim: usize, h: f64, runs: &[(usize, &str, f64)]) {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = unit_mesh(tmp.path(), dim, h);
    let case = write_case(&tmp.path().join("case.toml"), &case_text(dim, &mesh));
    let mut dirs = Vec::new();
    for (i, &(np, set, _)) in runs.iter().enumerate() {
        let out = tmp.path().join(format!("out{i}_{np}"));
        let mut args = vec![
            case.display().to_string(),
            "-o".into(),
            out.display().to_string(),
        ];
        if !set.is_empty() {
            args.extend(["--set".to_string(), set.to_string()]);
        }
        run_with_timeout(solver(np, &args), Duration::from_secs(180))
            .expect_code(0, &format!("{dim}D case on {np} ranks {set}"));
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["ranks"].as_u64(), Some(np as u64));
        dirs.push(out.display().to_string());
    }
    let res = json_after(&python(COMPARE_PY, &dirs), "RESULT ");
    let u_max = res["u_max"].as_f64().unwrap();
    assert!(
        u_max > 1e-4,
        "{dim}D: displacement too small to compare: {res}"
    );
    for (run, &(np, set, tol)) in res["runs"].as_array().unwrap().iter().zip(runs) {
        let seen: Vec<u64> = run["ranks_seen"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r.as_u64().unwrap())
            .collect();
        assert_eq!(
            seen,
            (0..np as u64).collect::<Vec<_>>(),
            "{dim}D on {np} ranks: every rank should own cells"
        );
        let d = run["max_abs_diff"].as_f64().unwrap();
        assert!(
            d <= tol * u_max,
            "{dim}D: {np} ranks {set} differ from the first run by {d:e} (max |u| {u_max:e})"
        );
    }
    println!("{dim}D: {res}");
}

#[test]
fn square_1_2_3_ranks_same_displacement() {
    ranks_agree(2, 0.05, &[(1, "", 0.0), (2, "", 1e-10), (3, "", 1e-10)]);
}

#[test]
fn cube_1_2_3_ranks_same_displacement() {
    ranks_agree(3, 0.15, &[(1, "", 0.0), (2, "", 1e-10), (3, "", 1e-10)]);
}

/// The iterative preset (GMRES + GAMG, rtol 1e-10 by default) on 2 ranks agrees with the
/// direct solver on 1 rank to the accuracy its tolerance allows (measured by hand with
/// `-mg_levels_pc_type jacobi -mg_levels_ksp_type chebyshev`, which works around the bug:
/// 8e-11 relative in 2D).
#[test]
fn iterative_preset_2_ranks_matches_direct_1_rank() {
    ranks_agree(
        2,
        0.05,
        &[(1, "", 0.0), (2, "solver.preset=iterative", 1e-7)],
    );
    ranks_agree(
        3,
        0.2,
        &[(1, "", 0.0), (2, "solver.preset=iterative", 1e-7)],
    );
}
