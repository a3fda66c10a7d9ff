//! Post-processing: the fields the case asks for (and no others) on this rank's nodes and
//! cells, ready for the output layer.

use crate::case::{OutputField, OutputSection};
use crate::fem::{self, Material};
use crate::mesh::Mesh;
use crate::output::{FieldBuf, SolutionFields};
use crate::partition::Layout;
use crate::petsc::{self, PInt, Vector};

/// The values of a nodal vector (dim per node) at every node of this rank's cells, owned or
/// not: (sorted mesh node indices, dim values each). Collective.
pub fn local_cell_values(
    mesh: &Mesh,
    layout: &Layout,
    u: &Vector,
) -> petsc::Result<(Vec<usize>, Vec<f64>)> {
    let dim = mesh.dim;
    let mut nodes: Vec<usize> = layout
        .local_cells
        .iter()
        .flat_map(|&c| mesh.cell(c).iter().copied())
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let idx: Vec<PInt> = nodes
        .iter()
        .flat_map(|&v| (0..dim).map(move |k| (layout.node_global[v] * dim + k) as PInt))
        .collect();
    let vals = u.gather(&idx)?;
    Ok((nodes, vals))
}

/// What the cell field `rank` holds (the `codes` attribute of /cell/rank).
pub const RANK_CODES: &str = "the MPI rank (0, 1, ...) that held the cell in the solve";

/// Stresses, von Mises values and the owning rank of the local cells — only what `fields`
/// asks for, in the order stress, von_mises, von_mises_thesis, rank. Collective.
pub fn cell_fields(
    mesh: &Mesh,
    layout: &Layout,
    material: &Material,
    u: &Vector,
    out: &OutputSection,
) -> petsc::Result<Vec<FieldBuf>> {
    let want_stress = out.wants(OutputField::Stress);
    let want_vm = out.wants(OutputField::VonMises);
    let want_vmt = out.wants(OutputField::VonMisesThesis);
    let dim = mesh.dim;
    let nlc = layout.local_cells.len();
    let mut fields = Vec::new();
    // Every rank skips alike: output.fields is the same everywhere (no collective skipped).
    if want_stress || want_vm || want_vmt {
        let (nodes, vals) = local_cell_values(mesh, layout, u)?;
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
            let s = fem::cell_stress(material, &x[..dim + 1], &ue[..(dim + 1) * dim]);
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
    Ok(fields)
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
