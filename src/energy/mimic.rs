//! Mimic joints, tied by a penalty (URDF `<mimic>`; not eliminated):
//!
//! ```text
//! T(θ) = Σ_ties ½ k (θ_d − a θ_m − b)²                          (J)
//! ```
//!
//! for a following coordinate `d`, the followed coordinate `m`, multiplier
//! `a`, offset `b` and stiffness `k` (J/rad² or J/m²). With `e = θ_d − aθ_m
//! − b`: `∂T/∂θ_d = k e`, `∂T/∂θ_m = −a k e`; Hessian `k [1, −a; −a, a²]`
//! (positive semi-definite, so Newton stays convex). The tie holds to
//! `|e| ≈ τ/k` under a generalized force `τ` across it. The term depends on
//! `θ^{t+1}` and constants only: its adjoint contribution is its Hessian
//! in the step's linear system, and its VJP adds nothing.

use super::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::kinematics::Kinematics;
use crate::model::{MimicTie, Model};
use nalgebra::DVector;

/// The mimic-tie term.
#[derive(Clone, Debug, Default)]
pub struct MimicTies {
    pub ties: Vec<MimicTie>,
}

impl MimicTies {
    /// The term for the model's ties; `None` when there are none.
    pub fn from_model(model: &Model) -> Option<MimicTies> {
        (!model.mimics.is_empty()).then(|| MimicTies {
            ties: model.mimics.clone(),
        })
    }
}

impl Energy for MimicTies {
    fn name(&self) -> &'static str {
        "mimic"
    }

    fn accumulate(
        &mut self,
        _ctx: &StepContext,
        q: &DVector<f64>,
        _kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        for t in &self.ties {
            let (d, m, a, k) = (t.dof, t.master, t.multiplier, t.stiffness);
            let e = q[d] - a * q[m] - t.offset;
            acc.value += 0.5 * k * e * e;
            if need >= Need::Gradient {
                acc.dof_grad[d] += k * e;
                acc.dof_grad[m] -= a * k * e;
            }
            if need >= Need::Hessian {
                acc.dof_hess[(d, d)] += k;
                acc.dof_hess[(m, m)] += a * a * k;
                acc.dof_hess[(d, m)] -= a * k;
                acc.dof_hess[(m, d)] -= a * k;
            }
        }
        Ok(())
    }

    /// No parameters and no dependence on earlier states.
    fn vjp(
        &mut self,
        _ctx: &StepContext,
        _q: &DVector<f64>,
        _kin: &Kinematics,
        _dir: &AdjointDirection,
        _out: &mut VjpAccumulator,
    ) -> Result<(), EnergyError> {
        Ok(())
    }
}
