//! Assembly of the stiffness matrix A and load vector f of (3.8), every rank its own rows.
//!
//! Row by row: every owned node gathers the cells around it (a compact copy of the cells that
//! touch owned nodes: this rank's in the layout's order, then those of other ranks), sums their
//! element rows into a small dense buffer and appends it to the CSR arrays of its rows, split
//! as PETSc stores them (owned columns / other columns). Each element matrix is thus computed
//! in pieces by the owners of its nodes, every value of an owned row on its owner: no entries
//! are sent to other ranks, no searches, no scatter into a large array. PETSc takes the two
//! CSR parts as they are (no per-entry insertion, no copy: the matrix keeps the arrays);
//! PETSc's storage is checked to hold exactly the entries given, with no mallocs.
//!
//! On one rank every entry is summed over the same cells in the same order as the former cell
//! loop (the layout's cell order), so A and f are the same bit for bit; on several ranks an
//! interface row's sum now runs over all its cells in one order instead of own cells first,
//! then the other ranks' parts (round-off differences only).
//!
//! Dirichlet data are eliminated symmetrically per entry (row and column of a fixed dof are
//! zero except the diagonal, the known value moves to the right-hand side), so A keeps its
//! full nonzero pattern and stays symmetric; the right-hand side of a fixed dof is A_jj · g_j.
//! Zeros are stored explicitly: the pattern never changes.

use crate::bigbuf::BigVec;
use crate::fem::{self, Materials};
use crate::mesh::Mesh;
use crate::partition::Layout;
use crate::petsc::{self, Csr, MPI_Comm, Matrix, PInt, Vector};
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
    /// Scaled by a load step's factor; `false`: held at its full value in every step.
    pub ramp: bool,
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
    /// The material of every cell.
    pub material: &'a Materials,
    /// Prescribed value per mesh dof (node * dim + component); NaN = free.
    pub fixed: Vec<f64>,
    /// Per mesh dof: a prescribed value held at full value in every load step (`ramp = false`);
    /// empty when the case holds none (the same on every rank).
    pub held_fixed: Vec<bool>,
    pub facet_loads: Vec<FacetLoad>,
    pub body_force: BodyForce,
}

/// Assembly statistics of this rank.
#[derive(Clone, Copy, Debug, Default)]
pub struct AssemblyStats {
    pub preallocation_seconds: f64,
    pub matrix_seconds: f64,
    /// Of `matrix_seconds`: the element rows summed into the CSR arrays (incl. the cell list).
    pub rows_seconds: f64,
    /// Of `matrix_seconds`: the arrays handed to PETSc (its assembly, no copy).
    pub petsc_seconds: f64,
    pub load_seconds: f64,
    pub mallocs: f64,
    pub nonzeros: f64,
}

/// A and f in PETSc form.
pub struct System {
    pub a: Matrix,
    pub b: Vector,
    /// The part of `b` from the facet loads that do not ramp with a load step's factor (zero
    /// on fixed dofs); `None` when every load ramps.
    pub b_held: Option<Vector>,
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

/// The cells that contribute to this rank's rows, in a compact, cache-friendly form: this
/// rank's cells in the layout's order (lowest node number first), then the cells of other
/// ranks that touch an owned node, and for every owned node its incidences `cell * N + a`
/// (cell in this list, a = the node's position in the cell), in list order.
struct RowCells {
    /// Mesh node indices, nodes-per-cell per cell.
    nodes: Vec<u32>,
    /// The material index of every cell in this list; empty with one material.
    mat: Vec<u16>,
    ptr: Vec<u32>,
    inc: Vec<u32>,
}

impl RowCells {
    /// The material index of cell i of this list.
    #[inline(always)]
    fn material(&self, i: usize) -> usize {
        if self.mat.is_empty() {
            0
        } else {
            self.mat[i] as usize
        }
    }
}

fn row_cells(mesh: &Mesh, layout: &Layout, materials: &Materials) -> RowCells {
    let npc = mesh.nodes_per_cell();
    let mut cells: Vec<usize> = layout.local_cells.clone();
    if layout.size > 1 {
        // Ordered by (lowest global node number, cell), each key computed once.
        let mut ghost: Vec<(usize, usize)> = (0..mesh.n_cells())
            .filter(|&c| {
                layout.cell_rank[c] as usize != layout.rank
                    && mesh.cell(c).iter().any(|&v| layout.owns_node(v))
            })
            .map(|c| {
                let lo = mesh.cell(c).iter().map(|&v| layout.node_global[v]).min();
                (lo.unwrap_or(0), c)
            })
            .collect();
        ghost.sort_unstable();
        ghost.dedup();
        cells.extend(ghost.into_iter().map(|(_, c)| c));
    }
    let mut nodes = Vec::with_capacity(cells.len() * npc);
    for &c in &cells {
        nodes.extend(mesh.cell(c).iter().map(|&v| v as u32));
    }
    let mat = if materials.list.len() > 1 {
        cells.iter().map(|&c| materials.index(c) as u16).collect()
    } else {
        Vec::new()
    };
    drop(cells);
    // Per mesh node: its owned (local) number, or u32::MAX.
    let (node_lo, node_hi) = layout.node_range();
    let owned: Vec<u32> = layout
        .node_global
        .iter()
        .map(|&g| {
            if (node_lo..node_hi).contains(&g) {
                (g - node_lo) as u32
            } else {
                u32::MAX
            }
        })
        .collect();
    let local = |v: u32| {
        let l = owned[v as usize];
        (l != u32::MAX).then_some(l as usize)
    };
    let mut ptr = vec![0u32; layout.n_owned_nodes() + 1];
    for &v in &nodes {
        if let Some(l) = local(v) {
            ptr[l + 1] += 1;
        }
    }
    for i in 0..layout.n_owned_nodes() {
        ptr[i + 1] += ptr[i];
    }
    let mut fill = ptr.clone();
    let mut inc = vec![0u32; ptr[layout.n_owned_nodes()] as usize];
    for (e, &v) in nodes.iter().enumerate() {
        if let Some(l) = local(v) {
            inc[fill[l] as usize] = e as u32;
            fill[l] += 1;
        }
    }
    RowCells {
        nodes,
        mat,
        ptr,
        inc,
    }
}

fn csr_with_capacity(rows: usize, nnz: usize) -> Csr {
    let mut rowptr = Vec::with_capacity(rows + 1);
    rowptr.push(0);
    Csr {
        rowptr,
        cols: BigVec::with_capacity(nnz),
        vals: BigVec::with_capacity(nnz),
    }
}

/// The owned rows of A as PETSc stores them (columns sorted per row): `diag` the columns of
/// owned nodes (local numbers), `off` the others (global numbers); and the owned entries of
/// the right-hand side that the Dirichlet elimination gives.
struct OwnedRows {
    diag: Csr,
    off: Csr,
    /// −Σ A_ij g_j over the fixed dofs j, per owned dof (0 for fixed dofs).
    elim_rhs: Vec<f64>,
    /// (owned dof, A_jj g_j) of the fixed dofs: their right-hand side.
    fixed_rhs: Vec<(usize, f64)>,
}

/// Per-row work space of [`owned_rows`], reused from node to node.
struct RowScratch {
    /// Per mesh node: its position in the current row (u32::MAX: not in it). The row of owned
    /// node `la` first stamps its neighbours with `la` while gathering them.
    slot: Vec<u32>,
    /// The row's neighbours as (global number << 32 | mesh node): sorted = by global number.
    nb: Vec<u64>,
    /// The node's D rows, dense over its neighbours (D × nb.len() × D values).
    buf: Vec<f64>,
    /// The columns shared by the node's D rows: owned ones (local numbers), the others
    /// (global numbers); one row's values split the same way; the off-rank neighbours.
    cols: [Vec<PInt>; 2],
    vals: [Vec<f64>; 2],
    off_slots: Vec<usize>,
}

impl RowScratch {
    /// The neighbours of owned node `la` (the nodes of its cells `inc`), sorted by global
    /// number, with `slot` set to their positions in the row.
    #[inline(always)]
    fn gather_neighbours<const N: usize>(
        &mut self,
        layout: &Layout,
        rc: &RowCells,
        la: usize,
        inc: &[u32],
    ) {
        let (slot, nb) = (&mut self.slot, &mut self.nb);
        nb.clear();
        for &e in inc {
            let c0 = e as usize / N * N;
            for &w in &rc.nodes[c0..c0 + N] {
                if slot[w as usize] != la as u32 {
                    slot[w as usize] = la as u32;
                    nb.push(((layout.node_global[w as usize] as u64) << 32) | w as u64);
                }
            }
        }
        nb.sort_unstable();
        for (s, &key) in nb.iter().enumerate() {
            slot[key as u32 as usize] = s as u32;
        }
    }

    /// Resets the row's slots (they must not alias the next row's stamp).
    fn clear_slots(&mut self) {
        for &key in &self.nb {
            self.slot[key as u32 as usize] = u32::MAX;
        }
    }

    /// Appends the node's D rows in `buf` to the two CSR parts (the columns of the owned nodes
    /// `lo..hi` in `diag`): the columns once per node, an interior row's values as one slice,
    /// an interface row's values split.
    #[inline(always)]
    fn append_rows<const D: usize>(&mut self, lo: usize, hi: usize, diag: &mut Csr, off: &mut Csr) {
        let width = self.nb.len() * D;
        let [dcols, ocols] = &mut self.cols;
        dcols.clear();
        ocols.clear();
        self.off_slots.clear();
        for (s, &key) in self.nb.iter().enumerate() {
            let g = (key >> 32) as usize;
            if (lo..hi).contains(&g) {
                dcols.extend((0..D).map(|j| ((g - lo) * D + j) as PInt));
            } else {
                ocols.extend((0..D).map(|j| (g * D + j) as PInt));
                self.off_slots.push(s);
            }
        }
        for i in 0..D {
            let row = &self.buf[i * width..(i + 1) * width];
            diag.cols.extend_from_slice(dcols);
            if self.off_slots.is_empty() {
                diag.vals.extend_from_slice(row);
            } else {
                let [dvals, ovals] = &mut self.vals;
                dvals.clear();
                ovals.clear();
                let mut next_off = self.off_slots.iter().copied().peekable();
                for s in 0..self.nb.len() {
                    let part = if next_off.peek() == Some(&s) {
                        next_off.next();
                        &mut *ovals
                    } else {
                        &mut *dvals
                    };
                    part.extend_from_slice(&row[s * D..(s + 1) * D]);
                }
                diag.vals.extend_from_slice(dvals);
                off.cols.extend_from_slice(ocols);
                off.vals.extend_from_slice(ovals);
            }
            diag.rowptr.push(diag.cols.len() as PInt);
            off.rowptr.push(off.cols.len() as PInt);
        }
    }
}

/// Node a's D rows of one cell's stiffness (3.8) added into the row buffer `row` (width
/// `width`, neighbour offsets `s0`) with the symmetric Dirichlet elimination per entry: a
/// fixed row (`fixed_v[i]` not NaN) keeps only its diagonal, a fixed column `gfix` moves
/// −K_ij g_j into `elim`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn add_rows_with_dirichlet<const D: usize, const N: usize>(
    k: &[[f64; 12]; 3],
    gfix: &[f64; 12],
    fixed_v: &[f64; D],
    a: usize,
    s0: &[usize; N],
    buf: &mut [f64],
    width: usize,
    elim: &mut [f64; D],
) {
    for i in 0..D {
        let row = &mut buf[i * width..(i + 1) * width];
        if !fixed_v[i].is_nan() {
            row[s0[a] + i] += k[i][a * D + i];
            continue;
        }
        let mut fe = 0.0;
        for b in 0..N {
            for j in 0..D {
                let gv = gfix[b * D + j];
                if gv.is_nan() {
                    row[s0[b] + j] += k[i][b * D + j];
                } else {
                    fe -= k[i][b * D + j] * gv;
                }
            }
        }
        if fe != 0.0 {
            elim[i] += fe;
        }
    }
}

impl OwnedRows {
    /// Empty CSR parts for the owned rows, with room reserved for their entries.
    fn with_capacity(layout: &Layout, d: usize) -> OwnedRows {
        let n_owned = layout.n_owned_nodes();
        // A generous guess of the row lengths (nodes incl. itself: ~7 in a triangle mesh,
        // 15-16 in a tetrahedral one; the 2.3 M-unknown Hertz ball has 15.3): the capacity is
        // only reserved (pages are touched as the arrays fill), while a growth copies the
        // arrays (a doubling at 2.3 M unknowns cost seconds).
        let guess = n_owned * d * d * if d == 2 { 9 } else { 20 };
        OwnedRows {
            diag: csr_with_capacity(n_owned * d, guess),
            off: csr_with_capacity(n_owned * d, if layout.size > 1 { guess / 8 } else { 0 }),
            elim_rhs: vec![0.0f64; n_owned * d],
            fixed_rhs: Vec::new(),
        }
    }
}

/// What every row of [`owned_rows`] reads besides its cells: the Dirichlet data per mesh dof
/// (NaN: free), per node whether any of its components is fixed (one byte, cache-resident),
/// and the Lamé constants (1.25) of every material.
struct RowData<'a> {
    fixed: &'a [f64],
    has_fixed: Vec<bool>,
    lame: &'a [(f64, f64)],
}

/// One cell around an owned node as the node's rows see it: the cell's nodes, the owned node's
/// position `a` among them, the gradients `g` of the P1 basis, the signed measure `vol` and the
/// Lamé constants (1.25) of the cell's material.
struct CellOfRow<'c, const D: usize, const N: usize> {
    nodes: &'c [u32],
    a: usize,
    g: [[f64; D]; N],
    vol: f64,
    lambda: f64,
    mu: f64,
}

/// One cell's part of owned node a's D rows of (3.8) added into the row buffer: with the
/// Dirichlet elimination ([`add_rows_with_dirichlet`]) when a node of the cell carries
/// Dirichlet data (the node's own values `fixed_v`, its right-hand side's part `elim`), else
/// the rows as they are, block by block (the numbers of `p1_stiffness_rows`, bit for bit).
#[inline(always)]
fn add_cell_rows<const D: usize, const N: usize>(
    rd: &RowData,
    sc: &mut RowScratch,
    cell: &CellOfRow<D, N>,
    fixed_v: &[f64; D],
    elim: &mut [f64; D],
) {
    let CellOfRow {
        nodes,
        a,
        g,
        vol,
        lambda,
        mu,
    } = *cell;
    let width = sc.nb.len() * D;
    let mut s0 = [0usize; N];
    let mut any_fixed = false;
    for b in 0..N {
        let w = nodes[b] as usize;
        s0[b] = sc.slot[w] as usize * D;
        any_fixed |= rd.has_fixed[w];
    }
    if any_fixed {
        let mut k = [[0.0f64; 12]; 3];
        fem::p1_stiffness_rows::<D, N>(&g, vol.abs(), lambda, mu, a, &mut k);
        let mut gfix = [f64::NAN; 12];
        for b in 0..N {
            let w = nodes[b] as usize;
            gfix[b * D..b * D + D].copy_from_slice(&rd.fixed[w * D..w * D + D]);
        }
        add_rows_with_dirichlet::<D, N>(&k, &gfix, fixed_v, a, &s0, &mut sc.buf, width, elim);
        return;
    }
    let (wl, wm) = (vol.abs() * lambda, vol.abs() * mu);
    for b in 0..N {
        let kb = fem::p1_stiffness_block::<D>(&g[a], &g[b], wl, wm);
        for i in 0..D {
            let dst = &mut sc.buf[i * width + s0[b]..i * width + s0[b] + D];
            for j in 0..D {
                dst[j] += kb[i][j];
            }
        }
    }
}

/// (3.8) row by row: every owned node sums the element rows of the cells around it (in the
/// order of the layout's cell loop; each cell with its own material's Lamé constants) into a
/// small dense row buffer, with the symmetric Dirichlet elimination applied per entry (a
/// fixed dof's row keeps only its diagonal, a fixed column moves −K_ij g_j to the right-hand
/// side), and appends the buffer to the CSR arrays. Every value of an owned row is computed
/// on its owner (other ranks' cells that touch it included): no entries go to other ranks,
/// and no searches (each neighbour's position in the row sits in `slot`). Phases per node:
/// its neighbours ([`RowScratch::gather_neighbours`]), its cells' rows ([`add_cell_rows`]),
/// the CSR parts ([`RowScratch::append_rows`]) and its right-hand-side entries.
fn owned_rows<const D: usize, const N: usize>(
    p: &Problem,
    layout: &Layout,
    rc: &RowCells,
    gradients: impl Fn(&[u32]) -> ([[f64; D]; N], f64),
) -> OwnedRows {
    let n_nodes = p.mesh.n_nodes();
    let mut out = OwnedRows::with_capacity(layout, D);
    let rd = RowData {
        fixed: &p.fixed,
        has_fixed: (0..n_nodes)
            .map(|w| (0..D).any(|j| !p.fixed[w * D + j].is_nan()))
            .collect(),
        lame: p.material.lame_table(),
    };
    let mut sc = RowScratch {
        slot: vec![u32::MAX; n_nodes],
        nb: Vec::with_capacity(64),
        buf: Vec::new(),
        cols: Default::default(),
        vals: Default::default(),
        off_slots: Vec::new(),
    };
    for (la, &v) in layout.owned_nodes.iter().enumerate() {
        let inc = &rc.inc[rc.ptr[la] as usize..rc.ptr[la + 1] as usize];
        sc.gather_neighbours::<N>(layout, rc, la, inc);
        let width = sc.nb.len() * D;
        sc.buf.clear();
        sc.buf.resize(D * width, 0.0);
        let fixed_v: [f64; D] = std::array::from_fn(|i| p.fixed[v * D + i]);
        let mut elim = [0.0f64; D];
        for &e in inc {
            let (cell, a) = (e as usize / N, e as usize % N);
            let nodes = &rc.nodes[cell * N..cell * N + N];
            let (lambda, mu) = rd.lame[rc.material(cell)];
            let (g, vol) = gradients(nodes);
            let cell = CellOfRow {
                nodes,
                a,
                g,
                vol,
                lambda,
                mu,
            };
            add_cell_rows::<D, N>(&rd, &mut sc, &cell, &fixed_v, &mut elim);
        }
        let (lo, hi) = layout.node_range();
        sc.append_rows::<D>(lo, hi, &mut out.diag, &mut out.off);
        let diag0 = sc.slot[v] as usize * D;
        for i in 0..D {
            if fixed_v[i].is_nan() {
                out.elim_rhs[la * D + i] = elim[i];
            } else {
                let a_jj = sc.buf[i * width + diag0 + i];
                out.fixed_rhs.push((la * D + i, a_jj * fixed_v[i]));
            }
        }
        sc.clear_slots();
    }
    out
}

/// [`owned_rows`] for the mesh's dimension (triangles or tetrahedra).
fn rows_of(p: &Problem, layout: &Layout) -> OwnedRows {
    let x = &p.mesh.coords;
    let rc = row_cells(p.mesh, layout, p.material);
    if p.mesh.dim == 2 {
        owned_rows::<2, 3>(p, layout, &rc, |n| {
            let p = |v: u32| [x[v as usize][0], x[v as usize][1]];
            fem::tri_gradients(&[p(n[0]), p(n[1]), p(n[2])])
        })
    } else {
        owned_rows::<3, 4>(p, layout, &rc, |n| {
            let p = |v: u32| x[v as usize];
            fem::tet_gradients(&[p(n[0]), p(n[1]), p(n[2]), p(n[3])])
        })
    }
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

/// Assembles A (MPIAIJ, block size dim, exact preallocation) and f (3.8): every rank its own
/// rows. Phases: the owned rows ([`rows_of`]) handed to PETSc, the right-hand side
/// ([`right_hand_side`]), the held parts ([`held_loads`], [`add_held_dirichlet`]).
pub fn assemble(comm: MPI_Comm, layout: &Layout, p: &Problem) -> petsc::Result<System> {
    let dim = p.mesh.dim;
    let t0 = Instant::now();
    let local_rows = layout.n_owned_nodes() * dim;
    let mut b = Vector::new_mpi(comm, local_rows, dim)?;
    let mut stats = AssemblyStats {
        preallocation_seconds: t0.elapsed().as_secs_f64(),
        ..Default::default()
    };

    let t1 = Instant::now();
    let OwnedRows {
        diag,
        off,
        elim_rhs,
        fixed_rhs,
    } = rows_of(p, layout);
    stats.rows_seconds = t1.elapsed().as_secs_f64();
    let t_petsc = Instant::now();
    let a = Matrix::from_split_csr(comm, dim, diag, off)?;
    stats.petsc_seconds = t_petsc.elapsed().as_secs_f64();
    stats.matrix_seconds = t1.elapsed().as_secs_f64();
    let st = a.stats()?;
    stats.mallocs = st.mallocs;
    stats.nonzeros = st.nonzeros;

    let t2 = Instant::now();
    right_hand_side(p, layout, &mut b, &elim_rhs, &fixed_rhs)?;
    let mut b_held = held_loads(p, layout, &b, &fixed_rhs)?;
    // A case-level decision (held_fixed is non-empty on every rank or on none): collective.
    if !p.held_fixed.is_empty() {
        let h = match b_held.take() {
            Some(h) => h,
            None => {
                let mut h = b.duplicate()?;
                h.write(|v| v.iter_mut().for_each(|x| *x = 0.0))?;
                h
            }
        };
        b_held = Some(add_held_dirichlet(p, layout, h)?);
    }
    stats.load_seconds = t2.elapsed().as_secs_f64();
    Ok(System {
        a,
        b,
        b_held,
        stats,
    })
}

/// f of (3.8) into `b`: the Dirichlet elimination's terms, the loads (summed in rank order:
/// repeatable runs), then the fixed dofs' entries A_jj g_j. Collective.
fn right_hand_side(
    p: &Problem,
    layout: &Layout,
    b: &mut Vector,
    elim_rhs: &[f64],
    fixed_rhs: &[(usize, f64)],
) -> petsc::Result<()> {
    b.write(|bv| bv.copy_from_slice(elim_rhs))?;
    let mut bidx: Vec<PInt> = Vec::new();
    let mut bval: Vec<f64> = Vec::new();
    load_entries(p, layout, false, &mut bidx, &mut bval);
    crate::par::add_in_rank_order(b, &bidx, &bval)?; // deterministic order: repeatable runs
    b.assemble()?;
    b.write(|bv| {
        for &(i, v) in fixed_rhs {
            bv[i] = v;
        }
    })
}

/// The elimination terms of the Dirichlet values held at full value (`ramp = false`) added
/// to `h`, and those values' right-hand side set: the rows assembled again with the same
/// fixed pattern and the ramped values set to 0 (the matrix part of this pass is dropped).
fn add_held_dirichlet(p: &Problem, layout: &Layout, mut h: Vector) -> petsc::Result<Vector> {
    let only_held = Problem {
        mesh: p.mesh,
        material: p.material,
        fixed: p
            .fixed
            .iter()
            .zip(&p.held_fixed)
            .map(|(&g, &h)| if g.is_nan() || h { g } else { 0.0 })
            .collect(),
        held_fixed: Vec::new(),
        facet_loads: Vec::new(),
        body_force: BodyForce::None,
    };
    let held = rows_of(&only_held, layout);
    h.write(|v| {
        for (x, e) in v.iter_mut().zip(&held.elim_rhs) {
            *x += e;
        }
        for &(i, g) in &held.fixed_rhs {
            v[i] = g;
        }
    })?;
    Ok(h)
}

/// The right-hand side of the facet loads with `ramp = false` alone (zero on fixed dofs), if
/// there are any. Collective.
fn held_loads(
    p: &Problem,
    layout: &Layout,
    like: &Vector,
    fixed_rhs: &[(usize, f64)],
) -> petsc::Result<Option<Vector>> {
    if p.facet_loads.iter().all(|l| l.ramp) {
        return Ok(None);
    }
    let mut h = like.duplicate()?;
    h.write(|x| x.iter_mut().for_each(|v| *v = 0.0))?;
    let (mut idx, mut val) = (Vec::new(), Vec::new());
    load_entries(p, layout, true, &mut idx, &mut val);
    crate::par::add_in_rank_order(&mut h, &idx, &val)?; // deterministic order: repeatable runs
    h.assemble()?;
    h.write(|x| {
        for &(i, _) in fixed_rhs {
            x[i] = 0.0;
        }
    })?;
    Ok(Some(h))
}

/// The load entries (3.8) of this rank: body force on its cells, facet loads on the facets
/// whose cell is its own; with `held_only` only the facet loads that do not ramp.
fn load_entries(
    p: &Problem,
    layout: &Layout,
    held_only: bool,
    bidx: &mut Vec<PInt>,
    bval: &mut Vec<f64>,
) {
    let mesh = p.mesh;
    let dim = mesh.dim;
    let nd = (dim + 1) * dim;
    let mut fe = [0.0f64; 12];
    let mut idx = [0 as PInt; 12];
    // Loads: body force on own cells, facet loads on facets whose cell is ours.
    let mut xs: Vec<[f64; 3]> = Vec::with_capacity(4);
    let body = if held_only {
        &BodyForce::None
    } else {
        &p.body_force
    };
    match body {
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
    for load in p.facet_loads.iter().filter(|l| !held_only || !l.ramp) {
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
