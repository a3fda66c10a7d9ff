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
//!
//! The phases live in submodules: `comm` (row blocks, the all-to-all-v exchange),
//! `blocks` (reading the blocks), `graph` (the dual graph), `parts` (the partition),
//! `groups` (group memberships), `cells` (migration of cells, ghosts, boundary elements),
//! `nodes` (node data, numbering, the local mesh), `read` (the pipeline), `refine`
//! (`mesh.refine` on the blocks before the partition).

mod blocks;
mod cells;
pub(crate) mod comm;
mod graph;
mod groups;
mod nodes;
mod parts;
mod read;
mod refine;

pub use comm::blk;
pub use read::{read_distributed, Distributed};
pub use refine::Refine;
