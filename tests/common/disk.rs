//! A small tmpfs for tests of a full disk (root only: scripts/test and CI run as root; a test
//! that cannot mount one fails, it does not pass untested), and what a directory holds.

use super::process::Run;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A tmpfs of a given size mounted for the test; unmounted when dropped.
pub struct SmallDisk {
    _tmp: tempfile::TempDir,
    pub path: PathBuf,
}

impl SmallDisk {
    /// Mounts a tmpfs of `size` (e.g. "900k"); panics, with mount's own message, where it
    /// cannot (not root, or no permission to mount).
    pub fn mount(size: &str) -> SmallDisk {
        let tmp = tempfile::tempdir().expect("tempdir");
        let path = tmp.path().join("disk");
        std::fs::create_dir(&path).expect("the mount point");
        let out = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(&path)
            .output()
            .unwrap_or_else(|e| panic!("cannot run mount: {e}"));
        assert!(
            out.status.success(),
            "cannot mount a tmpfs of {size} at {} (the full-disk tests need root, as \
             scripts/test and CI have): {}",
            path.display(),
            String::from_utf8_lossy(&out.stderr)
        );
        SmallDisk { _tmp: tmp, path }
    }

    /// After a run `r` that failed for the full disk while writing into `out` on it: one
    /// error line, which names solution.h5 (returned), `out` as it was (`before`, its
    /// [`listing`]) and nothing else on the disk (no staging left).
    pub fn assert_nothing_written(
        &self,
        r: &Run,
        out: &Path,
        before: &[(String, Vec<u8>)],
        what: &str,
    ) -> String {
        let errors: Vec<&str> = r
            .stderr
            .lines()
            .filter(|l| l.starts_with("error:"))
            .collect();
        assert_eq!(errors.len(), 1, "one error line:\n{}", r.output());
        assert!(errors[0].contains("solution.h5"), "{}", errors[0]);
        assert_eq!(listing(out), before, "{what}: previous results changed");
        assert_eq!(
            file_names(&self.path),
            ["out"],
            "{what}: staging left behind"
        );
        errors[0].to_string()
    }
}

/// The names of the entries of `dir`, sorted.
pub fn file_names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The entries of `dir` with their bytes (a directory's empty), sorted by name.
pub fn listing(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let p = e.path();
            let bytes = if p.is_file() {
                std::fs::read(&p).unwrap()
            } else {
                Vec::new()
            };
            (e.file_name().to_string_lossy().into_owned(), bytes)
        })
        .collect();
    v.sort();
    v
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.path).status();
    }
}
