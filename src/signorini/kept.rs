//! The factorisation a condensed solve hands from one load step to the next ([`KeptFactor`]).

use super::schur::Kept;

/// A condensed solve's factorisation of K_p with its Schur complement, compliance and
/// candidates ([`Kept`]; frictionless or Coulomb), handed from one load step to the
/// next: K_p does not change between load steps, so the next step reuses it where the
/// candidates' frames and the pins are the same (`Kept::holds`). Empty unless the last step
/// was solved on the contact unknowns. Owned by the run's [`Session`](super::session::Session).
#[derive(Default)]
pub struct KeptFactor {
    kept: Option<Kept>,
    /// Rank 0: the nested-dissection order of K_p's node graph (the same graph in every load
    /// step), where the step kept no factorisation with it (a frictionless step that held a
    /// wide zone, or a held zone's pass before).
    order: Option<Vec<usize>>,
}

impl KeptFactor {
    pub(crate) fn take(&mut self) -> Option<Kept> {
        self.kept.take()
    }

    pub(crate) fn put(&mut self, kept: Kept) {
        self.kept = Some(kept);
    }

    /// No factorisation is kept (the previous load step ran the plain path, or there was
    /// none).
    pub(crate) fn is_empty(&self) -> bool {
        self.kept.is_none()
    }

    /// The kept factorisation holds a wide zone's interior (friction: sticking).
    pub(crate) fn holds_zone(&self) -> bool {
        (self.kept.as_ref()).is_some_and(|k| k.held.iter().any(|&h| h))
    }

    pub(crate) fn take_order(&mut self) -> Option<Vec<usize>> {
        self.order.take()
    }

    pub(crate) fn put_order(&mut self, order: Option<Vec<usize>>) {
        self.order = order;
    }

    /// Drops the factorisation and the node order.
    pub(crate) fn clear(&mut self) {
        self.kept = None;
        self.order = None;
    }
}
