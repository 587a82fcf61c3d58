//! Helpers of the CLI's end-to-end tests: the core's shared test helpers
//! (`tests/common`) plus the `sdrs` binary this package builds.
#![allow(dead_code, unused_imports)]

#[path = "../../../tests/common/mod.rs"]
mod common;

pub use common::*;

/// The `sdrs` binary.
pub fn sdrs() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_sdrs"))
}
