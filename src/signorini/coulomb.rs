//! Coulomb friction's strategy (docs/friction.md): the generalised Newton's start (the
//! frictionless solution on the contact unknowns, the condensed passes, a load step on the
//! previous step's factorisation; [`schur::coulomb`] runs the
//! dense steps) and the fixed point on Tresca thresholds, each ending on the plain path where
//! the contact unknowns do not settle it.

use super::active_set::Law;
use super::boundary::{self, ContactBoundary, NodeResult};
use super::certificate;
use super::force;
use super::kept::KeptFactor;
use super::plain_path::{self, ContactProblem, NewtonResult, NewtonSettings, StepInfo, WarmStart};
use super::rigid::{self, FreeModes};
use super::schur::candidates::Sticking;
use super::schur::frictionless::{solve_keeping, Condensing};
use super::schur::{self, CoulombCondensedSummary};
use super::session::Session;
use super::step_system::ReducedSystem;
use crate::case::{self, CoulombAlgorithm, Reuse, SolverSection};
use crate::error::RunError;
use crate::par::Ctx;
use crate::say;
use crate::tuning::{
    FIRST_STICK_FACTORISATIONS, MAX_STICK_FACTORISATIONS, WARM_STICK_FACTORISATIONS,
};

/// How a Coulomb solve ends.
pub enum Outcome {
    /// Solved on the contact unknowns and checked on every contact node (taken as it is), with
    /// the condensed path's record.
    Checked(NewtonResult, Option<schur::CondensedSummary>),
    /// An iteration on the plain path, whose convergence the caller judges: the result, the
    /// fixed point's outer steps (`None` for the generalised Newton) and the condensed path's
    /// record.
    Iterated(NewtonResult, Option<usize>, Option<schur::CondensedSummary>),
}

/// How the case solves Coulomb friction: the algorithm and the solver section it runs under
/// (the linear solver's reuse and path).
#[derive(Clone, Copy)]
pub struct CoulombMethod<'a> {
    pub algorithm: CoulombAlgorithm,
    pub section: &'a SolverSection,
}

/// The settings of a condensed Coulomb start ([`coulomb_start`]): Coulomb's own and those of
/// its frictionless estimate (the frictionless law, no half-space model, the pins carrying
/// the load friction alone holds).
#[derive(Clone, Copy)]
struct StartSettings<'a> {
    coulomb: &'a NewtonSettings<'a>,
    frictionless: &'a NewtonSettings<'a>,
    /// Every node with a Tresca threshold a candidate (else those beyond the candidates carry
    /// their friction as a load: [`tresca_fits`]).
    thresholds: bool,
}

/// Coulomb friction by `method.algorithm` on the reduced system: the generalised Newton (under
/// newton.init = "auto" from [`coulomb_start`]) or the [`fixed_point`] on Tresca thresholds.
/// Collective.
pub fn solve(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &mut ReducedSystem,
    ns: &NewtonSettings,
    method: CoulombMethod,
    session: &mut Session,
    warm: Option<&WarmStart>,
) -> Result<Outcome, RunError> {
    let (algorithm, solver_section) = (method.algorithm, method.section);
    let coulomb_newton = algorithm == CoulombAlgorithm::Newton;
    if coulomb_newton && solver_section.reuse == Reuse::Always && reduced.factorises()? {
        say!(
            ctx,
            "newton: solver.reuse = \"always\" with Coulomb: its rows change the matrix \
             in every step, so every Newton step of the plain path factorises (solver.path \
             = \"schur\": Coulomb on the contact unknowns after one factorisation)"
        );
    }
    let (start, condensed_summary) = if coulomb_newton && ns.section.init == case::NewtonInit::Auto
    {
        coulomb_start(ctx, problem, reduced, ns, solver_section, session, warm)?
    } else {
        (Begin::Touching, None)
    };
    if let Begin::Solved(nr) = start {
        return Ok(Outcome::Checked(nr, condensed_summary));
    }
    plain_path::enable_reuse(ctx, ns, solver_section, reduced, true)?;
    if algorithm == CoulombAlgorithm::FixedPoint {
        let (nr, outer) = fixed_point(ctx, problem, reduced, ns, warm)?;
        return Ok(Outcome::Iterated(nr, Some(outer), condensed_summary));
    }
    let nr = match start {
        Begin::Start(first, u) => {
            let w = WarmStart {
                nodes: &first.nodes,
                u_local: &u,
                floors_from: warm,
            };
            // under force control from the start's approaches
            let force = force::starting_at(ns.force, &first.approach);
            let ns = NewtonSettings {
                force: &force,
                ..*ns
            };
            let mut nr = plain_path::semismooth_newton(ctx, problem, reduced, &ns, Some(&w))?;
            // the start's steps first in the record (and their factorisations)
            after(first.history, &mut nr);
            nr
        }
        _ => plain_path::semismooth_newton(ctx, problem, reduced, ns, warm)?,
    };
    Ok(Outcome::Iterated(nr, None, condensed_summary))
}

/// Coulomb by the fixed point on Tresca thresholds (docs/friction.md (a)):
/// b^{m+1}_k = μ max(0, −λ_n^{k,m}), every outer step a Tresca solve (Algorithm 2) warm-started
/// from the previous one (b^0 from the warm start's λ_n, else ‖f‖₁: all stick); stop when
/// max_k |b^{m+1} − b^m| ≤ [`FIXED_POINT_TOL`] · max_k b^{m+1}, or · max_k b^0 of a warm
/// start where the thresholds vanish (a load step that releases the contact: each Tresca solve then leaves a
/// friction force proportional to its thresholds, b^m decays geometrically, to 1e-323 in 100
/// outer steps without ever meeting the relative test — a failed step, cut back on some rank
/// counts and not on others). Under force control every
/// Tresca solve is force-controlled (force.rs), from the previous one's approaches. Returns
/// the last Tresca result with the history and step count of all outer steps, and the number
/// of outer steps. Collective.
fn fixed_point(
    ctx: &Ctx,
    p: &ContactProblem,
    reduced: &mut ReducedSystem,
    ns: &NewtonSettings,
    warm: Option<&WarmStart>,
) -> Result<(NewtonResult, usize), RunError> {
    // under force control each Tresca solve starts from the approaches of the previous one
    let mut force = ns.force.to_vec();
    let mut b = p.boundary.clone();
    let mut state: Option<(Vec<NodeResult>, Vec<f64>)> =
        warm.map(|w| (w.nodes.to_vec(), w.u_local.to_vec()));
    // each node's μ: its pair's
    let threshold = |k: &boundary::ContactNode, r: &NodeResult| k.mu * (-r.lambda_n).max(0.0);
    // b^0 without a warm start: ‖f‖₁, beyond any nodal friction force, so the first solve
    // sticks (b^0 = 0 would leave a free body with a tangential load without support).
    let stick_all = ctx.sum_f64(reduced.f_local.iter().map(|x| x.abs()).sum());
    for (i, k) in b.nodes.iter_mut().enumerate() {
        k.bound = state
            .as_ref()
            .map_or(stick_all, |(n, _)| threshold(&*k, &n[i]));
    }
    // the previous load step's thresholds (none without a warm start: ‖f‖₁ is no threshold)
    let start_scale = match warm {
        Some(_) => ctx.max_f64(b.nodes.iter().fold(0.0_f64, |m, k| m.max(k.bound))),
        None => 0.0,
    };
    let mut history: Vec<StepInfo> = Vec::new();
    let mut stop = certificate::StopRule::ActiveSet;
    for outer in 1..=ns.section.max_steps {
        let pm = ContactProblem { boundary: &b, ..*p };
        let start = state.as_ref().map(|(nodes, u)| WarmStart {
            nodes,
            u_local: u,
            floors_from: None,
        });
        let tresca = NewtonSettings {
            law: Law::Tresca,
            force: &force,
            ..*ns
        };
        let mut nr = plain_path::semismooth_newton(ctx, &pm, reduced, &tresca, start.as_ref())?;
        stop = stop.worse(nr.stop);
        nr.stop = stop;
        for (fc, &delta) in force.iter_mut().zip(&nr.approach) {
            fc.start = delta;
        }
        for h in &nr.history {
            let mut h = h.clone();
            h.step = history.len() + 1;
            history.push(h);
        }
        let (mut change, mut scale) = (0.0f64, 0.0f64);
        for (k, r) in b.nodes.iter_mut().zip(&nr.nodes) {
            let next = threshold(&*k, r);
            change = change.max((next - k.bound).abs());
            scale = scale.max(next);
            k.bound = next;
        }
        let (change, scale) = (ctx.max_f64(change), ctx.max_f64(scale));
        say!(
            ctx,
            "fixed point {outer:3}: {} Newton steps, max |b^(m+1) - b^m| = {change:.3e} \
             (max b = {scale:.3e})",
            nr.steps
        );
        let done = change <= FIXED_POINT_TOL * scale.max(start_scale);
        if !nr.converged || done {
            nr.converged &= done;
            nr.steps = history.len();
            nr.history = history;
            return Ok((nr, outer));
        }
        let u = nr.u.to_local_vec()?;
        state = Some((nr.nodes, u));
    }
    Err(RunError::NoConvergence(format!(
        "the fixed point on Tresca thresholds did not converge in newton.max_steps = {} outer \
         steps",
        ns.section.max_steps
    )))
}

/// `r`'s steps after `first` in its record (numbered on). Local.
fn after(first: Vec<StepInfo>, r: &mut NewtonResult) {
    let mut history = first;
    for mut h in std::mem::take(&mut r.history) {
        h.step += history.len();
        history.push(h);
    }
    r.steps = history.len();
    r.history = history;
}

/// How Coulomb's generalised Newton begins (`coulomb_start`).
enum Begin {
    /// Solved on the contact unknowns and checked on every contact node (schur::coulomb).
    Solved(NewtonResult),
    /// A start for the plain path: the records of every contact node, this rank's rows of u.
    Start(NewtonResult, Vec<f64>),
    /// The touching nodes (`ActiveSet::initial`), or the warm start of a load step.
    Touching,
}

/// The start of Coulomb's generalised Newton under newton.init = "auto" (no warm start) where
/// the condensed path applies (direct preset): the frictionless solution of the same case by
/// the condensed path (about one factorisation; the pins carry a load in the modes only
/// friction can hold, e.g. a tangential load on a floating body). For a body that Dirichlet
/// data hold, the Schur complement takes every dof of the candidates and Coulomb's iteration
/// runs on them (schur::coulomb): its checked result, or its expanded iterate as the plain
/// path's start. Else (or if that gives up) the frictionless active set and λ_n give the
/// thresholds b = μ(−λ_n) of (F1), every active node sticking — instead of a start from the
/// touching nodes, where the whole load first hangs on them and the set needs many steps to
/// shrink. Where friction alone holds a part of the load (the body rolls), the frictionless
/// estimate carries that part by a tangential force at the contact and the half-space model
/// locates the zone the candidates are taken from (`Unheld`, docs/friction.md). `Touching`
/// (said in the log) where the condensed path does not find a frictionless set; where it does
/// not apply (the iterative preset), [`iterative_start`]. A load step (`warm`) tries the
/// condensed iteration alone (the frictionless set from the warm one; references u_τ^ref of
/// the previous step) and otherwise keeps its warm start.
/// Under force control the dense Coulomb iteration takes the approaches as unknowns (a held
/// body); on a body that only its pairs hold the start is the frictionless force-controlled
/// solution, every active node sticking, at its approaches (the `approach` of the returned
/// start), and a load step keeps its warm start.
/// Returns the beginning and the condensed path's record. Collective.
fn coulomb_start(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &mut ReducedSystem,
    ns: &NewtonSettings,
    solver_section: &SolverSection,
    session: &mut Session,
    warm: Option<&WarmStart>,
) -> Result<(Begin, Option<schur::CondensedSummary>), RunError> {
    let fl = NewtonSettings {
        law: Law::Frictionless,
        halfspace: None,
        estimate: true,
        ..*ns
    };
    let b = problem.boundary;
    let condense = solver_section.path.allows_schur()
        && b.n_global > 0
        && b.n_global <= crate::tuning::MAX_CONTACT_NODES
        && reduced.factorises()?;
    if !condense {
        return iterative_start(ctx, problem, reduced, ns, warm);
    }
    let thresholds = ns.law != Law::Tresca || tresca_fits(ctx, b, problem.mesh.dim);
    let from = if warm.is_some() {
        "the previous load step"
    } else {
        "the touching nodes"
    };
    // the body's free modes (one construction: the tests below read them)
    let free = free_modes(ctx, problem, reduced, ns);
    if !thresholds && !far_nodes_apply(ctx, problem, ns, &free) {
        return Ok((Begin::Touching, None));
    }
    // a load that friction alone holds: the frictionless estimate carries it at the contact
    let carried = Unheld::of(ctx, b, &free).map(|un| {
        say!(
            ctx,
            "{}: {}; the frictionless estimate carries it by a tangential force at the \
             contact",
            ns.law.name(),
            un.why()
        );
        un.carried_at_contact(ctx, b, &free)
    });
    let fl = NewtonSettings {
        carried: carried.as_deref(),
        ..fl
    };
    // force control on a body that only its pairs hold: the plain path (the dense Coulomb
    // iteration takes the approaches as unknowns next to a held body's contact unknowns)
    let forced = !ns.force.is_empty() && free.floats();
    if forced {
        say!(
            ctx,
            "{}: force control on a body that only its pairs hold: the plain path",
            ns.law.name()
        );
    }
    let settings = StartSettings {
        coulomb: ns,
        frictionless: &fl,
        thresholds,
    };
    if let Some(w) = warm {
        if forced {
            drop(session.kept.take()); // no Coulomb step uses a kept factorisation here
            return Ok((Begin::Touching, None));
        }
        return coulomb_load_step(ctx, problem, reduced, session, settings, w);
    }
    let passes = coulomb_passes(ctx, problem, reduced, session, settings, forced, from)?;
    begin_after_passes(ctx, ns, b, passes)
}

/// Tresca with more nodes than its condensed path takes ([`tresca_fits`]): on a 3D body that
/// Dirichlet data hold (`free` leaves no mode free, no force control) the nodes beyond the
/// candidates carry their friction as a load (schur::coulomb); else (false) the plain path at
/// once (docs/friction.md, "Tresca's far nodes"), said in the log. Collective (log).
fn far_nodes_apply(
    ctx: &Ctx,
    problem: &ContactProblem,
    ns: &NewtonSettings,
    free: &FreeModes,
) -> bool {
    let plain = match (problem.mesh.dim, free.floats() || !ns.force.is_empty()) {
        (3, false) => None,
        (3, true) => Some("a body that its contacts hold, or force control"),
        _ => Some("in 2D"),
    };
    match plain {
        Some(why) => say!(ctx, "tresca: {why}: the plain path"),
        None => say!(
            ctx,
            "tresca: the nodes beyond the candidates carry their friction as a load"
        ),
    }
    plain.is_none()
}

/// The beginning [`coulomb_start`] takes from its condensed passes: their outcome, or from the
/// frictionless solution every active node sticking (Tresca: its own start, not the
/// frictionless solution: no fewer steps, docs/friction.md). Collective (log).
fn begin_after_passes(
    ctx: &Ctx,
    ns: &NewtonSettings,
    b: &ContactBoundary,
    passes: Passes,
) -> Result<(Begin, Option<schur::CondensedSummary>), RunError> {
    let (mut nr, summary) = match passes {
        Passes::Done(begin, summary) => return Ok((begin, summary)),
        Passes::Frictionless(_, summary) if ns.law == Law::Tresca => {
            return Ok((Begin::Touching, Some(summary)))
        }
        Passes::Frictionless(nr, summary) => (nr, summary),
    };
    say!(
        ctx,
        "{}: start from the frictionless solution, every active node sticking",
        ns.law.name()
    );
    let u = nr.u.to_local_vec()?;
    // under force control the references where the frictionless approaches put the obstacles
    let placed = force::placed(b, &force::starting_at(ns.force, &nr.approach));
    sticking(&mut nr.nodes, &placed);
    Ok((Begin::Start(nr, u), Some(summary)))
}

/// What the condensed passes of a Coulomb start end in.
enum Passes {
    /// The start's outcome: solved, a start for the plain path, or none (the touching nodes).
    Done(Begin, Option<schur::CondensedSummary>),
    /// The frictionless solution (the condensed Coulomb iteration does not apply or gave up).
    Frictionless(NewtonResult, schur::CondensedSummary),
}

/// [`coulomb_start`] on the condensed path: the frictionless solution by the condensed path
/// (`fl`; every dof of the candidates in the Schur complement, or, where the zone is too wide
/// for that, its interior held sticking in K_p), then Coulomb's iteration on its candidates
/// (schur::coulomb). Where a held zone's check finds nodes beyond the candidates changing
/// state, a new pass takes them as candidates (at most [`MAX_STICK_FACTORISATIONS`]
/// factorisations in all, while fewer change each pass), its dense iteration started from the
/// states of the pass before's expanded iterate. `forced`: force control on a body
/// that only its pairs hold (the frictionless solution alone); `from`: the start said where
/// there is none. Collective.
fn coulomb_passes(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &mut ReducedSystem,
    session: &mut Session,
    settings: StartSettings,
    forced: bool,
    from: &str,
) -> Result<Passes, RunError> {
    let (ns, fl) = (settings.coulomb, settings.frictionless);
    let dim = problem.mesh.dim;
    // errors are agreed: every rank takes the same branch
    // the Coulomb iteration on the candidates needs every dof of them, the plain path none
    let per = if forced { 1 } else { dim };
    // where the zone is too wide for every dof of its nodes: the nodes a held zone releases
    let mut passes = PassLoop::new(ns.law, Vec::new(), Vec::new());
    // the expanded iterate of the last pass: the plain path's start where the next one fails
    let mut last: Option<(NewtonResult, Vec<f64>, CoulombCondensedSummary)> = None;
    loop {
        // too many candidates' dofs for the dense tangential compliance: the predicted zone's
        // interior held sticking, the dense steps on its edge and beyond (schur/frictionless.rs)
        let held = (per > 1).then(|| passes.start_sticking());
        // a later pass factorises K_p alone, its dense iteration from the states of `last` (no
        // frictionless steps or nested start); not under force control (approaches found anew)
        let warm = ns.force.is_empty() && last.is_some();
        let how = Condensing {
            per,
            steps: !warm,
            stick: held,
            thresholds: settings.thresholds,
        };
        let mut tried = solve_keeping(ctx, problem, reduced, fl, session, None, how);
        if let Some((r, u, cs)) = last.take() {
            if warm && factorised(&tried) {
                // Coulomb from the last pass' states, where it gives up the plain path from it
                let run = warm_run(tried, passes.earlier, (&r.nodes, &u));
                match coulomb_pass(ctx, problem, reduced, session, ns, &mut passes, run)? {
                    PassStep::Done(done) => return Ok(done),
                    PassStep::Next(next) => last = Some(next),
                    PassStep::GaveUp(s) => return Ok(Passes::Done(Begin::Start(r, u), Some(s))),
                }
                continue;
            }
            let store = &mut session.kept;
            if let Some(done) = from_last_pass(ctx, store, &tried, r, u, cs, passes.earlier) {
                return Ok(done);
            }
        }
        if per > 1 && too_wide(&tried) {
            tried = match narrower(ctx, problem, reduced, session, settings, tried) {
                Ok(narrower) => narrower,
                Err(done) => return Ok(*done),
            };
        }
        // a frictionless solve on the normal dofs alone keeps its factorisation for a next
        // load step, which no Coulomb step can use
        drop(session.kept.take());
        let (mut nr, mut summary, kept) = match frictionless_start(ctx, ns.law, tried, from)? {
            Ok(start) => start,
            Err(done) => return Ok(done),
        };
        summary.factorisations += passes.earlier;
        let active = ctx.sum_usize(nr.nodes.iter().filter(|r| r.active).count());
        say!(
            ctx,
            "{}: the frictionless solution: {} steps, {active} active nodes",
            ns.law.name(),
            nr.steps
        );
        let Some(kept) = kept.filter(|_| !forced) else {
            return Ok(Passes::Frictionless(nr, summary));
        };
        let first = std::mem::take(&mut nr.history);
        let run = PassRun {
            kept,
            summary,
            warm: None,
            first: first.clone(),
        };
        match coulomb_pass(ctx, problem, reduced, session, ns, &mut passes, run)? {
            PassStep::Done(done) => return Ok(done),
            PassStep::Next(next) => last = Some(next),
            PassStep::GaveUp(summary) => {
                // the plain path from the frictionless solution
                nr.history = first;
                return Ok(Passes::Frictionless(nr, summary));
            }
        }
    }
}

/// A condensed solve's outcome with what it kept ([`solve_keeping`]).
type Tried = Result<(schur::Condensed, Option<schur::Kept>), RunError>;

/// A condensed attempt that factorised nothing: its candidates' dofs too many for the dense
/// limits (the same on every rank: errors are agreed).
fn too_wide(tried: &Tried) -> bool {
    let fell = |s: &schur::CondensedSummary| s.factorisations == 0;
    matches!(tried, Ok((schur::Condensed::Fallback(s), _)) if fell(s))
}

/// After an attempt too wide for every dof of its candidates with no zone to hold
/// ([`too_wide`]): Tresca's plain path ([`tresca_too_wide`], `Err`), else the frictionless
/// solve with the candidates' normal dofs alone in the Schur complement. Collective.
fn narrower(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &mut ReducedSystem,
    session: &mut Session,
    settings: StartSettings,
    tried: Tried,
) -> Result<Tried, Box<Passes>> {
    let ns = settings.coulomb;
    if ns.law == Law::Tresca {
        return Err(Box::new(tresca_too_wide(ctx, &mut session.kept, tried)));
    }
    say!(
        ctx,
        "{}: the candidates' normal dofs alone in the Schur complement",
        ns.law.name()
    );
    let how = Condensing::FRICTIONLESS;
    let fl = settings.frictionless;
    Ok(solve_keeping(ctx, problem, reduced, fl, session, None, how))
}

/// Whether Tresca's condensed attempt is made: every node with a threshold b_k > 0 is a
/// candidate with its d dofs, and their dense compliance, n³ flops for n dofs, must stay within
/// the dense work the condensed path allows whatever K_p's factorisation costs: the dense floor,
/// in 2D times the factor by which the dense work may exceed that factorisation
/// ([`DENSE_FLOOR_FLOPS`](crate::tuning::DENSE_FLOOR_FLOPS),
/// [`DENSE_SPEEDUP_2D`](crate::tuning::DENSE_SPEEDUP_2D)). Beyond it the attempt's ordering and
/// analysis (for the factorisation's flops, against which the dense limits are checked) were
/// measured at 12 % of the plain path's whole solve, and on every mesh measured the check then
/// failed (docs/numbers.md, "Tresca on the contact unknowns"): the plain path at once, said in
/// the log. Collective (one reduction).
fn tresca_fits(ctx: &Ctx, b: &ContactBoundary, dim: usize) -> bool {
    let nodes = ctx.sum_usize(b.nodes.iter().filter(|k| k.bound > 0.0).count());
    let fits = tresca_condensed_fits(nodes, dim);
    if !fits {
        let dofs = (nodes * dim) as f64;
        say!(
            ctx,
            "tresca: {nodes} nodes with a threshold, {dofs} dofs in the Schur complement: their \
             dense compliance ({:.1e} flops) exceeds the {:.1e} flops a condensed attempt with \
             all of them is made for",
            dofs.powi(3),
            tresca_dense_flops(dim)
        );
    }
    fits
}

/// Whether Tresca's condensed attempt with every node that has a threshold is made for `nodes`
/// such nodes in a mesh of dimension `dim` (their d dofs each in the Schur complement;
/// [`tresca_fits`]). Pure.
fn tresca_condensed_fits(nodes: usize, dim: usize) -> bool {
    ((nodes * dim) as f64).powi(3) <= tresca_dense_flops(dim)
}

/// The dense work (flops) Tresca's condensed attempt is made for ([`tresca_fits`]).
fn tresca_dense_flops(dim: usize) -> f64 {
    // (the test-only limit DENSE_SPEEDUP_2D replaces the 2D factor, as in the check itself)
    let speedup = match dim {
        2 => {
            crate::fault::limit("DENSE_SPEEDUP_2D", crate::tuning::DENSE_SPEEDUP_2D as usize) as f64
        }
        _ => 1.0,
    };
    speedup * crate::tuning::DENSE_FLOOR_FLOPS
}

/// Tresca, whose every node with a threshold must be condensed, where those nodes' dofs
/// exceed the dense limits (`tried`: the attempt that said so): the plain path from its own
/// start, not from a frictionless solution (no fewer steps for Tresca, docs/friction.md).
/// Collective (log).
fn tresca_too_wide(ctx: &Ctx, store: &mut KeptFactor, tried: Tried) -> Passes {
    drop(store.take());
    let summary = match tried {
        Ok((schur::Condensed::Fallback(s), _)) => Some(s),
        _ => None,
    };
    say!(
        ctx,
        "tresca: the nodes with a threshold exceed the dense limits: the plain path"
    );
    Passes::Done(Begin::Touching, summary)
}

/// The run of a warm pass' Coulomb iteration: its factorisation (`tried`, [`factorised`]),
/// counted after the `earlier` passes', from the pass before's states (its contact records
/// and this rank's rows of u). Local.
fn warm_run<'w>(
    tried: Tried,
    earlier: usize,
    (nodes, u_local): (&'w [NodeResult], &'w [f64]),
) -> PassRun<'w> {
    let Ok((schur::Condensed::Factorised(mut summary), Some(kept))) = tried else {
        unreachable!("a factorised pass keeps its factorisation")
    };
    summary.factorisations += earlier;
    PassRun {
        kept,
        summary,
        warm: Some(WarmStart {
            nodes,
            u_local,
            floors_from: None,
        }),
        first: Vec::new(),
    }
}

/// A pass of [`coulomb_passes`] that factorised K_p alone (its frictionless steps not run: a
/// warm pass). Pure.
fn factorised(tried: &Tried) -> bool {
    matches!(tried, Ok((schur::Condensed::Factorised(_), Some(_))))
}

/// One pass' Coulomb iteration as [`coulomb_pass`] runs it: the pass' factorisation and
/// summary, its warm start (the pass before's states; `None`: from the frictionless solution)
/// and the frictionless steps that came before it (the history's first steps).
struct PassRun<'w> {
    kept: schur::Kept,
    summary: schur::CondensedSummary,
    warm: Option<WarmStart<'w>>,
    first: Vec<StepInfo>,
}

/// How a pass' Coulomb iteration ends: the passes' outcome, a next pass from its expanded
/// iterate, or given up (the caller's start for the plain path, with the summary).
enum PassStep {
    Done(Passes),
    Next((NewtonResult, Vec<f64>, CoulombCondensedSummary)),
    GaveUp(schur::CondensedSummary),
}

/// The Coulomb iteration of one pass of [`coulomb_passes`] on its factorisation: solved (the
/// factorisation kept for the next load step), a next pass where nodes beyond the candidates
/// change state ([`PassLoop::goes_on`]), else the plain path from the expanded iterate; given
/// up where the iteration gives up. Collective.
fn coulomb_pass(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &mut ReducedSystem,
    session: &mut Session,
    ns: &NewtonSettings,
    passes: &mut PassLoop,
    run: PassRun,
) -> Result<PassStep, RunError> {
    let PassRun {
        mut kept,
        mut summary,
        warm,
        first,
    } = run;
    let joined = |mut r: NewtonResult| {
        after(first.clone(), &mut r);
        r
    };
    match schur::coulomb::solve(ctx, problem, reduced, ns, &mut kept, warm.as_ref())? {
        schur::CoulombCondensed::Solved(r, cs) => {
            summary.coulomb = Some(cs);
            // for the next load step (a held zone's too: its rows' values are in f)
            session.kept.put(kept);
            Ok(PassStep::Done(Passes::Done(
                Begin::Solved(joined(*r)),
                Some(summary),
            )))
        }
        schur::CoulombCondensed::Start(r, u, cs, beyond) => {
            if passes.goes_on(&beyond, summary.factorisations) {
                let store = &mut session.kept;
                passes.next(ctx, store, &mut kept, &beyond, summary.factorisations);
                return Ok(PassStep::Next((joined(*r), u, cs)));
            }
            say!(
                ctx,
                "{}: the plain path from the expanded iterate",
                ns.law.name()
            );
            summary.coulomb = Some(cs);
            Ok(PassStep::Done(Passes::Done(
                Begin::Start(joined(*r), u),
                Some(summary),
            )))
        }
        schur::CoulombCondensed::Fallback(cs) => {
            summary.coulomb = Some(cs);
            Ok(PassStep::GaveUp(summary))
        }
    }
}

/// A frictionless attempt's solution, its summary and kept factorisation (`Ok(Ok(..))`); or,
/// where it found none, the start from the touching nodes (`Ok(Err(..))`). Collective (log).
#[allow(clippy::type_complexity)]
fn frictionless_start(
    ctx: &Ctx,
    law: Law,
    tried: Tried,
    from: &str,
) -> Result<Result<(NewtonResult, schur::CondensedSummary, Option<schur::Kept>), Passes>, RunError>
{
    match tried {
        Ok((schur::Condensed::Solved(nr, s), kept)) => Ok(Ok((*nr, s, kept))),
        Ok((schur::Condensed::Fallback(s), _)) | Ok((schur::Condensed::Factorised(s), _)) => {
            say!(
                ctx,
                "{}: no frictionless start; starting from {from}",
                law.name()
            );
            Ok(Err(Passes::Done(Begin::Touching, Some(s))))
        }
        Err(RunError::Failed(why)) => {
            say!(
                ctx,
                "{}: no frictionless start ({why}); starting from {from}",
                law.name()
            );
            Ok(Err(Passes::Done(Begin::Touching, None)))
        }
        Err(e) => Err(e),
    }
}

/// A later pass of [`coulomb_passes`] (`tried`: its frictionless attempt) that found no
/// frictionless solution of its own: the plain path from the pass before's expanded iterate
/// (`last`; `earlier`: the factorisations of the passes before). `None`: the pass solved, or
/// failed with an error every rank returns. Collective (log).
fn from_last_pass(
    ctx: &Ctx,
    store: &mut KeptFactor,
    tried: &Tried,
    r: NewtonResult,
    u: Vec<f64>,
    cs: CoulombCondensedSummary,
    earlier: usize,
) -> Option<Passes> {
    let law = cs.law;
    let mut summary = match tried {
        Ok((schur::Condensed::Fallback(s), _)) | Ok((schur::Condensed::Factorised(s), _)) => {
            s.clone()
        }
        Err(RunError::Failed(_)) => schur::CondensedSummary::new(0),
        _ => return None, // solved, or an error every rank returns (the caller's)
    };
    drop(store.take());
    summary.factorisations += earlier;
    summary.coulomb = Some(cs);
    say!(
        ctx,
        "{}: the plain path from the last pass' expanded iterate",
        law
    );
    Some(Passes::Done(Begin::Start(r, u), Some(summary)))
}

/// Every node of a frictionless solution starts sticking (Δu_τ = 0, λ_τ = 0 against the
/// references of `b`): the first Coulomb step gives the all-stick λ_τ, and (3.33) lets slip
/// where |λ_τ| exceeds μ(−λ_n). Local.
fn sticking(nodes: &mut [NodeResult], b: &ContactBoundary) {
    for (k, r) in b.nodes.iter().zip(nodes.iter_mut()) {
        r.u_t = k.u_t_ref;
        r.lambda_t = [0.0; 2];
        r.slip = false;
    }
}

/// The start of Coulomb's generalised Newton where no factorisation is there to condense on
/// (the iterative preset): Algorithm 1's frictionless solution on the same Krylov solver,
/// every active node sticking — for a body that Dirichlet data hold, without force control or
/// a warm start; else the touching nodes. Measured on the 3D block held and pushed into a
/// sphere (μ = 0.3, 2 ranks; Newton steps with the frictionless ones, GMRES iterations in all)
/// at 7 071 / 44 529 / 112 890 unknowns: 11 / 12 / 14 steps, 146 / 223 / 461 iterations,
/// against 12 / 13 / 16 steps, 173 / 312 / 513 iterations from the touching nodes (the solve
/// times within 5 %; docs/numbers.md, "Coulomb on the iterative preset"). Collective.
fn iterative_start(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &mut ReducedSystem,
    ns: &NewtonSettings,
    warm: Option<&WarmStart>,
) -> Result<(Begin, Option<schur::CondensedSummary>), RunError> {
    let plain = warm.is_some()
        || !ns.force.is_empty()
        || problem.boundary.n_global == 0
        || reduced.factorises()?
        || free_modes(ctx, problem, reduced, ns).floats();
    if plain {
        return Ok((Begin::Touching, None));
    }
    let fl = NewtonSettings {
        law: Law::Frictionless,
        halfspace: None,
        ..*ns
    };
    let mut nr = match plain_path::semismooth_newton(ctx, problem, reduced, &fl, None) {
        Ok(nr) => nr,
        Err(RunError::Failed(why)) => {
            say!(
                ctx,
                "{}: no frictionless start ({why}); starting from the touching nodes",
                ns.law.name()
            );
            return Ok((Begin::Touching, None));
        }
        Err(e) => return Err(e),
    };
    let active = ctx.sum_usize(nr.nodes.iter().filter(|r| r.active).count());
    say!(
        ctx,
        "{}: the frictionless solution: {} steps, {active} active nodes; every active \
         node starts sticking",
        ns.law.name(),
        nr.steps
    );
    let u = nr.u.to_local_vec()?;
    sticking(&mut nr.nodes, problem.boundary);
    Ok((Begin::Start(nr, u), None))
}

/// A load step of Coulomb's generalised Newton (`warm`: the previous step's solution, or its
/// extrapolation) on the contact unknowns: the previous step's factorisation where it still
/// holds (only d₀ is new; grown by a new one where the warm set reaches beyond its
/// candidates), else one factorisation with the Schur complement on every dof of the
/// candidates (the nodes with the smallest gaps and the warm set); where that is too wide for
/// the dense limits, the warm set's interior held sticking in K_p but for the nodes that
/// slipped in the step before (which are candidates), and a new pass for the nodes its check
/// finds changing beyond the candidates, as in [`coulomb_passes`]. The dense iteration from
/// the warm states (no frictionless steps), the check on every contact node; if it gives up,
/// the plain path from the warm start or from the last pass' expanded iterate. Collective.
fn coulomb_load_step(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &mut ReducedSystem,
    session: &mut Session,
    settings: StartSettings,
    warm: &WarmStart,
) -> Result<(Begin, Option<schur::CondensedSummary>), RunError> {
    let (ns, fl) = (settings.coulomb, settings.frictionless);
    let dim = problem.mesh.dim;
    // the nodes that slipped in the step before are never held sticking (c_h's global order)
    let release = gathered(ctx, warm.nodes.iter().map(|r| r.active && r.slip));
    // where the step before held a zone, this step holds the warm set's (its factorisation
    // is reused where the held nodes are the same)
    let zone: Vec<bool> = match session.kept.holds_zone() {
        true => gathered(ctx, warm.nodes.iter().map(|r| r.active)),
        false => Vec::new(),
    };
    let mut passes = PassLoop::new(ns.law, zone, release);
    // the expanded iterate of the last pass: the plain path's start where the next one fails
    let mut last: Option<(NewtonResult, Vec<f64>)> = None;
    loop {
        let held = passes.sticking(0);
        // the previous step's factorisation where it holds (schur::round::reused), else a new one
        let how = Condensing {
            per: dim,
            steps: false,
            stick: Some(held),
            thresholds: settings.thresholds,
        };
        let tried = solve_keeping(ctx, problem, reduced, fl, session, Some(warm), how);
        let (mut summary, mut kept) = match tried {
            Ok((schur::Condensed::Factorised(s), Some(kept))) => (s, kept),
            Ok((schur::Condensed::Fallback(mut s), _))
            | Ok((schur::Condensed::Factorised(mut s), None))
            | Ok((schur::Condensed::Solved(_, mut s), _)) => {
                s.factorisations += passes.earlier;
                return Ok((begin_from(ctx, ns.law, last), Some(s)));
            }
            Err(RunError::Failed(why)) => {
                say!(
                    ctx,
                    "{}: not condensed ({why}); starting from the previous load step",
                    ns.law.name()
                );
                return Ok((begin_from(ctx, ns.law, last), None));
            }
            Err(e) => return Err(e),
        };
        summary.factorisations += passes.earlier;
        let begin = match schur::coulomb::solve(ctx, problem, reduced, ns, &mut kept, Some(warm))? {
            schur::CoulombCondensed::Solved(r, cs) => {
                summary.coulomb = Some(cs);
                session.kept.put(kept); // for the next load step (a held zone's too)
                Begin::Solved(*r)
            }
            schur::CoulombCondensed::Start(r, u, cs, beyond) => {
                summary.coulomb = Some(cs);
                // a held zone: at most WARM_STICK_FACTORISATIONS (where the warm set's
                // stick core is no prediction of this step's, a rolling body's, further
                // passes cost what the plain path's steps cost)
                let held_missed = kept.held.iter().any(|&h| h)
                    && summary.factorisations >= WARM_STICK_FACTORISATIONS;
                if !held_missed && passes.goes_on(&beyond, summary.factorisations) {
                    let store = &mut session.kept;
                    passes.next(ctx, store, &mut kept, &beyond, summary.factorisations);
                    last = Some((*r, u));
                    continue;
                }
                say!(
                    ctx,
                    "{}: the plain path from the expanded iterate",
                    ns.law.name()
                );
                Begin::Start(*r, u)
            }
            schur::CoulombCondensed::Fallback(cs) => {
                summary.coulomb = Some(cs);
                begin_from(ctx, ns.law, last)
            }
        };
        return Ok((begin, Some(summary)));
    }
}

/// The state of a Coulomb solve's condensed passes ([`coulomb_passes`], [`coulomb_load_step`]):
/// the held zone and the released nodes (c_h's global order; empty: none), the pass, the
/// factorisations of the passes before and the count of nodes that changed in the last one;
/// the law iterated (for the log).
struct PassLoop {
    law: Law,
    zone: Vec<bool>,
    release: Vec<bool>,
    pass: u32,
    earlier: usize,
    changed_before: usize,
}

impl PassLoop {
    fn new(law: Law, zone: Vec<bool>, release: Vec<bool>) -> PassLoop {
        PassLoop {
            law,
            zone,
            release,
            pass: 0,
            earlier: 0,
            changed_before: usize::MAX,
        }
    }

    /// The next pass' held zone, released nodes and band, with at most `factorisations`.
    fn sticking(&self, factorisations: usize) -> Sticking<'_> {
        Sticking {
            zone: (!self.zone.is_empty()).then_some(self.zone.as_slice()),
            release: &self.release,
            pass: self.pass,
            factorisations,
        }
    }

    /// A start's next pass ([`coulomb_passes`]): its held zone, released nodes and band, with
    /// at most [`FIRST_STICK_FACTORISATIONS`] in the first pass, else what is left of
    /// [`MAX_STICK_FACTORISATIONS`] (one at least).
    fn start_sticking(&self) -> Sticking<'_> {
        self.sticking(match self.pass {
            0 => FIRST_STICK_FACTORISATIONS,
            _ => MAX_STICK_FACTORISATIONS.saturating_sub(self.earlier).max(1),
        })
    }

    /// A new pass follows where nodes beyond the candidates change state (`beyond`), fewer
    /// than in the pass before, within [`MAX_STICK_FACTORISATIONS`] (`done` so far).
    fn goes_on(&self, beyond: &[usize], done: usize) -> bool {
        !beyond.is_empty() && beyond.len() < self.changed_before && done < MAX_STICK_FACTORISATIONS
    }

    /// The next pass from the nodes the check found changing beyond the candidates (c_h's
    /// global order): a node of the held zone (held, or in its band) that slips or leaves the
    /// obstacle is released (a candidate, never held); a node outside the zone that comes into
    /// contact widens the zone (its edge band moves out with it, so that a zone that grows with
    /// the load keeps its interior held); without a zone every such node is released, and so
    /// is every candidate of this pass (the next pass picks its first candidates anew, by gap:
    /// where the zone has moved, a rolling body's, the gaps alone would drop candidates that
    /// this pass needed). The pass's factorisation leaves its node order for the next (the
    /// same graph). Collective (log).
    fn next(
        &mut self,
        ctx: &Ctx,
        store: &mut KeptFactor,
        kept: &mut schur::Kept,
        beyond: &[usize],
        done: usize,
    ) {
        let held = beyond.iter().filter(|&&g| kept.held.get(g) == Some(&true));
        say!(
            ctx,
            "{}: condensed: {} node(s) beyond the candidates change state on the expanded \
             u, {} of them held: a new pass with them as candidates",
            self.law.name(),
            beyond.len(),
            held.count()
        );
        self.zone = std::mem::take(&mut kept.zone); // empty: none held
        self.release.resize(kept.cand.n, false);
        if self.zone.is_empty() {
            for &g in &kept.comp.list {
                self.release[g] = true;
            }
        }
        for &g in beyond {
            match self.zone.get(g) {
                Some(false) => self.zone[g] = true,
                _ => self.release[g] = true,
            }
        }
        self.earlier = done;
        self.changed_before = beyond.len();
        self.pass += 1;
        store.put_order(kept.comp.node_order.take());
    }
}

/// This rank's flags of its contact nodes, all-gathered in c_h's global order. Collective.
fn gathered(ctx: &Ctx, mine: impl Iterator<Item = bool>) -> Vec<bool> {
    let mine: Vec<f64> = mine.map(|f| f64::from(u8::from(f))).collect();
    let all = ctx.all_gather_varcount(&mine);
    all.iter().map(|&f| f > 0.0).collect()
}

/// Where a load step's condensed pass gives up: the plain path from the last pass' expanded
/// iterate, or from the warm start where there was none. Collective (log).
fn begin_from(ctx: &Ctx, law: Law, last: Option<(NewtonResult, Vec<f64>)>) -> Begin {
    match last {
        Some((r, u)) => {
            say!(
                ctx,
                "{}: the plain path from the last pass' expanded iterate",
                law.name()
            );
            Begin::Start(r, u)
        }
        None => Begin::Touching,
    }
}

/// The body's free rigid modes (those Dirichlet data leave free; none with the rigid-mode
/// handling off) and their load. Collective (reductions).
fn free_modes(
    ctx: &Ctx,
    problem: &ContactProblem,
    reduced: &ReducedSystem,
    ns: &NewtonSettings,
) -> FreeModes {
    let (mesh, b) = (problem.mesh, problem.boundary);
    FreeModes::new(
        ctx,
        mesh,
        problem.layout,
        problem.fixed,
        b,
        &reduced.f_local,
        ns.rigid,
    )
}

/// The part of the body's load that friction alone holds: the load φ = Zᵀ Rᵀ f in the rigid
/// modes that Dirichlet data leave free and that move no contact node along its normal (e.g. a
/// tangential load on a floating body pressed onto a plane).
struct Unheld {
    /// An orthonormal basis of those modes (m_z × count, in the coordinates of Z's columns).
    basis: nalgebra::DMatrix<f64>,
    /// |Uᵀ φ| and the load's scale.
    load: f64,
    scale: f64,
}

impl Unheld {
    /// The body's unheld load on the boundary `b`; `None`: the body is held, or that part is
    /// below [`rigid::BALANCE_RTOL`] of the load's scale. Collective (one reduction).
    fn of(ctx: &Ctx, b: &ContactBoundary, free: &FreeModes) -> Option<Unheld> {
        let mz = free.dirichlet_free().ncols();
        if !free.floats() || mz == 0 {
            return None;
        }
        // Σ_k g_k g_kᵀ over every contact node (g_k: the free modes' normal parts at k)
        let mut gram = vec![0.0; mz * mz];
        for k in &b.nodes {
            let g = free.normal_parts(k, &k.frame.n);
            for i in 0..mz {
                for j in 0..mz {
                    gram[i * mz + j] += g[i] * g[j];
                }
            }
        }
        let gram = nalgebra::DMatrix::from_row_slice(mz, mz, &ctx.sum_vec(&gram));
        let eig = gram.symmetric_eigen();
        let top = eig.eigenvalues.iter().fold(0.0_f64, |m, &e| m.max(e));
        let cols: Vec<_> = (0..mz)
            .filter(|&i| eig.eigenvalues[i] <= 1e-12 * top)
            .map(|i| eig.eigenvectors.column(i).into_owned())
            .collect();
        if cols.is_empty() {
            return None;
        }
        let basis = nalgebra::DMatrix::from_columns(&cols);
        let phi = nalgebra::DVector::from_vec(free.free_load());
        let (_, scale) = free.load();
        let load = (basis.transpose() * phi).norm();
        (load > rigid::BALANCE_RTOL * scale).then_some(Unheld { basis, load, scale })
    }

    /// Why the frictionless problem cannot carry the load.
    fn why(&self) -> String {
        format!(
            "a load of {:.3e} (of {:.3e}) in rigid modes no contact normal holds: friction \
             alone carries it",
            self.load, self.scale
        )
    }

    /// The load of Coulomb's frictionless estimate: φ' = φ + P T s, the part only friction
    /// holds carried by one tangential force T s at the contact node with the smallest gap
    /// (ties: the smallest gmsh tag; P: the free modes' motion there, T its tangents), s the
    /// least-squares solution of Uᵀ φ' = 0 — where the pins would carry it off the contact and tip the body. Friction
    /// acts in the contact zone, and the moment of a force along a plane does not depend on
    /// where on the plane it acts: the estimate's moment balance is the friction's (to first
    /// order on a curved obstacle). What one force cannot carry (a torsion about the normal
    /// in 3D) the pins carry: it is left out of φ'. Collective (one all-gather).
    fn carried_at_contact(&self, ctx: &Ctx, b: &ContactBoundary, free: &FreeModes) -> Vec<f64> {
        let mz = free.dirichlet_free().ncols();
        let mut phi = free.free_load();
        // this rank's node with the smallest gap (ties: the smallest gmsh tag): gap, tag, then
        // the free modes' motion along its tangents (2 × m_z)
        let rec = 2 + 2 * mz;
        let mut mine = vec![f64::INFINITY; rec];
        let nearest = b
            .nodes
            .iter()
            .min_by(|a, c| a.gap.total_cmp(&c.gap).then(a.tag.cmp(&c.tag)));
        if let Some(k) = nearest {
            mine[0] = k.gap;
            mine[1] = k.tag as f64;
            for (i, t) in k.frame.t.iter().enumerate() {
                mine[2 + mz * i..2 + mz * (i + 1)].copy_from_slice(&free.normal_parts(k, t));
            }
        }
        let all = ctx.all_gather_varcount(&mine);
        // the smallest gap of all ranks (ties: the smallest tag, on every partition)
        let Some(best) = all
            .chunks(rec)
            .filter(|r| r[0].is_finite())
            .min_by(|a, c| a[0].total_cmp(&c[0]).then(a[1].total_cmp(&c[1])))
        else {
            return phi;
        };
        let tangents = nalgebra::DMatrix::from_fn(mz, 2, |c, i| best[2 + mz * i + c]);
        let a = self.basis.transpose() * &tangents;
        let rhs = -(self.basis.transpose() * nalgebra::DVector::from_column_slice(&phi));
        let svd = a.svd(true, true);
        let Ok(s) = svd.solve(&rhs, 1e-12 * svd.singular_values.max()) else {
            return phi;
        };
        let moved = tangents * s;
        for (p, m) in phi.iter_mut().zip(moved.iter()) {
            *p += m;
        }
        // what one force cannot carry is left to the pins: out of φ'
        let phi = nalgebra::DVector::from_vec(phi);
        let rest = &self.basis * (self.basis.transpose() * &phi);
        (phi - rest).as_slice().to_vec()
    }
}

/// The fixed point's stopping tolerance on the thresholds, relative to max_k b_k.
pub const FIXED_POINT_TOL: f64 = 1e-9;

// tuning::MAX_STICK_FACTORISATIONS: Factorisations of K_p at most in a Coulomb start whose zone's interior is held sticking
// (each pass takes the nodes that changed state beyond the candidates as candidates, as long
// as fewer change than in the pass before); then the plain path from the last expanded
// iterate. Below what the plain path costs: 9–19 LU steps on the wide zones of
// docs/numbers.md ("Wide zones with friction").
