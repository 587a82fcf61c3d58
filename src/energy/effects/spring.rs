//! Joint spring: a generalized force `τ = −k (θ − θ_ref)` on each
//! coordinate (MuJoCo's joint `stiffness` and `springref`).
//!
//! Potential (paper, eq. `SDRS`: a conservative term of the step objective,
//! evaluated at the end of the step like gravity):
//!
//! ```text
//! S(θ) = Σ_k ½ k_k (θ_k − r_k)²            (J)
//! ∂S/∂θ_k = k_k (θ_k − r_k)                (the spring force, negated)
//! ∂²S/∂θ_k² = k_k
//! ```
//!
//! Units: `k` in N·m/rad (revolute) or N/m (prismatic), `r` in rad or m
//! (MuJoCo's `springref`, in `qpos` units; imported joints have `θ = qpos`).
//! Adjoint (`Φ = Σ_k λ_k k_k (θ_k − r_k)`): no dependence on earlier
//! steps; `∂Φ/∂k_k = λ_k (θ_k − r_k)`, `∂Φ/∂r_k = −λ_k k_k`.

use super::JointCoeffs;
use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::energy::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::kinematics::Kinematics;
use nalgebra::DVector;

/// The spring term over a set of coordinates sharing one stiffness and one
/// rest value; the rest value's parameter slot follows the stiffness's.
#[derive(Clone, Debug)]
pub struct JointSpring {
    /// Coordinates, stiffness `k` and its slot.
    pub coeffs: JointCoeffs,
    /// Rest value `r` (rad or m).
    pub rest: f64,
}

impl Energy for JointSpring {
    fn name(&self) -> &'static str {
        "joint_spring"
    }

    fn accumulate(
        &mut self,
        _ctx: &StepContext,
        q: &DVector<f64>,
        _kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        let r = self.rest;
        self.coeffs
            .accumulate_diagonal_quadratic(1.0, |k| q[k] - r, need, acc);
        Ok(())
    }

    fn vjp(
        &mut self,
        _ctx: &StepContext,
        q: &DVector<f64>,
        _kin: &Kinematics,
        dir: &AdjointDirection,
        out: &mut VjpAccumulator,
    ) -> Result<(), EnergyError> {
        for (k, c, slot) in self.coeffs.iter() {
            let l = dir.lambda[k];
            if let Some(s) = slot {
                *out.effect(s) += l * (q[k] - self.rest);
                *out.effect(s + 1) -= l * c;
            }
        }
        Ok(())
    }
}
