//! A distributed sparse PETSc matrix (MPIAIJ with a block size), its CSR input and its storage
//! statistics.

use super::error::{check, own_error, Result};
use super::ffi::{self, MPI_Comm, PInt};
use super::vector::Vector;
use crate::bigbuf::BigVec;
use std::os::raw::c_char;
use std::ptr;

/// One CSR part of a matrix's owned rows, handed to PETSc (see [`Matrix::from_split_csr`]).
#[derive(Default)]
pub struct Csr {
    pub rowptr: Vec<PInt>,
    pub cols: BigVec<PInt>,
    pub vals: BigVec<f64>,
}

/// A distributed sparse matrix (MPIAIJ with a block size).
pub struct Matrix {
    pub(super) raw: ffi::Mat,
    /// The CSR arrays PETSc works in, for a matrix made by [`Matrix::from_split_csr`]
    /// (PETSc does not own them): kept alive until the matrix is destroyed.
    pub(super) _arrays: Option<Box<(Csr, Csr)>>,
}

/// Storage statistics of a matrix (local to this rank).
#[derive(Clone, Copy, Debug)]
pub struct MatStats {
    pub nonzeros: f64,
    pub mallocs: f64,
}

impl Matrix {
    pub fn raw(&self) -> ffi::Mat {
        self.raw
    }

    /// An MPIAIJ (SeqAIJ on one rank) matrix with block size `bs` whose owned rows are given
    /// complete in CSR form: `rowptr` (local rows + 1), global column indices `cols` (sorted
    /// per row) and `vals`. The pattern is exact; new nonzeros are an error afterwards.
    pub fn from_csr(
        comm: MPI_Comm,
        bs: usize,
        rowptr: &[PInt],
        cols: &[PInt],
        vals: &[f64],
    ) -> Result<Matrix> {
        let local_rows = rowptr.len().saturating_sub(1);
        if cols.len() != vals.len() || rowptr.last().copied().unwrap_or(0) as usize != cols.len() {
            return Err(own_error("Matrix::from_csr: inconsistent CSR arrays"));
        }
        let mut raw: ffi::Mat = ptr::null_mut();
        // SAFETY: PETSc copies the CSR arrays, which outlive the calls.
        unsafe {
            check(ffi::MatCreate(comm, &mut raw))?;
            let m = Matrix { raw, _arrays: None };
            check(ffi::MatSetSizes(
                raw,
                local_rows as PInt,
                local_rows as PInt,
                ffi::PETSC_DETERMINE,
                ffi::PETSC_DETERMINE,
            ))?;
            check(ffi::MatSetType(raw, ffi::MATAIJ.as_ptr() as *const c_char))?;
            check(ffi::MatSetBlockSize(raw, bs as PInt))?;
            check(ffi::MatSeqAIJSetPreallocationCSR(
                raw,
                rowptr.as_ptr(),
                cols.as_ptr(),
                vals.as_ptr(),
            ))?;
            check(ffi::MatMPIAIJSetPreallocationCSR(
                raw,
                rowptr.as_ptr(),
                cols.as_ptr(),
                vals.as_ptr(),
            ))?;
            check(ffi::MatSetOption(
                raw,
                ffi::MAT_NEW_NONZERO_ALLOCATION_ERR,
                ffi::PETSC_TRUE,
            ))?;
            Ok(m)
        }
    }

    /// An AIJ matrix with block size `bs` from its owned rows given complete in two CSR
    /// parts, as PETSc stores them: `diag` holds the columns this rank owns (local column
    /// numbers), `off` the others (global column numbers); columns sorted per row. PETSc takes
    /// the arrays as they are (MatCreateSeqAIJWithArrays on one rank,
    /// MatCreateMPIAIJWithSplitArrays on several: no per-entry insertion, no copy). The
    /// matrix owns the arrays from then on and PETSc works in them (it rewrites `off`'s
    /// column numbers to its local numbering). The pattern is exact; new nonzeros are an
    /// error afterwards. On one rank `off` must be empty.
    pub fn from_split_csr(comm: MPI_Comm, bs: usize, diag: Csr, off: Csr) -> Result<Matrix> {
        let local_rows = diag.rowptr.len().saturating_sub(1);
        for p in [&diag, &off] {
            let n = p.rowptr.last().copied().unwrap_or(0) as usize;
            if p.rowptr.len() != local_rows + 1 || p.cols.len() != n || p.vals.len() != n {
                return Err(own_error("Matrix::from_split_csr: inconsistent CSR arrays"));
            }
        }
        let given = diag.cols.len() + off.cols.len();
        // Boxed: the matrix keeps the arrays; moving the box moves no heap buffer.
        let mut arrays = Box::new((diag, off));
        let mut size: std::os::raw::c_int = 0;
        let mut raw: ffi::Mat = ptr::null_mut();
        // SAFETY: the arrays are consistent (checked); PETSc works in them in place (it
        // renumbers the off-diagonal columns during assembly) and never frees or reallocates
        // them (new nonzeros are an error); they live in `arrays`, which the returned matrix
        // owns and drops only after MatDestroy (see Drop), and nothing else touches them.
        unsafe {
            ffi::MPI_Comm_size(comm, &mut size);
            let (diag, off) = &mut *arrays;
            if size == 1 && !off.cols.is_empty() {
                return Err(own_error(
                    "Matrix::from_split_csr: off-rank columns on one rank",
                ));
            }
            let n = local_rows as PInt;
            if size == 1 {
                check(ffi::MatCreateSeqAIJWithArrays(
                    comm,
                    n,
                    n,
                    diag.rowptr.as_mut_ptr(),
                    diag.cols.as_mut_ptr(),
                    diag.vals.as_mut_ptr(),
                    &mut raw,
                ))?;
            } else {
                check(ffi::MatCreateMPIAIJWithSplitArrays(
                    comm,
                    n,
                    n,
                    ffi::PETSC_DETERMINE,
                    ffi::PETSC_DETERMINE,
                    diag.rowptr.as_mut_ptr(),
                    diag.cols.as_mut_ptr(),
                    diag.vals.as_mut_ptr(),
                    off.rowptr.as_mut_ptr(),
                    off.cols.as_mut_ptr(),
                    off.vals.as_mut_ptr(),
                    &mut raw,
                ))?;
            }
            let m = Matrix {
                raw,
                _arrays: Some(arrays),
            };
            check(ffi::MatSetBlockSize(raw, bs as PInt))?;
            check(ffi::MatSetOption(
                raw,
                ffi::MAT_NEW_NONZERO_ALLOCATION_ERR,
                ffi::PETSC_TRUE,
            ))?;
            // Every entry handed over is stored, none merged or added.
            let st = m.stats()?;
            if st.nonzeros != given as f64 || st.mallocs != 0.0 {
                return Err(own_error(format!(
                    "Matrix::from_split_csr: {given} entries given, PETSc stores {} ({} mallocs)",
                    st.nonzeros, st.mallocs
                )));
            }
            Ok(m)
        }
    }

    /// Adds a dense block `vals` (rows.len() × cols.len(), row-major) at global indices.
    pub fn add_values(&mut self, rows: &[PInt], cols: &[PInt], vals: &[f64]) -> Result<()> {
        self.set_values_mode(rows, cols, vals, ffi::ADD_VALUES)
    }

    /// Inserts (overwrites) a dense block at global indices (entries must exist in the pattern).
    pub fn insert_values(&mut self, rows: &[PInt], cols: &[PInt], vals: &[f64]) -> Result<()> {
        self.set_values_mode(rows, cols, vals, ffi::INSERT_VALUES)
    }

    fn set_values_mode(
        &mut self,
        rows: &[PInt],
        cols: &[PInt],
        vals: &[f64],
        mode: ffi::InsertMode,
    ) -> Result<()> {
        if rows.len() * cols.len() != vals.len() {
            return Err(own_error("Matrix::set_values: size mismatch"));
        }
        // SAFETY: dimensions checked above.
        unsafe {
            check(ffi::MatSetValues(
                self.raw,
                rows.len() as PInt,
                rows.as_ptr(),
                cols.len() as PInt,
                cols.as_ptr(),
                vals.as_ptr(),
                mode,
            ))
        }
    }

    /// Collective: final assembly.
    pub fn assemble(&mut self) -> Result<()> {
        // SAFETY: valid matrix.
        unsafe {
            check(ffi::MatAssemblyBegin(self.raw, ffi::MAT_FINAL_ASSEMBLY))?;
            check(ffi::MatAssemblyEnd(self.raw, ffi::MAT_FINAL_ASSEMBLY))
        }
    }

    /// Local storage statistics (nonzeros, mallocs during assembly).
    pub fn stats(&self) -> Result<MatStats> {
        // SAFETY: MatInfo is plain old data filled by PETSc.
        unsafe {
            let mut info: ffi::MatInfo = std::mem::zeroed();
            check(ffi::MatGetInfo(self.raw, ffi::MAT_LOCAL, &mut info))?;
            Ok(MatStats {
                nonzeros: info.nz_used,
                mallocs: info.mallocs,
            })
        }
    }

    /// Owned row range [start, end).
    pub fn ownership_range(&self) -> Result<(usize, usize)> {
        let (mut lo, mut hi): (PInt, PInt) = (0, 0);
        // SAFETY: writes two ints.
        unsafe { check(ffi::MatGetOwnershipRange(self.raw, &mut lo, &mut hi))? };
        Ok((lo as usize, hi as usize))
    }

    /// A copy with the same pattern and values.
    pub fn duplicate(&self) -> Result<Matrix> {
        let mut raw: ffi::Mat = ptr::null_mut();
        // SAFETY: duplicate of an assembled matrix.
        unsafe {
            check(ffi::MatDuplicate(self.raw, ffi::MAT_COPY_VALUES, &mut raw))?;
        }
        Ok(Matrix { raw, _arrays: None })
    }

    /// self = other, both with the same nonzero pattern (no reallocation, nonzero state kept).
    pub fn copy_values_from(&mut self, other: &Matrix) -> Result<()> {
        // SAFETY: both valid; PETSc checks the layouts.
        unsafe { check(ffi::MatCopy(other.raw, self.raw, ffi::SAME_NONZERO_PATTERN)) }
    }

    /// Calls `f(columns, values)` with one owned row (global index).
    pub fn with_row<R>(&self, row: usize, f: impl FnOnce(&[PInt], &[f64]) -> R) -> Result<R> {
        let mut n: PInt = 0;
        let mut cols: *const PInt = ptr::null();
        let mut vals: *const f64 = ptr::null();
        // SAFETY: the arrays are valid for n entries between MatGetRow and MatRestoreRow.
        unsafe {
            check(ffi::MatGetRow(
                self.raw,
                row as PInt,
                &mut n,
                &mut cols,
                &mut vals,
            ))?;
            let (c, v) = if n == 0 {
                (&[][..], &[][..])
            } else {
                (
                    std::slice::from_raw_parts(cols, n as usize),
                    std::slice::from_raw_parts(vals, n as usize),
                )
            };
            let r = f(c, v);
            check(ffi::MatRestoreRow(
                self.raw,
                row as PInt,
                &mut n,
                &mut cols,
                &mut vals,
            ))?;
            Ok(r)
        }
    }

    /// y = A x
    pub fn mult(&self, x: &Vector, y: &mut Vector) -> Result<()> {
        // SAFETY: layouts checked by PETSc.
        unsafe { check(ffi::MatMult(self.raw, x.raw, y.raw)) }
    }

    /// Diagonal into `d`.
    pub fn diagonal(&self, d: &mut Vector) -> Result<()> {
        // SAFETY: layouts checked by PETSc.
        unsafe { check(ffi::MatGetDiagonal(self.raw, d.raw)) }
    }

    /// Attaches the rigid-body modes built from nodal coordinates (block size = dim) as the
    /// near-null space (used by GAMG).
    pub fn set_rigid_body_near_null_space(&self, coords: &Vector) -> Result<()> {
        let mut sp: ffi::MatNullSpace = ptr::null_mut();
        // SAFETY: coords has block size dim; the null space is referenced by the matrix.
        unsafe {
            check(ffi::MatNullSpaceCreateRigidBody(coords.raw, &mut sp))?;
            check(ffi::MatSetNearNullSpace(self.raw, sp))?;
            check(ffi::MatNullSpaceDestroy(&mut sp))
        }
    }

    /// Attaches `other`'s near-null space (if any) to this matrix too (GAMG reads it from the
    /// matrix it builds its hierarchy on).
    pub fn copy_near_null_space_from(&mut self, other: &Matrix) -> Result<()> {
        let mut sp: ffi::MatNullSpace = ptr::null_mut();
        // SAFETY: both matrices are valid; MatSetNearNullSpace takes its own reference.
        unsafe {
            check(ffi::MatGetNearNullSpace(other.raw, &mut sp))?;
            if sp.is_null() {
                return Ok(());
            }
            check(ffi::MatSetNearNullSpace(self.raw, sp))
        }
    }

    /// Attaches the span of `basis` (orthonormal vectors of this matrix's layout) as its null
    /// space and transpose null space: Krylov solves remove it from the right-hand side and
    /// from every preconditioned vector. An empty basis detaches both.
    pub fn set_null_space(&mut self, comm: MPI_Comm, basis: &[Vector]) -> Result<()> {
        if basis.is_empty() {
            // SAFETY: a null pointer detaches the null spaces.
            unsafe {
                check(ffi::MatSetNullSpace(self.raw, ptr::null_mut()))?;
                return check(ffi::MatSetTransposeNullSpace(self.raw, ptr::null_mut()));
            }
        }
        let mut sp = null_space_of(comm, basis)?;
        // SAFETY: the matrix takes its own references to the null space; ours is dropped.
        unsafe {
            check(ffi::MatSetNullSpace(self.raw, sp))?;
            check(ffi::MatSetTransposeNullSpace(self.raw, sp))?;
            check(ffi::MatNullSpaceDestroy(&mut sp))
        }
    }
}

/// A PETSc null space object spanned by `basis` (orthonormal vectors; no constant added); the
/// caller attaches it and drops this reference (MatNullSpaceDestroy).
fn null_space_of(comm: MPI_Comm, basis: &[Vector]) -> Result<ffi::MatNullSpace> {
    let raws: Vec<ffi::Vec> = basis.iter().map(|v| v.raw).collect();
    let mut sp: ffi::MatNullSpace = ptr::null_mut();
    // SAFETY: the vectors are valid; PETSc references them in the null space object.
    unsafe {
        check(ffi::MatNullSpaceCreate(
            comm,
            ffi::PETSC_FALSE,
            raws.len() as PInt,
            raws.as_ptr(),
            &mut sp,
        ))?;
    }
    Ok(sp)
}

impl Drop for Matrix {
    fn drop(&mut self) {
        crate::abort::before_collective();
        // SAFETY: destroys the matrix we own; its CSR arrays (if any) are dropped after this,
        // with the other fields.
        unsafe {
            ffi::MatDestroy(&mut self.raw);
        }
    }
}
