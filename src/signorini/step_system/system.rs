//! The step system (3.29) / (3.42) of one Newton step and its solver: the matrix S on A's
//! pattern, the right-hand side, the linear solver, and the constant rows of A at the contact
//! nodes and the pins.

use super::matrix_free::StepOperator;
use super::mortar_pc::{Held, HeldNodes, MortarParts, SHELL_NAME};
use super::reuse::{AmgReuser, AmgStep, ReuseCosts, ReuseStep, Reuser, SolveKind, StepSolve};
use super::rows::{
    direction_changes, spring_changes, ConstraintMap, Directions, NodeRows, Springs,
};
use super::write::{
    add_own_terms, left_factor, rewrites, rhs_by_operator, slip_block_changes, write_rows,
    write_unmixed, Rewrite, RowChange, RowWrites, ScaledSprings,
};
use crate::assembly::System;
use crate::case::Reuse;
use crate::linsolve::{LinearSetup, LinearSolver, SolverKind, SymbolicSchur};
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::mumps::SchurRequest;
use crate::petsc::{self, Matrix, PInt, SolveInfo, Vector};
use crate::signorini::active_set::{ActiveSet, Iterate};
use crate::signorini::boundary::ContactBoundary;
use crate::signorini::rigid::Pin;
use crate::tuning::INEXACT_REDUCTION;
use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;

/// The reduced system of one Newton step and its solver: the matrix S on A's pattern, the
/// right-hand side, the KSP, and the (constant) rows of A at the contact nodes and the pins.
pub struct ReducedSystem {
    s: Matrix,
    rhs: Vector,
    u: Vector,
    au: Vector,
    ls: LinearSolver,
    /// Shared with the rewrites of a step (which borrow them while the step's phases change
    /// the rest of the system).
    contact_rows: Rc<[NodeRows]>,
    pin_rows: Rc<[(usize, NodeRows)]>,
    /// This rank's rows of f.
    pub f_local: Vec<f64>,
    /// First global row of this rank.
    pub row_lo: usize,
    buf: Vec<f64>,
    /// Seconds spent writing the reduced systems, all steps.
    pub rows_seconds: f64,
    /// Seconds spent in λ recovery (MatMult + local work), all steps.
    pub lambda_seconds: f64,
    dim: usize,
    /// How the solver solves (known after the first solve).
    kind: Option<SolveKind>,
    /// The reuse path (direct preset, `solver.reuse` not "never").
    reuser: Option<Reuser>,
    /// The reuse path of the iterative preset (`solver.reuse` not "never").
    amg: Option<AmgReuser>,
    /// Force control: the last lift u¹ of each force-controlled pair, the next lift's start on
    /// the iterative preset (a lift depends on the set and F/|F| only, which change little
    /// from step to step).
    lifts: Vec<Option<Vector>>,
    /// With friction: the directions and this rank's slip blocks of the system written last,
    /// and how it differed from the one before ([`RowChange`]; `None` for the first).
    previous: Option<(Directions, ScaledSprings)>,
    change: Option<RowChange>,
    /// The iterative preset with Coulomb's (F7) rows: the matrix GAMG is built from, S without
    /// the row mix E (a scratch right-hand side with it), and whether this step uses it.
    amg_matrix: Option<(Matrix, Vector)>,
    unmixed: bool,
    /// Body pairs on the iterative preset: the held nodes that the preconditioner
    /// ([`super::mortar_pc::MortarPc`]) reads.
    held: Option<HeldNodes>,
    /// S is the operator of `held` (matrix_free.rs), not a matrix.
    matrix_free: Option<MatrixFree>,
}

/// What a matrix-free step system keeps: A in u, whose rows give the held rows' diagonals
/// (Qᵀ A Q may be an operator without rows), and a scratch vector of the prescribed values
/// for the right-hand sides, which come from products with A ([`rhs_by_operator`]).
struct MatrixFree {
    rows_in_u: Rc<Matrix>,
    ubar: Vector,
}

impl ReducedSystem {
    /// The symbolic part, made once: S with A's pattern, its KSP, the contact nodes' rows of A.
    /// Body pairs on the iterative preset (`mortar`: the run's parts of AMG in u): S is the
    /// operator L A P + D (matrix_free.rs), not stored, and the preconditioner AMG in u
    /// ([`MortarPc`](super::mortar_pc::MortarPc)) instead of AMG on Qᵀ A Q. Collective.
    pub fn new(
        ctx: &Ctx,
        sys: &System,
        b: &ContactBoundary,
        setup: &LinearSetup,
        dim: usize,
        mortar: Option<&MortarParts>,
    ) -> petsc::Result<ReducedSystem> {
        let held: Option<HeldNodes> = mortar.map(|_| Rc::new(RefCell::new(Vec::new())));
        // the assembled S instead, for the tests that compare both (a test-only limit)
        // the rows' diagonals (the held rows' s_k) from A in u where Qᵀ A Q may be an operator:
        // at a slave node the same (its column of Q is e_k); the right-hand sides then come
        // from products ([`rhs_by_operator`])
        let matrix_free = match mortar {
            Some(parts) if crate::fault::limit("MATRIX_FREE", 1) > 0 => Some(MatrixFree {
                rows_in_u: parts.a(),
                ubar: sys.b.duplicate()?,
            }),
            _ => None,
        };
        let rows_of = matrix_free.as_ref().map_or(&sys.a, |m| &*m.rows_in_u);
        let contact_rows = b
            .nodes
            .iter()
            .map(|k| NodeRows::read(rows_of, k.row, dim))
            .collect::<Result<Rc<[_]>, _>>()?;
        let f_local = sys.b.to_local_vec()?;
        let mut s = match held.as_ref().filter(|_| matrix_free.is_some()) {
            Some(rows) => {
                let op = StepOperator::new(sys.a.handle()?, &sys.b, rows.clone(), dim)?;
                Matrix::shell(ctx.comm(), f_local.len(), Box::new(op))?
            }
            None => sys.a.duplicate()?,
        };
        let mut ls = setup.solver(ctx.comm(), &mut s)?;
        if let (Some(parts), Some(rows)) = (mortar, &held) {
            let options = ls.ksp.options();
            let pc = parts.preconditioner(ctx.comm(), options, rows.clone(), dim)?;
            ls.ksp.set_shell_preconditioner(SHELL_NAME, Box::new(pc))?;
        }
        let (row_lo, _) = sys.a.ownership_range()?;
        Ok(ReducedSystem {
            s,
            rhs: sys.b.duplicate()?,
            u: sys.b.duplicate()?,
            au: sys.b.duplicate()?,
            ls,
            contact_rows,
            pin_rows: Rc::from(Vec::new()),
            f_local,
            row_lo,
            buf: Vec::new(),
            rows_seconds: 0.0,
            lambda_seconds: 0.0,
            dim,
            kind: None,
            reuser: None,
            amg: None,
            lifts: Vec::new(),
            previous: None,
            change: None,
            amg_matrix: None,
            unmixed: false,
            held,
            matrix_free,
        })
    }

    /// Enables the reuse of factorisations across steps (`solver.reuse`): only if the solver
    /// factorises (direct preset). With friction (`friction`: a Tresca threshold or Coulomb's
    /// fixed point) "auto" stays on the plain path with the direct preset: a node on its
    /// stick/slip threshold to round-off may flip between steps, and the ~1e-10 that a reuse
    /// solve leaves in Δu (GMRES to 1e-13 on the preconditioned residual) then hides that the
    /// iterate no longer moves, so the recurring-set stop (|Δu|/|u| < tol_u) cannot apply and the
    /// run ends as cycling (seen on 2 ranks: tests/coulomb.rs, warm start of the fixed point,
    /// whenever the timings made "auto" reuse). "always" still reuses. Collective.
    pub fn enable_reuse(&mut self, ctx: &Ctx, mode: Reuse, friction: bool) -> petsc::Result<()> {
        let factorises = self.ls.kind().factorises();
        self.amg = None;
        if mode == Reuse::Never {
            self.reuser = None;
            return Ok(());
        }
        if !factorises {
            // Krylov with a preconditioner that is set up per matrix (GAMG and the like).
            self.reuser = None;
            let (rtol, max_it) = self.ls.ksp.tolerances()?;
            self.amg = Some(AmgReuser {
                mode,
                rtol,
                max_it,
                fresh_rate: None,
                built: false,
                rebuild: false,
                rebuild_hierarchy: false,
                new_hierarchy: false,
                inexact: false,
                predictor: false,
                skip: false,
                null_space: false,
                prescribed: Vec::new(),
            });
            return Ok(());
        }
        if friction && mode == Reuse::Auto {
            self.reuser = None;
            return Ok(());
        }
        let ksp = self.ls.reuse_solver(ctx.comm())?;
        self.reuser = Some(Reuser {
            mode,
            ksp,
            factored: None,
            current: (Directions::new(), Springs::new()),
            costs: None,
        });
        Ok(())
    }

    /// Reads the rows of A of the owned pinned nodes (for their symmetric elimination).
    pub fn set_pins(&mut self, sys: &System, layout: &Layout, pins: &[Pin]) -> petsc::Result<()> {
        let dim = self.dim;
        let mut owned: Vec<usize> = pins
            .iter()
            .map(|&(v, _)| v)
            .filter(|&v| (layout.node_range().0..layout.node_range().1).contains(&v))
            .collect();
        owned.sort_unstable();
        owned.dedup();
        let rows_of = self.matrix_free.as_ref().map_or(&sys.a, |m| &*m.rows_in_u);
        self.pin_rows = owned
            .into_iter()
            .map(|v| Ok((v, NodeRows::read(rows_of, v * dim, dim)?)))
            .collect::<petsc::Result<Rc<[_]>>>()?;
        Ok(())
    }

    /// The numeric part of a step: S and its right-hand side for `set` and `pins` — (3.29)
    /// without friction, (3.42) with Tresca — applied symmetrically. Collective.
    pub fn write(
        &mut self,
        ctx: &Ctx,
        sys: &System,
        layout: &Layout,
        b: &ContactBoundary,
        set: &ActiveSet,
        pins: &[Pin],
    ) -> petsc::Result<()> {
        let t = Instant::now();
        let dim = self.dim;
        let cmap = ConstraintMap::gather(ctx, layout, b, set, pins, dim);
        let (contact_rows, pin_rows) = (self.contact_rows.clone(), self.pin_rows.clone());
        let writes = rewrites(
            (&contact_rows, &pin_rows, self.row_lo),
            layout,
            b,
            set,
            &cmap,
            dim,
        );
        self.record_changes(ctx, &cmap, &writes, set.tangential.is_some());
        self.share_rewritten(&writes);
        let rows = RowWrites {
            rows: &writes,
            cmap: &cmap,
        };
        self.write_values(ctx, sys, rows)?;
        self.rows_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// What the reuse path and the friction record need of the rows written: the directions
    /// and slip blocks of this step (`friction`: with tangential rows), and how they differ
    /// from the step before ([`RowChange`]). Collective with friction.
    fn record_changes(
        &mut self,
        ctx: &Ctx,
        cmap: &ConstraintMap,
        writes: &[Rewrite],
        friction: bool,
    ) {
        let dim = self.dim;
        let zero = [[0.0; 3]; 3];
        if let Some(re) = &mut self.reuser {
            let springs = writes
                .iter()
                .filter(|(_, me, _)| me.spring != zero)
                .map(|(_, me, lr)| (*lr, me.spring))
                .collect();
            re.current = (cmap.directions(), springs);
        }
        if !friction {
            return;
        }
        let dirs = cmap.directions();
        let springs: ScaledSprings = writes
            .iter()
            .filter(|(_, me, _)| me.spring != zero)
            .map(|(r, me, lr)| {
                let scale = (0..dim).map(|j| r.diag(j).abs()).sum::<f64>() / dim as f64;
                (*lr, (me.spring, scale))
            })
            .collect();
        self.change = match &self.previous {
            Some((d0, s0)) => {
                let (real, roundoff) = slip_block_changes(s0, &springs);
                let g = ctx.sum_vec(&[real as f64, roundoff as f64]);
                Some(RowChange {
                    directions: direction_changes(d0, &dirs),
                    slip_blocks: g[0].round() as usize,
                    slip_blocks_roundoff: g[1].round() as usize,
                })
            }
            None => None,
        };
        self.previous = Some((dirs, springs));
    }

    /// The rewritten nodes as the solvers read them: the preconditioner in u and the
    /// matrix-free operator ([`Held`]), the iterative reuse path's warm start (projector and
    /// prescribed part of every node with a held direction). Local.
    fn share_rewritten(&mut self, writes: &[Rewrite]) {
        let dim = self.dim;
        if let Some(held) = &self.held {
            *held.borrow_mut() = writes
                .iter()
                .map(|(r, me, lr)| {
                    let s = r.mean_diag(dim);
                    let proj = me.projector(dim);
                    let mut own = [[0.0; 3]; 3];
                    add_own_terms(&mut own, me, s, dim);
                    Held {
                        lr: *lr,
                        dirs: me.dirs.iter().map(|(c, _)| *c).collect(),
                        s,
                        proj,
                        left: left_factor(me, proj, dim),
                        own,
                    }
                })
                .collect();
        }
        if let Some(amg) = &mut self.amg {
            amg.prescribed = writes
                .iter()
                .filter(|(_, me, _)| !me.dirs.is_empty())
                .map(|(_, me, lr)| (*lr, me.projector(dim), me.known()))
                .collect();
        }
    }

    /// S (unless it is an operator) and the right-hand side of the rows `rows`, and with
    /// Coulomb's row mix on the iterative preset the matrix GAMG is built from. Collective.
    fn write_values(&mut self, ctx: &Ctx, sys: &System, rows: RowWrites) -> petsc::Result<()> {
        let dim = self.dim;
        let f_local = Some(&self.f_local[..]);
        if let Some(m) = self.matrix_free.as_mut() {
            let scratch = (&mut m.ubar, &mut self.au);
            rhs_by_operator(&sys.a, rows.rows, f_local, dim, scratch, &mut self.rhs)?;
        } else {
            self.s.copy_values_from(&sys.a)?;
            self.rhs.copy_from(&sys.b)?;
            write_rows(
                Some(&mut self.s),
                &mut self.rhs,
                rows,
                f_local,
                dim,
                &mut self.buf,
            )?;
        }
        // the same solver on every rank: the reduction only on the iterative preset, and not
        // for the preconditioner in u (which reads no matrix of the step)
        self.unmixed = !self.ls.kind().factorises()
            && self.matrix_free.is_none()
            && ctx.any(rows.rows.iter().any(|(_, me, _)| me.row_mix.is_some()));
        if self.unmixed {
            let made = &mut self.amg_matrix;
            write_unmixed(made, &self.s, &self.rhs, sys, rows, dim, &mut self.buf)?;
        }
        Ok(())
    }

    /// Solves the step's system. Without the reuse path: one KSPSolve (a numeric
    /// factorisation of the direct preset, or Krylov iterations). With it (`allow_reuse`:
    /// Coulomb's unsymmetric (F7) rows stay on the plain path): Krylov iterations on S_k
    /// preconditioned by the factorisation of the last factored S_j when [`Reuser::plan`]
    /// says so, and a numeric refactorisation of S_k otherwise or when they do not reach
    /// their tolerance within the budget. Collective.
    pub fn solve(&mut self, ctx: &Ctx, allow_reuse: bool) -> petsc::Result<StepSolve> {
        if self.amg.is_some() {
            return self.solve_amg(ctx);
        }
        if self.reuser.is_none() {
            return self.solve_plain();
        }
        let t = Instant::now();
        let dim = self.dim;
        let re = self.reuser.as_mut().expect("checked");
        // One Allreduce: the slip blocks changed on every rank, so that every rank takes the
        // same path (the costs are MUMPS' global counts, the same on every rank).
        let (dirs, springs) = match &re.factored {
            Some((d, sp)) => (
                direction_changes(d, &re.current.0),
                spring_changes(sp, &re.current.1),
            ),
            None => (0, 0),
        };
        let g = ctx.sum_vec(&[springs as f64]);
        let rank = 2 * dirs + (dim - 1) * (g[0].round() as usize);
        let weighed = match (&re.factored, re.costs) {
            (Some(_), Some(c)) => (c.factorisation + c.solve, c.iteration()),
            _ => (0.0, 0.0),
        };
        let mut step = ReuseStep {
            rank,
            budget: 0,
            krylov_iterations: 0,
            fallback: false,
            factorisation_seconds: 0.0,
            cost_factorisation: weighed.0,
            cost_iteration: weighed.1,
        };
        let plan = if allow_reuse { re.plan(rank) } else { None };
        if let Some(budget) = plan {
            re.ksp.set_operator(&self.s)?;
            re.ksp.set_reuse_preconditioner(true)?;
            re.ksp.set_max_iterations(budget)?;
            let info = re.ksp.solve(&self.rhs, &mut self.u)?;
            step.budget = budget;
            step.krylov_iterations = info.iterations;
            if info.converged() {
                let secs = t.elapsed().as_secs_f64();
                return Ok(StepSolve {
                    info,
                    kind: SolveKind::Reuse,
                    seconds: secs,
                    setup_seconds: None,
                    reuse: Some(step),
                    amg: None,
                });
            }
            step.fallback = true;
        }
        // A numeric factorisation of S_k (the shared PC sets up anew: its operator changed),
        // timed apart from its solve.
        self.ls.ksp.set_reuse_preconditioner(false)?;
        self.ls.ksp.set_operator(&self.s)?;
        let tf = Instant::now();
        self.ls.ksp.set_up()?;
        step.factorisation_seconds = tf.elapsed().as_secs_f64();
        let info = self.ls.solve(&self.rhs, &mut self.u)?;
        re.costs =
            petsc::ndfactor::record(&self.ls.ksp)?.and_then(|(r, _)| ReuseCosts::of(&r.stats));
        re.factored = Some(re.current.clone());
        Ok(StepSolve {
            info,
            kind: SolveKind::Factorisation,
            seconds: t.elapsed().as_secs_f64(),
            setup_seconds: None,
            reuse: Some(step),
            amg: None,
        })
    }

    /// The free rigid modes as the null space of S instead of pins (`Some(fields)`, this
    /// rank's rows of each mode; `None` detaches it): the fields are orthonormalised and
    /// attached to S, and Krylov solves then leave their components alone (the solution is
    /// one member of the family u + Σ α_j r_j; the Newton loop moves it to the pinned one).
    /// The iterative preset's use: a mode held by one pinned dof is a point constraint, whose
    /// stiffness falls with the mesh size, and GMRES + GAMG then needs more iterations per
    /// decade than on the same body held along a surface. Collective.
    pub fn set_free_null_space(
        &mut self,
        ctx: &Ctx,
        fields: Option<Vec<Vec<f64>>>,
    ) -> petsc::Result<()> {
        let mut basis: Vec<Vector> = Vec::new();
        for f in ctx.orthonormalised(fields.unwrap_or_default()) {
            let mut v = self.u.duplicate()?;
            v.write(|x| x.copy_from_slice(&f))?;
            basis.push(v);
        }
        if let Some(amg) = &mut self.amg {
            amg.null_space = !basis.is_empty();
        }
        self.s.set_null_space(ctx.comm(), &basis)
    }

    /// This rank's first global row and row count.
    pub fn local_rows(&self) -> (usize, usize) {
        (self.row_lo, self.f_local.len())
    }

    /// Adds `delta` (this rank's rows) to the last solution.
    pub fn add_to_solution(&mut self, delta: &[f64]) -> petsc::Result<()> {
        self.u
            .write(|x| x.iter_mut().zip(delta).for_each(|(a, b)| *a += b))
    }

    /// How the system written last differs from the one before (friction; `None` for the
    /// first and without friction).
    pub fn change(&self) -> Option<RowChange> {
        self.change
    }

    /// Krylov solves (no factorisation): the relative tolerance divided by `factor`, not below
    /// `floor`, for every solve from here; `Some((from, to))`, or `None` where the solver
    /// factorises or is at `floor` already. Local (the same on every rank).
    pub fn tighten_krylov(&mut self, factor: f64, floor: f64) -> petsc::Result<Option<(f64, f64)>> {
        if self.ls.kind().factorises() {
            return Ok(None);
        }
        let (rtol, _) = self.ls.ksp.tolerances()?;
        let from = self.amg.as_ref().map_or(rtol, |a| a.rtol);
        let to = (from / factor).max(floor);
        if to >= from {
            return Ok(None);
        }
        self.set_krylov_rtol(to)?;
        Ok(Some((from, to)))
    }

    /// Krylov solves: the relative tolerance of every solve from here (a solve's tightened
    /// tolerance given back at its end, [`ReducedSystem::tighten_krylov`]); nothing where the
    /// solver factorises. Local.
    pub fn set_krylov_rtol(&mut self, rtol: f64) -> petsc::Result<()> {
        if self.ls.kind().factorises() {
            return Ok(());
        }
        if let Some(a) = self.amg.as_mut() {
            a.rtol = rtol;
        }
        self.ls.ksp.set_rtol(rtol)
    }

    /// Whether the solver may make inexact steps (the iterative preset's reuse path).
    pub fn inexact_available(&self) -> bool {
        self.amg.is_some()
    }

    /// Lets the next solve stop at [`INEXACT_REDUCTION`] of its start's residual (`true`) or
    /// at the configured tolerance.
    pub fn set_inexact(&mut self, inexact: bool) {
        if let Some(amg) = &mut self.amg {
            amg.inexact = inexact;
        }
    }

    /// The half-space predictor's first solve (halfspace/): the next solve, inexact, stops
    /// at [`PREDICTOR_REDUCTION`](super::reuse::PREDICTOR_REDUCTION) of its start's residual, and
    /// ("auto") the solve after it sets the preconditioner up on its own matrix (the first matrix
    /// has no active node, a poor preconditioner for the predicted set's: 30 instead of 13
    /// iterations at 527 k unknowns, and an iterate whose set update flipped 115 edge nodes instead
    /// of 8).
    ///
    /// `skip`: no solve at all, u⁰ = 0 (a body that Dirichlet data leave free in a rigid mode:
    /// its pinned u⁰ is the load's deformation against arbitrary pins, and the model, whose free
    /// modes carry the load's resultant into contact, predicts as well from the gaps alone —
    /// measured on the full floating ball at 126 888 unknowns: the same 409 nodes, the same
    /// steps after, one GAMG setup fewer); the preconditioner is then set up by the next
    /// solve, on the predicted set's matrix.
    pub fn set_predictor_solve(&mut self, skip: bool) {
        if let Some(amg) = &mut self.amg {
            amg.predictor = true;
            amg.skip = skip;
        }
    }

    /// ‖rhs − S u‖₂ and ‖rhs‖₂. Collective.
    fn residual_norms(&mut self, ctx: &Ctx) -> petsc::Result<(f64, f64)> {
        self.s.mult(&self.u, &mut self.au)?;
        let (b, au) = (self.rhs.to_local_vec()?, self.au.to_local_vec()?);
        let (mut rr, mut bb) = (0.0, 0.0);
        for (x, y) in b.iter().zip(&au) {
            rr += (x - y) * (x - y);
            bb += x * x;
        }
        let g = ctx.sum_vec(&[rr, bb]);
        Ok((g[0].sqrt(), g[1].sqrt()))
    }

    /// The iterative preset's reuse path: the previous step's u as the start, its prescribed
    /// components set exactly (u_k ← P_k u_k + ū_k); the preconditioner set up in the first
    /// step and reused, set up anew when [`AmgReuser`]'s rule asks for it ("auto": the
    /// iterations per decade grew beyond [`REBUILD_GROWTH`](super::reuse::REBUILD_GROWTH) × those
    /// after the last setup) or when a solve on the reused one does not converge; the tolerance of
    /// an inexact step when the Newton loop says so. Every decision is taken from global quantities
    /// (iteration counts, norms), the same on every rank. Collective.
    fn solve_amg(&mut self, ctx: &Ctx) -> petsc::Result<StepSolve> {
        let t = Instant::now();
        let (r0, bnorm, zero_start) = self.warm_start(ctx)?;
        self.set_operators()?;
        let amg = self.amg.as_mut().expect("checked");
        let first = !amg.built;
        let skipped = std::mem::take(&mut amg.skip) && bnorm > 0.0;
        if (bnorm == 0.0 || skipped) && first {
            // No load yet (a body loaded only through the contact, the predictor's first
            // solve): u = 0 without a solve, and the preconditioner is set up by the first
            // solve that has a right-hand side, on its own matrix.
            amg.predictor = false;
            let info = SolveInfo {
                iterations: 0,
                reason: 2, // KSP_CONVERGED_RTOL_NORMAL's sign: converged
                reason_name: "zero right-hand side".into(),
            };
            let record = AmgStep {
                skipped,
                ..amg.record(false, 0.0, amg.rtol, 0.0, 0.0, false)
            };
            return Ok(StepSolve {
                info,
                kind: SolveKind::Krylov,
                seconds: t.elapsed().as_secs_f64(),
                setup_seconds: None,
                reuse: None,
                amg: Some(record),
            });
        }
        let setup = first || amg.rebuild;
        let predictor = std::mem::take(&mut amg.predictor);
        let rtol = amg.tolerance(predictor, r0, bnorm);
        let ksp = &mut self.ls.ksp;
        ksp.set_initial_guess_nonzero(!zero_start)?;
        ksp.set_rtol(rtol)?;
        ksp.set_max_iterations(amg.budget(setup, r0, rtol, bnorm))?;
        let (info, fallback, setup_seconds) = amg.krylov(ksp, &self.rhs, &mut self.u, setup)?;
        let r_end = ksp.residual_norm()?;
        let rate = amg.learn(predictor, setup, fallback, r0, r_end, info.iterations);
        let r0_rel = if bnorm > 0.0 { r0 / bnorm } else { 0.0 };
        let record = amg.record(
            setup || fallback,
            setup_seconds,
            rtol,
            r0_rel,
            rate,
            fallback,
        );
        Ok(StepSolve {
            info,
            kind: if setup || fallback {
                SolveKind::Krylov
            } else {
                SolveKind::Reuse
            },
            seconds: t.elapsed().as_secs_f64(),
            setup_seconds: None,
            reuse: None,
            amg: Some(record),
        })
    }

    /// The start of an iterative-preset solve: zero in the first solve, else the previous u
    /// with its prescribed components set exactly (u_k ← P_k u_k + ū_k) — or zero again if
    /// that start is worse than none. Returns (‖b − S u₀‖, ‖b‖, zero start). Collective.
    fn warm_start(&mut self, ctx: &Ctx) -> petsc::Result<(f64, f64, bool)> {
        let dim = self.dim;
        let amg = self.amg.as_ref().expect("checked");
        let first = !amg.built;
        if first {
            self.u.set_all(0.0)?;
        } else {
            let pres = &amg.prescribed;
            self.u.write(|x| {
                for (lr, p, known) in pres {
                    let mut v = [0.0; 3];
                    for a in 0..dim {
                        v[a] = (0..dim).map(|b| p[a][b] * x[lr + b]).sum::<f64>() + known[a];
                    }
                    x[*lr..*lr + dim].copy_from_slice(&v[..dim]);
                }
            })?;
        }
        let (r0, bnorm) = self.residual_norms(ctx)?;
        // A warm start worse than none (‖b − S u₀‖ ≥ ‖b‖: e.g. the rigid motion of a free body
        // that the previous step's pins allowed, measured on block2d at ν = 0.4999, where it
        // was > 1e5 ‖b‖ and GMRES stopped at once with DIVERGED_DTOL): start from zero.
        // The norms are global: every rank decides alike.
        if !first && r0 >= bnorm {
            self.u.set_all(0.0)?;
            return Ok((bnorm, bnorm, true));
        }
        Ok((r0, bnorm, first))
    }

    /// True when the solver factorises (its kind, decided once by [`LinearSetup`]). Local.
    pub fn factorises(&self) -> petsc::Result<bool> {
        Ok(self.kind().factorises())
    }

    /// What the steps' solver runs. Local.
    pub fn kind(&self) -> SolverKind {
        self.ls.kind()
    }

    /// The symbolic factorisation of the matrix written last with a Schur complement on
    /// `request.schur_rows` (in its order and node frames), by the steps' solver
    /// ([`LinearSolver::analyse_schur`]). Collective.
    pub fn analyse_schur(&self, ctx: &Ctx, request: &SchurRequest) -> petsc::Result<SymbolicSchur> {
        let root = ctx.rank == 0;
        self.ls.analyse_schur(ctx.comm(), &self.s, request, root)
    }

    /// The KSP and PC types of the steps' solver
    /// ([`Ksp::type_names`](crate::petsc::Ksp::type_names)). Local.
    pub fn solver_types(&self) -> petsc::Result<(String, String)> {
        self.ls.ksp.type_names()
    }

    /// The matrix written last (the condensed path hands K_p to MUMPS directly).
    pub fn matrix(&self) -> &Matrix {
        &self.s
    }

    /// This rank's rows of the right-hand side written last.
    pub fn rhs_local(&self) -> petsc::Result<Vec<f64>> {
        self.rhs.to_local_vec()
    }

    /// Entries of the last solution at global rows `idx` (any rank's), on every rank.
    /// Collective.
    pub fn solution_at(&self, idx: &[PInt]) -> petsc::Result<Vec<f64>> {
        self.u.gather(idx)
    }

    /// This rank's rows of the last solution.
    pub fn solution_local(&self) -> petsc::Result<Vec<f64>> {
        self.u.to_local_vec()
    }

    /// The lift of force control (force.rs): the step's system (3.29) with f = 0, no Dirichlet
    /// values and the values `b` and `set` prescribe (the active normals' u_n = −g_k), solved
    /// on the last solve's factorisation or preconditioner (S is unchanged since: no new
    /// factorisation or setup), to the preset's tolerance — on the iterative preset from the
    /// last lift of the same force-controlled pair (`slot`: its index among them), and in an
    /// inexact step to [`INEXACT_REDUCTION`] of its right-hand side. Returns this rank's rows
    /// of the solution u¹ and of A u¹. Not with the direct preset's reuse solver (GMRES on an
    /// earlier factorisation). Collective.
    #[allow(clippy::too_many_arguments)]
    pub fn solve_lift(
        &mut self,
        ctx: &Ctx,
        slot: usize,
        sys: &System,
        layout: &Layout,
        b: &ContactBoundary,
        set: &ActiveSet,
        pins: &[Pin],
    ) -> petsc::Result<(Vec<f64>, Vec<f64>)> {
        if self.reuser.is_some() {
            // the plain path's one reuse rule (signorini::plain_reuse) keeps this from happening
            return Err(petsc::PetscError {
                code: -1,
                message: "internal: the force-control lift on a reused factorisation (force \
                          control takes no reuse)"
                    .to_string(),
                location: format!("{}:{}", file!(), line!()),
            });
        }
        let t = Instant::now();
        let dim = self.dim;
        let cmap = ConstraintMap::gather(ctx, layout, b, set, pins, dim);
        let writes = rewrites(
            (&self.contact_rows, &self.pin_rows, self.row_lo),
            layout,
            b,
            set,
            &cmap,
            dim,
        );
        let mut rhs = self.rhs.duplicate()?;
        rhs.set_all(0.0)?;
        if let Some(m) = self.matrix_free.as_mut() {
            let scratch = (&mut m.ubar, &mut self.au);
            rhs_by_operator(&sys.a, &writes, None, dim, scratch, &mut rhs)?;
        } else {
            let rows = RowWrites {
                rows: &writes,
                cmap: &cmap,
            };
            write_rows(None, &mut rhs, rows, None, dim, &mut self.buf)?;
        }
        self.rows_seconds += t.elapsed().as_secs_f64();
        if self.lifts.len() <= slot {
            self.lifts.resize_with(slot + 1, || None);
        }
        let warm = self.amg.is_some() && self.lifts[slot].is_some();
        let mut x = match self.lifts[slot].take() {
            Some(v) if warm => v,
            _ => {
                let mut v = self.u.duplicate()?;
                v.set_all(0.0)?;
                v
            }
        };
        if let Some(amg) = &self.amg {
            // An inexact step's lift is inexact alike, to INEXACT_REDUCTION of its right-hand
            // side (not of its start's residual: the lift's error enters u times the step's
            // change of δ only, so the last lift's start is kept to that accuracy for free).
            let rtol = if amg.inexact {
                INEXACT_REDUCTION.max(amg.rtol)
            } else {
                amg.rtol
            };
            let ksp = &mut self.ls.ksp;
            ksp.set_initial_guess_nonzero(warm)?;
            ksp.set_rtol(rtol)?;
            ksp.set_max_iterations(amg.max_it)?;
            ksp.set_reuse_preconditioner(true)?;
        }
        let info = self.ls.solve(&rhs, &mut x)?;
        if !info.converged() {
            return Err(petsc::PetscError {
                code: -1,
                message: format!(
                    "the force-control lift did not converge ({} iterations)",
                    info.iterations
                ),
                location: format!("{}:{}", file!(), line!()),
            });
        }
        sys.a.mult(&x, &mut self.au)?;
        let out = (x.to_local_vec()?, self.au.to_local_vec()?);
        self.lifts[slot] = Some(x);
        Ok(out)
    }

    /// Replaces this rank's rows of the solution (what `recover` and `solution` read).
    pub fn set_solution_local(&mut self, v: &[f64]) -> petsc::Result<()> {
        self.u.write(|x| x.copy_from_slice(v))
    }

    /// S as the operator, and as the preconditioner's matrix unless this step has one of its
    /// own ([`write_unmixed`]).
    fn set_operators(&mut self) -> petsc::Result<()> {
        match (&self.amg_matrix, self.unmixed) {
            (Some((p, _)), true) => self.ls.ksp.set_operators(&self.s, p),
            _ => self.ls.ksp.set_operator(&self.s),
        }
    }

    /// One KSPSolve on the step's matrix (the plain path).
    fn solve_plain(&mut self) -> petsc::Result<StepSolve> {
        let t = Instant::now();
        self.set_operators()?;
        // the set-up (a numeric factorisation on the direct preset) timed apart from the solve
        // that follows it; KSPSolve then finds the KSP set up
        self.ls.ksp.set_up()?;
        let setup_seconds = t.elapsed().as_secs_f64();
        let info = self.ls.solve(&self.rhs, &mut self.u)?;
        let kind = match self.kind {
            Some(k) => k,
            None => {
                // The solver's type does not change between steps: asked once.
                let k = if self.ls.kind().factorises() {
                    SolveKind::Factorisation
                } else {
                    SolveKind::Krylov
                };
                self.kind = Some(k);
                k
            }
        };
        Ok(StepSolve {
            info,
            kind,
            seconds: t.elapsed().as_secs_f64(),
            setup_seconds: Some(setup_seconds),
            reuse: None,
            amg: None,
        })
    }

    /// (3.28) for the last solution: λ = f − A u on the contact rows (one MatMult), into `it`.
    /// Collective.
    pub fn recover(
        &mut self,
        sys: &System,
        b: &ContactBoundary,
        set: &ActiveSet,
        it: &mut Iterate,
    ) -> petsc::Result<()> {
        let t = Instant::now();
        sys.a.mult(&self.u, &mut self.au)?;
        let u_local = self.u.to_local_vec()?;
        let au_local = self.au.to_local_vec()?;
        it.recover(u_local, au_local, &self.f_local, b, set, self.dim);
        self.lambda_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// A copy of the last solution (the system stays for further solves: the fixed point).
    pub fn solution(&self) -> petsc::Result<Vector> {
        let mut u = self.u.duplicate()?;
        u.copy_from(&self.u)?;
        Ok(u)
    }
}
