//! The discrete contact boundary c_h: for every owned contact node its frame {n, τ}, gap
//! g_h^k (3.3), lumped weight w_k = ∫_Γc φ_k ds and Tresca bound b_k = ∫_Γc g_R φ_k ds (3.18).

use crate::case::{self, vec3, ContactSection, Friction};
use crate::contact::{Frame, Obstacle, Plane, Sphere};
use crate::error::InputError;
use crate::fem;
use crate::mesh::Mesh;
use crate::partition::Layout;
use mpi::traits::*;

/// One owned contact node.
#[derive(Clone, Debug)]
pub struct ContactNode {
    /// Mesh node index.
    pub node: usize,
    /// Gmsh node tag.
    pub tag: u64,
    /// Global index of the node's first dof (dofs row .. row + dim).
    pub row: usize,
    /// Index of the first dof within this rank's owned rows.
    pub local_row: usize,
    pub x: [f64; 3],
    pub frame: Frame,
    /// Initial normal gap g_h^k (3.3), ≥ 0 outside the obstacle.
    pub gap: f64,
    /// w_k = ∫_Γc φ_k ds.
    pub weight: f64,
    /// b_k = ∫_Γc g_R φ_k ds (0 without friction).
    pub bound: f64,
}

/// The owned part of c_h, plus what every rank knows about the whole set.
pub struct ContactSet {
    pub nodes: Vec<ContactNode>,
    /// |c_h| over all ranks.
    pub n_global: usize,
    /// Global numbering of contact nodes for output: this rank's are offset .. offset + len.
    pub offset: usize,
    /// Mesh nodes on the contact boundary (all of them, every rank), incl. ones excluded
    /// because Dirichlet data fix them.
    pub on_contact_boundary: Vec<bool>,
    /// Contact nodes dropped because Dirichlet data fix one of their components (global count).
    pub excluded_dirichlet: usize,
    pub obstacle: Obstacle,
}

/// The obstacle of the case, checked.
pub fn obstacle_of(
    c: &ContactSection,
    dim: usize,
    file: &std::path::Path,
) -> Result<Obstacle, InputError> {
    match &c.obstacle {
        case::Obstacle::Plane { point, normal } => Plane::new(vec3(point), vec3(normal), dim)
            .map(Obstacle::Plane)
            .map_err(|e| e.into_input_error(file, "contact.obstacle")),
        case::Obstacle::Sphere { center, radius } => Sphere::new(vec3(center), *radius, dim)
            .map(Obstacle::Sphere)
            .map_err(|e| e.into_input_error(file, "contact.obstacle")),
    }
}

/// Builds the owned contact nodes. `fixed` holds the Dirichlet value per mesh dof (NaN = free):
/// a node with a prescribed component is left to its Dirichlet data.
pub fn build<C: Communicator>(
    world: &C,
    mesh: &Mesh,
    layout: &Layout,
    contact: &ContactSection,
    fixed: &[f64],
    file: &std::path::Path,
) -> Result<ContactSet, InputError> {
    let dim = mesh.dim;
    let obstacle = obstacle_of(contact, dim, file)?;
    let facets: Vec<usize> = mesh
        .groups
        .iter()
        .filter(|g| g.name == contact.group && g.dim + 1 == dim)
        .flat_map(|g| g.elements.iter().copied())
        .collect();
    let mut weight = vec![0.0f64; mesh.n_nodes()];
    let mut on = vec![false; mesh.n_nodes()];
    let mut xs: Vec<[f64; 3]> = Vec::with_capacity(3);
    for &f in &facets {
        let nodes = mesh.facet(f);
        xs.clear();
        xs.extend(nodes.iter().map(|&v| mesh.coords[v]));
        let (_, m) = fem::facet_normal_measure(&xs);
        for &v in nodes {
            weight[v] += m / dim as f64;
            on[v] = true;
        }
    }
    let g_r = match contact.friction {
        Friction::None => 0.0,
        Friction::Tresca { threshold } => threshold,
    };
    let (lo, _) = layout.node_range();
    let mut nodes = Vec::new();
    let mut excluded = 0usize;
    let mut bad: Option<InputError> = None;
    for (i, &v) in layout.owned_nodes.iter().enumerate() {
        if !on[v] {
            continue;
        }
        if (0..dim).any(|k| !fixed[v * dim + k].is_nan()) {
            excluded += 1;
            continue;
        }
        let x = mesh.coords[v];
        let proj = match obstacle.project(x) {
            Ok(p) => p,
            Err(e) => {
                bad.get_or_insert(
                    InputError::new(
                        file,
                        format!("contact node {} at {:?}: {e}", mesh.node_tags[v], &x[..dim]),
                    )
                    .with_key("contact.obstacle"),
                );
                continue;
            }
        };
        let frame = Frame::new(proj.normal, dim).expect("obstacle normals are unit vectors");
        nodes.push(ContactNode {
            node: v,
            tag: mesh.node_tags[v],
            row: (lo + i) * dim,
            local_row: i * dim,
            x,
            frame,
            gap: proj.gap,
            weight: weight[v],
            bound: g_r * weight[v],
        });
    }
    if let Some(e) = bad {
        return Err(e);
    }
    let counts = {
        let mut all = vec![0u64; world.size() as usize];
        world.all_gather_into(&(nodes.len() as u64), &mut all[..]);
        all
    };
    let mut ex_all = 0u64;
    world.all_reduce_into(
        &(excluded as u64),
        &mut ex_all,
        mpi::collective::SystemOperation::sum(),
    );
    let rank = world.rank() as usize;
    Ok(ContactSet {
        n_global: counts.iter().sum::<u64>() as usize,
        offset: counts[..rank].iter().sum::<u64>() as usize,
        nodes,
        on_contact_boundary: on,
        excluded_dirichlet: ex_all as usize,
        obstacle,
    })
}
