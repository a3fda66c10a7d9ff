//! The distributed HDF5 reader makes the cell checks of the MSH reader (issue 10): a cell of
//! zero area is an input error naming the file and the element (exit code 2, one message, on
//! 1 and 2 ranks), and inverted cells are turned around (results as with the unflipped file,
//! and the written topology positively oriented). The meshes are made by `signorini-mpi
//! convert` from the Hertz disk (refined level 2) and damaged with h5py.

mod common;
use common::*;

use std::path::{Path, PathBuf};

/// `signorini-mpi convert` of the Hertz disk (refined level 2) into `dir/ok.h5`.
fn converted(dir: &Path) -> PathBuf {
    converted_from(dir, "cases/hertz/meshes/hertz_refined_L2.msh")
}

/// `signorini-mpi convert` of the repository's mesh `rel` into `dir/ok.h5`.
fn converted_from(dir: &Path, rel: &str) -> PathBuf {
    let h5 = dir.join("ok.h5");
    let msh = repo(rel);
    convert(&msh, &h5);
    h5
}

/// A copy of `src` as `dst` with `edit` (Python, `c`: the /cells dataset as an array, `tags`:
/// /cell_tags) applied to the cells; returns what the script prints as RESULT.
fn damaged(src: &Path, dst: &Path, edit: &str) -> serde_json::Value {
    let script = format!(
        "import h5py, json, shutil, sys\n\
         shutil.copy(sys.argv[1], sys.argv[2])\n\
         f = h5py.File(sys.argv[2], 'r+')\n\
         c = f['cells'][:]\n\
         tags = f['cell_tags'][:]\n\
         out = {{}}\n\
         {edit}\n\
         f['cells'][:] = c\n\
         f.close()\n\
         print('RESULT ' + json.dumps(out))\n"
    );
    python_json(&script, &[src, dst])
}

/// The Hertz case on `mesh` into `out`.
fn run_on(np: usize, mesh: &Path, out: &Path) -> Run {
    run_solver(
        np,
        &repo("cases/hertz/hertz.toml"),
        &[&format!("mesh.file={}", toml_path(mesh))],
        out,
    )
}

#[test]
fn degenerate_cell_in_h5_is_an_input_error_naming_file_and_cell() {
    let dir = tempfile::tempdir().expect("tempdir");
    let ok = converted(dir.path());
    let bad = dir.path().join("degenerate.h5");
    // one cell gets its first node twice: zero area
    let r = damaged(
        &ok,
        &bad,
        "k = len(c) // 3\nc[k, 2] = c[k, 0]\nout['tag'] = int(tags[k])",
    );
    let tag = r["tag"].as_u64().expect("tag");
    for np in [1, 2] {
        let out = dir.path().join(format!("out{np}"));
        let run = run_on(np, &bad, &out);
        run.expect_code(2, &format!("degenerate cell on {np} rank(s)"));
        let text = run.output();
        let lines: Vec<&str> = text
            .lines()
            .filter(|l| l.contains("degenerate cell"))
            .collect();
        assert_eq!(lines.len(), 1, "one message on {np} rank(s):\n{text}");
        assert!(
            lines[0].contains("degenerate.h5") && lines[0].contains(&format!("element {tag} ")),
            "the message names the file and element {tag}:\n{text}"
        );
        assert!(!text.contains("panicked"), "{text}");
        assert!(!out.join("summary.json").exists(), "nothing written");
    }
}

#[test]
fn inverted_cells_in_h5_are_reoriented_as_in_msh() {
    let dir = tempfile::tempdir().expect("tempdir");
    let ok = converted(dir.path());
    let flip = dir.path().join("flipped.h5");
    let r = damaged(
        &ok,
        &flip,
        "c[::7, [1, 2]] = c[::7, [2, 1]]\nout['flipped'] = len(c[::7])",
    );
    assert!(r["flipped"].as_u64().expect("count") > 100);
    let negative = "import h5py, json, sys\n\
        f = h5py.File(sys.argv[1] + '/solution.h5', 'r')\n\
        t = f['mesh/topology'][:]; x = f['mesh/geometry'][:]\n\
        a = x[t[:, 1]] - x[t[:, 0]]; b = x[t[:, 2]] - x[t[:, 0]]\n\
        area = 0.5 * (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])\n\
        print('RESULT ' + json.dumps({'cells': len(t), 'not_positive': int((area <= 0).sum())}))\n";
    for np in [1, 2] {
        let mut csv = Vec::new();
        for (name, mesh) in [("ok", &ok), ("flipped", &flip)] {
            let out = dir.path().join(format!("{name}{np}"));
            run_on(np, mesh, &out).expect_code(0, &format!("{name} on {np} rank(s)"));
            let orient = python_json(negative, &[&out]);
            assert_eq!(
                orient["not_positive"].as_u64(),
                Some(0),
                "{name} on {np} rank(s): written cells not positively oriented: {orient}"
            );
            let rows = by_node_id(read_csv(&out.join("contact_nodes.csv")));
            csv.push(columns(&rows, &["u_n", "lambda_n", "gap"]));
        }
        let (diff, scale) = max_diff(&csv[0], &csv[1]);
        assert!(
            scale > 0.0 && diff <= 1e-10 * scale,
            "{np} rank(s): flipped cells change the contact result (max diff {diff:e}, scale {scale:e})"
        );
    }
}

/// The 3D block (tetrahedra), clamped at the bottom and pressed on top: a tetrahedron with a
/// repeated node is named, flipped tetrahedra are turned around (the same displacement by
/// node id, every written tetrahedron of positive volume). 2 ranks.
#[test]
fn tetrahedra_in_h5_are_checked_and_reoriented() {
    let dir = tempfile::tempdir().expect("tempdir");
    let ok = converted_from(dir.path(), "cases/blocks/block3d.msh");
    let case = repo("tests/cases/tresca/block3d_clamped.toml");
    let bad = dir.path().join("degenerate3d.h5");
    let r = damaged(
        &ok,
        &bad,
        "k = len(c) // 2\nc[k, 3] = c[k, 1]\nout['tag'] = int(tags[k])",
    );
    let tag = r["tag"].as_u64().expect("tag");
    let run = run_solver(
        2,
        &case,
        &[&format!("mesh.file={}", toml_path(&bad))],
        &dir.path().join("bad"),
    );
    run.expect_code(2, "degenerate tetrahedron");
    let text = run.output();
    assert!(
        text.lines()
            .filter(|l| l.contains("degenerate cell"))
            .count()
            == 1
            && text.contains(&format!("element {tag} has zero volume"))
            && text.contains("degenerate3d.h5"),
        "{text}"
    );

    let flip = dir.path().join("flipped3d.h5");
    damaged(&ok, &flip, "c[::5, [2, 3]] = c[::5, [3, 2]]");
    let state = "import h5py, json, sys, numpy as np\n\
        f = h5py.File(sys.argv[1] + '/solution.h5', 'r')\n\
        t = f['mesh/topology'][:]; x = f['mesh/geometry'][:]\n\
        a = x[t[:, 1]] - x[t[:, 0]]; b = x[t[:, 2]] - x[t[:, 0]]; c = x[t[:, 3]] - x[t[:, 0]]\n\
        vol = np.einsum('ij,ij->i', a, np.cross(b, c)) / 6\n\
        u = f['nodal/displacement'][:]; ids = f['mesh/node_id'][:]\n\
        order = np.argsort(ids)\n\
        print('RESULT ' + json.dumps({'not_positive': int((vol <= 0).sum()), \
        'u': u[order].ravel().tolist()}))\n";
    let mut us = Vec::new();
    for (name, mesh) in [("ok", &ok), ("flipped", &flip)] {
        let out = dir.path().join(name);
        run_solver(2, &case, &[&format!("mesh.file={}", toml_path(mesh))], &out)
            .expect_code(0, name);
        let r = python_json(state, &[&out]);
        assert_eq!(
            r["not_positive"].as_u64(),
            Some(0),
            "{name}: {}",
            r["not_positive"]
        );
        us.push(floats(&r["u"]));
    }
    let scale = norm(&us[0]);
    let diff: Vec<f64> = us[0].iter().zip(&us[1]).map(|(a, b)| a - b).collect();
    assert!(
        scale > 0.0 && norm(&diff) <= 1e-10 * scale,
        "flipped tetrahedra change u: |du| {:e}, |u| {scale:e}",
        norm(&diff)
    );
}
