//! What a contact run keeps from one solve to the next ([`Session`]): created once per run by
//! the load stepping, handed to every solve as `&mut Session`.

use crate::case::{CoulombAlgorithm, SolverSection};
use crate::error::RunError;
use crate::linsolve::{LinearSetup, SolverKind};
use crate::mesh::Mesh;
use crate::mortar::Basis;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::Matrix;
use crate::setup::ContactSettings;
use crate::signorini::halfspace::Located;
use crate::signorini::kept::KeptFactor;
use crate::signorini::step_system::mortar_pc::MortarParts;

/// The run's lasting state: the linear solver's set-up, the factorisation a condensed solve
/// keeps for the next load step (with its node order) and the contact zone the half-space
/// model located in the solve under way.
pub struct Session {
    /// Built once: A is assembled once and only its right-hand side changes between load
    /// steps, so its scale (the iterative preset's coarse threshold) is the same in every
    /// step, and so are the law and with it the symmetry of the systems.
    setup: LinearSetup,
    /// The previous load step's condensed factorisation on the way into a solve, this
    /// solve's on the way out.
    pub(crate) kept: KeptFactor,
    /// The contact zone the half-space model located in this solve (schur/round.rs
    /// `locate`), once computed: a second condensed attempt (Coulomb's normal dofs alone)
    /// takes it again. Cleared at the start of every solve (the zone of another load).
    pub(crate) located: Option<Located>,
    /// Body pairs on the iterative preset: what their preconditioner keeps (AMG in u).
    pub(crate) mortar_pc: Option<MortarParts>,
}

impl Session {
    /// The session of a contact run on stiffness `a` (assembled once for the run; Qᵀ A Q with
    /// body pairs, `mortar` their change of basis): the linear solver set up from the case's
    /// `solver` section ([`LinearSetup::for_section`]), nothing kept yet. Collective.
    pub fn new(
        ctx: &Ctx,
        mesh: &Mesh,
        layout: &Layout,
        section: &SolverSection,
        settings: &ContactSettings,
        a: &Matrix,
        mortar: Option<&Basis>,
    ) -> Result<Session, RunError> {
        let setup = LinearSetup::for_section(
            ctx,
            mesh,
            layout,
            section,
            symmetric_rows(settings, mesh.dim),
            // body pairs: A's own scale (Qᵀ A Q may be an operator without entries; the
            // iterative preset's AMG works on A)
            crate::solver::matrix_scale(ctx, mortar.map_or(a, |m| m.a()))?,
        )?;
        // body pairs on the iterative preset: AMG on A in u, the held rows projected
        // (step_system/mortar_pc.rs)
        let mortar_pc = match (mortar, setup.kind() == SolverKind::Iterative) {
            (Some(basis), true) => {
                let (a, q_inv) = basis.shared();
                let coords = crate::assembly::coordinate_vector(ctx.comm(), mesh, layout)?;
                Some(MortarParts::new((a, q_inv), coords)?)
            }
            _ => None,
        };
        Ok(Session {
            setup,
            kept: KeptFactor::default(),
            located: None,
            mortar_pc,
        })
    }

    /// The linear solver's set-up of the run.
    pub fn setup(&self) -> &LinearSetup {
        &self.setup
    }

    /// Drops the factorisation kept for a next load step (none follows).
    pub fn release_factor(&mut self) {
        self.kept.clear();
    }
}

/// The reduced systems of the case are symmetric: frictionless (3.29) and, in 2D, Tresca's
/// (3.42) (also the fixed point's inner Tresca solves), both applied symmetrically — a 2D slip
/// row adds the scalar spring L̃ ≥ 0 of (3.39b) to its node's own tangential diagonal. Not
/// Coulomb's generalised Newton (its row mix (F7)) nor 3D Tresca (a 2 × 2 L̃ that is not
/// symmetric). The direct preset then factorises by LDLᵀ instead of LU.
fn symmetric_rows(settings: &ContactSettings, dim: usize) -> bool {
    match settings.coulomb {
        Some((_, CoulombAlgorithm::Newton)) => false,
        _ => !settings.friction() || dim == 2,
    }
}
