//! The half-space predictor of the frictionless active set (iterative preset).
//!
//! On the iterative preset every Newton step is a Krylov solve of the whole body, and the
//! steps Algorithm 1 makes from the all-inactive start (grow past the final set, then shrink
//! by about half the excess per step) cost 5–8 such solves. The direct preset avoids them with
//! the exact compliance C = Nᵀ K_p⁻¹ N on the candidates (schur/frictionless.rs); the iterative preset
//! has no factorisation to take it from. This module replaces C by the compliance of an
//! elastic half-space with the body's contact modulus E* (Boussinesq in 3D, Flamant in 2D),
//! with mirror images in the body's symmetry planes, and keeps the rest exact: d₀ = the
//! normal displacements of the first solve (no active node, u⁰ = K_p⁻¹ f), the gaps, the
//! free rigid modes and their load balance. Algorithm 1 on that dense model (the nested
//! iteration of schur/frictionless.rs) gives the set the second Newton step starts from; from there
//! Algorithm 1 goes on on the real system, so the final iterate is Algorithm 1's whatever
//! the model's error (it only costs steps). The model is that of Hertz' theory: exact for
//! a small contact zone on a smooth body, rougher for conforming contact or thin bodies.
//!
//! After every exact step from the predicted set on whose update (3.23) changes nodes, the
//! model corrects that update ([`correct`]): anchored at the step's exact solution
//! (d₀ = u_n + C λ_n), it models only the change of λ, so its error shrinks with the change,
//! and its Algorithm 1 also moves the nodes that change only after others have (a contact
//! edge that moves by several nodes, which (3.23) alone moves a node per step). A model that
//! keeps the step's set leaves (3.23)'s update, so a correction never ends the iteration: it
//! still ends on an exact step whose update changes nothing. Where the zone needs more model
//! nodes than the cap, the correction models the update's edge band alone and holds the rest.

use super::active_set::Iterate;
use super::boundary::ContactBoundary;
use super::dense::DenseLimits;
use super::rigid::FreeModes;
use crate::contact::normal_active;
use crate::error::RunError;
use crate::par::Ctx;
use crate::say;
use crate::tuning::{LOCATE_MODEL_NODES, MAX_REPRESENTED, MIN_MODEL_NODES, MODEL_MARGIN};
use serde::Serialize;
use std::time::Instant;

mod kernel;
mod model;

use kernel::column_share;
pub use kernel::{mirror_planes, HalfSpace};
use model::{max_model_nodes, Model};
pub use model::{model_nodes, refine_at_edge};

/// What the predictor did (summary.json `newton.history[0].predictor`).
#[derive(Clone, Debug, Serialize)]
pub struct PredictorStep {
    /// The set the second step starts from came from the model ("predicted"), or why not.
    pub outcome: String,
    /// Nodes in the model and contact nodes it represents (more when coarsened).
    pub model_nodes: usize,
    pub represented: usize,
    /// Nodes the model puts in contact.
    pub predicted_active: usize,
    pub mirror_planes: usize,
    /// Steps of Algorithm 1 on the model (finest level) and its coarse levels.
    pub model_steps: usize,
    pub coarse_levels: usize,
    /// The predicted set reaches the outer tenth of the model's nodes (by the first solve's
    /// clearance) while contact nodes are left out of the model ([`MAX_MODEL_NODES`]): the
    /// contact zone may extend beyond the model, and the steps after the prediction stay
    /// inexact while the set moves, as without one.
    pub truncated: bool,
    /// Force control: the model's change of each force-controlled pair's approach δ_j, in
    /// pair order (the second step starts there).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub approach_change: Option<Vec<f64>>,
    pub seconds: f64,
}

/// Values per node record gathered on every rank: x (3), n (3), gap, w, u_n, pair, λ_n of an
/// active node (0 off the set), the gmsh tag (exact in f64 below 2⁵³). The free modes' normal
/// parts G (m_z per node) are gathered beside them.
const REC: usize = 12;
/// Where the pair, λ_n and the tag are in a record.
const PAIR: usize = 9;
const LAMBDA: usize = 10;
const TAG: usize = 11;

/// Force control of one pair in the model: the direction e, |F| and the pair.
type PairForce = ([f64; 3], f64, usize);

/// The exact solve a model run starts from: the contact boundary as the solve saw it, its
/// iterate, and the solve's active set for a correction ([`correct`]; `None` for a prediction,
/// all nodes inactive).
#[derive(Clone, Copy)]
struct Anchor<'a> {
    boundary: &'a ContactBoundary,
    iterate: &'a Iterate,
    active: Option<&'a [bool]>,
    /// A coarsened model may run (else the run ends before the model is solved).
    coarse: bool,
}

/// The node records gathered on every rank ([`REC`] values per contact node,
/// [`gather_records`]) and beside them the free modes' normal parts G (m_z per node).
#[derive(Clone, Copy)]
struct Records<'a> {
    all: &'a [f64],
    g_all: &'a [f64],
}

/// What one run of the model on rank 0 solves ([`Model::solve`]): the free modes' count m_z,
/// the dense iteration's limits, the force-controlled pairs (e, |F|, pair) and whether the
/// model grows while its contact zone reaches its border.
struct ModelRun<'a> {
    mz: usize,
    limits: DenseLimits,
    force: &'a [PairForce],
    grow: bool,
}

/// The predicted normal set of this rank's contact nodes after the first solve (`it`, on the
/// boundary `b` as the solve saw it, all nodes inactive), or `None` when the model does not
/// apply (no node penetrates, the dense iteration did not converge); and the record.
/// Collective.
pub fn predict(
    ctx: &Ctx,
    hs: &HalfSpace,
    b: &ContactBoundary,
    it: &Iterate,
    free: &FreeModes,
    limits: DenseLimits,
    force: &[PairForce],
) -> Result<(Option<Vec<bool>>, PredictorStep), RunError> {
    let anchor = Anchor {
        boundary: b,
        iterate: it,
        active: None,
        coarse: true,
    };
    run_model(ctx, hs, anchor, free, limits, force)?
        .ok_or_else(|| RunError::Failed("the half-space model did not run".into()))
}

/// The model as a correction of an exact step (frictionless, no force control): after the
/// solve of (3.29) on the set `active`, the model is anchored at that solution — d₀ = u_n +
/// C λ_n, so that at the step's λ_n it gives the step's u_n exactly and only the change of λ
/// is modelled — and Algorithm 1 on it gives the set that the changes of (3.23) lead to,
/// including the nodes that change only once the others have (a contact edge that moves
/// by more than one node). The iteration starts from the exact step's own update, which its
/// first dense step reproduces. Where the model of every represented node would be coarser
/// than the mesh ([`model_nodes`]), the model is the update's edge band alone, at full
/// resolution, every other node held in its updated state at its λ_n ([`Model::edge_band`]):
/// a coarse model moves the edge by whole groups of nodes, and even refined at the edge
/// ([`refine_at_edge`]) its coarse interior misplaces it (measured: the full floating ball,
/// 2 ranks, 10 × its load: at 396 633 unknowns 8 steps with coarse corrections, 6 with refined
/// ones, 3 without; at 1 213 776 unknowns 10 steps with refined corrections, 5 without, 4
/// with the band). Returns the model's set of this rank's nodes as for [`predict`]; `None`
/// (nothing run, nothing logged) where the band exceeds [`MAX_MODEL_NODES`].
/// Collective.
pub fn correct(
    ctx: &Ctx,
    hs: &HalfSpace,
    b: &ContactBoundary,
    it: &Iterate,
    active: &[bool],
    free: &FreeModes,
    limits: DenseLimits,
) -> Result<Option<ModelSet>, RunError> {
    let anchor = Anchor {
        boundary: b,
        iterate: it,
        active: Some(active),
        coarse: false,
    };
    run_model(ctx, hs, anchor, free, limits, &[])
}

/// A model run's outcome: the set of this rank's nodes (`None`: no prediction) and the record.
pub type ModelSet = (Option<Vec<bool>>, PredictorStep);

/// [`predict`] (`active` = None) or [`correct`]; `None` where the model is coarsened and the
/// anchor does not allow that. Collective.
fn run_model(
    ctx: &Ctx,
    hs: &HalfSpace,
    anchor: Anchor,
    free: &FreeModes,
    limits: DenseLimits,
    force: &[PairForce],
) -> Result<Option<ModelSet>, RunError> {
    let (b, active) = (anchor.boundary, anchor.active);
    let t = Instant::now();
    let mz = if free.floats() {
        free.dirichlet_free().ncols()
    } else {
        0
    };
    let (all, g_all) = gather_records(ctx, b, anchor.iterate, free, active);
    let n = all.len() / REC;
    // Under force control nothing penetrates before the approach is known: the model grows
    // from MIN_MODEL_NODES (by MODEL_MARGIN) while its contact zone reaches its border.
    // A floating body whose first solve was skipped (u⁰ = 0: nothing penetrates) likewise: the
    // free modes bring it into contact in the model.
    let grow = !force.is_empty()
        || (mz > 0 && Model::choose(&all, None, max_model_nodes(), None).pen == 0);
    let mut wanted = grow.then(|| MIN_MODEL_NODES.min(n));
    let head = head(force.len());
    // a prediction by a coarsened model: a second run with its groups at the predicted edge at
    // full resolution (`refine_at_edge`)
    let mut edge: Option<Vec<f64>> = None;
    let recs = Records {
        all: &all,
        g_all: &g_all,
    };
    let run = ModelRun {
        mz,
        limits,
        force,
        grow,
    };
    // a correction starts from the exact step's own update (3.23)
    let updated = active.map(|_| exact_update(&all, limits.c));
    let packed = loop {
        let mut model = Model::choose(&all, wanted, max_model_nodes(), edge.as_deref());
        let coarsened = model.m() < model.fine.len();
        if coarsened && !anchor.coarse {
            // the same on every rank: the records are
            let band = updated.as_deref().and_then(|u| model.edge_band(&all, u));
            let Some(band) = band else {
                return Ok(None);
            };
            model = band;
        }
        let from = updated.as_deref().or(edge.as_deref());
        let packed = solve_everywhere(ctx, hs, (&model, from), recs, free, &run);
        match wanted {
            Some(w) if packed[0] == 3.0 && w < n.min(MAX_REPRESENTED) => {
                wanted = Some((MODEL_MARGIN * w).min(n).min(MAX_REPRESENTED));
            }
            _ if coarsened
                && force.is_empty()
                && active.is_none()
                && edge.is_none()
                && packed[0] == 0.0 =>
            {
                edge = Some(packed[head..].to_vec());
            }
            _ => break packed,
        }
    };
    let (mine, rec) = model_outcome(hs, b, &packed, force.len(), t);
    log_model(ctx, hs, &rec, active.is_some());
    Ok(Some((mine, rec)))
}

/// One run of the model: every rank builds a share of C's columns, rank 0 solves it
/// ([`Model::solve`]; a panic there is caught as code 4, so that the broadcast still happens)
/// and broadcasts [code, model nodes, model steps, coarse levels, represented, δ change,
/// flags of all nodes]. Collective.
fn solve_everywhere(
    ctx: &Ctx,
    hs: &HalfSpace,
    (model, from): (&Model, Option<&[f64]>),
    recs: Records,
    free: &FreeModes,
    run: &ModelRun,
) -> Vec<f64> {
    // this rank's share is dropped once gathered; rank 0 runs on the gathered triangle itself
    let packed_c = ctx.gather_to_root(&hs.columns(
        &model.x,
        &model.w,
        column_share(model.m(), ctx.rank, ctx.size),
    ));
    let mut packed: Vec<f64> = ctx
        .on_root_wide(model.m() + run.mz, move || {
            super::dense::guarded("predictor-model", move || {
                model.solve(recs, (packed_c, from), free, run)
            })
            .unwrap_or_else(|_| {
                let mut failed = vec![0.0; head(run.force.len())];
                failed[0] = 4.0;
                failed
            })
        })
        .unwrap_or_default();
    ctx.broadcast_f64s(&mut packed);
    packed
}

/// A model run's broadcast result ([`solve_everywhere`]) as this rank's set (`None`: no
/// prediction) and the record (`t`: since the run began). Local.
fn model_outcome(
    hs: &HalfSpace,
    b: &ContactBoundary,
    packed: &[f64],
    force_pairs: usize,
    t: Instant,
) -> ModelSet {
    let head = head(force_pairs);
    let code = packed[0];
    let flags_all = &packed[head..];
    let predicted = code == 0.0 || code == 3.0;
    let mine = predicted.then(|| {
        let o = b.offset;
        flags_all[o..o + b.nodes.len()]
            .iter()
            .map(|&f| f != 0.0)
            .collect()
    });
    let rec = PredictorStep {
        outcome: match code as i32 {
            0 | 3 => "predicted".into(),
            1 => "no node penetrates after the first solve".into(),
            4 => "the model failed on rank 0 (no prediction)".into(),
            _ => "the model's dense iteration did not converge".into(),
        },
        model_nodes: packed[1] as usize,
        represented: packed[4] as usize,
        predicted_active: flags_all.iter().filter(|&&f| f != 0.0).count(),
        mirror_planes: hs.mirrors.len(),
        model_steps: packed[2] as usize,
        coarse_levels: packed[3] as usize,
        truncated: code == 3.0,
        approach_change: (predicted && force_pairs > 0).then(|| packed[5..head].to_vec()),
        seconds: t.elapsed().as_secs_f64(),
    };
    (mine, rec)
}

/// The model's progress line (`correcting`: a correction of an exact step's set update).
/// Rank 0.
fn log_model(ctx: &Ctx, hs: &HalfSpace, rec: &PredictorStep, correcting: bool) {
    say!(
        ctx,
        "predictor{}: half-space model (E* = {:.4e}, {} mirror plane(s)) on {} nodes{} for {} contact nodes: {}{} ({} active, {} steps, {} coarse levels, {:.3} s){}",
        if correcting {
            " (correcting the set update of the exact step)"
        } else {
            ""
        },
        hs.modulus,
        rec.mirror_planes,
        rec.model_nodes,
        // a correction never runs a coarsened model: fewer nodes are its edge band
        if correcting && rec.model_nodes < rec.represented {
            " (the exact update's edge band; the other nodes held)"
        } else {
            ""
        },
        rec.represented,
        rec.outcome,
        if rec.truncated {
            ", reaching the model's border"
        } else {
            ""
        },
        rec.predicted_active,
        rec.model_steps,
        rec.coarse_levels,
        rec.seconds,
        rec.approach_change.as_ref().map_or(String::new(), |d| {
            let d: Vec<String> = d.iter().map(|d| format!("{d:.6e}")).collect();
            let what = if d.len() > 1 {
                "the approaches change"
            } else {
                "the approach changes"
            };
            format!("; {what} by {}", d.join(", "))
        })
    );
}

/// A located contact zone ([`locate`]): this rank's clearances and the nodes the model puts in
/// contact; `None` where the model did not converge.
pub type Located = Option<(Vec<f64>, usize)>;

/// Where the contact zone of a body that its contact alone holds lies, before anything is
/// solved: the model's Algorithm 1 (d₀ = 0, the load's own deformation left out) on a coarse
/// subset of every contact node ([`LOCATE_MODEL_NODES`]) with the free modes' load `phi` (which
/// the contact normals must hold). The zone may lie far from the smallest gaps: a
/// tangential load that friction holds rolls a disk on its plane until the pressure's centre
/// balances the load's moment. Returns the clearance g + G α of this rank's contact nodes
/// after the model's rigid motion α, and the number of contact nodes the model puts in
/// contact (those of its active nodes); `None` where the model does not converge. Collective.
pub fn locate(
    ctx: &Ctx,
    hs: &HalfSpace,
    b: &ContactBoundary,
    free: &FreeModes,
    phi: &[f64],
    limits: DenseLimits,
) -> Result<Option<(Vec<f64>, usize)>, RunError> {
    let t = Instant::now();
    let mz = free.dirichlet_free().ncols();
    let it = Iterate::new(b.nodes.len(), 0, false);
    let (all, g_all) = gather_records(ctx, b, &it, free, None);
    let n = all.len() / REC;
    let mut tried = Vec::new();
    let mut packed: Vec<f64> = Vec::new();
    for cap in LOCATE_MODEL_NODES {
        let model = Model::choose(&all, Some(n), cap, None);
        if tried.last() == Some(&model.m()) {
            break; // the same model again
        }
        tried.push(model.m());
        let share = hs.columns(
            &model.x,
            &model.w,
            column_share(model.m(), ctx.rank, ctx.size),
        );
        let packed_c = ctx.gather_to_root(&share);
        // rank 0: [α (m_z), nodes in contact] or nothing (no convergence, or a panic caught)
        packed = ctx
            .on_root_wide(model.m(), || {
                super::dense::guarded("locate-model", || {
                    let recs = Records {
                        all: &all,
                        g_all: &g_all,
                    };
                    model.locate(recs, &packed_c, free, phi, limits)
                })
                .unwrap_or_default()
            })
            .unwrap_or_default();
        ctx.broadcast_f64s(&mut packed);
        if packed.len() > mz {
            break;
        }
    }
    let on = if packed.len() > mz { packed[mz] } else { 0.0 };
    let sizes: Vec<String> = tried.iter().map(|m| m.to_string()).collect();
    say!(
        ctx,
        "newton: condensed: the contact zone located by the half-space model on {} of {n} \
         contact nodes: {} ({:.3} s)",
        sizes.join(", then "),
        if packed.len() > mz {
            format!("{} nodes in contact", on as usize)
        } else {
            "no convergence (the zone by the gaps)".to_string()
        },
        t.elapsed().as_secs_f64()
    );
    if packed.len() <= mz {
        return Ok(None);
    }
    let clearance = b
        .nodes
        .iter()
        .map(|k| {
            let g = free.normal_parts(k, &k.frame.n);
            k.gap + (0..mz).map(|c| g[c] * packed[c]).sum::<f64>()
        })
        .collect();
    Ok(Some((clearance, packed[mz] as usize)))
}

/// Values before the flags in the model's broadcast: five, then the approaches' changes (one
/// per force-controlled pair, at least one value).
fn head(force_pairs: usize) -> usize {
    5 + force_pairs.max(1)
}

/// Every contact node of every rank (rank order, = the boundary's global numbering): x, n,
/// gap, lumped weight, the first solve's u_n, pair, λ_n and tag ([`REC`] values), and beside
/// them the free modes' normal parts (m_z per node). Rank order depends on the partition:
/// decisions order by the tag. Collective.
fn gather_records(
    ctx: &Ctx,
    b: &ContactBoundary,
    it: &Iterate,
    free: &FreeModes,
    active: Option<&[bool]>,
) -> (Vec<f64>, Vec<f64>) {
    let mut mine = Vec::with_capacity(b.nodes.len() * REC);
    let mut parts = Vec::new();
    for (i, (k, r)) in b.nodes.iter().zip(&it.nodes).enumerate() {
        mine.extend_from_slice(&k.x);
        mine.extend_from_slice(&k.frame.n);
        mine.extend_from_slice(&[k.gap, k.weight, r.u_n]);
        parts.extend(free.normal_parts(k, &k.frame.n));
        mine.push(k.pair as f64);
        let on = active.is_some_and(|a| a[i]);
        mine.push(if on { r.lambda_n } else { 0.0 });
        mine.push(k.tag as f64);
    }
    (
        ctx.all_gather_varcount(&mine),
        ctx.all_gather_varcount(&parts),
    )
}

/// The set (3.23) of the exact step a correction is anchored at, on every contact node of
/// the records (1 in contact): the set its model iteration starts from, whose first dense step
/// reproduces the exact step's update. Local.
fn exact_update(all: &[f64], c: f64) -> Vec<f64> {
    all.chunks_exact(REC)
        .map(|r| f64::from(u8::from(normal_active(r[8], r[LAMBDA], r[6], c))))
        .collect()
}
