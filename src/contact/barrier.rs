//! The locally supported barrier `P_s` of the SDRS contact potential (paper §"Contact Mechanics
//! for Convex Polyhedrons", the function below Eq. `Cons`).
//!
//! ```text
//! P_s(x) = (x − s)⁴ / x⁵    for 0 < x < s,
//!        = 0                for x ≥ s,
//!        = +∞               for x ≤ 0.
//! ```
//!
//! The paper writes `max(0, (x−s)⁴/x⁵)`; that is shorthand only, because `(x−s)⁴/x⁵` is also
//! positive for `x > s`. The support is cut explicitly here.
//!
//! With `t = x − s` the derivatives on `(0, s)` are
//!
//! ```text
//! P'   = t³ (5s − x) / x⁶
//! P''  = 2 t² (x² − 10 s x + 15 s²) / x⁷
//! P''' = −6 t (x³ − 15 s x² + 45 s² x − 35 s³) / x⁸
//! ```
//!
//! All of them vanish as `x → s⁻` (like `t⁴, t³, t², t`), so `P_s` is C³ at `x = s` (not C⁴:
//! `P''''(s⁻) = 24/s⁵`). On `(0, s)`, `P' < 0` and `P'' > 0` (the quadratic
//! `x² − 10sx + 15s²` has its smaller root at `(5 − √10) s ≈ 1.84 s`), so `P_s` is convex and
//! decreasing: every term of the contact potential `U*` is convex in the plane `p`.
//!
//! `x` is a signed, scaled point-to-plane distance (a length when `‖n‖ = 1`); `s` has the same
//! unit. The value is dimensionless up to `1/length` (`P_s ~ 1/x` near 0); the simulator
//! multiplies it by the stiffness κ.

/// Value and the first three derivatives of `P_s` at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BarrierDerivs {
    /// `P_s(x)`.
    pub value: f64,
    /// `P_s'(x)`.
    pub d1: f64,
    /// `P_s''(x)`.
    pub d2: f64,
    /// `P_s'''(x)`.
    pub d3: f64,
}

/// `P_s(x)`; `+∞` for `x ≤ 0`, `0` for `x ≥ s`.
///
/// # Panics
/// Never. `s` is expected in `(0, 1)`; this is checked by the callers that take parameters.
#[inline]
pub fn barrier(x: f64, s: f64) -> f64 {
    if x >= s {
        0.0
    } else if x > 0.0 {
        let t = x - s;
        let t2 = t * t;
        let inv = 1.0 / x;
        let inv2 = inv * inv;
        let inv5 = inv2 * inv2 * inv;
        // Same expression as in `barrier_d2`, so both round identically.
        t2 * t2 * inv5
    } else {
        f64::INFINITY
    }
}

/// `(P_s, P_s', P_s'')` at `x` — the hot-loop variant used by the inner plane solve.
///
/// For `x ≤ 0` it returns the one-sided limits `(+∞, −∞, +∞)`; the solvers never evaluate
/// there (they keep every argument strictly positive).
#[inline]
pub fn barrier_d2(x: f64, s: f64) -> (f64, f64, f64) {
    if x >= s {
        (0.0, 0.0, 0.0)
    } else if x > 0.0 {
        let t = x - s;
        let t2 = t * t;
        let inv = 1.0 / x;
        let inv2 = inv * inv;
        let inv5 = inv2 * inv2 * inv;
        let inv6 = inv5 * inv;
        let inv7 = inv6 * inv;
        let v = t2 * t2 * inv5;
        let d1 = t2 * t * (5.0 * s - x) * inv6;
        let d2 = 2.0 * t2 * (x * x - 10.0 * s * x + 15.0 * s * s) * inv7;
        (v, d1, d2)
    } else {
        (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY)
    }
}

/// Value and first, second and third derivatives of `P_s` at `x` (see the module docs for the
/// formulas). For `x ≥ s` everything is exactly zero; for `x ≤ 0` the one-sided limits
/// `(+∞, −∞, +∞, −∞)` are returned.
#[inline]
pub fn barrier_derivs(x: f64, s: f64) -> BarrierDerivs {
    if x >= s {
        BarrierDerivs {
            value: 0.0,
            d1: 0.0,
            d2: 0.0,
            d3: 0.0,
        }
    } else if x > 0.0 {
        let (value, d1, d2) = barrier_d2(x, s);
        let t = x - s;
        let inv = 1.0 / x;
        let inv2 = inv * inv;
        let inv4 = inv2 * inv2;
        let inv8 = inv4 * inv4;
        let d3 =
            -6.0 * t * (x * x * x - 15.0 * s * x * x + 45.0 * s * s * x - 35.0 * s * s * s) * inv8;
        BarrierDerivs { value, d1, d2, d3 }
    } else {
        BarrierDerivs {
            value: f64::INFINITY,
            d1: f64::NEG_INFINITY,
            d2: f64::INFINITY,
            d3: f64::NEG_INFINITY,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::{DualNum, third_derivative};

    /// Central finite difference of `f` at `x` with step `h`.
    fn cfd(f: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
        (f(x + h) - f(x - h)) / (2.0 * h)
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / a.abs().max(b.abs()).max(1e-300)
    }

    /// Points spread over (0, s), with extra points near 0 and just below s.
    fn sample_points(s: f64) -> Vec<f64> {
        let mut xs = vec![];
        for k in 1..40 {
            xs.push(s * k as f64 / 40.0);
        }
        for k in 1..6 {
            xs.push(s * 10f64.powi(-k)); // near 0
            xs.push(s * (1.0 - 10f64.powi(-k))); // just inside s
        }
        xs
    }

    #[test]
    fn barrier_derivatives_match_dual_numbers_exactly() {
        for &s in &[0.3, 0.05, 1e-3] {
            for x in sample_points(s) {
                let (v, d1, d2, d3) = third_derivative(
                    |x: num_dual::Dual3_64| {
                        let t = x - s;
                        t.powi(4) / x.powi(5)
                    },
                    x,
                );
                let b = barrier_derivs(x, s);
                assert!(rel(b.value, v) < 1e-12, "value x={x} s={s}");
                assert!(rel(b.d1, d1) < 1e-11, "d1 x={x} s={s}: {} vs {d1}", b.d1);
                assert!(rel(b.d2, d2) < 1e-11, "d2 x={x} s={s}: {} vs {d2}", b.d2);
                // d3 is a difference of larger terms for x close to s: compare with a scale.
                let scale = d3.abs().max(1e-9 * (2.0 * s).powi(-4));
                assert!(
                    (b.d3 - d3).abs() < 1e-9 * scale,
                    "d3 x={x} s={s}: {} vs {d3}",
                    b.d3
                );
                let (v2, d12, d22) = barrier_d2(x, s);
                assert_eq!((v2, d12, d22), (b.value, b.d1, b.d2));
                assert_eq!(barrier(x, s), b.value);
            }
        }
    }

    #[test]
    fn barrier_derivatives_match_finite_differences_near_zero_and_support() {
        let s = 0.1;
        for x in sample_points(s) {
            // Step small relative to both x and the distance to s.
            let h = 1e-4 * x.min(s - x);
            let b = barrier_derivs(x, s);
            let fd1 = cfd(|y| barrier(y, s), x, h);
            let fd2 = cfd(|y| barrier_derivs(y, s).d1, x, h);
            let fd3 = cfd(|y| barrier_derivs(y, s).d2, x, h);
            assert!(rel(b.d1, fd1) < 1e-6, "d1 at x={x}: {} vs {fd1}", b.d1);
            assert!(rel(b.d2, fd2) < 1e-6, "d2 at x={x}: {} vs {fd2}", b.d2);
            assert!(rel(b.d3, fd3) < 1e-6, "d3 at x={x}: {} vs {fd3}", b.d3);
        }
    }

    #[test]
    fn barrier_is_c3_across_support_edge() {
        let s = 0.1;
        // Exactly zero on and beyond s.
        for x in [s, s * (1.0 + 1e-12), 1.5 * s, 10.0] {
            assert_eq!(
                barrier_derivs(x, s),
                BarrierDerivs {
                    value: 0.0,
                    d1: 0.0,
                    d2: 0.0,
                    d3: 0.0
                }
            );
        }
        // Approaches zero like t⁴, t³, t², t from inside: check the leading coefficients
        // P ≈ t⁴/s⁵, P' ≈ 4t³/s⁵, P'' ≈ 12t²/s⁵, P''' ≈ 24t/s⁵ (relative corrections are
        // O(10 t/s), e.g. P''' = 24t/s⁵ (1 − 12.5 t/s + …)).
        for k in 4..9 {
            let t = -s * 10f64.powi(-k);
            let b = barrier_derivs(s + t, s);
            let s5 = s.powi(5);
            assert!(rel(b.value, t.powi(4) / s5) < 1e-2);
            assert!(rel(b.d1, 4.0 * t.powi(3) / s5) < 1e-2);
            assert!(rel(b.d2, 12.0 * t.powi(2) / s5) < 1e-2);
            assert!(rel(b.d3, 24.0 * t / s5) < 1e-2);
        }
        // The jump of each derivative across s closes like h^(4-k): one decade of h shrinks
        // the k-th derivative's jump by 10^(4-k), so P and its first three derivatives are
        // continuous at s.
        for k in 0..4 {
            let jump = |h: f64| {
                let (lo, hi) = (barrier_derivs(s - h, s), barrier_derivs(s + h, s));
                let pick = |b: BarrierDerivs| [b.value, b.d1, b.d2, b.d3][k];
                (pick(lo) - pick(hi)).abs()
            };
            for e in 4..7 {
                let h = s * 10f64.powi(-e);
                let ratio = jump(h) / jump(h / 10.0);
                let expect = 10f64.powi(4 - k as i32);
                assert!(
                    (ratio / expect - 1.0).abs() < 0.05,
                    "order {k}: ratio {ratio} vs {expect}"
                );
            }
        }
    }

    #[test]
    fn barrier_is_infinite_at_and_below_zero_and_convex_decreasing_inside() {
        let s = 0.2;
        for x in [0.0, -1e-300, -1.0] {
            let b = barrier_derivs(x, s);
            assert_eq!(b.value, f64::INFINITY);
            assert_eq!(barrier(x, s), f64::INFINITY);
            assert!(
                b.d1 == f64::NEG_INFINITY && b.d2 == f64::INFINITY && b.d3 == f64::NEG_INFINITY
            );
        }
        for x in sample_points(s) {
            let b = barrier_derivs(x, s);
            assert!(b.value > 0.0 && b.d1 < 0.0 && b.d2 > 0.0, "x={x}");
            assert!(b.value.is_finite() && b.d3.is_finite());
        }
        // Tiny positive arguments stay finite or +∞ but never NaN.
        for x in [1e-10, 1e-40, 1e-300, f64::MIN_POSITIVE] {
            let b = barrier_derivs(x, s);
            assert!(
                !b.value.is_nan() && !b.d1.is_nan() && !b.d2.is_nan() && !b.d3.is_nan(),
                "x={x}"
            );
        }
    }
}
