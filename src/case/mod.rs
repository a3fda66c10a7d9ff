//! The TOML case file: schema, defaults, validation, `--set` overrides.
//!
//! The file is parsed with `toml_edit` (which keeps spans) into a small owned tree that
//! remembers the line of every key; `--set` overrides are applied to that tree (marked as
//! coming from the command line) and the result is validated by hand, so that every error
//! names the file, the key path (`material.poisson`, `dirichlet[1].value`, `neumann[0]`)
//! and the line of that key, or says "(from --set)".
//!
//! The sections' types and their readers live by topic: `body` (mesh, material, boundary
//! conditions, body force), `solver` (`[solver]`, `[newton]`), `output`, `contact`
//! (pairs, histories, friction), `shape` (obstacle shapes), `load` (`[load]`); `file`
//! holds the validated [`Case`], `against_mesh` its checks against the mesh, `reader` the
//! typed reading of the value tree.

mod against_mesh;
mod body;
mod contact;
mod file;
pub mod keys;
mod load;
mod magnitude;
mod output;
mod reader;
mod shape;
mod solver;
mod tree;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_shapes;

pub use body::{
    BodyForceSpec, Dirichlet, Load, MaterialModel, MaterialSection, MeshSection, Neumann,
    Projection,
};
pub use contact::{ContactSection, CoulombAlgorithm, Friction, Motion, RigidModeHandling};
pub use file::{Case, MAX_CASE_BYTES};
pub use load::LoadSection;
pub use output::{OutputField, OutputSection, DEFAULT_FIELDS};
pub use shape::{vec3, ObstacleSpec};
pub use solver::{
    DenseThreads, Method, NewtonInit, NewtonSection, OnCycle, Preset, Reuse, SolverPath,
    SolverSection,
};
