//! A private options database (PetscOptionsCreate): a linear solver's options held apart from
//! PETSc's global database, which the solver's set-up never writes.
//!
//! A KSP given this database (PetscObjectSetOptions) hands it to its PC (KSPGetPC), and a SNES
//! to its KSP (SNESGetKSP); but the objects PETSc creates inside a preconditioner's set-up read
//! the default database: the smoothers and the coarse solver of PCMG / PCGAMG (PCMGSetLevels
//! creates them without it) and the Galerkin products' matrices (`-matptap_via`, read by
//! MatProductSetFromOptions with no database). [`OptionsDb::scoped`] therefore makes the
//! private database PETSc's default (PetscOptionsPush) for the calls that set a solver up or
//! run it, and restores the global one after them (PetscOptionsPop).

use std::cell::{Cell, RefCell};
use std::collections::BTreeSet;
use std::ffi::{c_void, CStr};
use std::os::raw::{c_char, c_int};
use std::ptr;

use super::error::{check, cstring, own_error, Result};
use super::ffi;

/// An options database of its own. Not shared between threads.
pub struct OptionsDb {
    raw: ffi::PetscOptions,
    /// The names copied from the global database ([`OptionsDb::insert_global`]).
    copied: Vec<String>,
    /// The names whose use [`used_watched`] reports ([`OptionsDb::watch`]).
    watched: Vec<String>,
}

thread_local! {
    /// The database [`OptionsDb::scoped`] has made PETSc's default (null: the global one).
    static PUSHED: Cell<ffi::PetscOptions> = const { Cell::new(ptr::null_mut()) };
    /// The watched names that a dropped database had used ([`OptionsDb::watch`]).
    static USED: RefCell<BTreeSet<String>> = const { RefCell::new(BTreeSet::new()) };
}

/// Whether a database watching `name` ([`OptionsDb::watch`]) was dropped having used it
/// (some PETSc object or the project's own code read it). Local.
pub fn used_watched(name: &str) -> bool {
    USED.with(|u| u.borrow().contains(name))
}

/// Whether the global database's option `name` (with its '-') has been used: read by PETSc
/// at its start, or by a private database that copied it ([`OptionsDb::insert_global`]) and
/// has been dropped. Local.
pub fn used_global(name: &str) -> Result<bool> {
    let bare = cstring(name.trim_start_matches('-'));
    let mut used: ffi::PetscBool = ffi::PETSC_FALSE;
    // SAFETY: a query of the global database; writes one PetscBool.
    unsafe {
        check(ffi::PetscOptionsUsed(
            ptr::null_mut(),
            bare.as_ptr(),
            &mut used,
        ))?
    };
    Ok(used == ffi::PETSC_TRUE)
}

/// The names (with their '-') of the global database's options: the command line after
/// `--`, PETSC_OPTIONS and options files. Local; not while a private database is pushed.
pub fn global_names() -> Result<Vec<String>> {
    Ok(option_names(&OptionsDb::global_text()?))
}

/// The option names (tokens "-x" that are not numbers) of command-line text. Pure.
fn option_names(text: &str) -> Vec<String> {
    let is_name = |t: &&str| t.starts_with('-') && t[1..].starts_with(char::is_alphabetic);
    text.split_whitespace()
        .filter(is_name)
        .map(str::to_string)
        .collect()
}

impl OptionsDb {
    /// An empty database. Local.
    pub fn new() -> Result<OptionsDb> {
        let mut raw: ffi::PetscOptions = ptr::null_mut();
        // SAFETY: creates an object owned by the returned wrapper.
        unsafe { check(ffi::PetscOptionsCreate(&mut raw))? };
        Ok(OptionsDb {
            raw,
            copied: Vec::new(),
            watched: Vec::new(),
        })
    }

    pub(super) fn raw(&self) -> ffi::PetscOptions {
        self.raw
    }

    /// Sets `name` (with its leading '-') to `value` ("" for a flag), replacing an earlier
    /// value. Local.
    pub fn set(&self, name: &str, value: &str) -> Result<()> {
        let n = cstring(name);
        let v = cstring(value);
        // SAFETY: PETSc copies both strings.
        unsafe {
            check(ffi::PetscOptionsSetValue(
                self.raw,
                n.as_ptr(),
                if value.is_empty() {
                    ptr::null()
                } else {
                    v.as_ptr()
                },
            ))
        }
    }

    /// Inserts options given as PETSc's command-line text ("-a 1 -b"), replacing earlier
    /// values. Local.
    pub fn insert(&self, text: &str) -> Result<()> {
        let t = cstring(text);
        // SAFETY: PETSc copies what it keeps.
        unsafe { check(ffi::PetscOptionsInsertString(self.raw, t.as_ptr())) }
    }

    /// True when `name` is present. Local.
    pub fn has(&self, name: &str) -> Result<bool> {
        let n = cstring(name);
        let mut set: ffi::PetscBool = ffi::PETSC_FALSE;
        // SAFETY: writes one PetscBool.
        unsafe {
            check(ffi::PetscOptionsHasName(
                self.raw,
                ptr::null(),
                n.as_ptr(),
                &mut set,
            ))?;
        }
        Ok(set == ffi::PETSC_TRUE)
    }

    /// The value of `name` ("" for a flag), `None` when absent. Local.
    pub fn value(&self, name: &str) -> Result<Option<String>> {
        let n = cstring(name);
        let mut buf = vec![0 as c_char; 1024];
        let mut set: ffi::PetscBool = ffi::PETSC_FALSE;
        // SAFETY: PETSc writes at most `buf.len()` bytes, NUL-terminated.
        unsafe {
            check(ffi::PetscOptionsGetString(
                self.raw,
                ptr::null(),
                n.as_ptr(),
                buf.as_mut_ptr(),
                buf.len(),
                &mut set,
            ))?;
            if set != ffi::PETSC_TRUE {
                return Ok(None);
            }
            Ok(Some(
                CStr::from_ptr(buf.as_ptr()).to_string_lossy().into_owned(),
            ))
        }
    }

    /// Inserts the global database's options (the command line after `--`, PETSC_OPTIONS and
    /// the options files PETSc read at start), replacing earlier values. The ones this database
    /// uses count as used in the global one too (for `-options_left`) when it is dropped.
    /// Local.
    pub fn insert_global(&mut self) -> Result<()> {
        let text = Self::global_text()?;
        self.insert(&text)?;
        self.copied = option_names(&text);
        Ok(())
    }

    /// Watches `name` (with its '-'): when this database is dropped having used it,
    /// [`used_watched`] says so. Local.
    pub fn watch(&mut self, name: &str) {
        self.watched.push(name.to_string());
    }

    /// The global database's options as command-line text (PetscOptionsGetAll). Local.
    fn global_text() -> Result<String> {
        let mut text: *mut c_char = ptr::null_mut();
        // SAFETY: PETSc allocates the string (PetscMalloc); it is copied, then freed.
        unsafe {
            let pushed = PUSHED.with(|p| p.get());
            if !pushed.is_null() {
                // GetAll(NULL) reads the default database: the global one while none is pushed
                return Err(own_error(
                    "the global options read while another one is pushed",
                ));
            }
            check(ffi::PetscOptionsGetAll(ptr::null_mut(), &mut text))?;
            if text.is_null() {
                return Ok(String::new());
            }
            let out = CStr::from_ptr(text).to_string_lossy().into_owned();
            let mut p = text as *mut c_void;
            ffi::PetscFreeA(
                1,
                line!() as c_int,
                c"global_text".as_ptr(),
                c"src/petsc/optdb.rs".as_ptr(),
                &mut p as *mut *mut c_void as *mut c_void,
            );
            Ok(out)
        }
    }

    /// Runs `f` with this database as PETSc's default (PetscOptionsPush), the global one
    /// restored after it, also when `f` fails. Nested calls on the same database push once.
    /// Local.
    pub fn scoped<R>(&self, f: impl FnOnce() -> R) -> Result<R> {
        if PUSHED.with(|p| p.get()) == self.raw {
            return Ok(f());
        }
        // SAFETY: the database lives until its wrapper is dropped, after this call.
        let code = unsafe { ffi::PetscOptionsPush(self.raw) };
        if code != 0 {
            // (only a failed push is checked: a fault injected into a successful one would
            // leave it without its pop)
            check(code)?;
        }
        let before = PUSHED.with(|p| p.replace(self.raw));
        let out = f();
        PUSHED.with(|p| p.set(before));
        // SAFETY: pops the push above (pushes and pops nest with the Rust calls).
        unsafe { check(ffi::PetscOptionsPop())? };
        Ok(out)
    }
}

impl Drop for OptionsDb {
    fn drop(&mut self) {
        // SAFETY: queries of valid databases (a lookup marks the option used); then destroys
        // the database we own: no object that reads it outlives its owners (every KSP holding
        // it keeps the wrapper alive).
        unsafe {
            for name in &self.copied {
                // PetscOptionsUsed takes the name without its '-'
                let (n, bare) = (cstring(name), cstring(&name[1..]));
                let mut used: ffi::PetscBool = ffi::PETSC_FALSE;
                let mut set: ffi::PetscBool = ffi::PETSC_FALSE;
                ffi::PetscOptionsUsed(self.raw, bare.as_ptr(), &mut used);
                if used == ffi::PETSC_TRUE {
                    ffi::PetscOptionsHasName(ptr::null_mut(), ptr::null(), n.as_ptr(), &mut set);
                }
            }
            for name in &self.watched {
                let bare = cstring(name.trim_start_matches('-'));
                let mut used: ffi::PetscBool = ffi::PETSC_FALSE;
                ffi::PetscOptionsUsed(self.raw, bare.as_ptr(), &mut used);
                if used == ffi::PETSC_TRUE {
                    USED.with(|u| u.borrow_mut().insert(name.clone()));
                }
            }
            ffi::PetscOptionsDestroy(&mut self.raw);
        }
    }
}
