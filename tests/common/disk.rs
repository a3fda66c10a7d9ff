//! A small tmpfs for tests of a full disk (root only).

use std::path::PathBuf;
use std::process::Command;

/// A tmpfs of a given size mounted for the test; unmounted when dropped.
pub struct SmallDisk {
    _tmp: tempfile::TempDir,
    pub path: PathBuf,
}

impl SmallDisk {
    /// Mounts a tmpfs of `size` (e.g. "900k"); `None` where mounting is not allowed.
    pub fn mount(size: &str) -> Option<SmallDisk> {
        let tmp = tempfile::tempdir().ok()?;
        let path = tmp.path().join("disk");
        std::fs::create_dir(&path).ok()?;
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(&path)
            .output()
            .map(|o| o.status.success())
            .unwrap_or(false);
        ok.then_some(SmallDisk { _tmp: tmp, path })
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.path).status();
    }
}
