//! A deformable body as the target of a contact pair (`type = "body"`): not a shape but the
//! rows that dual mortar gives the pair's (slave) nodes against the other body's (master)
//! boundary group, filled in once from the mesh (src/mortar/). docs/bodies.md.

use std::collections::HashMap;

/// The mortar row of one slave node, in the terms of a rigid obstacle's projection: the
/// condition is n·(u_k − Σ_j m_kj u_j) + g ≥ 0 (node k against the master nodes j).
#[derive(Debug, Clone, PartialEq)]
pub struct SlaveRow {
    /// The unit normal pointing into the slave body (minus its outward nodal normal).
    pub normal: [f64; 3],
    /// The weighted gap over the node's weight, g̃_k / D_kk (> 0 apart, < 0 penetrating).
    pub gap: f64,
    /// D_kk = ∫ φ_k over the part of the slave facets around k that the master covers.
    pub weight: f64,
    /// (global master node j, m_kj = M_kj / D_kk), sorted by j; Σ_j m_kj = 1.
    pub masters: Vec<(usize, f64)>,
}

/// The master side of a body pair: its boundary group and, once set up, the rows of this
/// rank's slave nodes (by mesh node index).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BodyTarget {
    /// The master boundary group.
    pub group: String,
    pub dim: usize,
    /// This rank's slave nodes that the master covers, by mesh node index.
    pub rows: HashMap<usize, SlaveRow>,
}
