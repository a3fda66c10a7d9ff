//! The certificate of a contact solve that users read (summary.json's `certificate`, one log
//! line): the rule that stopped Newton, and in the problem's units the largest violations of
//! (3.14) and (3.18), the global equilibrium (applied loads + contact forces + reactions at the
//! Dirichlet nodes) and the force balance of every force-controlled pair. `newton.strict`
//! turns a loosened acceptance or a relative value above [`STRICT_TOL`] into an error.

use super::boundary::ContactBoundary;
use super::report::{ratio, FrictionCertificate, Kkt, Scales};
use crate::error::RunError;
use crate::fem::{self, Materials};
use crate::mesh::Mesh;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::{Matrix, PInt, Vector};
use serde::Serialize;

/// `newton.strict`: the largest relative certificate value accepted.
pub const STRICT_TOL: f64 = 1e-8;

/// The rule that stopped the Newton iteration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopRule {
    /// The exact active-set criterion: no set changed (Algorithm 1, step 5); with friction
    /// also |u^ℓ − u^{ℓ−1}|/|u^ℓ| < tol_u (Algorithm 2), with Coulomb also ‖C‖ ≤ 1e-9 ‖λ‖.
    ActiveSet,
    /// PETSc SNES VI's own convergence test (`solver.method = "snesvi"`).
    SnesVi,
    /// Loosened: Coulomb's residual stalled above 1e-9 of ‖λ‖, below 1e-6 of it or below the
    /// round-off that c puts into it (plain_path/step.rs `stalled`).
    CoulombStall,
    /// Loosened: a friction set recurred while |Δu|/|u| < tol_u (nodes on the stick/slip
    /// threshold to round-off).
    RecurringSet,
    /// Loosened: the condensed Coulomb iteration stalled and was accepted because its
    /// certificates hold to 1e-8 of the problem's scales.
    CondensedCoulombStall,
    /// Loosened: a load step's u and λ vanish below 1e-6 of the warm start's (plain_path/iteration.rs
    /// `VANISHING`); the states are round-off.
    Vanishing,
}

impl StopRule {
    /// Not the exact criterion.
    pub fn loosened(self) -> bool {
        !matches!(self, StopRule::ActiveSet | StopRule::SnesVi)
    }

    /// What the rule says, for the log and messages.
    pub fn describe(self) -> &'static str {
        match self {
            StopRule::ActiveSet => "the exact active-set criterion",
            StopRule::SnesVi => "SNES VI's convergence test",
            StopRule::CoulombStall => {
                "a stalled Coulomb residual (above 1e-9 of |lambda|, below 1e-6 of it or below 10 eps c |u|)"
            }
            StopRule::RecurringSet => "a recurring friction set with |du|/|u| < newton.tol_u",
            StopRule::CondensedCoulombStall => {
                "a stalled condensed Coulomb iteration whose certificates hold to 1e-8"
            }
            StopRule::Vanishing => {
                "a vanishing load step (u and lambda below 1e-6 of the warm start's)"
            }
        }
    }

    /// Of two solves' rules (a fixed point's Tresca solves, a load series' steps): the first
    /// loosened one, else `self`.
    pub fn worse(self, other: StopRule) -> StopRule {
        if self.loosened() || !other.loosened() {
            self
        } else {
            other
        }
    }
}

/// The global force balance: Σ applied loads + Σ contact forces (−λ) + Σ reactions = 0.
#[derive(Clone, Debug, Serialize)]
pub struct Equilibrium {
    /// Σ of the nodal loads f over the dofs without Dirichlet data (force).
    pub applied: Vec<f64>,
    /// Σ_k (−λ^k) with λ = f − A u at the contact nodes (force).
    pub contact: Vec<f64>,
    /// Σ of the element forces K_e u_e at the Dirichlet dofs (force; a load on such a dof is
    /// carried by the support and counts here).
    pub reactions: Vec<f64>,
    /// applied + contact + reactions (force).
    pub residual: Vec<f64>,
    /// |residual| (force).
    pub residual_norm: f64,
    /// The largest of the sums of magnitudes Σ|f_i|, Σ|λ_i|, Σ|R_i| over the dofs of each
    /// kind (force): the force that flows through the body; at least the size at which the
    /// round-off of the nodal forces it sums shows as 1e-10 ([`ROUND_OFF_SHOWS`]): a body moved
    /// by its Dirichlet data alone carries forces of 1e-17 that are round-off.
    pub reference: f64,
    /// residual_norm / reference (0 where both are 0).
    pub relative: f64,
}

impl Equilibrium {
    /// The balance judged against a reference of at least `floor` (a load step's: the step
    /// before's reference, as its other scales, `vanishing_floor` in mod.rs). A step whose
    /// solution vanishes carries the step before's round-off: three blocks of a stack held by
    /// contact, Coulomb on every pair, the load taken back to 0, ended on a residual of
    /// 2.5e-29 against its own reference of 2.6e-28 (relative 0.098; the step before's
    /// reference 3.0e-3). Pure.
    pub fn floored(mut self, floor: f64) -> Equilibrium {
        if floor > self.reference {
            self.reference = floor;
            self.relative = ratio(self.residual_norm, floor);
        }
        self
    }
}

/// The balance of one force-controlled pair: Σ_{k ∈ pair} (−λ^k)·e_j against |F_j|,
/// e_j = F_j/|F_j|.
#[derive(Clone, Debug, Serialize)]
pub struct PairBalance {
    /// The pair's table (`contact[i]`).
    pub key: String,
    /// |F_j| (force).
    pub force: f64,
    /// Σ (−λ^k)·e_j over the pair's nodes (force).
    pub carried: f64,
    /// |carried − force| / force.
    pub relative: f64,
}

/// The relative values the certificate is judged by (each ≤ 1e-8 for `newton.strict`).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Relative {
    /// Penetration / the length scale (max |u|, |g0|).
    pub penetration: f64,
    /// max λ_n > 0 / the force scale.
    pub sign: f64,
    /// max |λ_n (u_n + g)| / (force scale × length scale).
    pub complementarity: f64,
    /// Frictionless: max |λ_τ| / the force scale.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tangential: Option<f64>,
    /// Friction: the worst violation of (3.18) (`FrictionCertificate::worst`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    pub equilibrium: f64,
    /// Force control: the worst pair's relative defect.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub force_balance: Option<f64>,
}

impl Relative {
    /// The largest value and its name.
    pub fn worst(&self) -> (f64, &'static str) {
        let all = [
            (self.penetration, "penetration"),
            (self.sign, "sign"),
            (self.complementarity, "complementarity"),
            (self.tangential.unwrap_or(0.0), "tangential"),
            (self.friction.unwrap_or(0.0), "friction"),
            (self.equilibrium, "equilibrium"),
            (self.force_balance.unwrap_or(0.0), "force_balance"),
        ];
        all.into_iter()
            .fold((0.0, "none"), |w, v| if v.0 > w.0 { v } else { w })
    }

    fn max(&mut self, o: &Relative) {
        let opt = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(x), Some(y)) => Some(x.max(y)),
            (x, y) => x.or(y),
        };
        self.penetration = self.penetration.max(o.penetration);
        self.sign = self.sign.max(o.sign);
        self.complementarity = self.complementarity.max(o.complementarity);
        self.tangential = opt(self.tangential, o.tangential);
        self.friction = opt(self.friction, o.friction);
        self.equilibrium = self.equilibrium.max(o.equilibrium);
        self.force_balance = opt(self.force_balance, o.force_balance);
    }
}

/// The friction cone's violations (3.18), in the problem's units.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Cone {
    /// max(|λ_τ| − b_k, 0) (force).
    pub excess: f64,
    /// max |u_τ| on stick nodes (length; the increment of a load step).
    pub stick_motion: f64,
    /// max |λ_τ − b_k u_τ/|u_τ|| on slip nodes (force).
    pub slip_alignment: f64,
}

/// summary.json's `certificate`.
#[derive(Clone, Debug, Serialize)]
pub struct Certificate {
    /// The rule that stopped Newton ([`StopRule`]).
    pub stop_rule: StopRule,
    /// The rule is a loosened acceptance (not the exact criterion).
    pub loosened: bool,
    /// `newton.strict` of the case.
    pub strict: bool,
    /// Largest penetration −(u_n + g) (length).
    pub penetration: f64,
    /// The mean contact mesh size h_c (mean of w_k^(1/(d−1))) (length).
    pub mesh_size: f64,
    /// penetration / mesh_size.
    pub penetration_per_mesh_size: f64,
    /// Largest λ_n > 0 (force): the sign condition of (3.14).
    pub positive_lambda_n: f64,
    /// Largest |λ_n (u_n + g)| (force × length).
    pub complementarity: f64,
    /// Frictionless: largest |λ_τ| (force).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tangential_force: Option<f64>,
    /// Friction: the cone's violations.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<Cone>,
    pub equilibrium: Equilibrium,
    /// Force control: each force-controlled pair's balance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub force_balance: Option<Vec<PairBalance>>,
    /// The scales the relative values divide by: force and length.
    pub force_scale: f64,
    pub length_scale: f64,
    pub relative: Relative,
    /// The largest relative value and its name.
    pub worst: f64,
    pub worst_of: &'static str,
    /// A load series: the step the block's worst value is from (the block holds the worst
    /// of every value over the steps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub worst_step: Option<usize>,
}

/// The parts a certificate is built of.
pub struct Parts<'a> {
    pub stop: StopRule,
    pub strict: bool,
    pub kkt: &'a Kkt,
    pub friction: Option<&'a FrictionCertificate>,
    pub scales: &'a Scales,
    pub mesh_size: f64,
    pub equilibrium: Equilibrium,
    pub force_balance: Option<Vec<PairBalance>>,
}

impl Certificate {
    /// The certificate of a final state from its parts. Pure.
    pub fn new(p: Parts) -> Certificate {
        let (kkt, scales) = (p.kkt, p.scales);
        let frictionless = kkt.max_abs_lambda_t;
        let relative = Relative {
            penetration: ratio(kkt.max_penetration, kkt.length_scale),
            sign: ratio(kkt.max_positive_lambda_n, kkt.force_scale),
            complementarity: ratio(kkt.max_complementarity, kkt.force_scale * kkt.length_scale),
            tangential: frictionless.map(|t| ratio(t, kkt.force_scale)),
            friction: p.friction.map(|f| f.worst(scales)),
            equilibrium: p.equilibrium.relative,
            force_balance: p
                .force_balance
                .as_ref()
                .map(|v| v.iter().map(|b| b.relative).fold(0.0, f64::max)),
        };
        let (worst, worst_of) = relative.worst();
        Certificate {
            stop_rule: p.stop,
            loosened: p.stop.loosened(),
            strict: p.strict,
            penetration: kkt.max_penetration,
            mesh_size: p.mesh_size,
            penetration_per_mesh_size: ratio(kkt.max_penetration, p.mesh_size),
            positive_lambda_n: kkt.max_positive_lambda_n,
            complementarity: kkt.max_complementarity,
            tangential_force: frictionless,
            friction: p.friction.map(|f| Cone {
                excess: f.max_excess,
                stick_motion: f.max_stick_motion,
                slip_alignment: f.max_slip_alignment_defect,
            }),
            equilibrium: p.equilibrium,
            force_balance: p.force_balance,
            force_scale: kkt.force_scale,
            length_scale: kkt.length_scale,
            relative,
            worst,
            worst_of,
            worst_step: None,
        }
    }

    /// `newton.strict`: why this certificate is not accepted (a loosened acceptance, or a
    /// relative value above [`STRICT_TOL`]); `None` if it is. Pure.
    pub fn strict_failure(&self) -> Option<String> {
        if self.loosened {
            return Some(format!(
                "newton.strict = true: Newton stopped by a loosened acceptance, {} \
                 (stop_rule = \"{}\")",
                self.stop_rule.describe(),
                serde_json::to_value(self.stop_rule)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_string))
                    .unwrap_or_default()
            ));
        }
        (self.worst > STRICT_TOL).then(|| {
            format!(
                "newton.strict = true: the certificate's {} is {:.3e} (relative), above \
                 {STRICT_TOL:e}",
                self.worst_of, self.worst
            )
        })
    }

    /// A load series' block: the worst of every value over the steps (`step` is `other`'s
    /// number; the block starts as step 1's with `worst_step = Some(1)`); the stop rule the
    /// first loosened one. Pure.
    pub fn merge(&mut self, other: &Certificate, step: usize) {
        self.stop_rule = self.stop_rule.worse(other.stop_rule);
        self.loosened |= other.loosened;
        self.penetration = self.penetration.max(other.penetration);
        self.penetration_per_mesh_size = self
            .penetration_per_mesh_size
            .max(other.penetration_per_mesh_size);
        self.positive_lambda_n = self.positive_lambda_n.max(other.positive_lambda_n);
        self.complementarity = self.complementarity.max(other.complementarity);
        self.tangential_force = match (self.tangential_force, other.tangential_force) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
        self.friction = match (self.friction, other.friction) {
            (Some(a), Some(b)) => Some(Cone {
                excess: a.excess.max(b.excess),
                stick_motion: a.stick_motion.max(b.stick_motion),
                slip_alignment: a.slip_alignment.max(b.slip_alignment),
            }),
            (a, b) => a.or(b),
        };
        if other.equilibrium.relative > self.equilibrium.relative {
            self.equilibrium = other.equilibrium.clone();
        }
        if let (Some(mine), Some(theirs)) = (&mut self.force_balance, &other.force_balance) {
            for (a, b) in mine.iter_mut().zip(theirs) {
                if b.relative > a.relative {
                    *a = b.clone();
                }
            }
        }
        let before = self.worst;
        self.relative.max(&other.relative);
        (self.worst, self.worst_of) = self.relative.worst();
        if other.worst > before {
            self.worst_step = Some(step);
        }
    }

    /// The log line.
    pub fn line(&self) -> String {
        let mut s = format!(
            "certificate: stopped by {}{}; penetration {:.3e} ({:.1e} h), λ_n > 0 {:.3e}, \
             |λ_n g| {:.3e}",
            self.stop_rule.describe(),
            if self.loosened { " (loosened)" } else { "" },
            self.penetration,
            self.penetration_per_mesh_size,
            self.positive_lambda_n,
            self.complementarity
        );
        if let Some(t) = self.tangential_force {
            s += &format!(", |λ_τ| {t:.3e}");
        }
        if let Some(c) = self.friction {
            s += &format!(
                ", cone excess {:.3e}, stick motion {:.3e}, slip alignment {:.3e}",
                c.excess, c.stick_motion, c.slip_alignment
            );
        }
        s += &format!(
            "; equilibrium residual {:.3e} of {:.3e} ({:.1e})",
            self.equilibrium.residual_norm, self.equilibrium.reference, self.equilibrium.relative
        );
        for b in self.force_balance.iter().flatten() {
            s += &format!(
                "; {}: {:.6e} carried of |F| = {:.6e} ({:.1e})",
                b.key, b.carried, b.force, b.relative
            );
        }
        s + &format!("; worst relative {:.1e} ({})", self.worst, self.worst_of)
    }
}

/// The global balance of forces of THEORY §2 (Σ_k (−λ^k) = the load the obstacle carries),
/// extended by the reactions: residual = applied + contact + reactions, judged against the
/// largest of the three magnitudes `gross` (Σ|f_i|, Σ|λ_i|, Σ|R_i|). Pure.
pub fn balance(
    applied: [f64; 3],
    contact: [f64; 3],
    reactions: [f64; 3],
    gross: [f64; 3],
    dim: usize,
) -> Equilibrium {
    let residual: Vec<f64> = (0..dim)
        .map(|c| applied[c] + contact[c] + reactions[c])
        .collect();
    let residual_norm = residual.iter().map(|x| x * x).sum::<f64>().sqrt();
    let reference = gross.iter().copied().fold(0.0, f64::max);
    Equilibrium {
        applied: applied[..dim].to_vec(),
        contact: contact[..dim].to_vec(),
        reactions: reactions[..dim].to_vec(),
        residual,
        residual_norm,
        reference,
        relative: ratio(residual_norm, reference),
    }
}

/// The relative value at which the equilibrium shows a residual at the round-off of its
/// operands: its reference is at least ε × (the largest nodal force a λ_i or R_i is a
/// difference of, |A_ii u_i| at the contact rows, Σ_j |K_e,ij u_j| at the Dirichlet rows) ×
/// √(rows summed) / this ([`Equilibrium::reference`]), so such a residual stays 100 × below
/// the warning (1e-8). Where the body carries real forces that floor lies far below them: a
/// floor at the nodal force itself hid an iterative solve's error (the indentation of
/// tests/certificate.rs at solver.rtol = 1e-8: 1.0e-7 of its forces, 7.2e-9 of that
/// floor), and one from max |A_ii| × max |u| over different nodes was 3e6 × the load of two
/// floating bodies of E = 1e3 and 1e7. Without a floor the block of
/// tests/cases/block2d_pulled.toml, moved by its Dirichlet data alone, showed a residual of
/// 1e-16 against forces of 4e-16: 0.15.
pub const ROUND_OFF_SHOWS: f64 = 1e-10;

/// The elastic problem an equilibrium is checked on: the mesh and its partition, the
/// materials and the Dirichlet values per dof (NaN = free).
pub struct Elastic<'a> {
    pub mesh: &'a Mesh,
    pub layout: &'a Layout,
    pub material: &'a Materials,
    pub fixed: &'a [f64],
}

/// The global equilibrium of the solution u (3.8), (3.28): λ = f − A u at the contact rows
/// (A, f assembled, Dirichlet data eliminated; with body pairs also at `more_rows`, the master
/// rows that receive the slave nodes' forces), the reactions K_e u_e at the Dirichlet dofs and
/// the loads f + K_e[·, D] g_D at the other dofs (the elimination's lift added back), both
/// from the element matrices of the cells that touch a Dirichlet node only. Also returns λ
/// per contact node of this rank (global components), for the force balance. Collective.
pub fn equilibrium(
    ctx: &Ctx,
    elastic: &Elastic,
    a: &Matrix,
    f: &Vector,
    more_rows: &[bool],
    b: &ContactBoundary,
    u: &Vector,
) -> Result<(Equilibrium, Vec<[f64; 3]>), RunError> {
    let (layout, fixed, dim) = (elastic.layout, elastic.fixed, elastic.mesh.dim);
    let mut au = f.duplicate()?;
    a.mult(u, &mut au)?;
    let (au, f_local) = (au.to_local_vec()?, f.to_local_vec()?);
    let (v, products) = dirichlet_terms(elastic, f, u)?;
    let mut diagonal = f.duplicate()?;
    a.diagonal(&mut diagonal)?;
    let diagonal = diagonal.to_local_vec()?;
    let u_local = u.to_local_vec()?;
    // the largest nodal force a λ_i or R_i is a difference of (|A_ii u_i| at the contact rows)
    let mut operand = 0.0f64;
    let (mut contact_row, lambdas) = contact_forces(b, &f_local, &au);
    for (r, &m) in contact_row.iter_mut().zip(more_rows) {
        *r |= m;
    }
    let f = f_local;
    let start = layout.node_offsets[layout.rank];
    // per component: applied, contact, reactions; then Σ|f|, Σ|λ|, Σ|R|; the contact and
    // Dirichlet rows summed (counts)
    let mut local = [0.0; 14];
    for &node in &layout.owned_nodes {
        let row0 = (layout.node_global[node] - start) * dim;
        for c in 0..dim {
            let i = row0 + c;
            if !fixed[node * dim + c].is_nan() {
                local[6 + c] += v[i];
                local[11] += v[i].abs();
                local[13] += 1.0;
            } else {
                let load = f[i] + v[i];
                local[c] += load;
                local[9] += load.abs();
                if contact_row[i] {
                    let l = f[i] - au[i];
                    local[3 + c] -= l;
                    local[10] += l.abs();
                    local[12] += 1.0;
                    operand = operand.max((diagonal[i] * u_local[i]).abs());
                }
            }
        }
    }
    let s = ctx.sum_vec(&local);
    let three = |o: usize| [s[o], s[o + 1], s[o + 2]];
    let operand = ctx.max_f64(operand.max(products));
    let floor = f64::EPSILON * operand * (s[12] + s[13]).sqrt() / ROUND_OFF_SHOWS;
    let eq = balance(three(0), three(3), three(6), three(9), dim).floored(floor);
    Ok((eq, lambdas))
}

/// V of [`equilibrium`]: K_e u_e at the Dirichlet dofs and K_e[·, D] g_D at the others, over
/// the cells with a Dirichlet node (u at their nodes gathered), summed in rank order; this
/// rank's rows; with the largest Σ_j |K_e,ij u_j| of this rank's cells' Dirichlet rows (the
/// magnitude a reaction is a difference of). Collective.
fn dirichlet_terms(elastic: &Elastic, f: &Vector, u: &Vector) -> Result<(Vec<f64>, f64), RunError> {
    let Elastic {
        mesh,
        layout,
        material,
        fixed,
    } = *elastic;
    let dim = mesh.dim;
    let is_fixed = |v: usize| (0..dim).any(|c| !fixed[v * dim + c].is_nan());
    let cells: Vec<usize> = layout
        .local_cells
        .iter()
        .copied()
        .filter(|&c| mesh.cell(c).iter().any(|&v| is_fixed(v)))
        .collect();
    let (nodes, uvals) = crate::partition::values_at_cells(mesh, layout, &cells, u)?;
    let (mut vi, mut vv): (Vec<PInt>, Vec<f64>) = (Vec::new(), Vec::new());
    let mut ke = [0.0; 144];
    let mut products = 0.0f64;
    for &c in &cells {
        let (lambda, mu) = material.lame_of(c);
        let cell = mesh.cell(c);
        let n = cell.len();
        let nd = n * dim;
        if dim == 2 {
            let x = std::array::from_fn(|a| [mesh.coords[cell[a]][0], mesh.coords[cell[a]][1]]);
            let mut k = [0.0; 36];
            fem::tri_stiffness(&x, lambda, mu, &mut k);
            ke[..36].copy_from_slice(&k);
        } else {
            let x = std::array::from_fn(|a| mesh.coords[cell[a]]);
            fem::tet_stiffness(&x, lambda, mu, &mut ke);
        }
        let mut ue = [0.0; 12];
        let mut fx = [false; 12];
        for (a, &v) in cell.iter().enumerate() {
            let p = nodes.binary_search(&v).expect("node gathered");
            for i in 0..dim {
                let g = fixed[v * dim + i];
                fx[a * dim + i] = !g.is_nan();
                // the Dirichlet value itself where given (as the elimination took it)
                ue[a * dim + i] = if g.is_nan() { uvals[p * dim + i] } else { g };
            }
        }
        for r in 0..nd {
            let row = &ke[r * nd..(r + 1) * nd];
            // the row's value and the sum of the magnitudes it is made of, in one pass
            let (val, size) = (0..nd)
                .filter(|&j| fx[r] || fx[j])
                .map(|j| row[j] * ue[j])
                .fold((0.0, 0.0), |(v, m): (f64, f64), t| (v + t, m + t.abs()));
            if fx[r] {
                products = products.max(size);
            }
            vi.push((layout.node_global[cell[r / dim]] * dim + r % dim) as PInt);
            vv.push(val);
        }
    }
    let mut v = f.duplicate()?;
    v.set_all(0.0)?;
    crate::par::add_in_rank_order(&mut v, &vi, &vv)?;
    v.assemble()?;
    let v = v.to_local_vec()?;
    Ok((v, products))
}

/// λ = f − A u (3.28) at the contact rows: which local rows are contact rows, and λ per contact
/// node of this rank. Local.
fn contact_forces(b: &ContactBoundary, f: &[f64], au: &[f64]) -> (Vec<bool>, Vec<[f64; 3]>) {
    let mut contact_row = vec![false; f.len()];
    let mut lambdas = Vec::with_capacity(b.nodes.len());
    for k in &b.nodes {
        let mut l = [0.0; 3];
        for c in 0..k.frame.dim {
            contact_row[k.local_row + c] = true;
            l[c] = f[k.local_row + c] - au[k.local_row + c];
        }
        lambdas.push(l);
    }
    (contact_row, lambdas)
}

/// The balance of each force-controlled pair: Σ_{k ∈ pair} (−λ^k)·e_j against |F_j| (`lambdas`:
/// this rank's λ per contact node, from [`equilibrium`]). Collective (one reduction).
pub fn force_balance(
    ctx: &Ctx,
    b: &ContactBoundary,
    lambdas: &[[f64; 3]],
    forces: &[super::force::ForceControl],
) -> Vec<PairBalance> {
    let mut local = vec![0.0; forces.len()];
    for (k, l) in b.nodes.iter().zip(lambdas) {
        for (j, fc) in forces.iter().enumerate() {
            if fc.pair == k.pair {
                local[j] -= crate::geom::dot(*l, fc.direction());
            }
        }
    }
    let carried = ctx.sum_vec(&local);
    forces
        .iter()
        .zip(carried)
        .map(|(fc, carried)| pair_balance(fc.key.clone(), fc.magnitude(), carried))
        .collect()
}

/// One pair's balance from its force |F_j| and the force carried along e_j. Pure.
pub fn pair_balance(key: String, force: f64, carried: f64) -> PairBalance {
    PairBalance {
        key,
        force,
        carried,
        relative: ratio((carried - force).abs(), force),
    }
}

/// A certificate for tests: (3.14) held to 1e-11 of the scales (force 1, length 0.1, mesh
/// size 0.01), frictionless, with the equilibrium `eq` and the pairs' balances `force_balance`.
#[cfg(test)]
pub(crate) fn sample(
    stop: StopRule,
    strict: bool,
    eq: Equilibrium,
    force_balance: Option<Vec<PairBalance>>,
) -> Certificate {
    let kkt = Kkt {
        max_penetration: 1e-12,
        max_positive_lambda_n: 0.0,
        max_complementarity: 1e-15,
        force_scale: 1.0,
        length_scale: 0.1,
        max_abs_lambda_t: Some(0.0),
    };
    Certificate::new(Parts {
        stop,
        strict,
        kkt: &kkt,
        friction: None,
        scales: &Scales {
            force: 1.0,
            length: 0.1,
        },
        mesh_size: 0.01,
        equilibrium: eq,
        force_balance,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A body pushed down by 3 on its top, held by the obstacle (2) and a support (1).
    fn balanced() -> ([f64; 3], [f64; 3], [f64; 3]) {
        ([0.5, -3.0, 0.0], [0.0, 2.0, 0.0], [-0.5, 1.0, 0.0])
    }

    #[test]
    fn a_balanced_state_passes_a_perturbed_one_fails() {
        let (f, c, r) = balanced();
        let gross = [3.5, 2.0, 1.5];
        let e = balance(f, c, r, gross, 2);
        assert_eq!(e.residual, vec![0.0, 0.0]);
        assert_eq!(e.relative, 0.0);
        assert_eq!(e.reference, 3.5);
        // one contact force 1e-4 too small: the residual says so, relative to the reference
        let mut c2 = c;
        c2[1] -= 1e-4;
        let e = balance(f, c2, r, gross, 2);
        assert!((e.residual_norm - 1e-4).abs() < 1e-15, "{e:?}");
        assert!((e.relative - 1e-4 / 3.5).abs() < 1e-15, "{e:?}");
        assert!(e.relative > STRICT_TOL);
        // nothing at all: 0, not NaN
        assert_eq!(
            balance([0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3], 3).relative,
            0.0
        );
    }

    #[test]
    fn a_vanishing_step_is_judged_by_the_step_befores_reference() {
        // a residual of round-off against the step's own vanishing forces
        let e = balance(
            [0.0; 3],
            [1e-29, 2e-29, 0.0],
            [-1.1e-29, -2.2e-29, 0.0],
            [0.0, 3e-29, 3e-29],
            2,
        );
        assert!(e.relative > 1e-2, "{e:?}");
        let floored = e.clone().floored(3e-3);
        assert_eq!(floored.reference, 3e-3);
        assert!(floored.relative < 1e-25, "{floored:?}");
        // a floor below the step's own reference changes nothing
        let own = e.clone().floored(1e-30);
        assert_eq!(own.reference, e.reference);
        assert_eq!(own.relative, e.relative);
    }

    fn certificate(stop: StopRule, eq: Equilibrium) -> Certificate {
        let pair = pair_balance("contact[1]".into(), 2.0, 2.0 + 1e-6);
        sample(stop, true, eq, Some(vec![pair]))
    }

    #[test]
    fn strict_names_the_rule_and_the_value() {
        let (f, c, r) = balanced();
        let ok = balance(f, c, r, [3.5, 2.0, 1.5], 2);
        let cert = certificate(StopRule::ActiveSet, ok.clone());
        assert!((cert.penetration_per_mesh_size - 1e-10).abs() < 1e-20);
        // the force balance is 5e-7 off: named
        assert_eq!(cert.worst_of, "force_balance");
        let why = cert.strict_failure().expect("above 1e-8");
        assert!(
            why.contains("force_balance") && why.contains("5.000e-7"),
            "{why}"
        );
        // a loosened rule fails whatever the values
        let mut cert = certificate(StopRule::RecurringSet, ok.clone());
        cert.force_balance = None;
        let why = cert.strict_failure().expect("loosened");
        assert!(why.contains("recurring_set"), "{why}");
        // the exact rule with values at round-off passes
        let mut cert = certificate(StopRule::ActiveSet, ok);
        cert.relative.force_balance = Some(1e-14);
        (cert.worst, cert.worst_of) = cert.relative.worst();
        assert_eq!(cert.strict_failure(), None);
    }

    #[test]
    fn a_series_keeps_the_worst() {
        let (f, c, r) = balanced();
        let ok = balance(f, c, r, [3.5, 2.0, 1.5], 2);
        let mut c2 = c;
        c2[0] += 1e-3;
        let bad = balance(f, c2, r, [3.5, 2.0, 1.5], 2);
        let mut block = certificate(StopRule::ActiveSet, ok.clone());
        block.worst_step = Some(1);
        block.merge(&certificate(StopRule::Vanishing, bad), 2);
        block.merge(&certificate(StopRule::ActiveSet, ok), 3);
        assert_eq!(block.stop_rule, StopRule::Vanishing);
        assert!(block.loosened);
        assert!((block.equilibrium.residual_norm - 1e-3).abs() < 1e-15);
        assert_eq!(block.worst_of, "equilibrium");
        assert_eq!(block.worst_step, Some(2));
    }

    #[test]
    fn loosened_rules() {
        assert!(!StopRule::ActiveSet.loosened());
        for r in [
            StopRule::CoulombStall,
            StopRule::RecurringSet,
            StopRule::CondensedCoulombStall,
            StopRule::Vanishing,
        ] {
            assert!(r.loosened());
            assert_eq!(StopRule::ActiveSet.worse(r), r);
            assert_eq!(r.worse(StopRule::ActiveSet), r);
        }
    }
}
