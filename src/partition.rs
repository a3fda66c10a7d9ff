//! The distribution of a mesh over the ranks ([`Layout`]), node → cells incidence, the Morton
//! key of the global node numbering, and [`partition`] for a WHOLE mesh held by every rank
//! (examples and tools; runs read the mesh distributed through `crate::dist`, which builds a
//! local mesh with a layout of local size by the same rules).
//!
//! A node belongs to the lowest rank among the cells that touch it. Rank r owns global node
//! numbers `node_offsets[r] .. node_offsets[r+1]`, numbered along the Morton curve of the whole
//! mesh's bounding box (ties by mesh order). With PT-Scotch the partition is repeatable (one
//! thread per rank, deterministic mode, fixed seed; see `petsc::scotch_partition`).

use crate::mesh::Mesh;
use crate::petsc::{self, MPI_Comm, PInt};
use mpi::datatype::PartitionMut;
use mpi::traits::*;

/// Node → cells incidence in CSR form.
pub struct NodeCells {
    pub offsets: Vec<usize>,
    pub cells: Vec<usize>,
}

impl NodeCells {
    pub fn new(mesh: &Mesh) -> NodeCells {
        let n = mesh.n_nodes();
        let mut offsets = vec![0usize; n + 1];
        for &v in &mesh.cells {
            offsets[v + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut cells = vec![0usize; mesh.cells.len()];
        let npc = mesh.nodes_per_cell();
        for (c, nodes) in mesh.cells.chunks_exact(npc).enumerate() {
            for &v in nodes {
                cells[fill[v]] = c;
                fill[v] += 1;
            }
        }
        NodeCells { offsets, cells }
    }

    pub fn of(&self, node: usize) -> &[usize] {
        &self.cells[self.offsets[node]..self.offsets[node + 1]]
    }
}

/// Everything a rank needs to know about the distribution.
pub struct Layout {
    pub rank: usize,
    pub size: usize,
    /// Rank of every cell (mesh order).
    pub cell_rank: Vec<u32>,
    /// Owner rank of every node.
    pub node_owner: Vec<u32>,
    /// Mesh node index → global (PETSc) node number.
    pub node_global: Vec<usize>,
    /// Rank r owns global node numbers node_offsets[r] .. node_offsets[r+1].
    pub node_offsets: Vec<usize>,
    /// Mesh indices of the owned nodes, in global order.
    pub owned_nodes: Vec<usize>,
    /// Mesh indices of this rank's cells (mesh order).
    pub local_cells: Vec<usize>,
    /// Rank r's cells are numbered cell_offsets[r] .. cell_offsets[r+1] in the output.
    pub cell_offsets: Vec<usize>,
    pub node_cells: NodeCells,
    /// Mesh-order (file order) index of every local node (ascending).
    pub node_orig: Vec<usize>,
}

impl Layout {
    pub fn n_owned_nodes(&self) -> usize {
        self.owned_nodes.len()
    }
    pub fn node_range(&self) -> (usize, usize) {
        (
            self.node_offsets[self.rank],
            self.node_offsets[self.rank + 1],
        )
    }
    pub fn owns_node(&self, node: usize) -> bool {
        self.node_owner[node] as usize == self.rank
    }
    /// Number of cells on each rank.
    pub fn cells_per_rank(&self) -> Vec<usize> {
        self.cell_offsets.windows(2).map(|w| w[1] - w[0]).collect()
    }
    /// Number of owned nodes on each rank.
    pub fn nodes_per_rank(&self) -> Vec<usize> {
        self.node_offsets.windows(2).map(|w| w[1] - w[0]).collect()
    }
}

/// Dual-graph rows (cells sharing a facet) for cells `lo..hi`, CSR with global cell indices.
fn dual_graph_rows(mesh: &Mesh, nc: &NodeCells, lo: usize, hi: usize) -> (Vec<PInt>, Vec<PInt>) {
    let npc = mesh.nodes_per_cell();
    let shared_needed = npc - 1; // a facet has dim nodes
    let mut xadj = Vec::with_capacity(hi - lo + 1);
    let mut adjncy = Vec::with_capacity((hi - lo) * npc);
    let mut cand: Vec<usize> = Vec::with_capacity(64);
    xadj.push(0 as PInt);
    for c in lo..hi {
        cand.clear();
        for &v in mesh.cell(c) {
            cand.extend(nc.of(v).iter().copied().filter(|&o| o != c));
        }
        cand.sort_unstable();
        let mut i = 0;
        while i < cand.len() {
            let mut j = i;
            while j < cand.len() && cand[j] == cand[i] {
                j += 1;
            }
            if j - i >= shared_needed {
                adjncy.push(cand[i] as PInt);
            }
            i = j;
        }
        xadj.push(adjncy.len() as PInt);
    }
    (xadj, adjncy)
}

/// Morton (Z-order) key of every node: coordinates scaled to 21-bit integers, bits
/// interleaved.
fn morton_keys(mesh: &Mesh) -> Vec<u64> {
    let (lo, _) = mesh.bounding_box();
    let extent = mesh.extent();
    mesh.coords
        .iter()
        .map(|x| morton_key(x, mesh.dim, &lo, extent))
        .collect()
}

pub use crate::geom::morton_key;
use crate::tuning::SCOTCH_IMBALANCE;

/// Partitions the mesh over the ranks of `comm` (`ptype`: "ptscotch", or another PETSc
/// MatPartitioning type, e.g. "parmetis" where PETSc has it). PT-Scotch is called directly
/// (repeatable); the PETSc option `-mat_partitioning_type` sends the graph through PETSc's
/// MatPartitioning instead, with that type (`ptscotch` there is PT-Scotch's default,
/// non-repeatable context).
pub fn partition<C: Communicator>(
    world: &C,
    comm: MPI_Comm,
    mesh: &Mesh,
    ptype: &str,
) -> petsc::Result<Layout> {
    let rank = world.rank() as usize;
    let size = world.size() as usize;
    let n_cells = mesh.n_cells();
    let node_cells = NodeCells::new(mesh);
    let cell_rank = cell_ranks(world, comm, mesh, &node_cells, ptype)?;
    let (node_owner, node_offsets, order) = node_order(mesh, &cell_rank, size);
    let mut node_global = vec![0usize; mesh.n_nodes()];
    for (g, &v) in order.iter().enumerate() {
        node_global[v] = g;
    }
    let owned_nodes: Vec<usize> = order[node_offsets[rank]..node_offsets[rank + 1]].to_vec();
    let mut ccounts = vec![0usize; size];
    for &r in &cell_rank {
        ccounts[r as usize] += 1;
    }
    let cell_offsets = prefix_sums(&ccounts);
    // Local cells in the order of their lowest node number (locality of the assembly loop).
    let mut local_cells: Vec<usize> = (0..n_cells)
        .filter(|&c| cell_rank[c] as usize == rank)
        .collect();
    local_cells.sort_unstable_by_key(|&c| {
        (
            mesh.cell(c)
                .iter()
                .map(|&v| node_global[v])
                .min()
                .unwrap_or(0),
            c,
        )
    });
    Ok(Layout {
        rank,
        size,
        cell_rank,
        node_owner,
        node_global,
        node_offsets,
        owned_nodes,
        local_cells,
        cell_offsets,
        node_cells,
        node_orig: (0..mesh.n_nodes()).collect(),
    })
}

/// The rank of every cell: the dual graph of this rank's block of cells partitioned by
/// PT-Scotch (or PETSc's MatPartitioning of type `ptype`), all-gathered. Collective.
fn cell_ranks<C: Communicator>(
    world: &C,
    comm: MPI_Comm,
    mesh: &Mesh,
    node_cells: &NodeCells,
    ptype: &str,
) -> petsc::Result<Vec<u32>> {
    let (rank, size) = (world.rank() as usize, world.size() as usize);
    let n_cells = mesh.n_cells();
    if size == 1 {
        return Ok(vec![0; n_cells]);
    }
    let block = |r: usize| r * n_cells / size;
    let (lo, hi) = (block(rank), block(rank + 1));
    let (xadj, adjncy) = dual_graph_rows(mesh, node_cells, lo, hi);
    let part = if ptype == "ptscotch" && !petsc::options::has("-mat_partitioning_type")? {
        petsc::scotch_partition(comm, &xadj, &adjncy, None, size, SCOTCH_IMBALANCE)?
    } else {
        petsc::partition_graph(comm, n_cells, &xadj, &adjncy, ptype)?
    };
    let mine: Vec<u32> = part.iter().map(|&p| p as u32).collect();
    let counts: Vec<i32> = (0..size)
        .map(|r| (block(r + 1) - block(r)) as i32)
        .collect();
    let displs: Vec<i32> = (0..size).map(|r| block(r) as i32).collect();
    let mut all = vec![0u32; n_cells];
    {
        let mut buf = PartitionMut::new(&mut all[..], counts, displs);
        world.all_gather_varcount_into(&mine[..], &mut buf);
    }
    Ok(all)
}

/// The owner of every node (the lowest rank among its cells), the ranks' first global node
/// numbers, and the nodes in global order: by owner, then within each rank along a
/// space-filling (Morton) curve, so that neighbours in the mesh get nearby numbers and element
/// matrices hit nearby rows (gmsh's own numbering is nearly random on large meshes, which made
/// assembly several times slower). Local.
fn node_order(mesh: &Mesh, cell_rank: &[u32], size: usize) -> (Vec<u32>, Vec<usize>, Vec<usize>) {
    let n_nodes = mesh.n_nodes();
    let mut node_owner = vec![u32::MAX; n_nodes];
    for (c, nodes) in mesh.cells.chunks_exact(mesh.nodes_per_cell()).enumerate() {
        let r = cell_rank[c];
        for &v in nodes {
            if r < node_owner[v] {
                node_owner[v] = r;
            }
        }
    }
    let mut counts = vec![0usize; size];
    for &o in &node_owner {
        counts[o as usize] += 1;
    }
    let key = morton_keys(mesh);
    let mut order: Vec<usize> = (0..n_nodes).collect();
    order.sort_unstable_by_key(|&v| (node_owner[v], key[v], v));
    (node_owner, prefix_sums(&counts), order)
}

/// [0, c0, c0 + c1, …]: the first index of each part from the parts' counts.
fn prefix_sums(counts: &[usize]) -> Vec<usize> {
    let mut out = vec![0usize; counts.len() + 1];
    for (r, c) in counts.iter().enumerate() {
        out[r + 1] = out[r] + c;
    }
    out
}

/// The sorted, distinct nodes of `cells` and the values of the distributed nodal vector `u`
/// (`dim` per node) there, gathered from their owners. Collective.
pub fn values_at_cells(
    mesh: &Mesh,
    layout: &Layout,
    cells: &[usize],
    u: &petsc::Vector,
) -> petsc::Result<(Vec<usize>, Vec<f64>)> {
    let dim = mesh.dim;
    let mut nodes: Vec<usize> = cells
        .iter()
        .flat_map(|&c| mesh.cell(c).iter().copied())
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let idx: Vec<PInt> = nodes
        .iter()
        .flat_map(|&v| (0..dim).map(move |k| (layout.node_global[v] * dim + k) as PInt))
        .collect();
    let vals = u.gather(&idx)?;
    Ok((nodes, vals))
}
