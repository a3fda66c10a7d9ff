//! Why a round of candidates stops the Schur path.

/// Why a round of candidates stops the condensed path: the zone is too wide for the dense
/// limits (the plain path then starts from the half-space model's set, mod.rs), or something
/// failed.
pub(super) struct Stop {
    pub(super) why: String,
    pub(super) too_wide: bool,
}

impl Stop {
    pub(super) fn too_wide(why: String) -> Stop {
        Stop {
            why,
            too_wide: true,
        }
    }
    pub(super) fn failed(why: String) -> Stop {
        Stop {
            why,
            too_wide: false,
        }
    }
}
