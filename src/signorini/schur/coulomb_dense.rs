//! Coulomb's generalised Newton on the candidates' dense system: the unknowns (normal and
//! tangential contact values, the free modes' amplitudes), the rows of each node's state, the
//! equilibrated dense solve and the iteration with its stopping rules.

use super::coulomb_run::{DenseCoulomb, DenseStep};
use crate::case::NewtonInit;
use crate::contact::{normal_active, CoulombRow};
use crate::petsc::lapack::DenseLu;
use crate::signorini::active_set::{
    threshold_scale_local, ActiveSet, Iterate, Law, SetUpdate, FIXED_POINT_SLACK,
};
use crate::signorini::boundary::{ContactBoundary, NodeResult};
use crate::signorini::dense::{coarsen, CMatrix};
use crate::signorini::law::coulomb::{
    residual_floor, COULOMB_RESIDUAL_STALL, COULOMB_RESIDUAL_TOL, COULOMB_RESIDUAL_ZERO,
};
use crate::signorini::plain_path::stalled;
use nalgebra::{DMatrix, DVector};
use std::time::Instant;

/// One step's dense system (module note), its rows equilibrated.
struct System {
    /// The rows as columns (row ri of the system is column ri).
    a: DMatrix<f64>,
    rhs: DVector<f64>,
    /// The first unknowns: the active nodes' λ (the primal form: the free displacements' dofs);
    /// α follow.
    cols: Vec<Unknown>,
    /// The primal form ([`Stiff`]): u at every candidate dof, NaN where it is an unknown;
    /// `None`: the dual form.
    known: Option<Vec<f64>>,
    /// The primal form: the dofs whose λ is 0 by their rows (inactive nodes: λ_n, and λ_τ
    /// without friction).
    zero: Vec<usize>,
    /// The dual form: the λ that the rows give as values (Tresca's settled slip), no unknowns.
    given: Vec<(usize, f64)>,
    /// The last unknowns are `alpha_scale` × α: the dual form's are c α, a force as its λ are,
    /// so that each row has one unit and [`equilibrate`] scales it alike in every unit system
    /// (with α itself, a row's largest entry was C's (a length per force) or G's (none) as the
    /// stresses' unit decided: a force-controlled Coulomb block scaled by 2^26 took 5 dense
    /// steps instead of 6 and ended 1.4e-10 of max |u| away); 1 in the primal form.
    alpha_scale: f64,
}

/// S itself next to C = S⁻¹ (rank 0; frictionless.rs `Compliance::stiffness`): λ = r − S (u − G α)
/// on the candidates' dofs, with S G and Gᵀ S G. A step's system in the primal form has the
/// displacements the set leaves free as unknowns — every dof of an inactive candidate, the
/// tangential dofs of a slipping one — with the rows λ = 0 and the slip rows (F6) in λ
/// (module note), and the balance Gᵀ λ = φ: where the zone fills the candidates that is far
/// fewer unknowns than the dual form's λ of every active node.
pub(super) struct Stiff<'a> {
    pub(super) s: CMatrix<'a>,
    pub(super) r: &'a [f64],
    pub(super) sg: DMatrix<f64>,
    pub(super) gsg: DMatrix<f64>,
}

/// One λ unknown of the dense system: λ at the candidates' dof `dof`, and, where a 2D slip row
/// ties the node's λ_τ to its λ_n (`tied`: λ_τ's dof and factor), λ_τ with it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Unknown {
    dof: usize,
    tied: Option<(usize, f64)>,
}

impl Unknown {
    /// Σ over the λ dofs this unknown stands for of its factor times `at(dof)`.
    fn of(&self, at: impl Fn(usize) -> f64) -> f64 {
        at(self.dof) + self.tied.map_or(0.0, |(t, f)| f * at(t))
    }
}

/// The tie λ_τ = −q λ_n of a 2D slip row without spring and right-hand side (the settled row of
/// `active_set::settled`, −λ_τ' − q λ_n' = 0): λ_τ's dof and −q. Such a node's λ_τ is no unknown
/// of the dense system, and its tangential row no row (exact).
fn tie(row: CoulombRow<2>, dof_n: usize, d: usize) -> Option<(usize, f64)> {
    match row {
        CoulombRow::Slip { l, q, r }
            if d == 2 && l == [[0.0; 2]; 2] && r == [0.0; 2] && q[0] != 0.0 =>
        {
            Some((dof_n + 1, -q[0]))
        }
        _ => None,
    }
}

/// A slip row that makes λ_τ = 0 (no friction: an inactive node under Coulomb, a node without
/// a Tresca threshold). Pure.
fn frictionless_row(row: CoulombRow<2>) -> bool {
    matches!(row, CoulombRow::Slip { l, q, r }
        if l == [[0.0; 2]; 2] && q == [0.0; 2] && r == [0.0; 2])
}

/// The value λ_τ = −r̃ that a slip row without spring and coupling gives (Tresca's settled slip
/// row λ_τ' = b_k ν, 2D), or `None`. Pure.
fn given(row: CoulombRow<2>) -> Option<f64> {
    match row {
        CoulombRow::Slip { l, q, r }
            if l == [[0.0; 2]; 2] && q == [0.0; 2] && r[0] != 0.0 && r[1] == 0.0 =>
        {
            Some(-r[0])
        }
        _ => None,
    }
}

/// Each row (a column of `a`) and its right-hand side scaled to max |row| = 1: the rows are in
/// displacement (normal, stick) and force (slip, balance) units, the columns in force (λ) and
/// displacement (α) units (measured on the Hertz disk at 171 602 unknowns: the residual floor
/// of the dense steps 10 × lower).
fn equilibrate(a: &mut DMatrix<f64>, rhs: &mut DVector<f64>) {
    for (mut row, b) in a.column_iter_mut().zip(rhs.iter_mut()) {
        let s = row.iter().fold(0.0_f64, |x, v| x.max(v.abs()));
        if s > 0.0 {
            row.scale_mut(1.0 / s);
            *b /= s;
        }
    }
}

/// max |R (M x − b)| of a system at x, its rows R-equilibrated as built.
fn residual_at(sys: &System, x: &[f64]) -> f64 {
    sys.a
        .column_iter()
        .zip(sys.rhs.iter())
        .map(|(row, b)| (row.iter().zip(x).map(|(r, xi)| r * xi).sum::<f64>() - b).abs())
        .fold(0.0, f64::max)
}

/// The system's solution by LU (LAPACK), its columns equilibrated. `None`: singular (e.g. a
/// free mode that the set does not hold).
fn solve_system(sys: &System) -> Option<Vec<f64>> {
    let n = sys.rhs.len();
    let mut cmax = vec![0.0_f64; n];
    for row in sys.a.column_iter() {
        for (c, v) in cmax.iter_mut().zip(row.iter()) {
            *c = c.max(v.abs());
        }
    }
    let cs: Vec<f64> = cmax
        .iter()
        .map(|&s| if s > 0.0 { 1.0 / s } else { 1.0 })
        .collect();
    // the system column-major (the transpose of the rows-as-columns), columns scaled
    let mut at = sys.a.transpose();
    for (mut col, c) in at.column_iter_mut().zip(&cs) {
        col.scale_mut(*c);
    }
    let mut x = DenseLu::factor_owned(n, at.data.into())?.solve(&sys.rhs);
    for (xj, cj) in x.iter_mut().zip(&cs) {
        *xj *= cj;
    }
    if x.iter().any(|v| !v.is_finite()) {
        return None;
    }
    Some(x.as_slice().to_vec())
}

/// A step's system solved, or given back where it is singular (`None`: there was none).
enum Attempt {
    Solved(Vec<f64>, System),
    Singular(Option<System>),
}

/// `sys` solved by [`solve_system`].
fn attempt(sys: Option<System>) -> Attempt {
    let Some(sk) = sys else {
        return Attempt::Singular(None);
    };
    match solve_system(&sk) {
        Some(x) => Attempt::Solved(x, sk),
        None => Attempt::Singular(Some(sk)),
    }
}

/// A solved step, counted in `w.primal` where its system is in the primal form.
fn primal_counted(w: &mut Walk, done: (Vec<f64>, System)) -> (Vec<f64>, System) {
    w.primal += usize::from(done.1.known.is_some());
    done
}

/// The system `sys` solved with its free modes' amplitudes α fixed at `alpha` (its last
/// columns moved to the right-hand side, its balance rows dropped); the solution with α
/// appended. `None`: singular still.
fn solve_pinned(sys: &System, alpha: &[f64]) -> Option<Vec<f64>> {
    let m = sys.rhs.len() - alpha.len();
    let a = sys.a.view((0, 0), (m, m)).into_owned();
    let scaled: Vec<f64> = alpha.iter().map(|al| al * sys.alpha_scale).collect();
    let rhs = DVector::from_fn(m, |i, _| {
        sys.rhs[i]
            - (scaled.iter().enumerate())
                .map(|(cz, al)| sys.a[(m + cz, i)] * al)
                .sum::<f64>()
    });
    let pinned = System {
        a,
        rhs,
        cols: Vec::new(),
        known: None,
        zero: Vec::new(),
        given: Vec::new(),
        alpha_scale: 1.0,
    };
    let mut x = solve_system(&pinned)?;
    x.extend_from_slice(&scaled);
    Some(x)
}

/// The system `next` holds at `x` to the round-off of the solve that gave x (`own`: its
/// residual in its own system, [`residual_at`]): within FIXED_POINT_SLACK × max(own, ε |b|∞).
/// Measured on the Hertz disks of 42 k–345 k unknowns: at a fixed point the next residual
/// equalled `own` (1e-18–3e-16, |b|∞ = 1.5e-2), elsewhere it was 1.5e-7–1.3e-5. Pure.
fn fixed_point(next: &System, x: &[f64], own: f64) -> bool {
    let b = next.rhs.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    residual_at(next, x) <= FIXED_POINT_SLACK * own.max(f64::EPSILON * b)
}

/// An accepted iterate of the dense iteration: its system and u, λ and α, the steps taken
/// (`primal`: of them in the primal form), whether the stall rule accepted it, and the step
/// from which the (F5) rows ran.
struct Accepted<'s> {
    sys: &'s System,
    u: &'s [f64],
    lam: Vec<f64>,
    alpha: Vec<f64>,
    steps: Vec<DenseStep>,
    primal: usize,
    stalled: bool,
    f5_from: usize,
}

/// What the dense Coulomb iteration carries from step to step: the set and the records of the
/// last iterate, the residual of the last step that changed no state, the steps taken
/// (`primal`: of them in the primal form), the set the last iterate was solved on (for a step
/// whose settled rows leave the system singular), whether slip rows are settled and the step
/// from which the (F5) rows ran.
struct Walk {
    set: ActiveSet,
    it: Iterate,
    last_still: Option<f64>,
    steps: Vec<DenseStep>,
    primal: usize,
    before: Option<ActiveSet>,
    settle: bool,
    f5_from: usize,
    /// α of the last iterate (the free modes' amplitudes; 0 at the start).
    alpha: Vec<f64>,
    /// The last step was taken with α pinned ([`solve_pinned`]).
    pinned: bool,
    /// Pinned steps in a row that changed no state ([`STUCK_PINNED`]).
    pinned_still: usize,
}

/// Pinned steps in a row that change no state end the dense iteration: the next step is the
/// same singular system with the same α, so the iteration would repeat that iterate to its
/// step limit (a start in which a floating body touches nothing, e.g. the upper of two disks
/// stacked on a block whose frictionless estimate hung it on its pins: 100 dense steps on each
/// coarse level and on the candidates before the plain path: docs/friction.md).
const STUCK_PINNED: usize = 2;

/// A step's verdict on its iterate: accepted (`stalled`: by the stall rule, above the
/// residual tolerance), or the next step on the given system (`None`: singular).
enum Judgement {
    Accept { stalled: bool },
    Continue(Option<System>),
}

/// The primal form's unknowns ([`Stiff`]): u at every candidate dof (NaN where it is an
/// unknown), the unknowns, and the position of each node's first unknown.
struct PrimalUnknowns {
    known: Vec<f64>,
    cols: Vec<Unknown>,
    at: Vec<usize>,
    zero: Vec<usize>,
}

/// What the primal form's rows are built from: S with S G and Gᵀ S G, the unknowns (`m` of
/// them, then `mz` amplitudes α) and λ at u_F = 0, α = 0 (`base`); `s_row`: room for one row
/// of S, the system's for all its rows.
struct PrimalRows<'s, 't> {
    st: &'s Stiff<'t>,
    cols: &'s [Unknown],
    base: Vec<f64>,
    m: usize,
    mz: usize,
    s_row: Vec<f64>,
}

impl PrimalRows<'_, '_> {
    /// Row `ri` += Σ_t coef_t λ(dof_t); returns its constant part Σ_t coef_t base(dof_t)
    /// (S symmetric: S's row `dof` is its column).
    fn put_lam(&mut self, a: &mut DMatrix<f64>, ri: usize, terms: &[(usize, f64)]) -> f64 {
        let (st, m) = (self.st, self.m);
        let mut row = a.column_mut(ri);
        let s_row = &mut self.s_row;
        for &(dof, f) in terms {
            st.s.column_into(dof, s_row);
            for (jc, u) in self.cols.iter().enumerate() {
                row[jc] -= f * s_row[u.dof];
            }
            for cz in 0..self.mz {
                row[m + cz] += f * st.sg[(dof, cz)];
            }
        }
        terms
            .iter()
            .map(|&(dof, f)| f * self.base[dof])
            .sum::<f64>()
    }
}

/// λ at u_F = 0, α = 0: r − S u_K (`known`: u_K, NaN at the unknowns).
fn primal_base(st: &Stiff, known: &[f64]) -> Vec<f64> {
    let u_k = known
        .iter()
        .map(|&uj| if uj.is_finite() { uj } else { 0.0 });
    let su = st.s.times(&DVector::from_iterator(known.len(), u_k));
    st.r.iter().zip(su.iter()).map(|(r, s)| r - s).collect()
}

/// |u − u_prev| / |u| (0 for u = 0). Pure.
fn relative_change(u: &[f64], u_prev: &[f64]) -> f64 {
    let du: f64 = u.iter().zip(u_prev).map(|(a, b)| (a - b).powi(2)).sum();
    let uu: f64 = u.iter().map(|a| a * a).sum();
    if uu > 0.0 {
        (du / uu).sqrt()
    } else {
        0.0
    }
}

/// The generalised Newton of docs/friction.md on the candidates' dense system (module note).
pub(super) struct DenseIteration<'a> {
    pub(super) dim: usize,
    /// C, symmetric: its column `dof` is its row `dof`, read for the rows of the dense system.
    pub(super) cmat: CMatrix<'a>,
    pub(super) d0: &'a [f64],
    /// The free modes' parts at the candidates (d rows per node, frame components; mz columns)
    /// and the load in them, φ = zᵀ Rᵀ f: u = d₀ − C λ + G α, Gᵀ λ = φ.
    pub(super) g: &'a DMatrix<f64>,
    pub(super) phi: &'a [f64],
    pub(super) cb: &'a ContactBoundary,
    pub(super) law: Law,
    pub(super) c: f64,
    pub(super) max_steps: usize,
    pub(super) tol_u: f64,
    /// The rows of settled slip (`ActiveSet::update_with`; production: true).
    pub(super) settle: bool,
    /// S itself: each step in the form with fewer unknowns (`None`: the dual form always).
    pub(super) stiff: Option<&'a Stiff<'a>>,
}

impl DenseIteration<'_> {
    /// The start from the frictionless solution (`active`, λ_n per candidate, u = d₀ − C λ_n):
    /// every active node sticks (Δu_τ = 0, λ_τ = 0), so the first step gives the all-stick λ_τ
    /// and (F5) lets slip where |λ_τ| exceeds μ(−λ_n). Returns the records and u (d per node).
    pub(super) fn frictionless_start(
        &self,
        active: &[bool],
        lambda_n: &[f64],
    ) -> (Vec<NodeResult>, Vec<f64>) {
        let (d, n) = (self.dim, self.cb.nodes.len());
        let mut lam = vec![0.0; self.d0.len()];
        for (q, &l) in lambda_n.iter().enumerate() {
            lam[q * d] = l;
        }
        let cl = self.cmat.times(&DVector::from_vec(lam));
        let u_prev: Vec<f64> = self.d0.iter().zip(cl.iter()).map(|(w, c)| w - c).collect();
        // u_n = −g on the frictionless set (its rigid motion G α is not in u_prev), never a
        // penetration off it: b of (F1) is μ(−λ_n) on the set and 0 elsewhere
        let start: Vec<NodeResult> = (0..n)
            .map(|q| NodeResult {
                u_n: if active[q] {
                    -self.cb.nodes[q].gap
                } else {
                    u_prev[q * d].max(-self.cb.nodes[q].gap)
                },
                u_t: self.cb.nodes[q].u_t_ref,
                lambda_n: lambda_n[q],
                active: active[q],
                ..NodeResult::default()
            })
            .collect();
        (start, u_prev)
    }

    /// The iteration from `start` (per candidate; `u_prev`: its u, d per node).
    pub(super) fn run(&self, start: &[NodeResult], mut u_prev: Vec<f64>) -> DenseCoulomb {
        let (d, n) = (self.dim, self.cb.nodes.len());
        let (law, c) = (self.law, self.c);
        let scale = threshold_scale_local(self.cb, start, law, c);
        let warm = ActiveSet::warm(self.cb, start, law, c, scale, d);
        if let Some(run) = self.no_load(&warm) {
            return run;
        }
        let mut w = Walk {
            set: warm,
            it: Iterate::new(n, 0, true),
            last_still: None,
            steps: Vec::new(),
            primal: 0,
            before: None,
            settle: self.settle,
            f5_from: 0,
            alpha: vec![0.0; self.g.ncols()],
            pinned: false,
            pinned_still: 0,
        };
        let mut sys = self.system(&w.set);
        for step in 1..=self.max_steps {
            let t = Instant::now();
            let Some((x, sys_k)) = self.solve_step(&mut w, sys, step) else {
                let why = format!("the dense Coulomb system of step {step} is singular");
                return self.failed(w, why);
            };
            let (lam, u, alpha) = self.unknowns(&sys_k, &x);
            w.alpha.clone_from(&alpha);
            self.records(&w.set, &lam, &u, &mut w.it.nodes);
            let scale = threshold_scale_local(self.cb, &w.it.nodes, law, c);
            let up = w
                .set
                .update_with(&w.it, self.cb, law, c, scale, d, w.settle, 0.0); // (3.23) / (F5)
            let residual = up.residual2.sqrt();
            let du_rel = relative_change(&u, &u_prev);
            let seconds = t.elapsed().as_secs_f64();
            w.steps
                .push((step, w.set.local_active(), up.changed, residual, seconds));
            w.pinned_still = match w.pinned && up.changed == 0 {
                true => w.pinned_still + 1,
                false => 0,
            };
            if w.pinned_still >= STUCK_PINNED {
                let why = format!(
                    "the dense Coulomb steps from step {} on hold a free rigid mode by no row \
                     and change no state",
                    step + 1 - w.pinned_still
                );
                return self.failed(w, why);
            }
            // a pinned step balances no free mode: never accepted, the next step frees α
            let verdict = match w.pinned {
                true => {
                    w.last_still = None;
                    Judgement::Continue(self.system(&up.next))
                }
                false => self.judge(&mut w.last_still, &up, &sys_k, &x, du_rel),
            };
            let next = match verdict {
                Judgement::Accept { stalled } => {
                    let at = Accepted {
                        sys: &sys_k,
                        u: &u,
                        lam,
                        alpha,
                        steps: w.steps,
                        primal: w.primal,
                        stalled,
                        f5_from: w.f5_from,
                    };
                    return self.accepted(&w.set, at);
                }
                Judgement::Continue(next) => next,
            };
            let solved_on = std::mem::replace(&mut w.set, up.next);
            w.before = w.settle.then_some(solved_on);
            u_prev = u;
            sys = next;
        }
        let why = format!(
            "the dense Coulomb iteration did not converge in {} steps",
            self.max_steps
        );
        self.failed(w, why)
    }

    /// Coulomb with no load at the candidates (d₀ = 0 — in the primal form r = 0 —, φ = 0) and
    /// no candidate inside its obstacle: u = 0, λ = 0 is the solution (b = μ(−λ_n) of (F1) is 0
    /// where nothing presses), in one step with every candidate open (S2), `warm` the set it
    /// starts from. A load step taken back to no load otherwise iterates on round-off: its
    /// states flip from step to step until every value is exactly 0 (measured:
    /// tests/cases/punch_back.toml's last step, 5–9 dense steps by rank count and c). `None`
    /// where there is a load or a penetration, or for Tresca, whose thresholds hold a
    /// displacement without a load. Local (rank 0).
    fn no_load(&self, warm: &ActiveSet) -> Option<DenseCoulomb> {
        let zero = |v: &[f64]| v.iter().all(|&x| x == 0.0);
        let load = match self.stiff {
            Some(st) => zero(st.r),
            None => zero(self.d0),
        };
        let open = self.cb.nodes.iter().all(|k| k.gap >= 0.0);
        if self.law != Law::Coulomb || !load || !zero(self.phi) || !open {
            return None;
        }
        let t = Instant::now();
        let (d, n) = (self.dim, self.cb.nodes.len());
        let set = ActiveSet::initial(self.cb, NewtonInit::AllInactive, self.law, self.c, 0.0, d);
        let changed = (0..n).filter(|&q| set.state(q) != warm.state(q)).count();
        let steps = vec![(1, 0, changed, 0.0, t.elapsed().as_secs_f64())];
        let mut run = self.end(&set, vec![0.0; n * d], Vec::new(), steps, 0, Ok(()));
        if self.stiff.is_some() {
            run.x_s = vec![0.0; n * d];
        }
        Some(run)
    }

    /// The run ended without an accepted iterate (`why`), with the walk's set and steps.
    fn failed(&self, w: Walk, why: String) -> DenseCoulomb {
        let (d, n) = (self.dim, self.cb.nodes.len());
        self.end(
            &w.set,
            vec![0.0; n * d],
            Vec::new(),
            w.steps,
            w.primal,
            Err(why),
        )
    }

    /// A step's system `sys` solved, or where it is singular the system of the set the last
    /// iterate was solved on with unsettled (F5) rows (from then on the (F5) rows alone, as
    /// the plain path has them); the primal-form steps counted. `None`: singular.
    fn solve_step(
        &self,
        w: &mut Walk,
        sys: Option<System>,
        step: usize,
    ) -> Option<(Vec<f64>, System)> {
        w.pinned = false;
        let mut last = match attempt(sys) {
            Attempt::Solved(x, sk) => return Some(primal_counted(w, (x, sk))),
            Attempt::Singular(last) => last,
        };
        let unsettled = w.before.take().map(|b| self.unsettled(b, &w.it));
        if let Some(alt) = unsettled.filter(|alt| *alt != w.set) {
            w.settle = false;
            w.f5_from = step;
            w.set = alt;
            last = match attempt(self.system(&w.set)) {
                Attempt::Solved(x, sk) => return Some(primal_counted(w, (x, sk))),
                Attempt::Singular(last) => last,
            };
        }
        // where the (F5) rows leave it singular as well (a set that holds a free mode by no
        // row: Tresca with every node slipping at its bound, where (3.39) has no spring
        // either): the step with α pinned at its last value, as the plain path pins such a
        // mode for a step (tried before the (F5) rows instead, Tresca's settled rows cycled
        // through four sets on the floating Hertz disk at 4 764 unknowns on 2 ranks)
        if w.alpha.is_empty() {
            return None;
        }
        let sk = last?;
        w.pinned = true;
        let x = solve_pinned(&sk, &w.alpha)?;
        Some(primal_counted(w, (x, sk)))
    }

    /// Whether the iterate x of the system `sys_k` is accepted, given the set's update `up`
    /// at it and |Δu|/|u| (`last_still`: the residual of the last step that changed no
    /// state, updated here); else the next step's system.
    fn judge(
        &self,
        last_still: &mut Option<f64>,
        up: &SetUpdate,
        sys_k: &System,
        x: &[f64],
        du_rel: f64,
    ) -> Judgement {
        let (residual, lambda_norm) = (up.residual2.sqrt(), up.lambda2.sqrt());
        // The stall rule without |Δu| < tol_u: on a floating body the dense u carries the
        // round-off of α, |Δu|/|u| stays above tol_u while the residual sits at its
        // round-off (measured: the floating Hertz disk at 171 602 unknowns, |C| ~ 3e-11 of
        // |λ| ~ 8e-4 for 90 steps); the expanded iterate is checked on every node anyway.
        let unchanged = up.changed == 0;
        let floor = residual_floor(self.c, up.u2.sqrt());
        let stall = stalled(unchanged, *last_still, residual, lambda_norm, floor);
        *last_still = unchanged.then_some(residual);
        // (not Tresca's: with a small c its C_τ (3.31) measures λ_τ against itself and is at
        // round-off before λ_τ is parallel to u_τ, docs/friction.md; Algorithm 2's rule then)
        let zero = residual <= COULOMB_RESIDUAL_ZERO * lambda_norm && self.law != Law::Tresca;
        let small = residual <= COULOMB_RESIDUAL_TOL * lambda_norm;
        let accept = unchanged && (zero || stall || (du_rel < self.tol_u && small));
        // The next step's system holds at this iterate as well as its own did (states
        // unchanged, and the rows that changed hold at it to round-off): the next step would
        // return the same iterate, so it is not taken
        let next = if accept { None } else { self.system(&up.next) };
        let fixed = !accept
            && unchanged
            && residual <= COULOMB_RESIDUAL_STALL * lambda_norm
            && next.as_ref().is_some_and(|sn| {
                sn.cols == sys_k.cols
                    && sn.known.is_some() == sys_k.known.is_some()
                    && fixed_point(sn, x, residual_at(sys_k, x))
            });
        if accept || fixed {
            let stalled = residual > COULOMB_RESIDUAL_TOL * lambda_norm;
            return Judgement::Accept { stalled };
        }
        Judgement::Continue(next)
    }

    /// The set `before` updated at the iterate `it` (the last iterate: a singular step has no
    /// records of its own) with unsettled (F5) slip rows: the rows a step whose settled rows
    /// left its system singular is taken again on. Settled slip rows
    /// (λ_τ = μ(−λ_n) ν, docs/friction.md) give a slipping node's tangential displacement no
    /// stiffness of its own: where every active node of a floating body slips, its tangential
    /// rigid motion is free and the system singular (an iterate of the way, e.g. a rolling disk
    /// whose one sticking node slips for a step). The (F5) rows keep their spring L̃: the step
    /// again on them, and the iteration on them to its end. Local (rank 0).
    fn unsettled(&self, before: ActiveSet, it: &Iterate) -> ActiveSet {
        let (d, law, c) = (self.dim, self.law, self.c);
        let scale = threshold_scale_local(self.cb, &it.nodes, law, c);
        before
            .update_with(it, self.cb, law, c, scale, d, false, 0.0)
            .next
    }

    /// The run's end at an accepted iterate: its result with the primal form's Schur part and
    /// whether it was accepted by the stall rule. Local (rank 0).
    fn accepted(&self, set: &ActiveSet, at: Accepted) -> DenseCoulomb {
        let x_s = self.primal_x_s(at.sys, at.u, &at.alpha);
        let mut run = self.end(set, at.lam, at.alpha, at.steps, at.primal, Ok(()));
        run.stalled = at.stalled;
        run.x_s = x_s;
        run.f5_from = at.f5_from;
        run
    }

    fn end(
        &self,
        set: &ActiveSet,
        lambda: Vec<f64>,
        mut alpha: Vec<f64>,
        steps: Vec<DenseStep>,
        primal_steps: usize,
        end: Result<(), String>,
    ) -> DenseCoulomb {
        let n = self.cb.nodes.len();
        alpha.resize(self.g.ncols(), 0.0);
        DenseCoulomb {
            lambda,
            alpha,
            active: set.normal.clone(),
            slip: (0..n).map(|q| set.slip(q)).collect(),
            steps,
            end,
            stalled: false,
            coarse: Vec::new(),
            x_s: Vec::new(),
            primal_steps,
            f5_from: 0,
            f5_coarse: 0,
        }
    }

    /// Nested iteration (as the frictionless [`crate::signorini::dense::Dense::run_nested`]; used in 2D):
    /// the dense generalised Newton first on coarse subsets of the candidates (`coarsen`, coarsest
    /// first; each subset's problem holds the contact conditions at its nodes only, with the
    /// exact compliance C between them), each level's solution starting the next finer one
    /// through (3.23) and (F5) evaluated at every candidate (λ = 0 off the subset,
    /// u = d₀ − C λ + G α); then the iteration on all candidates from there. The result's
    /// `steps` are the fine ones, `coarse` (nodes, steps) per level. A coarse level that does
    /// not converge leaves the start as it was. Local.
    pub(super) fn run_nested(&self, start: &[NodeResult], u_prev: Vec<f64>) -> DenseCoulomb {
        let d = self.dim;
        let x: Vec<[f64; 3]> = self.cb.nodes.iter().map(|k| k.x).collect();
        let gap: Vec<f64> = self.cb.nodes.iter().map(|k| k.gap).collect();
        let (mut start, mut u_prev) = (start.to_vec(), u_prev);
        let mut coarse = Vec::new();
        let mut f5_coarse = 0;
        for idx in coarsen(&x, &gap).iter().rev() {
            let dofs: Vec<usize> = idx
                .iter()
                .flat_map(|&q| (0..d).map(move |a| q * d + a))
                .collect();
            let sub_c = self.cmat.block(&dofs);
            let sub_g = DMatrix::from_fn(dofs.len(), self.g.ncols(), |r, c| self.g[(dofs[r], c)]);
            let pick = |v: &[f64]| dofs.iter().map(|&i| v[i]).collect::<Vec<f64>>();
            let d0 = pick(self.d0);
            let cb = ContactBoundary {
                nodes: idx.iter().map(|&q| self.cb.nodes[q].clone()).collect(),
                n_global: idx.len(),
                offset: 0,
                on_contact_boundary: Vec::new(),
                excluded_dirichlet: 0,
                obstacles: self.cb.obstacles.clone(),
                keys: self.cb.keys.clone(),
                modes: self.cb.modes.clone(),
                stiffness: self.cb.stiffness,
            };
            let sub = DenseIteration {
                cmat: CMatrix::Full(&sub_c),
                d0: &d0,
                g: &sub_g,
                cb: &cb,
                stiff: None,
                ..*self
            };
            let sub_start: Vec<NodeResult> = idx.iter().map(|&q| start[q]).collect();
            let run = sub.run(&sub_start, pick(&u_prev));
            coarse.push((idx.len(), run.steps.len()));
            f5_coarse += usize::from(run.f5_from > 0);
            if run.end.is_err() {
                continue;
            }
            let mut lam = vec![0.0; self.d0.len()];
            for (r, &i) in dofs.iter().enumerate() {
                lam[i] = run.lambda[r];
            }
            let u = self.u_of(&lam, &run.alpha);
            let normal = (0..self.cb.nodes.len())
                .map(|q| normal_active(u[q * d], lam[q * d], self.cb.nodes[q].gap, self.c)) // (3.23)
                .collect();
            let set = ActiveSet {
                normal,
                tangential: None,
                spring_floor: 0.0,
                stick_active: false,
            };
            self.records(&set, &lam, &u, &mut start);
            u_prev = u;
        }
        let mut run = self.run(&start, u_prev);
        run.coarse = coarse;
        run.f5_coarse = f5_coarse;
        run
    }

    /// u = d₀ − C λ + G α at every candidate (d per node).
    fn u_of(&self, lam: &[f64], alpha: &[f64]) -> Vec<f64> {
        let cl = self.cmat.times(&DVector::from_column_slice(lam));
        let mut u: Vec<f64> = self.d0.iter().zip(cl.iter()).map(|(w, c)| w - c).collect();
        for (cz, &al) in alpha.iter().enumerate() {
            for (ui, gi) in u.iter_mut().zip(self.g.column(cz).iter()) {
                *ui += gi * al;
            }
        }
        u
    }

    /// The tangential rows the dense system takes from `set`: an inactive node's λ is 0 but
    /// under Tresca, whose thresholds act out of contact too (3.18) (Coulomb's b of (F1) is 0
    /// there, also where a warm start's record has a node penetrating that its set leaves
    /// inactive). `None` without tangential rows.
    fn rows_of(&self, set: &ActiveSet) -> Option<Vec<CoulombRow<2>>> {
        let rows = set.tangential.as_ref()?;
        let none = CoulombRow::Slip {
            l: [[0.0; 2]; 2],
            q: [0.0; 2],
            r: [0.0; 2],
        };
        let out_of_contact = self.law == Law::Tresca;
        Some(
            (rows.iter().zip(&set.normal))
                .map(|(&row, &on)| if on || out_of_contact { row } else { none })
                .collect(),
        )
    }

    /// The step's dense system in the form with fewer unknowns: the dual form
    /// ([`DenseIteration::system_dual`]) or, with S at hand, the primal one ([`DenseIteration::system_primal`]).
    /// Both give the same Newton step. `None` without tangential rows.
    fn system(&self, set: &ActiveSet) -> Option<System> {
        let rows = &self.rows_of(set)?;
        let Some(st) = self.stiff else {
            return Some(self.system_dual(set, rows));
        };
        let d = self.dim;
        let (mut dual, mut primal) = (0, 0);
        for (q, row) in rows.iter().enumerate() {
            if !set.normal[q] {
                // λ_n = 0; the tangential dofs free (no friction, or a slip row), or held
                // (Tresca: a node that sticks out of contact), each with a λ_τ under friction
                let friction = !frictionless_row(*row) && given(*row).is_none();
                primal += if matches!(row, CoulombRow::Stick) {
                    1
                } else {
                    d
                };
                dual += if friction { d - 1 } else { 0 };
            } else {
                let one = tie(*row, q * d, d).is_some() || given(*row).is_some();
                dual += if one { 1 } else { d };
                if row.is_slip() {
                    primal += d - 1;
                }
            }
        }
        if primal < dual {
            Some(self.system_primal(set, rows, st))
        } else {
            Some(self.system_dual(set, rows))
        }
    }

    /// The step's dense system in the primal form ([`Stiff`]): the unknowns u at the dofs the
    /// set leaves free and α; rows λ = 0 (inactive), (F6) −λ_τ + L̃ u_τ − q λ_n = r̃ + L̃ u_τ^ref
    /// (slip), Gᵀ λ = φ, with λ = r − S (u − G α) and u = −g, u_τ^ref where the set prescribes
    /// it; rows equilibrated as the dual form's.
    fn system_primal(&self, set: &ActiveSet, rows: &[CoulombRow<2>], st: &Stiff) -> System {
        let mz = self.g.ncols();
        let PrimalUnknowns {
            known,
            cols,
            at,
            zero,
        } = self.primal_unknowns(set, rows);
        let m = cols.len();
        let mut pr = PrimalRows {
            st,
            cols: &cols,
            base: primal_base(st, &known),
            m,
            mz,
            s_row: vec![0.0; st.s.n()],
        };
        let mut a = DMatrix::<f64>::zeros(m + mz, m + mz);
        let mut rhs = DVector::<f64>::zeros(m + mz);
        self.primal_contact_rows(set, rows, &mut pr, &at, &mut a, &mut rhs);
        self.primal_balance(&pr, &mut a, &mut rhs);
        equilibrate(&mut a, &mut rhs);
        System {
            a,
            rhs,
            cols,
            known: Some(known),
            zero,
            given: Vec::new(),
            alpha_scale: 1.0,
        }
    }

    /// The primal form's unknowns: every dof of an inactive candidate (but the tangential
    /// ones of a node that sticks out of contact, Tresca), the tangential dofs of a slipping
    /// one; u = −g, u_τ^ref where the set prescribes it. `zero`: the dofs whose λ is 0.
    fn primal_unknowns(&self, set: &ActiveSet, rows: &[CoulombRow<2>]) -> PrimalUnknowns {
        let (d, n) = (self.dim, self.cb.nodes.len());
        let mut known = vec![f64::NAN; n * d];
        let mut cols: Vec<Unknown> = Vec::new();
        let mut at = vec![usize::MAX; n];
        let mut zero = Vec::new();
        let free = |dof: usize| Unknown { dof, tied: None };
        for (q, k) in self.cb.nodes.iter().enumerate() {
            at[q] = cols.len();
            if !set.normal[q] {
                cols.push(free(q * d));
                zero.push(q * d);
                match rows[q] {
                    CoulombRow::Stick => {
                        known[q * d + 1..q * d + d].copy_from_slice(&k.u_t_ref[..d - 1])
                    }
                    row => {
                        cols.extend((1..d).map(|a| free(q * d + a)));
                        if frictionless_row(row) {
                            zero.extend((1..d).map(|a| q * d + a));
                        }
                    }
                }
                continue;
            }
            known[q * d] = -k.gap;
            if rows[q].is_slip() {
                cols.extend((1..d).map(|a| free(q * d + a)));
            } else {
                known[q * d + 1..q * d + d].copy_from_slice(&k.u_t_ref[..d - 1]);
            }
        }
        PrimalUnknowns {
            known,
            cols,
            at,
            zero,
        }
    }

    /// The primal form's rows of the candidates: λ = 0 (inactive; λ_n alone where the node has
    /// friction out of contact, Tresca) and (F6) (slip); a sticking node's tangential dofs have
    /// no unknown and no row.
    fn primal_contact_rows(
        &self,
        set: &ActiveSet,
        rows: &[CoulombRow<2>],
        pr: &mut PrimalRows,
        at: &[usize],
        a: &mut DMatrix<f64>,
        rhs: &mut DVector<f64>,
    ) {
        let d = self.dim;
        let mut ri = 0;
        for (q, k) in self.cb.nodes.iter().enumerate() {
            let inactive = !set.normal[q];
            if inactive && frictionless_row(rows[q]) {
                // λ = 0
                for b in 0..d {
                    rhs[ri] = -pr.put_lam(a, ri, &[(q * d + b, 1.0)]);
                    ri += 1;
                }
                continue;
            }
            if inactive {
                // λ_n = 0, the tangential rows of the node's friction below
                rhs[ri] = -pr.put_lam(a, ri, &[(q * d, 1.0)]);
                ri += 1;
            }
            let CoulombRow::Slip { l, q: qc, r } = rows[q].with_reference(&k.u_t_ref) else {
                continue; // stick: no unknown, no row
            };
            // (F6): −λ_τ − q λ_n + L̃ u_τ = r̃ (+ L̃ u_τ^ref, in r); out of contact q = 0
            // (Tresca's rows (3.39a)), u_τ's unknowns after u_n's
            let t0 = at[q] + usize::from(inactive);
            for i in 0..d - 1 {
                let c0 = pr.put_lam(a, ri, &[(q * d + 1 + i, -1.0), (q * d, -qc[i])]);
                for j in 0..d - 1 {
                    a[(t0 + j, ri)] += l[i][j];
                }
                rhs[ri] = r[i] - c0;
                ri += 1;
            }
        }
        debug_assert_eq!(ri, pr.m);
    }

    /// The primal form's balance of the free modes: Gᵀ λ = φ, λ = base − S u_F + S G α.
    fn primal_balance(&self, pr: &PrimalRows, a: &mut DMatrix<f64>, rhs: &mut DVector<f64>) {
        let (st, m, mz) = (pr.st, pr.m, pr.mz);
        for cz in 0..mz {
            let mut row = a.column_mut(m + cz);
            for (jc, u) in pr.cols.iter().enumerate() {
                row[jc] = -st.sg[(u.dof, cz)];
            }
            for c2 in 0..mz {
                row[m + c2] = st.gsg[(cz, c2)];
            }
            let gb: f64 = self
                .g
                .column(cz)
                .iter()
                .zip(&pr.base)
                .map(|(g, b)| g * b)
                .sum();
            rhs[m + cz] = self.phi[cz] - gb;
        }
    }

    /// The dual form's unknowns: per active node λ_n, then λ_τ unless its row ties it to λ_n
    /// or gives it; per inactive node with friction (Tresca) λ_τ unless given. Also `at`, the
    /// position of each node's first unknown (`usize::MAX`: none), and the λ_τ that the rows
    /// give as values (Tresca's settled slip, [`given`]).
    #[allow(clippy::type_complexity)]
    fn dual_unknowns(
        &self,
        set: &ActiveSet,
        rows: &[CoulombRow<2>],
    ) -> (Vec<Unknown>, Vec<usize>, Vec<(usize, f64)>) {
        let (d, n) = (self.dim, self.cb.nodes.len());
        let mut cols: Vec<Unknown> = Vec::new();
        let mut at = vec![usize::MAX; n];
        let tangents = |q: usize| {
            (1..d).map(move |b| Unknown {
                dof: q * d + b,
                tied: None,
            })
        };
        let mut values: Vec<(usize, f64)> = Vec::new();
        for q in 0..n {
            let value = given(rows[q]);
            if let Some(v) = value {
                values.push((q * d + 1, v));
            }
            if set.normal[q] {
                at[q] = cols.len();
                let tied = tie(rows[q], q * d, d);
                cols.push(Unknown { dof: q * d, tied });
                if tied.is_none() && value.is_none() {
                    cols.extend(tangents(q));
                }
            } else if !frictionless_row(rows[q]) && value.is_none() {
                at[q] = cols.len();
                cols.extend(tangents(q));
            }
        }
        (cols, at, values)
    }

    /// d₀ − C λ_given and φ − Gᵀ λ_given: the λ that the rows give (`values`) moved to the
    /// right-hand side of u = d₀ − C λ + G α and Gᵀ λ = φ (d₀ and φ where none is given).
    fn shifted_by(&self, values: &[(usize, f64)]) -> (std::borrow::Cow<'_, [f64]>, Vec<f64>) {
        let mut phi = self.phi.to_vec();
        if values.is_empty() {
            return (std::borrow::Cow::Borrowed(self.d0), phi);
        }
        let mut lam_given = vec![0.0; self.d0.len()];
        for &(dof, v) in values {
            lam_given[dof] = v;
        }
        let cl = self.cmat.times(&DVector::from_column_slice(&lam_given));
        let shifted = self.d0.iter().zip(cl.iter()).map(|(a, b)| a - b).collect();
        for (cz, p) in phi.iter_mut().enumerate() {
            *p -= values
                .iter()
                .map(|&(dof, v)| self.g[(dof, cz)] * v)
                .sum::<f64>();
        }
        (std::borrow::Cow::Owned(shifted), phi)
    }

    /// The step's dense system in the active nodes' λ and the free modes' α (module note;
    /// bordered by the balance Gᵀ λ = φ where Dirichlet data leave rigid modes free), its rows
    /// equilibrated; `rows`: the set's rows as [`DenseIteration::rows_of`] gives them.
    fn system_dual(&self, set: &ActiveSet, rows: &[CoulombRow<2>]) -> System {
        let (d, n, mz, c) = (self.dim, self.cb.nodes.len(), self.g.ncols(), self.c);
        let (cmat, g) = (self.cmat, self.g);
        let (cols, at, values) = self.dual_unknowns(set, rows);
        let (w, phi) = self.shifted_by(&values);
        let w = &w[..];
        let m = cols.len();
        // built as its transpose: row ri of the system is column ri here (contiguous; measured
        // on the floating Hertz disk at 344 620 unknowns, 1 875 dense unknowns: 0.15 s a step
        // against 0.18 s built row by row)
        let mut a = DMatrix::<f64>::zeros(m + mz, m + mz);
        let mut rhs = DVector::<f64>::zeros(m + mz);
        // row `ri` := Σ_j coef_j · u_(dof_j) (+ constants on the right): u = w − C λ + G α
        let mut c_row = vec![0.0; cmat.n()];
        let mut put_u = |a: &mut DMatrix<f64>, ri: usize, terms: &[(usize, f64)]| -> f64 {
            let mut row = a.column_mut(ri);
            for &(dof, f) in terms {
                cmat.column_into(dof, &mut c_row); // C's row `dof` (C symmetric)
                for (jc, u) in cols.iter().enumerate() {
                    row[jc] -= f * u.of(|col| c_row[col]);
                }
                for cz in 0..mz {
                    row[m + cz] += f * g[(dof, cz)] / c; // the unknown c α
                }
            }
            terms.iter().map(|&(dof, f)| f * w[dof]).sum::<f64>()
        };
        for p in (0..n).filter(|&q| at[q] != usize::MAX) {
            let k = &self.cb.nodes[p];
            let (r0, pn) = (at[p], p * d);
            // the node's λ_n (active) and the first λ_τ's position
            let (n0, t0) = match set.normal[p] {
                true => (Some(r0), r0 + 1),
                false => (None, r0),
            };
            if n0.is_some() {
                // u_n = −g
                rhs[r0] = -k.gap - put_u(&mut a, r0, &[(pn, 1.0)]);
            }
            match rows[p] {
                _ if n0.is_some() && cols[r0].tied.is_some() => {} // λ_τ = −q λ_n: the tie
                row if given(row).is_some() => {}                  // λ_τ given: no row
                CoulombRow::Stick => {
                    // u_τ = u_τ^ref (3.34a)
                    for i in 0..d - 1 {
                        let wi = put_u(&mut a, t0 + i, &[(pn + 1 + i, 1.0)]);
                        rhs[t0 + i] = k.u_t_ref[i] - wi;
                    }
                }
                row => {
                    // (F6) on an active node: −λ_τ + L̃ u_τ − q λ_n = r̃ + L̃ u_τ^ref. Its term
                    // q c (u_n + g) vanishes by the normal row; kept, it would carry that row's
                    // round-off times c (u_n = d₀ − C λ cancels to −g) into λ_τ (measured on the
                    // held disk at c = 1e7: u 2.1e-9 off the plain path's with it, 1.5e-14 without)
                    let CoulombRow::Slip { l, q, r } = row.with_reference(&k.u_t_ref) else {
                        unreachable!("a slip row stays a slip row")
                    };
                    for i in 0..d - 1 {
                        let ri = t0 + i;
                        let terms: Vec<(usize, f64)> =
                            (0..d - 1).map(|j| (pn + 1 + j, l[i][j])).collect();
                        let wi = put_u(&mut a, ri, &terms);
                        a[(ri, ri)] -= 1.0;
                        // out of contact q = 0 (Tresca's rows (3.39a)): no λ_n to couple
                        if let Some(n0) = n0 {
                            a[(n0, ri)] -= q[i];
                        }
                        rhs[ri] = r[i] - wi;
                    }
                }
            }
        }
        // the balance of the free modes: Gᵀ λ = φ (the pins carry nothing)
        for cz in 0..mz {
            for (jc, u) in cols.iter().enumerate() {
                a[(jc, m + cz)] = u.of(|col| g[(col, cz)]);
            }
            rhs[m + cz] = phi[cz];
        }
        equilibrate(&mut a, &mut rhs);
        System {
            a,
            rhs,
            cols,
            known: None,
            zero: Vec::new(),
            given: values,
            alpha_scale: c,
        }
    }

    /// λ (every candidate, d per node), u = d₀ − C λ + G α and α from a system's solution.
    #[allow(clippy::type_complexity)]
    fn unknowns(&self, sys: &System, x: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        if let (Some(known), Some(st)) = (&sys.known, self.stiff) {
            return self.unknowns_primal(sys, known, st, x);
        }
        let (d, n, m) = (self.dim, self.cb.nodes.len(), sys.cols.len());
        let mut lam = vec![0.0; n * d];
        for &(dof, v) in &sys.given {
            lam[dof] = v;
        }
        for (u, &xj) in sys.cols.iter().zip(x) {
            lam[u.dof] = xj;
            if let Some((t, f)) = u.tied {
                lam[t] = f * xj;
            }
        }
        let alpha: Vec<f64> = x[m..].iter().map(|b| b / sys.alpha_scale).collect();
        let u = self.u_of(&lam, &alpha);
        (lam, u, alpha)
    }

    /// u − G α at the candidates' dofs where `sys` is in the primal form (empty otherwise): the
    /// Schur variables' part of the expansion, from the step's own unknowns (d₀ − C λ would
    /// carry λ's round-off through C = S⁻¹: measured on the rolling Hertz disk at 344 620
    /// unknowns, the expanded residual 1.5e-9 of ‖λ‖ instead of round-off).
    fn primal_x_s(&self, sys: &System, u: &[f64], alpha: &[f64]) -> Vec<f64> {
        if sys.known.is_none() {
            return Vec::new();
        }
        (DVector::from_column_slice(u) - self.g * DVector::from_column_slice(alpha))
            .as_slice()
            .to_vec()
    }

    /// [`DenseIteration::unknowns`] of the primal form: u (`known` where the set prescribes it), α, and
    /// λ = r − S (u − G α), exactly 0 at the inactive candidates (their rows).
    #[allow(clippy::type_complexity)]
    fn unknowns_primal(
        &self,
        sys: &System,
        known: &[f64],
        st: &Stiff,
        x: &[f64],
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let m = sys.cols.len();
        let mut u = known.to_vec();
        for (c, &xj) in sys.cols.iter().zip(x) {
            u[c.dof] = xj;
        }
        let alpha: Vec<f64> = x[m..].to_vec();
        let w = DVector::from_column_slice(&u) - self.g * DVector::from_column_slice(&alpha);
        let mut lam = (DVector::from_column_slice(st.r) - st.s.times(&w))
            .as_slice()
            .to_vec();
        for &dof in &sys.zero {
            lam[dof] = 0.0;
        }
        (lam, u, alpha)
    }

    /// The iterate's per-node records (frame and global components) from λ and u.
    fn records(&self, set: &ActiveSet, lam: &[f64], u: &[f64], out: &mut [NodeResult]) {
        let d = self.dim;
        for (q, (k, r)) in self.cb.nodes.iter().zip(out.iter_mut()).enumerate() {
            let f = &k.frame;
            let (uq, lq) = (&u[q * d..q * d + d], &lam[q * d..q * d + d]);
            let mut ug = [0.0; 3];
            let mut lg = [0.0; 3];
            for a in 0..3 {
                ug[a] = f.n[a] * uq[0];
                lg[a] = f.n[a] * lq[0];
                for i in 0..d - 1 {
                    ug[a] += f.t[i][a] * uq[1 + i];
                    lg[a] += f.t[i][a] * lq[1 + i];
                }
            }
            let mut u_t = [0.0; 2];
            let mut lambda_t = [0.0; 2];
            u_t[..d - 1].copy_from_slice(&uq[1..d]);
            lambda_t[..d - 1].copy_from_slice(&lq[1..d]);
            *r = NodeResult {
                u: ug,
                lambda: lg,
                u_n: uq[0],
                u_t,
                lambda_n: lq[0],
                lambda_t,
                active: set.normal[q],
                slip: set.slip(q),
            };
        }
    }
}

#[cfg(test)]
mod tests;
