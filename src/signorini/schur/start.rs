//! The start of a frictionless pass: the base system, the first set and the split of the
//! candidates into zones.

use super::frictionless::{first_zone, Candidates, Compliance, Growth};
use super::outcome::Kept;
use super::round::dense_round;
use super::summary::record_steps;
use super::summary::CondensedSummary;
use crate::error::RunError;
use crate::par::Ctx;
use crate::signorini::active_set::{ActiveSet, Law};
use crate::signorini::dense::DenseRun;
use crate::signorini::halfspace::Located;
use crate::signorini::plain_path::{ContactProblem, NewtonSettings, StepInfo, WarmStart};
use crate::signorini::rigid::FreeModes;
use crate::signorini::step_system::ReducedSystem;
use std::time::Instant;

/// Whether a wide zone's interior may be held on the obstacle in the factorised matrix:
/// frictionless (with the frictionless steps; a load step only where the step before kept no
/// factorisation or one with a held zone), or for friction (`per` > 1) sticking as well where
/// `stick` asks (a load step without the frictionless steps: its dense iteration starts from
/// the warm states; a zone is held there only where the candidates grow too wide); not under
/// force control. Local.
pub(super) fn splits_zones(
    p: &ContactProblem,
    s: &NewtonSettings,
    warm: Option<&WarmStart>,
    (per, steps, stick): (usize, bool, bool),
) -> bool {
    let kept_allows = warm.is_none() || p.kept.is_empty() || p.kept.holds_zone();
    s.force.is_empty()
        && if per == 1 {
            steps && kept_allows && !s.estimate && s.carried.is_none()
        } else {
            stick && (steps || warm.is_some())
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

/// One pass of the condensed path: K_p's free modes and right-hand side (this rank's rows and
/// f on rank 0) with the pass' held nodes, the candidates, their growth (which knows the held
/// nodes) and compliance, and the seconds of a load step's condensation on a kept
/// factorisation.
pub(super) struct Pass {
    pub(super) free: FreeModes,
    pub(super) rhs0: Vec<f64>,
    pub(super) f_root: Vec<f64>,
    pub(super) cand: Candidates,
    pub(super) growth: Growth,
    pub(super) comp: Compliance,
    pub(super) condensation: f64,
}

impl Pass {
    /// A round's dense steps ([`dense_round`]; `first`: nested, `located`: the located zone's
    /// node count), recorded in `summary` and the step `history`. Collective.
    pub(super) fn dense(
        &mut self,
        ctx: &Ctx,
        s: &NewtonSettings,
        (first, located): (bool, Option<usize>),
        (summary, history): (&mut CondensedSummary, &mut Vec<StepInfo>),
    ) -> DenseRun {
        let t = Instant::now();
        let (cand, comp, free) = (&self.cand, &mut self.comp, &self.free);
        let active = &self.growth.active;
        let (run, x_s) = dense_round(ctx, cand, comp, free, s, (active, first), located);
        comp.x_s = x_s;
        summary.dense_seconds += t.elapsed().as_secs_f64();
        summary.record_coarse(ctx, &run);
        let round = (comp.list.len(), free.pins().len());
        record_steps(ctx, history, &run.steps, ("C_n", "condensed"), round);
        run
    }

    /// What the pass keeps for a friction solve or the next load step, with the candidates'
    /// multipliers `lambda`.
    pub(super) fn keep(self, lambda: Vec<f64>, zone: Option<Vec<bool>>) -> Kept {
        Kept {
            n_local: self.rhs0.len(),
            comp: self.comp,
            cand: self.cand,
            f_root: self.f_root,
            free: self.free,
            lambda,
            active: self.growth.active,
            held: self.growth.held,
            zone: zone.unwrap_or_default(),
        }
    }
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
    (p, reduced): (&ContactProblem, &mut ReducedSystem),
    free0: &FreeModes,
    (held, stick): (&[bool], bool),
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
    free.update(ctx, mesh, layout, &[0.0; 36])?;
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
