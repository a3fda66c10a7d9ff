//! The reduced systems (3.29) / (3.42), written into a matrix that keeps A's nonzero pattern
//! (the symbolic part, made once) so that only values change from step to step (the numeric
//! part) and MUMPS reuses its analysis. Every prescribed direction (active normal, stick
//! tangent, pinned dof) is eliminated symmetrically: from the node's own rows and from the
//! columns, i.e. a mirror block in each unconstrained neighbour's rows (which may belong to
//! another rank: PETSc moves those entries at assembly). A Tresca slip row adds L̃ and r̃
//! (3.39) to the node's own block. Dirichlet data are eliminated earlier, per element, in
//! assembly.rs; this is the same elimination at matrix level.
//!
//! | module | role |
//! |---|---|
//! | `rows` | a node's rows of A and its constraint |
//! | `write` | the symmetric elimination of the prescribed directions, the row changes |
//! | `system` | [`ReducedSystem`]: the matrix, right-hand side and solver of one step |
//! | `reuse` | how a step was solved and the reuse of factorisations / preconditioners |
//! | `mortar_pc` | the iterative preset's preconditioner for body pairs (AMG in u) |
//! | `matrix_free` | the step system as an operator S = L A P + D (body pairs, iterative) |

pub mod matrix_free;
pub mod mortar_pc;
pub mod reuse;
pub mod rows;
pub mod system;
pub mod write;

pub use reuse::{AmgStep, ReuseStep, SolveKind, StepSolve};
pub use system::ReducedSystem;
pub use write::RowChange;
