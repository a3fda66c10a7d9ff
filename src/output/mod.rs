//! XDMF + HDF5 output, written in parallel (every rank its own rows of one shared HDF5 file).
//!
//! INTERFACE (keep these names):
//!
//! ```ignore
//! /// One field: `ncomp` values per owned node / cell / contact node, row-major.
//! pub struct Field<'a> { pub name: &'a str, pub ncomp: usize, pub data: &'a [f64] }
//! /// What one rank contributes. Nodes and cells are numbered globally and contiguously by rank:
//! /// rank r owns nodes node_offset .. node_offset + coords.len() and cells likewise.
//! pub struct Piece<'a> {
//!     pub dim: usize,                    // 2 or 3
//!     pub n_nodes_global: usize, pub node_offset: usize,
//!     pub coords: &'a [[f64; 3]],        // owned nodes (z = 0 in 2D)
//!     pub node_ids: &'a [u64],           // gmsh node tag of each owned node
//!     pub n_cells_global: usize, pub cell_offset: usize,
//!     pub connectivity: &'a [usize],     // dim+1 GLOBAL node numbers per owned cell
//!     pub cell_ids: &'a [u64],           // gmsh element tag of each owned cell
//!     pub nodal: Vec<Field<'a>>,         // e.g. displacement, ncomp 3 (2D padded with 0)
//!     pub cellwise: Vec<Field<'a>>,      // e.g. stress ncomp 9, von_mises 1, rank 1
//!     pub contact: Option<ContactPiece<'a>>,
//! }
//! /// Contact nodes as their own point grid ("contact").
//! pub struct ContactPiece<'a> {
//!     pub n_global: usize, pub offset: usize,
//!     pub coords: &'a [[f64; 3]], pub node_ids: &'a [u64],
//!     pub fields: Vec<Field<'a>>,
//! }
//! /// Collective over `comm`: writes DIR/solution.h5 and DIR/solution.xdmf (DIR must exist).
//! pub fn write_xdmf_hdf5<C: mpi::topology::Communicator>(comm: &C, dir: &Path, piece: &Piece)
//!     -> Result<(), String>;
//! ```
