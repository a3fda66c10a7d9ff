//! The tangential laws of a solve as types (docs/friction.md). Each law's file gives what the
//! rest of the algorithm asks of it ([`FrictionLaw`], rules.rs): its nodes' tangential rows in
//! the set update (3.33)/(3.39) or (F5)/(F6), its threshold b, its residual, the thresholds the
//! friction certificate (3.18) judges its final state by and its friction capacity before the
//! solve. [`Law`] names the law of a solve; its `rules` is the one dispatch to its type.
//!
//! A new law: one file here implementing [`FrictionLaw`], a variant of [`Law`] with its lines
//! in `Law::rules` and `Law::of` (and its keys in the case file and setup.rs).

pub mod coulomb;
mod none;
mod rules;
mod tresca;

pub use coulomb::Coulomb;
pub use none::Frictionless;
pub use rules::{increment, FloatingLoad, FrictionLaw, STICK_TOL};
pub use tresca::Tresca;

use crate::setup::ContactSettings;

/// The tangential law of a solve: which rows the set update forms (docs/friction.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Law {
    /// Algorithm 1: no tangential state ([`Frictionless`]).
    Frictionless,
    /// Algorithm 2 with the nodal thresholds b_k of the contact boundary (3.18) ([`Tresca`]).
    Tresca,
    /// The generalised Newton: b = μ max(0, −λ_n − c(u_n + g)) (F1), rows (F5)/(F6), with each
    /// node's μ (`ContactNode::mu`: its pair's) ([`Coulomb`]).
    Coulomb,
}

impl Law {
    /// The law's type: its rows, threshold, residual, certificate thresholds and capacity.
    pub fn rules(self) -> &'static dyn FrictionLaw {
        match self {
            Law::Frictionless => &Frictionless,
            Law::Tresca => &Tresca,
            Law::Coulomb => &Coulomb,
        }
    }

    /// The law's name as the log's lines of a friction solve begin ("tresca: …").
    pub fn name(self) -> &'static str {
        match self {
            Law::Frictionless => "frictionless",
            Law::Tresca => "tresca",
            Law::Coulomb => "coulomb",
        }
    }

    /// The law has tangential states (rows, thresholds).
    pub fn friction(self) -> bool {
        self.rules().friction()
    }

    /// The tangential law of the settings (Coulomb's fixed point runs Tresca solves inside).
    pub fn of(settings: &ContactSettings) -> Law {
        match (settings.tresca, settings.coulomb) {
            (true, _) => Law::Tresca,
            (false, Some(_)) => Law::Coulomb,
            (false, None) => Law::Frictionless,
        }
    }
}
