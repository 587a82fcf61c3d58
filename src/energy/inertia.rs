//! Inertia term of position-level dynamics (paper, `pbad.tex`):
//! `I = Σ_i Σ_m ρ_m/(2Δt²) ‖X_m^{t+1} − 2X_m^t + X_m^{t−1}‖²` (J).
//!
//! With `X = A x̃` and `D_i = A_i^{t+1} − 2A_i^t + A_i^{t−1}` (3×4), the sum over a
//! link's vertices collapses to `tr(D_i M_i D_iᵀ)/(2Δt²)` with the 4×4 second
//! moment `M_i = Σ_m ρ_m x̃_m x̃_mᵀ`; its gradient is `∂I/∂A_i = D_i M_i/Δt²`
//! and its pose Hessian is `(M_i ⊗ I₃)/Δt²` (written as the structured block
//! `link_moment`). In generalized coordinates that
//! Hessian is the mass matrix over Δt², which keeps Newton convex for small Δt.

use super::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::kinematics::Kinematics;
use nalgebra::{DVector, Vector4};

/// The inertia term (no parameters: masses come from the links' mass models).
#[derive(Default, Clone, Debug)]
pub struct Inertia;

impl Energy for Inertia {
    fn name(&self) -> &'static str {
        "inertia"
    }

    fn kind(&self) -> crate::energy::TermKind {
        crate::energy::TermKind::Inertia
    }

    fn accumulate(
        &mut self,
        ctx: &StepContext,
        _q: &DVector<f64>,
        kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        let inv_dt2 = 1.0 / (ctx.dt * ctx.dt);
        for (i, m) in ctx.model.second_moment.iter().enumerate() {
            if m[(3, 3)] == 0.0 {
                continue; // massless link
            }
            let d = kin.pose[i] - 2.0 * ctx.poses_prev[i] + ctx.poses_prev2[i];
            let dm = d * m;
            acc.value += 0.5 * inv_dt2 * d.component_mul(&dm).sum();
            if need >= Need::Gradient {
                acc.link_grad[i] += dm * inv_dt2;
            }
            if need >= Need::Hessian {
                acc.link_moment[i] += m * inv_dt2;
                acc.link_moment_set = true;
            }
        }
        Ok(())
    }

    /// `Φ_i = ⟨δA_i, D_i M_i⟩/Δt²`: `∂Φ/∂A^t = δA M/Δt²`, `∂Φ/∂A^{t−1} = −2δA M/Δt²`,
    /// `∂Φ/∂A^{t−2} = δA M/Δt²`; with `W = D_iᵀδA_i/Δt²`, `Φ = ⟨W, M_i⟩` and
    /// `∂Φ/∂x_m` from [`crate::model::Link::moments_vjp`] (vertex masses:
    /// `ρ_m [(W + Wᵀ) x̃_m]_{xyz}`); `Φ` is linear in the masses.
    fn vjp(
        &mut self,
        ctx: &StepContext,
        _q: &DVector<f64>,
        kin: &Kinematics,
        dir: &AdjointDirection,
        out: &mut VjpAccumulator,
    ) -> Result<(), EnergyError> {
        let inv_dt2 = 1.0 / (ctx.dt * ctx.dt);
        for (i, m) in ctx.model.second_moment.iter().enumerate() {
            if m[(3, 3)] == 0.0 {
                continue;
            }
            let da = &dir.dpose[i];
            let dam = da * m * inv_dt2;
            out.pose[i] += dam;
            out.pose_prev[i] -= 2.0 * dam;
            out.pose_prev2[i] += dam;
            let d = kin.pose[i] - 2.0 * ctx.poses_prev[i] + ctx.poses_prev2[i];
            out.physical.mass_scale += d.component_mul(&dam).sum();
            if out.want_vertices {
                let w = d.transpose() * da * inv_dt2;
                ctx.model.links[i].moments_vjp(&w, &Vector4::zeros(), &mut out.vertex[i]);
            }
        }
        Ok(())
    }
}
