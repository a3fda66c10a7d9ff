//! The XDMF 3 text that describes the datasets of `solution.h5` (written by rank 0 only).
//!
//! Layout: one `Domain` holding the Uniform Grid "mesh" and, when contact nodes exist, a
//! second Uniform Grid "contact" (Polyvertex cells, one per contact node). ParaView's
//! XDMF readers turn two grids of one Domain into a multiblock data set with two blocks.
//!
//! A load history ([`xdmf_series_text`]): the same two grids, each a temporal collection
//! (`GridType="Collection" CollectionType="Temporal"`) of one Uniform grid per step with its
//! `<Time Value>`; ParaView's time slider walks the steps.

use std::fmt::Write;

/// Name and number of components of one field, as seen by the XDMF description.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldMeta {
    pub name: String,
    pub ncomp: usize,
}

/// Global sizes and fields of everything written to the HDF5 file.
#[derive(Debug, Clone, PartialEq)]
pub struct Meta {
    pub dim: usize,
    pub n_nodes: usize,
    pub n_cells: usize,
    pub nodal: Vec<FieldMeta>,
    pub cellwise: Vec<FieldMeta>,
    /// Number of contact nodes (0: no contact grid) and their fields.
    pub n_contact: usize,
    pub contact: Vec<FieldMeta>,
}

impl Meta {
    /// One line that must be identical on every rank (checked before any collective HDF5 call).
    pub fn signature(&self) -> String {
        let list = |v: &[FieldMeta]| {
            v.iter()
                .map(|f| format!("{}:{}", f.name, f.ncomp))
                .collect::<Vec<_>>()
                .join(",")
        };
        format!(
            "dim={} nodes={} cells={} nodal=[{}] cell=[{}] contact={} contact_fields=[{}]",
            self.dim,
            self.n_nodes,
            self.n_cells,
            list(&self.nodal),
            list(&self.cellwise),
            self.n_contact,
            list(&self.contact)
        )
    }
}

/// XDMF attribute type for a field with `ncomp` components per entity.
pub fn attribute_type(ncomp: usize) -> &'static str {
    match ncomp {
        1 => "Scalar",
        3 => "Vector",
        9 => "Tensor",
        _ => "Matrix",
    }
}

/// Shape text of a DataItem with `rows` entities of `ncomp` components (1 → one dimension).
fn dims(rows: usize, ncomp: usize) -> String {
    if ncomp == 1 {
        format!("{rows}")
    } else {
        format!("{rows} {ncomp}")
    }
}

fn data_item(out: &mut String, h5: &str, path: &str, dims: &str, float: bool) {
    let ty = if float { "Float" } else { "Int" };
    let _ = writeln!(
        out,
        "        <DataItem Dimensions=\"{dims}\" DataType=\"{ty}\" Precision=\"8\" \
         Format=\"HDF\">{h5}:{path}</DataItem>"
    );
}

#[allow(clippy::too_many_arguments)]
fn attribute(
    out: &mut String,
    h5: &str,
    name: &str,
    ncomp: usize,
    center: &str,
    path: &str,
    rows: usize,
    float: bool,
) {
    let _ = writeln!(
        out,
        "      <Attribute Name=\"{}\" AttributeType=\"{}\" Center=\"{center}\">",
        escape(name),
        attribute_type(ncomp)
    );
    data_item(out, h5, path, &dims(rows, ncomp), float);
    out.push_str("      </Attribute>\n");
}

fn geometry(out: &mut String, h5: &str, path: &str, rows: usize) {
    out.push_str("      <Geometry GeometryType=\"XYZ\">\n");
    data_item(out, h5, path, &dims(rows, 3), true);
    out.push_str("      </Geometry>\n");
}

/// XML-escape a name (field names are restricted to safe characters already; this is a guard).
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The whole XDMF document; `h5` is the HDF5 file name relative to the XDMF file.
pub fn xdmf_text(meta: &Meta, h5: &str) -> String {
    let mut out = String::with_capacity(4096);
    head(&mut out);
    mesh_grid(&mut out, meta, h5, "", None);
    if meta.n_contact > 0 {
        contact_grid(&mut out, meta, h5, "/contact", None);
    }
    tail(&mut out);
    out
}

/// The XDMF document of a load history: the grids "mesh" and (with contact nodes) "contact"
/// as temporal collections, step s (1, 2, …) at time `times[s − 1]` with its fields under
/// `/step_s/`; every step points at the one `/mesh` and `/contact` geometry.
pub fn xdmf_series_text(meta: &Meta, h5: &str, times: &[f64]) -> String {
    let mut out = String::with_capacity(4096 * (times.len() + 1));
    head(&mut out);
    let mut grids = vec!["mesh"];
    if meta.n_contact > 0 {
        grids.push("contact");
    }
    for name in grids {
        let _ = writeln!(
            out,
            "    <Grid Name=\"{name}\" GridType=\"Collection\" CollectionType=\"Temporal\">"
        );
        for (i, &t) in times.iter().enumerate() {
            let mut g = String::with_capacity(4096);
            let step = format!("/step_{}", i + 1);
            if name == "mesh" {
                mesh_grid(&mut g, meta, h5, &step, Some(t));
            } else {
                contact_grid(&mut g, meta, h5, &format!("{step}/contact"), Some(t));
            }
            for line in g.lines() {
                let _ = writeln!(out, "  {line}");
            }
        }
        out.push_str("    </Grid>\n");
    }
    tail(&mut out);
    out
}

fn head(out: &mut String) {
    out.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    out.push_str("<Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n");
    out.push_str("  <Domain>\n");
}

fn tail(out: &mut String) {
    out.push_str("  </Domain>\n");
    out.push_str("</Xdmf>\n");
}

/// `<Time Value>` of a step (the shortest text that reads back as the same number).
fn time(out: &mut String, t: Option<f64>) {
    if let Some(t) = t {
        let _ = writeln!(out, "      <Time Value=\"{t:?}\"/>");
    }
}

/// Grid "mesh"; its fields under `{fields}/nodal` and `{fields}/cell`.
fn mesh_grid(out: &mut String, meta: &Meta, h5: &str, fields: &str, t: Option<f64>) {
    let (topo, npe) = if meta.dim == 3 {
        ("Tetrahedron", 4)
    } else {
        ("Triangle", 3)
    };
    out.push_str("    <Grid Name=\"mesh\" GridType=\"Uniform\">\n");
    time(out, t);
    let _ = writeln!(
        out,
        "      <Topology TopologyType=\"{topo}\" NumberOfElements=\"{}\" NodesPerElement=\"{npe}\">",
        meta.n_cells
    );
    data_item(out, h5, "/mesh/topology", &dims(meta.n_cells, npe), false);
    out.push_str("      </Topology>\n");
    geometry(out, h5, "/mesh/geometry", meta.n_nodes);
    attribute(
        out,
        h5,
        "node_id",
        1,
        "Node",
        "/mesh/node_id",
        meta.n_nodes,
        false,
    );
    attribute(
        out,
        h5,
        "cell_id",
        1,
        "Cell",
        "/mesh/cell_id",
        meta.n_cells,
        false,
    );
    for f in &meta.nodal {
        let path = format!("{fields}/nodal/{}", f.name);
        attribute(out, h5, &f.name, f.ncomp, "Node", &path, meta.n_nodes, true);
    }
    for f in &meta.cellwise {
        let path = format!("{fields}/cell/{}", f.name);
        attribute(out, h5, &f.name, f.ncomp, "Cell", &path, meta.n_cells, true);
    }
    out.push_str("    </Grid>\n");
}

/// Grid "contact": one Polyvertex cell per contact node; its fields under `fields`.
fn contact_grid(out: &mut String, meta: &Meta, h5: &str, fields: &str, t: Option<f64>) {
    let k = meta.n_contact;
    out.push_str("    <Grid Name=\"contact\" GridType=\"Uniform\">\n");
    time(out, t);
    let _ = writeln!(
        out,
        "      <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"{k}\" NodesPerElement=\"1\">"
    );
    // K × 1 connectivity 0, 1, …, K−1 (Polyvertex wants an explicit second dimension)
    data_item(out, h5, "/contact/topology", &format!("{k} 1"), false);
    out.push_str("      </Topology>\n");
    geometry(out, h5, "/contact/geometry", k);
    attribute(out, h5, "node_id", 1, "Node", "/contact/node_id", k, false);
    for f in &meta.contact {
        let path = format!("{fields}/{}", f.name);
        attribute(out, h5, &f.name, f.ncomp, "Node", &path, k, true);
    }
    out.push_str("    </Grid>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn meta(n_contact: usize) -> Meta {
        Meta {
            dim: 2,
            n_nodes: 10,
            n_cells: 7,
            nodal: vec![FieldMeta {
                name: "displacement".into(),
                ncomp: 3,
            }],
            cellwise: vec![
                FieldMeta {
                    name: "stress".into(),
                    ncomp: 9,
                },
                FieldMeta {
                    name: "von_mises".into(),
                    ncomp: 1,
                },
                FieldMeta {
                    name: "strain2".into(),
                    ncomp: 4,
                },
            ],
            n_contact,
            contact: vec![FieldMeta {
                name: "pressure".into(),
                ncomp: 1,
            }],
        }
    }

    #[test]
    fn attribute_types() {
        assert_eq!(attribute_type(1), "Scalar");
        assert_eq!(attribute_type(3), "Vector");
        assert_eq!(attribute_type(9), "Tensor");
        assert_eq!(attribute_type(2), "Matrix");
        assert_eq!(attribute_type(6), "Matrix");
    }

    #[test]
    fn mesh_grid_text() {
        let t = xdmf_text(&meta(0), "solution.h5");
        assert!(t.contains("TopologyType=\"Triangle\" NumberOfElements=\"7\""));
        assert!(t.contains("Dimensions=\"7 3\" DataType=\"Int\""));
        assert!(t.contains(">solution.h5:/mesh/topology<"));
        assert!(t.contains("Dimensions=\"10 3\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">solution.h5:/mesh/geometry<"));
        assert!(t.contains("Name=\"displacement\" AttributeType=\"Vector\" Center=\"Node\""));
        assert!(t.contains("Name=\"stress\" AttributeType=\"Tensor\" Center=\"Cell\""));
        assert!(t.contains("Dimensions=\"7 9\""));
        assert!(t.contains("Name=\"von_mises\" AttributeType=\"Scalar\""));
        assert!(t.contains("Dimensions=\"7\" DataType=\"Float\""));
        assert!(t.contains("Name=\"strain2\" AttributeType=\"Matrix\""));
        assert!(t.contains("Dimensions=\"7 4\""));
        assert!(!t.contains("contact"));
        assert_eq!(t.matches("<Grid ").count(), 1);
        assert_eq!(
            t.matches("<Attribute ").count(),
            t.matches("</Attribute>").count()
        );
    }

    #[test]
    fn contact_grid_text() {
        let mut m = meta(4);
        m.dim = 3;
        let t = xdmf_text(&m, "solution.h5");
        assert!(t.contains("TopologyType=\"Tetrahedron\""));
        assert!(t.contains("Dimensions=\"7 4\" DataType=\"Int\""));
        assert_eq!(t.matches("<Grid ").count(), 2);
        assert!(t.contains("<Grid Name=\"contact\""));
        assert!(
            t.contains("TopologyType=\"Polyvertex\" NumberOfElements=\"4\" NodesPerElement=\"1\"")
        );
        assert!(t.contains("Dimensions=\"4 1\" DataType=\"Int\" Precision=\"8\" Format=\"HDF\">solution.h5:/contact/topology<"));
        assert!(t.contains(">solution.h5:/contact/geometry<"));
        assert!(t.contains(">solution.h5:/contact/pressure<"));
        // the contact grid comes after the mesh grid and both sit in the one Domain
        let mesh = t.find("Name=\"mesh\"").unwrap();
        let contact = t.find("Name=\"contact\"").unwrap();
        assert!(mesh < contact && contact < t.find("</Domain>").unwrap());
    }

    #[test]
    fn series_text() {
        let t = xdmf_series_text(&meta(4), "solution.h5", &[0.25, 0.5, 1.0]);
        assert_eq!(
            t.matches("GridType=\"Collection\" CollectionType=\"Temporal\"")
                .count(),
            2
        );
        assert_eq!(
            t.matches("<Grid Name=\"mesh\" GridType=\"Uniform\"")
                .count(),
            3
        );
        assert_eq!(
            t.matches("<Grid Name=\"contact\" GridType=\"Uniform\"")
                .count(),
            3
        );
        for (s, v) in [(1, "0.25"), (2, "0.5"), (3, "1.0")] {
            assert_eq!(t.matches(&format!("<Time Value=\"{v}\"/>")).count(), 2);
            assert!(t.contains(&format!(">solution.h5:/step_{s}/nodal/displacement<")));
            assert!(t.contains(&format!(">solution.h5:/step_{s}/cell/stress<")));
            assert!(t.contains(&format!(">solution.h5:/step_{s}/contact/pressure<")));
        }
        // the mesh and the contact geometry once in the file, referenced by every step
        assert_eq!(t.matches(">solution.h5:/mesh/geometry<").count(), 3);
        assert_eq!(t.matches(">solution.h5:/contact/geometry<").count(), 3);
        assert!(!t.contains(">solution.h5:/nodal/"));
        assert_eq!(t.matches("<Grid ").count(), t.matches("</Grid>").count());
        // without contact nodes one collection
        let t = xdmf_series_text(&meta(0), "solution.h5", &[1.0]);
        assert_eq!(t.matches("CollectionType=\"Temporal\"").count(), 1);
        assert!(!t.contains("contact"));
    }

    #[test]
    fn signature_differs_on_field_change() {
        let a = meta(0);
        let mut b = meta(0);
        b.nodal[0].ncomp = 2;
        assert_ne!(a.signature(), b.signature());
        assert_eq!(a.signature(), meta(0).signature());
    }
}
