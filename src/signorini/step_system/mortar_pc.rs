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
//! step_system/write.rs). A does not change during a run, so the hierarchy is built once; the
//! held set enters through Π alone. (AMG on A plus a penalty ρ c cᵀ on the held rows, rebuilt
//! when the set changes, took fewer iterations per step but cost more in its set-ups:
//! docs/numbers.md, "3D body pairs on the iterative preset".)

use crate::petsc::ksp::Ksp;
use crate::petsc::shellpc::Preconditioner;
use crate::petsc::{self, Matrix, Vector};
use std::cell::RefCell;
use std::rc::Rc;

/// The name of the shell (PCShellSetName).
pub const SHELL_NAME: &str = "amg in u for body pairs";

/// The options prefix of the inner AMG (its options are the iterative preset's GAMG options).
pub const PREFIX: &str = "mortar_";

/// One node whose directions the step holds: its first local row, the held unit directions
/// and the node's mean diagonal s_k (the held rows' diagonal).
#[derive(Clone, Debug)]
pub struct Held {
    pub lr: usize,
    pub dirs: Vec<[f64; 3]>,
    pub s: f64,
}

/// The held nodes of the step written last, shared by the step system (which writes them)
/// and the preconditioner (which reads them at its set-up and apply).
pub type HeldNodes = Rc<RefCell<Vec<Held>>>;

/// What the run keeps for it: A (in u), Q⁻¹ and the nodes' coordinates (AMG's rigid modes).
pub struct MortarParts {
    pub a: Rc<Matrix>,
    pub q_inv: Rc<Matrix>,
    pub coords: Vector,
}

/// The shell's state.
pub struct MortarPc {
    a: Rc<Matrix>,
    q_inv: Rc<Matrix>,
    held: HeldNodes,
    inner: Ksp,
    built: bool,
    dim: usize,
    t1: Vector,
    t2: Vector,
    t3: Vector,
    t4: Vector,
}

impl MortarPc {
    /// The preconditioner of A (in u) and Q⁻¹, AMG's coordinates (block size dim) and the
    /// held nodes the step system writes; `inner` a KSP with [`PREFIX`] (preonly + GAMG).
    /// Collective.
    pub fn new(
        (a, q_inv): (Rc<Matrix>, Rc<Matrix>),
        coords: &Vector,
        held: HeldNodes,
        inner: Ksp,
        dim: usize,
    ) -> petsc::Result<MortarPc> {
        a.set_rigid_body_near_null_space(coords)?;
        let t1 = coords.duplicate()?;
        Ok(MortarPc {
            t2: t1.duplicate()?,
            t3: t1.duplicate()?,
            t4: t1.duplicate()?,
            t1,
            a,
            q_inv,
            held,
            inner,
            built: false,
            dim,
        })
    }
}

impl Preconditioner for MortarPc {
    fn set_up(&mut self) -> petsc::Result<()> {
        if !self.built {
            self.inner.set_operator(&self.a)?;
            self.inner.set_up()?;
            self.built = true;
        }
        Ok(())
    }

    fn apply(&mut self, x: &Vector, y: &mut Vector) -> petsc::Result<()> {
        let dim = self.dim;
        let mut xl = x.to_local_vec()?;
        let mut own = vec![0.0; xl.len()];
        {
            let held = self.held.borrow();
            for h in held.iter() {
                for c in &h.dirs {
                    let p: f64 = (0..dim).map(|a| c[a] * xl[h.lr + a]).sum();
                    for a in 0..dim {
                        xl[h.lr + a] -= p * c[a];
                        own[h.lr + a] += p * c[a] / h.s;
                    }
                }
            }
        }
        self.t1.write(|s| s.copy_from_slice(&xl))?;
        self.q_inv.mult_transpose(&self.t1, &mut self.t2)?;
        self.inner.solve(&self.t2, &mut self.t3)?;
        self.q_inv.mult(&self.t3, &mut self.t4)?;
        let mut yl = self.t4.to_local_vec()?;
        {
            let held = self.held.borrow();
            for h in held.iter() {
                for c in &h.dirs {
                    let p: f64 = (0..dim).map(|a| c[a] * yl[h.lr + a]).sum();
                    for a in 0..dim {
                        yl[h.lr + a] -= p * c[a];
                    }
                }
            }
        }
        for (v, o) in yl.iter_mut().zip(&own) {
            *v += o;
        }
        y.write(|s| s.copy_from_slice(&yl))
    }
}
