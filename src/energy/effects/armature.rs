//! Armature (reflected rotor inertia): an inertia `a` acting on the joint
//! coordinate itself, as a motor's rotor seen through its gearbox.
//!
//! Position-level potential (the coordinate analogue of the inertia term,
//! paper `pbad.tex`):
//!
//! ```text
//! R(θ) = Σ_k a_k/(2Δt²) · (θ_k − 2θ_k^t + θ_k^{t−1})²      (J)
//! ∂R/∂θ_k = a_k (θ_k − 2θ_k^t + θ_k^{t−1})/Δt² = a_k θ̈_k
//! ∂²R/∂θ_k² = a_k/Δt²
//! ```
//!
//! Units: `a` in kg·m² (revolute) or kg (prismatic). Adjoint
//! (`Φ = Σ_k λ_k a_k s_k/Δt²`, `s_k = θ_k − 2θ_k^t + θ_k^{t−1}`):
//! `∂Φ/∂θ_k^t = −2λ_k a_k/Δt²`, `∂Φ/∂θ_k^{t−1} = λ_k a_k/Δt²`,
//! `∂Φ/∂a_k = λ_k s_k/Δt²`.

use super::JointCoeffs;
use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::energy::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::kinematics::Kinematics;
use nalgebra::DVector;

/// The armature term over a set of coordinates.
#[derive(Clone, Debug)]
pub struct Armature(pub JointCoeffs);

impl Energy for Armature {
    fn name(&self) -> &'static str {
        "armature"
    }

    fn accumulate(
        &mut self,
        ctx: &StepContext,
        q: &DVector<f64>,
        _kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        self.0.accumulate_diagonal_quadratic(
            1.0 / (ctx.dt * ctx.dt),
            |k| q[k] - 2.0 * ctx.q_prev[k] + ctx.q_prev2[k],
            need,
            acc,
        );
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
        let inv_dt2 = 1.0 / (ctx.dt * ctx.dt);
        for (k, a, slot) in self.0.iter() {
            let l = dir.lambda[k];
            out.q_prev[k] -= 2.0 * l * a * inv_dt2;
            out.q_prev2[k] += l * a * inv_dt2;
            if let Some(sl) = slot {
                let s = q[k] - 2.0 * ctx.q_prev[k] + ctx.q_prev2[k];
                *out.effect(sl) += l * s * inv_dt2;
            }
        }
        Ok(())
    }
}
