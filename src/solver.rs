//! Linear solver set-up: the presets, the case file's `petsc_options` and the command line
//! (after `--`), in increasing priority, all through PETSc's options database; and the one
//! linear solve of a case without contact.

use crate::assembly::{self, System};
use crate::case::{Preset, SolverSection};
use crate::error::RunError;
use crate::mesh::Mesh;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::ndfactor::FactorRecord;
use crate::petsc::{self, options, Ksp, MPI_Comm, Matrix, SolveInfo, Vector};
use crate::say;
use std::time::Instant;

/// The options a preset stands for. `symmetric`: the systems are symmetric (linear elasticity
/// and frictionless contact, whose (3.29) is applied symmetrically), so MUMPS factors them by
/// Cholesky (LDLᵀ), about half the work and memory of LU; Tresca's (3.42) needs LU.
pub fn preset_options(preset: Preset, rtol: f64, symmetric: bool) -> String {
    match preset {
        // ICNTL(14) = 40: 40 % workspace slack over MUMPS' estimate (a 2-rank 3D Cholesky of
        // 396k unknowns failed once with the default; the estimate depends on the partition).
        Preset::Direct | Preset::Auto => format!(
            "-ksp_type preonly -pc_type {} -pc_factor_mat_solver_type mumps \
             -mat_mumps_icntl_14 40",
            if symmetric { "cholesky" } else { "lu" }
        ),
        // GMRES with right preconditioning (the true residual is tested) and smoothed
        // aggregation AMG with the rigid-body near-null space; the symmetrised graph keeps
        // aggregation valid for the unsymmetric reduced systems of friction (Tresca (3.42),
        // Coulomb (F7) in docs/friction.md, unsymmetric also in 2D; for Coulomb the hierarchy
        // is built on the system without its row mix, reduced.rs `write_unmixed`). On those
        // unsymmetric systems classical Gram–Schmidt loses the Krylov basis' orthogonality in
        // long solves and GMRES broke down (DIVERGED_BREAKDOWN: the 3D block held and pushed
        // into a sphere, a floating ball, the hemisphere's load steps; 2 ranks): it is refined
        // where needed, which also halved the iterations of the longest solves (block at
        // 112 890 unknowns: 367 → 185). The coarsest level is
        // solved by a pseudo-inverse (SVD): a hierarchy built on a matrix with a null space
        // (a floating body's free rigid modes, reduced.rs) has a singular coarse matrix, on
        // which LU breaks GMRES down (2D Hertz at ν = 0.4999); on a regular one it is LU's
        // solve.
        Preset::Iterative => format!(
            "-ksp_type gmres -ksp_pc_side right -ksp_gmres_restart 200 -ksp_rtol {rtol:e} \
             -ksp_max_it 2000 -pc_type gamg -pc_gamg_sym_graph true \
             -mg_levels_ksp_type chebyshev -mg_levels_pc_type jacobi -mg_coarse_pc_type svd{}",
            if symmetric {
                ""
            } else {
                " -ksp_gmres_cgs_refinement_type refine_ifneeded"
            }
        ),
    }
}

/// Under `solver.preset = "auto"`, 3D meshes from this many unknowns are solved by the
/// iterative preset: a 3D factorisation's fill grows as n^(4/3) and its flops as n², so GMRES
/// with AMG overtakes it early (bench/results/ordering.md, 2 ranks, the full floating ball in
/// contact: 12 063 unknowns 0.34 s direct, 0.29 s iterative; 17 856: 0.79 / 0.50 s; 126 801:
/// 31.5 / 6.0 s). Below it both take a fraction of a second and the direct solve is the more
/// robust (no Krylov tolerance, nearly incompressible materials). 2D meshes stay direct at
/// every size measured (2D Hertz, 561 112 unknowns: contact 4.0 s direct, 4.6 s iterative).
pub const AUTO_ITERATIVE_3D_DOFS: usize = 10_000;

/// The preset to use for `asked` on a mesh of dimension `dim` with `dofs` unknowns and
/// `friction` (Tresca or Coulomb), and why (for the log and summary.json). With friction the
/// auto preset is direct at every size: on a 3D block held and pushed into a sphere (Coulomb
/// μ = 0.3, 2 ranks) the iterative preset takes 14 Newton steps of GMRES + GAMG, the longest
/// 185 iterations, where the direct preset's condensed path needs one factorisation
/// (112 890 unknowns: 17–18 s against 5.4–5.7 s; docs/numbers.md, "Coulomb on the iterative
/// preset").
pub fn choose_preset(asked: Preset, dim: usize, dofs: usize, friction: bool) -> (Preset, String) {
    match asked {
        Preset::Auto if dim == 3 && friction => (
            Preset::Direct,
            format!("auto: 3D with friction, {dofs} unknowns"),
        ),
        Preset::Auto if dim == 3 && dofs >= AUTO_ITERATIVE_3D_DOFS => (
            Preset::Iterative,
            format!("auto: 3D, {dofs} unknowns >= {AUTO_ITERATIVE_3D_DOFS}"),
        ),
        Preset::Auto if dim == 3 => (
            Preset::Direct,
            format!("auto: 3D, {dofs} unknowns < {AUTO_ITERATIVE_3D_DOFS}"),
        ),
        Preset::Auto => (Preset::Direct, format!("auto: {dim}D")),
        p => (p, "asked for in the case".to_string()),
    }
}

/// The coarsest level's zero singular values, relative to the matrix' largest diagonal entry
/// (PETSc's absolute default, for a matrix of unit size).
pub const SVD_ZERO_RELATIVE: f64 = 1e-12;

/// The largest |diagonal entry| of `a` over all ranks: the size the iterative preset's
/// coarse-level threshold is measured against ([`configure`]). Collective.
pub fn matrix_scale(ctx: &Ctx, a: &Matrix) -> petsc::Result<f64> {
    let (lo, hi) = a.ownership_range()?;
    let mut d = Vector::new_mpi(ctx.comm(), hi - lo, 1)?;
    a.diagonal(&mut d)?;
    let local = d.read(|x| x.iter().fold(0.0_f64, |m, v| m.max(v.abs())))?;
    Ok(ctx.max_f64(local))
}

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

/// Puts preset and case options into the database without overriding the command line:
/// command line > case file `petsc_options` > preset.
///
/// `scale` is the largest |diagonal entry| of the stiffness matrix ([`matrix_scale`]). PETSc's
/// SVD treats singular values below an absolute 1e-12 as zero; the iterative preset's coarsest
/// level is singular when a floating body's free rigid modes are S's null space, and its null
/// singular values sit at round-off of the matrix' own size. The threshold is therefore
/// 1e-12 × `scale`: on a body with E = 1e9 (block3d, 2 ranks) the absolute default inverted
/// those round-off singular values and GMRES stalled at 1.4e-4 ‖b‖ (DIVERGED_BREAKDOWN)
/// where E = 2 converged in 18 iterations; the run is now the same in any unit system.
pub fn configure(
    preset: Preset,
    rtol: f64,
    symmetric: bool,
    (case_options, repeatable): (&str, bool),
    scale: f64,
) -> petsc::Result<()> {
    for (name, value) in split_options(case_options) {
        options::set_default(&name, &value)?;
    }
    for (name, value) in split_options(&preset_options(preset, rtol, symmetric)) {
        options::set_default(&name, &value)?;
    }
    if matches!(preset, Preset::Iterative) && scale > 0.0 {
        options::set_default(
            "-mg_coarse_pc_svd_zero_sing",
            &format!("{:e}", SVD_ZERO_RELATIVE * scale),
        )?;
    }
    // Issue 10 (repeatable runs): on 3 or more ranks GAMG's Galerkin products PᵀAP by the
    // all-at-once algorithm, whose off-process sums do not depend on message arrival (the
    // default adds the parts of two or more other ranks in arrival order: round-off from run
    // to run). It also needs less memory (L7 on 4 ranks: 256 vs 326 MB peak per rank) but
    // was ~30 % slower on 2 ranks, where one partner per rank keeps the default repeatable.
    // Sequential matrices do not have it (one rank: unchanged).
    if matches!(preset, Preset::Iterative) && crate::par::world_size() > 2 {
        options::set_default("-matptap_via", "allatonce")?;
    }
    // solver.repeatable: the direct preset's MUMPS work (the plain path's factorisations, the
    // condensed path's Schur factorisation and solve phases) on rank 0 alone.
    if repeatable {
        options::set_default(petsc::ndfactor::ONE_PROCESS_OPTION, "")?;
    }
    Ok(())
}

/// A configured KSP on one operator.
pub struct LinearSolver {
    pub ksp: Ksp,
}

impl LinearSolver {
    /// KSP on `a`, configured from the options database. `coords` (block size dim) provides the
    /// rigid-body near-null space for AMG.
    pub fn new(comm: MPI_Comm, a: &mut Matrix, coords: Option<&Vector>) -> petsc::Result<Self> {
        if let Some(x) = coords {
            a.set_rigid_body_near_null_space(x)?;
        }
        let mut ksp = Ksp::new(comm)?;
        ksp.set_operator(a)?;
        ksp.set_from_options()?;
        // The direct preset's factorisations: MUMPS with our nested-dissection order.
        petsc::ndfactor::install_if_mumps(&ksp, comm, a)?;
        Ok(LinearSolver { ksp })
    }

    pub fn solve(&mut self, b: &Vector, x: &mut Vector) -> petsc::Result<SolveInfo> {
        self.ksp.solve(b, x)
    }
}

/// Options prefix of the Krylov solver that reuses a factorisation (`-reuse_ksp_monitor`, ...).
pub const REUSE_PREFIX: &str = "reuse_";

/// GMRES restart of the reuse solver: no budget exceeds it, so GMRES never restarts.
pub const REUSE_RESTART: usize = 200;

/// Relative tolerance of the reuse solver on the preconditioned residual ‖M⁻¹(b − S x)‖ with
/// x₀ = 0: M = S_j (the factored matrix) is close to S, so this bounds the relative error of
/// x, far below Algorithm 1's tolerances (tests/reuse.rs: u agrees with the plain path to
/// 1e-10).
pub const REUSE_RTOL: f64 = 1e-13;

/// The reuse solver's defaults (the case's `petsc_options` and the command line, with the
/// prefix, override them): GMRES, left preconditioning (the preconditioned residual is
/// tested), classical Gram–Schmidt refined when needed.
pub fn reuse_options() -> String {
    let p = REUSE_PREFIX;
    format!(
        "-{p}ksp_type gmres -{p}ksp_pc_side left -{p}ksp_norm_type preconditioned \
         -{p}ksp_rtol {REUSE_RTOL:e} -{p}ksp_gmres_restart {REUSE_RESTART} \
         -{p}ksp_gmres_cgs_refinement_type refine_ifneeded"
    )
}

/// A Krylov solver that applies the preconditioner of `direct` (its factorisation, shared, not
/// copied): the solver of the steps that reuse a factorisation. Collective.
pub fn reuse_solver(comm: MPI_Comm, direct: &Ksp) -> petsc::Result<Ksp> {
    for (name, value) in split_options(&reuse_options()) {
        options::set_default(&name, &value)?;
    }
    let mut ksp = Ksp::new(comm)?;
    ksp.set_options_prefix(REUSE_PREFIX)?;
    ksp.set_from_options()?;
    ksp.share_pc_of(direct)?;
    Ok(ksp)
}

/// The coordinates for AMG's rigid-body near-null space: only the iterative preset uses them.
pub fn near_null_space_coordinates(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    preset: Preset,
) -> petsc::Result<Option<Vector>> {
    match preset {
        Preset::Iterative => Ok(Some(assembly::coordinate_vector(ctx.comm(), mesh, layout)?)),
        Preset::Direct | Preset::Auto => Ok(None),
    }
}

/// Everything about a linear run that the summary reports.
pub struct LinearReport {
    pub solve: SolveInfo,
    pub ksp_type: String,
    pub pc_type: String,
    /// The factorisation with our order (direct preset).
    pub factor: Option<FactorRecord>,
}

/// summary.json's "linear_solver" section of a linear run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LinearSolverSummary {
    pub preset: &'static str,
    pub ksp_type: String,
    pub pc_type: String,
    pub iterations: usize,
    pub converged_reason: String,
    pub converged_reason_code: i64,
    /// The direct preset's factorisation with the nested-dissection order: flops, largest
    /// front, factor entries, seconds of ordering, analysis and numeric factorisation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub factorisation: Option<FactorRecord>,
}

/// What a linear run reports in summary.json.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LinearSummary {
    pub linear_solver: LinearSolverSummary,
}

impl LinearReport {
    pub fn summary(&self, preset: Preset) -> LinearSummary {
        LinearSummary {
            linear_solver: LinearSolverSummary {
                preset: preset.name(),
                ksp_type: self.ksp_type.clone(),
                pc_type: self.pc_type.clone(),
                iterations: self.solve.iterations,
                converged_reason: self.solve.reason_name.clone(),
                converged_reason_code: self.solve.reason as i64,
                factorisation: self.factor,
            },
        }
    }
}

/// The progress line of a factorisation with our order.
pub fn log_factor(ctx: &Ctx, r: &FactorRecord) {
    say!(
        ctx,
        "factorisation: {:.3e} flops, largest front {}, {} factor entries; nested-dissection \
         order {:.3} s, analysis {:.3} s, numeric {:.3} s",
        r.stats.flops,
        r.stats.largest_front,
        r.stats.factor_entries,
        r.ordering_seconds,
        r.analysis_seconds,
        r.factorisation_seconds
    );
}

/// Configures the linear solver from the options database (preset < case < command line)
/// and solves A u = f once.
pub fn linear_solve(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    sys: &mut System,
    settings: &SolverSection,
) -> Result<(Vector, LinearReport), RunError> {
    let t = Instant::now();
    let scale = matrix_scale(ctx, &sys.a)?;
    configure(
        settings.preset,
        settings.rtol,
        true,
        (&settings.petsc_options, settings.repeatable),
        scale,
    )?;
    let coords = near_null_space_coordinates(ctx, mesh, layout, settings.preset)?;
    let mut ls = LinearSolver::new(ctx.comm(), &mut sys.a, coords.as_ref())?;
    let mut u = sys.b.duplicate()?;
    let info = ls.solve(&sys.b, &mut u)?;
    let secs = t.elapsed().as_secs_f64();
    let (ksp_type, pc_type) = ls.ksp.type_names()?;
    say!(
        ctx,
        "solve: {secs:.3} s, {ksp_type}/{pc_type}, {} iterations, {}",
        info.iterations,
        info.reason_name
    );
    let factor = petsc::ndfactor::record(&ls.ksp)?.map(|(r, _)| r);
    if let Some(r) = &factor {
        log_factor(ctx, r);
    }
    if !info.converged() {
        return Err(RunError::Failed(format!(
            "the linear solver did not converge: {} after {} iterations ({ksp_type}/{pc_type})",
            info.reason_name, info.iterations
        )));
    }
    Ok((
        u,
        LinearReport {
            solve: info,
            ksp_type,
            pc_type,
            factor,
        },
    ))
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
}
