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
        file_names(tmp.path()),
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
            file_names(&tmp.path().join("out")),
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
    assert_eq!(file_names(tmp.path()), ["case.toml"]);
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
    // the case file's error: its key, and the file it names
    let t = case_2d(&mesh_dir().join("no_such_mesh.msh"));
    rejected(
        &t,
        &["case.toml", "mesh.file", "no_such_mesh.msh", "cannot read"],
    );
    let t = case_2d(&mesh_dir());
    rejected(&t, &["case.toml", "mesh.file", "is not a file"]);
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
    assert!(file_names(tmp.path()).is_empty());
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

/// `contact.motion` with as many components as the mesh has dimensions, checked once the
/// mesh is read: a 3-component motion on the 2D square, on 2 ranks, and a non-finite one.
#[test]
fn mpirun_2_motion_of_the_wrong_length() {
    let contact = "[contact]\ngroup = \"bottom\"\n\
                   obstacle = { type = \"plane\", point = [0.0, 0.0], normal = [0.0, 1.0] }\n";
    let t = format!("{}{contact}motion = [0.0, 0.01, 0.0]\n", case_2d(&square()));
    rejected_np(
        &t,
        2,
        &["case.toml", "contact.motion", "3 components", "2D"],
    );
    let t = format!("{}{contact}motion = [0.0, nan]\n", case_2d(&square()));
    rejected(&t, &["case.toml", "contact.motion[1]", "finite"]);
}

#[test]
fn mpirun_3_partitioned_msh() {
    let t = case_2d(&mesh_dir().join("square_h0.5_part2.msh"));
    rejected_np(&t, 3, &["partitioned"]);
}

// ---- corrupt counts, malformed headers, degenerate or interior load/contact facets --------

/// Writes `bytes` as `name` into `dir` and returns the case text that uses it.
fn case_on(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    case_2d(&p)
}

/// `bytes` with the first occurrence of `from` replaced by `to`.
fn patched(bytes: &[u8], from: &[u8], to: &[u8]) -> Vec<u8> {
    let p = bytes
        .windows(from.len())
        .position(|w| w == from)
        .expect("pattern in the mesh");
    [&bytes[..p], to, &bytes[p + from.len()..]].concat()
}

/// The `index`-th size_t of the header of `section` in a binary (little-endian) file.
fn binary_count(bytes: &[u8], section: &str, index: usize, value: u64) -> Vec<u8> {
    let tag = format!("{section}\n");
    let p = bytes
        .windows(tag.len())
        .position(|w| w == tag.as_bytes())
        .unwrap()
        + tag.len()
        + 8 * index;
    let mut out = bytes.to_vec();
    out[p..p + 8].copy_from_slice(&value.to_le_bytes());
    out
}

/// A `$PhysicalNames` count of 1e9 and corrupt `$Nodes` / `$Elements` / `$Entities` / block
/// counts (ASCII and binary) used to abort with "memory allocation of … bytes failed"
/// (SIGABRT) or, when small enough, to pass unnoticed. Now: exit 2, one line naming the file.
#[test]
fn msh_counts_beyond_the_file_size() {
    let meshes = tempfile::tempdir().unwrap();
    let ascii = std::fs::read(mesh_dir().join("square_h0.5.msh")).unwrap();
    let bin = std::fs::read(mesh_dir().join("square_h0.25_bin.msh")).unwrap();
    let bad: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "names.msh",
            patched(
                &ascii,
                b"$PhysicalNames\n5\n",
                b"$PhysicalNames\n1000000000\n",
            ),
            "$PhysicalNames announces 1000000000 names",
        ),
        (
            "nodes.msh",
            patched(
                &ascii,
                b"$Nodes\n9 12 1 12",
                b"$Nodes\n9 1000000000000 1 12",
            ),
            "$Nodes announces",
        ),
        (
            "elements.msh",
            patched(&ascii, b"$Elements\n5 22 ", b"$Elements\n5 99999999999 "),
            "$Elements announces",
        ),
        (
            "entities.msh",
            patched(
                &ascii,
                b"$Entities\n4 4 1 0",
                b"$Entities\n4 4000000000000 1 0",
            ),
            "$Entities announces",
        ),
        (
            "nodes_bin.msh",
            binary_count(&bin, "$Nodes", 1, 1 << 40),
            "$Nodes announces",
        ),
        (
            "nodes_bin_300.msh",
            binary_count(&bin, "$Nodes", 1, 300),
            "$Nodes announces",
        ),
        (
            "blocks_bin.msh",
            binary_count(&bin, "$Elements", 0, 1 << 50),
            "$Elements announces",
        ),
        (
            "elements_bin.msh",
            binary_count(&bin, "$Elements", 1, 59),
            "$Elements announces 59 elements, but its blocks hold 58",
        ),
    ];
    for (name, bytes, expect) in bad {
        let m = rejected(
            &case_on(meshes.path(), name, &bytes),
            &[name, expect, "corrupt"],
        );
        assert!(
            !m.contains("save the mesh as MSH 4.1"),
            "misleading hint: {m}"
        );
    }
}

/// A damaged MSH 4.1 file names the line where the parser stopped and shows it (the message
/// once gave the parser's hex dump, no line, and told the user to save the file as MSH 4.1,
/// which it already was); a file cut short says so.
#[test]
fn a_damaged_msh_file_names_the_line() {
    let meshes = tempfile::tempdir().unwrap();
    let ascii = std::fs::read(mesh_dir().join("square_h0.5.msh")).unwrap();
    let text = String::from_utf8(ascii.clone()).unwrap();
    // the header of the second node block, and the line it sits on
    let at = text.find("$Nodes\n").unwrap();
    let line = text[..at].lines().count() + 6;
    let block = text.lines().nth(line - 1).unwrap().to_string();
    assert_eq!(block.split_whitespace().count(), 4, "{block}");
    let damaged = patched(&ascii, format!("\n{block}\n").as_bytes(), b"\n1 zz 0\n");
    let m = rejected(
        &case_on(meshes.path(), "damaged.msh", &damaged),
        &["damaged.msh", &format!("line {line} (\"1 zz 0\")"), "node"],
    );
    assert!(
        !m.contains("save the mesh as MSH 4.1"),
        "misleading hint: {m}"
    );
    assert!(!m.contains("Hex dump"), "{m}");
    // cut short inside $Nodes (after its 9th block's header: enough bytes for its counts)
    let lines: Vec<&str> = text.split_inclusive('\n').collect();
    let cut = lines[..line + 21].concat().into_bytes();
    rejected(
        &case_on(meshes.path(), "cut.msh", &cut),
        &["cut.msh", "the end of the file", "cut short"],
    );
}

/// A binary header with a data size mshio has no reader for made mshio panic: caught, but a
/// panic message and a backtrace (RUST_BACKTRACE=1) came before the clean message.
#[test]
fn malformed_msh_header_gives_one_line_without_backtrace() {
    let meshes = tempfile::tempdir().unwrap();
    let bin = std::fs::read(mesh_dir().join("square_h0.25_bin.msh")).unwrap();
    let ascii = std::fs::read(mesh_dir().join("square_h0.5.msh")).unwrap();
    for (name, bytes) in [
        ("size3.msh", patched(&bin, b"4.1 1 8\n", b"4.1 1 3\n")),
        (
            "size_huge.msh",
            patched(&ascii, b"4.1 0 8\n", b"4.1 0 99999999999\n"),
        ),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let case = write_case(
            &tmp.path().join("case.toml"),
            &case_on(meshes.path(), name, &bytes),
        );
        let args = vec![
            case.display().to_string(),
            "-o".into(),
            tmp.path().join("out").display().to_string(),
        ];
        let mut cmd = solver(0, &args);
        cmd.env("RUST_BACKTRACE", "1");
        let r = run_with_timeout(cmd, Duration::from_secs(60));
        r.expect_code(2, "malformed header");
        let lines: Vec<&str> = r.stderr.trim().lines().collect();
        assert_eq!(lines.len(), 1, "one line expected:\n{}", r.stderr);
        assert!(lines[0].starts_with("error"), "{}", r.stderr);
        assert!(
            lines[0].contains(name) && lines[0].contains("data size"),
            "{}",
            r.stderr
        );
        assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    }
}

fn bad_facets() -> PathBuf {
    mesh_dir().join("square_bad_facets.msh")
}

/// A zero-length segment in the contact group was accepted and gave wrong pressures.
#[test]
fn zero_length_contact_facet() {
    let t = format!(
        "{}\n[contact]\ngroup = \"bottom\"\nobstacle = {{ type = \"plane\", point = [0.0, 0.0], \
         normal = [0.0, 1.0] }}\n",
        case_2d(&bad_facets())
    );
    rejected(
        &t,
        &[
            "square_bad_facets.msh",
            "line element 4",
            "\"bottom\"",
            "contact.group",
            "zero length",
        ],
    );
    // Control: the same case with the contact on "top" runs.
    let tmp = tempfile::tempdir().unwrap();
    let ok = edit(&t, "group = \"bottom\"", "group = \"top\"");
    run(tmp.path(), &ok, 0, &[]).expect_code(0, "contact on a proper boundary group");
}

#[test]
fn load_group_of_interior_or_stray_facets() {
    for (group, tag, what) in [
        ("bottom", "line element 4", "zero length"),
        ("diag", "line element 5", "interior facet"),
        ("stray", "line element 6", "not a side of any body cell"),
    ] {
        let t = edit(
            &case_2d(&bad_facets()),
            "group = \"right\"",
            &format!("group = \"{group}\""),
        );
        rejected(
            &t,
            &[tag, what, &format!("\"{group}\""), "neumann[0].group"],
        );
    }
}

#[test]
fn mpirun_2_interior_load_group() {
    let t = edit(
        &case_2d(&bad_facets()),
        "group = \"right\"",
        "group = \"diag\"",
    );
    rejected_np(&t, 2, &["line element 5", "interior facet"]);
}

/// A case file of 6 MB cost 700 MB and 10 s; a 60 000-component --set key crashed (SIGSEGV).
#[test]
fn huge_case_file_and_deep_set_key() {
    let t = format!("{}junk = [{}]\n", case_2d(&square()), "1,".repeat(400_000));
    rejected(&t, &["case.toml", "larger than 256 KiB"]);
    let tmp = tempfile::tempdir().unwrap();
    let deep = format!("x.{}b=1", "a.".repeat(60_000));
    let r = run(tmp.path(), &case_2d(&square()), 0, &["--set", &deep]);
    r.expect_code(2, "deep --set key path");
    assert!(r.stderr.contains("components"), "{}", r.stderr);
}

/// A body force expression that is not finite somewhere in the body (here ln(x − 0.5) for
/// x ≤ 0.5 of the unit square): exit 2 naming the component, on 1 and on 2 ranks (where the
/// other rank's cells may all be fine).
#[test]
fn body_force_expression_not_finite() {
    let t = case_2d(&square()) + "\n[body_force]\nexpr = [\"0\", \"ln(x - 0.5)\"]\n";
    for np in [0, 2] {
        rejected_np(
            &t,
            np,
            &["body_force.expr[1]", "case.toml", "not a finite number"],
        );
    }
    // The same expression shifted out of the body is accepted.
    let ok = case_2d(&square()) + "\n[body_force]\nexpr = [\"0\", \"ln(x + 0.5)\"]\n";
    let tmp = tempfile::tempdir().unwrap();
    run(tmp.path(), &ok, 0, &[]).expect_code(0, "finite body force");
}

/// An error found once the mesh is read (here a body force expression that is not finite in
/// the body) names the line of its key in the case file, and says "(from --set)" where the key
/// came from the command line (before, such errors named neither).
#[test]
fn a_late_error_names_its_keys_line_or_its_set() {
    let t = case_2d(&square()) + "\n[body_force]\nexpr = [\"0\", \"ln(x - 0.5)\"]\n";
    let line = 1 + t.lines().position(|l| l.starts_with("expr = ")).unwrap();
    let message = rejected(&t, &["not a finite number"]);
    assert!(
        message.contains(&format!("case.toml:{line}: key 'body_force.expr[1]'")),
        "no line {line}: {message}"
    );
    let ok = case_2d(&square()) + "\n[body_force]\nexpr = [\"0\", \"0\"]\n";
    let tmp = tempfile::tempdir().unwrap();
    let r = run(
        tmp.path(),
        &ok,
        0,
        &["--set", "body_force.expr=[\"0\", \"ln(x - 0.5)\"]"],
    );
    r.expect_code(2, "a body force from --set that is not finite");
    assert!(
        r.stderr.contains("not a finite number") && r.stderr.contains("(from --set)"),
        "{}",
        r.stderr
    );
}

/// A body force expression in z on a 2D mesh: exit 2 naming the component.
#[test]
fn body_force_expression_variable_not_in_2d() {
    let t = case_2d(&square()) + "\n[body_force]\nexpr = [\"z\", \"0\"]\n";
    rejected(&t, &["body_force.expr[0]", "'z'", "2D"]);
}

/// Two contact groups of interior facets at the two ends of a strip
/// (tests/meshes/strip_cuts.geo): the message names the first group of the case and its
/// facet on every rank count (each rank checks its own facets; the lowest failing rank's
/// message named the second group from 2 ranks on).
#[test]
fn the_first_faulty_group_is_named_on_every_rank_count() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = tmp.path().join("strip_cuts.msh");
    gmsh("strip_cuts.geo", 2, 0.1, &mesh);
    let mut t = case_2d(&mesh);
    for g in ["cut1", "cut3"] {
        t += &format!(
            "[[contact]]\ngroup = \"{g}\"\nobstacle = {{ type = \"plane\", point = [0.0, -1.0], \
             normal = [0.0, 1.0] }}\n"
        );
    }
    let mut first: Option<String> = None;
    for np in [1, 2, 3, 4] {
        let msg = rejected_np(&t, np, &["\"cut1\"", "contact[0].group", "interior facet"]);
        // (each run has its own directory, which the message names)
        let (head, tail) = msg.split_once(" at ").expect("the case file's line");
        let tail = tail.rsplit_once("case.toml").expect("case.toml").1;
        let msg = format!("{head} {tail}");
        match &first {
            None => first = Some(msg),
            Some(m) => assert_eq!(&msg, m, "{np} ranks against 1"),
        }
    }
}

/// Three contact pairs on the strip's right, bottom and left sides: the bottom shares a corner
/// node with each of the others; the message names the shared node of smallest Gmsh tag on
/// every rank count (each rank names its own first one otherwise).
#[test]
fn a_node_on_two_pairs_groups_is_named_by_its_smallest_tag() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = tmp.path().join("strip_cuts.msh");
    gmsh("strip_cuts.geo", 2, 0.1, &mesh);
    let mut t = edit(&case_2d(&mesh), "group = \"right\"", "group = \"top\"");
    for (g, point, normal) in [
        ("right", "[5.0, 0.0]", "[-1.0, 0.0]"),
        ("bottom", "[0.0, -1.0]", "[0.0, 1.0]"),
        ("left", "[-1.0, 0.0]", "[1.0, 0.0]"),
    ] {
        t += &format!(
            "[[contact]]\ngroup = \"{g}\"\nobstacle = {{ type = \"plane\", point = {point}, \
             normal = {normal} }}\n"
        );
    }
    // (the Dirichlet data on "left" would take its nodes out of the contact: on "top")
    let t = edit(&t, "group = \"left\"\nvalue", "group = \"top\"\nvalue");
    for np in [1, 2, 3, 4] {
        rejected_np(
            &t,
            np,
            &["mesh node 1 at [0.0, 0.0]", "contact[2].group", "two pairs"],
        );
    }
}
