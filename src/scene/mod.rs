//! Scene files → a ready-to-run [`Scene`] (model, settings, controller,
//! initial state). Schema: [`schema`]. Every problem is reported as a
//! [`SceneError`] naming the file and the element.

pub mod build;
pub mod chain;
pub mod environment;
pub mod schema;

pub use schema::SceneSpec;

use crate::control::Controller;
use crate::model::Model;
use crate::sim::{SimSettings, SimState, Simulator};
use nalgebra::{DVector, Matrix3};
use std::path::{Path, PathBuf};

/// A problem with a scene file.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The cause is part of the message (not a separate `source`), so a
    /// cause chain prints it once.
    #[error("{}: cannot read the file: {err}", path.display())]
    Io { path: PathBuf, err: std::io::Error },
    #[error("{}: malformed scene: {msg}", path.display())]
    Parse { path: PathBuf, msg: String },
    #[error("{}: {element}: {msg}", path.display())]
    Invalid {
        path: PathBuf,
        element: String,
        msg: String,
    },
}

/// A validation problem before the file name is attached.
#[derive(Debug, Clone, PartialEq)]
pub struct Invalid {
    pub element: String,
    pub msg: String,
}

impl Invalid {
    pub fn new(element: impl Into<String>, msg: impl Into<String>) -> Self {
        Invalid {
            element: element.into(),
            msg: msg.into(),
        }
    }
    fn at(self, path: &Path) -> SceneError {
        SceneError::Invalid {
            path: path.to_path_buf(),
            element: self.element,
            msg: self.msg,
        }
    }
}

/// A loaded scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// File the scene came from (for messages).
    pub source: PathBuf,
    pub model: Model,
    pub settings: SimSettings,
    pub controller: Controller,
    /// `θ^0`.
    pub q0: DVector<f64>,
    /// `θ̇^0`.
    pub qdot0: DVector<f64>,
    /// Initial chart centres.
    pub charts: Vec<Matrix3<f64>>,
    /// Default number of steps.
    pub steps: usize,
    /// Contact settings, when the scene enables contact (without the
    /// scene's contact effects; [`Scene::simulator`] applies them).
    pub contact: Option<ContactSettings>,
    /// Extra physical effects (`effects:`), validated.
    pub effects: Vec<crate::calibrate::effects::Effect>,
    /// The parsed specification (kept for writing designs back).
    pub spec: SceneSpec,
}

/// Validated contact parameters (see [`schema::ContactSpec`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ContactSettings {
    /// Barrier support `s`.
    pub s: f64,
    /// Barrier stiffness `κ`.
    pub kappa: f64,
    /// Friction coefficient `μ`.
    pub mu: f64,
    /// Friction velocity smoothing `ε` ((m/s)²).
    pub eps: f64,
    /// Normal-force smoothing `ε_f` (N²).
    pub eps_force: f64,
    /// Link pairs `(i, j)`, `i < j`, that never interact.
    pub excluded: std::collections::BTreeSet<(usize, usize)>,
}

impl Scene {
    /// Reads and validates a scene file.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|err| SceneError::Io {
            path: path.to_path_buf(),
            err,
        })?;
        Self::from_str(&text, path)
    }

    /// Parses and validates scene text; `path` is used in messages only.
    pub fn from_str(text: &str, path: &Path) -> Result<Scene, SceneError> {
        if text.trim().is_empty() {
            return Err(SceneError::Parse {
                path: path.to_path_buf(),
                msg: "the file is empty (a scene needs at least `dt` and `robots` or `objects`; see README, \"Scene files\")".into(),
            });
        }
        let spec: SceneSpec = serde_yaml::from_str(text).map_err(|e| SceneError::Parse {
            path: path.to_path_buf(),
            msg: e.to_string(),
        })?;
        Self::from_spec(spec, path)
    }

    /// Validates a parsed specification.
    pub fn from_spec(spec: SceneSpec, path: &Path) -> Result<Scene, SceneError> {
        build::build_scene(spec, path).map_err(|e| e.at(path))
    }

    /// A simulator at the scene's initial state.
    pub fn simulator(&self) -> Simulator {
        let state = SimState::new(
            &self.model,
            self.q0.clone(),
            &self.qdot0,
            self.charts.clone(),
            self.settings.dt,
        );
        let mut sim = Simulator::new(
            self.model.clone(),
            self.settings.clone(),
            self.controller.clone(),
            state,
        );
        let contact = self
            .contact
            .clone()
            .map(|c| crate::calibrate::effects::contact_settings(&self.effects, c));
        if let Some(c) = &contact {
            sim.energies
                .push(Box::new(crate::energy::ContactEnergy::new(
                    &self.model,
                    c.clone(),
                )));
            if c.mu > 0.0 {
                let friction =
                    crate::energy::FrictionEnergy::new(&self.model, c.clone(), self.settings.dt);
                sim.energies.push(Box::new(friction));
            }
        }
        crate::calibrate::effects::install(&self.effects, &mut sim);
        sim
    }
}
