//! `sdrs.Scene`: a loaded scene, its simulation and the adjoint gradients of
//! a loss w.r.t. its full design, controller and physics vectors.

use crate::eval::{backward_of, forward};
use crate::params::{
    apply_physics, physics_gradient, physics_names, physics_values, scene_controls, scene_design,
    vector,
};
use crate::trajectory::PyTrajectory;
use crate::{SdrsError, err};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sdrs::diff::Loss;
use sdrs::optimize::task::LossSpec;
use sdrs::optimize::{ControlSpace, DesignSpace};
use sdrs::scene::Scene;
use std::path::PathBuf;

/// A scene file loaded and validated (`sdrs.Scene.load(path)`).
///
/// `design`, `controller` and `physics` are flat float64 vectors (names in
/// `design_names`, `controller_names`, `physics_names`); assigning one
/// changes the scene for every later `simulate` and `gradient` call.
#[pyclass(name = "Scene", module = "sdrs")]
pub struct PyScene {
    pub scene: Scene,
    design: DesignSpace,
    controls: ControlSpace,
}

impl PyScene {
    pub fn new(scene: Scene) -> Self {
        PyScene {
            design: scene_design(&scene.model),
            controls: scene_controls(&scene.controller),
            scene,
        }
    }
}

/// `loss` (a dict or a list of dicts in the task file's `loss:` format) as
/// the core's loss terms over `horizon` steps of `scene`.
pub fn loss_from_py(scene: &Scene, loss: &Bound<'_, PyAny>, horizon: usize) -> PyResult<Loss> {
    let py = loss.py();
    let json: String = py
        .import("json")?
        .call_method1("dumps", (loss,))?
        .extract()?;
    let value: serde_json::Value = serde_json::from_str(&json).map_err(err)?;
    let list = match value {
        serde_json::Value::Array(_) => value,
        other => serde_json::Value::Array(vec![other]),
    };
    let specs: Vec<LossSpec> =
        serde_json::from_value(list).map_err(|e| SdrsError::new_err(format!("loss: {e}")))?;
    sdrs::optimize::build_loss(&scene.source, &scene.model, &specs, horizon).map_err(err)
}

#[pymethods]
impl PyScene {
    /// Reads and validates a scene YAML; raises `SdrsError` naming the file,
    /// the element and what is wrong.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<PyScene> {
        let scene = py.detach(|| Scene::load(&path)).map_err(err)?;
        Ok(PyScene::new(scene))
    }

    /// The scene file.
    #[getter]
    fn path(&self) -> PathBuf {
        self.scene.source.clone()
    }

    /// The scene's default number of steps.
    #[getter]
    fn steps(&self) -> usize {
        self.scene.steps
    }

    /// Time step Δt (s).
    #[getter]
    fn dt(&self) -> f64 {
        self.scene.settings.dt
    }

    /// Coordinate names (columns of `Trajectory.q`).
    #[getter]
    fn dof_names(&self) -> Vec<String> {
        self.scene
            .model
            .dofs
            .iter()
            .map(|d| d.name.clone())
            .collect()
    }

    /// Link names `robot/link`.
    #[getter]
    fn link_names(&self) -> Vec<String> {
        link_names(&self.scene)
    }

    /// Runs `steps` steps (default: the scene's `steps`) with the GIL
    /// released, exactly as `sdrs simulate` (same contact model, including
    /// `contact.model: ipc`); `poses=False` skips recording link poses.
    #[pyo3(signature = (steps=None, poses=true))]
    fn simulate(
        &self,
        py: Python<'_>,
        steps: Option<usize>,
        poses: bool,
    ) -> PyResult<PyTrajectory> {
        let steps = steps.unwrap_or(self.scene.steps);
        let scene = &self.scene;
        let traj = py
            .detach(|| {
                let mut sim = scene
                    .simulator_with(&sdrs_ipc::IpcFactory::default())
                    .map_err(|e| e.to_string())?;
                sdrs::sim::run::run_recording(&mut sim, steps, poses, |_| {})
                    .map_err(|e| format!("simulating {}: {e}", scene.source.display()))
            })
            .map_err(err)?;
        Ok(PyTrajectory {
            traj,
            link_names: link_names(scene),
        })
    }

    /// Design vector: every attachment point (parent frame, m) and hull
    /// vertex (link frame, m); names in `design_names`.
    #[getter]
    fn get_design<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.design
            .values(&self.scene.model)
            .data
            .as_vec()
            .clone()
            .into_pyarray(py)
    }

    #[setter]
    fn set_design(&mut self, d: PyReadonlyArray1<f64>) -> PyResult<()> {
        let d = vector("design", d.as_slice()?, self.design.len()).map_err(err)?;
        self.design.apply(&mut self.scene.model, &d);
        Ok(())
    }

    /// Names of `design`: `robot/link.attach.x|y|z`, `robot/link.hull<h>.v<k>.x|y|z`.
    #[getter]
    fn design_names(&self) -> Vec<String> {
        self.design.vars.iter().map(|v| v.name.clone()).collect()
    }

    /// Controller vector: per channel, its target-signal parameters, `kp`
    /// and `kd` (gains clamped at 0 when written); names in
    /// `controller_names`.
    #[getter]
    fn get_controller<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.controls
            .values(&self.scene.controller)
            .data
            .as_vec()
            .clone()
            .into_pyarray(py)
    }

    #[setter]
    fn set_controller(&mut self, c: PyReadonlyArray1<f64>) -> PyResult<()> {
        let c = vector("controller", c.as_slice()?, self.controls.len()).map_err(err)?;
        self.controls.apply(&mut self.scene.controller, &c);
        Ok(())
    }

    /// Names of `controller`: `robot/joint.<signal parameter>`, `….kp`, `….kd`.
    #[getter]
    fn controller_names(&self) -> Vec<String> {
        self.controls
            .names(&self.scene.model, &self.scene.controller)
    }

    /// Physics vector `[mass_scale, gravity.x, gravity.y, gravity.z,
    /// contact.mu, contact.s, contact.kappa]` (contact entries only with
    /// contact). `mass_scale` reads 1 and scales the current masses when set.
    #[getter]
    fn get_physics<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        physics_values(&self.scene).into_pyarray(py)
    }

    #[setter]
    fn set_physics(&mut self, p: PyReadonlyArray1<f64>) -> PyResult<()> {
        apply_physics(&mut self.scene, p.as_slice()?).map_err(err)
    }

    /// Names of `physics`.
    #[getter]
    fn physics_names(&self) -> Vec<String> {
        physics_names(&self.scene)
    }

    /// Initial coordinates `θ^0` (charted rotations: the rotation vector
    /// relative to the initial chart, 0 for a scene's own start).
    #[getter]
    fn get_q0<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.scene.q0.data.as_vec().clone().into_pyarray(py)
    }

    #[setter]
    fn set_q0(&mut self, q: PyReadonlyArray1<f64>) -> PyResult<()> {
        self.scene.q0 = vector("q0", q.as_slice()?, self.scene.model.ndof()).map_err(err)?;
        Ok(())
    }

    /// Initial velocities `θ̇^0`.
    #[getter]
    fn get_qdot0<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.scene.qdot0.data.as_vec().clone().into_pyarray(py)
    }

    #[setter]
    fn set_qdot0(&mut self, q: PyReadonlyArray1<f64>) -> PyResult<()> {
        self.scene.qdot0 = vector("qdot0", q.as_slice()?, self.scene.model.ndof()).map_err(err)?;
        Ok(())
    }

    /// Adjoint gradients of `loss` (a dict or list of dicts in the task
    /// file's `loss:` format) over `steps` steps (default: the scene's).
    /// Returns a dict of numpy arrays: `loss` (float), `design`,
    /// `controller`, `physics` (as the vectors above), `q0`, `qdot0`
    /// (initial state), `attachments` (nlinks×3). One forward and one
    /// backward pass, GIL released.
    #[pyo3(signature = (loss, steps=None))]
    fn gradient<'py>(
        &self,
        py: Python<'py>,
        loss: &Bound<'py, PyAny>,
        steps: Option<usize>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let steps = steps.unwrap_or(self.scene.steps);
        let loss = loss_from_py(&self.scene, loss, steps)?;
        let scene = &self.scene;
        let g = py
            .detach(|| {
                let mut rec = forward(scene, steps)?;
                backward_of(&mut rec, &loss)
            })
            .map_err(err)?;
        let out = PyDict::new(py);
        out.set_item("loss", g.loss)?;
        out.set_item(
            "design",
            self.design
                .gradient(&g)
                .data
                .as_vec()
                .clone()
                .into_pyarray(py),
        )?;
        out.set_item(
            "controller",
            self.controls
                .gradient(&g)
                .data
                .as_vec()
                .clone()
                .into_pyarray(py),
        )?;
        let p = physics_values(scene);
        out.set_item(
            "physics",
            physics_gradient(scene.contact.is_some(), &p, &g).into_pyarray(py),
        )?;
        out.set_item("q0", g.q0.data.as_vec().clone().into_pyarray(py))?;
        out.set_item("qdot0", g.qdot0.data.as_vec().clone().into_pyarray(py))?;
        let att: Vec<Vec<f64>> = g.attachments.iter().map(|a| vec![a.x, a.y, a.z]).collect();
        out.set_item(
            "attachments",
            numpy::PyArray2::from_vec2(py, &att).map_err(err)?,
        )?;
        Ok(out)
    }

    /// The loss alone (forward pass only), as `gradient(...)["loss"]`.
    #[pyo3(signature = (loss, steps=None))]
    fn loss(&self, py: Python<'_>, loss: &Bound<'_, PyAny>, steps: Option<usize>) -> PyResult<f64> {
        let steps = steps.unwrap_or(self.scene.steps);
        let loss = loss_from_py(&self.scene, loss, steps)?;
        let scene = &self.scene;
        py.detach(|| {
            let rec = forward(scene, steps)?;
            Ok::<_, String>(sdrs::diff::loss_of(&rec.sim.model, &rec.tape, &loss))
        })
        .map_err(err)
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({}: {} links, {} coordinates)",
            self.scene.source.display(),
            self.scene.model.links.len(),
            self.scene.model.ndof()
        )
    }
}

/// `robot/link` per link.
pub fn link_names(scene: &Scene) -> Vec<String> {
    let m = &scene.model;
    m.links
        .iter()
        .map(|l| format!("{}/{}", m.robots[l.robot].name, l.name))
        .collect()
}
