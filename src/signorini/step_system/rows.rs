//! A contact node's rows of A and its constraint (the prescribed directions and springs of
//! (3.29) / (3.42)), and the map of all nodes' constraints.

use crate::contact::{coulomb_block, CoulombRow, Frame, TangentialRow};
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::{self, Matrix, PInt};
use crate::signorini::active_set::ActiveSet;
use crate::signorini::boundary::ContactBoundary;
use crate::signorini::rigid::Pin;
use std::collections::HashMap;

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

    /// The node's mean diagonal entry s_k (the scale of its held rows, (3.29)).
    pub fn mean_diag(&self, dim: usize) -> f64 {
        (0..dim).map(|j| self.diag(j)).sum::<f64>() / dim as f64
    }
}

/// Prescribed components of one node: orthonormal directions c with cᵀ u = value (an active
/// contact node: c = n, value = −g; a stick tangent: c = τ_i, value = 0; a pinned dof:
/// c = e_k, value = 0), and a slip row's spring. A node with no direction (a Tresca slip node
/// of an inactive contact node) is still rewritten by its owner.
#[derive(Clone, Debug, Default)]
pub struct NodeConstraint {
    pub dirs: Vec<([f64; 3], f64)>,
    /// Added to the node's own block (Tresca slip rows (3.39): Σ τ_i L̃_ij τ_jᵀ); only the
    /// owner of the node uses it.
    pub spring: [[f64; 3]; 3],
    /// Added to the node's right-hand side (Σ τ_i r̃_i).
    pub spring_rhs: [f64; 3],
    /// A Coulomb slip row's λ_n coupling E = Σ q_i τ_i nᵀ (F7): the node's rows are
    /// (P_k + E) A_kj P_j; zero otherwise. Only the owner of the node uses it.
    pub row_mix: Option<[[f64; 3]; 3]>,
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

impl NodeConstraint {
    /// A slip row: Tresca's (3.39a) by [`Self::add_slip_spring`], Coulomb's (F7) with its
    /// coupling by `coulomb_block`.
    pub fn add_slip_row(&mut self, frame: &Frame, row: &CoulombRow<2>, dim: usize) {
        if !row.coupled() {
            self.add_slip_spring(&frame.t, &row.tresca_part(), dim);
            return;
        }
        let blk = coulomb_block(frame, row);
        for a in 0..dim {
            for b in 0..dim {
                self.spring[a][b] += blk.spring[a][b];
            }
            self.spring_rhs[a] += blk.spring_rhs[a];
        }
        self.row_mix = Some(blk.row_mix);
    }

    /// The slip row (3.39a) τᵀ(A u)_k + L̃ τᵀ u^k = τᵀ f_k + r̃: adds Σ τ_i L̃_ij τ_jᵀ to the node's
    /// block and Σ τ_i r̃_i to its right-hand side.
    pub fn add_slip_spring(&mut self, t: &[[f64; 3]; 2], row: &TangentialRow<2>, dim: usize) {
        let TangentialRow::Slip { l, r } = row else {
            return;
        };
        for a in 0..dim {
            for b in 0..dim {
                for (ii, ti) in t[..dim - 1].iter().enumerate() {
                    for (jj, tj) in t[..dim - 1].iter().enumerate() {
                        self.spring[a][b] += ti[a] * l[ii][jj] * tj[b];
                    }
                }
            }
            for (ii, ti) in t[..dim - 1].iter().enumerate() {
                self.spring_rhs[a] += ti[a] * r[ii];
            }
        }
    }
}

/// The constraints of every rewritten node (contact nodes with prescribed rows, pinned dofs) by
/// global node number, on every rank: a node's rows are rewritten by its owner, its columns in
/// every neighbour's rows.
pub struct ConstraintMap(HashMap<usize, NodeConstraint>);

impl ConstraintMap {
    /// One all-gather of the rewritten contact nodes' directions; the pins are known everywhere.
    /// Collective.
    pub fn gather(
        ctx: &Ctx,
        layout: &Layout,
        b: &ContactBoundary,
        set: &ActiveSet,
        pins: &[Pin],
        dim: usize,
    ) -> ConstraintMap {
        // Records (global node, c, value); a node rewritten without a direction sends value NaN.
        let mut mine: Vec<f64> = Vec::new();
        for (i, k) in b.nodes.iter().enumerate() {
            if let Some(p) = set.prescribed(b, i, dim) {
                let gk = layout.node_global[k.node] as f64;
                if p.dirs.is_empty() {
                    mine.extend_from_slice(&[gk, 0.0, 0.0, 0.0, f64::NAN]);
                }
                for (c, v) in &p.dirs {
                    mine.extend_from_slice(&[gk, c[0], c[1], c[2], *v]);
                }
            }
        }
        let all = ctx.all_gather_varcount(&mine);
        let mut map: HashMap<usize, NodeConstraint> = HashMap::new();
        for r in all.chunks_exact(5) {
            let e = map.entry(r[0] as usize).or_default();
            if !r[4].is_nan() {
                e.dirs.push(([r[1], r[2], r[3]], r[4]));
            }
        }
        for &(v, k) in pins {
            let mut e = [0.0; 3];
            e[k] = 1.0;
            map.entry(v) // pins name global nodes
                .or_default()
                .dirs
                .push((e, 0.0));
        }
        ConstraintMap(map)
    }

    pub fn get(&self, global_node: usize) -> Option<&NodeConstraint> {
        self.0.get(&global_node)
    }

    /// The prescribed directions of every rewritten node (the same on every rank): with the
    /// slip blocks, what the matrix S depends on (the values only reach the right-hand side).
    pub(super) fn directions(&self) -> Directions {
        self.0
            .iter()
            .map(|(&k, c)| (k, c.dirs.iter().map(|(d, _)| *d).collect()))
            .collect()
    }
}

/// Prescribed directions by global node.
pub(super) type Directions = HashMap<usize, Vec<[f64; 3]>>;

/// Slip blocks Σ τ_i L̃_ij τ_jᵀ of this rank's rewritten nodes, by first local row.
pub(super) type Springs = HashMap<usize, [[f64; 3]; 3]>;

/// Prescribed directions added or removed between two systems, over all nodes. Each changes
/// the node's rows and columns by a term of rank ≤ 2 (S' − S = c wᵀ + w cᵀ for one direction c
/// of (3.29) applied symmetrically).
pub(super) fn direction_changes(old: &Directions, new: &Directions) -> usize {
    let missing = |a: &Directions, b: &Directions| -> usize {
        a.iter()
            .map(|(k, dirs)| {
                let other = b.get(k).map(Vec::as_slice).unwrap_or(&[]);
                dirs.iter().filter(|d| !other.contains(d)).count()
            })
            .sum()
    };
    missing(old, new) + missing(new, old)
}

/// This rank's nodes whose slip block differs between two systems (each a change of rank
/// ≤ d − 1 in the node's own block).
pub(super) fn spring_changes(old: &Springs, new: &Springs) -> usize {
    let zero = [[0.0; 3]; 3];
    let differs = |a: &Springs, b: &Springs| -> usize {
        a.iter()
            .filter(|(k, m)| b.get(k).unwrap_or(&zero) != *m)
            .count()
    };
    // a key in both maps that differs is counted twice: count the union once
    let both = old
        .iter()
        .filter(|(k, m)| new.get(k).is_some_and(|n| n != *m))
        .count();
    differs(old, new) + differs(new, old) - both
}
