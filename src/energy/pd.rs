//! Stable-PD controller term (paper, `pbad.tex`):
//! `U_pd = Σ_k k_p,k (θ*_k − θ_k)² + k_d,k (θ̇*_k − (θ_k − θ_k^t)/Δt)²` (J).
//!
//! Note the paper's convention has no factor ½: the restoring generalized
//! force is `2 k_p (θ* − θ)`, and the damping force is `(2 k_d/Δt)(θ̇* − θ̇)`.
//! Units: `k_p` in J/rad² (or J/m²), `k_d` in J·s²/rad².
//!
//! The channels of a free root joint's pose target are not per coordinate:
//! they are handled by [`super::pd_pose`] (chart-free), called from here so
//! that the controller's work stays one term (`pd`).

use super::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::kinematics::Kinematics;
use nalgebra::DVector;

/// The PD term; targets come from the step context.
#[derive(Default, Clone, Debug)]
pub struct PdController;

impl Energy for PdController {
    fn name(&self) -> &'static str {
        "pd"
    }

    fn kind(&self) -> crate::energy::TermKind {
        crate::energy::TermKind::Controller
    }

    fn accumulate(
        &mut self,
        ctx: &StepContext,
        q: &DVector<f64>,
        kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        let inv_dt = 1.0 / ctx.dt;
        for (ch, t) in ctx.targets.iter().enumerate() {
            if in_pose_target(ctx, ch) {
                continue;
            }
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
        super::pd_pose::accumulate(ctx, kin, need, acc);
        Ok(())
    }

    /// `Φ = Σ_k λ_k (−2k_p e_p − 2k_d e_v/Δt)` with `e_p = θ* − θ`,
    /// `e_v = θ̇* − (θ − θ^{t−1})/Δt`. Channel gradients are ordered as the
    /// controller's targets: `(∂/∂θ*, ∂/∂θ̇*, ∂/∂k_p, ∂/∂k_d)`.
    fn vjp(
        &mut self,
        ctx: &StepContext,
        q: &DVector<f64>,
        kin: &Kinematics,
        dir: &AdjointDirection,
        out: &mut VjpAccumulator,
    ) -> Result<(), EnergyError> {
        let inv_dt = 1.0 / ctx.dt;
        for (ch, t) in ctx.targets.iter().enumerate() {
            if in_pose_target(ctx, ch) {
                continue;
            }
            let k = t.dof;
            let l = dir.lambda[k];
            let ep = t.q - q[k];
            let ev = t.qdot - (q[k] - ctx.q_prev[k]) * inv_dt;
            out.q_prev[k] -= 2.0 * t.kd * l * inv_dt * inv_dt;
            let c = &mut out.channels[ch];
            c[0] -= 2.0 * t.kp * l;
            c[1] -= 2.0 * t.kd * l * inv_dt;
            c[2] -= 2.0 * ep * l;
            c[3] -= 2.0 * ev * l * inv_dt;
        }
        super::pd_pose::vjp(ctx, kin, dir, out);
        Ok(())
    }
}

/// Whether channel `ch` belongs to a free root's pose target.
pub(crate) fn in_pose_target(ctx: &StepContext, ch: usize) -> bool {
    ctx.pose_targets
        .iter()
        .any(|p| (p.first..p.first + 6).contains(&ch))
}
