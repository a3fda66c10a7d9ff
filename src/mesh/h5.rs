//! The HDF5 mesh format (`signorini-mpi convert mesh.msh mesh.h5`), read by every rank at once
//! in contiguous blocks (hyperslabs). Layout of the file (all indices 0-based, all integer
//! datasets `u64`, documented for users in docs/mesh-h5.md):
//!
//! ```text
//! /                 attributes: format = 1 (u64), dim = 2 | 3 (u64)
//! /coordinates      f64 [n_nodes, 3]        node coordinates (z = 0 in 2D)
//! /node_tags        u64 [n_nodes]           gmsh node tags
//! /cells            u64 [n_cells, dim+1]    body cells (positively oriented), node indices
//! /cell_tags        u64 [n_cells]           gmsh element tags
//! /facets           u64 [n_facets, dim]     boundary facets (lines in 2D, triangles in 3D)
//! /facet_tags       u64 [n_facets]
//! /edges            u64 [n_edges, 2]        line elements of a 3D mesh
//! /edge_tags        u64 [n_edges]
//! /points           u64 [n_points]          point elements (node indices)
//! /point_tags       u64 [n_points]
//! /groups/names     u8  [..]                group names, each followed by a NUL byte
//! /groups/dim       u64 [n_groups]          dimension of each group (0..=dim)
//! /groups/tag       i64 [n_groups]          physical tag
//! /groups/offsets   u64 [n_groups + 1]      CSR: members of group g are members[offsets[g]..offsets[g+1]]
//! /groups/members   u64 [n_members]         element indices into cells / facets / edges / points
//!                                           (by the group's dimension), ascending per group
//! ```
//!
//! `convert` stores the cells along the Morton curve of their centroids ([`cell_order`]), so
//! that every rank's block of cells is compact; the reader takes any order, and checks and
//! orients the cells as the MSH reader does (`crate::dist`, after the migration).
//!
//! A sibling `.xdmf` file (written by [`write_h5`]) lets ParaView open the mesh with its cell
//! tags.

use super::{Group, Mesh};
use crate::error::InputError;
use hdf5::H5Type;
use ndarray::{s, Array2, ArrayView1, ArrayView2};
use std::path::Path;

/// Version written to the `format` attribute.
pub const FORMAT: u64 = 1;

/// HDF5's file signature (at offset 0 of a file without user block).
const MAGIC: &[u8; 8] = b"\x89HDF\r\n\x1a\n";

/// True if `path` names an HDF5 mesh: extension `.h5` / `.hdf5`, or the HDF5 signature.
pub fn is_h5(path: &Path) -> bool {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    if matches!(ext.as_deref(), Some("h5" | "hdf5")) {
        return true;
    }
    let mut head = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head))
        .is_ok()
        && &head == MAGIC
}

fn to_u64(v: &[usize]) -> Vec<u64> {
    v.iter().map(|&x| x as u64).collect()
}

fn put<T: H5Type>(f: &hdf5::Group, name: &str, data: &[T], ncomp: usize) -> hdf5::Result<()> {
    let rows = data.len().checked_div(ncomp).unwrap_or(0);
    if ncomp <= 1 {
        f.new_dataset::<T>()
            .shape([data.len()])
            .create(name)?
            .write(ArrayView1::from(data))
    } else {
        let v = ArrayView2::from_shape((rows, ncomp), data).map_err(|e| e.to_string())?;
        f.new_dataset::<T>()
            .shape([rows, ncomp])
            .create(name)?
            .write(v)
    }
}

/// The order in which [`write_h5`] stores the cells: along the Morton curve of their
/// centroids (ties by mesh order). Every rank then reads a compact block of cells, so the
/// distributed dual graph has few edges between blocks and the partitioner's aggregates are
/// full (`crate::dist`); gmsh's order (e.g. after its own refinement) scatters a block over
/// the whole body.
pub fn cell_order(mesh: &Mesh) -> Vec<usize> {
    let (lo, _) = mesh.bounding_box();
    let extent = mesh.extent();
    let npc = mesh.nodes_per_cell();
    let mut keyed: Vec<(u64, usize)> = (0..mesh.n_cells())
        .map(|c| {
            let mut x = [0.0; 3];
            for &v in mesh.cell(c) {
                for k in 0..3 {
                    x[k] += mesh.coords[v][k] / npc as f64;
                }
            }
            (crate::geom::morton_key(&x, mesh.dim, &lo, extent), c)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, c)| c).collect()
}

/// Writes `mesh` to an HDF5 mesh file (format above) and the sibling `.xdmf`, the cells in
/// [`cell_order`] (with their tags and group memberships). Serial.
pub fn write_h5(mesh: &Mesh, path: &Path) -> Result<(), String> {
    let order = cell_order(mesh);
    let mut new_index = vec![0usize; order.len()];
    for (i, &c) in order.iter().enumerate() {
        new_index[c] = i;
    }
    let cells: Vec<usize> = order.iter().flat_map(|&c| mesh.cell(c)).copied().collect();
    let cell_tags: Vec<u64> = order.iter().map(|&c| mesh.cell_tags[c]).collect();
    let fail = |e: hdf5::Error| format!("{}: {e}", path.display());
    let f = hdf5::File::create(path).map_err(fail)?;
    f.new_attr::<u64>()
        .create("format")
        .and_then(|a| a.write_scalar(&FORMAT))
        .map_err(fail)?;
    f.new_attr::<u64>()
        .create("dim")
        .and_then(|a| a.write_scalar(&(mesh.dim as u64)))
        .map_err(fail)?;
    let coords: Vec<f64> = mesh.coords.iter().flatten().copied().collect();
    let dim = mesh.dim;
    let w = || -> hdf5::Result<()> {
        put(&f, "coordinates", &coords, 3)?;
        put(&f, "node_tags", &mesh.node_tags, 1)?;
        put(&f, "cells", &to_u64(&cells), dim + 1)?;
        put(&f, "cell_tags", &cell_tags, 1)?;
        put(&f, "facets", &to_u64(&mesh.facets), dim)?;
        put(&f, "facet_tags", &mesh.facet_tags, 1)?;
        put(&f, "edges", &to_u64(&mesh.edges), 2)?;
        put(&f, "edge_tags", &mesh.edge_tags, 1)?;
        put(&f, "points", &to_u64(&mesh.points), 1)?;
        put(&f, "point_tags", &mesh.point_tags, 1)?;
        let g = f.create_group("groups")?;
        let mut names = Vec::new();
        let mut offsets = vec![0u64];
        let mut members = Vec::new();
        for gr in &mesh.groups {
            names.extend_from_slice(gr.name.as_bytes());
            names.push(0u8);
            let start = members.len();
            if gr.dim == dim {
                members.extend(gr.elements.iter().map(|&e| new_index[e] as u64));
                members[start..].sort_unstable();
            } else {
                members.extend(gr.elements.iter().map(|&e| e as u64));
            }
            offsets.push(members.len() as u64);
        }
        put(&g, "names", &names, 1)?;
        let dims: Vec<u64> = mesh.groups.iter().map(|g| g.dim as u64).collect();
        let tags: Vec<i64> = mesh.groups.iter().map(|g| g.tag as i64).collect();
        put(&g, "dim", &dims, 1)?;
        put(&g, "tag", &tags, 1)?;
        put(&g, "offsets", &offsets, 1)?;
        put(&g, "members", &members, 1)?;
        Ok(())
    };
    w().map_err(fail)?;
    drop(f);
    let xdmf = path.with_extension("xdmf");
    let h5 = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (topo, npe) = if dim == 2 {
        ("Triangle", 3)
    } else {
        ("Tetrahedron", 4)
    };
    let (nn, nc) = (mesh.n_nodes(), mesh.n_cells());
    let text = format!(
        r#"<?xml version="1.0" ?>
<Xdmf Version="3.0">
  <Domain>
    <Grid Name="mesh" GridType="Uniform">
      <Topology TopologyType="{topo}" NumberOfElements="{nc}">
        <DataItem Dimensions="{nc} {npe}" NumberType="UInt" Precision="8" Format="HDF">{h5}:/cells</DataItem>
      </Topology>
      <Geometry GeometryType="XYZ">
        <DataItem Dimensions="{nn} 3" NumberType="Float" Precision="8" Format="HDF">{h5}:/coordinates</DataItem>
      </Geometry>
      <Attribute Name="cell_tag" AttributeType="Scalar" Center="Cell">
        <DataItem Dimensions="{nc}" NumberType="UInt" Precision="8" Format="HDF">{h5}:/cell_tags</DataItem>
      </Attribute>
    </Grid>
  </Domain>
</Xdmf>
"#
    );
    std::fs::write(&xdmf, text).map_err(|e| format!("{}: {e}", xdmf.display()))
}

/// An open HDF5 mesh file: its sizes and groups; blocks of rows are read on demand.
pub struct H5Mesh {
    file: hdf5::File,
    pub dim: usize,
    pub n_nodes: usize,
    pub n_cells: usize,
    pub n_facets: usize,
    pub n_edges: usize,
    pub n_points: usize,
    /// Groups without their members (name, dim, tag), and the CSR offsets of the members.
    pub groups: Vec<Group>,
    pub group_offsets: Vec<usize>,
}

/// The rows of dataset `/name` of `f`, checked to be 1-D (`ncomp` ≤ 1) or of `ncomp` columns.
fn dataset_rows(f: &hdf5::File, name: &str, ncomp: usize) -> Result<usize, String> {
    let ds = f
        .dataset(name)
        .map_err(|_| format!("HDF5 mesh without dataset /{name}"))?;
    let shape = ds.shape();
    let ok = if ncomp <= 1 {
        shape.len() == 1
    } else {
        shape.len() == 2 && shape[1] == ncomp
    };
    if !ok {
        return Err(format!(
            "dataset /{name} has shape {shape:?}, expected [n{}]",
            if ncomp > 1 {
                format!(", {ncomp}")
            } else {
                String::new()
            }
        ));
    }
    Ok(shape[0])
}

/// The groups of `f` (name, dimension, tag; members not read) and the CSR offsets of their
/// members, checked against each other and against the mesh dimension `dim`.
fn read_groups(f: &hdf5::File, dim: usize) -> Result<(Vec<Group>, Vec<usize>), String> {
    let read_all = |name: &str| -> Result<Vec<u64>, String> {
        f.dataset(name)
            .and_then(|d| d.read_raw::<u64>())
            .map_err(|e| format!("cannot read /{name}: {e}"))
    };
    let names = f
        .dataset("groups/names")
        .and_then(|d| d.read_raw::<u8>())
        .map_err(|e| format!("cannot read /groups/names: {e}"))?;
    let dims = read_all("groups/dim")?;
    let tags = f
        .dataset("groups/tag")
        .and_then(|d| d.read_raw::<i64>())
        .map_err(|e| format!("cannot read /groups/tag: {e}"))?;
    let offsets: Vec<usize> = read_all("groups/offsets")?
        .into_iter()
        .map(|x| x as usize)
        .collect();
    let names: Vec<String> = names
        .split(|&b| b == 0)
        .map(|s| String::from_utf8_lossy(s).into_owned())
        .collect();
    let ng = dims.len();
    let n_members = dataset_rows(f, "groups/members", 1)?;
    if tags.len() != ng
        || offsets.len() != ng + 1
        || names.len() != ng + 1
        || offsets[0] != 0
        || offsets.windows(2).any(|w| w[0] > w[1])
        || offsets[ng] != n_members
    {
        return Err("inconsistent /groups datasets".into());
    }
    let groups = (0..ng)
        .map(|g| Group {
            name: names[g].clone(),
            dim: dims[g] as usize,
            tag: tags[g] as i32,
            elements: Vec::new(),
        })
        .collect::<Vec<_>>();
    if groups.iter().any(|g| g.dim > dim) {
        return Err("a group's dimension exceeds the mesh dimension".into());
    }
    Ok((groups, offsets))
}

impl H5Mesh {
    /// Opens the file (read only, independently on each rank) and reads its header.
    pub fn open(path: &Path) -> Result<H5Mesh, String> {
        let f = hdf5::File::open(path).map_err(|e| format!("cannot open as HDF5 mesh: {e}"))?;
        let attr = |name: &str| -> Result<u64, String> {
            f.attr(name)
                .and_then(|a| a.read_scalar::<u64>())
                .map_err(|_| format!("not a signorini-mpi HDF5 mesh (no attribute `{name}`)"))
        };
        let format = attr("format")?;
        if format != FORMAT {
            return Err(format!(
                "HDF5 mesh format {format}, this program reads format {FORMAT}"
            ));
        }
        let dim = attr("dim")? as usize;
        if dim != 2 && dim != 3 {
            return Err(format!("HDF5 mesh of dimension {dim} (2 or 3 expected)"));
        }
        let rows = |name: &str, ncomp: usize| dataset_rows(&f, name, ncomp);
        let n_nodes = rows("coordinates", 3)?;
        let n_cells = rows("cells", dim + 1)?;
        let n_facets = rows("facets", dim)?;
        let n_edges = rows("edges", 2)?;
        let n_points = rows("points", 1)?;
        for (name, n) in [
            ("node_tags", n_nodes),
            ("cell_tags", n_cells),
            ("facet_tags", n_facets),
            ("edge_tags", n_edges),
            ("point_tags", n_points),
        ] {
            if rows(name, 1)? != n {
                return Err(format!("dataset /{name} has the wrong length"));
            }
        }
        let (groups, group_offsets) = read_groups(&f, dim)?;
        Ok(H5Mesh {
            file: f,
            dim,
            n_nodes,
            n_cells,
            n_facets,
            n_edges,
            n_points,
            groups,
            group_offsets,
        })
    }

    /// Rows `lo..hi` of a 1-D dataset.
    pub fn rows1<T: H5Type + Clone>(
        &self,
        name: &str,
        lo: usize,
        hi: usize,
    ) -> Result<Vec<T>, String> {
        self.rows(name, lo, hi, |d| {
            d.read_slice_1d::<T, _>(s![lo..hi])
                .map(|a| a.into_raw_vec_and_offset().0)
        })
    }

    /// Rows `lo..hi` of a 2-D dataset, flat (row-major).
    pub fn rows2<T: H5Type + Clone>(
        &self,
        name: &str,
        lo: usize,
        hi: usize,
    ) -> Result<Vec<T>, String> {
        self.rows(name, lo, hi, |d| {
            d.read_slice_2d::<T, _>(s![lo..hi, ..])
                .map(|a: Array2<T>| a.as_standard_layout().iter().cloned().collect())
        })
    }

    /// Rows `lo..hi` of the dataset `name` as `read` takes them from it (none when the range
    /// is empty); a failure names the dataset and the rows.
    fn rows<T>(
        &self,
        name: &str,
        lo: usize,
        hi: usize,
        read: impl FnOnce(&hdf5::Dataset) -> hdf5::Result<Vec<T>>,
    ) -> Result<Vec<T>, String> {
        if lo >= hi {
            return Ok(Vec::new());
        }
        self.file
            .dataset(name)
            .and_then(|d| read(&d))
            .map_err(|e| format!("cannot read /{name}[{lo}..{hi}]: {e}"))
    }
}

/// Where an HDF5 mesh holds its node tags, and its element tags (in messages).
pub(crate) const H5_NODE_TAGS: &str = "/node_tags";
pub(crate) const H5_ELEMENT_TAGS: &str = "/cell_tags, /facet_tags, /edge_tags and /point_tags";

/// Reads a whole HDF5 mesh on one process (the checks of [`Mesh::validate_indices`], every
/// tag once, every coordinate finite).
pub fn read_h5(path: &Path) -> Result<Mesh, InputError> {
    let err = |m: String| InputError::new(path, m);
    let h = H5Mesh::open(path).map_err(err)?;
    let dim = h.dim;
    let us = |v: Vec<u64>| v.into_iter().map(|x| x as usize).collect::<Vec<_>>();
    let coords: Vec<f64> = h.rows2("coordinates", 0, h.n_nodes).map_err(err)?;
    let mut mesh = Mesh {
        dim,
        coords: coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        node_tags: h.rows1("node_tags", 0, h.n_nodes).map_err(err)?,
        cells: us(h.rows2("cells", 0, h.n_cells).map_err(err)?),
        cell_tags: h.rows1("cell_tags", 0, h.n_cells).map_err(err)?,
        facets: us(h.rows2("facets", 0, h.n_facets).map_err(err)?),
        facet_tags: h.rows1("facet_tags", 0, h.n_facets).map_err(err)?,
        edges: us(h.rows2("edges", 0, h.n_edges).map_err(err)?),
        edge_tags: h.rows1("edge_tags", 0, h.n_edges).map_err(err)?,
        points: us(h.rows1("points", 0, h.n_points).map_err(err)?),
        point_tags: h.rows1("point_tags", 0, h.n_points).map_err(err)?,
        groups: h.groups.clone(),
        ..Default::default()
    };
    let members: Vec<u64> = h
        .rows1("groups/members", 0, *h.group_offsets.last().unwrap_or(&0))
        .map_err(err)?;
    for (g, gr) in mesh.groups.iter_mut().enumerate() {
        gr.elements = us(members[h.group_offsets[g]..h.group_offsets[g + 1]].to_vec());
    }
    mesh.validate_indices().map_err(err)?;
    if let Some(t) = super::smallest_duplicate(&mesh.node_tags) {
        return Err(err(super::duplicate_tag("node", t, H5_NODE_TAGS)));
    }
    let element_tags = [
        &mesh.cell_tags[..],
        &mesh.facet_tags,
        &mesh.edge_tags,
        &mesh.point_tags,
    ]
    .concat();
    if let Some(t) = super::smallest_duplicate(&element_tags) {
        return Err(err(super::duplicate_tag("element", t, H5_ELEMENT_TAGS)));
    }
    let nodes = mesh.node_tags.iter().copied().zip(mesh.coords.iter());
    if let Some((_, m)) = super::non_finite_node(nodes) {
        return Err(err(m));
    }
    super::orient_cells(dim, &mut mesh.cells, &mesh.cell_tags, &mesh.coords).map_err(err)?;
    Ok(mesh)
}

impl Mesh {
    /// Every node index in range, every group member in range: a hand-made or damaged HDF5
    /// mesh gives an error instead of a panic.
    pub fn validate_indices(&self) -> Result<(), String> {
        let n = self.n_nodes();
        for (what, list) in [
            ("cells", &self.cells),
            ("facets", &self.facets),
            ("edges", &self.edges),
            ("points", &self.points),
        ] {
            if let Some(v) = list.iter().find(|&&v| v >= n) {
                return Err(format!(
                    "/{what} references node {v}, but there are {n} nodes"
                ));
            }
        }
        for g in &self.groups {
            let count = if g.dim == self.dim {
                self.n_cells()
            } else if g.dim + 1 == self.dim {
                self.n_facets()
            } else if g.dim == 1 {
                self.edge_tags.len()
            } else {
                self.point_tags.len()
            };
            if let Some(e) = g.elements.iter().find(|&&e| e >= count) {
                return Err(format!(
                    "group \"{}\" ({}D) has member {e}, but there are {count} such elements",
                    g.name, g.dim
                ));
            }
        }
        Ok(())
    }
}
