//! The driver: case → mesh → partition → assembly → the load steps (`crate::steps`: per step
//! the solve — linear, or the contact algorithm —, its post-processing and output) → summary
//! and the result set put in place, one line per stage.

use crate::assembly::{self, System};
use crate::bodies::{self, Bodies};
use crate::case::Case;
use crate::error::{InputError, RunError};
use crate::mesh::Mesh;
use crate::output::ResultSet;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::say;
use crate::setup::{self, Input};
use crate::solver;
use crate::steps::{LoadReport, SolveReport, Stepper};
use crate::summary::{self, AssemblyInfo, Clock, PartitionInfo, PresetChoice, Summary};
use serde::Serialize;

/// The solve's sections of summary.json: the last step's report, and the load history.
#[derive(Serialize)]
struct SolveSections {
    #[serde(flatten)]
    solve: SolveReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    load: Option<LoadReport>,
}

/// Runs a whole case. Returns summary.json's text (the same on every rank).
pub fn run_case(ctx: &Ctx, case: &Case) -> Result<String, RunError> {
    let asked = case.solver.preset;
    let mut clock = Clock::start();
    let Input {
        mesh,
        material,
        layout,
        read_seconds,
        partition_seconds,
    } = setup::read_input(ctx, case)?;
    clock.lap();
    (clock.t.read, clock.t.partition) = (read_seconds, partition_seconds);
    let partition = log_partition(ctx, &mesh, &layout);
    let friction = case
        .contacts
        .iter()
        .any(|c| c.friction != crate::case::Friction::None);
    let (preset, preset_reason) = solver::choose_preset(
        case.solver.preset,
        mesh.dim,
        mesh.n_nodes_global() * mesh.dim,
        friction,
    );
    say!(ctx, "solver: preset {} ({preset_reason})", preset.name());
    let blas = crate::blas::kernels();
    let dense_threads = ctx.cores.threads(); // rank 0's is the one logged and written
    if let Some(k) = &blas {
        say!(
            ctx,
            "blas: {k}; rank 0's dense phases on {dense_threads} thread(s) (the CPUs of the \
             ranks on its node)"
        );
    }
    let mut resolved = case.clone();
    resolved.solver.preset = preset;
    let case = &resolved;
    let problem = setup::problem(case, &mesh, material);
    let bodies = check_bodies(ctx, case, &mesh, &layout, &problem.fixed)?;
    let mut sys = assembly::assemble(ctx.comm(), &layout, &problem)?;
    clock.t.assembly = clock.lap();
    let assembly = check_assembly(ctx, &sys, clock.t.assembly)?;
    let out = ResultSet::begin(ctx, &case.output.dir, &case.file)?;
    clock.lap();
    let stepper = Stepper {
        ctx,
        case,
        mesh: &mesh,
        layout: &layout,
        material: &material,
        fixed: &problem.fixed,
        held_fixed: &problem.held_fixed,
        out: &out,
    };
    let stepped = stepper.run(&mut sys)?;
    clock.lap();
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
        bodies,
        preset: PresetChoice {
            asked: asked.name(),
            used: preset.name(),
            reason: preset_reason,
        },
        partition,
        assembly,
        peak_memory_bytes_per_rank: summary::peak_memory_and_log(ctx, &timings),
        timings,
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

/// The mesh's separate bodies ([`bodies::count`]): a line where there are several. A body
/// with a rigid motion its Dirichlet data leave free (none, or too few) beside another, in a
/// case with contact, is refused: the contact solver takes the free rigid modes of one body
/// (thesis 4.1), so the rigid position of such a body would be left to the factorisation's
/// round-off (measured: frictionless, a square beside a held one, moved sideways by about
/// 0.0038 on 1 rank and 0.0022 on 3) or its solve would fail. Collective; every rank returns
/// the same.
fn check_bodies(
    ctx: &Ctx,
    case: &Case,
    mesh: &Mesh,
    layout: &Layout,
    fixed: &[f64],
) -> Result<Bodies, RunError> {
    let b = bodies::count(ctx, mesh, layout, fixed);
    if b.count > 1 {
        say!(
            ctx,
            "mesh: {} separate bodies (parts that share no node), {} of them with a rigid motion \
             their Dirichlet data leave free",
            b.count,
            b.not_held
        );
    }
    if b.count > 1 && b.not_held > 0 && !case.contacts.is_empty() {
        return Err(RunError::Input(InputError::new(
            &case.mesh.file,
            format!(
                "the mesh has {} separate bodies (parts that share no node), {} of them \
                 with a rigid motion their Dirichlet data leave free: with contact the solver \
                 takes the free rigid modes of one body, so the position of such a body would \
                 be undetermined or its solve fail; hold every body by Dirichlet data, or solve \
                 each body that they do not hold from a mesh of its own",
                b.count, b.not_held
            ),
        )));
    }
    Ok(b)
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
