//! Co-design: shape and controller optimization with adjoint gradients
//! (paper, `problem.tex`: `min_{d∈D, c∈C} L(θ^H)` by projected gradient).

pub mod checkpoint;
pub mod controls;
pub mod design;
pub mod error;
pub mod grasp;
pub mod grasp_metrics;
pub mod method;
pub mod metric;
pub mod metrics;
pub mod multi;
pub mod names;
pub mod output;
pub mod report;
pub mod rest;
pub mod task;
pub mod trajectory;

pub use controls::ControlSpace;
pub use design::DesignSpace;
pub use error::OptimizeError;
pub use task::TaskSpec;
pub use trajectory::Trajectory;

use crate::diff::{Gradients, Loss, LossTerm, backward, record};
use crate::model::Model;
use crate::scene::Scene;
use method::{Adam, Radii, RadiusSettings};
use nalgebra::{DVector, Vector3};
use std::path::{Path, PathBuf};
use std::time::Instant;
use task::{LossSpec, Method, RadiusRule};

/// A problem with a task file.
#[derive(Debug, thiserror::Error)]
pub enum TaskError {
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: malformed task: {msg}", path.display())]
    Parse { path: PathBuf, msg: String },
    #[error("{}: {element}: {msg}", path.display())]
    Invalid {
        path: PathBuf,
        element: String,
        msg: String,
    },
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
}

/// A ready-to-run co-design task: one design space and one controller
/// space shared by a list of trajectories (one for a task with `scene:`,
/// several for one with `trajectories:`; see [`multi`]). The loss and its
/// gradients are sums over the trajectories.
#[derive(Clone)]
pub struct Problem {
    pub task_path: PathBuf,
    /// The task as written.
    pub task: TaskSpec,
    /// The design variables `d` (names, bounds; the map into each
    /// trajectory's model, the same in every trajectory: checked on load).
    pub design: DesignSpace,
    /// The controller variables `c` (the same in every trajectory).
    pub controls: ControlSpace,
    /// The trajectories, in task order (at least one).
    pub trajectories: Vec<Trajectory>,
}

impl Problem {
    /// Loads a task and its scene. `design = false` optimizes the controller only.
    pub fn load(path: &Path, design: bool) -> Result<Problem, TaskError> {
        Self::from_parsed(path, read_task(path)?, design)
    }

    /// [`Problem::load`] for a run with `seed`. The same, except for a
    /// controller-only run (`design = false`) of a task with
    /// `optimizer.design_init_noise > 0` and a `design:` section: that run
    /// starts from the co-design run's perturbed robot for the same seed,
    /// held fixed — the task is loaded with its design space, the design of
    /// [`start`]`(seed)` is applied to every trajectory's model
    /// ([`Problem::fix_design`]), and the design space is dropped. So
    /// `--design off --seed S` is the controller-only twin of `--seed S`
    /// on the same robot. (Without the noise the design space is never
    /// built, as before, so those runs are unchanged bit for bit.)
    pub fn load_for_seed(path: &Path, design: bool, seed: u64) -> Result<Problem, TaskError> {
        let task = read_task(path)?;
        let noisy_twin = !design && task.optimizer.design_init_noise > 0.0 && task.design.is_some();
        let mut p = Self::from_parsed(path, task, design || noisy_twin)?;
        if noisy_twin {
            let (d, _) = start(&p, seed);
            p.fix_design(&d);
        }
        Ok(p)
    }

    /// A problem from a parsed task of either form (`scene:` or
    /// `trajectories:`).
    fn from_parsed(path: &Path, task: TaskSpec, design: bool) -> Result<Problem, TaskError> {
        if !task.trajectories.is_empty() || task.scene.is_empty() {
            return multi::load(path, task, design);
        }
        Self::from_spec(path, task, design)
    }

    /// Applies design `d` to every trajectory's model and drops the design
    /// space: the problem then optimizes the controller alone on that robot.
    pub fn fix_design(&mut self, d: &DVector<f64>) {
        for t in &mut self.trajectories {
            self.design.apply(&mut t.model, d);
        }
        self.design = DesignSpace::default();
    }

    /// A problem from a parsed single-scene task (`path` names the task file
    /// in errors and anchors relative scene paths).
    pub fn from_spec(path: &Path, task: TaskSpec, design: bool) -> Result<Problem, TaskError> {
        let (t, design_space, controls) = trajectory::build(path, &task, design)?;
        Ok(Problem {
            task_path: path.into(),
            task,
            design: design_space,
            controls,
            trajectories: vec![t],
        })
    }

    /// The first trajectory (the only one of a single-scene task).
    pub fn first(&self) -> &Trajectory {
        &self.trajectories[0]
    }

    /// The first trajectory, to change it (its scene's settings, horizon).
    pub fn first_mut(&mut self) -> &mut Trajectory {
        &mut self.trajectories[0]
    }

    /// Gives every trajectory the provider of the contact terms its scene
    /// needs when the core does not implement its `contact.model`.
    pub fn set_contact_factory(&mut self, f: crate::scene::SharedContactFactory) {
        for t in &mut self.trajectories {
            t.contact_factory = Some(f.clone());
        }
    }

    /// Loss and gradients at design `d` and controller `c` (forward +
    /// backward), with timings: the sum over the trajectories
    /// ([`multi::evaluate`]); one trajectory's evaluation as is.
    pub fn evaluate(
        &self,
        d: &DVector<f64>,
        c: &DVector<f64>,
    ) -> Result<Evaluation, OptimizeError> {
        match self.trajectories.as_slice() {
            [t] => self.evaluate_trajectory(t, d, c),
            _ => multi::evaluate(self, d, c),
        }
    }

    /// Trajectory `t`'s scene at design `d` and controller `c` (what
    /// [`Problem::evaluate_trajectory`] simulates).
    pub fn scene_at(&self, t: &Trajectory, d: &DVector<f64>, c: &DVector<f64>) -> Scene {
        let mut model = t.model.clone();
        self.design.apply(&mut model, d);
        for r in &t.rest {
            r.place(&mut model);
        }
        let mut controller = t.controller.clone();
        self.controls.apply(&mut controller, c);
        let mut scene = t.scene.clone();
        scene.model = model;
        scene.controller = controller;
        scene
    }

    /// The loss alone at design `d` and controller `c`: the forward
    /// simulation without the adjoint pass (about half of
    /// [`Problem::evaluate`]'s cost; for finite-difference checks). Summed
    /// over the trajectories like [`Problem::evaluate`] (same order), and
    /// bitwise equal to its `loss`.
    pub fn loss_value(&self, d: &DVector<f64>, c: &DVector<f64>) -> Result<f64, OptimizeError> {
        match self.trajectories.as_slice() {
            [t] => self.trajectory_loss(t, d, c),
            _ => multi::loss_value(self, d, c),
        }
    }

    /// [`Problem::loss_value`] of trajectory `t` alone.
    pub fn trajectory_loss(
        &self,
        t: &Trajectory,
        d: &DVector<f64>,
        c: &DVector<f64>,
    ) -> Result<f64, OptimizeError> {
        let scene = self.scene_at(t, d, c);
        let mut sim = t.simulator(&scene)?;
        let tape = record(&mut sim, t.horizon)?;
        Ok(crate::diff::backward::loss_of(&scene.model, &tape, &t.loss))
    }

    /// [`Problem::evaluate`] of trajectory `t` alone.
    pub fn evaluate_trajectory(
        &self,
        t: &Trajectory,
        d: &DVector<f64>,
        c: &DVector<f64>,
    ) -> Result<Evaluation, OptimizeError> {
        let scene = self.scene_at(t, d, c);
        let model = scene.model.clone();
        let mut sim = t.simulator(&scene)?;
        let t0 = Instant::now();
        let tape = record(&mut sim, t.horizon)?;
        let forward = t0.elapsed().as_secs_f64();
        let mut grads = match t.factory_for(&scene)? {
            None => backward(&mut sim, &tape, &t.loss)?,
            Some(f) => backward(&mut scene.adjoint_simulator_with(f)?, &tape, &t.loss)?,
        };
        for r in &t.rest {
            r.add_gradient(&model, &mut grads);
        }
        if !grads.unavailable.is_empty() {
            return Err(OptimizeError::Unavailable {
                terms: grads.unavailable.iter().map(|t| t.to_string()).collect(),
            });
        }
        let gd = self.design.gradient(&grads);
        let gc = self.controls.gradient(&grads);
        Ok(Evaluation {
            loss: grads.loss,
            grad_design: gd,
            grad_controller: gc,
            parts_design: Vec::new(),
            forward_seconds: forward,
            backward_seconds: grads.seconds,
            grads,
            model,
        })
    }
}

/// The loss of a task's `loss:` terms on `model` (link, joint and robot
/// names resolved, `when` windows checked against `horizon`); `path` names
/// the task file in errors (`loss[i]: …`).
pub fn build_loss(
    path: &Path,
    model: &Model,
    specs: &[LossSpec],
    horizon: usize,
) -> Result<Loss, TaskError> {
    let invalid = |element: &str, msg: String| TaskError::Invalid {
        path: path.into(),
        element: element.into(),
        msg,
    };
    let mut loss = Loss::default();
    for (i, l) in specs.iter().enumerate() {
        let el = format!("loss[{i}]");
        let bad = |e: names::NameError| invalid(&el, e.to_string());
        loss.terms.push(match l {
            LossSpec::LinkPoint {
                link,
                point,
                target,
                weight,
                when,
            } => LossTerm::LinkPoint {
                link: names::link(model, link).map_err(bad)?,
                point: Vector3::from(*point),
                target: Vector3::from(*target),
                weight: *weight,
                when: *when,
            },
            LossSpec::Joint {
                joint,
                index,
                target,
                weight,
                when,
            } => {
                let li = names::joint(model, joint).map_err(bad)?;
                if *index >= model.links[li].ndof() {
                    return Err(invalid(
                        &el,
                        format!("joint {joint} has {} coordinate(s)", model.links[li].ndof()),
                    ));
                }
                LossTerm::Joint {
                    dof: model.links[li].dof_offset + index,
                    target: *target,
                    weight: *weight,
                    when: *when,
                }
            }
            LossSpec::Com {
                robot,
                target,
                axes,
                weight,
                when,
            } => {
                let r = names::robot(model, robot).map_err(bad)?;
                LossTerm::CenterOfMass {
                    links: model.robots[r].links.clone().collect(),
                    target: Vector3::from(*target),
                    axes: Vector3::from(*axes),
                    weight: *weight,
                    when: *when,
                }
            }
            LossSpec::Relative {
                link,
                point,
                to_link,
                to_point,
                offset,
                weight,
                when,
            } => LossTerm::Relative {
                link_a: names::link(model, link).map_err(bad)?,
                point_a: Vector3::from(*point),
                link_b: names::link(model, to_link).map_err(bad)?,
                point_b: Vector3::from(*to_point),
                offset: Vector3::from(*offset),
                weight: *weight,
                when: *when,
            },
        });
    }
    for (i, l) in specs.iter().enumerate() {
        multi::check_when(l, horizon).map_err(|m| invalid(&format!("loss[{i}].when"), m))?;
    }
    Ok(loss)
}

/// Tie groups of every robot's `design.ties`, as `(link, hull, vertex)`.
pub(crate) fn robot_ties(scene: &Scene, model: &Model) -> Result<Vec<design::TieGroup>, String> {
    let mut out = Vec::new();
    for r in &scene.spec.robots {
        let Some(d) = &r.design else { continue };
        for (k, group) in d.ties.iter().enumerate() {
            let mut g = Vec::new();
            for v in group {
                let l = names::link(model, &format!("{}/{}", r.name, v.link))
                    .map_err(|e| format!("{k}: {e}"))?;
                let ok = model.links[l]
                    .hulls
                    .get(v.hull)
                    .is_some_and(|h| v.vertex < h.x_local.len());
                if !ok {
                    return Err(format!(
                        "robot {} tie {k}: no vertex {} in hull {} of {}",
                        r.name, v.vertex, v.hull, v.link
                    ));
                }
                g.push((l, v.hull, v.vertex));
            }
            out.push(g);
        }
    }
    Ok(out)
}

/// One forward + backward evaluation.
pub struct Evaluation {
    pub loss: f64,
    pub grad_design: DVector<f64>,
    pub grad_controller: DVector<f64>,
    /// Each trajectory's design gradient, in task order, for a task with
    /// `trajectories:` (`grad_design` is their sum); empty otherwise.
    pub parts_design: Vec<DVector<f64>>,
    pub forward_seconds: f64,
    pub backward_seconds: f64,
    pub grads: Gradients,
    /// The model the evaluation ran (design applied).
    pub model: Model,
}

/// One row of `history.csv`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct IterRecord {
    pub iter: usize,
    pub loss: f64,
    pub best_loss: f64,
    pub grad_design_norm: f64,
    pub grad_controller_norm: f64,
    pub radius_design: f64,
    pub radius_controller: f64,
    pub accepted: bool,
    pub forward_seconds: f64,
    pub backward_seconds: f64,
    pub wall_seconds: f64,
}

/// The lowest-loss iterate of a run so far.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BestIterate {
    pub iter: usize,
    pub loss: f64,
    pub design: DVector<f64>,
    pub controller: DVector<f64>,
}

/// Result of an optimization: the iterate `optimizer.result` selects
/// ([`task::ResultIterate`]), its loss and iteration, and the history of
/// every iterate.
pub struct Outcome {
    pub history: Vec<IterRecord>,
    pub design: DVector<f64>,
    pub controller: DVector<f64>,
    pub initial_loss: f64,
    pub loss: f64,
    /// The iteration whose iterate this is (0 = the start).
    pub iter: usize,
    /// Why the run stopped before its last iteration, with the error's
    /// causes (an Adam or `radius: fixed` step that could not be simulated
    /// at any of its [`ADAM_RETRIES`] shortenings); `None` when it ran every
    /// iteration.
    pub stopped: Option<String>,
    /// Why a trust-region run ended before its last iteration at a
    /// converged iterate: a trial rounded to the iterate where no later
    /// trial can move ([`method::no_op_is_final`]); every iteration it
    /// skips would have been the same rejected trial, so the result is the
    /// one the full run returns. `None` otherwise.
    pub converged: Option<String>,
    /// `optimizer.plateau`: the iterations after which the run returned to
    /// its best iterate (empty without the option).
    pub plateau_returns: Vec<usize>,
    /// Trial points of this session that could not be simulated (a failed
    /// Newton or contact solve, an interpenetrating start): the trust region
    /// counts each as a rejected step, so many of them shrink its radii to
    /// nothing without any loss being compared; Adam and `radius: fixed`
    /// retry the step at half length (each such iteration counts once).
    pub failed_trials: FailedTrials,
}

/// Trial points that could not be simulated: how many, and the first
/// [`FailedTrials::KEPT`] with their errors and parameters (so that the
/// application can write each as a scene that reproduces the failure).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct FailedTrials {
    pub count: usize,
    /// The first failures.
    pub first: Vec<FailedTrial>,
}

/// One trial point that could not be simulated.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FailedTrial {
    pub iteration: usize,
    /// The error and its causes, `: `-separated.
    pub error: String,
    /// The trial's design and controller vectors (not serialized).
    #[serde(skip)]
    pub design: DVector<f64>,
    #[serde(skip)]
    pub controller: DVector<f64>,
}

impl FailedTrials {
    /// How many failures keep their error message: 3.
    pub const KEPT: usize = 3;

    fn push(
        &mut self,
        it: usize,
        e: &dyn std::error::Error,
        (d, c): (&DVector<f64>, &DVector<f64>),
    ) {
        self.count += 1;
        if self.first.len() < Self::KEPT {
            self.first.push(FailedTrial {
                iteration: it,
                error: error_chain(e),
                design: d.clone(),
                controller: c.clone(),
            });
        }
    }
}

/// How many times Adam halves a step whose trial cannot be simulated (a
/// failed Newton solve, an interpenetrating start) before the run stops:
/// 4, i.e. down to 1/16 of the step.
pub const ADAM_RETRIES: u32 = 4;

/// Runs the optimizer for `iters` iterations; `on_iter` sees each record
/// and the design vector that iteration simulated (after projection).
pub fn optimize(
    p: &Problem,
    iters: usize,
    on_iter: impl FnMut(&IterRecord, &DVector<f64>),
) -> Result<Outcome, OptimizeError> {
    optimize_with(p, iters, &RunOptions::default(), on_iter, |_| {
        Ok::<(), OptimizeError>(())
    })
}

/// Reads and parses a task file (errors name the file).
fn read_task(path: &Path) -> Result<TaskSpec, TaskError> {
    let text = std::fs::read_to_string(path).map_err(|source| TaskError::Io {
        path: path.into(),
        source,
    })?;
    serde_yaml::from_str(&text).map_err(|e| TaskError::Parse {
        path: path.into(),
        msg: e.to_string(),
    })
}

/// Options of [`optimize_with`].
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Seed of the run's randomness (the `optimizer.init_noise` and
    /// `optimizer.design_init_noise` perturbations of the start). Default 0.
    pub seed: u64,
    /// Continue from this state (a checkpoint) instead of the task's start.
    pub resume: Option<checkpoint::State>,
}

/// The run's starting point `(d, c)`: the task's design and controller,
/// the controller perturbed by `optimizer.init_noise` (uniform in
/// `±init_noise`) and then the design by `optimizer.design_init_noise`
/// (uniform in `±design_init_noise` m, clamped to the bounds `D`), both
/// from one ChaCha8 stream seeded by `seed`, when they are positive.
pub fn start(p: &Problem, seed: u64) -> (DVector<f64>, DVector<f64>) {
    use rand::{RngExt, SeedableRng};
    let mut d = p.design.values(&p.first().model);
    let mut c = p.controls.values(&p.first().controller);
    let o = &p.task.optimizer;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    if o.init_noise > 0.0 {
        for x in c.iter_mut() {
            *x += o.init_noise * rng.random_range(-1.0..1.0);
        }
    }
    if o.design_init_noise > 0.0 {
        for x in d.iter_mut() {
            *x += o.design_init_noise * rng.random_range(-1.0..1.0);
        }
        p.design.project(&mut d);
    }
    (d, c)
}

/// [`optimize`] with a seed, an optional state to resume from, and
/// `on_state` called with the full optimizer state after every iteration
/// (for checkpoints). Resuming from the state after iteration `k` of a run
/// gives bitwise the same iterates and losses as that run.
///
/// Phases: [`Run::begin`] (the start or the checkpoint), the first
/// evaluation, then per iteration [`Run::propose`] (the method's step,
/// projected onto the design bounds), the trial evaluation and
/// [`Run::settle`] (accept or reject), and [`Run::outcome`].
pub fn optimize_with<E: Into<OptimizeError>>(
    p: &Problem,
    iters: usize,
    opts: &RunOptions,
    mut on_iter: impl FnMut(&IterRecord, &DVector<f64>),
    mut on_state: impl FnMut(&checkpoint::State) -> Result<(), E>,
) -> Result<Outcome, OptimizeError> {
    let mut run = Run::begin(p, iters, opts)?;
    let mut ev = p.evaluate(&run.d, &run.c)?;
    run.initial_loss = opts.resume.as_ref().map_or(ev.loss, |s| s.initial_loss);
    if opts.resume.is_none() || run.best.is_none() {
        // A fresh start, or a checkpoint from before `best` was kept: the
        // current iterate is the best known.
        run.keep(run.first - 1, ev.loss);
    }
    if opts.resume.is_none() {
        let d = run.d.clone();
        run.record(0, &ev, &d, ev.loss, true, &mut on_iter);
        on_state(&run.state(0)).map_err(Into::into)?;
    }
    let (mut stopped, mut converged) = (None, None);
    for it in run.first..=iters {
        run.return_to_best_on_plateau(p, it, &mut ev)?;
        let (d_new, c_new) = run.propose(p, it, &ev);
        let final_no_op = p.task.optimizer.method == Method::TrustRegion
            && method::no_op_is_final(d_new == run.d && c_new == run.c, run.radii.phase);
        let radii = (run.radii.design, run.radii.controller);
        let trial = p.evaluate(&d_new, &c_new);
        let stop = run.settle(p, it, &mut ev, (d_new, c_new), trial, &mut on_iter)?;
        on_state(&run.state(it)).map_err(Into::into)?;
        if let Some(e) = stop {
            stopped = Some(format!("stopped at iteration {it}: {}", error_chain(&e)));
            break;
        }
        if final_no_op && it < iters {
            converged = Some(format!(
                "converged at iteration {it} of {iters}: the trust-region trial at radii (design {:.3e}, controller {:.3e}) rounds to the iterate, and so would every later one",
                radii.0, radii.1
            ));
            break;
        }
    }
    let mut outcome = run.outcome(p, ev);
    outcome.stopped = stopped;
    outcome.converged = converged;
    Ok(outcome)
}

/// `e` and its causes, `: `-separated; a cause whose text the message
/// already ends with (an error that prints its source) is not repeated.
fn error_chain(e: &dyn std::error::Error) -> String {
    let mut msg = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let text = c.to_string();
        if !msg.ends_with(&text) {
            msg.push_str(": ");
            msg.push_str(&text);
        }
        cause = c.source();
    }
    msg
}

/// Adam's answer to a trial `(d_new, c_new)` from `(d, c)` that could not be
/// simulated (`first`): the same step at half the length from the same
/// iterate, up to [`ADAM_RETRIES`] times. Returns the first trial that
/// `eval` simulates, or the last failure. Halving keeps a projected design
/// inside its box (the box is convex and holds both ends).
fn shorten_until_simulated<T, E>(
    (d, c): (&DVector<f64>, &DVector<f64>),
    (d_new, c_new): (DVector<f64>, DVector<f64>),
    first: E,
    mut eval: impl FnMut(&DVector<f64>, &DVector<f64>) -> Result<T, E>,
) -> Result<(DVector<f64>, DVector<f64>, T), E> {
    let (mut dd, mut dc) = (d_new - d, c_new - c);
    let mut err = first;
    for _ in 0..ADAM_RETRIES {
        dd *= 0.5;
        dc *= 0.5;
        let (d_try, c_try) = (d + &dd, c + &dc);
        match eval(&d_try, &c_try) {
            Ok(t) => return Ok((d_try, c_try, t)),
            Err(e) => err = e,
        }
    }
    Err(err)
}

/// The trust region's radius settings of the task after `returns` returns
/// to the best iterate (`optimizer.plateau`): the steps `(ᾱ_d, ᾱ_c)`
/// scaled by `factor^returns` (1 without a plateau).
fn radius_settings(p: &Problem, returns: usize) -> RadiusSettings {
    let o = &p.task.optimizer;
    let scale = o.plateau.map_or(1.0, |pl| {
        pl.factor.powi(returns.min(i32::MAX as usize) as i32)
    });
    RadiusSettings {
        rule: o.radius,
        step_design: o.step_design * scale,
        step_controller: o.step_controller * scale,
    }
}

/// The optimizer's iterate and bookkeeping during [`optimize_with`].
struct Run {
    /// Current design and controller.
    d: DVector<f64>,
    c: DVector<f64>,
    /// Trust-region radii (design, controller) and, for `radius: split`,
    /// which block the next trial moves.
    radii: Radii,
    adam: (Adam, Adam),
    history: Vec<IterRecord>,
    best: Option<BestIterate>,
    /// `optimizer.plateau`: the iterations after which the run returned to
    /// the best iterate.
    plateau_returns: Vec<usize>,
    /// The first iteration this session runs, and the run's last.
    first: usize,
    iters: usize,
    /// Wall time (s) of the sessions before a resume, and this session's clock.
    wall0: f64,
    t0: Instant,
    /// The loss at the run's start (of the first session, after a resume).
    initial_loss: f64,
    /// This session's trial points that could not be simulated.
    failed: FailedTrials,
}

impl Run {
    /// The task's start ([`start`]) or, with `opts.resume`, the checkpoint's
    /// state (checked against the task's sizes).
    fn begin(p: &Problem, iters: usize, opts: &RunOptions) -> Result<Run, OptimizeError> {
        let o = &p.task.optimizer;
        let (d, c) = start(p, opts.seed);
        let mut run = Run {
            adam: (
                Adam::new(d.len(), o.step_design),
                Adam::new(c.len(), o.step_controller),
            ),
            d,
            c,
            radii: Radii::new(&radius_settings(p, 0)),
            history: Vec::with_capacity(iters + 1),
            best: None,
            plateau_returns: Vec::new(),
            first: 1,
            iters,
            wall0: 0.0,
            t0: Instant::now(),
            initial_loss: f64::NAN,
            failed: FailedTrials::default(),
        };
        if let Some(s) = &opts.resume {
            if s.design.len() != run.d.len() || s.controller.len() != run.c.len() {
                return Err(OptimizeError::CheckpointSize {
                    design: s.design.len(),
                    controller: s.controller.len(),
                    task_design: run.d.len(),
                    task_controller: run.c.len(),
                });
            }
            run.d = s.design.clone();
            run.c = s.controller.clone();
            run.radii = Radii {
                design: s.radius_design,
                controller: s.radius_controller,
                phase: s.phase,
            };
            run.adam = (s.adam_design.clone(), s.adam_controller.clone());
            run.history = s.history.clone();
            run.best = s.best.clone();
            run.plateau_returns = s.plateau_returns.clone();
            run.first = s.iter + 1;
            run.wall0 = run.history.last().map_or(0.0, |r| r.wall_seconds);
        }
        run.t0 = Instant::now();
        Ok(run)
    }

    /// Appends the row of iteration `it` (evaluation `ev` at design `d`,
    /// best loss so far `best`, current radii) and shows it to `on_iter`.
    fn record(
        &mut self,
        it: usize,
        ev: &Evaluation,
        d: &DVector<f64>,
        best: f64,
        accepted: bool,
        on_iter: &mut impl FnMut(&IterRecord, &DVector<f64>),
    ) {
        let r = IterRecord {
            iter: it,
            loss: ev.loss,
            best_loss: best,
            grad_design_norm: ev.grad_design.norm(),
            grad_controller_norm: ev.grad_controller.norm(),
            radius_design: self.radii.design,
            radius_controller: self.radii.controller,
            accepted,
            forward_seconds: ev.forward_seconds,
            backward_seconds: ev.backward_seconds,
            wall_seconds: self.wall0 + self.t0.elapsed().as_secs_f64(),
        };
        on_iter(&r, d);
        self.history.push(r);
    }

    /// Keeps the current iterate as the best if its `loss` is strictly
    /// lower (ties keep the earliest).
    fn keep(&mut self, it: usize, loss: f64) {
        if self.best.as_ref().is_none_or(|b| loss < b.loss) {
            self.best = Some(BestIterate {
                iter: it,
                loss,
                design: self.d.clone(),
                controller: self.c.clone(),
            });
        }
    }

    /// The full optimizer state after iteration `it` (a checkpoint).
    fn state(&self, it: usize) -> checkpoint::State {
        checkpoint::State {
            iter: it,
            design: self.d.clone(),
            controller: self.c.clone(),
            radius_design: self.radii.design,
            radius_controller: self.radii.controller,
            phase: self.radii.phase,
            adam_design: self.adam.0.clone(),
            adam_controller: self.adam.1.clone(),
            initial_loss: self.initial_loss,
            history: self.history.clone(),
            best: self.best.clone(),
            plateau_returns: self.plateau_returns.clone(),
        }
    }

    /// `optimizer.plateau` ([`task::Plateau`]), before iteration `it`'s
    /// trial: after `patience` iterations without a new best loss (counted
    /// from the best iterate's iteration or the last return, whichever is
    /// later), the iterate becomes the best one again and `ev` its evaluation (the same
    /// evaluation a resume from a checkpoint makes), Adam's moments are reset
    /// and both rates scaled by `factor`.
    fn return_to_best_on_plateau(
        &mut self,
        p: &Problem,
        it: usize,
        ev: &mut Evaluation,
    ) -> Result<(), OptimizeError> {
        let Some(pl) = p.task.optimizer.plateau else {
            return Ok(());
        };
        let Some(best) = self.best.as_ref() else {
            return Ok(());
        };
        let since = self
            .plateau_returns
            .last()
            .map_or(best.iter, |&r| r.max(best.iter));
        if it - 1 - since < pl.patience {
            return Ok(());
        }
        (self.d, self.c) = (best.design.clone(), best.controller.clone());
        *ev = p.evaluate(&self.d, &self.c)?;
        let (lr_d, lr_c) = (self.adam.0.lr * pl.factor, self.adam.1.lr * pl.factor);
        self.adam = (Adam::new(self.d.len(), lr_d), Adam::new(self.c.len(), lr_c));
        self.plateau_returns.push(it - 1);
        self.radii = Radii::new(&radius_settings(p, self.plateau_returns.len()));
        Ok(())
    }

    /// The trial point of the next iteration from the gradients of `ev`:
    /// a trust-region step (design: projected-gradient step within the
    /// radius; controller: the normalized gradient scaled by the radius) or
    /// an Adam step on the clipped gradients at iteration `it`'s rates
    /// (`optimizer.step_decay`); the design is projected onto its bounds.
    fn propose(&mut self, p: &Problem, it: usize, ev: &Evaluation) -> (DVector<f64>, DVector<f64>) {
        let o = &p.task.optimizer;
        let scale = method::decay_factor(o.step_decay, it, self.iters);
        let (dd, dc) = match o.method {
            Method::TrustRegion => self.radii.trial(
                (&ev.grad_design, &ev.grad_controller),
                (&self.d, &p.design.lower(), &p.design.upper()),
                o.design_norm,
            ),
            Method::Adam => (
                self.adam.0.step_scaled(
                    &method::clip_norm(
                        &method::clip_parts(&ev.grad_design, &ev.parts_design, o.clip_trajectory),
                        o.clip_design,
                    ),
                    scale,
                ),
                self.adam.1.step_scaled(
                    &method::clip_norm(&ev.grad_controller, o.clip_controller),
                    scale,
                ),
            ),
        };
        let mut d_new = &self.d + dd;
        p.design.project(&mut d_new);
        (d_new, &self.c + dc)
    }

    /// Takes or rejects the trial `(d_new, c_new)` of iteration `it`: Adam
    /// and the trust region under `radius: fixed` always move (a trial that
    /// cannot be simulated is retried shorter, [`Self::move_shorter`]; if
    /// none can be, the iterate stays and the error is returned as `Some`:
    /// the run stops there); the other trust-region rules move on a lower
    /// loss and grow their radii, else keep the iterate, shrink them and
    /// record the trial (a trial that cannot be simulated is a rejected
    /// step).
    fn settle(
        &mut self,
        p: &Problem,
        it: usize,
        ev: &mut Evaluation,
        (d_new, c_new): (DVector<f64>, DVector<f64>),
        trial: Result<Evaluation, OptimizeError>,
        on_iter: &mut impl FnMut(&IterRecord, &DVector<f64>),
    ) -> Result<Option<OptimizeError>, OptimizeError> {
        let o = &p.task.optimizer;
        let rs = radius_settings(p, self.plateau_returns.len());
        let moved = (d_new != self.d, c_new != self.c);
        match (o.method, trial) {
            (Method::Adam, Ok(e)) => self.adam_move(it, ev, (d_new, c_new, e), on_iter),
            (Method::Adam, Err(first)) => {
                return Ok(self.move_shorter(p, it, ev, (d_new, c_new), first, on_iter));
            }
            (Method::TrustRegion, Ok(e)) if rs.rule == RadiusRule::Fixed => {
                self.radii = self.radii.after(&rs, moved, true);
                self.adam_move(it, ev, (d_new, c_new, e), on_iter);
            }
            (Method::TrustRegion, Err(first)) if rs.rule == RadiusRule::Fixed => {
                return Ok(self.move_shorter(p, it, ev, (d_new, c_new), first, on_iter));
            }
            (Method::TrustRegion, Ok(e)) if e.loss < ev.loss => {
                (self.d, self.c, *ev) = (d_new, c_new, e);
                self.radii = self.radii.after(&rs, moved, true);
                self.keep(it, ev.loss);
                let d = self.d.clone();
                self.record(it, ev, &d, ev.loss, true, on_iter);
            }
            (Method::TrustRegion, Ok(e)) => {
                // Rejected: the row shows the trial's loss; the iterate stays.
                self.radii = self.radii.after(&rs, moved, false);
                self.record(it, &e, &d_new, ev.loss, false, on_iter);
            }
            (Method::TrustRegion, Err(e)) => {
                // A trial point that cannot be simulated is a rejected step.
                self.failed.push(it, &e, (&d_new, &c_new));
                self.radii = self.radii.after(&rs, moved, false);
                self.record(it, ev, &d_new, ev.loss, false, on_iter);
            }
        }
        Ok(None)
    }

    /// A move that is always taken (Adam, the trust region's `radius: fixed`)
    /// whose full trial `(d_new, c_new)` could not be simulated (`first`):
    /// counted once as a failed trial (its shortened retries are not trial
    /// points of their own), then retried at half length from the iterate
    /// ([`shorten_until_simulated`]). `Some(error)` when no retry simulates:
    /// the iterate stays and the run stops there.
    fn move_shorter(
        &mut self,
        p: &Problem,
        it: usize,
        ev: &mut Evaluation,
        (d_new, c_new): (DVector<f64>, DVector<f64>),
        first: OptimizeError,
        on_iter: &mut impl FnMut(&IterRecord, &DVector<f64>),
    ) -> Option<OptimizeError> {
        self.failed.push(it, &first, (&d_new, &c_new));
        let step =
            shorten_until_simulated((&self.d, &self.c), (d_new.clone(), c_new), first, |d, c| {
                p.evaluate(d, c)
            });
        match step {
            Ok(trial) => {
                self.adam_move(it, ev, trial, on_iter);
                None
            }
            Err(e) => {
                let best_loss = self.history.iter().map(|h| h.loss).fold(ev.loss, f64::min);
                self.record(it, ev, &d_new, best_loss, false, on_iter);
                Some(e)
            }
        }
    }

    /// Adam's move to the simulated trial `(d, c, e)` of iteration `it`.
    fn adam_move(
        &mut self,
        it: usize,
        ev: &mut Evaluation,
        (d, c, e): (DVector<f64>, DVector<f64>, Evaluation),
        on_iter: &mut impl FnMut(&IterRecord, &DVector<f64>),
    ) {
        (self.d, self.c, *ev) = (d, c, e);
        self.keep(it, ev.loss);
        let best_loss = self.history.iter().map(|h| h.loss).fold(ev.loss, f64::min);
        let d = self.d.clone();
        self.record(it, ev, &d, best_loss, true, on_iter);
    }

    /// The run's result: the best iterate or the last accepted one
    /// (`optimizer.result`), with the whole history.
    fn outcome(self, p: &Problem, ev: Evaluation) -> Outcome {
        // The last accepted iterate's iteration (rejected trust-region
        // trials leave the iterate where it was).
        let last_iter = self
            .history
            .iter()
            .rev()
            .find(|r| r.accepted)
            .map_or(0, |r| r.iter);
        match (p.task.optimizer.result, self.best) {
            (task::ResultIterate::Best, Some(b)) => Outcome {
                history: self.history,
                loss: b.loss,
                design: b.design,
                controller: b.controller,
                initial_loss: self.initial_loss,
                iter: b.iter,
                stopped: None,
                converged: None,
                plateau_returns: self.plateau_returns,
                failed_trials: self.failed,
            },
            _ => Outcome {
                history: self.history,
                loss: ev.loss,
                design: self.d,
                controller: self.c,
                initial_loss: self.initial_loss,
                iter: last_iter,
                stopped: None,
                converged: None,
                plateau_returns: self.plateau_returns,
                failed_trials: self.failed,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trial "simulates" when every coordinate moved less than 0.3.
    fn eval(
        d0: &DVector<f64>,
    ) -> impl FnMut(&DVector<f64>, &DVector<f64>) -> Result<f64, String> + '_ {
        move |d, _c| {
            let step = (d - d0).amax();
            if step < 0.3 {
                Ok(step)
            } else {
                Err(format!("step {step}"))
            }
        }
    }

    #[test]
    fn an_unsimulable_adam_step_is_retried_at_half_length_from_the_same_iterate() {
        let (d, c) = (
            DVector::from_vec(vec![1.0, -1.0]),
            DVector::from_vec(vec![0.5]),
        );
        let trial = (
            DVector::from_vec(vec![2.0, -1.0]),
            DVector::from_vec(vec![1.5]),
        );
        let mut calls = 0;
        let mut inner = eval(&d);
        let r = shorten_until_simulated((&d, &c), trial, "first".to_string(), |a, b| {
            calls += 1;
            inner(a, b)
        });
        // 1.0 failed before the call; 0.5 fails, 0.25 simulates.
        let (d2, c2, step) = r.unwrap();
        assert_eq!(calls, 2);
        assert_eq!(step, 0.25);
        assert_eq!(d2.as_slice(), &[1.25, -1.0]);
        assert_eq!(c2.as_slice(), &[0.75]);
    }

    #[test]
    fn an_adam_step_that_never_simulates_returns_the_last_failure_after_the_retries() {
        let (d, c) = (DVector::from_vec(vec![0.0]), DVector::from_vec(vec![0.0]));
        let trial = (DVector::from_vec(vec![100.0]), DVector::from_vec(vec![0.0]));
        let mut calls = 0;
        let mut inner = eval(&d);
        let r = shorten_until_simulated((&d, &c), trial, "first".to_string(), |a, b| {
            calls += 1;
            inner(a, b)
        });
        assert_eq!(calls, ADAM_RETRIES);
        assert_eq!(r.unwrap_err(), format!("step {}", 100.0 / 16.0));
    }

    #[test]
    fn the_error_chain_lists_every_cause() {
        let e = OptimizeError::Iteration {
            iter: 3,
            source: Box::new(OptimizeError::Invalid {
                element: "x".into(),
                msg: "bad".into(),
            }),
        };
        let s = error_chain(&e);
        assert!(s.starts_with("iteration 3: "), "{s}");
        assert!(s.contains("bad"), "{s}");
        assert_eq!(s.matches("bad").count(), 1, "{s}");
    }

    /// An error whose message already prints its source (as the backward
    /// pass's does) is not followed by that source again.
    #[test]
    fn the_error_chain_does_not_repeat_a_printed_source() {
        #[derive(Debug, thiserror::Error)]
        #[error("backward pass at step 7: {0}")]
        struct Outer(#[source] Inner);
        #[derive(Debug, thiserror::Error)]
        #[error("plane did not converge")]
        struct Inner;
        let s = error_chain(&Outer(Inner));
        assert_eq!(s, "backward pass at step 7: plane did not converge");
    }

    #[test]
    fn failed_trials_count_every_failure_and_keep_the_first_errors() {
        let mut f = FailedTrials::default();
        for it in 1..=5 {
            let e = OptimizeError::Invalid {
                element: format!("trial {it}"),
                msg: "no Newton decrease".into(),
            };
            f.push(it * 2, &e, (&DVector::zeros(1), &DVector::zeros(0)));
        }
        assert_eq!(f.count, 5);
        assert_eq!(f.first.len(), FailedTrials::KEPT);
        assert_eq!(
            f.first.iter().map(|t| t.iteration).collect::<Vec<_>>(),
            [2, 4, 6]
        );
        let e = &f.first[2].error;
        assert!(
            e.contains("trial 3") && e.contains("no Newton decrease"),
            "{e}"
        );
    }
}
