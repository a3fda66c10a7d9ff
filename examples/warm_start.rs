//! Two contact solves on one mesh and partition, the second warm-started from the first through
//! `signorini::solve(.., session, Some(first), None)` (friction then acts on the tangential
//! increment since the first solve). Used by tests/coulomb.rs.
//!
//! ```text
//! mpirun -n 2 target/release/examples/warm_start CASE [--set k=v]... [--then k=v]...
//! ```
//!
//! `--set` overrides apply to both solves, `--then` overrides to the second only (e.g. a larger
//! prescribed drag). Rank 0 prints one line `warm_start: {json}` with the Newton steps of both
//! solves, the first step's |u^1 − u^0| / |u^1| of the second, the total contact force of
//! both, and the second solution's contact nodes (id, u_t, λ_n, λ_t, active, slip) sorted by id.
//! Nothing is written to disk.

use mpi::Threading;
use serde_json::json;
use signorini_mpi::assembly;
use signorini_mpi::case::Case;
use signorini_mpi::error::RunError;
use signorini_mpi::par::Ctx;
use signorini_mpi::petsc::Petsc;
use signorini_mpi::setup;
use signorini_mpi::signorini::session::Session;
use signorini_mpi::signorini::{self, ContactSolution};
use std::path::PathBuf;

struct Args {
    case: PathBuf,
    both: Vec<String>,
    then: Vec<String>,
}

fn args() -> Args {
    let mut it = std::env::args().skip(1);
    let case = PathBuf::from(
        it.next()
            .expect("usage: warm_start CASE [--set k=v] [--then k=v]"),
    );
    let (mut both, mut then) = (Vec::new(), Vec::new());
    while let Some(a) = it.next() {
        let v = it.next().expect("a value after --set / --then");
        match a.as_str() {
            "--set" => both.push(v),
            "--then" => then.push(v),
            other => panic!("unknown argument {other}"),
        }
    }
    Args { case, both, then }
}

fn steps(s: &ContactSolution) -> usize {
    s.report.newton.steps
}

fn run(ctx: &Ctx, a: &Args) -> Result<serde_json::Value, RunError> {
    let load = |extra: &[String]| {
        let mut sets = a.both.clone();
        sets.extend_from_slice(extra);
        ctx.agree(Case::load(&a.case, &sets, None).map_err(RunError::from))
    };
    let first_case = load(&[])?;
    let second_case = load(&a.then)?;
    let input = setup::read_input(ctx, &first_case)?;
    let mesh = &input.mesh;
    let layout = &input.layout;
    // one session for both solves (the linear solver and the factorisation the first keeps):
    // the second case differs from the first in its loads only, the same stiffness
    let mut session: Option<Session> = None;
    let mut solve = |case: &Case, previous: Option<&ContactSolution>| {
        let problem = setup::problem(case, mesh, &input.material);
        let sys = assembly::assemble(ctx.comm(), layout, &problem)?;
        assert!(!case.contacts.is_empty(), "a contact case");
        let settings = ctx.agree(
            setup::contact_settings(case, &case.contacts, &input.material).map_err(RunError::from),
        )?;
        if session.is_none() {
            session = Some(Session::new(
                ctx,
                mesh,
                layout,
                &case.solver,
                &settings,
                &sys.a,
                None,
            )?);
        }
        let session = session.as_mut().expect("set up above");
        signorini::solve(
            ctx,
            &settings,
            mesh,
            layout,
            &problem.fixed,
            &sys,
            &case.solver,
            session,
            previous,
            None,
        )
    };
    let first = solve(&first_case, None)?;
    let second = solve(&second_case, Some(&first))?;
    let mut nodes: Vec<serde_json::Value> = Vec::new();
    // every contact node with its id (gathered in the report's table)
    let csv = &second.result.csv;
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    for l in lines {
        let row: serde_json::Map<String, serde_json::Value> = head
            .iter()
            .zip(l.split(','))
            .map(|(h, v)| {
                let val = v
                    .parse::<f64>()
                    .map(|x| json!(x))
                    .unwrap_or_else(|_| json!(v));
                (h.to_string(), val)
            })
            .collect();
        nodes.push(serde_json::Value::Object(row));
    }
    let du1 = second.report.newton.history.first().and_then(|h| h.du_rel);
    Ok(json!({
        "first_steps": steps(&first),
        "second_steps": steps(&second),
        "second_first_du_rel": du1,
        "second_changed": second.report.newton.history.iter().map(|h| h.changed).collect::<Vec<_>>(),
        "first_total_force": first.report.contact.total_force,
        "second_total_force": second.report.contact.total_force,
        "second_friction": second.report.contact.friction,
        "nodes": nodes,
    }))
}

fn main() {
    let a = args();
    let code = {
        let Some((universe, _)) = mpi::initialize_with_threading(Threading::Multiple) else {
            eprintln!("error: MPI could not be initialised");
            std::process::exit(1);
        };
        let world = universe.world();
        let petsc = Petsc::init(&[]).expect("PETSc");
        let ctx = Ctx::new(&world, &petsc);
        let code = match run(&ctx, &a) {
            Ok(v) => {
                if ctx.rank == 0 {
                    println!("warm_start: {v}");
                }
                0
            }
            Err(e) => {
                if ctx.rank == 0 {
                    eprintln!("error: {e}");
                }
                e.exit_code()
            }
        };
        drop(petsc);
        code
    };
    std::process::exit(code);
}
