//! The "grasped" metric of a grasping trajectory (written to `summary.json`
//! by `sdrs optimize`).
//!
//! With `c_o(k)` the centre of mass of the object link and `p_g(k)` the
//! origin of the gripper link at time level `k` (world frame), the
//! relative position `r(k) = c_o(k) − p_g(k)` and the lift window
//! `from … H`, the object is **grasped** when both hold:
//! 1. *held*: `max_{from ≤ k ≤ H} ‖r(k) − r(from)‖ ≤ tolerance` — the
//!    object moves with the gripper through the lift (no slip, no drop);
//! 2. *lifted*: `c_o,z(H) − c_o,z(0) ≥ lift` — it left the ground.
//!
//! Defaults: `tolerance = 0.02` m, `lift = 0.05` m.

use super::names;
use super::{OptimizeError, Problem, Trajectory};
use crate::kinematics::link_poses;
use nalgebra::{DVector, Vector3};
use serde::{Deserialize, Serialize};

/// Which links and window define a grasp.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GraspSpec {
    /// The object link (`robot/link`).
    pub object: String,
    /// The gripper link (`robot/link`).
    pub gripper: String,
    /// First time level of the lift window.
    pub from: usize,
    /// Largest drift of the object relative to the gripper (m). Default 0.02.
    #[serde(default = "GraspSpec::default_tolerance")]
    pub tolerance: f64,
    /// Least rise of the object's centre of mass (m). Default 0.05.
    #[serde(default = "GraspSpec::default_lift")]
    pub lift: f64,
}

impl GraspSpec {
    fn default_tolerance() -> f64 {
        0.02
    }
    fn default_lift() -> f64 {
        0.05
    }
}

/// The measured grasp of one trajectory.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct GraspResult {
    pub scene: String,
    pub grasped: bool,
    pub held: bool,
    pub lifted: bool,
    /// `max ‖r(k) − r(from)‖` over the window (m).
    pub max_drift: f64,
    /// `c_o,z(H) − c_o,z(0)` (m).
    pub rise: f64,
}

/// Simulates every trajectory of `p` at `(d, c)` that has a grasp spec and
/// measures it (trajectories run in parallel; results in task order).
pub fn measure(
    p: &Problem,
    d: &DVector<f64>,
    c: &DVector<f64>,
) -> Result<Vec<GraspResult>, OptimizeError> {
    use rayon::prelude::*;
    p.trajectories
        .par_iter()
        .filter(|t| t.grasp.is_some())
        .map(|t| measure_one(p, t, d, c))
        .collect()
}

fn measure_one(
    p: &Problem,
    t: &Trajectory,
    d: &DVector<f64>,
    c: &DVector<f64>,
) -> Result<GraspResult, OptimizeError> {
    let g = t.grasp.as_ref().expect("filtered");
    let scene = p.scene_at(t, d, c);
    let model = scene.model.clone();
    let invalid = |element: &str, msg: String| OptimizeError::Invalid {
        element: element.into(),
        msg,
    };
    let obj = names::link(&model, &g.object).map_err(|e| invalid("grasp.object", e.to_string()))?;
    let grip =
        names::link(&model, &g.gripper).map_err(|e| invalid("grasp.gripper", e.to_string()))?;
    if g.from > t.horizon {
        return Err(invalid(
            "grasp.from",
            format!("{} is beyond the horizon {}", g.from, t.horizon),
        ));
    }
    let fm = model.first_moment[obj];
    let c_local = Vector3::new(fm[0], fm[1], fm[2]) / fm[3];
    let mut sim = t.simulator(&scene)?;
    let at = |sim: &crate::sim::Simulator| {
        let poses = link_poses(&model, &sim.state.q, &sim.state.charts);
        let co = crate::math::transform_point(&poses[obj], &c_local);
        let pg = poses[grip].column(3).into_owned();
        (co, co - pg)
    };
    let (c0, _) = at(&sim);
    let (mut r_from, mut drift) = (Vector3::zeros(), 0.0f64);
    let mut last = c0;
    for k in 0..=t.horizon {
        if k > 0 {
            sim.step().map_err(|err| OptimizeError::StepOf {
                path: t.scene.source.clone(),
                step: k,
                err,
            })?;
        }
        let (co, r) = at(&sim);
        if k == g.from {
            r_from = r;
        }
        if k >= g.from {
            drift = drift.max((r - r_from).norm());
        }
        last = co;
    }
    let rise = last.z - c0.z;
    let held = drift <= g.tolerance;
    let lifted = rise >= g.lift;
    Ok(GraspResult {
        scene: t.scene.source.display().to_string(),
        grasped: held && lifted,
        held,
        lifted,
        max_drift: drift,
        rise,
    })
}
