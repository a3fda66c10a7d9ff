//! The result set of a run: written into a staging directory next to the output directory and
//! put in place as a whole at the end, so the output directory holds exactly what one run wrote
//! (or, if the run fails, what was there before). Knows nothing of contact: the contact
//! surface and its table arrive as plain grid, fields and text.

use super::{
    write_series_xdmf, write_step_hdf5, write_xdmf_hdf5, ContactPiece, Field, FieldBuf, Meta,
    Piece, CONTACT_XDMF_FILE, XDMF_FILE,
};
use crate::error::{InputError, RunError};
use crate::par::Ctx;
use crate::say;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Name of the run summary inside the output directory.
pub const SUMMARY_FILE: &str = "summary.json";
/// Name of the contact-node table inside the output directory.
pub const CONTACT_CSV: &str = "contact_nodes.csv";

/// Name of the table of load steps inside the output directory (a run with `[load]`).
pub const HISTORY_CSV: &str = "history.csv";

/// Every file a run may write into the output directory.
pub const RESULT_FILES: &[&str] = &[
    super::H5_FILE,
    XDMF_FILE,
    CONTACT_XDMF_FILE,
    SUMMARY_FILE,
    CONTACT_CSV,
    HISTORY_CSV,
];

/// This rank's part of the mesh and its fields, owned.
pub struct SolutionFields {
    pub dim: usize,
    pub n_nodes_global: usize,
    pub node_offset: usize,
    pub coords: Vec<[f64; 3]>,
    pub node_ids: Vec<u64>,
    pub n_cells_global: usize,
    pub cell_offset: usize,
    pub connectivity: Vec<usize>,
    pub cell_ids: Vec<u64>,
    pub nodal: Vec<FieldBuf>,
    pub cellwise: Vec<FieldBuf>,
}

/// This rank's part of the contact surface (its nodes and facets, numbered globally like
/// [`ContactPiece`]'s) with the fields on its nodes, and the whole table of the contact nodes
/// (CSV text, the same on every rank).
pub struct ContactResult {
    pub n_global: usize,
    pub offset: usize,
    pub coords: Vec<[f64; 3]>,
    pub node_ids: Vec<u64>,
    pub n_facets_global: usize,
    pub facet_offset: usize,
    /// `dim` global surface node numbers per owned facet.
    pub facets: Vec<usize>,
    pub facet_ids: Vec<u64>,
    pub fields: Vec<FieldBuf>,
    pub csv: String,
}

fn views(v: &[FieldBuf]) -> Vec<Field<'_>> {
    v.iter().map(FieldBuf::view).collect()
}

impl SolutionFields {
    /// The piece the writer takes; the contact grid only if given.
    pub fn piece<'a>(&'a self, contact: Option<&'a ContactResult>) -> Piece<'a> {
        Piece {
            dim: self.dim,
            n_nodes_global: self.n_nodes_global,
            node_offset: self.node_offset,
            coords: &self.coords,
            node_ids: &self.node_ids,
            n_cells_global: self.n_cells_global,
            cell_offset: self.cell_offset,
            connectivity: &self.connectivity,
            cell_ids: &self.cell_ids,
            nodal: views(&self.nodal),
            cellwise: views(&self.cellwise),
            contact: contact.map(|c| ContactPiece {
                n_global: c.n_global,
                offset: c.offset,
                coords: &c.coords,
                node_ids: &c.node_ids,
                n_facets_global: c.n_facets_global,
                facet_offset: c.facet_offset,
                facets: &c.facets,
                facet_ids: &c.facet_ids,
                fields: views(&c.fields),
            }),
        }
    }
}

/// An output directory being written.
pub struct ResultSet {
    /// The output directory as the case gives it (for messages).
    dir: PathBuf,
    /// The directory the results go to ([`target_dir`]).
    target: PathBuf,
    staging: PathBuf,
    committed: bool,
    rank: usize,
    /// A load history's description and times so far: its XDMF files, written at the commit.
    series: std::cell::RefCell<Option<(Meta, Vec<f64>)>>,
}

/// The staging directory next to `dir` (hidden, same parent, so the final rename is atomic).
pub fn staging_dir(dir: &Path) -> PathBuf {
    sibling(dir, "partial")
}

fn sibling(dir: &Path, what: &str) -> PathBuf {
    let name = dir
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let parent = dir.parent().unwrap_or(Path::new("."));
    parent.join(format!(".{name}.{what}"))
}

/// The nearest existing ancestor of `p` (or "." for a relative path with none).
fn existing_ancestor(p: &Path) -> PathBuf {
    let mut a = p.to_path_buf();
    while !a.as_os_str().is_empty() && !a.exists() {
        if !a.pop() {
            break;
        }
    }
    if a.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        a
    }
}

/// The keys that every summary.json this program has written holds (since its first version):
/// a result directory of this program, of this version or an earlier one, is recognised by them.
const SUMMARY_KEYS: &[&str] = &["case", "mesh", "dimension", "ranks", "partition", "timings"];

/// The directory that results given the path `dir` really go to: `dir` without its "."
/// components (`out/.` is `out`), or, for a symbolic link, the directory it points to (the
/// link itself stays). An error for a path that names no directory of its own (the current
/// directory, a root, one ending in "..") and for a link to nothing or to a non-directory.
pub fn target_dir(dir: &Path) -> Result<PathBuf, String> {
    use std::path::Component;
    let plain: PathBuf = dir
        .components()
        .filter(|c| *c != Component::CurDir)
        .collect();
    let own_name = |p: &Path| matches!(p.components().next_back(), Some(Component::Normal(_)));
    if !own_name(&plain) {
        return Err(format!(
            "cannot write results to {}: it names no directory of its own (the current \
             directory, a root, or a path ending in '..'), and the results directory is \
             replaced as a whole: give it a name of its own, e.g. out/run1",
            dir.display()
        ));
    }
    let is_link = std::fs::symlink_metadata(&plain).is_ok_and(|m| m.file_type().is_symlink());
    if !is_link {
        return Ok(plain);
    }
    let to = std::fs::read_link(&plain).unwrap_or_default();
    match std::fs::canonicalize(&plain) {
        Ok(t) if t.is_dir() && own_name(&t) => Ok(t),
        Ok(_) => Err(format!(
            "cannot write results to {}: it is a symbolic link to {}, which is not a directory",
            dir.display(),
            to.display()
        )),
        Err(e) => Err(format!(
            "cannot write results to {}: it is a symbolic link to {}, which cannot be reached \
             ({e})",
            dir.display(),
            to.display()
        )),
    }
}

/// Why the existing directory `dir` is not one this program may replace, if it is not: it
/// may be empty, or hold regular files with the names of result files only, among them a
/// summary.json that this program wrote (a JSON object with [`SUMMARY_KEYS`]).
fn foreign_content(dir: &Path) -> Result<(), String> {
    let mut names = Vec::new();
    for e in std::fs::read_dir(dir).map_err(|e| format!("cannot be read ({e})"))? {
        let e = e.map_err(|e| format!("cannot be read ({e})"))?;
        let n = e.file_name().to_string_lossy().into_owned();
        if !RESULT_FILES.contains(&n.as_str()) {
            return Err(format!(
                "holds '{n}', which is not a result file of this program"
            ));
        }
        if !e.file_type().is_ok_and(|t| t.is_file()) {
            return Err(format!(
                "holds '{n}', which is not a regular file (a directory or a link): not a \
                 result file of this program"
            ));
        }
        names.push(n);
    }
    if names.is_empty() {
        return Ok(());
    }
    let summary = std::fs::read_to_string(dir.join(SUMMARY_FILE)).unwrap_or_default();
    let ours = serde_json::from_str::<serde_json::Value>(&summary)
        .ok()
        .and_then(|v| v.as_object().cloned())
        .is_some_and(|o| SUMMARY_KEYS.iter().all(|k| o.contains_key(*k)));
    if ours {
        Ok(())
    } else if names.iter().any(|n| n == SUMMARY_FILE) {
        Err(format!(
            "holds a {SUMMARY_FILE} that this program did not write"
        ))
    } else {
        Err(format!(
            "holds '{}' but no {SUMMARY_FILE} of this program: not a result directory of it",
            names[0]
        ))
    }
}

/// Can a directory be made where `dir`'s staging directory will go, and may `dir` (an
/// existing directory) be replaced? `dir` is a [`target_dir`]. Creates and removes a probe
/// directory in the nearest existing ancestor; writes nothing that stays.
fn check_writable(dir: &Path) -> Result<(), String> {
    let staging = staging_dir(dir);
    let parent = staging.parent().unwrap_or(Path::new("."));
    if dir.exists() && !dir.is_dir() {
        return Err(format!(
            "cannot write results to {}: it exists and is not a directory",
            dir.display()
        ));
    }
    if dir.is_dir() {
        // The directory is replaced as a whole: refuse to delete what this program did not write.
        if let Err(why) = foreign_content(dir) {
            return Err(format!(
                "the output directory {} {why}; the directory is replaced as a whole by each \
                 run: choose another output.dir (or -o) or remove it",
                dir.display()
            ));
        }
    }
    let base = existing_ancestor(parent);
    if !base.is_dir() {
        return Err(format!(
            "cannot write results to {}: {} is not a directory",
            dir.display(),
            base.display()
        ));
    }
    let probe = base.join(format!(".signorini-probe-{}", std::process::id()));
    std::fs::create_dir(&probe)
        .and_then(|_| std::fs::remove_dir(&probe))
        .map_err(|e| {
            format!(
                "cannot write results to {}: {} is not writable ({e})",
                dir.display(),
                base.display()
            )
        })
}

impl ResultSet {
    /// Checks (before the solve) that the output directory can be written; a directory that
    /// cannot is an input error of the case's `output.dir`. Collective.
    pub fn begin(ctx: &Ctx, dir: &Path, case_file: &Path) -> Result<ResultSet, RunError> {
        let target = Self::check(ctx, dir, case_file)?;
        Ok(ResultSet {
            dir: dir.to_path_buf(),
            staging: staging_dir(&target),
            target,
            committed: false,
            rank: ctx.rank,
            series: std::cell::RefCell::new(None),
        })
    }

    /// Whether results could go to `dir` (an input error naming `output.dir` if not), writing
    /// nothing; the directory they would really go to ([`target_dir`]). Collective.
    pub fn check(ctx: &Ctx, dir: &Path, case_file: &Path) -> Result<PathBuf, RunError> {
        let local = if ctx.rank == 0 {
            target_dir(dir)
                .and_then(|t| check_writable(&t).map(|()| t))
                .map_err(|m| RunError::Input(InputError::new(case_file, m).with_key("output.dir")))
        } else {
            Ok(PathBuf::new())
        };
        let mut target = ctx.agree(local)?;
        ctx.broadcast_path(&mut target);
        Ok(target)
    }

    /// The directory the results go to.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Writes solution.h5 + solution.xdmf into the staging directory. Collective. Returns the
    /// seconds it took.
    pub fn write_solution(&self, ctx: &Ctx, piece: &Piece) -> Result<f64, RunError> {
        let t = Instant::now();
        self.fresh_staging(ctx)?;
        write_xdmf_hdf5(ctx.world, &self.staging, piece).map_err(|e| self.cannot(e))?;
        Ok(t.elapsed().as_secs_f64())
    }

    /// Adds step `index` (1, 2, …) of a load history to solution.h5 in the staging directory;
    /// solution.xdmf (the temporal collection of `times`, one per step so far, the load
    /// factors) is written at the commit. Collective. Returns the seconds it took.
    pub fn write_step(
        &self,
        ctx: &Ctx,
        piece: &Piece,
        index: usize,
        times: &[f64],
    ) -> Result<f64, RunError> {
        let t = Instant::now();
        if index == 1 {
            self.fresh_staging(ctx)?;
        }
        let meta =
            write_step_hdf5(ctx.world, &self.staging, piece, index).map_err(|e| self.cannot(e))?;
        *self.series.borrow_mut() = Some((meta, times.to_vec()));
        Ok(t.elapsed().as_secs_f64())
    }

    /// An empty staging directory (rank 0 makes it, all agree).
    fn fresh_staging(&self, ctx: &Ctx) -> Result<(), RunError> {
        let local = if ctx.rank == 0 {
            let _ = std::fs::remove_dir_all(&self.staging);
            std::fs::create_dir_all(&self.staging)
                .map_err(|e| format!("cannot create {}: {e}", self.staging.display()))
        } else {
            Ok(())
        };
        ctx.agree(local.map_err(RunError::Failed))
    }

    fn cannot(&self, e: String) -> RunError {
        RunError::Failed(format!(
            "cannot write results to {}: {e}",
            self.dir.display()
        ))
    }

    /// Writes the summary (and the contact table, and the load history's table) and puts the
    /// staging directory in place of the output directory, replacing it as a whole.
    /// Collective.
    pub fn commit(
        mut self,
        ctx: &Ctx,
        summary_json: &str,
        csv: Option<&str>,
        history_csv: Option<&str>,
        output_seconds: f64,
    ) -> Result<(), RunError> {
        let local = if ctx.rank == 0 {
            self.finish(summary_json, csv, history_csv).map_err(|e| {
                RunError::Failed(format!(
                    "cannot write results to {}: {e}",
                    self.dir.display()
                ))
            })
        } else {
            Ok(())
        };
        self.committed = true;
        ctx.agree_after_commit(local)?;
        say!(
            ctx,
            "output: {} ({:.3} s)",
            self.dir.join(XDMF_FILE).display(),
            output_seconds
        );
        Ok(())
    }

    /// Rank 0: the small files, then the swap old → aside, staging → dir, aside removed.
    fn finish(
        &self,
        summary_json: &str,
        csv: Option<&str>,
        history_csv: Option<&str>,
    ) -> std::io::Result<()> {
        if let Some((meta, times)) = self.series.borrow().as_ref() {
            write_series_xdmf(&self.staging, meta, times)?;
        }
        std::fs::write(self.staging.join(SUMMARY_FILE), summary_json)?;
        if let Some(c) = csv {
            std::fs::write(self.staging.join(CONTACT_CSV), c)?;
        }
        if let Some(h) = history_csv {
            std::fs::write(self.staging.join(HISTORY_CSV), h)?;
        }
        if let Some(p) = self.target.parent() {
            if !p.as_os_str().is_empty() {
                std::fs::create_dir_all(p)?;
            }
        }
        if !self.target.exists() {
            return std::fs::rename(&self.staging, &self.target);
        }
        let aside = sibling(&self.target, "old");
        let _ = std::fs::remove_dir_all(&aside);
        std::fs::rename(&self.target, &aside)?;
        if let Err(e) = std::fs::rename(&self.staging, &self.target) {
            // Put the previous results back.
            let _ = std::fs::rename(&aside, &self.target);
            return Err(e);
        }
        std::fs::remove_dir_all(&aside)
    }
}

impl Drop for ResultSet {
    /// A run that fails after the staging directory was made leaves nothing behind.
    fn drop(&mut self) {
        if self.rank == 0 && (!self.committed || self.staging.exists()) {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn staging_is_a_hidden_sibling() {
        assert_eq!(
            staging_dir(Path::new("out/hertz")),
            PathBuf::from("out/.hertz.partial")
        );
        assert_eq!(
            sibling(Path::new("out/hertz"), "old"),
            PathBuf::from("out/.hertz.old")
        );
    }

    #[test]
    fn the_target_of_an_output_path() {
        assert_eq!(
            target_dir(Path::new("out/a/.")).unwrap(),
            Path::new("out/a")
        );
        assert_eq!(
            target_dir(Path::new("./out/./a/")).unwrap(),
            Path::new("out/a")
        );
        for bad in [".", "./", "out/..", "/", ""] {
            assert!(target_dir(Path::new(bad)).is_err(), "{bad:?}");
        }
        let t = tempfile::tempdir().unwrap();
        let dangling = t.path().join("dangling");
        std::os::unix::fs::symlink("/proc/nonexist", &dangling).unwrap();
        assert!(target_dir(&dangling).unwrap_err().contains("symbolic link"));
        let real = t.path().join("real");
        std::fs::create_dir(&real).unwrap();
        std::os::unix::fs::symlink(&real, t.path().join("link")).unwrap();
        assert_eq!(
            target_dir(&t.path().join("link")).unwrap(),
            real.canonicalize().unwrap()
        );
    }

    #[test]
    fn only_a_directory_of_its_own_results_is_replaced() {
        let t = tempfile::tempdir().unwrap();
        let d = t.path();
        assert!(foreign_content(d).is_ok(), "empty");
        std::fs::write(d.join(HISTORY_CSV), "a,b\n").unwrap();
        assert!(foreign_content(d).unwrap_err().contains("no summary.json"));
        std::fs::write(d.join(SUMMARY_FILE), "{\"my\": \"precious data\"}").unwrap();
        assert!(foreign_content(d).unwrap_err().contains("did not write"));
        let ours = r#"{"case": "c.toml", "mesh": "m.msh", "dimension": 2, "ranks": 1,
            "partition": {}, "timings": {}}"#;
        std::fs::write(d.join(SUMMARY_FILE), ours).unwrap();
        assert!(foreign_content(d).is_ok());
        std::fs::create_dir(d.join(super::super::H5_FILE)).unwrap();
        assert!(foreign_content(d)
            .unwrap_err()
            .contains("not a regular file"));
    }

    #[test]
    fn nearest_existing_ancestor() {
        let t = tempfile::tempdir().unwrap();
        let p = t.path().join("a/b/c");
        assert_eq!(existing_ancestor(&p), t.path());
        assert!(check_writable(&p).is_ok());
        assert!(!t.path().join(".signorini-probe").exists());
    }
}
