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

/// Test tiers (docs/testing.md). Tier 1 is hermetic: a bare `cargo test`
/// on a fresh clone needs only the Rust toolchain. Tier 2 needs the
/// project's Python environment `.venv` (made by `tools/setup/setup_python.sh`:
/// MuJoCo, Pinocchio, python-fcl, ipctk, trimesh, CoACD, pybullet's robot
/// files) or Chromium. A tier-2 test starts with
/// `if skip_without_venv() { return; }`: without `.venv` it writes a visible
/// `SKIPPED` line (straight to the terminal, past the test harness's output
/// capture) and the test returns — unless `SDRS_TEST_ALL_TIERS=1`
/// (`tools/test.sh` sets it, so CI never skips), where a missing environment
/// fails the test. `SDRS_TEST_PRETEND_NO_VENV=1` makes the environment look
/// missing (to check the tier split without deleting `.venv`).
pub fn skip_without_venv() -> bool {
    if venv_present() {
        return false;
    }
    skip_tier2("the project's Python environment .venv (run `bash tools/setup/setup_python.sh`)")
}

/// [`skip_without_venv`] for tests that drive headless Chromium.
pub fn skip_without_chromium() -> bool {
    let found = ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .any(|b| {
            std::env::var_os("PATH")
                .is_some_and(|p| std::env::split_paths(&p).any(|d| d.join(b).is_file()))
        });
    if found && venv_present() {
        return false;
    }
    skip_tier2("Chromium (run `bash tools/setup/setup_system.sh`) and .venv")
}

/// Whether `.venv` is there (and not hidden by `SDRS_TEST_PRETEND_NO_VENV=1`).
pub fn venv_present() -> bool {
    let pretend = std::env::var_os("SDRS_TEST_PRETEND_NO_VENV").is_some_and(|v| v == "1");
    root().join(".venv/bin/python").exists() && !pretend
}

fn skip_tier2(what: &str) -> bool {
    use std::io::Write;
    let test = std::thread::current()
        .name()
        .unwrap_or("a test")
        .to_string();
    assert!(
        std::env::var_os("SDRS_TEST_ALL_TIERS").is_none_or(|v| v != "1"),
        "{test} needs {what}; SDRS_TEST_ALL_TIERS=1 runs every tier, so it fails instead of skipping"
    );
    let _ = writeln!(std::io::stderr(), "SKIPPED {test}: needs {what}");
    true
}

/// The project's Python (`.venv`, made by `tools/setup/setup_python.sh`). Panics
/// with the setup command when it is missing: a test that needs it starts
/// with [`skip_without_venv`], so a missing environment is never silent.
pub fn python() -> Command {
    let py = root().join(".venv/bin/python");
    assert!(
        venv_present(),
        "{} is missing: run `bash tools/setup/setup_python.sh` (tools/test.sh does it)",
        py.display()
    );
    Command::new(py)
}
