//! The frictionless contact problem through PETSc's SNES VI, as an in-binary baseline for
//! Algorithm 1.
//!
//! The problem is the one Algorithm 1 solves (docs/method.md, "The method in brief"): minimise ½ uᵀAu − fᵀu subject
//! to n_kᵀu_k ≥ −g_k at every contact node k (3.3), whose optimality conditions are (3.14)
//! with λ = f − A u (3.28). SNES VI bounds act on single variables, so the dofs of every
//! contact node are rotated into its frame {n, τ₁, τ₂}:
//!
//!   u = R x,  R = blockdiag(R_k),  R_k = [n τ₁ τ₂] at contact nodes, identity elsewhere,
//!   A' = Rᵀ A R  (MatPtAP),  f' = Rᵀ f,
//!
//! and x_n^k ≥ −g_k is a lower bound on one variable. R is orthogonal, so A' is symmetric
//! positive (semi)definite like A and F(x) = A'x − f' is the gradient of the rotated energy.
//! At a solution, (f' − A'x)_k = R_kᵀ λ_k: its normal component is λ_n ≤ 0 and its tangential
//! components vanish (λ_τ = 0), which are (3.14) for the frictionless problem.
//!
//! Pinned dofs (rigid modes fixed by neither Dirichlet data nor contact, chosen by the caller)
//! are eliminated symmetrically in A' (row and column zero, diagonal kept at A's scale, f'_p =
//! 0), exactly as Algorithm 1 pins them. They are not given as bounds l = u = 0: PETSc's
//! reduced-space method treats a variable on its bound with F = 0 as inactive, and a pinned
//! dof at rest has F = 0, so the pin would be dropped from the first linear system.

use crate::petsc::{self, snes, MPI_Comm, Matrix, PInt, Vector};
use std::fmt;
use std::time::Instant;

/// One owned contact node, as plain data.
#[derive(Clone, Copy, Debug)]
pub struct SnesContactNode {
    /// Global index of the node's first dof (its dofs are row .. row + dim, all owned here).
    pub row: usize,
    /// Unit outer normal of the obstacle at the node's projection (z ignored in 2D).
    pub normal: [f64; 3],
    /// Initial normal gap g_k (3.3): the constraint is nᵀu_k ≥ −g_k.
    pub gap: f64,
}

/// What [`solve_snesvi`] returns.
pub struct SnesViResult {
    /// Displacement in the original (x, y, z) frame, with A's layout.
    pub u: Vector,
    /// SNES (nonlinear) iterations.
    pub steps: usize,
    /// KSP iterations over all steps (1 per step with the direct preset).
    pub linear_iterations: usize,
    /// Residual evaluations (line search included).
    pub function_evals: usize,
    pub converged: bool,
    /// SNESConvergedReason and its name.
    pub reason_code: i32,
    pub reason: String,
    /// "vinewtonrsls" unless the options database chose another type.
    pub snes_type: String,
    /// Rotation and elimination: building R, A' = RᵀAR, f' = Rᵀf, the bounds.
    pub setup_seconds: f64,
    /// SNESSolve.
    pub solve_seconds: f64,
    /// Everything, including u = R x.
    pub seconds: f64,
}

/// Why [`solve_snesvi`] failed.
#[derive(Debug)]
pub enum SnesViError {
    /// The arguments do not fit the matrix (a caller's bug).
    Input(String),
    Petsc(petsc::PetscError),
}

impl fmt::Display for SnesViError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SnesViError::Input(s) => write!(f, "snesvi: {s}"),
            SnesViError::Petsc(e) => write!(f, "snesvi: {e}"),
        }
    }
}

impl std::error::Error for SnesViError {}

impl From<petsc::PetscError> for SnesViError {
    fn from(e: petsc::PetscError) -> Self {
        SnesViError::Petsc(e)
    }
}

/// Default relative tolerance of the inactive-set residual (-snes_rtol overrides). The
/// residual is linear and every reduced-space step an exact solve, so the residual is either
/// that of a wrong active set (large) or round-off: any tolerance in between stops at the same
/// step. Round-off relative to the first residual grows with the mesh (1.2e-12 on the refined
/// Hertz level 6, 150 k unknowns, where 1e-12 was never reached and SNES ran into its
/// iteration cap): 1e-10 stays above it and far below the 1e-8 agreement with Algorithm 1.
pub const DEFAULT_RTOL: f64 = 1e-10;
/// Default line search of vinewtonrsls: the full projected Newton step (-snes_linesearch_type
/// overrides; vinewtonssls keeps PETSc's default).
/// The residual is linear and the linear solves exact, so each reduced-space step is already
/// the exact solution on its inactive set; PETSc's default for VI ("bt", sufficient decrease
/// of the inactive-set residual) rejects the first step whenever that system is singular in a
/// rigid mode only the contact holds (block on a plane: every contact node starts on its bound
/// with F = 0, which PETSc counts inactive) and stops with DIVERGED_LINE_SEARCH.
pub const DEFAULT_LINESEARCH: &str = "basic";
/// Default iteration cap (-snes_max_it overrides).
pub const DEFAULT_MAX_IT: usize = 200;

/// An orthonormal frame {n, τ₁, τ₂} with first vector the unit normal (the columns of R_k).
/// Any completion will do: the tangential variables are unbounded.
fn frame(normal: &[f64; 3], dim: usize) -> Option<[[f64; 3]; 3]> {
    let mut n = [0.0; 3];
    n[..dim].copy_from_slice(&normal[..dim]);
    let len = n.iter().map(|x| x * x).sum::<f64>().sqrt();
    if len.is_nan() || len <= 0.0 || !len.is_finite() {
        return None;
    }
    n.iter_mut().for_each(|x| *x /= len);
    if dim == 2 {
        return Some([n, [-n[1], n[0], 0.0], [0.0, 0.0, 1.0]]);
    }
    // τ₁ ⟂ n from the axis least aligned with n, τ₂ = n × τ₁.
    let k = (0..3)
        .min_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
        .expect("three axes");
    let mut e = [0.0; 3];
    e[k] = 1.0;
    let d: f64 = (0..3).map(|i| e[i] * n[i]).sum();
    let mut t1 = [0.0; 3];
    for i in 0..3 {
        t1[i] = e[i] - d * n[i];
    }
    let l1 = t1.iter().map(|x| x * x).sum::<f64>().sqrt();
    t1.iter_mut().for_each(|x| *x /= l1);
    let t2 = [
        n[1] * t1[2] - n[2] * t1[1],
        n[2] * t1[0] - n[0] * t1[2],
        n[0] * t1[1] - n[1] * t1[0],
    ];
    Some([n, t1, t2])
}

/// One contact node in its frame: the node's first dof, the columns of R_k and the gap g_k.
struct NodeFrame {
    row: usize,
    e: [[f64; 3]; 3],
    gap: f64,
}

/// The rotation R = blockdiag(R_k) (owned rows in CSR): at contact node k the rows
/// row .. row + dim hold R_k[a][j] = e_j[a] with e_0 = n, e_1 = τ₁, e_2 = τ₂; elsewhere 1.
fn rotation(
    comm: MPI_Comm,
    dim: usize,
    lo: usize,
    hi: usize,
    frames: &[NodeFrame],
) -> petsc::Result<Matrix> {
    let n = hi - lo;
    let mut node_of = vec![usize::MAX; n];
    for (i, f) in frames.iter().enumerate() {
        for a in 0..dim {
            node_of[f.row - lo + a] = i;
        }
    }
    let mut rowptr: Vec<PInt> = Vec::with_capacity(n + 1);
    let mut cols: Vec<PInt> = Vec::with_capacity(n);
    let mut vals: Vec<f64> = Vec::with_capacity(n);
    rowptr.push(0);
    for r in 0..n {
        match node_of[r] {
            usize::MAX => {
                cols.push((lo + r) as PInt);
                vals.push(1.0);
            }
            i => {
                let NodeFrame { row, e, .. } = &frames[i];
                let a = lo + r - row;
                for (j, ej) in e.iter().enumerate().take(dim) {
                    cols.push((row + j) as PInt);
                    vals.push(ej[a]);
                }
            }
        }
        rowptr.push(cols.len() as PInt);
    }
    let mut m = Matrix::from_csr(comm, dim, &rowptr, &cols, &vals)?;
    m.assemble()?;
    Ok(m)
}

/// This rank's owned dof range and the problem's dimension.
#[derive(Clone, Copy)]
struct Layout {
    dim: usize,
    lo: usize,
    hi: usize,
}

/// The frames of this rank's contact nodes, sorted by row, after checking that every node is
/// a whole owned node with a finite gap and a proper normal, listed once.
fn contact_frames(at: Layout, contact: &[SnesContactNode]) -> Result<Vec<NodeFrame>, SnesViError> {
    let Layout { dim, lo, hi } = at;
    let mut frames = Vec::with_capacity(contact.len());
    for k in contact {
        if k.row < lo || k.row + dim > hi || (k.row - lo) % dim != 0 {
            return Err(SnesViError::Input(format!(
                "contact node at dof {}: not a node of this rank's rows {lo}..{hi}",
                k.row
            )));
        }
        if !k.gap.is_finite() {
            return Err(SnesViError::Input(format!(
                "contact node at dof {}: gap {} is not finite",
                k.row, k.gap
            )));
        }
        let e = frame(&k.normal, dim).ok_or_else(|| {
            SnesViError::Input(format!(
                "contact node at dof {}: normal {:?} is not a direction",
                k.row,
                &k.normal[..dim]
            ))
        })?;
        frames.push(NodeFrame {
            row: k.row,
            e,
            gap: k.gap,
        });
    }
    frames.sort_by_key(|f| f.row);
    if frames.windows(2).any(|w| w[0].row == w[1].row) {
        return Err(SnesViError::Input("a contact node is listed twice".into()));
    }
    Ok(frames)
}

/// The pinned dofs this rank owns, sorted and without repeats; none may be a contact node's.
fn owned_pins(
    at: Layout,
    pinned_dofs: &[usize],
    frames: &[NodeFrame],
) -> Result<Vec<PInt>, SnesViError> {
    let Layout { dim, lo, hi } = at;
    let mut pins: Vec<PInt> = Vec::new();
    for &p in pinned_dofs {
        if p < lo || p >= hi {
            continue;
        }
        let node_row = p - (p - lo) % dim;
        if frames.binary_search_by_key(&node_row, |f| f.row).is_ok() {
            return Err(SnesViError::Input(format!(
                "pinned dof {p} belongs to a contact node"
            )));
        }
        pins.push(p as PInt);
    }
    pins.sort_unstable();
    pins.dedup();
    Ok(pins)
}

/// The problem in the contact frames: R, A' = Rᵀ A R and f' = Rᵀ f, pins eliminated.
struct Rotated {
    r: Matrix,
    a: Matrix,
    b: Vector,
}

/// A' = Rᵀ A R, f' = Rᵀ f, then the pins eliminated symmetrically at the scale of A's
/// diagonal (one value on every rank).
fn rotated_system(
    comm: MPI_Comm,
    at: Layout,
    a: &Matrix,
    b: &Vector,
    frames: &[NodeFrame],
    pins: &[PInt],
) -> petsc::Result<Rotated> {
    let r = rotation(comm, at.dim, at.lo, at.hi, frames)?;
    let mut ar = a.ptap(&r)?;
    let mut br = b.duplicate()?;
    r.mult_transpose(b, &mut br)?;
    let mut d = b.duplicate()?;
    a.diagonal(&mut d)?;
    let dmax_local = d.read(|s| s.iter().fold(0.0f64, |m, x| m.max(x.abs())))?;
    let dmax = all_max(comm, dmax_local)?;
    ar.zero_rows_columns(pins, if dmax > 0.0 { dmax } else { 1.0 })?;
    br.write(|s| {
        for &p in pins {
            s[p as usize - at.lo] = 0.0;
        }
    })?;
    Ok(Rotated { r, a: ar, b: br })
}

/// The bounds of the SNES VI and its start.
struct BoundsAndStart {
    lower: Vector,
    upper: Vector,
    x: Vector,
}

/// The bounds x_n ≥ −g at contact nodes (free elsewhere) and the start, u = 0 projected onto
/// them (x_n = max(0, −g)); vinewtonrsls would project it itself, vinewtonssls needs a
/// feasible start.
fn bounds_and_start(b: &Vector, lo: usize, frames: &[NodeFrame]) -> petsc::Result<BoundsAndStart> {
    let mut lower = b.duplicate()?;
    lower.set_all(-snes::INFINITY)?;
    let mut upper = b.duplicate()?;
    upper.set_all(snes::INFINITY)?;
    lower.write(|s| {
        for f in frames {
            s[f.row - lo] = -f.gap;
        }
    })?;
    let mut x = b.duplicate()?;
    x.write(|s| {
        for f in frames {
            s[f.row - lo] = (-f.gap).max(0.0);
        }
    })?;
    Ok(BoundsAndStart { lower, upper, x })
}

/// Solves the frictionless contact problem (3.3)/(3.14) — the problem of Algorithm 1 — on the
/// assembled A, f (Dirichlet data already eliminated) with PETSc SNES VI (`vinewtonrsls`, or
/// what `-snes_type` says), in the contact nodes' frames (module doc). `contact`: this rank's
/// contact nodes (owned dofs). `pinned_dofs`: global dof indices held at 0, the same list on
/// every rank (each rank uses the ones it owns); they must not be dofs of contact nodes. The
/// linear solver inside SNES comes from the options database (the project's presets).
/// Collective on `comm`. The multipliers are λ = f − A u (3.28).
pub fn solve_snesvi(
    comm: MPI_Comm,
    dim: usize,
    a: &Matrix,
    b: &Vector,
    contact: &[SnesContactNode],
    pinned_dofs: &[usize],
) -> Result<SnesViResult, SnesViError> {
    let t0 = Instant::now();
    if !(dim == 2 || dim == 3) {
        return Err(SnesViError::Input(format!(
            "dimension {dim}: must be 2 or 3"
        )));
    }
    let (lo, hi) = a.ownership_range()?;
    let at = Layout { dim, lo, hi };
    let frames = contact_frames(at, contact)?;
    let pins = owned_pins(at, pinned_dofs, &frames)?;
    let rot = rotated_system(comm, at, a, b, &frames, &pins)?;
    let BoundsAndStart {
        lower,
        upper,
        mut x,
    } = bounds_and_start(b, lo, &frames)?;
    let setup_seconds = t0.elapsed().as_secs_f64();

    let t1 = Instant::now();
    let settings = snes::ViSettings {
        default_type: "vinewtonrsls",
        default_linesearch: Some(DEFAULT_LINESEARCH),
        rtol: DEFAULT_RTOL,
        max_it: DEFAULT_MAX_IT,
    };
    let info = snes::solve_linear_vi(comm, &rot.a, &rot.b, &lower, &upper, &mut x, &settings)?;
    let solve_seconds = t1.elapsed().as_secs_f64();

    let mut u = b.duplicate()?;
    rot.r.mult(&x, &mut u)?;
    Ok(SnesViResult {
        u,
        steps: info.iterations,
        linear_iterations: info.linear_iterations,
        function_evals: info.function_evals,
        converged: info.converged(),
        reason_code: info.reason,
        reason: info.reason_name,
        snes_type: info.snes_type,
        setup_seconds,
        solve_seconds,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The largest `local` over all ranks (a PETSc vector with one entry per rank, so that this
/// module needs no rsmpi communicator).
fn all_max(comm: MPI_Comm, local: f64) -> petsc::Result<f64> {
    let mut v = Vector::new_mpi(comm, 1, 1)?;
    v.set_all(local)?;
    v.norm_inf()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal_with_the_normal_first() {
        let normals = [
            [0.0, 1.0, 0.0],
            [0.6, -0.8, 0.0],
            [0.0, 0.0, 2.0],
            [1.0, 2.0, -3.0],
            [-0.3, 0.1, 0.9],
        ];
        for dim in [2, 3] {
            for n in &normals {
                if dim == 2 && n[2] != 0.0 {
                    continue;
                }
                let e = frame(n, dim).expect("a direction");
                let len = n.iter().map(|x| x * x).sum::<f64>().sqrt();
                for a in 0..dim {
                    assert!((e[0][a] - n[a] / len).abs() < 1e-15);
                }
                for i in 0..dim {
                    for j in 0..dim {
                        let d: f64 = (0..dim).map(|a| e[i][a] * e[j][a]).sum();
                        let want = if i == j { 1.0 } else { 0.0 };
                        assert!(
                            (d - want).abs() < 1e-14,
                            "dim {dim} n {n:?}: e{i}·e{j} = {d}"
                        );
                    }
                }
            }
        }
        assert!(frame(&[0.0, 0.0, 0.0], 3).is_none());
        assert!(frame(&[f64::NAN, 0.0, 0.0], 2).is_none());
    }
}
