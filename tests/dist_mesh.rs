//! Distributed mesh input (issue 10, items 1 and 2): `signorini-mpi convert` writes an HDF5
//! mesh that solves exactly like its MSH source, and on 2 ranks no rank holds the whole mesh
//! (the "local mesh per rank" log line against the global counts of the "mesh" line).

mod common;
use common::*;

use std::time::Duration;

/// (nodes, cells) of the "mesh ...: 2D, N nodes, C cells, ..." line.
fn global_sizes(out: &str) -> (u64, u64) {
    let line = out
        .lines()
        .find(|l| l.starts_with("mesh ") && l.contains(" nodes, "))
        .expect("mesh line");
    let words: Vec<&str> = line.split_whitespace().collect();
    let before = |w: &str| -> u64 {
        let i = words
            .iter()
            .position(|x| x.trim_end_matches(',') == w)
            .expect("word");
        words[i - 1].parse().expect("number")
    };
    (before("nodes"), before("cells"))
}

/// (cells, nodes) per rank from the "local mesh per rank" line.
fn local_sizes(out: &str) -> Vec<(u64, u64)> {
    let line = out
        .lines()
        .find(|l| l.starts_with("local mesh per rank"))
        .expect("local mesh line");
    let list = &line[line.find('[').expect("[")..];
    list.trim_matches(|c| c == '[' || c == ']')
        .split("), (")
        .map(|p| {
            let p = p.trim_matches(|c| c == '(' || c == ')');
            let mut it = p.split(", ").map(|x| x.parse::<u64>().expect("number"));
            (it.next().unwrap(), it.next().unwrap())
        })
        .collect()
}

/// The lines of a run's stdout that do not depend on the file name, on timings, on the
/// order of round-off values or on the partition (`convert` stores the cells in Morton order, so the h5 file's blocks, and with
/// them the partition, differ from the msh file's).
fn result_lines(out: &str) -> Vec<String> {
    out.lines()
        .filter(|l| {
            !l.starts_with("mesh ")
                && !l.contains("timings")
                && !l.starts_with("output:")
                && !l.starts_with("local mesh per rank")
                && !l.starts_with("partition:")
        })
        .map(|l| {
            // the certificate's "worst relative v (name)" names the largest of values compared
            // one by one: at round-off (1e-14) which one is largest is round-off too
            let l = match l.find("; worst relative") {
                Some(i) if l.starts_with("certificate:") => &l[..i],
                _ => l,
            };
            // mask timings ("0.123 s")
            let w: Vec<&str> = l.split_whitespace().collect();
            (0..w.len())
                .map(|i| {
                    let timing = w[i].parse::<f64>().is_ok()
                        && w.get(i + 1)
                            .is_some_and(|n| n.starts_with('s') && n.len() <= 3);
                    if timing {
                        "X"
                    } else {
                        w[i]
                    }
                })
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect()
}

#[test]
fn h5_and_msh_agree_and_no_rank_holds_the_whole_mesh() {
    let dir = tempfile::tempdir().expect("tempdir");
    let msh = repo("cases/hertz/meshes/hertz_refined_L3.msh");
    let h5 = dir.path().join("hertz.h5");
    convert(&msh, &h5);
    assert!(h5.exists() && dir.path().join("hertz.xdmf").exists());

    let case = repo("cases/hertz/hertz.toml");
    let mut outs = Vec::new();
    for (name, mesh) in [("msh", &msh), ("h5", &h5)] {
        let out = dir.path().join(name);
        let run = run_with_timeout(
            solver(
                2,
                &[
                    case.display().to_string(),
                    "--set".into(),
                    format!("mesh.file=\"{}\"", mesh.display()),
                    "--set".into(),
                    // the plain path: what "auto" reuses follows the run's timings
                    "solver.reuse=\"never\"".into(),
                    "-o".into(),
                    out.display().to_string(),
                ],
            ),
            Duration::from_secs(120),
        );
        run.expect_code(0, name);
        let (nodes, cells) = global_sizes(&run.stdout);
        let local = local_sizes(&run.stdout);
        assert_eq!(local.len(), 2, "{}", run.output());
        for &(c, n) in &local {
            assert!(
                c < cells && n < nodes,
                "{name}: a rank holds {c} of {cells} cells, {n} of {nodes} nodes"
            );
        }
        let csv = std::fs::read_to_string(out.join("contact_nodes.csv")).expect("csv");
        outs.push((result_lines(&run.stdout), csv));
    }
    // The same numbering, another partition: the same results up to the round-off of a 2-rank
    // solve, text and integers exactly.
    same_to_roundoff(&outs[0].0.join("\n"), &outs[1].0.join("\n"), "stdout");
    same_to_roundoff(&outs[0].1, &outs[1].1, "contact_nodes.csv");
}

/// Two texts agree token by token; numbers to |a − b| ≤ 1e-12 + 1e-9 max(|a|, |b|).
fn same_to_roundoff(a: &str, b: &str, what: &str) {
    let split = |t: &str| -> Vec<String> {
        t.split(|c: char| c.is_whitespace() || ",;=[]()".contains(c))
            .filter(|w| !w.is_empty())
            .map(str::to_string)
            .collect()
    };
    let (ta, tb) = (split(a), split(b));
    assert_eq!(
        ta.len(),
        tb.len(),
        "{what}: different lengths\n{a}\n---\n{b}"
    );
    for (x, y) in ta.iter().zip(&tb) {
        match (x.parse::<f64>(), y.parse::<f64>()) {
            (Ok(u), Ok(v)) => assert!(
                (u - v).abs() <= 1e-12 + 1e-9 * u.abs().max(v.abs()),
                "{what}: {x} vs {y}"
            ),
            _ => assert_eq!(x, y, "{what}"),
        }
    }
}

#[test]
fn damaged_h5_mesh_is_an_input_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bad = dir.path().join("bad.h5");
    std::fs::write(&bad, b"not an hdf5 file").expect("write");
    let case = repo("cases/hertz/hertz.toml");
    let run = run_with_timeout(
        solver(
            2,
            &[
                case.display().to_string(),
                "--set".into(),
                format!("mesh.file=\"{}\"", bad.display()),
                "-o".into(),
                dir.path().join("out").display().to_string(),
            ],
        ),
        Duration::from_secs(60),
    );
    run.expect_code(2, "damaged h5");
    assert!(run.stderr.contains("bad.h5"), "{}", run.output());
    assert!(!run.stderr.contains("panicked"), "{}", run.output());
}
