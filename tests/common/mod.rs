//! Shared helpers of all integration tests, in one module with four parts:
//!
//! - [`process`]: running the binary and the examples under mpirun with a time limit, gmsh,
//!   case files, Debian's Python (`PYTHON`, `Run`, `run_with_timeout`, `mpirun`, `solver`, ...);
//! - [`solved`]: one solver run on a case file and what it wrote (`solve`, `Solved`, `get`);
//! - [`csv`]: the rows of contact_nodes.csv (`Row`, `read_csv`, `csv_dim`, `columns`);
//! - [`compare`]: numbers and fields by node id (`rel`, `norm`, `max_diff`, `floats`);
//! - [`disk`]: a small tmpfs for full-disk tests (`SmallDisk`) and a directory's entries
//!   (`file_names`, `listing`).
//!
//! Every test file includes it with `mod common;` + `use common::*;` and uses only part of it.
#![allow(dead_code, unused_imports)]

pub mod compare;
pub mod csv;
pub mod disk;
pub mod process;
pub mod solved;

pub use compare::*;
pub use csv::*;
pub use disk::*;
pub use process::*;
pub use solved::*;
