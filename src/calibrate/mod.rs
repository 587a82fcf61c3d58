//! Calibration (`sdrs calibrate`): find where simulation and measurement
//! disagree, name the missing physical effect, fit it, and show the gap
//! shrink.
//!
//! - [`effects`]: the library of candidate effects (terms of the step
//!   objective or parameters), each with its adjoint gradient.
pub mod effects;
