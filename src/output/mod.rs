//! XDMF + HDF5 output, written in parallel (every rank its own rows of one shared HDF5 file).
//!
//! File layout of `solution.h5` (all integers are stored as i64, which every XDMF reader
//! knows; XDMF 3 has no unsigned 64-bit type):
//!
//! | dataset              | shape        | content                                  |
//! |----------------------|--------------|------------------------------------------|
//! | /mesh/geometry       | N × 3 f64    | node coordinates                         |
//! | /mesh/topology       | M × (dim+1)  | global node numbers (rows of geometry)   |
//! | /mesh/node_id        | N            | gmsh node tags                           |
//! | /mesh/cell_id        | M            | gmsh element tags                        |
//! | /nodal/NAME          | N × ncomp    | (N when ncomp = 1)                       |
//! | /cell/NAME           | M × ncomp    |                                          |
//! | /contact/geometry    | K × 3 f64    | contact surface nodes, only when K > 0   |
//! | /contact/topology    | F × dim      | its facets: rows of /contact/geometry    |
//! | /contact/node_id     | K            | gmsh node tags                           |
//! | /contact/facet_id    | F            | gmsh element tags of the facets          |
//! | /contact/NAME        | K × ncomp    |                                          |
//!
//! A field with codes ([`Field::codes`]) is stored as i64 with a string attribute `codes`
//! saying what its values mean; every other field as f64.
//!
//! `solution.xdmf` (XDMF 3, written by rank 0) holds the one Grid "mesh", `contact.xdmf`
//! (when K > 0) the one Grid "contact" (see [`xdmf`]); `node_id`, `cell_id` and `facet_id`
//! appear there as Int attributes.
//!
//! A load history (several solutions on one mesh, [`Slot::Step`]) keeps `/mesh/*` and
//! `/contact/{geometry,topology,node_id,facet_id}` (written with the first step) and puts the
//! fields of step s (1, 2, …) under `/step_s/nodal/NAME`, `/step_s/cell/NAME`,
//! `/step_s/contact/NAME`. Each XDMF file then holds one temporal collection, one Uniform grid
//! per step with `<Time Value>` = the step's time, every step pointing at the same geometry.
//!
//! Error handling: every check that could differ between ranks is agreed on by all ranks
//! before the next collective step, so a bad piece on one rank gives the same `Err` on all
//! ranks instead of a hang. Messages name the file.

mod result_set;
mod xdmf;

pub use result_set::{ContactResult, ResultSet, SolutionFields};

pub use xdmf::{
    attribute_type, contact_series_text, contact_xdmf_text, xdmf_series_text, xdmf_text, FieldMeta,
    Meta,
};

use std::path::Path;

use hdf5::dataset::FillTime;
use hdf5::{Group, H5Type};
use mpi::collective::CommunicatorCollectives;
use mpi::raw::AsRaw;
use mpi::topology::Communicator;
use ndarray::{s, ArrayView1, ArrayView2};

/// Name of the HDF5 file inside the output directory.
pub const H5_FILE: &str = "solution.h5";
/// Disk space held beside the HDF5 file while it is written (removed afterwards): given back
/// if the disk fills, so that the file's metadata can still be written at its close.
const RESERVE_FILE: &str = ".reserve";
const RESERVE_BYTES: usize = 32 * 1024;
/// Name of the XDMF file inside the output directory.
pub const XDMF_FILE: &str = "solution.xdmf";
/// Name of the contact surface's XDMF file inside the output directory (its data is in
/// [`H5_FILE`] under `/contact`).
pub const CONTACT_XDMF_FILE: &str = "contact.xdmf";

/// An owned field, as the stages above produce it ([`FieldBuf::view`] lends it to a [`Piece`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FieldBuf {
    pub name: &'static str,
    pub ncomp: usize,
    pub data: Vec<f64>,
    /// An integer field: what its values mean (see [`Field::codes`]).
    pub codes: Option<&'static str>,
}

impl FieldBuf {
    /// A float field.
    pub fn float(name: &'static str, ncomp: usize, data: Vec<f64>) -> FieldBuf {
        FieldBuf {
            name,
            ncomp,
            data,
            codes: None,
        }
    }

    pub fn view(&self) -> Field<'_> {
        Field {
            name: self.name,
            ncomp: self.ncomp,
            data: &self.data,
            codes: self.codes,
        }
    }
}

/// One field: `ncomp` values per owned node / cell / contact node, row-major.
#[derive(Debug, Clone, Copy)]
pub struct Field<'a> {
    pub name: &'a str,
    pub ncomp: usize,
    pub data: &'a [f64],
    /// `Some(meaning)`: an integer field (its values, whole numbers, are written as i64) and
    /// what they mean, e.g. "0 open, 1 in contact" (the `codes` attribute of its dataset and a
    /// comment in the XDMF file). `None`: a float field.
    pub codes: Option<&'a str>,
}

/// What one rank contributes. Nodes and cells are numbered globally and contiguously by rank:
/// rank r owns nodes `node_offset .. node_offset + coords.len()` and cells likewise.
#[derive(Debug, Clone)]
pub struct Piece<'a> {
    /// 2 (triangles) or 3 (tetrahedra).
    pub dim: usize,
    pub n_nodes_global: usize,
    pub node_offset: usize,
    /// Owned nodes (z = 0 in 2D).
    pub coords: &'a [[f64; 3]],
    /// Gmsh node tag of each owned node.
    pub node_ids: &'a [u64],
    pub n_cells_global: usize,
    pub cell_offset: usize,
    /// `dim + 1` GLOBAL node numbers per owned cell.
    pub connectivity: &'a [usize],
    /// Gmsh element tag of each owned cell.
    pub cell_ids: &'a [u64],
    /// E.g. displacement, ncomp 3 (2D padded with 0).
    pub nodal: Vec<Field<'a>>,
    /// E.g. stress ncomp 9, von_mises 1, rank 1.
    pub cellwise: Vec<Field<'a>>,
    pub contact: Option<ContactPiece<'a>>,
}

/// The contact surface as its own grid ("contact"): nodes numbered globally and contiguously
/// by rank like the mesh's, and facets (`dim` nodes each: lines in 2D, triangles in 3D).
#[derive(Debug, Clone)]
pub struct ContactPiece<'a> {
    pub n_global: usize,
    pub offset: usize,
    pub coords: &'a [[f64; 3]],
    pub node_ids: &'a [u64],
    pub n_facets_global: usize,
    pub facet_offset: usize,
    /// `dim` GLOBAL surface node numbers (rows of the contact geometry) per owned facet.
    pub facets: &'a [usize],
    /// Gmsh element tag of each owned facet.
    pub facet_ids: &'a [u64],
    pub fields: Vec<Field<'a>>,
}

impl Piece<'_> {
    /// Global description of the output as this rank sees it (must agree on all ranks).
    pub fn meta(&self) -> Meta {
        let fm = |v: &[Field]| {
            v.iter()
                .map(|f| FieldMeta {
                    name: f.name.to_string(),
                    ncomp: f.ncomp,
                    codes: f.codes.map(str::to_string),
                })
                .collect()
        };
        Meta {
            dim: self.dim,
            n_nodes: self.n_nodes_global,
            n_cells: self.n_cells_global,
            nodal: fm(&self.nodal),
            cellwise: fm(&self.cellwise),
            n_contact: self.contact.as_ref().map_or(0, |c| c.n_global),
            n_contact_facets: self
                .contact
                .as_ref()
                .filter(|c| c.n_global > 0)
                .map_or(0, |c| c.n_facets_global),
            contact: self
                .contact
                .as_ref()
                .filter(|c| c.n_global > 0)
                .map_or_else(Vec::new, |c| fm(&c.fields)),
        }
    }

    /// Local consistency of this rank's piece (lengths, ranges, names). No communication.
    pub fn validate(&self) -> Result<(), String> {
        if self.dim != 2 && self.dim != 3 {
            return Err(format!("dimension must be 2 or 3, got {}", self.dim));
        }
        let n = self.coords.len();
        check_ids(self.node_ids.len(), "node ids", n, "owned nodes")?;
        check_block(
            "owned nodes",
            self.node_offset,
            n,
            self.n_nodes_global,
            "node",
        )?;
        let m = self.cell_ids.len();
        let npe = self.dim + 1;
        if self.connectivity.len() != m * npe {
            return Err(format!(
                "connectivity has {} entries, expected {} cells × {npe}",
                self.connectivity.len(),
                m
            ));
        }
        check_block(
            "owned cells",
            self.cell_offset,
            m,
            self.n_cells_global,
            "cell",
        )?;
        if let Some(&bad) = self
            .connectivity
            .iter()
            .find(|&&v| v >= self.n_nodes_global)
        {
            return Err(format!(
                "connectivity refers to node {bad}, but there are only {} nodes",
                self.n_nodes_global
            ));
        }
        check_fields("nodal", &self.nodal, n, &["node_id"])?;
        check_fields("cell", &self.cellwise, m, &["cell_id"])?;
        match &self.contact {
            Some(c) => c.validate(self.dim),
            None => Ok(()),
        }
    }
}

impl ContactPiece<'_> {
    /// Local consistency of this rank's contact surface (`dim`: the mesh's).
    fn validate(&self, dim: usize) -> Result<(), String> {
        let k = self.coords.len();
        check_ids(self.node_ids.len(), "contact node ids", k, "contact nodes")?;
        check_block("contact nodes", self.offset, k, self.n_global, "contact")?;
        let nf = self.facet_ids.len();
        if self.facets.len() != nf * dim {
            return Err(format!(
                "contact facets have {} entries, expected {nf} facets × {dim}",
                self.facets.len(),
            ));
        }
        let facets = self.n_facets_global;
        check_block("contact facets", self.facet_offset, nf, facets, "facet")?;
        if let Some(&bad) = self.facets.iter().find(|&&v| v >= self.n_global) {
            return Err(format!(
                "a contact facet refers to node {bad}, but the contact surface has only {} \
                 nodes",
                self.n_global
            ));
        }
        check_fields(
            "contact",
            &self.fields,
            k,
            &["node_id", "facet_id", "geometry", "topology"],
        )
    }
}

/// As many ids (`ids` of them, named `what_ids`) as items (`n`, named `what`).
fn check_ids(ids: usize, what_ids: &str, n: usize, what: &str) -> Result<(), String> {
    if ids != n {
        return Err(format!("{ids} {what_ids} for {n} {what}"));
    }
    Ok(())
}

/// An owned block `offset .. offset + count` (of `what`) within the global count `global` (of
/// `name`s, for the message).
fn check_block(
    what: &str,
    offset: usize,
    count: usize,
    global: usize,
    name: &str,
) -> Result<(), String> {
    if offset + count > global {
        return Err(format!(
            "{what} {offset}..{} exceed the global {name} count {global}",
            offset + count
        ));
    }
    Ok(())
}

/// Field names become HDF5 link names and XML attribute values: keep them plain.
fn check_name(kind: &str, name: &str, reserved: &[&str]) -> Result<(), String> {
    let ok_chars = name
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.');
    if name.is_empty() || !ok_chars || name.starts_with('.') {
        return Err(format!(
            "{kind} field name '{name}' must be non-empty, made of ASCII letters, digits, \
             '_', '-', '.' and not start with '.'"
        ));
    }
    if reserved.contains(&name) {
        return Err(format!("{kind} field name '{name}' is reserved"));
    }
    Ok(())
}

fn check_fields(
    kind: &str,
    fields: &[Field],
    rows: usize,
    reserved: &[&str],
) -> Result<(), String> {
    for (i, f) in fields.iter().enumerate() {
        check_name(kind, f.name, reserved)?;
        if fields[..i].iter().any(|g| g.name == f.name) {
            return Err(format!("{kind} field '{}' given twice", f.name));
        }
        if f.ncomp == 0 {
            return Err(format!("{kind} field '{}' has 0 components", f.name));
        }
        if let Some(bad) = f
            .codes
            .and_then(|_| f.data.iter().find(|&&v| v.fract() != 0.0 || !v.is_finite()))
        {
            return Err(format!(
                "{kind} field '{}' holds integer codes, but has the value {bad}",
                f.name
            ));
        }
        if f.data.len() != rows * f.ncomp {
            return Err(format!(
                "{kind} field '{}' has {} values, expected {rows} × {}",
                f.name,
                f.data.len(),
                f.ncomp
            ));
        }
    }
    Ok(())
}

/// The owned blocks (offset, count) of all ranks must tile 0..global without gaps or overlaps.
fn check_tiling(kind: &str, blocks: &mut [(u64, u64)], global: u64) -> Result<(), String> {
    blocks.sort_unstable();
    let mut next = 0u64;
    for &(off, cnt) in blocks.iter().filter(|b| b.1 > 0) {
        if off != next {
            return Err(format!(
                "the {kind} blocks of the ranks do not tile 0..{global}: expected a block at \
                 {next}, found one at {off}"
            ));
        }
        next = off + cnt;
    }
    if next != global {
        return Err(format!(
            "the ranks own {next} {kind} in total, but the global count is {global}"
        ));
    }
    Ok(())
}

/// All ranks learn whether any rank failed; the message of the lowest failing rank is returned
/// on every rank. Collective.
fn agree<C: Communicator>(comm: &C, local: Result<(), String>) -> Result<(), String> {
    match crate::par::first_error(comm, local.err()) {
        None => Ok(()),
        Some((first, msg)) if comm.size() > 1 => Err(format!("(rank {first}) {msg}")),
        Some((_, msg)) => Err(msg),
    }
}

/// Creates datasets (collective) and writes this rank's rows (independent).
struct Writer<'f> {
    path: &'f str,
    /// First error of an independent write on this rank; reported after the file is closed.
    local_err: Option<String>,
}

impl Writer<'_> {
    /// Collective: create `group/name` of `rows × ncomp` (1-D if ncomp = 1) with file type
    /// `F`, then write `data` (this rank's rows from `offset`) converting from `T` if needed.
    #[allow(clippy::too_many_arguments)]
    fn rows<F: H5Type, T: H5Type>(
        &mut self,
        group: &Group,
        name: &str,
        rows: usize,
        ncomp: usize,
        offset: usize,
        data: &[T],
    ) -> Result<hdf5::Dataset, String> {
        let builder = group.new_dataset::<F>().fill_time(FillTime::Never);
        let ds = if ncomp == 1 {
            builder.shape([rows]).create(name)
        } else {
            builder.shape([rows, ncomp]).create(name)
        }
        .map_err(|e| {
            format!(
                "{}: cannot create dataset {}/{name}: {e}",
                self.path,
                group.name()
            )
        })?;
        let local = data.len() / ncomp;
        if local == 0 || self.local_err.is_some() {
            return Ok(ds);
        }
        let res = if ncomp == 1 {
            ArrayView1::from(data)
                .into_shape_with_order(local)
                .map_or_else(
                    |e| Err(e.to_string()),
                    |v| {
                        ds.write_slice(v, s![offset..offset + local])
                            .map_err(|e| e.to_string())
                    },
                )
        } else {
            ArrayView2::from_shape((local, ncomp), data).map_or_else(
                |e| Err(e.to_string()),
                |v: ArrayView2<T>| {
                    ds.write_slice(v, s![offset..offset + local, ..])
                        .map_err(|e| e.to_string())
                },
            )
        };
        if let Err(e) = res {
            self.local_err = Some(format!(
                "{}: writing rows {offset}..{} of {}/{name} failed: {e}",
                self.path,
                offset + local,
                group.name()
            ));
        }
        Ok(ds)
    }

    /// Collective: a field's dataset (`rows` × its components from `offset`): f64, or i64
    /// with the string attribute `codes` for a field with codes.
    fn field(
        &mut self,
        group: &Group,
        f: &Field,
        rows: usize,
        offset: usize,
    ) -> Result<(), String> {
        let Some(codes) = f.codes else {
            self.rows::<f64, f64>(group, f.name, rows, f.ncomp, offset, f.data)?;
            return Ok(());
        };
        // whole numbers (validated)
        let ints: Vec<i64> = f.data.iter().map(|&v| v as i64).collect();
        let ds = self.rows::<i64, i64>(group, f.name, rows, f.ncomp, offset, &ints)?;
        let text: hdf5::types::VarLenUnicode = codes.parse().map_err(|e| {
            format!(
                "{}: the codes of {}/{} are not text HDF5 takes: {e}",
                self.path,
                group.name(),
                f.name
            )
        })?;
        ds.new_attr::<hdf5::types::VarLenUnicode>()
            .create("codes")
            .and_then(|a| a.write_scalar(&text))
            .map_err(|e| {
                format!(
                    "{}: cannot write the attribute codes of {}/{}: {e}",
                    self.path,
                    group.name(),
                    f.name
                )
            })
    }
}

fn create_group(parent: &Group, path: &str, name: &str) -> Result<Group, String> {
    parent.create_group(name).map_err(|e| {
        let at = parent.name();
        let sep = if at.ends_with('/') { "" } else { "/" };
        format!("{path}: cannot create group {at}{sep}{name}: {e}")
    })
}

/// Where a piece goes in `solution.h5`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slot {
    /// One solution: `/mesh`, `/nodal`, `/cell`, `/contact` in a new file.
    Static,
    /// Step `index` (1, 2, …) of a load history: step 1 creates the file with the mesh and the
    /// contact geometry, every step adds `/step_{index}/{nodal,cell,contact}`.
    Step { index: usize },
}

impl Slot {
    /// True when this piece creates the file and writes the mesh.
    fn creates(self) -> bool {
        matches!(self, Slot::Static | Slot::Step { index: 1 })
    }
}

/// All datasets of the HDF5 file, in the same order on every rank. Returns the collective
/// (same on all ranks) error, if any; independent write errors go to `w.local_err`.
fn write_datasets(
    file: &hdf5::File,
    w: &mut Writer,
    p: &Piece,
    meta: &Meta,
    slot: Slot,
) -> Result<(), String> {
    let path = w.path;
    let n = meta.n_nodes;
    let m = meta.n_cells;
    let npe = meta.dim + 1;
    // validated and agreed: every rank has Some(contact) when n_contact > 0
    let contact = match &p.contact {
        Some(c) if meta.n_contact > 0 => Some(c),
        None if meta.n_contact > 0 => {
            return Err(format!("{path}: contact piece missing on this rank"))
        }
        _ => None,
    };

    if slot.creates() {
        let mesh = create_group(file, path, "mesh")?;
        w.rows::<f64, f64>(
            &mesh,
            "geometry",
            n,
            3,
            p.node_offset,
            p.coords.as_flattened(),
        )?;
        w.rows::<i64, usize>(&mesh, "topology", m, npe, p.cell_offset, p.connectivity)?;
        w.rows::<i64, u64>(&mesh, "node_id", n, 1, p.node_offset, p.node_ids)?;
        w.rows::<i64, u64>(&mesh, "cell_id", m, 1, p.cell_offset, p.cell_ids)?;
    }
    let step = match slot {
        Slot::Static => None,
        Slot::Step { index } => Some(create_group(file, path, &format!("step_{index}"))?),
    };
    let root: &Group = step.as_ref().unwrap_or(file);

    let nodal = create_group(root, path, "nodal")?;
    for f in &p.nodal {
        w.field(&nodal, f, n, p.node_offset)?;
    }
    drop(nodal);

    let cell = create_group(root, path, "cell")?;
    for f in &p.cellwise {
        w.field(&cell, f, m, p.cell_offset)?;
    }
    drop(cell);

    if let Some(c) = contact {
        let k = meta.n_contact;
        let fields_group = if slot.creates() {
            let g = create_group(file, path, "contact")?;
            let (nf, d) = (meta.n_contact_facets, meta.dim);
            w.rows::<f64, f64>(&g, "geometry", k, 3, c.offset, c.coords.as_flattened())?;
            w.rows::<i64, usize>(&g, "topology", nf, d, c.facet_offset, c.facets)?;
            w.rows::<i64, u64>(&g, "node_id", k, 1, c.offset, c.node_ids)?;
            w.rows::<i64, u64>(&g, "facet_id", nf, 1, c.facet_offset, c.facet_ids)?;
            match step {
                None => g,
                Some(_) => create_group(root, path, "contact")?,
            }
        } else {
            create_group(root, path, "contact")?
        };
        for f in &c.fields {
            w.field(&fields_group, f, k, c.offset)?;
        }
    }
    Ok(())
}

/// Bytes `solution.h5` takes (`with_mesh`), or a step adds to it: its datasets exactly (every
/// value 8 bytes), plus room for the metadata (superblock, groups, object headers: measured
/// ~1 KiB per dataset).
fn file_bytes(meta: &Meta, with_mesh: bool) -> u64 {
    let (n, m, k) = (
        meta.n_nodes as u64,
        meta.n_cells as u64,
        meta.n_contact as u64,
    );
    let comps = |v: &[FieldMeta]| v.iter().map(|f| f.ncomp as u64).sum::<u64>();
    let mut values = n * comps(&meta.nodal) + m * comps(&meta.cellwise);
    let mut datasets = meta.nodal.len() + meta.cellwise.len();
    if with_mesh {
        values += n * (3 + 1) + m * (meta.dim as u64 + 1 + 1);
        datasets += 4;
    }
    if k > 0 {
        values += k * comps(&meta.contact);
        datasets += meta.contact.len();
        if with_mesh {
            let f = meta.n_contact_facets as u64;
            values += k * (3 + 1) + f * (meta.dim as u64 + 1);
            datasets += 4;
        }
    }
    // an integer field's attribute `codes`: its text and its header
    let codes = |v: &[FieldMeta]| {
        v.iter()
            .filter_map(|f| f.codes.as_ref().map(|c| c.len() as u64 + 512))
            .sum::<u64>()
    };
    let mut attrs = codes(&meta.nodal) + codes(&meta.cellwise);
    if k > 0 {
        attrs += codes(&meta.contact);
    }
    8 * values + 16 * 1024 + 2048 * datasets as u64 + attrs
}

/// Allocates the disk blocks of `path` up to `bytes` without changing its size or contents
/// (fallocate, KEEP_SIZE). A file system that cannot do this is left to the writes.
fn preallocate(path: &Path, bytes: u64) -> std::io::Result<()> {
    use rustix::fs::{fallocate, FallocateFlags};
    let f = std::fs::OpenOptions::new().write(true).open(path)?;
    match fallocate(&f, FallocateFlags::KEEP_SIZE, 0, bytes) {
        Ok(()) => Ok(()),
        Err(e) if e == rustix::io::Errno::OPNOTSUPP || e == rustix::io::Errno::NOSYS => Ok(()),
        Err(e) => Err(e.into()),
    }
}

/// Gives back the blocks reserved beyond the end of the written file (a file system keeps
/// them until the file is shortened: lengthen by one byte, shorten back).
fn release_unused(path: &Path) {
    if let Ok(f) = std::fs::OpenOptions::new().write(true).open(path) {
        if let Ok(len) = f.metadata().map(|m| m.len()) {
            let _ = f.set_len(len + 1).and_then(|()| f.set_len(len));
        }
    }
}

/// Collective over `comm`: writes `dir/solution.h5` (all ranks, MPI-IO) and
/// `dir/solution.xdmf` and, with a contact surface, `dir/contact.xdmf` (rank 0). `dir` must exist. Returns the same `Err` on every rank if
/// any rank's piece is inconsistent or any write fails.
pub fn write_xdmf_hdf5<C>(comm: &C, dir: &Path, piece: &Piece) -> Result<(), String>
where
    C: Communicator + AsRaw<Raw = mpi::ffi::MPI_Comm>,
{
    write_piece(comm, dir, piece, Slot::Static, |meta| {
        Some((xdmf_text(meta, H5_FILE), contact_xdmf_text(meta, H5_FILE)))
    })
    .map(drop)
}

/// Collective over `comm`: step `index` (1, 2, …; step 1 creates the file) of a load history
/// into `dir/solution.h5`. Every step's piece must describe the same mesh and fields. Returns
/// the description the series' XDMF files are made of ([`write_series_xdmf`], once, when the
/// history ends: rewriting them at every step made a history of n steps write O(n²) bytes —
/// 2.2 GB over 1 000 steps of a mesh of 8 unknowns, 5.7 s of its 6.3). The same `Err` on every
/// rank.
pub fn write_step_hdf5<C>(comm: &C, dir: &Path, piece: &Piece, index: usize) -> Result<Meta, String>
where
    C: Communicator + AsRaw<Raw = mpi::ffi::MPI_Comm>,
{
    write_piece(comm, dir, piece, Slot::Step { index }, |_| None)
}

/// `dir/solution.xdmf` (and, with a contact surface, `dir/contact.xdmf`) as the temporal
/// collection of the steps of `meta` written by [`write_step_hdf5`], `times[s − 1]` being the
/// time (load factor) of step s. Local (rank 0 calls it).
pub fn write_series_xdmf(dir: &Path, meta: &Meta, times: &[f64]) -> std::io::Result<()> {
    std::fs::write(dir.join(XDMF_FILE), xdmf_series_text(meta, H5_FILE, times))?;
    if let Some(text) = contact_series_text(meta, H5_FILE, times) {
        std::fs::write(dir.join(CONTACT_XDMF_FILE), text)?;
    }
    Ok(())
}

/// The common body of [`write_xdmf_hdf5`] and [`write_step_hdf5`]: checks, the HDF5 data
/// into `slot`, then the XDMF texts `xdmf` makes of the description (solution.xdmf and, if
/// any, contact.xdmf; none where it gives `None`). Returns the description.
fn write_piece<C>(
    comm: &C,
    dir: &Path,
    piece: &Piece,
    slot: Slot,
    xdmf: impl FnOnce(&Meta) -> Option<(String, Option<String>)>,
) -> Result<Meta, String>
where
    C: Communicator + AsRaw<Raw = mpi::ffi::MPI_Comm>,
{
    let h5_path = dir.join(H5_FILE);
    let xdmf_path = dir.join(XDMF_FILE);
    let h5_name = h5_path.display().to_string();

    // 1. Same global description everywhere, valid local piece, blocks tile the global ranges.
    let meta = piece.meta();
    check_piece(comm, piece, &meta, &h5_name)?;

    // 2. The shared HDF5 file (creation, dataset creation and close are collective), with a
    //    reserve of disk space beside it that a failed write gives back for the close.
    let reserve_path = dir.join(RESERVE_FILE);
    let file = open_h5(comm, &h5_path, &h5_name, &reserve_path, &meta, slot)?;
    let mut w = Writer {
        path: &h5_name,
        local_err: None,
    };
    let collective = write_datasets(&file, &mut w, piece, &meta, slot);
    let closed = file
        .close()
        .map_err(|e| format!("{h5_name}: closing failed: {e}"));
    if comm.rank() == 0 {
        let _ = std::fs::remove_file(&reserve_path);
        if closed.is_ok() {
            release_unused(&h5_path);
        }
    }
    let mut local = collective.and(closed);
    if local.is_ok() {
        if let Some(e) = w.local_err.take() {
            local = Err(e);
        }
    }

    // 3. The XDMF description (rank 0), after the data it points to is complete.
    if comm.rank() == 0 && local.is_ok() {
        if let Some((text, contact_text)) = xdmf(&meta) {
            let contact_path = dir.join(CONTACT_XDMF_FILE);
            for (path, text) in [(&xdmf_path, Some(text)), (&contact_path, contact_text)] {
                if let Some(text) = text {
                    if let Err(e) = std::fs::write(path, text) {
                        local = Err(format!("{}: cannot write: {e}", path.display()));
                        break;
                    }
                }
            }
        }
    }
    agree(comm, local).map(|()| meta)
}

/// Step 1 of [`write_piece`]: the same global description on every rank, a valid local piece,
/// and the ranks' blocks tiling the global ranges. Collective; the same `Err` on every rank.
fn check_piece<C>(comm: &C, piece: &Piece, meta: &Meta, h5_name: &str) -> Result<(), String>
where
    C: Communicator,
{
    let sig = meta.signature();
    let sig0 = crate::par::broadcast_string(comm, 0, &sig);
    let mut local = piece.validate();
    if local.is_ok() && sig != sig0 {
        local = Err(format!(
            "output description differs from rank 0: '{sig}' vs '{sig0}'"
        ));
    }
    let contact = piece.contact.as_ref();
    let mine: [u64; 8] = [
        piece.node_offset as u64,
        piece.coords.len() as u64,
        piece.cell_offset as u64,
        piece.cell_ids.len() as u64,
        contact.map_or(0, |c| c.offset as u64),
        contact.map_or(0, |c| c.coords.len() as u64),
        contact.map_or(0, |c| c.facet_offset as u64),
        contact.map_or(0, |c| c.facet_ids.len() as u64),
    ];
    let mut all = vec![0u64; 8 * comm.size() as usize];
    comm.all_gather_into(&mine[..], &mut all[..]);
    if local.is_ok() {
        let blocks = |j: usize| -> Vec<(u64, u64)> {
            all.chunks_exact(8).map(|r| (r[j], r[j + 1])).collect()
        };
        local = check_tiling("nodes", &mut blocks(0), meta.n_nodes as u64)
            .and_then(|()| check_tiling("cells", &mut blocks(2), meta.n_cells as u64))
            .and_then(|()| check_tiling("contact nodes", &mut blocks(4), meta.n_contact as u64))
            .and_then(|()| {
                check_tiling(
                    "contact facets",
                    &mut blocks(6),
                    meta.n_contact_facets as u64,
                )
            });
    }
    agree(comm, local.map_err(|e| format!("{h5_name}: {e}")))
}

/// Step 2 of [`write_piece`]: the reserve beside the HDF5 file, then the file created (or, for
/// a later step, opened) and its disk space reserved for the data of `meta`. Collective; the
/// same `Err` on every rank, with the reserve removed.
fn open_h5<C>(
    comm: &C,
    h5_path: &Path,
    h5_name: &str,
    reserve_path: &Path,
    meta: &Meta,
    slot: Slot,
) -> Result<hdf5::File, String>
where
    C: Communicator + AsRaw<Raw = mpi::ffi::MPI_Comm>,
{
    let reserved = if comm.rank() == 0 {
        std::fs::write(reserve_path, vec![0u8; RESERVE_BYTES]).map_err(|e| {
            format!("{h5_name}: cannot create: {e} (reserving {RESERVE_BYTES} bytes beside it)")
        })
    } else {
        Ok(())
    };
    if let Err(e) = agree(comm, reserved) {
        remove_reserve(comm, reserve_path);
        return Err(e);
    }
    let mut builder = hdf5::File::with_options();
    let builder = builder.with_fapl(|p| p.mpio(comm.as_raw(), None));
    // What the file holds already (a later step of a history appends to it).
    let mut before = 0;
    let created = if slot.creates() {
        builder
            .create(h5_path)
            .map_err(|e| format!("{h5_name}: cannot create: {e}"))
    } else {
        before = std::fs::metadata(h5_path).map_or(0, |m| m.len());
        builder
            .open_rw(h5_path)
            .map_err(|e| format!("{h5_name}: cannot open to add step {slot:?}: {e}"))
    };
    match created {
        Ok(f) => {
            agree(comm, Ok(()))?;
            // Reserve the file's disk space before any of it is written. A full disk found
            // by HDF5 itself cannot be reported cleanly: the OMPIO writes report nothing, the
            // flush at the close fails and leaves HDF5 1.10 with a half-destroyed file under
            // a live id, and the library's shutdown inside MPI_Finalize then crashes
            // (segfault after the error line). Here the file is still empty: give the reserve
            // back, close it (its first metadata fits) and stop with the reason.
            let need = before + file_bytes(meta, slot.creates());
            let reserved = if comm.rank() == 0 {
                preallocate(h5_path, need).map_err(|e| {
                    format!(
                        "{h5_name}: cannot reserve {need} bytes for the results ({e}): not \
                         enough free disk space?"
                    )
                })
            } else {
                Ok(())
            };
            if let Err(e) = agree(comm, reserved) {
                if comm.rank() == 0 {
                    // A partial reservation (some file systems keep it) and the reserve go.
                    release_unused(h5_path);
                    let _ = std::fs::remove_file(reserve_path);
                }
                let _ = f.close();
                return Err(e);
            }
            Ok(f)
        }
        Err(e) => {
            // Every rank returns here (MPI_File_open is collective, so it fails everywhere).
            remove_reserve(comm, reserve_path);
            agree(comm, Err(e.clone()))?;
            Err(e)
        }
    }
}

/// Rank 0 removes the reserve beside the HDF5 file (what is left of it, if anything).
fn remove_reserve<C: Communicator>(comm: &C, reserve_path: &Path) {
    if comm.rank() == 0 {
        let _ = std::fs::remove_file(reserve_path);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn piece<'a>(
        coords: &'a [[f64; 3]],
        ids: &'a [u64],
        conn: &'a [usize],
        cids: &'a [u64],
    ) -> Piece<'a> {
        Piece {
            dim: 2,
            n_nodes_global: coords.len(),
            node_offset: 0,
            coords,
            node_ids: ids,
            n_cells_global: cids.len(),
            cell_offset: 0,
            connectivity: conn,
            cell_ids: cids,
            nodal: vec![],
            cellwise: vec![],
            contact: None,
        }
    }

    const C: [[f64; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ];

    #[test]
    fn validate_accepts_consistent_piece() {
        let d = [0.0; 8];
        let mut p = piece(&C, &[1, 2, 3, 4], &[0, 1, 2, 1, 3, 2], &[7, 8]);
        p.nodal.push(Field {
            name: "u",
            ncomp: 2,
            data: &d,
            codes: None,
        });
        assert_eq!(p.validate(), Ok(()));
    }

    #[test]
    fn validate_rejects_bad_pieces() {
        let ids = [1, 2, 3, 4];
        let conn = [0, 1, 2, 1, 3, 2];
        // wrong connectivity length
        assert!(piece(&C, &ids, &conn[..5], &[7, 8]).validate().is_err());
        // node number out of range
        assert!(piece(&C, &ids, &[0, 1, 2, 1, 4, 2], &[7, 8])
            .validate()
            .unwrap_err()
            .contains("node 4"));
        // ids count
        assert!(piece(&C, &ids[..3], &conn, &[7, 8]).validate().is_err());
        // dim
        let mut p = piece(&C, &ids, &conn, &[7, 8]);
        p.dim = 4;
        assert!(p.validate().is_err());
        // field length, bad name, reserved name, duplicate, ncomp 0
        let d = [0.0; 8];
        for (name, ncomp, len) in [
            ("u", 3, 8),
            ("a/b", 2, 8),
            ("x:y", 2, 8),
            ("", 2, 8),
            ("node_id", 2, 8),
            ("u", 0, 0),
        ] {
            let mut p = piece(&C, &ids, &conn, &[7, 8]);
            p.nodal.push(Field {
                name,
                ncomp,
                data: &d[..len],
                codes: None,
            });
            assert!(p.validate().is_err(), "{name} {ncomp} {len}");
        }
        let mut p = piece(&C, &ids, &conn, &[7, 8]);
        for _ in 0..2 {
            p.nodal.push(Field {
                name: "u",
                ncomp: 2,
                data: &d,
                codes: None,
            });
        }
        assert!(p.validate().unwrap_err().contains("twice"));
        // offsets beyond the global count
        let mut p = piece(&C, &ids, &conn, &[7, 8]);
        p.node_offset = 1;
        assert!(p.validate().is_err());
    }

    #[test]
    fn validate_checks_codes_and_contact_facets() {
        let ids = [1, 2, 3, 4];
        let conn = [0, 1, 2, 1, 3, 2];
        let mut p = piece(&C, &ids, &conn, &[7, 8]);
        let ok = [1.0, 0.0, -1.0, 2.0];
        let bad = [1.0, 0.5, -1.0, 2.0];
        let nan = [1.0, f64::NAN, -1.0, 2.0];
        for (data, good) in [(&ok, true), (&bad, false), (&nan, false)] {
            p.nodal = vec![Field {
                name: "state",
                ncomp: 1,
                data,
                codes: Some("codes"),
            }];
            assert_eq!(p.validate().is_ok(), good, "{data:?}");
        }
        p.nodal.clear();
        let xs = [C[0], C[1]];
        let contact = |facets: &'static [usize], facet_ids: &'static [u64]| ContactPiece {
            n_global: 2,
            offset: 0,
            coords: &xs,
            node_ids: &[1, 2],
            n_facets_global: facet_ids.len(),
            facet_offset: 0,
            facets,
            facet_ids,
            fields: vec![],
        };
        p.contact = Some(contact(&[0, 1], &[9]));
        assert_eq!(p.validate(), Ok(()));
        assert_eq!(p.meta().n_contact_facets, 1);
        p.contact = Some(contact(&[0, 2], &[9]));
        assert!(p.validate().unwrap_err().contains("node 2"));
        p.contact = Some(contact(&[0, 1, 1], &[9]));
        assert!(p.validate().is_err());
    }

    #[test]
    fn tiling() {
        assert!(check_tiling("nodes", &mut [(3, 2), (0, 3)], 5).is_ok());
        assert!(check_tiling("nodes", &mut [(0, 3), (99, 0), (3, 2)], 5).is_ok());
        assert!(check_tiling("nodes", &mut [(0, 3), (2, 3)], 5).is_err());
        assert!(check_tiling("nodes", &mut [(0, 3), (4, 1)], 5).is_err());
        assert!(check_tiling("nodes", &mut [(0, 3)], 5).is_err());
        assert!(check_tiling("nodes", &mut [(0, 0)], 0).is_ok());
    }

    #[test]
    fn meta_drops_empty_contact_fields() {
        let d = [0.0; 0];
        let mut p = piece(&C, &[1, 2, 3, 4], &[0, 1, 2, 1, 3, 2], &[7, 8]);
        p.contact = Some(ContactPiece {
            n_global: 0,
            offset: 0,
            coords: &[],
            node_ids: &[],
            n_facets_global: 0,
            facet_offset: 0,
            facets: &[],
            facet_ids: &[],
            fields: vec![Field {
                name: "gap",
                ncomp: 1,
                data: &d,
                codes: None,
            }],
        });
        let m = p.meta();
        assert_eq!(m.n_contact, 0);
        assert!(m.contact.is_empty());
    }
}
