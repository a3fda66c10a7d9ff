//! Case-file tests of the `height` and `surface` obstacles: every rejection names the key and
//! its line (and, for a surface, the STL file).

use super::*;
use crate::contact::surface::{icosphere, write_stl_ascii};
use crate::contact::ObstacleError;
use crate::error::InputError;
use std::path::{Path, PathBuf};

const FILE: &str = "/cases/plate.toml";

const MINIMAL_2D: &str = "[mesh]\nfile = \"m.msh\"\n\n[material]\nyoung = 2.0\npoisson = 0.3\n\
                          model = \"plane_strain\"\n";
const MINIMAL_3D: &str = "[mesh]\nfile = \"m.msh\"\n\n[material]\nyoung = 2.0\npoisson = 0.3\n";

fn case(base: &str, obstacle: &str) -> String {
    format!("{base}\n[contact]\ngroup = \"c\"\nobstacle = {obstacle}\n")
}

fn parse_at(text: &str, file: &Path) -> Result<Case, InputError> {
    Case::parse(text, file, &[], None)
}

/// 1-based line of the first line containing `needle`.
fn line(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("test bug")
        + 1
}

/// The error names `file` (the case file), `key` and the line of `needle`; one line.
fn check(e: &InputError, file: &Path, key: &str, text: &str, needle: &str) {
    assert_eq!(e.file, file, "{e}");
    assert_eq!(e.key.as_deref(), Some(key), "{e}");
    assert_eq!(e.line, Some(line(text, needle)), "{e}");
    let shown = e.to_string();
    assert!(shown.contains(key) && !shown.contains('\n'), "{shown}");
}

fn expect_err(text: &str, key: &str, needle: &str) -> InputError {
    let e = parse_at(text, Path::new(FILE)).expect_err("should be rejected");
    check(&e, Path::new(FILE), key, text, needle);
    e
}

#[test]
fn height_parsed_and_checked_against_the_mesh() {
    let text = case(
        MINIMAL_2D,
        "{ type = \"height\", expr = \"0.1*x^2 - 1e-3\" }",
    );
    let c = parse_at(&text, Path::new(FILE)).unwrap();
    let spec = &c.contacts.first().unwrap().obstacle;
    assert_eq!(spec.type_name(), "height");
    let ObstacleSpec::Height { expr } = spec else {
        panic!("{spec:?}")
    };
    assert!((expr.eval([2.0, 0.0]) - 0.399).abs() < 1e-15);
    let g2 = vec![("c".to_string(), 1)];
    c.check_against_mesh(2, &g2).unwrap();
    let o = spec.to_obstacle(2).unwrap();
    let q = o.project([0.0, 1.0, 0.0]).unwrap();
    assert!((q.gap - 1.001).abs() < 1e-12, "{q:?}");
    // y in a 2D expression: found against the mesh, named with the key and line.
    let text = case(MINIMAL_2D, "{ type = \"height\", expr = \"x*y\" }");
    let e = parse_at(&text, Path::new(FILE))
        .unwrap()
        .check_against_mesh(2, &g2)
        .unwrap_err();
    check(
        &e,
        Path::new(FILE),
        "contact.obstacle.expr",
        &text,
        "obstacle = ",
    );
    assert!(
        e.message.contains("'y'") && e.message.contains("y = h(x)"),
        "{e}"
    );
    // The same expression on a 3D mesh is fine.
    let text = case(MINIMAL_3D, "{ type = \"height\", expr = \"x*y\" }");
    parse_at(&text, Path::new(FILE))
        .unwrap()
        .check_against_mesh(3, &[("c".to_string(), 2)])
        .unwrap();
}

#[test]
fn reject_bad_heights() {
    for (obstacle, key, msg) in [
        (
            "{ type = \"height\", expr = \"sin(x\" }",
            "contact.obstacle.expr",
            "cannot parse the height expression \"sin(x\"",
        ),
        (
            "{ type = \"height\", expr = \"x + z\" }",
            "contact.obstacle.expr",
            "unknown variable 'z'",
        ),
        (
            "{ type = \"height\", expr = \"foo(x)\" }",
            "contact.obstacle.expr",
            "unknown function 'foo'",
        ),
        (
            "{ type = \"height\", expr = \"\" }",
            "contact.obstacle.expr",
            "the expression is empty",
        ),
        (
            "{ type = \"height\", expr = 3 }",
            "contact.obstacle.expr",
            "expected a string",
        ),
        (
            "{ type = \"height\" }",
            "contact.obstacle.expr",
            "missing required key",
        ),
        (
            "{ type = \"height\", expr = \"x\", file = \"a.stl\" }",
            "contact.obstacle.file",
            "allowed keys: type, expr",
        ),
    ] {
        let text = case(MINIMAL_2D, obstacle);
        let e = expect_err(&text, key, "obstacle = ");
        assert!(e.message.contains(msg), "{e}");
    }
    // In a section, the line of the key itself.
    let text = format!(
        "{MINIMAL_3D}\n[contact]\ngroup = \"c\"\n[contact.obstacle]\ntype = \"height\"\n\
         expr = \"x ^\"\n"
    );
    expect_err(&text, "contact.obstacle.expr", "expr = ");
}

/// A directory with a case file name and STL files written into it.
struct Dir {
    tmp: tempfile::TempDir,
}

impl Dir {
    fn new() -> Self {
        Dir {
            tmp: tempfile::tempdir().unwrap(),
        }
    }
    fn case_file(&self) -> PathBuf {
        self.tmp.path().join("case.toml")
    }
    fn stl(&self, name: &str, tris: &[[[f64; 3]; 3]]) {
        let mut f = std::fs::File::create(self.tmp.path().join(name)).unwrap();
        write_stl_ascii(&mut f, "t", tris).unwrap();
    }
    fn text(&self, name: &str, text: &str) {
        std::fs::write(self.tmp.path().join(name), text).unwrap();
    }
}

#[test]
fn surface_read_relative_to_the_case_file() {
    let d = Dir::new();
    d.stl("ball.stl", &icosphere([0.0, 0.0, 1.0], 0.5, 2));
    let text = case(MINIMAL_3D, "{ type = \"surface\", file = \"ball.stl\" }");
    let c = parse_at(&text, &d.case_file()).unwrap();
    let spec = &c.contacts.first().unwrap().obstacle;
    let ObstacleSpec::Surface { file, surface } = spec else {
        panic!("{spec:?}")
    };
    assert_eq!(file, &d.tmp.path().join("ball.stl"));
    assert_eq!(surface.num_triangles(), 320);
    c.check_against_mesh(3, &[("c".to_string(), 2)]).unwrap();
    let q = spec
        .to_obstacle(3)
        .unwrap()
        .project([0.0, 0.0, 0.0])
        .unwrap();
    // The bottom vertex of the icosphere is not a vertex: the gap lies within the chord
    // error (0.5 (1 − cos 16°) < 0.02) above the sphere's 0.5.
    assert!(q.gap >= 0.5 - 1e-12 && q.gap < 0.52, "{q:?}");
    // 3D only.
    let text = case(MINIMAL_2D, "{ type = \"surface\", file = \"ball.stl\" }");
    let c = parse_at(&text, &d.case_file()).unwrap();
    let e = c
        .check_against_mesh(2, &[("c".to_string(), 1)])
        .unwrap_err();
    check(
        &e,
        &d.case_file(),
        "contact.obstacle.type",
        &text,
        "obstacle = ",
    );
    assert!(e.message.contains("in 2D use \"height\""), "{e}");
    assert_eq!(spec.to_obstacle(2), Err(ObstacleError::Only3D("surface")));
}

#[test]
fn reject_bad_surfaces() {
    let d = Dir::new();
    let ball = icosphere([0.0; 3], 1.0, 1);
    d.stl("open.stl", &ball[1..]);
    let mut flipped = ball.clone();
    flipped[7].swap(0, 1);
    d.stl("flipped.stl", &flipped);
    let inside_out: Vec<_> = ball.iter().map(|t| [t[1], t[0], t[2]]).collect();
    d.stl("inside_out.stl", &inside_out);
    let mut degenerate = ball.clone();
    degenerate[4][2] = degenerate[4][1];
    d.stl("degenerate.stl", &degenerate);
    d.text(
        "junk.stl",
        "solid x\nfacet normal 0 0 1\nouter loop\nvertex 1 2\n",
    );
    d.text("empty.stl", "");
    for (file, msg) in [
        ("missing.stl", "cannot read the file"),
        ("open.stl", "the surface is not closed"),
        ("flipped.stl", "oriented inconsistently"),
        ("inside_out.stl", "inside-out"),
        ("degenerate.stl", "triangle 5 is degenerate"),
        ("junk.stl", "not a valid STL file: line 4"),
        ("empty.stl", "the file is empty"),
    ] {
        let text = case(
            MINIMAL_3D,
            &format!("{{ type = \"surface\", file = \"{file}\" }}"),
        );
        let e = parse_at(&text, &d.case_file()).expect_err(file);
        check(
            &e,
            &d.case_file(),
            "contact.obstacle.file",
            &text,
            "obstacle = ",
        );
        assert!(e.message.contains(msg), "{file}: {e}");
        assert!(e.message.contains(file), "names the STL file: {e}");
    }
    let text = case(MINIMAL_3D, "{ type = \"surface\" }");
    expect_err(&text, "contact.obstacle.file", "obstacle = ");
    let text = case(MINIMAL_3D, "{ type = \"surface\", file = \"\" }");
    expect_err(&text, "contact.obstacle.file", "obstacle = ");
}

#[test]
fn mesh_project_refuses_height_and_surface() {
    for shape in [
        "{ type = \"height\", expr = \"x\" }",
        "{ type = \"surface\", file = \"a.stl\" }",
    ] {
        let text = MINIMAL_3D.replace(
            "file = \"m.msh\"\n",
            &format!("file = \"m.msh\"\nrefine = 1\n\n[[mesh.project]]\ngroup = \"g\"\nshape = {shape}\n"),
        );
        let e = expect_err(&text, "mesh.project[0].shape.type", "shape = ");
        assert!(e.message.contains("contact obstacle only"), "{e}");
    }
}
