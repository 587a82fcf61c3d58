//! Stribeck joint friction: a friction that is larger when a joint starts
//! to slide than when it slides fast,
//! `τ(v) = −[f_c + Δf·exp(−(v/v_s)²)]·sign v` (N·m or N), with two
//! parameters: the Coulomb level `f_c ≥ 0` and the breakaway excess
//! `Δf = f_s − f_c ≥ 0`, both smoothed below `√ε` as [`super::coulomb`] is.
//!
//! Why both in one effect: the excess alone cannot be found when the
//! Coulomb level is unknown too. It acts only near velocity reversals, so
//! on data with both it does not beat the baseline alone, and calibration
//! pairs only singles that do (`src/calibrate/select.rs`); the pair
//! `joint_friction + stribeck_friction(excess)` was never formed
//! (`notes/calibration.md`, session 9). With `f_c` in the effect a single
//! candidate is the whole curve, and on Coulomb-only data the parsimony
//! rule prefers the one-parameter `joint_friction`. The Stribeck speed
//! `v_s` is fixed at [`DEFAULT_VS`] (0.1 rad/s or m/s, within the usual
//! 0.01–0.3 rad/s of geared joints): fitting `v_s` as well from positions
//! is poorly conditioned (a larger excess over a narrower band moves the
//! trajectory much as a smaller one over a wider band does).
//!
//! Position-level dissipation potential per coordinate (as in
//! [`super::coulomb`]):
//!
//! ```text
//! F(θ) = Σ_k Δt [f_c,k A_ε(v_k) + Δf_k B(v_k)],   v_k = (θ_k − θ_k^t)/Δt
//! A_ε(v) = √(v² + ε) − √ε = r − √ε                              (rad/s or m/s)
//! B(v) = e^{ε/v_s²} v_s (√π/2) [erf(r/v_s) − erf(√ε/v_s)]      (rad/s or m/s)
//! B'(v) = exp(−(v/v_s)²) · v/r                     (→ exp(−(v/v_s)²) sign v)
//! B''(v) = exp(−(v/v_s)²) · [ε/r³ − 2v²/(v_s² r)]
//! ∂F/∂θ_k = f_c,k A_ε'(v_k) + Δf_k B'(v_k)         (the friction force, N·m)
//! ∂²F/∂θ_k² = [f_c,k A_ε''(v_k) + Δf_k B''(v_k)]/Δt
//! ```
//!
//! with `A_ε' = v/r`, `A_ε'' = ε/r³` ([`super::coulomb::smooth_abs`]).
//! (`d erf(r/v_s)/dv = (2/√π) e^{−r²/v_s²} v/(r v_s)` and `r² = v² + ε`,
//! so the factor `e^{ε/v_s²}` makes `B'` exactly `exp(−(v/v_s)²)·A_ε'(v)`.)
//! `B(0) = 0`, `B ≥ 0`. Units: `f_c`, `Δf` in N·m (revolute) or N
//! (prismatic), `v_s` in rad/s or m/s, `ε` in (rad/s)² or (m/s)².
//!
//! Non-convexity: the excess's force decreases with speed above
//! `|v| ≈ √ε`, so `B'' < 0` there (most negative `≈ −0.86/v_s` at
//! `|v| ≈ v_s/√2`). The exact Hessian is written (the adjoint pass needs
//! it); Newton's step clamps the eigenvalues of the whole step Hessian
//! ([`crate::sim::linear_solve`]), where the inertia term `M/Δt²` usually
//! dominates `Δf·0.86/(v_s Δt)`.
//!
//! Adjoint (`Φ = Σ_k λ_k ∂F/∂θ_k`):
//! `∂Φ/∂θ_k^t = −λ_k [f_c,k A_ε'' + Δf_k B'']/Δt`, `∂Φ/∂f_c,k = λ_k A_ε'(v_k)`,
//! `∂Φ/∂Δf_k = λ_k B'(v_k)`.

use super::JointCoeffs;
use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::energy::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::kinematics::Kinematics;
use nalgebra::DVector;

/// Stribeck speed `v_s` (rad/s or m/s).
pub const DEFAULT_VS: f64 = 0.1;

/// The error function, `erf(x) = (2/√π) ∫₀ˣ e^{−t²} dt`, within 1e-15.
///
/// For `|x| < 6`: the series of positive terms
/// `erf(x) = (2/√π) e^{−x²} Σ_{n≥0} 2ⁿ x^{2n+1} / (1·3·…·(2n+1))` (no
/// cancellation; about `x² + 40` terms). Beyond, `1 − erf(6) < 3e-17`:
/// `±1`.
pub fn erf(x: f64) -> f64 {
    let a = x.abs();
    if a >= 6.0 {
        return x.signum();
    }
    let x2 = a * a;
    let mut term = a;
    let mut sum = a;
    let mut n = 0.0;
    while term > 1e-17 * sum {
        n += 1.0;
        term *= 2.0 * x2 / (2.0 * n + 1.0);
        sum += term;
    }
    let v = 2.0 / std::f64::consts::PI.sqrt() * (-x2).exp() * sum;
    v.min(1.0).copysign(x)
}

/// `erf(a + d) − erf(a)` for `d ≥ 0` without cancellation: for `d < 0.01`
/// Boole's rule on `(2/√π) ∫_a^{a+d} e^{−t²} dt` (error `~(8/945)(d/4)⁷
/// max|f⁽⁶⁾|`, below 1e-16 relative), else the difference of [`erf`].
pub fn erf_increment(a: f64, d: f64) -> f64 {
    if d >= 0.01 {
        return erf(a + d) - erf(a);
    }
    let f = |k: f64| (-(a + 0.25 * k * d) * (a + 0.25 * k * d)).exp();
    let w = 7.0 * (f(0.0) + f(4.0)) + 32.0 * (f(1.0) + f(3.0)) + 12.0 * f(2.0);
    2.0 / std::f64::consts::PI.sqrt() * d / 90.0 * w
}

/// `(B(v), B'(v), B''(v))` of the module doc for speed `vs` and smoothing
/// `eps` (`ε ≪ v_s²` assumed, as with the defaults; `B` through
/// [`erf_increment`] with the increment `A_ε(v)/v_s = (r − √ε)/v_s`
/// written as `v²/((r + √ε) v_s)`, exact near `v = 0`).
pub fn stribeck_shape(v: f64, vs: f64, eps: f64) -> (f64, f64, f64) {
    let r = (v * v + eps).sqrt();
    let s = eps.sqrt();
    let b = (eps / (vs * vs)).exp()
        * vs
        * (0.5 * std::f64::consts::PI.sqrt())
        * erf_increment(s / vs, v * v / ((r + s) * vs));
    let g = (-(v / vs) * (v / vs)).exp();
    let db = g * v / r;
    let ddb = g * (eps / (r * r * r) - 2.0 * v * v / (vs * vs * r));
    (b.max(0.0), db, ddb)
}

/// The Stribeck friction over a set of coordinates: Coulomb levels and
/// excesses on the same coordinates (in the same order).
#[derive(Clone, Debug)]
pub struct StribeckFriction {
    /// `f_c` per coordinate.
    pub coulomb: JointCoeffs,
    /// `Δf` per coordinate (same `dofs` as `coulomb`).
    pub excess: JointCoeffs,
    /// Stribeck speed `v_s` (> 0).
    pub vs: f64,
    /// Velocity smoothing `ε` (> 0).
    pub eps: f64,
}

impl StribeckFriction {
    /// `(k, f_c, Δf, slot of f_c, slot of Δf)`.
    fn terms(&self) -> impl Iterator<Item = (usize, f64, f64, Option<usize>, Option<usize>)> + '_ {
        self.coulomb
            .iter()
            .zip(self.excess.iter())
            .map(|((k, fc, sc), (_, df, sd))| (k, fc, df, sc, sd))
    }

    /// `(F_k/Δt, ∂F/∂θ_k, Δt ∂²F/∂θ_k²)` at velocity `v`.
    fn local(&self, v: f64, fc: f64, df: f64) -> (f64, f64, f64) {
        let (a, da, dda) = super::coulomb::smooth_abs(v, self.eps);
        let (b, db, ddb) = stribeck_shape(v, self.vs, self.eps);
        (fc * a + df * b, fc * da + df * db, fc * dda + df * ddb)
    }
}

impl Energy for StribeckFriction {
    fn name(&self) -> &'static str {
        "stribeck_friction"
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
        for (k, fc, df, _, _) in self.terms() {
            let v = (q[k] - ctx.q_prev[k]) * inv_dt;
            let (f, g, h) = self.local(v, fc, df);
            acc.value += ctx.dt * f;
            if need >= Need::Gradient {
                acc.dof_grad[k] += g;
            }
            if need >= Need::Hessian {
                acc.dof_hess[(k, k)] += h * inv_dt;
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
        for (k, fc, df, sc, sd) in self.terms() {
            let l = dir.lambda[k];
            let v = (q[k] - ctx.q_prev[k]) * inv_dt;
            let (_, _, h) = self.local(v, fc, df);
            out.q_prev[k] -= l * h * inv_dt;
            if let Some(s) = sc {
                *out.effect(s) += l * super::coulomb::smooth_abs(v, self.eps).1;
            }
            if let Some(s) = sd {
                *out.effect(s) += l * stribeck_shape(v, self.vs, self.eps).1;
            }
        }
        Ok(())
    }
}
