//! The XDMF 3 texts that describe the datasets of `solution.h5` (written by rank 0 only).
//!
//! Two files, one grid each, so that every reader opens them (meshio reads one grid per
//! file; ParaView and VisIt read either):
//!
//! - `solution.xdmf`: the Uniform Grid "mesh" (triangles / tetrahedra, the body's nodal and
//!   cell fields);
//! - `contact.xdmf` (when the run has a contact boundary): the Uniform Grid "contact", the
//!   boundary facets of the contact groups (Polyline cells of 2 nodes in 2D, Triangle cells
//!   in 3D) with the contact fields on their nodes.
//!
//! A load history ([`xdmf_series_text`], [`contact_series_text`]): each file holds one
//! temporal collection (`GridType="Collection" CollectionType="Temporal"`) of one Uniform
//! grid per step with its `<Time Value>`, every step pointing at the same geometry and
//! topology — the layout meshio's `TimeSeriesReader` reads (it takes the points and cells of
//! the first step) and ParaView's time slider walks.
//!
//! Integer fields (codes, [`FieldMeta::codes`]) are written as `DataType="Int"`; what their
//! values mean is in an XML comment at the top of the file (readers skip comments) and in the
//! `codes` attribute of their HDF5 dataset.

use std::fmt::Write;

/// Name and number of components of one field, as seen by the XDMF description.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldMeta {
    pub name: String,
    pub ncomp: usize,
    /// An integer field: what its values mean (`None`: a float field).
    pub codes: Option<String>,
}

/// Global sizes and fields of everything written to the HDF5 file.
#[derive(Debug, Clone, PartialEq)]
pub struct Meta {
    pub dim: usize,
    pub n_nodes: usize,
    pub n_cells: usize,
    pub nodal: Vec<FieldMeta>,
    pub cellwise: Vec<FieldMeta>,
    /// Number of nodes of the contact surface (0: no contact grid) and their fields.
    pub n_contact: usize,
    /// Number of facets of the contact surface (`dim` nodes each).
    pub n_contact_facets: usize,
    pub contact: Vec<FieldMeta>,
}

impl Meta {
    /// One line that must be identical on every rank (checked before any collective HDF5 call).
    pub fn signature(&self) -> String {
        let list = |v: &[FieldMeta]| {
            v.iter()
                .map(|f| {
                    let int = if f.codes.is_some() { ":int" } else { "" };
                    format!("{}:{}{int}", f.name, f.ncomp)
                })
                .collect::<Vec<_>>()
                .join(",")
        };
        format!(
            "dim={} nodes={} cells={} nodal=[{}] cell=[{}] contact={}/{} contact_fields=[{}]",
            self.dim,
            self.n_nodes,
            self.n_cells,
            list(&self.nodal),
            list(&self.cellwise),
            self.n_contact,
            self.n_contact_facets,
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

/// `solution.xdmf` of a single solve: the Uniform grid "mesh" (fields under `/nodal`,
/// `/cell`); `h5` is the HDF5 file name relative to the XDMF file.
pub fn xdmf_text(meta: &Meta, h5: &str) -> String {
    document(meta, h5, Grid::Mesh, None)
}

/// `solution.xdmf` of a load history: the temporal collection "mesh", step s (1, 2, …) at
/// time `times[s − 1]` with its fields under `/step_s/`, every step on the one `/mesh`.
pub fn xdmf_series_text(meta: &Meta, h5: &str, times: &[f64]) -> String {
    document(meta, h5, Grid::Mesh, Some(times))
}

/// `contact.xdmf` of a single solve: the Uniform grid "contact" (the contact surface, fields
/// under `/contact`); `None` without a contact surface.
pub fn contact_xdmf_text(meta: &Meta, h5: &str) -> Option<String> {
    (meta.n_contact > 0).then(|| document(meta, h5, Grid::Contact, None))
}

/// `contact.xdmf` of a load history: the temporal collection "contact", step s with its
/// fields under `/step_s/contact`, every step on the one `/contact` surface.
pub fn contact_series_text(meta: &Meta, h5: &str, times: &[f64]) -> Option<String> {
    (meta.n_contact > 0).then(|| document(meta, h5, Grid::Contact, Some(times)))
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Grid {
    Mesh,
    Contact,
}

impl Grid {
    fn name(self) -> &'static str {
        match self {
            Grid::Mesh => "mesh",
            Grid::Contact => "contact",
        }
    }
}

/// One file: the grid alone (`times` None) or its temporal collection.
fn document(meta: &Meta, h5: &str, which: Grid, times: Option<&[f64]>) -> String {
    let steps = times.map_or(1, <[f64]>::len);
    let mut out = String::with_capacity(4096 * (steps + 1));
    head(&mut out, meta, which);
    let grid = |out: &mut String, fields: &str, t: Option<f64>| match which {
        Grid::Mesh => mesh_grid(out, meta, h5, fields, t),
        Grid::Contact => contact_grid(out, meta, h5, &format!("{fields}/contact"), t),
    };
    match times {
        None => grid(&mut out, "", None),
        Some(times) => {
            let _ = writeln!(
                out,
                "    <Grid Name=\"{}\" GridType=\"Collection\" CollectionType=\"Temporal\">",
                which.name()
            );
            for (i, &t) in times.iter().enumerate() {
                let mut g = String::with_capacity(4096);
                grid(&mut g, &format!("/step_{}", i + 1), Some(t));
                for line in g.lines() {
                    let _ = writeln!(out, "  {line}");
                }
            }
            out.push_str("    </Grid>\n");
        }
    }
    tail(&mut out);
    out
}

/// The XML declaration, a comment with the meaning of the grid's integer fields (if any), the
/// root and the Domain.
fn head(out: &mut String, meta: &Meta, which: Grid) {
    out.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    let fields: Vec<&FieldMeta> = match which {
        Grid::Mesh => meta.nodal.iter().chain(&meta.cellwise).collect(),
        Grid::Contact => meta.contact.iter().collect(),
    };
    let coded: Vec<(&str, &str)> = fields
        .iter()
        .filter_map(|f| f.codes.as_deref().map(|c| (f.name.as_str(), c)))
        .collect();
    if !coded.is_empty() {
        out.push_str("<!--\n  Integer fields (the attribute 'codes' of their HDF5 datasets says the same):\n");
        for (name, codes) in coded {
            // "--" may not appear inside an XML comment
            let text = codes.replace("--", "- -");
            let _ = writeln!(out, "  {}: {text}", name.replace("--", "- -"));
        }
        out.push_str("-->\n");
    }
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

/// The attributes of `fields` (rows of `rows`) under `{at}/NAME`.
fn field_attributes(
    out: &mut String,
    h5: &str,
    fields: &[FieldMeta],
    center: &str,
    at: &str,
    rows: usize,
) {
    for f in fields {
        let path = format!("{at}/{}", f.name);
        let float = f.codes.is_none();
        attribute(out, h5, &f.name, f.ncomp, center, &path, rows, float);
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
    let nodal = format!("{fields}/nodal");
    field_attributes(out, h5, &meta.nodal, "Node", &nodal, meta.n_nodes);
    let cell = format!("{fields}/cell");
    field_attributes(out, h5, &meta.cellwise, "Cell", &cell, meta.n_cells);
    out.push_str("    </Grid>\n");
}

/// Grid "contact": the contact surface's facets (Polyline of 2 nodes in 2D, Triangle in 3D)
/// with its nodes' fields under `fields`.
fn contact_grid(out: &mut String, meta: &Meta, h5: &str, fields: &str, t: Option<f64>) {
    let (k, nf, npe) = (meta.n_contact, meta.n_contact_facets, meta.dim);
    let topo = if meta.dim == 3 {
        "Triangle"
    } else {
        "Polyline"
    };
    out.push_str("    <Grid Name=\"contact\" GridType=\"Uniform\">\n");
    time(out, t);
    let _ = writeln!(
        out,
        "      <Topology TopologyType=\"{topo}\" NumberOfElements=\"{nf}\" NodesPerElement=\"{npe}\">"
    );
    data_item(out, h5, "/contact/topology", &dims(nf, npe), false);
    out.push_str("      </Topology>\n");
    geometry(out, h5, "/contact/geometry", k);
    attribute(out, h5, "node_id", 1, "Node", "/contact/node_id", k, false);
    attribute(
        out,
        h5,
        "facet_id",
        1,
        "Cell",
        "/contact/facet_id",
        nf,
        false,
    );
    field_attributes(out, h5, &meta.contact, "Node", fields, k);
    out.push_str("    </Grid>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fm(name: &str, ncomp: usize, codes: Option<&str>) -> FieldMeta {
        FieldMeta {
            name: name.into(),
            ncomp,
            codes: codes.map(str::to_string),
        }
    }

    fn meta(n_contact: usize) -> Meta {
        Meta {
            dim: 2,
            n_nodes: 10,
            n_cells: 7,
            nodal: vec![fm("displacement", 3, None)],
            cellwise: vec![
                fm("stress", 9, None),
                fm("von_mises", 1, None),
                fm("strain2", 4, None),
            ],
            n_contact,
            n_contact_facets: n_contact.saturating_sub(1),
            contact: vec![
                fm("pressure", 1, None),
                fm("state", 1, Some("1 in contact, 0 open")),
            ],
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
        let t = xdmf_text(&meta(4), "solution.h5");
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
        // the mesh alone, whatever the contact: one Uniform grid, no time, no comment
        assert!(!t.contains("contact"));
        assert!(!t.contains("<Time") && !t.contains("<!--"));
        assert_eq!(t.matches("<Grid ").count(), 1);
        assert!(t.contains("<Grid Name=\"mesh\" GridType=\"Uniform\">"));
        assert_eq!(
            t.matches("<Attribute ").count(),
            t.matches("</Attribute>").count()
        );
    }

    #[test]
    fn contact_grid_text() {
        assert!(contact_xdmf_text(&meta(0), "solution.h5").is_none());
        let t = contact_xdmf_text(&meta(4), "solution.h5").unwrap();
        assert_eq!(t.matches("<Grid ").count(), 1);
        assert!(t.contains("<Grid Name=\"contact\" GridType=\"Uniform\">"));
        assert!(
            t.contains("TopologyType=\"Polyline\" NumberOfElements=\"3\" NodesPerElement=\"2\"")
        );
        assert!(t.contains("Dimensions=\"3 2\" DataType=\"Int\" Precision=\"8\" Format=\"HDF\">solution.h5:/contact/topology<"));
        assert!(t.contains("Dimensions=\"4 3\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">solution.h5:/contact/geometry<"));
        assert!(t.contains("Dimensions=\"4\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">solution.h5:/contact/pressure<"));
        assert!(t.contains("Dimensions=\"4\" DataType=\"Int\" Precision=\"8\" Format=\"HDF\">solution.h5:/contact/state<"));
        assert!(t.contains("Name=\"facet_id\" AttributeType=\"Scalar\" Center=\"Cell\""));
        assert!(t.contains(">solution.h5:/contact/facet_id<"));
        assert!(!t.contains("mesh"));
        // the codes in a comment before the root element
        let c = t.find("<!--").unwrap();
        assert!(c < t.find("<Xdmf").unwrap());
        assert!(t.contains("  state: 1 in contact, 0 open\n"));
        // 3D: triangles
        let mut m = meta(4);
        m.dim = 3;
        let t = contact_xdmf_text(&m, "solution.h5").unwrap();
        assert!(
            t.contains("TopologyType=\"Triangle\" NumberOfElements=\"3\" NodesPerElement=\"3\"")
        );
        assert!(t.contains("Dimensions=\"3 3\" DataType=\"Int\""));
    }

    #[test]
    fn series_text() {
        let times = [0.25, 0.5, 1.0];
        let t = xdmf_series_text(&meta(4), "solution.h5", &times);
        let c = contact_series_text(&meta(4), "solution.h5", &times).unwrap();
        for (doc, name) in [(&t, "mesh"), (&c, "contact")] {
            assert_eq!(
                doc.matches("GridType=\"Collection\" CollectionType=\"Temporal\"")
                    .count(),
                1
            );
            assert!(doc.contains(&format!(
                "<Grid Name=\"{name}\" GridType=\"Collection\" CollectionType=\"Temporal\">"
            )));
            assert_eq!(
                doc.matches(&format!("<Grid Name=\"{name}\" GridType=\"Uniform\""))
                    .count(),
                3
            );
            assert_eq!(doc.matches("<Grid ").count(), 4);
            assert_eq!(
                doc.matches("<Grid ").count(),
                doc.matches("</Grid>").count()
            );
            for v in ["0.25", "0.5", "1.0"] {
                assert_eq!(doc.matches(&format!("<Time Value=\"{v}\"/>")).count(), 1);
            }
        }
        for s in 1..=3 {
            assert!(t.contains(&format!(">solution.h5:/step_{s}/nodal/displacement<")));
            assert!(t.contains(&format!(">solution.h5:/step_{s}/cell/stress<")));
            assert!(c.contains(&format!(">solution.h5:/step_{s}/contact/pressure<")));
            assert!(c.contains(&format!(">solution.h5:/step_{s}/contact/state<")));
        }
        // the mesh and the contact surface once in the file, referenced by every step
        assert_eq!(t.matches(">solution.h5:/mesh/geometry<").count(), 3);
        assert_eq!(c.matches(">solution.h5:/contact/geometry<").count(), 3);
        assert_eq!(c.matches(">solution.h5:/contact/topology<").count(), 3);
        assert!(!t.contains(">solution.h5:/nodal/") && !t.contains("contact"));
        // without contact nodes no contact file
        assert!(contact_series_text(&meta(0), "solution.h5", &[1.0]).is_none());
    }

    #[test]
    fn signature_differs_on_field_change() {
        let a = meta(0);
        let mut b = meta(0);
        b.nodal[0].ncomp = 2;
        assert_ne!(a.signature(), b.signature());
        let mut c = meta(0);
        c.nodal[0].codes = Some("x".into());
        assert_ne!(a.signature(), c.signature());
        let mut d = meta(0);
        d.n_contact_facets = 9;
        assert_ne!(a.signature(), d.signature());
        assert_eq!(a.signature(), meta(0).signature());
    }
}
