//! Shared helpers of the `import_*` integration tests.
#![allow(dead_code, unused_imports)]

// The binary's own `common` (declared by its root: `tests/integration.rs`,
// or `tests/import_bad_input.rs`), not a second copy of it.
use crate::common;
pub use common::{skip_without_chromium, skip_without_venv};

use std::path::{Path, PathBuf};
use std::process::Command;

pub const ROBOTS: [&str; 7] = [
    "rotating_chains",
    "chains_8link",
    "spider",
    "biped",
    "single_jaw_gripper",
    "parallel_jaw_gripper",
    "three_finger_hand",
];

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

pub fn robot_urdf(name: &str) -> PathBuf {
    root()
        .join("robots")
        .join(name)
        .join(format!("{name}.urdf"))
}

/// Every object mesh of the authored robots.
pub fn object_meshes() -> Vec<PathBuf> {
    let mut v = Vec::new();
    for r in ROBOTS {
        let dir = root().join("robots").join(r).join("objects");
        if let Ok(rd) = std::fs::read_dir(&dir) {
            for e in rd.flatten() {
                v.push(e.path());
            }
        }
    }
    v.sort();
    v
}

/// The project venv's Python; fails the test when missing (a test that needs
/// it starts with `common::skip_without_venv()`, which honours
/// `SDRS_TEST_PRETEND_NO_VENV=1` as this does).
pub fn venv_python() -> PathBuf {
    let py = root().join(".venv/bin/python");
    let pretend = std::env::var_os("SDRS_TEST_PRETEND_NO_VENV").is_some_and(|v| v == "1");
    assert!(
        py.exists() && !pretend,
        "the Python helpers' environment is missing ({}): run `bash tools/setup/setup_python.sh` from the repository root first",
        py.display()
    );
    py
}

/// Runs the check `tools/check/<script>` with the venv Python; returns (status ok, stdout, stderr).
pub fn run_tool(script: &str, args: &[&Path]) -> (bool, String, String) {
    let out = Command::new(venv_python())
        .arg(root().join("tools/check").join(script))
        .args(args)
        .output()
        .expect("run the Python helper");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The third-party robot: KUKA iiwa (URDF + STL meshes) from `pybullet_data`
/// in the venv (installed by tools/setup/setup_python.sh).
pub fn third_party_urdf() -> PathBuf {
    let out = Command::new(venv_python())
        .args([
            "-c",
            "import pybullet_data; print(pybullet_data.getDataPath())",
        ])
        .output()
        .expect("run Python");
    assert!(
        out.status.success(),
        "pybullet_data is not installed in .venv: run `bash tools/setup/setup_python.sh` ({})",
        String::from_utf8_lossy(&out.stderr)
    );
    let dir = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
    let urdf = dir.join("kuka_iiwa/model.urdf");
    assert!(urdf.is_file(), "{} not found", urdf.display());
    urdf
}

/// A fresh, empty temporary directory for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sdrs-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Sorted file names in `dir` (recursively, relative).
pub fn listing(dir: &Path) -> Vec<String> {
    let mut v = Vec::new();
    fn walk(base: &Path, d: &Path, v: &mut Vec<String>) {
        for e in std::fs::read_dir(d).unwrap().flatten() {
            let p = e.path();
            v.push(p.strip_prefix(base).unwrap().display().to_string());
            if p.is_dir() {
                walk(base, &p, v);
            }
        }
    }
    walk(dir, dir, &mut v);
    v.sort();
    v
}

/// Import settings of the independent-checker tests: one hull per mesh
/// (`--decomposer hull`), no progress bar, every other default.
pub fn hull_options() -> sdrs::import::ImportOptions {
    sdrs::import::ImportOptions {
        decomposer: sdrs::import::Decomposer::Hull,
        ..sdrs::import::ImportOptions::default()
    }
}
