//! The change of basis u = Q w + c that makes the body pairs' mortar rows node-local (the
//! module documentation): Q = I but for the free components d of every slave node k,
//! u_kd = w_kd + Σ_j m_kj u_jd over the master nodes j whose component d is free; the
//! couplings to Dirichlet-fixed master components form N_f, and c = N_f ū with ū the step's
//! Dirichlet values.

use super::{MasterFixed, PairRows};
use crate::assembly::System;
use crate::contact::obstacle::SlaveRow;
use crate::error::RunError;
use crate::mesh::Mesh;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::shellmat::Operator;
use crate::petsc::{self, Matrix, PInt, Vector};
use std::collections::HashMap;
use std::rc::Rc;

/// The change of basis of a case with body pairs.
pub struct Basis {
    q: Rc<Matrix>,
    /// Q⁻¹ = 2 I − Q (M² = 0): the iterative preset's preconditioner maps between w and u.
    q_inv: Rc<Matrix>,
    /// N_f: the couplings to fixed master components; `None` where no slave row couples to
    /// a fixed component.
    fixed: Option<Matrix>,
    /// The assembled A (for A c and the certificate in u), kept by
    /// [`Basis::transform_matrix`].
    a: Option<Rc<Matrix>>,
    /// This rank's rows that receive a slave node's contact force through Qᵀ (the coupled
    /// free components of master nodes), local row order; set by [`Basis::transform_matrix`].
    master_rows: Vec<bool>,
    dim: usize,
}

/// Qᵀ A Q as an operator: y = Qᵀ (A (Q x)), Qᵀ a matrix of its own (a forward product: the
/// same sums on every run).
struct Galerkin {
    a: Rc<Matrix>,
    q: Rc<Matrix>,
    qt: Matrix,
    qx: Vector,
    aqx: Vector,
}

impl Operator for Galerkin {
    fn mult(&mut self, x: &Vector, y: &mut Vector) -> petsc::Result<()> {
        self.q.mult(x, &mut self.qx)?;
        self.a.mult(&self.qx, &mut self.aqx)?;
        self.qt.mult(&self.aqx, y)
    }
}

/// The operator of a matrix between its two values in [`Basis::transform_matrix`] (never
/// applied).
struct Unset;

impl Operator for Unset {
    fn mult(&mut self, _: &Vector, _: &mut Vector) -> petsc::Result<()> {
        Err(petsc::raised_error(
            "internal: Qᵀ A Q applied before it was set",
        ))
    }
}

/// A contact solve's view of the problem in u while it runs in w: the basis, the step's
/// right-hand side f in u and c (`None`: zero). The certificate judges the equilibrium in u.
pub struct InU<'a> {
    pub basis: &'a Basis,
    pub f: &'a Vector,
    pub c: Option<&'a Vector>,
}

impl InU<'_> {
    /// u = Q w + c. Collective.
    pub fn u(&self, w: &Vector) -> petsc::Result<Vector> {
        self.basis.displacement(w, self.c)
    }
}

/// A CSR part of the owned rows under construction.
#[derive(Default)]
struct Rows {
    ptr: Vec<PInt>,
    cols: Vec<PInt>,
    vals: Vec<f64>,
}

impl Rows {
    fn push_row(&mut self, mut entries: Vec<(PInt, f64)>) {
        if self.ptr.is_empty() {
            self.ptr.push(0);
        }
        entries.sort_unstable_by_key(|e| e.0);
        for (c, v) in entries {
            match self.cols.last() {
                Some(&last)
                    if last == c && self.cols.len() > *self.ptr.last().unwrap() as usize =>
                {
                    *self.vals.last_mut().unwrap() += v;
                }
                _ => {
                    self.cols.push(c);
                    self.vals.push(v);
                }
            }
        }
        self.ptr.push(self.cols.len() as PInt);
    }
}

impl Basis {
    /// Q and N_f from the slave rows of every body pair (`rows_of`: (pair, rows by mesh node))
    /// and the fixed components of the master nodes. Collective.
    pub(super) fn new(
        ctx: &Ctx,
        mesh: &Mesh,
        layout: &Layout,
        rows_of: &[PairRows],
        master_fixed: &MasterFixed,
        fixed: &[f64],
    ) -> Result<Basis, RunError> {
        let dim = mesh.dim;
        let rows: HashMap<usize, &SlaveRow> = rows_of
            .iter()
            .flat_map(|(_, r)| r.iter().map(|(v, row)| (*v, row)))
            .collect();
        let (lo, _) = layout.node_range();
        let (mut q, mut qi, mut nf) = (Rows::default(), Rows::default(), Rows::default());
        for (i, &v) in layout.owned_nodes.iter().enumerate() {
            for d in 0..dim {
                let r = ((lo + i) * dim + d) as PInt;
                let mut qe = vec![(r, 1.0)];
                let mut qie = vec![(r, 1.0)];
                let mut fe = Vec::new();
                if let Some(row) = rows.get(&v) {
                    let free = fixed[v * dim + d].is_nan();
                    for &(j, m) in &row.masters {
                        let col = (j * dim + d) as PInt;
                        let master_fixed = master_fixed.get(&j).is_some_and(|f| f[d]);
                        if free && master_fixed {
                            fe.push((col, m));
                        }
                        // an explicit zero where the component is not coupled: every node
                        // block of Q, and so of Qᵀ A Q, is complete (the step system reads
                        // a node's rows in d × d blocks)
                        let mq = if free && !master_fixed { m } else { 0.0 };
                        qe.push((col, mq));
                        qie.push((col, -mq));
                    }
                }
                q.push_row(qe);
                qi.push_row(qie);
                nf.push_row(fe);
            }
        }
        let comm = ctx.comm();
        let qm = Rc::new(Matrix::from_csr(comm, dim, &q.ptr, &q.cols, &q.vals)?);
        let q_inv = Rc::new(Matrix::from_csr(comm, dim, &qi.ptr, &qi.cols, &qi.vals)?);
        let any_fixed = ctx.sum_usize(nf.cols.len()) > 0;
        let fixed = if any_fixed {
            Some(Matrix::from_csr(comm, dim, &nf.ptr, &nf.cols, &nf.vals)?)
        } else {
            None
        };
        Ok(Basis {
            q: qm,
            q_inv,
            fixed,
            a: None,
            master_rows: Vec::new(),
            dim,
        })
    }

    /// Replaces A by Qᵀ A Q (keeping A): assembled (`assembled`: a factorisation, SNES VI or
    /// GAMG on it needs its entries), or else as the operator x ↦ Qᵀ (A (Q x)) (the iterative
    /// preset's Newton steps: their preconditioner works on A in u and their step system is an
    /// operator too, step_system/matrix_free.rs), which stores nothing besides A, Q and Qᵀ and
    /// spends no time on the product. Collective.
    pub fn transform_matrix(
        &mut self,
        ctx: &Ctx,
        sys: &mut System,
        assembled: bool,
    ) -> petsc::Result<()> {
        if assembled {
            // On several ranks all at once: the default product holds A Q besides the result,
            // and its peak set the run's (3D body pair at 85 374 unknowns, 2 ranks: 363 against
            // 249 MB per rank with every product all at once; docs/numbers.md).
            let a_hat = if crate::par::world_size() > 1 {
                sys.a.ptap_all_at_once(&self.q)?
            } else {
                sys.a.ptap(&self.q)?
            };
            self.a = Some(Rc::new(std::mem::replace(&mut sys.a, a_hat)));
        } else {
            let (comm, local) = (ctx.comm(), sys.b.local_len()?);
            let none = Matrix::shell(comm, local, Box::new(Unset))?;
            let a = Rc::new(std::mem::replace(&mut sys.a, none));
            let op = Galerkin {
                a: a.clone(),
                q: self.q.clone(),
                qt: self.q.transposed()?,
                qx: sys.b.duplicate()?,
                aqx: sys.b.duplicate()?,
            };
            sys.a = Matrix::shell(comm, local, Box::new(op))?;
            self.a = Some(a);
        }
        // (Q − I)ᵀ 1 is Σ_k m_kj > 0 at the coupled master rows, 0 elsewhere
        let mut ones = sys.b.duplicate()?;
        ones.set_all(1.0)?;
        let mut qt = sys.b.duplicate()?;
        self.q.mult_transpose(&ones, &mut qt)?;
        self.master_rows = qt.read(|x| x.iter().map(|v| (v - 1.0).abs() > 1e-12).collect())?;
        Ok(())
    }

    /// The assembled A (in u), once [`Basis::transform_matrix`] ran.
    pub fn a(&self) -> &Matrix {
        self.a.as_ref().expect("transform_matrix ran")
    }

    /// A (in u) and Q⁻¹, shared: the iterative preset's preconditioner keeps them.
    pub fn shared(&self) -> (Rc<Matrix>, Rc<Matrix>) {
        let a = self.a.clone().expect("transform_matrix ran");
        (a, self.q_inv.clone())
    }

    /// This rank's rows that receive contact forces of slave nodes (master rows).
    pub fn master_rows(&self) -> &[bool] {
        &self.master_rows
    }

    /// The step's right-hand side in w, f̂ = Qᵀ (f − A c), and c (`None`: zero), from f (in u)
    /// and the step's Dirichlet values per local mesh dof (`fixed`, NaN = free). Collective.
    pub fn rhs(
        &self,
        layout: &Layout,
        f: &Vector,
        fixed: &[f64],
    ) -> petsc::Result<(Vector, Option<Vector>)> {
        let mut g = f.duplicate()?;
        g.copy_from(f)?;
        let c = match (&self.fixed, &self.a) {
            (Some(nf), Some(a)) => {
                let dim = self.dim;
                let mut ubar = f.duplicate()?;
                ubar.write(|x| {
                    for (i, &v) in layout.owned_nodes.iter().enumerate() {
                        for d in 0..dim {
                            let val = fixed[v * dim + d];
                            x[i * dim + d] = if val.is_nan() { 0.0 } else { val };
                        }
                    }
                })?;
                let mut c = f.duplicate()?;
                nf.mult(&ubar, &mut c)?;
                let mut ac = f.duplicate()?;
                a.mult(&c, &mut ac)?;
                let ac = ac.to_local_vec()?;
                g.write(|x| x.iter_mut().zip(&ac).for_each(|(x, y)| *x -= y))?;
                Some(c)
            }
            _ => None,
        };
        let mut out = f.duplicate()?;
        self.q.mult_transpose(&g, &mut out)?;
        Ok((out, c))
    }

    /// u = Q w + c. Collective.
    pub fn displacement(&self, w: &Vector, c: Option<&Vector>) -> petsc::Result<Vector> {
        let mut u = w.duplicate()?;
        self.q.mult(w, &mut u)?;
        if let Some(c) = c {
            let c = c.to_local_vec()?;
            u.write(|x| x.iter_mut().zip(&c).for_each(|(x, y)| *x += y))?;
        }
        Ok(u)
    }
}
