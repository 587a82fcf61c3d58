//! SDRS — shape-differentiable robot simulation.
//!
//! See the README for the pipeline and `shared/paper` for the method.

pub mod contact;
