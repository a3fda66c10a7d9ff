//! The PETSc binding layer: the only module with `unsafe`.
//!
//! RAII wrappers for Vec / Mat / KSP / MatPartitioning / MatNullSpace, the options database,
//! and PETSc error codes turned into Rust errors that carry PETSc's message and the Rust
//! caller's location. Everything here is collective where the PETSc call is collective.

mod error;
pub mod ffi;
pub mod lapack;
mod mpi;
pub mod mumps;
pub mod ndfactor;
pub mod optdb;
pub mod snes;

use std::ffi::{CStr, CString};
use std::os::raw::{c_char, c_int};
use std::ptr;
use std::rc::Rc;

use crate::bigbuf::BigVec;
use optdb::OptionsDb;

pub use ffi::MPI_Comm;
/// PETSc's index type (32-bit in Debian's build).
pub type PInt = ffi::PetscInt;

use error::{agreed_error, check, cstring, own_error};
pub use error::{raised_error, PetscError, Result};

/// The PETSc library, initialised once per process after MPI (rsmpi) and finalised on drop,
/// before the rsmpi `Universe` is dropped. Owns the argv strings PETSc keeps pointers to.
pub struct Petsc {
    _args: Vec<CString>,
    _argv: Vec<*mut c_char>,
}

impl Petsc {
    /// `PetscInitialize` with PETSc's own command-line options (`-ksp_type gmres`, `-log_view`, ...).
    /// MPI must already be initialised (PETSc then leaves MPI_Finalize to rsmpi).
    pub fn init(petsc_args: &[String]) -> Result<Petsc> {
        let mut args: Vec<CString> = vec![cstring("signorini-mpi")];
        args.extend(petsc_args.iter().map(|a| cstring(a)));
        let mut argv: Vec<*mut c_char> = args.iter().map(|a| a.as_ptr() as *mut c_char).collect();
        argv.push(ptr::null_mut());
        let mut argc: c_int = args.len() as c_int;
        let mut argv_ptr = argv.as_mut_ptr();
        // SAFETY: argc/argv describe NUL-terminated strings that live in `self` until finalize.
        unsafe {
            check(ffi::PetscInitialize(
                &mut argc,
                &mut argv_ptr,
                ptr::null(),
                ptr::null(),
            ))?;
            // Errors come back to Rust as values; we print them ourselves.
            check(ffi::PetscPushErrorHandler(
                Some(ffi::PetscReturnErrorHandler),
                ptr::null_mut(),
            ))?;
            check(ffi::PetscMemorySetGetMaximumUsage())?;
        }
        Ok(Petsc {
            _args: args,
            _argv: argv,
        })
    }

    /// PETSC_COMM_WORLD (the same type and value as rsmpi's world communicator).
    pub fn comm(&self) -> MPI_Comm {
        // SAFETY: valid after PetscInitialize, which `self` proves.
        unsafe { ffi::PETSC_COMM_WORLD }
    }
}

impl Drop for Petsc {
    fn drop(&mut self) {
        // SAFETY: every PETSc object is dropped before this (they borrow nothing from here,
        // but the binary drops them first by construction).
        unsafe {
            ffi::PetscFinalize();
        }
    }
}

/// The default options database: the global one (the command line), or the private one of a
/// solver while it is set up or run ([`optdb::OptionsDb::scoped`]).
pub mod options {
    use super::*;

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
}

/// A distributed PETSc vector.
pub struct Vector {
    raw: ffi::Vec,
}

impl Vector {
    /// An MPI vector with `local` owned entries and block size `bs`.
    pub fn new_mpi(comm: MPI_Comm, local: usize, bs: usize) -> Result<Vector> {
        let mut raw: ffi::Vec = ptr::null_mut();
        // SAFETY: standard creation sequence; `raw` is owned by the returned wrapper.
        unsafe {
            check(ffi::VecCreate(comm, &mut raw))?;
            let v = Vector { raw };
            check(ffi::VecSetSizes(raw, local as PInt, ffi::PETSC_DETERMINE))?;
            check(ffi::VecSetBlockSize(raw, bs as PInt))?;
            check(ffi::VecSetType(raw, ffi::VECMPI.as_ptr() as *const c_char))?;
            check(ffi::VecSet(raw, 0.0))?;
            Ok(v)
        }
    }

    /// A new vector with the same layout, zeroed.
    pub fn duplicate(&self) -> Result<Vector> {
        let mut raw: ffi::Vec = ptr::null_mut();
        // SAFETY: duplicate of a valid vector.
        unsafe {
            check(ffi::VecDuplicate(self.raw, &mut raw))?;
            let v = Vector { raw };
            check(ffi::VecSet(raw, 0.0))?;
            Ok(v)
        }
    }

    pub fn raw(&self) -> ffi::Vec {
        self.raw
    }

    /// Adds or inserts values at global indices (off-process entries are communicated at assembly).
    pub fn set_values(&mut self, idx: &[PInt], vals: &[f64], add: bool) -> Result<()> {
        if idx.len() != vals.len() {
            return Err(own_error("Vector::set_values: length mismatch"));
        }
        let mode = if add {
            ffi::ADD_VALUES
        } else {
            ffi::INSERT_VALUES
        };
        // SAFETY: slices of equal length.
        unsafe {
            check(ffi::VecSetValues(
                self.raw,
                idx.len() as PInt,
                idx.as_ptr(),
                vals.as_ptr(),
                mode,
            ))
        }
    }

    /// Collective: finishes `set_values`.
    pub fn assemble(&mut self) -> Result<()> {
        // SAFETY: valid vector.
        unsafe {
            check(ffi::VecAssemblyBegin(self.raw))?;
            check(ffi::VecAssemblyEnd(self.raw))
        }
    }

    pub fn set_all(&mut self, v: f64) -> Result<()> {
        // SAFETY: valid vector.
        unsafe { check(ffi::VecSet(self.raw, v)) }
    }

    /// Owned range [start, end) of global indices.
    pub fn ownership_range(&self) -> Result<(usize, usize)> {
        let (mut lo, mut hi): (PInt, PInt) = (0, 0);
        // SAFETY: writes two ints.
        unsafe { check(ffi::VecGetOwnershipRange(self.raw, &mut lo, &mut hi))? };
        Ok((lo as usize, hi as usize))
    }

    pub fn local_len(&self) -> Result<usize> {
        let mut n: PInt = 0;
        // SAFETY: writes one int.
        unsafe { check(ffi::VecGetLocalSize(self.raw, &mut n))? };
        Ok(n as usize)
    }

    /// Read access to the owned entries.
    pub fn read<R>(&self, f: impl FnOnce(&[f64]) -> R) -> Result<R> {
        let n = self.local_len()?;
        let mut p: *const f64 = ptr::null();
        // SAFETY: the array is valid for n entries between Get and Restore.
        unsafe {
            check(ffi::VecGetArrayRead(self.raw, &mut p))?;
            let r = f(if n == 0 {
                &[]
            } else {
                std::slice::from_raw_parts(p, n)
            });
            check(ffi::VecRestoreArrayRead(self.raw, &mut p))?;
            Ok(r)
        }
    }

    /// Write access to the owned entries.
    pub fn write<R>(&mut self, f: impl FnOnce(&mut [f64]) -> R) -> Result<R> {
        let n = self.local_len()?;
        let mut p: *mut f64 = ptr::null_mut();
        // SAFETY: the array is valid for n entries between Get and Restore.
        unsafe {
            check(ffi::VecGetArray(self.raw, &mut p))?;
            let r = f(if n == 0 {
                &mut []
            } else {
                std::slice::from_raw_parts_mut(p, n)
            });
            check(ffi::VecRestoreArray(self.raw, &mut p))?;
            Ok(r)
        }
    }

    /// Copies the owned entries into a Rust vector.
    pub fn to_local_vec(&self) -> Result<Vec<f64>> {
        self.read(|s| s.to_vec())
    }

    /// Values at arbitrary global indices (owned or not), gathered with a VecScatter
    /// (collective: every rank calls it, possibly with an empty list).
    pub fn gather(&self, global: &[PInt]) -> Result<Vec<f64>> {
        let n = global.len();
        // SAFETY: sequential target vector and index set live until destroyed below; the
        // index array is copied by PETSc.
        unsafe {
            let mut y: ffi::Vec = ptr::null_mut();
            check(ffi::VecCreateSeq(ffi::RSMPI_COMM_SELF, n as PInt, &mut y))?;
            let y = Vector { raw: y };
            let mut is: ffi::IS = ptr::null_mut();
            check(ffi::ISCreateGeneral(
                ffi::RSMPI_COMM_SELF,
                n as PInt,
                global.as_ptr(),
                ffi::PETSC_COPY_VALUES,
                &mut is,
            ))?;
            let mut sc: ffi::VecScatter = ptr::null_mut();
            let r = check(ffi::VecScatterCreate(
                self.raw,
                is,
                y.raw,
                ptr::null_mut(),
                &mut sc,
            ));
            ffi::ISDestroy(&mut is);
            r?;
            let r = check(ffi::VecScatterBegin(
                sc,
                self.raw,
                y.raw,
                ffi::INSERT_VALUES,
                ffi::SCATTER_FORWARD,
            ))
            .and_then(|_| {
                check(ffi::VecScatterEnd(
                    sc,
                    self.raw,
                    y.raw,
                    ffi::INSERT_VALUES,
                    ffi::SCATTER_FORWARD,
                ))
            });
            ffi::VecScatterDestroy(&mut sc);
            r?;
            y.to_local_vec()
        }
    }

    /// self = x
    pub fn copy_from(&mut self, x: &Vector) -> Result<()> {
        // SAFETY: compatible layouts are checked by PETSc.
        unsafe { check(ffi::VecCopy(x.raw, self.raw)) }
    }
}

impl Drop for Vector {
    fn drop(&mut self) {
        crate::abort::before_collective();
        // SAFETY: destroys the vector we own.
        unsafe {
            ffi::VecDestroy(&mut self.raw);
        }
    }
}

/// One CSR part of a matrix's owned rows, handed to PETSc (see [`Matrix::from_split_csr`]).
#[derive(Default)]
pub struct Csr {
    pub rowptr: Vec<PInt>,
    pub cols: BigVec<PInt>,
    pub vals: BigVec<f64>,
}

/// A distributed sparse matrix (MPIAIJ with a block size).
pub struct Matrix {
    raw: ffi::Mat,
    /// The CSR arrays PETSc works in, for a matrix made by [`Matrix::from_split_csr`]
    /// (PETSc does not own them): kept alive until the matrix is destroyed.
    _arrays: Option<Box<(Csr, Csr)>>,
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
    pub fn set_rigid_body_near_null_space(&mut self, coords: &Vector) -> Result<()> {
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
        // SAFETY: the vectors are valid; PETSc references them in the null space object,
        // which the matrix references in turn; our reference is dropped at once.
        unsafe {
            if basis.is_empty() {
                check(ffi::MatSetNullSpace(self.raw, ptr::null_mut()))?;
                return check(ffi::MatSetTransposeNullSpace(self.raw, ptr::null_mut()));
            }
            let raws: Vec<ffi::Vec> = basis.iter().map(|v| v.raw).collect();
            let mut sp: ffi::MatNullSpace = ptr::null_mut();
            check(ffi::MatNullSpaceCreate(
                comm,
                ffi::PETSC_FALSE,
                raws.len() as PInt,
                raws.as_ptr(),
                &mut sp,
            ))?;
            check(ffi::MatSetNullSpace(self.raw, sp))?;
            check(ffi::MatSetTransposeNullSpace(self.raw, sp))?;
            check(ffi::MatNullSpaceDestroy(&mut sp))
        }
    }
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

/// A Krylov solver (with its preconditioner) reading its options from a private database.
pub struct Ksp {
    raw: ffi::KSP,
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

    /// A failure inside our MUMPS preconditioner reaches PETSc as an error code only: its
    /// message replaces PETSc's generic one.
    fn explain(&self, mut e: PetscError) -> PetscError {
        if let Ok(Some((_, Some(m)))) = ndfactor::record(self) {
            crate::abort::reworded(&m);
            e.message = m;
        }
        e
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

/// Partitions a distributed graph with PETSc's MatPartitioning (type from `ptype`;
/// `-mat_partitioning_type` overrides). This rank passes the adjacency of its rows
/// `[row_start, row_start + xadj.len() - 1)` in CSR form (global column indices, no
/// self-loops); the result is the target rank of each of these rows.
///
/// For PT-Scotch prefer [`scotch_partition`]: through PETSc, PT-Scotch runs with its default
/// context (one thread per core, non-deterministic message order), so the partition changes
/// from run to run.
pub fn partition_graph(
    comm: MPI_Comm,
    n_global: usize,
    xadj: &[PInt],
    adjncy: &[PInt],
    ptype: &str,
) -> Result<Vec<PInt>> {
    let n_local = xadj.len().saturating_sub(1);
    // SAFETY: the CSR arrays are copied into PETSc-allocated memory; MatCreateMPIAdj takes
    // ownership of them on success (MatDestroy frees them) and we free them on failure. The IS
    // is read and destroyed before returning.
    unsafe {
        let ia = petsc_malloc_copy(xadj)?;
        let ja = match petsc_malloc_copy(adjncy) {
            Ok(ja) => ja,
            Err(e) => {
                petsc_free(ia);
                return Err(e);
            }
        };
        // MatCreateMPIAdj's steps, one by one: the matrix takes ownership of ia/ja in the last
        // step of MatMPIAdjSetPreallocation (before an assembly that cannot fail for MPIADJ),
        // so on any failure the arrays are still ours to free.
        let mut adj: ffi::Mat = ptr::null_mut();
        let created = (|| {
            check(ffi::MatCreate(comm, &mut adj))?;
            check(ffi::MatSetSizes(
                adj,
                n_local as PInt,
                ffi::PETSC_DETERMINE,
                ffi::PETSC_DETERMINE,
                n_global as PInt,
            ))?;
            check(ffi::MatSetType(
                adj,
                ffi::MATMPIADJ.as_ptr() as *const c_char,
            ))?;
            check(ffi::MatMPIAdjSetPreallocation(adj, ia, ja, ptr::null_mut()))
        })();
        if let Err(e) = created {
            if !adj.is_null() {
                ffi::MatDestroy(&mut adj);
            }
            petsc_free(ia);
            petsc_free(ja);
            return Err(e);
        }
        let adj = Matrix {
            raw: adj,
            _arrays: None,
        };
        let mut part: ffi::MatPartitioning = ptr::null_mut();
        check(ffi::MatPartitioningCreate(comm, &mut part))?;
        let t = cstring(ptype);
        let result = (|| {
            check(ffi::MatPartitioningSetAdjacency(part, adj.raw))?;
            check(ffi::MatPartitioningSetType(part, t.as_ptr()))?;
            check(ffi::MatPartitioningSetFromOptions(part))?;
            let mut is: ffi::IS = ptr::null_mut();
            check(ffi::MatPartitioningApply(part, &mut is))?;
            let mut idx: *const PInt = ptr::null();
            check(ffi::ISGetIndices(is, &mut idx))?;
            let out = if n_local == 0 {
                Vec::new()
            } else {
                std::slice::from_raw_parts(idx, n_local).to_vec()
            };
            check(ffi::ISRestoreIndices(is, &mut idx))?;
            check(ffi::ISDestroy(&mut is))?;
            Ok(out)
        })();
        ffi::MatPartitioningDestroy(&mut part);
        drop(adj);
        result
    }
}

/// The seed of PT-Scotch's pseudo-random generator in [`scotch_partition`] (any fixed value).
const SCOTCH_SEED: ffi::SCOTCH_Num = 1;

/// Owned PT-Scotch / MPI objects, released in reverse order of creation on every path.
struct ScotchRun {
    comm: MPI_Comm,
    context: Option<Box<ffi::SCOTCH_Context>>,
    graph: Option<Box<ffi::SCOTCH_Dgraph>>,
    strat: Option<Box<ffi::SCOTCH_Strat>>,
}

impl Drop for ScotchRun {
    fn drop(&mut self) {
        crate::abort::before_collective();
        // SAFETY: each object is present only if its init call succeeded; the bound graph
        // container needs no exit of its own.
        unsafe {
            if let Some(s) = self.strat.as_mut() {
                ffi::SCOTCH_stratExit(&mut **s);
            }
            if let Some(g) = self.graph.as_mut() {
                ffi::SCOTCH_dgraphExit(&mut **g);
            }
            if let Some(c) = self.context.as_mut() {
                ffi::SCOTCH_contextExit(&mut **c);
            }
            if self.comm != ffi::RSMPI_COMM_NULL {
                ffi::MPI_Comm_free(&mut self.comm);
            }
        }
    }
}

/// A PT-Scotch return code as a `Result` (PT-Scotch prints its own message on stderr).
#[track_caller]
fn scotch_check(code: c_int, call: &str) -> Result<()> {
    if code == 0 {
        Ok(())
    } else {
        Err(own_error(format!(
            "PT-Scotch {call} failed with code {code}"
        )))
    }
}

/// Partitions a distributed graph into `n_parts` parts with PT-Scotch, called directly so that
/// it runs under an explicit context: one thread per rank, deterministic mode and a fixed
/// seed. The same graph on the same communicator size then gives the same partition on
/// every run, and PT-Scotch never calls MPI from two threads at once. (Debian's PT-Scotch is
/// built with SCOTCH_PTHREAD_MPI: under its default context, used through PETSc's
/// MatPartitioning, it folds graphs in two threads that both communicate; with MPI below
/// MPI_THREAD_MULTIPLE that hangs or crashes, and the thread count and the arrival order of
/// messages change the partition from run to run.)
///
/// This rank passes the rows `[row_start, row_start + xadj.len() - 1)` of a symmetric graph
/// without self-loops, in CSR form with global 0-based column indices; rows are distributed
/// in rank order. `weights`, if given, are the vertex weights of the local rows and the edge
/// weights in `adjncy`'s order (positive; the balance is then by vertex weight, the cut by edge
/// weight). `imbalance` is the allowed load imbalance (0.01 = 1 %). Returns the part of each
/// local row. Collective over `comm`; the graph is checked (`SCOTCH_dgraphCheck`)
/// before it is partitioned.
pub fn scotch_partition(
    comm: MPI_Comm,
    xadj: &[PInt],
    adjncy: &[PInt],
    weights: Option<(&[PInt], &[PInt])>,
    n_parts: usize,
    imbalance: f64,
) -> Result<Vec<PInt>> {
    // Declared before `run`: PT-Scotch keeps pointers into the arrays until the graph is freed.
    let mut arrays = ScotchArrays::new(xadj, adjncy, weights)?;
    let n_local = arrays.vert.len() - 1;
    let mut part: Vec<ffi::SCOTCH_Num> = vec![0; n_local.max(1)];
    let mut run = ScotchRun::new(comm)?;
    // SAFETY: `arrays` outlives `run` (dropped explicitly below, before `arrays`).
    unsafe { run.build_graph(&mut arrays)? };
    run.partition(n_parts, imbalance, &mut part)?;
    drop(run);
    part.truncate(n_local);
    Ok(part.into_iter().map(|p| p as PInt).collect())
}

/// PT-Scotch's private copies of a graph's CSR arrays and weights, in its index type (it takes
/// non-const pointers, does not write through them, and keeps them until the graph is freed).
struct ScotchArrays {
    vert: Vec<ffi::SCOTCH_Num>,
    edge: Vec<ffi::SCOTCH_Num>,
    velo: Vec<ffi::SCOTCH_Num>,
    edlo: Vec<ffi::SCOTCH_Num>,
    weighted: bool,
}

impl ScotchArrays {
    /// Checks the CSR arrays and the weights' lengths, and copies them.
    fn new(
        xadj: &[PInt],
        adjncy: &[PInt],
        weights: Option<(&[PInt], &[PInt])>,
    ) -> Result<ScotchArrays> {
        type Num = ffi::SCOTCH_Num;
        let n_local = xadj.len().saturating_sub(1);
        let n_edges = xadj.last().copied().unwrap_or(0) as usize;
        if xadj.is_empty() || xadj[0] != 0 || n_edges != adjncy.len() {
            return Err(own_error(format!(
                "scotch_partition: malformed CSR rows ({} offsets, {} edges, last offset {n_edges})",
                xadj.len(),
                adjncy.len()
            )));
        }
        if let Some((v, e)) = weights {
            if v.len() != n_local || e.len() != n_edges {
                return Err(own_error(format!(
                    "scotch_partition: {} vertex weights for {n_local} rows, {} edge weights for {n_edges} edges",
                    v.len(),
                    e.len()
                )));
            }
        }
        let copy = |x: &[PInt]| -> Vec<Num> {
            let mut v: Vec<Num> = x.iter().map(|&w| w as Num).collect();
            v.reserve(1); // a valid pointer even when empty
            v
        };
        let (velo, edlo) = match weights {
            Some((v, e)) => (copy(v), copy(e)),
            None => (copy(&[]), copy(&[])),
        };
        Ok(ScotchArrays {
            vert: copy(xadj),
            edge: copy(adjncy),
            velo,
            edlo,
            weighted: weights.is_some(),
        })
    }
}

impl ScotchRun {
    /// PT-Scotch's own communicator (its messages can never meet ours) and a context with one
    /// thread (no concurrent MPI calls inside PT-Scotch, no dependence on the core count),
    /// deterministic mode and a private generator with a fixed seed.
    fn new(comm: MPI_Comm) -> Result<ScotchRun> {
        let mut run = ScotchRun {
            // SAFETY: reads mpi-sys' constant for MPI_COMM_NULL.
            comm: unsafe { ffi::RSMPI_COMM_NULL },
            context: None,
            graph: None,
            strat: None,
        };
        // SAFETY: the context is boxed (PT-Scotch keeps a pointer to it), initialised before
        // use and released by `run`'s Drop.
        unsafe {
            let rc = ffi::MPI_Comm_dup(comm, &mut run.comm);
            if rc != 0 {
                run.comm = ffi::RSMPI_COMM_NULL;
                return Err(own_error(format!("MPI_Comm_dup failed with code {rc}")));
            }
            let mut context: Box<ffi::SCOTCH_Context> = Box::new(std::mem::zeroed());
            scotch_check(ffi::SCOTCH_contextInit(&mut *context), "SCOTCH_contextInit")?;
            let context = &mut **run.context.insert(context);
            scotch_check(
                ffi::SCOTCH_contextThreadSpawn(context, 1, ptr::null()),
                "SCOTCH_contextThreadSpawn",
            )?;
            scotch_check(
                ffi::SCOTCH_contextOptionSetNum(
                    context,
                    ffi::SCOTCH_OPTIONNUMDETERMINISTIC as c_int,
                    1,
                ),
                "SCOTCH_contextOptionSetNum(deterministic)",
            )?;
            scotch_check(
                ffi::SCOTCH_contextOptionSetNum(
                    context,
                    ffi::SCOTCH_OPTIONNUMRANDOMFIXEDSEED as c_int,
                    1,
                ),
                "SCOTCH_contextOptionSetNum(fixed seed)",
            )?;
            // A private generator with a fixed seed, independent of earlier PT-Scotch calls.
            scotch_check(
                ffi::SCOTCH_contextRandomClone(context),
                "SCOTCH_contextRandomClone",
            )?;
            ffi::SCOTCH_contextRandomSeed(context, SCOTCH_SEED);
        }
        Ok(run)
    }

    /// Builds the distributed graph on `a` and checks it (`SCOTCH_dgraphCheck`).
    ///
    /// # Safety
    /// `a` must outlive `self` and stay unchanged: PT-Scotch keeps pointers into it.
    unsafe fn build_graph(&mut self, a: &mut ScotchArrays) -> Result<()> {
        type Num = ffi::SCOTCH_Num;
        let n_local = (a.vert.len() - 1) as Num;
        let n_edges = a.edge.len() as Num;
        let weighted = a.weighted;
        let or_null = |v: &mut Vec<Num>| {
            if weighted {
                v.as_mut_ptr()
            } else {
                ptr::null_mut()
            }
        };
        let (velo, edlo) = (or_null(&mut a.velo), or_null(&mut a.edlo));
        let mut graph: Box<ffi::SCOTCH_Dgraph> = Box::new(std::mem::zeroed());
        scotch_check(
            ffi::SCOTCH_dgraphInit(&mut *graph, self.comm),
            "SCOTCH_dgraphInit",
        )?;
        let graph = &mut **self.graph.insert(graph);
        scotch_check(
            ffi::SCOTCH_dgraphBuild(
                graph,
                0,
                n_local,
                n_local,
                a.vert.as_mut_ptr(),
                a.vert.as_mut_ptr().add(1),
                velo,
                ptr::null_mut(),
                n_edges,
                n_edges,
                a.edge.as_mut_ptr(),
                ptr::null_mut(),
                edlo,
            ),
            "SCOTCH_dgraphBuild",
        )?;
        scotch_check(ffi::SCOTCH_dgraphCheck(graph), "SCOTCH_dgraphCheck")
    }

    /// Partitions the built graph under the context into `n_parts` parts: PETSc's
    /// MatPartitioning defaults (the default strategy) with the allowed `imbalance`.
    fn partition(
        &mut self,
        n_parts: usize,
        imbalance: f64,
        part: &mut [ffi::SCOTCH_Num],
    ) -> Result<()> {
        type Num = ffi::SCOTCH_Num;
        let (Some(context), Some(graph)) = (self.context.as_mut(), self.graph.as_ref()) else {
            return Err(own_error("scotch_partition: no context or graph"));
        };
        // SAFETY: context and graph are initialised (build_graph succeeded), the strategy is
        // boxed and released by Drop; `part` holds one entry per local vertex (at least one).
        unsafe {
            let mut bound: ffi::SCOTCH_Dgraph = std::mem::zeroed();
            scotch_check(
                ffi::SCOTCH_contextBindDgraph(&mut **context, &**graph, &mut bound),
                "SCOTCH_contextBindDgraph",
            )?;
            let mut strat: Box<ffi::SCOTCH_Strat> = Box::new(std::mem::zeroed());
            scotch_check(ffi::SCOTCH_stratInit(&mut *strat), "SCOTCH_stratInit")?;
            let strat = &mut **self.strat.insert(strat);
            let mut n_procs: c_int = 0;
            ffi::MPI_Comm_size(self.comm, &mut n_procs);
            scotch_check(
                ffi::SCOTCH_stratDgraphMapBuild(
                    strat,
                    ffi::SCOTCH_STRATDEFAULT as Num,
                    n_procs as Num,
                    n_parts as Num,
                    imbalance,
                ),
                "SCOTCH_stratDgraphMapBuild",
            )?;
            scotch_check(
                ffi::SCOTCH_dgraphPart(&mut bound, n_parts as Num, strat, part.as_mut_ptr()),
                "SCOTCH_dgraphPart",
            )
        }
    }
}

/// Frees memory from PetscMalloc that no PETSc object has taken over.
unsafe fn petsc_free(p: *mut PInt) {
    let mut p = p as *mut std::ffi::c_void;
    ffi::PetscFreeA(
        1,
        line!() as c_int,
        c"petsc_free".as_ptr(),
        c"src/petsc/mod.rs".as_ptr(),
        &mut p as *mut *mut std::ffi::c_void as *mut std::ffi::c_void,
    );
}

/// Copies a slice into memory from PetscMalloc (for objects that take ownership of arrays).
unsafe fn petsc_malloc_copy(src: &[PInt]) -> Result<*mut PInt> {
    let bytes = std::mem::size_of_val(src).max(std::mem::size_of::<PInt>());
    let mut p: *mut std::ffi::c_void = ptr::null_mut();
    check(ffi::PetscMallocA(
        1,
        ffi::PETSC_FALSE,
        line!() as c_int,
        c"petsc_malloc_copy".as_ptr(),
        c"src/petsc/mod.rs".as_ptr(),
        bytes,
        &mut p as *mut *mut std::ffi::c_void as *mut std::ffi::c_void,
    ))?;
    let dst = p as *mut PInt;
    ptr::copy_nonoverlapping(src.as_ptr(), dst, src.len());
    Ok(dst)
}
