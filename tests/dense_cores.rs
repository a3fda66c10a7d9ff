//! Rank 0's dense phases on the cores of its node (src/blas.rs `NodeCores`, par.rs
//! `Ctx::on_root_wide`): the condensed path's dense work runs with one OpenBLAS thread per CPU
//! that the ranks on rank 0's node may use, the other ranks waiting without spinning, and the
//! answer does not depend on it.

mod common;

use common::compare::max_diff;
use common::process::{binary, mesh_dir, mpirun_with, repo, run_with_timeout, Run};
use common::solved::{solved, step_displacement, Solved, LIMIT};
use std::path::Path;
use std::process::Command;

/// examples/hemisphere_mindlin.toml on the committed coarse mesh (11 862 unknowns), pushed
/// twice as deep: a hemisphere held at its top, pushed onto a plane and moved sideways in 3
/// load steps, μ = 0.3. On the direct preset its dense phases, the inverse of the Schur
/// complement on 546 candidates' dofs (1 638) and 7–12 dense Coulomb steps per load step,
/// are above `WIDE_MIN_DIM`: they run widened.
fn hemisphere_case(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(repo("examples/hemisphere_mindlin.toml"))
        .expect("examples/hemisphere_mindlin.toml")
        .replace(
            "file = \"../cases/hemisphere.msh\"",
            &format!(
                "file = {:?}",
                mesh_dir()
                    .join("hemisphere_hc0.02.msh")
                    .display()
                    .to_string()
            ),
        )
        .replace(
            "factors = [0.0, 0.25, 0.5, 0.75, 1.0]",
            "factors = [0.0, 0.5, 1.0]",
        )
        .replace("-0.0225]", "-0.045]");
    assert!(text.contains("hemisphere_hc0.02") && text.contains("[0.0, 0.5, 1.0]"));
    assert!(text.contains("-0.045]"));
    let case = dir.join("hemisphere.toml");
    std::fs::write(&case, text).expect("writing the case");
    case
}

/// `mpirun -n np --oversubscribe --bind-to bind program args...` with the tests' MPI
/// environment (OPENBLAS_NUM_THREADS = 1 among it).
fn launch(np: usize, bind: &str, program: &Path, args: &[String]) -> Command {
    mpirun_with(np, &["--bind-to", bind], program, args)
}

/// The CPUs that the ranks of `mpirun -n np --bind-to bind` on this one node may run on,
/// together, from the machine and the launcher's documented binding alone (not from the
/// solver's way of finding them, the union of the ranks' affinity masks): unbound, every
/// CPU this test may use (`nproc`); bound to cores, one core per rank (its hardware threads,
/// /sys's thread siblings of CPU 0), at most every CPU.
fn cpus_of_ranks(np: usize, bind: &str) -> usize {
    // (nproc would take OMP_NUM_THREADS, which the tests' MPI environment sets to 1, for a limit)
    let mut nproc = Command::new("nproc");
    nproc
        .env_remove("OMP_NUM_THREADS")
        .env_remove("OMP_THREAD_LIMIT");
    let run = run_with_timeout(nproc, LIMIT);
    run.expect_code(0, "nproc");
    let online: usize = run.stdout.trim().parse().expect("nproc's count");
    let siblings =
        std::fs::read_to_string("/sys/devices/system/cpu/cpu0/topology/thread_siblings_list")
            .expect("CPU 0's thread siblings");
    let per_core: usize = siblings
        .trim()
        .split(',')
        .map(|part| match part.split_once('-') {
            Some((a, b)) => b.parse::<usize>().unwrap() - a.parse::<usize>().unwrap() + 1,
            None => 1,
        })
        .sum();
    match bind {
        "none" => online,
        "core" => (np * per_core).min(online),
        other => panic!("no expectation for --bind-to {other}"),
    }
}

/// The hemisphere on `np` ranks bound by `bind`.
fn solve(np: usize, bind: &str) -> Solved {
    let tmp = tempfile::tempdir().expect("tempdir");
    let case = hemisphere_case(tmp.path());
    let dir = tmp.path().join("out");
    let args = [
        case.display().to_string(),
        "-o".into(),
        dir.display().to_string(),
    ];
    let run: Run = run_with_timeout(launch(np, bind, &binary(), &args), LIMIT);
    solved(run, tmp, dir)
}

/// Newton steps per load step.
fn load_steps(s: &Solved) -> Vec<u64> {
    s.summary["load"]["steps"]
        .as_array()
        .expect("load.steps")
        .iter()
        .map(|st| st["newton_steps"].as_u64().expect("newton_steps"))
        .collect()
}

#[test]
fn rank_zeros_dense_phases_take_the_cpus_of_the_ranks_beside_it_and_the_answer_stays() {
    let mut runs = Vec::new();
    for (np, bind) in [(1, "core"), (1, "none"), (2, "core")] {
        let want = cpus_of_ranks(np, bind);
        let s = solve(np, bind);
        let threads = s.f(&["dense_threads"]) as usize;
        println!("{np} rank(s), bound to {bind}: {want} CPU(s), dense threads {threads}");
        assert_eq!(threads, want.max(1), "{}", s.run.output());
        assert!(
            s.run
                .stdout
                .contains(&format!("dense phases on {threads} thread(s)")),
            "{}",
            s.run.output()
        );
        runs.push(s);
    }
    let base = &runs[0];
    let schur_dofs = base.summary["newton"]["condensed"]["schur_dofs"].as_u64();
    let schur_dofs = schur_dofs.expect("newton.condensed.schur_dofs") as usize;
    assert!(
        schur_dofs >= signorini_mpi::tuning::WIDE_MIN_DIM,
        "the dense phases run widened: {schur_dofs} Schur dofs"
    );
    assert!(!base.active_node_ids().is_empty(), "some node in contact");
    assert!(!base.slip_node_ids().is_empty(), "some node slips");
    for (s, what, tol) in [
        (&runs[1], "1 rank, unbound", 1e-12),
        (&runs[2], "2 ranks", 1e-10),
    ] {
        // the Newton steps per load step are printed, not compared: the threads' and the
        // ranks' round-off may decide a borderline state on the way
        println!(
            "{what}: Newton steps per load step {:?} against {:?}",
            load_steps(s),
            load_steps(base)
        );
        assert_eq!(
            s.active_node_ids(),
            base.active_node_ids(),
            "{what}: active"
        );
        assert_eq!(s.slip_node_ids(), base.slip_node_ids(), "{what}: slipping");
        for step in 1..=3 {
            let (u, u0) = (
                step_displacement(&s.dir, step),
                step_displacement(&base.dir, step),
            );
            let scale = u0.values().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
            assert!(scale > 0.0, "u = 0: nothing tested");
            let du = max_diff(&u, &u0).0 / scale;
            println!("{what} against 1 rank bound to a core, load step {step}: u {du:.1e}");
            assert!(du <= tol, "{what}, load step {step}: u differs by {du:.1e}");
        }
    }
}

/// `solver.dense_threads = N` fixes rank 0's dense threads whatever the launcher's binding
/// ("auto" follows it): summary.json's `dense_threads` and `dense_threads_asked`, and the log.
#[test]
fn solver_dense_threads_fixes_the_count_whatever_the_binding() {
    let hertz = repo("cases/hertz/hertz.toml");
    for (bind, set, want, asked) in [
        ("none", None, cpus_of_ranks(1, "none"), "auto"),
        ("core", None, cpus_of_ranks(1, "core"), "auto"),
        ("none", Some("solver.dense_threads=1"), 1, "1"),
        ("core", Some("solver.dense_threads=3"), 3, "3"),
    ] {
        let tmp = tempfile::tempdir().expect("tempdir");
        let dir = tmp.path().join("out");
        let mut args = vec![hertz.display().to_string()];
        if let Some(s) = set {
            args.extend(["--set".to_string(), s.to_string()]);
        }
        args.extend(["-o".to_string(), dir.display().to_string()]);
        let s = solved(
            run_with_timeout(launch(1, bind, &binary(), &args), LIMIT),
            tmp,
            dir,
        );
        let what = format!("--bind-to {bind}, {set:?}");
        assert_eq!(s.f(&["dense_threads"]) as usize, want, "{what}");
        assert_eq!(s.summary["dense_threads_asked"], asked, "{what}");
        let from = if set.is_some() {
            "solver.dense_threads"
        } else {
            "the CPUs of the ranks on its node"
        };
        assert!(
            s.run
                .stdout
                .contains(&format!("dense phases on {want} thread(s) ({from})")),
            "{what}: {}",
            s.run.output()
        );
    }
}
