//! The choice of the preset, the matrix scale the solver's set-up is measured against, the
//! linear solver's reports, and the one linear solve of a case without contact (the solver
//! itself: [`crate::linsolve`]).

use crate::assembly::System;
use crate::case::{Preset, SolverSection};
use crate::error::RunError;
use crate::linsolve::LinearSetup;
use crate::mesh::Mesh;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::ndfactor::FactorRecord;
use crate::petsc::{self, Matrix, SolveInfo, Vector};
use crate::say;
use crate::tuning::{AUTO_ITERATIVE_3D_DOFS, STIFF_SLAVE_RATIO};
use std::time::Instant;

/// What of a case's contact chooses the auto preset in 3D.
#[derive(Clone, Copy, Debug, Default)]
pub struct AutoContact {
    /// Tresca or Coulomb friction on some pair.
    pub friction: bool,
    /// `solver.method = "snesvi"`.
    pub snesvi: bool,
    /// The largest ratio of a body pair's slave-side to master-side contact modulus (0
    /// without body pairs).
    pub slave_over_master: f64,
}

/// The preset to use for `asked` on a mesh of dimension `dim` with `dofs` unknowns and the
/// case's `contact`, and why (for the log and summary.json). With friction the auto preset is
/// direct at every size: on a 3D block held and pushed into a sphere (Coulomb μ = 0.3,
/// 2 ranks) the iterative preset takes 14 Newton steps of GMRES + GAMG, the longest 185
/// iterations, where the direct preset's condensed path needs one factorisation (112 890
/// unknowns: 17–18 s against 5.4–5.7 s; docs/numbers.md, "Coulomb on the iterative preset").
/// Frictionless contact between bodies takes the single body's rule: its iterative solves
/// precondition in u (step_system/mortar_pc.rs; a quarter ball on a block at 85 374
/// unknowns, 2 ranks: 2.2–2.9 s against 6.4–7.0 s on the direct preset's condensed path,
/// docs/numbers.md, "3D body pairs on the iterative preset"). SNES VI takes the direct preset
/// at every size: GMRES + GAMG does not converge on its reduced systems (sub-matrices of the
/// system rotated into the contact frames, whose rigid modes are not the coordinates'; 2D
/// Hertz: 2 000 iterations in its first step; 3D: sub-matrices whose size is no multiple of
/// the block size). A body pair whose slave side is [`STIFF_SLAVE_RATIO`] or more times as
/// stiff as its master takes the direct preset too: the preconditioner in u corrects a held
/// slave node on the slave side (step_system/mortar_pc.rs), which costs more the stiffer that
/// side is (docs/numbers.md, "The slave side's stiffness on the iterative preset").
pub fn choose_preset(
    asked: Preset,
    dim: usize,
    dofs: usize,
    contact: AutoContact,
) -> (Preset, String) {
    match asked {
        Preset::Auto if contact.snesvi => (
            Preset::Direct,
            format!("auto: SNES VI, {dofs} unknowns (its reduced systems need a factorisation)"),
        ),
        Preset::Auto if dim == 3 && contact.friction => (
            Preset::Direct,
            format!("auto: 3D with friction, {dofs} unknowns"),
        ),
        Preset::Auto if dim == 3 && contact.slave_over_master >= STIFF_SLAVE_RATIO => (
            Preset::Direct,
            format!(
                "auto: 3D, a body pair's slave side {:.3e} × as stiff as its master",
                contact.slave_over_master
            ),
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

/// The largest |diagonal entry| of `a` over all ranks: the size the iterative preset's
/// coarse-level threshold is measured against ([`crate::linsolve::LinearSetup::new`]).
/// Collective.
pub fn matrix_scale(ctx: &Ctx, a: &Matrix) -> petsc::Result<f64> {
    let (lo, hi) = a.ownership_range()?;
    let mut d = Vector::new_mpi(ctx.comm(), hi - lo, 1)?;
    a.diagonal(&mut d)?;
    let local = d.read(|x| x.iter().fold(0.0_f64, |m, v| m.max(v.abs())))?;
    Ok(ctx.max_f64(local))
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

/// The linear solver's keys of a case with their values, for the diagnoses.
pub fn solver_keys(s: &SolverSection) -> String {
    let mut keys = vec![format!("'solver.preset' = \"{}\"", s.preset.name())];
    if s.preset == Preset::Iterative {
        keys.push(format!("'solver.rtol' = {:e}", s.rtol));
    }
    if !s.petsc_options.trim().is_empty() {
        keys.push(format!(
            "'solver.petsc_options' = {:?}",
            s.petsc_options.trim()
        ));
    }
    keys.join(", ")
}

/// Sets the linear solver up (preset < case < command line, [`LinearSetup`]) and solves
/// A u = f once; a solve that does not converge is an error naming the case file and its
/// solver keys.
pub fn linear_solve(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    sys: &mut System,
    settings: &SolverSection,
    file: &std::path::Path,
) -> Result<(Vector, LinearReport), RunError> {
    let t = Instant::now();
    let scale = matrix_scale(ctx, &sys.a)?;
    let setup = LinearSetup::for_section(ctx, mesh, layout, settings, true, scale)?;
    let mut ls = setup.solver(ctx.comm(), &mut sys.a)?;
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
            "the linear solver did not converge: {} after {} iterations ({ksp_type}/{pc_type}); \
             {}: it is set by {} (and PETSc options after --)",
            info.reason_name,
            info.iterations,
            file.display(),
            solver_keys(settings)
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
    fn snesvi_takes_the_direct_preset_at_every_size() {
        let snesvi = AutoContact {
            snesvi: true,
            ..AutoContact::default()
        };
        for (dim, dofs) in [(2, 1_000_000), (3, 10 * AUTO_ITERATIVE_3D_DOFS), (3, 100)] {
            assert_eq!(
                choose_preset(Preset::Auto, dim, dofs, snesvi).0,
                Preset::Direct
            );
        }
        let newton = AutoContact::default();
        let big = 10 * AUTO_ITERATIVE_3D_DOFS;
        assert_eq!(
            choose_preset(Preset::Auto, 3, big, newton).0,
            Preset::Iterative
        );
        // an explicit preset is kept (the case reader refuses SNES VI on the iterative one)
        assert_eq!(
            choose_preset(Preset::Iterative, 3, 100, snesvi).0,
            Preset::Iterative
        );
    }
}
