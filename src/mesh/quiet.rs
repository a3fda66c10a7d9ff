//! `catch_unwind` without the panic message: a panic of the MSH parser on a malformed file is
//! turned into an `InputError`, and the user must see only that one line (no panic message
//! and no backtrace before it, even with `RUST_BACKTRACE=1`).
//!
//! The panic hook is process-wide, so it is not swapped around the call (that would also
//! silence a panic of another thread, e.g. another test). Instead a wrapper hook is installed
//! once; it stays quiet only on the thread that is inside [`catch_unwind_silently`] and
//! otherwise calls the hook that was installed before it.

use std::cell::Cell;
use std::panic::{self, UnwindSafe};
use std::sync::Once;

thread_local! {
    static QUIET: Cell<bool> = const { Cell::new(false) };
}

static INSTALL: Once = Once::new();

/// Runs `f`, catching a panic; the panic hook prints nothing for a panic on this thread
/// while `f` runs. The previous quiet state is restored afterwards.
pub(crate) fn catch_unwind_silently<R>(
    f: impl FnOnce() -> R + UnwindSafe,
) -> std::thread::Result<R> {
    INSTALL.call_once(|| {
        let previous = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            if !QUIET.with(Cell::get) {
                previous(info);
            }
        }));
    });
    let was = QUIET.with(|q| q.replace(true));
    let r = panic::catch_unwind(f);
    QUIET.with(|q| q.set(was));
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panic_is_caught_and_quiet_state_restored() {
        let r = catch_unwind_silently(|| -> u32 { panic!("parser failure") });
        assert!(r.is_err());
        assert!(!QUIET.with(Cell::get));
        assert_eq!(catch_unwind_silently(|| 7).ok(), Some(7));
    }
}
