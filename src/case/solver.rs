//! `[solver]` and `[newton]`.

use super::contact::{ContactSection, CoulombAlgorithm, Friction};
use super::keys;
use super::reader::{Reader, Res, Tab};
use super::tree::Kind;

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

/// `solver.path`: which algorithm solves a Newton contact case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SolverPath {
    /// The Schur path where it runs (direct preset; frictionless, or Coulomb's generalised
    /// Newton from newton.init = "auto"), else the plain path.
    Auto,
    /// One factorisation with MUMPS' Schur complement on the candidate contact nodes for the
    /// whole solve, Algorithm 1 (or Coulomb's generalised Newton) on their dense system
    /// (signorini/schur/); it falls back to the plain path by itself.
    Schur,
    /// Algorithms 1 / 2 (or Coulomb's generalised Newton) on the whole reduced system, solved
    /// in every Newton step (signorini/plain_path/), carrying a factorisation or
    /// preconditioner from step to step as `solver.reuse` says.
    Plain,
}

impl SolverPath {
    pub fn name(self) -> &'static str {
        match self {
            SolverPath::Auto => "auto",
            SolverPath::Schur => "schur",
            SolverPath::Plain => "plain",
        }
    }

    /// The Schur path may run (where the solver factorises and the contact boundary fits it).
    pub fn allows_schur(self) -> bool {
        self != SolverPath::Plain
    }
}

/// `solver.reuse`: how the plain path carries a factorisation or preconditioner from one Newton
/// step to the next: whether a Newton step of the direct preset may solve its reduced system by
/// Krylov iterations preconditioned with the last factorisation instead of refactorising; with
/// the iterative preset, whether Newton steps share one preconditioner (GAMG hierarchy), start
/// from the previous iterate and (frictionless) solve inexactly while the active set changes
/// (signorini::reduced, `solve_amg`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reuse {
    /// Direct, frictionless: a factorisation is reused when MUMPS' counts say it pays (flops
    /// of the factorisation against those of its solves, signorini::reduced `ReuseCosts`;
    /// never timings). Direct with friction: every step refactorises.
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
/// path's dense work from [`crate::tuning::WIDE_MIN_DIM`] unknowns on, crate::blas::NodeCores).
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
    /// The algorithm: the Schur path or the plain path (contact, method = "newton").
    pub path: SolverPath,
    /// The plain path's reuse of a factorisation (direct preset) or of the preconditioner,
    /// warm starts and inexact early steps (iterative preset) across Newton steps (contact).
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
            path: SolverPath::Auto,
            reuse: Reuse::Auto,
            repeatable: false,
            dense_threads: DenseThreads::Auto,
        }
    }
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
    /// Complementarity parameter c > 0 (a nodal force per length); None: c = 100 E h_c^(d−2)
    /// (h_c the mean contact mesh size; tuning::DEFAULT_C_FACTOR).
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

impl Reader<'_> {
    pub(super) fn solver(&self, top: &Tab) -> Res<SolverSection> {
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
        (s.path, s.reuse) = self.path_and_reuse(&t)?;
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

    /// `solver.path` and `solver.reuse`. Without `path`, `reuse = "never"` or `"always"`
    /// imply the plain path (the Schur path keeps one factorisation for the whole solve, itself
    /// a reuse); `reuse = "condensed"` (the former name of the default, kept so that older
    /// case files run as they did) is `"auto"`; with `path = "schur"`, `reuse` may only be
    /// `"auto"` (or `"condensed"`).
    fn path_and_reuse(&self, t: &Tab) -> Res<(SolverPath, Reuse)> {
        let paths = [
            ("auto", SolverPath::Auto),
            ("schur", SolverPath::Schur),
            ("plain", SolverPath::Plain),
        ];
        let path = match t.get("path") {
            Some((pk, p)) => Some(self.choice(&pk, p, &paths)?),
            None => None,
        };
        let Some((uk, u)) = t.get("reuse") else {
            return Ok((path.unwrap_or(SolverPath::Auto), Reuse::Auto));
        };
        let reuses = [
            ("auto", (Reuse::Auto, false)),
            ("never", (Reuse::Never, false)),
            ("always", (Reuse::Always, false)),
            ("condensed", (Reuse::Auto, true)),
        ];
        let (reuse, condensed) = self.choice(&uk, u, &reuses)?;
        match path {
            // the former name of the default: cases written with it run as they always did
            None if condensed => Ok((SolverPath::Auto, reuse)),
            None if reuse == Reuse::Auto => Ok((SolverPath::Auto, reuse)),
            None => Ok((SolverPath::Plain, reuse)),
            Some(p) if condensed && p != SolverPath::Schur => Err(self.err(
                &uk,
                u.loc,
                format!(
                    "\"condensed\" names the Schur path, which solver.path = \"{}\" does not \
                     take: use solver.path alone",
                    p.name()
                ),
            )),
            Some(SolverPath::Schur) if reuse != Reuse::Auto => Err(self.err(
                &uk,
                u.loc,
                format!(
                    "\"{}\" is how the plain path carries a factorisation from one Newton step \
                     to the next; solver.path = \"schur\" keeps one factorisation for the whole \
                     solve (drop one of the two keys)",
                    reuse.name()
                ),
            )),
            Some(p) => Ok((p, reuse)),
        }
    }

    /// `solver.path = "schur"` where the Schur path cannot run: an error at the key.
    pub(super) fn check_schur_path(
        &self,
        top: &Tab,
        solver: &SolverSection,
        contacts: &[ContactSection],
        newton: &NewtonSection,
    ) -> Res<()> {
        if solver.path != SolverPath::Schur {
            return Ok(());
        }
        let coulomb = |alg: CoulombAlgorithm| {
            let of = |f: &Friction| match f {
                Friction::Coulomb { algorithm, .. } => *algorithm == alg,
                _ => false,
            };
            contacts.iter().any(|c| of(&c.friction))
        };
        let why = if solver.method == Method::SnesVi {
            Some("runs the semismooth Newton method, not method = \"snesvi\"")
        } else if solver.preset == Preset::Iterative {
            Some("needs a factorisation: not the iterative preset")
        } else if (contacts.iter()).any(|c| matches!(c.friction, Friction::Tresca { .. }))
            && newton.init != NewtonInit::Auto
        {
            Some("starts Tresca's Algorithm 2 only from newton.init = \"auto\"")
        } else if coulomb(CoulombAlgorithm::FixedPoint) {
            Some("does not run Coulomb's fixed point (its Tresca solves run on the plain path)")
        } else if coulomb(CoulombAlgorithm::Newton) && newton.init != NewtonInit::Auto {
            Some("starts Coulomb's generalised Newton only from newton.init = \"auto\"")
        } else {
            None
        };
        let Some(why) = why else {
            return Ok(());
        };
        let (sk, sn) = top
            .get("solver")
            .expect("path = \"schur\" was set in [solver]");
        let t = self.table(&sk, sn, keys::SOLVER)?;
        let (key, node) = match (t.get("path"), t.get("reuse")) {
            (Some(p), _) | (None, Some(p)) => p,
            (None, None) => unreachable!("the Schur path was asked by path or reuse"),
        };
        Err(self.err(&key, node.loc, format!("the Schur path {why}")))
    }

    pub(super) fn newton(&self, top: &Tab) -> Res<NewtonSection> {
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
