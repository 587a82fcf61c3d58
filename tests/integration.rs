//! The package's integration tests as one binary: each file of this
//! directory is a module (one link of the whole crate instead of one per
//! file; notes/ci-time.md). Run one file's tests with
//! `cargo nextest run --release -E 'test(/^FILE::/)'` or
//! `cargo test --release --test integration FILE::`.

mod calibrate_support;
mod common;
mod import_support;

mod adjoint_contact_gradients;
mod adjoint_gradients;
mod adjoint_pose_target;
mod analytic_dynamics;
mod calibrate_bad_input;
mod calibrate_effects;
mod calibrate_fit_gradient;
mod calibrate_floor;
mod calibrate_hidden;
mod calibrate_identifiability;
mod calibrate_mcap;
mod calibrate_recordings;
mod calibrate_residual;
mod codesign;
mod contact_physics;
mod degenerate_blocks;
mod energy_balance;
mod fuzz_inputs;
mod grasping;
mod import_collada;
mod import_coverage;
mod import_decomposers;
mod import_dynamics;
mod import_fk_pinocchio;
mod import_hull;
mod import_mass_pinocchio;
mod import_mjcf;
mod import_mjcf_actuators;
mod import_pybullet_shapes;
mod import_robots;
mod import_robustness;
mod import_third_party;
mod joint_limits;
mod layers;
mod locomotion;
mod mass_models;
mod newton_regressions;
mod objective_derivatives;
mod scene_errors;
mod step_solution_invariance;
mod stress_scenes;
mod test_targets;
mod topology_demo;
mod tunnelling;
