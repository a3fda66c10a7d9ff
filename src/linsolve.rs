//! The linear-solver seam: one [`LinearSetup`] per solve, built from the resolved preset, the
//! systems' symmetry, the relative tolerance, the case file's `solver.petsc_options` and the
//! command line (after `--`), in increasing priority. Its options live in a database of its
//! own ([`OptionsDb`]), never in PETSc's global one, and its [`SolverKind`] — what the solves
//! will actually run — is decided once, from those resolved options; every algorithmic choice
//! (the condensed path, the reuse of factorisations, the reduction of Coulomb's rows, the
//! near-null space) asks the kind.

use crate::assembly;
use crate::case::{Preset, SolverSection};
use crate::error::{InputError, RunError};
use crate::mesh::Mesh;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::mumps::{
    Controls, FactorStats, SchurFactor, SchurRequest, Settings, USER_CNTL, USER_ICNTL,
};
use crate::petsc::optdb::{self, OptionsDb};
use crate::petsc::{self, ndfactor, Ksp, MPI_Comm, Matrix, PInt, SolveInfo, Vector};
pub use crate::tuning::REUSE_RESTART;
use crate::tuning::{ALLATONCE_MIN_RANKS, ITERATIVE_MAX_IT, ITERATIVE_RESTART, WORKSPACE_PERCENT};
use crate::warnings::{self, Warning};
use std::rc::Rc;

/// What the linear solves run, as the solver's options resolve it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolverKind {
    /// A factorisation by Cholesky / LDLᵀ (PCCHOLESKY): symmetric systems.
    DirectSymmetric,
    /// A factorisation by LU (PCLU).
    DirectUnsymmetric,
    /// Krylov iterations with a preconditioner that does not factorise (GAMG, ...).
    Iterative,
}

impl SolverKind {
    /// The kind of a PETSc PC type name.
    fn of_pc(pc_type: &str) -> SolverKind {
        match pc_type {
            "cholesky" => SolverKind::DirectSymmetric,
            "lu" => SolverKind::DirectUnsymmetric,
            _ => SolverKind::Iterative,
        }
    }

    /// True for a factorisation (PCLU / PCCHOLESKY).
    pub fn factorises(self) -> bool {
        !matches!(self, SolverKind::Iterative)
    }
}

/// The options a preset stands for. `symmetric`: the systems are symmetric (linear elasticity
/// and frictionless contact, whose (3.29) is applied symmetrically), so MUMPS factors them by
/// Cholesky (LDLᵀ), about half the work and memory of LU; Tresca's (3.42) needs LU.
pub fn preset_options(preset: Preset, rtol: f64, symmetric: bool) -> String {
    match preset {
        // ICNTL(14): workspace slack over MUMPS' estimate (tuning::WORKSPACE_PERCENT).
        Preset::Direct | Preset::Auto => format!(
            "-ksp_type preonly -pc_type {} -pc_factor_mat_solver_type mumps \
             -mat_mumps_icntl_14 {WORKSPACE_PERCENT}",
            if symmetric { "cholesky" } else { "lu" }
        ),
        // GMRES with right preconditioning (the true residual is tested) and smoothed
        // aggregation AMG with the rigid-body near-null space; the symmetrised graph keeps
        // aggregation valid for the unsymmetric reduced systems of friction (Tresca (3.42),
        // Coulomb (F7) in docs/friction.md, unsymmetric also in 2D; for Coulomb the hierarchy
        // is built on the system without its row mix, step_system/write.rs `write_unmixed`). On those
        // unsymmetric systems classical Gram–Schmidt loses the Krylov basis' orthogonality in
        // long solves and GMRES broke down (DIVERGED_BREAKDOWN: the 3D block held and pushed
        // into a sphere, a floating ball, the hemisphere's load steps; 2 ranks): it is refined
        // where needed, which also halved the iterations of the longest solves (block at
        // 112 890 unknowns: 367 → 185). The symmetric systems of a body pair whose slave side
        // is much stiffer than its master lose it as well (a 2D disk 3e6 times as stiff as its
        // block broke down after 400 iterations, 20–28 refined; a 3D block 3 000 times as
        // stiff as its ball: 284 + 133 + 82 iterations, 96 + 95 + 88 refined), so every
        // system is refined where needed; where nothing is lost that costs one norm per
        // iteration and leaves the iterations as they were. The coarsest level is
        // solved by a pseudo-inverse (SVD): a hierarchy built on a matrix with a null space
        // (a floating body's free rigid modes, step_system/) has a singular coarse matrix, on
        // which LU breaks GMRES down (2D Hertz at ν = 0.4999); on a regular one it is LU's
        // solve. No absolute tolerance: PETSc's default 1e-50 is a residual in the case's unit
        // of force, and ended the solves of the 3D block in a unit of force 2^150 times the
        // case's (residuals ~1e-47) at once, with a final state that was not a solution.
        Preset::Iterative => format!(
            "-ksp_type gmres -ksp_pc_side right -ksp_gmres_restart {ITERATIVE_RESTART} \
             -ksp_rtol {rtol:e} -ksp_atol 0 -ksp_max_it {ITERATIVE_MAX_IT} -pc_type gamg \
             -pc_gamg_sym_graph true \
             -mg_levels_ksp_type chebyshev -mg_levels_pc_type jacobi -mg_coarse_pc_type svd \
             -ksp_gmres_cgs_refinement_type refine_ifneeded"
        ),
    }
}

/// The coarsest level's zero singular values, relative to the matrix' largest diagonal entry
/// (PETSc's absolute default, for a matrix of unit size).
pub const SVD_ZERO_RELATIVE: f64 = 1e-12;

/// Splits "-a 1 -b -c x" into (name, value) pairs; a token that starts with '-' and is not a
/// number begins a new option.
pub fn split_options(s: &str) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for tok in s.split_whitespace() {
        let is_name = tok.starts_with('-') && tok.len() > 1 && tok.parse::<f64>().is_err();
        if is_name {
            out.push((tok.to_string(), String::new()));
        } else if let Some(last) = out.last_mut() {
            if last.1.is_empty() {
                last.1 = tok.to_string();
            } else {
                last.1.push(' ');
                last.1.push_str(tok);
            }
        }
    }
    out
}

/// Options prefix of the Krylov solver that reuses a factorisation (`-reuse_ksp_monitor`, ...).
pub const REUSE_PREFIX: &str = "reuse_";

/// Relative tolerance of the reuse solver on the preconditioned residual ‖M⁻¹(b − S x)‖ with
/// x₀ = 0: M = S_j (the factored matrix) is close to S, so this bounds the relative error of
/// x, far below Algorithm 1's tolerances (tests/reuse.rs: u agrees with the plain path to
/// 1e-10).
pub const REUSE_RTOL: f64 = 1e-13;

/// The reuse solver's defaults (the case's `petsc_options` and the command line, with the
/// prefix, override them): GMRES, left preconditioning (the preconditioned residual is
/// tested), classical Gram–Schmidt refined when needed, no absolute tolerance (a residual in
/// the case's unit of force: the iterative preset's note).
pub fn reuse_options() -> String {
    let p = REUSE_PREFIX;
    format!(
        "-{p}ksp_type gmres -{p}ksp_pc_side left -{p}ksp_norm_type preconditioned \
         -{p}ksp_rtol {REUSE_RTOL:e} -{p}ksp_atol 0 -{p}ksp_gmres_restart {REUSE_RESTART} \
         -{p}ksp_gmres_cgs_refinement_type refine_ifneeded"
    )
}

/// The user's MUMPS controls in `db` (`-mat_mumps_icntl_K`, `-mat_mumps_cntl_K` for the K of
/// [`USER_ICNTL`] and [`USER_CNTL`]); a value that is not a number is refused, naming the
/// option. Local.
fn mumps_controls(db: &OptionsDb) -> petsc::Result<Controls> {
    let mut out = Controls::default();
    for &(k, _) in USER_ICNTL {
        let name = format!("-mat_mumps_icntl_{k}");
        if let Some(v) = db.value(&name)? {
            let v = v
                .trim()
                .parse::<i32>()
                .map_err(|_| petsc::raised_error(format!("{name} {v:?}: not an integer")))?;
            out.icntl.push((k, v));
        }
    }
    for &(k, _) in USER_CNTL {
        let name = format!("-mat_mumps_cntl_{k}");
        if let Some(v) = db.value(&name)? {
            let v = v
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| petsc::raised_error(format!("{name} {v:?}: not a number")))?;
            out.cntl.push((k, v));
        }
    }
    Ok(out)
}

/// What a [`LinearSetup`] is built from.
#[derive(Clone, Copy, Debug)]
pub struct SolverRequest<'a> {
    /// The resolved preset (not "auto").
    pub preset: Preset,
    /// The iterative preset's relative tolerance.
    pub rtol: f64,
    /// The systems are symmetric (Cholesky on the direct preset).
    pub symmetric: bool,
    /// The case file's `solver.petsc_options`.
    pub case_options: &'a str,
    /// `solver.repeatable`: MUMPS on rank 0 alone.
    pub repeatable: bool,
    /// The largest |diagonal entry| of the stiffness matrix (`solver::matrix_scale`).
    pub scale: f64,
}

/// The linear solver's set-up: its private options database, its kind, the MUMPS variant of
/// its factorisations and AMG's near-null space coordinates.
pub struct LinearSetup {
    options: Rc<OptionsDb>,
    kind: SolverKind,
    /// MUMPS with the project's nested-dissection order ([`ndfactor`]) in place of PETSc's
    /// factorisation: a MUMPS factorisation whose ordering the options do not choose.
    own_order: bool,
    /// MUMPS' work on rank 0 alone ([`ndfactor::ONE_PROCESS_OPTION`]).
    one_process: bool,
    /// The user's MUMPS controls for the project's own MUMPS instances.
    controls: Controls,
    /// AMG's near-null space (iterative kind): the rigid-body modes of these coordinates.
    near_null: Option<Vector>,
}

impl LinearSetup {
    /// The options of `req` in a private database — the preset, then the case file's
    /// `petsc_options`, then the global database's options (the command line), each
    /// overriding the one before — and the kind they resolve to. Local.
    ///
    /// The iterative preset's coarse SVD treats singular values below 1e-12 × `req.scale` as
    /// zero (PETSc's default is an absolute 1e-12): the coarsest level is singular when a
    /// floating body's free rigid modes are S's null space, and its null singular values sit at
    /// round-off of the matrix' own size. On a body with E = 1e9 (block3d, 2 ranks) the absolute
    /// default inverted those round-off singular values and GMRES stalled at 1.4e-4 ‖b‖
    /// (DIVERGED_BREAKDOWN) where E = 2 converged in 18 iterations; the run is now the same in
    /// any unit system.
    pub fn new(req: &SolverRequest) -> petsc::Result<LinearSetup> {
        let mut db = OptionsDb::new()?;
        let iterative = matches!(req.preset, Preset::Iterative);
        for (name, value) in split_options(&preset_options(req.preset, req.rtol, req.symmetric)) {
            db.set(&name, &value)?;
        }
        if iterative && req.scale > 0.0 {
            let zero = format!("{:e}", SVD_ZERO_RELATIVE * req.scale);
            db.set("-mg_coarse_pc_svd_zero_sing", &zero)?;
            db.set("-mortar_mg_coarse_pc_svd_zero_sing", &zero)?;
        }
        if iterative {
            for (name, value) in split_options(
                "-mortar_ksp_type preonly -mortar_pc_type gamg -mortar_pc_gamg_sym_graph true \
                 -mortar_mg_levels_ksp_type chebyshev -mortar_mg_levels_pc_type jacobi \
                 -mortar_mg_coarse_pc_type svd",
            ) {
                db.set(&name, &value)?;
            }
        }
        // Repeatable runs: on 3 or more ranks GAMG's Galerkin products PᵀAP by the all-at-once
        // algorithm, whose off-process sums do not depend on message arrival (the default adds
        // the parts of two or more other ranks in arrival order: round-off from run to run).
        // It also needs less memory (L7 on 4 ranks: 256 vs 326 MB peak per rank) but was ~30 %
        // slower on 2 ranks, where one partner per rank keeps the default repeatable.
        // Sequential matrices do not have it (one rank: unchanged).
        if iterative && crate::par::world_size() >= ALLATONCE_MIN_RANKS {
            db.set("-matptap_via", "allatonce")?;
        }
        // solver.repeatable: the direct preset's MUMPS work (the plain path's factorisations,
        // the condensed path's Schur factorisation and solve phases) on rank 0 alone.
        if req.repeatable {
            db.set(ndfactor::ONE_PROCESS_OPTION, "")?;
        }
        for (name, value) in split_options(&reuse_options()) {
            db.set(&name, &value)?;
        }
        for (name, value) in split_options(req.case_options) {
            db.set(&name, &value)?;
            db.watch(&name);
        }
        db.insert_global()?;
        Self::resolved(db)
    }

    /// The kind and the MUMPS variant of the options in `db`: decided here alone.
    fn resolved(db: OptionsDb) -> petsc::Result<LinearSetup> {
        let pc_type = db.value("-pc_type")?.unwrap_or_default();
        let kind = SolverKind::of_pc(&pc_type);
        let package = db.value("-pc_factor_mat_solver_type")?;
        let own_order = kind.factorises()
            && package.as_deref() == Some("mumps")
            && !db.has("-mat_mumps_icntl_7")?;
        let one_process = db.has(ndfactor::ONE_PROCESS_OPTION)?;
        // read only where the project's instances factorise (elsewhere PETSc reads them)
        let controls = if own_order {
            mumps_controls(&db)?
        } else {
            Controls::default()
        };
        Ok(LinearSetup {
            options: Rc::new(db),
            kind,
            own_order,
            one_process,
            controls,
            near_null: None,
        })
    }

    /// [`LinearSetup::new`] for the case's `solver` section with the coordinates of AMG's
    /// rigid-body near-null space (only an iterative kind uses them). Collective.
    pub fn for_section(
        ctx: &Ctx,
        mesh: &Mesh,
        layout: &Layout,
        section: &SolverSection,
        symmetric: bool,
        scale: f64,
    ) -> petsc::Result<LinearSetup> {
        let mut setup = LinearSetup::new(&SolverRequest {
            preset: section.preset,
            rtol: section.rtol,
            symmetric,
            case_options: &section.petsc_options,
            repeatable: section.repeatable,
            scale,
        })?;
        if setup.kind == SolverKind::Iterative {
            let x = assembly::coordinate_vector(ctx.comm(), mesh, layout)?;
            setup.near_null = Some(x);
        }
        Ok(setup)
    }

    /// What the solves run. Local.
    pub fn kind(&self) -> SolverKind {
        self.kind
    }

    /// What the solves of `section` will run (its options resolved as [`Self::for_section`]
    /// resolves them), before any matrix exists. Local.
    pub fn kind_of(section: &SolverSection) -> petsc::Result<SolverKind> {
        let setup = LinearSetup::new(&SolverRequest {
            preset: section.preset,
            rtol: section.rtol,
            symmetric: true,
            case_options: &section.petsc_options,
            repeatable: section.repeatable,
            scale: 0.0,
        })?;
        Ok(setup.kind)
    }

    /// Runs `f` with the solver's options as PETSc's default (for a PETSc solver made
    /// elsewhere, SNES VI). Local.
    pub fn scoped<R>(&self, f: impl FnOnce() -> R) -> petsc::Result<R> {
        self.options.scoped(f)
    }

    /// A KSP on `a` configured from the options, with the near-null space where the kind
    /// uses it and, for a MUMPS factorisation, the project's nested-dissection order.
    /// Collective.
    pub fn solver(&self, comm: MPI_Comm, a: &mut Matrix) -> petsc::Result<LinearSolver> {
        if let Some(x) = &self.near_null {
            a.set_rigid_body_near_null_space(x)?;
        }
        let mut ksp = Ksp::new(comm, self.options.clone())?;
        ksp.set_operator(a)?;
        ksp.set_from_options()?;
        let pc_type = ksp.type_names()?.1;
        if SolverKind::of_pc(&pc_type) != self.kind {
            return Err(petsc::raised_error(format!(
                "the linear solver's PC is {pc_type:?}, its options resolved to {:?}",
                self.kind
            )));
        }
        if self.own_order {
            let symmetric = self.kind == SolverKind::DirectSymmetric;
            ndfactor::install_on(&ksp, comm, a, symmetric, self.one_process, &self.controls)?;
        }
        Ok(LinearSolver {
            ksp,
            kind: self.kind,
            one_process: self.one_process,
            controls: self.controls.clone(),
        })
    }
}

/// Whether PETSc takes the solver options of `section` (its preset resolved), before anything
/// is assembled: a KSP and the reuse solver on a matrix of one row per rank read them
/// (KSPSetFromOptions refuses e.g. an unknown type or an integer it cannot read), first the preset's
/// and the command line's (after `--`) alone, then with the case's `solver.petsc_options`. A
/// refusal is an input error of the case naming the command line or the key. Collective.
pub fn check_options(
    ctx: &Ctx,
    case_file: &std::path::Path,
    section: &SolverSection,
) -> Result<(), RunError> {
    options_taken(ctx, section, "", &|why| {
        InputError::new(
            case_file,
            format!("the PETSc options after -- (or in PETSC_OPTIONS) are refused by PETSc: {why}"),
        )
    })?;
    options_taken(ctx, section, &section.petsc_options, &|why| {
        InputError::new(
            case_file,
            format!(
                "{:?} is refused by PETSc: {why}",
                section.petsc_options.trim()
            ),
        )
        .with_key("solver.petsc_options")
    })
}

/// [`warnings::UNUSED_PETSC_OPTIONS`]: the options of the case's `solver.petsc_options` and of
/// the command line (after `--`, PETSC_OPTIONS) that nothing in the run read — misspelt, or
/// meant for a solver the run did not use (`-pc_gamg_threshold` on the direct preset,
/// `-mat_mumps_icntl_14` on the iterative one). PETSc itself takes such an option without a
/// word. An option counts as read where any rank read it. Call it once the run's solvers are
/// dropped. Collective.
pub fn unused_options_warning(
    ctx: &Ctx,
    section: &SolverSection,
) -> Result<Option<Warning>, RunError> {
    let case: Vec<String> = split_options(&section.petsc_options)
        .into_iter()
        .map(|(name, _)| name)
        .collect();
    let global = ctx.agree(optdb::global_names().map_err(RunError::Petsc))?;
    let local: Result<Vec<f64>, RunError> = case
        .iter()
        .map(|n| Ok(optdb::used_watched(n)))
        .chain(
            global
                .iter()
                .map(|n| optdb::used_global(n).map_err(RunError::Petsc)),
        )
        .map(|used| used.map(|u| f64::from(u8::from(u))))
        .collect();
    let used = ctx.sum_vec(&ctx.agree(local)?);
    let unread = |names: &[String], used: &[f64]| -> Vec<String> {
        let mut out: Vec<String> = names
            .iter()
            .zip(used)
            .filter(|(_, &u)| u == 0.0)
            .map(|(n, _)| n.clone())
            .collect();
        out.dedup();
        out
    };
    let (in_case, on_line) = (
        unread(&case, &used[..case.len()]),
        unread(&global, &used[case.len()..]),
    );
    if in_case.is_empty() && on_line.is_empty() {
        return Ok(None);
    }
    let mut parts = Vec::new();
    if !in_case.is_empty() {
        parts.push(format!("{} (solver.petsc_options)", in_case.join(" ")));
    }
    if !on_line.is_empty() {
        parts.push(format!(
            "{} (the command line or PETSC_OPTIONS)",
            on_line.join(" ")
        ));
    }
    Ok(Some(Warning {
        code: warnings::UNUSED_PETSC_OPTIONS,
        message: format!(
            "PETSc options that nothing in this run read: {}; misspelt, or meant for a solver \
             this run did not use (preset {})",
            parts.join(", "),
            section.preset.name()
        ),
        key: (!in_case.is_empty()).then(|| "solver.petsc_options".to_string()),
        pair: None,
        value: (in_case.len() + on_line.len()) as f64,
        threshold: 0.0,
        at: None,
        steps: Vec::new(),
    }))
}

/// One pass of [`check_options`] with `case_options` in place of the case's: `blame` makes the
/// input error of a refusal (from PETSc's message). Collective; every rank returns the same.
fn options_taken(
    ctx: &Ctx,
    section: &SolverSection,
    case_options: &str,
    blame: &dyn Fn(String) -> InputError,
) -> Result<(), RunError> {
    let setup = ctx.agree(
        LinearSetup::new(&SolverRequest {
            preset: section.preset,
            rtol: section.rtol,
            symmetric: true,
            case_options,
            repeatable: section.repeatable,
            scale: 0.0,
        })
        .map_err(|e| RunError::Input(blame(e.message))),
    )?;
    let a = Matrix::from_csr(ctx.comm(), 1, &[0, 1], &[ctx.rank as PInt], &[1.0])?;
    let mut ksp = Ksp::new(ctx.comm(), setup.options.clone())?;
    ksp.set_operator(&a)?;
    let mut reuse = Ksp::new(ctx.comm(), setup.options.clone())?;
    reuse.set_options_prefix(REUSE_PREFIX)?;
    reuse.set_operator(&a)?;
    let read = ksp
        .set_from_options()
        .and_then(|()| reuse.set_from_options());
    let local = read.map_err(|e| {
        if e.code > 0 {
            // PETSc's own refusal (our layer's errors have code -1)
            let detail = petsc::last_detail();
            RunError::Input(blame(if detail.is_empty() { e.message } else { detail }))
        } else {
            RunError::Petsc(e)
        }
    });
    // agreed while the objects live: their collective destroys follow on every rank
    ctx.agree(local)
}

/// A configured KSP on one operator, and what it runs.
pub struct LinearSolver {
    pub ksp: Ksp,
    kind: SolverKind,
    one_process: bool,
    controls: Controls,
}

impl LinearSolver {
    pub fn solve(&mut self, b: &Vector, x: &mut Vector) -> petsc::Result<SolveInfo> {
        self.ksp.solve(b, x)
    }

    /// What the solves run (decided by the set-up). Local.
    pub fn kind(&self) -> SolverKind {
        self.kind
    }

    /// A Krylov solver that applies this solver's preconditioner (its factorisation, shared,
    /// not copied), with the options prefix [`REUSE_PREFIX`]: the solver of the steps that
    /// reuse a factorisation. Collective.
    pub fn reuse_solver(&self, comm: MPI_Comm) -> petsc::Result<Ksp> {
        let mut ksp = Ksp::new(comm, self.ksp.options())?;
        ksp.set_options_prefix(REUSE_PREFIX)?;
        ksp.set_from_options()?;
        ksp.share_pc_of(&self.ksp)?;
        Ok(ksp)
    }
}

impl LinearSolver {
    /// The symbolic factorisation of `mat` (symmetric: its lower triangle) with the Schur
    /// complement `request` asks (the order read on rank 0, `root`;
    /// [`SchurFactor::analyse`]): MUMPS with this solver's settings (`solver.repeatable`: on
    /// rank 0 alone). Only for a kind that factorises. Collective.
    pub fn analyse_schur(
        &self,
        comm: MPI_Comm,
        mat: &Matrix,
        request: &SchurRequest,
        root: bool,
    ) -> petsc::Result<SymbolicSchur> {
        if !self.kind.factorises() {
            return Err(petsc::raised_error(
                "a Schur complement asked of a solver that does not factorise",
            ));
        }
        let f = SchurFactor::analyse(
            comm,
            mat,
            request,
            root,
            &Settings {
                one_process: self.one_process,
                controls: self.controls.clone(),
            },
        )?;
        Ok(SymbolicSchur(f))
    }
}

/// The symbolic factorisation with a Schur complement (the order and MUMPS' analysis):
/// [`SymbolicSchur::factorise`] makes the numeric one of it.
pub struct SymbolicSchur(SchurFactor);

impl SymbolicSchur {
    /// The analysis' estimate of the flops of eliminating the variables outside the Schur
    /// list (the same on every rank).
    pub fn flops(&self) -> f64 {
        self.0.flops()
    }

    /// The numeric factorisation, which fills the Schur complement. Collective.
    pub fn factorise(mut self) -> petsc::Result<NumericSchur> {
        self.0.factorise()?;
        Ok(NumericSchur(self.0))
    }
}

/// The numeric factorisation with a Schur complement: the complement itself (once) and the
/// solve phases on the rest.
pub struct NumericSchur(SchurFactor);

impl NumericSchur {
    /// The analysis' estimate of the factorisation's flops.
    pub fn flops(&self) -> f64 {
        self.0.flops()
    }

    /// The factorisation's statistics: the analysis' flops, the factor entries and the
    /// largest front (MUMPS' LLᵀ: `symmetric`), the same on every rank.
    pub fn stats(&self) -> FactorStats {
        self.0.stats()
    }

    /// The Schur complement S on rank 0 (column-major), empty elsewhere; handed over.
    pub fn take_schur(&mut self) -> Vec<f64> {
        self.0.take_schur()
    }

    /// `rhs` (on rank 0) condensed onto the Schur variables ([`SchurFactor::condense`]).
    /// Collective.
    pub fn condense(&mut self, rhs: &[f64]) -> petsc::Result<Vec<f64>> {
        self.0.condense(rhs)
    }

    /// The whole system's solution from the Schur variables' `x_s` ([`SchurFactor::expand`]).
    /// Collective.
    pub fn expand(&mut self, rhs: &[f64], x_s: &[f64]) -> petsc::Result<Vec<f64>> {
        self.0.expand(rhs, x_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_names_and_values() {
        let v = split_options("-ksp_type gmres -ksp_monitor -ksp_rtol 1e-8 -x -1.5");
        assert_eq!(
            v,
            vec![
                ("-ksp_type".into(), "gmres".into()),
                ("-ksp_monitor".into(), "".into()),
                ("-ksp_rtol".into(), "1e-8".into()),
                ("-x".into(), "-1.5".into()),
            ]
        );
    }

    #[test]
    fn kinds_of_pc_types() {
        assert_eq!(SolverKind::of_pc("cholesky"), SolverKind::DirectSymmetric);
        assert_eq!(SolverKind::of_pc("lu"), SolverKind::DirectUnsymmetric);
        assert_eq!(SolverKind::of_pc("gamg"), SolverKind::Iterative);
        assert!(SolverKind::DirectUnsymmetric.factorises());
        assert!(!SolverKind::Iterative.factorises());
    }
}
