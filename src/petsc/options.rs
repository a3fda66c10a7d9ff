//! The default options database: the global one (the command line), or the private one of a
//! solver while it is set up or run ([`super::optdb::OptionsDb::scoped`]).

use super::error::{check, cstring, Result};
use super::ffi;
use std::ptr;

/// True when the option is present in the database.
pub fn has(name: &str) -> Result<bool> {
    let n = cstring(name);
    let mut set: ffi::PetscBool = ffi::PETSC_FALSE;
    // SAFETY: writes one PetscBool.
    unsafe {
        check(ffi::PetscOptionsHasName(
            ptr::null_mut(),
            ptr::null(),
            n.as_ptr(),
            &mut set,
        ))?;
    }
    Ok(set == ffi::PETSC_TRUE)
}
