//! Actuator deadband (backlash-like): the PD controller ignores position
//! errors smaller than `b` (rad or m, ≥ 0), as a gear train with play or a
//! servo with a tolerance band does.
//!
//! The stable-PD term ([`crate::energy::pd`], paper `pbad.tex`) has
//! position part `k_p e²` with `e = θ* − θ` (restoring force `2 k_p e`).
//! With the deadband the force is `2 k_p e_b(e)`, the error passed
//! through a smoothed deadband of half-width `b`:
//!
//! ```text
//! e_b(e) = e + ½[A(e − b) − A(e + b)],   A(x) = √(x² + δ²)      (rad or m)
//!        → sign(e)·max(|e| − b, 0)  for ||e| − b| ≫ δ
//! ```
//!
//! (`½[(x−b) + |x−b|] + ½[(x+b) − |x+b|]` with `|·|` smoothed to `A`:
//! C^∞, odd, `0 ≤ e_b' ≤ 1`, and exactly `e` at `b = 0`). The smoothing
//! width `δ` is [`DEFAULT_WIDTH`] = 1e-3 rad (or m): the band's edges are
//! rounded over about `±δ`. The effect is an energy term added next to the
//! PD term, on every controller channel of the affected coordinates
//! (not the pose-target channels of a free root), that turns `k_p e²` into
//! `k_p G(e)` with `G' = 2 e_b`, `G(0) = 0`:
//!
//! ```text
//! S(x) = ½[x A(x) + δ² asinh(x/δ)]            (S' = A, S odd)
//! D(θ) = Σ_ch k_p,ch [S(e − b) − S(e + b) + 2 S(b)]                 (J)
//! ∂D/∂θ_k = −k_p [A(e − b) − A(e + b)]
//! ∂²D/∂θ_k² = k_p [A'(e − b) − A'(e + b)],   A'(x) = x/A(x)
//! ```
//!
//! `D` alone is concave in `θ` (`A'` is increasing); PD plus deadband has
//! `∂²/∂θ² = 2 k_p e_b'(e) ∈ [0, 2k_p]`, so the step Hessian stays positive
//! semi-definite in the position part (the `k_d` and inertia terms keep it
//! definite). At `b = 0` the term is exactly zero (value, gradient,
//! Hessian): the neutral value. Several deadband effects on one coordinate
//! (e.g. `on: all` and `on: elbow`) each subtract their band from `k_p e²`
//! and so do not compose into one band of the summed width.
//!
//! Adjoint (`Φ = Σ_ch λ_k ∂D/∂θ_k`, `k` the channel's coordinate):
//!
//! ```text
//! ∂Φ/∂b    = λ k_p [A'(e − b) + A'(e + b)]
//! ∂Φ/∂θ*   = −λ k_p [A'(e − b) − A'(e + b)]
//! ∂Φ/∂k_p  = −λ [A(e − b) − A(e + b)]
//! ∂Φ/∂θ^t  = ∂Φ/∂θ̇* = ∂Φ/∂k_d = 0
//! ```
//!
//! The `θ*` and `k_p` parts go to the controller channels of the adjoint
//! pass, so actuator gains, actuation delays and signal parameters fitted
//! together with a deadband see it.

use super::JointCoeffs;
use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::energy::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::kinematics::Kinematics;
use nalgebra::DVector;

/// Smoothing width `δ` of the band's edges (rad or m).
pub const DEFAULT_WIDTH: f64 = 1e-3;

/// `(S(x), A(x), A'(x))` of the module doc for width `delta`.
pub fn smooth_parts(x: f64, delta: f64) -> (f64, f64, f64) {
    let a = x.hypot(delta);
    let s = 0.5 * (x * a + delta * delta * (x / delta).asinh());
    (s, a, x / a)
}

/// `e_b(e)`, the smoothed deadband of half-width `b` (module doc).
pub fn deadband(e: f64, b: f64, delta: f64) -> f64 {
    e + 0.5 * (smooth_parts(e - b, delta).1 - smooth_parts(e + b, delta).1)
}

/// The deadband term over a set of coordinates (one half-width each).
#[derive(Clone, Debug)]
pub struct ActuatorDeadband {
    pub coeffs: JointCoeffs,
    /// Smoothing width `δ` (> 0).
    pub width: f64,
}

/// The channels of `ctx` on coordinate `k` (not pose-target channels).
fn channels_on<'a>(ctx: &'a StepContext<'a>, k: usize) -> impl Iterator<Item = usize> + 'a {
    ctx.targets
        .iter()
        .enumerate()
        .filter(move |(ch, t)| t.dof == k && !crate::energy::pd::in_pose_target(ctx, *ch))
        .map(|(ch, _)| ch)
}

impl Energy for ActuatorDeadband {
    fn name(&self) -> &'static str {
        "actuator_deadband"
    }

    fn kind(&self) -> crate::energy::TermKind {
        crate::energy::TermKind::Controller
    }

    fn accumulate(
        &mut self,
        ctx: &StepContext,
        q: &DVector<f64>,
        _kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        for (k, b, _) in self.coeffs.iter() {
            let (s_b, _, _) = smooth_parts(b, self.width);
            for ch in channels_on(ctx, k) {
                let t = &ctx.targets[ch];
                let e = t.q - q[k];
                let (s_m, a_m, da_m) = smooth_parts(e - b, self.width);
                let (s_p, a_p, da_p) = smooth_parts(e + b, self.width);
                acc.value += t.kp * (s_m - s_p + 2.0 * s_b);
                if need >= Need::Gradient {
                    acc.dof_grad[k] -= t.kp * (a_m - a_p);
                }
                if need >= Need::Hessian {
                    acc.dof_hess[(k, k)] += t.kp * (da_m - da_p);
                }
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
        for (k, b, slot) in self.coeffs.iter() {
            let l = dir.lambda[k];
            for ch in channels_on(ctx, k) {
                let t = &ctx.targets[ch];
                let e = t.q - q[k];
                let (_, a_m, da_m) = smooth_parts(e - b, self.width);
                let (_, a_p, da_p) = smooth_parts(e + b, self.width);
                if let Some(s) = slot {
                    *out.effect(s) += l * t.kp * (da_m + da_p);
                }
                let c = &mut out.channels[ch];
                c[0] -= l * t.kp * (da_m - da_p);
                c[2] -= l * (a_m - a_p);
            }
        }
        Ok(())
    }
}
