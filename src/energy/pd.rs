//! Stable-PD controller term (paper, `pbad.tex`):
//! `U_pd = Σ_k k_p,k (θ*_k − θ_k)² + k_d,k (θ̇*_k − (θ_k − θ_k^t)/Δt)²` (J).
//!
//! Note the paper's convention has no factor ½: the restoring generalized
//! force is `2 k_p (θ* − θ)`, and the damping force is `(2 k_d/Δt)(θ̇* − θ̇)`.
//! Units: `k_p` in J/rad² (or J/m²), `k_d` in J·s²/rad².

use super::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::kinematics::Kinematics;
use nalgebra::DVector;

/// Target of one controlled coordinate for the current step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PdTarget {
    /// Coordinate index in `θ`.
    pub dof: usize,
    pub kp: f64,
    pub kd: f64,
    /// `θ*^{t+1}`.
    pub q: f64,
    /// `θ̇*^{t+1}`.
    pub qdot: f64,
}

/// The PD term; targets come from the step context.
#[derive(Default, Clone, Debug)]
pub struct PdController;

impl Energy for PdController {
    fn name(&self) -> &'static str {
        "pd"
    }

    fn accumulate(
        &mut self,
        ctx: &StepContext,
        q: &DVector<f64>,
        _kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        let inv_dt = 1.0 / ctx.dt;
        for t in ctx.targets {
            let k = t.dof;
            let ep = t.q - q[k];
            let ev = t.qdot - (q[k] - ctx.q_prev[k]) * inv_dt;
            acc.value += t.kp * ep * ep + t.kd * ev * ev;
            if need >= Need::Gradient {
                acc.dof_grad[k] += -2.0 * t.kp * ep - 2.0 * t.kd * ev * inv_dt;
            }
            if need >= Need::Hessian {
                acc.dof_hess[(k, k)] += 2.0 * t.kp + 2.0 * t.kd * inv_dt * inv_dt;
            }
        }
        Ok(())
    }
}
