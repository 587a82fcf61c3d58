//! Helpers shared by integration tests.
#![allow(dead_code)]

pub mod adjoint;
pub mod fd;

use std::path::{Path, PathBuf};
use std::process::Command;

/// Repository root (the workspace root: these helpers are shared by the
/// core's tests and the CLI member's tests).
pub fn root() -> &'static Path {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.ancestors()
        .find(|d| d.join("robots").is_dir() && d.join("tools").is_dir())
        .unwrap_or(here)
}

/// A bundled scene.
pub fn robots(name: &str) -> PathBuf {
    root().join("robots").join(name)
}

/// A fresh scratch directory for one test.
pub fn scratch_dir(name: &str) -> Scratch {
    let d = std::env::temp_dir().join(format!("sdrs-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    Scratch(d)
}

/// A test's scratch directory: removed when the test passes, kept (for
/// inspection) when it panics.
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for Scratch {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// The project's Python (`.venv`, made by `tools/setup_python.sh`). Panics
/// with the setup command when it is missing: these checks must not be
/// skipped silently.
pub fn python() -> Command {
    let py = root().join(".venv/bin/python");
    assert!(
        py.exists(),
        "{} is missing: run `bash tools/setup_python.sh` (tools/test.sh does it)",
        py.display()
    );
    Command::new(py)
}
