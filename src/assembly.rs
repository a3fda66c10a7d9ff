//! Assembly of the stiffness matrix A and load vector f of (3.8), every rank its own cells.
//!
//! The exact pattern of the owned rows is built first (every cell touching an owned node, from
//! the whole mesh every rank holds); element matrices are scatter-added into those CSR values
//! and handed to PETSc in one piece (MatMPIAIJSetPreallocationCSR), rows of nodes owned by
//! other ranks go through MatSetValues. No mallocs (checked), no per-entry searches in PETSc.
//!
//! Dirichlet data are eliminated symmetrically inside the element loop (row and column of a
//! fixed dof are zero except the diagonal, the known value moves to the right-hand side), so A
//! keeps its full nonzero pattern and stays symmetric; the right-hand side of a fixed dof is set
//! to A_jj · g_j after assembly. Zeros are inserted explicitly: the pattern never changes.

use crate::fem::{self, Material};
use crate::mesh::Mesh;
use crate::partition::Layout;
use crate::petsc::{self, MPI_Comm, Matrix, PInt, Vector};
use std::time::Instant;

/// A load on a set of boundary facets.
#[derive(Clone, Debug)]
pub enum FacetLoadKind {
    /// Normal pressure, positive pushes into the body.
    Pressure(f64),
    /// Vector traction (3 components, z ignored in 2D).
    Traction([f64; 3]),
}

#[derive(Clone, Debug)]
pub struct FacetLoad {
    /// Indices into `mesh.facets`.
    pub facets: Vec<usize>,
    pub kind: FacetLoadKind,
}

/// Volume load.
pub enum BodyForce {
    None,
    Constant([f64; 3]),
    /// A smooth field, integrated with a degree-2 rule (manufactured solutions).
    Function(Box<dyn Fn([f64; 3]) -> [f64; 3]>),
}

/// The linear-elastic problem as assembly sees it.
pub struct Problem<'a> {
    pub mesh: &'a Mesh,
    pub material: Material,
    /// Prescribed value per mesh dof (node * dim + component); NaN = free.
    pub fixed: Vec<f64>,
    pub facet_loads: Vec<FacetLoad>,
    pub body_force: BodyForce,
}

/// Assembly statistics of this rank.
#[derive(Clone, Copy, Debug, Default)]
pub struct AssemblyStats {
    pub preallocation_seconds: f64,
    pub matrix_seconds: f64,
    pub load_seconds: f64,
    pub mallocs: f64,
    pub nonzeros: f64,
}

/// A and f in PETSc form.
pub struct System {
    pub a: Matrix,
    pub b: Vector,
    pub stats: AssemblyStats,
}

/// Global dof numbers of the nodes of a cell / facet.
#[inline]
fn dofs_of(nodes: &[usize], layout: &Layout, dim: usize, out: &mut [PInt]) {
    for (a, &v) in nodes.iter().enumerate() {
        let g = layout.node_global[v] * dim;
        for i in 0..dim {
            out[a * dim + i] = (g + i) as PInt;
        }
    }
}

/// The exact pattern of the owned node rows: for each owned node (in global order) its
/// neighbour nodes (itself included, every cell of the mesh that touches it), as sorted
/// global node numbers.
struct NodePattern {
    ptr: Vec<usize>,
    nbr: Vec<usize>,
}

fn node_pattern(mesh: &Mesh, layout: &Layout) -> NodePattern {
    let n_owned = layout.n_owned_nodes();
    let mut ptr = Vec::with_capacity(n_owned + 1);
    let mut nbr = Vec::with_capacity(n_owned * if mesh.dim == 2 { 7 } else { 15 });
    ptr.push(0);
    let mut stamp = vec![usize::MAX; mesh.n_nodes()];
    for (i, &v) in layout.owned_nodes.iter().enumerate() {
        let start = nbr.len();
        for &c in layout.node_cells.of(v) {
            for &w in mesh.cell(c) {
                if stamp[w] != i {
                    stamp[w] = i;
                    nbr.push(layout.node_global[w]);
                }
            }
        }
        nbr[start..].sort_unstable();
        ptr.push(nbr.len());
    }
    NodePattern { ptr, nbr }
}

/// Owned dof rows of the pattern in CSR form (global columns), values zero.
fn dof_csr(pat: &NodePattern, dim: usize) -> (Vec<PInt>, Vec<PInt>, Vec<usize>) {
    let n_owned = pat.ptr.len() - 1;
    let mut rowptr = Vec::with_capacity(n_owned * dim + 1);
    let mut base = Vec::with_capacity(n_owned);
    let mut cols: Vec<PInt> = Vec::with_capacity(pat.nbr.len() * dim * dim);
    rowptr.push(0 as PInt);
    for i in 0..n_owned {
        base.push(cols.len());
        let nb = &pat.nbr[pat.ptr[i]..pat.ptr[i + 1]];
        for _ in 0..dim {
            for &w in nb {
                for c in 0..dim {
                    cols.push((w * dim + c) as PInt);
                }
            }
            rowptr.push(cols.len() as PInt);
        }
    }
    (rowptr, cols, base)
}

/// The cell that contains a boundary facet, and the cell node opposite to it.
pub fn facet_cell(mesh: &Mesh, layout: &Layout, facet: usize) -> Option<(usize, usize)> {
    let fnodes = mesh.facet(facet);
    layout
        .node_cells
        .of(fnodes[0])
        .iter()
        .copied()
        .find(|&c| {
            let cn = mesh.cell(c);
            fnodes.iter().all(|v| cn.contains(v))
        })
        .map(|c| {
            let opp = *mesh
                .cell(c)
                .iter()
                .find(|v| !fnodes.contains(v))
                .expect("a cell has a node off its facet");
            (c, opp)
        })
}

/// Outward unit normal and measure of a boundary facet (oriented away from its cell).
pub fn outward_normal(mesh: &Mesh, facet: usize, opposite: usize) -> ([f64; 3], f64) {
    let fn_ = mesh.facet(facet);
    let x: Vec<[f64; 3]> = fn_.iter().map(|&v| mesh.coords[v]).collect();
    let (mut n, m) = fem::facet_normal_measure(&x);
    let xo = mesh.coords[opposite];
    let s: f64 = (0..3).map(|i| (xo[i] - x[0][i]) * n[i]).sum();
    if s > 0.0 {
        n = [-n[0], -n[1], -n[2]];
    }
    (n, m)
}

/// Assembles A (MPIAIJ, block size dim, exact preallocation) and f (3.8) on this rank's cells.
pub fn assemble(comm: MPI_Comm, layout: &Layout, p: &Problem) -> petsc::Result<System> {
    let mesh = p.mesh;
    let dim = mesh.dim;
    let npc = dim + 1;
    let nd = npc * dim;
    let t0 = Instant::now();
    let pat = node_pattern(mesh, layout);
    let (rowptr, cols, base) = dof_csr(&pat, dim);
    let mut vals = vec![0.0f64; cols.len()];
    let local_rows = layout.n_owned_nodes() * dim;
    let (node_lo, _) = layout.node_range();
    let mut b = Vector::new_mpi(comm, local_rows, dim)?;
    let mut stats = AssemblyStats {
        preallocation_seconds: t0.elapsed().as_secs_f64(),
        ..Default::default()
    };

    let t1 = Instant::now();
    let (lambda, mu) = p.material.lame();
    let mut ke = [0.0f64; 144];
    let mut idx = [0 as PInt; 12];
    let mut bidx: Vec<PInt> = Vec::with_capacity(layout.local_cells.len() * nd);
    let mut bval: Vec<f64> = Vec::with_capacity(layout.local_cells.len() * nd);
    // Element rows of nodes owned by other ranks: (local node, dofs, element matrix).
    let mut off_rows: Vec<(usize, [PInt; 12], [f64; 144])> = Vec::new();
    for &c in &layout.local_cells {
        let nodes = mesh.cell(c);
        element_stiffness(mesh, nodes, lambda, mu, &mut ke);
        dofs_of(nodes, layout, dim, &mut idx);
        eliminate_fixed(p, nodes, &mut ke, &idx, &mut bidx, &mut bval);
        // Scatter-add into the owned rows' CSR values; rows of other ranks' nodes go through
        // MatSetValues after the matrix exists.
        for (ia, &va) in nodes.iter().enumerate() {
            if !layout.owns_node(va) {
                off_rows.push((ia, idx, ke));
                continue;
            }
            let la = layout.node_global[va] - node_lo;
            let nb = &pat.nbr[pat.ptr[la]..pat.ptr[la + 1]];
            let m = nb.len();
            for (ib, &vb) in nodes.iter().enumerate() {
                let pos = nb
                    .binary_search(&layout.node_global[vb])
                    .expect("pattern holds every cell neighbour");
                for r in 0..dim {
                    let row0 = base[la] + r * dim * m + pos * dim;
                    let krow = (ia * dim + r) * nd + ib * dim;
                    for cc in 0..dim {
                        vals[row0 + cc] += ke[krow + cc];
                    }
                }
            }
        }
    }
    let mut a = Matrix::from_csr(comm, dim, &rowptr, &cols, &vals)?;
    drop(vals);
    for (ia, ix, k) in &off_rows {
        for r in 0..dim {
            let row = ia * dim + r;
            a.add_values(&[ix[row]], &ix[..nd], &k[row * nd..(row + 1) * nd])?;
        }
    }
    a.assemble()?;
    stats.matrix_seconds = t1.elapsed().as_secs_f64();
    let st = a.stats()?;
    stats.mallocs = st.mallocs;
    stats.nonzeros = st.nonzeros;

    let t2 = Instant::now();
    load_entries(p, layout, &mut bidx, &mut bval);
    b.set_values(&bidx, &bval, true)?;
    b.assemble()?;
    fixed_rhs(&a, &mut b, layout, p)?;
    stats.load_seconds = t2.elapsed().as_secs_f64();
    Ok(System { a, b, stats })
}

/// A cell's element stiffness matrix (row-major, (d+1)d × (d+1)d).
fn element_stiffness(mesh: &Mesh, nodes: &[usize], lambda: f64, mu: f64, ke: &mut [f64; 144]) {
    if mesh.dim == 2 {
        let x = [
            [mesh.coords[nodes[0]][0], mesh.coords[nodes[0]][1]],
            [mesh.coords[nodes[1]][0], mesh.coords[nodes[1]][1]],
            [mesh.coords[nodes[2]][0], mesh.coords[nodes[2]][1]],
        ];
        let k: &mut [f64; 36] = (&mut ke[..36]).try_into().expect("36 entries");
        fem::tri_stiffness(&x, lambda, mu, k);
    } else {
        let x = [
            mesh.coords[nodes[0]],
            mesh.coords[nodes[1]],
            mesh.coords[nodes[2]],
            mesh.coords[nodes[3]],
        ];
        fem::tet_stiffness(&x, lambda, mu, ke);
    }
}

/// Symmetric elimination of the cell's fixed dofs: their rows and columns of `ke` become zero
/// off the diagonal, and −K_ij g_j goes to the right-hand side of the free dofs i (entries
/// appended to `bidx`/`bval`).
fn eliminate_fixed(
    p: &Problem,
    nodes: &[usize],
    ke: &mut [f64; 144],
    idx: &[PInt; 12],
    bidx: &mut Vec<PInt>,
    bval: &mut Vec<f64>,
) {
    let dim = p.mesh.dim;
    let nd = nodes.len() * dim;
    let mut fixed_local = [f64::NAN; 12];
    let mut any_fixed = false;
    for (a, &v) in nodes.iter().enumerate() {
        for i in 0..dim {
            let g = p.fixed[v * dim + i];
            fixed_local[a * dim + i] = g;
            any_fixed |= !g.is_nan();
        }
    }
    if !any_fixed {
        return;
    }
    let mut fe = [0.0f64; 12];
    for j in 0..nd {
        let g = fixed_local[j];
        if g.is_nan() {
            continue;
        }
        for i in 0..nd {
            if i != j {
                if fixed_local[i].is_nan() {
                    fe[i] -= ke[i * nd + j] * g;
                }
                ke[i * nd + j] = 0.0;
                ke[j * nd + i] = 0.0;
            }
        }
    }
    for i in 0..nd {
        if fixed_local[i].is_nan() && fe[i] != 0.0 {
            bidx.push(idx[i]);
            bval.push(fe[i]);
        }
    }
}

/// The load entries (3.8) of this rank: body force on its cells, facet loads on the facets
/// whose cell is its own.
fn load_entries(p: &Problem, layout: &Layout, bidx: &mut Vec<PInt>, bval: &mut Vec<f64>) {
    let mesh = p.mesh;
    let dim = mesh.dim;
    let nd = (dim + 1) * dim;
    let mut fe = [0.0f64; 12];
    let mut idx = [0 as PInt; 12];
    // Loads: body force on own cells, facet loads on facets whose cell is ours.
    let mut xs: Vec<[f64; 3]> = Vec::with_capacity(4);
    match &p.body_force {
        BodyForce::None => {}
        BodyForce::Constant(f) => {
            for &c in &layout.local_cells {
                let nodes = mesh.cell(c);
                let m = mesh.cell_measure(c);
                fem::body_force_load(m, *f, dim, &mut fe[..nd]);
                dofs_of(nodes, layout, dim, &mut idx);
                bidx.extend_from_slice(&idx[..nd]);
                bval.extend_from_slice(&fe[..nd]);
            }
        }
        BodyForce::Function(f) => {
            for &c in &layout.local_cells {
                let nodes = mesh.cell(c);
                xs.clear();
                xs.extend(nodes.iter().map(|&v| mesh.coords[v]));
                fem::cell_load_quadrature(&xs, dim, f.as_ref(), &mut fe[..nd]);
                dofs_of(nodes, layout, dim, &mut idx);
                bidx.extend_from_slice(&idx[..nd]);
                bval.extend_from_slice(&fe[..nd]);
            }
        }
    }
    let nf = dim * dim;
    for load in &p.facet_loads {
        for &f in &load.facets {
            let Some((c, opp)) = facet_cell(mesh, layout, f) else {
                continue;
            };
            if layout.cell_rank[c] as usize != layout.rank {
                continue;
            }
            let (n, m) = outward_normal(mesh, f, opp);
            let t = match &load.kind {
                FacetLoadKind::Pressure(pr) => [-pr * n[0], -pr * n[1], -pr * n[2]],
                FacetLoadKind::Traction(t) => *t,
            };
            fem::lumped_facet_load(m, t, dim, &mut fe[..nf]);
            dofs_of(mesh.facet(f), layout, dim, &mut idx);
            bidx.extend_from_slice(&idx[..nf]);
            bval.extend_from_slice(&fe[..nf]);
        }
    }
}

/// Fixed dofs: b_j = A_jj g_j (A's row j is zero off the diagonal).
fn fixed_rhs(a: &Matrix, b: &mut Vector, layout: &Layout, p: &Problem) -> petsc::Result<()> {
    let dim = p.mesh.dim;
    let mut diag = b.duplicate()?;
    a.diagonal(&mut diag)?;
    let dvals = diag.to_local_vec()?;
    b.write(|bv| {
        for (i, &v) in layout.owned_nodes.iter().enumerate() {
            for k in 0..dim {
                let g = p.fixed[v * dim + k];
                if !g.is_nan() {
                    bv[i * dim + k] = dvals[i * dim + k] * g;
                }
            }
        }
    })?;
    Ok(())
}

/// Nodal coordinates of the owned nodes as a PETSc vector with block size dim (for the
/// rigid-body near-null space of AMG).
pub fn coordinate_vector(comm: MPI_Comm, mesh: &Mesh, layout: &Layout) -> petsc::Result<Vector> {
    let dim = mesh.dim;
    let mut v = Vector::new_mpi(comm, layout.n_owned_nodes() * dim, dim)?;
    v.write(|x| {
        for (i, &n) in layout.owned_nodes.iter().enumerate() {
            for k in 0..dim {
                x[i * dim + k] = mesh.coords[n][k];
            }
        }
    })?;
    Ok(v)
}
