//! The readers of signorini-mpi, compiled from the main crate's source files (see Cargo.toml).
#![allow(dead_code)]

#[path = "../../src/error.rs"]
pub mod error;

#[path = "../../src/mesh/mod.rs"]
pub mod mesh;

#[path = "../../src/case/mod.rs"]
pub mod case;

#[path = "../../src/expr.rs"]
pub mod expr;

#[path = "../../src/geom.rs"]
pub mod geom;

/// The obstacle shapes the case reader builds and checks (contact/mod.rs).
pub mod contact;

/// The one PETSc type `error.rs` names (`RunError::Petsc`); the readers never produce it.
pub mod petsc {
    #[derive(Debug)]
    pub struct PetscError;

    impl std::fmt::Display for PetscError {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "PETSc error")
        }
    }
}
