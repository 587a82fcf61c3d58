//! Gravity potential: `G = −Σ_i Σ_m ρ_m g·(X_m^{t+1} − X_m^t)` (J).
//!
//! Measured from the step-`t` positions (a constant shift, which does not
//! change the dynamics) so the objective stays small and the line search is
//! not swamped by round-off. With the first moment `c_i = Σ_m ρ_m x̃_m`:
//! `G = −Σ_i gᵀ(A_i − A_i^t)c_i`, `∂G/∂A_i = −g c_iᵀ`, no pose Hessian.

use super::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::kinematics::Kinematics;
use nalgebra::{DVector, Matrix4};

/// Uniform gravity (the acceleration is read from the step context).
#[derive(Default, Clone, Debug)]
pub struct Gravity;

impl Energy for Gravity {
    fn name(&self) -> &'static str {
        "gravity"
    }

    fn kind(&self) -> crate::energy::TermKind {
        crate::energy::TermKind::Gravity
    }

    fn accumulate(
        &mut self,
        ctx: &StepContext,
        _q: &DVector<f64>,
        kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        let g = ctx.gravity;
        if g == nalgebra::Vector3::zeros() {
            return Ok(());
        }
        for (i, c) in ctx.model.first_moment.iter().enumerate() {
            if c[3] == 0.0 {
                continue;
            }
            let dx = (kin.pose[i] - ctx.poses_prev[i]) * c;
            acc.value -= g.dot(&dx);
            if need >= Need::Gradient {
                acc.link_grad[i] -= g * c.transpose();
            }
        }
        Ok(())
    }

    /// `Φ = −Σ_i gᵀ δA_i c_i`: no pose dependence; `∂Φ/∂g = −Σ δA_i c_i`,
    /// `∂Φ/∂c_i = −δA_iᵀ g` taken to the vertices by
    /// [`crate::model::Link::moments_vjp`] (vertex masses: `−ρ_m [δA_iᵀ g]_{xyz}`);
    /// `Φ` is linear in the masses.
    fn vjp(
        &mut self,
        ctx: &StepContext,
        _q: &DVector<f64>,
        _kin: &Kinematics,
        dir: &AdjointDirection,
        out: &mut VjpAccumulator,
    ) -> Result<(), EnergyError> {
        let g = ctx.gravity;
        for (i, c) in ctx.model.first_moment.iter().enumerate() {
            if c[3] == 0.0 {
                continue;
            }
            let dac = dir.dpose[i] * c;
            out.physical.mass_scale -= g.dot(&dac);
            for e in 0..3 {
                out.physical.gravity[e] -= dac[e];
            }
            if out.want_vertices {
                let w1 = -(dir.dpose[i].transpose() * g);
                ctx.model.links[i].moments_vjp(&Matrix4::zeros(), &w1, &mut out.vertex[i]);
            }
        }
        Ok(())
    }
}
