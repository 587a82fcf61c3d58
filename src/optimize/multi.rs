//! Several trajectories optimized collectively (paper, `evaluation.tex`:
//! "the gripper sequentially grasps 4 objects … we optimize these 4
//! trajectories collectively").
//!
//! A task with `trajectories:` is one [`Problem`] holding one
//! [`Trajectory`] per scene, sharing one design vector `d` and one
//! controller vector `c`; the loss and its gradients are
//! sums over the trajectories,
//! `L(d, c) = Σ_j L_j(θ_j^{1…H_j}(d, c))`, `∇L = Σ_j ∇L_j`.
//! The trajectories run in parallel (rayon); the sum is taken afterwards in
//! the task's order, so the result is bitwise the same for any number of
//! threads.

use super::grasp::GraspSpec;
use super::task::{LossSpec, TaskSpec};
use super::trajectory::{self, Trajectory};
use super::{ControlSpace, DesignSpace, Evaluation, OptimizeError, Problem, TaskError};
use crate::diff::When;
use nalgebra::DVector;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One trajectory of a collective task.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TrajectorySpec {
    /// Scene file, relative to the task file.
    pub scene: String,
    /// Steps `H_j` (default: the task's `horizon`, else the scene's `steps`).
    #[serde(default)]
    pub horizon: Option<usize>,
    /// The loss terms of this trajectory (as the task's `loss`).
    pub loss: Vec<LossSpec>,
    /// The grasp metric of this trajectory (see [`super::grasp`]).
    #[serde(default)]
    pub grasp: Option<GraspSpec>,
}

/// Checks that a stage window lies within the horizon.
pub fn check_when(l: &LossSpec, horizon: usize) -> Result<(), String> {
    let when = match l {
        LossSpec::LinkPoint { when, .. }
        | LossSpec::Joint { when, .. }
        | LossSpec::Com { when, .. }
        | LossSpec::Relative { when, .. } => *when,
    };
    match when {
        When::Window { from, to } if !(from < to && to <= horizon) => Err(format!(
            "the window {{from: {from}, to: {to}}} needs from < to <= horizon ({horizon})"
        )),
        _ => Ok(()),
    }
}

/// Loads a task with `trajectories:` (called by [`Problem::load`]): one
/// [`super::Trajectory`] per entry, sharing the design and controller
/// spaces of the first (each entry's must be the same, checked).
pub fn load(path: &Path, task: TaskSpec, design: bool) -> Result<Problem, TaskError> {
    let invalid = |element: String, msg: String| TaskError::Invalid {
        path: path.into(),
        element,
        msg,
    };
    if task.trajectories.is_empty() {
        return Err(invalid(
            "scene".into(),
            "a task needs `scene` (one trajectory) or `trajectories` (several)".into(),
        ));
    }
    if !task.scene.is_empty() || !task.loss.is_empty() || task.grasp.is_some() {
        return Err(invalid(
            "trajectories".into(),
            "with `trajectories`, give `scene`, `loss` and `grasp` per trajectory only".into(),
        ));
    }
    let mut trajectories = Vec::with_capacity(task.trajectories.len());
    let mut shared: Option<(DesignSpace, ControlSpace)> = None;
    for (j, t) in task.trajectories.iter().enumerate() {
        let spec = TaskSpec {
            scene: t.scene.clone(),
            horizon: t.horizon.or(task.horizon),
            loss: t.loss.clone(),
            trajectories: Vec::new(),
            grasp: t.grasp.clone(),
            ..task.clone()
        };
        let (traj, ds, cs) = trajectory::build(path, &spec, design).map_err(|e| match e {
            TaskError::Invalid { element, msg, .. } => {
                invalid(format!("trajectories[{j}].{element}"), msg)
            }
            e => e,
        })?;
        if let Some(first) = &shared {
            same_spaces(first, (&ds, &cs), &trajectories[0], &traj)
                .map_err(|m| invalid(format!("trajectories[{j}]"), m))?;
        } else {
            shared = Some((ds, cs));
        }
        trajectories.push(traj);
    }
    let (design_space, controls) = shared.expect("at least one trajectory");
    Ok(Problem {
        task_path: path.into(),
        task,
        design: design_space,
        controls,
        trajectories,
    })
}

/// The shared design and controller spaces must be the same in every
/// trajectory (same robot first in every scene, same designable links):
/// the same variables (names, bounds) mapped the same way into each model,
/// and the same initial controller values.
fn same_spaces(
    (da, ca): &(DesignSpace, ControlSpace),
    (db, cb): (&DesignSpace, &ControlSpace),
    a: &Trajectory,
    b: &Trajectory,
) -> Result<(), String> {
    if da.vars.len() != db.vars.len()
        || da
            .vars
            .iter()
            .zip(&db.vars)
            .any(|(x, y)| x.name != y.name || x.lower != y.lower || x.upper != y.upper)
    {
        return Err(
            "its design space differs from trajectories[0]'s (the designed robot must be the same, listed first)"
                .into(),
        );
    }
    if ca.values(&a.controller) != cb.values(&b.controller) {
        return Err("its controller parameters differ from trajectories[0]'s".into());
    }
    if da != db || ca != cb {
        return Err(
            "its design or controller variables act on other links or joints than in trajectories[0] (the designed robot must be the same, listed first)"
                .into(),
        );
    }
    Ok(())
}

/// Runs `one` on every trajectory in parallel and folds the results with
/// `add` in trajectory order (the same sum for any thread count); an error
/// names its trajectory.
fn sum_in_order<T: Send>(
    p: &Problem,
    one: impl Fn(&Trajectory) -> Result<T, OptimizeError> + Sync,
    mut add: impl FnMut(&mut T, T),
) -> Result<T, OptimizeError> {
    let parts: Vec<Result<T, OptimizeError>> = p.trajectories.par_iter().map(&one).collect();
    let mut out: Option<T> = None;
    for (j, r) in parts.into_iter().enumerate() {
        let x = r.map_err(|e| OptimizeError::Trajectory {
            index: j,
            source: Box::new(e),
        })?;
        match out.as_mut() {
            None => out = Some(x),
            Some(o) => add(o, x),
        }
    }
    out.ok_or(OptimizeError::NoTrajectories)
}

/// The summed loss alone ([`Problem::trajectory_loss`] of every trajectory,
/// summed in trajectory order as [`evaluate`] does).
pub fn loss_value(p: &Problem, d: &DVector<f64>, c: &DVector<f64>) -> Result<f64, OptimizeError> {
    sum_in_order(p, |t| p.trajectory_loss(t, d, c), |s, l| *s += l)
}

/// The summed evaluation (see the module docs). `grads` and `model` are the
/// first trajectory's; the timings are sums (CPU seconds).
pub fn evaluate(
    p: &Problem,
    d: &DVector<f64>,
    c: &DVector<f64>,
) -> Result<Evaluation, OptimizeError> {
    sum_in_order(
        p,
        |t| {
            let mut e = p.evaluate_trajectory(t, d, c)?;
            e.parts_design = vec![e.grad_design.clone()];
            Ok(e)
        },
        |o, e| {
            o.loss += e.loss;
            o.grad_design += &e.grad_design;
            o.parts_design.extend(e.parts_design);
            o.grad_controller += &e.grad_controller;
            o.forward_seconds += e.forward_seconds;
            o.backward_seconds += e.backward_seconds;
        },
    )
}
