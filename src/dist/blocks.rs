//! This rank's blocks of the mesh file, read (HDF5 hyperslabs, or MSH on rank 0 and sent
//! out), packed and checked.

use super::comm::{blk, exchange};
use crate::error::{InputError, RunError};
use crate::mesh;
use crate::mesh::h5::H5Mesh;
use crate::mesh::{Group, Mesh};
use crate::par::Ctx;
use mpi::traits::*;
use std::path::Path;

/// This rank's blocks of the mesh file.
#[derive(Default)]
pub(super) struct Blocks {
    pub(super) dim: usize,
    pub(super) n_nodes: usize,
    pub(super) n_cells: usize,
    /// Counts of facets, edges, points.
    pub(super) n_bnd: [usize; 3],
    pub(super) groups: Vec<Group>,
    pub(super) group_sizes: Vec<usize>,
    pub(super) cells: Vec<u64>,
    pub(super) cell_tags: Vec<u64>,
    pub(super) coords: Vec<f64>,
    pub(super) node_tags: Vec<u64>,
    pub(super) bnd: [Vec<u64>; 3],
    pub(super) bnd_tags: [Vec<u64>; 3],
    /// (group, element) of a block of the group members.
    pub(super) members: Vec<(u64, u64)>,
}

impl Blocks {
    /// Kind of the elements of a group: 0 cells, 1 facets, 2 edges, 3 points.
    pub(super) fn kind(&self, gdim: usize) -> usize {
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
    pub(super) fn count(&self, kind: usize) -> usize {
        if kind == 0 {
            self.n_cells
        } else {
            self.n_bnd[kind - 1]
        }
    }
    pub(super) fn width(&self, kind: usize) -> usize {
        [self.dim + 1, self.dim, 2, 1][kind]
    }

    /// Rank r's blocks of a whole mesh.
    pub(super) fn of_mesh(m: &Mesh, size: usize, r: usize) -> Blocks {
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
    pub(super) fn of_h5(h: &H5Mesh, size: usize, r: usize) -> Result<Blocks, String> {
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
    pub(super) fn pack(&self) -> Vec<u64> {
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

    pub(super) fn unpack(v: &[u64]) -> Blocks {
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
    pub(super) fn validate(&self) -> Result<(), String> {
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
pub(super) fn read_blocks(
    ctx: &Ctx,
    path: &Path,
    lengths: &mesh::LengthCheck,
) -> Result<Blocks, RunError> {
    let (rank, size) = (ctx.rank, ctx.size);
    let err = |m: String| RunError::Input(InputError::new(path, m));
    if mesh::h5::is_h5(path) {
        let b = H5Mesh::open(path)
            .and_then(|h| Blocks::of_h5(&h, size, rank))
            .and_then(|b| b.validate().map(|()| b))
            .map_err(err);
        let b = ctx.agree(b)?;
        check_tags(ctx, path, &b)?;
        check_coordinates(ctx, path, &b)?;
        // the cells are measured after the migration (crate::dist::read)
        let (lo, hi) = super::nodes::global_bbox(ctx.world, &b);
        let (extent, far) = mesh::lengths(b.dim, &[lo, hi]);
        ctx.agree(lengths(b.dim, extent, far, b.n_nodes).map_err(RunError::from))?;
        Ok(b)
    } else {
        let whole = if rank == 0 {
            mesh::read_msh_checked(path, lengths)
                .map(Some)
                .map_err(RunError::Input)
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

/// The tags of an HDF5 mesh, a check that spans the blocks of all ranks (the MSH reader makes
/// it on the whole file): every node tag and every element tag (cells, facets, edges, points)
/// defined once. Each tag goes to rank `tag % size`, which so sees every definition of it (one
/// all-to-all-v of the node tags, one of the element tags); the smallest tag defined twice is
/// named, the same on every rank count. Collective.
fn check_tags(ctx: &Ctx, path: &Path, b: &Blocks) -> Result<(), RunError> {
    let size = ctx.size as u64;
    let element_tags = [&b.cell_tags, &b.bnd_tags[0], &b.bnd_tags[1], &b.bnd_tags[2]];
    for (what, place, tags) in [
        ("node", mesh::h5::H5_NODE_TAGS, [&b.node_tags][..].iter()),
        ("element", mesh::h5::H5_ELEMENT_TAGS, element_tags.iter()),
    ] {
        let homes = exchange(ctx.world, |p| {
            for &t in tags.clone().copied().flatten() {
                p.to((t % size) as usize).push(t);
            }
        });
        let dup = mesh::smallest_duplicate(&homes.data).map(|t| {
            let m = mesh::duplicate_tag(what, t, place);
            (t, RunError::Input(InputError::new(path, m)))
        });
        ctx.agree_smallest(dup)?;
    }
    Ok(())
}

/// Every node coordinate of this rank's block of an HDF5 mesh is finite: else an input error
/// naming the node of smallest tag over all ranks. Collective.
fn check_coordinates(ctx: &Ctx, path: &Path, b: &Blocks) -> Result<(), RunError> {
    let coords: Vec<[f64; 3]> = (b.coords.chunks_exact(3))
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let bad = mesh::non_finite_node(b.node_tags.iter().copied().zip(coords.iter()));
    ctx.agree_smallest(bad.map(|(t, m)| (t, RunError::Input(InputError::new(path, m)))))
}
