//! The Schur path: the contact problem condensed onto the candidate contact nodes' unknowns
//! with MUMPS' Schur complement, frictionless (Algorithm 1 on the dense compliance) and
//! Coulomb (the generalised Newton on the same candidates' dense system).
//!
//! | module | role |
//! |---|---|
//! | `frictionless` | the frictionless pass: candidates, rounds, growth of the zone |
//! | `start` | the base system, the first set, the zones of the candidates |
//! | `round` | one round: factorisation, dense Algorithm 1, expansion, judgement |
//! | `outcome` | how a pass ends: solved, factorised and kept, or fallen back |
//! | `coulomb` | the Coulomb pass on the kept factorisation: check, finish, warm start |
//! | `coulomb_dense` | Coulomb's generalised Newton on the dense system |
//! | `summary` | the summaries (summary.json's `condensed`) and the dense steps' records |

pub mod candidates;
pub mod coulomb;
pub mod coulomb_dense;
pub mod coulomb_run;
pub mod frictionless;
pub mod outcome;
pub mod round;
pub mod start;
pub mod stop;
pub mod summary;

pub use coulomb::CoulombCondensed;
pub use outcome::{Condensed, Kept};
pub use summary::{CondensedSummary, CoulombCondensedSummary};
