//! `sdrs.Task`: a co-design task file (scene, loss, design and controller
//! spaces) — evaluation, the rollout/backward pair behind
//! `sdrs.torch.rollout`, and the Rust optimizer of `sdrs optimize`.

use crate::eval::{Recorded, backward_of, final_state, forward};
use crate::params::{apply_physics, physics_gradient, physics_names, physics_values, vector};
use crate::{SdrsError, err};
use nalgebra::DVector;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sdrs::diff::{Gradients, Loss, LossTerm};
use sdrs::optimize::{ControlSpace, DesignSpace, Problem};
use sdrs::scene::Scene;
use std::path::PathBuf;

/// A co-design task (`sdrs.Task.load(path)`), as `sdrs optimize` loads it.
///
/// `design` (bounded, `design_lower` ≤ d ≤ `design_upper`), `controller`
/// and `physics` are the task's initial vectors; `evaluate`, `rollout` and
/// `optimize` take vectors of those lengths.
#[pyclass(name = "Task", module = "sdrs", frozen)]
pub struct PyTask {
    problem: Problem,
}

fn arr<'py>(py: Python<'py>, v: &DVector<f64>) -> Bound<'py, PyArray1<f64>> {
    v.data.as_vec().clone().into_pyarray(py)
}

fn slice(x: &Option<PyReadonlyArray1<'_, f64>>) -> PyResult<Option<Vec<f64>>> {
    x.as_ref().map(|a| Ok(a.as_slice()?.to_vec())).transpose()
}

impl PyTask {
    fn single(&self) -> PyResult<()> {
        if self.problem.trajectories.len() == 1 {
            Ok(())
        } else {
            Err(SdrsError::new_err(format!(
                "{}: a task of several trajectories: evaluate/rollout take one scene (use optimize)",
                self.problem.task_path.display()
            )))
        }
    }

    /// The task's scene with `d`, `c` and `φ` written in (each defaults to
    /// the task's own values).
    fn configured(
        &self,
        d: Option<Vec<f64>>,
        c: Option<Vec<f64>>,
        p: Option<Vec<f64>>,
    ) -> Result<(Scene, Vec<f64>), String> {
        let pr = &self.problem;
        let d = match d {
            Some(d) => vector("design", &d, pr.design.len())?,
            None => pr.design.values(&pr.first().model),
        };
        let c = match c {
            Some(c) => vector("controller", &c, pr.controls.len())?,
            None => pr.controls.values(&pr.first().controller),
        };
        let mut model = pr.first().model.clone();
        pr.design.apply(&mut model, &d);
        let mut controller = pr.first().controller.clone();
        pr.controls.apply(&mut controller, &c);
        let mut scene = pr.first().scene.clone();
        scene.model = model;
        scene.controller = controller;
        let p = p.unwrap_or_else(|| physics_values(&pr.first().scene));
        apply_physics(&mut scene, &p)?;
        Ok((scene, p))
    }
}

/// `{design, controller, physics}` gradients as numpy arrays.
fn grads_dict<'py>(
    py: Python<'py>,
    design: &DesignSpace,
    controls: &ControlSpace,
    contact: bool,
    p: &[f64],
    g: &Gradients,
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("design", arr(py, &design.gradient(g)))?;
    out.set_item("controller", arr(py, &controls.gradient(g)))?;
    out.set_item("physics", physics_gradient(contact, p, g).into_pyarray(py))?;
    Ok(out)
}

#[pymethods]
impl PyTask {
    /// Loads a task YAML and its scene (`design=False`: the controller
    /// alone, as `sdrs optimize --design off`; with
    /// `optimizer.design_init_noise` its fixed robot is the co-design start
    /// for `seed`, as `--design off --seed SEED`). Raises `SdrsError` naming
    /// the file and element of a problem.
    #[staticmethod]
    #[pyo3(signature = (path, design=true, seed=0))]
    fn load(py: Python<'_>, path: PathBuf, design: bool, seed: u64) -> PyResult<PyTask> {
        let problem = py
            .detach(|| Problem::load_for_seed(&path, design, seed))
            .map_err(err)?;
        Ok(PyTask { problem })
    }

    /// The task file.
    #[getter]
    fn path(&self) -> PathBuf {
        self.problem.task_path.clone()
    }

    /// Steps `H` per rollout.
    #[getter]
    fn horizon(&self) -> usize {
        self.problem.first().horizon
    }

    /// Initial design vector (attachment points and vertices the task
    /// designs, m).
    #[getter]
    fn design<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        arr(py, &self.problem.design.values(&self.problem.first().model))
    }

    /// Names of `design` (`robot/link.attach.x`, vertex coordinates).
    #[getter]
    fn design_names(&self) -> Vec<String> {
        self.problem
            .design
            .vars
            .iter()
            .map(|v| v.name.clone())
            .collect()
    }

    /// Lower bounds of the design box.
    #[getter]
    fn design_lower<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        arr(py, &self.problem.design.lower())
    }

    /// Upper bounds of the design box.
    #[getter]
    fn design_upper<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        arr(py, &self.problem.design.upper())
    }

    /// Initial controller vector (the task's `controller.joints` signal
    /// parameters, and gains with `controller.gains`).
    #[getter]
    fn controller<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        arr(
            py,
            &self
                .problem
                .controls
                .values(&self.problem.first().controller),
        )
    }

    /// Names of `controller` (`robot/joint.<signal parameter>`, gains).
    #[getter]
    fn controller_names(&self) -> Vec<String> {
        self.problem.controls.names(
            &self.problem.first().model,
            &self.problem.first().controller,
        )
    }

    /// The scene's physics vector (see `Scene.physics`).
    #[getter]
    fn physics<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        physics_values(&self.problem.first().scene).into_pyarray(py)
    }

    /// Names of `physics`.
    #[getter]
    fn physics_names(&self) -> Vec<String> {
        physics_names(&self.problem.first().scene)
    }

    /// The optimizer's starting point `(design, controller)` for `seed`
    /// (perturbed by `optimizer.init_noise` and `optimizer.design_init_noise`).
    #[pyo3(signature = (seed=0))]
    fn start<'py>(
        &self,
        py: Python<'py>,
        seed: u64,
    ) -> (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>) {
        let (d, c) = sdrs::optimize::start(&self.problem, seed);
        (arr(py, &d), arr(py, &c))
    }

    /// Loss and gradients at `(design, controller, physics)` (each defaults
    /// to the task's): one forward and one backward pass, GIL released.
    /// Returns `{loss, design, controller, physics}`.
    #[pyo3(signature = (design=None, controller=None, physics=None))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        design: Option<PyReadonlyArray1<'py, f64>>,
        controller: Option<PyReadonlyArray1<'py, f64>>,
        physics: Option<PyReadonlyArray1<'py, f64>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        self.single()?;
        let (d, c, p) = (slice(&design)?, slice(&controller)?, slice(&physics)?);
        let pr = &self.problem;
        let (g, p) = py
            .detach(|| {
                let (scene, p) = self.configured(d, c, p)?;
                let mut rec = forward(&scene, pr.first().horizon)?;
                Ok::<_, String>((backward_of(&mut rec, &pr.first().loss)?, p))
            })
            .map_err(err)?;
        let out = grads_dict(
            py,
            &pr.design,
            &pr.controls,
            pr.first().scene.contact.is_some(),
            &p,
            &g,
        )?;
        out.set_item("loss", g.loss)?;
        Ok(out)
    }

    /// The forward pass of `sdrs.torch.rollout`: simulates `horizon` steps
    /// at `(design, controller, physics)` and keeps the tape for one
    /// `backward`. `output="loss"`: the task's loss; `"state"`: `θ^H`.
    #[pyo3(signature = (design=None, controller=None, physics=None, output="loss"))]
    fn rollout<'py>(
        &self,
        py: Python<'py>,
        design: Option<PyReadonlyArray1<'py, f64>>,
        controller: Option<PyReadonlyArray1<'py, f64>>,
        physics: Option<PyReadonlyArray1<'py, f64>>,
        output: &str,
    ) -> PyResult<PyRollout> {
        self.single()?;
        let state = match output {
            "loss" => false,
            "state" => true,
            o => {
                return Err(SdrsError::new_err(format!(
                    "rollout: output must be \"loss\" or \"state\", got \"{o}\""
                )));
            }
        };
        let (d, c, p) = (slice(&design)?, slice(&controller)?, slice(&physics)?);
        let pr = &self.problem;
        let (rec, p, scene) = py
            .detach(|| {
                let (scene, p) = self.configured(d, c, p)?;
                Ok::<_, String>((forward(&scene, pr.first().horizon)?, p, scene))
            })
            .map_err(err)?;
        let loss = if state {
            f64::NAN
        } else {
            sdrs::diff::loss_of(&rec.sim.model, &rec.tape, &pr.first().loss)
        };
        Ok(PyRollout {
            rec: Some(rec),
            loss_terms: pr.first().loss.clone(),
            design: pr.design.clone(),
            controls: pr.controls.clone(),
            contact: pr.first().scene.contact.is_some(),
            physics: p,
            state,
            loss,
            scene,
            steps: pr.first().horizon,
            backward_done: false,
        })
    }

    /// Runs the Rust optimizer of `sdrs optimize` (the task's method, step
    /// sizes and bounds) for `iters` iterations (default: the task's) from
    /// the start for `seed`, GIL released. Returns `{loss, initial_loss,
    /// history (loss per iteration), design, controller, stopped,
    /// converged, plateau_returns}` (`converged`: why a trust-region run
    /// ended early at a converged iterate, else None; `plateau_returns`: the
    /// iterations after which `optimizer.plateau` returned to the best
    /// iterate) — the same numbers
    /// as `sdrs optimize TASK --seed SEED --iters ITERS`: `design`,
    /// `controller` and `loss` are the iterate `optimizer.result` selects
    /// (default `best`, the lowest loss seen).
    #[pyo3(signature = (iters=None, seed=0))]
    fn optimize<'py>(
        &self,
        py: Python<'py>,
        iters: Option<usize>,
        seed: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let pr = &self.problem;
        let iters = iters.unwrap_or(pr.task.optimizer.iters);
        let opts = sdrs::optimize::RunOptions { seed, resume: None };
        let o = py
            .detach(|| {
                sdrs::optimize::optimize_with(
                    pr,
                    iters,
                    &opts,
                    |_, _| {},
                    |_| Ok::<(), sdrs::optimize::OptimizeError>(()),
                )
            })
            .map_err(|e| SdrsError::new_err(crate::cause_chain(&e)))?;
        let out = PyDict::new(py);
        out.set_item("loss", o.loss)?;
        out.set_item("initial_loss", o.initial_loss)?;
        let h: Vec<f64> = o.history.iter().map(|r| r.loss).collect();
        out.set_item("history", h.into_pyarray(py))?;
        out.set_item("design", arr(py, &o.design))?;
        out.set_item("controller", arr(py, &o.controller))?;
        // Why the run ended early (an Adam step that could not be
        // simulated), else None.
        out.set_item("stopped", o.stopped)?;
        out.set_item("converged", o.converged)?;
        out.set_item("plateau_returns", o.plateau_returns)?;
        Ok(out)
    }

    fn __repr__(&self) -> String {
        format!(
            "Task({}: {} design, {} controller variables, horizon {})",
            self.problem.task_path.display(),
            self.problem.design.len(),
            self.problem.controls.len(),
            self.problem.first().horizon
        )
    }
}

/// A recorded rollout awaiting its backward pass (`Task.rollout`).
#[pyclass(name = "Rollout", module = "sdrs")]
pub struct PyRollout {
    /// The rollout's simulator and tape (`None` only if a backward pass
    /// panicked mid-way).
    rec: Option<Recorded>,
    loss_terms: Loss,
    design: DesignSpace,
    controls: ControlSpace,
    contact: bool,
    physics: Vec<f64>,
    state: bool,
    loss: f64,
    /// The configured scene and horizon (to re-record for a second pass).
    scene: Scene,
    steps: usize,
    backward_done: bool,
}

#[pymethods]
impl PyRollout {
    /// The output: the loss (float) or `θ^H` (numpy array).
    #[getter]
    fn value(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        if self.state {
            let rec = self.rec.as_ref().ok_or_else(used)?;
            Ok(final_state(rec).into_pyarray(py).into_any().unbind())
        } else {
            Ok(self.loss.into_pyobject(py)?.into_any().unbind())
        }
    }

    /// One adjoint pass: the vector–Jacobian product of the output with
    /// `grad` (a float for `output="loss"`, an array of `θ^H`'s length for
    /// `"state"`: the loss `Σ_k grad_k θ^H_k`). Returns `{design,
    /// controller, physics}`. Each call is one adjoint pass over the kept
    /// tape (the same tape and `grad` give bitwise the same result), so
    /// torch may call it once per output row (Jacobians, gradcheck).
    fn backward<'py>(
        &mut self,
        py: Python<'py>,
        grad: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        // The energy terms keep warm starts (separating planes) across
        // calls, so a second pass over the same simulator would start from
        // the first one's: later passes re-record the rollout first
        // (deterministic, so the same tape and the same start as the first).
        if self.backward_done {
            let scene = &self.scene;
            let steps = self.steps;
            self.rec = Some(py.detach(|| forward(scene, steps)).map_err(err)?);
        }
        self.backward_done = true;
        let rec = self.rec.as_mut().ok_or_else(used)?;
        let (loss, scale) = if self.state {
            let w: Vec<f64> = grad.extract()?;
            let level = rec.tape.len();
            if w.len() != rec.sim.model.ndof() {
                return Err(SdrsError::new_err(format!(
                    "backward: grad has {} entries, the state {}",
                    w.len(),
                    rec.sim.model.ndof()
                )));
            }
            let terms = w
                .iter()
                .enumerate()
                .map(|(dof, &coef)| LossTerm::JointLinear { dof, level, coef })
                .collect();
            (Loss { terms }, 1.0)
        } else {
            (self.loss_terms.clone(), grad.extract::<f64>()?)
        };
        let mut g = py.detach(|| backward_of(rec, &loss)).map_err(err)?;
        if scale != 1.0 {
            scale_gradients(&mut g, scale);
        }
        grads_dict(
            py,
            &self.design,
            &self.controls,
            self.contact,
            &self.physics,
            &g,
        )
    }
}

fn used() -> PyErr {
    SdrsError::new_err("this rollout holds no tape")
}

/// `g ← a g` for the parts the parameter vectors read.
fn scale_gradients(g: &mut Gradients, a: f64) {
    for v in g.attachments.iter_mut() {
        *v *= a;
    }
    for v in g.vertices.iter_mut().flatten().flatten() {
        *v *= a;
    }
    for ch in &mut g.channels {
        ch.kp *= a;
        ch.kd *= a;
        ch.signal.iter_mut().for_each(|s| *s *= a);
    }
    let zero = sdrs::diff::PhysicalGrad::default();
    let mut p = zero.clone();
    p.axpy(a, &g.physical);
    g.physical = p;
}
