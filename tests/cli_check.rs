//! `signorini-mpi check`: reads and checks a case as a run does, says what the run would do
//! (bodies, groups, contact nodes and initial gaps, the preset) and writes nothing; a case
//! that a run refuses, it refuses alike (exit code 2, the key named). And `--help` lists the
//! subcommands.

mod common;

use common::*;
use std::path::Path;
use std::time::Duration;

/// `signorini-mpi check CASE -o DIR/out` on `np` ranks (0: without mpirun), with `extra`.
fn check(np: usize, case: &Path, dir: &Path, extra: &[&str]) -> Run {
    let mut args = vec![
        "check".to_string(),
        case.display().to_string(),
        "-o".into(),
        dir.join("out").display().to_string(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    run_with_timeout(solver(np, &args), Duration::from_secs(120))
}

/// The 2D Hertz disk of cases/hertz on its coarsest mesh, the plane at `y`.
fn hertz_case(y: f64, group: &str) -> String {
    format!(
        r#"[mesh]
file = {}

[material]
young = 2.0
poisson = 0.3
model = "plane_strain"

[[neumann]]
group = "load"
pressure = 0.02

[contact]
group = "{group}"
obstacle = {{ type = "plane", point = [0.0, {y}], normal = [0.0, 1.0] }}
"#,
        toml_path(&repo("cases/hertz/meshes/hertz_L0.msh"))
    )
}

#[test]
fn help_lists_the_subcommands() {
    let r = run_with_timeout(solver(0, &["--help".into()]), Duration::from_secs(60));
    r.expect_code(0, "--help");
    for sub in ["check", "convert"] {
        assert!(
            r.stdout.lines().any(|l| l.trim_start().starts_with(sub)),
            "--help does not list {sub}:\n{}",
            r.output()
        );
    }
}

/// The shipped Hertz case on 1 and 2 ranks: every section, the same numbers, nothing written.
#[test]
fn check_says_what_hertz_would_do_and_writes_nothing() {
    let mut seen = Vec::new();
    for np in [0, 2] {
        let tmp = tempfile::tempdir().unwrap();
        let r = check(np, &repo("cases/hertz/hertz.toml"), tmp.path(), &[]);
        r.expect_code(0, "check hertz");
        let lines: Vec<&str> = r
            .stdout
            .lines()
            .filter(|l| l.starts_with("check:"))
            .collect();
        for want in [
            "check: bodies: 1",
            "check:   body 1: 6309 nodes from node tag 1, free in 3 of its 3 rigid modes",
            "check: groups: 4",
            "check:   'contact' (1D): 256 elements",
            "check:   'body' (2D): 12168 elements",
            "check: contact pair contact on 'contact': 257 nodes; none starts penetrating",
            "check: preset: direct (asked auto; auto: 2D)",
            "is valid; nothing solved or written",
        ] {
            assert!(
                lines
                    .iter()
                    .any(|l| l.starts_with(want) || l.contains(want)),
                "{np} ranks: no line {want:?}\n{}",
                r.output()
            );
        }
        assert!(
            !r.stdout.contains("newton") && !r.stdout.contains("assembly:"),
            "check solved or assembled:\n{}",
            r.output()
        );
        assert!(
            file_names(tmp.path()).is_empty(),
            "check wrote {:?}",
            file_names(tmp.path())
        );
        // the same but for the output directory, a temporary one per run
        seen.push(lines[..lines.len() - 1].join("\n"));
    }
    assert_eq!(seen[0], seen[1], "1 and 2 ranks say different things");
}

/// A plane moved 0.01 into the disk: the nodes that start inside it, and how deep.
#[test]
fn check_counts_the_nodes_that_start_penetrating() {
    let tmp = tempfile::tempdir().unwrap();
    let case = write_case(&tmp.path().join("case.toml"), &hertz_case(-0.99, "contact"));
    let r = check(0, &case, tmp.path(), &[]);
    r.expect_code(0, "check a penetrating start");
    let line = r
        .stdout
        .lines()
        .find(|l| l.starts_with("check: contact pair"))
        .unwrap_or_else(|| panic!("no contact line:\n{}", r.output()));
    assert!(
        line.contains("start(s) penetrating the obstacle, by up to 1.000000e-2"),
        "{line}"
    );
    assert_eq!(file_names(tmp.path()), ["case.toml"]);
}

/// A case a run refuses: check refuses it alike, naming the file and the key, on 1 and 2
/// ranks, writing nothing.
#[test]
fn check_refuses_a_broken_case_naming_the_key() {
    for np in [0, 2] {
        let tmp = tempfile::tempdir().unwrap();
        let case = write_case(&tmp.path().join("case.toml"), &hertz_case(-1.0, "contakt"));
        let r = check(np, &case, tmp.path(), &[]);
        r.expect_code(2, "check a broken case");
        let errors: Vec<&str> = r
            .stderr
            .lines()
            .filter(|l| l.starts_with("error"))
            .collect();
        assert_eq!(errors.len(), 1, "{}", r.output());
        assert!(
            errors[0].contains("case.toml") && errors[0].contains("contact.group"),
            "{}",
            r.output()
        );
        assert_eq!(file_names(tmp.path()), ["case.toml"]);
    }
}

/// A linear solver that does not converge in a Newton step names the case's solver keys.
#[test]
fn linear_solver_failure_names_the_solver_keys() {
    let tmp = tempfile::tempdir().unwrap();
    let text = hertz_case(-1.0, "contact")
        + "[solver]\npreset = \"iterative\"\npetsc_options = \"-ksp_max_it 1\"\n";
    let case = write_case(&tmp.path().join("case.toml"), &text);
    let args = [
        case.display().to_string(),
        "-o".into(),
        tmp.path().join("out").display().to_string(),
    ];
    let r = run_with_timeout(solver(0, &args), Duration::from_secs(120));
    r.expect_code(1, "one Krylov iteration");
    let msg = r
        .stderr
        .lines()
        .find(|l| l.starts_with("error"))
        .unwrap_or("");
    for want in [
        "the linear solver did not converge",
        "case.toml",
        "'solver.preset' = \"iterative\"",
        "'solver.petsc_options' = \"-ksp_max_it 1\"",
    ] {
        assert!(msg.contains(want), "no {want:?}:\n{}", r.output());
    }
}

/// `rigid_modes = "none"` on a body that no Dirichlet data hold (the Hertz disk here is free in
/// all 3 rigid modes) is warned about by the set-up stage, run and check alike (round-off
/// decides such a mode where the contact does not hold it: a disk between two planes drifted
/// by +0.216, −0.0048 and +0.026 on 1, 2 and 3 ranks); "auto" is not.
#[test]
fn rigid_modes_none_on_a_free_body_is_warned_about() {
    let tmp = tempfile::tempdir().unwrap();
    let case = write_case(&tmp.path().join("case.toml"), &hertz_case(-1.0, "contact"));
    for (setting, warned) in [("none", true), ("auto", false)] {
        let set = format!("contact.rigid_modes=\"{setting}\"");
        let r = check(2, &case, tmp.path(), &["--set", &set]);
        r.expect_code(0, &set);
        let lines: Vec<&str> = (r.stdout.lines())
            .filter(|l| l.starts_with("warning: rigid_modes = \"none\" while the body"))
            .collect();
        assert_eq!(lines.len(), usize::from(warned), "{set}:\n{}", r.output());
        if warned {
            assert!(lines[0].contains("free in 3 rigid mode(s)"), "{}", lines[0]);
        }
    }
}
