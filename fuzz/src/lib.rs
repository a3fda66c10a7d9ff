//! The readers of signorini-mpi, compiled from the main crate's source files (see Cargo.toml).
#![allow(dead_code)]

#[path = "../../src/error.rs"]
pub mod error;

#[path = "../../src/mesh/mod.rs"]
pub mod mesh;

#[path = "../../src/case/mod.rs"]
pub mod case;
