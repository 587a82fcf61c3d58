//! Persistent simulation state: the two most recent configurations (the
//! position-level scheme is a two-step method), the one before them (for
//! the Newton solve's initial guess only) and the rotation charts.

use crate::kinematics::link_poses;
use crate::math::{Pose, so3};
use crate::model::Model;
use nalgebra::{DVector, Matrix3, Vector3};

/// Rotation-vector charts are re-centred when `‖φ‖` exceeds this (rad),
/// keeping `exp` far from its singular set `‖φ‖ = 2π`.
pub const CHART_RECENTER: f64 = 1.0;

/// State after step `t`.
#[derive(Clone, Debug)]
pub struct SimState {
    /// Number of completed steps.
    pub step: usize,
    /// Time `t·Δt` (s).
    pub time: f64,
    /// `θ^t`.
    pub q: DVector<f64>,
    /// `θ^{t−1}` (in the same charts as `q`).
    pub q_prev: DVector<f64>,
    /// `θ^{t−2}` (in the same charts as `q`) when known: `None` in an
    /// initial state. Read only by the quadratic predictor
    /// ([`crate::sim::Predictor::Quadratic`]), i.e. by the initial guess of
    /// the next step's Newton solve, never by the dynamics.
    pub q_prev2: Option<DVector<f64>>,
    /// `θ^{t−3}` (in the same charts as `q`) when known, for the cubic
    /// predictor ([`crate::sim::Predictor::Cubic`]) only; `None` until three
    /// steps have been taken from an initial state.
    pub q_prev3: Option<DVector<f64>>,
    /// Whether the cubic guess of the last step was closer (max norm) to its
    /// solution than the quadratic one (both formed from the states before
    /// it; `false` until both exist). Read only by
    /// [`crate::sim::Predictor::Adaptive`].
    pub cubic_closer: bool,
    /// Chart centres `R_c` of spherical/free joints.
    pub charts: Vec<Matrix3<f64>>,
    /// `A^t`.
    pub poses: Vec<Pose>,
    /// `A^{t−1}`.
    pub poses_prev: Vec<Pose>,
}

impl SimState {
    /// Initial state from `θ^0`, `θ̇^0`: `θ^{−1} = θ^0 − Δt θ̇^0` (first-order
    /// start; a body in free fall then lags the analytic parabola by
    /// `g t Δt / 2`). For charted joints `θ̇` of the rotation coordinates is
    /// the body-frame angular velocity (chart centred on the initial
    /// orientation, so `φ^0 = 0`).
    pub fn new(
        model: &Model,
        q0: DVector<f64>,
        qdot0: &DVector<f64>,
        charts: Vec<Matrix3<f64>>,
        dt: f64,
    ) -> Self {
        let q_prev = &q0 - qdot0 * dt;
        let poses = link_poses(model, &q0, &charts);
        let poses_prev = link_poses(model, &q_prev, &charts);
        SimState {
            step: 0,
            time: 0.0,
            q: q0,
            q_prev,
            q_prev2: None,
            q_prev3: None,
            cubic_closer: false,
            charts,
            poses,
            poses_prev,
        }
    }

    /// Moves a chart centre onto the current orientation when its rotation
    /// vector grew past [`CHART_RECENTER`]: `R_c ← R_c exp(φ^t)`, `φ^t ← 0`,
    /// `φ^{t−1} ← log(R_c'ᵀ R_c exp(φ^{t−1}))` (and `φ^{t−2}`, `φ^{t−3}` alike). Poses
    /// are unchanged.
    pub fn recenter_charts(&mut self, model: &Model) {
        for link in &model.links {
            let Some(c) = link.chart else { continue };
            let o = link.dof_offset + link.joint.chart_offset();
            let phi = Vector3::new(self.q[o], self.q[o + 1], self.q[o + 2]);
            if phi.norm() <= CHART_RECENTER {
                continue;
            }
            let old = self.charts[c];
            let new = old * so3::exp(&phi);
            let rechart = |q: &mut DVector<f64>| {
                let phi = Vector3::new(q[o], q[o + 1], q[o + 2]);
                let phi_new = so3::log(&(new.transpose() * old * so3::exp(&phi)));
                q.rows_mut(o, 3).copy_from(&phi_new);
            };
            rechart(&mut self.q_prev);
            for older in [&mut self.q_prev2, &mut self.q_prev3].into_iter().flatten() {
                rechart(older);
            }
            self.q.rows_mut(o, 3).fill(0.0);
            self.charts[c] = new;
        }
    }

    /// The coordinates reported to users: charted rotation coordinates are
    /// replaced by the absolute rotation vector `log(R_c exp(φ))`.
    pub fn reported_q(&self, model: &Model) -> DVector<f64> {
        let mut out = self.q.clone();
        for link in &model.links {
            let Some(c) = link.chart else { continue };
            let o = link.dof_offset + link.joint.chart_offset();
            let phi = Vector3::new(self.q[o], self.q[o + 1], self.q[o + 2]);
            let abs = so3::log(&(self.charts[c] * so3::exp(&phi)));
            out.rows_mut(o, 3).copy_from(&abs);
        }
        out
    }
}
