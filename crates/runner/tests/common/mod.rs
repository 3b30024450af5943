//! Test helpers: scratch directories and the repository's paths.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The workspace root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A fresh scratch directory under the target dir (removed when dropped).
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(name: &str) -> Self {
        let base =
            std::env::temp_dir().join(format!("stride-runner-test-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        std::fs::create_dir_all(&base).unwrap();
        Scratch(base)
    }
    pub fn write(&self, rel: &str, text: &str) -> PathBuf {
        let p = self.0.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
        p
    }
    pub fn path(&self, rel: &str) -> PathBuf {
        self.0.join(rel)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A scenario text that uses the bundled model through an absolute URDF path.
pub fn robot_section() -> String {
    let urdf = root().join("models/stride_humanoid.urdf");
    let robot =
        std::fs::read_to_string(root().join("configs/robots/stride_humanoid.toml")).unwrap();
    robot.replace(
        "\"../../models/stride_humanoid.urdf\"",
        &format!("{:?}", urdf.display().to_string()),
    )
}
