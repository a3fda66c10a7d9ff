//! `mesh.refine = k`: uniform refinement of the distributed mesh.
//!
//! The refinement works on the blocks every rank holds after the distributed read, before the
//! partition: each level turns the blocks of a mesh into the blocks of its refined mesh, so the
//! rest of the pipeline (dual graph, PT-Scotch, migration, ghosts, numbering) sees exactly what
//! it would see had it read the refined mesh from a file, and no rank ever holds the whole mesh.
//!
//! One level, in mesh numbers (the same on every rank count):
//! - the edge (a, b), a < b, of the cells and boundary elements gets its midpoint node
//!   `n_nodes + e`, e the edge's position in the lexicographic order of all edges: the keys go
//!   to the home rank of `a` (the rank whose node block holds `a`), which dedups them, counts
//!   and answers with the numbers (an exclusive scan of the counts);
//! - triangle c becomes the cells 4c..4c+3, tetrahedron c the cells 8c..8c+7 (Bey's corner
//!   tetrahedra and the octahedron cut along its shortest diagonal, decided from the parent's
//!   coordinates only), boundary triangle f the facets 4f..4f+3, a boundary edge 2 edges, a
//!   point stays; children keep the parent's tag, groups and orientation;
//! - a new node on a facet (3D: or edge) of a group named in `[[mesh.project]]` is moved onto
//!   that entry's shape by the home of its edge (the first entry whose group holds one of the
//!   edge's elements); old nodes never move; new node tags continue after the largest tag;
//! - everything is then sent to the standard blocks of the refined counts.

use super::blocks::Blocks;
use super::comm::{blk, block_of, gathered_offsets, rank_size};
use super::groups::element_groups;
use crate::case::{vec3, ObstacleSpec, Projection};
use crate::error::{InputError, RunError};
use crate::par::Ctx;
use crate::say;
use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use std::path::Path;

/// Checks projections against a mesh's dimension and (name, dimension) groups.
pub type GroupCheck<'a> = dyn Fn(usize, &[(String, usize)]) -> Result<(), InputError> + 'a;

/// What `mesh.refine` and `[[mesh.project]]` ask for.
pub struct Refine<'a> {
    /// Uniform refinements (0: the mesh as read).
    pub level: usize,
    pub project: &'a [Projection],
    /// Checks `project` against the mesh's dimension and (name, dimension) groups, naming the
    /// case key on an error (`Case::check_projections`).
    pub check: &'a GroupCheck<'a>,
}

impl Refine<'_> {
    /// No refinement.
    pub fn none() -> Refine<'static> {
        Refine {
            level: 0,
            project: &[],
            check: &|_, _| Ok(()),
        }
    }
}

/// At most this many `[[mesh.project]]` entries (one bit each in an edge's mask).
const MAX_PROJECTIONS: usize = 64;

/// A projection with the group ids it applies to.
struct Shape {
    groups: Vec<u64>,
    shape: ObstacleSpec,
}

impl Shape {
    /// x moved onto the shape: the nearest point of its surface.
    fn project(&self, x: [f64; 3]) -> [f64; 3] {
        match &self.shape {
            ObstacleSpec::Sphere { center, radius } => {
                let c = vec3(center);
                let d = [x[0] - c[0], x[1] - c[1], x[2] - c[2]];
                let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                if r > 0.0 {
                    let s = radius / r;
                    [c[0] + s * d[0], c[1] + s * d[1], c[2] + s * d[2]]
                } else {
                    x
                }
            }
            ObstacleSpec::Plane { point, normal } => {
                let (p, n) = (vec3(point), vec3(normal));
                let t = (0..3).map(|k| (x[k] - p[k]) * n[k]).sum::<f64>();
                [x[0] - t * n[0], x[1] - t * n[1], x[2] - t * n[2]]
            }
            // The indenter shapes: the nearest point of the surface (contact::obstacle); their
            // vectors have the mesh's dimension (Case::check_projections). A point without a
            // nearest point (on a cylinder's axis) stays, as a sphere's centre does.
            shape => {
                // (A height or a surface is refused when the case is read.)
                let Some(&(_, dim)) = shape.vectors().first() else {
                    return x;
                };
                match shape.to_obstacle(dim).and_then(|o| o.project(x)) {
                    Ok(q) => q.closest,
                    Err(_) => x,
                }
            }
        }
    }
}

/// Refines the blocks `spec.level` times (see the module doc). Collective; an input error
/// (a projection naming a group the mesh lacks, ...) is the same on every rank.
pub(super) fn refine_blocks(
    ctx: &Ctx,
    path: &Path,
    mut b: Blocks,
    spec: &Refine,
) -> Result<Blocks, RunError> {
    if spec.level == 0 {
        return Ok(b);
    }
    let t0 = std::time::Instant::now();
    let groups: Vec<(String, usize)> = b.groups.iter().map(|g| (g.name.clone(), g.dim)).collect();
    let checked = (spec.check)(b.dim, &groups)
        .map_err(RunError::Input)
        .and_then(|()| {
            if !(2..=3).contains(&b.dim) {
                Err(RunError::Input(
                    InputError::new(
                        path,
                        format!("the mesh is {}D; only 2D and 3D meshes are refined", b.dim),
                    )
                    .with_key("mesh.refine"),
                ))
            } else if spec.project.len() > MAX_PROJECTIONS {
                Err(RunError::Input(
                    InputError::new(path, format!("at most {MAX_PROJECTIONS} entries"))
                        .with_key("mesh.project"),
                ))
            } else {
                Ok(())
            }
        });
    ctx.agree(checked)?;
    let shapes: Vec<Shape> = spec
        .project
        .iter()
        .map(|p| Shape {
            groups: (0..b.groups.len() as u64)
                .filter(|&g| {
                    let gr = &b.groups[g as usize];
                    gr.name == p.group && gr.dim >= 1 && gr.dim < b.dim
                })
                .collect(),
            shape: p.shape.clone(),
        })
        .collect();
    let (c0, n0) = (b.n_cells, b.n_nodes);
    for _ in 0..spec.level {
        b = refine_once(ctx.world, b, &shapes);
    }
    if !shapes.is_empty() {
        let bad = first_bad_cell(ctx.world, &b).map_err(|msg| {
            RunError::Input(
                InputError::new(
                    path,
                    format!(
                        "{msg}: the projected nodes moved too far for this mesh (use a finer mesh \
                     file or fewer refinements)"
                    ),
                )
                .with_key("mesh.project"),
            )
        });
        ctx.agree(bad)?;
    }
    say!(
        ctx,
        "refine: {} level(s), {} -> {} cells, {} -> {} nodes ({:.3} s)",
        spec.level,
        c0,
        b.n_cells,
        n0,
        b.n_nodes,
        t0.elapsed().as_secs_f64()
    );
    Ok(b)
}

/// Err naming the first cell of this rank's block that is inverted or flat (measure at most
/// 1e-12 h^dim, as the mesh readers refuse) after the projections. Collective.
fn first_bad_cell(world: &SimpleCommunicator, b: &Blocks) -> Result<(), String> {
    let (rank, size) = rank_size(world);
    let npc = b.dim + 1;
    let (need, xyz) = fetch_coords(world, b);
    let lo = blk(b.n_cells, size, rank);
    for (i, cell) in b.cells.chunks_exact(npc).enumerate() {
        let p: Vec<[f64; 3]> = cell
            .iter()
            .map(|v| xyz[need.binary_search(v).expect("fetched")])
            .collect();
        let mut h2 = 0.0f64;
        for a in 0..npc {
            for c in a + 1..npc {
                h2 = h2.max((0..3).map(|k| (p[a][k] - p[c][k]).powi(2)).sum());
            }
        }
        let m = det(&p);
        if m.is_nan() || m <= 1e-12 * h2.sqrt().powi(b.dim as i32) {
            return Err(format!(
                "refined cell {} (a child of element tag {}) is {}",
                lo + i,
                b.cell_tags[i],
                if m < 0.0 { "inverted" } else { "flat" }
            ));
        }
    }
    Ok(())
}

/// Children per element of kind 0 (cells), 1 (facets), 2 (edges), 3 (points).
fn factors(dim: usize) -> [usize; 4] {
    if dim == 2 {
        [4, 2, 2, 1]
    } else {
        [8, 4, 2, 1]
    }
}

/// The local edges of one level: sorted (a, b), a < b, with their midpoint nodes.
struct Edges {
    keys: Vec<(u64, u64)>,
    ids: Vec<u64>,
}

impl Edges {
    fn mid(&self, a: u64, b: u64) -> u64 {
        let k = if a < b { (a, b) } else { (b, a) };
        self.ids[self
            .keys
            .binary_search(&k)
            .expect("edge of a local element")]
    }
}

/// Coordinates of the nodes this rank's elements use, from the node homes: (sorted nodes,
/// coordinates). Collective.
fn fetch_coords(world: &SimpleCommunicator, b: &Blocks) -> (Vec<u64>, Vec<[f64; 3]>) {
    let (rank, size) = rank_size(world);
    let mut need: Vec<u64> = b.cells.clone();
    need.extend_from_slice(&b.bnd[0]);
    need.extend_from_slice(&b.bnd[1]);
    need.sort_unstable();
    need.dedup();
    let mut send = vec![Vec::new(); size];
    for &v in &need {
        send[block_of(v as usize, b.n_nodes, size)].push(v);
    }
    let (req, counts) = exchange_counted(world, send);
    let node_lo = blk(b.n_nodes, size, rank) as u64;
    let mut reply = vec![Vec::new(); size];
    let mut i = 0;
    for (r, &c) in counts.iter().enumerate() {
        for &v in &req[i..i + c] {
            let j = 3 * (v - node_lo) as usize;
            reply[r].extend(b.coords[j..j + 3].iter().map(|x| x.to_bits()));
        }
        i += c;
    }
    // `need` is sorted and the node blocks ascend with the rank: the answers come in its order
    let xyz = exchange(world, reply)
        .chunks_exact(3)
        .map(|c| {
            [
                f64::from_bits(c[0]),
                f64::from_bits(c[1]),
                f64::from_bits(c[2]),
            ]
        })
        .collect();
    (need, xyz)
}

/// The midpoint of a and b (the same bits whichever rank computes it).
fn midpoint(xa: &[f64; 3], xb: &[f64; 3]) -> [f64; 3] {
    [
        0.5 * (xa[0] + xb[0]),
        0.5 * (xa[1] + xb[1]),
        0.5 * (xa[2] + xb[2]),
    ]
}

/// Signed volume (area) factor of a simplex.
fn det(x: &[[f64; 3]]) -> f64 {
    let d = |i: usize, k: usize| x[i][k] - x[0][k];
    if x.len() == 3 {
        d(1, 0) * d(2, 1) - d(1, 1) * d(2, 0)
    } else {
        d(1, 0) * (d(2, 1) * d(3, 2) - d(2, 2) * d(3, 1))
            - d(1, 1) * (d(2, 0) * d(3, 2) - d(2, 2) * d(3, 0))
            + d(1, 2) * (d(2, 0) * d(3, 1) - d(2, 1) * d(3, 0))
    }
}

/// Diagonals of a tetrahedron's octahedron whose squared lengths differ by less than this many
/// ε · max|x| · |v| (|v| the longest) are equal ([`tet_children`]): the rounding of the
/// coordinates moves each squared length by up to about 16 of them (four coordinates of
/// rounding ε max|x| each, before and after a change of units). Not measured; not
/// machine-specific.
const TIE_ROUNDING: f64 = 64.0;

/// The 8 children of tetrahedron (v0, v1, v2, v3) as local indices 0..10 into
/// [v0, v1, v2, v3, m01, m02, m03, m12, m13, m23]: Bey's four corner tetrahedra and the
/// octahedron cut into four along its shortest diagonal (the first of those equal within the
/// coordinates' rounding, [`TIE_ROUNDING`]), from the vertex coordinates only.
fn tet_children(x: &[[f64; 3]; 4]) -> [[usize; 4]; 8] {
    let len2 = |s: [f64; 4]| {
        (0..3)
            .map(|k| {
                let v = s[0] * x[0][k] + s[1] * x[1][k] + s[2] * x[2][k] + s[3] * x[3][k];
                v * v
            })
            .sum::<f64>()
    };
    // |m01 - m23|, |m02 - m13|, |m03 - m12| (times 2)
    let l = [
        len2([1.0, 1.0, -1.0, -1.0]),
        len2([1.0, -1.0, 1.0, -1.0]),
        len2([1.0, -1.0, -1.0, 1.0]),
    ];
    // Lengths within the rounding of the coordinates are equal: the coordinates carry a
    // relative rounding of ε (a mesh written in other units carries another), which moves
    // |v|² by up to ~16 ε max|x| |v|; decided by that rounding, a tie (any regular
    // tetrahedron's children) would cut a mesh in mm other than the same mesh in m.
    let big = x.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let longest = l.iter().fold(0.0f64, |m, &v| m.max(v));
    let slack = TIE_ROUNDING * f64::EPSILON * big * longest.sqrt();
    let mut pick = 0;
    for i in 1..3 {
        if l[i] < l[pick] - slack {
            pick = i;
        }
    }
    const M01: usize = 4;
    const M02: usize = 5;
    const M03: usize = 6;
    const M12: usize = 7;
    const M13: usize = 8;
    const M23: usize = 9;
    // the diagonal and the cycle of the other four octahedron vertices around it
    let (p, q, ring) = match pick {
        0 => (M01, M23, [M02, M03, M13, M12]),
        1 => (M02, M13, [M01, M03, M23, M12]),
        _ => (M03, M12, [M01, M02, M23, M13]),
    };
    [
        [0, M01, M02, M03],
        [M01, 1, M12, M13],
        [M02, M12, 2, M23],
        [M03, M13, M23, 3],
        [p, q, ring[0], ring[1]],
        [p, q, ring[1], ring[2]],
        [p, q, ring[2], ring[3]],
        [p, q, ring[3], ring[0]],
    ]
}

/// The 4 children of triangle (v0, v1, v2) as indices into [v0, v1, v2, m01, m02, m12]
/// (orientation kept).
const TRI_CHILDREN: [[usize; 3]; 4] = [[0, 3, 4], [3, 1, 5], [4, 5, 2], [3, 5, 4]];

/// Rows with global numbers on their way to the standard blocks of `total` rows (`width`
/// u64 each), packed as they are pushed.
struct Outbox {
    total: usize,
    width: usize,
    send: Vec<Vec<u64>>,
}

impl Outbox {
    fn new(world: &SimpleCommunicator, total: usize, width: usize) -> Outbox {
        Outbox {
            total,
            width,
            send: vec![Vec::new(); rank_size(world).1],
        }
    }

    fn push(&mut self, id: u64, row: &[u64]) {
        debug_assert_eq!(row.len(), self.width);
        let to = block_of(id as usize, self.total, self.send.len());
        let s = &mut self.send[to];
        s.push(id);
        s.extend_from_slice(row);
    }

    /// Sends the rows; returns this rank's block, rows in order. Collective.
    fn deliver(self, world: &SimpleCommunicator) -> Vec<u64> {
        let (rank, size) = rank_size(world);
        let (total, width) = (self.total, self.width);
        let recv = exchange(world, self.send);
        let lo = blk(total, size, rank);
        let n = blk(total, size, rank + 1) - lo;
        let mut out = vec![0u64; n * width];
        let mut seen = 0;
        for rec in recv.chunks_exact(width + 1) {
            let i = rec[0] as usize - lo;
            out[i * width..(i + 1) * width].copy_from_slice(&rec[1..]);
            seen += 1;
        }
        debug_assert_eq!(seen, n, "every row of the block arrives once");
        out
    }
}

/// The coordinates of the nodes this rank's elements use (sorted ids and their points).
struct Fetched {
    need: Vec<u64>,
    xyz: Vec<[f64; 3]>,
}

impl Fetched {
    fn at(&self, v: u64) -> &[f64; 3] {
        &self.xyz[self.need.binary_search(&v).expect("fetched")]
    }
}

/// The new nodes this rank numbers (the edges whose smaller node it holds): their midpoints
/// (projected where a group asks), the first global edge number of every rank, the largest
/// node tag of the mesh; and the new node of every local edge.
struct NewNodes {
    edges: Edges,
    home_mid: Vec<[f64; 3]>,
    edge_offsets: Vec<usize>,
    max_tag: u64,
}

/// One level of refinement of the blocks: edges numbered, nodes, cells, boundary elements
/// and group members of the refined mesh sent to their standard blocks. Collective.
fn refine_once(world: &SimpleCommunicator, b: Blocks, shapes: &[Shape]) -> Blocks {
    let dim = b.dim;
    let f = factors(dim);
    let (need, xyz) = fetch_coords(world, &b);
    let pts = Fetched { need, xyz };
    let (keys, masks) = local_edges(world, &b, shapes);
    let nn = number_edges(world, &b, keys, masks, &pts, shapes);
    let n_nodes2 = b.n_nodes + nn.edge_offsets[world.size() as usize];
    let nodes = refined_nodes(world, &b, &nn, n_nodes2);
    let edges = nn.edges;
    let cells = refined_cells(world, &b, &edges, &pts);
    let bnd = refined_boundary(world, &b, &edges);
    drop(edges);
    let kinds: Vec<usize> = b.groups.iter().map(|g| b.kind(g.dim)).collect();
    let members = refined_members(world, &b, &kinds);

    let split = |v: Vec<u64>, w: usize| -> (Vec<u64>, Vec<u64>) {
        let n = v.len() / (w + 1);
        let mut a = Vec::with_capacity(n * w);
        let mut t = Vec::with_capacity(n);
        for r in v.chunks_exact(w + 1) {
            a.extend_from_slice(&r[..w]);
            t.push(r[w]);
        }
        (a, t)
    };
    let (cells, cell_tags) = split(cells, dim + 1);
    let (coord_bits, node_tags) = split(nodes, 3);
    let [b0, b1, b2] = bnd;
    let (f0, t0) = split(b0, dim);
    let (e0, t1) = split(b1, 2);
    let (p0, t2) = split(b2, 1);
    Blocks {
        dim,
        n_nodes: n_nodes2,
        n_cells: b.n_cells * f[0],
        n_bnd: [b.n_bnd[0] * f[1], b.n_bnd[1] * f[2], b.n_bnd[2] * f[3]],
        group_sizes: b
            .group_sizes
            .iter()
            .zip(&kinds)
            .map(|(&n, &k)| n * f[k])
            .collect(),
        groups: b.groups,
        cells,
        cell_tags,
        coords: coord_bits.into_iter().map(f64::from_bits).collect(),
        node_tags,
        bnd: [f0, e0, p0],
        bnd_tags: [t0, t1, t2],
        members: members.chunks_exact(2).map(|c| (c[0], c[1])).collect(),
    }
}

/// Phase 1: the edges (a < b) of this rank's cells and boundary elements, sorted and unique,
/// each with the OR of the projection masks of the boundary elements it lies on. Collective.
fn local_edges(
    world: &SimpleCommunicator,
    b: &Blocks,
    shapes: &[Shape],
) -> (Vec<(u64, u64)>, Vec<u64>) {
    let dim = b.dim;
    let eg = element_groups(world, b);
    let mask_of = |gs: &[u32]| -> u64 {
        shapes
            .iter()
            .enumerate()
            .filter(|(_, s)| gs.iter().any(|&g| s.groups.contains(&u64::from(g))))
            .fold(0u64, |m, (p, _)| m | (1u64 << p))
    };
    let mut recs: Vec<(u64, u64, u64)> = Vec::new();
    let mut push_edges = |nodes: &[u64], mask: u64| {
        for i in 0..nodes.len() {
            for j in i + 1..nodes.len() {
                let (a, c) = (nodes[i].min(nodes[j]), nodes[i].max(nodes[j]));
                recs.push((a, c, mask));
            }
        }
    };
    for cell in b.cells.chunks_exact(dim + 1) {
        push_edges(cell, 0);
    }
    for (k, w) in [(1usize, dim), (2, 2)] {
        for (i, e) in b.bnd[k - 1].chunks_exact(w).enumerate() {
            push_edges(e, mask_of(eg.of(k, i)));
        }
    }
    drop(eg);
    recs.sort_unstable();
    let mut keys: Vec<(u64, u64)> = Vec::new();
    let mut masks: Vec<u64> = Vec::new();
    for (a, c, m) in recs {
        if keys.last() == Some(&(a, c)) {
            *masks.last_mut().expect("pushed with the key") |= m;
        } else {
            keys.push((a, c));
            masks.push(m);
        }
    }
    (keys, masks)
}

/// Phase 2: every edge sent to the home of its smaller node ([a, b, mask, midpoint]); the
/// homes number their unique edges after the old nodes (a running count over the ranks),
/// project the midpoints of masked edges, and answer every sender with the new node ids (in
/// the order of `keys`). Collective.
fn number_edges(
    world: &SimpleCommunicator,
    b: &Blocks,
    keys: Vec<(u64, u64)>,
    masks: Vec<u64>,
    pts: &Fetched,
    shapes: &[Shape],
) -> NewNodes {
    let (rank, size) = rank_size(world);
    let mut send = vec![Vec::new(); size];
    for (&(a, c), &m) in keys.iter().zip(&masks) {
        let mid = midpoint(pts.at(a), pts.at(c));
        let s = &mut send[block_of(a as usize, b.n_nodes, size)];
        s.extend_from_slice(&[a, c, m]);
        s.extend(mid.iter().map(|v| v.to_bits()));
    }
    drop(masks);
    let (recv, counts) = exchange_counted(world, send);
    let n_recv = recv.len() / 6;
    let mut order: Vec<((u64, u64), usize)> = (0..n_recv)
        .map(|i| ((recv[6 * i], recv[6 * i + 1]), i))
        .collect();
    order.sort_unstable();
    let mut unique_of = vec![0usize; n_recv];
    let mut home_mask: Vec<u64> = Vec::new();
    let mut home_mid: Vec<[f64; 3]> = Vec::new();
    let mut last = None;
    for &(key, i) in &order {
        if last != Some(key) {
            last = Some(key);
            home_mask.push(0);
            home_mid.push([
                f64::from_bits(recv[6 * i + 3]),
                f64::from_bits(recv[6 * i + 4]),
                f64::from_bits(recv[6 * i + 5]),
            ]);
        }
        *home_mask.last_mut().expect("pushed") |= recv[6 * i + 2];
        unique_of[i] = home_mask.len() - 1;
    }
    drop(order);
    let edge_offsets = gathered_offsets(world, home_mask.len());
    let first_new = b.n_nodes as u64 + edge_offsets[rank] as u64;
    let mut reply = vec![Vec::new(); size];
    let mut i = 0;
    for (r, &c) in counts.iter().enumerate() {
        for _ in 0..c / 6 {
            reply[r].push(first_new + unique_of[i] as u64);
            i += 1;
        }
    }
    drop(recv);
    // the answers come in the order of `keys` (sorted by a; the node blocks ascend with rank)
    let edges = Edges {
        keys,
        ids: exchange(world, reply),
    };
    for (m, p) in home_mid.iter_mut().zip(&home_mask) {
        if *p != 0 {
            *m = shapes[p.trailing_zeros() as usize].project(*m);
        }
    }
    let local_max = b.node_tags.iter().copied().max().unwrap_or(0);
    let mut max_tag = 0u64;
    world.all_reduce_into(&local_max, &mut max_tag, SystemOperation::max());
    NewNodes {
        edges,
        home_mid,
        edge_offsets,
        max_tag,
    }
}

/// Phase 3: the old nodes and the new ones numbered here, as rows [x, y, z, tag] of the
/// refined node blocks (new tags continue after the largest tag). Collective.
fn refined_nodes(
    world: &SimpleCommunicator,
    b: &Blocks,
    nn: &NewNodes,
    n_nodes2: usize,
) -> Vec<u64> {
    let (rank, size) = rank_size(world);
    let node_lo = blk(b.n_nodes, size, rank) as u64;
    let mut out = Outbox::new(world, n_nodes2, 4);
    for (i, (c, &t)) in b.coords.chunks_exact(3).zip(&b.node_tags).enumerate() {
        out.push(
            node_lo + i as u64,
            &[c[0].to_bits(), c[1].to_bits(), c[2].to_bits(), t],
        );
    }
    for (j, m) in nn.home_mid.iter().enumerate() {
        let e = nn.edge_offsets[rank] as u64 + j as u64;
        out.push(
            b.n_nodes as u64 + e,
            &[
                m[0].to_bits(),
                m[1].to_bits(),
                m[2].to_bits(),
                nn.max_tag + 1 + e,
            ],
        );
    }
    out.deliver(world)
}

/// Phase 4: the children of every cell (cell c → cells f·c .. f·c + f − 1, oriented like the
/// parent) as rows [nodes, tag] of the refined cell blocks. Collective.
fn refined_cells(world: &SimpleCommunicator, b: &Blocks, edges: &Edges, pts: &Fetched) -> Vec<u64> {
    let (rank, size) = rank_size(world);
    let (dim, npc) = (b.dim, b.dim + 1);
    let f = factors(dim);
    let cell_lo = blk(b.n_cells, size, rank) as u64;
    let mut out = Outbox::new(world, b.n_cells * f[0], npc + 1);
    for (i, cell) in b.cells.chunks_exact(npc).enumerate() {
        let tag = b.cell_tags[i];
        let gc = (cell_lo + i as u64) * f[0] as u64;
        let mut all: Vec<u64> = cell.to_vec();
        for p in 0..npc {
            for q in p + 1..npc {
                all.push(edges.mid(cell[p], cell[q]));
            }
        }
        let mut pos: Vec<[f64; 3]> = cell.iter().map(|&v| *pts.at(v)).collect();
        for p in 0..npc {
            for q in p + 1..npc {
                pos.push(midpoint(&pos[p], &pos[q]));
            }
        }
        let children: Vec<Vec<usize>> = if dim == 2 {
            TRI_CHILDREN.iter().map(|c| c.to_vec()).collect()
        } else {
            tet_children(&[pos[0], pos[1], pos[2], pos[3]])
                .iter()
                .map(|c| c.to_vec())
                .collect()
        };
        let sign = det(&pos[..npc]) >= 0.0;
        for (j, mut ch) in children.into_iter().enumerate() {
            let px: Vec<[f64; 3]> = ch.iter().map(|&l| pos[l]).collect();
            if (det(&px) >= 0.0) != sign {
                ch.swap(0, 1);
            }
            let mut row: Vec<u64> = ch.iter().map(|&l| all[l]).collect();
            row.push(tag);
            out.push(gc + j as u64, &row);
        }
    }
    out.deliver(world)
}

/// Phase 5: the children of the boundary elements (facets, edges, points) as rows
/// [nodes, tag] of the refined blocks of each kind. Collective.
fn refined_boundary(world: &SimpleCommunicator, b: &Blocks, edges: &Edges) -> [Vec<u64>; 3] {
    let (rank, size) = rank_size(world);
    let f = factors(b.dim);
    let n_bnd2 = [b.n_bnd[0] * f[1], b.n_bnd[1] * f[2], b.n_bnd[2] * f[3]];
    let mut bnd: [Vec<u64>; 3] = Default::default();
    for k in 1..4 {
        let w = b.width(k);
        let lo = blk(b.count(k), size, rank) as u64;
        let mut out = Outbox::new(world, n_bnd2[k - 1], w + 1);
        for (i, e) in b.bnd[k - 1].chunks_exact(w).enumerate() {
            let tag = b.bnd_tags[k - 1][i];
            let id = (lo + i as u64) * f[k] as u64;
            let kids: Vec<Vec<u64>> = match w {
                1 => vec![e.to_vec()],
                2 => {
                    let m = edges.mid(e[0], e[1]);
                    vec![vec![e[0], m], vec![m, e[1]]]
                }
                _ => {
                    let all = [
                        e[0],
                        e[1],
                        e[2],
                        edges.mid(e[0], e[1]),
                        edges.mid(e[0], e[2]),
                        edges.mid(e[1], e[2]),
                    ];
                    TRI_CHILDREN
                        .iter()
                        .map(|c| c.iter().map(|&l| all[l]).collect())
                        .collect()
                }
            };
            for (j, mut row) in kids.into_iter().enumerate() {
                row.push(tag);
                out.push(id + j as u64, &row);
            }
        }
        bnd[k - 1] = out.deliver(world);
    }
    bnd
}

/// Phase 6: group members: member k of group g (element e) → its f members (the children of
/// e), as rows [group, element] of the refined member blocks. Collective.
fn refined_members(world: &SimpleCommunicator, b: &Blocks, kinds: &[usize]) -> Vec<u64> {
    let (rank, size) = rank_size(world);
    let f = factors(b.dim);
    let mut off_old = vec![0usize; b.groups.len() + 1];
    let mut off_new = vec![0usize; b.groups.len() + 1];
    for (g, &n) in b.group_sizes.iter().enumerate() {
        off_old[g + 1] = off_old[g] + n;
        off_new[g + 1] = off_new[g] + n * f[kinds[g]];
    }
    let n_members = off_old[b.groups.len()];
    let mem_lo = blk(n_members, size, rank);
    let mut out = Outbox::new(world, off_new[b.groups.len()], 2);
    for (i, &(g, e)) in b.members.iter().enumerate() {
        let gi = g as usize;
        let fk = f[kinds[gi]];
        let base = off_new[gi] + (mem_lo + i - off_old[gi]) * fk;
        for j in 0..fk {
            out.push((base + j) as u64, &[g, e * fk as u64 + j as u64]);
        }
    }
    out.deliver(world)
}

/// One all-to-all-v of per-rank rows (`send[r]` goes to rank r) through dist's flat
/// [`super::comm::exchange`]; returns the data received (in rank order) and the count from each rank.
/// Collective.
fn exchange_counted(world: &SimpleCommunicator, send: Vec<Vec<u64>>) -> (Vec<u64>, Vec<usize>) {
    let recv = super::comm::exchange(world, |p| {
        for (r, v) in send.iter().enumerate() {
            p.to(r).extend(v);
        }
    });
    let counts = recv.offsets.windows(2).map(|w| w[1] - w[0]).collect();
    (recv.data, counts)
}

/// As [`exchange_counted`], the data only.
fn exchange(world: &SimpleCommunicator, send: Vec<Vec<u64>>) -> Vec<u64> {
    exchange_counted(world, send).0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The children of a tetrahedron (midpoints added as in `refine_once`), orientation fixed
    /// as there.
    fn children(x: [[f64; 3]; 4]) -> Vec<Vec<[f64; 3]>> {
        let mut pos: Vec<[f64; 3]> = x.to_vec();
        for p in 0..4 {
            for q in p + 1..4 {
                pos.push(midpoint(&x[p], &x[q]));
            }
        }
        let sign = det(&pos[..4]) >= 0.0;
        tet_children(&x)
            .iter()
            .map(|c| {
                let mut px: Vec<[f64; 3]> = c.iter().map(|&l| pos[l]).collect();
                if (det(&px) >= 0.0) != sign {
                    px.swap(0, 1);
                }
                px
            })
            .collect()
    }

    #[test]
    fn tet_children_fill_the_parent_with_its_orientation() {
        let tets = [
            [
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            [
                [0.1, 0.2, 0.0],
                [0.9, -0.1, 0.3],
                [0.2, 1.3, 0.1],
                [0.4, 0.3, 2.0],
            ],
            [
                [0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.3, 0.2, -0.7],
            ],
        ];
        for t in tets {
            let v = det(&t);
            let kids = children(t);
            assert_eq!(kids.len(), 8);
            let sum: f64 = kids.iter().map(|k| det(k)).sum();
            assert!((sum - v).abs() < 1e-14 * v.abs(), "volumes {sum} vs {v}");
            for k in &kids {
                let d = det(k);
                assert!(d * v > 0.0, "a child is inverted or flat: {d} vs {v}");
                assert!(
                    (d.abs() - v.abs() / 8.0).abs() < 1e-12 * v.abs(),
                    "{d} vs {v}/8"
                );
            }
        }
    }

    #[test]
    fn tet_diagonal_is_the_shortest_and_independent_of_vertex_order() {
        // a tetrahedron stretched along x: the diagonals have different lengths
        let x = [
            [0.0, 0.0, 0.0],
            [3.0, 0.1, 0.0],
            [0.2, 1.0, 0.1],
            [2.9, 0.8, 1.1],
        ];
        let diag = |x: &[[f64; 3]; 4]| -> f64 {
            let k = children(*x);
            // the diagonal: the common edge of the four interior children
            let d = |a: [f64; 3], b: [f64; 3]| {
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            };
            let mut best = f64::INFINITY;
            for p in 0..4 {
                for q in p + 1..4 {
                    if (4..8).all(|c| k[c].contains(&k[4][p]) && k[c].contains(&k[4][q])) {
                        best = best.min(d(k[4][p], k[4][q]));
                    }
                }
            }
            best
        };
        let mids: Vec<[f64; 3]> = (0..4)
            .flat_map(|p| (p + 1..4).map(move |q| (p, q)))
            .map(|(p, q)| midpoint(&x[p], &x[q]))
            .collect();
        let shortest = [(0, 5), (1, 4), (2, 3)]
            .iter()
            .map(|&(a, b)| {
                let (u, v): ([f64; 3], [f64; 3]) = (mids[a], mids[b]);
                ((u[0] - v[0]).powi(2) + (u[1] - v[1]).powi(2) + (u[2] - v[2]).powi(2)).sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!((diag(&x) - shortest).abs() < 1e-15);
        let y = [x[2], x[0], x[3], x[1]];
        assert!((diag(&y) - shortest).abs() < 1e-15);
    }

    #[test]
    fn triangle_children_fill_the_parent_with_its_orientation() {
        for t in [
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [[0.3, 0.1, 0.0], [-0.2, 0.9, 0.0], [1.4, 0.5, 0.0]],
        ] {
            let pos = [
                t[0],
                t[1],
                t[2],
                midpoint(&t[0], &t[1]),
                midpoint(&t[0], &t[2]),
                midpoint(&t[1], &t[2]),
            ];
            let v = det(&t);
            for c in TRI_CHILDREN {
                let d = det(&[pos[c[0]], pos[c[1]], pos[c[2]]]);
                assert!((d - v / 4.0).abs() < 1e-14 * v.abs(), "{d} vs {v}/4");
            }
        }
    }

    #[test]
    fn projection_onto_circle_and_plane() {
        let circle = Shape {
            groups: vec![],
            shape: ObstacleSpec::Sphere {
                center: vec![0.0, 1.0],
                radius: 2.0,
            },
        };
        let p = circle.project([0.6, 1.8, 0.0]);
        assert!(((p[0] * p[0] + (p[1] - 1.0).powi(2)).sqrt() - 2.0).abs() < 1e-15);
        assert!(
            (p[0] / (p[1] - 1.0) - 0.75).abs() < 1e-15,
            "along the ray: {p:?}"
        );
        let plane = Shape {
            groups: vec![],
            shape: ObstacleSpec::Plane {
                point: vec![0.0, 0.0, 1.0],
                normal: vec![0.0, 0.6, 0.8],
            },
        };
        let p = plane.project([1.0, 2.0, 3.0]);
        assert!((0.6 * p[1] + 0.8 * (p[2] - 1.0)).abs() < 1e-15);
        assert!((p[0] - 1.0).abs() < 1e-15);
    }
}
