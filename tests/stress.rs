//! The reduced stress suite (`scripts/stress --quick`, issue 11 item 7): about 70 runs of the
//! contact cases under extreme E, ν, loads, c, starts, obstacles, Tresca within and beyond
//! the friction capacity and the iterative preset, each compared with its reference or
//! required to stop with a clear diagnosis. The test fails on any FAIL row (a hang, crash,
//! NaN, silent wrong answer or false diagnosis) and prints the table.

mod common;
use common::*;

use std::process::Command;
use std::time::Duration;

#[test]
fn quick_stress_suite_has_no_fail_row() {
    let mut cmd = Command::new("bash");
    cmd.arg(repo("scripts/stress"))
        .arg("--quick")
        .env("STRESS_BIN", binary());
    mpi_env(&mut cmd);
    // Each run has its own limit inside the script (60 s); this only catches the script.
    let r = run_with_timeout(cmd, Duration::from_secs(1800));
    println!("{}", r.stdout);
    let rows: Vec<&str> = r
        .stdout
        .lines()
        .filter(|l| l.starts_with("| ") && l.matches(" | ").count() >= 6)
        .filter(|l| !l.starts_with("| case |"))
        .collect();
    let count = |o: &str| {
        rows.iter()
            .filter(|l| l.split(" | ").nth(3) == Some(o))
            .count()
    };
    let fails: Vec<&&str> = rows
        .iter()
        .filter(|l| l.split(" | ").nth(3) == Some("FAIL"))
        .collect();
    assert!(
        fails.is_empty(),
        "{} FAIL row(s):\n{}\n{}",
        fails.len(),
        fails
            .iter()
            .map(|l| l.to_string())
            .collect::<Vec<_>>()
            .join("\n"),
        r.output()
    );
    r.expect_code(0, "scripts/stress --quick");
    assert!(rows.len() >= 50, "only {} rows:\n{}", rows.len(), r.stdout);
    assert!(count("ok") >= 40, "too few ok rows:\n{}", r.stdout);
    assert!(count("diag") >= 5, "too few diag rows:\n{}", r.stdout);
}
