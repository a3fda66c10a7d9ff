//! Distributed mesh input: every rank reads a contiguous block of the mesh (HDF5 hyperslabs;
//! an MSH file is read by rank 0, which sends every rank its blocks and then drops the whole
//! mesh), the dual graph of the cells is built without the whole mesh (facet keys hashed to a
//! home rank), PT-Scotch partitions the graph of its block-local aggregates (≤ 16 cells; the
//! dual graph itself on small meshes), the cells migrate to their ranks, the cells are checked
//! and oriented like the MSH reader's, and every rank builds a LOCAL [`Mesh`] (its own cells, the ghost cells touching its owned nodes, the boundary
//! elements touching any of its nodes) with a [`Layout`] of local size.
//!
//! Node homes: node i (mesh order) lives on rank `block_of(i, n_nodes)`, which read its
//! coordinates; the home learns which ranks hold the node (the ranks of the cells touching it),
//! its owner (the lowest of them) and the physical groups of the elements containing it.
//!
//! Every exchange is one all-to-all-v of flat u64 records, written by a closure in two
//! passes (count, fill: `exchange`); per-element data (groups, holders) are CSR arrays, and
//! local numbers come from one sort of (value, position) pairs, not from a search per entry.
//! Nothing depends on the order in which messages arrive or on a hash seed, so a run on a
//! fixed rank count repeats bit for bit. `SIGNORINI_DIST_PHASES=1` prints the seconds and
//! peak memory of every phase (`scripts/bench-dist`).
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

/// The records of one all-to-all-v, written by the same closure in two passes: the first
/// counts the u64 sent to every rank, the second writes them into one contiguous buffer at
/// their rank's place. No vector per item or per rank.
struct Packer {
    filling: bool,
    dest: usize,
    counts: Vec<usize>,
    fill: Vec<usize>,
    buf: Vec<u64>,
}

impl Packer {
    /// The next values go to rank r.
    fn to(&mut self, r: usize) -> &mut Packer {
        self.dest = r;
        self
    }

    fn push(&mut self, x: u64) {
        if self.filling {
            self.buf[self.fill[self.dest]] = x;
            self.fill[self.dest] += 1;
        } else {
            self.counts[self.dest] += 1;
        }
    }

    fn extend(&mut self, xs: &[u64]) {
        if self.filling {
            let f = self.fill[self.dest];
            self.buf[f..f + xs.len()].copy_from_slice(xs);
            self.fill[self.dest] += xs.len();
        } else {
            self.counts[self.dest] += xs.len();
        }
    }
}

/// What one all-to-all-v brought: every rank's records, concatenated in rank order.
struct Received {
    data: Vec<u64>,
    /// Rank r's records are data[offsets[r]..offsets[r + 1]].
    offsets: Vec<usize>,
}

impl Received {
    fn from(&self, r: usize) -> &[u64] {
        &self.data[self.offsets[r]..self.offsets[r + 1]]
    }
}

/// One all-to-all-v of u64 records (and one all-to-all of the counts): `pack` writes every
/// record with its destination; it is called twice (count, fill) and must write the same
/// records both times. Collective.
fn exchange(world: &SimpleCommunicator, mut pack: impl FnMut(&mut Packer)) -> Received {
    let size = world.size() as usize;
    let mut p = Packer {
        filling: false,
        dest: 0,
        counts: vec![0; size],
        fill: Vec::new(),
        buf: Vec::new(),
    };
    pack(&mut p);
    let displs = crate::par::offsets(&p.counts);
    let total: usize = p.counts.iter().sum();
    p.fill = displs.clone();
    p.buf = vec![0u64; total];
    p.filling = true;
    pack(&mut p);
    debug_assert!((0..size).all(|r| p.fill[r] == displs[r] + p.counts[r]));
    let to_i32 = |v: &[usize]| -> Vec<i32> {
        v.iter()
            .map(|&c| i32::try_from(c).expect("fewer than 2^31 values per message"))
            .collect()
    };
    let counts = to_i32(&p.counts);
    let mut rcounts = vec![0i32; size];
    world.all_to_all_into(&counts[..], &mut rcounts[..]);
    let rc: Vec<usize> = rcounts.iter().map(|&c| c as usize).collect();
    let mut offsets = crate::par::offsets(&rc);
    let rtotal: usize = rc.iter().sum();
    let mut data = vec![0u64; rtotal];
    {
        let sp = Partition::new(&p.buf[..], counts, to_i32(&displs));
        let mut rp = PartitionMut::new(&mut data[..], rcounts, to_i32(&offsets));
        world.all_to_all_varcount_into(&sp, &mut rp);
    }
    offsets.push(rtotal);
    Received { data, offsets }
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

/// The facet of `cell` without its corner `skip`: its nodes ascending (`u64::MAX` pads the
/// unused places).
fn facet_key(cell: &[u64], skip: usize) -> [u64; 3] {
    let mut key = [u64::MAX; 3];
    let mut j = 0;
    for (a, &v) in cell.iter().enumerate() {
        if a != skip {
            key[j] = v;
            j += 1;
        }
    }
    key[..j].sort_unstable();
    key
}

/// A 64-bit hash of a facet key.
fn facet_hash(key: &[u64; 3]) -> u64 {
    key.iter()
        .fold(0xcbf29ce484222325u64, |h, &k| {
            (h ^ k).wrapping_mul(0x100000001b3)
        })
        .wrapping_mul(0x9E3779B97F4A7C15)
}

/// A second, independent 24-bit hash of a facet key (with [`facet_hash`]: 88 bits).
fn facet_check(key: &[u64; 3]) -> u64 {
    key.iter().fold(0x2545F4914F6CDD1Du64, |h, &k| {
        (h.rotate_left(23) ^ k).wrapping_mul(0xff51afd7ed558ccd)
    }) >> 40
}

/// The rank that matches the cells sharing a facet (a hash of its key).
fn facet_home(key: &[u64; 3], size: usize) -> usize {
    ((facet_hash(key) >> 32) % size as u64) as usize
}

/// Calls `f` with every run of records with the same facet key (records sorted).
fn facet_runs(recs: &[[u64; 4]], mut f: impl FnMut(&[[u64; 4]])) {
    let mut i = 0;
    while i < recs.len() {
        let mut j = i + 1;
        while j < recs.len() && recs[j][..3] == recs[i][..3] {
            j += 1;
        }
        f(&recs[i..j]);
        i = j;
    }
}

/// Dual-graph rows of this rank's block of cells (cells sharing a facet), CSR, global cell
/// indices, neighbours ascending. A facet of exactly two cells of the block is matched on the
/// block's rank (by an 88-bit hash of its key); every other facet (on the boundary, between blocks, or of more than two
/// cells) is sent to a home rank chosen by hashing its key, which sends every pair of cells
/// sharing it back to the readers of the cells. Two exchanges. (A facet of two cells of one
/// block and more of other blocks — not a valid mesh — loses the pairs across.)
fn dual_graph(world: &SimpleCommunicator, b: &Blocks) -> (Vec<PInt>, Vec<PInt>) {
    let (rank, size) = rank_size(world);
    let (w, npc) = (b.dim, b.dim + 1);
    let lo = blk(b.n_cells, size, rank);
    let n_local = b.cell_tags.len();
    // (88-bit facet hash, cell · 4 + corner left out) of this block, sorted: 16-byte records,
    // equal facets next to each other. Two records of equal hash are taken as one facet of two
    // cells without comparing the keys (a false match, ~2^-88 per pair of facets, would only
    // add one edge to the partitioner's graph, never change the mesh); every other run of
    // equal hashes goes to the facets' homes, which match the keys exactly.
    let mut mine: Vec<u128> = Vec::with_capacity(n_local * npc);
    for (i, cell) in b.cells.chunks_exact(npc).enumerate() {
        for skip in 0..npc {
            let key = facet_key(cell, skip);
            mine.push(
                ((facet_hash(&key) as u128) << 64)
                    | ((facet_check(&key) as u128) << 40)
                    | (4 * i + skip) as u128,
            );
        }
    }
    mine.sort_unstable();
    let cell_of = |r: u128| ((r as u64 & ((1 << 40) - 1)) >> 2) as usize;
    let mut local_pairs: Vec<u64> = Vec::new();
    // [facet key (padded), cell] of the facets matched at their home rank
    let mut remote: Vec<[u64; 4]> = Vec::new();
    let mut i = 0;
    while i < mine.len() {
        let mut j = i + 1;
        while j < mine.len() && mine[j] >> 40 == mine[i] >> 40 {
            j += 1;
        }
        let (a, c) = (cell_of(mine[i]), cell_of(mine[j - 1]));
        if j - i == 2 && a != c {
            let (a, c) = ((lo + a) as u64, (lo + c) as u64);
            local_pairs.extend_from_slice(&[a, c, c, a]);
        } else {
            for &r in &mine[i..j] {
                let (c, skip) = (cell_of(r), (r as u64 & 3) as usize);
                let key = facet_key(&b.cells[c * npc..(c + 1) * npc], skip);
                remote.push([key[0], key[1], key[2], (lo + c) as u64]);
            }
        }
        i = j;
    }
    drop(mine);
    let recv = exchange(world, |p| {
        for r in &remote {
            let key = [r[0], r[1], r[2]];
            p.to(facet_home(&key, size)).extend(&key[..w]);
            p.push(r[3]);
        }
    });
    drop(remote);
    // at the homes: the cells of a facet are neighbours
    let mut recs: Vec<[u64; 4]> = recv
        .data
        .chunks_exact(w + 1)
        .map(|c| {
            let mut r = [u64::MAX; 4];
            r[..w].copy_from_slice(&c[..w]);
            r[3] = c[w];
            r
        })
        .collect();
    drop(recv);
    recs.sort_unstable();
    let pairs = exchange(world, |p| {
        facet_runs(&recs, |run| {
            for a in run {
                for c in run {
                    if a[3] != c[3] {
                        p.to(block_of(a[3] as usize, b.n_cells, size))
                            .extend(&[a[3], c[3]]);
                    }
                }
            }
        });
    });
    drop(recs);
    let all = || {
        local_pairs
            .chunks_exact(2)
            .chain(pairs.data.chunks_exact(2))
    };
    // CSR by a counting sort on the local cell, then every row sorted and unique.
    let mut start = vec![0usize; n_local + 1];
    for pr in all() {
        start[pr[0] as usize - lo + 1] += 1;
    }
    for i in 0..n_local {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut adjncy = vec![0 as PInt; start[n_local]];
    for pr in all() {
        let i = pr[0] as usize - lo;
        adjncy[fill[i]] = pr[1] as PInt;
        fill[i] += 1;
    }
    drop(pairs);
    drop(local_pairs);
    drop(fill);
    let mut xadj = Vec::with_capacity(n_local + 1);
    xadj.push(0 as PInt);
    let mut out = 0;
    for i in 0..n_local {
        adjncy[start[i]..start[i + 1]].sort_unstable();
        for k in start[i]..start[i + 1] {
            if k == start[i] || adjncy[k] != adjncy[k - 1] {
                adjncy[out] = adjncy[k];
                out += 1;
            }
        }
        xadj.push(out as PInt);
    }
    adjncy.truncate(out);
    (xadj, adjncy)
}

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
    let mut phases = Phases::start(world);
    let b = read_blocks(ctx, path)?;
    let b = refine::refine_blocks(ctx, path, b, refine)?;
    let read_seconds = t0.elapsed().as_secs_f64();
    phases.lap("read");
    phases.report(world);
    let t1 = std::time::Instant::now();
    let (mut mesh, layout) = build(world, comm, b)?;
    orient_local_cells(ctx, path, &mut mesh)?;
    Ok(Distributed {
        mesh,
        layout,
        read_seconds,
        partition_seconds: t1.elapsed().as_secs_f64(),
    })
}

/// The checks the MSH reader makes (`mesh::orient_cell`) on the local cells after the
/// migration (HDF5 cells are as the file has them; refined cells carry their parent's
/// orientation): an inverted cell gets two nodes swapped (ghost copies the same way as the
/// owner's), a cell of zero measure is an input error naming the file and the element. Of
/// several degenerate cells the one with the smallest tag is named, on any rank count.
/// Collective (one reduction, one agreement).
fn orient_local_cells(ctx: &Ctx, path: &Path, mesh: &mut Mesh) -> Result<(), RunError> {
    let (dim, npc) = (mesh.dim, mesh.dim + 1);
    let n_own = mesh
        .global
        .as_ref()
        .map_or(mesh.n_cells(), |g| g.n_own_cells);
    let mut worst: Option<(u64, String)> = None;
    for (c, cell) in mesh.cells.chunks_exact_mut(npc).enumerate() {
        let tag = mesh.cell_tags[c];
        if let Err(m) = mesh::orient_cell(dim, cell, tag, &mesh.coords) {
            // a ghost's owner reports it
            if c < n_own && worst.as_ref().is_none_or(|w| tag < w.0) {
                worst = Some((tag, m));
            }
        }
    }
    let mine = worst.as_ref().map_or(u64::MAX, |w| w.0);
    let mut first = u64::MAX;
    ctx.world
        .all_reduce_into(&mine, &mut first, mpi::collective::SystemOperation::min());
    let local = match worst {
        Some((tag, m)) if tag == first => Err(RunError::Input(InputError::new(path, m))),
        _ => Ok(()),
    };
    ctx.agree(local)
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
/// elements, node data, global numbering, local mesh, layout. Every exchange is one
/// all-to-all-v of flat records; the blocks' arrays are freed as soon as their last phase
/// ends. Collective.
fn build(
    world: &SimpleCommunicator,
    comm: MPI_Comm,
    mut b: Blocks,
) -> Result<(Mesh, Layout), RunError> {
    let mut phases = Phases::start(world);
    let dim = b.dim;
    let part = partition_cells(world, comm, &b, &mut phases)?;
    let elem_groups = element_groups(world, &b);
    b.members = Vec::new();
    phases.lap("element_groups");
    let node_groups = node_groups(world, &b, &elem_groups);
    phases.lap("node_groups");
    let own = own_cells(world, &b, &part, &elem_groups);
    drop(part);
    b.cells = Vec::new();
    b.cell_tags = Vec::new();
    let (own_nodes, own_index) = number_nodes(&own.nodes);
    phases.lap("own_cells");
    let (homes, own_owner) = node_homes(world, &b, &own_nodes);
    phases.lap("node_homes");
    let ghosts = ghost_cells(world, &own, &own_index, &own_owner);
    drop(own_owner);
    phases.lap("ghost_cells");
    let bnd = boundary_elements(world, &b, &elem_groups, &homes);
    drop(elem_groups);
    b.bnd = Default::default();
    b.bnd_tags = Default::default();
    phases.lap("boundary_elements");
    let (orig, own_local) = local_node_list(own_nodes, &ghosts, &bnd);
    let bbox = global_bbox(world, &b);
    let mut nodes = node_data(world, &b, &homes, &node_groups, orig);
    let whole = WholeMesh {
        dim,
        n_nodes: b.n_nodes,
        n_facets: b.n_bnd[0],
        groups: std::mem::take(&mut b.groups),
        group_sizes: std::mem::take(&mut b.group_sizes),
        bbox,
    };
    drop(b);
    drop(homes);
    drop(node_groups);
    phases.lap("node_data");
    let numbering = global_numbering(world, &nodes, &whole);
    phases.lap("global_numbering");
    let cell_nodes: Vec<usize> = own_index
        .iter()
        .map(|&i| own_local[i as usize] as usize)
        .chain(ghosts.nodes.iter().map(|&v| nodes.local(v)))
        .collect();
    drop(own_index);
    drop(own_local);
    let mesh = local_mesh(world, &whole, &mut nodes, cell_nodes, &own, &ghosts, &bnd);
    drop(bnd);
    phases.lap("local_mesh");
    let layout = local_layout(world, &mesh, nodes, numbering, &own, &ghosts);
    phases.lap("local_layout");
    phases.report(world);
    Ok((mesh, layout))
}

/// Phase 1: the rank of every cell of this block. PT-Scotch partitions the coarse graph of
/// [`aggregate`]'s aggregates (vertex weight: cells, edge weight: facets), which makes its
/// multilevel run far shorter (on the 557 k-cell Hertz disk: 35 k vertices instead of 557 k,
/// at a ~25 % larger edge cut); meshes with fewer than 2 × [`COARSE_PER_PART`] cells per part
/// partition the dual graph itself (as the whole-mesh path `partition::partition` does).
/// `-mat_partitioning_type` sends the dual graph through PETSc's MatPartitioning instead.
fn partition_cells(
    world: &SimpleCommunicator,
    comm: MPI_Comm,
    b: &Blocks,
    phases: &mut Phases,
) -> Result<Vec<u32>, RunError> {
    let (_, size) = rank_size(world);
    if size == 1 {
        return Ok(vec![0; b.cell_tags.len()]);
    }
    let (xadj, adjncy) = dual_graph(world, b);
    phases.lap("dual_graph");
    let part: Vec<u32> = if petsc::options::has("-mat_partitioning_type")? {
        let p = petsc::partition_graph(comm, b.n_cells, &xadj, &adjncy, "ptscotch")?;
        phases.lap("scotch");
        p.iter().map(|&r| r as u32).collect()
    } else if aggregate_size(b.n_cells, size) == 1 {
        let p = petsc::scotch_partition(comm, &xadj, &adjncy, None, size, SCOTCH_IMBALANCE)?;
        phases.lap("scotch");
        p.iter().map(|&r| r as u32).collect()
    } else {
        let k = aggregate_size(b.n_cells, size);
        let lo = blk(b.n_cells, size, world.rank() as usize);
        let (agg, n_agg) = aggregate(lo, &xadj, &adjncy, k);
        let c = coarse_graph(world, b.n_cells, &xadj, &adjncy, &agg, n_agg);
        phases.lap("coarse_graph");
        let p = petsc::scotch_partition(
            comm,
            &c.xadj,
            &c.adjncy,
            Some((&c.vwgt, &c.ewgt)),
            size,
            SCOTCH_IMBALANCE,
        )?;
        phases.lap("scotch");
        agg.iter().map(|&a| p[a as usize] as u32).collect()
    };
    if phases.on {
        report_partition(world, b.n_cells, &xadj, &adjncy, &part);
    }
    Ok(part)
}

/// Most cells in one aggregate of the coarse graph that PT-Scotch partitions.
const AGGREGATE_CELLS: usize = 16;
/// Fewest coarse vertices per part: smaller meshes get smaller aggregates.
const COARSE_PER_PART: usize = 256;

/// Cells per aggregate for `n_cells` cells on `size` parts: [`AGGREGATE_CELLS`], less where
/// that would leave fewer than [`COARSE_PER_PART`] coarse vertices per part (1: the dual
/// graph itself).
fn aggregate_size(n_cells: usize, size: usize) -> usize {
    (n_cells / (size * COARSE_PER_PART)).clamp(1, AGGREGATE_CELLS)
}

/// Groups the cells of this block (first global index `lo`, dual-graph rows `xadj`/`adjncy`)
/// into aggregates of at most `k` cells: each grows breadth first from the lowest cell not yet
/// taken, over neighbours of the same block, so it is connected and compact. Returns every
/// cell's aggregate (local number, in the order of the seeds) and the number of aggregates.
/// Depends only on the block's rows: deterministic.
fn aggregate(lo: usize, xadj: &[PInt], adjncy: &[PInt], k: usize) -> (Vec<u32>, usize) {
    let n = xadj.len() - 1;
    let mut agg = vec![u32::MAX; n];
    let mut queue: Vec<usize> = Vec::with_capacity(4 * k);
    let mut n_agg = 0u32;
    for seed in 0..n {
        if agg[seed] != u32::MAX {
            continue;
        }
        agg[seed] = n_agg;
        queue.clear();
        queue.push(seed);
        let (mut head, mut taken) = (0, 1);
        while head < queue.len() && taken < k {
            let i = queue[head];
            head += 1;
            for &j in &adjncy[xadj[i] as usize..xadj[i + 1] as usize] {
                let j = (j as usize).wrapping_sub(lo);
                if j < n && agg[j] == u32::MAX && taken < k {
                    agg[j] = n_agg;
                    queue.push(j);
                    taken += 1;
                }
            }
        }
        n_agg += 1;
    }
    (agg, n_agg as usize)
}

/// The coarse graph of the aggregates: this rank's rows (aggregates numbered in rank order),
/// vertex weight = cells, edge weight = facets between the two aggregates.
struct CoarseGraph {
    xadj: Vec<PInt>,
    adjncy: Vec<PInt>,
    vwgt: Vec<PInt>,
    ewgt: Vec<PInt>,
}

/// Builds the coarse graph of [`aggregate`]'s aggregates from the dual-graph rows of this
/// block. One exchange: every cell with a neighbour in another block sends its global
/// aggregate to that block. Collective.
fn coarse_graph(
    world: &SimpleCommunicator,
    n_cells: usize,
    xadj: &[PInt],
    adjncy: &[PInt],
    agg: &[u32],
    n_agg: usize,
) -> CoarseGraph {
    let (rank, size) = rank_size(world);
    let (lo, n) = (blk(n_cells, size, rank), agg.len());
    let first = gathered_offsets(world, n_agg)[rank] as u64;
    let recv = exchange(world, |p| {
        for i in 0..n {
            for &j in &adjncy[xadj[i] as usize..xadj[i + 1] as usize] {
                let j = j as usize;
                if j < lo || j >= lo + n {
                    p.to(block_of(j, n_cells, size))
                        .extend(&[(lo + i) as u64, first + agg[i] as u64]);
                }
            }
        }
    });
    // remote cell → its global aggregate, sorted by cell
    let mut remote: Vec<(u64, u64)> = recv.data.chunks_exact(2).map(|c| (c[0], c[1])).collect();
    drop(recv);
    remote.sort_unstable();
    remote.dedup();
    let global_agg = |j: usize| -> u64 {
        if j >= lo && j < lo + n {
            first + agg[j - lo] as u64
        } else {
            let at = remote.partition_point(|r| r.0 < j as u64);
            remote[at].1
        }
    };
    // (local aggregate, neighbour aggregate) of every facet between aggregates
    let mut pairs: Vec<(u32, u64)> = Vec::new();
    let mut vwgt = vec![0 as PInt; n_agg];
    for i in 0..n {
        let a = agg[i];
        vwgt[a as usize] += 1;
        for &j in &adjncy[xadj[i] as usize..xadj[i + 1] as usize] {
            let c = global_agg(j as usize);
            if c != first + a as u64 {
                pairs.push((a, c));
            }
        }
    }
    pairs.sort_unstable();
    let mut cx = Vec::with_capacity(n_agg + 1);
    let (mut adj, mut ewgt) = (Vec::new(), Vec::new());
    cx.push(0 as PInt);
    let mut k = 0;
    for a in 0..n_agg as u32 {
        while k < pairs.len() && pairs[k].0 == a {
            let c = pairs[k].1;
            let mut w = 0;
            while k < pairs.len() && pairs[k] == (a, c) {
                w += 1;
                k += 1;
            }
            adj.push(c as PInt);
            ewgt.push(w);
        }
        cx.push(adj.len() as PInt);
    }
    CoarseGraph {
        xadj: cx,
        adjncy: adj,
        vwgt,
        ewgt,
    }
}

/// Diagnostics (`SIGNORINI_DIST_PHASES`): rank 0 prints the edge cut of the dual graph (facets
/// between cells of different parts) and the cells per part. Collective; gathers the whole
/// partition, so only for benchmarks.
fn report_partition(
    world: &SimpleCommunicator,
    n_cells: usize,
    xadj: &[PInt],
    adjncy: &[PInt],
    part: &[u32],
) {
    let (rank, size) = rank_size(world);
    let counts: Vec<i32> = (0..size)
        .map(|r| (blk(n_cells, size, r + 1) - blk(n_cells, size, r)) as i32)
        .collect();
    let displs: Vec<i32> = (0..size).map(|r| blk(n_cells, size, r) as i32).collect();
    let mut all = vec![0u32; n_cells];
    world.all_gather_varcount_into(part, &mut PartitionMut::new(&mut all[..], counts, displs));
    let lo = blk(n_cells, size, rank);
    let mut cut = 0u64;
    for (i, w) in xadj.windows(2).enumerate() {
        for &j in &adjncy[w[0] as usize..w[1] as usize] {
            cut += (all[lo + i] != all[j as usize]) as u64;
        }
    }
    let mut total = 0u64;
    world.all_reduce_into(&cut, &mut total, mpi::collective::SystemOperation::sum());
    if rank == 0 {
        let mut per = vec![0usize; size];
        for &p in &all {
            per[p as usize] += 1;
        }
        let max = per.iter().copied().max().unwrap_or(0) as f64;
        eprintln!(
            "dist partition edge cut {} facets, cells per part {per:?} (max/mean {:.4})",
            total / 2,
            max * size as f64 / n_cells.max(1) as f64
        );
    }
}

/// The groups of this rank's block of elements of every kind, CSR over (element − first of
/// the block).
struct ElemGroups {
    ptr: [Vec<usize>; 4],
    ids: [Vec<u32>; 4],
}

impl ElemGroups {
    /// The groups of element i (of this rank's block) of kind k.
    fn of(&self, k: usize, i: usize) -> &[u32] {
        &self.ids[k][self.ptr[k][i]..self.ptr[k][i + 1]]
    }
}

/// Phase 2a: group memberships sent to the readers of the elements (one exchange of
/// [kind, element, group]); each element's groups in the file's order.
fn element_groups(world: &SimpleCommunicator, b: &Blocks) -> ElemGroups {
    let (rank, size) = rank_size(world);
    let recv = exchange(world, |p| {
        for &(g, e) in &b.members {
            let k = b.kind(b.groups[g as usize].dim);
            p.to(block_of(e as usize, b.count(k), size))
                .extend(&[k as u64, e, g]);
        }
    });
    let lo: [usize; 4] = std::array::from_fn(|k| blk(b.count(k), size, rank));
    let mut ptr: [Vec<usize>; 4] =
        std::array::from_fn(|k| vec![0; blk(b.count(k), size, rank + 1) - lo[k] + 1]);
    for c in recv.data.chunks_exact(3) {
        let k = c[0] as usize;
        ptr[k][c[1] as usize - lo[k] + 1] += 1;
    }
    for p in ptr.iter_mut() {
        for i in 1..p.len() {
            p[i] += p[i - 1];
        }
    }
    let mut ids: [Vec<u32>; 4] = std::array::from_fn(|k| vec![0; *ptr[k].last().unwrap_or(&0)]);
    let mut fill = ptr.clone();
    for c in recv.data.chunks_exact(3) {
        let (k, i) = (c[0] as usize, c[1] as usize - lo[c[0] as usize]);
        ids[k][fill[k][i]] = c[2] as u32;
        fill[k][i] += 1;
    }
    ElemGroups { ptr, ids }
}

/// The groups of this rank's home nodes, CSR over (node − first home node): the groups of
/// every element containing the node, ascending, unique.
struct NodeGroups {
    ptr: Vec<usize>,
    ids: Vec<u32>,
}

impl NodeGroups {
    fn of(&self, j: usize) -> &[u32] {
        &self.ids[self.ptr[j]..self.ptr[j + 1]]
    }
}

/// Phase 2b: node-level memberships at the node homes: every rank sends the distinct
/// (node, group) pairs of its block's elements (one exchange, one u64 each).
fn node_groups(world: &SimpleCommunicator, b: &Blocks, eg: &ElemGroups) -> NodeGroups {
    let (rank, size) = rank_size(world);
    let ng = b.groups.len().max(1) as u64;
    let mut codes: Vec<u64> = Vec::new();
    for k in 0..4 {
        let w = b.width(k);
        let list = if k == 0 { &b.cells } else { &b.bnd[k - 1] };
        for (i, nodes) in list.chunks_exact(w).enumerate() {
            for &g in eg.of(k, i) {
                codes.extend(nodes.iter().map(|&v| v * ng + g as u64));
            }
        }
    }
    codes.sort_unstable();
    codes.dedup();
    let recv = exchange(world, |p| {
        for &c in &codes {
            p.to(block_of((c / ng) as usize, b.n_nodes, size)).push(c);
        }
    });
    drop(codes);
    let mut got = recv.data;
    got.sort_unstable();
    got.dedup();
    let node_lo = blk(b.n_nodes, size, rank);
    let mut ptr = vec![0usize; b.node_tags.len() + 1];
    for &c in &got {
        ptr[(c / ng) as usize - node_lo + 1] += 1;
    }
    for i in 1..ptr.len() {
        ptr[i] += ptr[i - 1];
    }
    let ids = got.iter().map(|&c| (c % ng) as u32).collect();
    NodeGroups { ptr, ids }
}

/// Migrated elements of one width (cells, or boundary elements of one kind) as flat arrays:
/// global element number, rank (cells: the rank that owns the cell), tag, nodes (mesh
/// numbers), groups (CSR).
struct Elems {
    width: usize,
    id: Vec<u64>,
    rank: Vec<u32>,
    tag: Vec<u64>,
    nodes: Vec<u64>,
    gptr: Vec<usize>,
    gids: Vec<u32>,
}

impl Elems {
    fn new(width: usize) -> Elems {
        Elems {
            width,
            id: Vec::new(),
            rank: Vec::new(),
            tag: Vec::new(),
            nodes: Vec::new(),
            gptr: vec![0],
            gids: Vec::new(),
        }
    }

    fn len(&self) -> usize {
        self.id.len()
    }

    fn nodes_of(&self, i: usize) -> &[u64] {
        &self.nodes[i * self.width..(i + 1) * self.width]
    }

    fn groups_of(&self, i: usize) -> &[u32] {
        &self.gids[self.gptr[i]..self.gptr[i + 1]]
    }

    /// Writes element i as the record [id, tag, nodes (width), n groups, groups].
    fn pack(&self, i: usize, p: &mut Packer) {
        p.extend(&[self.id[i], self.tag[i]]);
        p.extend(self.nodes_of(i));
        let gs = self.groups_of(i);
        p.push(gs.len() as u64);
        for &g in gs {
            p.push(g as u64);
        }
    }

    /// Appends the record at the start of `rec` (as [`Elems::pack`] writes it) with the rank
    /// `rank`; returns its length.
    fn push_record(&mut self, rec: &[u64], rank: u32) -> usize {
        let w = self.width;
        self.id.push(rec[0]);
        self.tag.push(rec[1]);
        self.rank.push(rank);
        self.nodes.extend_from_slice(&rec[2..2 + w]);
        let ng = rec[2 + w] as usize;
        self.gids
            .extend(rec[3 + w..3 + w + ng].iter().map(|&g| g as u32));
        self.gptr.push(self.gids.len());
        3 + w + ng
    }

    /// Appends every record of `data`, with the rank `rank`.
    fn push_all(&mut self, data: &[u64], rank: u32) {
        let mut i = 0;
        while i < data.len() {
            i += self.push_record(&data[i..], rank);
        }
    }

    /// Sorted by element number; an element received more than once is kept once.
    fn sorted(self) -> Elems {
        if self.id.windows(2).all(|p| p[0] < p[1]) {
            return self;
        }
        let mut order: Vec<(u64, u32)> = self
            .id
            .iter()
            .enumerate()
            .map(|(i, &e)| (e, i as u32))
            .collect();
        order.sort_unstable();
        order.dedup_by_key(|p| p.0);
        let mut out = Elems::new(self.width);
        for &(_, i) in &order {
            let i = i as usize;
            out.id.push(self.id[i]);
            out.tag.push(self.tag[i]);
            out.rank.push(self.rank[i]);
            out.nodes.extend_from_slice(self.nodes_of(i));
            out.gids.extend_from_slice(self.groups_of(i));
            out.gptr.push(out.gids.len());
        }
        out
    }
}

/// Phase 3: the cells to their ranks (one exchange): this rank's own cells, in global order
/// (the blocks are in rank order, so they arrive sorted).
fn own_cells(world: &SimpleCommunicator, b: &Blocks, part: &[u32], eg: &ElemGroups) -> Elems {
    let (rank, size) = rank_size(world);
    let npc = b.dim + 1;
    let cell_lo = blk(b.n_cells, size, rank);
    let recv = exchange(world, |p| {
        for (i, cell) in b.cells.chunks_exact(npc).enumerate() {
            p.to(part[i] as usize)
                .extend(&[(cell_lo + i) as u64, b.cell_tags[i]]);
            p.extend(cell);
            let gs = eg.of(0, i);
            p.push(gs.len() as u64);
            for &g in gs {
                p.push(g as u64);
            }
        }
    });
    let mut own = Elems::new(npc);
    own.push_all(&recv.data, rank as u32);
    own.sorted()
}

/// The distinct values of `list` (ascending) and the index of every entry of `list` in them
/// (one sort of (value, position) pairs: no search per entry).
fn number_nodes(list: &[u64]) -> (Vec<u64>, Vec<u32>) {
    let mut pairs: Vec<(u64, u32)> = list
        .iter()
        .enumerate()
        .map(|(i, &v)| (v, i as u32))
        .collect();
    pairs.sort_unstable();
    let mut uniq: Vec<u64> = Vec::new();
    let mut index = vec![0u32; list.len()];
    for &(v, i) in &pairs {
        if uniq.last() != Some(&v) {
            uniq.push(v);
        }
        index[i as usize] = (uniq.len() - 1) as u32;
    }
    (uniq, index)
}

/// What the home rank of a block of nodes knows of them: the ranks holding each (ascending;
/// the first, the lowest, owns it), CSR over (node − first home node).
struct Homes {
    node_lo: usize,
    ptr: Vec<usize>,
    ranks: Vec<u32>,
}

impl Homes {
    fn holders_of(&self, v: u64) -> &[u32] {
        let j = v as usize - self.node_lo;
        &self.ranks[self.ptr[j]..self.ptr[j + 1]]
    }

    /// The owner of home node v (u64::MAX if no cell holds it).
    fn owner(&self, v: u64) -> u64 {
        self.holders_of(v).first().map_or(u64::MAX, |&r| r as u64)
    }
}

/// Phase 4: holders and owners: every rank tells the homes which nodes its cells hold; the homes
/// answer with the owners (two exchanges). Returns the homes' knowledge and the owner of
/// every own node (in the order of `own_nodes`, ascending).
fn node_homes(world: &SimpleCommunicator, b: &Blocks, own_nodes: &[u64]) -> (Homes, Vec<u32>) {
    let (rank, size) = rank_size(world);
    let node_lo = blk(b.n_nodes, size, rank);
    let recv = exchange(world, |p| {
        for &v in own_nodes {
            p.to(block_of(v as usize, b.n_nodes, size)).push(v);
        }
    });
    // a counting sort on the node, ranks in ascending order
    let mut ptr = vec![0usize; b.node_tags.len() + 1];
    for &v in &recv.data {
        ptr[v as usize - node_lo + 1] += 1;
    }
    for i in 1..ptr.len() {
        ptr[i] += ptr[i - 1];
    }
    let mut fill = ptr.clone();
    let mut ranks = vec![0u32; recv.data.len()];
    for r in 0..size {
        for &v in recv.from(r) {
            let j = v as usize - node_lo;
            ranks[fill[j]] = r as u32;
            fill[j] += 1;
        }
    }
    drop(fill);
    let homes = Homes {
        node_lo,
        ptr,
        ranks,
    };
    // The answers in the order asked: in rank order they follow `own_nodes` (sorted, and
    // the homes' blocks are in rank order).
    let reply = exchange(world, |p| {
        for r in 0..size {
            p.to(r);
            for &v in recv.from(r) {
                p.push(homes.owner(v));
            }
        }
    });
    let owner = reply.data.iter().map(|&o| o as u32).collect();
    (homes, owner)
}

/// Phase 5: ghost cells: every own cell to the owners of its nodes (one exchange); sorted by
/// global cell.
fn ghost_cells(
    world: &SimpleCommunicator,
    own: &Elems,
    own_index: &[u32],
    own_owner: &[u32],
) -> Elems {
    let (rank, size) = rank_size(world);
    let npc = own.width;
    let recv = exchange(world, |p| {
        for c in 0..own.len() {
            let mut to = [u32::MAX; 4];
            let mut n = 0;
            for &i in &own_index[c * npc..(c + 1) * npc] {
                let r = own_owner[i as usize];
                if r as usize != rank && !to[..n].contains(&r) {
                    to[n] = r;
                    n += 1;
                }
            }
            to[..n].sort_unstable();
            for &r in &to[..n] {
                own.pack(c, p.to(r as usize));
            }
        }
    });
    let mut ghosts = Elems::new(npc);
    for r in 0..size {
        ghosts.push_all(recv.from(r), r as u32);
    }
    ghosts.sorted()
}

/// Phase 6: boundary elements to every rank holding one of their nodes, through the homes (two
/// exchanges of [kind, element, tag, nodes (width), n groups, groups]): kind − 1 → elements
/// sorted by number.
fn boundary_elements(
    world: &SimpleCommunicator,
    b: &Blocks,
    eg: &ElemGroups,
    homes: &Homes,
) -> [Elems; 3] {
    let (rank, size) = rank_size(world);
    let recv = exchange(world, |p| {
        for k in 1..4 {
            let w = b.width(k);
            let lo = blk(b.count(k), size, rank);
            for (i, nodes) in b.bnd[k - 1].chunks_exact(w).enumerate() {
                let mut to = [usize::MAX; 3];
                let mut n = 0;
                for &v in nodes {
                    let h = block_of(v as usize, b.n_nodes, size);
                    if !to[..n].contains(&h) {
                        to[n] = h;
                        n += 1;
                    }
                }
                to[..n].sort_unstable();
                let gs = eg.of(k, i);
                for &h in &to[..n] {
                    p.to(h)
                        .extend(&[k as u64, (lo + i) as u64, b.bnd_tags[k - 1][i]]);
                    p.extend(nodes);
                    p.push(gs.len() as u64);
                    for &g in gs {
                        p.push(g as u64);
                    }
                }
            }
        }
    });
    // the length of the record at the start of `rec`
    let len = |rec: &[u64]| {
        let w = b.width(rec[0] as usize);
        4 + w + rec[3 + w] as usize
    };
    // at the homes: each record to the holders of its home nodes
    let mut to: Vec<u32> = Vec::new();
    let fwd = exchange(world, |p| {
        let mut i = 0;
        while i < recv.data.len() {
            let rec = &recv.data[i..];
            let (k, n) = (rec[0] as usize, len(rec));
            to.clear();
            for &v in &rec[3..3 + b.width(k)] {
                if block_of(v as usize, b.n_nodes, size) == rank {
                    to.extend_from_slice(homes.holders_of(v));
                }
            }
            to.sort_unstable();
            to.dedup();
            for &r in &to {
                p.to(r as usize).extend(&rec[..n]);
            }
            i += n;
        }
    });
    drop(recv);
    let mut bnd: [Elems; 3] = std::array::from_fn(|k| Elems::new(b.width(k + 1)));
    let mut i = 0;
    while i < fwd.data.len() {
        let k = fwd.data[i] as usize;
        i += 1 + bnd[k - 1].push_record(&fwd.data[i + 1..], 0);
    }
    bnd.map(Elems::sorted)
}

/// Phase 7a: the local nodes (mesh numbers, ascending): the own nodes merged with those of the
/// ghosts and the boundary elements; and the local index of every own node.
fn local_node_list(own_nodes: Vec<u64>, ghosts: &Elems, bnd: &[Elems; 3]) -> (Vec<u64>, Vec<u32>) {
    let mut extra: Vec<u64> = ghosts
        .nodes
        .iter()
        .chain(bnd.iter().flat_map(|e| e.nodes.iter()))
        .copied()
        .filter(|v| own_nodes.binary_search(v).is_err())
        .collect();
    extra.sort_unstable();
    extra.dedup();
    let mut orig = Vec::with_capacity(own_nodes.len() + extra.len());
    let mut own_local = Vec::with_capacity(own_nodes.len());
    let mut e = extra.iter().peekable();
    for &v in &own_nodes {
        while let Some(&&x) = e.peek() {
            if x > v {
                break;
            }
            orig.push(x);
            e.next();
        }
        own_local.push(orig.len() as u32);
        orig.push(v);
    }
    orig.extend(e);
    (orig, own_local)
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
    /// The local index of mesh node v.
    fn local(&self, v: u64) -> usize {
        self.orig.binary_search(&v).expect("local node")
    }
}

/// Phase 7b: the local nodes' data from their homes (two exchanges: the nodes asked, the
/// answers [owner, tag, x, y, z, n groups, groups] in the order asked, which in rank order
/// is the order of `orig`).
fn node_data(
    world: &SimpleCommunicator,
    b: &Blocks,
    homes: &Homes,
    node_groups: &NodeGroups,
    orig: Vec<u64>,
) -> LocalNodes {
    let (_, size) = rank_size(world);
    let req = exchange(world, |p| {
        for &v in &orig {
            p.to(block_of(v as usize, b.n_nodes, size)).push(v);
        }
    });
    let reply = exchange(world, |p| {
        for r in 0..size {
            p.to(r);
            for &v in req.from(r) {
                let j = v as usize - homes.node_lo;
                let x = &b.coords[3 * j..3 * j + 3];
                let gs = node_groups.of(j);
                p.extend(&[
                    homes.owner(v),
                    b.node_tags[j],
                    x[0].to_bits(),
                    x[1].to_bits(),
                    x[2].to_bits(),
                    gs.len() as u64,
                ]);
                for &g in gs {
                    p.push(g as u64);
                }
            }
        }
    });
    drop(req);
    let nl = orig.len();
    let mut n = LocalNodes {
        coords: Vec::with_capacity(nl),
        tags: Vec::with_capacity(nl),
        owner: Vec::with_capacity(nl),
        group_ptr: Vec::with_capacity(nl + 1),
        group_ids: Vec::new(),
        orig,
    };
    n.group_ptr.push(0);
    let d = &reply.data;
    let mut i = 0;
    while i < d.len() {
        n.owner.push(d[i] as u32);
        n.tags.push(d[i + 1]);
        n.coords.push([
            f64::from_bits(d[i + 2]),
            f64::from_bits(d[i + 3]),
            f64::from_bits(d[i + 4]),
        ]);
        let ng = d[i + 5] as usize;
        n.group_ids
            .extend(d[i + 6..i + 6 + ng].iter().map(|&g| g as u32));
        n.group_ptr.push(n.group_ids.len());
        i += 6 + ng;
    }
    debug_assert_eq!(n.owner.len(), nl);
    n
}

/// The global node numbering.
struct Numbering {
    /// Local indices of the owned nodes, in global order.
    owned: Vec<usize>,
    node_offsets: Vec<usize>,
    node_global: Vec<usize>,
}

/// Phase 8: global numbering: the owned nodes along the Morton curve of the whole mesh (ties
/// by mesh order); the owners answer for the other local nodes (two exchanges, the answers
/// in the order asked). Collective.
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
    // a node no cell holds has no owner (u32::MAX) and no number
    let asked = |l: usize| n.owner[l] as usize != rank && (n.owner[l] as usize) < size;
    let req = exchange(world, |p| {
        for l in (0..nl).filter(|&l| asked(l)) {
            p.to(n.owner[l] as usize).push(n.orig[l]);
        }
    });
    let reply = exchange(world, |p| {
        for r in 0..size {
            p.to(r);
            for &v in req.from(r) {
                p.push(node_global[n.local(v)] as u64);
            }
        }
    });
    drop(req);
    let mut next = reply.offsets.clone();
    for l in (0..nl).filter(|&l| asked(l)) {
        let r = n.owner[l] as usize;
        node_global[l] = reply.data[next[r]] as usize;
        next[r] += 1;
    }
    Numbering {
        owned,
        node_offsets,
        node_global,
    }
}

/// Phase 9: the local mesh: own cells (global order), then ghosts (`cell_nodes`: their local
/// nodes); boundary elements; groups (cell groups hold own cells only); the whole mesh's
/// counts. Takes the nodes' coordinates, tags and groups out of `n` (no copies). Collective
/// (one sum).
fn local_mesh(
    world: &SimpleCommunicator,
    whole: &WholeMesh,
    n: &mut LocalNodes,
    cell_nodes: Vec<usize>,
    own: &Elems,
    ghosts: &Elems,
    bnd: &[Elems; 3],
) -> Mesh {
    let (rank, _) = rank_size(world);
    let dim = whole.dim;
    let n_own = own.len();
    let mut groups: Vec<Group> = whole
        .groups
        .iter()
        .map(|g| Group {
            elements: Vec::new(),
            ..g.clone()
        })
        .collect();
    for ci in 0..n_own {
        for &g in own.groups_of(ci) {
            if groups[g as usize].dim == dim {
                groups[g as usize].elements.push(ci);
            }
        }
    }
    let cell_tags = own.tag.iter().chain(&ghosts.tag).copied().collect();
    let mut lists: [(Vec<usize>, Vec<u64>); 3] = Default::default();
    for (k, e) in bnd.iter().enumerate() {
        lists[k].0 = e.nodes.iter().map(|&v| n.local(v)).collect();
        lists[k].1 = e.tag.clone();
        for i in 0..e.len() {
            for &g in e.groups_of(i) {
                groups[g as usize].elements.push(i);
            }
        }
    }
    let [(facets, facet_tags), (edges, edge_tags), (points, point_tags)] = lists;
    let mut mesh = Mesh {
        dim,
        coords: std::mem::take(&mut n.coords),
        node_tags: std::mem::take(&mut n.tags),
        cells: cell_nodes,
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
/// global node (locality of the assembly loop; ties by global cell), cell offsets of the
/// output. Collective.
fn local_layout(
    world: &SimpleCommunicator,
    mesh: &Mesh,
    n: LocalNodes,
    numbering: Numbering,
    own: &Elems,
    ghosts: &Elems,
) -> Layout {
    let (rank, size) = rank_size(world);
    let n_own = own.len();
    let node_global = numbering.node_global;
    // the keys computed once (a key per comparison would read scattered memory)
    let mut keyed: Vec<(usize, u64, usize)> = (0..n_own)
        .map(|c| {
            let first = mesh
                .cell(c)
                .iter()
                .map(|&v| node_global[v])
                .min()
                .unwrap_or(0);
            (first, own.id[c], c)
        })
        .collect();
    keyed.sort_unstable();
    let local_cells = keyed.into_iter().map(|k| k.2).collect();
    Layout {
        rank,
        size,
        cell_rank: own.rank.iter().chain(&ghosts.rank).copied().collect(),
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

/// Seconds and memory of the phases of the pipeline, printed by rank 0 to stderr when the
/// environment variable `SIGNORINI_DIST_PHASES` is set (on any rank): per phase the slowest
/// rank's seconds, and per rank the peak resident memory (VmHWM) at the end of the phase.
struct Phases {
    on: bool,
    t: std::time::Instant,
    rows: Vec<(&'static str, f64, f64)>,
}

impl Phases {
    /// Collective (one reduction: the ranks agree on printing).
    fn start(world: &SimpleCommunicator) -> Phases {
        let mine = std::env::var_os("SIGNORINI_DIST_PHASES").is_some() as u32;
        let mut on = 0u32;
        world.all_reduce_into(&mine, &mut on, mpi::collective::SystemOperation::max());
        Phases {
            on: on != 0,
            t: std::time::Instant::now(),
            rows: Vec::new(),
        }
    }

    fn lap(&mut self, name: &'static str) {
        if self.on {
            let s = self.t.elapsed().as_secs_f64();
            self.rows
                .push((name, s, crate::par::peak_memory_bytes() / 1e6));
            self.t = std::time::Instant::now();
        }
    }

    /// Collective when on (one all-gather per phase).
    fn report(&self, world: &SimpleCommunicator) {
        if !self.on {
            return;
        }
        let size = world.size() as usize;
        for &(name, s, mb) in &self.rows {
            let mut all = vec![0.0f64; 2 * size];
            world.all_gather_into(&[s, mb][..], &mut all[..]);
            if world.rank() == 0 {
                let tmax = all.iter().step_by(2).fold(0.0f64, |m, &p| m.max(p));
                let mbs: Vec<String> = all[1..]
                    .iter()
                    .step_by(2)
                    .map(|p| format!("{p:.0}"))
                    .collect();
                eprintln!(
                    "dist phase {name:<18} {tmax:8.3} s  peak MB per rank [{}]",
                    mbs.join(", ")
                );
            }
        }
    }
}
