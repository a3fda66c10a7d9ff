//! `signorini-mpi CASE.toml [--set key=value]... [-o DIR] [-- PETSc options]`,
//! `signorini-mpi check CASE.toml [--set key=value]... [-o DIR]`,
//! `signorini-mpi convert MESH.msh MESH.h5`.

use clap::{Args, Parser, Subcommand};
use mpi::traits::*;
use mpi::Threading;
use signorini_mpi::case::Case;
use signorini_mpi::driver;
use signorini_mpi::error::RunError;
use signorini_mpi::par::Ctx;
use signorini_mpi::petsc::Petsc;
use std::path::{Path, PathBuf};

/// Static contact of linear-elastic bodies with rigid obstacles and with each other (semismooth Newton, MPI + PETSc).
#[derive(Parser, Debug)]
#[command(
    name = "signorini-mpi",
    version,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Without a subcommand: solve the case.
    #[command(flatten)]
    run: CaseArgs,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Read and check a case and its mesh and say what a run would do, without solving or
    /// writing anything.
    Check(CaseArgs),
    /// Convert an MSH mesh to an HDF5 mesh (+ .xdmf), serial.
    Convert {
        /// The Gmsh mesh (.msh).
        msh: PathBuf,
        /// The HDF5 mesh to write (.h5).
        h5: PathBuf,
    },
}

/// A case and its overrides.
#[derive(Args, Debug)]
struct CaseArgs {
    /// The case file (TOML).
    #[arg(required = true)]
    case: Option<PathBuf>,
    /// Override a case key, e.g. --set mesh.file=fine.msh --set newton.c=10 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Output directory (replaces output.dir).
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    output: Option<PathBuf>,
    /// PETSc options, after `--` (e.g. -- -ksp_monitor -log_view).
    #[arg(last = true, value_name = "PETSC_OPTIONS")]
    petsc: Vec<String>,
}

impl Cli {
    /// The case to solve or check (`true`: check); `None` for `convert`.
    fn job(&self) -> Option<(&CaseArgs, bool)> {
        match &self.command {
            None => Some((&self.run, false)),
            Some(Command::Check(args)) => Some((args, true)),
            Some(Command::Convert { .. }) => None,
        }
    }
}

/// Why `convert` cannot write `out` (the HDF5 mesh or its .xdmf) for the input `src`, if it
/// cannot: `out` is `src` itself (by another path or a link too), a directory, or in a
/// directory that is missing or not writable. Writes nothing that stays.
fn convert_target_fault(src: &Path, out: &Path) -> Option<String> {
    use std::os::unix::fs::MetadataExt;
    let same =
        |a: &std::fs::Metadata, b: &std::fs::Metadata| a.dev() == b.dev() && a.ino() == b.ino();
    if let (Ok(a), Ok(b)) = (std::fs::metadata(src), std::fs::metadata(out)) {
        if same(&a, &b) {
            return Some(format!(
                "{} is the input mesh {}: it would be overwritten; give another output file",
                out.display(),
                src.display()
            ));
        }
        if b.is_dir() {
            return Some(format!(
                "{} is a directory: give the HDF5 file to write, e.g. mesh.h5",
                out.display()
            ));
        }
    }
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        return Some(format!(
            "cannot write {}: {} is not an existing directory",
            out.display(),
            parent.display()
        ));
    }
    let probe = parent.join(format!(".signorini-probe-{}", std::process::id()));
    let writable = std::fs::File::create(&probe).and_then(|_| std::fs::remove_file(&probe));
    match writable {
        Ok(()) => None,
        Err(e) => Some(format!(
            "cannot write {}: {} is not writable ({e})",
            out.display(),
            parent.display()
        )),
    }
}

/// `signorini-mpi convert MESH.msh MESH.h5`: the MSH file as an HDF5 mesh (+ .xdmf), serial.
/// A bad input or output path is exit code 2, before anything is written.
fn convert(src: &Path, dst: &Path) -> i32 {
    let mesh = match signorini_mpi::mesh::read_msh(src) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let xdmf = dst.with_extension("xdmf");
    if xdmf == dst {
        eprintln!(
            "error: convert: {} ends in .xdmf, the name of the mesh's XDMF file written beside \
             it: give the HDF5 file to write, e.g. mesh.h5",
            dst.display()
        );
        return 2;
    }
    if let Some(why) = [dst, xdmf.as_path()]
        .iter()
        .find_map(|out| convert_target_fault(src, out))
    {
        eprintln!("error: convert: {why}");
        return 2;
    }
    match signorini_mpi::mesh::h5::write_h5(&mesh, dst) {
        Ok(()) => {
            println!(
                "{}: {}D, {} nodes, {} cells, {} groups (and {})",
                dst.display(),
                mesh.dim,
                mesh.n_nodes(),
                mesh.n_cells(),
                mesh.groups.len(),
                dst.with_extension("xdmf").display()
            );
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}

/// This process' rank as the MPI launcher tells it in the environment (before MPI is
/// initialised); `None` when not started by a launcher.
fn launcher_rank() -> Option<u32> {
    [
        "OMPI_COMM_WORLD_RANK",
        "PMIX_RANK",
        "PMI_RANK",
        "SLURM_PROCID",
    ]
    .iter()
    .find_map(|k| std::env::var(k).ok()?.parse().ok())
}

fn main() {
    // Under mpirun every rank parses the same command line: rank 0 alone prints its errors
    // (and --help, --version); every rank exits with clap's code (2 for an error) once rank 0
    // has printed. A rank that exits first makes mpirun end the job, and rank 0 may not have
    // written its message yet: under load, tests/output_guard.rs saw a run on 3 ranks end
    // with exit code 2 and no message.
    let cli = Cli::try_parse().unwrap_or_else(|e| {
        let launched = launcher_rank();
        if launched.unwrap_or(0) == 0 {
            let _ = e.print();
            let _ = std::io::Write::flush(&mut std::io::stdout());
        }
        if launched.is_some() {
            if let Some(universe) = mpi::initialize() {
                universe.world().barrier();
            }
        }
        std::process::exit(e.exit_code())
    });
    if let Some(Command::Convert { msh, h5 }) = &cli.command {
        std::process::exit(convert(msh, h5));
    }
    // Before anything loads MPI or PETSc state: OpenBLAS' kernels fit for this CPU.
    signorini_mpi::blas::restart_with_fitting_kernels();
    let Some((args, _)) = cli.job() else {
        unreachable!("convert returned above")
    };
    let code = {
        // MPI_THREAD_MULTIPLE where the MPI library grants it (Open MPI does): libraries that
        // run PT-Scotch with its default context (one thread per core, threads that call MPI
        // concurrently: PETSc's own ptscotch partitioner, MUMPS' parallel ordering) hang or
        // crash under MPI_THREAD_SINGLE. Our partitioner does not rely on it (it runs
        // PT-Scotch single-threaded, see petsc::scotch_partition).
        let Some((universe, _granted)) = mpi::initialize_with_threading(Threading::Multiple) else {
            eprintln!("error: MPI could not be initialised");
            std::process::exit(1);
        };
        let world = universe.world();
        // From here a panic on any rank ends every rank (no collective destructor runs on one
        // rank while the others wait).
        signorini_mpi::abort::install_panic_hook();
        // PETSc is initialised after MPI and finalised before the universe is dropped.
        match Petsc::init(&args.petsc) {
            Err(e) => {
                eprintln!("error: PETSc could not be initialised: {e}");
                world.abort(1);
            }
            Ok(petsc) => {
                let code = run(&cli, &world, &petsc);
                drop(petsc);
                code
            }
        }
    };
    std::process::exit(code);
}

fn run(cli: &Cli, world: &mpi::topology::SimpleCommunicator, petsc: &Petsc) -> i32 {
    let ctx = Ctx::new(world, petsc);
    let Some((args, check)) = cli.job() else {
        return 2;
    };
    let case_file = args.case.as_deref().expect("clap requires the case");
    let result = ctx
        .agree(Case::load(case_file, &args.set, args.output.as_deref()).map_err(RunError::from))
        .and_then(|case| {
            match check {
                false => driver::run_case(&ctx, &case).map(drop),
                true => driver::check_case(&ctx, &case),
            }
            .map_err(|e| case.locate(e))
        });
    match result {
        Ok(_) => 0,
        Err(e @ RunError::Petsc(_)) => {
            // A PETSc failure may be local to this rank: end every rank (PETSc's and MPI's
            // finalisations are collective).
            signorini_mpi::abort::end_every_rank(&e.to_string(), 1);
        }
        Err(e) if signorini_mpi::abort::pending().is_some() => {
            // a failure of this rank that no agreement covered
            signorini_mpi::abort::end_every_rank(&e.to_string(), e.exit_code());
        }
        // Agreed errors: every rank has the same one; rank 0 says it.
        Err(e) => {
            if ctx.rank == 0 {
                eprintln!("error: {e}");
            }
            e.exit_code()
        }
    }
}
