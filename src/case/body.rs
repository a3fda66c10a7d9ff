//! The body's sections: `[mesh]`, `[material]`, `[[dirichlet]]`, `[[neumann]]`,
//! `[body_force]`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::keys;
use super::reader::{Reader, Res, Tab};
use super::shape::ObstacleSpec;
use super::tree::{join_index, Kind, Node};
use crate::expr::{quoted, Expr, VARIABLES};

/// The largest `mesh.refine` (each level multiplies the cells by 4 in 2D, 8 in 3D).
pub const MAX_REFINE: usize = 10;

/// `[body_force]`: a constant vector (`value`) or one expression per component (`expr`).
#[derive(Debug, Clone, PartialEq)]
pub enum BodyForceSpec {
    /// `value = [fx, fy(, fz)]`.
    Constant(Vec<f64>),
    /// `expr = ["fx", "fy"(, "fz")]`: expressions of x, y (, z), evaluated at the quadrature
    /// points of every cell.
    Expr(Vec<Arc<Expr>>),
}

impl BodyForceSpec {
    /// The number of components.
    pub fn len(&self) -> usize {
        match self {
            BodyForceSpec::Constant(v) => v.len(),
            BodyForceSpec::Expr(e) => e.len(),
        }
    }

    /// Never true (a body force has 2 or 3 components); for clippy's `len_without_is_empty`.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The key of the components (`body_force.value` or `body_force.expr`).
    pub fn key(&self) -> &'static str {
        match self {
            BodyForceSpec::Constant(_) => "body_force.value",
            BodyForceSpec::Expr(_) => "body_force.expr",
        }
    }
}

/// Elastic model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaterialModel {
    PlaneStrain,
    PlaneStress,
    ThreeD,
}

impl MaterialModel {
    /// The spelling used in the case file.
    pub fn name(self) -> &'static str {
        match self {
            MaterialModel::PlaneStrain => "plane_strain",
            MaterialModel::PlaneStress => "plane_stress",
            MaterialModel::ThreeD => "3d",
        }
    }

    /// Spatial dimension the model belongs to.
    pub fn dim(self) -> usize {
        match self {
            MaterialModel::PlaneStrain | MaterialModel::PlaneStress => 2,
            MaterialModel::ThreeD => 3,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct MeshSection {
    /// Resolved against the case file's directory.
    pub file: PathBuf,
    /// `mesh.refine`: uniform refinements after the distributed read (0: none).
    pub refine: usize,
    /// `[[mesh.project]]`: the new nodes of a group's facets moved onto a shape.
    pub project: Vec<Projection>,
}

/// `[[mesh.project]]`: the nodes that refinement adds on the facets (or, in 3D, edges) of
/// `group` are moved onto `shape` (the first entry naming a group of the facet wins).
#[derive(Debug, Clone, PartialEq)]
pub struct Projection {
    pub group: String,
    /// A sphere (circle in 2D) or a plane, written as a contact obstacle is.
    pub shape: ObstacleSpec,
}

/// `[material]` (the whole mesh) or one `[[material]]` (the cells of a volume group).
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialSection {
    /// The table's key path: `material` or `material[i]`, named in messages.
    pub key: String,
    /// The volume group whose cells have this material; `None` (`[material]`): every cell.
    pub group: Option<String>,
    pub young: f64,
    pub poisson: f64,
    /// As given; use [`Case::model`] to get the model for a mesh dimension.
    pub model: Option<MaterialModel>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Dirichlet {
    pub group: String,
    /// One entry per component; `None` = "free".
    pub value: Vec<Option<f64>>,
    /// Scaled by the load factor of `[load]` (default); `ramp = false` holds the prescribed
    /// components at their full value in every step.
    pub ramp: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Load {
    /// Normal pressure, positive pushes into the body.
    Pressure(f64),
    /// Vector traction.
    Traction(Vec<f64>),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Neumann {
    pub group: String,
    pub load: Load,
    /// Scaled by the load factor of `[load]` (default); `ramp = false` holds the load at its
    /// full value in every step (e.g. a normal force held while a tangential one grows).
    pub ramp: bool,
}

impl Reader<'_> {
    /// `[body_force]`: exactly one of `value` (a vector) and `expr` (an array of 2 or 3
    /// expressions of x, y, z; the variables are checked against the mesh's dimension in
    /// [`Case::check_against_mesh`]).
    pub(super) fn body_force(&self, key: &str, n: &Node) -> Res<BodyForceSpec> {
        let t = self.table(key, n, keys::BODY_FORCE)?;
        match (t.get("value"), t.get("expr")) {
            (Some((vk, v)), None) => Ok(BodyForceSpec::Constant(self.vector(&vk, v)?)),
            (None, Some((ek, e))) => {
                let elems = self.array(&ek, e, "an array of expression strings")?;
                self.check_len(&ek, e, elems.len())?;
                let mut out = Vec::new();
                for (i, el) in elems.iter().enumerate() {
                    let ik = join_index(&ek, i);
                    let text = self.string(&ik, el)?;
                    let expr = Expr::parse(text).map_err(|m| {
                        self.err(
                            &ik,
                            el.loc,
                            format!("cannot parse the body force expression \"{text}\": {m}"),
                        )
                    })?;
                    let bad = expr.unknown_variables(&VARIABLES);
                    if !bad.is_empty() {
                        return Err(self.err(
                            &ik,
                            el.loc,
                            format!(
                                "unknown variable{} {} in \"{text}\": the variables are x, y \
                                 (and z in 3D) (functions: sin, cos, tan, exp, ln, sqrt, abs, \
                                 min, max, …; powers with ^; constants pi, e)",
                                if bad.len() > 1 { "s" } else { "" },
                                quoted(&bad)
                            ),
                        ));
                    }
                    out.push(Arc::new(expr));
                }
                Ok(BodyForceSpec::Expr(out))
            }
            (Some(_), Some((ek, e))) => Err(self.err(
                &ek,
                e.loc,
                "give either value (a constant vector) or expr (expressions), not both",
            )),
            (None, None) => Err(self.err(
                key,
                n.loc,
                "missing key: value (a constant vector) or expr (one expression per component)",
            )),
        }
    }

    pub(super) fn mesh(&self, top: &Tab) -> Res<MeshSection> {
        let (k, n) = self.required(top, "mesh")?;
        let t = self.table(&k, n, keys::MESH)?;
        let (fk, f) = self.required(&t, "file")?;
        let rel = self.name(&fk, f)?;
        let dir = self.file.parent().unwrap_or(Path::new(""));
        let refine = match t.get("refine") {
            None => 0,
            Some((rk, r)) => {
                let Kind::Int(v) = r.kind else {
                    return Err(self.type_err(&rk, r, "an integer >= 0"));
                };
                if !(0..=MAX_REFINE as i64).contains(&v) {
                    return Err(self.err(
                        &rk,
                        r.loc,
                        format!("must be an integer from 0 to {MAX_REFINE}, got {v}"),
                    ));
                }
                v as usize
            }
        };
        let mut project = Vec::new();
        for p in self.tables(&t, "project", keys::MESH_PROJECT)? {
            let (gk, g) = self.required(&p, "group")?;
            let group = self.name(&gk, g)?;
            let (sk, sh) = self.required(&p, "shape")?;
            self.analytic_shape(&sk, sh)?;
            let shape = self.obstacle(&sk, sh)?;
            project.push(Projection { group, shape });
        }
        Ok(MeshSection {
            file: dir.join(rel),
            refine,
            project,
        })
    }

    /// `[material]` (one material, every cell) or `[[material]]` (one per volume group,
    /// each with `group`; all of one model where a model is given; a group named once).
    pub(super) fn materials(&self, top: &Tab) -> Res<Vec<MaterialSection>> {
        let (k, n) = self.required(top, "material")?;
        if matches!(n.kind, Kind::Table(_)) {
            let t = self.table(&k, n, keys::MATERIAL)?;
            return Ok(vec![self.material(&t, None)?]);
        }
        let tables = self.tables(top, "material", keys::MATERIALS)?;
        if tables.is_empty() {
            return Err(self.err(
                &k,
                n.loc,
                "is empty: give [material] (every cell) or [[material]] tables, each with a group",
            ));
        }
        let mut out: Vec<MaterialSection> = Vec::new();
        for t in &tables {
            let (gk, g) = self.required(t, "group")?;
            let group = self.name(&gk, g)?;
            if let Some(o) = out.iter().find(|o| o.group.as_deref() == Some(&group)) {
                return Err(self.err(
                    &gk,
                    g.loc,
                    format!(
                        "group \"{group}\" already has a material ({}): a cell has one",
                        o.key
                    ),
                ));
            }
            let m = self.material(t, Some(group))?;
            let first = out.iter().find(|o| o.model.is_some());
            if let (Some(f), Some(model)) = (first, m.model) {
                if f.model != Some(model) {
                    let (mk, mn) = t.get("model").expect("the model was read");
                    return Err(self.err(
                        &mk,
                        mn.loc,
                        format!(
                            "model \"{}\" differs from {}.model = \"{}\": every material \
                             of a case has the same model",
                            model.name(),
                            f.key,
                            f.model.map_or("", MaterialModel::name)
                        ),
                    ));
                }
            }
            out.push(m);
        }
        Ok(out)
    }

    /// The keys of one material table (`group` read by the caller).
    fn material(&self, t: &Tab, group: Option<String>) -> Res<MaterialSection> {
        let (yk, y) = self.required(t, "young")?;
        let young = self.positive(&yk, y)?;
        let (pk, p) = self.required(t, "poisson")?;
        let poisson = self.num(&pk, p)?;
        if !(poisson > -1.0 && poisson < 0.5) {
            return Err(self.err(
                &pk,
                p.loc,
                format!("Poisson's ratio must lie in (-1, 0.5), got {poisson}"),
            ));
        }
        let model = match t.get("model") {
            None => None,
            Some((mk, m)) => Some(self.choice(
                &mk,
                m,
                &[
                    ("plane_strain", MaterialModel::PlaneStrain),
                    ("plane_stress", MaterialModel::PlaneStress),
                    ("3d", MaterialModel::ThreeD),
                ],
            )?),
        };
        Ok(MaterialSection {
            key: t.key.clone(),
            group,
            young,
            poisson,
            model,
        })
    }

    /// Elements of an array of tables (`[[name]]`), each checked against `allowed`.
    pub(super) fn tables<'n>(
        &self,
        top: &Tab<'n>,
        name: &str,
        allowed: &[&str],
    ) -> Res<Vec<Tab<'n>>> {
        let Some((k, n)) = top.get(name) else {
            return Ok(Vec::new());
        };
        let elems = self.array(&k, n, &format!("an array of tables ([[{name}]])"))?;
        elems
            .iter()
            .enumerate()
            .map(|(i, e)| self.table(&join_index(&k, i), e, allowed))
            .collect()
    }

    pub(super) fn dirichlet(&self, top: &Tab) -> Res<Vec<Dirichlet>> {
        let mut out = Vec::new();
        for t in self.tables(top, "dirichlet", keys::DIRICHLET)? {
            let (gk, g) = self.required(&t, "group")?;
            let group = self.name(&gk, g)?;
            let (vk, v) = self.required(&t, "value")?;
            let elems = self.array(&vk, v, "an array of numbers or \"free\"")?;
            self.check_len(&vk, v, elems.len())?;
            let mut value = Vec::new();
            for (i, e) in elems.iter().enumerate() {
                let ek = join_index(&vk, i);
                value.push(match &e.kind {
                    Kind::Str(s) if s == "free" => None,
                    Kind::Str(s) => {
                        return Err(self.err(
                            &ek,
                            e.loc,
                            format!("expected a number or \"free\", found \"{s}\""),
                        ))
                    }
                    Kind::Int(_) | Kind::Float(_) => Some(self.num(&ek, e)?),
                    _ => return Err(self.type_err(&ek, e, "a number or \"free\"")),
                });
            }
            let ramp = match t.get("ramp") {
                None => true,
                Some((rk, r)) => self.boolean(&rk, r)?,
            };
            out.push(Dirichlet { group, value, ramp });
        }
        Ok(out)
    }

    pub(super) fn neumann(&self, top: &Tab) -> Res<Vec<Neumann>> {
        let mut out = Vec::new();
        for t in self.tables(top, "neumann", keys::NEUMANN)? {
            let (gk, g) = self.required(&t, "group")?;
            let group = self.name(&gk, g)?;
            let load = match (t.get("pressure"), t.get("traction")) {
                (Some((pk, p)), None) => Load::Pressure(self.num(&pk, p)?),
                (None, Some((tk, tr))) => Load::Traction(self.vector(&tk, tr)?),
                (Some((_, p)), Some(_)) => {
                    return Err(self.err(
                        &t.key,
                        p.loc,
                        "give exactly one of 'pressure' and 'traction', not both",
                    ))
                }
                (None, None) => {
                    return Err(self.err(
                        &t.key,
                        t.loc,
                        "needs a load: give exactly one of 'pressure' (number) and \
                         'traction' (vector)",
                    ))
                }
            };
            let ramp = match t.get("ramp") {
                None => true,
                Some((rk, r)) => self.boolean(&rk, r)?,
            };
            out.push(Neumann { group, load, ramp });
        }
        Ok(out)
    }
}
