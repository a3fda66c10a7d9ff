//! Obstacle shapes (`contact.obstacle`, `mesh.project[i].shape`).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::keys;
use super::reader::{Reader, Res, Tab};
use super::tree::{Kind, Node};
use crate::contact::obstacle::{
    Cone, Cylinder, Height, HeightExpr, Punch, Pyramid, TriSurface, MAX_FACES, MIN_FACES,
};
use crate::contact::{Obstacle, ObstacleError, Plane, Sphere};

/// A vector of the case file (2 or 3 entries) as 3 components, z = 0 in 2D.
pub fn vec3(v: &[f64]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (o, x) in out.iter_mut().zip(v) {
        *o = *x;
    }
    out
}

/// A rigid obstacle (or a `[[mesh.project]]` shape) as the case file gives it: vectors with
/// 2 or 3 components (their number checked against the mesh later), axes and normals unit
/// vectors, angles in degrees (docs/obstacles.md).
#[derive(Debug, Clone, PartialEq)]
pub enum ObstacleSpec {
    /// Half-space bounded by the plane through `point`; `normal` is a unit vector.
    Plane { point: Vec<f64>, normal: Vec<f64> },
    /// Ball (circle in 2D).
    Sphere { center: Vec<f64>, radius: f64 },
    /// Infinite circular cylinder around the line through `point` along `axis` (3D only).
    Cylinder {
        point: Vec<f64>,
        axis: Vec<f64>,
        radius: f64,
    },
    /// Solid cone (wedge in 2D) with its tip at `apex`; `axis` points from the tip into the
    /// indenter; 0 < `half_angle` < 90 degrees.
    Cone {
        apex: Vec<f64>,
        axis: Vec<f64>,
        half_angle: f64,
    },
    /// Regular pyramid (3D only) of `faces` planar faces, each at `half_angle` degrees to the
    /// axis; `azimuth` (degrees) turns face 0 about the axis from the reference direction.
    Pyramid {
        apex: Vec<f64>,
        axis: Vec<f64>,
        half_angle: f64,
        faces: usize,
        azimuth: f64,
    },
    /// Flat-ended cylinder (strip in 2D) whose end face is centred at `center` with the
    /// outward normal −`axis`; its edge rounded with `edge_radius` in [0, `radius`].
    Punch {
        center: Vec<f64>,
        axis: Vec<f64>,
        radius: f64,
        edge_radius: f64,
    },
    /// The solid below the graph y = h(x) (2D) or z = h(x, y) (3D) of a parsed expression.
    Height { expr: Arc<HeightExpr> },
    /// The solid inside the closed triangle surface read from `file` (3D only; resolved
    /// against the case file's directory).
    Surface {
        file: PathBuf,
        surface: Arc<TriSurface>,
    },
    /// Another deformable body of the mesh: `group` names its boundary facets that the pair's
    /// group may touch (the master side of dual mortar; docs/bodies.md).
    Body { group: String },
}

impl ObstacleSpec {
    /// The spelling of the type in the case file.
    pub fn type_name(&self) -> &'static str {
        match self {
            ObstacleSpec::Plane { .. } => "plane",
            ObstacleSpec::Sphere { .. } => "sphere",
            ObstacleSpec::Cylinder { .. } => "cylinder",
            ObstacleSpec::Cone { .. } => "cone",
            ObstacleSpec::Pyramid { .. } => "pyramid",
            ObstacleSpec::Punch { .. } => "punch",
            ObstacleSpec::Height { .. } => "height",
            ObstacleSpec::Surface { .. } => "surface",
            ObstacleSpec::Body { .. } => "body",
        }
    }

    /// The vector keys with their numbers of components, in the order they are checked.
    pub fn vectors(&self) -> Vec<(&'static str, usize)> {
        match self {
            ObstacleSpec::Plane { point, normal } => {
                vec![("point", point.len()), ("normal", normal.len())]
            }
            ObstacleSpec::Sphere { center, .. } => vec![("center", center.len())],
            ObstacleSpec::Cylinder { point, axis, .. } => {
                vec![("point", point.len()), ("axis", axis.len())]
            }
            ObstacleSpec::Cone { apex, axis, .. } | ObstacleSpec::Pyramid { apex, axis, .. } => {
                vec![("apex", apex.len()), ("axis", axis.len())]
            }
            ObstacleSpec::Punch { center, axis, .. } => {
                vec![("center", center.len()), ("axis", axis.len())]
            }
            ObstacleSpec::Height { .. }
            | ObstacleSpec::Surface { .. }
            | ObstacleSpec::Body { .. } => Vec::new(),
        }
    }

    /// For a shape that exists in 3D only: what to use in 2D instead.
    pub(super) fn in_2d_use(&self) -> Option<&'static str> {
        match self {
            ObstacleSpec::Cylinder { .. } => Some("\"sphere\" (a circle)"),
            ObstacleSpec::Pyramid { .. } => Some("\"cone\" (a wedge)"),
            ObstacleSpec::Surface { .. } => Some("\"height\" (a curve y = h(x))"),
            _ => None,
        }
    }

    /// The obstacle of dimension `dim` (the vectors have `dim` components:
    /// [`Case::check_against_mesh`], [`Case::check_projections`]).
    pub fn to_obstacle(&self, dim: usize) -> Result<Obstacle, ObstacleError> {
        Ok(match self {
            ObstacleSpec::Plane { point, normal } => {
                Obstacle::Plane(Plane::new(vec3(point), vec3(normal), dim)?)
            }
            ObstacleSpec::Sphere { center, radius } => {
                Obstacle::Sphere(Sphere::new(vec3(center), *radius, dim)?)
            }
            ObstacleSpec::Cylinder {
                point,
                axis,
                radius,
            } => Obstacle::Cylinder(Cylinder::new(vec3(point), vec3(axis), *radius, dim)?),
            ObstacleSpec::Cone {
                apex,
                axis,
                half_angle,
            } => Obstacle::Cone(Cone::new(vec3(apex), vec3(axis), *half_angle, dim)?),
            ObstacleSpec::Pyramid {
                apex,
                axis,
                half_angle,
                faces,
                azimuth,
            } => Obstacle::Pyramid(Pyramid::new(
                vec3(apex),
                vec3(axis),
                *half_angle,
                *faces,
                *azimuth,
                dim,
            )?),
            ObstacleSpec::Punch {
                center,
                axis,
                radius,
                edge_radius,
            } => Obstacle::Punch(Punch::new(
                vec3(center),
                vec3(axis),
                *radius,
                *edge_radius,
                dim,
            )?),
            ObstacleSpec::Height { expr } => Obstacle::Height(Height::new(expr.clone(), dim)?),
            ObstacleSpec::Surface { surface, .. } => {
                if dim != 3 {
                    return Err(ObstacleError::Only3D("surface"));
                }
                Obstacle::Surface(surface.clone())
            }
            ObstacleSpec::Body { group } => {
                Obstacle::Body(std::sync::Arc::new(crate::contact::obstacle::BodyTarget {
                    group: group.clone(),
                    dim,
                    rows: Default::default(),
                }))
            }
        })
    }
}

impl Reader<'_> {
    /// An obstacle shape at `key`: its `type` first, then the keys that type allows.
    pub(super) fn obstacle(&self, key: &str, n: &Node) -> Res<ObstacleSpec> {
        // First read the type, then check the keys that type allows.
        let t = self.table_any(key, n)?;
        let (tk, ty) = self.required(&t, "type")?;
        #[derive(Clone, Copy)]
        enum Ty {
            Plane,
            Sphere,
            Cylinder,
            Cone,
            Pyramid,
            Punch,
            Height,
            Surface,
            Body,
        }
        let ty = self.choice(
            &tk,
            ty,
            &[
                ("plane", Ty::Plane),
                ("sphere", Ty::Sphere),
                ("cylinder", Ty::Cylinder),
                ("cone", Ty::Cone),
                ("pyramid", Ty::Pyramid),
                ("punch", Ty::Punch),
                ("height", Ty::Height),
                ("surface", Ty::Surface),
                ("body", Ty::Body),
            ],
        )?;
        match ty {
            Ty::Plane => self.plane(key, n),
            Ty::Sphere => self.sphere(key, n),
            Ty::Cylinder => self.cylinder(key, n),
            Ty::Cone => self.cone(key, n),
            Ty::Pyramid => self.pyramid(key, n),
            Ty::Punch => self.punch(key, n),
            Ty::Height => self.height(key, n),
            Ty::Surface => self.surface(key, n),
            Ty::Body => {
                let t = self.table(key, n, keys::BODY)?;
                let (gk, g) = self.required(&t, "group")?;
                Ok(ObstacleSpec::Body {
                    group: self.string(&gk, g)?.to_string(),
                })
            }
        }
    }

    /// `type = "plane"`: `point` and `normal` (of as many components), the normal made a unit vector.
    fn plane(&self, key: &str, n: &Node) -> Res<ObstacleSpec> {
        let t = self.table(key, n, keys::PLANE)?;
        let (pk, p) = self.required(&t, "point")?;
        let point = self.vector(&pk, p)?;
        let (nk, nn) = self.required(&t, "normal")?;
        let mut normal = self.vector(&nk, nn)?;
        if normal.len() != point.len() {
            return Err(self.err(
                &nk,
                nn.loc,
                format!(
                    "has {} components but point has {}",
                    normal.len(),
                    point.len()
                ),
            ));
        }
        let norm = normal.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return Err(self.err(&nk, nn.loc, "the normal must be a nonzero vector"));
        }
        normal.iter_mut().for_each(|x| *x /= norm);
        Ok(ObstacleSpec::Plane { point, normal })
    }

    /// `type = "sphere"`.
    fn sphere(&self, key: &str, n: &Node) -> Res<ObstacleSpec> {
        let t = self.table(key, n, keys::SPHERE)?;
        let (ck, c) = self.required(&t, "center")?;
        let center = self.vector(&ck, c)?;
        let (rk, r) = self.required(&t, "radius")?;
        let radius = self.positive(&rk, r)?;
        Ok(ObstacleSpec::Sphere { center, radius })
    }

    /// `type = "cylinder"`.
    fn cylinder(&self, key: &str, n: &Node) -> Res<ObstacleSpec> {
        let t = self.table(key, n, keys::CYLINDER)?;
        let (pk, p) = self.required(&t, "point")?;
        let point = self.vector(&pk, p)?;
        let axis = self.axis(&t, "point", point.len())?;
        let (rk, r) = self.required(&t, "radius")?;
        let radius = self.positive(&rk, r)?;
        Ok(ObstacleSpec::Cylinder {
            point,
            axis,
            radius,
        })
    }

    /// `type = "cone"`.
    fn cone(&self, key: &str, n: &Node) -> Res<ObstacleSpec> {
        let t = self.table(key, n, keys::CONE)?;
        let (pk, p) = self.required(&t, "apex")?;
        let apex = self.vector(&pk, p)?;
        let axis = self.axis(&t, "apex", apex.len())?;
        let half_angle = self.half_angle(&t)?;
        Ok(ObstacleSpec::Cone {
            apex,
            axis,
            half_angle,
        })
    }

    /// `type = "pyramid"`: a cone's keys, `faces` and `azimuth` (default 0).
    fn pyramid(&self, key: &str, n: &Node) -> Res<ObstacleSpec> {
        let t = self.table(key, n, keys::PYRAMID)?;
        let (pk, p) = self.required(&t, "apex")?;
        let apex = self.vector(&pk, p)?;
        let axis = self.axis(&t, "apex", apex.len())?;
        let half_angle = self.half_angle(&t)?;
        let (fk, f) = self.required(&t, "faces")?;
        let Kind::Int(v) = f.kind else {
            return Err(self.type_err(&fk, f, "an integer"));
        };
        if !(MIN_FACES as i64..=MAX_FACES as i64).contains(&v) {
            return Err(self.err(
                &fk,
                f.loc,
                format!("must be an integer from {MIN_FACES} to {MAX_FACES}, got {v}"),
            ));
        }
        let azimuth = match t.get("azimuth") {
            None => 0.0,
            Some((ak, a)) => self.num(&ak, a)?,
        };
        Ok(ObstacleSpec::Pyramid {
            apex,
            axis,
            half_angle,
            faces: v as usize,
            azimuth,
        })
    }

    /// A `[[mesh.project]]` shape must be one of the analytic ones: refinement moves nodes
    /// onto them (not onto a height graph or a triangle surface).
    pub(super) fn analytic_shape(&self, key: &str, n: &Node) -> Res<()> {
        let t = self.table_any(key, n)?;
        if let Some((tk, ty)) = t.get("type") {
            if let Kind::Str(s) = &ty.kind {
                if s == "height" || s == "surface" {
                    return Err(self.err(
                        &tk,
                        ty.loc,
                        format!(
                            "\"{s}\" is a contact obstacle only; [[mesh.project]] takes plane, \
                             sphere, cylinder, cone, pyramid or punch"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// `type = "punch"`.
    fn punch(&self, key: &str, n: &Node) -> Res<ObstacleSpec> {
        let t = self.table(key, n, keys::PUNCH)?;
        let (ck, c) = self.required(&t, "center")?;
        let center = self.vector(&ck, c)?;
        let axis = self.axis(&t, "center", center.len())?;
        let (rk, r) = self.required(&t, "radius")?;
        let radius = self.positive(&rk, r)?;
        let edge_radius = match t.get("edge_radius") {
            None => 0.0,
            Some((ek, e)) => {
                let x = self.num(&ek, e)?;
                if !(0.0..=radius).contains(&x) {
                    return Err(self.err(
                        &ek,
                        e.loc,
                        format!("must lie in [0, radius] = [0, {radius}], got {x}"),
                    ));
                }
                x
            }
        };
        Ok(ObstacleSpec::Punch {
            center,
            axis,
            radius,
            edge_radius,
        })
    }

    /// `type = "height"`: `expr`, an expression of x (2D) or x and y (3D), parsed here (its
    /// variables are checked against the mesh's dimension in [`Case::check_against_mesh`]).
    fn height(&self, key: &str, n: &Node) -> Res<ObstacleSpec> {
        let t = self.table(key, n, keys::HEIGHT)?;
        let (ek, e) = self.required(&t, "expr")?;
        let text = self.string(&ek, e)?;
        let expr = HeightExpr::parse(text).map_err(|m| {
            self.err(
                &ek,
                e.loc,
                format!("cannot parse the height expression \"{text}\": {m}"),
            )
        })?;
        if let Some(v) = expr.variables().iter().find(|v| *v != "x" && *v != "y") {
            return Err(self.err(
                &ek,
                e.loc,
                format!(
                    "unknown variable '{v}' in \"{text}\": the height is y = h(x) in 2D, \
                     z = h(x, y) in 3D (functions: sin, cos, tan, exp, ln, sqrt, abs, min, max, \
                     …; powers with ^; constants pi, e)"
                ),
            ));
        }
        let expr = Arc::new(expr);
        Ok(ObstacleSpec::Height { expr })
    }

    /// `type = "surface"`: `file`, a closed STL surface (path relative to the case file), read
    /// and checked here.
    fn surface(&self, key: &str, n: &Node) -> Res<ObstacleSpec> {
        let t = self.table(key, n, keys::SURFACE)?;
        let (fk, f) = self.required(&t, "file")?;
        let rel = self.name(&fk, f)?;
        let file = self.file.parent().unwrap_or(Path::new("")).join(rel);
        let surface = TriSurface::read_stl(&file)
            .map_err(|m| self.err(&fk, f.loc, format!("surface file {}: {m}", file.display())))?;
        let surface = Arc::new(surface);
        Ok(ObstacleSpec::Surface { file, surface })
    }

    /// The required `axis` of an obstacle: a nonzero vector with as many components as the
    /// vector `with` (`len`), returned as a unit vector.
    fn axis(&self, t: &Tab, with: &str, len: usize) -> Res<Vec<f64>> {
        let (ak, a) = self.required(t, "axis")?;
        let axis = self.vector(&ak, a)?;
        if axis.len() != len {
            return Err(self.err(
                &ak,
                a.loc,
                format!("has {} components but {with} has {len}", axis.len()),
            ));
        }
        // Scaled by the largest entry first: huge entries do not overflow.
        let big = axis.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        if big == 0.0 {
            return Err(self.err(&ak, a.loc, "the axis must be a nonzero vector"));
        }
        let scaled: Vec<f64> = axis.iter().map(|x| x / big).collect();
        let norm = scaled.iter().map(|x| x * x).sum::<f64>().sqrt();
        Ok(scaled.iter().map(|x| x / norm).collect())
    }

    /// The required `half_angle` of a cone or pyramid, in degrees, 0 < half_angle < 90.
    fn half_angle(&self, t: &Tab) -> Res<f64> {
        let (hk, h) = self.required(t, "half_angle")?;
        let x = self.num(&hk, h)?;
        if x > 0.0 && x < 90.0 {
            Ok(x)
        } else {
            Err(self.err(&hk, h.loc, format!("must be in (0, 90) degrees, got {x}")))
        }
    }
}
