//! The `height` and `surface` obstacles end to end (docs/obstacles.md): a height that is a
//! plane solves the same problem as `type = "plane"` (2D and 3D), an STL sphere indenter lies
//! between the analytic spheres that bound it, the results do not depend on the number of
//! ranks, and bad input stops the run with exit code 2 and one message naming the key.

mod common;

use common::*;
use signorini_mpi::contact::surface::{icosphere, write_stl_ascii};
use std::path::{Path, PathBuf};

/// The box [-1,1]² × [0,0.5] of tests/meshes/indent_box.geo, size 0.06 at the top centre
/// (about 3100 tetrahedra).
fn box_mesh(dir: &Path) -> PathBuf {
    let out = dir.join("indent_box.msh");
    gmsh("indent_box.geo", 3, 0.06, &out);
    out
}

/// A 3D case on `mesh`: E = 1, ν = 0.3, Dirichlet `held` = value on `held_group`, contact on
/// `contact_group` against `obstacle`.
fn case_3d(
    mesh: &Path,
    held_group: &str,
    held: &str,
    contact_group: &str,
    obstacle: &str,
) -> String {
    format!(
        "[mesh]\nfile = {}\n[material]\nyoung = 1.0\npoisson = 0.3\nmodel = \"3d\"\n\
         [[dirichlet]]\ngroup = \"{held_group}\"\nvalue = {held}\n\
         [contact]\ngroup = \"{contact_group}\"\nobstacle = {obstacle}\n\
         [output]\nfields = [\"displacement\", \"contact\"]\n",
        toml_path(mesh)
    )
}

fn solve_text(np: usize, dir: &Path, name: &str, text: &str, sets: &[&str]) -> Solved {
    let case = write_case(&dir.join(format!("{name}.toml")), text);
    let s = solve(np, &case, sets);
    s.assert_converged(name);
    s
}

/// Relative difference of the total contact forces, against the larger.
fn force_diff(a: &Solved, b: &Solved) -> f64 {
    let (fa, fb) = (a.total_force(), b.total_force());
    let scale = norm(&fa).max(norm(&fb));
    assert!(scale > 0.0, "no contact force: nothing tested");
    let d: Vec<f64> = fa.iter().zip(&fb).map(|(x, y)| x - y).collect();
    norm(&d) / scale
}

/// A tilted plane as a height and as a plane: the gaps agree to round-off and the normals to
/// the central differences' truncation error (zero for a linear h, so round-off of h over the
/// step, ~1e-11), so the solutions agree to the solver's tolerance (rtol 1e-10). 2D: the block
/// of cases/blocks/block2d pressed down by its top onto y = 0.02 x − 0.005, partly in contact;
/// 3D: the box pressed onto z = 0.02 x − 0.01 y − 0.005, also on 2 ranks.
#[test]
fn height_plane_equals_plane() {
    let block = repo("tests/cases/block2d_pulled.toml");
    let down = "dirichlet.0.value=[0.0, -0.01]";
    let height = solve(
        1,
        &block,
        &[
            down,
            "contact.obstacle={type=\"height\", expr=\"0.02*x - 0.005\"}",
        ],
    );
    let plane = solve(
        1,
        &block,
        &[
            down,
            "contact.obstacle={type=\"plane\", point=[0.0, -0.005], normal=[-0.02, 1.0]}",
        ],
    );
    height.assert_converged("2D height");
    plane.assert_converged("2D plane");
    let active = plane.active_node_ids();
    let all = plane.contact_rows().len();
    assert!(
        !active.is_empty() && active.len() < all,
        "partial contact: {} of {all} active",
        active.len()
    );
    assert_eq!(height.active_node_ids(), active);
    let (du, df) = (height.u_rel_diff(&plane), force_diff(&height, &plane));
    println!(
        "2D: |Δu|/|u| = {du:.2e}, |ΔF|/|F| = {df:.2e}, {} of {all} active",
        active.len()
    );
    assert!(du < 1e-8 && df < 1e-8, "2D: Δu {du:e}, ΔF {df:e}");

    let tmp = tempfile::tempdir().unwrap();
    let mesh = box_mesh(tmp.path());
    let held = "[0.0, 0.0, -0.01]";
    let h = case_3d(
        &mesh,
        "top",
        held,
        "bottom",
        "{ type = \"height\", expr = \"0.02*x - 0.01*y - 0.005\" }",
    );
    let p = case_3d(
        &mesh,
        "top",
        held,
        "bottom",
        "{ type = \"plane\", point = [0, 0, -0.005], normal = [-0.02, 0.01, 1] }",
    );
    let h_text = h;
    let (h, p) = (
        solve_text(1, tmp.path(), "height3d", &h_text, &[]),
        solve_text(1, tmp.path(), "plane3d", &p, &[]),
    );
    let active = p.active_node_ids();
    let all = p.contact_rows().len();
    assert!(
        !active.is_empty() && active.len() < all,
        "{} of {all}",
        active.len()
    );
    assert_eq!(h.active_node_ids(), active);
    let (du, df) = (h.u_rel_diff(&p), force_diff(&h, &p));
    println!(
        "3D: |Δu|/|u| = {du:.2e}, |ΔF|/|F| = {df:.2e}, {} of {all} active",
        active.len()
    );
    assert!(du < 1e-8 && df < 1e-8, "3D: Δu {du:e}, ΔF {df:e}");
    let h2 = solve_text(2, tmp.path(), "height3d", &h_text, &[]);
    let du = h2.u_rel_diff(&h);
    println!("3D height 1 vs 2 ranks: |Δu|/|u| = {du:.2e}");
    assert!(du < 1e-8, "1 vs 2 ranks: {du:e}");
    assert_eq!(h2.active_node_ids(), active);
}

/// An icosphere (inscribed polyhedron, 20 480 triangles) of radius R pressed 0.04 into the box
/// against the analytic spheres: the polyhedron lies between the ball of radius R and the
/// concentric ball of radius R − sag (sag: the largest distance of a face plane inside the
/// sphere), so its gaps lie between theirs, node by node; without friction the pressed force
/// grows with the obstacle, and the STL force lies between the two spheres' forces. The band
/// is a few per cent wide (Hertz: F ∝ δ^{3/2}, 1.5 sag/δ ≈ 0.6 %) — allowed beyond it: 1e-3
/// of the force, for the faceted normals (the force is the sum of −λ along each node's own
/// normal, tilted by up to the facets' angle, 0.02 rad, from the sphere's). Then the same on
/// 2 ranks: the STL is read on each rank and the result is the same to the solver's tolerance.
#[test]
fn stl_sphere_between_the_analytic_spheres() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = box_mesh(tmp.path());
    let (r, zc) = (1.0, 0.5 + 1.0 - 0.04);
    let c = [0.0, 0.0, zc];
    let tris = icosphere(c, r, 5);
    let mut sag: f64 = 0.0;
    for [a, b, cc] in &tris {
        let n = signorini_mpi::geom::cross(
            signorini_mpi::geom::sub(*b, *a),
            signorini_mpi::geom::sub(*cc, *a),
        );
        let len = signorini_mpi::geom::dot(n, n).sqrt();
        let dist = signorini_mpi::geom::dot(signorini_mpi::geom::sub(*a, c), n) / len;
        sag = sag.max(r - dist);
    }
    assert!(sag > 0.0 && sag < 0.1 * 0.04, "sag {sag}");
    let stl = tmp.path().join("ball.stl");
    let mut f = std::fs::File::create(&stl).unwrap();
    write_stl_ascii(&mut f, "ball", &tris).unwrap();
    drop(f);
    let held = "[0.0, 0.0, 0.0]";
    let sphere =
        |radius: f64| format!("{{ type = \"sphere\", center = [0, 0, {zc}], radius = {radius} }}");
    let outer = case_3d(&mesh, "bottom", held, "top", &sphere(r));
    let inner = case_3d(&mesh, "bottom", held, "top", &sphere(r - sag));
    let faceted = case_3d(
        &mesh,
        "bottom",
        held,
        "top",
        "{ type = \"surface\", file = \"ball.stl\" }",
    );
    let outer = solve_text(1, tmp.path(), "outer", &outer, &[]);
    let inner = solve_text(1, tmp.path(), "inner", &inner, &[]);
    let stl_1 = solve_text(1, tmp.path(), "stl", &faceted, &[]);
    let fz = |s: &Solved| -s.total_force()[2];
    let (fo, fi, fs) = (fz(&outer), fz(&inner), fz(&stl_1));
    println!(
        "sag {sag:.3e}: F_z sphere R {fo:.6e}, STL {fs:.6e}, sphere R − sag {fi:.6e}; \
         active {} / {} / {}",
        outer.active_node_ids().len(),
        stl_1.active_node_ids().len(),
        inner.active_node_ids().len()
    );
    assert!(
        fi > 0.0 && fi < fo,
        "the smaller sphere presses less: {fi} vs {fo}"
    );
    assert!(
        fs >= fi * (1.0 - 1e-3) && fs <= fo * (1.0 + 1e-3),
        "STL force {fs} outside [{fi}, {fo}]"
    );
    // The gaps node by node: between the two spheres' (exact bounds, up to round-off).
    let (go, gi, gs) = (
        outer.contact_rows_by_id(),
        inner.contact_rows_by_id(),
        stl_1.contact_rows_by_id(),
    );
    assert_eq!(go.len(), gs.len());
    for (id, row) in &gs {
        let g = row.f("gap0");
        let (lo, hi) = (go[id].f("gap0"), gi[id].f("gap0"));
        assert!(
            g >= lo - 1e-12 && g <= hi + 1e-12,
            "node {id}: STL gap {g} outside [{lo}, {hi}]"
        );
    }
    let stl_2 = solve_text(2, tmp.path(), "stl", &faceted, &[]);
    let du = stl_2.u_rel_diff(&stl_1);
    println!("STL 1 vs 2 ranks: |Δu|/|u| = {du:.2e}");
    assert!(du < 1e-8, "1 vs 2 ranks: {du:e}");
    assert_eq!(stl_2.active_node_ids(), stl_1.active_node_ids());
}

/// Bad input found only with the mesh or at the contact nodes: exit code 2, one message naming
/// the key, nothing written. (Errors of the case file itself: src/case/tests_shapes.rs.)
#[test]
fn rejected_with_exit_code_2() {
    let tmp = tempfile::tempdir().unwrap();
    let block = repo("tests/cases/block2d_pulled.toml");
    let stl = tmp.path().join("ball.stl");
    let mut f = std::fs::File::create(&stl).unwrap();
    write_stl_ascii(&mut f, "ball", &icosphere([0.0, -1.0, 0.0], 0.5, 1)).unwrap();
    let surface = format!(
        "contact.obstacle={{type=\"surface\", file={}}}",
        toml_path(&stl)
    );
    let open_stl = tmp.path().join("open.stl");
    let mut f = std::fs::File::create(&open_stl).unwrap();
    write_stl_ascii(&mut f, "open", &icosphere([0.0, -1.0, 0.0], 0.5, 1)[1..]).unwrap();
    let open = format!(
        "contact.obstacle={{type=\"surface\", file={}}}",
        toml_path(&open_stl)
    );
    for (set, expect) in [
        // h not defined at the contact nodes (x < 0 on the block's bottom).
        (
            "contact.obstacle={type=\"height\", expr=\"sqrt(x) - 1\"}",
            vec![
                "contact.obstacle",
                "contact.obstacle.expr",
                "not a finite number",
            ],
        ),
        // y in a 2D expression.
        (
            "contact.obstacle={type=\"height\", expr=\"x*y\"}",
            vec!["contact.obstacle.expr", "'y'"],
        ),
        // A ridge under the block: the bottom nodes with |x| < 0.25 are nearest to its edge,
        // which has no normal.
        (
            "contact.obstacle={type=\"height\", expr=\"-0.05 - 5*abs(x)\"}",
            vec!["contact.obstacle.expr", "smooth (C¹)"],
        ),
        // A surface on a 2D mesh.
        (
            surface.as_str(),
            vec!["contact.obstacle.type", "3D", "in 2D use \"height\""],
        ),
        // An open surface: found when the case is read.
        (
            open.as_str(),
            vec!["contact.obstacle.file", "open.stl", "not closed"],
        ),
    ] {
        let out = tmp.path().join("out");
        // The errors found at the contact nodes on 2 ranks too: every rank stops, one message.
        let np = if set.contains("abs(x)") { 2 } else { 1 };
        let r = run_solver(np, &block, &[set], &out);
        r.expect_code(2, set);
        let errors: Vec<&str> = r
            .stderr
            .lines()
            .filter(|l| l.starts_with("error"))
            .collect();
        assert_eq!(errors.len(), 1, "one message for {set}:\n{}", r.stderr);
        println!("rejected: {}", errors[0]);
        for e in &expect {
            assert!(
                errors[0].contains(e),
                "{set}: message lacks {e:?}: {}",
                errors[0]
            );
        }
        assert!(!out.exists(), "{set}: output written");
    }
}
