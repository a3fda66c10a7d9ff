//! The validated case: reading and parsing the file, errors at its keys.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::body::{BodyForceSpec, Dirichlet, MaterialModel, MaterialSection, MeshSection, Neumann};
use super::contact::{ContactSection, Friction};
use super::keys;
use super::load::LoadSection;
use super::output::OutputSection;
use super::reader::{Reader, Res};
use super::solver::{Method, NewtonSection, Preset, SolverSection};
use super::tree::{self, Loc, Node};
use crate::error::{InputError, RunError};

/// A validated case: defaults filled in, paths resolved.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// The case file as given on the command line.
    pub file: PathBuf,
    pub mesh: MeshSection,
    /// `[material]` (one entry, no group) or the `[[material]]` tables, in file order.
    pub materials: Vec<MaterialSection>,
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
    pub(super) locs: BTreeMap<String, Loc>,
}

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

    /// An input error found after the case was read (against the mesh, in the contact set-up,
    /// ...) that names a key of this case but no line: placed as [`Case::error_at`] places
    /// one — at the key's line in the file, or said to come from `--set`. Other errors as
    /// they are. Pure.
    pub fn locate(&self, e: RunError) -> RunError {
        match e {
            RunError::Input(i) if i.line.is_none() && i.file == self.file => {
                let line = i.key.as_deref().and_then(|k| self.locs.get(k).copied());
                RunError::Input(match line {
                    Some(Loc::Line(l)) => i.with_line(Some(l)),
                    Some(Loc::Set) if !i.message.contains("(from --set)") => InputError {
                        message: format!("{} (from --set)", i.message),
                        ..i
                    },
                    _ => i,
                })
            }
            e => e,
        }
    }

    /// An input error of the key path `key`, at its line when it came from the file.
    pub fn error_at(&self, key: &str, msg: impl Into<String>) -> InputError {
        self.err_at(key, msg)
    }

    pub(super) fn err_at(&self, key: &str, msg: impl Into<String>) -> InputError {
        let loc = self.locs.get(key).copied().unwrap_or(Loc::Unknown);
        Reader { file: &self.file }.err(key, loc, msg)
    }

    /// The model to use for a mesh of dimension `dim`: a 2D mesh needs `plane_strain` or
    /// `plane_stress`, a 3D mesh needs `3d` or no model; every material the same (the
    /// reader refuses two different models).
    pub fn model(&self, dim: usize) -> Result<MaterialModel, InputError> {
        let mut out = MaterialModel::ThreeD;
        for m in &self.materials {
            out = self.model_of(m, dim)?;
        }
        Ok(out)
    }

    fn model_of(&self, m: &MaterialSection, dim: usize) -> Result<MaterialModel, InputError> {
        let key = &m.key;
        match (dim, m.model) {
            (2, Some(m @ (MaterialModel::PlaneStrain | MaterialModel::PlaneStress))) => Ok(m),
            (2, None) => Err(self.err_at(
                key,
                format!(
                    "the mesh is 2D: {key}.model is required, \"plane_strain\" or \"plane_stress\""
                ),
            )),
            (3, None | Some(MaterialModel::ThreeD)) => Ok(MaterialModel::ThreeD),
            (2 | 3, Some(m)) => Err(self.err_at(
                &format!("{key}.model"),
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
    /// force (a table, or a ramped vector: zero at factor 0) gives a nonzero force at every
    /// planned factor (force control needs a direction).
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
            if let Some(f) = &c.force {
                if let Some(t) = factors.iter().find(|&&t| f.at(t).iter().all(|&x| x == 0.0)) {
                    let ramped = if f.table.is_empty() {
                        " (a ramped force is t·F; `ramp = false` holds F in every step)"
                    } else {
                        ""
                    };
                    return Err(self.err_at(
                        &f.key,
                        format!(
                            "gives a zero force at the load factor {t} of the run{ramped}: \
                             force control needs a direction (a nonzero force) in every step"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

impl Reader<'_> {
    /// The whole case: every section read, then the checks across sections.
    pub(super) fn case(&self, root: &Node, output_dir: Option<&Path>) -> Res<Case> {
        let top = self.table("", root, keys::ROOT)?;
        let mesh = self.mesh(&top)?;
        let materials = self.materials(&top)?;
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
        self.check_schur_path(&top, &solver, &contacts, &newton)?;
        if solver.method == Method::SnesVi {
            let why = if contacts.is_empty() {
                Some("needs a [contact] section")
            } else if contacts.iter().any(|c| c.friction != Friction::None) {
                Some("solves frictionless contact only (use method = \"newton\" with friction)")
            } else if contacts.iter().any(|c| c.force.is_some()) {
                Some("has no force control (contact.force): use method = \"newton\"")
            } else if solver.preset == Preset::Iterative {
                Some(
                    "needs a factorisation of its reduced systems, not preset = \"iterative\" \
                     (GMRES + GAMG does not converge on them): use preset = \"direct\" or \
                     \"auto\"",
                )
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
            materials,
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
}

impl Case {
    /// An input error at `solver.path = "schur"`, which cannot run because `why`.
    pub fn schur_path_refused(&self, why: &str) -> InputError {
        self.err_at("solver.path", format!("the Schur path {why}"))
    }
}
