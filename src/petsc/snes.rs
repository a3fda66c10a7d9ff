//! PETSc's SNES variational-inequality solvers (`vinewtonrsls`, `vinewtonssls`) on a *linear*
//! residual F(x) = A x − b with a constant Jacobian A, plus the few matrix operations the
//! frame rotation of src/snesvi.rs needs (PᵀAP, Aᵀx, symmetric row/column elimination).
//!
//! The SNES object lives only inside [`solve_linear_vi`]: the residual callback reads A and b
//! through a context on that function's stack, so nothing can outlive what it points to.

use super::*;
use std::ffi::c_void;

/// PETSc's "no bound" value (PETSC_INFINITY = PETSC_MAX_REAL / 4, petscmath.h); SNES VI treats
/// exactly this value (and its negative) as an absent bound.
pub const INFINITY: f64 = f64::MAX / 4.0;

/// How a SNES VI solve ended.
#[derive(Clone, Debug)]
pub struct ViInfo {
    /// Nonlinear (SNES) iterations.
    pub iterations: usize,
    /// Linear (KSP) iterations summed over all SNES iterations.
    pub linear_iterations: usize,
    /// Residual evaluations (line search included).
    pub function_evals: usize,
    /// SNESConvergedReason: > 0 converged, < 0 diverged.
    pub reason: i32,
    pub reason_name: String,
    /// The SNES type actually used (after the options database).
    pub snes_type: String,
    /// Norm of the residual on the inactive set at the end (what SNES VI tests).
    pub fnorm: f64,
}

impl ViInfo {
    pub fn converged(&self) -> bool {
        self.reason > 0
    }
}

/// What the residual callback reads: the matrix and right-hand side of F(x) = A x − b.
struct LinearResidual {
    a: ffi::Mat,
    b: ffi::Vec,
}

/// F(x) = A x − b (SNES residual callback).
unsafe extern "C" fn linear_residual(
    _snes: ffi::SNES,
    x: ffi::Vec,
    f: ffi::Vec,
    ctx: *mut c_void,
) -> ffi::PetscErrorCode {
    // SAFETY: ctx is the `LinearResidual` that `solve_linear_vi` passed to SNESSetFunction and
    // keeps alive on its stack until after SNESDestroy; x and f are valid vectors from SNES.
    unsafe {
        let r = &*(ctx as *const LinearResidual);
        let code = ffi::MatMult(r.a, x, f);
        if code != 0 {
            return code;
        }
        ffi::VecAXPY(f, -1.0, r.b)
    }
}

/// The Jacobian is the constant matrix given to SNESSetJacobian: nothing to recompute.
unsafe extern "C" fn constant_jacobian(
    _snes: ffi::SNES,
    _x: ffi::Vec,
    _j: ffi::Mat,
    _p: ffi::Mat,
    _ctx: *mut c_void,
) -> ffi::PetscErrorCode {
    0
}

/// J = A again (SNES Jacobian callback): `vinewtonssls` overwrites its Jacobian matrix with
/// D_a + D_b J in place, so a constant Jacobian must be restored before every step.
unsafe extern "C" fn restored_jacobian(
    _snes: ffi::SNES,
    _x: ffi::Vec,
    j: ffi::Mat,
    _p: ffi::Mat,
    ctx: *mut c_void,
) -> ffi::PetscErrorCode {
    // SAFETY: ctx is the `LinearResidual` of `solve_linear_vi` (alive until SNESDestroy); j is
    // the duplicate of its A given to SNESSetJacobian, so the patterns are the same.
    unsafe {
        let r = &*(ctx as *const LinearResidual);
        ffi::MatCopy(r.a, j, ffi::SAME_NONZERO_PATTERN)
    }
}

fn c_str(p: *const c_char) -> String {
    if p.is_null() {
        String::new()
    } else {
        // SAFETY: a non-null pointer from PETSc to a NUL-terminated static string.
        unsafe { CStr::from_ptr(p).to_string_lossy().into_owned() }
    }
}

/// The solver choice and default tolerances of [`solve_linear_vi`]; the options database
/// overrides each of them.
#[derive(Clone, Copy, Debug)]
pub struct ViSettings<'a> {
    /// SNES type, e.g. "vinewtonrsls" (`-snes_type` overrides).
    pub default_type: &'a str,
    /// Line search used with `default_type` unless `-snes_linesearch_type` is given (e.g.
    /// "basic"); another type keeps PETSc's own.
    pub default_linesearch: Option<&'a str>,
    /// Relative tolerance on the inactive-set residual (`-snes_rtol` overrides).
    pub rtol: f64,
    /// Iteration cap (`-snes_max_it` overrides).
    pub max_it: usize,
}

/// Solves the box-constrained linear VI  lower ≤ x ≤ upper,  F(x) = A x − b ⟂ bounds  with SNES
/// (type `settings.default_type`; `-snes_type` and the other `-snes_*`, `-ksp_*`, `-pc_*`
/// options of the database override; see [`ViSettings`]). `x` holds the initial guess (SNES
/// projects it onto the bounds) and receives the solution. Collective on `comm`.
pub fn solve_linear_vi(
    comm: MPI_Comm,
    a: &Matrix,
    b: &Vector,
    lower: &Vector,
    upper: &Vector,
    x: &mut Vector,
    settings: &ViSettings,
) -> Result<ViInfo> {
    let ctx = LinearResidual { a: a.raw, b: b.raw };
    let f = b.duplicate()?;
    let ty = cstring(settings.default_type);
    let mut snes: ffi::SNES = ptr::null_mut();
    // SAFETY: `snes` is created and destroyed here; `ctx`, `a`, `b`, `f`, `lower`, `upper` and
    // `x` outlive it (SNESDestroy runs before they are dropped; SNES takes its own references
    // on A, f and the bound vectors). The callbacks match PETSc's signatures.
    unsafe {
        check(ffi::SNESCreate(comm, &mut snes))?;
        let result = (|| {
            check(ffi::SNESSetType(snes, ty.as_ptr()))?;
            check(ffi::SNESSetFunction(
                snes,
                f.raw,
                Some(linear_residual),
                &ctx as *const LinearResidual as *mut c_void,
            ))?;
            check(ffi::SNESSetJacobian(
                snes,
                a.raw,
                a.raw,
                Some(constant_jacobian),
                ptr::null_mut(),
            ))?;
            check(ffi::SNESVISetVariableBounds(snes, lower.raw, upper.raw))?;
            let chosen = configure(snes, settings)?;
            // Only the reduced-space method leaves the Jacobian matrix alone; the others get
            // their own copy, restored from A before every step.
            let _jac_copy = if chosen != "vinewtonrsls" {
                cholesky_to_lu(snes)?;
                Some(restored_jacobian_copy(snes, a, &ctx)?)
            } else {
                None
            };
            check(ffi::SNESSolve(snes, ptr::null_mut(), x.raw))?;
            vi_info(snes)
        })();
        ffi::SNESDestroy(&mut snes);
        result
    }
}

/// Tolerances and line search of `snes` from `settings` and the options database (which may
/// also change the type); returns the SNES type chosen.
///
/// # Safety
/// `snes` is a valid SNES object.
unsafe fn configure(snes: ffi::SNES, settings: &ViSettings) -> Result<String> {
    // SAFETY: `snes` is valid (caller); the strings outlive the calls that read them.
    unsafe {
        // no absolute tolerance: PETSc's default 1e-50 is a residual in the case's unit of
        // force (crate::linsolve's iterative preset has none either)
        check(ffi::SNESSetTolerances(
            snes,
            0.0,
            settings.rtol,
            ffi::PETSC_DEFAULT as f64,
            settings.max_it as PInt,
            ffi::PETSC_DEFAULT as PInt,
        ))?;
        check(ffi::SNESSetFromOptions(snes))?;
        let mut tname: *const c_char = ptr::null();
        check(ffi::SNESGetType(snes, &mut tname))?;
        let chosen = c_str(tname);
        if let Some(ls_type) = settings.default_linesearch {
            if chosen == settings.default_type && !options::has("-snes_linesearch_type")? {
                let lt = cstring(ls_type);
                let mut ls: ffi::SNESLineSearch = ptr::null_mut();
                check(ffi::SNESGetLineSearch(snes, &mut ls))?;
                check(ffi::SNESLineSearchSetType(ls, lt.as_ptr()))?;
            }
        }
        Ok(chosen)
    }
}

/// The semismooth Jacobian D_a + D_b A is not symmetric: a Cholesky preset (symmetric
/// systems) becomes LU with the same factorisation package.
///
/// # Safety
/// `snes` is a valid SNES object.
unsafe fn cholesky_to_lu(snes: ffi::SNES) -> Result<()> {
    // SAFETY: `snes` is valid (caller); KSP and PC are its own; the package name outlives
    // PCFactorSetMatSolverType.
    unsafe {
        let mut ksp: ffi::KSP = ptr::null_mut();
        let mut pc: ffi::PC = ptr::null_mut();
        let mut pt: *const c_char = ptr::null();
        check(ffi::SNESGetKSP(snes, &mut ksp))?;
        check(ffi::KSPGetPC(ksp, &mut pc))?;
        check(ffi::PCGetType(pc, &mut pt))?;
        if c_str(pt) == "cholesky" {
            // (PCSetFromOptions would read -pc_type cholesky again: copy the package.)
            let mut st: *const c_char = ptr::null();
            check(ffi::PCFactorGetMatSolverType(pc, &mut st))?;
            let package = cstring(&c_str(st));
            check(ffi::PCSetType(pc, ffi::PCLU.as_ptr() as *const c_char))?;
            if !st.is_null() {
                check(ffi::PCFactorSetMatSolverType(pc, package.as_ptr()))?;
            }
        }
        Ok(())
    }
}

/// A copy of A as the Jacobian matrix of `snes`, restored from A before every step
/// ([`restored_jacobian`]). The caller keeps the copy alive while `snes` is used.
///
/// # Safety
/// `snes` is a valid SNES object; `ctx` outlives it.
unsafe fn restored_jacobian_copy(
    snes: ffi::SNES,
    a: &Matrix,
    ctx: &LinearResidual,
) -> Result<Matrix> {
    let j = a.duplicate()?;
    // SAFETY: `snes` is valid and `ctx` outlives it (caller); SNES references `j` itself.
    unsafe {
        check(ffi::SNESSetJacobian(
            snes,
            j.raw,
            j.raw,
            Some(restored_jacobian),
            ctx as *const LinearResidual as *mut c_void,
        ))?;
    }
    Ok(j)
}

/// How the solve of `snes` ended.
///
/// # Safety
/// `snes` is a valid SNES object after SNESSolve.
unsafe fn vi_info(snes: ffi::SNES) -> Result<ViInfo> {
    let (mut its, mut lits, mut nf): (PInt, PInt, PInt) = (0, 0, 0);
    let mut reason: ffi::SNESConvergedReason = 0;
    let mut name: *const c_char = ptr::null();
    let mut tname: *const c_char = ptr::null();
    let mut fnorm: ffi::PetscReal = 0.0;
    // SAFETY: `snes` is valid (caller); every call writes one value of the given type.
    unsafe {
        check(ffi::SNESGetIterationNumber(snes, &mut its))?;
        check(ffi::SNESGetLinearSolveIterations(snes, &mut lits))?;
        check(ffi::SNESGetNumberFunctionEvals(snes, &mut nf))?;
        check(ffi::SNESGetConvergedReason(snes, &mut reason))?;
        check(ffi::SNESGetConvergedReasonString(snes, &mut name))?;
        check(ffi::SNESGetType(snes, &mut tname))?;
        check(ffi::SNESGetFunctionNorm(snes, &mut fnorm))?;
    }
    Ok(ViInfo {
        iterations: its as usize,
        linear_iterations: lits as usize,
        function_evals: nf as usize,
        reason: reason as i32,
        reason_name: c_str(name),
        snes_type: c_str(tname),
        fnorm,
    })
}

impl Matrix {
    /// C = Pᵀ A P (MatPtAP, a new matrix). Collective.
    pub fn ptap(&self, p: &Matrix) -> Result<Matrix> {
        let mut c: ffi::Mat = ptr::null_mut();
        // SAFETY: both matrices are assembled; the product is a new matrix we own.
        unsafe {
            check(ffi::MatPtAP(
                self.raw,
                p.raw,
                ffi::MAT_INITIAL_MATRIX,
                ffi::PETSC_DEFAULT as f64,
                &mut c,
            ))?;
        }
        Ok(Matrix {
            raw: c,
            _arrays: None,
        })
    }

    /// C = Pᵀ A P by the all-at-once algorithm (MatProduct PtAP "allatonce", MPI matrices
    /// only): no intermediate A P is stored, so the product's peak memory stays near C's own.
    /// Collective.
    pub fn ptap_all_at_once(&self, p: &Matrix) -> Result<Matrix> {
        let mut c: ffi::Mat = ptr::null_mut();
        let algorithm = super::error::cstring("allatonce");
        // SAFETY: both matrices are assembled; the product is a new matrix we own (destroyed
        // with the wrapper, also when a later call fails); PETSc copies the algorithm's name.
        unsafe {
            check(ffi::MatProductCreate(
                self.raw,
                p.raw,
                ptr::null_mut(),
                &mut c,
            ))?;
            let out = Matrix {
                raw: c,
                _arrays: None,
            };
            check(ffi::MatProductSetType(c, ffi::MATPRODUCT_PtAP))?;
            check(ffi::MatProductSetAlgorithm(c, algorithm.as_ptr() as _))?;
            check(ffi::MatProductSetFromOptions(c))?;
            check(ffi::MatProductSymbolic(c))?;
            check(ffi::MatProductNumeric(c))?;
            Ok(out)
        }
    }

    /// y = Aᵀ x
    /// Aᵀ as a matrix of its own (MatTranspose): its products are forward ones, whose sums
    /// do not depend on the order in which other ranks' parts arrive. Collective.
    pub fn transposed(&self) -> Result<Matrix> {
        let mut t: ffi::Mat = ptr::null_mut();
        // SAFETY: an assembled matrix; the transpose is a new matrix we own.
        unsafe {
            check(ffi::MatTranspose(self.raw, ffi::MAT_INITIAL_MATRIX, &mut t))?;
        }
        Ok(Matrix {
            raw: t,
            _arrays: None,
        })
    }

    pub fn mult_transpose(&self, x: &Vector, y: &mut Vector) -> Result<()> {
        // SAFETY: layouts checked by PETSc.
        unsafe { check(ffi::MatMultTranspose(self.raw, x.raw, y.raw)) }
    }

    /// Zeros the given rows and columns (global indices, owned by this rank) and puts `diag`
    /// on their diagonal (MatZeroRowsColumns; the right-hand side is left to the caller).
    /// Collective.
    pub fn zero_rows_columns(&mut self, rows: &[PInt], diag: f64) -> Result<()> {
        // SAFETY: `rows` is a valid slice; no vectors are passed.
        unsafe {
            check(ffi::MatZeroRowsColumns(
                self.raw,
                rows.len() as PInt,
                rows.as_ptr(),
                diag,
                ptr::null_mut(),
                ptr::null_mut(),
            ))
        }
    }
}

impl Vector {
    /// Collective max-norm.
    pub fn norm_inf(&self) -> Result<f64> {
        let mut n: ffi::PetscReal = 0.0;
        // SAFETY: writes one real.
        unsafe { check(ffi::VecNorm(self.raw, ffi::NORM_INFINITY, &mut n))? };
        Ok(n)
    }
}
