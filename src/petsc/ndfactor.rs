//! Direct solves by MUMPS with a nested-dissection order computed by the project: the matrix's
//! node graph gathered on rank 0 and ordered there by Scotch ([`nested_dissection`]), handed to
//! MUMPS as its elimination order (ICNTL(7) = 1, [`Factor`]). Debian's MUMPS has neither METIS
//! nor Scotch and falls back to PORD, whose orders cost several times the flops in 3D
//! (docs/ordering.md).
//!
//! [`install`] puts this factorisation behind a PETSc preconditioner (PCSHELL named
//! [`SHELL_NAME`]) so that every KSP of the project — the linear solve, the Newton steps, the
//! Krylov solves on an earlier step's factorisation that share the PC — uses it unchanged: the
//! shell's set-up analyses once per nonzero pattern and factorises the new values, its apply
//! gathers the vector on rank 0, solves there by MUMPS and scatters the solution back.

use std::ffi::c_void;
use std::ptr;
use std::time::Instant;

use super::mpi::{all_true, first_message, gather_u64, rank_of, say_root};
use super::mumps::{nested_dissection, Controls, Factor, FactorStats, Settings};
use super::shellpc::{code_of, context, drop_context, ERR_LIB};
use super::{agreed_error, check, cstring, ffi, own_error, Ksp, MPI_Comm, Matrix, Result};

/// The name of the preconditioner (PCShellSetName), by which [`is_ours`] knows it.
pub const SHELL_NAME: &str = "mumps with nested-dissection order";

/// The last factorisation's record, for the logs and summary.json.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct FactorRecord {
    #[serde(flatten)]
    pub stats: FactorStats,
    /// The node graph's gathering and Scotch's ordering, last analysis [s].
    pub ordering_seconds: f64,
    /// MUMPS' analysis (JOB = 1), last one [s].
    pub analysis_seconds: f64,
    /// The last numeric factorisation (JOB = 2) [s].
    pub factorisation_seconds: f64,
    /// Analyses so far (one per nonzero pattern).
    pub analyses: usize,
    /// Numeric factorisations so far.
    pub factorisations: usize,
}

/// A fill-reducing order of the dofs of `mat` (block size `dim`, every node's dofs together):
/// the node graph (the union of the patterns of a node's rows, without self-loops) gathered on
/// rank 0 of `comm` and ordered there by nested dissection. On rank 0 order[i] = position of
/// dof i; empty on the other ranks, and on rank 0 when Scotch fails or the graph exceeds MPI's
/// 32-bit counts (said on stdout; MUMPS then orders by itself). Collective: every rank takes
/// the same path.
pub fn dof_order(comm: MPI_Comm, mat: &Matrix, dim: usize) -> Result<Vec<usize>> {
    let perm = node_order(comm, mat, dim)?;
    let mut order = Vec::with_capacity(perm.len() * dim);
    if !perm.is_empty() {
        order.resize(perm.len() * dim, 0);
        for (v, &p) in perm.iter().enumerate() {
            for a in 0..dim {
                order[v * dim + a] = p * dim + a;
            }
        }
    }
    Ok(order)
}

/// The nested-dissection order of the nodes of `mat` (block size `dim`): on rank 0 perm[v] =
/// position of node v; empty elsewhere and when no order could be made. Collective.
pub fn node_order(comm: MPI_Comm, mat: &Matrix, dim: usize) -> Result<Vec<usize>> {
    let (lo, hi) = mat.ownership_range()?;
    let (mut deg, mut adj, mut nb): (Vec<u64>, Vec<u64>, Vec<u64>) = Default::default();
    let mut read = Ok(());
    for node in lo / dim..hi / dim {
        nb.clear();
        for a in 0..dim {
            read = read.and_then(|_| {
                mat.with_row(node * dim + a, |cols, _| {
                    nb.extend(cols.iter().map(|&c| c as u64 / dim as u64))
                })
            });
        }
        nb.sort_unstable();
        nb.dedup();
        nb.retain(|&v| v != node as u64);
        deg.push(nb.len() as u64);
        adj.extend_from_slice(&nb);
    }
    if let Some(m) = crate::fault::injected("nd-graph", rank_of(comm)? as usize) {
        read = Err(own_error(m));
    }
    // A failed read on one rank fails every rank (with its message), before any gathering.
    let local = read.as_ref().err().map(|e| e.message.clone());
    if let Some(m) = first_message(comm, local.as_deref())? {
        return Err(agreed_error(m));
    }
    let fits = adj.len() < i32::MAX as usize && hi % dim == 0 && lo % dim == 0;
    if !all_true(comm, fits)? {
        say_root(
            comm,
            "factorisation: no node graph (32-bit counts or block size); MUMPS orders",
        );
        return Ok(Vec::new());
    }
    let (Some(deg), Some(adj)) = (gather_u64(comm, &deg)?, gather_u64(comm, &adj)?) else {
        return Ok(Vec::new()); // not rank 0
    };
    let mut xadj = Vec::with_capacity(deg.len() + 1);
    xadj.push(0usize);
    for d in deg {
        xadj.push(xadj.last().expect("not empty") + d as usize);
    }
    let adj: Vec<usize> = adj.into_iter().map(|v| v as usize).collect();
    match nested_dissection(&xadj, &adj) {
        Ok(perm) => Ok(perm),
        Err(e) => {
            // rank 0's own fallback: MUMPS orders (the other ranks pass no order either way)
            crate::abort::handled();
            println!("factorisation: no nested-dissection order ({e}); MUMPS orders");
            Ok(Vec::new())
        }
    }
}

/// The shell's state (PCShellSetContext), owned by the PC and dropped by its destroy callback.
struct Shell {
    comm: MPI_Comm,
    dim: usize,
    symmetric: bool,
    /// MUMPS on rank 0 alone ([`Factor`]): the same bits on every run.
    one_process: bool,
    /// The user's MUMPS controls.
    controls: Controls,
    root: bool,
    factor: Option<Factor>,
    record: FactorRecord,
    /// VecScatterCreateToZero of the operator's layout, made at the first apply.
    scatter: ffi::VecScatter,
    seq: ffi::Vec,
    buf: Vec<f64>,
    /// The message of the last failure in a callback (PETSc only sees an error code).
    error: Option<String>,
}

impl Shell {
    /// Analysis when the pattern is new (on any rank), then the numeric factorisation.
    fn set_up(&mut self, pmat: ffi::Mat) -> Result<()> {
        // A non-owning view: the PC owns the matrix.
        let mat = std::mem::ManuallyDrop::new(Matrix {
            raw: pmat,
            _arrays: None,
        });
        let t = Instant::now();
        let refactorised = match self.factor.as_mut() {
            Some(f) => f.refactorise(&mat)?,
            None => false,
        };
        if !refactorised {
            self.factor = None; // collective drop (JOB = −2) on every rank alike
            let order = dof_order(self.comm, &mat, self.dim)?;
            self.record.ordering_seconds = t.elapsed().as_secs_f64();
            let (mut m, mut nn) = (0, 0);
            // SAFETY: valid matrix, two ints out.
            unsafe { check(ffi::MatGetSize(pmat, &mut m, &mut nn))? };
            let ta = Instant::now();
            let order = (!order.is_empty()).then_some(&order[..]);
            let mut f = Factor::analyse(
                self.comm,
                &mat,
                m as usize,
                order,
                self.symmetric,
                self.root,
                &Settings {
                    one_process: self.one_process,
                    controls: self.controls.clone(),
                },
            )?;
            self.record.analysis_seconds = ta.elapsed().as_secs_f64();
            self.record.analyses += 1;
            let tf = Instant::now();
            f.factorise()?;
            self.record.factorisation_seconds = tf.elapsed().as_secs_f64();
            self.factor = Some(f);
        } else {
            self.record.factorisation_seconds = t.elapsed().as_secs_f64();
        }
        self.record.factorisations += 1;
        self.record.stats = self.factor.as_ref().expect("factorised above").stats();
        Ok(())
    }

    /// y = A⁻¹ x through rank 0.
    fn apply(&mut self, x: ffi::Vec, y: ffi::Vec) -> Result<()> {
        // SAFETY: x, y are the PC's vectors; the scatter and the sequential vector are made
        // once from x's layout (the operator's, fixed for the PC's life) and destroyed with the
        // shell; the array of `seq` is read and written between Get/Restore only.
        unsafe {
            if self.scatter.is_null() {
                check(ffi::VecScatterCreateToZero(
                    x,
                    &mut self.scatter,
                    &mut self.seq,
                ))?;
            }
            let fwd = (ffi::INSERT_VALUES, ffi::SCATTER_FORWARD);
            check(ffi::VecScatterBegin(
                self.scatter,
                x,
                self.seq,
                fwd.0,
                fwd.1,
            ))?;
            check(ffi::VecScatterEnd(self.scatter, x, self.seq, fwd.0, fwd.1))?;
            let mut n = 0;
            check(ffi::VecGetLocalSize(self.seq, &mut n))?;
            let mut a: *mut f64 = ptr::null_mut();
            check(ffi::VecGetArray(self.seq, &mut a))?;
            // (off the host the sequential vector is empty and its array may be null)
            let seq: &mut [f64] = if n == 0 || a.is_null() {
                &mut []
            } else {
                std::slice::from_raw_parts_mut(a, n as usize)
            };
            self.buf.clear();
            self.buf.extend_from_slice(seq);
            let solved = match self.factor.as_mut() {
                Some(f) => f.solve(&mut self.buf),
                None => Err(own_error("apply before set-up")),
            };
            if solved.is_ok() && self.root {
                seq.copy_from_slice(&self.buf[..seq.len()]);
            }
            check(ffi::VecRestoreArray(self.seq, &mut a))?;
            solved?;
            let rev = (ffi::INSERT_VALUES, ffi::SCATTER_REVERSE);
            check(ffi::VecScatterBegin(
                self.scatter,
                self.seq,
                y,
                rev.0,
                rev.1,
            ))?;
            check(ffi::VecScatterEnd(self.scatter, self.seq, y, rev.0, rev.1))
        }
    }
}

impl Drop for Shell {
    fn drop(&mut self) {
        crate::abort::before_collective();
        // SAFETY: objects made by `apply` (or null: the destroy calls accept null handles).
        unsafe {
            ffi::VecScatterDestroy(&mut self.scatter);
            ffi::VecDestroy(&mut self.seq);
        }
    }
}

/// The shell's context.
///
/// # Safety
/// `pc` must be a PC made by [`install`] and not yet destroyed.
unsafe fn shell_of<'a>(pc: ffi::PC) -> Option<&'a mut Shell> {
    context::<Shell>(pc)
}

unsafe extern "C" fn shell_set_up(pc: ffi::PC) -> ffi::PetscErrorCode {
    let Some(shell) = shell_of(pc) else {
        return ERR_LIB;
    };
    let (mut amat, mut pmat): (ffi::Mat, ffi::Mat) = (ptr::null_mut(), ptr::null_mut());
    let got = check(ffi::PCGetOperators(pc, &mut amat, &mut pmat));
    let r = got.and_then(|_| shell.set_up(pmat));
    code_of(&mut shell.error, r)
}

unsafe extern "C" fn shell_apply(pc: ffi::PC, x: ffi::Vec, y: ffi::Vec) -> ffi::PetscErrorCode {
    let Some(shell) = shell_of(pc) else {
        return ERR_LIB;
    };
    let r = shell.apply(x, y);
    code_of(&mut shell.error, r)
}

unsafe extern "C" fn shell_destroy(pc: ffi::PC) -> ffi::PetscErrorCode {
    drop_context::<Shell>(pc)
}

/// The option (in the database) that puts the factorisation on rank 0 alone, repeatable bit for
/// bit ([`Factor`]; the case's `solver.repeatable`).
pub const ONE_PROCESS_OPTION: &str = "-ndfactor_one_process";

/// Makes the PC of `ksp` the MUMPS factorisation with the project's nested-dissection order
/// (LDLᵀ when `symmetric`, else LU) on matrices of block size `dim`; `one_process`: MUMPS on
/// rank 0 alone ([`Factor`]), with the user's MUMPS `controls`. Collective.
pub fn install(
    ksp: &Ksp,
    comm: MPI_Comm,
    dim: usize,
    symmetric: bool,
    one_process: bool,
    controls: &Controls,
) -> Result<()> {
    let shell = Box::new(Shell {
        comm,
        dim: dim.max(1),
        symmetric,
        one_process,
        controls: controls.clone(),
        root: rank_of(comm)? == 0,
        factor: None,
        record: FactorRecord::default(),
        scatter: ptr::null_mut(),
        seq: ptr::null_mut(),
        buf: Vec::new(),
        error: None,
    });
    let name = cstring(SHELL_NAME);
    // SAFETY: the PC takes the boxed shell as its context and frees it in its destroy
    // callback; PETSc copies the name.
    unsafe {
        let mut pc: ffi::PC = ptr::null_mut();
        check(ffi::KSPGetPC(ksp.raw, &mut pc))?;
        check(ffi::PCSetType(pc, ffi::PCSHELL.as_ptr() as *const _))?;
        let raw = Box::into_raw(shell);
        check(ffi::PCShellSetContext(pc, raw as *mut c_void))?;
        check(ffi::PCShellSetDestroy(pc, Some(shell_destroy)))?;
        check(ffi::PCShellSetSetUp(pc, Some(shell_set_up)))?;
        check(ffi::PCShellSetApply(pc, Some(shell_apply)))?;
        check(ffi::PCShellSetName(pc, name.as_ptr()))?;
    }
    Ok(())
}

/// After `set_from_options`, for a solver whose options ask for a MUMPS factorisation
/// (PCCHOLESKY or PCLU with the solver type "mumps") and no MUMPS ordering
/// (`-mat_mumps_icntl_7`): the PC of `ksp` becomes the shell of [`install`] with the operator
/// `mat`'s block size, `symmetric` (Cholesky), on rank 0 alone with `one_process`
/// ([`ONE_PROCESS_OPTION`]), with the user's MUMPS `controls`. Collective.
pub fn install_on(
    ksp: &Ksp,
    comm: MPI_Comm,
    mat: &Matrix,
    symmetric: bool,
    one_process: bool,
    controls: &Controls,
) -> Result<()> {
    let mut bs = 1;
    // SAFETY: reads the block size of a valid matrix.
    unsafe { check(ffi::MatGetBlockSize(mat.raw, &mut bs))? };
    install(
        ksp,
        comm,
        bs.max(1) as usize,
        symmetric,
        one_process,
        controls,
    )
}

/// For a PC of type "shell": `Some(symmetric)` when it is the shell of [`install`]. Local.
pub(super) fn kind(pc: ffi::PC) -> Result<Option<bool>> {
    // SAFETY: reads the shell's name (a PETSc-owned string); a shell with our name has a live
    // Shell as its context.
    unsafe {
        let mut name: *const std::os::raw::c_char = ptr::null();
        check(ffi::PCShellGetName(pc, &mut name))?;
        if name.is_null() || std::ffi::CStr::from_ptr(name).to_bytes() != SHELL_NAME.as_bytes() {
            return Ok(None);
        }
        Ok(shell_of(pc).map(|s| s.symmetric))
    }
}

/// The last factorisation's record of the shell of `ksp` and the message of its last failure
/// (taken), or `None` when the PC is not ours. Local.
pub fn record(ksp: &Ksp) -> Result<Option<(FactorRecord, Option<String>)>> {
    // SAFETY: the context is a live Shell when `kind` recognises the PC as ours.
    unsafe {
        let mut pc: ffi::PC = ptr::null_mut();
        check(ffi::KSPGetPC(ksp.raw, &mut pc))?;
        let mut t: *const std::os::raw::c_char = ptr::null();
        check(ffi::PCGetType(pc, &mut t))?;
        if t.is_null() || std::ffi::CStr::from_ptr(t).to_bytes() != b"shell" || kind(pc)?.is_none()
        {
            return Ok(None);
        }
        Ok(shell_of(pc).map(|s| (s.record, s.error.take())))
    }
}
