//! Rank independence of the contact solution: the Hertz case (L4) and the 3D block on the
//! plane give the same active set and displacement (matched by node_id) on 1, 2 and 3 ranks.

mod common;

use common::*;
use std::path::Path;

/// Compares solution.h5 of the later directories with the first, matched by node_id:
/// max |Δu| / max |u| and whether the contact states agree node by node.
const COMPARE_PY: &str = r#"
import sys, json, h5py, numpy as np
def load(d):
    f = h5py.File(d + "/solution.h5", "r")
    nid = f["mesh/node_id"][:]; u = f["nodal/displacement"][:]
    cid = f["contact/node_id"][:]; st = f["contact/state"][:]
    o = np.argsort(nid); co = np.argsort(cid)
    return nid[o], u[o], cid[co], st[co]
ref = load(sys.argv[1])
out = []
for d in sys.argv[2:]:
    r = load(d)
    same_ids = bool(np.array_equal(r[0], ref[0]) and np.array_equal(r[2], ref[2]))
    du = float(np.abs(r[1] - ref[1]).max() / np.abs(ref[1]).max()) if same_ids else None
    same_state = bool(np.array_equal(r[3], ref[3])) if same_ids else False
    out.append({"same_ids": same_ids, "u_rel": du, "same_state": same_state,
                "active": int((r[3] > 0.5).sum()), "ref_active": int((ref[3] > 0.5).sum())})
print("RESULT " + json.dumps(out))
"#;

/// On the plain path (`solver.reuse = "never"`): "auto" decides from wall-clock times whether a
/// step reuses a factorisation, and a stop decided on a reuse step costs one confirming
/// factorised step, so under load the step counts of the default path may differ by one
/// between runs (seen in CI: 10 against 9 on Hertz L4) while the answer is the same.
fn same_on_1_2_3_ranks(case: &Path, sets: &[&str], what: &str) {
    let mut sets = sets.to_vec();
    sets.push("solver.reuse=\"never\"");
    let sets = &sets[..];
    let runs: Vec<Solved> = (1..=3).map(|np| solve(np, case, sets)).collect();
    for (np, s) in runs.iter().enumerate() {
        assert!(
            s.converged(),
            "{what} on {} rank(s):\n{}",
            np + 1,
            s.run.output()
        );
    }
    let dirs: Vec<&Path> = runs.iter().map(|s| s.dir.as_path()).collect();
    let res = python_json(COMPARE_PY, &dirs);
    for (k, r) in res.as_array().expect("list").iter().enumerate() {
        let np = k + 2;
        assert_eq!(
            r["same_ids"], true,
            "{what}: node ids differ on {np} ranks: {r}"
        );
        assert_eq!(
            r["same_state"], true,
            "{what}: active set differs on {np} ranks: {r}"
        );
        let du = r["u_rel"].as_f64().expect("u_rel");
        assert!(
            du < 1e-10,
            "{what}: u differs by {du:e} (relative) on {np} ranks"
        );
        println!(
            "{what}: {np} ranks vs 1: |Δu|/|u| = {du:.1e}, active {}",
            r["active"]
        );
    }
    let a1 = runs[0].f(&["contact", "active_count"]);
    assert!(a1 > 0.0, "{what}: no contact");
    for s in &runs[1..] {
        assert_eq!(
            s.f(&["contact", "active_count"]),
            a1,
            "{what}: active_count"
        );
        assert_eq!(s.steps(), runs[0].steps(), "{what}: Newton steps differ");
    }
}

#[test]
fn hertz_l4_same_on_1_2_3_ranks() {
    same_on_1_2_3_ranks(
        &repo("cases/hertz/hertz.toml"),
        &["mesh.file=meshes/hertz_L4.msh", "newton.init=all_active"],
        "Hertz L4",
    );
}

#[test]
fn block3d_same_on_1_2_3_ranks() {
    same_on_1_2_3_ranks(&repo("cases/blocks/block3d.toml"), &[], "block3d");
}
