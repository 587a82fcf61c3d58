//! IPC's log barrier (Li et al. 2020, eq. 6) on **squared** distances:
//!
//! `b(d, d̂²) = −(d − d̂²)² ln(d / d̂²)` for `0 < d < d̂²`, `0` for `d ≥ d̂²`,
//! `+∞` for `d ≤ 0`,
//!
//! where `d = dist²` (m²) and `d̂` (m) is the activation distance, so the
//! barrier's argument and its threshold are both squared lengths, as in the
//! IPC code and ipc-toolkit (`barrier(d², d̂²)`, `BarrierPotential(d̂)`). `b`
//! has units m⁴; the stiffness `κ` (J/m⁴) is applied by the caller. `b` is
//! C² at `d = d̂²` (value, first and second derivatives vanish there).

use num_dual::DualNum;

/// `b(d, dhat2)` for `d` inside `(0, dhat2)`; callers handle `d ≤ 0` (+∞)
/// and `d ≥ dhat2` (0) before entering dual arithmetic.
pub fn barrier<T: DualNum<Primitive = f64> + Copy>(d: T, dhat2: f64) -> T {
    let t = d - dhat2;
    -(t * t) * (d / dhat2).ln()
}

/// `b` for plain numbers, including the out-of-range cases.
pub fn barrier_value(d: f64, dhat2: f64) -> f64 {
    if d <= 0.0 {
        f64::INFINITY
    } else if d >= dhat2 {
        0.0
    } else {
        barrier(d, dhat2)
    }
}

/// `∂b/∂d = (d̂² − d)(2 ln(d/d̂²) − d̂²/d + 1)` (m²), zero outside `(0, d̂²)`.
pub fn barrier_derivative(d: f64, dhat2: f64) -> f64 {
    if d <= 0.0 || d >= dhat2 {
        return 0.0;
    }
    (dhat2 - d) * (2.0 * (d / dhat2).ln() - dhat2 / d + 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivative_matches_central_differences_up_to_dhat() {
        let dhat2 = 1e-6;
        for k in 1..200 {
            let d = dhat2 * (k as f64 / 200.0);
            let h = 1e-7 * d;
            let fd = (barrier_value(d + h, dhat2) - barrier_value(d - h, dhat2)) / (2.0 * h);
            let an = barrier_derivative(d, dhat2);
            assert!(
                (fd - an).abs() <= 1e-6 * an.abs().max(1e-12),
                "d = {d}: {fd} vs {an}"
            );
        }
        // C¹ at d̂²: value and slope vanish from the left.
        assert!(barrier_value(dhat2 * (1.0 - 1e-9), dhat2) < 1e-27);
        assert!(barrier_derivative(dhat2 * (1.0 - 1e-9), dhat2).abs() < 1e-20);
    }
}
