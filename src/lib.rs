//! signorini-mpi: static contact of linear-elastic bodies with a rigid obstacle,
//! solved by the semismooth Newton method (exact active set strategy) on MPI + PETSc.

#![allow(clippy::needless_range_loop)] // index loops read like the tensor formulas

pub mod assembly;
pub mod case;
pub mod contact;
pub mod contact_report;
pub mod contact_set;
pub mod error;
pub mod fem;
pub mod mesh;
pub mod newton;
pub mod output;
pub mod partition;
pub mod petsc;
pub mod reduced;
pub mod rigid;
pub mod run;
pub mod snesvi;
pub mod solver;
