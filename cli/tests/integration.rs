//! The package's integration tests as one binary: each file of this
//! directory is a module (one link of the whole crate instead of one per
//! file; notes/ci-time.md). Run one file's tests with
//! `cargo nextest run --release -E 'test(/^FILE::/)'` or
//! `cargo test --release --test integration FILE::`.

mod support;

mod bench_mujoco;
mod calibrate_acceptance;
mod calibrate_cli;
mod calibrate_floating;
mod calibrate_mujoco;
mod child_cleanup;
mod cli;
mod compare;
mod first_hour;
mod grasping_cli;
mod import_cache;
mod installed;
mod ipc;
mod ipc_source_surface;
mod mjcf;
mod mjcf_roundtrip;
mod multistart;
mod optimize;
mod optimize_ipc;
mod optimize_resume;
mod outcomes_table;
mod plot;
mod pybullet_data;
mod schema;
mod separation;
mod simulate_stream;
mod swing_mujoco;
mod tutorial;
mod view;
