//! The decision rules of Algorithms 1 and 2 after each step (converge, test the load balance,
//! iterate on the same sets, take new sets) and the guard against a recurring set (cycling).
//! Pure logic: no MPI, no PETSc, tested on one rank.

use crate::case::OnCycle;
use crate::error::RunError;

/// Identity of a set for the cycle test: |A_n|, two fingerprints and, with friction, ‖u‖²
/// rounded to 10 digits (the slip rows depend on the iterate, so only a recurring (set, u)
/// pair is a cycle there).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SetKey {
    pub n_active: usize,
    pub fingerprint: (f64, f64),
    pub u_norm2_rounded: f64,
}

impl SetKey {
    pub fn new(n_active: usize, fingerprint: (f64, f64), u_norm2: Option<f64>) -> SetKey {
        SetKey {
            n_active,
            fingerprint,
            u_norm2_rounded: u_norm2
                .map(|x| format!("{x:.9e}").parse::<f64>().unwrap_or(0.0))
                .unwrap_or(0.0),
        }
    }
}

/// What the loop does after a step's reduction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decision {
    /// No node changed and (friction) |u^ℓ − u^{ℓ−1}| / |u^ℓ| < tol_u (Coulomb: and the
    /// residual (F3) small): stop.
    Converged,
    /// No node changed but rigid modes are pinned: test that the pins carry no load first.
    TestBalance,
    /// No node changed but the slip rows still move (friction): same sets, new rows.
    SameSets,
    /// Nodes changed: new sets (after the cycle test).
    NewSets,
}

/// The stopping rules of Algorithm 1 (step 5: no set changed) and Algorithm 2 (no set changed
/// and |u^ℓ − u^{ℓ−1}| / |u^ℓ| < tol_u), with the balance test of free rigid modes first
/// whenever pins exist and the balance is not yet confirmed. `residual_ok`: Coulomb's residual
/// (F3) is below its tolerance (always true for the other laws); `residual_zero`: it is at
/// round-off, so the iterate is a solution without a further step to test |u^ℓ − u^{ℓ−1}|.
pub fn decide(
    changed: usize,
    balance_pending: bool,
    friction: bool,
    du_rel: f64,
    tol_u: f64,
    residual_ok: bool,
    residual_zero: bool,
) -> Decision {
    if changed > 0 {
        Decision::NewSets
    } else if balance_pending {
        Decision::TestBalance
    } else if !friction || residual_zero || (du_rel < tol_u && residual_ok) {
        Decision::Converged
    } else {
        Decision::SameSets
    }
}

/// The sets seen so far and the reaction to a recurrence.
pub struct CycleGuard {
    seen: Vec<SetKey>,
    on_cycle: OnCycle,
    friction: bool,
    least_index: bool,
    /// Step after which a recurring set switched the iteration to single-node updates.
    pub detected_at: Option<usize>,
}

/// The outcome of the cycle test of a new set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Seen {
    /// A set not seen before (or the iteration is already safeguarded).
    New,
    /// The set of step `prev` recurs: from now on single-node updates (least index).
    SwitchToLeastIndex { prev: usize },
}

impl CycleGuard {
    pub fn new(on_cycle: OnCycle, friction: bool, first: SetKey) -> CycleGuard {
        CycleGuard {
            seen: vec![first],
            on_cycle,
            friction,
            least_index: false,
            detected_at: None,
        }
    }

    /// Single-node updates are in force.
    pub fn least_index(&self) -> bool {
        self.least_index
    }

    /// Whether the plain iteration has gone through this set already (a recurrence that
    /// [`Self::check`] would report).
    pub fn has_seen(&self, key: SetKey) -> bool {
        !self.least_index && self.seen.contains(&key)
    }

    /// Records a set the iteration goes on with.
    pub fn record(&mut self, key: SetKey) {
        self.seen.push(key);
    }

    /// Test of the plain iteration's next set after `step` (before it is recorded). A recurrence
    /// is an error with friction or `on_cycle = "stop"`; otherwise the iteration switches to
    /// single-node updates (the seen sets restart from the current one).
    pub fn check(&mut self, step: usize, key: SetKey) -> Result<Seen, RunError> {
        if self.least_index {
            return Ok(Seen::New);
        }
        let Some(prev) = self.seen.iter().position(|s| *s == key) else {
            return Ok(Seen::New);
        };
        if self.friction || self.on_cycle == OnCycle::Stop {
            return Err(cycling_error(
                step + 1,
                key.n_active,
                Some(prev + 1),
                self.friction,
            ));
        }
        self.least_index = true;
        self.detected_at = Some(step + 1);
        // The safeguarded sequence may pass through sets of the plain iteration again.
        let current = *self.seen.last().expect("the current set is recorded");
        self.seen.clear();
        self.seen.push(current);
        Ok(Seen::SwitchToLeastIndex { prev: prev + 1 })
    }

    /// Test of a safeguarded (single-node) set: a recurrence even so is an error.
    pub fn check_safeguarded(&self, step: usize, key: SetKey) -> Result<(), RunError> {
        if self.seen.contains(&key) {
            return Err(cycling_error(step + 1, key.n_active, None, false));
        }
        Ok(())
    }
}

/// `prev`: the step whose set recurs (`None`: a recurrence of the safeguarded iteration).
fn cycling_error(step: usize, n: usize, prev: Option<usize>, friction: bool) -> RunError {
    RunError::NoConvergence(format!(
        "Newton cycling: the active set of step {step} (|A_n| = {n}) equals one seen {}{} — the \
         exact active-set iteration would loop forever; stopping",
        match prev {
            None => "earlier".to_string(),
            Some(p) => format!("at step {p}"),
        },
        if prev.is_none() {
            " even with single-node updates"
        } else if friction {
            " (Tresca/Coulomb: no single-node fallback)"
        } else {
            " (newton.on_cycle = \"stop\")"
        }
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(n: usize, h: f64) -> SetKey {
        SetKey::new(n, (h, 2.0 * h), None)
    }

    #[test]
    fn stopping_rules() {
        let d = |changed, pending, friction, du, ok, zero| {
            decide(changed, pending, friction, du, 1e-10, ok, zero)
        };
        assert_eq!(d(3, true, false, 0.0, true, false), Decision::NewSets);
        assert_eq!(d(0, true, false, 0.0, true, false), Decision::TestBalance);
        assert_eq!(d(0, false, false, 1.0, true, false), Decision::Converged);
        assert_eq!(d(0, false, true, 1e-12, true, false), Decision::Converged);
        assert_eq!(d(0, false, true, 1e-3, true, false), Decision::SameSets);
        // Coulomb: a small step is not enough while (F3) is not small
        assert_eq!(d(0, false, true, 1e-12, false, false), Decision::SameSets);
        assert_eq!(d(1, false, true, 1e-12, true, true), Decision::NewSets);
        // ... and (F3) at round-off needs no further step (but the balance test first)
        assert_eq!(d(0, false, true, 1e-3, true, true), Decision::Converged);
        assert_eq!(d(0, true, true, 1e-3, true, true), Decision::TestBalance);
    }

    #[test]
    fn a_recurring_set_switches_to_least_index() {
        let mut g = CycleGuard::new(OnCycle::LeastIndex, false, key(5, 1.0));
        assert_eq!(g.check(1, key(3, 2.0)).unwrap(), Seen::New);
        g.record(key(3, 2.0));
        assert_eq!(g.check(2, key(4, 3.0)).unwrap(), Seen::New);
        g.record(key(4, 3.0));
        // the set of step 2 (recorded second) recurs after step 3
        assert_eq!(
            g.check(3, key(3, 2.0)).unwrap(),
            Seen::SwitchToLeastIndex { prev: 2 }
        );
        assert!(g.least_index());
        assert_eq!(g.detected_at, Some(4));
        // only the current set is remembered: an older one is new again
        assert!(g.check_safeguarded(4, key(5, 1.0)).is_ok());
        assert!(g.check_safeguarded(4, key(4, 3.0)).is_err());
    }

    #[test]
    fn a_recurrence_is_an_error_with_friction_or_stop() {
        let mut g = CycleGuard::new(OnCycle::Stop, false, key(5, 1.0));
        let e = g.check(1, key(5, 1.0)).unwrap_err().to_string();
        assert!(e.contains("step 2") && e.contains("at step 1"), "{e}");
        assert!(e.contains("on_cycle"), "{e}");
        let mut g = CycleGuard::new(OnCycle::LeastIndex, true, key(5, 1.0));
        let e = g.check(1, key(5, 1.0)).unwrap_err().to_string();
        assert!(e.contains("Tresca/Coulomb"), "{e}");
        assert!(matches!(
            g.check(2, key(5, 1.0)),
            Err(RunError::NoConvergence(_))
        ));
    }

    #[test]
    fn friction_keys_tell_iterates_apart() {
        let a = SetKey::new(5, (1.0, 2.0), Some(1.234_567_890_12));
        let b = SetKey::new(5, (1.0, 2.0), Some(1.234_567_890_13));
        let c = SetKey::new(5, (1.0, 2.0), Some(1.3));
        assert_eq!(a, b); // equal to 10 digits
        assert_ne!(a, c);
    }
}
