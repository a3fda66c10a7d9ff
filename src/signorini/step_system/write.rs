//! Writing the step system's rows: the symmetric elimination of every prescribed direction
//! (active normal, stick tangent, pinned dof) from a node's own rows and, as a mirror block, from
//! its unconstrained neighbours' rows, and what changed between two steps' rows.

use super::reuse::SLIP_BLOCK_ROUNDOFF;
use super::rows::{ConstraintMap, NodeConstraint, NodeRows};
use crate::assembly::System;
use crate::partition::Layout;
use crate::petsc::{self, Matrix, PInt, Vector};
use crate::signorini::active_set::ActiveSet;
use crate::signorini::boundary::ContactBoundary;
use std::collections::HashMap;

/// A rewritten node: its rows of A, its constraint, its first local row.
pub(super) type Rewrite<'r> = (&'r NodeRows, NodeConstraint, usize);

/// The rows a step writes: its rewritten nodes ([`rewrites`]) and the constraints of every
/// node their rows couple to (the neighbours' included).
#[derive(Clone, Copy)]
pub(super) struct RowWrites<'w> {
    pub rows: &'w [Rewrite<'w>],
    pub cmap: &'w ConstraintMap,
}

/// How a friction step's matrix (3.42) differs from the previous step's: S_ℓ − S_{ℓ−1} has
/// rank at most 2 per direction added or removed plus d − 1 per changed slip block, the cost
/// of an exact low-rank update of the previous factorisation (summary.json
/// `newton.history[].change`; docs/numbers.md, "Tresca and the reuse of factorisations").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct RowChange {
    /// Prescribed directions (normal and stick rows) added or removed, over all nodes.
    pub directions: usize,
    /// Slip blocks Σ τ_i L̃_ij τ_jᵀ (3.39) added, removed or changed beyond
    /// [`SLIP_BLOCK_ROUNDOFF`] of the node's stiffness.
    pub slip_blocks: usize,
    /// Slip blocks that changed by round-off only.
    pub slip_blocks_roundoff: usize,
}

/// This rank's slip blocks by first local row, with the node's stiffness (mean diagonal of its
/// rows of A): what [`slip_block_changes`] compares.
pub(super) type ScaledSprings = HashMap<usize, ([[f64; 3]; 3], f64)>;

/// Slip blocks of this rank that differ between two systems: (beyond round-off, round-off
/// only); a block present in one system only counts as beyond round-off unless all of its
/// entries are within round-off of 0.
pub(super) fn slip_block_changes(old: &ScaledSprings, new: &ScaledSprings) -> (usize, usize) {
    let zero = [[0.0; 3]; 3];
    let (mut real, mut roundoff) = (0, 0);
    let mut seen = |k: &usize, a: &[[f64; 3]; 3], scale: f64, other: &ScaledSprings| {
        let b = other.get(k).map_or(&zero, |(m, _)| m);
        let d = (0..3)
            .flat_map(|i| (0..3).map(move |j| (a[i][j] - b[i][j]).abs()))
            .fold(0.0, f64::max);
        if d > SLIP_BLOCK_ROUNDOFF * scale {
            real += 1;
        } else if d > 0.0 {
            roundoff += 1;
        }
    };
    for (k, (a, scale)) in new {
        seen(k, a, *scale, old);
    }
    for (k, (a, scale)) in old {
        if !new.contains_key(k) {
            seen(k, a, *scale, new);
        }
    }
    (real, roundoff)
}

/// (rows of A, constraint, first local row) of every node this rank rewrites: the contact
/// nodes `set` prescribes (rows of inactive frictionless nodes stay as in A (3.29)) and the
/// owned pinned nodes. `rows` = (the contact nodes' rows, the pinned nodes' rows, first
/// global row of this rank).
pub(super) fn rewrites<'r>(
    rows: (&'r [NodeRows], &'r [(usize, NodeRows)], usize),
    layout: &Layout,
    b: &ContactBoundary,
    set: &ActiveSet,
    cmap: &ConstraintMap,
    dim: usize,
) -> Vec<Rewrite<'r>> {
    let (contact_rows, pin_rows, row_lo) = rows;
    let mut writes = Vec::new();
    for (i, (k, r)) in b.nodes.iter().zip(contact_rows).enumerate() {
        let Some(p) = set.prescribed(b, i, dim) else {
            continue;
        };
        let mut me = cmap
            .get(layout.node_global[k.node])
            .expect("gathered")
            .clone();
        if let Some(row) = &p.slip {
            me.add_slip_row(&k.frame, row, dim);
        }
        writes.push((r, me, k.local_row));
    }
    for (v, r) in pin_rows {
        let me = cmap.get(*v).expect("pins are in the map").clone();
        writes.push((r, me, v * dim - row_lo));
    }
    writes
}

/// The rows `writes` of the reduced system (3.29) applied symmetrically
/// ([`write_symmetric_constraint`]): into `s` when given (then assembled), and into `rhs`
/// (whose other rows stay; the neighbours' corrections added in rank order: repeatable runs), with f
/// from `f_local` (this rank's rows) or f = 0. Collective.
pub(super) fn write_rows(
    mut s: Option<&mut Matrix>,
    rhs: &mut Vector,
    writes: RowWrites,
    f_local: Option<&[f64]>,
    dim: usize,
    buf: &mut Vec<f64>,
) -> petsc::Result<()> {
    let zero = [0.0; 3];
    let cmap = writes.cmap;
    let mut rhs_add: Vec<(PInt, f64)> = Vec::new();
    let mut rhs_updates: Vec<(usize, f64)> = Vec::new();
    for (r, me, lr) in writes.rows {
        let fk = f_local.map_or(&zero[..dim], |f| &f[*lr..*lr + dim]);
        let rk = write_symmetric_constraint(
            s.as_deref_mut(),
            r,
            me,
            fk,
            dim,
            |j| cmap.get(j),
            &mut rhs_add,
            buf,
        )?;
        for (a, v) in rk.iter().enumerate().take(dim) {
            rhs_updates.push((lr + a, *v));
        }
    }
    let (idx, vals): (Vec<PInt>, Vec<f64>) = rhs_add.into_iter().unzip();
    crate::par::add_in_rank_order(rhs, &idx, &vals)?; // deterministic order: repeatable runs
    rhs.assemble()?;
    if let Some(s) = s {
        s.assemble()?;
    }
    rhs.write(|x| {
        for &(i, v) in &rhs_updates {
            x[i] = v;
        }
    })
}

/// The right-hand side of (3.29) / (3.42) for the rows `writes` (as [`write_rows`] writes it) from one product
/// with A instead of A's rows: with ū the prescribed values (zero off the rewritten nodes),
/// out = f − A ū, and on a rewritten node k left_k (f_k − (A ū)_k) + s_k ū_k + r̃_k — the same
/// P_k (f_k − Σ_j A_kj ū_j) + s_k ū_k of [`write_symmetric_constraint`], and f_i − Σ_k A_ik ū_k
/// on every other row. For A as an operator (the step system of matrix_free.rs); f = 0 where
/// `f_local` is `None`. `ubar` and `au` are scratch vectors of A's layout. Collective.
pub(super) fn rhs_by_operator(
    a: &Matrix,
    writes: &[Rewrite],
    f_local: Option<&[f64]>,
    dim: usize,
    (ubar, au): (&mut Vector, &mut Vector),
    out: &mut Vector,
) -> petsc::Result<()> {
    ubar.write(|x| {
        x.fill(0.0);
        for (_, me, lr) in writes {
            x[*lr..*lr + dim].copy_from_slice(&me.known()[..dim]);
        }
    })?;
    a.mult(ubar, au)?;
    let aub = au.to_local_vec()?;
    out.write(|x| {
        for (i, v) in x.iter_mut().enumerate() {
            *v = f_local.map_or(0.0, |f| f[i]) - aub[i];
        }
        for (r, me, lr) in writes {
            let sk = r.mean_diag(dim);
            let left = left_factor(me, me.projector(dim), dim);
            let mut ft = [0.0; 3];
            ft[..dim].copy_from_slice(&x[*lr..*lr + dim]);
            let uk = me.known();
            for a in 0..dim {
                x[lr + a] = (0..dim).map(|b| left[a][b] * ft[b]).sum::<f64>()
                    + sk * uk[a]
                    + me.spring_rhs[a];
            }
        }
    })
}

/// The matrix GAMG is built from on the iterative preset with Coulomb's (F7) rows: S with
/// the slip nodes' rows P_k A_kj P_j (Tresca's form, symmetric up to the slip springs)
/// instead of (P_k + E) A_kj P_j. S differs from it by one row per slip node (rank ≤ |slip|),
/// which GMRES absorbs; measured on 2 ranks (GMRES iterations in all, with the Gram–Schmidt
/// refinement of the preset): the 3D block held and pushed into a sphere at 112 890 unknowns
/// 461 against 518 with GAMG built on S itself, the floating ball with a tangential traction
/// (12 129) 1 044 against 1 305; peak memory 379 against 350 MB per rank. Collective.
pub(super) fn write_unmixed(
    made: &mut Option<(Matrix, Vector)>,
    s: &Matrix,
    rhs: &Vector,
    sys: &System,
    writes: RowWrites,
    dim: usize,
    buf: &mut Vec<f64>,
) -> petsc::Result<()> {
    if made.is_none() {
        let mut p = s.duplicate()?;
        p.copy_near_null_space_from(s)?;
        *made = Some((p, rhs.duplicate()?));
    }
    let (p, scratch) = made.as_mut().expect("made above");
    p.copy_values_from(&sys.a)?;
    let plain: Vec<Rewrite> = writes
        .rows
        .iter()
        .map(|(r, me, lr)| {
            let mut me = me.clone();
            me.row_mix = None;
            (*r, me, *lr)
        })
        .collect();
    let unmixed = RowWrites {
        rows: &plain,
        cmap: writes.cmap,
    };
    write_rows(Some(p), scratch, unmixed, None, dim, buf)
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
/// With `s` = None only the right-hand side is formed (S unchanged).
#[allow(clippy::too_many_arguments)]
pub fn write_symmetric_constraint<'c>(
    mut s: Option<&mut Matrix>,
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
    let left = left_factor(me, pk, dim);
    let uk = me.known();
    let sk = rows.mean_diag(dim);
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
        let mut nb = matmul3(&left, &matmul3(&blk, &pj, dim), dim);
        if j == node_k {
            add_own_terms(&mut nb, me, sk, dim);
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
            if let Some(s) = s.as_mut() {
                s.insert_values(&mrows, &mirror_cols[..dim], buf)?;
            }
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
    if let Some(s) = s.as_mut() {
        for (a, row) in new_rows.iter().enumerate() {
            s.insert_values(&[(rows.row + a) as PInt], &rows.cols, row)?;
        }
    }
    Ok(node_rhs(me, &left, f_k, &t, sk, dim))
}

/// The left factor of a constrained node's rows: P_k, plus E for a Coulomb slip row (F7).
pub(super) fn left_factor(me: &NodeConstraint, pk: [[f64; 3]; 3], dim: usize) -> [[f64; 3]; 3] {
    match me.row_mix {
        None => pk,
        Some(e) => {
            let mut l = pk;
            for a in 0..dim {
                for b in 0..dim {
                    l[a][b] += e[a][b];
                }
            }
            l
        }
    }
}

/// The node's own block of (3.29) / (3.42): s_k Σ c cᵀ over its prescribed directions and its
/// spring (a Tresca or Coulomb slip block), added to P_k A_kk P_k in `nb`.
pub(super) fn add_own_terms(nb: &mut [[f64; 3]; 3], me: &NodeConstraint, sk: f64, dim: usize) {
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

/// The node's right-hand side P_k (f_k − Σ_j A_kj ū_j) + s_k ū_k (plus the spring's part):
/// `f_k` = the node's load, `t` = Σ_j A_kj ū_j, `left` its left factor.
fn node_rhs(
    me: &NodeConstraint,
    left: &[[f64; 3]; 3],
    f_k: &[f64],
    t: &[f64; 3],
    sk: f64,
    dim: usize,
) -> [f64; 3] {
    let uk = me.known();
    let mut rhs = [0.0; 3];
    let mut ft = [0.0; 3];
    for a in 0..dim {
        ft[a] = f_k[a] - t[a];
    }
    for a in 0..dim {
        rhs[a] = (0..dim).map(|b| left[a][b] * ft[b]).sum::<f64>() + sk * uk[a] + me.spring_rhs[a];
    }
    rhs
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(l: f64) -> [[f64; 3]; 3] {
        let mut m = [[0.0; 3]; 3];
        m[0][0] = l;
        m[0][1] = 0.5 * l;
        m
    }

    #[test]
    fn slip_blocks_split_into_real_and_round_off_changes() {
        let scale = 2.0;
        let old: ScaledSprings = [
            (0, (block(1.0), scale)),   // unchanged
            (2, (block(1.0), scale)),   // changes by 1e-3: real
            (4, (block(3e-14), scale)), // round-off, then gone: round-off
            (6, (block(1.0), scale)),   // removed: real
            (8, (block(0.25), scale)),  // changes by 1e-13: round-off
            (10, (block(1e-9), scale)), // at 5e-10 of the stiffness: real
        ]
        .into_iter()
        .collect();
        let new: ScaledSprings = [
            (0, (block(1.0), scale)),
            (2, (block(1.0 + 1e-3), scale)),
            (8, (block(0.25 + 1e-13), scale)),
            (10, (block(0.0), scale)),
            (12, (block(4e-12), scale)), // appears at round-off
            (14, (block(0.1), scale)),   // appears: real
        ]
        .into_iter()
        .collect();
        assert_eq!(slip_block_changes(&old, &new), (4, 3));
        assert_eq!(slip_block_changes(&new, &old), (4, 3));
        assert_eq!(slip_block_changes(&new, &new), (0, 0));
    }
}
