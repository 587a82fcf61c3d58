//! Task metrics for `summary.json` (locomotion: distance walked, upright at
//! the horizon, time of the first fall), measured by simulating a design
//! and controller over the task's horizon.
//!
//! Definitions (all in the world frame, positions in m, time in s):
//! - COM `x̄(t) = Σ_l m_l p_l(t) / Σ_l m_l` over the links of `robot`
//!   (`m_l p_l` = the link's first moment of mass, the same COM as the
//!   `com` loss term).
//! - **distance** `= (x̄(H) − x̄(0)) · u`, `u = direction / ‖direction‖`:
//!   signed progress along the task direction.
//! - **tilt** `τ(t) = acos( n · R(t) R(0)ᵀ n )` (degrees): the angle by
//!   which the torso's initially-up axis `R(0)ᵀ n` (torso frame) has turned
//!   away from the reference up `n` (the ground normal, or `up`). It is 0
//!   in the initial pose whatever the torso's own axes are.
//! - **fall**: the first step `t ∈ 1…H` with `τ(t) > fall_tilt_deg`
//!   (default 45°); `first_fall_time = t·Δt`, or `null` if it never happens.
//! - **upright at H**: `τ(H) ≤ fall_tilt_deg` (a robot that fell and got up
//!   again is upright at H but has a `first_fall_time`).

use super::names;
use super::{OptimizeError, Problem, TaskError};
use crate::kinematics::link_poses;
use crate::math::rot;
use nalgebra::{DVector, Matrix3, Rotation3, Unit, Vector3};
use serde::{Deserialize, Serialize};

/// The `metrics:` section of a task.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MetricsSpec {
    /// Robot whose COM is tracked.
    pub robot: String,
    /// Link (`robot/link`) whose tilt decides upright/fall.
    pub torso: String,
    /// Task direction (any length > 0) for `distance`.
    pub direction: [f64; 3],
    /// Reference up. Default: the ground's normal, else `+z`.
    #[serde(default)]
    pub up: Option<[f64; 3]>,
    /// Tilt beyond which the robot counts as fallen (degrees). Default 45.
    #[serde(default = "MetricsSpec::default_tilt")]
    pub fall_tilt_deg: f64,
}

impl MetricsSpec {
    fn default_tilt() -> f64 {
        45.0
    }
}

/// Measured metrics of one design + controller.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct TaskMetrics {
    pub distance: f64,
    pub com_initial: [f64; 3],
    pub com_final: [f64; 3],
    pub tilt_final_deg: f64,
    pub max_tilt_deg: f64,
    pub upright_at_horizon: bool,
    pub first_fall_time: Option<f64>,
    pub first_fall_step: Option<usize>,
    pub fall_tilt_deg: f64,
    pub horizon_time: f64,
}

/// A resolved [`MetricsSpec`].
#[derive(Clone, Debug)]
pub struct Metrics {
    links: Vec<usize>,
    torso: usize,
    direction: Vector3<f64>,
    up: Vector3<f64>,
    fall_tilt_deg: f64,
}

impl Metrics {
    /// Resolves the task's `metrics:` section (None if it has none).
    pub fn from_problem(p: &Problem) -> Result<Option<Metrics>, TaskError> {
        let Some(m) = &p.task.metrics else {
            return Ok(None);
        };
        let invalid = |element: &str, msg: String| TaskError::Invalid {
            path: p.task_path.clone(),
            element: element.into(),
            msg,
        };
        let first = p.first();
        let r = names::robot(&first.model, &m.robot)
            .map_err(|e| invalid("metrics.robot", e.to_string()))?;
        let torso = names::link(&first.model, &m.torso)
            .map_err(|e| invalid("metrics.torso", e.to_string()))?;
        let unit = |v: [f64; 3], el: &str| {
            let v = Vector3::from(v);
            if v.iter().all(|x| x.is_finite()) && v.norm() > 0.0 {
                Ok(v.normalize())
            } else {
                Err(invalid(
                    el,
                    format!("must be a finite non-zero vector, got {v:?}"),
                ))
            }
        };
        let direction = unit(m.direction, "metrics.direction")?;
        let up = match (m.up, &first.scene.spec.ground) {
            (Some(u), _) => unit(u, "metrics.up")?,
            (None, Some(g)) => {
                let axis = unit(g.slope_axis, "ground.slope_axis")?;
                Rotation3::from_axis_angle(&Unit::new_normalize(axis), g.slope_deg.to_radians())
                    * Vector3::z()
            }
            (None, None) => Vector3::z(),
        };
        if !(m.fall_tilt_deg > 0.0 && m.fall_tilt_deg < 180.0) {
            return Err(invalid(
                "metrics.fall_tilt_deg",
                format!("must be in (0, 180), got {}", m.fall_tilt_deg),
            ));
        }
        Ok(Some(Metrics {
            links: first.model.robots[r].links.clone().collect(),
            torso,
            direction,
            up,
            fall_tilt_deg: m.fall_tilt_deg,
        }))
    }

    /// Simulates design `d` and controller `c` over the horizon of the
    /// (first) trajectory and measures (see the module docs).
    pub fn measure(
        &self,
        p: &Problem,
        d: &DVector<f64>,
        c: &DVector<f64>,
    ) -> Result<TaskMetrics, OptimizeError> {
        let t = p.first();
        let scene = p.scene_at(t, d, c);
        let model = scene.model.clone();
        let mut sim = t.simulator(&scene)?;
        let com = |q: &DVector<f64>, charts: &[Matrix3<f64>]| {
            let poses = link_poses(&model, q, charts);
            let mass: f64 = self.links.iter().map(|&i| model.first_moment[i][3]).sum();
            let x: Vector3<f64> = self
                .links
                .iter()
                .map(|&i| poses[i] * model.first_moment[i])
                .sum();
            (x / mass, rot(&poses[self.torso]))
        };
        let (c0, r0) = com(&sim.state.q, &sim.state.charts);
        let body_up = r0.transpose() * self.up;
        let tilt = |r: &Matrix3<f64>| {
            (self.up.dot(&(r * body_up)))
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees()
        };
        let (mut max_tilt, mut fall, mut last) = (0.0f64, None, (c0, 0.0));
        for k in 1..=t.horizon {
            sim.step()?;
            let (x, r) = com(&sim.state.q, &sim.state.charts);
            let a = tilt(&r);
            max_tilt = max_tilt.max(a);
            if fall.is_none() && a > self.fall_tilt_deg {
                fall = Some(k);
            }
            last = (x, a);
        }
        let dt = sim.settings.dt;
        Ok(TaskMetrics {
            distance: (last.0 - c0).dot(&self.direction),
            com_initial: c0.into(),
            com_final: last.0.into(),
            tilt_final_deg: last.1,
            max_tilt_deg: max_tilt,
            upright_at_horizon: last.1 <= self.fall_tilt_deg,
            first_fall_time: fall.map(|t| t as f64 * dt),
            first_fall_step: fall,
            fall_tilt_deg: self.fall_tilt_deg,
            horizon_time: t.horizon as f64 * dt,
        })
    }
}
