//! The driver: case → mesh → partition → assembly → solve (linear, or the contact algorithm)
//! → post-processing → output, one line per stage.

use crate::assembly::{self, System};
use crate::case::{Case, OutputField};
use crate::error::RunError;
use crate::mesh::Mesh;
use crate::output::{ContactResult, ResultSet};
use crate::par::Ctx;
use crate::partition::{self, Layout};
use crate::petsc::Vector;
use crate::post;
use crate::say;
use crate::setup::{self, Input};
use crate::signorini::{self, ContactReport};
use crate::solver::{self, LinearSummary};
use crate::summary::{self, AssemblyInfo, Clock, PartitionInfo, Summary};
use serde::Serialize;

/// The solve's own summary section(s).
#[derive(Serialize)]
#[serde(untagged)]
enum SolveReport {
    Linear(LinearSummary),
    Contact(Box<ContactReport>),
}

/// The solve stage's product.
struct Solved {
    u: Vector,
    report: SolveReport,
    contact: Option<ContactResult>,
}

/// Runs a whole case. Returns summary.json's text (the same on every rank).
pub fn run_case(ctx: &Ctx, case: &Case) -> Result<String, RunError> {
    let mut clock = Clock::start();
    let Input { mesh, material } = setup::read_input(ctx, case)?;
    clock.t.read = clock.lap();
    let layout = partition::partition(ctx.world, ctx.comm(), &mesh, "ptscotch")?;
    clock.t.partition = clock.lap();
    let partition = log_partition(ctx, &mesh, &layout);
    let problem = setup::problem(case, &mesh, material);
    let mut sys = assembly::assemble(ctx.comm(), &layout, &problem)?;
    clock.t.assembly = clock.lap();
    let assembly = check_assembly(ctx, &sys, clock.t.assembly)?;
    let out = ResultSet::begin(ctx, &case.output.dir, &case.file)?;
    clock.lap();
    let solved = solve(ctx, case, &mesh, &layout, &problem.fixed, &mut sys)?;
    clock.t.solve = clock.lap();
    let cells = post::cell_fields(&mesh, &layout, &material, &solved.u, &case.output)?;
    let fields = post::solution_fields(&mesh, &layout, &solved.u, cells, &case.output)?;
    clock.t.post = clock.lap();
    let grid = solved
        .contact
        .as_ref()
        .filter(|_| case.output.wants(OutputField::Contact));
    clock.t.output = out.write_solution(ctx, &fields.piece(grid))?;
    let timings = clock.finish();
    let summary = Summary {
        case: case.file.display().to_string(),
        mesh: case.mesh.file.display().to_string(),
        dimension: mesh.dim,
        model: format!("{:?}", material.model),
        cells: mesh.n_cells(),
        nodes: mesh.n_nodes(),
        dofs: mesh.n_nodes() * mesh.dim,
        ranks: ctx.size,
        partition,
        assembly,
        peak_memory_bytes_per_rank: summary::peak_memory_and_log(ctx, &timings),
        timings,
        solve: solved.report,
    };
    let json = summary.to_json();
    let csv = solved.contact.as_ref().map(|c| c.csv.as_str());
    out.commit(ctx, &json, csv, timings.output)?;
    Ok(json)
}

/// One linear solve, or the contact algorithm.
fn solve(
    ctx: &Ctx,
    case: &Case,
    mesh: &Mesh,
    layout: &Layout,
    fixed: &[f64],
    sys: &mut System,
) -> Result<Solved, RunError> {
    match &case.contact {
        None => {
            let (u, report) = solver::linear_solve(ctx, mesh, layout, sys, &case.solver)?;
            Ok(Solved {
                u,
                report: SolveReport::Linear(report.summary(case.solver.preset)),
                contact: None,
            })
        }
        Some(cc) => {
            let settings =
                ctx.agree(setup::contact_settings(case, cc, mesh.dim).map_err(RunError::from))?;
            let s = signorini::solve(ctx, &settings, mesh, layout, fixed, sys, &case.solver, None)?;
            Ok(Solved {
                u: s.u,
                report: SolveReport::Contact(Box::new(s.report)),
                contact: Some(s.result),
            })
        }
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
    say!(ctx, "dofs: {}", mesh.n_nodes() * mesh.dim);
    info
}

/// The assembly line; a malloc during assembly means a wrong preallocation (a bug).
fn check_assembly(ctx: &Ctx, sys: &System, seconds: f64) -> Result<AssemblyInfo, RunError> {
    let info = AssemblyInfo {
        mallocs: ctx.sum_f64(sys.stats.mallocs),
        matrix_seconds_max: ctx.max_f64(sys.stats.matrix_seconds),
    };
    let nonzeros = ctx.sum_f64(sys.stats.nonzeros);
    say!(
        ctx,
        "assembly: {:.3} s (matrix {:.3} s, {} nonzeros, {} mallocs)",
        seconds,
        info.matrix_seconds_max,
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
