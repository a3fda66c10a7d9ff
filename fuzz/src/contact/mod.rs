//! The obstacle shapes of the main crate's `contact` module, compiled from its source files
//! (the rest of `contact` is the solver's).

#[path = "../../../src/contact/obstacle/mod.rs"]
pub mod obstacle;

#[path = "../../../src/contact/height.rs"]
pub mod height;

#[path = "../../../src/contact/surface.rs"]
pub mod surface;

pub use obstacle::{Obstacle, ObstacleError, Plane, Projection, Sphere};
