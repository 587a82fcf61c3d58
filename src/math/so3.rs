//! The SO(3) exponential map and logarithm.
//!
//! `exp(φ) = I + a(θ)[φ]× + b(θ)[φ]×²` with `θ = ‖φ‖`, `a = sin θ/θ`,
//! `b = (1 − cos θ)/θ²` (Rodrigues). The functions are generic over
//! [`num_dual::DualNum`] so joint transforms get exact first and second
//! derivatives; near `θ = 0` the coefficients use their Taylor series in `θ²`
//! (no square root), so derivatives stay exact there too.

use nalgebra::{Matrix3, Vector3};
use num_dual::DualNum;

/// Below this `θ²` the Taylor series is used (truncation error < 1e-24).
const SERIES_THETA2: f64 = 1e-8;

/// Rodrigues coefficients `(sin θ/θ, (1−cos θ)/θ²)` as functions of `θ² = φ·φ`.
pub fn rodrigues_coefficients<D: DualNum<Primitive = f64> + Copy>(theta2: D) -> (D, D) {
    if theta2.re() < SERIES_THETA2 {
        let t4 = theta2 * theta2;
        let a = D::one() - theta2 / 6.0 + t4 / 120.0;
        let b = D::from(0.5) - theta2 / 24.0 + t4 / 720.0;
        (a, b)
    } else {
        let theta = theta2.sqrt();
        (theta.sin() / theta, (D::one() - theta.cos()) / theta2)
    }
}

/// Row-major 3×3 rotation `exp([φ]×)`, generic over dual numbers.
pub fn exp_generic<D: DualNum<Primitive = f64> + Copy>(phi: [D; 3]) -> [D; 9] {
    let theta2 = phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2];
    let (a, b) = rodrigues_coefficients(theta2);
    let [x, y, z] = phi;
    // [φ]×² = φφᵀ − θ² I
    let k2 = |i: usize, j: usize| -> D {
        let p = phi[i] * phi[j];
        if i == j { p - theta2 } else { p }
    };
    let skew = [D::zero(), -z, y, z, D::zero(), -x, -y, x, D::zero()];
    let mut r = [D::zero(); 9];
    for i in 0..3 {
        for j in 0..3 {
            let id = if i == j { D::one() } else { D::zero() };
            r[i * 3 + j] = id + a * skew[i * 3 + j] + b * k2(i, j);
        }
    }
    r
}

/// `exp([φ]×)` for plain `f64`.
pub fn exp(phi: &Vector3<f64>) -> Matrix3<f64> {
    let r = exp_generic([phi.x, phi.y, phi.z]);
    Matrix3::from_row_slice(&r)
}

/// Principal logarithm: the rotation vector `φ` with `‖φ‖ ≤ π` and
/// `exp(φ) = R`. Robust near `θ = 0` and `θ = π`.
pub fn log(r: &Matrix3<f64>) -> Vector3<f64> {
    let rot = nalgebra::Rotation3::from_matrix_unchecked(*r);
    rot.scaled_axis()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_is_orthonormal_and_inverts_log() {
        for phi in [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1e-6, -2e-6, 3e-7),
            Vector3::new(0.3, -1.2, 0.4),
            Vector3::new(0.0, 0.0, std::f64::consts::PI - 1e-4),
        ] {
            let r = exp(&phi);
            assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-14);
            assert!((r.determinant() - 1.0).abs() < 1e-14);
            assert!((log(&r) - phi).norm() < 1e-9, "phi={phi:?}");
        }
    }

    #[test]
    fn exp_series_branch_matches_closed_form_at_the_switch() {
        // Just below the switch the series is used; compare with the closed form.
        let theta = SERIES_THETA2.sqrt() * 0.999;
        let (a, b) = rodrigues_coefficients(theta * theta);
        assert!((a - theta.sin() / theta).abs() < 1e-15);
        assert!(
            (b - (1.0 - theta.cos()) / (theta * theta)).abs() < 1e-8,
            "closed form loses digits here"
        );
        let (a2, b2) = rodrigues_coefficients(1.001f64 * SERIES_THETA2);
        assert!((a2 - a).abs() < 1e-10 && (b2 - b).abs() < 1e-8);
    }
}
