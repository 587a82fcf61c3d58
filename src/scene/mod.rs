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
    /// Attaches the scene file.
    pub fn at(self, path: &Path) -> SceneError {
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

pub use crate::contact::settings::ContactSettings;

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

    /// A simulator at the scene's initial state with the core's contact
    /// model (SDRS). A scene that selects another model (`contact.model:
    /// ipc`) needs [`Scene::simulator_with`] and a factory providing it (the
    /// `sdrs` CLI has one); here it runs with the SDRS model.
    pub fn simulator(&self) -> Simulator {
        let mut sim = self.bare_simulator();
        if let Some(c) = &self.contact_settings() {
            push_sdrs_contact(&mut sim, &self.model, c, self.settings.dt);
        }
        crate::calibrate::effects::install(&self.effects, &mut sim);
        sim
    }

    /// The contact settings with the scene's calibration effects applied
    /// (fitted μ, κ, s).
    fn contact_settings(&self) -> Option<ContactSettings> {
        self.contact
            .clone()
            .map(|c| crate::calibrate::effects::contact_settings(&self.effects, c))
    }

    /// A simulator at the scene's initial state whose contact terms, for a
    /// scene with `contact.model` other than `sdrs`, come from `factory`
    /// (the extension point that keeps the core independent of the
    /// baselines). SDRS scenes get exactly [`Scene::simulator`].
    pub fn simulator_with(
        &self,
        factory: &dyn ContactModelFactory,
    ) -> Result<Simulator, SceneError> {
        self.simulator_from(factory, false)
    }

    /// [`Scene::simulator_with`] for the backward pass of a trajectory
    /// recorded with it: the factory's [`ContactModelFactory::adjoint_energies`]
    /// (e.g. exact instead of PSD-projected Hessians). SDRS scenes get
    /// exactly [`Scene::simulator`].
    pub fn adjoint_simulator_with(
        &self,
        factory: &dyn ContactModelFactory,
    ) -> Result<Simulator, SceneError> {
        self.simulator_from(factory, true)
    }

    fn simulator_from(
        &self,
        factory: &dyn ContactModelFactory,
        adjoint: bool,
    ) -> Result<Simulator, SceneError> {
        let mut sim = self.bare_simulator();
        if let Some(c) = &self.contact_settings() {
            if c.model.is_sdrs() {
                push_sdrs_contact(&mut sim, &self.model, c, self.settings.dt);
            } else {
                let energies = if adjoint {
                    factory.adjoint_energies(self, c)
                } else {
                    factory.contact_energies(self, c)
                }
                .map_err(|e| e.at(&self.source))?;
                sim.energies.extend(energies);
                // IPC's barrier makes the joint-space Hessian's kinematic
                // part indefinite: see `NewtonOptions::eig_abs`.
                sim.settings.newton.eig_abs = true;
                // Newton starts from the scene's predictor, as under SDRS, so
                // contact-free scenes give the same bytes under both models.
                // (It was pinned to θ^t after the four chains stopped
                // converging at step 1596 with the predictor, notes/performance.md;
                // on the current code they run 2000 steps with it, python-fcl
                // clean, in 3.4 instead of 5.0 Newton iterations per step,
                // and 32 links per chain 600 steps: notes/ipc-baseline-source-meshes.md.)
            }
        }
        crate::calibrate::effects::install(&self.effects, &mut sim);
        Ok(sim)
    }

    fn bare_simulator(&self) -> Simulator {
        let state = SimState::new(
            &self.model,
            self.q0.clone(),
            &self.qdot0,
            self.charts.clone(),
            self.settings.dt,
        );
        Simulator::new(
            self.model.clone(),
            self.settings.clone(),
            self.controller.clone(),
            state,
        )
    }
}

fn push_sdrs_contact(sim: &mut Simulator, model: &Model, c: &ContactSettings, dt: f64) {
    sim.energies
        .push(Box::new(crate::energy::ContactEnergy::new(
            model,
            c.clone(),
        )));
    if c.mu > 0.0 {
        let friction = crate::energy::FrictionEnergy::new(model, c.clone(), dt);
        sim.energies.push(Box::new(friction));
    }
}

/// Provides the contact (and friction) terms of a contact model the core
/// does not implement itself (`contact.model: ipc`). Implemented outside the
/// core (the IPC baseline), passed in by the CLI to
/// [`Scene::simulator_with`].
pub trait ContactModelFactory {
    /// The terms for `settings.model` on `scene`, or a validation problem
    /// naming the element (e.g. an open mesh, an intersecting start, or a
    /// model the factory does not know).
    fn contact_energies(
        &self,
        scene: &Scene,
        settings: &ContactSettings,
    ) -> Result<Vec<Box<dyn crate::energy::Energy>>, Invalid>;

    /// The terms a backward pass linearizes a trajectory recorded with
    /// [`ContactModelFactory::contact_energies`] with: the same functions,
    /// with whatever the Newton solve approximates made exact (IPC: the
    /// per-primitive Hessians without PSD projection). Default: the same
    /// terms.
    fn adjoint_energies(
        &self,
        scene: &Scene,
        settings: &ContactSettings,
    ) -> Result<Vec<Box<dyn crate::energy::Energy>>, Invalid> {
        self.contact_energies(scene, settings)
    }
}

/// A shareable contact-model factory (co-design problems carry one).
pub type SharedContactFactory = std::sync::Arc<dyn ContactModelFactory + Send + Sync>;
