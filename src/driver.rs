//! The driver: case → mesh → partition → assembly → the load steps (`crate::steps`: per step
//! the solve — linear, or the contact algorithm —, its post-processing and output) → summary
//! and the result set put in place, one line per stage.

use crate::assembly::{self, System};
use crate::bodies::{self, Body};
use crate::case::{Case, DenseThreads};
use crate::case::{Method, Preset, SolverPath, SolverSection};
use crate::coincident;
use crate::error::RunError;
use crate::fem::Materials;
use crate::linsolve::{LinearSetup, SolverKind};
use crate::mesh::Mesh;
use crate::output::ResultSet;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::say;
use crate::setup::ContactSettings;
use crate::setup::{self, Input};
use crate::solver;
use crate::steps::{LoadReport, SolveReport, Stepper};
use crate::summary::{self, AssemblyInfo, Clock, PartitionInfo, PresetChoice, Summary};
use crate::warnings::{self, Warning};
use serde::Serialize;

/// The solve's sections of summary.json: the last step's report, and the load history.
#[derive(Serialize)]
struct SolveSections {
    #[serde(flatten)]
    solve: SolveReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    load: Option<LoadReport>,
}

/// A case set up up to its solve: read, partitioned and checked (the run's input errors all
/// found), nothing assembled or written.
pub struct Prepared<'c> {
    pub case: &'c Case,
    /// The case's `solver` section with its preset resolved.
    pub solver: SolverSection,
    /// The preset the case asked for, and why the one used was chosen.
    pub asked: Preset,
    pub preset_reason: String,
    pub mesh: Mesh,
    pub material: Materials,
    pub layout: Layout,
    pub partition: PartitionInfo,
    /// The mesh's bodies, by their first node tags.
    pub bodies: Vec<Body>,
    /// The body of every local node (an index into `bodies`).
    pub body_of: Vec<u32>,
    /// The contact settings (`None` without contact).
    pub contact: Option<ContactSettings>,
    blas: Option<String>,
    dense_threads: usize,
    clock: Clock,
    /// The input's warnings (logged already), first in summary.json's `warnings`.
    warnings: Vec<Warning>,
}

/// Runs a whole case. Returns summary.json's text (the same on every rank).
pub fn run_case(ctx: &Ctx, case: &Case) -> Result<String, RunError> {
    let ctx = &ctx.with_dense_threads(case.solver.dense_threads);
    solve(ctx, prepare(ctx, case)?)
}

/// The set-up stage of a run: mesh, partition, preset, bodies, contact settings. Collective;
/// every rank returns the same `Ok` / `Err` kind.
pub fn prepare<'c>(ctx: &Ctx, case: &'c Case) -> Result<Prepared<'c>, RunError> {
    let asked = case.solver.preset;
    let mut clock = Clock::start();
    let Input {
        mesh,
        material,
        layout,
        read_seconds,
        partition_seconds,
        warnings,
    } = setup::read_input(ctx, case)?;
    clock.lap();
    (clock.t.read, clock.t.partition) = (read_seconds, partition_seconds);
    let partition = log_partition(ctx, &mesh, &layout);
    let contact = solver::AutoContact {
        friction: (case.contacts.iter()).any(|c| c.friction != crate::case::Friction::None),
        snesvi: case.solver.method == Method::SnesVi,
        slave_over_master: material.slave_over_master.unwrap_or(0.0),
    };
    let (preset, preset_reason) = solver::choose_preset(
        case.solver.preset,
        mesh.dim,
        mesh.n_nodes_global() * mesh.dim,
        contact,
    );
    say!(ctx, "solver: preset {} ({preset_reason})", preset.name());
    if case.solver.path == SolverPath::Schur && preset == Preset::Iterative {
        let why = format!("needs a factorisation, not the iterative preset ({preset_reason})");
        return Err(case.schur_path_refused(&why).into());
    }
    let blas = crate::blas::kernels();
    let dense_threads = ctx.cores.threads(); // rank 0's is the one logged and written
    if let Some(k) = &blas {
        say!(
            ctx,
            "blas: {k}; rank 0's dense phases on {dense_threads} thread(s) ({})",
            match case.solver.dense_threads {
                DenseThreads::Auto => "the CPUs of the ranks on its node",
                DenseThreads::Fixed(_) => "solver.dense_threads",
            }
        );
    }
    let solver = SolverSection {
        preset,
        ..case.solver.clone()
    };
    crate::linsolve::check_options(ctx, &case.file, &solver)?;
    let problem = setup::problem(case, &mesh, &material);
    let (survey, unjoined) = check_bodies(ctx, case, &mesh, &layout, &problem.fixed)?;
    drop(problem);
    let contact = if case.contacts.is_empty() {
        None
    } else {
        let mut c = ctx.agree(
            setup::contact_settings(case, &case.contacts, &material).map_err(RunError::from),
        )?;
        c.modes = Some(std::sync::Arc::new(survey.modes(ctx, &mesh)));
        Some(c)
    };
    let mut warnings = warnings;
    if let Some(w) = unjoined {
        warnings::log(ctx, std::slice::from_ref(&w), "");
        warnings.push(w);
    }
    if let Some(w) = contact
        .as_ref()
        .and_then(|c| unhandled_modes(c, &survey.bodies))
    {
        warnings::log(ctx, std::slice::from_ref(&w), "");
        warnings.push(w);
    }
    let (bodies, body_of) = (survey.bodies, survey.body_of);
    ResultSet::check(ctx, &case.output.dir, &case.file)?;
    Ok(Prepared {
        case,
        solver,
        asked,
        preset_reason,
        mesh,
        material,
        layout,
        partition,
        bodies,
        body_of,
        contact,
        blas,
        dense_threads,
        clock,
        warnings,
    })
}

/// [`warnings::RIGID_MODES_UNHANDLED`]: `rigid_modes = "none"` while a body of the mesh is
/// free in some rigid mode. The solver then neither pins such a mode nor tests the load in
/// it; where the contact does not hold it (a frictionless disk between two planes, free to
/// slide along them) the factorisation's round-off decides the body's rigid motion: it drifted
/// sideways by +0.216, −0.0048 and +0.026 on 1, 2 and 3 ranks, where the obstacle moved by
/// 0.02, at exit 0. Pure.
fn unhandled_modes(c: &ContactSettings, bodies: &[Body]) -> Option<Warning> {
    if c.rigid_modes != crate::case::RigidModeHandling::None {
        return None;
    }
    let free = bodies.iter().find(|b| b.free_modes > 0)?;
    Some(Warning {
        code: warnings::RIGID_MODES_UNHANDLED,
        message: format!(
            "rigid_modes = \"none\" while the body from node tag {} is free in {} rigid \
             mode(s) (its Dirichlet data do not hold them): where its contact does not hold \
             them either, its rigid motion is whatever round-off gives (it changes with the rank \
             count); \"auto\" finds and pins them",
            free.first_tag, free.free_modes
        ),
        key: Some(c.pairs[0].key("rigid_modes")),
        pair: None,
        value: free.free_modes as f64,
        threshold: 0.0,
        at: None,
        steps: Vec::new(),
    })
}

/// The solve stage of a run: assembly, the load steps, summary.json and the result set.
/// Where the auto preset chose the iterative preset and its solve fails (no convergence of
/// the contact iteration or of GMRES, a final state its certificate rejects), the case is
/// solved again on the direct preset before anything is written ([`falls_back`]). Returns
/// summary.json's text (the same on every rank). Collective.
pub fn solve(ctx: &Ctx, prepared: Prepared) -> Result<String, RunError> {
    let Prepared {
        case,
        solver,
        asked,
        preset_reason,
        mesh,
        material,
        layout,
        partition,
        bodies,
        body_of,
        contact,
        blas,
        dense_threads,
        mut clock,
        warnings: input_warnings,
    } = prepared;
    let problem = setup::problem(case, &mesh, &material);
    let on = Discretised {
        case,
        mesh: &mesh,
        layout: &layout,
        material: &material,
        problem: &problem,
        body_of: &body_of,
    };
    let (solver, preset_reason, attempt) =
        on.attempt_or_direct(ctx, asked, (solver, preset_reason), contact, &mut clock)?;
    let Attempt {
        assembly,
        out,
        stepped,
    } = attempt?;
    let preset = solver.preset;
    let mut warnings = [input_warnings, stepped.warnings].concat();
    if let Some(w) = crate::linsolve::unused_options_warning(ctx, &solver)? {
        warnings::log(ctx, std::slice::from_ref(&w), "");
        warnings.push(w);
    }
    (clock.t.solve, clock.t.post, clock.t.output) = (
        stepped.solve_seconds,
        stepped.post_seconds,
        stepped.output_seconds,
    );
    let timings = clock.finish();
    let summary = Summary {
        case: case.file.display().to_string(),
        mesh: case.mesh.file.display().to_string(),
        dimension: mesh.dim,
        model: format!("{:?}", material.model),
        cells: mesh.n_cells_global(),
        nodes: mesh.n_nodes_global(),
        dofs: mesh.n_nodes_global() * mesh.dim,
        refine: case.mesh.refine,
        ranks: ctx.size,
        blas,
        dense_threads,
        dense_threads_asked: case.solver.dense_threads.name(),
        bodies: bodies::summed(&bodies),
        preset: PresetChoice {
            asked: asked.name(),
            used: preset.name(),
            reason: preset_reason,
        },
        partition,
        assembly,
        peak_memory_bytes_per_rank: summary::peak_memory_and_log(ctx, &timings),
        timings,
        warnings,
        solve: SolveSections {
            solve: stepped.report,
            load: stepped.load,
        },
    };
    let json = summary.to_json();
    let csv = stepped.contact_csv.as_deref();
    let history = stepped.history_csv.as_deref();
    out.commit(ctx, &json, csv, history, timings.output)?;
    match stepped.failure {
        None => Ok(json),
        Some(e) => Err(RunError::Failed(format!(
            "{e} (the steps that converged are written to {}, summary.json says load.completed \
             = false)",
            case.output.dir.display()
        ))),
    }
}

/// Whether a solve on the preset `solver` that ended in `attempt` is taken again on the direct
/// preset: the auto preset chose the iterative one and the solve failed — the contact
/// iteration or a linear solve did not converge, the final state's certificate rejected it, or
/// a load series stopped at a step. The iterative preset rests on a
/// multigrid preconditioner and a half-space predictor that a body can defeat (a floating
/// plate 2 × 2 × 0.02 pressed onto a large sphere, 18 897 unknowns: 170–300 GMRES iterations
/// a step and a final state whose frictionless rows kept tangential forces of 2.9e-5 of the
/// force scale, exit 1 after 9.6 s, where the direct preset solves it in 0.4 s); a case the
/// user gave no preset for is solved where a factorisation can solve it. An explicit
/// `solver.preset = "iterative"` is kept and fails as asked. Pure.
fn falls_back(asked: Preset, solver: &SolverSection, attempt: &Result<Attempt, RunError>) -> bool {
    asked == Preset::Auto
        && solver.preset == Preset::Iterative
        && match attempt {
            Err(RunError::Failed(_) | RunError::NoConvergence(_)) => true,
            // an input error, or PETSc's own (out of memory, say): not the preset's to mend
            Err(_) => false,
            Ok(a) => a.stepped.failure.is_some(),
        }
}

/// The gist of an error message for the log's line: up to its first "; " or " — ", and of a
/// longer one its head up to the first ": " after its first words ("the final state is not a
/// solution"). Pure.
fn first_sentence(message: &str) -> &str {
    let end = ["; ", " — "]
        .iter()
        .filter_map(|p| message.find(p))
        .min()
        .unwrap_or(message.len());
    let head = &message[..end];
    if head.chars().count() <= 120 {
        return head;
    }
    match head.get(20..).and_then(|rest| rest.find(": ")) {
        Some(i) => &head[..20 + i],
        None => head,
    }
}

/// What one solve of a case needs besides its solver section: the case, its mesh, partition,
/// materials, the problem's data and every local node's body.
struct Discretised<'a, 'p> {
    case: &'a Case,
    mesh: &'a Mesh,
    layout: &'a Layout,
    material: &'a Materials,
    problem: &'a assembly::Problem<'p>,
    body_of: &'a [u32],
}

/// A solve's assembly report, its result set (being written) and the steps' results.
struct Attempt {
    assembly: AssemblyInfo,
    out: ResultSet,
    stepped: crate::steps::Stepped,
}

impl Discretised<'_, '_> {
    /// [`Discretised::attempt`] on `solver`'s preset and, where [`falls_back`] says so, once
    /// more on the direct preset (the first attempt's staging directory removed: nothing of it
    /// is written); the preset's section and reason as they end, and the attempt. A failure
    /// that this rank raised alone is not retried: main ends every rank with it. Collective.
    fn attempt_or_direct(
        &self,
        ctx: &Ctx,
        asked: Preset,
        (mut solver, mut reason): (SolverSection, String),
        contact: Option<ContactSettings>,
        clock: &mut Clock,
    ) -> Result<(SolverSection, String, Result<Attempt, RunError>), RunError> {
        let attempt = self.attempt(ctx, &solver, contact.clone(), clock);
        if !falls_back(asked, &solver, &attempt) || crate::abort::pending().is_some() {
            return Ok((solver, reason, attempt));
        }
        let why = match &attempt {
            Err(e) => e.to_string(),
            Ok(a) => (a.stepped.failure.as_ref()).map_or_else(String::new, |e| e.to_string()),
        };
        let why = first_sentence(&why);
        drop(attempt);
        say!(
            ctx,
            "solver: the iterative preset failed ({why}); the auto preset solves the case again \
             on the direct preset"
        );
        solver.preset = Preset::Direct;
        reason = format!("{reason}; the iterative preset failed ({why}), then direct");
        crate::linsolve::check_options(ctx, &self.case.file, &solver)?;
        clock.lap();
        let attempt = self.attempt(ctx, &solver, contact, clock);
        Ok((solver, reason, attempt))
    }

    /// Assembly and the load steps on the preset of `solver`, the results staged (not yet
    /// committed). Collective.
    fn attempt(
        &self,
        ctx: &Ctx,
        solver: &SolverSection,
        contact: Option<ContactSettings>,
        clock: &mut Clock,
    ) -> Result<Attempt, RunError> {
        let case = self.case;
        let mut contact = contact;
        let (mut sys, basis) = assemble(
            ctx,
            solver,
            (self.mesh, self.layout),
            self.problem,
            &mut contact,
        )?;
        clock.t.assembly = clock.lap();
        let assembly = check_assembly(ctx, &sys, clock.t.assembly)?;
        let out = ResultSet::begin(ctx, &case.output.dir, &case.file)?;
        clock.lap();
        let stepper = Stepper {
            ctx,
            case,
            solver,
            mesh: self.mesh,
            layout: self.layout,
            material: self.material,
            fixed: &self.problem.fixed,
            held_fixed: &self.problem.held_fixed,
            contact: contact.as_ref(),
            mortar: basis.as_ref(),
            body_of: self.body_of,
            out: &out,
        };
        let stepped = stepper.run(&mut sys)?;
        clock.lap();
        Ok(Attempt {
            assembly,
            out,
            stepped,
        })
    }
}

/// The system of a run: A and f assembled, and with body pairs the change of basis u = Q w + c
/// set up and A replaced by Qᵀ A Q — as an operator where the Newton steps are iterative
/// (their preconditioner works in u and never factorises it; the test-only limit
/// MATRIX_FREE = 0 assembles it for the tests that compare both). Collective.
fn assemble(
    ctx: &Ctx,
    solver: &SolverSection,
    (mesh, layout): (&Mesh, &Layout),
    problem: &assembly::Problem,
    contact: &mut Option<ContactSettings>,
) -> Result<(System, Option<crate::mortar::Basis>), RunError> {
    let mut sys = assembly::assemble(ctx.comm(), layout, problem)?;
    let mut basis = match contact.as_mut() {
        Some(c) => crate::mortar::set_up(ctx, mesh, layout, c, &problem.fixed)?,
        None => None,
    };
    if let Some(b) = basis.as_mut() {
        let operator = solver.method == Method::Newton
            && LinearSetup::kind_of(solver)? == SolverKind::Iterative
            && crate::fault::limit("MATRIX_FREE", 1) > 0;
        b.transform_matrix(ctx, &mut sys, !operator)?;
    }
    Ok((sys, basis))
}

/// `signorini-mpi check`: the set-up stage of a run and its contact boundary (every input
/// error a run finds before its solve), then what the run would do, on rank 0's stdout.
/// Solves, assembles and writes nothing. Collective.
pub fn check_case(ctx: &Ctx, case: &Case) -> Result<(), RunError> {
    let p = prepare(ctx, case)?;
    let (mesh, case) = (&p.mesh, p.case);
    let problem = setup::problem(case, mesh, &p.material);
    let modes = if mesh.dim == 2 { 3 } else { 6 };
    say!(ctx, "check: bodies: {}", p.bodies.len());
    for (i, b) in p.bodies.iter().enumerate() {
        let held = match (b.free_modes, &p.contact) {
            (0, _) => "held by its Dirichlet data".to_string(),
            (m, Some(c)) => format!(
                "free in {m} of its {modes} rigid modes (Dirichlet data too few or none): \
                 the contact solver takes them ({})",
                c.pairs[0].key("rigid_modes")
            ),
            (m, None) => {
                format!("free in {m} of its {modes} rigid modes (Dirichlet data too few or none)")
            }
        };
        say!(
            ctx,
            "check:   body {}: {} nodes from node tag {}, {held}",
            i + 1,
            b.nodes,
            b.first_tag
        );
    }
    say!(ctx, "check: groups: {}", mesh.groups.len());
    for (i, g) in mesh.groups.iter().enumerate() {
        say!(
            ctx,
            "check:   '{}' ({}D): {} elements",
            g.name,
            g.dim,
            mesh.group_size_global(i)
        );
    }
    if let Some(settings) = &p.contact {
        let mut settings = settings.clone();
        // the body pairs' rows (their change of basis itself is not needed here)
        crate::mortar::set_up(ctx, mesh, &p.layout, &mut settings, &problem.fixed)?;
        let first = case.load.as_ref().and_then(|l| l.factors.first().copied());
        settings.at_factor(first.unwrap_or(1.0));
        let (b, warned) =
            crate::signorini::contact_boundary(ctx, &settings, mesh, &p.layout, &problem.fixed)?;
        for w in &warned {
            say!(ctx, "check: warning: {}", w.message);
        }
        for (j, pair) in settings.pairs.iter().enumerate() {
            let mine = || b.nodes.iter().filter(|k| k.pair == j);
            let nodes = ctx.sum_usize(mine().count());
            let inside = ctx.sum_usize(mine().filter(|k| k.gap < 0.0).count());
            let min_gap = ctx.min_f64(mine().map(|k| k.gap).fold(f64::INFINITY, f64::min));
            let max_gap = ctx.max_f64(mine().map(|k| k.gap).fold(f64::NEG_INFINITY, f64::max));
            let gaps = if nodes == 0 {
                "no contact node".to_string()
            } else if inside == 0 {
                format!("none starts penetrating (gaps {min_gap:.6e} to {max_gap:.6e})")
            } else {
                format!(
                    "{inside} start(s) penetrating the obstacle, by up to {:.6e} (gaps \
                     {min_gap:.6e} to {max_gap:.6e})",
                    -min_gap
                )
            };
            say!(
                ctx,
                "check: contact pair {} on '{}': {nodes} nodes; {gaps}",
                pair.key,
                pair.group
            );
        }
    } else {
        say!(ctx, "check: contact: none (a linear solve)");
    }
    say!(
        ctx,
        "check: preset: {} (asked {}; {})",
        p.solver.preset.name(),
        p.asked.name(),
        p.preset_reason
    );
    say!(
        ctx,
        "check: {} is valid; nothing solved or written (results would go to {})",
        case.file.display(),
        case.output.dir.display()
    );
    Ok(())
}

/// The partition line and its summary record.
fn log_partition(ctx: &Ctx, mesh: &Mesh, layout: &Layout) -> PartitionInfo {
    let info = PartitionInfo {
        cells_per_rank: layout.cells_per_rank(),
        nodes_per_rank: layout.nodes_per_rank(),
        cell_imbalance: summary::imbalance(&layout.cells_per_rank()),
    };
    say!(
        ctx,
        "partition: {} ranks, cells per rank {:?} (max/mean {:.3}), nodes per rank {:?}",
        ctx.size,
        info.cells_per_rank,
        info.cell_imbalance,
        info.nodes_per_rank
    );
    say!(ctx, "dofs: {}", mesh.n_nodes_global() * mesh.dim);
    info
}

/// The mesh's separate bodies ([`bodies::labelled`]): a line where there are several. The
/// contact solver takes the rigid modes each body's Dirichlet data leave free (thesis 4.1, per
/// body: signorini/rigid.rs); a body free in some rigid mode is refused where no contact group
/// lies on it (beside another body, or in a case without contact pairs): nothing could hold
/// it. Collective; every rank returns the same.
fn check_bodies(
    ctx: &Ctx,
    case: &Case,
    mesh: &Mesh,
    layout: &Layout,
    fixed: &[f64],
) -> Result<(bodies::Survey, Option<Warning>), RunError> {
    let survey = bodies::labelled(ctx, mesh, layout, fixed);
    let unjoined = unjoined_warning(ctx, case, mesh, layout, &survey);
    let list = &survey.bodies;
    let b = bodies::summed(list);
    if b.count > 1 {
        say!(
            ctx,
            "mesh: {} separate bodies (parts that share no node), {} of them with a rigid motion \
             their Dirichlet data leave free",
            b.count,
            b.not_held
        );
    }
    let no_pairs = case.contacts.is_empty();
    if b.not_held > 0 && (b.count > 1 || no_pairs) {
        let touched = if no_pairs {
            vec![false; list.len()]
        } else {
            bodies::touched(ctx, mesh, &survey, &contact_groups(case))
        };
        let loose = (list.iter().zip(&touched)).find(|(body, &t)| body.free_modes > 0 && !t);
        if let Some((body, _)) = loose {
            let which = if b.count > 1 {
                format!(
                    "the mesh {} has {} separate bodies (parts that share no node); the body of \
                     {} nodes from node tag {}",
                    case.mesh.file.display(),
                    b.count,
                    body.nodes,
                    body.first_tag
                )
            } else {
                format!(
                    "the body of the mesh {} ({} nodes)",
                    case.mesh.file.display(),
                    body.nodes
                )
            };
            let none_on_it = if no_pairs {
                "the case has no contact pair"
            } else {
                "no pair's group, no body pair's obstacle group"
            };
            return Err(RunError::Input(case.error_at(
                "dirichlet",
                format!(
                    "{which} has {} rigid mode(s) its Dirichlet data leave free and no contact \
                     group on it ({none_on_it}), so nothing holds it: hold it by Dirichlet \
                     data, or name a group of its boundary in a contact pair{}",
                    body.free_modes,
                    match &unjoined {
                        Some(w) => format!(" (besides, {})", w.message),
                        None => String::new(),
                    }
                ),
            )));
        }
    }
    Ok((survey, unjoined))
}

/// [`warnings::UNJOINED_NODES`]: surface nodes of the mesh that lie on another node
/// ([`coincident::unjoined`]) and are not both in a contact pair's groups. Collective.
fn unjoined_warning(
    ctx: &Ctx,
    case: &Case,
    mesh: &Mesh,
    layout: &Layout,
    survey: &bodies::Survey,
) -> Option<Warning> {
    let mut in_pair = vec![false; mesh.n_nodes()];
    for g in contact_groups(case) {
        for f in setup::group_facets(mesh, g) {
            for &v in mesh.facet(f) {
                in_pair[v] = true;
            }
        }
    }
    let u = coincident::unjoined(ctx, mesh, layout, survey, &in_pair)?;
    let body = |b: usize| survey.bodies.get(b).map_or(0, |b| b.first_tag);
    let (a, b) = u.bodies;
    let between = if a == b {
        format!(
            "both of the body from node tag {}: a crack through it",
            body(a)
        )
    } else {
        format!(
            "of the bodies from node tags {} and {}, which are thus separate",
            body(a),
            body(b)
        )
    };
    let dim = mesh.dim;
    let x: Vec<String> = u.at[..dim].iter().map(|c| format!("{c}")).collect();
    Some(Warning {
        code: warnings::UNJOINED_NODES,
        message: format!(
            "{} pair(s) of surface nodes of the mesh {} lie at one point without being one node, \
             and no contact pair joins them, e.g. node tags {} and {} at ({}), {between}: the \
             parts were meshed apart and never joined. If they are one body, make the mesh \
             conformal (Gmsh: BooleanFragments, or Coherence in a .geo); if they touch, name the \
             two surfaces as a body pair",
            u.pairs,
            case.mesh.file.display(),
            u.first.0,
            u.first.1,
            x.join(", ")
        ),
        key: Some("mesh.file".to_string()),
        pair: None,
        value: u.pairs as f64,
        threshold: 0.0,
        at: Some(warnings::Place {
            node: Some(u.first.0),
            cell: None,
            x: u.at[..dim].to_vec(),
        }),
        steps: Vec::new(),
    })
}

/// The boundary groups of the contact pairs: each pair's group and a body pair's obstacle
/// group.
fn contact_groups(case: &Case) -> Vec<&str> {
    let mut groups = Vec::new();
    for c in &case.contacts {
        groups.push(c.group.as_str());
        if let crate::case::ObstacleSpec::Body { group } = &c.obstacle {
            groups.push(group.as_str());
        }
    }
    groups
}

/// The assembly line; a malloc during assembly means a wrong preallocation (a bug).
fn check_assembly(ctx: &Ctx, sys: &System, seconds: f64) -> Result<AssemblyInfo, RunError> {
    let info = AssemblyInfo {
        mallocs: ctx.sum_f64(sys.stats.mallocs),
        matrix_seconds_max: ctx.max_f64(sys.stats.matrix_seconds),
        rows_seconds_max: ctx.max_f64(sys.stats.rows_seconds),
        petsc_seconds_max: ctx.max_f64(sys.stats.petsc_seconds),
    };
    let nonzeros = ctx.sum_f64(sys.stats.nonzeros);
    say!(
        ctx,
        "assembly: {:.3} s (matrix {:.3} s: rows {:.3} s, PETSc {:.3} s; {} nonzeros, {} mallocs)",
        seconds,
        info.matrix_seconds_max,
        info.rows_seconds_max,
        info.petsc_seconds_max,
        nonzeros,
        info.mallocs
    );
    if info.mallocs > 0.0 {
        return Err(RunError::Failed(format!(
            "assembly needed {} mallocs: the preallocation is wrong (a bug)",
            info.mallocs
        )));
    }
    Ok(info)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_log_gives_an_errors_gist() {
        let step = "Newton step 5: the linear solver did not converge (DIVERGED_ITS after 2000 \
                    iterations); case.toml: it is set by 'solver.preset'";
        assert_eq!(
            first_sentence(step),
            "Newton step 5: the linear solver did not converge (DIVERGED_ITS after 2000 \
             iterations)"
        );
        let long = format!(
            "the final state is not a solution: it violates (3.14) beyond 1e-6 of the \
             problem's scales (force 1e-3, length 2e-1): KKT {} — the problem is ill-posed",
            "x".repeat(200)
        );
        assert_eq!(first_sentence(&long), "the final state is not a solution");
        assert_eq!(first_sentence("no support"), "no support");
    }

    #[test]
    fn only_the_auto_presets_iterative_failures_fall_back() {
        let iterative = SolverSection {
            preset: Preset::Iterative,
            ..SolverSection::default()
        };
        let direct = SolverSection {
            preset: Preset::Direct,
            ..SolverSection::default()
        };
        let failed = || Err(RunError::Failed("the final state is not a solution".into()));
        let stuck = || Err(RunError::NoConvergence("100 steps".into()));
        assert!(falls_back(Preset::Auto, &iterative, &failed()));
        assert!(falls_back(Preset::Auto, &iterative, &stuck()));
        // asked for explicitly: kept, and fails as asked
        assert!(!falls_back(Preset::Iterative, &iterative, &failed()));
        // the direct preset has nothing to fall back on
        assert!(!falls_back(Preset::Auto, &direct, &failed()));
        // input errors and PETSc's own are not the preset's to mend
        let input = crate::error::InputError::new(std::path::Path::new("c.toml"), "bad");
        assert!(!falls_back(Preset::Auto, &iterative, &Err(input.into())));
    }
}
