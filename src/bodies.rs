//! The separate bodies of a mesh (its connected parts, cells joined by shared nodes), counted
//! over the distributed mesh, with those that their Dirichlet data do not hold in every rigid
//! mode: said in the log where there are several, and written to summary.json. The contact
//! solver computes the free rigid modes of one body (thesis 4.1), so the driver refuses a case
//! with contact in which one of several bodies is free in a rigid mode (README, "Limitations").
//!
//! Every rank joins its local cells (its own and the ghost cells touching its owned nodes) by a
//! union-find over its local nodes; a local part is named by its smallest global node number.
//! The nodes a part shares with another rank's parts — those not owned here, and those of
//! ghost cells — go to rank 0 with the part's name, and rank 0 joins the parts that share a
//! node: O(the partition's interfaces) on rank 0, never the mesh.

use crate::mesh::{Mesh, RigidModes};
use crate::par::Ctx;
use crate::partition::Layout;
use serde::Serialize;
use std::collections::HashMap;

/// summary.json's `bodies`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Bodies {
    /// Connected parts of the mesh.
    pub count: usize,
    /// Of them, the parts whose rigid modes their Dirichlet data do not all fix (none, or
    /// too few: e.g. one symmetry line).
    pub not_held: usize,
}

/// One body of the mesh, for `signorini-mpi check`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Body {
    /// Its smallest Gmsh node tag (names it whatever the rank count).
    pub first_tag: u64,
    /// Its nodes.
    pub nodes: usize,
    /// Its rigid modes that its Dirichlet data leave free (0: held).
    pub free_modes: usize,
}

/// A union-find over `n` items (path halving, union by the smaller index as root).
struct Joins {
    parent: Vec<usize>,
}

impl Joins {
    fn new(n: usize) -> Joins {
        Joins {
            parent: (0..n).collect(),
        }
    }

    fn root(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }

    fn join(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.root(a), self.root(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb);
        }
    }
}

/// The bodies of the distributed `mesh` (`fixed`: the prescribed value of every local dof, NaN
/// where free). Collective; every rank returns the same count.
pub fn count(ctx: &Ctx, mesh: &Mesh, layout: &Layout, fixed: &[f64]) -> Bodies {
    summed(&survey(ctx, mesh, layout, fixed))
}

/// The count of `bodies`.
pub fn summed(bodies: &[Body]) -> Bodies {
    Bodies {
        count: bodies.len(),
        not_held: bodies.iter().filter(|b| b.free_modes > 0).count(),
    }
}

/// Every body of the distributed `mesh`, by its first node tag. Collective; every rank
/// returns the same list.
pub fn survey(ctx: &Ctx, mesh: &Mesh, layout: &Layout, fixed: &[f64]) -> Vec<Body> {
    let (n, dim) = (mesh.n_nodes(), mesh.dim);
    let mut joins = Joins::new(n);
    let mut in_ghost = vec![false; n];
    // the local mesh has the nodes of boundary elements of other ranks' cells too: only the
    // nodes of local cells belong to a part here
    let mut in_cell = vec![false; n];
    for c in 0..mesh.n_cells() {
        let cell = mesh.cell(c);
        let ghost = layout.cell_rank[c] as usize != layout.rank;
        for &v in cell {
            joins.join(cell[0], v);
            in_ghost[v] |= ghost;
            in_cell[v] = true;
        }
    }
    // every local part's name: its smallest global node number
    let mut name = vec![u64::MAX; n];
    for v in (0..n).filter(|&v| in_cell[v]) {
        let r = joins.root(v);
        name[r] = name[r].min(layout.node_global[v] as u64);
    }
    // the local parts, numbered by their roots
    let roots: Vec<usize> = (0..n)
        .filter(|&v| in_cell[v] && joins.root(v) == v)
        .collect();
    let mut part = vec![usize::MAX; n];
    for (q, &r) in roots.iter().enumerate() {
        part[r] = q;
    }
    let names: Vec<u64> = roots.iter().map(|&r| name[r]).collect();
    // per part: its smallest node tag and its owned nodes
    let mut tags = vec![u64::MAX; roots.len()];
    let mut owned = vec![0u64; roots.len()];
    for v in (0..n).filter(|&v| in_cell[v]) {
        let q = part[joins.root(v)];
        tags[q] = tags[q].min(mesh.node_tags[v]);
        owned[q] += u64::from(layout.owns_node(v));
    }
    // per part: the Gram matrix of the rigid modes' values at its Dirichlet dofs (owned nodes)
    let modes = RigidModes::new(mesh);
    let mm = modes.m * modes.m;
    let mut grams = vec![0.0; roots.len() * mm];
    let mut shared: Vec<u64> = Vec::new(); // (global node, part name) pairs
    for v in (0..n).filter(|&v| in_cell[v]) {
        let r = joins.root(v);
        if layout.owns_node(v) {
            let q = part[r];
            for a in (0..dim).filter(|&a| !fixed[v * dim + a].is_nan()) {
                let row = modes.dof_row(&mesh.coords[v], a);
                modes.add_outer(&mut grams[q * mm..(q + 1) * mm], &row);
            }
        }
        if in_ghost[v] || !layout.owns_node(v) {
            shared.extend_from_slice(&[layout.node_global[v] as u64, name[r]]);
        }
    }
    let shared = ctx.gather_to_root(&shared);
    let names = ctx.gather_to_root(&names);
    let grams = ctx.gather_to_root(&grams);
    let tags = ctx.gather_to_root(&tags);
    let owned = ctx.gather_to_root(&owned);
    // three numbers per body (the tag as f64: exact below 2^53)
    let mut list = Vec::new();
    if ctx.rank == 0 {
        for b in join_parts(&names, &grams, &shared, &modes, (&tags, &owned)) {
            list.extend([b.first_tag as f64, b.nodes as f64, b.free_modes as f64]);
        }
    }
    ctx.broadcast_f64s(&mut list);
    list.chunks_exact(3)
        .map(|c| Body {
            first_tag: c[0] as u64,
            nodes: c[1] as usize,
            free_modes: c[2] as usize,
        })
        .collect()
}

/// Rank 0: the parts (their names and the Gram matrices of their Dirichlet rows, from every
/// rank) joined where they share a node (pairs of global node and part name); returns the
/// bodies (`parts`: each part's smallest tag and owned nodes), in the order of their first
/// tags. Local.
fn join_parts(
    names: &[u64],
    grams: &[f64],
    shared: &[u64],
    modes: &RigidModes,
    (tags, owned): (&[u64], &[u64]),
) -> Vec<Body> {
    let mm = modes.m * modes.m;
    let mut index: HashMap<u64, usize> = HashMap::new();
    for &p in names {
        let next = index.len();
        index.entry(p).or_insert(next);
    }
    let mut joins = Joins::new(index.len());
    let mut first: HashMap<u64, usize> = HashMap::new();
    for s in shared.chunks_exact(2) {
        let Some(&part) = index.get(&s[1]) else {
            continue;
        };
        let f = *first.entry(s[0]).or_insert(part);
        joins.join(f, part);
    }
    let mut body: HashMap<usize, (Vec<f64>, u64, u64)> = HashMap::new();
    for (q, &p) in names.iter().enumerate() {
        let (g, tag, nodes) = body
            .entry(joins.root(index[&p]))
            .or_insert_with(|| (vec![0.0; mm], u64::MAX, 0));
        for (a, b) in g.iter_mut().zip(&grams[q * mm..(q + 1) * mm]) {
            *a += b;
        }
        *tag = (*tag).min(tags[q]);
        *nodes += owned[q];
    }
    let mut list: Vec<Body> = body
        .values()
        .map(|(g, tag, nodes)| Body {
            first_tag: *tag,
            nodes: *nodes as usize,
            free_modes: modes.free_modes(g).ncols(),
        })
        .collect();
    list.sort_by_key(|b| b.first_tag);
    list
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two ranks' parts: rank 0 has parts 0 and 10, rank 1 has parts 3 and 20; part 0 and
    /// part 3 share node 5, part 10 and part 20 share nothing: three bodies. Part 0 alone has
    /// Dirichlet rows that fix every rigid mode (a full Gram matrix), part 20 only some.
    #[test]
    fn parts_that_share_a_node_are_one_body() {
        let square =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/meshes/square_h0.5.msh");
        let modes = RigidModes::new(&crate::mesh::read_msh(&square).expect("the square"));
        let mm = 9;
        let mut grams = vec![0.0; 4 * mm];
        for k in 0..3 {
            grams[k * 3 + k] = 1.0; // part 0: every mode fixed
        }
        grams[3 * mm] = 1.0; // part 20: the x-translation fixed only
        let names = [0, 10, 3, 20];
        let parts = ([1, 11, 4, 21].as_slice(), [2, 3, 4, 5].as_slice());
        let counted = |shared: &[u64]| {
            let list = join_parts(&names, &grams, shared, &modes, parts);
            let b = summed(&list);
            (b.count, b.not_held, list)
        };
        let shared = [5, 0, 7, 10, 5, 3, 8, 20];
        let (count, not_held, list) = counted(&shared);
        assert_eq!((count, not_held), (3, 2));
        assert_eq!(
            list[0],
            Body {
                first_tag: 1,
                nodes: 6,
                free_modes: 0
            }
        );
        // node 7 shared by part 10 and part 20 as well: two bodies, the second not held
        let shared = [5, 0, 7, 10, 5, 3, 7, 20];
        let (count, not_held, list) = counted(&shared);
        assert_eq!((count, not_held), (2, 1));
        assert_eq!((list[1].first_tag, list[1].nodes), (11, 8));
    }

    #[test]
    fn joins_chain_to_one_root() {
        let mut j = Joins::new(6);
        j.join(4, 5);
        j.join(2, 4);
        j.join(0, 5);
        assert_eq!(j.root(5), 0);
        assert_eq!(j.root(2), 0);
        assert_ne!(j.root(1), 0);
        assert_ne!(j.root(3), j.root(1));
    }
}
