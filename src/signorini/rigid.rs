//! Rigid body modes that neither Dirichlet data nor the current sets fix (docs/method.md;
//! thesis 4.1, where V*_h removes only the tangential translation).
//!
//! Mechanism: the rigid modes r_1..r_M of the bodies that Dirichlet data leave free (m = 3 in
//! 2D, 6 in 3D per body; [`BodyModes`], in the solver's unknowns: a body pair's slave node
//! sees a master body's mode through its mortar row) are tested against the constraint rows — every Dirichlet dof, the normal row nᵀ of every active contact node and,
//! with friction, the tangent rows τᵀ of nodes whose tangential row holds u_τ — through the
//! M×M Gram matrix G = Σ (C r)ᵀ (C r). Its null space is exactly the set of free modes: no
//! fewer are removed (the system would be singular) and no more (that would change the
//! answer). Each free mode is removed by pinning one dof, eliminated symmetrically like the
//! contact constraints (step_system/). The pinned dofs are chosen from the whole mesh by a
//! pivoted Gram–Schmidt on the free modes' values, away from the contact boundary and the
//! Dirichlet data, identically on every rank (so the result does not depend on the number of
//! ranks). Pinning selects one member of the family u + Σ α_j r_j, which all have the same
//! strains, stresses and multipliers. If the load is not balanced in a free mode, the body is
//! moved along the unbalanced load until the first contact node touches ([`Balance::Touch`]);
//! if no node approaches the obstacle there is no equilibrium ([`Balance::NoSupport`]).
//!
//! The balance test reads the load, not the iterate: the reaction the pins carry is, in exact
//! arithmetic, the load's component in the free modes, φ = Qᵀ Rᵀ f (A R = 0 for P1 elements,
//! Dirichlet data eliminated symmetrically keep it so, and every other row either holds a
//! constraint the free modes do not move or is an equilibrium row). Computed from u, as
//! Qᵀ Rᵀ (f − A u) at the pins, it is the sum of every other row's solver residual: rounding of
//! order ε‖A‖‖u‖·√n when u carries a large rigid motion (an obstacle far below the body), or
//! the Krylov tolerance of the iterative preset — both produced false "no support" diagnoses.

use super::boundary::{CaseKeys, ContactBoundary, ContactNode, NodeResult};
use crate::case;
use crate::error::RunError;
use crate::mesh::Mesh;
use crate::par::Ctx;
use crate::partition::Layout;
use nalgebra::{DMatrix, SymmetricEigen};
use std::sync::Arc;

/// The M×M Gram matrix of a set of rows against the modes (row-major; M = [`BodyModes::count`]).
pub type Gram = Vec<f64>;

/// One pinned dof: (global node number, component).
pub type Pin = (usize, usize);

pub use crate::mesh::BodyModes;

impl BodyModes {
    /// Chooses one dof per free mode: among the owned nodes allowed by `candidate`, greedily
    /// the dof whose free-mode values are largest after removing the directions already
    /// pinned (pivoted Gram–Schmidt); each step picks the largest over the ranks (near ties:
    /// the lowest mesh-order node). Returns (global node, component) and the node's
    /// coordinates and body slot, the same on every rank. Collective.
    pub fn pins(
        &self,
        ctx: &Ctx,
        mesh: &Mesh,
        layout: &Layout,
        q: &DMatrix<f64>,
        candidate: impl Fn(usize) -> bool,
    ) -> Vec<PinAt> {
        let mf = q.ncols();
        if mf == 0 {
            return Vec::new();
        }
        let dim = self.dim;
        let m = self.count();
        // Values of the free modes at every owned candidate dof (mesh order).
        let mut dofs: Vec<(usize, usize)> = Vec::new();
        let mut w: Vec<f64> = Vec::new();
        for v in 0..mesh.n_nodes() {
            if !layout.owns_node(v) || !candidate(v) {
                continue;
            }
            for k in 0..dim {
                let row = self.dof_row(v, &mesh.coords[v], k);
                dofs.push((v, k));
                for c in 0..mf {
                    w.push((0..m).map(|j| row[j] * q[(j, c)]).sum());
                }
            }
        }
        let mut chosen = Vec::new();
        let rec_len = 8 + mf;
        for _ in 0..mf {
            let mut best = (0.0f64, usize::MAX);
            for i in 0..dofs.len() {
                let n2: f64 = w[i * mf..(i + 1) * mf].iter().map(|x| x * x).sum();
                if n2 > best.0 * (1.0 + 1e-12) {
                    best = (n2, i);
                }
            }
            // [n2, mesh-order node, k, global node, x, y, z, slot, free-mode values (mf)]
            let mut rec = vec![0.0f64; rec_len];
            if best.1 != usize::MAX {
                let (v, k) = dofs[best.1];
                let x = mesh.coords[v];
                rec[..8].copy_from_slice(&[
                    best.0,
                    layout.node_orig[v] as f64,
                    k as f64,
                    layout.node_global[v] as f64,
                    x[0],
                    x[1],
                    x[2],
                    f64::from(self.slot_of(v)),
                ]);
                rec[8..8 + mf].copy_from_slice(&w[best.1 * mf..(best.1 + 1) * mf]);
            }
            let all = ctx.all_gather_varcount(&rec);
            let top = all
                .chunks_exact(rec_len)
                .map(|r| r[0])
                .fold(0.0f64, f64::max);
            let Some(win) = all
                .chunks_exact(rec_len)
                .filter(|r| r[0] > 0.0 && r[0] * (1.0 + 1e-12) >= top)
                .min_by(|a, b| (a[1], a[2]).partial_cmp(&(b[1], b[2])).expect("finite"))
            else {
                break;
            };
            if win[0] < 1e-20 {
                break;
            }
            chosen.push(PinAt {
                pin: (win[3] as usize, win[2] as usize),
                x: [win[4], win[5], win[6]],
                slot: win[7] as u32,
            });
            let pn = win[0].sqrt();
            let p: Vec<f64> = win[8..8 + mf].iter().map(|x| x / pn).collect();
            for r in 0..dofs.len() {
                let s: f64 = (0..mf).map(|c| w[r * mf + c] * p[c]).sum();
                for c in 0..mf {
                    w[r * mf + c] -= s * p[c];
                }
            }
        }
        chosen
    }
}

/// A pinned dof where it is: the pin, the node's coordinates and its body's slot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PinAt {
    pub pin: Pin,
    pub x: [f64; 3],
    pub slot: u32,
}

impl PinAt {
    /// The pin's row over the modes (a non-slave node: its own body's modes only).
    fn row(&self, modes: &BodyModes) -> Vec<f64> {
        let mut e = [0.0; 3];
        e[self.pin.1] = 1.0;
        modes.row_of_slot(self.slot, &self.x, &e)
    }
}

/// A rigid motion Σ_j ρ_j r_j, by its mode coefficients (M entries).
pub type Motion = Vec<f64>;

/// Outcome of the load-balance test of the free rigid modes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Balance {
    Balanced,
    /// Activate the contact node with this gmsh tag (the first to touch).
    Touch(u64),
    /// No equilibrium; the size of the unbalanced load.
    NoSupport(f64),
}

/// Force control on a floating body (force.rs): a force-controlled pair's approach δ_j tied
/// to the body's rigid modes by the set's rows on that pair. A held row cᵀu_k = cᵀ(u_ref) + δ_j
/// (c·e_j) of the pair (c the normal of an active node or a held tangent) keeps holding under
/// the rigid motion ρ with the approach δ_j + cᵀρ(x_k)/(c·e_j); in the least-squares sense over
/// the pair's rows, δ_j(ρ) = bᵀρ / s with b = Σ_rows (c·e_j) a_row and s = Σ_rows (c·e_j)²,
/// a_row the row's values on the rigid modes ([`FreeModes::row`]).
#[derive(Clone, Debug)]
pub struct ApproachCoupling {
    /// b (M entries).
    pub b: Vec<f64>,
    /// s > 0 (a pair without held rows has no coupling).
    pub s: f64,
    /// |F_j|: the load the prescribed force puts on the mode (with δ_j(ρ) as its work).
    pub magnitude: f64,
    /// e_j.
    pub dir: [f64; 3],
    /// The pair.
    pub pair: usize,
}

/// The rigid modes left free by Dirichlet data and the current sets, and the dofs pinned to
/// remove them.
#[derive(Clone)]
pub struct FreeModes {
    modes: Arc<BodyModes>,
    enabled: bool,
    /// Gram matrix of the Dirichlet dofs (fixed for the whole run).
    g_dirichlet: Gram,
    /// The Gram matrix the current pins were chosen for.
    key: Option<Gram>,
    /// Basis of the free modes (M × m_f).
    q: DMatrix<f64>,
    /// Basis of the modes Dirichlet data leave free (M × m_z): the room of the rigid motion
    /// taken out of the solve ([`FreeModes::fit_motion`]).
    z: DMatrix<f64>,
    pins: Vec<Pin>,
    /// Where the pinned nodes are.
    pin_at: Vec<PinAt>,
    /// Nodes allowed as pins: off the contact boundary, without Dirichlet data.
    candidate: Vec<bool>,
    /// The load in every rigid mode, Rᵀ f (summed over the ranks; M entries).
    load: Vec<f64>,
    /// Σ_i |f_i| ‖R_i‖ over all dofs i: the size of the terms that cancel in `load`, the scale
    /// of the balance test.
    load_scale: f64,
    /// Force control on a floating body: the approaches the set ties to the rigid modes
    /// ([`FreeModes::couple`]); empty otherwise.
    coupling: Vec<ApproachCoupling>,
    /// The case file and keys its diagnoses name.
    keys: CaseKeys,
}

/// An unbalanced load in the free modes below this fraction of `load_scale` is balanced: the
/// sum Rᵀ f itself is exact to about √n·ε of it, far below (also the dense steps' balance,
/// dense.rs, and Coulomb's unheld load, coulomb.rs).
pub const BALANCE_RTOL: f64 = 1e-10;

impl FreeModes {
    /// Collective (two reductions).
    pub fn new(
        ctx: &Ctx,
        mesh: &Mesh,
        layout: &Layout,
        fixed: &[f64],
        b: &ContactBoundary,
        f_local: &[f64],
        setting: case::RigidModeHandling,
    ) -> FreeModes {
        let dim = mesh.dim;
        let modes = b.modes.clone();
        let mm = modes.count();
        let enabled = setting == case::RigidModeHandling::Auto;
        let mut g_dirichlet = modes.zero_gram();
        if enabled && mm > 0 {
            for &v in &layout.owned_nodes {
                for k in 0..dim {
                    if !fixed[v * dim + k].is_nan() {
                        let row = modes.dof_row(v, &mesh.coords[v], k);
                        modes.add_outer(&mut g_dirichlet, &row);
                    }
                }
            }
            g_dirichlet = ctx.sum_vec(&g_dirichlet);
        }
        // Rᵀ f and its scale over the owned rows (owned node i holds rows i·d .. i·d + d).
        let mut local = vec![0.0; mm + 1];
        for (i, &v) in layout.owned_nodes.iter().enumerate() {
            for k in 0..dim {
                let f = f_local[i * dim + k];
                if f == 0.0 || mm == 0 {
                    continue;
                }
                let row = modes.dof_row(v, &mesh.coords[v], k);
                for j in 0..mm {
                    local[j] += row[j] * f;
                }
                local[mm] += f.abs() * row.iter().map(|x| x * x).sum::<f64>().sqrt();
            }
        }
        let total = ctx.sum_vec(&local);
        let load = total[..mm].to_vec();
        let candidate = (0..mesh.n_nodes())
            .map(|v| !b.on_contact_boundary[v] && (0..dim).all(|k| fixed[v * dim + k].is_nan()))
            .collect();
        let z = if enabled {
            modes.free_modes(&g_dirichlet)
        } else {
            DMatrix::zeros(mm, 0)
        };
        FreeModes {
            q: DMatrix::zeros(mm, 0),
            z,
            modes,
            enabled,
            g_dirichlet,
            key: None,
            pins: Vec::new(),
            pin_at: Vec::new(),
            candidate,
            load,
            load_scale: total[mm],
            coupling: Vec::new(),
            keys: b.keys.clone(),
        }
    }

    /// Counts the rows of `g_set` (the Gram matrix of a set of contact normals, summed over
    /// the ranks) as Dirichlet data: the condensed path's nodes held on their obstacle in the
    /// factorised matrix. The free modes, their basis Z and the pins are then those of
    /// Dirichlet data and that set. Local.
    pub fn hold_also(&mut self, g_set: &Gram) {
        if !self.enabled {
            return;
        }
        for (x, y) in self.g_dirichlet.iter_mut().zip(g_set) {
            *x += y;
        }
        self.z = self.modes.free_modes(&self.g_dirichlet);
        self.key = None;
        self.q = DMatrix::zeros(self.modes.count(), 0);
        self.pins.clear();
        self.pin_at.clear();
    }

    /// True when rigid-mode handling is on and Dirichlet data leave some rigid mode free.
    pub fn floats(&self) -> bool {
        self.enabled && self.z.ncols() > 0
    }

    /// The modes to test sets against (`None` when rigid-mode handling is off).
    pub fn modes(&self) -> Option<&BodyModes> {
        self.enabled.then_some(&*self.modes)
    }

    pub fn pins(&self) -> &[Pin] {
        &self.pins
    }

    /// Basis of the modes Dirichlet data leave free (M × m_z, orthonormal columns; no
    /// columns with rigid-mode handling off).
    pub fn dirichlet_free(&self) -> &DMatrix<f64> {
        &self.z
    }

    /// The rigid modes (also with handling off: then nothing is free).
    pub fn rigid_modes(&self) -> &BodyModes {
        &self.modes
    }

    /// The number of modes M.
    pub fn count(&self) -> usize {
        self.modes.count()
    }

    /// No motion (M zeros).
    pub fn no_motion(&self) -> Motion {
        vec![0.0; self.count()]
    }

    /// The load in every rigid mode, Rᵀ f (M entries), and its scale Σ|f_i|‖R_i‖.
    pub fn load(&self) -> (&[f64], f64) {
        (&self.load, self.load_scale)
    }

    /// The row cᵀ w of contact node `k` over the modes (c a normal or a tangent at k).
    pub fn row(&self, k: &ContactNode, c: &[f64; 3]) -> Vec<f64> {
        self.modes.direction_row(k.node, &k.x, c)
    }

    /// The Dirichlet-free modes' parts of the row cᵀ w at contact node `k` (c its normal or a
    /// tangent): the row times Z (Z.ncols() entries; a row of G in the condensed systems).
    pub fn normal_parts(&self, k: &ContactNode, c: &[f64; 3]) -> Vec<f64> {
        let z = &self.z;
        let row = self.row(k, c);
        (0..z.ncols())
            .map(|col| (0..row.len()).map(|j| row[j] * z[(j, col)]).sum())
            .collect()
    }

    /// The load in the Dirichlet-free modes, φ = Zᵀ (Rᵀ f) (one entry per column of Z).
    pub fn free_load(&self) -> Vec<f64> {
        (0..self.z.ncols())
            .map(|c| {
                (0..self.count())
                    .map(|j| self.z[(j, c)] * self.load[j])
                    .sum()
            })
            .collect()
    }

    /// Force control on a floating body (docs/obstacles.md, "Force control on a body that only
    /// its pairs hold"): the approaches δ_j are more free modes next to the body's, each held
    /// row of a force-controlled pair reading [a_row, −(c·e_j)] on (ρ, δ_j). The body's part of
    /// the extended free modes is the null space of the Gram matrix with the δ's eliminated,
    /// G − Σ_j b_j b_jᵀ / s_j ([`ApproachCoupling`]), returned for [`FreeModes::update`]; the
    /// couplings are kept for the balance test (the prescribed forces are loads of the extended
    /// modes). A pair without held rows is not coupled: its δ_j alone is free, and force.rs
    /// moves it until its first node touches. Local.
    pub fn couple(&mut self, g_set: &Gram, coupling: Vec<ApproachCoupling>) -> Gram {
        let m = self.count();
        let mut g = g_set.clone();
        for c in &coupling {
            for a in 0..m {
                for b in 0..m {
                    g[a * m + b] -= c.b[a] * c.b[b] / c.s;
                }
            }
        }
        self.coupling = coupling;
        g
    }

    /// The approach δ_j per unit rigid motion `coef` (mode coefficients) of the coupled pair
    /// `pair`, 0 for the other pairs: δ_j(ρ) = bᵀρ / s ([`ApproachCoupling`]). Pure.
    fn approach_of(&self, coef: &[f64], pair: usize) -> Option<(f64, [f64; 3])> {
        let c = self.coupling.iter().find(|c| c.pair == pair)?;
        let d: f64 = (0..self.count()).map(|j| c.b[j] * coef[j]).sum::<f64>() / c.s;
        Some((d, c.dir))
    }

    /// The load in the free modes, φ = Qᵀ (Rᵀ f + Σ_j |F_j| b_j / s_j) (the prescribed forces
    /// do the work |F_j| δ_j(ρ) on a free extended mode), and the balance test's scale, the
    /// load's Σ|f_i|‖R_i‖ plus Σ_j |F_j| ‖b_j‖ / s_j. Pure.
    fn free_mode_load(&self) -> (Vec<f64>, f64) {
        let (m, q) = (self.count(), &self.q);
        let mut load = self.load.clone();
        let mut scale = self.load_scale;
        for c in &self.coupling {
            for (l, b) in load.iter_mut().zip(&c.b).take(m) {
                *l += c.magnitude * b / c.s;
            }
            scale += c.magnitude * c.b.iter().map(|x| x * x).sum::<f64>().sqrt() / c.s;
        }
        let g = (0..q.ncols())
            .map(|col| (0..m).map(|j| q[(j, col)] * load[j]).sum())
            .collect();
        (g, scale)
    }

    /// New pins when the Gram matrix of Dirichlet data + the set (`g_set`) changed; `Ok(true)`
    /// if the pins changed. Collective when they change (the same on every rank).
    pub fn update(
        &mut self,
        ctx: &Ctx,
        mesh: &Mesh,
        layout: &Layout,
        g_set: &Gram,
    ) -> Result<bool, RunError> {
        if !self.enabled {
            return Ok(false);
        }
        let mut g = self.g_dirichlet.clone();
        for (x, y) in g.iter_mut().zip(g_set) {
            *x += y;
        }
        if self.key.as_ref() == Some(&g) {
            return Ok(false);
        }
        let q = self.modes.free_modes(&g);
        let pins = self
            .modes
            .pins(ctx, mesh, layout, &q, |v| self.candidate[v]);
        if pins.len() < q.ncols() {
            return Err(RunError::Failed(format!(
                "{}: {} free rigid mode(s) but only {} dof(s) available to fix them (nodes off \
                 the contact boundary without Dirichlet data): hold the body by Dirichlet data \
                 or leave nodes off the contact group",
                self.keys.named(&["dirichlet", ".group", ".rigid_modes"]),
                q.ncols(),
                pins.len()
            )));
        }
        self.key = Some(g);
        self.q = q;
        self.pins = pins.iter().map(|p| p.pin).collect();
        self.pin_at = pins;
        Ok(true)
    }

    /// Pins for a solver that keeps them for the whole solve (SNES VI): the modes that neither
    /// Dirichlet data nor the whole contact boundary (every contact normal) can fix. Collective.
    pub fn update_for_whole_boundary(
        &mut self,
        ctx: &Ctx,
        mesh: &Mesh,
        layout: &Layout,
        b: &ContactBoundary,
    ) -> Result<&[Pin], RunError> {
        let mut g = self.modes.zero_gram();
        if self.enabled {
            for k in &b.nodes {
                self.modes.add_outer(&mut g, &self.row(k, &k.frame.n));
            }
            g = ctx.sum_vec(&g);
        }
        self.update(ctx, mesh, layout, &g)?;
        Ok(&self.pins)
    }

    /// The unbalanced load in the free rigid modes, φ = Qᵀ Rᵀ f (what the pins carry, see the
    /// module note), and, if it is not zero against the load's scale, the inactive contact
    /// node that a rigid motion along φ brings into contact first (smallest gap / closing
    /// speed; ties by tag). `nodes` the iterate at the contact nodes, `active` their A_n
    /// membership in its solve. Collective only when the load is unbalanced (the same on every
    /// rank: φ is summed once, in `new`).
    pub fn balance(
        &self,
        ctx: &Ctx,
        b: &ContactBoundary,
        nodes: &[NodeResult],
        active: &[bool],
    ) -> Balance {
        let (mm, q) = (self.count(), &self.q);
        let mf = q.ncols();
        let (g, scale) = self.free_mode_load();
        let norm = g.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm <= BALANCE_RTOL * scale {
            return Balance::Balanced;
        }
        // Motion per unit α in mode coefficients: Q φ / |φ|.
        let coef: Vec<f64> = (0..mm)
            .map(|j| (0..mf).map(|c| q[(j, c)] * g[c]).sum::<f64>() / norm)
            .collect();
        let mut best = (f64::INFINITY, u64::MAX);
        for ((k, r), &a) in b.nodes.iter().zip(nodes).zip(active) {
            if a {
                continue;
            }
            let nr = self.row(k, &k.frame.n);
            let mut speed = -(0..mm).map(|j| nr[j] * coef[j]).sum::<f64>();
            if let Some((delta, e)) = self.approach_of(&coef, k.pair) {
                // the coupled obstacle moves with the body: its gap closes by δ_j (n·e_j)
                speed += delta * crate::geom::dot(k.frame.n, e);
            }
            if speed <= 1e-12 {
                continue;
            }
            let alpha = (r.u_n + k.gap).max(0.0) / speed;
            if alpha < best.0 || (alpha == best.0 && k.tag < best.1) {
                best = (alpha, k.tag);
            }
        }
        let amin = ctx.min_f64(best.0);
        if !amin.is_finite() {
            return Balance::NoSupport(norm);
        }
        let mine = if best.0 <= amin * (1.0 + 1e-12) {
            best.1
        } else {
            u64::MAX
        };
        Balance::Touch(ctx.min_u64(mine))
    }

    /// The rigid motion ρ that the frictionless solve is relieved of (u = ρ + w, the solve
    /// sees the gaps after ρ, [`FreeModes::shift`]): among the motions Dirichlet data leave free,
    /// the least-squares fit of the active nodes' prescribed normal displacements
    /// nᵀρ(x_k) = −g_k (3.29), then moved by a free mode of the set (which no constraint sees)
    /// to vanish at the pins. In exact arithmetic this changes nothing; in floating point the
    /// solve no longer carries a large rigid motion (a body far from the obstacle, moved to it
    /// by [`Balance::Touch`] or started all-active), whose rounding, ε‖A‖|g| in every row,
    /// would exceed the elastic part's accuracy. Zero with rigid-mode handling off. `g_set` is
    /// the Gram matrix of the active normals (the set summary). Collective (one reduction).
    pub fn fit_motion(
        &self,
        ctx: &Ctx,
        b: &ContactBoundary,
        active: &[bool],
        g_set: &Gram,
        _mesh: &Mesh,
    ) -> Motion {
        let m = self.count();
        let mut local = vec![0.0; m];
        for (k, _) in b.nodes.iter().zip(active).filter(|(_, &a)| a) {
            let row = self.row(k, &k.frame.n);
            for (l, r) in local.iter_mut().zip(row) {
                *l -= r * k.gap;
            }
        }
        let rhs = ctx.sum_vec(&local);
        let mut rho = self.no_motion();
        if !self.enabled || self.z.ncols() == 0 {
            return rho;
        }
        // Normal equations on the Dirichlet-free modes, solved by the pseudo-inverse (the set's
        // free modes are its null space).
        let z = &self.z;
        let gm = DMatrix::from_row_slice(m, m, &g_set[..m * m]);
        let mz = z.transpose() * &gm * z;
        let rz = z.transpose() * nalgebra::DVector::from_column_slice(&rhs[..m]);
        let eig = SymmetricEigen::new(mz);
        let lmax = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        let mut c = nalgebra::DVector::zeros(z.ncols());
        for (i, &l) in eig.eigenvalues.iter().enumerate() {
            if l > 1e-9 * lmax {
                let v = eig.eigenvectors.column(i);
                c += v * (v.dot(&rz) / l);
            }
        }
        let r = z * c;
        rho[..m].copy_from_slice(r.as_slice());
        // Zero at the pins: ρ minus the free-mode motion with ρ's values there.
        let at: Vec<f64> = (self.pin_at.iter())
            .map(|p| {
                let row = p.row(&self.modes);
                (0..m).map(|j| row[j] * rho[j]).sum()
            })
            .collect();
        if let Some(corr) = self.motion_with_pin_values(&at) {
            for (x, d) in rho.iter_mut().zip(corr.iter()) {
                *x -= d;
            }
        }
        rho
    }

    /// Q α with (pin rows of Q) α = `at`: the motion in the free modes Q that takes the values
    /// `at` at the pins (in the order of [`FreeModes::pins`]). `None` without free modes, with
    /// a pin count other than theirs, or singular. Local.
    fn motion_with_pin_values(&self, at: &[f64]) -> Option<nalgebra::DVector<f64>> {
        let (m, mf) = (self.count(), self.q.ncols());
        if mf == 0 || self.pins.len() != mf || at.len() != mf {
            return None;
        }
        let mut p = DMatrix::zeros(mf, mf);
        for (a, pin) in self.pin_at.iter().enumerate() {
            let row = pin.row(&self.modes);
            for cc in 0..mf {
                p[(a, cc)] = (0..m).map(|j| row[j] * self.q[(j, cc)]).sum();
            }
        }
        let alpha = p.lu().solve(&nalgebra::DVector::from_column_slice(at))?;
        Some(&self.q * alpha)
    }

    /// The motion in the current free modes that, added to a displacement whose pinned dofs
    /// hold `at_pins` (in the order of [`FreeModes::pins`]), makes it vanish there: the
    /// normalisation the plain path's pins give the modes that nothing fixes. Local.
    pub fn motion_to_zero_pins(&self, at_pins: &[f64], before: &Motion) -> Motion {
        let mut rho = self.no_motion();
        let at: Vec<f64> = (at_pins.iter().zip(&self.pin_at))
            .map(|(&u, p)| {
                let row = p.row(&self.modes);
                u + row.iter().zip(before).map(|(a, b)| a * b).sum::<f64>()
            })
            .collect();
        if let Some(corr) = self.motion_with_pin_values(&at) {
            for (x, d) in rho.iter_mut().zip(corr.iter()) {
                *x = -d;
            }
        }
        rho
    }

    /// Component k of the rigid motion `rho` in the unknowns of local node v at x.
    pub fn motion_at(&self, rho: &Motion, v: usize, x: &[f64; 3], k: usize) -> f64 {
        self.modes.motion_at(rho, v, x, k)
    }

    /// The gaps after the rigid motion `rho` (g_k + nᵀρ(x_k): what (3.23) and (3.29) see for
    /// w = u − ρ) into `shifted`, a copy of `b`. Local.
    pub fn shift(&self, b: &ContactBoundary, rho: &Motion, shifted: &mut ContactBoundary) {
        for (k, s) in b.nodes.iter().zip(shifted.nodes.iter_mut()) {
            let row = self.row(k, &k.frame.n);
            let nr: f64 = row.iter().zip(rho).map(|(a, b)| a * b).sum();
            s.gap = k.gap + nr;
        }
    }

    /// Whether the load is balanced in every free mode (the pins would carry no reaction:
    /// the test of [`FreeModes::balance`] before it looks for a touching node). Local.
    pub fn balanced(&self) -> bool {
        let (g, scale) = self.free_mode_load();
        let norm = g.iter().map(|g| g * g).sum::<f64>().sqrt();
        norm <= BALANCE_RTOL * scale
    }

    /// The free modes as fields on this rank's rows (`row_lo` its first global row, `n_local`
    /// its row count): one vector per column of the free-mode basis. Local.
    pub fn free_fields(
        &self,
        mesh: &Mesh,
        layout: &Layout,
        row_lo: usize,
        n_local: usize,
    ) -> Vec<Vec<f64>> {
        let (dim, m) = (mesh.dim, self.count());
        let mut fields = vec![vec![0.0; n_local]; self.q.ncols()];
        for &v in &layout.owned_nodes {
            for k in 0..dim {
                let r = layout.node_global[v] * dim + k - row_lo;
                let row = self.modes.dof_row(v, &mesh.coords[v], k);
                for (c, f) in fields.iter_mut().enumerate() {
                    f[r] = (0..m).map(|j| self.q[(j, c)] * row[j]).sum();
                }
            }
        }
        fields
    }

    /// Whether the contact can carry no force in the rigid modes that Dirichlet data leave
    /// free: there are such modes, the load has no component in them, and the contact normals
    /// of every contact node (any set) push the body from one side only in them — each node's
    /// normal row on those modes a_k = Zᵀ R(x_k)ᵀ n_k has a positive product with one common
    /// direction (the sum of the rows, or of their translation parts), so no forces λ_k ≥ 0
    /// but zero balance there. A pressed obstacle then has no equilibrium but the body
    /// moving off it (its position undetermined): a "no support" case the active-set
    /// iteration meets as cycling on nodes whose force and gap are both zero. Off with
    /// force control. Collective when Dirichlet data leave modes free (the same on every
    /// rank).
    pub fn unpressable(&self, ctx: &Ctx, b: &ContactBoundary) -> bool {
        let (m, z) = (self.count(), &self.z);
        if !self.floats() || !self.coupling.is_empty() {
            return false;
        }
        let lz: f64 = (0..z.ncols())
            .map(|c| {
                (0..m)
                    .map(|j| z[(j, c)] * self.load[j])
                    .sum::<f64>()
                    .powi(2)
            })
            .sum::<f64>()
            .sqrt();
        if lz > BALANCE_RTOL * self.load_scale {
            return false;
        }
        let rows: Vec<Vec<f64>> = (b.nodes.iter()).map(|k| self.row(k, &k.frame.n)).collect();
        let mut sum = vec![0.0; m];
        for r in &rows {
            for (s, x) in sum.iter_mut().zip(r) {
                *s += x;
            }
        }
        let sum = ctx.sum_vec(&sum);
        let in_z = |full: &[f64]| -> Vec<f64> {
            (0..z.ncols())
                .map(|c| (0..m).map(|j| z[(j, c)] * full[j]).sum())
                .collect()
        };
        let unit = |v: Vec<f64>| {
            let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            v.into_iter()
                .map(|x| if n > 0.0 { x / n } else { 0.0 })
                .collect::<Vec<f64>>()
        };
        let mut translation = sum.clone();
        self.modes.keep_translations(&mut translation);
        let directions = [unit(in_z(&sum)), unit(in_z(&translation))];
        let mut worst = [f64::INFINITY; 2];
        for r in &rows {
            let a = unit(in_z(r));
            if a.iter().all(|&x| x == 0.0) {
                continue;
            }
            for (w, v) in worst.iter_mut().zip(&directions) {
                *w = w.min(a.iter().zip(v).map(|(x, y)| x * y).sum());
            }
        }
        let n = ctx.sum_usize(rows.len());
        n > 0 && worst.iter().any(|&w| ctx.min_f64(w) > 1e-9)
    }

    /// Who has the free modes: "the body has", or with several bodies free in some rigid
    /// mode, "the bodies free of Dirichlet data have" (mode counts are over all of them).
    fn who(&self) -> &'static str {
        match self.modes.slots() {
            0 | 1 => "the body has",
            _ => "the bodies that Dirichlet data leave free have",
        }
    }

    /// What a frictionless cycle of a body that its contacts alone hold likely means, for the
    /// cycling error: the load in its free modes that the contact normals cannot balance in
    /// any set (a sideways load on a body resting on a flat face, on two disks stacked on a
    /// block: every balance step brings another node into contact and the sets recur).
    /// `None` where Dirichlet data leave no mode free or the load has no part in the free
    /// modes. Local (the same on every rank).
    pub fn cycle_hint(&self) -> Option<String> {
        if !self.floats() {
            return None;
        }
        let lz = self.free_load().iter().map(|x| x * x).sum::<f64>().sqrt();
        (lz > BALANCE_RTOL * self.load_scale).then(|| {
            format!(
                "; {} rigid mode(s) that no Dirichlet data fix and a load in them: frictionless \
                 contact may have no equilibrium for it (a sideways load on a body that rests \
                 on a flat or nearly flat face) — check the loads, or add friction or \
                 Dirichlet data that hold the body ({}); where it has one (a body that starts \
                 apart from its support), the plain path's steps may cycle on the way to it \
                 while the condensed path (solver.path = \"auto\", direct preset) or the \
                 iterative preset reaches it",
                self.who(),
                self.keys.named(&["dirichlet", ".obstacle"]),
            )
        })
    }

    /// The "no support" diagnosis of a body that the contact cannot hold
    /// ([`FreeModes::unpressable`]).
    pub fn no_support_unpressed(&self) -> RunError {
        RunError::Failed(format!(
            "{}: no support: {} {} rigid mode(s) that no Dirichlet data fix, no load \
             pushes it against the obstacle in them (total load {:.3e}) and the obstacle can \
             only push it from one side: the contact can carry no force, so the obstacle pushes \
             the body away and its position is undetermined (the active-set iteration cycles on \
             nodes whose force and gap are both zero) — add Dirichlet data that hold the body, \
             or a load that presses it against the obstacle",
            self.keys.named(&["dirichlet", ".obstacle"]),
            self.who(),
            self.z.ncols(),
            self.load_scale
        ))
    }

    /// The "no support" diagnosis of an unbalanced load that no contact can carry.
    pub fn no_support(&self, n_active: usize, reaction: f64) -> RunError {
        RunError::Failed(format!(
            "{}: no support: {} {} rigid mode(s) fixed neither by Dirichlet data nor by \
             contact ({} active contact node(s)), the load is not balanced in them (unbalanced \
             load {:.3e} against a total load of {:.3e}) and moving along it brings no \
             contact node closer to the obstacle: there is no equilibrium — add Dirichlet data \
             or move the obstacle into the body's way",
            self.keys.named(&["dirichlet", ".obstacle"]),
            self.who(),
            self.pins.len(),
            n_active,
            reaction,
            self.load_scale
        ))
    }
}
