//! Ending every rank when one rank cannot go on: the last resort of the parallel rule (see
//! [`crate::par`]). Two ways lead here:
//!
//! - a panic outside a caught scope ([`catching`]): the hook installed by [`install_panic_hook`]
//!   prints the message and aborts the communicator before anything unwinds, so no collective
//!   destructor (MUMPS' JOB = −2, PETSc's destroys) runs on one rank while the others wait;
//! - a failure this rank raised alone ([`raised`]: every failed PETSc call and every error of the
//!   binding layer's own checks) that no agreement has yet shared with the other ranks
//!   ([`covered`]): the next collective destructor or collective helper on this rank
//!   ([`before_collective`]) ends every rank with it instead of entering a collective the
//!   others are not in.
//!
//! Agreed errors (every rank has the same one, [`crate::par::Ctx::agree`]) never end here: they
//! return to `main`, which prints them once, or become an agreed fallback.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// A failure this rank raised alone, pending until an agreement covers it.
struct Pending {
    /// Fast path of the check.
    set: AtomicBool,
    /// The first pending failure's message.
    message: Mutex<String>,
}

impl Pending {
    const fn new() -> Self {
        Pending {
            set: AtomicBool::new(false),
            message: Mutex::new(String::new()),
        }
    }

    fn raise(&self, message: &str) {
        if let Ok(mut m) = self.message.lock() {
            if !self.set.load(Ordering::Acquire) {
                *m = message.to_string();
            }
        }
        self.set.store(true, Ordering::Release);
    }

    fn reword(&self, message: &str) {
        if self.set.load(Ordering::Acquire) {
            if let Ok(mut m) = self.message.lock() {
                *m = message.to_string();
            }
        }
    }

    fn cover(&self) {
        self.set.store(false, Ordering::Release);
    }

    fn get(&self) -> Option<String> {
        self.set
            .load(Ordering::Acquire)
            .then(|| self.message.lock().map(|m| m.clone()).unwrap_or_default())
    }
}

static PENDING: Pending = Pending::new();
/// Set once the panic hook is installed (by the binary, after MPI is initialised): without it
/// (unit tests, no MPI) nothing here aborts.
static ARMED: AtomicBool = AtomicBool::new(false);

thread_local! {
    /// Depth of [`catching`] scopes on this thread: a panic there is caught and agreed.
    static CAUGHT: Cell<u32> = const { Cell::new(0) };
}

/// Records a failure raised on this rank alone (`message`): from here until an agreement
/// covers it, a collective on this rank ends every rank. Local.
pub fn raised(message: &str) {
    PENDING.raise(message);
}

/// The pending failure, if any, said better (e.g. PETSc's "Error in external library" as the
/// library's own message). Local.
pub fn reworded(message: &str) {
    PENDING.reword(message);
}

/// An agreement has shared this rank's failure with every rank (or every rank learned that
/// none failed): nothing is pending any more. Local.
pub fn covered() {
    PENDING.cover();
}

/// This rank handled its failure by itself, on a path that needs no other rank to know (e.g. a
/// local ordering that falls back to MUMPS' own): nothing is pending any more. Local.
pub fn handled() {
    PENDING.cover();
}

/// The failure this rank raised alone and no agreement has covered, if any. Local.
pub fn pending() -> Option<String> {
    PENDING.get()
}

/// Called before a collective that is not an agreement (a collective destroy, a reduction, a
/// gather): with a failure pending on this rank, the others are not in this collective, so
/// every rank ends now, with the failure's message and exit code 1. Local (no MPI call unless
/// it aborts).
pub fn before_collective() {
    if !ARMED.load(Ordering::Acquire) {
        return;
    }
    let Some(m) = pending() else {
        return;
    };
    end_every_rank(&format!("{m} (on this rank alone: every rank ends)"), 1);
}

/// This process' rank in the world communicator (MPI must be initialised). Local.
pub fn world_rank() -> usize {
    use mpi::traits::Communicator;
    mpi::topology::SimpleCommunicator::world().rank() as usize
}

/// Prints `error (rank R): message` and aborts every rank of the world communicator with
/// `code`. No destructor runs. Requires MPI to be initialised.
pub fn end_every_rank(message: &str, code: i32) -> ! {
    use mpi::traits::Communicator;
    let world = mpi::topology::SimpleCommunicator::world();
    eprintln!("error (rank {}): {message}", world.rank());
    world.abort(code)
}

/// Installs the process-wide panic hook of the binary (after MPI is initialised): a panic on
/// any thread outside [`catching`] prints `error (rank R): internal error: …` with its place and
/// aborts every rank (exit code 101) before unwinding; inside [`catching`] the previous hook
/// prints it and the panic unwinds to the catch.
pub fn install_panic_hook() {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if CAUGHT.with(Cell::get) > 0 {
            previous(info);
            return;
        }
        let what = panic_message(info.payload());
        let place = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        end_every_rank(&format!("internal error: {what}{place}"), 101);
    }));
    ARMED.store(true, Ordering::Release);
}

/// Runs `f` with a panic caught (for a one-rank computation inside a collective stage whose
/// failure the stage then agrees on): the panic hook does not abort for it. Local.
pub fn catching<R>(f: impl FnOnce() -> R) -> std::thread::Result<R> {
    CAUGHT.with(|c| c.set(c.get() + 1));
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    CAUGHT.with(|c| c.set(c.get() - 1));
    r
}

/// The message of a caught panic's payload.
pub fn panic_message(e: &(dyn std::any::Any + Send)) -> String {
    e.downcast_ref::<String>()
        .cloned()
        .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "a panic".to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_raised_failure_is_pending_until_covered() {
        let p = Pending::new();
        assert!(p.get().is_none());
        p.raise("first");
        p.raise("second");
        assert_eq!(p.get().as_deref(), Some("first"));
        p.cover();
        assert!(p.get().is_none());
        p.reword("not pending: ignored");
        assert!(p.get().is_none());
        p.raise("third");
        p.reword("third, said better");
        assert_eq!(p.get().as_deref(), Some("third, said better"));
    }

    #[test]
    fn catching_returns_the_panic() {
        let r = catching(|| -> u32 { panic!("inside") });
        assert_eq!(panic_message(&*r.unwrap_err()), "inside");
        assert_eq!(catching(|| 3).ok(), Some(3));
    }
}
