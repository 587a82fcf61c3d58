//! Helpers of the CLI's end-to-end tests: the core's shared test helpers
//! (`tests/common`) plus the `sdrs` binary this package builds.
#![allow(dead_code, unused_imports)]

#[path = "../../../tests/common/mod.rs"]
mod common;

pub use common::*;

pub mod browser;

/// The `sdrs` binary.
pub fn sdrs() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_sdrs"))
}

/// pybullet's robot files (`pybullet_data`, installed in `.venv` by
/// `tools/setup_python.sh`).
pub fn pybullet_data() -> std::path::PathBuf {
    let out = python()
        .args([
            "-c",
            "import pybullet_data; print(pybullet_data.getDataPath())",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "pybullet_data missing: run tools/setup_python.sh"
    );
    std::path::PathBuf::from(String::from_utf8_lossy(&out.stdout).trim())
}
