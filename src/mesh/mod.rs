//! Gmsh MSH 4.1 reading (ASCII and binary) through `mshio`, physical groups by name,
//! P1 triangles / tetrahedra, boundary entities, quality checks.
//!
//! INTERFACE (used by the rest of the code; keep these names):
//!
//! ```ignore
//! pub struct Group { pub name: String, pub dim: usize, pub tag: i32, pub elements: Vec<usize> }
//! pub struct Mesh {
//!     pub dim: usize,                 // 2 or 3 (dimension of the body cells)
//!     pub coords: Vec<[f64; 3]>,      // node coordinates, z = 0 in 2D; only nodes used by cells
//!     pub node_tags: Vec<u64>,        // gmsh node tag per node
//!     pub cells: Vec<usize>,          // flat, dim+1 node indices per cell, positively oriented
//!     pub cell_tags: Vec<u64>,        // gmsh element tag per cell
//!     pub facets: Vec<usize>,         // flat, dim node indices per facet (lines 2D / triangles 3D)
//!     pub facet_tags: Vec<u64>,
//!     pub edges: Vec<usize>,          // flat, 2 per line element of a 3D mesh (may be empty)
//!     pub points: Vec<usize>,         // node index per point element
//!     pub groups: Vec<Group>,         // elements: indices into cells / facets / edges / points by dim
//! }
//! impl Mesh {
//!     pub fn nodes_per_cell(&self) -> usize;
//!     pub fn n_nodes(&self) -> usize; pub fn n_cells(&self) -> usize;
//!     pub fn cell(&self, c: usize) -> &[usize]; pub fn facet(&self, f: usize) -> &[usize];
//!     pub fn group(&self, name: &str) -> Option<&Group>;
//!     pub fn group_names(&self) -> Vec<String>;      // for error messages
//!     pub fn group_nodes(&self, g: &Group) -> Vec<usize>;  // sorted, unique node indices
//! }
//! pub fn read_msh(path: &Path) -> Result<Mesh, crate::error::InputError>;
//! ```
