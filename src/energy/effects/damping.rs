//! Viscous joint damping: a generalized force `τ = −c θ̇` on each coordinate.
//!
//! Position-level potential (paper, eq. `SDRS`, added to the step objective):
//!
//! ```text
//! D(θ) = Σ_k c_k/(2Δt) · (θ_k − θ_k^t)²            (J)
//! ∂D/∂θ_k = c_k (θ_k − θ_k^t)/Δt = c_k θ̇_k          (the damping force)
//! ∂²D/∂θ_k² = c_k/Δt
//! ```
//!
//! with `θ̇ = (θ − θ^t)/Δt` the backward-difference velocity of the step.
//! Units: `c` in N·m·s/rad (revolute) or N·s/m (prismatic). Adjoint
//! (`Φ = Σ_k λ_k c_k (θ_k − θ_k^t)/Δt`): `∂Φ/∂θ_k^t = −λ_k c_k/Δt`,
//! `∂Φ/∂c_k = λ_k (θ_k − θ_k^t)/Δt`.

use super::JointCoeffs;
use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::energy::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::kinematics::Kinematics;
use nalgebra::DVector;

/// The damping term over a set of coordinates.
#[derive(Clone, Debug)]
pub struct JointDamping(pub JointCoeffs);

impl Energy for JointDamping {
    fn name(&self) -> &'static str {
        "joint_damping"
    }

    fn accumulate(
        &mut self,
        ctx: &StepContext,
        q: &DVector<f64>,
        _kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        self.0
            .accumulate_diagonal_quadratic(1.0 / ctx.dt, |k| q[k] - ctx.q_prev[k], need, acc);
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
        for (k, c, slot) in self.0.iter() {
            let l = dir.lambda[k];
            out.q_prev[k] -= l * c * inv_dt;
            if let Some(s) = slot {
                *out.effect(s) += l * (q[k] - ctx.q_prev[k]) * inv_dt;
            }
        }
        Ok(())
    }
}
