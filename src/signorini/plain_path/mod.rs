//! The semismooth Newton method in its exact active-set form: Algorithm 1 (frictionless,
//! reduced system (3.29)) and Algorithm 2 (Tresca, (3.42) with the regularised slip rows
//! (3.39)/(3.40)). One step: update the pins of free rigid modes, write the reduced system,
//! solve, recover λ (3.28), update the sets (3.23)/(3.33), one reduction, log, decide.
//!
//! Collectives per step: with the reuse path one Allreduce of 4 values (its costs and changed
//! slip blocks, `ReducedSystem::solve`), with the iterative preset's reuse path one MatMult and
//! one Allreduce of 2 values (the warm start's residual); without friction one Allreduce of m values (the rigid motion fitted to
//! the active gaps, taken out of the solve: u = ρ + w, see `FreeModes::fit_motion`), the
//! writing of the reduced system (one all-gather of the rewritten nodes' directions, PETSc's
//! assembly of entries in other ranks' rows), the solve, one MatMult, one Allreduce; rarely a
//! load-balance test that finds an unbalanced load (two reductions) or a least-index pick.
//!
//! | module | role |
//! |---|---|
//! | `problem` | what the loop takes and gives: settings, problem, warm start, results |
//! | `iteration` | [`semismooth_newton`]: the loop and its stopping rules |
//! | `step` | one step's plan, the rigid motion added back, the stall rule, the log lines |
//! | `reuse` | the plain path's reuse of factorisations, one rule for every branch |

pub mod iteration;
pub mod problem;
pub mod reuse;
pub mod step;

pub(crate) use iteration::auto_start;
pub use iteration::semismooth_newton;
pub use problem::{
    nodal_stiffness, ContactProblem, NewtonResult, NewtonSettings, StepInfo, WarmStart,
};
pub use reuse::enable_reuse;
pub(crate) use step::{add_motion, stalled};
