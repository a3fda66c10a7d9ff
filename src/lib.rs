//! signorini-mpi: static contact of linear-elastic bodies with a rigid obstacle,
//! solved by the semismooth Newton method (exact active set strategy) on MPI + PETSc.

#![allow(clippy::needless_range_loop)] // index loops read like the tensor formulas

pub mod abort;
pub mod assembly;
pub mod bigbuf;
pub mod blas;
pub mod bodies;
pub mod case;
pub mod coincident;
pub mod contact;
pub mod dist;
pub mod driver;
pub mod error;
pub mod expr;
pub mod fault;
pub mod fem;
pub mod geom;
pub mod linsolve;
pub mod mesh;
pub mod mortar;
pub mod output;
pub mod par;
pub mod partition;
pub mod petsc;
pub mod post;
pub mod setup;
pub mod signorini;
pub mod solver;
pub mod steps;
pub mod summary;
pub mod tuning;
pub mod warnings;
