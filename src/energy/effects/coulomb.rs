//! Smoothed Coulomb joint friction: a force of magnitude `f` opposing the
//! joint velocity, smoothed below `√ε`.
//!
//! Position-level potential (the joint analogue of the paper's friction
//! term, `friction.tex`):
//!
//! ```text
//! F(θ) = Σ_k f_k Δt A_ε(v_k),   v_k = (θ_k − θ_k^t)/Δt,
//! A_ε(v) = √(v² + ε) − √ε                                   (J)
//! ∂F/∂θ_k = f_k A_ε'(v_k) = f_k v_k/√(v_k² + ε)              (→ f_k sign v_k)
//! ∂²F/∂θ_k² = f_k A_ε''(v_k)/Δt = f_k ε/((v_k² + ε)^{3/2} Δt)
//! ```
//!
//! Units: `f` in N·m (revolute) or N (prismatic); `ε` in (rad/s)² or
//! (m/s)². Below `|v| ≈ √ε` the friction acts as viscous damping with
//! coefficient `f/√ε`, which keeps Newton's Hessian bounded at `v = 0`
//! (`f/(√ε Δt)`). Adjoint (`Φ = Σ_k λ_k f_k A_ε'(v_k)`):
//! `∂Φ/∂θ_k^t = −λ_k f_k A_ε''(v_k)/Δt`, `∂Φ/∂f_k = λ_k A_ε'(v_k)`.

use super::JointCoeffs;
use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::energy::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::kinematics::Kinematics;
use nalgebra::DVector;

/// Default velocity smoothing `ε` ((rad/s)² or (m/s)²): `√ε` = 0.01.
pub const DEFAULT_EPS: f64 = 1e-4;

/// `(A_ε(v), A_ε'(v), A_ε''(v))`, written to stay exact near `v = 0`
/// (`A_ε = v²/(√(v²+ε) + √ε)` avoids cancellation).
pub fn smooth_abs(v: f64, eps: f64) -> (f64, f64, f64) {
    let r = (v * v + eps).sqrt();
    (v * v / (r + eps.sqrt()), v / r, eps / (r * r * r))
}

/// The friction term over a set of coordinates.
#[derive(Clone, Debug)]
pub struct JointFriction {
    pub coeffs: JointCoeffs,
    /// Velocity smoothing `ε` (> 0).
    pub eps: f64,
}

impl Energy for JointFriction {
    fn name(&self) -> &'static str {
        "joint_friction"
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
        for (k, f, _) in self.coeffs.iter() {
            let v = (q[k] - ctx.q_prev[k]) * inv_dt;
            let (a, da, dda) = smooth_abs(v, self.eps);
            acc.value += f * ctx.dt * a;
            if need >= Need::Gradient {
                acc.dof_grad[k] += f * da;
            }
            if need >= Need::Hessian {
                acc.dof_hess[(k, k)] += f * dda * inv_dt;
            }
        }
        Ok(())
    }

    fn vjp(
        &mut self,
        ctx: &StepContext,
        q: &DVector<f64>,
        _kin: &Kinematics,
        dir: &AdjointDirection,
        out: &mut VjpAccumulator,
    ) -> Result<(), EnergyError> {
        let inv_dt = 1.0 / ctx.dt;
        for (k, f, slot) in self.coeffs.iter() {
            let l = dir.lambda[k];
            let v = (q[k] - ctx.q_prev[k]) * inv_dt;
            let (_, da, dda) = smooth_abs(v, self.eps);
            out.q_prev[k] -= l * f * dda * inv_dt;
            if let Some(s) = slot {
                *out.effect(s) += l * da;
            }
        }
        Ok(())
    }
}
