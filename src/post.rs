//! Post-processing: the fields the case asks for (and no others) on this rank's nodes and
//! cells, ready for the output layer.

use crate::case::{OutputField, OutputSection};
use crate::fem::{self, Materials};
use crate::mesh::Mesh;
use crate::output::{FieldBuf, SolutionFields};
use crate::par::Ctx;
use crate::partition::Layout;
use crate::petsc::{self, Vector};
use crate::warnings::{self, Place, Warning};

/// The values of a nodal vector (dim per node) at every node of this rank's cells, owned or
/// not: (sorted mesh node indices, dim values each). Collective.
pub fn local_cell_values(
    mesh: &Mesh,
    layout: &Layout,
    u: &Vector,
) -> petsc::Result<(Vec<usize>, Vec<f64>)> {
    crate::partition::values_at_cells(mesh, layout, &layout.local_cells, u)
}

/// What the cell field `rank` holds (the `codes` attribute of /cell/rank).
pub const RANK_CODES: &str = "the MPI rank (0, 1, ...) that held the cell in the solve";

/// The values of u at this rank's cells' nodes ([`local_cell_values`]).
pub type CellValues = (Vec<usize>, Vec<f64>);

/// What the cell field `body` holds (the `codes` attribute of /cell/body).
pub const BODY_CODES: &str = "the body (1, 2, ...): the mesh's separate parts, in the order of \
                              their smallest node tags (as signorini-mpi check lists them)";

/// Stresses (each cell's by its own material), von Mises values, the owning rank and the body
/// of the local cells — only what `fields` asks for, in the order stress, von_mises,
/// von_mises_thesis, rank, body. `(nodes, vals)`: u at the cells' nodes
/// ([`local_cell_values`]); `body_of`: the body of every local node (0, 1, ...). Local.
pub fn cell_fields(
    mesh: &Mesh,
    layout: &Layout,
    material: &Materials,
    (nodes, vals): &CellValues,
    out: &OutputSection,
    body_of: &[u32],
) -> Vec<FieldBuf> {
    let want_stress = out.wants(OutputField::Stress);
    let want_vm = out.wants(OutputField::VonMises);
    let want_vmt = out.wants(OutputField::VonMisesThesis);
    let dim = mesh.dim;
    let nlc = layout.local_cells.len();
    let mut fields = Vec::new();
    // Every rank skips alike: output.fields is the same everywhere (no collective skipped).
    if want_stress || want_vm || want_vmt {
        let mut stress = Vec::with_capacity(if want_stress { nlc * 9 } else { 0 });
        let mut vm = Vec::with_capacity(if want_vm { nlc } else { 0 });
        let mut vmt = Vec::with_capacity(if want_vmt { nlc } else { 0 });
        let mut x = [[0.0; 3]; 4];
        let mut ue = [0.0; 12];
        for &c in &layout.local_cells {
            for (a, &v) in mesh.cell(c).iter().enumerate() {
                x[a] = mesh.coords[v];
                let p = nodes.binary_search(&v).expect("node gathered");
                ue[a * dim..(a + 1) * dim].copy_from_slice(&vals[p * dim..(p + 1) * dim]);
            }
            let m = material.of(c); // the cell's own material
            let s = fem::cell_stress(m, &x[..dim + 1], &ue[..(dim + 1) * dim]);
            if want_stress {
                stress.extend(s.iter().flatten());
            }
            if want_vm {
                vm.push(fem::von_mises(&s));
            }
            if want_vmt {
                vmt.push(fem::von_mises_thesis(&s, dim));
            }
        }
        let wanted = [
            (want_stress, "stress", 9, stress),
            (want_vm, "von_mises", 1, vm),
            (want_vmt, "von_mises_thesis", 1, vmt),
        ];
        for (want, name, ncomp, data) in wanted {
            if want {
                fields.push(FieldBuf::float(name, ncomp, data));
            }
        }
    }
    if out.wants(OutputField::Rank) {
        fields.push(FieldBuf {
            name: "rank",
            ncomp: 1,
            data: vec![layout.rank as f64; nlc],
            codes: Some(RANK_CODES),
        });
    }
    if out.wants(OutputField::Body) {
        let body = |c: usize| body_of[mesh.cell(c)[0]] as f64 + 1.0;
        fields.push(FieldBuf {
            name: "body",
            ncomp: 1,
            data: layout.local_cells.iter().map(|&c| body(c)).collect(),
            codes: Some(BODY_CODES),
        });
    }
    fields
}

/// The largest absolute principal strain (the spectral norm of ε = (∇u + ∇uᵀ)/2, P1:
/// constant per cell; in 2D the in-plane strain) over every rank's cells, the cell's gmsh tag
/// and centroid (dim entries); ties go to the smallest tag. The same on every rank.
/// Collective (one gather of 5 numbers per rank).
pub fn largest_strain(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    (nodes, vals): &CellValues,
) -> (f64, u64, Vec<f64>) {
    let dim = mesh.dim;
    // [value, tag, centroid (3)]
    let mut best = [f64::NEG_INFINITY, 0.0, 0.0, 0.0, 0.0];
    let mut ue = [[0.0; 3]; 4];
    for &c in &layout.local_cells {
        let cell = mesh.cell(c);
        let mut centroid = [0.0; 3];
        for (a, &v) in cell.iter().enumerate() {
            let p = nodes.binary_search(&v).expect("node gathered");
            ue[a][..dim].copy_from_slice(&vals[p * dim..(p + 1) * dim]);
            for k in 0..3 {
                centroid[k] += mesh.coords[v][k] / cell.len() as f64;
            }
        }
        let mut g = [[0.0; 3]; 3];
        if dim == 2 {
            let x = [0, 1, 2].map(|a| [mesh.coords[cell[a]][0], mesh.coords[cell[a]][1]]);
            let (grads, _) = fem::tri_gradients(&x);
            for i in 0..2 {
                for j in 0..2 {
                    g[i][j] = (0..3).map(|a| ue[a][i] * grads[a][j]).sum();
                }
            }
        } else {
            let x = [0, 1, 2, 3].map(|a| mesh.coords[cell[a]]);
            let (grads, _) = fem::tet_gradients(&x);
            for i in 0..3 {
                for j in 0..3 {
                    g[i][j] = (0..4).map(|a| ue[a][i] * grads[a][j]).sum();
                }
            }
        }
        let e = [0, 1, 2].map(|i| [0, 1, 2].map(|j| 0.5 * (g[i][j] + g[j][i])));
        // the spectral norm is at most the Frobenius norm: most cells need no eigenvalues
        let frobenius = e.iter().flatten().map(|x| x * x).sum::<f64>().sqrt();
        if frobenius < best[0] {
            continue;
        }
        let value = spectral_norm_sym(&e);
        let tag = mesh.cell_tags[c] as f64;
        if value > best[0] || (value == best[0] && tag < best[1]) {
            best = [value, tag, centroid[0], centroid[1], centroid[2]];
        }
    }
    let all = ctx.all_gather_varcount(&best);
    let mut top = [f64::NEG_INFINITY, 0.0, 0.0, 0.0, 0.0];
    for r in all.chunks_exact(5) {
        if r[0] > top[0] || (r[0] == top[0] && r[1] < top[1]) {
            top.copy_from_slice(r);
        }
    }
    (top[0].max(0.0), top[1] as u64, top[2..2 + dim].to_vec())
}

/// The largest |eigenvalue| of a symmetric 3×3 matrix (closed form, the trigonometric
/// solution of the characteristic cubic).
fn spectral_norm_sym(a: &[[f64; 3]; 3]) -> f64 {
    let p1 = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
    let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
    let p2 = (0..3).map(|i| (a[i][i] - q).powi(2)).sum::<f64>() + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    if p == 0.0 {
        return q.abs();
    }
    let b = [0, 1, 2].map(|i| [0, 1, 2].map(|j| (a[i][j] - if i == j { q } else { 0.0 }) / p));
    let det = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1])
        - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0])
        + b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
    let phi = (0.5 * det).clamp(-1.0, 1.0).acos() / 3.0;
    let l1 = q + 2.0 * p * phi.cos();
    let l3 = q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos();
    l1.abs().max(l3.abs())
}

/// The [`warnings::LARGE_DEFORMATION`] warning of a solution whose largest principal strain
/// ([`largest_strain`]) exceeds [`warnings::LARGE_STRAIN`]. Collective.
pub fn deformation_warning(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    values: &CellValues,
) -> Option<Warning> {
    let (g, tag, x) = largest_strain(ctx, mesh, layout, values);
    // above the threshold beyond round-off: cases/blocks' uniaxial strain p / E is 0.05 itself
    (g > warnings::LARGE_STRAIN * (1.0 + warnings::STRAIN_RTOL)).then(|| Warning {
        code: warnings::LARGE_DEFORMATION,
        message: format!(
            "the solution is beyond small deformations: its largest principal strain is \
             {g:.4} in cell {tag} (centroid {}), above {} — linear elasticity \
             and the linearised contact condition no longer hold there; are the loads, the \
             obstacle's motion or the units as intended?",
            warnings::coords(&x),
            warnings::LARGE_STRAIN
        ),
        key: None,
        pair: None,
        value: g,
        threshold: warnings::LARGE_STRAIN,
        at: Some(Place {
            node: None,
            cell: Some(tag),
            x,
        }),
        steps: Vec::new(),
    })
}

/// This rank's mesh piece with the displacement (if asked for, padded to 3 components) and
/// the given cell fields.
pub fn solution_fields(
    mesh: &Mesh,
    layout: &Layout,
    u: &Vector,
    cellwise: Vec<FieldBuf>,
    out: &OutputSection,
) -> petsc::Result<SolutionFields> {
    let dim = mesh.dim;
    let mut nodal = Vec::new();
    if out.wants(OutputField::Displacement) {
        let uo = u.to_local_vec()?;
        nodal.push(FieldBuf::float(
            "displacement",
            3,
            uo.chunks_exact(dim)
                .flat_map(|c| (0..3).map(move |k| if k < dim { c[k] } else { 0.0 }))
                .collect(),
        ));
    }
    let (node_offset, _) = layout.node_range();
    Ok(SolutionFields {
        dim,
        n_nodes_global: mesh.n_nodes_global(),
        node_offset,
        coords: layout.owned_nodes.iter().map(|&v| mesh.coords[v]).collect(),
        node_ids: layout
            .owned_nodes
            .iter()
            .map(|&v| mesh.node_tags[v])
            .collect(),
        n_cells_global: mesh.n_cells_global(),
        cell_offset: layout.cell_offsets[layout.rank],
        connectivity: layout
            .local_cells
            .iter()
            .flat_map(|&c| mesh.cell(c).iter().map(|&v| layout.node_global[v]))
            .collect(),
        cell_ids: layout
            .local_cells
            .iter()
            .map(|&c| mesh.cell_tags[c])
            .collect(),
        nodal,
        cellwise,
    })
}

#[cfg(test)]
mod tests {
    use super::spectral_norm_sym;

    #[test]
    fn the_spectral_norm_of_symmetric_matrices() {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
        assert!(close(spectral_norm_sym(&[[0.0; 3]; 3]), 0.0));
        assert!(close(
            spectral_norm_sym(&[[2.0, 0.0, 0.0], [0.0, -3.0, 0.0], [0.0, 0.0, 1.0]]),
            3.0
        ));
        // pure shear in 2D: eigenvalues ±0.1, 0
        assert!(close(
            spectral_norm_sym(&[[0.0, 0.1, 0.0], [0.1, 0.0, 0.0], [0.0, 0.0, 0.0]]),
            0.1
        ));
        // [[2,1,0],[1,2,0],[0,0,5]]: 1, 3, 5; [[1,2,3],[2,4,5],[3,5,6]]: ≈ 11.3448, −0.5157, 0.1709
        assert!(close(
            spectral_norm_sym(&[[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 5.0]]),
            5.0
        ));
        let v = spectral_norm_sym(&[[1.0, 2.0, 3.0], [2.0, 4.0, 5.0], [3.0, 5.0, 6.0]]);
        assert!((v - 11.344814282762082).abs() < 1e-9, "{v}");
    }
}
