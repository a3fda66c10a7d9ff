//! The BLAS kernels the solver runs: where OpenBLAS takes a CPU with AVX2 / AVX-512 for an
//! older core, the solver restarts with OPENBLAS_CORETYPE (src/blas.rs); a user's own
//! OPENBLAS_CORETYPE is kept.

mod common;

use common::process::{run_with_timeout, solver};
use common::solved::{case, solve, solved, LIMIT};
use signorini_mpi::blas::{better_core, Isa};

/// The kernel set of summary.json's `blas` ("OpenBLAS <core> ...").
fn core(summary: &serde_json::Value) -> String {
    let blas = summary["blas"]
        .as_str()
        .expect("summary.json names the BLAS kernels");
    let mut words = blas.split_whitespace();
    assert_eq!(words.next(), Some("OpenBLAS"), "{blas}");
    words.next().expect("a kernel set").to_string()
}

#[test]
fn the_solver_runs_kernels_that_fit_the_cpu() {
    let s = solve(2, &case("block2d_tresca.toml"), &[]);
    let core = core(&s.summary);
    assert_eq!(better_core(&core, Isa::of_this_cpu()), None, "{core}");
}

#[test]
fn a_users_openblas_coretype_is_kept() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("out");
    let args = [
        case("block2d_tresca.toml").display().to_string(),
        "-o".into(),
        dir.display().to_string(),
    ];
    let mut cmd = solver(0, &args);
    cmd.env("OPENBLAS_CORETYPE", "Prescott");
    let s = solved(run_with_timeout(cmd, LIMIT), tmp, dir);
    assert_eq!(core(&s.summary), "Prescott");
    assert!(!s.summary["blas"].as_str().unwrap().contains("had taken"));
}
