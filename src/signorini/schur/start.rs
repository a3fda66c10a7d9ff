//! The start of a frictionless pass: the base system, the first set and the split of the
//! candidates into zones.

use super::candidates::{first_zone, Candidates, Sticking};
use crate::error::RunError;
use crate::par::Ctx;
use crate::signorini::active_set::{ActiveSet, Law};
use crate::signorini::halfspace::Located;
use crate::signorini::kept::KeptFactor;
use crate::signorini::plain_path::{ContactProblem, NewtonSettings, WarmStart};
use crate::signorini::rigid::FreeModes;
use crate::signorini::step_system::ReducedSystem;

/// Whether a wide zone's interior may be held on the obstacle in the factorised matrix:
/// frictionless (with the frictionless steps; a load step only where the step before kept no
/// factorisation or one with a held zone), or for friction (`per` > 1) sticking as well where
/// `stick` asks (a load step or a later pass of a start without the frictionless steps: its
/// dense iteration starts from the warm states or the pass before's; a zone is held there only
/// where the candidates grow too wide); not under force control. Local.
pub(super) fn splits_zones(
    kept: &KeptFactor,
    s: &NewtonSettings,
    warm: Option<&WarmStart>,
    per: usize,
    steps: bool,
    stick: bool,
) -> bool {
    let kept_allows = warm.is_none() || kept.is_empty() || kept.holds_zone();
    s.force.is_empty()
        && if per == 1 {
            steps && kept_allows && !s.estimate && s.carried.is_none()
        } else {
            stick
        }
}

/// The predicted zone of [`first_zone`] on every contact node as the case starts (`all0`,
/// where zones may be held), with the located zone's node count. Local.
pub(super) fn predicted_zone(
    all0: Option<&Candidates>,
    located: &Located,
    per: usize,
) -> Option<Vec<bool>> {
    all0.and_then(|all| first_zone(all, located.as_ref().map(|(_, on)| *on), per))
}

/// What every pass of one solve starts from (fixed for the solve): the problem and its warm
/// start, the modes Dirichlet data leave free, every contact node as the case starts (`all0`,
/// where zones may be held), the start set, the located zone and the Schur variables per
/// candidate.
pub(super) struct SolveStart<'a> {
    pub(super) p: &'a ContactProblem<'a>,
    pub(super) warm: Option<&'a WarmStart<'a>>,
    pub(super) free0: &'a FreeModes,
    pub(super) all0: Option<&'a Candidates>,
    pub(super) start: &'a [bool],
    pub(super) located: &'a Located,
    pub(super) per: usize,
    /// Every node with a Tresca threshold a candidate ([`super::frictionless::Condensing`]).
    pub(super) thresholds: bool,
}

/// What one pass is asked to hold: the predicted `zone` (or none), the node order kept from a
/// pass before, and the sticking zone's settings.
pub(super) struct PassPlan<'a> {
    pub(super) zone: Option<&'a [bool]>,
    pub(super) order: Option<Vec<usize>>,
    pub(super) sticking: Sticking<'a>,
}

/// K_p: A with every rigid mode that Dirichlet data and the held nodes (`held`: every
/// contact node in c_h's global order, or empty) leave free pinned, the held nodes' normal
/// rows written as the reduced system (3.29) writes an active node (u_n = −g) — with `stick`
/// their tangential rows too, as (3.42) writes a sticking node (u_τ = u_ref) — and no other
/// contact row, into the reduced system's matrix (factorised later, by MUMPS directly, with
/// the Schur complement). `free0`: the modes Dirichlet data leave free. Returns the free
/// modes (with K_p's pins) and this rank's rows of K_p's right-hand side. Collective.
pub(super) fn prepare_base(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    free0: &FreeModes,
    held: &[bool],
    stick: bool,
) -> Result<(FreeModes, Vec<f64>), RunError> {
    let (mesh, layout, b, sys) = (p.mesh, p.layout, p.boundary, p.sys);
    let mut free = free0.clone();
    let mine = match held.is_empty() {
        true => vec![false; b.nodes.len()],
        false => held[b.offset..b.offset + b.nodes.len()].to_vec(),
    };
    let set = ActiveSet::held(mine, stick);
    if held.iter().any(|&h| h) {
        let gram = set.summarise(ctx, b, free.modes(), mesh.dim).gram;
        free.hold_also(&gram);
    }
    let none = free.rigid_modes().zero_gram();
    free.update(ctx, mesh, layout, &none)?;
    reduced.set_pins(sys, layout, free.pins())?;
    reduced.write(ctx, sys, layout, b, &set, free.pins())?;
    Ok((free, reduced.rhs_local()?))
}

/// The start set of this rank's contact nodes: the warm start's final set, or the case's
/// start as the plain path forms it. Local.
pub(super) fn start_set(
    p: &ContactProblem,
    s: &NewtonSettings,
    free: &FreeModes,
    warm: Option<&WarmStart>,
) -> Vec<bool> {
    match warm {
        Some(w) => w.nodes.iter().map(|r| r.active).collect(),
        None => {
            let init = crate::signorini::plain_path::auto_start(s.section.init, false, free);
            let (b, dim) = (p.boundary, p.mesh.dim);
            ActiveSet::initial(b, init, Law::Frictionless, s.c, p.mesh.extent(), dim).normal
        }
    }
}
