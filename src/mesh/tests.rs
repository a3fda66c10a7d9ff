use super::*;
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::PathBuf;

fn mesh_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/meshes")
        .join(name)
}

fn read(name: &str) -> Mesh {
    read_msh(&mesh_path(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// A hand-written MSH 4.1 ASCII file: surface entity 1 in physical groups 1 "body" and
/// 2 "steel"; curve entity 1 in physical group 1 "edge" (tag 1 again, other dimension);
/// point entity 1 in physical group 3 "corner".
fn hand_msh(
    nodes: &[(u64, [f64; 3])],
    tris: &[(u64, [u64; 3])],
    lines: &[(u64, [u64; 2])],
    points: &[(u64, u64)],
) -> String {
    let mut s = String::from(
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n4\n0 3 \"corner\"\n\
         1 1 \"edge\"\n2 1 \"body\"\n2 2 \"steel\"\n$EndPhysicalNames\n$Entities\n1 1 1 0\n\
         1 0 0 0 1 3\n1 0 0 0 1 1 0 1 1 0\n1 0 0 0 1 1 0 2 1 2 0\n$EndEntities\n",
    );
    let (nmin, nmax) = (
        nodes.iter().map(|n| n.0).min().unwrap(),
        nodes.iter().map(|n| n.0).max().unwrap(),
    );
    s += &format!(
        "$Nodes\n1 {} {nmin} {nmax}\n2 1 0 {}\n",
        nodes.len(),
        nodes.len()
    );
    for n in nodes {
        s += &format!("{}\n", n.0);
    }
    for n in nodes {
        s += &format!("{} {} {}\n", n.1[0], n.1[1], n.1[2]);
    }
    s += "$EndNodes\n";
    let all: Vec<u64> = tris
        .iter()
        .map(|t| t.0)
        .chain(lines.iter().map(|l| l.0))
        .chain(points.iter().map(|p| p.0))
        .collect();
    let nblocks = [!tris.is_empty(), !lines.is_empty(), !points.is_empty()]
        .iter()
        .filter(|&&b| b)
        .count();
    s += &format!(
        "$Elements\n{nblocks} {} {} {}\n",
        all.len(),
        all.iter().min().unwrap(),
        all.iter().max().unwrap()
    );
    if !points.is_empty() {
        s += &format!("0 1 15 {}\n", points.len());
        for p in points {
            s += &format!("{} {}\n", p.0, p.1);
        }
    }
    if !lines.is_empty() {
        s += &format!("1 1 1 {}\n", lines.len());
        for l in lines {
            s += &format!("{} {} {}\n", l.0, l.1[0], l.1[1]);
        }
    }
    if !tris.is_empty() {
        s += &format!("2 1 2 {}\n", tris.len());
        for t in tris {
            s += &format!("{} {} {} {}\n", t.0, t.1[0], t.1[1], t.1[2]);
        }
    }
    s += "$EndElements\n";
    s
}

fn write_tmp(dir: &tempfile::TempDir, name: &str, text: &str) -> PathBuf {
    let p = dir.path().join(name);
    let mut f = std::fs::File::create(&p).unwrap();
    f.write_all(text.as_bytes()).unwrap();
    p
}

fn read_text(text: &str) -> Result<Mesh, InputError> {
    let dir = tempfile::tempdir().unwrap();
    let p = write_tmp(&dir, "m.msh", text);
    read_msh(&p)
}

fn unit_square_nodes() -> Vec<(u64, [f64; 3])> {
    vec![
        (1, [0.0, 0.0, 0.0]),
        (2, [1.0, 0.0, 0.0]),
        (3, [1.0, 1.0, 0.0]),
        (4, [0.0, 1.0, 0.0]),
    ]
}

/// Set of boundary edges (sorted node pairs) of a 2D mesh: edges used by exactly one cell.
fn boundary_edges_2d(m: &Mesh) -> BTreeSet<(usize, usize)> {
    let mut count: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    for c in 0..m.n_cells() {
        let v = m.cell(c);
        for (a, b) in [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])] {
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    count
        .into_iter()
        .filter(|&(_, n)| n == 1)
        .map(|(e, _)| e)
        .collect()
}

fn facet_measure(m: &Mesh, f: usize) -> f64 {
    let v = m.facet(f);
    let p: Vec<[f64; 3]> = v.iter().map(|&n| m.coords[n]).collect();
    if m.dim == 2 {
        norm2(sub(p[1], p[0])).sqrt()
    } else {
        let a = sub(p[1], p[0]);
        let b = sub(p[2], p[0]);
        let c = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        0.5 * norm2(c).sqrt()
    }
}

#[test]
fn ascii_and_binary_give_the_same_mesh() {
    for (a, b) in [
        ("square_h0.25.msh", "square_h0.25_bin.msh"),
        ("cube_h0.5.msh", "cube_h0.5_bin.msh"),
    ] {
        let ma = read(a);
        let mb = read(b);
        assert!(ma.n_cells() > 0);
        assert_eq!(ma.dim, mb.dim);
        // ASCII has 16 significant digits, binary is exact.
        assert_eq!(ma.n_nodes(), mb.n_nodes());
        for (p, q) in ma.coords.iter().zip(&mb.coords) {
            for k in 0..3 {
                assert!((p[k] - q[k]).abs() < 1e-14, "{a} vs {b}: {p:?} {q:?}");
            }
        }
        assert_eq!(ma.node_tags, mb.node_tags);
        assert_eq!(ma.cells, mb.cells);
        assert_eq!(ma.cell_tags, mb.cell_tags);
        assert_eq!(ma.facets, mb.facets);
        assert_eq!(ma.facet_tags, mb.facet_tags);
        assert_eq!(ma.edges, mb.edges);
        assert_eq!(ma.points, mb.points);
        assert_eq!(ma.groups, mb.groups);
    }
}

/// The side groups of the unit square or cube `m` (file `name`): each of the facets' dimension,
/// not empty, its nodes on its side (to `tol`), its measure 1; every facet in one side.
fn unit_sides(m: &Mesh, name: &str, tol: f64) {
    let sides = [
        ("left", 0, 0.0),
        ("right", 0, 1.0),
        ("bottom", 1, 0.0),
        ("top", 1, 1.0),
        ("front", 2, 0.0),
        ("back", 2, 1.0),
    ];
    let mut in_groups = vec![0usize; m.n_facets()];
    for (side, axis, value) in &sides[..2 * m.dim] {
        let g = m.group(side).unwrap();
        assert_eq!(g.dim, m.dim - 1);
        assert!(!g.elements.is_empty());
        let mut measure = 0.0;
        for &f in &g.elements {
            in_groups[f] += 1;
            measure += facet_measure(m, f);
        }
        assert!(
            (measure - 1.0).abs() < 1e-12,
            "{name}: {side} measure {measure}"
        );
        for n in m.group_nodes(g) {
            assert!((m.coords[n][*axis] - value).abs() <= tol, "{name}: {side}");
        }
    }
    assert!(in_groups.iter().all(|&k| k == 1), "{name}");
}

#[test]
fn unit_square_area_and_groups() {
    for name in [
        "square_h0.25.msh",
        "square_h0.5.msh",
        "square_h0.25_bin.msh",
    ] {
        let m = read(name);
        assert_eq!(m.dim, 2);
        assert_eq!(m.nodes_per_cell(), 3);
        let area: f64 = (0..m.n_cells()).map(|c| m.cell_measure(c)).sum();
        assert!((area - 1.0).abs() < 1e-12, "{name}: area {area}");
        assert!((0..m.n_cells()).all(|c| m.cell_measure(c) > 0.0));
        assert!(m.coords.iter().all(|p| p[2] == 0.0));
        assert_eq!(m.cells.len(), 3 * m.n_cells());
        assert!(m.cells.iter().all(|&n| n < m.n_nodes()));

        let names: BTreeSet<String> = m.group_names().into_iter().collect();
        let expected: BTreeSet<String> = ["left", "right", "bottom", "top", "body"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        assert_eq!(names, expected);
        let body = m.group("body").unwrap();
        assert_eq!(body.dim, 2);
        assert_eq!(body.elements, (0..m.n_cells()).collect::<Vec<_>>());
        assert_eq!(m.group_nodes(body), (0..m.n_nodes()).collect::<Vec<_>>());

        // Each side: facets on the right line, total length 1.
        unit_sides(&m, name, 0.0);
        // The facets are exactly the boundary edges of the cells.
        let facets: BTreeSet<(usize, usize)> = (0..m.n_facets())
            .map(|f| {
                let v = m.facet(f);
                (v[0].min(v[1]), v[0].max(v[1]))
            })
            .collect();
        assert_eq!(facets.len(), m.n_facets());
        assert_eq!(facets, boundary_edges_2d(&m));
    }
}

#[test]
fn unit_cube_volume_and_groups() {
    for name in ["cube_h0.5.msh", "cube_h0.25.msh", "cube_h0.5_bin.msh"] {
        let m = read(name);
        assert_eq!(m.dim, 3);
        assert_eq!(m.nodes_per_cell(), 4);
        let vol: f64 = (0..m.n_cells()).map(|c| m.cell_measure(c)).sum();
        assert!((vol - 1.0).abs() < 1e-12, "{name}: volume {vol}");
        assert!((0..m.n_cells()).all(|c| m.cell_measure(c) > 0.0));
        let body = m.group("body").unwrap();
        assert_eq!(body.dim, 3);
        assert_eq!(body.elements.len(), m.n_cells());
        unit_sides(&m, name, 1e-12);
        assert_eq!(m.group_names().len(), 7);
    }
}

#[test]
fn hand_written_groups_by_dim_and_tag() {
    let text = hand_msh(
        &unit_square_nodes(),
        &[(10, [1, 2, 3]), (11, [1, 3, 4])],
        &[(20, [1, 2])],
        &[(30, 4)],
    );
    let m = read_text(&text).unwrap();
    assert_eq!(m.n_cells(), 2);
    assert_eq!(m.cell_tags, vec![10, 11]);
    // Physical tag 1 names "body" in 2D and "edge" in 1D.
    let body = m.group_dim("body", 2).unwrap();
    assert_eq!((body.tag, body.elements.clone()), (1, vec![0, 1]));
    let steel = m.group("steel").unwrap();
    assert_eq!(
        (steel.dim, steel.tag, steel.elements.clone()),
        (2, 2, vec![0, 1])
    );
    let edge = m.group("edge").unwrap();
    assert_eq!((edge.dim, edge.tag), (1, 1));
    assert_eq!(edge.elements, vec![0]);
    assert_eq!(m.facet_tags, vec![20]);
    assert_eq!(m.group_nodes(edge), vec![0, 1]);
    let corner = m.group("corner").unwrap();
    assert_eq!(corner.dim, 0);
    assert_eq!(m.group_nodes(corner), vec![3]);
    assert_eq!(m.points, vec![3]);
    assert!(m.group("nothing").is_none());
}

#[test]
fn inverted_cell_is_reoriented() {
    // Cell 11 = (1,4,3) is clockwise.
    let text = hand_msh(
        &unit_square_nodes(),
        &[(10, [1, 2, 3]), (11, [1, 4, 3])],
        &[],
        &[],
    );
    let m = read_text(&text).unwrap();
    for c in 0..2 {
        assert!((m.cell_measure(c) - 0.5).abs() < 1e-15);
    }
    // Same node set as in the file.
    let mut v = m.cell(1).to_vec();
    v.sort_unstable();
    assert_eq!(v, vec![0, 2, 3]);
    assert_eq!(m.cell(0), &[0, 1, 2]);
}

#[test]
fn inverted_tetrahedron_is_reoriented() {
    let text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 1\n\
        1 0 0 0 1 1 1 1 7 0\n$EndEntities\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n\
        0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n1 1 5 5\n3 1 4 1\n5 1 3 2 4\n\
        $EndElements\n";
    let m = read_text(text).unwrap();
    assert_eq!(m.dim, 3);
    assert!((m.cell_measure(0) - 1.0 / 6.0).abs() < 1e-15);
    assert_eq!(m.groups.len(), 1);
    assert_eq!(m.groups[0].name, "7"); // unnamed group: its tag
}

#[test]
fn zero_area_cell_is_rejected_with_its_tag() {
    let mut nodes = unit_square_nodes();
    nodes.push((5, [0.5, 0.0, 0.0]));
    let text = hand_msh(&nodes, &[(10, [1, 2, 3]), (17, [1, 5, 2])], &[], &[]);
    let e = read_text(&text).unwrap_err();
    assert!(e.message.contains("element 17"), "{e}");
    assert!(e.message.contains("zero area"), "{e}");
}

#[test]
fn node_tags_sparse_and_unused_nodes_dropped() {
    let nodes = vec![
        (40, [0.0, 1.0, 0.0]),
        (10, [0.0, 0.0, 0.0]),
        (99, [5.0, 5.0, 0.0]), // used by no cell
        (20, [1.0, 0.0, 0.0]),
        (30, [1.0, 1.0, 0.0]),
    ];
    let text = hand_msh(&nodes, &[(1, [10, 20, 30]), (2, [10, 30, 40])], &[], &[]);
    let m = read_text(&text).unwrap();
    assert_eq!(m.node_tags, vec![40, 10, 20, 30]); // gmsh order, 99 dropped
    assert_eq!(m.coords[0], [0.0, 1.0, 0.0]);
    assert_eq!(m.coords[3], [1.0, 1.0, 0.0]);
    assert_eq!(m.cell(0), &[1, 2, 3]);
    // A point element on the unused node is an error.
    let text = hand_msh(
        &nodes,
        &[(1, [10, 20, 30]), (2, [10, 30, 40])],
        &[],
        &[(3, 99)],
    );
    let e = read_text(&text).unwrap_err();
    assert!(e.message.contains("node 99"), "{e}");
}

#[test]
fn dense_node_tags_out_of_order() {
    // Tags 1..4 (dense: mshio drops them) written in the order 3, 1, 4, 2.
    let nodes = vec![
        (3, [1.0, 1.0, 0.0]),
        (1, [0.0, 0.0, 0.0]),
        (4, [0.0, 1.0, 0.0]),
        (2, [1.0, 0.0, 0.0]),
    ];
    let text = hand_msh(&nodes, &[(10, [1, 2, 3]), (11, [1, 3, 4])], &[], &[]);
    let m = read_text(&text).unwrap();
    assert_eq!(m.node_tags, vec![3, 1, 4, 2]);
    for (i, &t) in m.node_tags.iter().enumerate() {
        assert_eq!(m.coords[i], nodes.iter().find(|n| n.0 == t).unwrap().1);
    }
    assert!((m.cell_measure(0) - 0.5).abs() < 1e-15);
    assert!((m.cell_measure(1) - 0.5).abs() < 1e-15);
    assert_eq!(m.cell(0), &[1, 3, 0]);
}

#[test]
fn dense_node_tags_binary_file() {
    // The binary file has dense node tags; their order must match the ASCII file's.
    let a = read("cube_h0.5.msh");
    let b = read("cube_h0.5_bin.msh");
    assert_eq!(a.node_tags, b.node_tags);
    let mut t = a.node_tags.clone();
    t.sort_unstable();
    t.dedup();
    assert_eq!(t.len(), a.n_nodes());
}

#[test]
fn two_d_z_must_be_constant() {
    let mut nodes = unit_square_nodes();
    nodes[2].1[2] = 0.1;
    let e = read_text(&hand_msh(
        &nodes,
        &[(10, [1, 2, 3]), (11, [1, 3, 4])],
        &[],
        &[],
    ))
    .unwrap_err();
    assert!(e.message.contains("z"), "{e}");
    // Constant z != 0 is accepted and flattened to 0.
    let nodes: Vec<_> = unit_square_nodes()
        .into_iter()
        .map(|(t, p)| (t, [p[0], p[1], 2.5]))
        .collect();
    let m = read_text(&hand_msh(
        &nodes,
        &[(10, [1, 2, 3]), (11, [1, 3, 4])],
        &[],
        &[],
    ))
    .unwrap();
    assert!(m.coords.iter().all(|p| p[2] == 0.0));
}

#[test]
fn quadratic_elements_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("q.msh");
    let st = std::process::Command::new("gmsh")
        .args(["-v", "0", "-2", "-order", "2", "-setnumber", "h", "0.5"])
        .arg(mesh_path("square.geo"))
        .args(["-format", "msh41", "-o"])
        .arg(&out)
        .status()
        .expect("gmsh must be installed for this test");
    assert!(st.success());
    let e = read_msh(&out).unwrap_err();
    assert!(
        e.message.contains("Tri6") || e.message.contains("Lin3"),
        "{e}"
    );
    assert!(e.message.contains("not supported"), "{e}");
}

#[test]
fn save_all_cells_without_group_rejected() {
    let e = read_msh(&mesh_path("square_nobody_saveall.msh")).unwrap_err();
    assert!(e.message.contains("no physical group"), "{e}");
    assert!(e.message.contains("Physical Surface"), "{e}");
}

#[test]
fn partitioned_rejected() {
    let e = read_msh(&mesh_path("square_h0.5_part2.msh")).unwrap_err();
    assert!(e.message.contains("partitioned"), "{e}");
    assert!(e.message.contains("-part"), "{e}");
}

#[test]
fn msh22_rejected_with_hint() {
    let p = mesh_path("square_h0.5_msh22.msh");
    let e = read_msh(&p).unwrap_err();
    assert_eq!(e.file, p);
    assert!(e.message.contains("2.2"), "{e}");
    assert!(e.message.contains("msh41"), "{e}");
}

#[test]
fn garbage_and_missing_files_rejected() {
    let e = read_msh(Path::new("/nonexistent/dir/x.msh")).unwrap_err();
    assert!(e.message.contains("cannot read"), "{e}");
    let e = read_text("hello world\n").unwrap_err();
    assert!(e.message.contains("msh41"), "{e}");
    // Valid header, broken body: the line where the parser stopped, no hint to save as 4.1
    let e =
        read_text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 x\n$EndNodes\n").unwrap_err();
    assert!(e.message.contains("line 5 (\"1 2 x\")"), "{e}");
    assert!(!e.message.contains("msh41"), "{e}");
    // Truncated binary file.
    let bytes = std::fs::read(mesh_path("cube_h0.5_bin.msh")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("t.msh");
    std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
    assert!(read_msh(&p).is_err());
}

#[test]
fn lines_only_mesh_rejected() {
    let text = hand_msh(&unit_square_nodes(), &[], &[(20, [1, 2])], &[]);
    let e = read_text(&text).unwrap_err();
    assert!(e.message.contains("no triangles or tetrahedra"), "{e}");
}

/// Timing on a large binary mesh (generated with gmsh, or `MESH_FILE=path`):
/// `cargo test --release --lib mesh::tests::big -- --ignored --nocapture`
#[test]
#[ignore]
fn big_binary_mesh_timing() {
    let dir = tempfile::tempdir().unwrap();
    let out = match std::env::var("MESH_FILE") {
        Ok(f) => PathBuf::from(f),
        Err(_) => {
            let h = std::env::var("MESH_H").unwrap_or_else(|_| "0.0013".into());
            let out = dir.path().join("big.msh");
            let st = std::process::Command::new("gmsh")
                .args(["-v", "0", "-2", "-bin", "-setnumber", "h", &h])
                .arg(mesh_path("square.geo"))
                .args(["-format", "msh41", "-o"])
                .arg(&out)
                .status()
                .unwrap();
            assert!(st.success());
            out
        }
    };
    let t = std::time::Instant::now();
    let bytes = std::fs::read(&out).unwrap();
    let t_read = t.elapsed().as_secs_f64();
    let msh = mshio::parse_msh_bytes(&bytes).unwrap();
    let t_parse = t.elapsed().as_secs_f64() - t_read;
    drop(msh);
    drop(bytes);
    let t = std::time::Instant::now();
    let m = read_msh(&out).unwrap();
    let dt = t.elapsed().as_secs_f64();
    eprintln!(
        "read_msh: {} triangles, {} nodes in {dt:.2} s (file read {t_read:.2} s, mshio parse {t_parse:.2} s)",
        m.n_cells(),
        m.n_nodes()
    );
    let area: f64 = (0..m.n_cells()).map(|c| m.cell_measure(c)).sum();
    assert!((area - 1.0).abs() < 1e-9);
}

// ---- counts bounded by the file size ------------------------------------------------------

/// `bytes` with the first occurrence of `from` replaced by `to`.
fn patched(bytes: &[u8], from: &[u8], to: &[u8]) -> Vec<u8> {
    let p = bytes
        .windows(from.len())
        .position(|w| w == from)
        .unwrap_or_else(|| panic!("{:?} not in the file", String::from_utf8_lossy(from)));
    [&bytes[..p], to, &bytes[p + from.len()..]].concat()
}

/// The `size_t` header values of section `name` of a binary file, replaced one at a time.
fn binary_header_patched(bytes: &[u8], name: &str, index: usize, value: u64) -> Vec<u8> {
    let tag = format!("{name}\n");
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

fn read_bytes_err(bytes: &[u8]) -> String {
    let e = read_msh_bytes(bytes, Path::new("corrupt.msh")).unwrap_err();
    assert_eq!(e.file, Path::new("corrupt.msh"));
    e.message
}

#[test]
fn ascii_counts_beyond_the_file_size_rejected_before_allocating() {
    let good = std::fs::read(mesh_path("square_h0.5.msh")).unwrap();
    read_msh_bytes(&good, Path::new("good.msh")).unwrap();
    let cases: [(&[u8], &[u8], &str); 5] = [
        (
            b"$PhysicalNames\n5\n",
            b"$PhysicalNames\n1000000000\n",
            "$PhysicalNames announces 1000000000 names",
        ),
        (
            b"$Nodes\n9 12 1 12",
            b"$Nodes\n9 1000000000000 1 12",
            "$Nodes announces",
        ),
        (
            b"$Nodes\n9 12 1 12",
            b"$Nodes\n900000000000 12 1 12",
            "900000000000 entity blocks",
        ),
        (
            b"$Entities\n4 4 1 0",
            b"$Entities\n4000000000000 4 1 0",
            "$Entities announces",
        ),
        (
            b"$Elements\n5 22 ",
            b"$Elements\n5 99999999999 ",
            "$Elements announces",
        ),
    ];
    for (from, to, expect) in cases {
        let m = read_bytes_err(&patched(&good, from, to));
        assert!(m.contains(expect), "{m}");
    }
    // A count that fits in the file but does not match the blocks.
    let m = read_bytes_err(&patched(&good, b"$Nodes\n9 12 1 12", b"$Nodes\n9 13 1 12"));
    assert!(
        m.contains("announces 13 nodes, but its blocks hold 12"),
        "{m}"
    );
    let m = read_bytes_err(&patched(&good, b"$Nodes\n9 12 1 12", b"$Nodes\n9 0 1 12"));
    assert!(m.contains("no nodes"), "{m}");
}

#[test]
fn binary_counts_beyond_the_file_size_rejected_before_allocating() {
    let good = std::fs::read(mesh_path("square_h0.25_bin.msh")).unwrap();
    read_msh_bytes(&good, Path::new("good.msh")).unwrap();
    for (section, index, value) in [
        ("$Nodes", 1, 1u64 << 40),
        ("$Nodes", 1, u64::MAX),
        ("$Nodes", 0, 1 << 50),
        ("$Elements", 1, 1 << 40),
        ("$Elements", 0, u64::MAX),
        ("$Entities", 2, 1 << 45),
    ] {
        let m = read_bytes_err(&binary_header_patched(&good, section, index, value));
        assert!(m.contains(&format!("{section} announces")), "{m}");
        assert!(m.contains("corrupt"), "{m}");
    }
    // Off by a little: the blocks disagree with the header.
    let m = read_bytes_err(&binary_header_patched(&good, "$Nodes", 1, 31));
    assert!(
        m.contains("announces 31 nodes, but its blocks hold 30"),
        "{m}"
    );
}

#[test]
fn node_tag_scan_does_not_trust_the_count() {
    // The raw node-tag scan used to allocate `count` tags up front.
    let good = std::fs::read(mesh_path("cube_h0.5_bin.msh")).unwrap();
    let bad = binary_header_patched(&good, "$Nodes", 1, 1 << 61);
    let info = raw::scan_header(&bad).unwrap();
    assert!(raw::scan_node_tags(&bad, &info).is_none());
    let good = std::fs::read(mesh_path("square_h0.5.msh")).unwrap();
    let bad = patched(
        &good,
        b"$Nodes\n9 12 1 12",
        b"$Nodes\n9 4000000000000000 1 12",
    );
    let info = raw::scan_header(&bad).unwrap();
    assert!(raw::scan_node_tags(&bad, &info).is_none());
}

#[test]
fn malformed_binary_header_rejected_before_the_parser() {
    // mshio panics on a data size it has no reader for (unimplemented!) and on one that does
    // not fit in an i32 (unwrap): the header check must stop these first.
    let bin = std::fs::read(mesh_path("square_h0.25_bin.msh")).unwrap();
    let ascii = std::fs::read(mesh_path("square_h0.5.msh")).unwrap();
    for bytes in [
        patched(&bin, b"4.1 1 8\n", b"4.1 1 3\n"),
        patched(&bin, b"4.1 1 8\n", b"4.1 1 16\n"),
        patched(&ascii, b"4.1 0 8\n", b"4.1 0 99999999999\n"),
    ] {
        set_catch_parser_panics(false);
        let r = std::panic::catch_unwind(|| read_msh_bytes(&bytes, Path::new("h.msh")));
        set_catch_parser_panics(true);
        let m = r
            .expect("the parser must not be reached")
            .unwrap_err()
            .message;
        assert!(m.contains("data size"), "{m}");
    }
    let m = read_bytes_err(&patched(&bin, b"4.1 1 8\n", b"4.1 7 8\n"));
    assert!(m.contains("file type"), "{m}");
    let m = read_bytes_err(&patched(
        &bin,
        b"4.1 1 8\n\x01\x00\x00\x00",
        b"4.1 1 8\n\x02\x00\x00\x00",
    ));
    assert!(m.contains("endianness"), "{m}");
}

#[test]
fn too_many_physical_tags_per_entity_rejected() {
    // Surface 1 of a 2-triangle square in 3 million physical groups would need 6 million
    // group entries from a few MB: bounded relative to the number of elements.
    let mut text = hand_msh(
        &unit_square_nodes(),
        &[(10, [1, 2, 3]), (11, [1, 3, 4])],
        &[],
        &[],
    );
    read_text(&text).unwrap();
    let tags: Vec<String> = (1..=1_200_000).map(|t| t.to_string()).collect();
    text = text.replacen(
        "1 0 0 0 1 1 0 2 1 2 0\n",
        &format!("1 0 0 0 1 1 0 {} {} 0\n", tags.len(), tags.join(" ")),
        1,
    );
    let e = read_text(&text).unwrap_err();
    assert!(e.message.contains("too many physical tags"), "{e}");
}

// ---- load and contact groups on the boundary ---------------------------------------------

#[test]
fn degenerate_interior_and_stray_facets_named() {
    let p = mesh_path("square_bad_facets.msh");
    let m = read_msh(&p).unwrap();
    for g in ["left", "right", "top"] {
        m.check_boundary_group(&p, g, "test").unwrap();
    }
    for (g, tag, what) in [
        ("bottom", "line element 4", "zero length"),
        (
            "diag",
            "line element 5",
            "interior facet (a side of 2 body cells)",
        ),
        ("stray", "line element 6", "not a side of any body cell"),
    ] {
        let e = m.check_boundary_group(&p, g, "contact.group").unwrap_err();
        assert_eq!(e.file, p);
        for s in [tag, what, &format!("\"{g}\""), "contact.group"] {
            assert!(e.message.contains(s), "{s:?} not in: {e}");
        }
    }
}

#[test]
fn degenerate_and_interior_triangles_3d() {
    let p = mesh_path("cube_h0.5.msh");
    let mut m = read("cube_h0.5.msh");
    let right = m.group_dim("right", 2).unwrap().clone();
    m.check_boundary_group(&p, "right", "t").unwrap();
    // An interior face: a face shared by two tetrahedra.
    let mut seen: HashMap<[usize; 3], usize> = HashMap::new();
    let mut interior = None;
    'cells: for c in 0..m.n_cells() {
        let v = m.cell(c);
        for skip in 0..4 {
            let mut f: Vec<usize> = (0..4).filter(|&i| i != skip).map(|i| v[i]).collect();
            f.sort_unstable();
            let k = [f[0], f[1], f[2]];
            if seen.insert(k, c).is_some() {
                interior = Some(k);
                break 'cells;
            }
        }
    }
    let face = interior.expect("a tetrahedral mesh of a cube has interior faces");
    let f_new = m.n_facets();
    m.facets.extend_from_slice(&face);
    m.facet_tags.push(999);
    let mut g = right.clone();
    g.name = "inner".into();
    g.elements = vec![right.elements[0], f_new];
    m.groups.push(g);
    let e = m
        .check_boundary_group(&p, "inner", "neumann[0].group")
        .unwrap_err();
    assert!(e.message.contains("triangle 999"), "{e}");
    assert!(e.message.contains("interior"), "{e}");
    // A degenerate triangle: two equal nodes (zero area).
    let f0 = right.elements[0];
    let v = m.facet(f0).to_vec();
    m.facets[f0 * 3 + 2] = v[1];
    let e = m
        .check_boundary_group(&p, "right", "contact.group")
        .unwrap_err();
    assert!(e.message.contains("zero area"), "{e}");
    assert!(
        e.message
            .contains(&format!("triangle {}", m.facet_tags[f0])),
        "{e}"
    );
}

// ---- inputs found by fuzzing (scripts/fuzz msh): each once crashed the reader ------------

/// Every file in tests/meshes/fuzz must give an `InputError` with the parser's panics not
/// caught (as in fuzzing: overflow checks of a debug build included).
#[test]
fn fuzz_findings_are_input_errors() {
    let dir = mesh_path("fuzz");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let p = entry.unwrap().path();
        let bytes = std::fs::read(&p).unwrap();
        set_catch_parser_panics(false);
        let r = std::panic::catch_unwind(|| read_msh_bytes(&bytes, &p));
        set_catch_parser_panics(true);
        let r = r.unwrap_or_else(|_| panic!("{} panics in the parser", p.display()));
        assert!(r.is_err(), "{} accepted", p.display());
        n += 1;
    }
    assert!(n > 0);
}

/// A second `$Nodes` section with 0 nodes made mshio compute `0 - 1` (overflow panic with
/// overflow checks; found by fuzzing after 476 827 executions).
#[test]
fn second_nodes_section_with_zero_count() {
    let bytes = std::fs::read(mesh_path("fuzz/msh_second_nodes_zero_count.msh")).unwrap();
    let e = read_msh_bytes(&bytes, Path::new("f.msh")).unwrap_err();
    assert!(e.message.contains("$Nodes holds no nodes"), "{e}");
}
