//! Checks of the case against the mesh read.

use super::body::{BodyForceSpec, Load};
use super::file::Case;
use super::shape::ObstacleSpec;
use super::tree::{join_index, join_key};
use crate::error::InputError;
use crate::expr::{quoted, VARIABLES};
use crate::mesh::Mesh;

impl Case {
    /// Checks the case against the mesh: model vs dimension, vector lengths = `dim`,
    /// group names exist, Neumann/contact groups are boundary groups (dimension `dim - 1`),
    /// material groups are volume groups (dimension `dim`).
    /// `groups` lists the mesh's physical groups as (name, dimension).
    pub fn check_against_mesh(
        &self,
        dim: usize,
        groups: &[(String, usize)],
    ) -> Result<(), InputError> {
        self.model(dim)?;
        for m in &self.materials {
            if let Some(g) = &m.group {
                self.check_group(&join_key(&m.key, "group"), g, groups, Some(dim))?;
            }
        }
        let len = |key: String, n: usize| -> Result<(), InputError> {
            if n == dim {
                Ok(())
            } else {
                Err(self.err_at(
                    &key,
                    format!("has {n} components, but the mesh is {dim}D and needs {dim}"),
                ))
            }
        };
        for (i, d) in self.dirichlet.iter().enumerate() {
            let k = join_index("dirichlet", i);
            self.check_group(&join_key(&k, "group"), &d.group, groups, None)?;
            len(join_key(&k, "value"), d.value.len())?;
        }
        for (i, n) in self.neumann.iter().enumerate() {
            let k = join_index("neumann", i);
            self.check_group(&join_key(&k, "group"), &n.group, groups, Some(dim - 1))?;
            if let Load::Traction(t) = &n.load {
                len(join_key(&k, "traction"), t.len())?;
            }
        }
        if let Some(b) = &self.body_force {
            len(b.key().into(), b.len())?;
            if let BodyForceSpec::Expr(es) = b {
                for (i, e) in es.iter().enumerate() {
                    let bad = e.unknown_variables(&VARIABLES[..dim]);
                    if !bad.is_empty() {
                        return Err(self.err_at(
                            &join_index("body_force.expr", i),
                            format!(
                                "\"{}\": unknown variable{} {}; the mesh is {dim}D: the \
                                 variables are {}",
                                e.text(),
                                if bad.len() > 1 { "s" } else { "" },
                                quoted(&bad),
                                VARIABLES[..dim].join(", ")
                            ),
                        ));
                    }
                }
            }
        }
        for c in &self.contacts {
            self.check_group(&join_key(&c.key, "group"), &c.group, groups, Some(dim - 1))?;
            if let ObstacleSpec::Body { group } = &c.obstacle {
                // a volume group named here said "has no facets", which is not the fault
                let key = join_key(&c.key, "obstacle.group");
                self.check_group(&key, group, groups, Some(dim - 1))?;
            }
            self.check_shape(&join_key(&c.key, "obstacle"), &c.obstacle, dim)?;
            for m in [&c.motion, &c.force].into_iter().flatten() {
                if m.table.is_empty() {
                    len(m.key.clone(), m.value.len())?;
                }
                for (i, (_, row)) in m.table.iter().enumerate() {
                    if row.len() != dim {
                        return Err(self.err_at(
                            &join_index(&m.key, i),
                            format!(
                                "a row of {} numbers, but the mesh is {dim}D: each row is \
                                 [load factor, {}] (1 + {dim} numbers)",
                                1 + row.len(),
                                ["x", "y", "z"][..dim].join(", ")
                            ),
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// The groups that hold Dirichlet data, a load or a contact pair (`dirichlet`, `neumann`,
    /// `contact`, a body pair's `obstacle.group`, in this order): each name labels groups of
    /// one dimension only (else which is meant is ambiguous), and has elements in the whole
    /// mesh (a boundary group facets); a name the mesh does not have is left to the check of
    /// its key (a body pair's group: the mortar set-up). `groups` lists the mesh's physical groups as (name,
    /// dimension, number of elements in the whole mesh). Call after
    /// [`Case::check_against_mesh`].
    pub fn check_groups_used(
        &self,
        dim: usize,
        groups: &[(String, usize, usize)],
    ) -> Result<(), InputError> {
        // (key, group, a boundary group: facets needed)
        let mut used: Vec<(String, &str, bool)> = Vec::new();
        for (i, d) in self.dirichlet.iter().enumerate() {
            used.push((
                join_key(&join_index("dirichlet", i), "group"),
                &d.group,
                false,
            ));
        }
        for (i, n) in self.neumann.iter().enumerate() {
            used.push((join_key(&join_index("neumann", i), "group"), &n.group, true));
        }
        for c in &self.contacts {
            used.push((join_key(&c.key, "group"), &c.group, true));
            if let ObstacleSpec::Body { group } = &c.obstacle {
                used.push((join_key(&c.key, "obstacle.group"), group, true));
            }
        }
        const WORDS: [&str; 4] = ["point", "curve", "surface", "volume"];
        for (key, name, boundary) in used {
            let mut dims: Vec<usize> = (groups.iter())
                .filter(|(g, _, _)| g == name)
                .map(|(_, d, _)| *d)
                .collect();
            dims.dedup();
            if dims.is_empty() {
                continue; // not in the mesh: the key's own check names it
            }
            if dims.len() > 1 {
                let list: Vec<String> = (dims.iter())
                    .map(|&d| format!("a {} group ({d}D)", WORDS[d.min(3)]))
                    .collect();
                return Err(self.err_at(
                    &key,
                    format!(
                        "physical group name \"{name}\" labels {} of the mesh: which is meant \
                         is ambiguous; give the groups different names",
                        list.join(" and ")
                    ),
                ));
            }
            let n: usize = (groups.iter())
                .filter(|(g, d, _)| g == name && (!boundary || *d + 1 == dim))
                .map(|(_, _, n)| n)
                .sum();
            if n == 0 {
                return Err(self.err_at(
                    &key,
                    format!(
                        "physical group \"{name}\" has no {}: the mesh names it, but no \
                         element belongs to it",
                        if boundary { "facets" } else { "elements" }
                    ),
                ));
            }
        }
        Ok(())
    }

    /// A 3D-only shape needs a 3D mesh; every vector of the shape needs `dim` components.
    fn check_shape(&self, key: &str, shape: &ObstacleSpec, dim: usize) -> Result<(), InputError> {
        if let (2, Some(instead)) = (dim, shape.in_2d_use()) {
            return Err(self.err_at(
                &join_key(key, "type"),
                format!(
                    "\"{}\" is a 3D obstacle, but the mesh is 2D; in 2D use {instead}",
                    shape.type_name()
                ),
            ));
        }
        if let ObstacleSpec::Height { expr } = shape {
            expr.check_variables(dim).map_err(|m| {
                self.err_at(&join_key(key, "expr"), format!("\"{}\": {m}", expr.text()))
            })?;
        }
        for (name, n) in shape.vectors() {
            if n != dim {
                return Err(self.err_at(
                    &join_key(key, name),
                    format!("has {n} components, but the mesh is {dim}D and needs {dim}"),
                ));
            }
        }
        Ok(())
    }

    /// Checks `[[mesh.project]]` against the mesh read (before it is refined): every group
    /// exists and has facets (dimension `dim - 1`) or, in 3D, edges; the shape's vectors have
    /// `dim` components. `groups` lists the mesh's physical groups as (name, dimension).
    pub fn check_projections(
        &self,
        dim: usize,
        groups: &[(String, usize)],
    ) -> Result<(), InputError> {
        for (i, p) in self.mesh.project.iter().enumerate() {
            let k = join_index("mesh.project", i);
            let gk = join_key(&k, "group");
            self.check_group(&gk, &p.group, groups, None)?;
            if !groups
                .iter()
                .any(|(g, d)| g == &p.group && *d >= 1 && *d < dim)
            {
                return Err(self.err_at(
                    &gk,
                    format!(
                        "physical group \"{}\" has no facets{}: only new nodes on the \
                         boundary can be projected",
                        p.group,
                        if dim == 3 { " or edges" } else { "" }
                    ),
                ));
            }
            self.check_shape(&join_key(&k, "shape"), &p.shape, dim)?;
        }
        Ok(())
    }

    /// The first group that carries a load or the contact condition (in the case's order:
    /// `neumann`, then `contact`) with a faulty facet — degenerate, or not on the boundary of
    /// the body ([`Mesh::boundary_group_fault`], among this rank's facets on a distributed
    /// mesh): its position in that order, the facet's gmsh tag and the error. Call after
    /// [`Case::check_against_mesh`]. Local.
    pub fn facet_group_fault(&self, mesh: &Mesh) -> Option<(usize, u64, InputError)> {
        let mut used: Vec<(String, &str)> = self
            .neumann
            .iter()
            .enumerate()
            .map(|(i, n)| {
                (
                    join_key(&join_index("neumann", i), "group"),
                    n.group.as_str(),
                )
            })
            .collect();
        for c in &self.contacts {
            used.push((join_key(&c.key, "group"), c.group.as_str()));
        }
        used.iter().enumerate().find_map(|(i, (key, group))| {
            let (tag, msg) = mesh.boundary_group_fault(group)?;
            let at = match self.line_of(key) {
                Some(l) => format!("{key} at {}:{l}", self.file.display()),
                None => format!("{key} of {}", self.file.display()),
            };
            let e = mesh.facet_error(&self.mesh.file, group, &at, tag, &msg);
            Some((i, tag, e))
        })
    }

    fn check_group(
        &self,
        key: &str,
        name: &str,
        groups: &[(String, usize)],
        need_dim: Option<usize>,
    ) -> Result<(), InputError> {
        let dims: Vec<usize> = groups
            .iter()
            .filter(|(g, _)| g == name)
            .map(|(_, d)| *d)
            .collect();
        if dims.is_empty() {
            let avail = if groups.is_empty() {
                "the mesh has no named physical groups".to_string()
            } else {
                let list: Vec<String> = groups
                    .iter()
                    .map(|(g, d)| format!("\"{g}\" (dim {d})"))
                    .collect();
                format!("the mesh has: {}", list.join(", "))
            };
            return Err(self.err_at(
                key,
                format!("physical group \"{name}\" is not in the mesh; {avail}"),
            ));
        }
        if let Some(nd) = need_dim {
            if !dims.contains(&nd) {
                let have: Vec<String> = dims.iter().map(|d| d.to_string()).collect();
                return Err(self.err_at(
                    key,
                    format!(
                        "physical group \"{name}\" has dimension {}, but a {} group \
                         (dimension {nd}) is needed here",
                        have.join("/"),
                        if key.starts_with("material") {
                            "volume"
                        } else {
                            "boundary"
                        }
                    ),
                ));
            }
        }
        Ok(())
    }
}
