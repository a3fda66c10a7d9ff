//! No false "no support" far from the obstacle or with the iterative preset, and a full disk
//! while writing the results is one clean error (issue 11, item 5).

mod common;
use common::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn hertz() -> PathBuf {
    repo("cases/hertz/hertz.toml")
}

fn plane_at(y: f64) -> String {
    format!("contact.obstacle={{type=\"plane\",point=[0.0,{y:.1}],normal=[0.0,1.0]}}")
}

fn table(dir: &Path) -> BTreeMap<u64, Row> {
    by_node_id(read_csv(&dir.join("contact_nodes.csv")))
}

fn max_abs(t: &BTreeMap<u64, Row>, key: &str) -> f64 {
    t.values().map(|r| r.f(key).abs()).fold(0.0, f64::max)
}

/// Largest |a − b| of a column over the nodes of `a` (which `b` must hold too).
fn max_diff(a: &BTreeMap<u64, Row>, b: &BTreeMap<u64, Row>, key: &str) -> f64 {
    a.iter()
        .map(|(id, r)| (r.f(key) - b[id].f(key)).abs())
        .fold(0.0, f64::max)
}

fn active_ids(t: &BTreeMap<u64, Row>) -> Vec<u64> {
    t.iter()
        .filter(|(_, r)| r.active())
        .map(|(&id, _)| id)
        .collect()
}

#[test]
fn an_obstacle_700_below_gives_the_touching_answer_moved_down() {
    // The disk (default mesh) touching the plane at y = −1, and the plane 700 below that: the
    // disk moves rigidly down by 700 and ends in the same contact. Before: "no support" (the
    // pins' residual held the rounding of the 700-unit motion, ~1e-11 > 1e-8 · the largest
    // nodal load), and, where it converged, errors ~1e-10 in u and ~1e-8 relative in λ.
    let touching = solve(1, &hertz(), &[]);
    let t0 = table(&touching.dir);
    let shift = 700.0;
    // Round-off of the geometry at |y| ≈ 700: the gaps are 700.x − 700.
    let tol_u = 100.0 * f64::EPSILON * shift;
    let tol_lambda = 1e-9 * max_abs(&t0, "lambda_n");
    for (np, init) in [(1, "auto"), (1, "all_active"), (2, "auto")] {
        let init_set = format!("newton.init={init}");
        let far = solve(np, &hertz(), &[&plane_at(-1.0 - shift), &init_set]);
        far.assert_converged(init);
        let t = table(&far.dir);
        let what = format!("{np} rank(s), init {init}");
        assert_eq!(
            active_ids(&t),
            active_ids(&t0),
            "{what}: active sets differ"
        );
        // gap = u_n + gap0 is the same; u_n itself is 700 lower; u_t the same.
        for (key, tol) in [("gap", tol_u), ("u_t1", tol_u), ("lambda_n", tol_lambda)] {
            let d = max_diff(&t0, &t, key);
            assert!(d <= tol, "{what}: {key} differs by {d:.3e} (> {tol:.3e})");
        }
        let d_un = t0
            .iter()
            .map(|(id, r)| (r.f("u_n") - shift - t[id].f("u_n")).abs())
            .fold(0.0, f64::max);
        assert!(d_un <= tol_u, "{what}: u_n + 700 differs by {d_un:.3e}");
        let (f0, f1) = (touching.total_force(), far.total_force());
        assert!(
            (f0[1] - f1[1]).abs() <= 1e-12 * f0[1].abs(),
            "{what}: total force {f1:?} vs {f0:?}"
        );
    }
}

#[test]
fn the_iterative_preset_at_poisson_04999_converges_like_the_direct_one() {
    // ν = 0.4999: GMRES + GAMG stops at its relative tolerance with a residual whose sum over
    // the body (~2e-10 here) the pins used to carry, read as an unbalanced load: "no support".
    let mesh = "mesh.file=meshes/hertz_refined_L2.msh";
    let nu = "material.poisson=0.4999";
    let direct = solve(1, &hertz(), &[mesh, nu]);
    let iterative = solve(1, &hertz(), &[mesh, nu, "solver.preset=\"iterative\""]);
    iterative.assert_converged("iterative");
    assert!(
        !iterative.run.stderr.contains("no support"),
        "{}",
        iterative.run.output()
    );
    let (td, ti) = (table(&direct.dir), table(&iterative.dir));
    assert_eq!(active_ids(&ti), active_ids(&td), "active sets differ");
    // As close as the Krylov tolerance allows (measured 3e-7 relative).
    let lam = max_abs(&td, "lambda_n");
    let d = max_diff(&td, &ti, "lambda_n");
    assert!(
        d <= 1e-5 * lam,
        "λ_n differs by {d:.3e} (max |λ_n| {lam:.3e})"
    );
}

#[test]
fn a_full_disk_while_writing_is_one_error_and_exit_1_on_every_rank() {
    // Before: on 1 rank "closing failed: … unable to flush cached data" and then a segfault
    // (exit 139) in HDF5's shutdown inside MPI_Finalize; on 2 ranks a hang, with the staging
    // directory left.
    let disk = SmallDisk::mount("900k");
    let out = disk.path.join("out");
    // Previous results that fit (block2d: ~70 KB).
    run_solver(1, &repo("cases/blocks/block2d.toml"), &[], &out).expect_code(0, "small run");
    let before = listing(&out);
    assert!(before.iter().any(|(n, _)| n == "solution.h5"));
    for np in [1, 2] {
        // The Hertz results (0.89 MB) do not fit beside them.
        let r = run_solver(np, &hertz(), &[], &out);
        r.expect_code(1, &format!("full disk, {np} rank(s)"));
        let line = disk.assert_nothing_written(&r, &out, &before, &format!("{np} rank(s)"));
        assert!(
            line.contains(&format!("cannot write results to {}", out.display())),
            "{line}"
        );
        let all = r.output();
        assert!(
            !all.contains("Segmentation") && !all.contains("signal"),
            "crash:\n{all}"
        );
    }
}
