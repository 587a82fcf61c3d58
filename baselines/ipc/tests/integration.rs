//! The package's integration tests as one binary: each file of this
//! directory is a module (one link of the whole crate instead of one per
//! file; notes/ci-time.md). Run one file's tests with
//! `cargo nextest run --release -E 'test(/^FILE::/)'` or
//! `cargo test --release --test integration FILE::`.

#[allow(dead_code, unused_imports)]
mod support;

/// The core's shared test helpers (`tests/common`), once for the binary.
#[path = "../../../tests/common/mod.rs"]
mod common;

mod adjoint_stencil_fd;
mod adjoint_trajectory;
mod cage;
mod ccd_sliding;
mod friction_derivatives;
mod ipc_scenes;
mod ipctk_crosscheck;
mod pose_chain;
mod primitive_derivatives;
mod source_surface;
