//! The BLAS kernels the solver runs: where OpenBLAS takes a CPU with AVX2 / AVX-512 for an
//! older core, the solver restarts with OPENBLAS_CORETYPE (src/blas.rs); a user's own
//! OPENBLAS_CORETYPE is kept.

mod common;

use common::process::{run_with_timeout, solver};
use common::solved::{case, solve, solved, LIMIT};

/// The kernel set of summary.json's `blas` ("OpenBLAS <core> ...").
fn core(summary: &serde_json::Value) -> String {
    let blas = summary["blas"]
        .as_str()
        .expect("summary.json names the BLAS kernels");
    let mut words = blas.split_whitespace();
    assert_eq!(words.next(), Some("OpenBLAS"), "{blas}");
    words.next().expect("a kernel set").to_string()
}

/// The flags of the first processor in /proc/cpuinfo (read here, not through the crate).
fn cpu_flags() -> Vec<String> {
    let text = std::fs::read_to_string("/proc/cpuinfo").expect("/proc/cpuinfo");
    let line = text
        .lines()
        .find(|l| l.starts_with("flags"))
        .expect("a flags line in /proc/cpuinfo");
    let (_, flags) = line.split_once(':').expect("flags: ...");
    flags.split_whitespace().map(str::to_string).collect()
}

/// OpenBLAS' x86-64 kernel sets (names as `openblas_get_corename` gives them, lower case) by
/// the widest vector instructions they use.
const AVX512_CORES: [&str; 3] = ["skylakex", "cooperlake", "sapphirerapids"];
const AVX2_CORES: [&str; 2] = ["haswell", "zen"];

#[test]
fn the_solver_runs_kernels_that_fit_the_cpu() {
    let s = solve(2, &case("block2d_tresca.toml"), &[]);
    let core = core(&s.summary).to_ascii_lowercase();
    let flags = cpu_flags();
    let has = |f: &str| flags.iter().any(|x| x == f);
    let avx512 = ["avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"]
        .iter()
        .all(|f| has(f));
    let avx2 = has("avx2") && has("fma");
    println!("CPU: AVX2+FMA {avx2}, AVX-512 {avx512}; OpenBLAS kernels {core}");
    if avx512 {
        // AVX-512 kernels, or OpenBLAS' own AVX2 choice for a CPU it knows (e.g. Zen)
        assert!(
            AVX512_CORES.contains(&core.as_str()) || AVX2_CORES.contains(&core.as_str()),
            "an AVX-512 CPU runs {core}"
        );
    } else if avx2 {
        assert!(
            AVX2_CORES.contains(&core.as_str()),
            "an AVX2 CPU runs {core}"
        );
    } else {
        assert!(
            !AVX512_CORES.contains(&core.as_str()) && !AVX2_CORES.contains(&core.as_str()),
            "a CPU without AVX2 runs {core}"
        );
    }
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
