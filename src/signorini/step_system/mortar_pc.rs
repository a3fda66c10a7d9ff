//! The iterative preset's preconditioner for body pairs. The step system lives in the contact
//! unknowns w (u = Q w + c, mortar/basis.rs), where algebraic multigrid on Qᵀ A Q converges
//! slowly even with no node held: the change of basis glues the bodies' stencils along the
//! slave group (a quarter ball on a block, 85 374 unknowns: 295 GMRES iterations with no node
//! in contact, against 18 for A). This preconditioner works in u instead. With Π the
//! projection off the directions the step holds (a contact node's normal, a stick node's
//! tangents, pins), u = Q Π w spans the displacements that satisfy the held mortar rows, on
//! which the step's matrix is A itself; so P⁻¹ = Π Q⁻¹ M⁻¹ Q⁻ᵀ Π on the free directions,
//! M⁻¹ one AMG cycle on A (the linear solve's hierarchy: the two bodies apart), and the held
//! rows' own inverse 1/s_k on the held directions (their rows are s_k c cᵀ alone,
//! step_system/write.rs). A slip row's spring (3.39) and Coulomb's row mix (F7) are left to
//! the Krylov iterations. A does not change during a run, so the hierarchy is built once for
//! the run (every Newton and load step); the held set enters through Π alone. (AMG on A plus
//! a penalty ρ c cᵀ on the held rows, rebuilt when the set changes, took fewer iterations per
//! step but cost more in its set-ups: docs/numbers.md, "3D body pairs on the iterative
//! preset".)

use crate::petsc::ksp::Ksp;
use crate::petsc::optdb::OptionsDb;
use crate::petsc::shellpc::Preconditioner;
use crate::petsc::{self, Matrix, Vector};
use std::cell::RefCell;
use std::rc::Rc;

/// The name of the shell (PCShellSetName).
pub const SHELL_NAME: &str = "amg in u for body pairs";

/// The options prefix of the inner AMG (its options are the iterative preset's GAMG options).
pub const PREFIX: &str = "mortar_";

/// One node whose rows the step rewrote: its first local row, the held unit directions (none
/// for a slip row alone), the node's mean diagonal s_k (the held rows' diagonal), and its
/// factors in S = L A P + D (matrix_free.rs): P_k, left_k and its own block D_k.
#[derive(Clone, Debug)]
pub struct Held {
    pub lr: usize,
    pub dirs: Vec<[f64; 3]>,
    pub s: f64,
    pub proj: [[f64; 3]; 3],
    pub left: [[f64; 3]; 3],
    pub own: [[f64; 3]; 3],
}

/// The rewritten nodes of the step written last, shared by the step system (which writes them)
/// and the preconditioner and operator (which read them).
pub type HeldNodes = Rc<RefCell<Vec<Held>>>;

/// The AMG cycle on A: a KSP with [`PREFIX`] (preonly + GAMG) and whether its hierarchy is
/// built. A does not change during a run, so the session keeps it for every solve and load
/// step.
pub struct InnerAmg {
    ksp: Ksp,
    built: bool,
}

/// What the run keeps for the preconditioner: A (in u, AMG's near-null space the coordinates'
/// rigid modes), Q⁻¹ and the AMG cycle on A, made by the first solve that uses it.
pub struct MortarParts {
    a: Rc<Matrix>,
    q_inv: Rc<Matrix>,
    amg: RefCell<Option<Rc<RefCell<InnerAmg>>>>,
    /// A vector of A's row layout (the coordinates).
    template: Vector,
}

impl MortarParts {
    /// The parts of A and Q⁻¹ (`shared`) with AMG's coordinates (block size dim). Collective.
    pub fn new((a, q_inv): (Rc<Matrix>, Rc<Matrix>), coords: Vector) -> petsc::Result<Self> {
        a.set_rigid_body_near_null_space(&coords)?;
        Ok(MortarParts {
            a,
            q_inv,
            amg: RefCell::new(None),
            template: coords,
        })
    }

    /// A in u (the stiffness before the change of basis).
    pub fn a(&self) -> Rc<Matrix> {
        self.a.clone()
    }

    /// The preconditioner of a step system whose solver reads `options` and whose held nodes
    /// are `held`; the AMG cycle on A made here the first time. Collective.
    pub fn preconditioner(
        &self,
        comm: petsc::ffi::MPI_Comm,
        options: Rc<OptionsDb>,
        held: HeldNodes,
        dim: usize,
    ) -> petsc::Result<MortarPc> {
        let mut slot = self.amg.borrow_mut();
        let amg = match &*slot {
            Some(amg) => amg.clone(),
            None => {
                let mut ksp = Ksp::new(comm, options)?;
                ksp.set_options_prefix(PREFIX)?;
                ksp.set_from_options()?;
                let amg = Rc::new(RefCell::new(InnerAmg { ksp, built: false }));
                *slot = Some(amg.clone());
                amg
            }
        };
        let t1 = self.template.duplicate()?;
        Ok(MortarPc {
            t2: t1.duplicate()?,
            t3: t1.duplicate()?,
            t4: t1.duplicate()?,
            t1,
            scratch: Vec::new(),
            own: Vec::new(),
            a: self.a.clone(),
            q_inv: self.q_inv.clone(),
            held,
            amg,
            dim,
        })
    }
}

/// The shell's state.
pub struct MortarPc {
    a: Rc<Matrix>,
    q_inv: Rc<Matrix>,
    held: HeldNodes,
    amg: Rc<RefCell<InnerAmg>>,
    dim: usize,
    t1: Vector,
    t2: Vector,
    t3: Vector,
    t4: Vector,
    /// This rank's rows of the vector being preconditioned, and the held rows' own part
    /// (kept between applications: no allocation per GMRES iteration).
    scratch: Vec<f64>,
    own: Vec<f64>,
}

impl Preconditioner for MortarPc {
    fn set_up(&mut self) -> petsc::Result<()> {
        let mut amg = self.amg.borrow_mut();
        if !amg.built {
            amg.ksp.set_operator(&self.a)?;
            amg.ksp.set_up()?;
            amg.built = true;
        }
        Ok(())
    }

    /// y = P⁻¹ x: Π Q⁻¹ M⁻¹ Q⁻ᵀ Π x on the free directions, x_c / s_k on the held ones.
    fn apply(&mut self, x: &Vector, y: &mut Vector) -> petsc::Result<()> {
        let dim = self.dim;
        let held = self.held.borrow();
        let (v, own) = (&mut self.scratch, &mut self.own);
        x.read(|xl| {
            v.clear();
            v.extend_from_slice(xl);
        })?;
        own.clear();
        own.resize(v.len(), 0.0);
        project_off(&held, v, dim, |i, part, s| own[i] += part / s);
        self.t1.write(|s| s.copy_from_slice(v))?;
        self.q_inv.mult_transpose(&self.t1, &mut self.t2)?;
        self.amg.borrow_mut().ksp.solve(&self.t2, &mut self.t3)?;
        self.q_inv.mult(&self.t3, &mut self.t4)?;
        self.t4.read(|yl| v.copy_from_slice(yl))?;
        project_off(&held, v, dim, |_, _, _| {});
        y.write(|s| {
            for ((s, v), o) in s.iter_mut().zip(v.iter()).zip(own.iter()) {
                *s = v + o;
            }
        })
    }
}

/// v ← Π v: every held direction c of a held node taken out of its block of `v` (this rank's
/// rows); `removed(row, part, s_k)` sees each component of the removed part (c · v) c.
fn project_off(held: &[Held], v: &mut [f64], dim: usize, mut removed: impl FnMut(usize, f64, f64)) {
    for h in held {
        for c in &h.dirs {
            let p: f64 = (0..dim).map(|a| c[a] * v[h.lr + a]).sum();
            for a in 0..dim {
                v[h.lr + a] -= p * c[a];
                removed(h.lr + a, p * c[a], h.s);
            }
        }
    }
}
