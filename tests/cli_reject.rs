//! Input rejections of the binary (issue acceptance criterion 5). Each bad input must give exit
//! code 2, one message on stderr that names the problem (and the key or file), and leave NO
//! output behind: neither the output directory nor its staging directory, nor any other file.
//! One test per kind of error; the last tests repeat some of them under `mpirun -n 2` (exit
//! code 2 from every rank, one message, no hang).

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::time::Duration;

fn square() -> PathBuf {
    mesh_dir().join("square_h0.25.msh")
}

fn cube() -> PathBuf {
    mesh_dir().join("cube_h0.5.msh")
}

/// A valid 2D case on `mesh` (groups left, right, bottom, top, body).
fn case_2d(mesh: &Path) -> String {
    format!(
        r#"[mesh]
file = {}

[material]
young = 1.0
poisson = 0.3
model = "plane_strain"

[[dirichlet]]
group = "left"
value = [0.0, 0.0]

[[neumann]]
group = "right"
traction = [1.0, 0.0]
"#,
        toml_path(mesh)
    )
}

/// A valid 3D case on the unit cube.
fn case_3d() -> String {
    format!(
        r#"[mesh]
file = {}

[material]
young = 1.0
poisson = 0.3

[[dirichlet]]
group = "left"
value = [0.0, 0.0, 0.0]

[[neumann]]
group = "right"
traction = [1.0, 0.0, 0.0]
"#,
        toml_path(&cube())
    )
}

/// Replaces `from` (which must occur) by `to`.
fn edit(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "{from:?} not in the case");
    text.replacen(from, to, 1)
}

/// Runs the case on `np` ranks (0 = without mpirun) with `extra` arguments.
fn run(dir: &Path, text: &str, np: usize, extra: &[&str]) -> Run {
    let case = write_case(&dir.join("case.toml"), text);
    let out = dir.join("out");
    let mut args = vec![
        case.display().to_string(),
        "-o".into(),
        out.display().to_string(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    run_with_timeout(solver(np, &args), Duration::from_secs(120))
}

/// Files in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The case must be rejected: exit code 2, every `expect` substring in the message, only
/// case.toml in the directory afterwards.
fn rejected_np(text: &str, np: usize, expect: &[&str]) -> String {
    let tmp = tempfile::tempdir().unwrap();
    let r = run(tmp.path(), text, np, &[]);
    r.expect_code(2, "bad input");
    let errors: Vec<&str> = r
        .stderr
        .lines()
        .filter(|l| l.starts_with("error"))
        .collect();
    assert_eq!(
        errors.len(),
        1,
        "expected one error message, stderr:\n{}",
        r.stderr
    );
    if np == 0 {
        assert_eq!(
            r.stderr.trim().lines().count(),
            1,
            "stderr must be one message:\n{}",
            r.stderr
        );
    }
    let msg = errors[0].to_string();
    println!("rejected ({np} ranks): {msg}");
    for e in expect {
        assert!(msg.contains(e), "message lacks {e:?}: {msg}");
    }
    assert_eq!(
        listing(tmp.path()),
        ["case.toml"],
        "something was written for a rejected case ({msg})"
    );
    msg
}

fn rejected(text: &str, expect: &[&str]) -> String {
    rejected_np(text, 0, expect)
}

/// The base cases themselves run (so every rejection below is caused by the one edit).
#[test]
fn base_cases_are_accepted() {
    for text in [case_2d(&square()), case_3d()] {
        let tmp = tempfile::tempdir().unwrap();
        run(tmp.path(), &text, 0, &[]).expect_code(0, "base case");
        assert_eq!(
            listing(&tmp.path().join("out")),
            ["solution.h5", "solution.xdmf", "summary.json"]
        );
    }
}

#[test]
fn unknown_key() {
    let t = edit(&case_2d(&square()), "young = 1.0", "youngs_modulus = 1.0");
    let m = rejected(
        &t,
        &["case.toml:5:", "material.youngs_modulus", "unknown key"],
    );
    assert!(m.contains("young"), "should list the allowed keys: {m}");
}

#[test]
fn unknown_top_level_section() {
    let t = format!("{}\n[sovler]\npreset = \"direct\"\n", case_2d(&square()));
    rejected(&t, &["sovler", "unknown key"]);
}

#[test]
fn unknown_key_from_set() {
    let tmp = tempfile::tempdir().unwrap();
    let r = run(
        tmp.path(),
        &case_2d(&square()),
        0,
        &["--set", "material.yuong=3"],
    );
    r.expect_code(2, "--set unknown key");
    assert!(
        r.stderr.contains("material.yuong") && r.stderr.contains("--set"),
        "{}",
        r.stderr
    );
    assert_eq!(listing(tmp.path()), ["case.toml"]);
}

#[test]
fn wrong_type() {
    let t = edit(&case_2d(&square()), "young = 1.0", "young = \"hard\"");
    rejected(
        &t,
        &[
            "case.toml:5:",
            "material.young",
            "expected a number",
            "string",
        ],
    );
}

#[test]
fn wrong_type_group_is_number() {
    let t = edit(&case_2d(&square()), "group = \"left\"", "group = 4");
    rejected(&t, &["dirichlet[0].group", "expected a string"]);
}

#[test]
fn unknown_group_lists_the_mesh_groups() {
    let t = edit(&case_2d(&square()), "group = \"left\"", "group = \"lft\"");
    let m = rejected(&t, &["dirichlet[0].group", "\"lft\""]);
    for g in ["left", "right", "bottom", "top", "body"] {
        assert!(m.contains(&format!("\"{g}\"")), "group {g} not listed: {m}");
    }
}

#[test]
fn young_zero_and_negative() {
    for e in ["0.0", "-1.0", "0"] {
        let t = edit(&case_2d(&square()), "young = 1.0", &format!("young = {e}"));
        rejected(&t, &["case.toml:5:", "material.young", "> 0"]);
    }
}

#[test]
fn poisson_outside_range() {
    for nu in ["0.5", "-1.0", "0.7", "-3"] {
        let t = edit(
            &case_2d(&square()),
            "poisson = 0.3",
            &format!("poisson = {nu}"),
        );
        rejected(&t, &["case.toml:6:", "material.poisson", "0.5"]);
    }
}

#[test]
fn vector_length_not_matching_2d_mesh() {
    let t = edit(
        &case_2d(&square()),
        "value = [0.0, 0.0]",
        "value = [0.0, 0.0, 0.0]",
    );
    rejected(&t, &["dirichlet[0].value", "3 components", "2D"]);
}

#[test]
fn vector_length_not_matching_3d_mesh() {
    let t = edit(
        &case_3d(),
        "traction = [1.0, 0.0, 0.0]",
        "traction = [1.0, 0.0]",
    );
    rejected(&t, &["neumann[0].traction", "2 components", "3D"]);
}

#[test]
fn pressure_and_traction_together() {
    let t = edit(
        &case_2d(&square()),
        "traction = [1.0, 0.0]",
        "traction = [1.0, 0.0]\npressure = 2.0",
    );
    rejected(&t, &["neumann[0]", "pressure", "traction"]);
}

#[test]
fn zero_area_cell() {
    // A hand-written MSH 4.1 file: a unit square of two triangles plus triangle 5 on nodes
    // (0,0), (0.5,0), (1,0), which are collinear.
    let bad = mesh_dir().join("square_zero_area.msh");
    let t = edit(
        &case_2d(&bad),
        "group = \"right\"\ntraction",
        "group = \"right\"\ntraction",
    );
    rejected(&t, &["square_zero_area.msh", "element 5", "zero area"]);
    // Control: the same file with node 5 moved off the line is accepted, so the rejection
    // above is about the degenerate cell and not the format of the file.
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(&bad).unwrap();
    let good = tmp.path().join("moved.msh");
    std::fs::write(&good, edit(&text, "\n0.5 0 0\n", "\n0.5 -0.5 0\n")).unwrap();
    run(tmp.path(), &case_2d(&good), 0, &[]).expect_code(0, "control mesh");
}

#[test]
fn body_cells_without_physical_group() {
    let t = case_2d(&mesh_dir().join("square_nobody_saveall.msh"));
    rejected(&t, &["square_nobody_saveall.msh", "no physical group"]);
}

#[test]
fn partitioned_msh() {
    let t = case_2d(&mesh_dir().join("square_h0.5_part2.msh"));
    rejected(&t, &["square_h0.5_part2.msh", "partitioned"]);
}

#[test]
fn missing_mesh_file() {
    let t = case_2d(&mesh_dir().join("no_such_mesh.msh"));
    rejected(&t, &["no_such_mesh.msh", "cannot read"]);
}

#[test]
fn msh22_file() {
    let t = case_2d(&mesh_dir().join("square_h0.5_msh22.msh"));
    rejected(&t, &["square_h0.5_msh22.msh", "4.1"]);
}

#[test]
fn missing_case_file() {
    let tmp = tempfile::tempdir().unwrap();
    let args = vec![
        tmp.path().join("nope.toml").display().to_string(),
        "-o".into(),
        tmp.path().join("out").display().to_string(),
    ];
    let r = run_with_timeout(solver(0, &args), Duration::from_secs(60));
    r.expect_code(2, "missing case file");
    assert!(r.stderr.contains("nope.toml"), "{}", r.stderr);
    assert!(listing(tmp.path()).is_empty());
}

#[test]
fn model_not_matching_mesh_dimension() {
    let t = edit(
        &case_3d(),
        "poisson = 0.3",
        "poisson = 0.3\nmodel = \"plane_strain\"",
    );
    rejected(&t, &["material.model", "3D"]);
}

#[test]
fn neumann_on_body_group() {
    let t = edit(&case_2d(&square()), "group = \"right\"", "group = \"body\"");
    rejected(&t, &["neumann[0].group", "body", "boundary"]);
}

// ---- the same under mpirun -n 2: every rank must stop with code 2, nothing hangs ----------

#[test]
fn mpirun_2_unknown_group() {
    let t = edit(&case_2d(&square()), "group = \"left\"", "group = \"lft\"");
    rejected_np(&t, 2, &["dirichlet[0].group", "\"lft\"", "\"left\""]);
}

#[test]
fn mpirun_2_unknown_key() {
    let t = edit(&case_2d(&square()), "young = 1.0", "youngs_modulus = 1.0");
    rejected_np(&t, 2, &["material.youngs_modulus"]);
}

#[test]
fn mpirun_2_zero_area_cell() {
    let t = case_2d(&mesh_dir().join("square_zero_area.msh"));
    rejected_np(&t, 2, &["zero area"]);
}

#[test]
fn mpirun_3_partitioned_msh() {
    let t = case_2d(&mesh_dir().join("square_h0.5_part2.msh"));
    rejected_np(&t, 3, &["partitioned"]);
}
