//! The few raw MPI calls of the binding layer that run inside PETSc callbacks or next to MUMPS,
//! where no `Ctx` is at hand: agreement on a flag, on a maximum or on the first failing rank's
//! message, a gather of integers to rank 0 and their broadcast from it.

use std::ffi::c_void;
use std::os::raw::c_int;

use super::{ffi, own_error, MPI_Comm, Result};

/// `flag` on every rank of `comm` (one Allreduce).
pub(super) fn all_true(comm: MPI_Comm, flag: bool) -> Result<bool> {
    Ok(min_i32(comm, flag as i32)? == 1)
}

/// The minimum of `v` over the ranks of `comm` (one Allreduce).
fn min_i32(comm: MPI_Comm, v: i32) -> Result<i32> {
    allreduce_i32(comm, v, false)
}

/// The maximum of `v` over the ranks of `comm` (one Allreduce).
pub(super) fn max_i32(comm: MPI_Comm, v: i32) -> Result<i32> {
    allreduce_i32(comm, v, true)
}

/// The maximum (`max`) or minimum of `v` over the ranks of `comm` (one Allreduce).
fn allreduce_i32(comm: MPI_Comm, v: i32, max: bool) -> Result<i32> {
    let mut out: i32 = 0;
    // SAFETY: one int in, one out, on a valid communicator; the ops are MPI's predefined ones.
    let rc = unsafe {
        let op = if max { ffi::RSMPI_MAX } else { ffi::RSMPI_MIN };
        ffi::MPI_Allreduce(
            &v as *const i32 as *const c_void,
            &mut out as *mut i32 as *mut c_void,
            1,
            ffi::RSMPI_INT32_T,
            op,
            comm,
        )
    };
    mpi_ok(rc, "MPI_Allreduce")?;
    Ok(out)
}

/// The message of the lowest rank whose `local` is `Some`, on every rank (`None` when no rank
/// failed). Collective (one Allreduce, and two broadcasts when a rank failed).
pub(super) fn first_message(comm: MPI_Comm, local: Option<&str>) -> Result<Option<String>> {
    let (mut size, rank) = (0, rank_of(comm)?);
    // SAFETY: valid communicator, one int out.
    mpi_ok(
        unsafe { ffi::MPI_Comm_size(comm, &mut size) },
        "MPI_Comm_size",
    )?;
    let first = min_i32(comm, if local.is_some() { rank } else { size })?;
    // every rank now knows whether one failed: nothing of this rank's is pending alone
    crate::abort::covered();
    if first >= size {
        return Ok(None);
    }
    let mut bytes = if rank == first {
        local.unwrap_or_default().as_bytes().to_vec()
    } else {
        Vec::new()
    };
    let mut len = bytes.len() as i32;
    // SAFETY: one int, then `len` bytes into a buffer of that length, from rank `first`.
    unsafe {
        mpi_ok(
            ffi::MPI_Bcast(
                &mut len as *mut i32 as *mut c_void,
                1,
                ffi::RSMPI_INT32_T,
                first,
                comm,
            ),
            "MPI_Bcast",
        )?;
        bytes.resize(len.max(0) as usize, 0);
        mpi_ok(
            ffi::MPI_Bcast(
                bytes.as_mut_ptr() as *mut c_void,
                len,
                ffi::RSMPI_UINT8_T,
                first,
                comm,
            ),
            "MPI_Bcast",
        )?;
    }
    Ok(Some(String::from_utf8_lossy(&bytes).into_owned()))
}

pub(super) fn mpi_ok(rc: c_int, call: &str) -> Result<()> {
    if rc == 0 {
        Ok(())
    } else {
        Err(own_error(format!("{call} failed with code {rc}")))
    }
}

pub(super) fn rank_of(comm: MPI_Comm) -> Result<i32> {
    let mut r = 0;
    // SAFETY: valid communicator, one int out.
    mpi_ok(unsafe { ffi::MPI_Comm_rank(comm, &mut r) }, "MPI_Comm_rank")?;
    Ok(r)
}

pub(super) fn say_root(comm: MPI_Comm, line: &str) {
    if rank_of(comm).unwrap_or(1) == 0 {
        println!("{line}");
    }
}

/// Every rank's `mine` in rank order on rank 0 (`Some` there, `None` elsewhere); the total must
/// fit MPI's int counts (checked by the caller on every rank). Collective.
pub(super) fn gather_u64(comm: MPI_Comm, mine: &[u64]) -> Result<Option<Vec<u64>>> {
    let (mut size, root) = (0, rank_of(comm)? == 0);
    // SAFETY: valid communicator, one int out.
    mpi_ok(
        unsafe { ffi::MPI_Comm_size(comm, &mut size) },
        "MPI_Comm_size",
    )?;
    let count = mine.len() as i32;
    let mut counts = vec![0i32; if root { size as usize } else { 0 }];
    // SAFETY: one int per rank into `counts` (size entries on the root).
    mpi_ok(
        unsafe {
            ffi::MPI_Gather(
                &count as *const i32 as *const c_void,
                1,
                ffi::RSMPI_INT32_T,
                counts.as_mut_ptr() as *mut c_void,
                1,
                ffi::RSMPI_INT32_T,
                0,
                comm,
            )
        },
        "MPI_Gather",
    )?;
    let mut displs = Vec::with_capacity(counts.len());
    let mut total = 0i64;
    for &c in &counts {
        displs.push(total as i32);
        total += c as i64;
    }
    let mut all = vec![0u64; total as usize];
    // SAFETY: the root's buffer holds the sum of the counts; the others pass no buffer.
    mpi_ok(
        unsafe {
            ffi::MPI_Gatherv(
                mine.as_ptr() as *const c_void,
                count,
                ffi::RSMPI_UINT64_T,
                all.as_mut_ptr() as *mut c_void,
                counts.as_ptr(),
                displs.as_ptr(),
                ffi::RSMPI_UINT64_T,
                0,
                comm,
            )
        },
        "MPI_Gatherv",
    )?;
    Ok(root.then_some(all))
}

/// `v` of rank 0 on every rank of `comm` (the same length on every rank). Collective.
pub(super) fn broadcast_u64(comm: MPI_Comm, v: &mut [u64]) -> Result<()> {
    // SAFETY: `v.len()` u64 in place, from rank 0, on a valid communicator.
    mpi_ok(
        unsafe {
            ffi::MPI_Bcast(
                v.as_mut_ptr() as *mut c_void,
                v.len() as c_int,
                ffi::RSMPI_UINT64_T,
                0,
                comm,
            )
        },
        "MPI_Bcast",
    )
}
