//! The TOML case file: schema, defaults, validation, `--set` overrides.
//!
//! The file is parsed with `toml_edit` (which keeps spans) into a small owned tree that
//! remembers the line of every key; `--set` overrides are applied to that tree (marked as
//! coming from the command line) and the result is validated by hand, so that every error
//! names the file, the key path (`material.poisson`, `dirichlet[1].value`, `neumann[0]`)
//! and the line of that key, or says "(from --set)".

pub mod keys;
mod load;
mod tree;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_shapes;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::contact::obstacle::{
    Cone, Cylinder, Height, HeightExpr, Punch, Pyramid, TriSurface, MAX_FACES, MIN_FACES,
};
use crate::contact::{Obstacle, ObstacleError, Plane, Sphere};
use crate::error::InputError;
use crate::expr::{quoted, Expr, VARIABLES};
use crate::mesh::Mesh;
pub use load::LoadSection;
use tree::{join_index, join_key, Kind, Loc, Node};

/// A vector of the case file (2 or 3 entries) as 3 components, z = 0 in 2D.
pub fn vec3(v: &[f64]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (o, x) in out.iter_mut().zip(v) {
        *o = *x;
    }
    out
}

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

#[derive(Debug, Clone, PartialEq)]
pub struct MaterialSection {
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

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preset {
    /// MUMPS: Cholesky for symmetric systems (linear, frictionless), LU for friction.
    Direct,
    /// Krylov + AMG.
    Iterative,
    /// The default: direct or iterative from the dimension and the size of the mesh
    /// (`solver::choose_preset`), chosen once the mesh is read.
    Auto,
}

impl Preset {
    pub fn name(self) -> &'static str {
        match self {
            Preset::Direct => "direct",
            Preset::Iterative => "iterative",
            Preset::Auto => "auto",
        }
    }
}

/// The contact algorithm.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Algorithms 1 / 2: the semismooth Newton method in its exact active-set form.
    Newton,
    /// PETSc SNES VI (vinewtonrsls) on the same discrete frictionless problem: a baseline.
    SnesVi,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Newton => "newton",
            Method::SnesVi => "snesvi",
        }
    }
}

/// `solver.reuse`: whether a Newton step of the direct preset may solve its reduced system by
/// Krylov iterations preconditioned with the last factorisation instead of refactorising; with
/// the iterative preset, whether Newton steps share one preconditioner (GAMG hierarchy), start
/// from the previous iterate and (frictionless) solve inexactly while the active set changes
/// (signorini::reduced, `solve_amg`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reuse {
    /// Direct, frictionless: the condensed path (Algorithm 1 on the contact unknowns, one
    /// factorisation with MUMPS' Schur complement, signorini::condensed; the case file may
    /// also say "condensed"); where it falls back, the plain path reuses a factorisation when
    /// MUMPS' counts say it pays (flops of the factorisation against those of its solves,
    /// signorini::reduced `ReuseCosts`; never timings). Direct with friction: every step
    /// refactorises (the condensed Coulomb path aside).
    /// Iterative: warm starts, inexact early steps, the preconditioner of an earlier step, set
    /// up anew when the Krylov iterations per decade grew by more than 30 % over those after
    /// the last setup, or when a solve on it does not converge.
    Auto,
    /// Every step refactorises (direct) or sets its preconditioner up and solves from zero to
    /// the preset's tolerance (iterative): the plain path, the reference.
    Never,
    /// Direct: every step after the first tries the reuse (bounded budget, then refactorises).
    /// Iterative: as "auto", but the preconditioner of the first step is kept unless a solve
    /// on it fails.
    Always,
}

impl Reuse {
    pub fn name(self) -> &'static str {
        match self {
            Reuse::Auto => "auto",
            Reuse::Never => "never",
            Reuse::Always => "always",
        }
    }
}

/// `solver.dense_threads`: the OpenBLAS threads of rank 0's dense phases (the condensed
/// path's dense work from [`crate::blas::WIDE_MIN_DIM`] unknowns on, crate::blas::NodeCores).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DenseThreads {
    /// One per CPU that the ranks on rank 0's node may use (the launcher's binding decides).
    Auto,
    /// This many, whatever the binding (on the CPUs of the ranks on rank 0's node).
    Fixed(usize),
}

impl DenseThreads {
    /// "auto" or the count, for summary.json and the log.
    pub fn name(self) -> String {
        match self {
            DenseThreads::Auto => "auto".into(),
            DenseThreads::Fixed(n) => n.to_string(),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct SolverSection {
    pub preset: Preset,
    /// The contact algorithm (contact cases only).
    pub method: Method,
    /// Override the preset's options (the command line overrides both).
    pub petsc_options: String,
    /// Relative tolerance of the iterative preset.
    pub rtol: f64,
    /// Reuse of a factorisation (direct preset) or of the preconditioner, warm starts and
    /// inexact early steps (iterative preset) across Newton steps (contact).
    pub reuse: Reuse,
    /// The direct preset's MUMPS work (LU with friction, LDLᵀ on the plain path, and the
    /// condensed path's LLᵀ with the Schur complement and its solve phases) on rank 0 alone,
    /// so that repeated runs on a fixed rank count give the same bits (MUMPS on several ranks
    /// adds other ranks' contributions as their messages arrive: round-off from run to run).
    pub repeatable: bool,
    /// The threads of rank 0's dense phases.
    pub dense_threads: DenseThreads,
}

impl Default for SolverSection {
    fn default() -> Self {
        SolverSection {
            preset: Preset::Auto,
            method: Method::Newton,
            petsc_options: String::new(),
            rtol: 1e-10,
            reuse: Reuse::Auto,
            repeatable: false,
            dense_threads: DenseThreads::Auto,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum OutputField {
    Displacement,
    Stress,
    VonMises,
    VonMisesThesis,
    Rank,
    Contact,
}

impl OutputField {
    pub const ALL: [OutputField; 6] = [
        OutputField::Displacement,
        OutputField::Stress,
        OutputField::VonMises,
        OutputField::VonMisesThesis,
        OutputField::Rank,
        OutputField::Contact,
    ];

    /// The spelling used in the case file.
    pub fn name(self) -> &'static str {
        match self {
            OutputField::Displacement => "displacement",
            OutputField::Stress => "stress",
            OutputField::VonMises => "von_mises",
            OutputField::VonMisesThesis => "von_mises_thesis",
            OutputField::Rank => "rank",
            OutputField::Contact => "contact",
        }
    }

    fn from_name(s: &str) -> Option<OutputField> {
        OutputField::ALL.into_iter().find(|f| f.name() == s)
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct OutputSection {
    /// Relative to the working directory.
    pub dir: PathBuf,
    /// Requested fields, in file order, without duplicates.
    pub fields: Vec<OutputField>,
}

impl OutputSection {
    pub fn wants(&self, f: OutputField) -> bool {
        self.fields.contains(&f)
    }
}

/// The default `output.fields`.
pub const DEFAULT_FIELDS: [OutputField; 3] = [
    OutputField::Displacement,
    OutputField::VonMises,
    OutputField::Contact,
];

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
            ObstacleSpec::Height { .. } | ObstacleSpec::Surface { .. } => Vec::new(),
        }
    }

    /// For a shape that exists in 3D only: what to use in 2D instead.
    fn in_2d_use(&self) -> Option<&'static str> {
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
        })
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Friction {
    None,
    Tresca {
        threshold: f64,
    },
    /// Coulomb's law node-wise, threshold b_k = μ (−λ_n^k) (docs/friction.md).
    Coulomb {
        mu: f64,
        algorithm: CoulombAlgorithm,
    },
}

/// How Coulomb friction is solved (docs/friction.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CoulombAlgorithm {
    /// One generalised semismooth Newton on (C_n, C_τ) with b = μ max(0, −λ_n − c(u_n + g)).
    Newton,
    /// Fixed point on Tresca thresholds b^{m+1} = μ max(0, −λ_n^m), a Tresca solve per step.
    FixedPoint,
}

impl CoulombAlgorithm {
    pub fn name(self) -> &'static str {
        match self {
            CoulombAlgorithm::Newton => "newton",
            CoulombAlgorithm::FixedPoint => "fixed-point",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RigidModeHandling {
    Auto,
    None,
}

/// One contact pair: a boundary group against its obstacle (`[contact]`, or one table of
/// `[[contact]]`; docs/obstacles.md, "Several contact pairs").
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSection {
    /// The pair's table in the case file: `contact`, or `contact[i]` of `[[contact]]` (every
    /// message about the pair names its keys under it).
    pub key: String,
    pub group: String,
    pub obstacle: ObstacleSpec,
    /// `contact.motion`: a rigid translation of the obstacle (docs/obstacles.md, "Moving
    /// obstacles"); None: the obstacle stays where it is given.
    pub motion: Option<Motion>,
    /// `contact.force`: force control (docs/obstacles.md, "Force control"): the obstacle moves
    /// along F/|F| by the unknown approach δ until the contact force along F/|F| is |F|
    /// (any friction law; never together with `motion`). Scaled with `[load]` as a motion.
    pub force: Option<Motion>,
    pub friction: Friction,
    pub rigid_modes: RigidModeHandling,
}

/// A rigid translation m of the obstacle, reached at load factor 1: at factor t the obstacle
/// has moved by t·m (by m in every step with `ramp = false`), or, given as a `table` of rows
/// `[t_i, m_i…]`, by the piecewise-linear interpolation of the rows at t (docs/load_steps.md,
/// "Load histories"). The same record holds a prescribed force (`contact.force`), scaled alike.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    /// m, one component per dimension; with a table, the components of its last row.
    pub value: Vec<f64>,
    /// Scaled by the load factor of `[load]` (default); `ramp = false` holds it at m. True
    /// with a table (unused).
    pub ramp: bool,
    /// `KEY.table`: the rows (load factor, components), the factors increasing from 0; empty
    /// for the vector form.
    pub table: Vec<(f64, Vec<f64>)>,
    /// The key of the vector in the case file (`contact.motion`, `contact.motion.value` or
    /// `contact.motion.table`, under `contact[i]` with several pairs).
    pub key: String,
}

impl Motion {
    /// The obstacle's displacement at load factor t: t·m, m when held, or the table's
    /// piecewise-linear interpolation at t (its last row beyond its last factor: the case
    /// reader refuses a run whose factors go beyond it) (padded to 3).
    pub fn at(&self, t: f64) -> [f64; 3] {
        if !self.table.is_empty() {
            return table_at(&self.table, t);
        }
        let m = vec3(&self.value);
        if self.ramp {
            m.map(|x| t * x)
        } else {
            m
        }
    }

    /// The largest load factor the motion is defined at (`None`: every factor).
    pub fn last_factor(&self) -> Option<f64> {
        self.table.last().map(|(t, _)| *t)
    }
}

/// The piecewise-linear interpolation of `rows` (factors increasing) at t, held at the first
/// and the last row outside them.
fn table_at(rows: &[(f64, Vec<f64>)], t: f64) -> [f64; 3] {
    let (first, last) = (&rows[0], &rows[rows.len() - 1]);
    if t <= first.0 {
        return vec3(&first.1);
    }
    if t >= last.0 {
        return vec3(&last.1);
    }
    let i = rows.partition_point(|(ti, _)| *ti <= t).max(1);
    let ((t0, a), (t1, b)) = (&rows[i - 1], &rows[i]);
    let w = (t - t0) / (t1 - t0);
    let (a, b) = (vec3(a), vec3(b));
    std::array::from_fn(|k| a[k] + w * (b[k] - a[k]))
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NewtonInit {
    Auto,
    AllActive,
    AllInactive,
    Gap,
}

impl NewtonInit {
    pub fn name(self) -> &'static str {
        match self {
            NewtonInit::Auto => "auto",
            NewtonInit::AllActive => "all_active",
            NewtonInit::AllInactive => "all_inactive",
            NewtonInit::Gap => "gap",
        }
    }
}

/// What Algorithm 1/2 does when an active set recurs (cycling).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OnCycle {
    /// Continue with single-node updates by the least-index rule (Murty), reported.
    LeastIndex,
    /// Stop with an error (exit code 1).
    Stop,
}

impl OnCycle {
    pub fn name(self) -> &'static str {
        match self {
            OnCycle::LeastIndex => "least_index",
            OnCycle::Stop => "stop",
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct NewtonSection {
    pub init: NewtonInit,
    /// Reaction to a recurring active set.
    pub on_cycle: OnCycle,
    /// Complementarity parameter c > 0; None: c = E / h_c (h_c the mean contact mesh size),
    /// the middle of the range that converged on every case of scripts/bench-tresca-c.
    pub c: Option<f64>,
    pub max_steps: usize,
    pub tol_u: f64,
    /// `newton.strict`: a run that stops by a loosened acceptance, or whose certificate has a
    /// relative value above `signorini::certificate::STRICT_TOL`, is an error (exit 1).
    pub strict: bool,
}

impl Default for NewtonSection {
    fn default() -> Self {
        NewtonSection {
            init: NewtonInit::Auto,
            on_cycle: OnCycle::LeastIndex,
            c: None,
            max_steps: 100,
            tol_u: 1e-10,
            strict: false,
        }
    }
}

/// A validated case: defaults filled in, paths resolved.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// The case file as given on the command line.
    pub file: PathBuf,
    pub mesh: MeshSection,
    pub material: MaterialSection,
    pub dirichlet: Vec<Dirichlet>,
    pub neumann: Vec<Neumann>,
    pub body_force: Option<BodyForceSpec>,
    pub solver: SolverSection,
    pub output: OutputSection,
    /// The contact pairs (`[contact]` or `[[contact]]`); empty: a linear case.
    pub contacts: Vec<ContactSection>,
    pub newton: NewtonSection,
    /// The load history (`[load]`); None: one step at factor 1.
    pub load: Option<LoadSection>,
    /// Where every key path came from, for errors found after loading.
    locs: BTreeMap<String, Loc>,
}

/// The largest `mesh.refine` (each level multiplies the cells by 4 in 2D, 8 in 3D).
pub const MAX_REFINE: usize = 10;

/// The largest case file read (a case file is a few hundred bytes; the bound keeps a wrong
/// file from costing gigabytes of memory for its value tree).
pub const MAX_CASE_BYTES: usize = 256 * 1024;

fn too_large(file: &Path) -> InputError {
    InputError::new(
        file,
        format!(
            "the case file is larger than {} KiB: is it a case file?",
            MAX_CASE_BYTES / 1024
        ),
    )
}

impl Case {
    /// Reads and validates the case file. `overrides` are `key.path=value` strings from
    /// `--set` (the value is parsed as a TOML value, falling back to a plain string; a
    /// numeric component indexes an array of tables, one past the end appends a new entry);
    /// `output_dir` (from `-o`) replaces `output.dir`.
    pub fn load(
        path: &Path,
        overrides: &[String],
        output_dir: Option<&Path>,
    ) -> Result<Case, InputError> {
        use std::io::Read;
        let cannot =
            |e: std::io::Error| InputError::new(path, format!("cannot read the case file: {e}"));
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .map_err(cannot)?
            .take(MAX_CASE_BYTES as u64 + 1)
            .read_to_end(&mut bytes)
            .map_err(cannot)?;
        if bytes.len() > MAX_CASE_BYTES {
            return Err(too_large(path));
        }
        let text = String::from_utf8(bytes).map_err(|_| {
            InputError::new(
                path,
                "cannot read the case file: it is not valid UTF-8 text",
            )
        })?;
        let case = Case::parse(&text, path, overrides, output_dir)?;
        case.check_mesh_file()?;
        Ok(case)
    }

    /// A mesh file that is not there is the case file's error, naming `mesh.file` and its
    /// line; what is wrong inside a mesh file its reader says, naming that file.
    fn check_mesh_file(&self) -> Result<(), InputError> {
        let f = &self.mesh.file;
        match std::fs::metadata(f) {
            Ok(m) if m.is_file() => Ok(()),
            Ok(_) => Err(self.err_at(
                "mesh.file",
                format!("the mesh file {} is not a file", f.display()),
            )),
            Err(e) => Err(self.err_at(
                "mesh.file",
                format!("cannot read the mesh file {}: {e}", f.display()),
            )),
        }
    }

    /// As [`Case::load`], with the file's text already in hand (`file` is used for
    /// messages, for resolving `mesh.file` and for the default output directory).
    pub fn parse(
        text: &str,
        file: &Path,
        overrides: &[String],
        output_dir: Option<&Path>,
    ) -> Result<Case, InputError> {
        let cx = Reader { file };
        if text.len() > MAX_CASE_BYTES {
            return Err(too_large(file));
        }
        let mut root =
            tree::parse(text).map_err(|(line, msg)| InputError::new(file, msg).with_line(line))?;
        for spec in overrides {
            tree::apply_override(&mut root, spec)
                .map_err(|(key, msg)| cx.err(&key, Loc::Set, msg))?;
        }
        let mut locs = BTreeMap::new();
        tree::collect_locs(&root, "", &mut locs);
        let mut case = cx.case(&root, output_dir)?;
        case.locs = locs;
        case.check_histories()?;
        Ok(case)
    }

    /// The line of a key path (e.g. `dirichlet[0].group`) in the case file, if it came from
    /// the file.
    pub fn line_of(&self, key: &str) -> Option<usize> {
        match self.locs.get(key) {
            Some(Loc::Line(l)) => Some(*l),
            _ => None,
        }
    }

    /// An input error of the key path `key`, at its line when it came from the file.
    pub fn error_at(&self, key: &str, msg: impl Into<String>) -> InputError {
        self.err_at(key, msg)
    }

    fn err_at(&self, key: &str, msg: impl Into<String>) -> InputError {
        let loc = self.locs.get(key).copied().unwrap_or(Loc::Unknown);
        Reader { file: &self.file }.err(key, loc, msg)
    }

    /// The model to use for a mesh of dimension `dim`: a 2D mesh needs `plane_strain` or
    /// `plane_stress`, a 3D mesh needs `3d` or no model.
    pub fn model(&self, dim: usize) -> Result<MaterialModel, InputError> {
        match (dim, self.material.model) {
            (2, Some(m @ (MaterialModel::PlaneStrain | MaterialModel::PlaneStress))) => Ok(m),
            (2, None) => Err(self.err_at(
                "material",
                "the mesh is 2D: material.model is required, \"plane_strain\" or \"plane_stress\"",
            )),
            (3, None | Some(MaterialModel::ThreeD)) => Ok(MaterialModel::ThreeD),
            (2 | 3, Some(m)) => Err(self.err_at(
                "material.model",
                format!(
                    "model \"{}\" is for {}D meshes, but the mesh is {dim}D",
                    m.name(),
                    m.dim()
                ),
            )),
            _ => Err(self.err_at(
                "mesh.file",
                format!("the mesh has dimension {dim}; only 2D and 3D meshes are supported"),
            )),
        }
    }

    /// Every table of `contact.motion` / `contact.force` covers every load factor of the run
    /// (the largest of `load.factors`, 1 without `[load]`): a table is not extrapolated. A
    /// force table gives a nonzero force at every planned factor (force control needs a
    /// direction).
    fn check_histories(&self) -> Result<(), InputError> {
        let factors = self
            .load
            .as_ref()
            .map_or_else(|| vec![1.0], |l| l.factors.clone());
        let reach = factors.iter().copied().fold(0.0, f64::max);
        let plan = if self.load.is_some() {
            "load.factors reaches"
        } else {
            "a run without [load] solves at"
        };
        for c in &self.contacts {
            for m in [&c.motion, &c.force].into_iter().flatten() {
                let Some(last) = m.last_factor() else {
                    continue;
                };
                if last < reach {
                    return Err(self.err_at(
                        &m.key,
                        format!(
                            "covers the load factors 0 to {last}, but {plan} {reach}: \
                             add a row at a factor ≥ {reach} (a table is not extrapolated)"
                        ),
                    ));
                }
            }
            if let Some(f) = c.force.as_ref().filter(|f| !f.table.is_empty()) {
                if let Some(t) = factors.iter().find(|&&t| f.at(t).iter().all(|&x| x == 0.0)) {
                    return Err(self.err_at(
                        &f.key,
                        format!(
                            "gives a zero force at the load factor {t} of the run: force \
                             control needs a direction (a nonzero force) in every step"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Checks the case against the mesh: model vs dimension, vector lengths = `dim`,
    /// group names exist, Neumann/contact groups are boundary groups (dimension `dim - 1`).
    /// `groups` lists the mesh's physical groups as (name, dimension).
    pub fn check_against_mesh(
        &self,
        dim: usize,
        groups: &[(String, usize)],
    ) -> Result<(), InputError> {
        self.model(dim)?;
        let len = |key: String, n: usize| -> Result<(), InputError> {
            if n == dim {
                Ok(())
            } else {
                Err(self.err_at(
                    &key,
                    format!("has {n} components, but the mesh is {dim}D and needs {dim}"),
                ))
            }
        };
        for (i, d) in self.dirichlet.iter().enumerate() {
            let k = join_index("dirichlet", i);
            self.check_group(&join_key(&k, "group"), &d.group, groups, None)?;
            len(join_key(&k, "value"), d.value.len())?;
        }
        for (i, n) in self.neumann.iter().enumerate() {
            let k = join_index("neumann", i);
            self.check_group(&join_key(&k, "group"), &n.group, groups, Some(dim - 1))?;
            if let Load::Traction(t) = &n.load {
                len(join_key(&k, "traction"), t.len())?;
            }
        }
        if let Some(b) = &self.body_force {
            len(b.key().into(), b.len())?;
            if let BodyForceSpec::Expr(es) = b {
                for (i, e) in es.iter().enumerate() {
                    let bad = e.unknown_variables(&VARIABLES[..dim]);
                    if !bad.is_empty() {
                        return Err(self.err_at(
                            &join_index("body_force.expr", i),
                            format!(
                                "\"{}\": unknown variable{} {}; the mesh is {dim}D: the \
                                 variables are {}",
                                e.text(),
                                if bad.len() > 1 { "s" } else { "" },
                                quoted(&bad),
                                VARIABLES[..dim].join(", ")
                            ),
                        ));
                    }
                }
            }
        }
        for c in &self.contacts {
            self.check_group(&join_key(&c.key, "group"), &c.group, groups, Some(dim - 1))?;
            self.check_shape(&join_key(&c.key, "obstacle"), &c.obstacle, dim)?;
            for m in [&c.motion, &c.force].into_iter().flatten() {
                if m.table.is_empty() {
                    len(m.key.clone(), m.value.len())?;
                }
                for (i, (_, row)) in m.table.iter().enumerate() {
                    if row.len() != dim {
                        return Err(self.err_at(
                            &join_index(&m.key, i),
                            format!(
                                "a row of {} numbers, but the mesh is {dim}D: each row is \
                                 [load factor, {}] (1 + {dim} numbers)",
                                1 + row.len(),
                                ["x", "y", "z"][..dim].join(", ")
                            ),
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// A 3D-only shape needs a 3D mesh; every vector of the shape needs `dim` components.
    fn check_shape(&self, key: &str, shape: &ObstacleSpec, dim: usize) -> Result<(), InputError> {
        if let (2, Some(instead)) = (dim, shape.in_2d_use()) {
            return Err(self.err_at(
                &join_key(key, "type"),
                format!(
                    "\"{}\" is a 3D obstacle, but the mesh is 2D; in 2D use {instead}",
                    shape.type_name()
                ),
            ));
        }
        if let ObstacleSpec::Height { expr } = shape {
            expr.check_variables(dim).map_err(|m| {
                self.err_at(&join_key(key, "expr"), format!("\"{}\": {m}", expr.text()))
            })?;
        }
        for (name, n) in shape.vectors() {
            if n != dim {
                return Err(self.err_at(
                    &join_key(key, name),
                    format!("has {n} components, but the mesh is {dim}D and needs {dim}"),
                ));
            }
        }
        Ok(())
    }

    /// Checks `[[mesh.project]]` against the mesh read (before it is refined): every group
    /// exists and has facets (dimension `dim - 1`) or, in 3D, edges; the shape's vectors have
    /// `dim` components. `groups` lists the mesh's physical groups as (name, dimension).
    pub fn check_projections(
        &self,
        dim: usize,
        groups: &[(String, usize)],
    ) -> Result<(), InputError> {
        for (i, p) in self.mesh.project.iter().enumerate() {
            let k = join_index("mesh.project", i);
            let gk = join_key(&k, "group");
            self.check_group(&gk, &p.group, groups, None)?;
            if !groups
                .iter()
                .any(|(g, d)| g == &p.group && *d >= 1 && *d < dim)
            {
                return Err(self.err_at(
                    &gk,
                    format!(
                        "physical group \"{}\" has no facets{}: only new nodes on the \
                         boundary can be projected",
                        p.group,
                        if dim == 3 { " or edges" } else { "" }
                    ),
                ));
            }
            self.check_shape(&join_key(&k, "shape"), &p.shape, dim)?;
        }
        Ok(())
    }

    /// Checks the facets of every group that carries a load (`neumann`) or the contact
    /// condition: no degenerate facet, every facet on the boundary of the body (see
    /// [`Mesh::check_boundary_group`]). Call after [`Case::check_against_mesh`].
    pub fn check_facet_groups(&self, mesh: &Mesh) -> Result<(), InputError> {
        let mut used: Vec<(String, &str)> = self
            .neumann
            .iter()
            .enumerate()
            .map(|(i, n)| {
                (
                    join_key(&join_index("neumann", i), "group"),
                    n.group.as_str(),
                )
            })
            .collect();
        for c in &self.contacts {
            used.push((join_key(&c.key, "group"), c.group.as_str()));
        }
        for (key, group) in used {
            let at = match self.line_of(&key) {
                Some(l) => format!("{key} at {}:{l}", self.file.display()),
                None => format!("{key} of {}", self.file.display()),
            };
            mesh.check_boundary_group(&self.mesh.file, group, &at)?;
        }
        Ok(())
    }

    fn check_group(
        &self,
        key: &str,
        name: &str,
        groups: &[(String, usize)],
        need_dim: Option<usize>,
    ) -> Result<(), InputError> {
        let dims: Vec<usize> = groups
            .iter()
            .filter(|(g, _)| g == name)
            .map(|(_, d)| *d)
            .collect();
        if dims.is_empty() {
            let avail = if groups.is_empty() {
                "the mesh has no named physical groups".to_string()
            } else {
                let list: Vec<String> = groups
                    .iter()
                    .map(|(g, d)| format!("\"{g}\" (dim {d})"))
                    .collect();
                format!("the mesh has: {}", list.join(", "))
            };
            return Err(self.err_at(
                key,
                format!("physical group \"{name}\" is not in the mesh; {avail}"),
            ));
        }
        if let Some(nd) = need_dim {
            if !dims.contains(&nd) {
                let have: Vec<String> = dims.iter().map(|d| d.to_string()).collect();
                return Err(self.err_at(
                    key,
                    format!(
                        "physical group \"{name}\" has dimension {}, but a boundary group \
                         (dimension {nd}) is needed here",
                        have.join("/")
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Validation context: builds errors that name the file.
struct Reader<'a> {
    file: &'a Path,
}

type Res<T> = Result<T, InputError>;

/// A table node being read, with its key path.
struct Tab<'n> {
    key: String,
    loc: Loc,
    entries: &'n [(String, Node)],
}

impl<'n> Tab<'n> {
    fn get(&self, k: &str) -> Option<(String, &'n Node)> {
        self.entries
            .iter()
            .find(|(name, _)| name == k)
            .map(|(name, n)| (join_key(&self.key, name), n))
    }
}

fn list(xs: &[&str]) -> String {
    xs.join(", ")
}

impl Reader<'_> {
    fn err(&self, key: &str, loc: Loc, msg: impl Into<String>) -> InputError {
        let mut msg = msg.into();
        let line = match loc {
            Loc::Line(l) => Some(l),
            Loc::Set => {
                msg.push_str(" (from --set)");
                None
            }
            Loc::Unknown => None,
        };
        let e = InputError::new(self.file, msg).with_line(line);
        if key.is_empty() {
            e
        } else {
            e.with_key(key)
        }
    }

    fn type_err(&self, key: &str, n: &Node, expected: &str) -> InputError {
        let mut msg = format!("expected {expected}, found {}", n.type_name());
        if let (Loc::Set, Kind::Str(s)) = (n.loc, &n.kind) {
            if s.starts_with('[') || s.starts_with('{') {
                msg.push_str(
                    " (the value is not valid TOML, so it was taken as a string; \
                     quote the strings inside arrays and tables)",
                );
            }
        }
        self.err(key, n.loc, msg)
    }

    /// The node as a table, keys not checked.
    fn table_any<'n>(&self, key: &str, n: &'n Node) -> Res<Tab<'n>> {
        match &n.kind {
            Kind::Table(entries) => Ok(Tab {
                key: key.to_string(),
                loc: n.loc,
                entries,
            }),
            _ => Err(self.type_err(key, n, "a table")),
        }
    }

    /// The node as a table whose keys are all in `allowed`.
    fn table<'n>(&self, key: &str, n: &'n Node, allowed: &[&str]) -> Res<Tab<'n>> {
        let Kind::Table(entries) = &n.kind else {
            return Err(self.type_err(key, n, "a table"));
        };
        for (k, v) in entries {
            if !allowed.contains(&k.as_str()) {
                let where_ = if key.is_empty() {
                    "at the top level".to_string()
                } else {
                    format!("in [{key}]")
                };
                return Err(self.err(
                    &join_key(key, k),
                    v.loc,
                    format!("unknown key {where_}; allowed keys: {}", list(allowed)),
                ));
            }
        }
        Ok(Tab {
            key: key.to_string(),
            loc: n.loc,
            entries,
        })
    }

    fn required<'n>(&self, t: &Tab<'n>, k: &str) -> Res<(String, &'n Node)> {
        t.get(k).ok_or_else(|| {
            let what = if t.key.is_empty() {
                format!("missing required section [{k}]")
            } else {
                "missing required key".to_string()
            };
            let loc = if t.key.is_empty() {
                Loc::Unknown
            } else {
                t.loc
            };
            self.err(&join_key(&t.key, k), loc, what)
        })
    }

    fn num(&self, key: &str, n: &Node) -> Res<f64> {
        let x = match n.kind {
            Kind::Float(x) => x,
            Kind::Int(i) => i as f64,
            _ => return Err(self.type_err(key, n, "a number")),
        };
        if !x.is_finite() {
            return Err(self.err(key, n.loc, format!("must be a finite number, got {x}")));
        }
        Ok(x)
    }

    fn positive(&self, key: &str, n: &Node) -> Res<f64> {
        let x = self.num(key, n)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(key, n.loc, format!("must be > 0, got {x}")))
        }
    }

    fn boolean(&self, key: &str, n: &Node) -> Res<bool> {
        match n.kind {
            Kind::Bool(b) => Ok(b),
            _ => Err(self.type_err(key, n, "a boolean (true or false)")),
        }
    }

    fn string<'n>(&self, key: &str, n: &'n Node) -> Res<&'n str> {
        match &n.kind {
            Kind::Str(s) => Ok(s),
            _ => Err(self.type_err(key, n, "a string")),
        }
    }

    fn name(&self, key: &str, n: &Node) -> Res<String> {
        let s = self.string(key, n)?;
        if s.trim().is_empty() {
            Err(self.err(key, n.loc, "must not be empty"))
        } else {
            Ok(s.to_string())
        }
    }

    fn choice<T: Copy>(&self, key: &str, n: &Node, options: &[(&str, T)]) -> Res<T> {
        let s = self.string(key, n)?;
        options
            .iter()
            .find(|(name, _)| *name == s)
            .map(|(_, v)| *v)
            .ok_or_else(|| {
                let names: Vec<String> = options.iter().map(|(o, _)| format!("\"{o}\"")).collect();
                self.err(
                    key,
                    n.loc,
                    format!("unknown value \"{s}\"; allowed: {}", names.join(", ")),
                )
            })
    }

    fn array<'n>(&self, key: &str, n: &'n Node, expected: &str) -> Res<&'n [Node]> {
        match &n.kind {
            Kind::Array(v) => Ok(v),
            _ => Err(self.type_err(key, n, expected)),
        }
    }

    fn check_len(&self, key: &str, n: &Node, len: usize) -> Res<()> {
        if len == 2 || len == 3 {
            Ok(())
        } else {
            Err(self.err(
                key,
                n.loc,
                format!("expected 2 or 3 components (one per dimension), got {len}"),
            ))
        }
    }

    /// A vector of 2 or 3 numbers.
    fn vector(&self, key: &str, n: &Node) -> Res<Vec<f64>> {
        let elems = self.array(key, n, "an array of numbers")?;
        self.check_len(key, n, elems.len())?;
        elems
            .iter()
            .enumerate()
            .map(|(i, e)| self.num(&join_index(key, i), e))
            .collect()
    }

    fn case(&self, root: &Node, output_dir: Option<&Path>) -> Res<Case> {
        let top = self.table("", root, keys::ROOT)?;
        let mesh = self.mesh(&top)?;
        let material = self.material(&top)?;
        let dirichlet = self.dirichlet(&top)?;
        let neumann = self.neumann(&top)?;
        let body_force = match top.get("body_force") {
            None => None,
            Some((k, n)) => Some(self.body_force(&k, n)?),
        };
        let solver = self.solver(&top)?;
        let output = self.output(&top, output_dir)?;
        let contacts = self.contacts(&top)?;
        let newton = self.newton(&top)?;
        let load = self.load(&top)?;
        if solver.method == Method::SnesVi {
            let why = if contacts.is_empty() {
                Some("needs a [contact] section")
            } else if contacts.iter().any(|c| c.friction != Friction::None) {
                Some("solves frictionless contact only (use method = \"newton\" with friction)")
            } else if contacts.iter().any(|c| c.force.is_some()) {
                Some("has no force control (contact.force): use method = \"newton\"")
            } else {
                None
            };
            if let Some(why) = why {
                let (sk, sn) = top.get("solver").expect("method was set in [solver]");
                let t = self.table(&sk, sn, keys::SOLVER)?;
                let (mk, m) = t.get("method").expect("method was set");
                return Err(self.err(&mk, m.loc, format!("\"snesvi\" {why}")));
            }
        }
        Ok(Case {
            file: self.file.to_path_buf(),
            mesh,
            material,
            dirichlet,
            neumann,
            body_force,
            solver,
            output,
            contacts,
            newton,
            load,
            locs: BTreeMap::new(),
        })
    }

    /// `[body_force]`: exactly one of `value` (a vector) and `expr` (an array of 2 or 3
    /// expressions of x, y, z; the variables are checked against the mesh's dimension in
    /// [`Case::check_against_mesh`]).
    fn body_force(&self, key: &str, n: &Node) -> Res<BodyForceSpec> {
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

    fn mesh(&self, top: &Tab) -> Res<MeshSection> {
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

    fn material(&self, top: &Tab) -> Res<MaterialSection> {
        let (k, n) = self.required(top, "material")?;
        let t = self.table(&k, n, keys::MATERIAL)?;
        let (yk, y) = self.required(&t, "young")?;
        let young = self.positive(&yk, y)?;
        let (pk, p) = self.required(&t, "poisson")?;
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
            young,
            poisson,
            model,
        })
    }

    /// Elements of an array of tables (`[[name]]`), each checked against `allowed`.
    fn tables<'n>(&self, top: &Tab<'n>, name: &str, allowed: &[&str]) -> Res<Vec<Tab<'n>>> {
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

    fn dirichlet(&self, top: &Tab) -> Res<Vec<Dirichlet>> {
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

    fn neumann(&self, top: &Tab) -> Res<Vec<Neumann>> {
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

    fn solver(&self, top: &Tab) -> Res<SolverSection> {
        let mut s = SolverSection::default();
        let Some((k, n)) = top.get("solver") else {
            return Ok(s);
        };
        let t = self.table(&k, n, keys::SOLVER)?;
        if let Some((mk, m)) = t.get("method") {
            s.method = self.choice(
                &mk,
                m,
                &[("newton", Method::Newton), ("snesvi", Method::SnesVi)],
            )?;
        }
        if let Some((pk, p)) = t.get("preset") {
            s.preset = self.choice(
                &pk,
                p,
                &[
                    ("auto", Preset::Auto),
                    ("direct", Preset::Direct),
                    ("iterative", Preset::Iterative),
                ],
            )?;
        }
        if let Some((uk, u)) = t.get("reuse") {
            s.reuse = self.choice(
                &uk,
                u,
                &[
                    ("auto", Reuse::Auto),
                    ("never", Reuse::Never),
                    ("always", Reuse::Always),
                    ("condensed", Reuse::Auto), // the name of auto's direct path
                ],
            )?;
        }
        if let Some((bk, b)) = t.get("repeatable") {
            s.repeatable = self.boolean(&bk, b)?;
        }
        if let Some((dk, d)) = t.get("dense_threads") {
            s.dense_threads = match &d.kind {
                Kind::Int(v) if (1..=1024).contains(v) => DenseThreads::Fixed(*v as usize),
                Kind::Int(v) => {
                    return Err(self.err(&dk, d.loc, format!("must be 1 to 1024, got {v}")));
                }
                Kind::Str(_) => self.choice(&dk, d, &[("auto", DenseThreads::Auto)])?,
                _ => return Err(self.type_err(&dk, d, "\"auto\" or an integer from 1 to 1024")),
            };
        }
        if let Some((ok, o)) = t.get("petsc_options") {
            s.petsc_options = self.string(&ok, o)?.to_string();
        }
        if let Some((rk, r)) = t.get("rtol") {
            s.rtol = self.positive(&rk, r)?;
            if s.rtol >= 1.0 {
                return Err(self.err(&rk, r.loc, format!("must be < 1, got {}", s.rtol)));
            }
        }
        Ok(s)
    }

    fn output(&self, top: &Tab, output_dir: Option<&Path>) -> Res<OutputSection> {
        let stem = self
            .file
            .file_stem()
            .map_or_else(|| "case".into(), |s| s.to_string_lossy().into_owned());
        let mut out = OutputSection {
            dir: Path::new("out").join(stem),
            fields: DEFAULT_FIELDS.to_vec(),
        };
        if let Some((k, n)) = top.get("output") {
            let t = self.table(&k, n, keys::OUTPUT)?;
            if let Some((dk, d)) = t.get("dir") {
                out.dir = PathBuf::from(self.name(&dk, d)?);
            }
            if let Some((fk, f)) = t.get("fields") {
                let elems = self.array(&fk, f, "an array of field names")?;
                let mut fields = Vec::new();
                for (i, e) in elems.iter().enumerate() {
                    let ek = join_index(&fk, i);
                    let s = self.string(&ek, e)?;
                    let Some(field) = OutputField::from_name(s) else {
                        let names: Vec<&str> = OutputField::ALL.iter().map(|f| f.name()).collect();
                        return Err(self.err(
                            &ek,
                            e.loc,
                            format!("unknown field \"{s}\"; allowed: {}", list(&names)),
                        ));
                    };
                    if !fields.contains(&field) {
                        fields.push(field);
                    }
                }
                out.fields = fields;
            }
        }
        if let Some(d) = output_dir {
            out.dir = d.to_path_buf();
        }
        Ok(out)
    }

    /// The contact pairs: one `[contact]` table or an array `[[contact]]`, checked against each
    /// other (distinct groups, one friction law the solver can combine, one rigid-mode
    /// handling).
    fn contacts(&self, top: &Tab) -> Res<Vec<ContactSection>> {
        let Some((k, n)) = top.get("contact") else {
            return Ok(Vec::new());
        };
        let pairs = match n.kind {
            Kind::Array(_) => {
                let elems = self.array(
                    &k,
                    n,
                    "a table ([contact]) or an array of tables ([[contact]])",
                )?;
                if elems.is_empty() {
                    return Err(self.err(
                        &k,
                        n.loc,
                        "is empty: give at least one [[contact]] table",
                    ));
                }
                elems
                    .iter()
                    .enumerate()
                    .map(|(i, e)| self.contact(&join_index(&k, i), e))
                    .collect::<Res<Vec<_>>>()?
            }
            _ => vec![self.contact(&k, n)?],
        };
        self.check_pairs(top, &pairs)?;
        Ok(pairs)
    }

    /// What several pairs must agree on (docs/obstacles.md, "Several contact pairs").
    fn check_pairs(&self, top: &Tab, pairs: &[ContactSection]) -> Res<()> {
        let (_, cn) = top.get("contact").expect("pairs were read");
        let elems = match cn.kind {
            Kind::Array(ref a) => a.iter().collect::<Vec<_>>(),
            _ => vec![cn],
        };
        let at = |i: usize, name: &str| -> (String, Loc) {
            let key = join_key(&pairs[i].key, name);
            let loc = match elems[i].kind {
                Kind::Table(ref t) => t
                    .iter()
                    .find(|(n, _)| n.as_str() == name)
                    .map_or(elems[i].loc, |(_, v)| v.loc),
                _ => elems[i].loc,
            };
            (key, loc)
        };
        for (j, b) in pairs.iter().enumerate() {
            if let Some(a) = pairs[..j].iter().find(|a| a.group == b.group) {
                let (key, loc) = at(j, "group");
                return Err(self.err(
                    &key,
                    loc,
                    format!(
                        "\"{}\" is already the group of {}: a contact node belongs to one pair only",
                        b.group, a.key
                    ),
                ));
            }
        }
        // Tresca pairs combine with frictionless ones (threshold 0), Coulomb pairs with
        // frictionless ones (μ = 0) and with each other (each its μ, one algorithm); Tresca and
        // Coulomb are two different iterations and do not mix.
        let coulomb = pairs.iter().find_map(|p| match p.friction {
            Friction::Coulomb { algorithm, .. } => Some((p, algorithm)),
            _ => None,
        });
        if let Some((c, algorithm)) = coulomb {
            let clash = pairs.iter().position(|p| match p.friction {
                Friction::None => false,
                Friction::Tresca { .. } => true,
                Friction::Coulomb { algorithm: a, .. } => a != algorithm,
            });
            if let Some(j) = clash {
                let (key, loc) = at(j, "friction");
                return Err(self.err(
                    &key,
                    loc,
                    format!(
                        "does not combine with {}.friction: Coulomb pairs may have their own μ \
                         but need the same algorithm, and Tresca and Coulomb do not mix \
                         (frictionless pairs combine with either)",
                        c.key
                    ),
                ));
            }
        }
        if let Some(j) = pairs
            .iter()
            .position(|p| p.rigid_modes != pairs[0].rigid_modes)
        {
            let (key, loc) = at(j, "rigid_modes");
            return Err(self.err(
                &key,
                loc,
                format!(
                    "differs from {}.rigid_modes: the body's rigid modes are handled one way",
                    pairs[0].key
                ),
            ));
        }
        Ok(())
    }

    /// One contact pair at `k` (`contact` or `contact[i]`).
    fn contact(&self, k: &str, n: &Node) -> Res<ContactSection> {
        let t = self.table(k, n, keys::CONTACT)?;
        let (gk, g) = self.required(&t, "group")?;
        let group = self.name(&gk, g)?;
        let (ok, o) = self.required(&t, "obstacle")?;
        let obstacle = self.obstacle(&ok, o)?;
        let motion = match t.get("motion") {
            None => None,
            Some((mk, m)) => Some(self.motion(&mk, m, "the obstacle's translation")?),
        };
        let friction = match t.get("friction") {
            None => Friction::None,
            Some((fk, f)) => self.friction(&fk, f)?,
        };
        let force = match t.get("force") {
            None => None,
            Some((fk, f)) => {
                let force = self.motion(&fk, f, "the force pressing the obstacle onto the body")?;
                let why = if motion.is_some() {
                    Some("prescribes the force instead of the motion: give one of them")
                } else if force.table.is_empty() && force.value.iter().all(|&x| x == 0.0) {
                    Some("is zero: force control needs a direction (a nonzero vector)")
                } else {
                    None
                };
                if let Some(why) = why {
                    return Err(self.err(&fk, f.loc, format!("{fk} {why}")));
                }
                Some(force)
            }
        };
        let rigid_modes = match t.get("rigid_modes") {
            None => RigidModeHandling::Auto,
            Some((rk, r)) => self.choice(
                &rk,
                r,
                &[
                    ("auto", RigidModeHandling::Auto),
                    ("none", RigidModeHandling::None),
                ],
            )?,
        };
        Ok(ContactSection {
            key: k.to_string(),
            group,
            obstacle,
            motion,
            force,
            friction,
            rigid_modes,
        })
    }

    /// `contact.motion` (`contact.force`): a vector `[dx, dy(, dz)]`, a table
    /// `{ value = [...], ramp = false }`, or `{ table = [[t, dx, dy(, dz)], ...] }`; `keys`
    /// names the vector and its table entry.
    fn motion(&self, key: &str, n: &Node, what: &str) -> Res<Motion> {
        if let Kind::Table(_) = n.kind {
            let t = self.table(key, n, keys::MOTION)?;
            if let Some((tk, tn)) = t.get("table") {
                if let Some((ok, o)) = t.get("value").or_else(|| t.get("ramp")) {
                    return Err(self.err(
                        &ok,
                        o.loc,
                        format!("{tk} gives the whole history: no '{ok}' beside it"),
                    ));
                }
                let table = self.history_table(&tk, tn, what)?;
                return Ok(Motion {
                    value: table.last().expect("two rows or more").1.clone(),
                    ramp: true,
                    table,
                    key: tk,
                });
            }
            let (vk, v) = self.required(&t, "value")?;
            let value = self.vector(&vk, v)?;
            let ramp = match t.get("ramp") {
                None => true,
                Some((rk, r)) => self.boolean(&rk, r)?,
            };
            return Ok(Motion {
                value,
                ramp,
                table: Vec::new(),
                key: vk,
            });
        }
        let value = match n.kind {
            Kind::Array(_) => self.vector(key, n)?,
            _ => {
                return Err(self.type_err(
                    key,
                    n,
                    &format!(
                        "an array of numbers ({what}), a table {{ value, ramp }} or {{ table }}"
                    ),
                ))
            }
        };
        Ok(Motion {
            value,
            ramp: true,
            table: Vec::new(),
            key: key.to_string(),
        })
    }

    /// `KEY.table`: at least two rows `[load factor, x, y(, z)]`, all of one length (3 in 2D,
    /// 4 in 3D; checked against the mesh later), the first factor 0, the factors increasing.
    fn history_table(&self, key: &str, n: &Node, what: &str) -> Res<Vec<(f64, Vec<f64>)>> {
        let expected = format!("an array of rows [load factor, x, y(, z)] ({what})");
        let rows = self.array(key, n, &expected)?;
        if rows.len() < 2 {
            return Err(self.err(
                key,
                n.loc,
                format!(
                    "needs at least two rows [load factor, x, y(, z)], got {} (a value held in \
                     every step is {{ value = [...], ramp = false }})",
                    rows.len()
                ),
            ));
        }
        if rows.len() > load::MAX_STEPS {
            return Err(self.err(
                key,
                n.loc,
                format!("at most {} rows, got {}", load::MAX_STEPS, rows.len()),
            ));
        }
        let mut out: Vec<(f64, Vec<f64>)> = Vec::with_capacity(rows.len());
        for (i, r) in rows.iter().enumerate() {
            let rk = join_index(key, i);
            let elems = self.array(&rk, r, "a row [load factor, x, y(, z)]")?;
            let width = out.first().map(|(_, v)| v.len() + 1);
            if !(elems.len() == 3 || elems.len() == 4) || width.is_some_and(|w| w != elems.len()) {
                let need = match width {
                    Some(w) => format!("{w} like the first row"),
                    None => "3 (2D) or 4 (3D)".to_string(),
                };
                return Err(self.err(
                    &rk,
                    r.loc,
                    format!(
                        "a row is [load factor, x, y(, z)]: 1 + one number per dimension, \
                         {need}; got {}",
                        elems.len()
                    ),
                ));
            }
            let nums = elems
                .iter()
                .enumerate()
                .map(|(j, e)| self.num(&join_index(&rk, j), e))
                .collect::<Res<Vec<f64>>>()?;
            let t = nums[0];
            match out.last() {
                None if t != 0.0 => {
                    return Err(self.err(
                        &join_index(&rk, 0),
                        r.loc,
                        format!(
                            "the first row's load factor must be 0 (the history starts at the \
                             unloaded state; its values there may be nonzero), got {t}"
                        ),
                    ))
                }
                Some((prev, _)) if t <= *prev => {
                    return Err(self.err(
                        &join_index(&rk, 0),
                        r.loc,
                        format!(
                            "load factor {t} is not above the row before's ({prev}): the \
                             factors of a table must increase"
                        ),
                    ))
                }
                _ => {}
            }
            out.push((t, nums[1..].to_vec()));
        }
        Ok(out)
    }

    fn obstacle(&self, key: &str, n: &Node) -> Res<ObstacleSpec> {
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
            ],
        )?;
        match ty {
            Ty::Plane => {
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
            Ty::Sphere => {
                let t = self.table(key, n, keys::SPHERE)?;
                let (ck, c) = self.required(&t, "center")?;
                let center = self.vector(&ck, c)?;
                let (rk, r) = self.required(&t, "radius")?;
                let radius = self.positive(&rk, r)?;
                Ok(ObstacleSpec::Sphere { center, radius })
            }
            Ty::Cylinder => {
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
            Ty::Cone => {
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
            Ty::Pyramid => {
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
            Ty::Punch => self.punch(key, n),
            Ty::Height => self.height(key, n),
            Ty::Surface => self.surface(key, n),
        }
    }

    /// A `[[mesh.project]]` shape must be one of the analytic ones: refinement moves nodes
    /// onto them (not onto a height graph or a triangle surface).
    fn analytic_shape(&self, key: &str, n: &Node) -> Res<()> {
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

    fn friction(&self, key: &str, n: &Node) -> Res<Friction> {
        const FORMS: &str = "\"none\", { law = \"tresca\", threshold = ... } or \
                             { law = \"coulomb\", mu = ... }";
        match &n.kind {
            Kind::Str(s) if s == "none" => Ok(Friction::None),
            Kind::Str(s) if s == "tresca" => Err(self.err(
                key,
                n.loc,
                "Tresca friction needs a threshold: friction = { law = \"tresca\", threshold = ... }",
            )),
            Kind::Str(s) if s == "coulomb" => Err(self.err(
                key,
                n.loc,
                "Coulomb friction needs a friction coefficient: friction = { law = \"coulomb\", mu = ... }",
            )),
            Kind::Str(s) => Err(self.err(
                key,
                n.loc,
                format!("unknown value \"{s}\"; allowed: {FORMS}"),
            )),
            Kind::Table(_) => {
                let t = self.table(key, n, keys::FRICTION_ANY)?;
                let (lk, l) = self.required(&t, "law")?;
                #[derive(Clone, Copy)]
                enum Law {
                    None,
                    Tresca,
                    Coulomb,
                }
                let law = self.choice(
                    &lk,
                    l,
                    &[
                        ("none", Law::None),
                        ("tresca", Law::Tresca),
                        ("coulomb", Law::Coulomb),
                    ],
                )?;
                match law {
                    Law::None => {
                        self.table(key, n, keys::FRICTION_NONE)?;
                        Ok(Friction::None)
                    }
                    Law::Tresca => {
                        self.table(key, n, keys::FRICTION_TRESCA)?;
                        let (hk, h) = self.required(&t, "threshold")?;
                        let threshold = self.num(&hk, h)?;
                        if threshold < 0.0 {
                            return Err(self.err(
                                &hk,
                                h.loc,
                                format!("must be >= 0, got {threshold}"),
                            ));
                        }
                        Ok(Friction::Tresca { threshold })
                    }
                    Law::Coulomb => {
                        self.table(key, n, keys::FRICTION_COULOMB)?;
                        let (mk, m) = self.required(&t, "mu")?;
                        let mu = self.num(&mk, m)?;
                        if mu < 0.0 {
                            return Err(self.err(&mk, m.loc, format!("must be >= 0, got {mu}")));
                        }
                        let algorithm = match t.get("algorithm") {
                            None => CoulombAlgorithm::Newton,
                            Some((ak, a)) => self.choice(
                                &ak,
                                a,
                                &[
                                    ("newton", CoulombAlgorithm::Newton),
                                    ("fixed-point", CoulombAlgorithm::FixedPoint),
                                ],
                            )?,
                        };
                        Ok(Friction::Coulomb { mu, algorithm })
                    }
                }
            }
            _ => Err(self.type_err(key, n, FORMS)),
        }
    }

    fn newton(&self, top: &Tab) -> Res<NewtonSection> {
        let mut s = NewtonSection::default();
        let Some((k, n)) = top.get("newton") else {
            return Ok(s);
        };
        let t = self.table(&k, n, keys::NEWTON)?;
        if let Some((ok, o)) = t.get("on_cycle") {
            s.on_cycle = self.choice(
                &ok,
                o,
                &[
                    ("least_index", OnCycle::LeastIndex),
                    ("stop", OnCycle::Stop),
                ],
            )?;
        }
        if let Some((ik, i)) = t.get("init") {
            s.init = self.choice(
                &ik,
                i,
                &[
                    ("auto", NewtonInit::Auto),
                    ("all_active", NewtonInit::AllActive),
                    ("all_inactive", NewtonInit::AllInactive),
                    ("gap", NewtonInit::Gap),
                ],
            )?;
        }
        if let Some((ck, c)) = t.get("c") {
            s.c = Some(self.positive(&ck, c)?);
        }
        if let Some((mk, m)) = t.get("max_steps") {
            let Kind::Int(v) = m.kind else {
                return Err(self.type_err(&mk, m, "an integer"));
            };
            if v < 1 {
                return Err(self.err(&mk, m.loc, format!("must be >= 1, got {v}")));
            }
            s.max_steps = usize::try_from(v).unwrap_or(usize::MAX);
        }
        if let Some((tk, tol)) = t.get("tol_u") {
            s.tol_u = self.positive(&tk, tol)?;
        }
        if let Some((sk, st)) = t.get("strict") {
            s.strict = self.boolean(&sk, st)?;
        }
        Ok(s)
    }
}
