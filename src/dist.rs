//! Distributed mesh input: every rank reads a contiguous block of the mesh (HDF5 hyperslabs;
//! an MSH file is read by rank 0, which sends every rank its blocks and then drops the whole
//! mesh), the dual graph of the cells is built without the whole mesh (facet keys hashed to a
//! home rank), PT-Scotch partitions it, the cells migrate to their ranks, and every rank builds
//! a LOCAL [`Mesh`] (its own cells, the ghost cells touching its owned nodes, the boundary
//! elements touching any of its nodes) with a [`Layout`] of local size.
//!
//! Node homes: node i (mesh order) lives on rank `block_of(i, n_nodes)`, which read its
//! coordinates; the home learns which ranks hold the node (the ranks of the cells touching it),
//! its owner (the lowest of them) and the physical groups of the elements containing it.
//!
//! The rules are today's: the same dual graph rows on the same blocks (so the same partition),
//! a node belongs to the lowest rank among its cells, rank r owns a contiguous range of global
//! numbers, numbered along the Morton curve of the whole mesh's bounding box (ties by mesh
//! order), local cells ordered by their lowest global node number.

use crate::error::{InputError, RunError};
use crate::mesh::{self, h5::H5Mesh, GlobalInfo, Group, Mesh};
use crate::par::Ctx;
use crate::partition::{morton_key, Layout, NodeCells};
use crate::petsc::{self, MPI_Comm, PInt};
use mpi::datatype::{Partition, PartitionMut};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use std::path::Path;

mod refine; // `mesh.refine`: the blocks refined before the partition (src/dist/refine.rs)
pub use refine::Refine;

/// First row of rank r's block of n rows (the same blocks as the partitioner's).
pub fn blk(n: usize, size: usize, r: usize) -> usize {
    ((r as u128 * n as u128) / size as u128) as usize
}

/// The rank whose block holds row i.
fn block_of(i: usize, n: usize, size: usize) -> usize {
    let mut lo = 0;
    let mut hi = size; // blk(lo) <= i < blk(hi)
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if blk(n, size, mid) <= i {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// All-to-all of u64 streams: `send[r]` goes to rank r; returns what every rank sent here,
/// concatenated in rank order.
fn exchange(world: &SimpleCommunicator, send: Vec<Vec<u64>>) -> Vec<u64> {
    exchange_counted(world, send).0
}

/// As [`exchange`], with the number of u64 received from each rank.
fn exchange_counted(world: &SimpleCommunicator, send: Vec<Vec<u64>>) -> (Vec<u64>, Vec<usize>) {
    let size = send.len();
    let counts: Vec<i32> = send.iter().map(|v| v.len() as i32).collect();
    let mut rcounts = vec![0i32; size];
    world.all_to_all_into(&counts[..], &mut rcounts[..]);
    let displs: Vec<i32> = counts
        .iter()
        .scan(0, |s, &c| {
            let d = *s;
            *s += c;
            Some(d)
        })
        .collect();
    let rdispls: Vec<i32> = rcounts
        .iter()
        .scan(0, |s, &c| {
            let d = *s;
            *s += c;
            Some(d)
        })
        .collect();
    let flat: Vec<u64> = send.into_iter().flatten().collect();
    let total: usize = rcounts.iter().map(|&c| c as usize).sum();
    let mut recv = vec![0u64; total];
    {
        let sp = Partition::new(&flat[..], counts, displs);
        let mut rp = PartitionMut::new(&mut recv[..], rcounts.clone(), rdispls);
        world.all_to_all_varcount_into(&sp, &mut rp);
    }
    (recv, rcounts.iter().map(|&c| c as usize).collect())
}

/// This rank's blocks of the mesh file.
#[derive(Default)]
struct Blocks {
    dim: usize,
    n_nodes: usize,
    n_cells: usize,
    /// Counts of facets, edges, points.
    n_bnd: [usize; 3],
    groups: Vec<Group>,
    group_sizes: Vec<usize>,
    cells: Vec<u64>,
    cell_tags: Vec<u64>,
    coords: Vec<f64>,
    node_tags: Vec<u64>,
    bnd: [Vec<u64>; 3],
    bnd_tags: [Vec<u64>; 3],
    /// (group, element) of a block of the group members.
    members: Vec<(u64, u64)>,
}

impl Blocks {
    /// Kind of the elements of a group: 0 cells, 1 facets, 2 edges, 3 points.
    fn kind(&self, gdim: usize) -> usize {
        if gdim == self.dim {
            0
        } else if gdim + 1 == self.dim {
            1
        } else if gdim == 1 {
            2
        } else {
            3
        }
    }
    fn count(&self, kind: usize) -> usize {
        if kind == 0 {
            self.n_cells
        } else {
            self.n_bnd[kind - 1]
        }
    }
    fn width(&self, kind: usize) -> usize {
        [self.dim + 1, self.dim, 2, 1][kind]
    }

    /// Rank r's blocks of a whole mesh.
    fn of_mesh(m: &Mesh, size: usize, r: usize) -> Blocks {
        let n_bnd = [m.facet_tags.len(), m.edge_tags.len(), m.point_tags.len()];
        let sl = |v: &[usize], n: usize, w: usize| -> Vec<u64> {
            v[blk(n, size, r) * w..blk(n, size, r + 1) * w]
                .iter()
                .map(|&x| x as u64)
                .collect()
        };
        let st = |v: &[u64], n: usize| v[blk(n, size, r)..blk(n, size, r + 1)].to_vec();
        let (nn, nc) = (m.n_nodes(), m.n_cells());
        let mut members = Vec::new();
        let all: Vec<(u64, u64)> = m
            .groups
            .iter()
            .enumerate()
            .flat_map(|(g, gr)| gr.elements.iter().map(move |&e| (g as u64, e as u64)))
            .collect();
        members.extend_from_slice(&all[blk(all.len(), size, r)..blk(all.len(), size, r + 1)]);
        Blocks {
            dim: m.dim,
            n_nodes: nn,
            n_cells: nc,
            n_bnd,
            groups: m
                .groups
                .iter()
                .map(|g| Group {
                    elements: Vec::new(),
                    ..g.clone()
                })
                .collect(),
            group_sizes: m.groups.iter().map(|g| g.elements.len()).collect(),
            cells: sl(&m.cells, nc, m.dim + 1),
            cell_tags: st(&m.cell_tags, nc),
            coords: m.coords[blk(nn, size, r)..blk(nn, size, r + 1)]
                .iter()
                .flatten()
                .copied()
                .collect(),
            node_tags: st(&m.node_tags, nn),
            bnd: [
                sl(&m.facets, n_bnd[0], m.dim),
                sl(&m.edges, n_bnd[1], 2),
                sl(&m.points, n_bnd[2], 1),
            ],
            bnd_tags: [
                st(&m.facet_tags, n_bnd[0]),
                st(&m.edge_tags, n_bnd[1]),
                st(&m.point_tags, n_bnd[2]),
            ],
            members,
        }
    }

    /// Rank r's blocks read from an HDF5 mesh (hyperslabs).
    fn of_h5(h: &H5Mesh, size: usize, r: usize) -> Result<Blocks, String> {
        let b = |n: usize| (blk(n, size, r), blk(n, size, r + 1));
        let n_bnd = [h.n_facets, h.n_edges, h.n_points];
        let (nl, nh) = b(h.n_nodes);
        let (cl, ch) = b(h.n_cells);
        let mut bnd: [Vec<u64>; 3] = Default::default();
        let mut bnd_tags: [Vec<u64>; 3] = Default::default();
        for (k, (name, w)) in [("facets", h.dim), ("edges", 2), ("points", 1)]
            .into_iter()
            .enumerate()
        {
            let (lo, hi) = b(n_bnd[k]);
            bnd[k] = if w == 1 {
                h.rows1(name, lo, hi)?
            } else {
                h.rows2(name, lo, hi)?
            };
            bnd_tags[k] = h.rows1(&format!("{}_tags", &name[..name.len() - 1]), lo, hi)?;
        }
        let nm = *h.group_offsets.last().unwrap_or(&0);
        let (ml, mh) = b(nm);
        let mem: Vec<u64> = h.rows1("groups/members", ml, mh)?;
        let members = mem
            .iter()
            .enumerate()
            .map(|(i, &e)| {
                let k = ml + i;
                let g = h.group_offsets.partition_point(|&o| o <= k) - 1;
                (g as u64, e)
            })
            .collect();
        Ok(Blocks {
            dim: h.dim,
            n_nodes: h.n_nodes,
            n_cells: h.n_cells,
            n_bnd,
            groups: h.groups.clone(),
            group_sizes: h.group_offsets.windows(2).map(|w| w[1] - w[0]).collect(),
            cells: h.rows2("cells", cl, ch)?,
            cell_tags: h.rows1("cell_tags", cl, ch)?,
            coords: h.rows2("coordinates", nl, nh)?,
            node_tags: h.rows1("node_tags", nl, nh)?,
            bnd,
            bnd_tags,
            members,
        })
    }

    /// Serialised for sending (f64 as bits).
    fn pack(&self) -> Vec<u64> {
        let mut o = vec![
            self.dim as u64,
            self.n_nodes as u64,
            self.n_cells as u64,
            self.n_bnd[0] as u64,
            self.n_bnd[1] as u64,
            self.n_bnd[2] as u64,
            self.groups.len() as u64,
        ];
        for (g, &n) in self.groups.iter().zip(&self.group_sizes) {
            o.extend([
                g.dim as u64,
                g.tag as i64 as u64,
                n as u64,
                g.name.len() as u64,
            ]);
            o.extend(g.name.bytes().map(u64::from));
        }
        let mut vec = |v: &[u64]| {
            o.push(v.len() as u64);
            o.extend_from_slice(v);
        };
        vec(&self.cells);
        vec(&self.cell_tags);
        vec(&self.coords.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
        vec(&self.node_tags);
        for k in 0..3 {
            vec(&self.bnd[k]);
            vec(&self.bnd_tags[k]);
        }
        vec(&self
            .members
            .iter()
            .flat_map(|&(g, e)| [g, e])
            .collect::<Vec<_>>());
        o
    }

    fn unpack(v: &[u64]) -> Blocks {
        let mut i = 0;
        let mut next = || {
            i += 1;
            v[i - 1]
        };
        let mut b = Blocks {
            dim: next() as usize,
            n_nodes: next() as usize,
            n_cells: next() as usize,
            n_bnd: [next() as usize, next() as usize, next() as usize],
            ..Default::default()
        };
        let ng = next();
        for _ in 0..ng {
            let dim = next() as usize;
            let tag = next() as i64 as i32;
            let n = next() as usize;
            let len = next() as usize;
            let name: Vec<u8> = (0..len).map(|_| next() as u8).collect();
            b.groups.push(Group {
                name: String::from_utf8_lossy(&name).into_owned(),
                dim,
                tag,
                elements: Vec::new(),
            });
            b.group_sizes.push(n);
        }
        let mut vec = || {
            let n = next() as usize;
            (0..n).map(|_| next()).collect::<Vec<u64>>()
        };
        b.cells = vec();
        b.cell_tags = vec();
        b.coords = vec().into_iter().map(f64::from_bits).collect();
        b.node_tags = vec();
        for k in 0..3 {
            b.bnd[k] = vec();
            b.bnd_tags[k] = vec();
        }
        b.members = vec().chunks_exact(2).map(|c| (c[0], c[1])).collect();
        b
    }

    /// Indices in range (a damaged or hand-made file gives an error, not a panic).
    fn validate(&self) -> Result<(), String> {
        let n = self.n_nodes as u64;
        for (what, list) in [
            ("cells", &self.cells),
            ("facets", &self.bnd[0]),
            ("edges", &self.bnd[1]),
            ("points", &self.bnd[2]),
        ] {
            if let Some(v) = list.iter().find(|&&v| v >= n) {
                return Err(format!(
                    "/{what} references node {v}, but there are {n} nodes"
                ));
            }
        }
        for &(g, e) in &self.members {
            let gr = &self.groups[g as usize];
            if gr.dim > self.dim || e as usize >= self.count(self.kind(gr.dim)) {
                return Err(format!(
                    "group \"{}\" ({}D) has member {e} out of range",
                    gr.name, gr.dim
                ));
            }
        }
        Ok(())
    }
}

/// Reads this rank's blocks: HDF5 by hyperslabs on every rank, MSH on rank 0 (sent out).
/// Errors are agreed (every rank gets the same).
fn read_blocks(ctx: &Ctx, path: &Path) -> Result<Blocks, RunError> {
    let (rank, size) = (ctx.rank, ctx.size);
    let err = |m: String| RunError::Input(InputError::new(path, m));
    if mesh::h5::is_h5(path) {
        let b = H5Mesh::open(path)
            .and_then(|h| Blocks::of_h5(&h, size, rank))
            .and_then(|b| b.validate().map(|()| b))
            .map_err(err);
        ctx.agree(b)
    } else {
        let whole = if rank == 0 {
            mesh::read_msh(path).map(Some).map_err(RunError::Input)
        } else {
            Ok(None)
        };
        let whole = ctx.agree(whole)?;
        if let Some(m) = whole {
            for r in 1..size {
                let buf = Blocks::of_mesh(&m, size, r).pack();
                ctx.world.process_at_rank(r as i32).send(&buf[..]);
            }
            Ok(Blocks::of_mesh(&m, size, 0))
        } else {
            let (buf, _) = ctx.world.process_at_rank(0).receive_vec::<u64>();
            Ok(Blocks::unpack(&buf))
        }
    }
}

/// Dual-graph rows of this rank's block of cells (cells sharing a facet), CSR, global cell
/// indices, neighbours ascending: facet keys are sent to a home rank by hash.
fn dual_graph(world: &SimpleCommunicator, b: &Blocks) -> (Vec<PInt>, Vec<PInt>) {
    let size = world.size() as usize;
    let rank = world.rank() as usize;
    let npc = b.dim + 1;
    let lo = blk(b.n_cells, size, rank);
    let n_local = b.cell_tags.len();
    let mut send = vec![Vec::new(); size];
    for (i, cell) in b.cells.chunks_exact(npc).enumerate() {
        for skip in 0..npc {
            let mut key = [u64::MAX; 3];
            let mut j = 0;
            for (a, &v) in cell.iter().enumerate() {
                if a != skip {
                    key[j] = v;
                    j += 1;
                }
            }
            key.sort_unstable();
            let h = key
                .iter()
                .fold(0xcbf29ce484222325u64, |h, &k| {
                    (h ^ k).wrapping_mul(0x100000001b3)
                })
                .wrapping_mul(0x9E3779B97F4A7C15);
            let home = ((h >> 32) % size as u64) as usize;
            send[home].extend_from_slice(&[key[0], key[1], key[2], (lo + i) as u64]);
        }
    }
    let recv = exchange(world, send);
    let mut recs: Vec<[u64; 4]> = recv
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    recs.sort_unstable();
    let mut back = vec![Vec::new(); size];
    let mut i = 0;
    while i < recs.len() {
        let mut j = i;
        while j < recs.len() && recs[j][..3] == recs[i][..3] {
            j += 1;
        }
        for a in i..j {
            for c in i..j {
                if a != c {
                    let ca = recs[a][3] as usize;
                    back[block_of(ca, b.n_cells, size)].extend_from_slice(&[ca as u64, recs[c][3]]);
                }
            }
        }
        i = j;
    }
    let recv = exchange(world, back);
    let mut adj: Vec<Vec<PInt>> = vec![Vec::new(); n_local];
    for p in recv.chunks_exact(2) {
        adj[p[0] as usize - lo].push(p[1] as PInt);
    }
    let mut xadj = Vec::with_capacity(n_local + 1);
    let mut adjncy = Vec::new();
    xadj.push(0 as PInt);
    for mut a in adj {
        a.sort_unstable();
        a.dedup();
        adjncy.extend_from_slice(&a);
        xadj.push(adjncy.len() as PInt);
    }
    (xadj, adjncy)
}

/// A received boundary element: (element, tag, nodes, groups).
type BndRec = (u64, u64, [u64; 3], Vec<u64>);

/// Load imbalance PT-Scotch may leave between the parts (PETSc's default, 1 %).
const SCOTCH_IMBALANCE: f64 = 0.01;

/// What [`read_distributed`] gives: the local mesh and its layout, and the seconds of the
/// read and of the partition (with the migration).
pub struct Distributed {
    pub mesh: Mesh,
    pub layout: Layout,
    pub read_seconds: f64,
    pub partition_seconds: f64,
}

/// Reads the mesh file distributed over the ranks of `world`, refines it as `refine` asks,
/// partitions and migrates it. Collective; an input error is the same on every rank.
pub fn read_distributed(ctx: &Ctx, path: &Path, refine: &Refine) -> Result<Distributed, RunError> {
    let (world, comm) = (ctx.world, ctx.comm());
    let t0 = std::time::Instant::now();
    let b = read_blocks(ctx, path)?;
    let b = refine::refine_blocks(ctx, path, b, refine)?;
    let read_seconds = t0.elapsed().as_secs_f64();
    let t1 = std::time::Instant::now();
    let (mesh, layout) = build(world, comm, b)?;
    Ok(Distributed {
        mesh,
        layout,
        read_seconds,
        partition_seconds: t1.elapsed().as_secs_f64(),
    })
}

/// Sorted, unique.
fn sorted_unique(mut v: Vec<u64>) -> Vec<u64> {
    v.sort_unstable();
    v.dedup();
    v
}

/// This rank and the number of ranks.
fn rank_size(world: &SimpleCommunicator) -> (usize, usize) {
    (world.rank() as usize, world.size() as usize)
}

/// Offsets of the ranks' blocks of `n` items each (all-gathered), with the total at the end.
fn gathered_offsets(world: &SimpleCommunicator, n: usize) -> Vec<usize> {
    let (_, size) = rank_size(world);
    let mut counts = vec![0u64; size];
    world.all_gather_into(&(n as u64), &mut counts[..]);
    let mut offsets = vec![0usize; size + 1];
    for r in 0..size {
        offsets[r + 1] = offsets[r] + counts[r] as usize;
    }
    offsets
}

/// Builds the local mesh and layout from the blocks read, in phases: partition, group
/// memberships, cells to their ranks, node holders and owners, ghost cells, boundary
/// elements, node data, global numbering, local mesh, layout. Collective.
fn build(
    world: &SimpleCommunicator,
    comm: MPI_Comm,
    b: Blocks,
) -> Result<(Mesh, Layout), RunError> {
    let dim = b.dim;
    let part = partition_cells(world, comm, &b)?;
    let elem_groups = element_groups(world, &b);
    let node_groups = node_groups(world, &b, &elem_groups);
    let own = own_cells(world, &b, part, &elem_groups);
    let own_nodes = sorted_unique(
        own.iter()
            .flat_map(|c| c.nodes[..dim + 1].to_vec())
            .collect(),
    );
    let (homes, owners) = node_homes(world, &b, &own_nodes);
    let ghosts = ghost_cells(world, &own, &owners, dim + 1);
    let bnd = boundary_elements(world, &b, &elem_groups, &homes);
    drop(elem_groups);
    let orig = local_node_list(&b, own_nodes, &ghosts, &bnd);
    let bbox = global_bbox(world, &b);
    let reply = node_data_reply(world, &b, &homes, &node_groups, &orig);
    let whole = WholeMesh {
        dim,
        n_nodes: b.n_nodes,
        n_facets: b.n_bnd[0],
        groups: b.groups.clone(),
        group_sizes: b.group_sizes.clone(),
        bbox,
    };
    drop(b);
    drop(homes);
    drop(node_groups);
    let nodes = LocalNodes::receive(world, reply, orig);
    let numbering = global_numbering(world, &nodes, &whole);
    let mut nodes = nodes;
    let mesh = local_mesh(world, &whole, &mut nodes, &own, &ghosts, &bnd);
    let layout = local_layout(world, &mesh, nodes, numbering, &own, &ghosts);
    Ok((mesh, layout))
}

/// Phase 1: the rank of every cell of this block (the same dual-graph rows on the same blocks as
/// the whole-mesh path: the same partition).
fn partition_cells(
    world: &SimpleCommunicator,
    comm: MPI_Comm,
    b: &Blocks,
) -> Result<Vec<u64>, RunError> {
    let (_, size) = rank_size(world);
    if size == 1 {
        return Ok(vec![0; b.cell_tags.len()]);
    }
    let (xadj, adjncy) = dual_graph(world, b);
    let p = if !petsc::options::has("-mat_partitioning_type")? {
        petsc::scotch_partition(comm, &xadj, &adjncy, size, SCOTCH_IMBALANCE)?
    } else {
        petsc::partition_graph(comm, b.n_cells, &xadj, &adjncy, "ptscotch")?
    };
    Ok(p.iter().map(|&r| r as u64).collect())
}

/// Phase 2a: group memberships sent to the readers of the elements:
/// kind → (element − first of this rank's block) → groups.
fn element_groups(world: &SimpleCommunicator, b: &Blocks) -> [Vec<Vec<u64>>; 4] {
    let (rank, size) = rank_size(world);
    let mut send = vec![Vec::new(); size];
    for &(g, e) in &b.members {
        let k = b.kind(b.groups[g as usize].dim);
        let r = block_of(e as usize, b.count(k), size);
        send[r].extend_from_slice(&[k as u64, e, g]);
    }
    let recv = exchange(world, send);
    let mut elem_groups: [Vec<Vec<u64>>; 4] = Default::default();
    let elem_lo: [usize; 4] = std::array::from_fn(|k| blk(b.count(k), size, rank));
    for k in 0..4 {
        elem_groups[k] = vec![Vec::new(); blk(b.count(k), size, rank + 1) - elem_lo[k]];
    }
    for c in recv.chunks_exact(3) {
        let k = c[0] as usize;
        elem_groups[k][c[1] as usize - elem_lo[k]].push(c[2]);
    }
    elem_groups
}

/// Phase 2b: node-level memberships at the node homes: per home node, its groups (sorted, unique).
fn node_groups(
    world: &SimpleCommunicator,
    b: &Blocks,
    elem_groups: &[Vec<Vec<u64>>; 4],
) -> Vec<Vec<u64>> {
    let (rank, size) = rank_size(world);
    let node_lo = blk(b.n_nodes, size, rank);
    let mut send = vec![Vec::new(); size];
    for (k, list) in elem_groups.iter().enumerate() {
        let w = b.width(k);
        for (i, gs) in list.iter().enumerate() {
            if gs.is_empty() {
                continue;
            }
            let nodes = if k == 0 {
                &b.cells[i * w..(i + 1) * w]
            } else {
                &b.bnd[k - 1][i * w..(i + 1) * w]
            };
            for &v in nodes {
                let h = block_of(v as usize, b.n_nodes, size);
                for &g in gs {
                    send[h].extend_from_slice(&[v, g]);
                }
            }
        }
    }
    let recv = exchange(world, send);
    let mut node_groups: Vec<Vec<u64>> = vec![Vec::new(); b.node_tags.len()];
    for c in recv.chunks_exact(2) {
        node_groups[c[0] as usize - node_lo].push(c[1]);
    }
    for g in node_groups.iter_mut() {
        g.sort_unstable();
        g.dedup();
    }
    node_groups
}

/// A migrated cell: global number, rank, tag, nodes, groups.
struct CellRec {
    gc: u64,
    rank: u32,
    tag: u64,
    nodes: [u64; 4],
    groups: Vec<u64>,
}

/// Cell records [global cell, (rank,) tag, nodes (npc), n groups, groups], sorted by global
/// cell; without `with_rank` the cells are this rank's (`rank`).
fn parse_cells(recv: &[u64], with_rank: bool, rank: usize, npc: usize) -> Vec<CellRec> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < recv.len() {
        let gc = recv[i];
        let (r, off) = if with_rank {
            (recv[i + 1] as u32, 1)
        } else {
            (rank as u32, 0)
        };
        let tag = recv[i + 1 + off];
        let mut nodes = [0u64; 4];
        nodes[..npc].copy_from_slice(&recv[i + 2 + off..i + 2 + off + npc]);
        let ng = recv[i + 2 + off + npc] as usize;
        let s = i + 3 + off + npc;
        out.push(CellRec {
            gc,
            rank: r,
            tag,
            nodes,
            groups: recv[s..s + ng].to_vec(),
        });
        i = s + ng;
    }
    out.sort_unstable_by_key(|c| c.gc);
    out
}

/// Phase 3: the cells to their ranks: this rank's own cells, in global order.
fn own_cells(
    world: &SimpleCommunicator,
    b: &Blocks,
    part: Vec<u64>,
    elem_groups: &[Vec<Vec<u64>>; 4],
) -> Vec<CellRec> {
    let (rank, size) = rank_size(world);
    let npc = b.dim + 1;
    let cell_lo = blk(b.n_cells, size, rank);
    let mut send = vec![Vec::new(); size];
    for (i, cell) in b.cells.chunks_exact(npc).enumerate() {
        let s = &mut send[part[i] as usize];
        s.extend_from_slice(&[(cell_lo + i) as u64, b.cell_tags[i]]);
        s.extend_from_slice(cell);
        let gs = &elem_groups[0][i];
        s.push(gs.len() as u64);
        s.extend_from_slice(gs);
    }
    drop(part);
    parse_cells(&exchange(world, send), false, rank, npc)
}

/// What the home rank of a block of nodes knows of them: the ranks holding each (ascending;
/// the first, the lowest, owns it).
struct Homes {
    node_lo: usize,
    holders: Vec<Vec<u32>>,
}

impl Homes {
    fn holders_of(&self, v: u64) -> &[u32] {
        &self.holders[v as usize - self.node_lo]
    }

    /// The owner of home node v (u64::MAX if no cell holds it).
    fn owner(&self, v: u64) -> u64 {
        self.holders_of(v).first().map_or(u64::MAX, |&r| r as u64)
    }
}

/// The owners of this rank's own nodes, sorted by node.
struct Owners(Vec<(u64, u64)>);

impl Owners {
    fn of(&self, v: u64) -> u64 {
        let i = self
            .0
            .binary_search_by_key(&v, |p| p.0)
            .expect("asked for it");
        self.0[i].1
    }
}

/// Phase 4: holders and owners: every rank tells the homes which nodes its cells hold; the homes
/// answer with the owners.
fn node_homes(world: &SimpleCommunicator, b: &Blocks, own_nodes: &[u64]) -> (Homes, Owners) {
    let (rank, size) = rank_size(world);
    let node_lo = blk(b.n_nodes, size, rank);
    let mut send = vec![Vec::new(); size];
    for &v in own_nodes {
        send[block_of(v as usize, b.n_nodes, size)].push(v);
    }
    let (recv_nodes, node_counts) = exchange_counted(world, send);
    // per home node, the holder ranks (ascending by construction of exchange)
    let mut homes = Homes {
        node_lo,
        holders: vec![Vec::new(); b.node_tags.len()],
    };
    let mut i = 0;
    for (r, &c) in node_counts.iter().enumerate() {
        for _ in 0..c {
            homes.holders[recv_nodes[i] as usize - node_lo].push(r as u32);
            i += 1;
        }
    }
    let mut reply = vec![Vec::new(); size];
    let mut i = 0;
    for (r, &c) in node_counts.iter().enumerate() {
        for _ in 0..c {
            let v = recv_nodes[i];
            reply[r].extend_from_slice(&[v, homes.owner(v)]);
            i += 1;
        }
    }
    let recv = exchange(world, reply);
    let mut owner_pairs: Vec<(u64, u64)> = recv.chunks_exact(2).map(|c| (c[0], c[1])).collect();
    owner_pairs.sort_unstable();
    (homes, Owners(owner_pairs))
}

/// Phase 5: ghost cells: every own cell to the owners of its nodes.
fn ghost_cells(
    world: &SimpleCommunicator,
    own: &[CellRec],
    owners: &Owners,
    npc: usize,
) -> Vec<CellRec> {
    let (rank, size) = rank_size(world);
    let mut send = vec![Vec::new(); size];
    for c in own {
        let mut targets: Vec<usize> = c.nodes[..npc]
            .iter()
            .map(|&v| owners.of(v) as usize)
            .filter(|&r| r != rank)
            .collect();
        targets.sort_unstable();
        targets.dedup();
        for r in targets {
            let s = &mut send[r];
            s.extend_from_slice(&[c.gc, rank as u64, c.tag]);
            s.extend_from_slice(&c.nodes[..npc]);
            s.push(c.groups.len() as u64);
            s.extend_from_slice(&c.groups);
        }
    }
    parse_cells(&exchange(world, send), true, rank, npc)
}

/// Phase 6: boundary elements to every rank holding one of their nodes, through the homes:
/// [kind, element, tag, nodes (width), n groups, groups] → kind − 1 → sorted records.
fn boundary_elements(
    world: &SimpleCommunicator,
    b: &Blocks,
    elem_groups: &[Vec<Vec<u64>>; 4],
    homes: &Homes,
) -> [Vec<BndRec>; 3] {
    let (rank, size) = rank_size(world);
    let mut send = vec![Vec::new(); size];
    for k in 1..4 {
        let w = b.width(k);
        let lo = blk(b.count(k), size, rank);
        for (i, nodes) in b.bnd[k - 1].chunks_exact(w).enumerate() {
            let gs = &elem_groups[k][i];
            let mut to: Vec<usize> = nodes
                .iter()
                .map(|&v| block_of(v as usize, b.n_nodes, size))
                .collect();
            to.sort_unstable();
            to.dedup();
            for h in to {
                let s = &mut send[h];
                s.extend_from_slice(&[k as u64, (lo + i) as u64, b.bnd_tags[k - 1][i]]);
                s.extend_from_slice(nodes);
                s.push(gs.len() as u64);
                s.extend_from_slice(gs);
            }
        }
    }
    let recv = exchange(world, send);
    // at the homes: forward each record to the holders of its home nodes
    let mut send = vec![Vec::new(); size];
    let mut i = 0;
    while i < recv.len() {
        let k = recv[i] as usize;
        let w = b.width(k);
        let len = 3 + w + 1 + recv[i + 3 + w] as usize;
        let rec = &recv[i..i + len];
        let mut to: Vec<u32> = rec[3..3 + w]
            .iter()
            .filter(|&&v| block_of(v as usize, b.n_nodes, size) == rank)
            .flat_map(|&v| homes.holders_of(v).iter().copied())
            .collect();
        to.sort_unstable();
        to.dedup();
        for r in to {
            send[r as usize].extend_from_slice(rec);
        }
        i += len;
    }
    let recv = exchange(world, send);
    let mut bnd: [Vec<BndRec>; 3] = Default::default();
    let mut i = 0;
    while i < recv.len() {
        let k = recv[i] as usize;
        let w = b.width(k);
        let ng = recv[i + 3 + w] as usize;
        let mut nodes = [0u64; 3];
        nodes[..w].copy_from_slice(&recv[i + 3..i + 3 + w]);
        bnd[k - 1].push((
            recv[i + 1],
            recv[i + 2],
            nodes,
            recv[i + 4 + w..i + 4 + w + ng].to_vec(),
        ));
        i += 4 + w + ng;
    }
    for list in bnd.iter_mut() {
        list.sort_unstable_by_key(|e| e.0);
        list.dedup_by_key(|e| e.0);
    }
    bnd
}

/// Phase 7a: the local nodes (mesh numbers, sorted): those of the own cells, the ghosts and the
/// boundary elements.
fn local_node_list(
    b: &Blocks,
    own_nodes: Vec<u64>,
    ghosts: &[CellRec],
    bnd: &[Vec<BndRec>; 3],
) -> Vec<u64> {
    let mut all = own_nodes;
    all.extend(ghosts.iter().flat_map(|c| c.nodes[..b.dim + 1].to_vec()));
    for (k, list) in bnd.iter().enumerate() {
        let w = b.width(k + 1);
        all.extend(list.iter().flat_map(|e| e.2[..w].to_vec()));
    }
    sorted_unique(all)
}

/// The bounding box of the whole mesh, from the coordinate blocks. Collective.
fn global_bbox(world: &SimpleCommunicator, b: &Blocks) -> ([f64; 3], [f64; 3]) {
    let mut lohi = [f64::INFINITY; 6];
    for x in b.coords.chunks_exact(3) {
        for k in 0..3 {
            lohi[k] = lohi[k].min(x[k]);
            lohi[3 + k] = lohi[3 + k].min(-x[k]);
        }
    }
    let mut glohi = [0.0; 6];
    world.all_reduce_into(
        &lohi[..],
        &mut glohi[..],
        mpi::collective::SystemOperation::min(),
    );
    (
        [glohi[0], glohi[1], glohi[2]],
        [-glohi[3], -glohi[4], -glohi[5]],
    )
}

/// Phase 7b: the homes' answers to the requests for the local nodes' data:
/// [v, owner, tag, x, y, z, n groups, groups] per requested node, per requesting rank.
fn node_data_reply(
    world: &SimpleCommunicator,
    b: &Blocks,
    homes: &Homes,
    node_groups: &[Vec<u64>],
    orig: &[u64],
) -> Vec<Vec<u64>> {
    let (_, size) = rank_size(world);
    let mut send = vec![Vec::new(); size];
    for &v in orig {
        send[block_of(v as usize, b.n_nodes, size)].push(v);
    }
    let (req, counts) = exchange_counted(world, send);
    let mut reply = vec![Vec::new(); size];
    let mut i = 0;
    for (r, &c) in counts.iter().enumerate() {
        for _ in 0..c {
            let v = req[i];
            let j = v as usize - homes.node_lo;
            let x = &b.coords[3 * j..3 * j + 3];
            let gs = &node_groups[j];
            reply[r].extend_from_slice(&[
                v,
                homes.owner(v),
                b.node_tags[j],
                x[0].to_bits(),
                x[1].to_bits(),
                x[2].to_bits(),
                gs.len() as u64,
            ]);
            reply[r].extend_from_slice(gs);
            i += 1;
        }
    }
    reply
}

/// What is kept of the whole mesh once its blocks are dropped.
struct WholeMesh {
    dim: usize,
    n_nodes: usize,
    n_facets: usize,
    groups: Vec<Group>,
    group_sizes: Vec<usize>,
    bbox: ([f64; 3], [f64; 3]),
}

/// The local nodes (mesh numbers `orig`, sorted) and their data.
struct LocalNodes {
    orig: Vec<u64>,
    coords: Vec<[f64; 3]>,
    tags: Vec<u64>,
    owner: Vec<u32>,
    /// Groups of local node l: group_ids[group_ptr[l]..group_ptr[l + 1]].
    group_ptr: Vec<usize>,
    group_ids: Vec<u32>,
}

impl LocalNodes {
    /// Phase 7c: sends the homes' replies and unpacks the answers. Collective.
    fn receive(world: &SimpleCommunicator, reply: Vec<Vec<u64>>, orig: Vec<u64>) -> LocalNodes {
        let recv = exchange(world, reply);
        let nl = orig.len();
        let mut n = LocalNodes {
            coords: vec![[0.0; 3]; nl],
            tags: vec![0u64; nl],
            owner: vec![0u32; nl],
            group_ptr: vec![0usize; nl + 1],
            group_ids: Vec::new(),
            orig,
        };
        let mut recs: Vec<(usize, usize)> = Vec::with_capacity(nl); // (local, start in recv)
        let mut i = 0;
        while i < recv.len() {
            let l = n.local(recv[i]);
            recs.push((l, i));
            i += 7 + recv[i + 6] as usize;
        }
        recs.sort_unstable();
        for &(l, i) in &recs {
            n.owner[l] = recv[i + 1] as u32;
            n.tags[l] = recv[i + 2];
            n.coords[l] = [
                f64::from_bits(recv[i + 3]),
                f64::from_bits(recv[i + 4]),
                f64::from_bits(recv[i + 5]),
            ];
            let ng = recv[i + 6] as usize;
            n.group_ids
                .extend(recv[i + 7..i + 7 + ng].iter().map(|&g| g as u32));
            n.group_ptr[l + 1] = n.group_ids.len();
        }
        n
    }

    /// The local index of mesh node v.
    fn local(&self, v: u64) -> usize {
        self.orig.binary_search(&v).expect("local node")
    }
}

/// The global node numbering.
struct Numbering {
    /// Local indices of the owned nodes, in global order.
    owned: Vec<usize>,
    node_offsets: Vec<usize>,
    node_global: Vec<usize>,
}

/// Phase 8: global numbering: the owned nodes along the Morton curve of the whole mesh (ties
/// by mesh order); the owners answer for the other local nodes. Collective.
fn global_numbering(world: &SimpleCommunicator, n: &LocalNodes, whole: &WholeMesh) -> Numbering {
    let (rank, size) = rank_size(world);
    let (dim, bbox) = (whole.dim, &whole.bbox);
    let nl = n.orig.len();
    let extent = (0..dim)
        .map(|k| bbox.1[k] - bbox.0[k])
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut keyed: Vec<(u64, u64, usize)> = (0..nl)
        .filter(|&l| n.owner[l] as usize == rank)
        .map(|l| (morton_key(&n.coords[l], dim, &bbox.0, extent), n.orig[l], l))
        .collect();
    keyed.sort_unstable();
    let owned: Vec<usize> = keyed.into_iter().map(|k| k.2).collect();
    let node_offsets = gathered_offsets(world, owned.len());
    let mut node_global = vec![usize::MAX; nl];
    for (i, &l) in owned.iter().enumerate() {
        node_global[l] = node_offsets[rank] + i;
    }
    let mut send = vec![Vec::new(); size];
    for l in 0..nl {
        if n.owner[l] as usize != rank {
            send[n.owner[l] as usize].push(n.orig[l]);
        }
    }
    let (req, counts_req) = exchange_counted(world, send);
    let mut reply = vec![Vec::new(); size];
    let mut i = 0;
    for (r, &c) in counts_req.iter().enumerate() {
        for _ in 0..c {
            let l = n.local(req[i]);
            reply[r].extend_from_slice(&[req[i], node_global[l] as u64]);
            i += 1;
        }
    }
    let recv = exchange(world, reply);
    for c in recv.chunks_exact(2) {
        node_global[n.local(c[0])] = c[1] as usize;
    }
    Numbering {
        owned,
        node_offsets,
        node_global,
    }
}

/// Phase 9: the local mesh: own cells (global order), then ghosts; boundary elements; groups (cell
/// groups hold own cells only); the whole mesh's counts. Takes the nodes' coordinates, tags
/// and groups out of `n` (no copies). Collective (one sum).
fn local_mesh(
    world: &SimpleCommunicator,
    whole: &WholeMesh,
    n: &mut LocalNodes,
    own: &[CellRec],
    ghosts: &[CellRec],
    bnd: &[Vec<BndRec>; 3],
) -> Mesh {
    let (rank, _) = rank_size(world);
    let (dim, npc) = (whole.dim, whole.dim + 1);
    let n_own = own.len();
    let mut cells = Vec::with_capacity((n_own + ghosts.len()) * npc);
    let mut cell_tags = Vec::with_capacity(n_own + ghosts.len());
    let mut groups: Vec<Group> = whole
        .groups
        .iter()
        .map(|g| Group {
            elements: Vec::new(),
            ..g.clone()
        })
        .collect();
    for (ci, c) in own.iter().chain(ghosts.iter()).enumerate() {
        cells.extend(c.nodes[..npc].iter().map(|&v| n.local(v)));
        cell_tags.push(c.tag);
        if ci < n_own {
            for &g in &c.groups {
                if groups[g as usize].dim == dim {
                    groups[g as usize].elements.push(ci);
                }
            }
        }
    }
    let mut lists: [(Vec<usize>, Vec<u64>); 3] = Default::default();
    for k in 0..3 {
        let w = [dim, 2, 1][k];
        for (i, e) in bnd[k].iter().enumerate() {
            lists[k].0.extend(e.2[..w].iter().map(|&v| n.local(v)));
            lists[k].1.push(e.1);
            for &g in &e.3 {
                groups[g as usize].elements.push(i);
            }
        }
    }
    let [(facets, facet_tags), (edges, edge_tags), (points, point_tags)] = lists;
    let mut mesh = Mesh {
        dim,
        coords: std::mem::take(&mut n.coords),
        node_tags: std::mem::take(&mut n.tags),
        cells,
        cell_tags,
        facets,
        facet_tags,
        edges,
        edge_tags,
        points,
        point_tags,
        groups,
        global: None,
    };
    let facet_checked: Vec<bool> = (0..mesh.n_facets())
        .map(|f| mesh.facet(f).iter().any(|&v| n.owner[v] as usize == rank))
        .collect();
    mesh.global = Some(Box::new(GlobalInfo {
        n_nodes: whole.n_nodes,
        n_cells: counts_sum(world, n_own),
        n_facets: whole.n_facets,
        group_sizes: whole.group_sizes.clone(),
        bbox: whole.bbox,
        node_group_ptr: std::mem::take(&mut n.group_ptr),
        node_group_ids: std::mem::take(&mut n.group_ids),
        facet_checked,
        n_own_cells: n_own,
    }));
    mesh
}

/// Phase 10: the layout: node ownership and numbering, own cells in the order of their lowest
/// global node (locality of the assembly loop), cell offsets of the output. Collective.
fn local_layout(
    world: &SimpleCommunicator,
    mesh: &Mesh,
    n: LocalNodes,
    numbering: Numbering,
    own: &[CellRec],
    ghosts: &[CellRec],
) -> Layout {
    let (rank, size) = rank_size(world);
    let n_own = own.len();
    let node_global = numbering.node_global;
    let mut local_cells: Vec<usize> = (0..n_own).collect();
    local_cells.sort_unstable_by_key(|&c| {
        (
            mesh.cell(c)
                .iter()
                .map(|&v| node_global[v])
                .min()
                .unwrap_or(0),
            own[c].gc,
        )
    });
    Layout {
        rank,
        size,
        cell_rank: own.iter().chain(ghosts).map(|c| c.rank).collect(),
        node_owner: n.owner,
        node_global,
        node_offsets: numbering.node_offsets,
        owned_nodes: numbering.owned,
        local_cells,
        cell_offsets: gathered_offsets(world, n_own),
        node_cells: NodeCells::new(mesh),
        node_orig: n.orig.iter().map(|&v| v as usize).collect(),
    }
}

fn counts_sum(world: &SimpleCommunicator, n: usize) -> usize {
    let mut s = 0u64;
    world.all_reduce_into(&(n as u64), &mut s, mpi::collective::SystemOperation::sum());
    s as usize
}
