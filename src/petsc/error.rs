//! PETSc error codes as Rust errors: PETSc's message and the Rust caller's location.

use std::ffi::{CStr, CString};
use std::fmt;
use std::os::raw::c_char;
use std::panic::Location;
use std::ptr;

use super::ffi;

/// A failed PETSc call: PETSc's own message plus where in our code it was called.
#[derive(Debug, Clone)]
pub struct PetscError {
    pub code: i32,
    pub message: String,
    pub location: String,
}

impl fmt::Display for PetscError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "PETSc error {} ({}) at {}",
            self.code, self.message, self.location
        )
    }
}

impl std::error::Error for PetscError {}

pub type Result<T> = std::result::Result<T, PetscError>;

/// Converts a PETSc return code into a `Result`, naming the Rust caller.
#[track_caller]
pub(super) fn check(code: ffi::PetscErrorCode) -> Result<()> {
    if let Some((m, kind)) = crate::fault::counted("petsc-call", crate::abort::world_rank) {
        match kind {
            crate::fault::Kind::Panic => panic!("{m}"),
            _ => return Err(own_error(m)),
        }
    }
    if code == 0 {
        return Ok(());
    }
    let loc = Location::caller();
    let mut text: *const c_char = ptr::null();
    // SAFETY: PetscErrorMessage writes a pointer to a static string (or leaves it null).
    let message = unsafe {
        ffi::PetscErrorMessage(code, &mut text, ptr::null_mut());
        if text.is_null() {
            String::from("unknown error")
        } else {
            CStr::from_ptr(text).to_string_lossy().into_owned()
        }
    };
    crate::abort::raised(&message);
    Err(PetscError {
        code,
        message,
        location: format!("{}:{}", loc.file(), loc.line()),
    })
}

/// PETSc's own text of the last error a PETSc call raised on this rank (what its SETERRQ
/// said, e.g. "Unknown KSP type given: nonsense"), trimmed; empty if there is none. Local.
pub fn last_detail() -> String {
    let mut specific: *mut c_char = ptr::null_mut();
    // SAFETY: PetscErrorMessage points `specific` at PETSc's static buffer of the last message.
    unsafe {
        ffi::PetscErrorMessage(0, ptr::null_mut(), &mut specific);
        if specific.is_null() {
            String::new()
        } else {
            CStr::from_ptr(specific)
                .to_string_lossy()
                .trim()
                .to_string()
        }
    }
}

/// An error raised by our own checks in this layer (not by a PETSc call), on this rank alone
/// until an agreement covers it ([`crate::abort::raised`]).
#[track_caller]
pub(super) fn own_error(message: impl Into<String>) -> PetscError {
    let e = agreed_error(message);
    crate::abort::raised(&e.message);
    e
}

/// A PETSc error raised on this rank alone (the test-only fault injection, `crate::fault`).
#[track_caller]
pub fn raised_error(message: impl Into<String>) -> PetscError {
    own_error(message)
}

/// An error that every rank has alike (after an agreement, or from MUMPS' INFOG, which is the
/// same on every rank).
#[track_caller]
pub(super) fn agreed_error(message: impl Into<String>) -> PetscError {
    let loc = Location::caller();
    PetscError {
        code: -1,
        message: message.into(),
        location: format!("{}:{}", loc.file(), loc.line()),
    }
}

pub(super) fn cstring(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).expect("no interior NUL after replace")
}
