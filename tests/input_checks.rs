//! Bad input refused before anything is solved or written: exit code 2, one message naming the
//! file and the key (or the mesh node, element or group), the same message on 1, 2 and 3
//! ranks. One section per kind of input.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The unit square of tests/meshes/square_h0.5.msh (nodes 1–12, lines 1–8, triangles 9–22;
/// groups bottom, right, top, left, body) as text.
fn square_text() -> String {
    std::fs::read_to_string(mesh_dir().join("square_h0.5.msh")).expect("square_h0.5.msh")
}

/// Replaces `from` (which must occur) by `to`, once.
fn edit(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "{from:?} not in the text");
    text.replacen(from, to, 1)
}

/// A 2D case on `mesh`: clamped on `left`, a traction on `right`, then `extra`.
fn case_on(mesh: &Path, extra: &str) -> String {
    format!(
        "[mesh]\nfile = {}\n\n[material]\nyoung = 1.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\n\
         [[dirichlet]]\ngroup = \"left\"\nvalue = [0.0, 0.0]\n\n\
         [[neumann]]\ngroup = \"right\"\ntraction = [1.0, 0.0]\n{extra}",
        toml_path(mesh)
    )
}

/// Runs `text` as `dir/case.toml` on 1, 2 and 3 ranks: each run exits with 2, prints one
/// error line holding every `expect` substring, the same line on every rank count, and writes
/// nothing (the directory as before). Returns the message.
fn refused_everywhere(dir: &Path, text: &str, expect: &[&str]) -> String {
    let case = write_case(&dir.join("case.toml"), text);
    let before = file_names(dir);
    let out = dir.join("out");
    let args = [
        case.display().to_string(),
        "-o".into(),
        out.display().to_string(),
    ];
    let mut first: Option<String> = None;
    for np in [1, 2, 3] {
        let r = run_with_timeout(solver(np, &args), Duration::from_secs(120));
        let msg = r
            .the_error_line(&format!("bad input on {np} rank(s)"))
            .to_string();
        println!("refused ({np} ranks): {msg}");
        for e in expect {
            assert!(msg.contains(e), "message lacks {e:?}: {msg}");
        }
        assert!(!msg.contains("panick"), "{msg}");
        assert_eq!(file_names(dir), before, "something was written ({msg})");
        match &first {
            None => first = Some(msg),
            Some(m) => assert_eq!(&msg, m, "{np} ranks against 1"),
        }
    }
    first.expect("a message")
}

/// Writes `text` as `dir/name`.
fn mesh_file(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write the mesh");
    p
}

/// `signorini-mpi convert` of the unit square of mesh size 0.1 into `dir/ok.h5`, copied to
/// `dir/name` with `edit` (Python; `f`: the file open for writing, `out`: a dict printed as
/// RESULT) applied. Returns the copy and RESULT.
fn h5_edited(dir: &Path, name: &str, edit: &str) -> (PathBuf, serde_json::Value) {
    let h5 = dir.join("ok.h5");
    if !h5.exists() {
        let msh = unit_mesh(dir, 2, 0.1);
        convert(&msh, &h5);
    }
    let dst = dir.join(name);
    let script = format!(
        "import h5py, json, shutil, sys\n\
         import numpy as np\n\
         shutil.copy(sys.argv[1], sys.argv[2])\n\
         f = h5py.File(sys.argv[2], 'r+')\n\
         out = {{}}\n\
         {edit}\n\
         f.close()\n\
         print('RESULT ' + json.dumps(out))\n"
    );
    let out = python_json(&script, &[&h5, &dst]);
    (dst, out)
}

// ---- A: a body that nothing holds ----

/// A single body with no Dirichlet data and no contact pair (a pressure on its top) is free
/// in all its rigid modes: refused before the solve (it was solved, |u| ~ 1e13).
#[test]
fn a_free_body_without_contact_pairs_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = mesh_dir().join("square_h0.25.msh");
    let text = format!(
        "[mesh]\nfile = {}\n[material]\nyoung = 1.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\
         [[neumann]]\ngroup = \"top\"\npressure = 0.1\n",
        toml_path(&mesh)
    );
    refused_everywhere(
        tmp.path(),
        &text,
        &[
            "square_h0.25.msh",
            "key 'dirichlet'",
            "3 rigid mode(s)",
            "the case has no contact pair",
            "nothing holds it",
        ],
    );
    // one rigid mode left free (u_y held on the bottom alone: x free) is refused as well
    let text = text + "[[dirichlet]]\ngroup = \"bottom\"\nvalue = [\"free\", 0.0]\n";
    refused_everywhere(tmp.path(), &text, &["1 rigid mode(s)", "nothing holds it"]);
}

/// Two squares (tests/meshes/two_squares.geo), the first clamped, the second free, no contact
/// pair: refused naming the free body by its smallest node tag (it was solved).
#[test]
fn a_free_body_beside_a_held_one_without_contact_pairs_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = tmp.path().join("two_squares.msh");
    gmsh("two_squares.geo", 2, 0.1, &mesh);
    let text = format!(
        "[mesh]\nfile = {}\n[material]\nyoung = 1.0\npoisson = 0.3\nmodel = \"plane_strain\"\n\
         [[dirichlet]]\ngroup = \"left_a\"\nvalue = [0.0, 0.0]\n\
         [[neumann]]\ngroup = \"top\"\npressure = 0.01\n",
        toml_path(&mesh)
    );
    refused_everywhere(
        tmp.path(),
        &text,
        &[
            "2 separate bodies",
            "from node tag",
            "the case has no contact pair",
            "nothing holds it",
        ],
    );
    // both held: solved
    let held = text + "[[dirichlet]]\ngroup = \"left_b\"\nvalue = [0.0, 0.0]\n";
    let case = write_case(&tmp.path().join("held.toml"), &held);
    let args = [
        case.display().to_string(),
        "-o".into(),
        tmp.path().join("out").display().to_string(),
    ];
    run_with_timeout(solver(2, &args), Duration::from_secs(120)).expect_code(0, "both held");
}

// ---- B: tags defined twice ----

/// Node 12 defined a second time (another block of $Nodes, or node 12 written as 11 in the
/// same block), and the square's triangle 21 written with the tag 20 of another triangle, or
/// its line 8 with the tag 9 of a triangle: refused naming the file and the tag, by the run and
/// by `convert` (last definition won).
#[test]
fn msh_tags_defined_twice_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let sq = square_text();
    let twice = edit(&sq, "9 12 1 12\n", "10 13 1 12\n");
    let twice = edit(&twice, "$EndNodes", "2 1 0 1\n12\n0.9 0.9 0\n$EndNodes");
    let nodes = mesh_file(tmp.path(), "dup_node.msh", &twice);
    // twice in one block, its tags sparse (the largest tag 13): node 12 written as 11
    let one_block = edit(&sq, "9 12 1 12\n", "9 12 1 13\n");
    let one_block = edit(&one_block, "11\n12\n0.29", "11\n11\n0.29");
    let in_block = mesh_file(tmp.path(), "dup_in_block.msh", &one_block);
    let tri = mesh_file(
        tmp.path(),
        "dup_cell.msh",
        &edit(&sq, "21 11 10 12 \n", "20 11 10 12 \n"),
    );
    let line = mesh_file(
        tmp.path(),
        "dup_line.msh",
        &edit(&sq, "8 8 1 \n", "9 8 1 \n"),
    );
    for (mesh, expect) in [
        (&nodes, "node tag 12 is defined more than once in $Nodes"),
        (&in_block, "node tag 11 is defined more than once in $Nodes"),
        (
            &tri,
            "element tag 20 is defined more than once in $Elements",
        ),
        (
            &line,
            "element tag 9 is defined more than once in $Elements",
        ),
    ] {
        let name = mesh.file_name().unwrap().to_str().unwrap();
        refused_everywhere(tmp.path(), &case_on(mesh, ""), &[name, expect]);
        let args = [
            "convert".to_string(),
            mesh.display().to_string(),
            tmp.path().join("x.h5").display().to_string(),
        ];
        let r = run_with_timeout(solver(0, &args), Duration::from_secs(60));
        r.expect_code(2, "convert of a mesh with a tag twice");
        assert!(r.stderr.contains(expect), "{}", r.output());
        assert!(!tmp.path().join("x.h5").exists());
    }
}

/// An HDF5 mesh (read in blocks, one per rank) with two node tags, or two cell tags, each
/// defined twice, the copies far apart in the file (on different ranks' blocks): the smaller
/// duplicated tag is named on every rank count.
#[test]
fn h5_tags_defined_twice_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    for (name, dataset, what) in [
        ("dup_node.h5", "node_tags", "node"),
        ("dup_cell.h5", "cell_tags", "element"),
    ] {
        let (h5, out) = h5_edited(
            tmp.path(),
            name,
            &format!(
                "t = f['{dataset}'][:]\n\
                 n = len(t)\n\
                 t[n - 1] = t[1]\n\
                 t[n - 2] = t[n // 2]\n\
                 f['{dataset}'][:] = t\n\
                 out['tag'] = int(min(t[1], t[n // 2]))"
            ),
        );
        let tag = out["tag"].as_u64().expect("the tag");
        let expect = format!("{what} tag {tag} is defined more than once in /");
        refused_everywhere(tmp.path(), &case_on(&h5, ""), &[name, &expect]);
    }
}

// ---- C: empty and ambiguous groups ----

/// A group named in $PhysicalNames without elements, as Dirichlet, Neumann or contact group:
/// refused naming the key and the group (it was accepted and did nothing).
#[test]
fn an_empty_group_is_refused_where_a_case_uses_it() {
    let tmp = tempfile::tempdir().unwrap();
    let text = edit(
        &square_text(),
        "5\n1 1 \"bottom\"",
        "6\n1 6 \"ghost\"\n1 1 \"bottom\"",
    );
    let mesh = mesh_file(tmp.path(), "empty_group.msh", &text);
    let contact = "[contact]\ngroup = \"ghost\"\n\
                   obstacle = { type = \"plane\", point = [0.0, -0.1], normal = [0.0, 1.0] }\n";
    let dirichlet = "[[dirichlet]]\ngroup = \"ghost\"\nvalue = [0.0, 0.0]\n";
    let neumann = "[[neumann]]\ngroup = \"ghost\"\npressure = 0.1\n";
    for (extra, key, what) in [
        (contact, "contact.group", "has no facets"),
        (dirichlet, "dirichlet[1].group", "has no elements"),
        (neumann, "neumann[1].group", "has no facets"),
    ] {
        refused_everywhere(
            tmp.path(),
            &case_on(&mesh, extra),
            &["case.toml", key, "\"ghost\"", what],
        );
    }
}

/// The name "body" given to the surface group and to a curve group (the top): a Dirichlet,
/// Neumann or contact group of that name is refused as ambiguous (Dirichlet data held both).
#[test]
fn a_group_name_of_two_dimensions_is_refused_where_a_case_uses_it() {
    let tmp = tempfile::tempdir().unwrap();
    let text = edit(&square_text(), "1 3 \"top\"", "1 3 \"body\"");
    let mesh = mesh_file(tmp.path(), "two_dims.msh", &text);
    let dirichlet = "[[dirichlet]]\ngroup = \"body\"\nvalue = [0.0, -0.01]\n";
    let neumann = "[[neumann]]\ngroup = \"body\"\npressure = 0.1\n";
    for (extra, key) in [
        (dirichlet, "dirichlet[1].group"),
        (neumann, "neumann[1].group"),
    ] {
        refused_everywhere(
            tmp.path(),
            &case_on(&mesh, extra),
            &[
                key,
                "\"body\"",
                "a curve group (1D) and a surface group (2D)",
                "ambiguous",
            ],
        );
    }
}

// ---- D: a body force that is not finite ----

/// The smallest triangle tag of an ASCII MSH 4.1 file (its element blocks of type 2).
fn smallest_triangle_tag(msh: &str) -> u64 {
    let body = msh.split("$Elements\n").nth(1).expect("$Elements");
    let mut lines = body.lines().skip(1);
    let mut least = u64::MAX;
    while let Some(header) = lines.next() {
        if header.starts_with("$End") {
            break;
        }
        let h: Vec<usize> = header
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        for _ in 0..h[3] {
            let tag: u64 = lines
                .next()
                .unwrap()
                .split_whitespace()
                .next()
                .unwrap()
                .parse()
                .unwrap();
            if h[2] == 2 {
                least = least.min(tag);
            }
        }
    }
    least
}

/// A body force that is not finite in every cell (1/(x − x)) or in part of the body
/// (sqrt(0.5 − x), ln(x − 0.3)): the message names the faulty cell of smallest tag on every rank
/// count (each rank named its own first cell).
#[test]
fn a_body_force_that_is_not_finite_is_named_by_its_smallest_cell() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = tmp.path().join("square.msh");
    gmsh("square.geo", 2, 0.1, &mesh);
    let all = smallest_triangle_tag(&std::fs::read_to_string(&mesh).unwrap());
    let expr = "[body_force]\nexpr = [\"0\", \"1/(x - x)\"]\n";
    refused_everywhere(
        tmp.path(),
        &case_on(&mesh, expr),
        &[
            "body_force.expr[1]",
            "not a finite number",
            &format!("a quadrature point of cell {all})"),
        ],
    );
    for expr in ["[\"sqrt(0.5 - x)\", \"0\"]", "[\"0\", \"ln(x - 0.3)\"]"] {
        let msg = refused_everywhere(
            tmp.path(),
            &case_on(&mesh, &format!("[body_force]\nexpr = {expr}\n")),
            &["body_force.expr[", "not a finite number", "of cell "],
        );
        println!("{msg}");
    }
}

// ---- E: a node coordinate that is not a number ----

/// A node with a NaN coordinate (MSH, and the HDF5 form, read in blocks): the node is named,
/// not a degenerate cell.
#[test]
fn a_node_coordinate_that_is_not_finite_names_the_node() {
    let tmp = tempfile::tempdir().unwrap();
    let text = edit(
        &square_text(),
        "0.7187499999993462 0.2812499999995109 0",
        "nan 0.2812499999995109 0",
    );
    let mesh = mesh_file(tmp.path(), "nan_node.msh", &text);
    let msg = refused_everywhere(
        tmp.path(),
        &case_on(&mesh, ""),
        &[
            "nan_node.msh",
            "node 12 has a coordinate that is not a finite number",
        ],
    );
    assert!(!msg.contains("degenerate"), "{msg}");
    let (h5, out) = h5_edited(
        tmp.path(),
        "nan_node.h5",
        "c = f['coordinates'][:]\n\
         n = len(c)\n\
         c[n - 1, 1] = np.nan\n\
         c[n // 3, 0] = np.inf\n\
         f['coordinates'][:] = c\n\
         t = f['node_tags'][:]\n\
         out['tag'] = int(min(t[n - 1], t[n // 3]))",
    );
    let tag = out["tag"].as_u64().expect("the tag");
    let msg = refused_everywhere(
        tmp.path(),
        &case_on(&h5, ""),
        &[
            "nan_node.h5",
            &format!("node {tag} has a coordinate that is not a finite number"),
        ],
    );
    assert!(!msg.contains("degenerate"), "{msg}");
}

// ---- F: force control with a zero force at a load factor ----

/// A ramped vector force is zero at the load factor 0: a history that solves there is refused
/// up front, as the same history as a table is (it ran two steps and failed with exit code 1).
#[test]
fn a_ramped_vector_force_at_the_load_factor_0_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = mesh_dir().join("square_h0.5.msh");
    let pair = |force: &str| {
        format!(
            "[contact]\ngroup = \"bottom\"\n\
             obstacle = {{ type = \"plane\", point = [0.0, -0.1], normal = [0.0, 1.0] }}\n\
             force = {force}\n[load]\nfactors = [0.5, 1.0, 0.0]\n"
        )
    };
    for force in [
        "[0.001, 0.003]",
        "{ value = [0.001, 0.003] }",
        "{ table = [[0.0, 0.0, 0.0], [1.0, 0.001, 0.003]] }",
    ] {
        refused_everywhere(
            tmp.path(),
            &case_on(&mesh, &pair(force)),
            &[
                "contact.force",
                "gives a zero force at the load factor 0 of the run",
                "needs a direction",
            ],
        );
    }
    // held at F in every step: accepted by the case reader
    let held = case_on(&mesh, &pair("{ value = [0.001, 0.003], ramp = false }"));
    let case = write_case(&tmp.path().join("held.toml"), &held);
    let args = ["check".to_string(), case.display().to_string()];
    let r = run_with_timeout(solver(0, &args), Duration::from_secs(120));
    assert!(
        !r.stderr.contains("zero force"),
        "a held force is refused:\n{}",
        r.output()
    );
}
