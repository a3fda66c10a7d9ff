//! The step system (3.29) / (3.42) as an operator instead of a matrix: S = L A P + D, with
//! P = diag(P_k) the projection off each node's prescribed directions, L = diag(left_k) its
//! rows' left factor (P_k, or P_k + E for a Coulomb slip row (F7); the identity on rows that
//! the step leaves as in A) and D = diag(s_k Σ c cᵀ + spring_k) the rewritten nodes' own terms
//! (write.rs `write_symmetric_constraint`, which writes the same S into a copy of A's
//! pattern). Body pairs on the iterative preset solve with it: their preconditioner works in
//! u (mortar_pc.rs) and needs no entries of S, so S is never stored — one matrix with the
//! pattern of Qᵀ A Q less per run.

use super::mortar_pc::HeldNodes;
use crate::petsc::shellmat::Operator;
use crate::petsc::{self, Matrix, Vector};

/// y = S x = L A (P x) + D x on the rewritten nodes of the step written last (`rows`).
pub struct StepOperator {
    a: Matrix,
    rows: HeldNodes,
    dim: usize,
    px: Vector,
    apx: Vector,
}

impl StepOperator {
    /// The operator of the steps written into `rows`, on A = `a` (a second handle on the
    /// step's A). Collective.
    pub fn new(a: Matrix, template: &Vector, rows: HeldNodes, dim: usize) -> petsc::Result<Self> {
        Ok(StepOperator {
            a,
            rows,
            dim,
            px: template.duplicate()?,
            apx: template.duplicate()?,
        })
    }
}

impl Operator for StepOperator {
    fn mult(&mut self, x: &Vector, y: &mut Vector) -> petsc::Result<()> {
        let dim = self.dim;
        let rows = self.rows.borrow();
        let px = &mut self.px;
        x.read(|xl| {
            px.write(|v| {
                v.copy_from_slice(xl);
                for h in rows.iter() {
                    let xk = &xl[h.lr..h.lr + dim];
                    for a in 0..dim {
                        v[h.lr + a] = (0..dim).map(|b| h.proj[a][b] * xk[b]).sum();
                    }
                }
            })
        })??;
        self.a.mult(&self.px, &mut self.apx)?;
        x.read(|xl| {
            self.apx.read(|apx| {
                y.write(|v| {
                    v.copy_from_slice(apx);
                    for h in rows.iter() {
                        let (xk, tk) = (&xl[h.lr..h.lr + dim], &apx[h.lr..h.lr + dim]);
                        for a in 0..dim {
                            v[h.lr + a] = (0..dim)
                                .map(|b| h.left[a][b] * tk[b] + h.own[a][b] * xk[b])
                                .sum();
                        }
                    }
                })
            })
        })???;
        Ok(())
    }
}
