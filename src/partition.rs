//! The distribution of a mesh over the ranks ([`Layout`]), node → cells incidence, and the
//! Morton key of the global node numbering. The distributed read, partition (PT-Scotch, called
//! directly: repeatable) and migration that build them are in `crate::dist`.
//!
//! A node belongs to the lowest rank among the cells that touch it. Rank r owns global node
//! numbers `node_offsets[r] .. node_offsets[r+1]`, numbered along the Morton curve of the whole
//! mesh's bounding box (ties by mesh order). Every array of a [`Layout`] is of local size (the
//! rank's local mesh: own cells, ghost cells, the nodes they touch).

use crate::mesh::Mesh;

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
    /// Rank of every local cell (own cells and ghosts).
    pub cell_rank: Vec<u32>,
    /// Owner rank of every local node.
    pub node_owner: Vec<u32>,
    /// Local node index → global (PETSc) node number.
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

/// Morton key of one point in the box from `lo` of size `extent`.
pub fn morton_key(x: &[f64; 3], dim: usize, lo: &[f64; 3], extent: f64) -> u64 {
    let scale = ((1u64 << 21) - 1) as f64 / extent;
    let mut key = 0u64;
    let mut q = [0u64; 3];
    for k in 0..dim {
        q[k] = (((x[k] - lo[k]) * scale) as u64).min((1 << 21) - 1);
    }
    for bit in (0..21).rev() {
        for qk in &q[..dim] {
            key = (key << 1) | ((qk >> bit) & 1);
        }
    }
    key
}
