//! One trajectory of a co-design task: a scene simulated over a horizon
//! with the task's shared design and controller, and the loss on it
//! (paper, `problem.tex`: `L(θ^1 … θ^H)`). A task holds one or several
//! ([`super::Problem::trajectories`]).

use super::grasp::GraspSpec;
use super::{ControlSpace, DesignSpace, OptimizeError, TaskError, TaskSpec};
use crate::control::Controller;
use crate::diff::Loss;
use crate::model::Model;
use crate::scene::Scene;
use std::path::Path;

/// One trajectory: its scene, the model the design acts on, the preset
/// controller, the loss and the horizon.
#[derive(Clone)]
pub struct Trajectory {
    /// The scene (with the task's `optimizer.newton_tol`, if given).
    pub scene: Scene,
    /// The scene's model with the design's connectivity vertices added.
    pub model: Model,
    /// The scene's controller before the task's controller variables apply.
    pub controller: Controller,
    /// The loss on this trajectory (the task's or the trajectory's `loss:`).
    pub loss: Loss,
    /// Steps `H` simulated per evaluation.
    pub horizon: usize,
    /// The grasp metric of this trajectory (`grasp:`), if any.
    pub grasp: Option<GraspSpec>,
    /// Provider of the contact terms of a scene whose `contact.model` the
    /// core does not implement (`ipc`: the baseline's factory, set by the
    /// CLI); `None` runs SDRS scenes only.
    pub contact_factory: Option<crate::scene::SharedContactFactory>,
    /// `design.rest_on_ground`: the placement of each designed free-floating
    /// robot (empty without the option).
    pub rest: Vec<super::rest::RestOnGround>,
}

impl Trajectory {
    /// The factory `scene` needs: `None` for SDRS (or contact-free) scenes,
    /// [`Trajectory::contact_factory`] otherwise (an error without one).
    pub fn factory_for(
        &self,
        scene: &Scene,
    ) -> Result<Option<&dyn crate::scene::ContactModelFactory>, OptimizeError> {
        match scene.contact.as_ref().filter(|c| !c.model.is_sdrs()) {
            None => Ok(None),
            Some(c) => match &self.contact_factory {
                Some(f) => Ok(Some(f.as_ref())),
                None => Err(OptimizeError::NoContactProvider {
                    path: scene.source.clone(),
                    model: c.model.name().to_string(),
                }),
            },
        }
    }

    /// The simulator of `scene` (a variant of this trajectory's scene) with
    /// its contact model: [`Scene::simulator`] for SDRS scenes (unchanged),
    /// the factory's terms otherwise. Its energy balance (each term's work
    /// per step, [`crate::sim::Simulator::energy_balance`]) is off: nothing
    /// in an optimization reads it, and it does not change the trajectory
    /// (`tests/energy_balance.rs`). One iteration of the spider / parallel
    /// jaw tasks: 0.8 % / 0.5 % fewer instructions, the same history
    /// (2026-11-30).
    pub fn simulator(&self, scene: &Scene) -> Result<crate::sim::Simulator, OptimizeError> {
        let mut sim = match self.factory_for(scene)? {
            None => scene.simulator(),
            Some(f) => scene.simulator_with(f)?,
        };
        sim.energy_balance = false;
        Ok(sim)
    }
}

/// The task's `optimizer:` step, clip and noise settings, checked (errors
/// name the task file `path` and the element).
fn check_optimizer(path: &Path, task: &TaskSpec) -> Result<(), TaskError> {
    let invalid = |element: &str, msg: String| TaskError::Invalid {
        path: path.into(),
        element: element.into(),
        msg,
    };
    let o = &task.optimizer;
    if !(o.step_design > 0.0 && o.step_controller > 0.0) {
        return Err(invalid("optimizer", "steps must be positive".into()));
    }
    for (name, clip) in [
        ("optimizer.clip_design", o.clip_design),
        ("optimizer.clip_controller", o.clip_controller),
        ("optimizer.clip_trajectory", o.clip_trajectory),
    ] {
        if let Some(v) = clip.filter(|v| !(*v > 0.0 && v.is_finite())) {
            return Err(invalid(
                name,
                format!("must be positive and finite, got {v}"),
            ));
        }
    }
    if let Some(f) = o.step_decay.filter(|f| !(*f > 0.0 && *f <= 1.0)) {
        return Err(invalid(
            "optimizer.step_decay",
            format!("must be a fraction in (0, 1], got {f}"),
        ));
    }
    if let Some(pl) = &o.plateau {
        let walks =
            o.method == super::task::Method::Adam || o.radius == super::task::RadiusRule::Fixed;
        if !walks {
            return Err(invalid(
                "optimizer.plateau",
                "applies to `method: adam` and the trust region's `radius: fixed` only (the \
                 other radius rules never leave their best iterate)"
                    .into(),
            ));
        }
        if pl.patience == 0 {
            return Err(invalid(
                "optimizer.plateau.patience",
                "must be at least 1 iteration, got 0".into(),
            ));
        }
        if !(pl.factor > 0.0 && pl.factor <= 1.0) {
            return Err(invalid(
                "optimizer.plateau.factor",
                format!("must be a fraction in (0, 1], got {}", pl.factor),
            ));
        }
    }
    for (key, v) in [
        ("optimizer.init_noise", o.init_noise),
        ("optimizer.design_init_noise", o.design_init_noise),
    ] {
        if !(v >= 0.0 && v.is_finite()) {
            return Err(invalid(
                key,
                format!("must be finite and non-negative, got {v}"),
            ));
        }
    }
    Ok(())
}

/// The trajectory of a single-scene task (`task.scene`, `task.loss`,
/// `task.grasp`) and the design and controller spaces on its model; `path`
/// names the task file in errors and anchors the scene path.
pub fn build(
    path: &Path,
    task: &TaskSpec,
    design: bool,
) -> Result<(Trajectory, DesignSpace, ControlSpace), TaskError> {
    let invalid = |element: &str, msg: String| TaskError::Invalid {
        path: path.into(),
        element: element.into(),
        msg,
    };
    if task.version != 1 {
        return Err(invalid(
            "version",
            format!("unsupported task version {}", task.version),
        ));
    }
    let scene_path = path.parent().unwrap_or(Path::new(".")).join(&task.scene);
    let mut scene = Scene::load(&scene_path)?;
    if let Some(t) = task.optimizer.newton_tol {
        if !(t > 0.0 && t.is_finite()) {
            return Err(invalid(
                "optimizer.newton_tol",
                format!("must be positive and finite, got {t}"),
            ));
        }
        scene.settings.newton.tol = t;
    }
    let mut model = scene.model.clone();
    let horizon = task.horizon.unwrap_or(scene.steps);
    if horizon == 0 {
        return Err(invalid("horizon", "must be at least 1".into()));
    }
    check_optimizer(path, task)?;
    let (design_space, controls) = spaces(path, task, design, &scene, &mut model)?;
    if design_space.is_empty() && controls.is_empty() && design {
        // (With `--design off` and a preset controller the run is an
        // evaluation of the initial design, the twin of a co-design run.)
        return Err(invalid("design/controller", "nothing to optimize".into()));
    }
    let loss = super::build_loss(path, &model, &task.loss, horizon)?;
    let rest = rest_on_ground(path, task, &scene, &model)?;
    let t = Trajectory {
        controller: scene.controller.clone(),
        scene,
        model,
        loss,
        horizon,
        grasp: task.grasp.clone(),
        contact_factory: None,
        rest,
    };
    Ok((t, design_space, controls))
}

/// The placements of `design.rest_on_ground` (empty without it): one per
/// robot named in `design.vertices` (with or without `--design off`, so a
/// controller-only twin starts where its co-design run does).
fn rest_on_ground(
    path: &Path,
    task: &TaskSpec,
    scene: &Scene,
    model: &Model,
) -> Result<Vec<super::rest::RestOnGround>, TaskError> {
    let Some(d) = task.design.as_ref().filter(|d| d.rest_on_ground) else {
        return Ok(Vec::new());
    };
    let mut robots = Vec::new();
    for name in &d.vertices {
        let robot = name.split('/').next().unwrap_or_default();
        if let Some(r) = model.robots.iter().position(|r| r.name == robot)
            && !robots.contains(&r)
        {
            robots.push(r);
        }
    }
    super::rest::RestOnGround::build(scene, model, &robots).map_err(|msg| TaskError::Invalid {
        path: path.into(),
        element: "design.rest_on_ground".into(),
        msg,
    })
}

/// The design space (empty with `design = false` or no `design:`) and the
/// controller space of `task` on `model` (connectivity vertices added to it).
fn spaces(
    path: &Path,
    task: &TaskSpec,
    design: bool,
    scene: &Scene,
    model: &mut Model,
) -> Result<(DesignSpace, ControlSpace), TaskError> {
    let invalid = |element: &str, msg: String| TaskError::Invalid {
        path: path.into(),
        element: element.into(),
        msg,
    };
    let ds = match (&task.design, design) {
        (Some(d), true) => {
            if d.bound.is_nan() || d.bound <= 0.0 {
                return Err(invalid(
                    "design.bound",
                    format!("must be positive, got {}", d.bound),
                ));
            }
            let ties =
                super::robot_ties(scene, model).map_err(|e| invalid("robots[].design.ties", e))?;
            DesignSpace::build(model, &d.attachments, &d.vertices, d.bound, &ties)
                .map_err(|e| invalid("design", e.to_string()))?
        }
        _ => DesignSpace::default(),
    };
    let cs = ControlSpace::build(
        model,
        &scene.controller,
        &task.controller.joints,
        task.controller.gains,
    )
    .map_err(|e| invalid("controller", e.to_string()))?;
    Ok((ds, cs))
}
