//! A one-dimensional model of the step objective along a Newton direction, for the first
//! trial's step length ([`super::NewtonOptions::line_model`]).
//!
//! Along `q + α Δ` the objective is modelled as
//!
//! ```text
//! M(α) = a₁ α + ½ a₂ α² + Σ_pairs W_k(α),
//! a₁ = φ'(0) − Σ_k W_k'(0),   a₂ = φ''(0) − Σ_k W_k''(0),
//! φ'(0) = ∇O·Δ,               φ''(0) = Δᵀ H Δ,
//! ```
//!
//! where `W_k` is contact pair `k`'s potential along the first-order motion of its vertices
//! with its plane moved at the optimal plane's rate ([`crate::contact::PlaneLine`]), and
//! everything else — inertia, gravity, PD, friction, the kinematics' curvature — is the
//! quadratic part. So `M` has the objective's slope and curvature at `α = 0` (Newton's own
//! quadratic model) and the barriers' nonlinearity along the line. From a point deep in a
//! barrier's support Newton's full step undershoots the line's minimum (each step lengthens a
//! gap `y` by about `y/6` where `P_s ≈ s⁴/y⁵`); `M`'s minimizer does not.
//!
//! The minimizer is found by Newton's method on `M'` safeguarded by bisection inside a bracket
//! (`M'(0) < 0`, an upper end where `M' > 0` or `M = +∞`); it costs a pass over the pairs'
//! vertices per iteration and no objective evaluation.

use crate::contact::PlaneLine;

/// The model `M` of one line search (see the module docs).
pub struct LineModel<'a> {
    /// `a₁ = φ'(0) − Σ W_k'(0)`.
    a1: f64,
    /// `a₂ = φ''(0) − Σ W_k''(0)`.
    a2: f64,
    /// `φ'(0) < 0`.
    slope: f64,
    pairs: &'a [PlaneLine],
}

/// Iteration limit of [`LineModel::minimizer`] (each halves the bracket at worst: 60 reach
/// round-off on any bracket).
const MAX_ITERS: usize = 60;

/// [`LineModel::minimizer`] stops when `|M'(α)| ≤ SLOPE_TOL |φ'(0)|`.
const SLOPE_TOL: f64 = 1e-6;

impl<'a> LineModel<'a> {
    /// The model from the line's slope `φ'(0) = ∇O·Δ`, curvature `φ''(0) = ΔᵀHΔ` and the
    /// pairs' lines. `None` (no model: the search keeps its full step) when there is no pair,
    /// `Δ` is not a descent direction, or the quadratic part is not convex (`a₂ ≤ 0`: the
    /// barriers carry all the curvature, and `M` could fall without bound where they end).
    pub fn new(slope: f64, curvature: f64, pairs: &'a [PlaneLine]) -> Option<Self> {
        if pairs.is_empty() || !(slope < 0.0) || !curvature.is_finite() {
            return None;
        }
        let (mut w1, mut w2) = (0.0, 0.0);
        for p in pairs {
            let at = p.at(0.0);
            if !at.value.is_finite() {
                return None;
            }
            w1 += at.d1;
            w2 += at.d2;
        }
        let (a1, a2) = (slope - w1, curvature - w2);
        (a1.is_finite() && a2 > 0.0).then_some(LineModel {
            a1,
            a2,
            slope,
            pairs,
        })
    }

    /// `(M'(α), M''(α))`, `None` where `M = +∞`.
    fn derivatives(&self, alpha: f64) -> Option<(f64, f64)> {
        let (mut d1, mut d2) = (self.a1 + self.a2 * alpha, self.a2);
        for p in self.pairs {
            let at = p.at(alpha);
            if !at.value.is_finite() {
                return None;
            }
            d1 += at.d1;
            d2 += at.d2;
        }
        Some((d1, d2))
    }

    /// The minimizer of `M` on `(0, hi]` (`hi > 0`, the search's bound on the step length):
    /// `hi` itself when `M` still descends there, else the root of `M'` to
    /// `|M'| ≤ 10⁻⁶ |φ'(0)|` or a bracket of relative width `10⁻⁹`. Starts from the full step
    /// `α = 1` (Newton's own choice) when it lies inside.
    pub fn minimizer(&self, hi: f64) -> f64 {
        if let Some((d1, _)) = self.derivatives(hi)
            && d1 <= 0.0
        {
            return hi;
        }
        let (mut lo, mut hi) = (0.0, hi);
        let mut alpha = if hi > 1.0 { 1.0 } else { 0.5 * hi };
        for _ in 0..MAX_ITERS {
            let Some((d1, d2)) = self.derivatives(alpha) else {
                hi = alpha;
                alpha = 0.5 * (lo + hi);
                continue;
            };
            if d1.abs() <= SLOPE_TOL * self.slope.abs() {
                return alpha;
            }
            if d1 < 0.0 {
                lo = alpha;
            } else {
                hi = alpha;
            }
            if hi - lo <= 1e-9 * hi {
                break;
            }
            let newton = alpha - d1 / d2;
            alpha = if d2 > 0.0 && newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
        }
        lo.max(f64::MIN_POSITIVE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::barrier;
    use nalgebra::Vector3;

    const S: f64 = 0.01;

    /// One vertex at gap `y0` moving out at `y1` per unit `α` (the plane fixed, `‖n‖ = ½` so
    /// the normal's own barrier is inactive), scale `k`.
    fn vertex(y0: f64, y1: f64, k: f64) -> PlaneLine {
        let n = Vector3::new(0.5, 0.0, 0.0);
        PlaneLine::from_parts(n, Vector3::zeros(), S, k, vec![[y0, y1, 0.0]])
    }

    /// `M(α)` from its definition, independently of [`LineModel::derivatives`].
    fn m_value(m: &LineModel, y0: f64, y1: f64, k: f64, a: f64) -> f64 {
        m.a1 * a + 0.5 * m.a2 * a * a + k * barrier(y0 + y1 * a, S)
    }

    /// Golden sections on `M`'s value over `(0, hi]`.
    fn golden(f: impl Fn(f64) -> f64, hi: f64) -> f64 {
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let (mut a, mut b) = (0.0, hi);
        for _ in 0..200 {
            let (c, d) = (b - g * (b - a), a + g * (b - a));
            if f(c) < f(d) {
                b = d;
            } else {
                a = c;
            }
        }
        0.5 * (a + b)
    }

    #[test]
    fn no_pair_or_no_descent_or_no_convex_rest_gives_no_model() {
        let p = [vertex(0.5 * S, 0.1 * S, 1.0)];
        assert!(LineModel::new(-1.0, 1.0, &[]).is_none());
        assert!(LineModel::new(1.0, 1e9, &p).is_none());
        assert!(LineModel::new(-1.0, f64::NAN, &p).is_none());
        // All the curvature in the barrier: a₂ ≤ 0.
        let w2 = p[0].at(0.0).d2;
        assert!(LineModel::new(-1.0, w2, &p).is_none());
    }

    /// A vertex deep in the support moving out, with Newton's quadratic model from `α = 0`
    /// putting the full step at `α = 1` (`φ''(0) = −φ'(0)`): the model's minimizer lies
    /// beyond 1 (the undershoot) and matches golden sections on `M`'s value; a vertex moving
    /// in gives a minimizer short of 1. Swept from near the pole to near the support's edge.
    #[test]
    fn minimizer_matches_golden_sections_and_corrects_the_full_step() {
        for &y0 in &[1e-4 * S, 0.01 * S, 0.2 * S, 0.6 * S, 0.95 * S] {
            for &(dir, k) in &[(1.0, 1.0), (-1.0, 1.0), (1.0, 1e-6), (-1.0, 1e3)] {
                let y1 = dir * 0.5 * y0;
                let p = [vertex(y0, y1, k)];
                let at0 = p[0].at(0.0);
                // A rest term pulling the way the vertex moves, with the same curvature as the
                // barrier at α = 0.
                let slope = -(at0.d1.abs() + at0.d2 * 1.0);
                let curvature = -slope;
                let m = LineModel::new(slope, curvature, &p).expect("model");
                let hi = 4.0;
                let a = m.minimizer(hi);
                let want = golden(|x| m_value(&m, y0, y1, k, x), hi);
                let tol = 1e-6 * want.max(1e-3);
                assert!(
                    (a - want).abs() <= tol,
                    "y0 {y0} dir {dir} k {k}: {a} vs {want}"
                );
                if dir > 0.0 && k >= 1.0 {
                    assert!(
                        a > 1.0,
                        "y0 {y0}: moving out, {a} should exceed the full step"
                    );
                }
                if dir < 0.0 && k >= 1.0 && y0 < 0.9 * S {
                    assert!(a < 1.0, "y0 {y0}: moving in, {a} should fall short of it");
                }
            }
        }
    }

    /// A line that reaches the barrier's pole inside the bound: the minimizer stays strictly
    /// feasible; a line still descending at the bound returns the bound.
    #[test]
    fn minimizer_stays_feasible_and_returns_the_bound_when_still_descending() {
        let p = [vertex(0.5 * S, -0.5 * S, 1.0)];
        let at0 = p[0].at(0.0);
        let m = LineModel::new(-1e3 * at0.d1.abs(), at0.d2 * 1.001, &p).expect("model");
        let a = m.minimizer(4.0);
        assert!(a > 0.0 && a < 1.0 && m.derivatives(a).is_some(), "{a}");
        let far = [vertex(0.5 * S, 1e-3 * S, 1e-9)];
        let m = LineModel::new(-1.0, 1e-3, &far).expect("model");
        assert_eq!(m.minimizer(4.0), 4.0);
    }
}
