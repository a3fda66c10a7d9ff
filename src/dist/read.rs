//! The distributed read: blocks, refinement, partition and migration, in phases.

use super::blocks::{read_blocks, Blocks};
use super::cells::{
    boundary_elements, ghost_cells, local_node_list, node_homes, number_nodes, own_cells,
};
use super::groups::{element_groups, node_groups};
use super::nodes::{global_bbox, global_numbering, local_layout, local_mesh, node_data, WholeMesh};
use super::parts::partition_cells;
use super::refine::{self, Refine};
use crate::error::{InputError, RunError};
use crate::mesh;
use crate::mesh::Mesh;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::MPI_Comm;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use std::path::Path;

/// What [`read_distributed`] gives: the local mesh and its layout, and the seconds of the
/// read and of the partition (with the migration).
pub struct Distributed {
    pub mesh: Mesh,
    pub layout: Layout,
    pub read_seconds: f64,
    pub partition_seconds: f64,
}

/// Reads the mesh file distributed over the ranks of `world` (its lengths asked of `lengths`
/// before any cell is measured), refines it as `refine` asks, partitions and migrates it. Collective; an input error is the
/// same on every rank.
pub fn read_distributed(
    ctx: &Ctx,
    path: &Path,
    refine: &Refine,
    lengths: &mesh::LengthCheck,
) -> Result<Distributed, RunError> {
    let (world, comm) = (ctx.world, ctx.comm());
    let t0 = std::time::Instant::now();
    let mut phases = Phases::start(world);
    let b = read_blocks(ctx, path, lengths)?;
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
pub(super) fn orient_local_cells(ctx: &Ctx, path: &Path, mesh: &mut Mesh) -> Result<(), RunError> {
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

/// Builds the local mesh and layout from the blocks read, in phases: partition, group
/// memberships, cells to their ranks, node holders and owners, ghost cells, boundary
/// elements, node data, global numbering, local mesh, layout. Every exchange is one
/// all-to-all-v of flat records; the blocks' arrays are freed as soon as their last phase
/// ends. Collective.
pub(super) fn build(
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

/// Seconds and memory of the phases of the pipeline, printed by rank 0 to stderr when the
/// environment variable `SIGNORINI_DIST_PHASES` is set (on any rank): per phase the slowest
/// rank's seconds, and per rank the peak resident memory (VmHWM) at the end of the phase.
pub(super) struct Phases {
    pub(super) on: bool,
    pub(super) t: std::time::Instant,
    pub(super) rows: Vec<(&'static str, f64, f64)>,
}

impl Phases {
    /// Collective (one reduction: the ranks agree on printing).
    pub(super) fn start(world: &SimpleCommunicator) -> Phases {
        let mine = std::env::var_os("SIGNORINI_DIST_PHASES").is_some() as u32;
        let mut on = 0u32;
        world.all_reduce_into(&mine, &mut on, mpi::collective::SystemOperation::max());
        Phases {
            on: on != 0,
            t: std::time::Instant::now(),
            rows: Vec::new(),
        }
    }

    pub(super) fn lap(&mut self, name: &'static str) {
        if self.on {
            let s = self.t.elapsed().as_secs_f64();
            self.rows
                .push((name, s, crate::par::peak_memory_bytes() / 1e6));
            self.t = std::time::Instant::now();
        }
    }

    /// Collective when on (one all-gather per phase).
    pub(super) fn report(&self, world: &SimpleCommunicator) {
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
