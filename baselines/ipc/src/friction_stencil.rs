//! IPC's lagged, smoothed friction on one contact stencil (Li et al. 2020,
//! §5): with the lagged normal force magnitude `λ` (N), lagged closest-point
//! weights `w` (relative point `v = Σ_k w_k ΔX_k`, `ΔX = X − X^t`) and
//! lagged orthonormal tangent basis `T` (3×2, ⊥ the contact normal),
//! the tangential relative displacement is `u = Tᵀ v` (m) and
//!
//! `D = μ λ f₀(‖u‖)`, with `ε = ε_v Δt` (m) and
//! `f₀(y) = −y³/(3ε²) + y²/ε + ε/3` for `y < ε`, `y` otherwise,
//! `f₁ = f₀' = −y²/ε² + 2y/ε` for `y < ε`, `1` otherwise.
//!
//! Units: J. Gradient over the stencil: `∂D/∂X_k = μλ w_k T (f₁(‖u‖)/‖u‖) u`;
//! Hessian blocks `μλ w_k w_l T M Tᵀ` with
//! `M = (f₁/y) I + (f₁' − f₁/y) û ûᵀ` (`y = ‖u‖`), whose eigenvalues `f₁/y`
//! and `f₁'` are ≥ 0, so it is PSD without projection (`M → (2/ε) I` as
//! `y → 0`).

use crate::primitive::{Mat12, Vec12};
use nalgebra::{Matrix2, Matrix3x2, Vector2, Vector3};

/// Lagged data of one friction contact.
#[derive(Clone, Debug)]
pub struct FrictionStencil {
    /// Closest-point weights of the four stencil points.
    pub w: [f64; 4],
    /// Tangent basis (columns ⊥ normal, orthonormal).
    pub basis: Matrix3x2<f64>,
    /// `μ λ` (N).
    pub mu_lambda: f64,
}

/// `f₀(y; ε)` (m).
pub fn f0(y: f64, eps: f64) -> f64 {
    if y >= eps {
        y
    } else {
        -y * y * y / (3.0 * eps * eps) + y * y / eps + eps / 3.0
    }
}

/// `f₁(y; ε) = f₀'(y)`.
pub fn f1(y: f64, eps: f64) -> f64 {
    if y >= eps {
        1.0
    } else {
        -y * y / (eps * eps) + 2.0 * y / eps
    }
}

/// `f₁(y)/y`, finite at `y = 0`.
fn f1_over_y(y: f64, eps: f64) -> f64 {
    if y >= eps {
        1.0 / y
    } else {
        -y / (eps * eps) + 2.0 / eps
    }
}

impl FrictionStencil {
    /// Tangential relative displacement `u` from the stencil displacement.
    pub fn tangential(&self, dx: &[Vector3<f64>; 4]) -> Vector2<f64> {
        let v: Vector3<f64> = (0..4).map(|k| dx[k] * self.w[k]).sum();
        self.basis.transpose() * v
    }

    /// Value, and gradient/Hessian over the 12 stencil coordinates when
    /// `derivatives`.
    pub fn evaluate(
        &self,
        dx: &[Vector3<f64>; 4],
        eps: f64,
        derivatives: bool,
    ) -> (f64, Vec12, Mat12) {
        let u = self.tangential(dx);
        let y = u.norm();
        let value = self.mu_lambda * f0(y, eps);
        let (mut g, mut h) = (Vec12::zeros(), Mat12::zeros());
        if derivatives {
            let a = f1_over_y(y, eps);
            let gu = u * a; // ∂f₀/∂u
            let d1 = if y >= eps {
                0.0
            } else {
                -2.0 * y / (eps * eps) + 2.0 / eps
            };
            let m = if y > 0.0 {
                let uh = u / y;
                Matrix2::identity() * a + uh * uh.transpose() * (d1 - a)
            } else {
                Matrix2::identity() * (2.0 / eps)
            };
            let tg = self.basis * gu * self.mu_lambda;
            let tmt = self.basis * m * self.basis.transpose() * self.mu_lambda;
            for k in 0..4 {
                g.fixed_rows_mut::<3>(3 * k).copy_from(&(tg * self.w[k]));
                for l in 0..4 {
                    h.fixed_view_mut::<3, 3>(3 * k, 3 * l)
                        .copy_from(&(tmt * (self.w[k] * self.w[l])));
                }
            }
        }
        (value, g, h)
    }
}

/// An orthonormal tangent basis of the plane ⊥ `n` (unit): `e₁` from the
/// coordinate axis least aligned with `n`, `e₂ = n × e₁`.
pub fn tangent_basis(n: &Vector3<f64>) -> Matrix3x2<f64> {
    let mut axis = Vector3::zeros();
    axis[tangent_axis(n)] = 1.0;
    let e1 = n.cross(&axis).normalize();
    let e2 = n.cross(&e1);
    Matrix3x2::from_columns(&[e1, e2])
}

/// The coordinate axis (0, 1, 2) least aligned with `n`, from which
/// [`tangent_basis`] builds `e₁` (a piecewise-constant choice the adjoint
/// holds fixed).
pub fn tangent_axis(n: &Vector3<f64>) -> usize {
    let a = n.abs();
    if a.x <= a.y && a.x <= a.z {
        0
    } else if a.y <= a.z {
        1
    } else {
        2
    }
}
