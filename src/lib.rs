//! SDRS — shape-differentiable robot simulation.
//!
//! Pipeline stages, one folder each: [`import`] (URDF / OBJ / STL →
//! convex-hull design spaces), [`scene`] (files → model), [`model`] (links,
//! hulls, joints), [`kinematics`] (poses and derivatives), [`geometry`]
//! (world hulls, broad phase), [`contact`] (separating-plane contact and
//! friction potentials of one hull pair), [`energy`] (terms of the step
//! objective), [`sim`] (Newton per step), [`control`] (target signals),
//! [`diff`] (adjoint gradients of trajectories), [`optimize`] (co-design),
//! [`output`] (trajectory CSV, summary JSON).
//!
//! The method is the SDRS paper (`shared/paper/sdrs-paper.tex`).

pub mod calibrate;
pub mod contact;
pub mod control;
pub mod counters;
pub mod diff;
pub mod energy;
pub mod files;
pub mod geometry;
pub mod import;
pub mod kinematics;
pub mod math;
pub mod model;
pub mod optimize;
pub mod output;
pub mod progress;
pub mod scene;
pub mod sim;
