//! The plain path's reuse of factorisations (Algorithms 1/2 and Coulomb's steps on the whole
//! reduced system), one rule for every branch that enters it.

use super::problem::NewtonSettings;
use crate::case::{Reuse, SolverSection};
use crate::error::RunError;
use crate::par::Ctx;
use crate::signorini::step_system::ReducedSystem;

/// Sets up the reuse of factorisations (or preconditioners) of the plain path: force control
/// solves its lift on the step's own factorisation (force.rs), so a factorising solver never
/// reuses one under force control; the iterative preset's reuse of preconditioners stays.
/// `friction`: the rows change with the tangential states. Collective.
pub fn enable_reuse(
    ctx: &Ctx,
    ns: &NewtonSettings,
    section: &SolverSection,
    reduced: &mut ReducedSystem,
    friction: bool,
) -> Result<(), RunError> {
    let reuse = if !ns.force.is_empty() && reduced.factorises()? {
        Reuse::Never
    } else {
        section.reuse
    };
    reduced.enable_reuse(ctx, reuse, friction)?;
    Ok(())
}
