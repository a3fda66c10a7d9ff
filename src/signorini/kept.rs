//! The factorisation a condensed solve hands from one load step to the next ([`KeptFactor`]).

use super::schur::Kept;
use std::cell::RefCell;

/// A condensed solve's factorisation of K_p with its Schur complement, compliance and
/// candidates ([`Kept`]; frictionless or Coulomb), handed from one load step to the
/// next: K_p does not change between load steps, so the next step reuses it where the
/// candidates' frames and the pins are the same (`Kept::holds`). Empty unless the last step
/// was solved on the contact unknowns.
#[derive(Default)]
pub struct KeptFactor {
    kept: RefCell<Option<Kept>>,
    /// Rank 0: the nested-dissection order of K_p's node graph (the same graph in every load
    /// step), where the step kept no factorisation with it (a frictionless step that held a
    /// wide zone, or a held zone's pass before).
    order: RefCell<Option<Vec<usize>>>,
}

impl KeptFactor {
    /// What the previous load step kept (`previous`: its own, taken from it); empty without
    /// one.
    pub(super) fn taken_from(previous: Option<&KeptFactor>) -> KeptFactor {
        KeptFactor {
            kept: RefCell::new(previous.and_then(|p| p.take())),
            order: RefCell::new(previous.and_then(|p| p.take_order())),
        }
    }

    pub(super) fn take(&self) -> Option<Kept> {
        self.kept.borrow_mut().take()
    }

    pub(super) fn put(&self, kept: Kept) {
        *self.kept.borrow_mut() = Some(kept);
    }

    /// No factorisation is kept (the previous load step ran the plain path, or there was
    /// none).
    pub(super) fn is_empty(&self) -> bool {
        self.kept.borrow().is_none()
    }

    /// The kept factorisation holds a wide zone's interior (friction: sticking).
    pub(super) fn holds_zone(&self) -> bool {
        let kept = self.kept.borrow();
        kept.as_ref().is_some_and(|k| k.held.iter().any(|&h| h))
    }

    pub(super) fn take_order(&self) -> Option<Vec<usize>> {
        self.order.borrow_mut().take()
    }

    pub(super) fn put_order(&self, order: Option<Vec<usize>>) {
        *self.order.borrow_mut() = order;
    }
}
