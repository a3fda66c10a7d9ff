//! A small tmpfs for tests of a full disk (root only: scripts/test and CI run as root; a test
//! that cannot mount one fails, it does not pass untested).

use std::path::PathBuf;
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
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.path).status();
    }
}
