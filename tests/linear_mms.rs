//! Convergence study with manufactured solutions (issue acceptance criterion 2).
//!
//! Unit square (plane strain) and unit cube, smooth exact displacements (sin/cos products, see
//! examples/linear_check.rs), body force f = -div sigma(u) written out by hand (and checked
//! there against central differences), u as Dirichlet data on the whole boundary. Meshes from
//! tests/meshes/square.geo and cube.geo with h halving; errors by a degree-2 quadrature per
//! cell. P1 elements must give an L2 error O(h^2) and an H1-seminorm error O(h).
//!
//! Runs examples/linear_check.rs (`mms` mode) under `mpirun -n 2`, so the parallel assembly of
//! a variable body force and non-homogeneous Dirichlet data is what is measured. The table is
//! printed (`cargo test --release --test linear_mms -- --nocapture`).

mod common;

use common::*;
use std::time::Duration;

struct Row {
    /// Longest cell edge.
    h_max: f64,
    /// (|Omega| / cells)^(1/dim): smooth in the refinement, used for the rates.
    h: f64,
    cells: u64,
    dofs: u64,
    l2: f64,
    h1: f64,
}

fn study(dim: usize, hs: &[f64]) -> Vec<Row> {
    let tmp = tempfile::tempdir().unwrap();
    let meshes: Vec<String> = hs
        .iter()
        .map(|&h| unit_mesh(tmp.path(), dim, h).display().to_string())
        .collect();
    let mut args = vec!["mms".to_string()];
    args.extend(meshes.iter().cloned());
    let r = run_with_timeout(
        mpirun(2, &example("linear_check"), &args),
        Duration::from_secs(300),
    );
    r.expect_code(0, &format!("linear_check mms ({dim}D)"));
    // The hand-written gradient and body force agree with finite differences of u / sigma.
    let chk = json_after(&r.stdout, "CHECK ");
    assert_eq!(chk["dim"].as_u64(), Some(dim as u64));
    for k in ["grad_rel_err", "f_rel_err"] {
        let e = chk[k].as_f64().unwrap();
        assert!(
            e < 1e-6,
            "{dim}D manufactured solution: {k} = {e} (formula typo?)"
        );
    }
    let rows: Vec<Row> = json_lines(&r.stdout, "MMS ")
        .iter()
        .map(|v| Row {
            h_max: v["h_max"].as_f64().unwrap(),
            h: v["h_eff"].as_f64().unwrap(),
            cells: v["cells"].as_u64().unwrap(),
            dofs: v["dofs"].as_u64().unwrap(),
            l2: v["l2"].as_f64().unwrap(),
            h1: v["h1"].as_f64().unwrap(),
        })
        .collect();
    assert_eq!(rows.len(), hs.len(), "one MMS line per mesh:\n{}", r.stdout);
    rows
}

fn rate(e0: f64, e1: f64, h0: f64, h1: f64) -> f64 {
    (e0 / e1).ln() / (h0 / h1).ln()
}

/// Prints the table (Markdown) and returns the (L2, H1) rates between consecutive meshes,
/// measured against h_eff = (|Omega| / cells)^(1/dim) (the longest edge of an unstructured
/// mesh jumps around and makes single rates noisy).
fn table(title: &str, rows: &[Row]) -> Vec<(f64, f64)> {
    let mut rates = Vec::new();
    println!("\n{title}\n");
    println!("| h_eff | h_max | cells | dofs | L2 error | rate | H1 error | rate |");
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (i, r) in rows.iter().enumerate() {
        let (rl, rh) = if i == 0 {
            ("".to_string(), "".to_string())
        } else {
            let p = &rows[i - 1];
            let rl = rate(p.l2, r.l2, p.h, r.h);
            let rh = rate(p.h1, r.h1, p.h, r.h);
            rates.push((rl, rh));
            (format!("{rl:.2}"), format!("{rh:.2}"))
        };
        println!(
            "| {:.4} | {:.4} | {} | {} | {:.3e} | {rl} | {:.3e} | {rh} |",
            r.h, r.h_max, r.cells, r.dofs, r.l2, r.h1
        );
    }
    rates
}

fn assert_rates(title: &str, rows: &[Row], rates: &[(f64, f64)]) {
    // Errors fall on every refinement, and the mesh really is refined.
    for w in rows.windows(2) {
        assert!(w[1].h < 0.7 * w[0].h, "{title}: mesh sizes do not shrink");
        assert!(
            w[1].l2 < w[0].l2 && w[1].h1 < w[0].h1,
            "{title}: error grew"
        );
    }
    let (l2, h1) = *rates.last().unwrap();
    assert!(
        l2 > 1.8,
        "{title}: L2 rate {l2:.3} between the finest meshes, expected ~2"
    );
    assert!(
        h1 > 0.9,
        "{title}: H1 rate {h1:.3} between the finest meshes, expected ~1"
    );
    // Not faster than P1 can be either (a too-good rate would mean the error is not measured).
    assert!(
        l2 < 2.5 && h1 < 1.5,
        "{title}: implausible rates {l2:.3} / {h1:.3}"
    );
}

#[test]
fn manufactured_solution_square_and_cube_2_ranks() {
    let rows2 = study(2, &[0.2, 0.1, 0.05, 0.025, 0.0125]);
    let rates2 = table(
        "2D, unit square, plane strain (E = 1, nu = 0.3), 2 ranks",
        &rows2,
    );
    let rows3 = study(3, &[0.5, 0.25, 0.125, 0.0625]);
    let rates3 = table("3D, unit cube (E = 1, nu = 0.3), 2 ranks", &rows3);
    assert_rates("2D", &rows2, &rates2);
    assert_rates("3D", &rows3, &rates3);
}
