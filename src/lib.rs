//! signorini-mpi: static contact of linear-elastic bodies with a rigid obstacle,
//! solved by the semismooth Newton method (exact active set strategy) on MPI + PETSc.

pub mod assembly;
pub mod case;
pub mod contact;
pub mod error;
pub mod fem;
pub mod mesh;
pub mod output;
pub mod partition;
pub mod petsc;
pub mod run;
pub mod solver;
