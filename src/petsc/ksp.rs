//! A Krylov solver (KSP, with its preconditioner) reading its options from a private
//! database, and how a solve ended.

use super::error::{check, cstring, PetscError, Result};
use super::ffi::{self, MPI_Comm, PInt};
use super::matrix::Matrix;
use super::ndfactor;
use super::optdb::OptionsDb;
use super::shellmat;
use super::shellpc::{self, Preconditioner};
use super::vector::Vector;
use std::ffi::CStr;
use std::os::raw::c_char;
use std::ptr;
use std::rc::Rc;

/// A Krylov solver (with its preconditioner) reading its options from a private database.
pub struct Ksp {
    pub(super) raw: ffi::KSP,
    /// Kept alive while the KSP (and its PC, which may be shared) can read it.
    options: Rc<OptionsDb>,
}

/// How a linear solve ended.
#[derive(Clone, Debug)]
pub struct SolveInfo {
    pub iterations: usize,
    pub reason: i32,
    pub reason_name: String,
}

impl SolveInfo {
    pub fn converged(&self) -> bool {
        self.reason > 0
    }
}

impl Ksp {
    /// A KSP whose options (and its PC's) come from `options`, not the global database.
    pub fn new(comm: MPI_Comm, options: Rc<OptionsDb>) -> Result<Ksp> {
        let mut raw: ffi::KSP = ptr::null_mut();
        // SAFETY: creation of an owned KSP; the database outlives it (held in `options`).
        unsafe {
            check(ffi::KSPCreate(comm, &mut raw))?;
            let ksp = Ksp { raw, options };
            check(ffi::PetscObjectSetOptions(
                raw as ffi::PetscObject,
                ksp.options.raw(),
            ))?;
            Ok(ksp)
        }
    }

    /// The options database this KSP reads.
    pub fn options(&self) -> Rc<OptionsDb> {
        self.options.clone()
    }

    /// Operator and preconditioning matrix (the same here).
    pub fn set_operator(&mut self, a: &Matrix) -> Result<()> {
        // SAFETY: KSP takes a reference on the matrix.
        unsafe { check(ffi::KSPSetOperators(self.raw, a.raw, a.raw)) }
    }

    /// The operator `a` and the matrix `p` the preconditioner is built from.
    pub fn set_operators(&mut self, a: &Matrix, p: &Matrix) -> Result<()> {
        // SAFETY: KSP takes a reference on both matrices.
        unsafe { check(ffi::KSPSetOperators(self.raw, a.raw, p.raw)) }
    }

    /// Applies the KSP's options database (preset defaults, case file, command line).
    pub fn set_from_options(&mut self) -> Result<()> {
        // SAFETY: valid KSP.
        self.options
            .scoped(|| unsafe { check(ffi::KSPSetFromOptions(self.raw)) })?
    }

    /// Solves A x = b; returns iterations and PETSc's converged reason.
    pub fn solve(&mut self, b: &Vector, x: &mut Vector) -> Result<SolveInfo> {
        let mut its: PInt = 0;
        let mut reason: ffi::KSPConvergedReason = 0;
        let mut name: *const c_char = ptr::null();
        // SAFETY: valid objects; the reason name is a static string.
        unsafe {
            let raw = self.raw;
            self.options
                .scoped(|| check(ffi::KSPSolve(raw, b.raw, x.raw)))?
                .map_err(|e| self.explain(e))?;
            check(ffi::KSPGetIterationNumber(self.raw, &mut its))?;
            check(ffi::KSPGetConvergedReason(self.raw, &mut reason))?;
            check(ffi::KSPGetConvergedReasonString(self.raw, &mut name))?;
            let reason_name = if name.is_null() {
                String::new()
            } else {
                CStr::from_ptr(name).to_string_lossy().into_owned()
            };
            Ok(SolveInfo {
                iterations: its as usize,
                reason: reason as i32,
                reason_name,
            })
        }
    }

    /// KSPSetUp: builds the preconditioner for the current operator (for LU / Cholesky the
    /// numeric factorisation, after the symbolic one the first time) without solving.
    pub fn set_up(&mut self) -> Result<()> {
        // SAFETY: valid KSP with operators set.
        self.options
            .scoped(|| unsafe { check(ffi::KSPSetUp(self.raw)) })?
            .map_err(|e| self.explain(e))
    }

    /// A failure inside one of our preconditioners (MUMPS, a shell of shellpc.rs) reaches
    /// PETSc as an error code only: its message replaces PETSc's generic one.
    fn explain(&self, mut e: PetscError) -> PetscError {
        let ours = match ndfactor::record(self) {
            Ok(Some((_, Some(m)))) => Some(m),
            _ => shellpc::last_error(self.raw)
                .ok()
                .flatten()
                .or_else(|| shellmat::last_error(self.raw)),
        };
        if let Some(m) = ours {
            crate::abort::reworded(&m);
            e.message = m;
        }
        e
    }

    /// Makes this KSP's PC the shell named `name` that runs `pc` (shellpc.rs). Collective.
    pub fn set_shell_preconditioner(
        &mut self,
        name: &str,
        pc: Box<dyn Preconditioner>,
    ) -> Result<()> {
        shellpc::install(self.raw, name, pc)
    }

    /// The prefix of this KSP's options (call before `set_from_options`).
    pub fn set_options_prefix(&mut self, prefix: &str) -> Result<()> {
        let p = cstring(prefix);
        // SAFETY: PETSc copies the string.
        unsafe { check(ffi::KSPSetOptionsPrefix(self.raw, p.as_ptr())) }
    }

    /// Makes this KSP use `other`'s preconditioner object (KSPSetPC: shared and reference
    /// counted), so a factorisation made by one KSP is applied by the other.
    pub fn share_pc_of(&mut self, other: &Ksp) -> Result<()> {
        let mut pc: ffi::PC = ptr::null_mut();
        // SAFETY: both KSPs valid; KSPSetPC takes its own reference on the PC.
        unsafe {
            check(ffi::KSPGetPC(other.raw, &mut pc))?;
            check(ffi::KSPSetPC(self.raw, pc))
        }
    }

    /// KSPSetReusePreconditioner: with `true`, PCSetUp keeps the preconditioner it has even
    /// when the operator's values changed (PETSc tests this flag first in PCSetUp); with
    /// `false` a changed operator is set up anew (for a factorisation with the same nonzero
    /// pattern: the numeric part only). The flag lives in the PC, so a shared PC sees it.
    pub fn set_reuse_preconditioner(&mut self, reuse: bool) -> Result<()> {
        let flag = if reuse {
            ffi::PETSC_TRUE
        } else {
            ffi::PETSC_FALSE
        };
        // SAFETY: valid KSP.
        unsafe { check(ffi::KSPSetReusePreconditioner(self.raw, flag)) }
    }

    /// PCGAMGSetReuseInterpolation on this KSP's PC: with `false` the next set-up on a changed
    /// operator builds the aggregates and prolongators anew (PETSc's default keeps them and
    /// recomputes only the coarse operators). No effect on another PC type.
    pub fn set_gamg_reuse_interpolation(&mut self, reuse: bool) -> Result<()> {
        let flag = if reuse {
            ffi::PETSC_TRUE
        } else {
            ffi::PETSC_FALSE
        };
        let mut pc: ffi::PC = ptr::null_mut();
        // SAFETY: valid KSP; the PC is borrowed from it.
        unsafe {
            check(ffi::KSPGetPC(self.raw, &mut pc))?;
            check(ffi::PCGAMGSetReuseInterpolation(pc, flag))
        }
    }

    /// The maximum number of iterations; the other tolerances stay as they are.
    pub fn set_max_iterations(&mut self, max_it: usize) -> Result<()> {
        let d = ffi::PETSC_DEFAULT;
        // SAFETY: valid KSP; PETSC_DEFAULT leaves a tolerance unchanged.
        unsafe {
            check(ffi::KSPSetTolerances(
                self.raw,
                d as f64,
                d as f64,
                d as f64,
                max_it as PInt,
            ))
        }
    }

    /// KSPSetInitialGuessNonzero: with `true` the solve starts from the values in x (a warm
    /// start); the default convergence test then measures the residual against ‖b‖.
    pub fn set_initial_guess_nonzero(&mut self, nonzero: bool) -> Result<()> {
        let flag = if nonzero {
            ffi::PETSC_TRUE
        } else {
            ffi::PETSC_FALSE
        };
        // SAFETY: valid KSP.
        unsafe { check(ffi::KSPSetInitialGuessNonzero(self.raw, flag)) }
    }

    /// The relative tolerance and the maximum number of iterations (KSPGetTolerances).
    pub fn tolerances(&self) -> Result<(f64, usize)> {
        let (mut rtol, mut abstol, mut dtol, mut maxit) = (0.0, 0.0, 0.0, 0 as PInt);
        // SAFETY: valid KSP; outputs are plain values.
        unsafe {
            check(ffi::KSPGetTolerances(
                self.raw,
                &mut rtol,
                &mut abstol,
                &mut dtol,
                &mut maxit,
            ))?
        };
        Ok((rtol, maxit.max(0) as usize))
    }

    /// Sets the relative tolerance; the other tolerances stay as they are.
    pub fn set_rtol(&mut self, rtol: f64) -> Result<()> {
        let d = ffi::PETSC_DEFAULT;
        // SAFETY: valid KSP; PETSC_DEFAULT leaves a tolerance unchanged.
        unsafe {
            check(ffi::KSPSetTolerances(
                self.raw, rtol, d as f64, d as f64, d as PInt,
            ))
        }
    }

    /// The residual norm of the last iteration (KSPGetResidualNorm; for GMRES with right
    /// preconditioning the norm of b − A x).
    pub fn residual_norm(&self) -> Result<f64> {
        let mut r = 0.0;
        // SAFETY: valid KSP.
        unsafe { check(ffi::KSPGetResidualNorm(self.raw, &mut r))? };
        Ok(r)
    }

    /// The KSP and PC type names in use (after set_from_options).
    pub fn type_names(&self) -> Result<(String, String)> {
        let mut kt: *const c_char = ptr::null();
        let mut pt: *const c_char = ptr::null();
        let mut pc: ffi::PC = ptr::null_mut();
        // SAFETY: type names are PETSc-owned static strings.
        unsafe {
            check(ffi::KSPGetType(self.raw, &mut kt))?;
            check(ffi::KSPGetPC(self.raw, &mut pc))?;
            check(ffi::PCGetType(pc, &mut pt))?;
            let s = |p: *const c_char| {
                if p.is_null() {
                    String::new()
                } else {
                    CStr::from_ptr(p).to_string_lossy().into_owned()
                }
            };
            let pc_type = s(pt);
            if pc_type == "shell" {
                if let Some(sym) = ndfactor::kind(pc)? {
                    let t = if sym { "cholesky" } else { "lu" };
                    return Ok((s(kt), format!("{t}-mumps-nd")));
                }
            }
            Ok((s(kt), pc_type))
        }
    }
}

impl Drop for Ksp {
    fn drop(&mut self) {
        crate::abort::before_collective();
        // SAFETY: destroys the KSP we own.
        unsafe {
            ffi::KSPDestroy(&mut self.raw);
        }
    }
}
