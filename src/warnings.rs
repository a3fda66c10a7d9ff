//! Warnings: runs that succeed but whose result looks wrong (docs/warnings.md). Each is one
//! log line `warning: ...` on rank 0 and an entry of summary.json's `warnings` list; the exit
//! code stays 0. Every warning is computed from reductions, so every rank holds the same list.

use crate::par::Ctx;
use crate::say;
use serde::Serialize;

/// A pressed obstacle that ends with no active contact node (signorini/warn.rs).
pub const PRESSED_WITHOUT_CONTACT: &str = "pressed_without_contact";
/// Contact nodes that start on the obstacle's far side, or inside it by more than
/// [`START_INSIDE_FRACTION`] of the body's size (signorini/warn.rs).
pub const START_INSIDE: &str = "start_inside_obstacle";
/// A contact force that pulls the body's surface outward (signorini/warn.rs).
pub const PULLING_FORCE: &str = "pulling_contact_force";
/// Boundary nodes outside a pair's contact group (or left to their Dirichlet data) that end
/// beyond its rigid obstacle's surface, having started on the body's side (signorini/warn.rs).
pub const THROUGH_OBSTACLE: &str = "boundary_through_obstacle";
/// A strain beyond small deformations (post.rs).
pub const LARGE_DEFORMATION: &str = "large_deformation";
/// A final state that violates (3.14) or (3.18) beyond round-off but within the acceptance
/// tolerance: the linear solves were inexact (signorini/final_state.rs).
pub const INEXACT_FINAL_STATE: &str = "inexact_final_state";

/// `contact.rigid_modes = "none"` on a body that its Dirichlet data leave free in some rigid
/// mode (driver.rs): where its contact does not hold that mode, round-off decides it.
pub const RIGID_MODES_UNHANDLED: &str = "rigid_modes_unhandled";

/// Two `[[dirichlet]]` entries on different groups that prescribe a shared node's component
/// differently: the later one's value holds (setup.rs).
pub const DIRICHLET_OVERRIDDEN: &str = "dirichlet_overridden";

/// PETSc options (case file or command line) that nothing in the run read (linsolve.rs).
pub const UNUSED_PETSC_OPTIONS: &str = "unused_petsc_options";

/// Surface nodes of the mesh at one point without being one node, not joined by a contact pair:
/// parts meshed apart and never joined (driver.rs, coincident.rs).
pub const UNJOINED_NODES: &str = "unjoined_nodes";

/// A material whose Poisson's ratio is close to 1/2: P1 elements lock (setup.rs).
pub const NEARLY_INCOMPRESSIBLE: &str = "nearly_incompressible";

/// The worst violation of the final state's certificates, relative to the problem's scales,
/// above which [`INEXACT_FINAL_STATE`] is raised: about what the round-off of a direct solve
/// leaves (the default runs end at 1e-16–1e-10, docs/numbers.md), far below what an iterative
/// solve at `solver.rtol` = 1e-7 leaves (1e-7 on the 2D Hertz case, tests/warnings.rs).
pub const CERTIFICATE_ROUND_OFF: f64 = 1e-8;

/// Contact nodes starting deeper inside the obstacle than this fraction of the body's size
/// (the largest side of its bounding box) are warned about (deeper than
/// `boundary::DEEP_START_FRACTION`, 10 %, is an input error). Smaller overlaps are the usual
/// way to prescribe an indenter's depth (examples/indent_wedge2d.toml: 0.98 %,
/// cases/blocks/indent2d.toml: 0.5 %, tests/cases/indent2d_half.toml: 1 %).
pub const START_INSIDE_FRACTION: f64 = 0.02;

/// The largest absolute principal strain of a cell above which the solution is beyond small
/// deformations (strains of 5 %: the linear theory's error, of the order of the strain, then
/// exceeds a usual mesh's discretisation error). The strain, not the displacement gradient:
/// the gradient also holds the rotation, which reaches 0.088 at the edge of the default Hertz
/// case's contact zone while its largest strain stays below 0.05 (docs/warnings.md).
pub const LARGE_STRAIN: f64 = 0.05;

/// A strain counts as above [`LARGE_STRAIN`] from (1 + this) times it on: a strain of 0.05
/// itself (the uniaxial strain p / E of cases/blocks/block2d.toml in plane stress and of
/// block3d.toml, p = E / 20) is not warned about, whatever its round-off.
pub const STRAIN_RTOL: f64 = 1e-6;

/// A pair's contact force is warned about when the part of it that pulls the body's surface
/// outward exceeds this fraction of its normal part.
pub const PULL_FRACTION: f64 = 0.1;

/// Where a warning's value was found: a node or cell (gmsh tag) and its coordinates.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Place {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub node: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cell: Option<u64>,
    /// Coordinates (dim entries; a cell's centroid).
    pub x: Vec<f64>,
}

/// One warning of summary.json's `warnings` list.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Warning {
    /// What kind (the constants above).
    pub code: &'static str,
    /// The log line's text (after `warning: `).
    pub message: String,
    /// The case key concerned, e.g. `contact.obstacle` (absent where none is).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub key: Option<String>,
    /// The contact pair's table, `contact` or `contact[i]` (a pair's warning).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pair: Option<String>,
    /// The value the threshold was exceeded by (a depth, a gradient, a force fraction, ...).
    pub value: f64,
    /// The threshold it was judged against.
    pub threshold: f64,
    /// Where the value was found.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at: Option<Place>,
    /// A load series' top-level list: the converged steps that raised it (the first one's
    /// message is kept).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub steps: Vec<usize>,
}

impl Warning {
    /// Is `other` the same warning (code, key and pair), raised again?
    fn same(&self, other: &Warning) -> bool {
        self.code == other.code && self.key == other.key && self.pair == other.pair
    }
}

/// Logs every warning of `list` on rank 0, one line each (`warning: PREFIXmessage`).
/// Collective-free.
pub fn log(ctx: &Ctx, list: &[Warning], prefix: &str) {
    for w in list {
        say!(ctx, "warning: {prefix}{}", w.message);
    }
}

/// A load series' warnings: each step's list and the run's list, where a warning raised in
/// several steps is one entry (its first message, the steps that raised it). Pure.
#[derive(Debug, Default, Clone)]
pub struct Collected {
    pub list: Vec<Warning>,
}

impl Collected {
    /// Adds step `step`'s warnings; returns those not raised by an earlier step (to log).
    pub fn add(&mut self, step: usize, warnings: &[Warning]) -> Vec<Warning> {
        let mut new = Vec::new();
        for w in warnings {
            match self.list.iter_mut().find(|x| x.same(w)) {
                Some(x) => x.steps.push(step),
                None => {
                    new.push(w.clone());
                    self.list.push(Warning {
                        steps: vec![step],
                        ..w.clone()
                    });
                }
            }
        }
        new
    }
}

/// Formats coordinates for a message: `[x, y]` with 6 decimals.
pub fn coords(x: &[f64]) -> String {
    let parts: Vec<String> = x.iter().map(|v| format!("{v:.6}")).collect();
    format!("[{}]", parts.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(code: &'static str, pair: &str) -> Warning {
        Warning {
            code,
            message: format!("{code} {pair}"),
            key: None,
            pair: Some(pair.to_string()),
            value: 1.0,
            threshold: 0.5,
            at: None,
            steps: Vec::new(),
        }
    }

    #[test]
    fn a_warning_raised_again_is_one_entry_with_its_steps() {
        let mut c = Collected::default();
        let new = c.add(1, &[w(START_INSIDE, "contact")]);
        assert_eq!(new.len(), 1);
        let new = c.add(
            2,
            &[w(START_INSIDE, "contact"), w(PULLING_FORCE, "contact")],
        );
        assert_eq!(new.len(), 1);
        assert_eq!(new[0].code, PULLING_FORCE);
        assert!(c.add(3, &[w(START_INSIDE, "contact[1]")]).len() == 1);
        assert_eq!(c.list.len(), 3);
        assert_eq!(c.list[0].steps, vec![1, 2]);
        assert_eq!(c.list[1].steps, vec![2]);
        assert_eq!(c.list[2].steps, vec![3]);
    }
}
