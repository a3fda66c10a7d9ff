//! One round of the frictionless Schur path: MUMPS' factorisation with the Schur complement on
//! the candidates, the dense Algorithm 1 on the compliance, the expansion of the iterate and the
//! judgement of its set on the full system.

use super::candidates::{Added, Candidates, Compliance, Growth, Shape};
use super::outcome::{Expanded, Kept};
use super::start::SolveStart;
use super::stop::Stop;
use super::summary::record_steps;
use super::summary::CondensedSummary;
use crate::contact::{normal_active_or_tie, ties};
use crate::error::RunError;
use crate::par::Ctx;
use crate::petsc::PInt;
use crate::say;
use crate::signorini::active_set::{ActiveSet, Iterate};
use crate::signorini::boundary::ContactBoundary;
use crate::signorini::dense::{guarded, CMatrix, Dense, DenseRun, End, Moves, Primal};
use crate::signorini::halfspace::{self};
use crate::signorini::plain_path::{ContactProblem, NewtonSettings, StepInfo, WarmStart};
use crate::signorini::rigid::{FreeModes, Motion};
use crate::signorini::step_system::ReducedSystem;
use nalgebra::{DMatrix, DVector};
use std::time::Instant;

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
        first: bool,
        located: Option<usize>,
        summary: &mut CondensedSummary,
        history: &mut Vec<StepInfo>,
    ) -> DenseRun {
        let t = Instant::now();
        let (cand, comp, free) = (&self.cand, &mut self.comp, &self.free);
        let from = DenseStart {
            active: &self.growth.active,
            nested: first,
            located,
        };
        let (run, x_s) = dense_round(ctx, cand, comp, free, s, from);
        comp.x_s = x_s;
        summary.dense_seconds += t.elapsed().as_secs_f64();
        summary.record_coarse(ctx, &run);
        let (candidates, pinned) = (comp.list.len(), free.pins().len());
        record_steps(
            ctx,
            history,
            &run.steps,
            "C_n",
            "condensed",
            candidates,
            pinned,
        );
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

/// A round's first phase: the nodes it adds (`Growth::next`) and K_p factorised with their
/// Schur complement (`Compliance::grow`), or the previous load step's factorisation where it
/// holds every candidate; recorded in `summary`. `Err`: why the condensed path stops.
/// Collective.
pub(super) fn factorise_round(
    ctx: &Ctx,
    reduced: &ReducedSystem,
    pass: &mut Pass,
    summary: &mut CondensedSummary,
    round: usize,
    shape: &Shape,
) -> Result<(), Stop> {
    let Pass {
        cand,
        growth,
        comp,
        condensation,
        f_root,
        ..
    } = pass;
    let (cand, growth, condensation) = (&*cand, &*growth, *condensation);
    let t = Instant::now();
    let new = growth.next(cand, comp, round)?;
    if new.is_empty() && comp.factor.is_some() {
        // the previous load step's factorisation holds every candidate of this one
        summary.record_kept(ctx, comp, cand, condensation + t.elapsed().as_secs_f64());
        return Ok(());
    }
    let added = Added {
        nodes: &new,
        why: &growth.why,
    };
    comp.grow(ctx, reduced, cand, added, shape, f_root)?;
    summary.factorisation_kept = false;
    summary.primal = comp.primal;
    summary.record_factorisation(comp, cand, t.elapsed().as_secs_f64());
    Ok(())
}

/// What a dense round's end means for the condensed path.
pub(super) enum Judged {
    /// Converged: expand and check on every contact node.
    Expand,
    /// No support among fewer candidates than contact nodes: every node a candidate, again.
    Again,
    Stop(Stop),
}

/// A round's dense end judged (the round of `pass`): no support on a body that nothing else
/// can hold is the case's error (force control: the obstacle never touches); a fallback of
/// the primal form means the zone is too wide even for it. Collective (force control's check).
pub(super) fn judge(
    ctx: &Ctx,
    p: &ContactProblem,
    s: &NewtonSettings,
    pass: &mut Pass,
    run: &DenseRun,
) -> Result<Judged, RunError> {
    let (free, comp, n) = (&pass.free, &pass.comp, pass.cand.n);
    let growth = &mut pass.growth;
    match &run.end {
        End::Converged => Ok(Judged::Expand),
        End::NoSupport(_) if comp.list.len() < n => {
            // a node beyond the candidates may still carry the load: all of them
            growth.take_all();
            growth.why = format!(
                "no support among the {} candidates, so every contact node",
                comp.list.len()
            );
            Ok(Judged::Again)
        }
        End::NoSupport(reaction) => {
            // under force control: the pair whose obstacle never reaches the body, if one
            // does not; else no support as without force control
            if let Some(fc) = crate::signorini::force::unreached(ctx, p.boundary, s.force) {
                return Err(crate::signorini::force::never_touches(fc));
            }
            Err(free.no_support(run.active.iter().filter(|&&a| a).count(), *reaction))
        }
        // the primal form gives up where the zone is too wide even for it
        End::Fallback(why) if comp.primal => Ok(Judged::Stop(Stop::too_wide(why.clone()))),
        End::Fallback(why) => Ok(Judged::Stop(Stop::failed(why.clone()))),
    }
}

/// A floating body's contact zone located by the half-space model before anything is
/// factorised (the first solve of a case, `s.model` given): it may lie far from the smallest
/// gaps (the body rolls where friction alone holds a part of the load, `s.carried`) and be
/// wider than the dense limits. The clearance of this rank's contact nodes after the model's
/// rigid motion and the nodes it puts in contact ([`halfspace::locate`]), computed once per
/// solve (`located`). Collective.
pub(super) fn locate(
    ctx: &Ctx,
    p: &ContactProblem,
    located: &mut Option<halfspace::Located>,
    s: &NewtonSettings,
    free: &FreeModes,
    warm: Option<&WarmStart>,
) -> Result<Option<(Vec<f64>, usize)>, RunError> {
    match (s.model, warm) {
        (Some(hs), None) if free.floats() && free.dirichlet_free().ncols() > 0 => {
            if let Some(done) = located.as_ref() {
                return Ok(done.clone()); // the same body, load and model: located once
            }
            let phi = s.carried.map_or_else(|| free.free_load(), <[f64]>::to_vec);
            let zone = halfspace::locate(ctx, hs, p.boundary, free, &phi, s.dense_limits())?;
            *located = Some(zone.clone());
            Ok(zone)
        }
        _ => Ok(None),
    }
}

/// A floating body under force control: with one pair the load balance fixes the force;
/// with several, each approach is one more free mode next to the body's own (the dense
/// iteration's G has a column per mode), unless every pair is force-controlled (the
/// approaches and the body's position along them are then not determined). Local.
pub(super) fn refuse_floating_force(
    p: &ContactProblem,
    s: &NewtonSettings,
    free: &FreeModes,
) -> Result<(), RunError> {
    if let (Some(fc), true) = (s.force.first(), free.floats()) {
        if p.boundary.n_pairs() == 1 {
            return Err(crate::signorini::force::floating(fc));
        }
        if s.force.len() == p.boundary.n_pairs() {
            return Err(crate::signorini::force::all_pairs_floating(fc));
        }
    }
    Ok(())
}

/// A load step's compliance on the previous step's factorisation (`kept`): K_p
/// is the same matrix in every load step where it holds the same nodes (`held`; their rows'
/// values, this step's references and gaps, are in f), so where the pins, `per`, the held
/// nodes and the kept candidates' rows and frames are this step's, only d₀ is new (MUMPS'
/// condensation of this step's f, `f_root` on rank 0). `None`: nothing kept, or it does not
/// hold (it is dropped; its node order is returned). Collective (the decision is taken on
/// all-gathered data: the same on every rank).
pub(super) fn reused(
    ctx: &Ctx,
    at: &SolveStart,
    kept: Option<Kept>,
    free: &FreeModes,
    cand: &Candidates,
    f_root: &[f64],
    held: &[bool],
) -> (Option<Compliance>, Option<Vec<usize>>) {
    let per = at.per;
    let Some(kept) = kept else {
        return (None, None);
    };
    let holding = |h: &[bool]| h.iter().any(|&x| x);
    let same_held = match (holding(&kept.held), holding(held)) {
        (false, false) => true,
        (true, true) => kept.held == held,
        _ => false,
    };
    if kept.comp.primal || !same_held || !kept.holds(free, cand, per) {
        return (None, kept.comp.node_order);
    }
    let mut comp = kept.comp;
    match comp.recondense(ctx, f_root) {
        Ok(()) => (Some(comp), None),
        Err(why) => {
            say!(ctx, "newton: condensed: {why}; a new factorisation");
            (None, comp.node_order.take())
        }
    }
}

/// Force control's approaches as free modes: each pair's direction e_j, load |F_j| and pair.
type ForceModes = Vec<([f64; 3], f64, usize)>;

/// The dense system's free-mode columns G (the free modes' normal parts at the candidates, then
/// each force-controlled approach δ_j's, −e_j·n on its pair's candidates), their loads φ and
/// the load scale. Local (rank 0).
fn mode_columns(
    cand: &Candidates,
    comp: &Compliance,
    free: &FreeModes,
    s: &NewtonSettings,
    force: &ForceModes,
) -> (DMatrix<f64>, Vec<f64>, f64) {
    let (ns, mz) = (comp.list.len(), cand.mz + force.len());
    let (_, mut load_scale) = free.load();
    let mut phi = s.carried.map_or_else(|| free.free_load(), <[f64]>::to_vec);
    let list = &comp.list;
    let g = DMatrix::from_fn(ns, mz, |q, c| match force.get(c.wrapping_sub(cand.mz)) {
        Some(&(e, _, pair)) if c >= cand.mz => {
            if cand.pair(list[q]) == pair {
                -crate::geom::dot(cand.n(list[q]), e)
            } else {
                0.0 // another pair's obstacle stays
            }
        }
        _ => cand.g(list[q], c),
    });
    for &(_, magnitude, _) in force {
        phi.push(magnitude);
        load_scale = load_scale.max(magnitude);
    }
    (g, phi, load_scale)
}

/// The primal form's start set over the Schur candidates `list`: as many candidates as the
/// model put in contact (`located`), by clearance after the located rigid motion; else the
/// start set `active` where it has a candidate, else all of them (no inactive unknowns). Local.
fn primal_start(
    cand: &Candidates,
    list: &[usize],
    active: &[bool],
    located: Option<usize>,
) -> Vec<bool> {
    let ns = list.len();
    match located {
        None if list.iter().any(|&i| active[i]) => list.iter().map(|&i| active[i]).collect(),
        Some(on) => {
            let mut by: Vec<usize> = (0..ns).collect();
            by.sort_by(|&a, &b| cand.by_key(list[a], list[b]));
            let mut start = vec![false; ns];
            for &q in by.iter().take(on) {
                start[q] = true;
            }
            start
        }
        None => vec![true; ns],
    }
}

/// Where a round's dense iteration starts ([`dense_round`]): the set `active`, whether the
/// nested start (coarse levels first) is taken, and the located zone's node count.
pub(super) struct DenseStart<'a> {
    pub(super) active: &'a [bool],
    pub(super) nested: bool,
    pub(super) located: Option<usize>,
}

/// Algorithm 1 on the candidates' dense system, from `from`, on rank 0; the outcome
/// broadcast to every rank. Collective.
pub(super) fn dense_round(
    ctx: &Ctx,
    cand: &Candidates,
    comp: &Compliance,
    free: &FreeModes,
    s: &NewtonSettings,
    from: DenseStart,
) -> (DenseRun, Vec<f64>) {
    let DenseStart {
        active,
        nested,
        located,
    } = from;
    // force control: each approach δ_j is one more free mode, its normal parts −e_j·n on its
    // pair's candidates and its load |F_j| (force.rs)
    let force: ForceModes = s
        .force
        .iter()
        .map(|fc| (fc.direction(), fc.magnitude(), fc.pair))
        .collect();
    let (ns, mz) = (comp.list.len(), cand.mz + force.len());
    let mut packed: Vec<f64> = Vec::new();
    // the primal form's Schur variables' part of the expansion, u − G α (rank 0)
    let mut x_s = Vec::new();
    let root = ctx.on_root_wide(ns + mz, || {
        let run = guarded("dense-steps", || {
            let (g, phi, load_scale) = mode_columns(cand, comp, free, s, &force);
            let list = &comp.list;
            let gap: Vec<f64> = list.iter().map(|&i| cand.gap(i)).collect();
            if comp.primal {
                // from as many candidates as the model put in contact, by clearance after the
                // located rigid motion; else from the start set where it has a candidate, else
                // from all of them (no inactive unknowns)
                let start = primal_start(cand, list, active, located);
                let primal = Primal {
                    s: &comp.schur,
                    r: &comp.r,
                    gap: &gap,
                    g: &g,
                    phi: &phi,
                    load_scale,
                    c: s.c,
                    max_steps: s.section.max_steps,
                    max_flops: comp.max_flops,
                };
                let run = primal.run(start);
                if run.end == End::Converged {
                    let ga = &g * DVector::from_column_slice(&run.alpha);
                    x_s = (0..ns).map(|q| run.u_n[q] - ga[q]).collect();
                }
                return run;
            }
            let (block, d0) = comp.normal_part();
            let d0 = &d0[..];
            let cmat = match &block {
                Some(b) => CMatrix::Full(b),
                None => comp.c(),
            };
            let start: Vec<bool> = list.iter().map(|&i| active[i]).collect();
            // an estimate's pins carry a body's load only beside its nodes in contact
            let dim = free.rigid_modes().dim;
            let parts = (s.estimate && cand.mz > 0).then(|| {
                DMatrix::from_fn(ns * dim, cand.mz, |r, c| {
                    cand.g_along(list[r / dim], r % dim, c)
                })
            });
            let dense = Dense {
                cmat,
                d0,
                gap: &gap,
                g: &g,
                phi: &phi,
                load_scale,
                c: s.c,
                max_steps: s.section.max_steps,
                pins: parts.as_ref().map(|parts| Moves { parts, dim }),
            };
            if nested {
                let x: Vec<[f64; 3]> = list.iter().map(|&i| cand.x(i)).collect();
                dense.run_nested(start, &x)
            } else {
                dense.run(start)
            }
        });
        run.unwrap_or_else(|why| DenseRun::failed(ns, mz, why))
            .pack(ns, mz)
    });
    if let Some(p) = root {
        packed = p;
    }
    ctx.broadcast_f64s(&mut packed);
    (DenseRun::unpack(&packed, ns, mz), x_s)
}

/// What the expansion of a round's dense result works on: the settings, the pass' free modes,
/// compliance and candidates, f on rank 0 and this rank's number of rows.
pub(super) struct Expansion<'a> {
    pub(super) s: &'a NewtonSettings<'a>,
    pub(super) free: &'a FreeModes,
    pub(super) comp: &'a mut Compliance,
    pub(super) cand: &'a Candidates,
    pub(super) f_root: &'a [f64],
    pub(super) n_local: usize,
}

/// Expansion: w = K_p⁻¹ (f − N λ_n) (MUMPS' condensation and expansion with the Schur
/// variables' part S⁻¹ (r − N_s λ_n) = x₀ − S⁻¹N_s λ_n; w goes into `reduced`),
/// ρ = R z α normalised at the pins the plain path chooses for the set (the modes the set
/// leaves free are balanced, else the dense iteration had not stopped), then (3.28) and (3.23)
/// on w with the gaps after ρ, as the plain path does, so that a large rigid motion does not
/// round λ. `(lambda, active)` of every contact node in c_h's global order. The inner `Err`:
/// MUMPS' solve failed (the plain path takes over). Collective.
pub(super) fn expand(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    at: Expansion,
    lambda: &[f64],
    active: &[bool],
    alpha: &[f64],
) -> Result<Result<Expanded, String>, RunError> {
    let Expansion {
        s,
        free,
        comp,
        cand,
        f_root,
        n_local,
    } = at;
    let b = p.boundary;
    let off = b.offset;
    let lam = root_multipliers(ctx, comp, lambda);
    let w = match comp.expand_u(ctx, cand, f_root, n_local, &lam, &[]) {
        Ok(w) => w,
        Err(why) => return Ok(Err(why)),
    };
    set_expanded(ctx, reduced, &w)?;
    let set = ActiveSet::frictionless(active[off..off + b.nodes.len()].to_vec());
    let (rho, fin) = pinned_motion(ctx, p, reduced, s, free, &set, alpha)?;
    let mut shifted = b.clone();
    free.shift(b, &rho, &mut shifted);
    let approach = force_approach(s, alpha, free.dirichlet_free().ncols(), &mut shifted);
    let mut it = Iterate::new(b.nodes.len(), n_local, false);
    reduced.recover(p.sys, &shifted, &set, &mut it)?; // (3.28)
                                                      // (3.23) on every contact node, ties keeping their state as in the dense iteration
    let nodes = shifted.nodes.iter().zip(&it.nodes);
    let (mut lambda_inf, mut length_inf) = (0.0f64, 0.0f64);
    for (k, r) in nodes.clone() {
        lambda_inf = lambda_inf.max(r.lambda_n.abs());
        length_inf = length_inf.max(r.u_n.abs()).max(k.gap.abs());
    }
    let tie = ties(ctx.max_f64(lambda_inf), ctx.max_f64(length_inf), s.c);
    let changed_here: Vec<u64> = (nodes.zip(&set.normal).enumerate())
        .filter(|(_, ((k, r), &was))| {
            normal_active_or_tie(r.u_n, r.lambda_n, k.gap, s.c, tie, was) != was
        })
        .map(|(i, _)| (off + i) as u64)
        .collect();
    Ok(Ok(Expanded {
        it,
        rho,
        pins: fin.pins().to_vec(),
        changed: ctx.all_gather_varcount(&changed_here),
        approach,
    }))
}

/// On rank 0, in the candidates' frames, the multipliers that enter Qᵀ (f − N λ_n) (λ_n
/// vanishes off the candidates: it enters each candidate's normal dof) and the normal dofs'
/// part d₀ − C λ_n; empty elsewhere.
fn root_multipliers(ctx: &Ctx, comp: &Compliance, lambda: &[f64]) -> Vec<f64> {
    if ctx.rank != 0 {
        return Vec::new();
    }
    let per = comp.per;
    let mut lam = vec![0.0; comp.list.len() * per];
    for (q, &i) in comp.list.iter().enumerate() {
        lam[q * per] = lambda[i];
    }
    lam
}

/// w into `reduced` (this rank's array), agreed before the collectives that follow.
/// Collective.
fn set_expanded(ctx: &Ctx, reduced: &mut ReducedSystem, w: &[f64]) -> Result<(), RunError> {
    let set = reduced.set_solution_local(w).map_err(RunError::from);
    let set = set.and_then(
        |()| match crate::fault::injected("condensed-expand", ctx.rank) {
            Some(m) => Err(RunError::Failed(m)),
            None => Ok(()),
        },
    );
    ctx.agree(set)
}

/// ρ = R z α, normalised at the pins the plain path chooses for `set` on the expanded w, and
/// the free modes that chose them. Collective.
fn pinned_motion(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &ReducedSystem,
    s: &NewtonSettings,
    free: &FreeModes,
    set: &ActiveSet,
    alpha: &[f64],
) -> Result<(Motion, FreeModes), RunError> {
    let (mesh, layout, b) = (p.mesh, p.layout, p.boundary);
    let dim = mesh.dim;
    let z = free.dirichlet_free();
    let mut rho = free.no_motion();
    for (j, r) in rho.iter_mut().enumerate() {
        *r = (0..z.ncols()).map(|c| z[(j, c)] * alpha[c]).sum();
    }
    let gram = set.summarise(ctx, b, free.modes(), dim).gram;
    let mut fin = FreeModes::new(ctx, mesh, layout, p.fixed, b, &reduced.f_local, s.rigid);
    fin.update(ctx, mesh, layout, &gram)?;
    if !fin.pins().is_empty() {
        let idx: Vec<PInt> = fin
            .pins()
            .iter()
            .map(|&(v, k)| (v * dim + k) as PInt)
            .collect();
        let at = reduced.solution_at(&idx)?;
        let corr = fin.motion_to_zero_pins(&at, &rho);
        for (x, c) in rho.iter_mut().zip(corr) {
            *x += c;
        }
    }
    Ok((rho, fin))
}

/// Force control: the gaps of `shifted` to the obstacles moved by δ_j e_j (δ_j the free-mode
/// coefficients after the body's own `body` ones); returns the δ_j.
fn force_approach(
    s: &NewtonSettings,
    alpha: &[f64],
    body: usize,
    shifted: &mut ContactBoundary,
) -> Vec<f64> {
    s.force
        .iter()
        .enumerate()
        .map(|(j, fc)| {
            let delta = alpha[body + j];
            for k in shifted.nodes.iter_mut().filter(|k| k.pair == fc.pair) {
                k.gap -= delta * fc.weight(k);
            }
            delta
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::petsc::mumps::nested_dissection;
    use crate::signorini::dense::coarsen;
    use crate::signorini::schur::candidates::dof_order;
    use crate::tuning::COARSEST;

    /// A dense problem without free modes (c = 1, unit load scale).
    fn no_modes<'a>(
        cmat: &'a DMatrix<f64>,
        d0: &'a [f64],
        gap: &'a [f64],
        g: &'a DMatrix<f64>,
        max_steps: usize,
    ) -> Dense<'a> {
        Dense {
            cmat: CMatrix::Full(cmat),
            d0,
            gap,
            g,
            phi: &[],
            load_scale: 1.0,
            c: 1.0,
            max_steps,
            pins: None,
        }
    }

    /// Two springs of compliance 1 under a load pressing both onto an obstacle at gap 0 and a
    /// third far away: the dense Algorithm 1 finds the set and λ by hand.
    #[test]
    fn dense_algorithm1_on_independent_springs() {
        // u_n = d0 − C λ; node 0 and 1 would penetrate (d0 < −g), node 2 not.
        let cmat = DMatrix::<f64>::identity(3, 3);
        let d0 = [-1.0, -0.5, 0.2];
        let gap = [0.0, 0.1, 0.0];
        let g = DMatrix::<f64>::zeros(3, 0);
        let dense = no_modes(&cmat, &d0, &gap, &g, 20);
        let run = dense.run(vec![false; 3]);
        assert_eq!(run.end, End::Converged);
        assert_eq!(run.active, vec![true, true, false]);
        // u_n = −g on A: λ = d0 + g (≤ 0, pressing)
        assert!((run.lambda[0] - -1.0).abs() < 1e-15);
        assert!((run.lambda[1] - -0.4).abs() < 1e-15);
        assert_eq!(run.lambda[2], 0.0);
        assert!((run.u_n[2] - 0.2).abs() < 1e-15);
    }

    /// A floating "body" of two uncoupled nodes (C = I, d₀ = 0) with one free translation along
    /// the normal, which moves both normal displacements equally, pressed by a load of 1
    /// (Gᵀ λ = φ = −1): the dense iteration from the empty set; `estimate`: the pins carry
    /// the load where the translation moves a node in contact (its parts: the normal ones).
    fn pressed_pair(gap: [f64; 2], estimate: bool) -> DenseRun {
        let cmat = DMatrix::<f64>::identity(2, 2);
        let g = DMatrix::from_row_slice(2, 1, &[1.0, 1.0]);
        let pins = estimate.then_some(Moves { parts: &g, dim: 1 });
        let dense = Dense {
            cmat: CMatrix::Full(&cmat),
            d0: &[0.0, 0.0],
            gap: &gap,
            g: &g,
            phi: &[-1.0],
            load_scale: 1.0,
            c: 1.0,
            max_steps: 20,
            pins,
        };
        dense.run(vec![false; 2])
    }

    /// The pressed pair ([`pressed_pair`]): the load φ must be carried by the contact
    /// (Σ λ = φ); from the empty set the balance test activates the node that touches first,
    /// then the set converges.
    #[test]
    fn dense_algorithm1_floating_translation() {
        let gap = [0.0, 0.5];
        let run = pressed_pair(gap, false);
        assert_eq!(run.end, End::Converged, "{run:?}");
        // node 0 alone carries λ = −1, u_n,0 = 0 = −λ + α → α = −1; node 1: u_n = α = −1 < −0.5
        // penetrates → both active: λ0 + λ1 = −1, −λ0 + α = 0, −λ1 + α = −0.5 → α = −0.75
        assert_eq!(run.active, vec![true, true]);
        let s: f64 = run.lambda.iter().sum();
        assert!((s - -1.0).abs() < 1e-14);
        assert!((run.alpha[0] - -0.75).abs() < 1e-14);
        assert!((run.u_n[0] + gap[0]).abs() < 1e-14 && (run.u_n[1] + gap[1]).abs() < 1e-14);
    }

    /// An estimate (the pins carry the load where the set leaves a mode free, Coulomb's
    /// frictionless start) from the empty set, with no node penetrating at d₀: the load still
    /// brings the body into contact (the balance test activates the node that touches first),
    /// instead of the pins carrying all of it with nothing in contact.
    #[test]
    fn an_estimate_from_the_empty_set_brings_the_pressed_body_into_contact() {
        let run = pressed_pair([0.1, 0.5], true);
        assert_eq!(run.end, End::Converged, "{run:?}");
        assert_eq!(run.active, vec![true, true], "{run:?}");
        let s: f64 = run.lambda.iter().sum();
        assert!((s - -1.0).abs() < 1e-14, "{run:?}");
    }

    /// The primal form on S ends where the dual form on C = S⁻¹ ends (same set, λ, u, α): a
    /// line of 40 candidates with a coupled SPD S (a discrete Laplacian plus a diagonal), a
    /// curved gap, pressed down by a load held by the contact alone (one free translation)
    /// and, with the translation pinned, by a load through d₀.
    #[test]
    fn primal_form_on_s_equals_the_dual_form_on_its_inverse() {
        let n = 40;
        let mut sm = DMatrix::<f64>::zeros(n, n);
        for i in 0..n {
            sm[(i, i)] = 2.5;
            if i + 1 < n {
                sm[(i, i + 1)] = -1.0;
                sm[(i + 1, i)] = -1.0;
            }
        }
        let cmat = sm.clone().try_inverse().expect("SPD");
        let gap: Vec<f64> = (0..n)
            .map(|i| {
                let x = (i as f64 - 19.5) / 20.0;
                0.5 * x * x
            })
            .collect();
        for (mz, r) in [(1, vec![0.0; n]), (0, vec![-0.05; n])] {
            let g = DMatrix::from_element(n, mz, 1.0);
            let phi = vec![-0.4; mz];
            let d0 = (&cmat * DVector::from_column_slice(&r)).as_slice().to_vec();
            let dual = Dense {
                cmat: CMatrix::Full(&cmat),
                d0: &d0,
                gap: &gap,
                g: &g,
                phi: &phi,
                load_scale: 1.0,
                c: 1.0,
                max_steps: 50,
                pins: None,
            }
            .run(vec![false; n]);
            let primal = Primal {
                s: &sm,
                r: &r,
                gap: &gap,
                g: &g,
                phi: &phi,
                load_scale: 1.0,
                c: 1.0,
                max_steps: 50,
                max_flops: 1e9,
            }
            .run(vec![true; n]);
            assert_eq!(dual.end, End::Converged, "{dual:?}");
            assert_eq!(primal.end, End::Converged, "{primal:?}");
            let on = primal.active.iter().filter(|&&a| a).count();
            assert!(on > 2 && on < n, "{mz} modes: {on} active");
            assert_eq!(primal.active, dual.active, "{mz} modes");
            for i in 0..n {
                assert!((primal.lambda[i] - dual.lambda[i]).abs() < 1e-12, "λ {i}");
                assert!((primal.u_n[i] - dual.u_n[i]).abs() < 1e-12, "u {i}");
            }
            for (a, b) in primal.alpha.iter().zip(&dual.alpha) {
                assert!((a - b).abs() < 1e-12, "α");
            }
        }
    }

    #[test]
    fn dense_no_support_when_the_load_pulls_away() {
        let cmat = DMatrix::<f64>::identity(1, 1);
        let g = DMatrix::from_row_slice(1, 1, &[1.0]);
        let dense = Dense {
            cmat: CMatrix::Full(&cmat),
            d0: &[0.0],
            gap: &[0.0],
            g: &g,
            phi: &[1.0],
            load_scale: 1.0,
            c: 1.0,
            max_steps: 20,
            pins: None,
        };
        let run = dense.run(vec![false]);
        assert!(matches!(run.end, End::NoSupport(_)), "{run:?}");
    }

    #[test]
    fn coarsening_of_a_line_halves_it_and_keeps_the_first_contact() {
        // 201 points at spacing 0.01 on a line, the smallest gap at point 137
        let x: Vec<[f64; 3]> = (0..201).map(|i| [0.01 * i as f64, 0.0, 0.0]).collect();
        let gap: Vec<f64> = (0..201).map(|i| (i as f64 - 137.0).abs()).collect();
        let levels = coarsen(&x, &gap);
        assert!(levels.len() >= 3, "{} levels", levels.len());
        let mut before = x.len();
        for (k, l) in levels.iter().enumerate() {
            assert!(l.contains(&137), "level {k} lost the first contact");
            assert!(l.len() >= COARSEST);
            assert!(
                l.len() * 4 <= before * 3,
                "level {k}: {} of {before}",
                l.len()
            );
            // spread: the kept points are 2^(k+1) spacings apart, so about n / 2^(k+1)
            let r = 0.01 * 0.99 * f64::powi(2.0, k as i32 + 1);
            for (a, &i) in l.iter().enumerate() {
                for &j in &l[..a] {
                    assert!((x[i][0] - x[j][0]).abs() >= r * (1.0 - 1e-12));
                }
            }
            assert!(
                l.len() <= 201 / (1 << (k + 1)) + 2,
                "level {k}: {}",
                l.len()
            );
            before = l.len();
        }
    }

    #[test]
    fn nested_run_ends_in_the_plain_runs_solution_in_fewer_fine_steps() {
        // A coupled line of 129 nodes pressed onto a flat obstacle: C_ij = exp(−|i−j| / 8)
        // (positive definite), d₀ a parabola deepest at the middle.
        let n = 129;
        let cmat = DMatrix::from_fn(n, n, |i, j| (-(i as f64 - j as f64).abs() / 8.0).exp());
        let d0: Vec<f64> = (0..n)
            .map(|i| {
                let t = (i as f64 - 64.0) / 64.0;
                -1.0 + 2.0 * t * t
            })
            .collect();
        let gap = vec![0.0; n];
        let x: Vec<[f64; 3]> = (0..n).map(|i| [i as f64, 0.0, 0.0]).collect();
        let g = DMatrix::<f64>::zeros(n, 0);
        let dense = no_modes(&cmat, &d0, &gap, &g, 50);
        let mut start = vec![false; n];
        start[64] = true;
        let plain = dense.run(start.clone());
        let nested = dense.run_nested(start, &x);
        assert_eq!(plain.end, End::Converged);
        assert_eq!(nested.end, End::Converged);
        assert_eq!(nested.active, plain.active);
        for i in 0..n {
            assert!((nested.lambda[i] - plain.lambda[i]).abs() <= 1e-12);
        }
        assert!(!nested.coarse.is_empty());
        assert!(
            nested.steps.len() < plain.steps.len(),
            "fine steps: nested {} plain {}",
            nested.steps.len(),
            plain.steps.len()
        );
    }

    #[test]
    fn dof_order_keeps_nodes_together_and_the_schur_dofs_last() {
        // 5 nodes, 2 dofs each; node order 4 2 0 3 1; Schur: nodes 2 and 0 (listed 2 first)
        let node_perm = [2, 4, 1, 3, 0];
        let schur = [4, 5, 0, 1];
        let order = dof_order(&node_perm, &schur, 2, 10);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..10).collect::<Vec<_>>(), "not a permutation");
        // the other nodes in Scotch's order 4, 3, 1, then the Schur dofs in their list order
        assert_eq!(order, vec![8, 9, 4, 5, 6, 7, 2, 3, 0, 1]);
    }

    #[test]
    fn nested_dissection_orders_a_grid() {
        // a 20 × 20 grid graph: a permutation, with the first separator (the last positions)
        // splitting the grid
        let (m, n) = (20usize, 400usize);
        let mut xadj = vec![0];
        let mut adj = Vec::new();
        for v in 0..n {
            let (i, j) = (v / m, v % m);
            for (di, dj) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                let (a, b) = (i as i64 + di, j as i64 + dj);
                if a >= 0 && b >= 0 && (a as usize) < m && (b as usize) < m {
                    adj.push(a as usize * m + b as usize);
                }
            }
            xadj.push(adj.len());
        }
        let perm = nested_dissection(&xadj, &adj).unwrap();
        let mut sorted = perm.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..n).collect::<Vec<_>>());
        // nested dissection eliminates a separator last: the last 20 positions do not hold a
        // connected corner block of the natural order (as a band order would)
        let last: Vec<usize> = (0..n).filter(|&v| perm[v] >= n - m).collect();
        assert!(last
            .iter()
            .any(|&v| v / m > 0 && v / m < m - 1 && v % m > 0 && v % m < m - 1));
        assert!(
            nested_dissection(&[0, 1], &[5]).is_err(),
            "malformed graph accepted"
        );
    }
}
