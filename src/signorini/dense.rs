//! Algorithm 1 on a dense model of the contact unknowns, shared by the condensed path
//! (schur/frictionless.rs: the exact compliance from MUMPS' Schur complement) and the half-space
//! predictor (halfspace/: a modelled compliance): the dense active-set iteration with the free
//! rigid modes' balance (`Dense`), its primal form on the Schur complement itself for zones too
//! wide for the compliance (`Primal`), their result and how it ended (`DenseRun`, `End`), the
//! saddle solver of one step, and the coarsening of the nested start.

// an unbalanced load in the set's free modes below this fraction of the load's scale is
// balanced (as in rigid.rs's balance test)
use super::rigid::BALANCE_RTOL;
use crate::contact::{c_n, inf_norm, normal_active, normal_active_or_tie, ties};
use crate::petsc::lapack::{DenseCholesky, DenseLu};
use crate::tuning::{COARSEN_KEEP, COARSEN_RADIUS, COARSEST, SPACING_SAMPLES};
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use std::collections::HashSet;
use std::time::Instant;

/// The limits of a dense iteration: the complementarity parameter c > 0 and the number of
/// steps it may take (newton.max_steps).
#[derive(Clone, Copy, Debug)]
pub struct DenseLimits {
    pub c: f64,
    pub max_steps: usize,
}

/// The compliance C (n × n, symmetric) of a dense iteration (or the Schur complement S, read
/// the same way): a full matrix, or its upper triangle packed column by column — column j's
/// entries i = 0..=j one after the other: the half-space model's column shares gathered
/// (`halfspace::kernel::HalfSpace::columns`), the condensed path's S⁻¹ and S ([`pack_upper`])
/// — in half the memory.
#[derive(Clone, Copy)]
pub enum CMatrix<'a> {
    Full(&'a DMatrix<f64>),
    Upper { n: usize, packed: &'a [f64] },
}

impl CMatrix<'_> {
    /// n. Local.
    pub fn n(&self) -> usize {
        match self {
            CMatrix::Full(c) => c.nrows(),
            CMatrix::Upper { n, .. } => *n,
        }
    }

    /// Column j of C (= its row j) into `out` (n values). Local.
    pub fn column_into(&self, j: usize, out: &mut [f64]) {
        match self {
            CMatrix::Full(c) => out.copy_from_slice(c.column(j).as_slice()),
            CMatrix::Upper { n, packed } => {
                let top = j * (j + 1) / 2;
                out[..=j].copy_from_slice(&packed[top..=top + j]);
                for (i, o) in out.iter_mut().enumerate().take(*n).skip(j + 1) {
                    *o = packed[i * (i + 1) / 2 + j];
                }
            }
        }
    }

    /// C X for the columns of X. Local.
    pub fn times_columns(&self, x: &DMatrix<f64>) -> DMatrix<f64> {
        match self {
            CMatrix::Full(c) => *c * x,
            CMatrix::Upper { n, .. } => {
                let mut y = DMatrix::<f64>::zeros(*n, x.ncols());
                for k in 0..x.ncols() {
                    let cx = self.times(&x.column(k).clone_owned());
                    y.column_mut(k).copy_from(&cx);
                }
                y
            }
        }
    }

    /// C_ij. Local.
    pub fn at(&self, i: usize, j: usize) -> f64 {
        match self {
            CMatrix::Full(c) => c[(i, j)],
            CMatrix::Upper { packed, .. } => {
                let (i, j) = if i <= j { (i, j) } else { (j, i) };
                packed[j * (j + 1) / 2 + i]
            }
        }
    }

    /// C x. Local.
    pub fn times(&self, x: &DVector<f64>) -> DVector<f64> {
        match self {
            CMatrix::Full(c) => *c * x,
            CMatrix::Upper { n, packed } => {
                let mut y = DVector::<f64>::zeros(*n);
                let (ys, xs) = (y.as_mut_slice(), x.as_slice());
                let nz: Vec<usize> = (0..*n).filter(|&j| xs[j] != 0.0).collect();
                if 4 * nz.len() < *n {
                    // few nonzeros (a coarse level's multipliers): column j's head for each
                    // nonzero x_j, and each column's dot with the nonzeros above its diagonal
                    for &j in &nz {
                        let top = j * (j + 1) / 2;
                        for (yi, ci) in ys[..=j].iter_mut().zip(&packed[top..=top + j]) {
                            *yi += ci * xs[j];
                        }
                    }
                    for (i, yi) in ys.iter_mut().enumerate() {
                        let top = i * (i + 1) / 2;
                        let above = nz.iter().take_while(|&&j| j < i);
                        *yi += above.map(|&j| packed[top + j] * xs[j]).sum::<f64>();
                    }
                    return y;
                }
                let mut p = 0;
                for j in 0..*n {
                    let col = &packed[p..p + j + 1];
                    let xj = xs[j];
                    let mut dot = 0.0;
                    for ((yi, ci), xi) in ys[..j].iter_mut().zip(&col[..j]).zip(&xs[..j]) {
                        *yi += ci * xj;
                        dot += ci * xi;
                    }
                    ys[j] += col[j] * xj + dot;
                    p += j + 1;
                }
                y
            }
        }
    }

    /// The block C_II of the indices `idx`. Local.
    pub fn block(&self, idx: &[usize]) -> DMatrix<f64> {
        let CMatrix::Upper { n, packed } = self else {
            return DMatrix::from_fn(idx.len(), idx.len(), |r, q| self.at(idx[r], idx[q]));
        };
        // each packed column j of idx read once, front to back, its entries i ≤ j of idx
        // placed at (i, j) and (j, i) (entry by entry, the entries i > j would be read with a
        // stride that grows with i)
        let mut pos = vec![usize::MAX; *n];
        for (r, &i) in idx.iter().enumerate() {
            if pos[i] != usize::MAX {
                // an index twice: entry by entry
                return DMatrix::from_fn(idx.len(), idx.len(), |r, q| self.at(idx[r], idx[q]));
            }
            pos[i] = r;
        }
        let mut b = DMatrix::<f64>::zeros(idx.len(), idx.len());
        for (q, &j) in idx.iter().enumerate() {
            let col = &packed[j * (j + 1) / 2..=j * (j + 1) / 2 + j];
            for (i, &v) in col.iter().enumerate() {
                let r = pos[i];
                if r != usize::MAX {
                    b[(r, q)] = v;
                    b[(q, r)] = v;
                }
            }
        }
        b
    }

    /// C_II x for the indices `idx` (x: one value per index). Local.
    fn block_times(&self, idx: &[usize], x: &[f64]) -> DVector<f64> {
        match self {
            CMatrix::Full(c) => {
                let mut y = DVector::<f64>::zeros(idx.len());
                for (&j, &xj) in idx.iter().zip(x) {
                    let col = c.column(j);
                    for (yr, &i) in y.iter_mut().zip(idx) {
                        *yr += col[i] * xj;
                    }
                }
                y
            }
            CMatrix::Upper { n, .. } => {
                let mut full = DVector::<f64>::zeros(*n);
                for (&i, &xi) in idx.iter().zip(x) {
                    full[i] = xi;
                }
                let cx = self.times(&full);
                DVector::from_iterator(idx.len(), idx.iter().map(|&i| cx[i]))
            }
        }
    }
}

/// Algorithm 1 on the condensed system (module note): C (n × n), d₀, the gaps, the free
/// modes' normal parts G (n × m_z), the load in them φ = zᵀ Rᵀ f and its scale, c.
pub struct Dense<'a> {
    pub cmat: CMatrix<'a>,
    pub d0: &'a [f64],
    pub gap: &'a [f64],
    pub g: &'a DMatrix<f64>,
    pub phi: &'a [f64],
    pub load_scale: f64,
    pub c: f64,
    pub max_steps: usize,
    /// An estimate of the contact zone for a start (Coulomb's, where friction holds a
    /// tangential load), not a solution of the frictionless problem: the pins carry the load in
    /// the first modes (the body's own, the columns of these parts) where a set leaves them
    /// free, but only in the motions that move a node in contact (a body the set does not
    /// touch yet, e.g. the upper of two disks stacked on a block, is not hung on its pins).
    /// The modes after them (force control's approaches) are always balanced. `None`: the
    /// balance test on every mode.
    pub pins: Option<Moves<'a>>,
}

/// The parts of the modes the pins may carry at the candidates in every direction
/// ([`Dense::pins`]): rows `dim` i … `dim` i + `dim` − 1 for candidate i, one column per mode.
#[derive(Clone, Copy)]
pub struct Moves<'a> {
    pub parts: &'a DMatrix<f64>,
    pub dim: usize,
}

impl Moves<'_> {
    /// The rows of the candidates `idx` (a coarse level's subset).
    pub fn subset(&self, idx: &[usize]) -> DMatrix<f64> {
        let d = self.dim;
        DMatrix::from_fn(idx.len() * d, self.parts.ncols(), |r, c| {
            self.parts[(idx[r / d] * d + r % d, c)]
        })
    }

    /// φ (its first entries, one per column of the parts) with the load the pins carry taken
    /// out: its part in the motions of those modes that move an `active` node, leaving the
    /// part in the motions that move none (the orthogonal complement, the Gram matrix of the
    /// active rows' eigenvectors of relative eigenvalue ≤ [`UNTOUCHED_RTOL`]). Local.
    fn uncarried(&self, active: &[bool], phi: &mut DVector<f64>) {
        let (d, m) = (self.dim, self.parts.ncols());
        let mut gram = DMatrix::<f64>::zeros(m, m);
        for i in (0..active.len()).filter(|&i| active[i]) {
            for a in 0..d {
                let row = self.parts.view((i * d + a, 0), (1, m));
                gram += row.transpose() * row;
            }
        }
        let eig = nalgebra::SymmetricEigen::new(gram);
        let top = eig.eigenvalues.iter().fold(0.0_f64, |t, &e| t.max(e));
        let head = DVector::from_iterator(m, phi.iter().take(m).copied());
        let mut kept = DVector::<f64>::zeros(m);
        for (k, &e) in eig.eigenvalues.iter().enumerate() {
            if e <= UNTOUCHED_RTOL * top {
                let v = eig.eigenvectors.column(k);
                kept += v * v.dot(&head);
            }
        }
        for (x, k) in phi.iter_mut().zip(kept.iter()) {
            *x = *k;
        }
    }
}

/// A motion whose squared displacement at the active nodes is at most this part of the
/// largest such (the eigenvalues of their Gram matrix) moves none of them: round-off of the
/// modes' parts (each O(1) per unit amplitude, or the lever arm), far below any motion that
/// does move a node. Not measured as a value.
const UNTOUCHED_RTOL: f64 = 1e-12;

/// How the dense iteration ended.
#[derive(Debug, Clone, PartialEq)]
pub enum End {
    Converged,
    /// The load is unbalanced in a mode no contact node can fix (the unbalanced load).
    NoSupport(f64),
    Fallback(String),
}

/// The dense iteration's result: final set, λ_n, the free modes' coefficients α, u_n, and per
/// step (step, |A_n|, changed, ‖C_n‖, seconds).
#[derive(Debug, Clone)]
pub struct DenseRun {
    pub active: Vec<bool>,
    pub lambda: Vec<f64>,
    pub alpha: Vec<f64>,
    pub u_n: Vec<f64>,
    pub steps: Vec<(usize, usize, usize, f64, f64)>,
    pub end: End,
    /// The nested start's coarse levels, coarsest first: (nodes, steps).
    pub coarse: Vec<(usize, usize)>,
}

/// The upper triangle of the symmetric n × n matrix whose lower triangle `lower` holds
/// (column-major, as MUMPS returns a Schur complement), packed column by column
/// ([`CMatrix::Upper`]) into a new buffer of n (n + 1) / 2. Local.
pub fn pack_upper_of_lower(lower: &[f64], n: usize) -> Vec<f64> {
    assert_eq!(lower.len(), n * n, "an n × n matrix");
    let mut packed = Vec::with_capacity(n * (n + 1) / 2);
    for j in 0..n {
        // column j of the upper triangle is row j of the lower one
        packed.extend((0..=j).map(|i| lower[i * n + j]));
    }
    packed
}

/// The upper triangle of the symmetric n × n matrix `full` (column-major, its upper triangle
/// holding the values) packed column by column ([`CMatrix::Upper`]) in `full`'s own memory,
/// which shrinks to it: half of n² is returned to the allocator without a second n × n
/// buffer. Local.
pub fn pack_upper(mut full: Vec<f64>, n: usize) -> Vec<f64> {
    assert_eq!(full.len(), n * n, "an n × n matrix");
    // column j's entries 0..=j move to j (j + 1) / 2 ≤ j n: forward, never over an entry
    // still to be read
    let mut at = 0;
    for j in 0..n {
        full.copy_within(j * n..j * n + j + 1, at);
        at += j + 1;
    }
    full.truncate(at);
    full.shrink_to_fit();
    full
}

/// Runs `f` (rank 0's share of a collective stage: the other ranks wait in the broadcast that
/// follows) with a panic caught: `Err` with its message instead of unwinding out of the stage,
/// so that rank 0 still broadcasts and every rank learns of the failure (the parallel rule).
/// The test-only fault stage `stage` (`crate::fault`) panics inside. Local.
pub(super) fn guarded<T>(stage: &str, f: impl FnOnce() -> T) -> Result<T, String> {
    let run = crate::abort::catching(|| {
        if let Some(m) = crate::fault::injected(stage, 0) {
            panic!("{m}");
        }
        f()
    });
    run.map_err(|e| {
        format!(
            "the dense computation on rank 0 failed: {}",
            crate::abort::panic_message(&*e)
        )
    })
}

impl DenseRun {
    /// A run that failed before its first step (`why`: the fallback reason).
    pub(super) fn failed(n: usize, mz: usize, why: String) -> DenseRun {
        DenseRun::unsolved(vec![false; n], mz, Vec::new(), why)
    }

    /// A run that ends without a solution: the set and steps it reached, λ_n, α and u_n zero.
    fn unsolved(
        active: Vec<bool>,
        mz: usize,
        steps: Vec<(usize, usize, usize, f64, f64)>,
        why: String,
    ) -> DenseRun {
        let n = active.len();
        DenseRun {
            active,
            lambda: vec![0.0; n],
            alpha: vec![0.0; mz],
            u_n: vec![0.0; n],
            steps,
            end: End::Fallback(why),
            coarse: Vec::new(),
        }
    }

    /// One flat vector for the broadcast.
    pub(super) fn pack(&self, n: usize, mz: usize) -> Vec<f64> {
        let mut v = Vec::with_capacity(4 * n + mz + 5 * self.steps.len() + 3);
        let (code, x) = match &self.end {
            End::Converged => (0.0, 0.0),
            End::NoSupport(r) => (1.0, *r),
            End::Fallback(_) => (2.0, 0.0),
        };
        v.extend_from_slice(&[code, x, self.steps.len() as f64, self.coarse.len() as f64]);
        v.extend(self.active.iter().map(|&a| if a { 1.0 } else { 0.0 }));
        v.extend_from_slice(&self.lambda);
        v.extend_from_slice(&self.u_n);
        v.extend_from_slice(&self.alpha[..mz]);
        for s in &self.steps {
            v.extend_from_slice(&[s.0 as f64, s.1 as f64, s.2 as f64, s.3, s.4]);
        }
        for c in &self.coarse {
            v.extend_from_slice(&[c.0 as f64, c.1 as f64]);
        }
        if let End::Fallback(why) = &self.end {
            v.extend(why.bytes().map(f64::from));
        }
        v
    }

    pub(super) fn unpack(v: &[f64], n: usize, mz: usize) -> DenseRun {
        let (steps_n, coarse_n) = (v[2] as usize, v[3] as usize);
        let mut p = 4;
        let mut take = |len: usize| {
            let s = &v[p..p + len];
            p += len;
            s.to_vec()
        };
        let active = take(n).iter().map(|&x| x != 0.0).collect();
        let lambda = take(n);
        let u_n = take(n);
        let alpha = take(mz);
        let steps = (0..steps_n)
            .map(|_| {
                let s = take(5);
                (s[0] as usize, s[1] as usize, s[2] as usize, s[3], s[4])
            })
            .collect();
        let coarse = (0..coarse_n)
            .map(|_| {
                let c = take(2);
                (c[0] as usize, c[1] as usize)
            })
            .collect();
        let end = match v[0] as i32 {
            0 => End::Converged,
            1 => End::NoSupport(v[1]),
            // the reason's UTF-8 bytes, one per entry (0..=255: exact in f64)
            _ => End::Fallback(
                String::from_utf8_lossy(&v[p..].iter().map(|&b| b as u8).collect::<Vec<u8>>())
                    .into_owned(),
            ),
        };
        DenseRun {
            active,
            lambda,
            alpha,
            u_n,
            steps,
            end,
            coarse,
        }
    }
}

/// What (3.21) and (3.23) read besides a step's u_n and λ_n, fixed over a dense iteration:
/// the candidates' gaps and the complementarity parameter c.
#[derive(Clone, Copy)]
struct Complementarity<'a> {
    gap: &'a [f64],
    c: f64,
    /// ‖g‖∞ (for the tie width; the gaps do not change over the iteration).
    gap_inf: f64,
}

impl<'a> Complementarity<'a> {
    fn new(gap: &'a [f64], c: f64) -> Self {
        Complementarity {
            gap,
            c,
            gap_inf: inf_norm(gap),
        }
    }
}

/// (3.21) and (3.23) on every candidate from a step's u_n and λ_n on the set `active`: the
/// next set and how many nodes change; the step's record (step, |A_n|, changed, ‖C_n‖₂, the
/// seconds since `t`) pushed onto `steps`. A node whose test is a tie ([`ties`]) keeps its
/// state. Local.
fn update(
    active: &[bool],
    u_n: &[f64],
    lambda: &[f64],
    data: Complementarity,
    step: usize,
    t: Instant,
    steps: &mut Vec<(usize, usize, usize, f64, f64)>,
) -> (Vec<bool>, usize) {
    let Complementarity { gap, c, gap_inf } = data;
    let tie = ties(inf_norm(lambda), inf_norm(u_n).max(gap_inf), c);
    let mut next = active.to_vec();
    let mut changed = 0;
    let mut res2 = 0.0;
    for i in 0..active.len() {
        let cn = c_n(u_n[i], lambda[i], gap[i], c); // (3.21)
        res2 += cn * cn;
        next[i] = normal_active_or_tie(u_n[i], lambda[i], gap[i], c, tie, active[i]); // (3.23)
        changed += usize::from(next[i] != active[i]);
    }
    let n_active = active.iter().filter(|&&a| a).count();
    let secs = t.elapsed().as_secs_f64();
    steps.push((step, n_active, changed, res2.sqrt(), secs));
    (next, changed)
}

/// Algorithm 1 in the primal form on the Schur complement S of the candidates' normal dofs,
/// for zones too wide for the dual form (`Dense`): there C = S⁻¹ costs n³ flops before the
/// first step, here each step solves for the inactive candidates' displacements only. With
/// u the candidates' normal displacements (rigid motion G α included) and r MUMPS' condensation
/// of the load, λ = r − S (u − G α) (the dual's u = d₀ − C λ + G α multiplied by S). On a set
/// A: u_A = −g_A, λ_I = 0 on the rest and the free modes balanced, G_Aᵀ λ_A = φ:
/// [S_II, −(S G)_I; −G_Aᵀ S_AI, G_Aᵀ (S G)_A] [u_I; α] = [r_I − S_IA u_A; φ − G_Aᵀ (r_A − S_AA u_A)],
/// a step of |I| + m_z unknowns — few where the zone fills the candidates.
pub struct Primal<'a> {
    pub s: &'a DMatrix<f64>,
    pub r: &'a [f64],
    pub gap: &'a [f64],
    pub g: &'a DMatrix<f64>,
    pub phi: &'a [f64],
    pub load_scale: f64,
    pub c: f64,
    pub max_steps: usize,
    /// Dense work (flops of one step's LU) beyond which the iteration gives up.
    pub max_flops: f64,
}

impl Primal<'_> {
    /// Algorithm 1 from the set `active` (every candidate active is the cheap start: no
    /// inactive unknowns), (3.23) on λ and u of every candidate, until no node changes; a set
    /// that leaves a free mode unheld (a singular step) or a step beyond `max_flops` gives up.
    /// Local.
    pub fn run(&self, mut active: Vec<bool>) -> DenseRun {
        let mz = self.g.ncols();
        let sg = self.s * self.g;
        let mut seen: HashSet<Vec<bool>> = HashSet::new();
        seen.insert(active.clone());
        let mut steps = Vec::new();
        let data = Complementarity::new(self.gap, self.c);
        for step in 1..=self.max_steps {
            let t = Instant::now();
            let ni = active.iter().filter(|&&a| !a).count();
            if 2.0 / 3.0 * ((ni + mz) as f64).powi(3) > self.max_flops {
                let why = format!(
                    "step {step} of the primal dense iteration has {ni} inactive candidates: \
                     beyond the dense work that pays"
                );
                return DenseRun::unsolved(active, mz, steps, why);
            }
            let Some((lambda, alpha, u)) = self.solve_set(&active, &sg) else {
                let why = format!(
                    "the primal dense system of step {step} is singular or leaves a loaded \
                     rigid mode free"
                );
                return DenseRun::unsolved(active, mz, steps, why);
            };
            let (next, changed) = update(&active, &u, &lambda, data, step, t, &mut steps);
            if changed == 0 {
                return DenseRun {
                    active,
                    lambda,
                    alpha,
                    u_n: u,
                    steps,
                    end: End::Converged,
                    coarse: Vec::new(),
                };
            }
            if !seen.insert(next.clone()) {
                let why = format!("the set of step {} recurs (cycling)", step + 1);
                return DenseRun::unsolved(active, mz, steps, why);
            }
            active = next;
        }
        let why = format!(
            "no convergence in newton.max_steps = {} primal dense steps",
            self.max_steps
        );
        DenseRun::unsolved(active, mz, steps, why)
    }

    /// One step on the set `active`: (λ, α, u) of every candidate, or `None` if singular or
    /// if the load has a part in a free mode the set does not hold (the dual form's balance
    /// test would move the body: not done here). Only the modes the set holds (V_f, as the
    /// dual form) take part: α = V_f β.
    fn solve_set(
        &self,
        active: &[bool],
        sg: &DMatrix<f64>,
    ) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)> {
        let n = self.r.len();
        let mz = self.g.ncols();
        let ii: Vec<usize> = (0..n).filter(|&i| !active[i]).collect();
        let aa: Vec<usize> = (0..n).filter(|&i| active[i]).collect();
        let ga = DMatrix::from_fn(aa.len(), mz, |r, c| self.g[(aa[r], c)]);
        let (vf, vu) = split_modes(&(ga.transpose() * &ga), mz);
        let phi = DVector::from_column_slice(self.phi);
        if mz > 0 && (vu.transpose() * &phi).norm() > BALANCE_RTOL * self.load_scale {
            return None;
        }
        let nf = vf.ncols();
        let (g, sg) = if mz > 0 {
            (self.g * &vf, sg * &vf)
        } else {
            (DMatrix::zeros(n, 0), DMatrix::zeros(n, 0))
        };
        let pf = if mz > 0 {
            vf.transpose() * phi
        } else {
            DVector::zeros(0)
        };
        let ni = ii.len();
        // u with u_A = −g_A and u_I = 0 (its unknowns), S u of it; G with its rows off A zero
        let mut u = vec![0.0; n];
        let mut g_a = DMatrix::<f64>::zeros(n, nf);
        for &j in &aa {
            u[j] = -self.gap[j];
            g_a.set_row(j, &g.row(j));
        }
        let su = self.s * DVector::from_column_slice(&u);
        let s_ga = self.s * &g_a; // S symmetric: (S_IA G_A) on I's rows
        let dim = ni + nf;
        let mut m = DMatrix::<f64>::zeros(dim, dim);
        let mut rhs = DVector::<f64>::zeros(dim);
        for (q, &j) in ii.iter().enumerate() {
            for (p, &i) in ii.iter().enumerate() {
                m[(p, q)] = self.s[(i, j)];
            }
        }
        for (p, &i) in ii.iter().enumerate() {
            for cz in 0..nf {
                m[(p, ni + cz)] = -sg[(i, cz)];
                // −(G_Aᵀ S_AI) = −(S_IA G_A)ᵀ
                m[(ni + cz, p)] = -s_ga[(i, cz)];
            }
            rhs[p] = self.r[i] - su[i];
        }
        for cz in 0..nf {
            for cy in 0..nf {
                m[(ni + cz, ni + cy)] = aa.iter().map(|&a| g[(a, cz)] * sg[(a, cy)]).sum();
            }
            let ga_ra: f64 = aa.iter().map(|&a| g[(a, cz)] * (self.r[a] - su[a])).sum();
            rhs[ni + cz] = pf[cz] - ga_ra;
        }
        let x = if dim == 0 {
            DVector::zeros(0)
        } else {
            DenseLu::factor(&m)?.solve(&rhs)
        };
        if !x.iter().all(|v| v.is_finite()) {
            return None;
        }
        for (p, &i) in ii.iter().enumerate() {
            u[i] = x[p];
        }
        let beta = DVector::from_iterator(nf, (0..nf).map(|cz| x[ni + cz]));
        // λ = r − S (u − G α), zero on I by construction (set exactly)
        let sw = self.s * (DVector::from_column_slice(&u) - &g * &beta);
        let mut lambda = vec![0.0; n];
        for &a in &aa {
            lambda[a] = self.r[a] - sw[a];
        }
        let alpha = if mz > 0 {
            (&vf * beta).as_slice().to_vec()
        } else {
            Vec::new()
        };
        Some((lambda, alpha, u))
    }
}

impl Dense<'_> {
    /// Algorithm 1 from the set `active`: solve the set's dense system, λ_n and u_n of every
    /// candidate, update by (3.23); stop when no node changes (with the balance test of the
    /// modes the set leaves free, as the plain path). Local.
    pub fn run(&self, mut active: Vec<bool>) -> DenseRun {
        let mz = self.g.ncols();
        let mut seen: HashSet<Vec<bool>> = HashSet::new();
        seen.insert(active.clone());
        let mut steps = Vec::new();
        let out = |active: Vec<bool>, lambda, alpha, u_n, steps, end| DenseRun {
            active,
            lambda,
            alpha,
            u_n,
            steps,
            end,
            coarse: Vec::new(),
        };
        let data = Complementarity::new(self.gap, self.c);
        for step in 1..=self.max_steps {
            let t = Instant::now();
            let (lambda, alpha, u_n, free_dirs) = match self.solve_set(&active) {
                Some(x) => x,
                None => {
                    let why = format!("the dense system of step {step} is singular");
                    return DenseRun::unsolved(active, mz, steps, why);
                }
            };
            let (mut next, changed) = update(&active, &u_n, &lambda, data, step, t, &mut steps);
            if changed == 0 {
                match self.balance(&active, &u_n, &free_dirs) {
                    None => return out(active, lambda, alpha, u_n, steps, End::Converged),
                    Some(Ok(i)) => next[i] = true,
                    Some(Err(r)) => {
                        return out(active, lambda, alpha, u_n, steps, End::NoSupport(r))
                    }
                }
            }
            if !seen.insert(next.clone()) {
                return out(
                    active,
                    lambda,
                    alpha,
                    u_n,
                    steps,
                    End::Fallback(format!("the set of step {} recurs (cycling)", step + 1)),
                );
            }
            active = next;
        }
        let n_active = active.iter().filter(|&&a| a).count();
        let why = format!(
            "no convergence in newton.max_steps = {} dense steps ({n_active} active)",
            self.max_steps
        );
        DenseRun::unsolved(active, mz, steps, why)
    }

    /// Nested iteration: Algorithm 1 first on coarse subsets of the candidates (`coarsen`,
    /// coarsest first; each subset's problem holds the contact conditions at its nodes only,
    /// with the exact compliance C between them), each level's solution starting the next
    /// finer one through (3.23) evaluated at every candidate (λ_n = 0 off the subset,
    /// u_n = d₀ − C λ_n + G α); then Algorithm 1 on all candidates from there. The coarse
    /// steps are dense solves of at most half the size; the result's `steps` are the fine
    /// ones, `coarse` (nodes, steps) per level. A coarse level that does not converge leaves
    /// the set as it was. `x`: the candidates' coordinates. Local.
    pub fn run_nested(&self, start: Vec<bool>, x: &[[f64; 3]]) -> DenseRun {
        let levels = coarsen(x, self.gap);
        let mut active = start;
        let mut coarse = Vec::new();
        for idx in levels.iter().rev() {
            let sub_c = self.cmat.block(idx);
            let sub_g = DMatrix::from_fn(idx.len(), self.g.ncols(), |r, c| self.g[(idx[r], c)]);
            let pick = |v: &[f64]| idx.iter().map(|&i| v[i]).collect::<Vec<f64>>();
            let (d0, gap) = (pick(self.d0), pick(self.gap));
            let sub_pins = self.pins.map(|m| (m.subset(idx), m.dim));
            let sub = Dense {
                cmat: CMatrix::Full(&sub_c),
                d0: &d0,
                gap: &gap,
                g: &sub_g,
                pins: sub_pins
                    .as_ref()
                    .map(|(parts, dim)| Moves { parts, dim: *dim }),
                ..*self
            };
            let run = sub.run(idx.iter().map(|&i| active[i]).collect());
            coarse.push((idx.len(), run.steps.len()));
            if run.end != End::Converged {
                continue;
            }
            let mut lambda = DVector::<f64>::zeros(self.d0.len());
            for (r, &i) in idx.iter().enumerate() {
                lambda[i] = run.lambda[r];
            }
            let alpha = DVector::from_column_slice(&run.alpha);
            let un =
                DVector::from_column_slice(self.d0) - self.cmat.times(&lambda) + self.g * alpha;
            active = (0..self.d0.len())
                .map(|i| normal_active(un[i], lambda[i], self.gap[i], self.c)) // (3.23)
                .collect();
        }
        let mut run = self.run(active);
        run.coarse = coarse;
        run
    }

    /// The system of set A: [C_AA, −H; −Hᵀ, 0] [λ_A; β] = [g_A + d₀_A; −V_fᵀ φ] with H = G_A V_f,
    /// V_f the modes A fixes (α = V_f β; the others stay pinned). Returns λ_n (0 off A), α,
    /// u_n = d₀ − C λ + G α, and V_u (the modes A leaves free, m_z × ·). `None` if singular.
    #[allow(clippy::type_complexity)]
    fn solve_set(&self, active: &[bool]) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>, DMatrix<f64>)> {
        let n = self.d0.len();
        let mz = self.g.ncols();
        let idx: Vec<usize> = (0..n).filter(|&i| active[i]).collect();
        let na = idx.len();
        let ga = DMatrix::from_fn(na, mz, |r, c| self.g[(idx[r], c)]);
        let (vf, vu) = split_modes(&(ga.transpose() * &ga), mz);
        let nf = vf.ncols();
        let h = &ga * &vf;
        let dimn = na + nf;
        let mut rhs = DVector::<f64>::zeros(dimn);
        for (r, &i) in idx.iter().enumerate() {
            rhs[r] = self.gap[i] + self.d0[i];
        }
        let phi = DVector::from_column_slice(self.phi);
        let pf = vf.transpose() * phi;
        for c in 0..nf {
            rhs[na + c] = -pf[c];
        }
        // M x for M = [C_AA, −H; −Hᵀ, 0]
        let apply = |x: &DVector<f64>| {
            let (l, b) = (x.rows(0, na), x.rows(na, nf));
            let mut y = DVector::zeros(dimn);
            y.rows_mut(0, na)
                .copy_from(&(self.cmat.block_times(&idx, l.as_slice()) - &h * b));
            y.rows_mut(na, nf).copy_from(&(-(h.transpose() * l)));
            y
        };
        let x = if dimn == 0 {
            DVector::zeros(0)
        } else {
            // C_AA is factorised in place (the half-space model's largest matrix after C)
            let solve = SaddleSolver::new(|| self.cmat.block(&idx), &h)?;
            let mut x = solve.solve(&rhs);
            // Two steps of iterative refinement: the balance rows' residual (the load the
            // pins would carry, i.e. the total contact force) to round-off of their own
            // scale, also when the gaps and α hold a large rigid motion (a body 700 units
            // away: the rows' right-hand sides are ~700 while λ's effect is ~1e-3).
            for _ in 0..2 {
                let r = &rhs - apply(&x);
                x += solve.solve(&r);
            }
            if !x.iter().all(|v| v.is_finite()) {
                return None;
            }
            x
        };
        let mut lambda = vec![0.0; n];
        for (r, &i) in idx.iter().enumerate() {
            lambda[i] = x[r];
        }
        let beta = DVector::from_iterator(nf, (0..nf).map(|c| x[na + c]));
        let alpha = &vf * beta;
        let la = DVector::from_column_slice(&lambda);
        let un = DVector::from_column_slice(self.d0) - self.cmat.times(&la) + self.g * &alpha;
        Some((
            lambda,
            alpha.as_slice().to_vec(),
            un.as_slice().to_vec(),
            vu,
        ))
    }

    /// The plain path's balance test on the modes the set leaves free (`vu`): `None` balanced;
    /// `Some(Ok(i))` the inactive node a rigid motion along the unbalanced load brings into
    /// contact first; `Some(Err(r))` no node approaches (no support, unbalanced load r).
    fn balance(
        &self,
        active: &[bool],
        u_n: &[f64],
        vu: &DMatrix<f64>,
    ) -> Option<Result<usize, f64>> {
        if vu.ncols() == 0 {
            return None;
        }
        let mut phi = DVector::from_column_slice(self.phi);
        // An estimate's pins carry the load only beside a node in contact: from the empty
        // set they would carry all of it, and the estimate would end with nothing in contact
        // (measured: the floating ball at 56 k unknowns, Coulomb's start, when no coarse node
        // of the nested start penetrated). Where no node approaches, they still carry it.
        let empty = !active.iter().any(|&a| a);
        if let Some(pins) = self.pins.filter(|_| !empty) {
            pins.uncarried(active, &mut phi);
        }
        let pu = vu.transpose() * phi;
        let norm = pu.norm();
        if norm <= BALANCE_RTOL * self.load_scale {
            return None;
        }
        let dir = vu * pu / norm; // motion per unit length, in z coordinates
        let mut best: Option<(f64, usize)> = None;
        for i in 0..active.len() {
            if active[i] {
                continue;
            }
            let speed = -(0..dir.len()).map(|c| self.g[(i, c)] * dir[c]).sum::<f64>();
            if speed <= 1e-12 {
                continue;
            }
            let a = (u_n[i] + self.gap[i]).max(0.0) / speed;
            if best.is_none_or(|(b, _)| a < b) {
                best = Some((a, i));
            }
        }
        match best {
            Some((_, i)) => Some(Ok(i)),
            None if empty && self.pins.is_some() => None,
            None => Some(Err(norm)),
        }
    }
}

/// Solves [C, −H; −Hᵀ, 0] [λ; β] = [r₁; r₂] (C symmetric positive definite, n × n; H n × m,
/// m ≤ 6): by LAPACK's Cholesky of C and the m × m Schur complement Hᵀ C⁻¹ H, or, if C is
/// not positive definite to LAPACK or H is rank-deficient, by the LU of the whole matrix.
enum SaddleSolver {
    Cholesky {
        c: DenseCholesky,
        /// C⁻¹ H and the LU of Hᵀ C⁻¹ H.
        ch: DMatrix<f64>,
        t: nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>,
        h: DMatrix<f64>,
    },
    Lu(DenseLu),
}

impl SaddleSolver {
    /// The solver of C = `c()` (formed once for the Cholesky, factorised in place, and once
    /// more for the LU where that fails) and `h`.
    fn new(c: impl Fn() -> DMatrix<f64>, h: &DMatrix<f64>) -> Option<SaddleSolver> {
        let (n, m) = (h.nrows(), h.ncols());
        if let Some(chol) = DenseCholesky::factor_owned(n, c().data.into()) {
            let ch = chol.solve(h);
            let t = (h.transpose() * &ch).lu();
            if m == 0 || t.is_invertible() {
                return Some(SaddleSolver::Cholesky {
                    c: chol,
                    ch,
                    t,
                    h: h.clone(),
                });
            }
        }
        let mut full = DMatrix::zeros(n + m, n + m);
        full.view_mut((0, 0), (n, n)).copy_from(&c());
        full.view_mut((0, n), (n, m)).copy_from(&(-h));
        full.view_mut((n, 0), (m, n)).copy_from(&(-h.transpose()));
        DenseLu::factor(&full).map(SaddleSolver::Lu)
    }

    fn solve(&self, r: &DVector<f64>) -> DVector<f64> {
        match self {
            SaddleSolver::Lu(lu) => lu.solve(r),
            SaddleSolver::Cholesky { c, ch, t, h } => {
                let (n, m) = (h.nrows(), h.ncols());
                let r1 = DMatrix::from_column_slice(n, 1, r.rows(0, n).as_slice());
                let y1 = c.solve(&r1).column(0).into_owned();
                let mut x = DVector::zeros(n + m);
                if m == 0 {
                    x.copy_from(&y1);
                    return x;
                }
                // −Hᵀ (y₁ + C⁻¹H β) = r₂  ⇒  (Hᵀ C⁻¹ H) β = −r₂ − Hᵀ y₁
                let rhs = -r.rows(n, m) - h.transpose() * &y1;
                let beta = t
                    .solve(&rhs)
                    .unwrap_or_else(|| DVector::from_element(m, f64::NAN));
                x.rows_mut(0, n).copy_from(&(y1 + ch * &beta));
                x.rows_mut(n, m).copy_from(&beta);
                x
            }
        }
    }
}

/// The coarse subsets of the nested iteration, finest first, for points `x` (the candidates):
/// level k keeps, greedily in the order of increasing gap (the first contact first), the
/// points of level k − 1 farther than r_k = 2^k · 0.99 h from every point kept before, h the
/// median distance of a point to its nearest neighbour (sampled): about every second point of
/// a contact line, every fourth of a contact surface, whatever the mesh. Levels stop at
/// fewer than COARSEST points; a radius that keeps more than 3/4 of the level before (graded
/// meshes) makes no level, the next radius is tried. Local.
/// The points' spacing: the median distance of every (n / `samples`)-th point to its nearest
/// other one (`samples` ≥ n: of every point). At least two points. Local.
pub(super) fn median_spacing(x: &[[f64; 3]], samples: usize) -> f64 {
    let n = x.len();
    let d2 = |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>();
    let mut nn: Vec<f64> = (0..n)
        .step_by((n / samples.max(1)).max(1))
        .map(|i| {
            (0..n)
                .filter(|&j| j != i)
                .map(|j| d2(&x[i], &x[j]))
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    nn.sort_by(f64::total_cmp);
    nn[nn.len() / 2].sqrt()
}

pub(super) fn coarsen(x: &[[f64; 3]], gap: &[f64]) -> Vec<Vec<usize>> {
    let n = x.len();
    if n < 2 * COARSEST {
        return Vec::new();
    }
    let d2 = |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>();
    let h = median_spacing(x, SPACING_SAMPLES);
    if !(h > 0.0 && h.is_finite()) {
        return Vec::new();
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| gap[a].total_cmp(&gap[b]).then(a.cmp(&b)));
    let mut levels: Vec<Vec<usize>> = Vec::new();
    let mut prev: Vec<usize> = order; // level 0: every point, by gap
    let mut r = COARSEN_RADIUS * h;
    loop {
        r *= 2.0;
        let mut kept: Vec<usize> = Vec::new();
        for &i in &prev {
            if kept.iter().all(|&j| d2(&x[i], &x[j]) >= r * r) {
                kept.push(i);
            }
        }
        if kept.len() < COARSEST {
            break;
        }
        if COARSEN_KEEP[1] * kept.len() <= COARSEN_KEEP[0] * prev.len() {
            levels.push(kept.clone());
            prev = kept;
        }
    }
    levels
}

/// The modes (columns of the m_z × m_z identity's eigenbasis of the Gram matrix `gram`) that
/// a set fixes (eigenvalue above 1e-9 of the largest, at least 1e-9) and those it leaves free.
fn split_modes(gram: &DMatrix<f64>, mz: usize) -> (DMatrix<f64>, DMatrix<f64>) {
    if mz == 0 {
        return (DMatrix::zeros(0, 0), DMatrix::zeros(0, 0));
    }
    let eig = SymmetricEigen::new(gram.clone());
    let lmax = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let tol = 1e-9 * lmax.max(1.0);
    let fixed: Vec<usize> = (0..mz).filter(|&i| eig.eigenvalues[i] >= tol).collect();
    let loose: Vec<usize> = (0..mz).filter(|&i| eig.eigenvalues[i] < tol).collect();
    let pick = |cols: &[usize]| {
        let mut q = DMatrix::zeros(mz, cols.len());
        for (c, &i) in cols.iter().enumerate() {
            q.set_column(c, &eig.eigenvectors.column(i));
        }
        q
    };
    (pick(&fixed), pick(&loose))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric positive definite n × n compliance (decaying with the distance of points
    /// on a line) and its upper triangle packed column by column.
    fn compliance(n: usize) -> (DMatrix<f64>, Vec<f64>) {
        let c = DMatrix::from_fn(n, n, |i, j| {
            let d = (i as f64 - j as f64).abs();
            1.0 / (1.0 + d) + if i == j { 1.0 } else { 0.0 }
        });
        let packed = (0..n).flat_map(|j| (0..=j).map(move |i| (i, j)));
        let packed = packed.map(|(i, j)| c[(i, j)]).collect();
        (c, packed)
    }

    /// A dense iteration on `cmat` without free modes, c = 1, at most 50 steps.
    fn plain<'a>(
        cmat: CMatrix<'a>,
        d0: &'a [f64],
        gap: &'a [f64],
        g: &'a DMatrix<f64>,
    ) -> Dense<'a> {
        Dense {
            cmat,
            d0,
            gap,
            g,
            phi: &[],
            load_scale: 1.0,
            c: 1.0,
            max_steps: 50,
            pins: None,
        }
    }

    /// The packed upper triangle reads as the full matrix: entries, products, blocks.
    #[test]
    fn a_packed_compliance_reads_as_the_full_matrix() {
        let n = 37;
        let (c, packed) = compliance(n);
        let (full, upper) = (CMatrix::Full(&c), CMatrix::Upper { n, packed: &packed });
        for i in 0..n {
            for j in 0..n {
                assert_eq!(full.at(i, j), upper.at(i, j), "({i}, {j})");
            }
        }
        let x = DVector::from_fn(n, |i, _| (i as f64 * 0.7).sin());
        let (yf, yu) = (full.times(&x), upper.times(&x));
        assert!((&yf - &yu).amax() <= 1e-13 * yf.amax(), "C x");
        // against the sums Σ_j C_ij x_j written out
        let sums = DVector::from_fn(n, |i, _| (0..n).map(|j| c[(i, j)] * x[j]).sum::<f64>());
        assert!(
            (&yu - &sums).amax() <= 1e-13 * sums.amax(),
            "C x by its sums"
        );
        // few nonzeros (the sparse branch of the packed product)
        let sparse = DVector::from_fn(n, |i, _| if i % 9 == 4 { i as f64 - 10.0 } else { 0.0 });
        let (yf, yu) = (full.times(&sparse), upper.times(&sparse));
        assert!((&yf - &yu).amax() <= 1e-13 * yf.amax(), "C x, x sparse");
        let idx = [30, 2, 17, 5, 36];
        assert_eq!(full.block(&idx), upper.block(&idx));
        assert_eq!(
            full.block(&[3, 3, 8]),
            upper.block(&[3, 3, 8]),
            "an index twice"
        );
        let xi = [1.0, -2.0, 0.5, 3.0, -1.5];
        let by_block = full.block(&idx) * DVector::from_column_slice(&xi);
        for cm in [full, upper] {
            let y = cm.block_times(&idx, &xi);
            assert!((&y - &by_block).amax() <= 1e-13 * by_block.amax(), "C_II x");
        }
        // a column (= a row) and C X
        let (mut col_f, mut col_u) = (vec![0.0; n], vec![0.0; n]);
        for j in [0, 1, 18, n - 1] {
            full.column_into(j, &mut col_f);
            upper.column_into(j, &mut col_u);
            assert_eq!(col_f, col_u, "column {j}");
            assert!((0..n).all(|i| col_u[i] == c[(j, i)]), "row {j}");
        }
        let xs = DMatrix::from_fn(n, 3, |i, k| ((i + 7 * k) as f64 * 0.3).cos());
        let (yf, yu) = (full.times_columns(&xs), upper.times_columns(&xs));
        assert!((&yf - &yu).amax() <= 1e-13 * yf.amax(), "C X");
    }

    #[test]
    fn pack_upper_packs_either_triangle() {
        let n = 23;
        let (c, packed) = compliance(n);
        // the full matrix in place, and a copy from one with only its lower triangle (the
        // upper one garbage)
        let mut lower = c.as_slice().to_vec();
        for j in 0..n {
            for i in 0..j {
                lower[j * n + i] = f64::NAN;
            }
        }
        let in_place = pack_upper(c.as_slice().to_vec(), n);
        assert_eq!(in_place, packed);
        assert!(in_place.capacity() < n * n, "shrunk to the triangle");
        assert_eq!(pack_upper_of_lower(&lower, n), packed);
    }

    /// Algorithm 1 on either storage of the same compliance: the same set and λ_n.
    #[test]
    fn algorithm_1_on_a_packed_compliance_is_the_full_one() {
        let n = 60;
        let (c, packed) = compliance(n);
        let gap: Vec<f64> = (0..n).map(|i| 0.01 * (i as f64 - 29.5).powi(2)).collect();
        let d0 = vec![-2.0; n];
        let g = DMatrix::zeros(n, 0);
        let run = |cmat| plain(cmat, &d0, &gap, &g).run(vec![false; n]);
        let (a, b) = (
            run(CMatrix::Full(&c)),
            run(CMatrix::Upper { n, packed: &packed }),
        );
        assert_eq!(a.end, End::Converged);
        assert_eq!(a.active, b.active);
        let active = a.active.iter().filter(|&&x| x).count();
        assert!(
            active > 2 && active < n,
            "{active} active: a set with an edge"
        );
        let scale = a.lambda.iter().fold(0.0f64, |m, l| m.max(l.abs()));
        for (la, lb) in a.lambda.iter().zip(&b.lambda) {
            assert!((la - lb).abs() <= 1e-12 * scale, "{la} {lb}");
        }
    }

    /// A node that carries no force at zero gap in the solution (a tie of (3.23)) ends in the
    /// same state whichever sign round-off gives its gap: the iteration does not turn on the
    /// sign of round-off (a floating plate tipped on an edge failed in 2 of 8 runs on 3 ranks
    /// when such a node left the set). A gap a thousand times the tie's width still decides.
    #[test]
    fn a_node_at_a_tie_keeps_its_state_whatever_the_sign_of_round_off() {
        let n = 40;
        let (c, _) = compliance(n);
        let mut gap: Vec<f64> = (0..n).map(|i| 0.01 * (i as f64 - 19.5).powi(2)).collect();
        let d0 = vec![-2.0; n];
        let g = DMatrix::zeros(n, 0);
        let run = |gap: &[f64]| plain(CMatrix::Full(&c), &d0, gap, &g).run(vec![false; n]);
        let first = run(&gap);
        assert_eq!(first.end, End::Converged);
        // the first inactive node beside the zone, moved to touch with no force
        let j = (1..n)
            .find(|&i| first.active[i - 1] && !first.active[i])
            .unwrap();
        gap[j] = -first.u_n[j];
        let scale = gap.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let mut ends = Vec::new();
        for delta in [-4e-16, -1e-16, 0.0, 1e-16, 4e-16] {
            let mut moved = gap.clone();
            moved[j] += delta * scale;
            let r = run(&moved);
            assert_eq!(r.end, End::Converged, "δ = {delta}");
            ends.push(r.active);
        }
        assert!(ends.iter().all(|a| *a == ends[0]), "the sets differ by δ");
        // a clear penetration decides
        let mut deeper = gap.clone();
        deeper[j] -= 1e-10 * scale;
        assert!(run(&deeper).active[j], "1e-10 inside the obstacle enters");
    }
}
