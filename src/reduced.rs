//! Rows of the reduced systems (3.29) / (3.42), written into a matrix that keeps A's nonzero
//! pattern: a contact node's d rows are replaced by combinations of its own rows of A plus
//! entries in its own d columns, so only values change and MUMPS reuses its analysis.

use crate::petsc::{self, Matrix, PInt};

/// A contact node's d rows of A (all with the same columns: A is assembled in d×d blocks).
#[derive(Clone, Debug)]
pub struct NodeRows {
    /// Global index of the node's first row.
    pub row: usize,
    pub cols: Vec<PInt>,
    /// vals[j] = row `row + j` of A on `cols`.
    pub vals: Vec<Vec<f64>>,
    /// Position of the node's own column `row + j` in `cols`.
    pub own: [usize; 3],
}

impl NodeRows {
    /// Copies the node's rows out of A (they do not change during the Newton iteration).
    pub fn read(a: &Matrix, row: usize, dim: usize) -> petsc::Result<NodeRows> {
        let mut cols: Vec<PInt> = Vec::new();
        let mut vals = Vec::with_capacity(dim);
        for j in 0..dim {
            let (c, v) = a.with_row(row + j, |c, v| (c.to_vec(), v.to_vec()))?;
            if j == 0 {
                cols = c;
            } else if c != cols {
                return Err(petsc::PetscError {
                    code: -1,
                    message: format!(
                        "rows {row}..{} of A do not share one pattern (internal error)",
                        row + dim
                    ),
                    location: format!("{}:{}", file!(), line!()),
                });
            }
            vals.push(v);
        }
        let mut own = [0usize; 3];
        for (j, o) in own.iter_mut().enumerate().take(dim) {
            *o = cols
                .binary_search(&((row + j) as PInt))
                .expect("the diagonal block is in A's pattern");
        }
        Ok(NodeRows {
            row,
            cols,
            vals,
            own,
        })
    }

    /// Writes into `s` the node's d new rows: row i = Σ_j comb[i][j] · (row j of A)
    /// + Σ_j own[i][j] · e_(row+j)ᵀ. `buf` is scratch space.
    pub fn write(
        &self,
        s: &mut Matrix,
        dim: usize,
        comb: &[[f64; 3]; 3],
        own: &[[f64; 3]; 3],
        buf: &mut Vec<f64>,
    ) -> petsc::Result<()> {
        let n = self.cols.len();
        for i in 0..dim {
            buf.clear();
            buf.resize(n, 0.0);
            for j in 0..dim {
                let w = comb[i][j];
                if w != 0.0 {
                    for (b, v) in buf.iter_mut().zip(&self.vals[j]) {
                        *b += w * v;
                    }
                }
            }
            for j in 0..dim {
                buf[self.own[j]] += own[i][j];
            }
            s.insert_values(&[(self.row + i) as PInt], &self.cols, buf)?;
        }
        Ok(())
    }

    /// Row `row + j` of A times the local values: the diagonal entry a_jj.
    pub fn diag(&self, j: usize) -> f64 {
        self.vals[j][self.own[j]]
    }
}

/// Replaces one row of `s` by a_pp e_pᵀ (a pinned dof), keeping the pattern.
pub fn pin_row(s: &mut Matrix, a: &Matrix, p: usize) -> petsc::Result<()> {
    let (cols, mut vals) = a.with_row(p, |c, v| (c.to_vec(), v.to_vec()))?;
    for (c, v) in cols.iter().zip(vals.iter_mut()) {
        if *c as usize != p {
            *v = 0.0;
        }
    }
    s.insert_values(&[p as PInt], &cols, &vals)
}
