//! The separate bodies of a mesh (its connected parts, cells joined by shared nodes), counted
//! over the distributed mesh, with those that their Dirichlet data do not hold in every rigid
//! mode: said in the log where there are several, and written to summary.json; the body of
//! every local node, and the rigid modes of the bodies Dirichlet data leave free, for the
//! contact solver (signorini/rigid.rs).
//!
//! Every rank joins its local cells (its own and the ghost cells touching its owned nodes) by a
//! union-find over its local nodes; a local part is named by its smallest global node number.
//! The nodes a part shares with another rank's parts — those not owned here, and those of
//! ghost cells — go to rank 0 with the part's name, and rank 0 joins the parts that share a
//! node: O(the partition's interfaces) on rank 0, never the mesh.

use crate::mesh::{BodyModes, Mesh, RigidModes};
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
    labelled(ctx, mesh, layout, fixed).bodies
}

/// The bodies of a mesh and the body of every local node.
pub struct Survey {
    /// Every body, by its first node tag (the same on every rank).
    pub bodies: Vec<Body>,
    /// Per local mesh node: its body's index in `bodies` (`u32::MAX`: a node of no local
    /// cell).
    pub body_of: Vec<u32>,
}

/// Every body of the distributed `mesh` and the body of every local node. Collective.
pub fn labelled(ctx: &Ctx, mesh: &Mesh, layout: &Layout, fixed: &[f64]) -> Survey {
    let mut local = LocalParts::of(mesh, layout);
    let (grams, shared, tags, owned) = local.data(mesh, layout, fixed);
    let modes = RigidModes::new(mesh);
    let all_names = ctx.gather_to_root(&local.names);
    let grams = ctx.gather_to_root(&grams);
    let shared = ctx.gather_to_root(&shared);
    let tags = ctx.gather_to_root(&tags);
    let owned = ctx.gather_to_root(&owned);
    // the body count, three numbers per body (the tag as f64: exact below 2^53), then
    // (part name, body) pairs
    let mut list = Vec::new();
    if ctx.rank == 0 {
        let (bodies, of_part) = join_parts(&all_names, &grams, &shared, &modes, &tags, &owned);
        list.push(bodies.len() as f64);
        for b in bodies {
            list.extend([b.first_tag as f64, b.nodes as f64, b.free_modes as f64]);
        }
        for (p, b) in all_names.iter().zip(of_part) {
            list.extend([*p as f64, b as f64]);
        }
    }
    ctx.broadcast_f64s(&mut list);
    let count = list[0] as usize;
    let bodies = list[1..1 + 3 * count]
        .chunks_exact(3)
        .map(|c| Body {
            first_tag: c[0] as u64,
            nodes: c[1] as usize,
            free_modes: c[2] as usize,
        })
        .collect();
    let body_of_name: HashMap<u64, u32> = list[1 + 3 * count..]
        .chunks_exact(2)
        .map(|c| (c[0] as u64, c[1] as u32))
        .collect();
    let body_of = (0..mesh.n_nodes())
        .map(|v| match local.name_of(v) {
            Some(p) => body_of_name[&p],
            None => u32::MAX,
        })
        .collect();
    Survey { bodies, body_of }
}

/// Per body of `survey`: whether some node of one of the boundary `groups` lies on it.
/// Collective.
pub fn touched(ctx: &Ctx, mesh: &Mesh, survey: &Survey, groups: &[&str]) -> Vec<bool> {
    let mut on = vec![0.0; survey.bodies.len()];
    for g in groups {
        for f in crate::setup::group_facets(mesh, g) {
            for &v in mesh.facet(f) {
                if let Some(x) = on.get_mut(survey.body_of[v] as usize) {
                    *x = 1.0;
                }
            }
        }
    }
    ctx.sum_vec(&on).iter().map(|&x| x > 0.0).collect()
}

impl Survey {
    /// The rigid modes of the bodies that Dirichlet data leave free (each body's centre and
    /// scale its bounding box over every rank); the whole mesh's shape for a mesh of one body.
    /// Collective.
    pub fn modes(&self, ctx: &Ctx, mesh: &Mesh) -> BodyModes {
        let nb = self.bodies.len();
        if nb == 1 {
            if self.bodies[0].free_modes > 0 {
                return BodyModes::whole(mesh);
            }
            return BodyModes::new(mesh, &self.body_of, &[None]);
        }
        // per body: lo (3), then −hi (3): one all-gather, the minimum over the ranks
        let mut mine = vec![f64::INFINITY; nb * 6];
        for (v, &b) in self.body_of.iter().enumerate() {
            let Some(r) = mine.get_mut(b as usize * 6..b as usize * 6 + 6) else {
                continue;
            };
            for k in 0..3 {
                r[k] = r[k].min(mesh.coords[v][k]);
                r[3 + k] = r[3 + k].min(-mesh.coords[v][k]);
            }
        }
        let all = ctx.all_gather_varcount(&mine);
        let mut least = vec![f64::INFINITY; nb * 6];
        for r in all.chunks_exact(nb * 6) {
            for (l, x) in least.iter_mut().zip(r) {
                *l = l.min(*x);
            }
        }
        let boxes: Vec<Option<([f64; 3], [f64; 3])>> = (0..nb)
            .map(|b| {
                let r = &least[b * 6..b * 6 + 6];
                (self.bodies[b].free_modes > 0).then(|| ([r[0], r[1], r[2]], [-r[3], -r[4], -r[5]]))
            })
            .collect();
        BodyModes::new(mesh, &self.body_of, &boxes)
    }
}

/// A rank's parts of the mesh: its local cells joined by shared nodes.
struct LocalParts {
    joins: Joins,
    /// Nodes of local cells (the local mesh has the nodes of boundary elements of other ranks'
    /// cells too: only the nodes of local cells belong to a part here).
    in_cell: Vec<bool>,
    /// Nodes of ghost cells.
    in_ghost: Vec<bool>,
    /// Per root: the part's name, its smallest global node number.
    name: Vec<u64>,
    /// Per root: the part's index.
    part: Vec<usize>,
    /// The parts' names, by index.
    names: Vec<u64>,
}

impl LocalParts {
    fn of(mesh: &Mesh, layout: &Layout) -> LocalParts {
        let n = mesh.n_nodes();
        let mut joins = Joins::new(n);
        let mut in_ghost = vec![false; n];
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
        let mut name = vec![u64::MAX; n];
        for v in (0..n).filter(|&v| in_cell[v]) {
            let r = joins.root(v);
            name[r] = name[r].min(layout.node_global[v] as u64);
        }
        let roots: Vec<usize> = (0..n)
            .filter(|&v| in_cell[v] && joins.root(v) == v)
            .collect();
        let mut part = vec![usize::MAX; n];
        for (q, &r) in roots.iter().enumerate() {
            part[r] = q;
        }
        let names = roots.iter().map(|&r| name[r]).collect();
        LocalParts {
            joins,
            in_cell,
            in_ghost,
            name,
            part,
            names,
        }
    }

    /// The name of local node v's part (`None`: v is in no local cell).
    fn name_of(&mut self, v: usize) -> Option<u64> {
        self.in_cell[v].then(|| self.name[self.joins.root(v)])
    }

    /// Per part: the Gram matrix of the rigid modes' values at its Dirichlet dofs (owned
    /// nodes), its smallest node tag and its owned node count; and the (global node, part
    /// name) pairs of the nodes it may share with other ranks' parts. Local.
    fn data(
        &mut self,
        mesh: &Mesh,
        layout: &Layout,
        fixed: &[f64],
    ) -> (Vec<f64>, Vec<u64>, Vec<u64>, Vec<u64>) {
        let (n, dim) = (mesh.n_nodes(), mesh.dim);
        let parts = self.names.len();
        let modes = RigidModes::new(mesh);
        let mm = modes.m * modes.m;
        let mut grams = vec![0.0; parts * mm];
        let mut shared: Vec<u64> = Vec::new();
        let mut tags = vec![u64::MAX; parts];
        let mut owned = vec![0u64; parts];
        for v in (0..n).filter(|&v| self.in_cell[v]) {
            let r = self.joins.root(v);
            let q = self.part[r];
            tags[q] = tags[q].min(mesh.node_tags[v]);
            owned[q] += u64::from(layout.owns_node(v));
            if layout.owns_node(v) {
                for a in (0..dim).filter(|&a| !fixed[v * dim + a].is_nan()) {
                    let row = modes.dof_row(&mesh.coords[v], a);
                    modes.add_outer(&mut grams[q * mm..(q + 1) * mm], &row);
                }
            }
            if self.in_ghost[v] || !layout.owns_node(v) {
                shared.extend_from_slice(&[layout.node_global[v] as u64, self.name[r]]);
            }
        }
        (grams, shared, tags, owned)
    }
}

/// Rank 0: the parts (their names and the Gram matrices of their Dirichlet rows, from every
/// rank) joined where they share a node (pairs of global node and part name); returns the
/// bodies (`parts`: each part's smallest tag and owned nodes), in the order of their first
/// tags, and each part's body (an index into them). Local.
fn join_parts(
    names: &[u64],
    grams: &[f64],
    shared: &[u64],
    modes: &RigidModes,
    tags: &[u64],
    owned: &[u64],
) -> (Vec<Body>, Vec<usize>) {
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
    let mut list: Vec<(usize, Body)> = body
        .iter()
        .map(|(&root, (g, tag, nodes))| {
            let b = Body {
                first_tag: *tag,
                nodes: *nodes as usize,
                free_modes: modes.free_modes(g).ncols(),
            };
            (root, b)
        })
        .collect();
    list.sort_by_key(|(_, b)| b.first_tag);
    let at: HashMap<usize, usize> = (list.iter().enumerate())
        .map(|(i, (root, _))| (*root, i))
        .collect();
    let of_part = names.iter().map(|p| at[&joins.root(index[p])]).collect();
    (list.into_iter().map(|(_, b)| b).collect(), of_part)
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
            let (list, _) = join_parts(&names, &grams, shared, &modes, parts.0, parts.1);
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
