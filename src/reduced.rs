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

    /// Row `row + j` of A times the local values: the diagonal entry a_jj.
    pub fn diag(&self, j: usize) -> f64 {
        self.vals[j][self.own[j]]
    }
}

/// Prescribed components of one node: orthonormal directions c with cᵀ u = value
/// (an active contact node: c = n, value = −g; a pinned dof: c = e_k, value = 0).
#[derive(Clone, Debug, Default)]
pub struct NodeConstraint {
    pub dirs: Vec<([f64; 3], f64)>,
    /// Added to the node's own block (Tresca slip rows (3.39): Σ τ_i L̃_ij τ_jᵀ); only the
    /// owner of the node uses it.
    pub spring: [[f64; 3]; 3],
    /// Added to the node's right-hand side (Σ τ_i r̃_i).
    pub spring_rhs: [f64; 3],
}

impl NodeConstraint {
    /// P = I − Σ c cᵀ (projector onto the free components).
    pub fn projector(&self, dim: usize) -> [[f64; 3]; 3] {
        let mut p = [[0.0; 3]; 3];
        for (a, row) in p.iter_mut().enumerate().take(dim) {
            row[a] = 1.0;
        }
        for (c, _) in &self.dirs {
            for a in 0..dim {
                for b in 0..dim {
                    p[a][b] -= c[a] * c[b];
                }
            }
        }
        p
    }

    /// ū = Σ value · c (the prescribed part of u).
    pub fn known(&self) -> [f64; 3] {
        let mut u = [0.0; 3];
        for (c, v) in &self.dirs {
            for a in 0..3 {
                u[a] += v * c[a];
            }
        }
        u
    }
}

fn matmul3(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3], dim: usize) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for i in 0..dim {
        for j in 0..dim {
            c[i][j] = (0..dim).map(|l| a[i][l] * b[l][j]).sum();
        }
    }
    c
}

/// The (3.29) constraints of one node, applied symmetrically. The node's rows become
/// P_k A_kj P_j (plus s_k Σ c cᵀ on its own block) and its right-hand side
/// P_k (f_k − Σ_j A_kj ū_j) + s_k ū_k; in every unconstrained neighbour row i the block A_ik
/// becomes A_ik P_k and A_ik ū_k moves to the right-hand side. This is (3.29) with the known
/// normal displacement eliminated from the columns too: the same solution, on A's pattern,
/// and symmetric (positive definite without friction), so CG/AMG and Cholesky apply.
/// `constrained(j)` gives the constraint of global node j, if any. Returns the node's
/// right-hand side; the neighbour corrections are appended to `rhs_add` (global row, value).
#[allow(clippy::too_many_arguments)]
pub fn write_symmetric_constraint<'c>(
    s: &mut Matrix,
    rows: &NodeRows,
    me: &NodeConstraint,
    f_k: &[f64],
    dim: usize,
    constrained: impl Fn(usize) -> Option<&'c NodeConstraint>,
    rhs_add: &mut Vec<(PInt, f64)>,
    buf: &mut Vec<f64>,
) -> petsc::Result<[f64; 3]> {
    let n = rows.cols.len();
    let node_k = rows.row / dim;
    let pk = me.projector(dim);
    let uk = me.known();
    let sk = (0..dim).map(|j| rows.diag(j)).sum::<f64>() / dim as f64;
    let mut new_rows = vec![vec![0.0; n]; dim];
    let mut t = [0.0; 3]; // Σ_j A_kj ū_j
    let mut mirror_cols: [PInt; 3] = [0; 3];
    for c in 0..dim {
        mirror_cols[c] = (node_k * dim + c) as PInt;
    }
    let mut blk = [[0.0; 3]; 3];
    let mut m = 0;
    while m < n {
        let j = rows.cols[m] as usize / dim;
        for a in 0..dim {
            for b in 0..dim {
                blk[a][b] = rows.vals[a][m + b];
            }
        }
        let cj = if j == node_k {
            Some(me)
        } else {
            constrained(j)
        };
        let pj = match cj {
            Some(c) => c.projector(dim),
            None => NodeConstraint::default().projector(dim),
        };
        if let Some(c) = cj {
            let uj = c.known();
            for a in 0..dim {
                t[a] += (0..dim).map(|b| blk[a][b] * uj[b]).sum::<f64>();
            }
        }
        let mut nb = matmul3(&pk, &matmul3(&blk, &pj, dim), dim);
        if j == node_k {
            for (cvec, _) in &me.dirs {
                for a in 0..dim {
                    for b in 0..dim {
                        nb[a][b] += sk * cvec[a] * cvec[b];
                    }
                }
            }
            for a in 0..dim {
                for b in 0..dim {
                    nb[a][b] += me.spring[a][b];
                }
            }
        }
        for a in 0..dim {
            for b in 0..dim {
                new_rows[a][m + b] = nb[a][b];
            }
        }
        if cj.is_none() {
            // Mirror block in the unconstrained neighbour's rows: A_jk P_k = (A_kj)ᵀ P_k.
            let mut mb = [[0.0; 3]; 3];
            for a in 0..dim {
                for b in 0..dim {
                    mb[a][b] = (0..dim).map(|l| blk[l][a] * pk[l][b]).sum();
                }
            }
            buf.clear();
            for row in mb.iter().take(dim) {
                buf.extend_from_slice(&row[..dim]);
            }
            let mrows: Vec<PInt> = (0..dim).map(|c| (j * dim + c) as PInt).collect();
            s.insert_values(&mrows, &mirror_cols[..dim], buf)?;
            // rhs_j −= A_jk ū_k
            for a in 0..dim {
                let v: f64 = (0..dim).map(|l| blk[l][a] * uk[l]).sum();
                if v != 0.0 {
                    rhs_add.push(((j * dim + a) as PInt, -v));
                }
            }
        }
        m += dim;
    }
    for (a, row) in new_rows.iter().enumerate() {
        s.insert_values(&[(rows.row + a) as PInt], &rows.cols, row)?;
    }
    let mut rhs = [0.0; 3];
    let mut ft = [0.0; 3];
    for a in 0..dim {
        ft[a] = f_k[a] - t[a];
    }
    for a in 0..dim {
        rhs[a] = (0..dim).map(|b| pk[a][b] * ft[b]).sum::<f64>() + sk * uk[a] + me.spring_rhs[a];
    }
    Ok(rhs)
}
