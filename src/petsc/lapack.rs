//! LAPACK's dense Cholesky (dpotrf / dpotrs) and LU (dgetrf / dgetrs) for the dense systems on rank 0 (the condensed path's
//! active blocks, the half-space predictor): blocked and BLAS-3, against nalgebra's unblocked
//! LU (1 600 unknowns: ~0.1 s instead of seconds). The LAPACK PETSc itself links (Debian:
//! liblapack.so.3, OpenBLAS by default). OpenBLAS' threaded LU takes a few MiB of the calling
//! thread's stack: call it from the main thread (8 MiB) or a thread with as much.

use nalgebra::{DMatrix, DVector};
use std::os::raw::c_int;

// LAPACK's Fortran interface takes every argument by reference: `In` an integer read,
// `Out` an integer written, `Mat`/`MatMut` a column-major array, `Flag` a character code.
type In = *const c_int;
type Out = *mut c_int;
type Mat = *const f64;
type MatMut = *mut f64;
type Flag = *const u8;

extern "C" {
    fn dgetrf_(m: In, n: In, a: MatMut, lda: In, ipiv: Out, info: Out);
    fn dgetrs_(tr: Flag, n: In, nrhs: In, a: Mat, lda: In, ipiv: In, b: MatMut, ldb: In, i: Out);
    fn dpotrf_(uplo: Flag, n: In, a: MatMut, lda: In, info: Out);
    fn dpotri_(uplo: Flag, n: In, a: MatMut, lda: In, info: Out);
    fn dpotrs_(uplo: Flag, n: In, nrhs: In, a: Mat, lda: In, b: MatMut, ldb: In, info: Out);
}

extern "C" {
    fn dlsym(
        handle: *mut std::ffi::c_void,
        symbol: *const std::ffi::c_char,
    ) -> *mut std::ffi::c_void;
}

/// The name of the kernel set OpenBLAS chose for this CPU (`openblas_get_corename`, e.g.
/// "SkylakeX", "Haswell", "Prescott"), or `None` when the BLAS this process loaded is not
/// OpenBLAS. Looked up at run time (dlsym on the loaded libraries), so that a reference
/// BLAS behind libblas.so.3 still links. Local.
pub fn openblas_core() -> Option<String> {
    type CoreName = unsafe extern "C" fn() -> *const std::ffi::c_char;
    let f = openblas_symbol(c"openblas_get_corename");
    if f.is_null() {
        return None;
    }
    // SAFETY: a non-null result is OpenBLAS' `char *openblas_get_corename()`, which returns a
    // static NUL-terminated string (or null).
    unsafe {
        let name = std::mem::transmute::<*mut std::ffi::c_void, CoreName>(f)();
        if name.is_null() {
            return None;
        }
        Some(
            std::ffi::CStr::from_ptr(name)
                .to_string_lossy()
                .into_owned(),
        )
    }
}

/// OpenBLAS' function `name` from the loaded libraries (dlsym with RTLD_DEFAULT), or null.
fn openblas_symbol(name: &std::ffi::CStr) -> *mut std::ffi::c_void {
    // SAFETY: dlsym with the null handle (RTLD_DEFAULT on glibc) only searches the loaded
    // objects and returns an address or null; nothing is called here.
    unsafe { dlsym(std::ptr::null_mut(), name.as_ptr()) }
}

/// OpenBLAS' thread count (`openblas_get_num_threads`), or `None` when the BLAS this process
/// loaded is not OpenBLAS. Local.
pub fn openblas_threads() -> Option<usize> {
    type Get = unsafe extern "C" fn() -> c_int;
    let f = openblas_symbol(c"openblas_get_num_threads");
    if f.is_null() {
        return None;
    }
    // SAFETY: a non-null result is OpenBLAS' `int openblas_get_num_threads(void)`.
    let n = unsafe { std::mem::transmute::<*mut std::ffi::c_void, Get>(f)() };
    Some(n.max(1) as usize)
}

/// Sets OpenBLAS' thread count (`openblas_set_num_threads`; OpenBLAS starts the threads it
/// lacks). False when the BLAS this process loaded is not OpenBLAS. Local; call it between
/// BLAS calls of this process, not from inside one.
pub fn set_openblas_threads(n: usize) -> bool {
    type Set = unsafe extern "C" fn(c_int);
    let f = openblas_symbol(c"openblas_set_num_threads");
    if f.is_null() {
        return false;
    }
    // SAFETY: a non-null result is OpenBLAS' `void openblas_set_num_threads(int)`.
    unsafe { std::mem::transmute::<*mut std::ffi::c_void, Set>(f)(n.clamp(1, 4096) as c_int) };
    true
}

/// The Cholesky factor of a symmetric positive definite matrix (its lower triangle is read),
/// for repeated solves: half the work of [`DenseLu`].
pub struct DenseCholesky {
    n: usize,
    l: Vec<f64>,
}

impl DenseCholesky {
    /// Factorises `m` (n × n). `None` if not positive definite (or too large for LAPACK's
    /// 32-bit indices).
    pub fn factor(m: &DMatrix<f64>) -> Option<DenseCholesky> {
        assert_eq!(m.nrows(), m.ncols(), "square matrix");
        DenseCholesky::factor_owned(m.nrows(), m.as_slice().to_vec())
    }

    /// [`DenseCholesky::factor`] of the n × n matrix `l` (column-major), factorised in place.
    pub fn factor_owned(n: usize, mut l: Vec<f64>) -> Option<DenseCholesky> {
        assert_eq!(l.len(), n * n, "n × n values");
        let ni = c_int::try_from(n).ok()?;
        let mut info: c_int = 0;
        if n > 0 {
            // SAFETY: l holds n × n values with leading dimension n.
            unsafe { dpotrf_(b"L".as_ptr(), &ni, l.as_mut_ptr(), &ni, &mut info) };
        }
        (info == 0).then_some(DenseCholesky { n, l })
    }

    /// A⁻¹ from the factor (dpotri: n³ flops with the factorisation's n³/3, against 2n³ for
    /// n solves), symmetric, both triangles filled.
    pub fn inverse(mut self) -> DMatrix<f64> {
        let n = self.n;
        if n > 0 {
            let ni = n as c_int;
            let mut info: c_int = 0;
            // SAFETY: the factor of an n × n matrix with leading dimension n.
            unsafe { dpotri_(b"L".as_ptr(), &ni, self.l.as_mut_ptr(), &ni, &mut info) };
            debug_assert_eq!(info, 0); // a factor with a positive diagonal is regular
        }
        let mut m = DMatrix::from_vec(n, n, self.l);
        for j in 0..n {
            for i in 0..j {
                m[(i, j)] = m[(j, i)];
            }
        }
        m
    }

    /// X with A X = B (B: n × k).
    pub fn solve(&self, b: &DMatrix<f64>) -> DMatrix<f64> {
        assert_eq!(b.nrows(), self.n, "right-hand side rows");
        let mut x = b.clone();
        if self.n == 0 || b.ncols() == 0 {
            return x;
        }
        let ni = self.n as c_int;
        let k = b.ncols() as c_int;
        let mut info: c_int = 0;
        // SAFETY: the factor of an n × n matrix, x n × k column-major (ldb = n).
        unsafe {
            dpotrs_(
                b"L".as_ptr(),
                &ni,
                &k,
                self.l.as_ptr(),
                &ni,
                x.as_mut_slice().as_mut_ptr(),
                &ni,
                &mut info,
            )
        };
        debug_assert_eq!(info, 0);
        x
    }
}

/// The LU factors of a square matrix (partial pivoting), for repeated solves.
pub struct DenseLu {
    n: usize,
    lu: Vec<f64>,
    piv: Vec<c_int>,
}

impl DenseLu {
    /// Factorises `m` (n × n). `None` if singular (a zero pivot) or too large for LAPACK's
    /// 32-bit indices.
    pub fn factor(m: &DMatrix<f64>) -> Option<DenseLu> {
        assert_eq!(m.nrows(), m.ncols(), "square matrix");
        DenseLu::factor_owned(m.nrows(), m.as_slice().to_vec()) // column-major, as LAPACK
    }

    /// [`DenseLu::factor`] of the n × n matrix `lu` (column-major), factorised in place.
    pub fn factor_owned(n: usize, mut lu: Vec<f64>) -> Option<DenseLu> {
        assert_eq!(lu.len(), n * n, "n × n values");
        let ni = c_int::try_from(n).ok()?;
        let mut piv = vec![0 as c_int; n];
        let mut info: c_int = 0;
        if n > 0 {
            // SAFETY: lu holds n × n values with leading dimension n, piv n entries.
            unsafe { dgetrf_(&ni, &ni, lu.as_mut_ptr(), &ni, piv.as_mut_ptr(), &mut info) };
        }
        (info == 0).then_some(DenseLu { n, lu, piv })
    }

    /// x with A x = b.
    pub fn solve(&self, b: &DVector<f64>) -> DVector<f64> {
        assert_eq!(b.len(), self.n, "right-hand side length");
        let mut x = b.clone();
        if self.n == 0 {
            return x;
        }
        let ni = self.n as c_int;
        let one: c_int = 1;
        let mut info: c_int = 0;
        // SAFETY: the factors of an n × n matrix, n pivots, x of length n (ldb = n).
        unsafe {
            dgetrs_(
                b"N".as_ptr(),
                &ni,
                &one,
                self.lu.as_ptr(),
                &ni,
                self.piv.as_ptr(),
                x.as_mut_slice().as_mut_ptr(),
                &ni,
                &mut info,
            )
        };
        debug_assert_eq!(info, 0);
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lu_solves_an_indefinite_saddle_system_like_nalgebra() {
        // [C -h; -hᵀ 0] with C symmetric positive definite: indefinite, needs pivoting
        let n = 40;
        let c = DMatrix::from_fn(n, n, |i, j| 1.0 / (1.0 + (i as f64 - j as f64).abs()));
        let mut m = DMatrix::zeros(n + 1, n + 1);
        m.view_mut((0, 0), (n, n)).copy_from(&c);
        for i in 0..n {
            m[(i, n)] = -1.0;
            m[(n, i)] = -1.0;
        }
        let b = DVector::from_fn(n + 1, |i, _| (i as f64 * 0.37).sin());
        let x = DenseLu::factor(&m).expect("regular").solve(&b);
        let y = m.clone().lu().solve(&b).expect("regular");
        assert!((&x - &y).norm() <= 1e-10 * y.norm(), "{}", (&x - &y).norm());
        assert!((&m * &x - &b).norm() <= 1e-12 * b.norm().max(1.0));
    }

    #[test]
    fn cholesky_inverse_is_the_inverse() {
        let n = 30;
        let m = DMatrix::from_fn(n, n, |i, j| {
            1.0 / (1.0 + (i as f64 - j as f64).abs()) + if i == j { 2.0 } else { 0.0 }
        });
        let inv = DenseCholesky::factor(&m).expect("definite").inverse();
        let err = (&m * &inv - DMatrix::identity(n, n)).abs().max();
        assert!(err <= 1e-13, "{err}");
        assert_eq!(inv, inv.transpose());
    }

    #[test]
    fn cholesky_solves_and_rejects_an_indefinite_matrix() {
        let n = 30;
        let c = DMatrix::from_fn(n, n, |i, j| 1.0 / (1.0 + (i as f64 - j as f64).abs()));
        let b = DMatrix::from_fn(n, 2, |i, j| ((i + 7 * j) as f64 * 0.37).sin());
        let x = DenseCholesky::factor(&c)
            .expect("positive definite")
            .solve(&b);
        assert!((&c * &x - &b).norm() <= 1e-12 * b.norm());
        let mut d = c.clone();
        d[(3, 3)] = -1.0;
        assert!(DenseCholesky::factor(&d).is_none());
    }

    #[test]
    fn lu_reports_a_singular_matrix() {
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0]);
        assert!(DenseLu::factor(&m).is_none());
    }
}
