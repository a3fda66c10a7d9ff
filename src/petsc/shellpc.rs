//! A preconditioner written in Rust behind PETSc's PCSHELL: its set-up and apply are the
//! methods of a [`Preconditioner`], which the PC owns and drops with itself.

use super::error::{check, cstring, Result};
use super::ffi;
use super::vector::Vector;
use std::mem::ManuallyDrop;
use std::os::raw::c_void;
use std::ptr;

/// What a shell preconditioner does.
pub trait Preconditioner {
    /// Builds the preconditioner for the KSP's current operators (PCSetUp).
    fn set_up(&mut self) -> Result<()>;
    /// y = P⁻¹ x.
    fn apply(&mut self, x: &Vector, y: &mut Vector) -> Result<()>;
}

/// The PC's context: the preconditioner and the message of its last failure (PETSc sees an
/// error code only).
struct Shell {
    pc: Box<dyn Preconditioner>,
    error: Option<String>,
}

/// PETSC_ERR_LIB: the code a shell's callback returns on a failure (its message kept in the
/// shell's context). Also the MUMPS shell's (ndfactor.rs).
pub(super) const ERR_LIB: ffi::PetscErrorCode = 76;

/// A shell's context, as the `T` it was installed with.
///
/// # Safety
/// `pc` must be a live PCSHELL whose context is a boxed `T` (or null).
pub(super) unsafe fn context<'a, T>(pc: ffi::PC) -> Option<&'a mut T> {
    let mut p: *mut c_void = ptr::null_mut();
    if ffi::PCShellGetContext(pc, &mut p as *mut *mut c_void as *mut c_void) != 0 || p.is_null() {
        return None;
    }
    Some(&mut *(p as *mut T))
}

/// Drops a shell's boxed `T` context and detaches it (a destroy callback's work).
///
/// # Safety
/// As [`context`]; the context is not used afterwards.
pub(super) unsafe fn drop_context<T>(pc: ffi::PC) -> ffi::PetscErrorCode {
    let mut p: *mut c_void = ptr::null_mut();
    if ffi::PCShellGetContext(pc, &mut p as *mut *mut c_void as *mut c_void) == 0 && !p.is_null() {
        drop(Box::from_raw(p as *mut T));
        ffi::PCShellSetContext(pc, ptr::null_mut());
    }
    0
}

/// A callback's result as PETSc's error code, its message kept in `error`.
pub(super) fn code_of(error: &mut Option<String>, r: Result<()>) -> ffi::PetscErrorCode {
    match r {
        Ok(()) => 0,
        Err(e) => {
            *error = Some(e.message);
            ERR_LIB
        }
    }
}

unsafe extern "C" fn shell_set_up(pc: ffi::PC) -> ffi::PetscErrorCode {
    let Some(shell) = context::<Shell>(pc) else {
        return ERR_LIB;
    };
    let r = shell.pc.set_up();
    code_of(&mut shell.error, r)
}

unsafe extern "C" fn shell_apply(pc: ffi::PC, x: ffi::Vec, y: ffi::Vec) -> ffi::PetscErrorCode {
    let Some(shell) = context::<Shell>(pc) else {
        return ERR_LIB;
    };
    // Non-owning views: the PC's vectors are PETSc's.
    let xv = ManuallyDrop::new(Vector { raw: x });
    let mut yv = ManuallyDrop::new(Vector { raw: y });
    let r = shell.pc.apply(&xv, &mut yv);
    code_of(&mut shell.error, r)
}

unsafe extern "C" fn shell_destroy(pc: ffi::PC) -> ffi::PetscErrorCode {
    drop_context::<Shell>(pc)
}

/// The prefix of every name this module gives its shells (PCShellSetName): how
/// [`last_error`] tells them from other shells (ndfactor.rs), whose contexts are of another type.
const NAME_PREFIX: &str = "rust: ";

/// Makes the PC of `ksp` the shell named `name` (after [`NAME_PREFIX`]) that runs `pc`
/// (`Ksp::set_shell_preconditioner`). Collective.
pub(super) fn install(ksp: ffi::KSP, name: &str, pc: Box<dyn Preconditioner>) -> Result<()> {
    let shell = Box::new(Shell { pc, error: None });
    let name = cstring(&format!("{NAME_PREFIX}{name}"));
    // SAFETY: the PC takes the boxed shell as its context and frees it in its destroy
    // callback; PETSc copies the name.
    unsafe {
        let mut raw_pc: ffi::PC = ptr::null_mut();
        check(ffi::KSPGetPC(ksp, &mut raw_pc))?;
        check(ffi::PCSetType(raw_pc, ffi::PCSHELL.as_ptr() as *const _))?;
        let raw = Box::into_raw(shell);
        check(ffi::PCShellSetContext(raw_pc, raw as *mut c_void))?;
        check(ffi::PCShellSetDestroy(raw_pc, Some(shell_destroy)))?;
        check(ffi::PCShellSetSetUp(raw_pc, Some(shell_set_up)))?;
        check(ffi::PCShellSetApply(raw_pc, Some(shell_apply)))?;
        check(ffi::PCShellSetName(raw_pc, name.as_ptr()))?;
    }
    Ok(())
}

/// The message of the last failure of the shell of `ksp` (taken), if its PC is one of this
/// module's shells and it failed. Local.
pub(super) fn last_error(ksp: ffi::KSP) -> Result<Option<String>> {
    // SAFETY: a shell whose name has our prefix has a live Shell as its context.
    unsafe {
        let mut pc: ffi::PC = ptr::null_mut();
        check(ffi::KSPGetPC(ksp, &mut pc))?;
        let mut t: *const std::os::raw::c_char = ptr::null();
        check(ffi::PCGetType(pc, &mut t))?;
        if t.is_null() || std::ffi::CStr::from_ptr(t).to_bytes() != b"shell" {
            return Ok(None);
        }
        let mut n: *const std::os::raw::c_char = ptr::null();
        check(ffi::PCShellGetName(pc, &mut n))?;
        if n.is_null()
            || !std::ffi::CStr::from_ptr(n)
                .to_bytes()
                .starts_with(NAME_PREFIX.as_bytes())
        {
            return Ok(None);
        }
        Ok(context::<Shell>(pc).and_then(|s| s.error.take()))
    }
}
