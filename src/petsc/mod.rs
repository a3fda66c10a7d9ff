//! The PETSc binding layer: the only module with `unsafe`.
//!
//! RAII wrappers for Vec / Mat / KSP / MatPartitioning / MatNullSpace, the options database,
//! and PETSc error codes turned into Rust errors that carry PETSc's message and the Rust
//! caller's location. Everything here is collective where the PETSc call is collective.

mod error;
pub mod ffi;
pub mod ksp;
pub mod lapack;
pub mod matrix;
mod mpi;
pub mod mumps;
pub mod ndfactor;
pub mod optdb;
pub mod options;
pub mod shellmat;
pub mod shellpc;
pub mod snes;
pub mod vector;

use std::ffi::{CStr, CString};
use std::os::raw::{c_char, c_int};
use std::ptr;

pub use ffi::{MPI_Comm, PInt};
pub use ksp::{Ksp, SolveInfo};
pub use matrix::{Csr, MatStats, Matrix};
pub use vector::Vector;

use error::{agreed_error, check, cstring, own_error};
pub use error::{last_detail, raised_error, PetscError, Result};

/// The PETSc library, initialised once per process after MPI (rsmpi) and finalised on drop,
/// before the rsmpi `Universe` is dropped. Owns the argv strings PETSc keeps pointers to.
pub struct Petsc {
    _args: Vec<CString>,
    _argv: Vec<*mut c_char>,
}

impl Petsc {
    /// `PetscInitialize` with PETSc's own command-line options (`-ksp_type gmres`, `-log_view`, ...).
    /// MPI must already be initialised (PETSc then leaves MPI_Finalize to rsmpi).
    pub fn init(petsc_args: &[String]) -> Result<Petsc> {
        let mut args: Vec<CString> = vec![cstring("signorini-mpi")];
        args.extend(petsc_args.iter().map(|a| cstring(a)));
        let mut argv: Vec<*mut c_char> = args.iter().map(|a| a.as_ptr() as *mut c_char).collect();
        argv.push(ptr::null_mut());
        let mut argc: c_int = args.len() as c_int;
        let mut argv_ptr = argv.as_mut_ptr();
        // SAFETY: argc/argv describe NUL-terminated strings that live in `self` until finalize.
        unsafe {
            check(ffi::PetscInitialize(
                &mut argc,
                &mut argv_ptr,
                ptr::null(),
                ptr::null(),
            ))?;
            // Errors come back to Rust as values; we print them ourselves.
            check(ffi::PetscPushErrorHandler(
                Some(ffi::PetscReturnErrorHandler),
                ptr::null_mut(),
            ))?;
            check(ffi::PetscMemorySetGetMaximumUsage())?;
        }
        Ok(Petsc {
            _args: args,
            _argv: argv,
        })
    }

    /// PETSC_COMM_WORLD (the same type and value as rsmpi's world communicator).
    pub fn comm(&self) -> MPI_Comm {
        // SAFETY: valid after PetscInitialize, which `self` proves.
        unsafe { ffi::PETSC_COMM_WORLD }
    }
}

impl Drop for Petsc {
    fn drop(&mut self) {
        // SAFETY: every PETSc object is dropped before this (they borrow nothing from here,
        // but the binary drops them first by construction).
        unsafe {
            ffi::PetscFinalize();
        }
    }
}

/// Partitions a distributed graph with PETSc's MatPartitioning (type from `ptype`;
/// `-mat_partitioning_type` overrides). This rank passes the adjacency of its rows
/// `[row_start, row_start + xadj.len() - 1)` in CSR form (global column indices, no
/// self-loops); the result is the target rank of each of these rows.
///
/// For PT-Scotch prefer [`scotch_partition`]: through PETSc, PT-Scotch runs with its default
/// context (one thread per core, non-deterministic message order), so the partition changes
/// from run to run.
pub fn partition_graph(
    comm: MPI_Comm,
    n_global: usize,
    xadj: &[PInt],
    adjncy: &[PInt],
    ptype: &str,
) -> Result<Vec<PInt>> {
    let n_local = xadj.len().saturating_sub(1);
    // SAFETY: the CSR arrays are copied into PETSc-allocated memory; MatCreateMPIAdj takes
    // ownership of them on success (MatDestroy frees them) and we free them on failure. The IS
    // is read and destroyed before returning.
    unsafe {
        let ia = petsc_malloc_copy(xadj)?;
        let ja = match petsc_malloc_copy(adjncy) {
            Ok(ja) => ja,
            Err(e) => {
                petsc_free(ia);
                return Err(e);
            }
        };
        // MatCreateMPIAdj's steps, one by one: the matrix takes ownership of ia/ja in the last
        // step of MatMPIAdjSetPreallocation (before an assembly that cannot fail for MPIADJ),
        // so on any failure the arrays are still ours to free.
        let mut adj: ffi::Mat = ptr::null_mut();
        let created = (|| {
            check(ffi::MatCreate(comm, &mut adj))?;
            check(ffi::MatSetSizes(
                adj,
                n_local as PInt,
                ffi::PETSC_DETERMINE,
                ffi::PETSC_DETERMINE,
                n_global as PInt,
            ))?;
            check(ffi::MatSetType(
                adj,
                ffi::MATMPIADJ.as_ptr() as *const c_char,
            ))?;
            check(ffi::MatMPIAdjSetPreallocation(adj, ia, ja, ptr::null_mut()))
        })();
        if let Err(e) = created {
            if !adj.is_null() {
                ffi::MatDestroy(&mut adj);
            }
            petsc_free(ia);
            petsc_free(ja);
            return Err(e);
        }
        let adj = Matrix {
            raw: adj,
            _arrays: None,
        };
        let mut part: ffi::MatPartitioning = ptr::null_mut();
        check(ffi::MatPartitioningCreate(comm, &mut part))?;
        let t = cstring(ptype);
        let result = (|| {
            check(ffi::MatPartitioningSetAdjacency(part, adj.raw))?;
            check(ffi::MatPartitioningSetType(part, t.as_ptr()))?;
            check(ffi::MatPartitioningSetFromOptions(part))?;
            let mut is: ffi::IS = ptr::null_mut();
            check(ffi::MatPartitioningApply(part, &mut is))?;
            let mut idx: *const PInt = ptr::null();
            check(ffi::ISGetIndices(is, &mut idx))?;
            let out = if n_local == 0 {
                Vec::new()
            } else {
                std::slice::from_raw_parts(idx, n_local).to_vec()
            };
            check(ffi::ISRestoreIndices(is, &mut idx))?;
            check(ffi::ISDestroy(&mut is))?;
            Ok(out)
        })();
        ffi::MatPartitioningDestroy(&mut part);
        drop(adj);
        result
    }
}

/// The seed of PT-Scotch's pseudo-random generator in [`scotch_partition`] (any fixed value).
const SCOTCH_SEED: ffi::SCOTCH_Num = 1;

/// Owned PT-Scotch / MPI objects, released in reverse order of creation on every path.
struct ScotchRun {
    comm: MPI_Comm,
    context: Option<Box<ffi::SCOTCH_Context>>,
    graph: Option<Box<ffi::SCOTCH_Dgraph>>,
    strat: Option<Box<ffi::SCOTCH_Strat>>,
}

impl Drop for ScotchRun {
    fn drop(&mut self) {
        crate::abort::before_collective();
        // SAFETY: each object is present only if its init call succeeded; the bound graph
        // container needs no exit of its own.
        unsafe {
            if let Some(s) = self.strat.as_mut() {
                ffi::SCOTCH_stratExit(&mut **s);
            }
            if let Some(g) = self.graph.as_mut() {
                ffi::SCOTCH_dgraphExit(&mut **g);
            }
            if let Some(c) = self.context.as_mut() {
                ffi::SCOTCH_contextExit(&mut **c);
            }
            if self.comm != ffi::RSMPI_COMM_NULL {
                ffi::MPI_Comm_free(&mut self.comm);
            }
        }
    }
}

/// A PT-Scotch return code as a `Result` (PT-Scotch prints its own message on stderr).
#[track_caller]
fn scotch_check(code: c_int, call: &str) -> Result<()> {
    if code == 0 {
        Ok(())
    } else {
        Err(own_error(format!(
            "PT-Scotch {call} failed with code {code}"
        )))
    }
}

/// Partitions a distributed graph into `n_parts` parts with PT-Scotch, called directly so that
/// it runs under an explicit context: one thread per rank, deterministic mode and a fixed
/// seed. The same graph on the same communicator size then gives the same partition on
/// every run, and PT-Scotch never calls MPI from two threads at once. (Debian's PT-Scotch is
/// built with SCOTCH_PTHREAD_MPI: under its default context, used through PETSc's
/// MatPartitioning, it folds graphs in two threads that both communicate; with MPI below
/// MPI_THREAD_MULTIPLE that hangs or crashes, and the thread count and the arrival order of
/// messages change the partition from run to run.)
///
/// This rank passes the rows `[row_start, row_start + xadj.len() - 1)` of a symmetric graph
/// without self-loops, in CSR form with global 0-based column indices; rows are distributed
/// in rank order. `weights`, if given, are the vertex weights of the local rows and the edge
/// weights in `adjncy`'s order (positive; the balance is then by vertex weight, the cut by edge
/// weight). `imbalance` is the allowed load imbalance (0.01 = 1 %). Returns the part of each
/// local row. Collective over `comm`; the graph is checked (`SCOTCH_dgraphCheck`)
/// before it is partitioned.
pub fn scotch_partition(
    comm: MPI_Comm,
    xadj: &[PInt],
    adjncy: &[PInt],
    weights: Option<(&[PInt], &[PInt])>,
    n_parts: usize,
    imbalance: f64,
) -> Result<Vec<PInt>> {
    // Declared before `run`: PT-Scotch keeps pointers into the arrays until the graph is freed.
    let mut arrays = ScotchArrays::new(xadj, adjncy, weights)?;
    let n_local = arrays.vert.len() - 1;
    let mut part: Vec<ffi::SCOTCH_Num> = vec![0; n_local.max(1)];
    let mut run = ScotchRun::new(comm)?;
    // SAFETY: `arrays` outlives `run` (dropped explicitly below, before `arrays`).
    unsafe { run.build_graph(&mut arrays)? };
    run.partition(n_parts, imbalance, &mut part)?;
    drop(run);
    part.truncate(n_local);
    Ok(part.into_iter().map(|p| p as PInt).collect())
}

/// PT-Scotch's private copies of a graph's CSR arrays and weights, in its index type (it takes
/// non-const pointers, does not write through them, and keeps them until the graph is freed).
struct ScotchArrays {
    vert: Vec<ffi::SCOTCH_Num>,
    edge: Vec<ffi::SCOTCH_Num>,
    velo: Vec<ffi::SCOTCH_Num>,
    edlo: Vec<ffi::SCOTCH_Num>,
    weighted: bool,
}

impl ScotchArrays {
    /// Checks the CSR arrays and the weights' lengths, and copies them.
    fn new(
        xadj: &[PInt],
        adjncy: &[PInt],
        weights: Option<(&[PInt], &[PInt])>,
    ) -> Result<ScotchArrays> {
        type Num = ffi::SCOTCH_Num;
        let n_local = xadj.len().saturating_sub(1);
        let n_edges = xadj.last().copied().unwrap_or(0) as usize;
        if xadj.is_empty() || xadj[0] != 0 || n_edges != adjncy.len() {
            return Err(own_error(format!(
                "scotch_partition: malformed CSR rows ({} offsets, {} edges, last offset {n_edges})",
                xadj.len(),
                adjncy.len()
            )));
        }
        if let Some((v, e)) = weights {
            if v.len() != n_local || e.len() != n_edges {
                return Err(own_error(format!(
                    "scotch_partition: {} vertex weights for {n_local} rows, {} edge weights for {n_edges} edges",
                    v.len(),
                    e.len()
                )));
            }
        }
        let copy = |x: &[PInt]| -> Vec<Num> {
            let mut v: Vec<Num> = x.iter().map(|&w| w as Num).collect();
            v.reserve(1); // a valid pointer even when empty
            v
        };
        let (velo, edlo) = match weights {
            Some((v, e)) => (copy(v), copy(e)),
            None => (copy(&[]), copy(&[])),
        };
        Ok(ScotchArrays {
            vert: copy(xadj),
            edge: copy(adjncy),
            velo,
            edlo,
            weighted: weights.is_some(),
        })
    }
}

impl ScotchRun {
    /// PT-Scotch's own communicator (its messages can never meet ours) and a context with one
    /// thread (no concurrent MPI calls inside PT-Scotch, no dependence on the core count),
    /// deterministic mode and a private generator with a fixed seed.
    fn new(comm: MPI_Comm) -> Result<ScotchRun> {
        let mut run = ScotchRun {
            // SAFETY: reads mpi-sys' constant for MPI_COMM_NULL.
            comm: unsafe { ffi::RSMPI_COMM_NULL },
            context: None,
            graph: None,
            strat: None,
        };
        // SAFETY: the context is boxed (PT-Scotch keeps a pointer to it), initialised before
        // use and released by `run`'s Drop.
        unsafe {
            let rc = ffi::MPI_Comm_dup(comm, &mut run.comm);
            if rc != 0 {
                run.comm = ffi::RSMPI_COMM_NULL;
                return Err(own_error(format!("MPI_Comm_dup failed with code {rc}")));
            }
            let mut context: Box<ffi::SCOTCH_Context> = Box::new(std::mem::zeroed());
            scotch_check(ffi::SCOTCH_contextInit(&mut *context), "SCOTCH_contextInit")?;
            let context = &mut **run.context.insert(context);
            scotch_check(
                ffi::SCOTCH_contextThreadSpawn(context, 1, ptr::null()),
                "SCOTCH_contextThreadSpawn",
            )?;
            scotch_check(
                ffi::SCOTCH_contextOptionSetNum(
                    context,
                    ffi::SCOTCH_OPTIONNUMDETERMINISTIC as c_int,
                    1,
                ),
                "SCOTCH_contextOptionSetNum(deterministic)",
            )?;
            scotch_check(
                ffi::SCOTCH_contextOptionSetNum(
                    context,
                    ffi::SCOTCH_OPTIONNUMRANDOMFIXEDSEED as c_int,
                    1,
                ),
                "SCOTCH_contextOptionSetNum(fixed seed)",
            )?;
            // A private generator with a fixed seed, independent of earlier PT-Scotch calls.
            scotch_check(
                ffi::SCOTCH_contextRandomClone(context),
                "SCOTCH_contextRandomClone",
            )?;
            ffi::SCOTCH_contextRandomSeed(context, SCOTCH_SEED);
        }
        Ok(run)
    }

    /// Builds the distributed graph on `a` and checks it (`SCOTCH_dgraphCheck`).
    ///
    /// # Safety
    /// `a` must outlive `self` and stay unchanged: PT-Scotch keeps pointers into it.
    unsafe fn build_graph(&mut self, a: &mut ScotchArrays) -> Result<()> {
        type Num = ffi::SCOTCH_Num;
        let n_local = (a.vert.len() - 1) as Num;
        let n_edges = a.edge.len() as Num;
        let weighted = a.weighted;
        let or_null = |v: &mut Vec<Num>| {
            if weighted {
                v.as_mut_ptr()
            } else {
                ptr::null_mut()
            }
        };
        let (velo, edlo) = (or_null(&mut a.velo), or_null(&mut a.edlo));
        let mut graph: Box<ffi::SCOTCH_Dgraph> = Box::new(std::mem::zeroed());
        scotch_check(
            ffi::SCOTCH_dgraphInit(&mut *graph, self.comm),
            "SCOTCH_dgraphInit",
        )?;
        let graph = &mut **self.graph.insert(graph);
        scotch_check(
            ffi::SCOTCH_dgraphBuild(
                graph,
                0,
                n_local,
                n_local,
                a.vert.as_mut_ptr(),
                a.vert.as_mut_ptr().add(1),
                velo,
                ptr::null_mut(),
                n_edges,
                n_edges,
                a.edge.as_mut_ptr(),
                ptr::null_mut(),
                edlo,
            ),
            "SCOTCH_dgraphBuild",
        )?;
        scotch_check(ffi::SCOTCH_dgraphCheck(graph), "SCOTCH_dgraphCheck")
    }

    /// Partitions the built graph under the context into `n_parts` parts: PETSc's
    /// MatPartitioning defaults (the default strategy) with the allowed `imbalance`.
    fn partition(
        &mut self,
        n_parts: usize,
        imbalance: f64,
        part: &mut [ffi::SCOTCH_Num],
    ) -> Result<()> {
        type Num = ffi::SCOTCH_Num;
        let (Some(context), Some(graph)) = (self.context.as_mut(), self.graph.as_ref()) else {
            return Err(own_error("scotch_partition: no context or graph"));
        };
        // SAFETY: context and graph are initialised (build_graph succeeded), the strategy is
        // boxed and released by Drop; `part` holds one entry per local vertex (at least one).
        unsafe {
            let mut bound: ffi::SCOTCH_Dgraph = std::mem::zeroed();
            scotch_check(
                ffi::SCOTCH_contextBindDgraph(&mut **context, &**graph, &mut bound),
                "SCOTCH_contextBindDgraph",
            )?;
            let mut strat: Box<ffi::SCOTCH_Strat> = Box::new(std::mem::zeroed());
            scotch_check(ffi::SCOTCH_stratInit(&mut *strat), "SCOTCH_stratInit")?;
            let strat = &mut **self.strat.insert(strat);
            let mut n_procs: c_int = 0;
            ffi::MPI_Comm_size(self.comm, &mut n_procs);
            scotch_check(
                ffi::SCOTCH_stratDgraphMapBuild(
                    strat,
                    ffi::SCOTCH_STRATDEFAULT as Num,
                    n_procs as Num,
                    n_parts as Num,
                    imbalance,
                ),
                "SCOTCH_stratDgraphMapBuild",
            )?;
            scotch_check(
                ffi::SCOTCH_dgraphPart(&mut bound, n_parts as Num, strat, part.as_mut_ptr()),
                "SCOTCH_dgraphPart",
            )
        }
    }
}

/// Frees memory from PetscMalloc that no PETSc object has taken over.
unsafe fn petsc_free(p: *mut PInt) {
    let mut p = p as *mut std::ffi::c_void;
    ffi::PetscFreeA(
        1,
        line!() as c_int,
        c"petsc_free".as_ptr(),
        c"src/petsc/mod.rs".as_ptr(),
        &mut p as *mut *mut std::ffi::c_void as *mut std::ffi::c_void,
    );
}

/// Copies a slice into memory from PetscMalloc (for objects that take ownership of arrays).
unsafe fn petsc_malloc_copy(src: &[PInt]) -> Result<*mut PInt> {
    let bytes = std::mem::size_of_val(src).max(std::mem::size_of::<PInt>());
    let mut p: *mut std::ffi::c_void = ptr::null_mut();
    check(ffi::PetscMallocA(
        1,
        ffi::PETSC_FALSE,
        line!() as c_int,
        c"petsc_malloc_copy".as_ptr(),
        c"src/petsc/mod.rs".as_ptr(),
        bytes,
        &mut p as *mut *mut std::ffi::c_void as *mut std::ffi::c_void,
    ))?;
    let dst = p as *mut PInt;
    ptr::copy_nonoverlapping(src.as_ptr(), dst, src.len());
    Ok(dst)
}
