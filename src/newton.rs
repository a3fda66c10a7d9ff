//! The semismooth Newton method in its exact active-set form: Algorithm 1 (frictionless,
//! reduced system (3.29)). Each step: copy A's values into the system matrix S (same
//! pattern), overwrite the rows of the active nodes and of the pinned dofs, solve with the
//! KSP, recover λ by (3.28), update the sets by (3.23). The only collectives per step are the
//! solve, one MatMult and one Allreduce (set changes, counts, set fingerprint, residual norm
//! and the rigid-mode Gram matrix of the next set).

use crate::assembly::System;
use crate::case::{NewtonInit, NewtonSection, OnCycle, RigidModes as RigidSetting};
use crate::contact::{self, TangentialRow};
use crate::contact_set::ContactSet;
use crate::mesh::Mesh;
use crate::partition::Layout;
use crate::petsc::PInt;
use crate::petsc::{Matrix, Vector};
use crate::reduced::{write_symmetric_constraint, NodeConstraint, NodeRows};
use crate::rigid::RigidModes;
use crate::run::{Ctx, RunError};
use crate::say;
use crate::solver::LinearSolver;
use mpi::collective::SystemOperation;
use mpi::traits::*;
use std::collections::HashMap;
use std::time::Instant;

/// One Newton step, for the history.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StepInfo {
    pub step: usize,
    /// |A_n^ℓ|: active nodes used in this step's solve.
    pub active: usize,
    /// Nodes whose state changed in the update after this solve.
    pub changed: usize,
    /// ‖C_n(u^ℓ, λ^ℓ)‖₂ over all contact nodes (3.21).
    pub residual: f64,
    pub solve_seconds: f64,
    pub iterations: usize,
    /// Number of rigid modes pinned in this step.
    pub pinned: usize,
    /// Tresca: nodes in S1..S4 (inactive/stick, inactive/slip, active/stick, active/slip) in
    /// this step's solve.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub states: Option<[usize; 4]>,
    /// Tresca: |u^ℓ − u^{ℓ−1}| / |u^ℓ|.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub du_rel: Option<f64>,
}

/// Per owned contact node: displacement and multiplier in the node's frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct NodeResult {
    pub u: [f64; 3],
    pub lambda: [f64; 3],
    pub u_n: f64,
    pub u_t: [f64; 2],
    pub lambda_n: f64,
    pub lambda_t: [f64; 2],
    pub active: bool,
    /// Tresca: in A_τ (slip) in the last solve.
    pub slip: bool,
}

/// What Algorithm 1 returns.
pub struct NewtonResult {
    pub u: Vector,
    pub nodes: Vec<NodeResult>,
    pub history: Vec<StepInfo>,
    pub converged: bool,
    pub steps: usize,
    /// Seconds spent in λ recovery (MatMult + local work), all steps.
    pub lambda_seconds: f64,
    /// Seconds spent writing the reduced systems, all steps.
    pub rows_seconds: f64,
    pub pinned_final: Vec<(usize, usize)>,
    /// Step after which a recurring set switched the iteration to least-index updates.
    pub cycle_detected_at: Option<usize>,
    /// The complementarity parameter used.
    pub c: f64,
}

fn cycling_error(step: usize, n: usize, prev: usize, tresca: bool, safeguarded: bool) -> RunError {
    RunError::Failed(format!(
        "Newton cycling: the active set of step {step} (|A_n| = {n}) equals one seen {}{} — the \
         exact active-set iteration would loop forever; stopping",
        if safeguarded {
            "earlier".to_string()
        } else {
            format!("at step {prev}")
        },
        if safeguarded {
            " even with single-node updates"
        } else if tresca {
            " (Tresca: no single-node fallback)"
        } else {
            " (newton.on_cycle = \"stop\")"
        }
    ))
}

/// Prescribed directions of one node: (unit vector c, value of cᵀu).
type Dirs = Vec<([f64; 3], f64)>;

/// The constraints of every rewritten contact node (active normal n with −g, stick tangents
/// with 0) and pinned dof, by global node number, on every rank (one all-gather of the
/// rewritten contact nodes; the pins are known everywhere).
fn constraint_map(
    ctx: &Ctx,
    layout: &Layout,
    cs: &ContactSet,
    dirs: &[Option<Dirs>],
    pins: &[(usize, usize)],
) -> HashMap<usize, NodeConstraint> {
    let mut mine: Vec<f64> = Vec::new();
    for (k, d) in cs.nodes.iter().zip(dirs) {
        if let Some(d) = d {
            let gk = layout.node_global[k.node] as f64;
            if d.is_empty() {
                // rewritten by its owner without a prescribed direction (Tresca slip node)
                mine.extend_from_slice(&[gk, 0.0, 0.0, 0.0, 0.0]);
            }
            for (c, v) in d {
                mine.extend_from_slice(&[gk, c[0], c[1], c[2], *v]);
            }
        }
    }
    let mut counts = vec![0i32; ctx.size];
    ctx.world
        .all_gather_into(&(mine.len() as i32), &mut counts[..]);
    let displs: Vec<i32> = counts
        .iter()
        .scan(0, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect();
    let mut all = vec![0.0f64; counts.iter().sum::<i32>() as usize];
    {
        let mut part = mpi::datatype::PartitionMut::new(&mut all[..], counts, displs);
        ctx.world.all_gather_varcount_into(&mine[..], &mut part);
    }
    let mut map: HashMap<usize, NodeConstraint> = HashMap::new();
    for r in all.chunks_exact(5) {
        map.entry(r[0] as usize)
            .or_default()
            .dirs
            .push(([r[1], r[2], r[3]], r[4]));
    }
    for &(v, k) in pins {
        let mut e = [0.0; 3];
        e[k] = 1.0;
        map.entry(layout.node_global[v])
            .or_default()
            .dirs
            .push((e, 0.0));
    }
    map
}

/// Default c = E / h_c with h_c the mean contact mesh size (w_k^(1/(d−1)) over all contact
/// nodes): c u then has the size of a nodal force, as λ (measured in bench/results/tresca_c.md).
fn default_c(ctx: &Ctx, cs: &ContactSet, dim: usize, young: f64) -> f64 {
    let local: f64 = cs
        .nodes
        .iter()
        .map(|k| k.weight.powf(1.0 / (dim - 1) as f64))
        .sum();
    let mut out = [0.0f64; 2];
    ctx.world.all_reduce_into(
        &[local, cs.nodes.len() as f64][..],
        &mut out[..],
        SystemOperation::sum(),
    );
    if out[1] > 0.0 && out[0] > 0.0 {
        young / (out[0] / out[1])
    } else {
        young
    }
}

/// Outcome of the load-balance test of the free rigid modes.
enum Balance {
    Balanced,
    /// Activate the contact node with this gmsh tag (the first to touch).
    Touch(u64),
    /// No equilibrium; the size of the unbalanced load.
    NoSupport(f64),
}

/// The unbalanced load in the free rigid modes, φ = Qᵀ Rᵀ (f − A u) at the pins (the dropped
/// equations), and, if it is not zero, the inactive contact node that a rigid motion along
/// φ brings into contact first (smallest gap / closing speed; ties by tag). Collective.
#[allow(clippy::too_many_arguments)]
fn unbalanced_mode_contact(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    cs: &ContactSet,
    modes: &RigidModes,
    q: &nalgebra::DMatrix<f64>,
    pins: &[(usize, usize)],
    f_local: &[f64],
    au_local: &[f64],
    nodes: &[NodeResult],
    active: &[bool],
    row_lo: usize,
    fmax: f64,
) -> Balance {
    let dim = mesh.dim;
    let mf = q.ncols();
    let mut phi = vec![0.0f64; mf];
    for &(v, k) in pins {
        if layout.owns_node(v) {
            let p = layout.node_global[v] * dim + k - row_lo;
            let res = f_local[p] - au_local[p];
            let row = modes.dof_row(&mesh.coords[v], k);
            for (c, ph) in phi.iter_mut().enumerate() {
                *ph += res * (0..modes.m).map(|j| row[j] * q[(j, c)]).sum::<f64>();
            }
        }
    }
    let mut g = vec![0.0f64; mf];
    ctx.world
        .all_reduce_into(&phi[..], &mut g[..], SystemOperation::sum());
    let norm = g.iter().map(|x| x * x).sum::<f64>().sqrt();
    if norm <= 1e-8 * fmax.max(f64::MIN_POSITIVE) {
        return Balance::Balanced;
    }
    // Motion per unit α in mode coefficients: Q φ / |φ|.
    let coef: Vec<f64> = (0..modes.m)
        .map(|j| (0..mf).map(|c| q[(j, c)] * g[c]).sum::<f64>() / norm)
        .collect();
    let mut best = (f64::INFINITY, u64::MAX);
    for ((k, r), &a) in cs.nodes.iter().zip(nodes).zip(active) {
        if a {
            continue;
        }
        let nr = modes.normal_row(&k.x, &k.frame.n);
        let speed = -(0..modes.m).map(|j| nr[j] * coef[j]).sum::<f64>();
        if speed <= 1e-12 {
            continue;
        }
        let alpha = (r.u_n + k.gap).max(0.0) / speed;
        if alpha < best.0 || (alpha == best.0 && k.tag < best.1) {
            best = (alpha, k.tag);
        }
    }
    let mut amin = 0.0f64;
    ctx.world
        .all_reduce_into(&best.0, &mut amin, SystemOperation::min());
    if !amin.is_finite() {
        return Balance::NoSupport(norm);
    }
    let mine = if best.0 <= amin * (1.0 + 1e-12) {
        best.1
    } else {
        u64::MAX
    };
    let mut tag = 0u64;
    ctx.world
        .all_reduce_into(&mine, &mut tag, SystemOperation::min());
    Balance::Touch(tag)
}

/// Does a tangential row hold u_τ (stick, or slip with a spring L̃ ≠ 0)?
fn holds_tangent(r: &TangentialRow<2>) -> bool {
    match r {
        TangentialRow::Stick => true,
        TangentialRow::Slip { l, .. } => l.iter().flatten().any(|&x| x != 0.0),
    }
}

/// Two fingerprints of an active set that do not depend on the partition (sums of per-node
/// hashes of gmsh tags, exact in f64).
fn node_hash(tag: u64) -> (f64, f64) {
    let mut x = tag.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 29;
    let mut y = tag.wrapping_mul(0xC2B2_AE3D_27D4_EB4F) ^ 0x1656_67B1_9E37_79F9;
    y ^= y >> 31;
    ((x >> 44) as f64, (y >> 44) as f64)
}

/// The initial active set A_n^1.
fn initial_active(cs: &ContactSet, init: NewtonInit, scale: f64) -> Vec<bool> {
    let touching = |g: f64| g <= 1e-9 * scale;
    cs.nodes
        .iter()
        .map(|k| match init {
            NewtonInit::AllActive => true,
            NewtonInit::AllInactive => false,
            NewtonInit::Gap => touching(k.gap),
            // Our default: the initially touching nodes (empty if none touches, which is the
            // all-inactive start). Fewer steps than the thesis' all-active start at every
            // Hertz level measured (README).
            NewtonInit::Auto => touching(k.gap),
        })
        .collect()
}

/// Algorithm 1 (frictionless, reduced system (3.29)) or, with `tresca`, Algorithm 2 (Tresca,
/// reduced system (3.42) with the regularised slip rows (3.39)/(3.40)) on the assembled
/// system `sys` (A, f). Without friction no tangential state is formed or tested.
#[allow(clippy::too_many_arguments)]
pub fn semismooth_newton(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    sys: &mut System,
    fixed: &[f64],
    cs: &ContactSet,
    settings: &NewtonSection,
    rigid_setting: RigidSetting,
    coords: Option<&Vector>,
    tresca: bool,
    young: f64,
) -> Result<NewtonResult, RunError> {
    let comm = ctx.petsc.comm();
    let dim = mesh.dim;
    let c = match settings.c {
        Some(c) => c,
        None => default_c(ctx, cs, dim, young),
    };
    say!(
        ctx,
        "newton: c = {c:.6e}{}",
        if settings.c.is_none() {
            " (E / h_c)"
        } else {
            ""
        }
    );
    let modes = RigidModes::new(mesh);
    let use_rigid = rigid_setting == RigidSetting::Auto;

    // Rows of A of the contact nodes (constant), the load f at them.
    let rows: Vec<NodeRows> = cs
        .nodes
        .iter()
        .map(|k| NodeRows::read(&sys.a, k.row, dim))
        .collect::<Result<_, _>>()?;
    let f_local = sys.b.to_local_vec()?;

    // Gram matrix of the Dirichlet constraints (fixed for the whole run).
    let mut g_dir = vec![0.0; 36];
    if use_rigid {
        for &v in &layout.owned_nodes {
            for k in 0..dim {
                if !fixed[v * dim + k].is_nan() {
                    modes.add_outer(&mut g_dir, &modes.dof_row(&mesh.coords[v], k));
                }
            }
        }
        let local = g_dir.clone();
        ctx.world
            .all_reduce_into(&local[..], &mut g_dir[..], SystemOperation::sum());
    }
    let scale = mesh.extent();
    // Constraint rows of a set for the rigid-mode test: nᵀ at active nodes; with friction also
    // τᵀ where the tangential row holds u_τ (stick, or a slip row with a spring L̃ ≠ 0).
    let active_gram = |active: &[bool], trow: &[TangentialRow<2>]| -> Vec<f64> {
        let mut g = vec![0.0; 36];
        if use_rigid {
            for (i, (k, &a)) in cs.nodes.iter().zip(active).enumerate() {
                if a {
                    modes.add_outer(&mut g, &modes.normal_row(&k.x, &k.frame.n));
                }
                if tresca && holds_tangent(&trow[i]) {
                    for t in &k.frame.t[..dim - 1] {
                        modes.add_outer(&mut g, &modes.normal_row(&k.x, t));
                    }
                }
            }
        }
        g
    };

    let mut active = initial_active(cs, settings.init, scale);
    // Tangential rows from u = 0, λ = 0: stick where b_k > 0 (3.33), slip with λ_τ = 0 where
    // b_k = 0 (§3.4.3). Not formed without friction.
    let mut trow: Vec<TangentialRow<2>> = if tresca {
        cs.nodes
            .iter()
            .map(|k| contact::tangential_row_dyn(dim, [0.0; 2], [0.0; 2], k.bound, c))
            .collect()
    } else {
        Vec::new()
    };
    // Global Gram matrix of the first set.
    let mut g_act = vec![0.0; 36];
    {
        let local = active_gram(&active, &trow);
        ctx.world
            .all_reduce_into(&local[..], &mut g_act[..], SystemOperation::sum());
    }
    let mut n_active_global = {
        let mut n = 0u64;
        ctx.world.all_reduce_into(
            &(active.iter().filter(|&&a| a).count() as u64),
            &mut n,
            SystemOperation::sum(),
        );
        n as usize
    };

    let mut s: Matrix = sys.a.duplicate()?;
    let mut ls = LinearSolver::new(comm, &mut s, coords)?;
    let mut rhs = sys.b.duplicate()?;
    let mut u = sys.b.duplicate()?;
    let mut au = sys.b.duplicate()?;
    let mut buf = Vec::new();
    let mut u_prev: Vec<f64> = if tresca {
        vec![0.0; f_local.len()]
    } else {
        Vec::new()
    };
    let (row_lo, _) = sys.a.ownership_range()?;
    let mut history: Vec<StepInfo> = Vec::new();
    // Sets seen so far: (|A_n|, two fingerprints, and for Tresca ‖u‖² to 10 digits — there the
    // slip rows depend on the iterate, so only a recurring (set, u) pair is a cycle).
    let mut seen: Vec<(usize, f64, f64, f64)> = Vec::new();
    let mut nodes = vec![NodeResult::default(); cs.nodes.len()];
    let mut lambda_seconds = 0.0;
    let mut rows_seconds = 0.0;
    let mut converged = false;
    let mut least_index = false;
    let mut cycle_detected_at: Option<usize> = None;
    let mut pins: Vec<(usize, usize)> = Vec::new();
    let mut pins_key: Option<Vec<f64>> = None;
    let mut q_free = nalgebra::DMatrix::<f64>::zeros(modes.m, 0);
    let mut pin_rows: Vec<(usize, NodeRows)> = Vec::new();
    let fmax = {
        let local = f_local.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let mut out = 0.0f64;
        ctx.world
            .all_reduce_into(&local, &mut out, SystemOperation::max());
        out
    };
    let candidate =
        |v: usize| !cs.on_contact_boundary[v] && (0..dim).all(|k| fixed[v * dim + k].is_nan());

    // Fingerprint of the first set.
    let fp = |active: &[bool], trow: &[TangentialRow<2>]| -> (f64, f64) {
        let mut h = (0.0, 0.0);
        for (i, (k, &a)) in cs.nodes.iter().zip(active).enumerate() {
            let slip = tresca && trow[i].is_slip();
            let state = a as u64 + 2 * slip as u64;
            if state != 0 {
                let (x, y) = node_hash(k.tag.wrapping_mul(4).wrapping_add(state));
                h.0 += x;
                h.1 += y;
            }
        }
        h
    };
    // Global count, fingerprints and Gram matrix of a set (one Allreduce).
    let set_summary = |act: &[bool], tr: &[TangentialRow<2>]| -> ((usize, f64, f64), Vec<f64>) {
        let (h1, h2) = fp(act, tr);
        let mut local = vec![act.iter().filter(|&&a| a).count() as f64, h1, h2];
        local.extend(active_gram(act, tr));
        let mut g2 = vec![0.0f64; local.len()];
        ctx.world
            .all_reduce_into(&local[..], &mut g2[..], SystemOperation::sum());
        ((g2[0] as usize, g2[1], g2[2]), g2[3..3 + 36].to_vec())
    };
    {
        let (h1, h2) = fp(&active, &trow);
        let mut out = [0.0; 2];
        ctx.world
            .all_reduce_into(&[h1, h2][..], &mut out[..], SystemOperation::sum());
        seen.push((n_active_global, out[0], out[1], 0.0));
    }

    for step in 1..=settings.max_steps {
        // (3.29): S = A with the rows of active nodes replaced; rhs = f likewise.
        let t_rows = Instant::now();
        s.copy_values_from(&sys.a)?;
        rhs.copy_from(&sys.b)?;
        let mut rhs_updates: Vec<(usize, f64)> = Vec::new();
        // Free rigid modes of this set: pin one dof each.
        let mut g = g_dir.clone();
        for (x, y) in g.iter_mut().zip(&g_act) {
            *x += y;
        }
        if use_rigid {
            let key = g.clone();
            if pins_key.as_ref() != Some(&key) {
                let q = modes.free_modes(&g);
                pins = modes.pins(mesh, &q, candidate);
                if pins.len() < q.ncols() {
                    return Err(RunError::Failed(format!(
                        "{} free rigid mode(s) but only {} dof(s) available to fix them",
                        q.ncols(),
                        pins.len()
                    )));
                }
                pins_key = Some(key);
                q_free = q;
                // Rows of the owned pinned nodes (for the symmetric elimination).
                pin_rows.clear();
                let mut pn: Vec<usize> = pins
                    .iter()
                    .map(|&(v, _)| v)
                    .filter(|&v| layout.owns_node(v))
                    .collect();
                pn.sort_unstable();
                pn.dedup();
                for v in pn {
                    pin_rows.push((v, NodeRows::read(&sys.a, layout.node_global[v] * dim, dim)?));
                }
            }
        }
        {
            // (3.29) / (3.42), applied symmetrically (reduced::write_symmetric_constraint):
            // prescribed directions (active normal, stick tangents, pins) are eliminated from
            // rows and columns; Tresca slip rows add L̃ and r̃ (3.39) to the node's own block.
            let dirs: Vec<Option<Dirs>> = cs
                .nodes
                .iter()
                .enumerate()
                .map(|(i, k)| {
                    let mut d = Vec::new();
                    if active[i] {
                        d.push((k.frame.n, -k.gap));
                    }
                    if tresca {
                        if let TangentialRow::Stick = trow[i] {
                            for t in &k.frame.t[..dim - 1] {
                                d.push((*t, 0.0));
                            }
                        }
                    }
                    (tresca || active[i]).then_some(d)
                })
                .collect();
            let cmap = constraint_map(ctx, layout, cs, &dirs, &pins);
            let mut rhs_add: Vec<(PInt, f64)> = Vec::new();
            // (rows of A, constraint, first local row) of every node this rank rewrites
            let mut writes: Vec<(&NodeRows, NodeConstraint, usize)> = Vec::new();
            for (i, (k, r)) in cs.nodes.iter().zip(&rows).enumerate() {
                if dirs[i].is_none() {
                    continue; // (3.29): rows of inactive frictionless nodes stay as in A
                }
                let gk = layout.node_global[k.node];
                let mut me = cmap[&gk].clone();
                let slip_row = if tresca { Some(&trow[i]) } else { None };
                if let Some(TangentialRow::Slip { l, r: rt }) = slip_row {
                    // slip: τᵀ(A u)_k + L̃ τᵀ u^k = τᵀ f_k + r̃  (3.39a)
                    let t = &k.frame.t;
                    for a in 0..dim {
                        for b in 0..dim {
                            for (ii, ti) in t[..dim - 1].iter().enumerate() {
                                for (jj, tj) in t[..dim - 1].iter().enumerate() {
                                    me.spring[a][b] += ti[a] * l[ii][jj] * tj[b];
                                }
                            }
                        }
                        for (ii, ti) in t[..dim - 1].iter().enumerate() {
                            me.spring_rhs[a] += ti[a] * rt[ii];
                        }
                    }
                }
                writes.push((r, me, k.local_row));
            }
            for (v, r) in &pin_rows {
                let gv = layout.node_global[*v];
                writes.push((r, cmap[&gv].clone(), gv * dim - row_lo));
            }
            for (r, me, lr) in &writes {
                let fk = &f_local[*lr..*lr + dim];
                let rk = write_symmetric_constraint(
                    &mut s,
                    r,
                    me,
                    fk,
                    dim,
                    |j| cmap.get(&j),
                    &mut rhs_add,
                    &mut buf,
                )?;
                for (a, v) in rk.iter().enumerate().take(dim) {
                    rhs_updates.push((lr + a, *v));
                }
            }
            let (idx, vals): (Vec<PInt>, Vec<f64>) = rhs_add.into_iter().unzip();
            rhs.set_values(&idx, &vals, true)?;
            rhs.assemble()?;
        }
        s.assemble()?;
        rhs.write(|x| {
            for &(i, v) in &rhs_updates {
                x[i] = v;
            }
        })?;
        rows_seconds += t_rows.elapsed().as_secs_f64();

        let t_solve = Instant::now();
        ls.ksp.set_operator(&s)?;
        let info = ls.solve(&rhs, &mut u)?;
        let solve_seconds = t_solve.elapsed().as_secs_f64();
        if !info.converged() {
            return Err(RunError::Failed(format!(
                "Newton step {step}: the linear solver did not converge ({} after {} iterations)",
                info.reason_name, info.iterations
            )));
        }

        // (3.28): λ = f − A u on the contact rows.
        let t_l = Instant::now();
        sys.a.mult(&u, &mut au)?;
        let u_local = u.to_local_vec()?;
        let au_local = au.to_local_vec()?;
        let mut changed = 0usize;
        let mut new_active = active.clone();
        let mut new_trow = trow.clone();
        let mut res2 = 0.0;
        let mut counts = [0.0f64; 4];
        for (i, k) in cs.nodes.iter().enumerate() {
            let mut uk = [0.0; 3];
            let mut lk = [0.0; 3];
            for j in 0..dim {
                uk[j] = u_local[k.local_row + j];
                lk[j] = f_local[k.local_row + j] - au_local[k.local_row + j];
            }
            let u_n = k.frame.normal_part(&uk);
            let l_n = k.frame.normal_part(&lk);
            let u_t = k.frame.tangential_part(&uk);
            let l_t = k.frame.tangential_part(&lk);
            let slip = tresca && trow[i].is_slip();
            nodes[i] = NodeResult {
                u: uk,
                lambda: lk,
                u_n,
                u_t,
                lambda_n: l_n,
                lambda_t: l_t,
                active: active[i],
                slip,
            };
            counts[active[i] as usize * 2 + slip as usize] += 1.0;
            // (3.23)
            new_active[i] = contact::normal_active(u_n, l_n, k.gap, c);
            let mut flip = new_active[i] != active[i];
            let cn = contact::c_n(u_n, l_n, k.gap, c);
            res2 += cn * cn;
            if tresca {
                // (3.33) with the newest iterate (THEORY §4 erratum), and the next slip row.
                new_trow[i] = contact::tangential_row_dyn(dim, u_t, l_t, k.bound, c);
                flip |= new_trow[i].is_slip() != slip;
                let ct = contact::c_tau(&u_t, &l_t, k.bound, c);
                res2 += ct[0] * ct[0] + ct[1] * ct[1];
            }
            if flip {
                changed += 1;
            }
        }
        // ‖u^ℓ − u^{ℓ−1}‖² and ‖u^ℓ‖² (Algorithm 2's stopping rule).
        let (mut du2, mut uu) = (0.0, 0.0);
        if tresca {
            for (x, y) in u_local.iter().zip(&u_prev) {
                du2 += (x - y) * (x - y);
                uu += x * x;
            }
            u_prev.copy_from_slice(&u_local);
        }
        lambda_seconds += t_l.elapsed().as_secs_f64();

        // One Allreduce: changes, |A|, fingerprints, residual², state counts, ‖Δu‖², ‖u‖²,
        // Gram matrix of the new set.
        let (h1, h2) = fp(&new_active, &new_trow);
        let mut local = vec![
            changed as f64,
            new_active.iter().filter(|&&a| a).count() as f64,
            h1,
            h2,
            res2,
            counts[0],
            counts[1],
            counts[2],
            counts[3],
            du2,
            uu,
        ];
        local.extend(active_gram(&new_active, &new_trow));
        let mut global = vec![0.0f64; local.len()];
        ctx.world
            .all_reduce_into(&local[..], &mut global[..], SystemOperation::sum());
        let changed_g = global[0] as usize;
        let du_rel = if global[10] > 0.0 {
            (global[9] / global[10]).sqrt()
        } else {
            0.0
        };
        let u_print = if tresca {
            format!("{:.9e}", global[10]).parse::<f64>().unwrap_or(0.0)
        } else {
            0.0
        };
        let info_step = StepInfo {
            step,
            active: n_active_global,
            changed: changed_g,
            residual: global[4].sqrt(),
            solve_seconds,
            iterations: info.iterations,
            pinned: pins.len(),
            states: tresca.then(|| [0, 1, 2, 3].map(|j| global[5 + j] as usize)),
            du_rel: tresca.then_some(du_rel),
        };
        say!(
            ctx,
            "newton {:3}: |A_n| = {:6}  changed {:6}  |C_n| = {:.3e}  pinned {}  solve {:.3} s ({} its)",
            step,
            info_step.active,
            info_step.changed,
            info_step.residual,
            info_step.pinned,
            solve_seconds,
            info.iterations
        );
        if tresca {
            say!(
                ctx,
                "            S1 {} S2 {} S3 {} S4 {}  |du|/|u| = {:.3e}",
                global[5],
                global[6],
                global[7],
                global[8],
                du_rel
            );
        }
        history.push(info_step);
        if changed_g == 0 && !pins.is_empty() {
            // A free rigid mode is harmless only if the load is balanced in it (the pins then
            // carry no reaction). If not, the body moves along the unbalanced load until a
            // contact node touches: activate the first one to touch and go on; if no node
            // approaches the obstacle, there is no equilibrium.
            match unbalanced_mode_contact(
                ctx, mesh, layout, cs, &modes, &q_free, &pins, &f_local, &au_local, &nodes,
                &active, row_lo, fmax,
            ) {
                Balance::Balanced => {}
                Balance::Touch(tag) => {
                    for (k, a) in cs.nodes.iter().zip(new_active.iter_mut()) {
                        if k.tag == tag {
                            *a = true;
                        }
                    }
                    say!(
                        ctx,
                        "newton: the load is not balanced in a free rigid mode: the body moves \
                         until contact node {tag} touches (activated)"
                    );
                    let (k2, g2) = set_summary(&new_active, &new_trow);
                    seen.push((k2.0, k2.1, k2.2, u_print));
                    active = new_active;
                    trow = new_trow;
                    n_active_global = k2.0;
                    g_act.copy_from_slice(&g2);
                    continue;
                }
                Balance::NoSupport(reaction) => {
                    return Err(RunError::Failed(format!(
                        "no support: the body has {} rigid mode(s) fixed neither by Dirichlet \
                         data nor by contact ({} active contact node(s)), the load is not \
                         balanced in them (unbalanced load {:.3e} against a largest nodal load \
                         of {:.3e}) and moving along it brings no contact node closer to the \
                         obstacle: there is no equilibrium — add Dirichlet data or move the \
                         obstacle into the body's way",
                        pins.len(),
                        n_active_global,
                        reaction,
                        fmax
                    )));
                }
            }
        }
        if changed_g == 0 {
            if !tresca || du_rel < settings.tol_u {
                converged = true;
                break;
            }
            // Same sets, but the slip rows are a linearisation: iterate on.
            trow = new_trow;
            continue;
        }
        let mut key = (global[1] as usize, global[2], global[3], u_print);
        if !least_index {
            if let Some(prev) = seen.iter().position(|s| *s == key) {
                if tresca || settings.on_cycle == OnCycle::Stop {
                    return Err(cycling_error(step + 1, key.0, prev + 1, tresca, false));
                }
                least_index = true;
                cycle_detected_at = Some(step + 1);
                // The safeguarded sequence may pass through sets of the plain iteration again.
                let current = *seen.last().expect("the current set is recorded");
                seen.clear();
                seen.push(current);
                say!(
                    ctx,
                    "newton: cycling detected (the set of step {} recurs at step {}): continuing \
                     with single-node updates (penetrating nodes first, least index first)",
                    prev + 1,
                    step + 1
                );
            }
        }
        if least_index {
            // Single-node updates: activate the penetrating node with the smallest tag; only
            // if none penetrates, release the node in tension with the smallest tag (a
            // least-index rule in the spirit of Murty's, biased towards sets that hold the
            // body, since sets that leave rigid modes to the pins are not LCP pivots).
            let pick = |want_activate: bool| -> u64 {
                let my_min = cs
                    .nodes
                    .iter()
                    .zip(active.iter().zip(&new_active))
                    .filter(|(_, (a, b))| a != b && **b == want_activate)
                    .map(|(k, _)| k.tag)
                    .min()
                    .unwrap_or(u64::MAX);
                let mut tag = 0u64;
                ctx.world
                    .all_reduce_into(&my_min, &mut tag, SystemOperation::min());
                tag
            };
            let mut tag = pick(true);
            if tag == u64::MAX {
                tag = pick(false);
            }
            for ((k, a), b) in cs
                .nodes
                .iter()
                .zip(active.iter())
                .zip(new_active.iter_mut())
            {
                *b = if k.tag == tag { !*a } else { *a };
            }
            let (k2, g2) = set_summary(&new_active, &new_trow);
            key = (k2.0, k2.1, k2.2, u_print);
            g_act.copy_from_slice(&g2);
            if let Some(prev) = seen.iter().position(|s| *s == key) {
                return Err(cycling_error(step + 1, key.0, prev, false, true));
            }
        } else {
            g_act.copy_from_slice(&global[11..11 + 36]);
        }
        seen.push(key);
        active = new_active;
        trow = new_trow;
        n_active_global = key.0;
    }
    let steps = history.len();
    Ok(NewtonResult {
        u,
        nodes,
        history,
        converged,
        steps,
        lambda_seconds,
        rows_seconds,
        pinned_final: pins,
        cycle_detected_at,
        c,
    })
}
