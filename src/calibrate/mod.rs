//! Calibration (`sdrs calibrate`): find where simulation and measurement
//! disagree, name the missing physical effect, fit it, and show the gap
//! shrink.
//!
//! - [`crate::energy::effects`]: the library of candidate effects (terms of
//!   the step objective or parameters), each with its adjoint gradient; how
//!   to add one is in its module doc.
//! - [`data`]: measured CSV files, validation, alignment by interpolation.
//! - [`mcap_log`]: MCAP robot logs (`sensor_msgs/JointState`, CDR or JSON) as measured data.
//! - [`problem`]: the least-squares problem of a candidate on a window.
//! - [`recordings`]: several recordings fitted with one parameter set.
//! - [`candidates`]: the candidate list with bounds and starts.
//! - [`adjoint`]: the exact gradient `Jᵀr` of a candidate's residuals.
//! - [`fit`]: bounded Levenberg–Marquardt, Gauss–Newton confidence.
//! - [`identifiability`]: each candidate's scaled Gauss–Newton matrix at
//!   its start: condition number, near-singular parameters, what to excite.
//! - [`nuisance`]: the contact model's resolution (`s`, `κ`) fitted before
//!   the selection: a setting of our contact model, never named as an effect.
//! - [`floor`]: the model's own error on the data (noise, integrator error
//!   by Richardson extrapolation), measured before attributing anything.
//! - [`select`]: fits in parallel, pairs, the criterion.
//! - [`verdict`]: the smallest set of effects explaining the gap down to
//!   the floor; `effect`, `none` or `unexplained`; plausibility checks.
//! - [`analysis`]: residuals per channel, regime and time window.
//! - [`residual`]: sparse regression of the residual generalized force on
//!   candidate terms per joint (effects outside the library).
//! - [`report`]: `calibration.json`, `report.md`; the SVG plots are drawn by
//!   the application through [`run::PlotWriter`] (`cli/src/svg/calibration.rs`).
//! - [`run`]: options, [`run()`].
//!
//! Outputs and their schema: [`report`] and the README.

pub mod adjoint;
pub mod analysis;
pub mod candidates;
pub mod data;
pub mod error;
pub mod fit;
pub mod floor;
pub mod identifiability;
pub mod mcap_log;
pub mod nuisance;
pub mod problem;
pub mod recordings;
pub mod report;
pub mod residual;
pub mod run;
pub mod select;
pub mod verdict;

pub use error::CalibrateError;
pub use report::CalibrationResult;
pub use run::{
    CalibrateOptions, Hooks, ModelWriter, PlotWriter, ReportWriter, calibrate, calibrate_with,
    check_resolution_names, effect_kinds, run, run_with,
};
