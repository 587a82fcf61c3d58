//! Mass added to a link: a payload point mass (mass and link-local
//! position) or a scale of the link's own mass.
//!
//! Both add the inertia and gravity of extra lumped mass rigidly attached
//! to link `i` (paper, `pbad.tex`, with the vertex sums collapsed to
//! moments as in [`crate::energy::inertia`]):
//!
//! ```text
//! E = tr(D_i ΔM_i D_iᵀ)/(2Δt²) − gᵀ(A_i − A_i^t) Δc_i          (J)
//! D_i = A_i − 2A_i^t + A_i^{t−1}
//! payload (m kg at p, link frame, m):  ΔM = m p̃ p̃ᵀ,  Δc = m p̃,  p̃ = [p; 1]
//! mass scale σ (dimensionless):        ΔM = (σ − 1) M_i, Δc = (σ − 1) c_i
//! ```
//!
//! (`M_i`, `c_i`: the link's second and first mass moments, so the link's
//! total becomes `σ M_i`.) `∂E/∂A_i = D_i ΔM/Δt² − g Δcᵀ`, pose Hessian
//! `(ΔM ⊗ I₃)/Δt²`. Adjoint, with `W = D_iᵀ δA_i/Δt²` (4×4):
//! `Φ = ⟨W, ΔM⟩ − gᵀ δA_i Δc`, so `∂Φ/∂m = p̃ᵀWp̃ − gᵀδA_i p̃`,
//! `∂Φ/∂p = m[(W + Wᵀ)p̃ − δA_iᵀg]_{xyz}`, `∂Φ/∂σ = ⟨W, M_i⟩ − gᵀδA_i c_i`;
//! pose parts as the inertia term with `ΔM`.

use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::energy::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::kinematics::Kinematics;
use nalgebra::{DVector, Matrix4, Vector3, Vector4};

/// What is added to the link.
#[derive(Clone, Debug, PartialEq)]
pub enum ExtraMassKind {
    /// A point mass `mass` (kg) at `point` (link frame, m).
    Payload { mass: f64, point: Vector3<f64> },
    /// The link's mass multiplied by `scale`.
    Scale { scale: f64 },
}

/// Extra mass on one link; `slot` is the first effect-parameter slot
/// (payload: mass, x, y, z; scale: σ), `None` when not differentiated.
#[derive(Clone, Debug)]
pub struct ExtraMass {
    pub link: usize,
    pub kind: ExtraMassKind,
    pub slot: Option<usize>,
}

impl ExtraMass {
    /// `(ΔM, Δc)` of this term for the given model.
    fn moments(&self, ctx: &StepContext) -> (Matrix4<f64>, Vector4<f64>) {
        match &self.kind {
            ExtraMassKind::Payload { mass, point } => {
                let p = Vector4::new(point.x, point.y, point.z, 1.0);
                (p * p.transpose() * *mass, p * *mass)
            }
            ExtraMassKind::Scale { scale } => (
                ctx.model.second_moment[self.link] * (scale - 1.0),
                ctx.model.first_moment[self.link] * (scale - 1.0),
            ),
        }
    }
}

impl Energy for ExtraMass {
    fn name(&self) -> &'static str {
        match self.kind {
            ExtraMassKind::Payload { .. } => "payload",
            ExtraMassKind::Scale { .. } => "link_mass_scale",
        }
    }

    fn accumulate(
        &mut self,
        ctx: &StepContext,
        _q: &DVector<f64>,
        kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        let i = self.link;
        let (m, c) = self.moments(ctx);
        let inv_dt2 = 1.0 / (ctx.dt * ctx.dt);
        let d = kin.pose[i] - 2.0 * ctx.poses_prev[i] + ctx.poses_prev2[i];
        let dm = d * m;
        let g = ctx.gravity;
        acc.value += 0.5 * inv_dt2 * d.component_mul(&dm).sum()
            - g.dot(&((kin.pose[i] - ctx.poses_prev[i]) * c));
        if need >= Need::Gradient {
            acc.link_grad[i] += dm * inv_dt2 - g * c.transpose();
        }
        if need >= Need::Hessian {
            acc.link_moment[i] += m * inv_dt2;
            acc.link_moment_set = true;
        }
        Ok(())
    }

    fn vjp(
        &mut self,
        ctx: &StepContext,
        _q: &DVector<f64>,
        kin: &Kinematics,
        dir: &AdjointDirection,
        out: &mut VjpAccumulator,
    ) -> Result<(), EnergyError> {
        let i = self.link;
        let (m, c) = self.moments(ctx);
        let inv_dt2 = 1.0 / (ctx.dt * ctx.dt);
        let g = ctx.gravity;
        let da = &dir.dpose[i];
        let dam = da * m * inv_dt2;
        out.pose[i] += dam;
        out.pose_prev[i] -= 2.0 * dam;
        out.pose_prev2[i] += dam;
        let dac = da * c;
        for e in 0..3 {
            out.physical.gravity[e] -= dac[e];
        }
        let d = kin.pose[i] - 2.0 * ctx.poses_prev[i] + ctx.poses_prev2[i];
        let w = d.transpose() * da * inv_dt2;
        let dag = da.transpose() * g;
        match &self.kind {
            ExtraMassKind::Payload { mass, point } => {
                let p = Vector4::new(point.x, point.y, point.z, 1.0);
                if let Some(s) = self.slot {
                    *out.effect(s) += p.dot(&(w * p)) - dag.dot(&p);
                    let gp = ((w + w.transpose()) * p - dag) * *mass;
                    for e in 0..3 {
                        *out.effect(s + 1 + e) += gp[e];
                    }
                }
            }
            ExtraMassKind::Scale { scale } => {
                let (m0, c0) = (&ctx.model.second_moment[i], &ctx.model.first_moment[i]);
                if let Some(s) = self.slot {
                    *out.effect(s) += w.component_mul(m0).sum() - dag.dot(c0);
                }
                if out.want_vertices {
                    // ΔM, Δc are the link's moments times σ − 1.
                    let f = scale - 1.0;
                    let link = &ctx.model.links[i];
                    link.moments_vjp(&(w * f), &(-dag * f), &mut out.vertex[i]);
                }
            }
        }
        Ok(())
    }
}
