//! Gmsh MSH 4.1 reading (ASCII and binary) through `mshio`, physical groups by name,
//! P1 triangles / tetrahedra, boundary entities, quality checks.
//!
//! INTERFACE (used by the rest of the code; keep these names):
//!
//! ```ignore
//! pub struct Group { pub name: String, pub dim: usize, pub tag: i32, pub elements: Vec<usize> }
//! pub struct Mesh {
//!     pub dim: usize,                 // 2 or 3 (dimension of the body cells)
//!     pub coords: Vec<[f64; 3]>,      // node coordinates, z = 0 in 2D; only nodes used by cells
//!     pub node_tags: Vec<u64>,        // gmsh node tag per node
//!     pub cells: Vec<usize>,          // flat, dim+1 node indices per cell, positively oriented
//!     pub cell_tags: Vec<u64>,        // gmsh element tag per cell
//!     pub facets: Vec<usize>,         // flat, dim node indices per facet (lines 2D / triangles 3D)
//!     pub facet_tags: Vec<u64>,
//!     pub edges: Vec<usize>,          // flat, 2 per line element of a 3D mesh (may be empty)
//!     pub points: Vec<usize>,         // node index per point element
//!     pub groups: Vec<Group>,         // elements: indices into cells / facets / edges / points by dim
//! }
//! impl Mesh {
//!     pub fn nodes_per_cell(&self) -> usize;
//!     pub fn n_nodes(&self) -> usize; pub fn n_cells(&self) -> usize;
//!     pub fn cell(&self, c: usize) -> &[usize]; pub fn facet(&self, f: usize) -> &[usize];
//!     pub fn group(&self, name: &str) -> Option<&Group>;
//!     pub fn group_names(&self) -> Vec<String>;      // for error messages
//!     pub fn group_nodes(&self, g: &Group) -> Vec<usize>;  // sorted, unique node indices
//! }
//! pub fn read_msh(path: &Path) -> Result<Mesh, crate::error::InputError>;
//! ```
//!
//! Details:
//! - The mesh dimension is the highest dimension of the elements in the file. Body cells
//!   are 3-node triangles (2D) or 4-node tetrahedra (3D); boundary elements are 2-node
//!   lines (facets in 2D, `edges` in 3D), 3-node triangles (facets in 3D) and points.
//!   Any other element type is refused.
//! - Only nodes used by body cells are kept, renumbered 0.. in gmsh order.
//! - Cells are positively oriented (inverted ones get two nodes swapped); cells of zero
//!   (or nearly zero) measure are refused.
//! - Groups come from the entities' physical tags, sorted by (dim, tag); unnamed physical
//!   groups get their tag as name. Element indices of a group are ascending.
//! - In 2D, z must be constant; it is set to 0.

mod facets;
pub mod h5;
mod quiet;
mod raw;
mod rigid_modes;
pub use rigid_modes::{BodyModes, Part, RigidModes, NO_SLOT};
#[cfg(test)]
mod tests;

use crate::geom::{norm2, sub};
use std::collections::HashMap;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use mshio::ElementType;

use crate::error::InputError;

/// A physical group: its elements are indices into `cells` (dim = mesh dim), `facets`
/// (dim = mesh dim − 1), `edges` (dim 1 of a 3D mesh) or `points` (dim 0).
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    pub name: String,
    pub dim: usize,
    pub tag: i32,
    pub elements: Vec<usize>,
}

/// A P1 simplex mesh with its boundary elements and physical groups.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    pub dim: usize,
    pub coords: Vec<[f64; 3]>,
    pub node_tags: Vec<u64>,
    pub cells: Vec<usize>,
    pub cell_tags: Vec<u64>,
    pub facets: Vec<usize>,
    pub facet_tags: Vec<u64>,
    pub edges: Vec<usize>,
    pub edge_tags: Vec<u64>,
    pub points: Vec<usize>,
    pub point_tags: Vec<u64>,
    pub groups: Vec<Group>,
    /// Set on a rank's local part of a distributed mesh (`crate::dist`): what the whole mesh
    /// is like. `None`: this is the whole mesh.
    pub global: Option<Box<GlobalInfo>>,
}

/// The whole mesh, seen from a rank's local part (see `crate::dist`).
#[derive(Debug, Clone, Default)]
pub struct GlobalInfo {
    pub n_nodes: usize,
    pub n_cells: usize,
    pub n_facets: usize,
    /// Number of elements of every group (in group order).
    pub group_sizes: Vec<usize>,
    /// Bounding box of the whole mesh.
    pub bbox: ([f64; 3], [f64; 3]),
    /// Groups of every local node (CSR: group indices of node v are
    /// `node_group_ids[node_group_ptr[v]..node_group_ptr[v + 1]]`), from all elements of the
    /// whole mesh that contain it.
    pub node_group_ptr: Vec<usize>,
    pub node_group_ids: Vec<u32>,
    /// Local facets whose boundary check is made here (those with an owned node: all cells
    /// containing them are local).
    pub facet_checked: Vec<bool>,
    /// The local cells 0..n_own_cells are this rank's, the rest ghosts.
    pub n_own_cells: usize,
}

impl Mesh {
    /// Number of nodes of the whole mesh.
    pub fn n_nodes_global(&self) -> usize {
        self.global.as_ref().map_or(self.n_nodes(), |g| g.n_nodes)
    }
    /// Number of cells of the whole mesh.
    pub fn n_cells_global(&self) -> usize {
        self.global.as_ref().map_or(self.n_cells(), |g| g.n_cells)
    }
    /// Number of boundary facets of the whole mesh.
    pub fn n_facets_global(&self) -> usize {
        self.global.as_ref().map_or(self.n_facets(), |g| g.n_facets)
    }
    /// Number of elements of group i in the whole mesh.
    pub fn group_size_global(&self, i: usize) -> usize {
        self.global
            .as_ref()
            .map_or(self.groups[i].elements.len(), |g| g.group_sizes[i])
    }
    pub fn nodes_per_cell(&self) -> usize {
        self.dim + 1
    }
    pub fn nodes_per_facet(&self) -> usize {
        self.dim
    }
    pub fn n_nodes(&self) -> usize {
        self.coords.len()
    }
    pub fn n_cells(&self) -> usize {
        self.cell_tags.len()
    }
    pub fn n_facets(&self) -> usize {
        self.facet_tags.len()
    }
    pub fn cell(&self, c: usize) -> &[usize] {
        let k = self.nodes_per_cell();
        &self.cells[c * k..(c + 1) * k]
    }
    pub fn facet(&self, f: usize) -> &[usize] {
        let k = self.dim;
        &self.facets[f * k..(f + 1) * k]
    }
    pub fn edge(&self, e: usize) -> &[usize] {
        &self.edges[2 * e..2 * e + 2]
    }
    /// First group with this name (any dimension; see [`Mesh::group_dim`] if a name is
    /// used in several dimensions).
    pub fn group(&self, name: &str) -> Option<&Group> {
        self.groups.iter().find(|g| g.name == name)
    }
    /// The group with this name and dimension.
    pub fn group_dim(&self, name: &str, dim: usize) -> Option<&Group> {
        self.groups.iter().find(|g| g.name == name && g.dim == dim)
    }
    /// Names of all groups (in group order), for error messages.
    pub fn group_names(&self) -> Vec<String> {
        self.groups.iter().map(|g| g.name.clone()).collect()
    }
    /// Sorted, unique node indices of the elements of `g`.
    pub fn group_nodes(&self, g: &Group) -> Vec<usize> {
        if let Some(gl) = &self.global {
            // every local node of the group, also one whose group elements are elsewhere
            let Some(i) = self.groups.iter().position(|x| std::ptr::eq(x, g)) else {
                return Vec::new();
            };
            return (0..self.n_nodes())
                .filter(|&v| {
                    gl.node_group_ids[gl.node_group_ptr[v]..gl.node_group_ptr[v + 1]]
                        .contains(&(i as u32))
                })
                .collect();
        }
        let mut nodes = Vec::new();
        for &e in &g.elements {
            nodes.extend_from_slice(self.element_nodes(g.dim, e));
        }
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }
    /// Node indices of element `e` of dimension `dim` (cell, facet, edge or point).
    pub fn element_nodes(&self, dim: usize, e: usize) -> &[usize] {
        if dim == self.dim {
            self.cell(e)
        } else if dim + 1 == self.dim {
            self.facet(e)
        } else if dim == 1 {
            self.edge(e)
        } else {
            &self.points[e..e + 1]
        }
    }
    /// Bounding box (lowest and highest coordinates) of the nodes.
    /// Of the whole mesh for a distributed one.
    pub fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        if let Some(g) = &self.global {
            return g.bbox;
        }
        bounding_box(&self.coords)
    }

    /// The largest extent of the bounding box over the mesh's dimensions (> 0).
    pub fn extent(&self) -> f64 {
        let (lo, hi) = self.bounding_box();
        (0..self.dim)
            .map(|k| hi[k] - lo[k])
            .fold(0.0f64, f64::max)
            .max(f64::MIN_POSITIVE)
    }

    /// Signed area (2D) or volume (3D) of cell `c`; positive for every cell after reading.
    pub fn cell_measure(&self, c: usize) -> f64 {
        let p: Vec<[f64; 3]> = self.cell(c).iter().map(|&n| self.coords[n]).collect();
        signed_measure(self.dim, &p).0
    }
}

/// Bounding box (lowest and highest coordinates) of points.
pub fn bounding_box(coords: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for x in coords {
        for k in 0..3 {
            lo[k] = lo[k].min(x[k]);
            hi[k] = hi[k].max(x[k]);
        }
    }
    (lo, hi)
}

/// Signed measure of a simplex and its longest edge length.
fn signed_measure(dim: usize, p: &[[f64; 3]]) -> (f64, f64) {
    let mut h2: f64 = 0.0;
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            h2 = h2.max(norm2(sub(p[j], p[i])));
        }
    }
    let a = sub(p[1], p[0]);
    let b = sub(p[2], p[0]);
    let m = if dim == 2 {
        0.5 * (a[0] * b[1] - a[1] * b[0])
    } else {
        let c = sub(p[3], p[0]);
        (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]))
            / 6.0
    };
    (m, h2.sqrt())
}

/// Whether a panic of the MSH parser (`mshio`) is caught (silently) and reported as an
/// `InputError`. On by default; fuzzing turns it off so that every parser panic that the
/// header checks do not prevent shows up as a crash.
static CATCH_PARSER_PANICS: AtomicBool = AtomicBool::new(true);

/// Turns the catching of MSH parser panics on or off (see [`read_msh_bytes`]); for fuzzing.
pub fn set_catch_parser_panics(on: bool) {
    CATCH_PARSER_PANICS.store(on, Ordering::Relaxed);
}

const HINT_MSH41: &str =
    "save the mesh as MSH 4.1 (gmsh ... -format msh41, or Mesh.MshFileVersion = 4.1;)";

/// Node tag → node index, dense table when the tags allow it.
enum TagIndex {
    Dense { min: u64, index: Vec<usize> },
    Sparse(HashMap<u64, usize>),
}

impl TagIndex {
    fn new(tags: &[u64]) -> Self {
        let (min, max) = tags
            .iter()
            .fold((u64::MAX, 0u64), |(lo, hi), &t| (lo.min(t), hi.max(t)));
        if tags.is_empty() {
            return TagIndex::Dense {
                min: 0,
                index: Vec::new(),
            };
        }
        let span = max - min;
        if span <= 4 * tags.len() as u64 + 1024 {
            let mut index = vec![usize::MAX; span as usize + 1];
            for (i, &t) in tags.iter().enumerate() {
                index[(t - min) as usize] = i;
            }
            TagIndex::Dense { min, index }
        } else {
            TagIndex::Sparse(tags.iter().enumerate().map(|(i, &t)| (t, i)).collect())
        }
    }
    fn get(&self, tag: u64) -> Option<usize> {
        match self {
            TagIndex::Dense { min, index } => {
                let k = tag.checked_sub(*min)?;
                index
                    .get(usize::try_from(k).ok()?)
                    .copied()
                    .filter(|&i| i != usize::MAX)
            }
            TagIndex::Sparse(m) => m.get(&tag).copied(),
        }
    }
}

/// Kind of a supported element type: its dimension.
fn element_dim(t: ElementType) -> Option<usize> {
    match t {
        ElementType::Pnt => Some(0),
        ElementType::Lin2 => Some(1),
        ElementType::Tri3 => Some(2),
        ElementType::Tet4 => Some(3),
        _ => None,
    }
}

fn entity_word(dim: usize) -> &'static str {
    ["Point", "Curve", "Surface", "Volume"][dim.min(3)]
}

/// Reads a mesh file: the HDF5 mesh format of [`h5`] (by extension or signature), else Gmsh MSH.
pub fn read_mesh(path: &Path) -> Result<Mesh, InputError> {
    if h5::is_h5(path) {
        h5::read_h5(path)
    } else {
        read_msh(path)
    }
}

/// Reads a Gmsh MSH 4.1 file (ASCII or binary). All problems with the file are
/// `InputError`s naming the file.
pub fn read_msh(path: &Path) -> Result<Mesh, InputError> {
    read_msh_checked(path, &|_, _, _, _| Ok(()))
}

/// A check of a mesh's lengths before its cells are measured: (dimension, extent — the
/// largest side of the bounding box —, largest |coordinate|, nodes) → `Err` to refuse it
/// (a case's admissible range, `Case::check_mesh_lengths`).
pub type LengthCheck<'a> = dyn Fn(usize, f64, f64, usize) -> Result<(), InputError> + 'a;

/// As [`read_msh`], with `lengths` asked about the mesh's lengths before any cell is measured
/// (a mesh whose coordinates leave double precision's range for its cell measures is refused
/// by `lengths`, not as degenerate).
pub fn read_msh_checked(path: &Path, lengths: &LengthCheck) -> Result<Mesh, InputError> {
    let bytes = std::fs::read(path)
        .map_err(|e| InputError::new(path, format!("cannot read mesh file: {e}")))?;
    read_msh_bytes_checked(&bytes, path, lengths)
}

/// As [`read_msh`], from the bytes of the file already in memory; `path` only names the file
/// in messages.
pub fn read_msh_bytes(bytes: &[u8], path: &Path) -> Result<Mesh, InputError> {
    read_msh_bytes_checked(bytes, path, &|_, _, _, _| Ok(()))
}

/// The extent (the largest side of the bounding box) and the largest |coordinate| of the
/// first `dim` coordinates of `coords` (0 for none). Pure.
pub fn lengths(dim: usize, coords: &[[f64; 3]]) -> (f64, f64) {
    let (lo, hi) = bounding_box(coords);
    let extent = (0..dim).map(|k| hi[k] - lo[k]).fold(0.0f64, f64::max);
    let far = (0..dim)
        .map(|k| lo[k].abs().max(hi[k].abs()))
        .fold(0.0f64, f64::max);
    if coords.is_empty() {
        (0.0, 0.0)
    } else {
        (extent, far)
    }
}

/// A failure of [`build`]: a message about the file, or the length check's own error.
enum BuildError {
    Msg(String),
    Lengths(InputError),
}

impl From<String> for BuildError {
    fn from(m: String) -> Self {
        BuildError::Msg(m)
    }
}

impl From<&str> for BuildError {
    fn from(m: &str) -> Self {
        BuildError::Msg(m.to_string())
    }
}

/// As [`read_msh_bytes`], with the check `lengths` of [`read_msh_checked`].
fn read_msh_bytes_checked(
    bytes: &[u8],
    path: &Path,
    lengths: &LengthCheck,
) -> Result<Mesh, InputError> {
    let err = |m: String| InputError::new(path, m);
    let info = raw::scan_header(bytes).map_err(err)?;
    if info.partitioned {
        return Err(err(
            "partitioned mesh ($PartitionedEntities, written by gmsh -part) is not supported: \
             re-mesh without -part (signorini-mpi partitions the mesh itself)"
                .into(),
        ));
    }

    raw::check_section_counts(bytes, &info).map_err(err)?;

    let parse = || mshio::parse_msh_bytes(bytes).map_err(|e| parse_error(bytes, &info, &e));
    let parsed = if CATCH_PARSER_PANICS.load(Ordering::Relaxed) {
        quiet::catch_unwind_silently(parse)
    } else {
        Ok(parse())
    };
    let msh = match parsed {
        Ok(Ok(m)) => m,
        Ok(Err(m)) => return Err(err(m)),
        Err(_) => {
            return Err(err(format!(
                "cannot parse as Gmsh MSH 4.1 (the parser failed); {HINT_MSH41}"
            )))
        }
    };

    build(bytes, &info, &msh, lengths).map_err(|e| match e {
        BuildError::Msg(m) => err(m),
        BuildError::Lengths(e) => e,
    })
}

/// The parser's error as one line: where (line and byte of the file, from the position the
/// parser reports), in which section and block, what, and the line as it reads (ASCII files);
/// the hint to save as MSH 4.1 only where the file says another version.
fn parse_error(bytes: &[u8], info: &raw::HeaderInfo, e: &mshio::MshParserError<&[u8]>) -> String {
    let trace = e.filtered_backtrace();
    let what = trace.first().map_or_else(
        || "the parser failed".to_string(),
        |(_, kind)| kind.to_string(),
    );
    let within: Vec<String> = (trace.iter().skip(1).rev())
        .map(|(_, kind)| {
            kind.context()
                .map_or_else(|| kind.to_string(), str::to_string)
        })
        .collect();
    let within = if within.is_empty() {
        String::new()
    } else {
        format!(" (in {})", within.join(", in "))
    };
    // the position: the input the parser was at, a slice of `bytes`
    let at = (trace.first())
        .map(|(rest, _)| bytes.len().saturating_sub(rest.len()))
        .filter(|&at| at <= bytes.len());
    let place = match at {
        Some(at) if at == bytes.len() => {
            let line = bytes.iter().filter(|&&b| b == b'\n').count() + 1;
            format!("the end of the file (line {line}: the file is cut short)")
        }
        Some(at) if info.file_type == 0 => {
            let line = bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
            let start = bytes[..at]
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |p| p + 1);
            let end =
                (bytes[at..].iter().position(|&b| b == b'\n')).map_or(bytes.len(), |p| at + p);
            let text = String::from_utf8_lossy(&bytes[start..end.min(start + 80)]);
            format!("line {line} (\"{}\")", text.trim_end())
        }
        Some(at) => format!("byte {at}"),
        None => "an unknown place".to_string(),
    };
    let hint = if info.version == "4.1" {
        "the file is damaged or was not written by gmsh".to_string()
    } else {
        HINT_MSH41.to_string()
    };
    format!("cannot parse as Gmsh MSH 4.1 at {place}: {what}{within}; {hint}")
}

fn build(
    bytes: &[u8],
    info: &raw::HeaderInfo,
    msh: &mshio::MshFile<u64, i32, f64>,
    check_lengths: &LengthCheck,
) -> Result<Mesh, BuildError> {
    let nodes = msh
        .data
        .nodes
        .as_ref()
        .ok_or("the file has no $Nodes section")?;
    let elements = msh
        .data
        .elements
        .as_ref()
        .ok_or("the file has no $Elements section")?;
    let (all_coords, all_tags) = file_nodes(bytes, info, nodes, elements)?;
    if let Some(t) = smallest_duplicate(&all_tags) {
        return Err(duplicate_tag("node", t, "$Nodes").into());
    }
    let element_tags: Vec<u64> = (elements.element_blocks.iter())
        .flat_map(|b| b.elements.iter().map(|e| e.element_tag))
        .collect();
    if let Some(t) = smallest_duplicate(&element_tags) {
        return Err(duplicate_tag("element", t, "$Elements").into());
    }
    drop(element_tags);
    let tag_index = TagIndex::new(&all_tags);
    let phys = entity_physical_tags(msh);
    let (dim, counts) = mesh_dimension(elements)?;
    let (mut cells, cell_tags, used) =
        body_cells(elements, dim, &phys, &tag_index, all_tags.len())?;
    let (mut coords, node_tags, new_index) = compact(&used, &all_coords, &all_tags, &mut cells);
    if let Some((_, m)) = non_finite_node(node_tags.iter().copied().zip(coords.iter())) {
        return Err(m.into());
    }
    if dim == 2 {
        flatten_2d(&mut coords)?;
    }
    let (extent, far) = lengths(dim, &coords);
    check_lengths(dim, extent, far, coords.len()).map_err(BuildError::Lengths)?;
    orient_cells(dim, &mut cells, &cell_tags, &coords)?;
    let mut mesh = Mesh {
        dim,
        coords,
        node_tags,
        cells,
        cell_tags,
        facets: Vec::with_capacity(counts[dim - 1] * dim),
        facet_tags: Vec::with_capacity(counts[dim - 1]),
        ..Default::default()
    };
    let members = boundary_elements(&mut mesh, elements, &phys, &tag_index, &new_index)?;
    mesh.groups = groups(members, info, dim);
    Ok(mesh)
}

/// The smallest tag that occurs more than once in `tags`: a bitmap over their span where it
/// needs at most one word per tag (Gmsh's usual dense numbering), else a sorted copy.
pub(crate) fn smallest_duplicate(tags: &[u64]) -> Option<u64> {
    let (lo, hi) = (tags.iter()).fold((u64::MAX, 0), |(l, h), &t| (l.min(t), h.max(t)));
    if tags.len() < 2 {
        return None;
    }
    let words = (hi - lo) / 64 + 1;
    if words > tags.len() as u64 {
        let mut sorted = tags.to_vec();
        sorted.sort_unstable();
        return sorted.windows(2).find(|w| w[0] == w[1]).map(|w| w[0]);
    }
    let mut seen = vec![0u64; words as usize];
    let mut dup: Option<u64> = None;
    for &t in tags {
        let k = t - lo;
        let (w, bit) = ((k / 64) as usize, 1u64 << (k % 64));
        if seen[w] & bit == 0 {
            seen[w] |= bit;
        } else if dup.is_none_or(|d| t < d) {
            dup = Some(t);
        }
    }
    dup
}

/// The message for a `what` ("node" or "element") tag defined more than once in `place`.
pub(crate) fn duplicate_tag(what: &str, tag: u64, place: &str) -> String {
    format!("{what} tag {tag} is defined more than once in {place}: every {what} needs its own tag")
}

/// Of the nodes (tag, coordinates) with a coordinate that is not a finite number (NaN or
/// infinite), the one of smallest tag: (tag, message naming it).
pub(crate) fn non_finite_node<'a>(
    nodes: impl Iterator<Item = (u64, &'a [f64; 3])>,
) -> Option<(u64, String)> {
    let (tag, x) = nodes
        .filter(|(_, x)| x.iter().any(|v| !v.is_finite()))
        .min_by_key(|(t, _)| *t)?;
    Some((
        tag,
        format!(
            "node {tag} has a coordinate that is not a finite number: ({}, {}, {})",
            x[0], x[1], x[2]
        ),
    ))
}

/// Physical tags by (dimension, entity tag).
type PhysicalTags<'a> = HashMap<(usize, i32), &'a [i32]>;

/// The node of tag `ntag` (an index into the file's nodes), named by the element using it.
fn lookup(tag_index: &TagIndex, etag: u64, ntag: u64) -> Result<usize, String> {
    tag_index
        .get(ntag)
        .ok_or_else(|| format!("element {etag} references node {ntag}, which is not in $Nodes"))
}

/// All nodes of the file, in file order, with their tags; the counts of the headers checked
/// against the blocks.
fn file_nodes(
    bytes: &[u8],
    info: &raw::HeaderInfo,
    nodes: &mshio::Nodes<u64, i32, f64>,
    elements: &mshio::Elements<u64, i32>,
) -> Result<(Vec<[f64; 3]>, Vec<u64>), String> {
    let n_all: usize = nodes.node_blocks.iter().map(|b| b.nodes.len()).sum();
    if n_all as u64 != nodes.num_nodes {
        return Err(format!(
            "$Nodes announces {} nodes, but its blocks hold {n_all}: the file is corrupt",
            nodes.num_nodes
        ));
    }
    let n_elements: usize = elements
        .element_blocks
        .iter()
        .map(|b| b.elements.len())
        .sum();
    if n_elements as u64 != elements.num_elements {
        return Err(format!(
            "$Elements announces {} elements, but its blocks hold {n_elements}: the file is \
             corrupt",
            elements.num_elements
        ));
    }
    let mut all_coords: Vec<[f64; 3]> = Vec::with_capacity(n_all);
    let mut all_tags: Vec<u64> = vec![0; n_all];
    let mut have_all_tags = true;
    for b in &nodes.node_blocks {
        let off = all_coords.len();
        all_coords.extend(b.nodes.iter().map(|n| [n.x, n.y, n.z]));
        match &b.node_tags {
            // (a tag twice in one block leaves the map short: read the tags as written)
            Some(map) if map.len() == b.nodes.len() => {
                for (&t, &i) in map {
                    all_tags[off + i] = t;
                }
            }
            _ => have_all_tags = false,
        }
    }
    if !have_all_tags {
        // mshio drops the tags of densely numbered nodes: read them from the raw bytes;
        // if that fails, gmsh's usual layout (tag = first tag + position) is assumed.
        match raw::scan_node_tags(bytes, info) {
            Some(t) if t.len() == n_all => all_tags = t,
            _ => {
                for (i, t) in all_tags.iter_mut().enumerate() {
                    *t = nodes
                        .min_node_tag
                        .checked_add(i as u64)
                        .ok_or("node tags beyond the largest integer")?;
                }
            }
        }
    }

    Ok((all_coords, all_tags))
}

/// (dimension, entity tag) → physical tags, from $Entities.
fn entity_physical_tags(msh: &mshio::MshFile<u64, i32, f64>) -> PhysicalTags<'_> {
    let mut phys: HashMap<(usize, i32), &[i32]> = HashMap::new();
    if let Some(ent) = &msh.data.entities {
        for p in &ent.points {
            phys.insert((0, p.tag), &p.physical_tags);
        }
        for c in &ent.curves {
            phys.insert((1, c.tag), &c.physical_tags);
        }
        for s in &ent.surfaces {
            phys.insert((2, s.tag), &s.physical_tags);
        }
        for v in &ent.volumes {
            phys.insert((3, v.tag), &v.physical_tags);
        }
    }

    phys
}

/// The mesh dimension (that of the highest-dimensional elements) and the element counts per
/// dimension; only linear elements are accepted.
fn mesh_dimension(elements: &mshio::Elements<u64, i32>) -> Result<(usize, [usize; 4]), String> {
    let mut dim = 0;
    let mut counts = [0usize; 4];
    for b in &elements.element_blocks {
        let d = element_dim(b.element_type).ok_or_else(|| {
            format!(
                "element type {:?} (gmsh type {}) is not supported: only linear elements \
                 (3-node triangles, 4-node tetrahedra, 2-node lines, points) are read; \
                 mesh with Mesh.ElementOrder = 1",
                b.element_type, b.element_type as i32
            )
        })?;
        dim = dim.max(d);
        counts[d] += b.elements.len();
    }
    if dim < 2 || counts[dim] == 0 {
        return Err(
            "the mesh has no triangles or tetrahedra (body cells); mesh it with gmsh -2 or -3, \
             and give the body a Physical Surface (2D) or Physical Volume (3D): with physical \
             groups defined, gmsh writes only the elements that belong to one"
                .into(),
        );
    }

    Ok((dim, counts))
}

/// (cells as file node indices, dim + 1 per cell; their tags; which file nodes they use).
type BodyCells = (Vec<usize>, Vec<u64>, Vec<bool>);

/// The body cells (file node indices), their tags, and which file nodes they use.
fn body_cells(
    elements: &mshio::Elements<u64, i32>,
    dim: usize,
    phys: &PhysicalTags,
    tag_index: &TagIndex,
    n_all: usize,
) -> Result<BodyCells, String> {
    let nc = dim + 1;
    let count: usize = elements
        .element_blocks
        .iter()
        .filter(|b| element_dim(b.element_type) == Some(dim))
        .map(|b| b.elements.len())
        .sum();
    let mut cells: Vec<usize> = Vec::with_capacity(count * nc);
    let mut cell_tags: Vec<u64> = Vec::with_capacity(count);
    let mut used = vec![false; n_all];
    for b in elements
        .element_blocks
        .iter()
        .filter(|b| element_dim(b.element_type) == Some(dim))
    {
        let edim = dim;
        if phys.get(&(edim, b.entity_tag)).is_none_or(|p| p.is_empty()) && !b.elements.is_empty() {
            return Err(format!(
                "{} body cells (e.g. element {}) of {} {} belong to no physical group: \
                 define a Physical {} for the body (gmsh writes such cells with -save_all \
                 or Mesh.SaveAll = 1)",
                b.elements.len(),
                b.elements[0].element_tag,
                entity_word(edim),
                b.entity_tag,
                entity_word(edim),
            ));
        }
        for e in &b.elements {
            if e.nodes.len() != nc {
                return Err(format!(
                    "element {} has {} nodes",
                    e.element_tag,
                    e.nodes.len()
                ));
            }
            for &nt in &e.nodes {
                let i = lookup(tag_index, e.element_tag, nt)?;
                used[i] = true;
                cells.push(i);
            }
            cell_tags.push(e.element_tag);
        }
    }

    Ok((cells, cell_tags, used))
}

/// Compact renumbering of the used nodes, in gmsh order: (coordinates, tags, new index of every
/// file node or usize::MAX); `cells` renumbered in place.
fn compact(
    used: &[bool],
    all_coords: &[[f64; 3]],
    all_tags: &[u64],
    cells: &mut [usize],
) -> (Vec<[f64; 3]>, Vec<u64>, Vec<usize>) {
    let n_all = used.len();
    let mut new_index = vec![usize::MAX; n_all];
    let mut coords = Vec::with_capacity(n_all);
    let mut node_tags = Vec::with_capacity(n_all);
    for i in 0..n_all {
        if used[i] {
            new_index[i] = coords.len();
            coords.push(all_coords[i]);
            node_tags.push(all_tags[i]);
        }
    }
    for v in cells.iter_mut() {
        *v = new_index[*v];
    }

    (coords, node_tags, new_index)
}

/// 2D: the nodes must lie in a plane z = const; z is set to 0.
fn flatten_2d(coords: &mut [[f64; 3]]) -> Result<(), String> {
    let (lo, hi) = bounding_box(coords);
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let spread = hi[2] - lo[2];
    if spread.is_nan() || spread > 1e-10 * size {
        return Err(format!(
            "2D mesh whose nodes are not in a plane z = const (z from {} to {}): a 2D \
                 body must lie in the xy plane",
            lo[2], hi[2]
        ));
    }
    for p in coords.iter_mut() {
        p[2] = 0.0;
    }
    Ok(())
}

/// Cells of zero measure are refused, inverted ones reoriented.
pub(crate) fn orient_cells(
    dim: usize,
    cells: &mut [usize],
    cell_tags: &[u64],
    coords: &[[f64; 3]],
) -> Result<(), String> {
    for (c, cell) in cells.chunks_exact_mut(dim + 1).enumerate() {
        orient_cell(dim, cell, cell_tags[c], coords)?;
    }
    Ok(())
}

/// One cell of [`orient_cells`]: an error naming element `tag` if its measure is zero (or
/// nearly: |m| ≤ 1e-12 h^dim, h its longest edge) or NaN, two nodes swapped if it is inverted.
/// Also used by the distributed reader (`crate::dist`) on every rank's cells.
pub(crate) fn orient_cell(
    dim: usize,
    cell: &mut [usize],
    tag: u64,
    coords: &[[f64; 3]],
) -> Result<(), String> {
    let nc = dim + 1;
    let mut p = [[0.0; 3]; 4];
    for k in 0..nc {
        p[k] = coords[cell[k]];
    }
    let (m, h) = signed_measure(dim, &p[..nc]);
    let tol = 1e-12 * h.powi(dim as i32);
    if m.is_nan() || m.abs() <= tol {
        return Err(format!(
            "element {tag} has zero {} ({m:e}, longest edge {h:e}): degenerate cell",
            if dim == 2 { "area" } else { "volume" }
        ));
    }
    if m < 0.0 {
        cell.swap(nc - 2, nc - 1);
    }
    Ok(())
}

/// The boundary elements (facets, edges, points) into `mesh`; returns the members of every
/// physical group: (dim, physical tag) → element indices.
fn boundary_elements(
    mesh: &mut Mesh,
    elements: &mshio::Elements<u64, i32>,
    phys: &PhysicalTags,
    tag_index: &TagIndex,
    new_index: &[usize],
) -> Result<HashMap<(usize, i32), Vec<usize>>, String> {
    let dim = mesh.dim;
    let n_elements: usize = elements
        .element_blocks
        .iter()
        .map(|b| b.elements.len())
        .sum();
    // (dim, physical tag) -> element indices. An element is stored once per physical tag of
    // its entity: bound the total (a corrupt $Entities could give one entity millions of
    // physical tags and so need elements x tags of memory).
    let memberships = elements.element_blocks.iter().fold(0u128, |acc, b| {
        let n_phys = element_dim(b.element_type)
            .and_then(|d| phys.get(&(d, b.entity_tag)))
            .map_or(0, |p| p.len());
        acc + (b.elements.len() as u128) * (n_phys as u128)
    });
    let limit = 64 * (n_elements as u128) + (1 << 20);
    if memberships > limit {
        return Err(format!(
            "the elements belong to {memberships} physical groups in all (more than {limit}): \
             the $Entities section gives entities too many physical tags"
        ));
    }
    let mut members: HashMap<(usize, i32), Vec<usize>> = HashMap::new();
    let mut cell_count = 0usize;
    for b in &elements.element_blocks {
        let Some(d) = element_dim(b.element_type) else {
            continue;
        };
        let first = if d == dim {
            let f = cell_count;
            cell_count += b.elements.len();
            f
        } else {
            let (list, tags) = if d + 1 == dim {
                (&mut mesh.facets, &mut mesh.facet_tags)
            } else if d == 1 {
                (&mut mesh.edges, &mut mesh.edge_tags)
            } else {
                (&mut mesh.points, &mut mesh.point_tags)
            };
            let f = tags.len();
            for e in &b.elements {
                for &nt in &e.nodes {
                    let i = new_index[lookup(tag_index, e.element_tag, nt)?];
                    if i == usize::MAX {
                        return Err(format!(
                            "boundary element {} ({:?}) uses node {nt}, which belongs to no \
                             body cell",
                            e.element_tag, b.element_type
                        ));
                    }
                    list.push(i);
                }
                tags.push(e.element_tag);
            }
            f
        };
        if let Some(pt) = phys.get(&(d, b.entity_tag)) {
            for &t in pt.iter() {
                members
                    .entry((d, t))
                    .or_default()
                    .extend(first..first + b.elements.len());
            }
        }
    }

    Ok(members)
}

/// Every physical group of the entities and of $PhysicalNames, sorted by (dim, tag).
fn groups(
    mut members: HashMap<(usize, i32), Vec<usize>>,
    info: &raw::HeaderInfo,
    dim: usize,
) -> Vec<Group> {
    for &(d, t) in info.physical_names.keys() {
        if d <= dim {
            members.entry((d, t)).or_default();
        }
    }
    let mut groups: Vec<Group> = members
        .into_iter()
        .map(|((d, t), mut elements)| {
            if !elements.is_sorted() {
                elements.sort_unstable();
            }
            elements.dedup();
            let name = info
                .physical_names
                .get(&(d, t))
                .cloned()
                .unwrap_or_else(|| t.to_string());
            Group {
                name,
                dim: d,
                tag: t,
                elements,
            }
        })
        .collect();
    groups.sort_by_key(|g| (g.dim, g.tag));
    groups
}
