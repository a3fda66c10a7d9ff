//! Invalid obstacle data, or a query point without a defined normal.

use crate::error::InputError;
use std::fmt;
use std::path::Path;

/// Fewest faces of a pyramid (`Pyramid`).
pub const MIN_FACES: usize = 3;
/// Most faces of a pyramid (`Pyramid`) (a pyramid with many more faces is a cone (`Cone`); the queries cost
/// O(faces)).
pub const MAX_FACES: usize = 64;

/// Invalid obstacle data, or a query point without a defined normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ObstacleError {
    /// A coordinate or the radius is NaN or infinite.
    NotFinite,
    /// The plane's normal is the zero vector.
    ZeroNormal,
    /// The sphere's radius is ≤ 0.
    NonPositiveRadius,
    /// A 2D obstacle has a non-zero z component (point, normal or centre).
    NonZeroZ,
    /// Dimension other than 2 or 3.
    BadDim(usize),
    /// Sphere query at its centre: no defined normal.
    AtCentre,
    /// The axis of a cylinder, cone, pyramid or punch is the zero vector.
    ZeroAxis,
    /// The radius of a cylinder or punch is ≤ 0.
    BadRadius,
    /// A cone's or pyramid's half angle is not in (0, 90) degrees.
    BadHalfAngle,
    /// A pyramid's number of faces is not in [`MIN_FACES`, `MAX_FACES`].
    BadFaces(usize),
    /// A punch's edge radius is not in [0, radius].
    BadEdgeRadius,
    /// A shape that exists in 3D only (its name) asked for in 2D.
    Only3D(&'static str),
    /// A deformable body (`type = "body"`) asked for as a rigid shape.
    NotRigid,
    /// Cylinder query on its axis: no defined normal.
    OnAxis,
    /// A height expression with variables other than x (2D) or x, y (3D).
    HeightVariables,
    /// The height h is not a finite number at (x) or (x, y) near a queried point.
    HeightNotFinite { x: f64, y: Option<f64> },
    /// The nearest point of a height surface was not found.
    HeightNoConvergence,
    /// The slope of h jumps at the nearest point (x) or (x, y): a kink or a step.
    HeightNotSmooth { x: f64, y: Option<f64> },
}

impl fmt::Display for ObstacleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ObstacleError::NotFinite => write!(f, "obstacle data must be finite numbers"),
            ObstacleError::ZeroNormal => write!(f, "the plane normal must not be the zero vector"),
            ObstacleError::NonPositiveRadius => write!(f, "the sphere radius must be > 0"),
            ObstacleError::NonZeroZ => {
                write!(
                    f,
                    "a 2D obstacle must have z = 0 in its point, normal and centre"
                )
            }
            ObstacleError::BadDim(d) => write!(f, "dimension must be 2 or 3, got {d}"),
            ObstacleError::AtCentre => write!(
                f,
                "a contact node lies at the centre of the sphere obstacle: no normal is defined"
            ),
            ObstacleError::ZeroAxis => write!(f, "the axis must not be the zero vector"),
            ObstacleError::BadRadius => write!(f, "the radius must be > 0"),
            ObstacleError::BadHalfAngle => {
                write!(f, "the half angle must lie in (0, 90) degrees")
            }
            ObstacleError::BadFaces(n) => write!(
                f,
                "a pyramid needs {MIN_FACES} to {MAX_FACES} faces, got {n}"
            ),
            ObstacleError::BadEdgeRadius => {
                write!(f, "the edge radius must lie in [0, radius]")
            }
            ObstacleError::Only3D(name) => {
                write!(f, "a {name} obstacle exists in 3D only")
            }
            ObstacleError::NotRigid => write!(
                f,
                "a body (type = \"body\") is not a rigid obstacle: its contact is set up from \
                 the mesh (dual mortar)"
            ),
            ObstacleError::OnAxis => write!(
                f,
                "a contact node lies on the axis of the cylinder obstacle: no normal is defined"
            ),
            ObstacleError::HeightVariables => write!(
                f,
                "the height expression 'expr' may use only x (2D) or x and y (3D)"
            ),
            ObstacleError::HeightNotFinite { x, y } => {
                let at = match y {
                    Some(y) => format!("(x, y) = ({x}, {y})"),
                    None => format!("x = {x}"),
                };
                write!(
                    f,
                    "the height expression 'expr' is not a finite number at \
                     {at}, near the node (the obstacle's surface must be defined and smooth \
                     under the contact boundary)"
                )
            }
            ObstacleError::HeightNotSmooth { x, y } => {
                let at = match y {
                    Some(y) => format!("(x, y) = ({x}, {y})"),
                    None => format!("x = {x}"),
                };
                write!(
                    f,
                    "the height surface 'expr' has a kink or a step at {at}, \
                     the nearest point to the node (its slope jumps there): the surface must be \
                     smooth (C¹) near the body"
                )
            }
            ObstacleError::HeightNoConvergence => write!(
                f,
                "the nearest point on the height surface 'expr' was not found \
                 (the projection did not converge): the surface must be smooth (C¹) near the \
                 body, without kinks or steps"
            ),
        }
    }
}

impl std::error::Error for ObstacleError {}

impl ObstacleError {
    /// Wrap as a user-facing [`InputError`] for the case file `file`, key `key`.
    pub fn into_input_error(self, file: &Path, key: &str) -> InputError {
        InputError::new(file, self.to_string()).with_key(key)
    }

    /// The key of the obstacle's table the error is about: `obstacle.expr` for the height
    /// expression, else `obstacle`.
    pub fn key_in_pair(&self) -> &'static str {
        match self {
            ObstacleError::HeightVariables
            | ObstacleError::HeightNotFinite { .. }
            | ObstacleError::HeightNotSmooth { .. }
            | ObstacleError::HeightNoConvergence => "obstacle.expr",
            _ => "obstacle",
        }
    }
}
