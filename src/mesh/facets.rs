//! Checks of a facet group that carries a load or the contact condition: every facet must be
//! a proper boundary facet. A degenerate facet (zero length or area) gives wrong nodal weights
//! (contact pressures, lumped loads); an interior facet has a cell on both sides, so its
//! outward normal, and with it the direction of a pressure, is arbitrary; a facet that is not
//! a side of any cell silently carries nothing.

use std::collections::HashMap;
use std::path::Path;

use super::{norm2, sub, Mesh};
use crate::error::InputError;

/// Relative size below which a facet counts as degenerate: length ≤ `DEGENERATE` × mesh
/// extent (2D), area ≤ `DEGENERATE` × (longest edge)² (3D).
const DEGENERATE: f64 = 1e-12;

/// Sorted node indices of a facet (2 or 3 nodes), padded to 3.
fn key(nodes: &[usize]) -> [usize; 3] {
    let mut k = [usize::MAX; 3];
    k[..nodes.len()].copy_from_slice(nodes);
    k.sort_unstable();
    k
}

impl Mesh {
    /// Length (2D) or area (3D) of facet `f`, and its longest edge.
    pub fn facet_measure(&self, f: usize) -> (f64, f64) {
        let p: Vec<[f64; 3]> = self.facet(f).iter().map(|&v| self.coords[v]).collect();
        let mut h2: f64 = 0.0;
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                h2 = h2.max(norm2(sub(p[j], p[i])));
            }
        }
        let m = if p.len() == 2 {
            h2.sqrt()
        } else {
            let (a, b) = (sub(p[1], p[0]), sub(p[2], p[0]));
            let c = [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ];
            0.5 * norm2(c).sqrt()
        };
        (m, h2.sqrt())
    }

    /// Checks that the facets of the group(s) `name` of dimension `dim − 1` can carry a load
    /// or the contact condition: none is degenerate (zero length in 2D, zero area in 3D,
    /// relative to the mesh size) and each is a side of exactly one body cell (it lies on the
    /// boundary). The error names the mesh `file`, the group and, of its faulty facets (this
    /// rank's on a distributed mesh), the one of smallest gmsh tag; `used_as` says where the
    /// case uses the group (e.g. "contact.group").
    pub fn check_boundary_group(
        &self,
        file: &Path,
        name: &str,
        used_as: &str,
    ) -> Result<(), InputError> {
        match self.boundary_group_fault(name) {
            None => Ok(()),
            Some((tag, msg)) => Err(self.facet_error(file, name, used_as, tag, &msg)),
        }
    }

    /// The faulty facet of smallest gmsh tag of the group(s) `name` ([`Mesh::check_boundary_group`];
    /// on a distributed mesh among this rank's facets) with what is wrong with it. Local.
    pub fn boundary_group_fault(&self, name: &str) -> Option<(u64, String)> {
        let facets: Vec<usize> = self
            .groups
            .iter()
            .filter(|g| g.name == name && g.dim + 1 == self.dim)
            .flat_map(|g| g.elements.iter().copied())
            .filter(|&f| self.global.as_ref().is_none_or(|g| g.facet_checked[f]))
            .collect();
        if facets.is_empty() {
            return None;
        }
        let sides = self.side_counts(&facets);
        facets
            .iter()
            .filter_map(|&f| {
                let why = self
                    .degenerate_facet(f)
                    .or_else(|| off_boundary(sides[&key(self.facet(f))]))?;
                Some((self.facet_tags[f], why))
            })
            .min_by_key(|(tag, _)| *tag)
    }

    /// The input error of facet `tag` of group `name` (used by `used_as`): `msg` is what is
    /// wrong with it.
    pub fn facet_error(
        &self,
        file: &Path,
        name: &str,
        used_as: &str,
        tag: u64,
        msg: &str,
    ) -> InputError {
        let what = if self.dim == 2 {
            "line element"
        } else {
            "triangle"
        };
        InputError::new(
            file,
            format!("{what} {tag} of group \"{name}\" (used by {used_as}) {msg}"),
        )
    }

    /// What makes facet `f` degenerate (zero length in 2D, zero area in 3D, relative to the
    /// mesh size), if it is.
    fn degenerate_facet(&self, f: usize) -> Option<String> {
        let extent = self.extent();
        let (m, h) = self.facet_measure(f);
        let degenerate = if self.dim == 2 {
            m <= DEGENERATE * extent
        } else {
            m <= DEGENERATE * h * h
        };
        if !(degenerate || m.is_nan()) {
            return None;
        }
        let (kind, size) = if self.dim == 2 {
            ("length", format!("mesh size {extent:e}"))
        } else {
            ("area", format!("longest edge {h:e}"))
        };
        Some(format!(
            "has zero {kind} ({m:e}, {size}): degenerate boundary facet"
        ))
    }

    /// Number of body cells that have each of `facets` as a side (by [`key`]).
    fn side_counts(&self, facets: &[usize]) -> HashMap<[usize; 3], u32> {
        let mut sides: HashMap<[usize; 3], u32> =
            facets.iter().map(|&f| (key(self.facet(f)), 0)).collect();
        let nc = self.nodes_per_cell();
        let mut face = [0usize; 3];
        for c in 0..self.n_cells() {
            let cell = self.cell(c);
            for skip in 0..nc {
                let mut k = 0;
                for (i, &v) in cell.iter().enumerate() {
                    if i != skip {
                        face[k] = v;
                        k += 1;
                    }
                }
                if let Some(n) = sides.get_mut(&key(&face[..nc - 1])) {
                    *n += 1;
                }
            }
        }
        sides
    }
}

/// What is wrong with a facet that is a side of `n` body cells (not exactly one), if anything.
fn off_boundary(n: u32) -> Option<String> {
    match n {
        1 => None,
        0 => Some(
            "is not a side of any body cell: a load or contact group must consist of sides of \
             the body's cells on its boundary"
                .into(),
        ),
        n => Some(format!(
            "is an interior facet (a side of {n} body cells): a load or contact group must lie \
             on the boundary of the body"
        )),
    }
}
