//! An operator written in Rust behind PETSc's MATSHELL: y = A x by the method of an
//! [`Operator`], which the matrix owns and drops with itself. Krylov solvers need nothing else
//! of their operator when the preconditioner is a shell too (shellpc.rs).

use super::error::{check, own_error, Result};
use super::ffi::{self, MPI_Comm};
use super::matrix::Matrix;
use super::shellpc::{code_of, ERR_LIB};
use super::vector::Vector;
use std::mem::ManuallyDrop;
use std::os::raw::c_void;
use std::ptr;

/// What a shell matrix does.
pub trait Operator {
    /// y = A x.
    fn mult(&mut self, x: &Vector, y: &mut Vector) -> Result<()>;
}

/// The matrix's context: the operator and the message of its last failure.
struct Shell {
    op: Box<dyn Operator>,
    error: Option<String>,
}

/// The shell's context.
///
/// # Safety
/// `mat` must be a live MATSHELL made by [`Matrix::shell`].
unsafe fn context<'a>(mat: ffi::Mat) -> Option<&'a mut Shell> {
    let mut p: *mut c_void = ptr::null_mut();
    if ffi::MatShellGetContext(mat, &mut p as *mut *mut c_void as *mut c_void) != 0 || p.is_null() {
        return None;
    }
    Some(&mut *(p as *mut Shell))
}

unsafe extern "C" fn shell_mult(mat: ffi::Mat, x: ffi::Vec, y: ffi::Vec) -> ffi::PetscErrorCode {
    let Some(shell) = context(mat) else {
        return ERR_LIB;
    };
    // Non-owning views: the vectors are the caller's.
    let xv = ManuallyDrop::new(Vector { raw: x });
    let mut yv = ManuallyDrop::new(Vector { raw: y });
    let r = shell.op.mult(&xv, &mut yv);
    code_of(&mut shell.error, r)
}

unsafe extern "C" fn shell_destroy(ctx: *mut c_void) -> ffi::PetscErrorCode {
    if !ctx.is_null() {
        drop(Box::from_raw(ctx as *mut Shell));
    }
    0
}

/// The message of the last failure of the shell operator of `ksp` (taken), if its operator is
/// one of this module's shells and it failed. Local.
pub(super) fn last_error(ksp: ffi::KSP) -> Option<String> {
    // SAFETY: the operator stays the KSP's; the view is not destroyed.
    unsafe {
        let mut a: ffi::Mat = ptr::null_mut();
        if ffi::KSPGetOperators(ksp, &mut a, ptr::null_mut()) != 0 || a.is_null() {
            return None;
        }
        ManuallyDrop::new(Matrix {
            raw: a,
            _arrays: None,
        })
        .shell_error()
    }
}

impl Matrix {
    /// A square matrix of `local` rows on this rank whose product is `op` (MATSHELL): for a
    /// Krylov solver's operator; it has no entries to factorise or to build AMG from.
    /// Collective.
    pub fn shell(comm: MPI_Comm, local: usize, op: Box<dyn Operator>) -> Result<Matrix> {
        let shell = Box::new(Shell { op, error: None });
        let n = local as ffi::PetscInt;
        let mut raw: ffi::Mat = ptr::null_mut();
        // SAFETY: the matrix takes the boxed shell as its context and frees it through the
        // context destroy callback; the wrapper destroys the matrix (also on a failure below).
        unsafe {
            let ctx = Box::into_raw(shell);
            let made = check(ffi::MatCreateShell(
                comm,
                n,
                n,
                ffi::PETSC_DETERMINE,
                ffi::PETSC_DETERMINE,
                ctx as *mut c_void,
                &mut raw,
            ));
            if let Err(e) = made {
                drop(Box::from_raw(ctx));
                return Err(e);
            }
            let out = Matrix { raw, _arrays: None };
            check(ffi::MatShellSetContextDestroy(raw, Some(shell_destroy)))?;
            let mult: unsafe extern "C" fn(ffi::Mat, ffi::Vec, ffi::Vec) -> ffi::PetscErrorCode =
                shell_mult;
            check(ffi::MatShellSetOperation(
                raw,
                ffi::MATOP_MULT,
                Some(std::mem::transmute::<
                    unsafe extern "C" fn(ffi::Mat, ffi::Vec, ffi::Vec) -> ffi::PetscErrorCode,
                    unsafe extern "C" fn(),
                >(mult)),
            ))?;
            Ok(out)
        }
    }

    /// The message of the last failure of this shell matrix's operator (taken); `None` for
    /// other matrices or where it did not fail. Local.
    pub fn shell_error(&self) -> Option<String> {
        // SAFETY: only a MATSHELL of ours has a Shell as its context.
        unsafe {
            let mut t: ffi::MatType = ptr::null();
            if ffi::MatGetType(self.raw, &mut t) != 0 || t.is_null() {
                return None;
            }
            if std::ffi::CStr::from_ptr(t).to_bytes() != b"shell" {
                return None;
            }
            context(self.raw).and_then(|s| s.error.take())
        }
    }

    /// A second handle on this matrix (PetscObjectReference): the matrix lives while either
    /// does. Only for matrices whose storage PETSc owns (not [`Matrix::from_split_csr`]'s).
    pub fn handle(&self) -> Result<Matrix> {
        if self._arrays.is_some() {
            return Err(own_error(
                "internal: a second handle on a matrix whose arrays the first one owns",
            ));
        }
        // SAFETY: a valid matrix; the new wrapper's MatDestroy drops the reference taken here.
        unsafe {
            check(ffi::PetscObjectReference(self.raw as ffi::PetscObject))?;
        }
        Ok(Matrix {
            raw: self.raw,
            _arrays: None,
        })
    }
}
