//! Parameters of the friction potential (`μ`, `Δt`, `ε_v`, `ε_f`) and the tangent basis `B` of a
//! plane normal.

use nalgebra::{Matrix3x2, Vector3};

use crate::contact::error::FrictionError;

/// Parameters of the friction potential.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrictionParams {
    /// Coulomb friction coefficient `μ ≥ 0` (dimensionless). Default `0.5`.
    pub mu: f64,
    /// Time step `Δt > 0` in seconds. Default `0.01`.
    pub dt: f64,
    /// Velocity smoothing `ε_v > 0` in `√(‖ẋ − ṗ‖² + ε_v)`, in (m/s)². Below relative speeds of
    /// about `√ε_v` friction behaves like viscous damping. Default `1e-6` (1 mm/s).
    pub eps_velocity: f64,
    /// Force smoothing `ε_f > 0` of `A_ε(f) = √(f² + ε_f) − √ε_f`, in N². The paper uses one `ε`
    /// for both roles; they are separate here because their units differ. Default `1e-6`.
    pub eps_force: f64,
    /// Absolute tolerance on `‖∇_(u,ω) U*‖`. Default `1e-8`; honoured when above the
    /// rounding-noise floor.
    pub inner_tol: f64,
    /// Relative tolerance on `‖∇_(u,ω) U*‖` w.r.t. the total friction-force magnitude on the
    /// plane. Default `1e-10`.
    pub inner_rtol: f64,
    /// Iteration cap of the inner Newton solve. Default `100`.
    pub inner_max_iters: usize,
}

impl Default for FrictionParams {
    fn default() -> Self {
        Self {
            mu: 0.5,
            dt: 0.01,
            eps_velocity: 1e-6,
            eps_force: 1e-6,
            inner_tol: 1e-8,
            inner_rtol: 1e-10,
            inner_max_iters: 100,
        }
    }
}

impl FrictionParams {
    /// Parameters with the given `μ` and `Δt` and default smoothing and solver settings.
    pub fn new(mu: f64, dt: f64) -> Self {
        Self {
            mu,
            dt,
            ..Self::default()
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), FrictionError> {
        let ok = self.mu >= 0.0
            && self.mu.is_finite()
            && self.dt > 0.0
            && self.dt.is_finite()
            && self.eps_velocity > 0.0
            && self.eps_velocity.is_finite()
            && self.eps_force > 0.0
            && self.eps_force.is_finite()
            && self.inner_tol >= 0.0
            && self.inner_tol.is_finite()
            && self.inner_rtol >= 0.0
            && self.inner_rtol.is_finite()
            && self.inner_max_iters > 0;
        if ok {
            Ok(())
        } else {
            Err(FrictionError::InvalidParams {
                mu: self.mu,
                dt: self.dt,
                eps_velocity: self.eps_velocity,
                eps_force: self.eps_force,
            })
        }
    }

    /// `A_ε(f) = √(f² + ε_f) − √ε_f`, written without cancellation as `f²/(√(f² + ε_f) + √ε_f)`.
    pub fn smoothed_force(&self, f: f64) -> f64 {
        let se = self.eps_force.sqrt();
        f * f / ((f * f + self.eps_force).sqrt() + se)
    }
}

/// A deterministic orthonormal tangent basis `B = [b₁ b₂]` of the plane with unit normal `n`
/// (`b₁ × b₂ = n`).
pub fn tangent_basis(n: &Vector3<f64>) -> Matrix3x2<f64> {
    // Cross with the world axis least aligned with n.
    let a = n
        .iter()
        .map(|v| v.abs())
        .enumerate()
        .fold(
            (0, f64::INFINITY),
            |m, (i, v)| {
                if v < m.1 { (i, v) } else { m }
            },
        );
    let mut e = Vector3::zeros();
    e[a.0] = 1.0;
    let b1 = e.cross(n).normalize();
    let b2 = n.cross(&b1);
    Matrix3x2::from_columns(&[b1, b2])
}
