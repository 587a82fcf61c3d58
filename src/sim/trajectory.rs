//! The recorded trajectory of a run: reported coordinates per time, the
//! per-step diagnostics, and optionally every link pose. Recorded by
//! [`crate::sim::run`]; written out by `crate::output` (CSV, summaries).

use crate::counters::StepDiagnostics;
use crate::math::Pose;
use crate::model::Model;
use nalgebra::DVector;

/// Trajectory and per-step diagnostics of a run.
#[derive(Clone, Debug, Default)]
pub struct Trajectory {
    pub names: Vec<String>,
    pub times: Vec<f64>,
    /// Reported coordinates per recorded time (charted rotations as absolute
    /// rotation vectors).
    pub states: Vec<DVector<f64>>,
    /// Diagnostics per completed step (one fewer than `states`).
    pub diagnostics: Vec<StepDiagnostics>,
    /// Link poses per recorded time, when recording was asked for.
    pub poses: Vec<Vec<Pose>>,
}

impl Trajectory {
    pub fn new(model: &Model) -> Self {
        Trajectory {
            names: model.dofs.iter().map(|d| d.name.clone()).collect(),
            ..Default::default()
        }
    }
}
