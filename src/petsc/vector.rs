//! A distributed PETSc vector (Vec).

use super::error::{check, own_error, Result};
use super::ffi::{self, MPI_Comm, PInt};
use std::os::raw::c_char;
use std::ptr;

/// A distributed PETSc vector.
pub struct Vector {
    pub(super) raw: ffi::Vec,
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
