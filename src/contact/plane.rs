//! Inner problem of the contact potential: the optimal separating plane `p* = argmin_p U*(p)`.
//!
//! ```text
//! U*(p) = P_s(1 − ‖n‖) + Σ_{m∈a} P_s(−(n·X_a^m + o)) + Σ_{m∈b} P_s(n·X_b^m + o),   p = (n, o)
//! ```
//!
//! Write `y_m = σ_m (n·X_m + o)` with `σ = −1` on hull `a`, `+1` on hull `b`, and
//! `x̃_m = [X_m; 1]`. Then (paper Eq. `hessian` for the norm term)
//!
//! ```text
//! ∇_p U*  = Σ_m σ_m P'(y_m) x̃_m  −  P'(q) [n̂; 0],                       q = 1 − ‖n‖
//! ∇²_p U* = Σ_m P''(y_m) x̃_m x̃_mᵀ + [P''(q) n̂n̂ᵀ − P'(q)/‖n‖ (I − n̂n̂ᵀ), 0; 0, 0]
//! ```
//!
//! Every term is convex in `p`, so Newton's method with a backtracking line search finds the
//! global minimum. The iterate is kept strictly feasible (all `y_m > 0`, `‖n‖ < 1`): the largest
//! feasible step along the Newton direction is computed in closed form (the `y_m` are affine in
//! `p` and `‖n‖ < 1` is a quadratic condition) and the line search starts just inside it.
//!
//! Coordinates: this module works on vertex positions already shifted by an origin `c0` chosen
//! by the caller near the pair (for conditioning); the plane is expressed in the same shifted
//! frame.
//!
//! Convergence: the barrier spans many orders of magnitude (`P_s' ~ x⁻⁶` near contact), so a
//! fixed absolute tolerance is either unreachable in floating point or meaningless near the
//! support edge where everything is tiny. The solve stops when
//!
//! ```text
//! ‖∇_p U*‖ ≤ max(noise, min(tol, rtol · scale))
//! ```
//!
//! where `scale = Σ_m |P'(y_m)| ‖x̃_m‖ + |P'(q)|` is the total magnitude of the forces acting on
//! the massless plane (the gradient is their net sum), and `noise` is a rounding-error bound on
//! the computed gradient (`64 ε_mach Σ (|P'| + |P''| |y|) ‖x̃‖`, the second term accounting for
//! the rounding of `y_m` itself). So the absolute tolerance is honoured whenever it is
//! meaningful, the relative one guarantees accuracy when the potential is tiny, and the noise
//! floor prevents chasing rounding errors when the potential is huge.

use nalgebra::{Matrix4, Vector3, Vector4};

use super::barrier::{barrier, barrier_d2};
use super::error::ContactError;

/// Value, gradient and Hessian of `U*` at a feasible plane, plus the tolerance scales.
#[derive(Clone, Copy, Debug)]
pub struct PlaneEval {
    /// `U*(p)`.
    pub value: f64,
    /// `∇_p U*`.
    pub grad: Vector4<f64>,
    /// `∇²_p U*`.
    pub hess: Matrix4<f64>,
    /// `Σ |P'| ‖x̃‖ + |P'(q)|`: total force magnitude on the plane.
    pub scale: f64,
    /// Rounding-error bound on `grad`.
    pub noise: f64,
    /// Rounding-error bound on `value` (dominated by the rounding of the barrier arguments
    /// amplified by `P'`: near contact `P ~ y⁻⁵`, so a relative error `δy/y` in an argument
    /// becomes `5 δy/y` in the value).
    pub value_noise: f64,
}

/// Converged inner solution.
#[derive(Clone, Copy, Debug)]
pub struct PlaneSolution {
    /// `p*` in the shifted frame.
    pub p: Vector4<f64>,
    /// Evaluation at `p*` (value, gradient, Hessian `U*_pp`).
    pub eval: PlaneEval,
    /// Newton iterations taken.
    pub iterations: usize,
}

/// Settings of the inner Newton solve.
#[derive(Clone, Copy, Debug)]
pub struct PlaneSolveSettings {
    /// Barrier width `s`.
    pub s: f64,
    /// Absolute gradient tolerance.
    pub tol: f64,
    /// Relative gradient tolerance (w.r.t. the total force magnitude on the plane).
    pub rtol: f64,
    /// Iteration cap.
    pub max_iters: usize,
}

/// `U*(p)`, or `+∞` if `p` is infeasible (some `y_m ≤ 0` or `‖n‖ ≥ 1`).
pub fn value(xa: &[Vector3<f64>], xb: &[Vector3<f64>], p: &Vector4<f64>, s: f64) -> f64 {
    let n = Vector3::new(p.x, p.y, p.z);
    let o = p.w;
    let norm = n.norm();
    if norm >= 1.0 {
        return f64::INFINITY;
    }
    let mut v = barrier(1.0 - norm, s);
    for x in xa {
        let y = -(n.dot(x) + o);
        if y <= 0.0 {
            return f64::INFINITY;
        }
        if y < s {
            v += barrier(y, s);
        }
    }
    for x in xb {
        let y = n.dot(x) + o;
        if y <= 0.0 {
            return f64::INFINITY;
        }
        if y < s {
            v += barrier(y, s);
        }
    }
    v
}

/// Accumulator layout: 0 value, 1..5 gradient, 5..15 upper Hessian
/// (00 01 02 03 11 12 13 22 23 33), 15 force scale, 16 gradient rounding bound, 17 value
/// rounding bound.
type Acc = [f64; 18];

/// Accumulates one vertex term `P(y)` with `y = σ (n·x + o)` into value, gradient, Hessian.
#[inline(always)]
fn accumulate(x: &Vector3<f64>, sigma: f64, n: &Vector3<f64>, o: f64, s: f64, acc: &mut Acc) {
    let nx = n.dot(x);
    let y = sigma * (nx + o);
    if y >= s {
        return;
    }
    let (v, d1, d2) = barrier_d2(y, s);
    let (px, py, pz) = (x.x, x.y, x.z);
    let g = sigma * d1;
    acc[0] += v;
    acc[1] += g * px;
    acc[2] += g * py;
    acc[3] += g * pz;
    acc[4] += g;
    let (wx, wy, wz) = (d2 * px, d2 * py, d2 * pz);
    acc[5] += wx * px;
    acc[6] += wx * py;
    acc[7] += wx * pz;
    acc[8] += wx;
    acc[9] += wy * py;
    acc[10] += wy * pz;
    acc[11] += wy;
    acc[12] += wz * pz;
    acc[13] += wz;
    acc[14] += d2;
    let xn = (px * px + py * py + pz * pz + 1.0).sqrt();
    acc[15] += d1.abs() * xn;
    // Rounding of P' itself plus the rounding of y (≲ ε(|n·x| + |o|)) amplified by P''.
    let yerr = nx.abs() + o.abs();
    acc[16] += (d1.abs() + d2 * yerr) * xn;
    acc[17] += v - d1 * yerr;
}

/// Full evaluation at a feasible plane.
pub fn eval(xa: &[Vector3<f64>], xb: &[Vector3<f64>], p: &Vector4<f64>, s: f64) -> PlaneEval {
    let n = Vector3::new(p.x, p.y, p.z);
    let o = p.w;
    let mut acc: Acc = [0.0; 18];
    for x in xa {
        accumulate(x, -1.0, &n, o, s, &mut acc);
    }
    for x in xb {
        accumulate(x, 1.0, &n, o, s, &mut acc);
    }
    let mut noise = acc[16];
    let mut value_noise = acc[17];
    let norm = n.norm();
    let q = 1.0 - norm;
    let (vq, d1q, d2q) = barrier_d2(q, s);
    let mut grad = Vector4::new(acc[1], acc[2], acc[3], acc[4]);
    let mut hess = Matrix4::new(
        acc[5], acc[6], acc[7], acc[8], //
        acc[6], acc[9], acc[10], acc[11], //
        acc[7], acc[10], acc[12], acc[13], //
        acc[8], acc[11], acc[13], acc[14],
    );
    let mut scale = acc[15];
    if d1q != 0.0 || d2q != 0.0 {
        let nh = n / norm;
        for i in 0..3 {
            grad[i] -= d1q * nh[i];
            for j in 0..3 {
                let delta = if i == j { 1.0 } else { 0.0 };
                hess[(i, j)] += d2q * nh[i] * nh[j] - d1q / norm * (delta - nh[i] * nh[j]);
            }
        }
        scale += d1q.abs();
        noise += d1q.abs() + d2q * (norm + q);
        value_noise += vq + d1q.abs() * (norm + q);
    }
    PlaneEval {
        value: acc[0] + vq,
        grad,
        hess,
        scale,
        noise: 64.0 * f64::EPSILON * noise,
        value_noise: 64.0 * f64::EPSILON * value_noise,
    }
}

/// Largest `α > 0` such that `p + α dp` is feasible for all `α' < α` (`+∞` if unbounded).
pub fn max_feasible_step(
    xa: &[Vector3<f64>],
    xb: &[Vector3<f64>],
    p: &Vector4<f64>,
    dp: &Vector4<f64>,
) -> f64 {
    let n = Vector3::new(p.x, p.y, p.z);
    let dn = Vector3::new(dp.x, dp.y, dp.z);
    let mut amax = f64::INFINITY;
    for (xs, sigma) in [(xa, -1.0), (xb, 1.0)] {
        for x in xs {
            let dy = sigma * (dn.dot(x) + dp.w);
            if dy < 0.0 {
                let y = sigma * (n.dot(x) + p.w);
                amax = amax.min(y / -dy);
            }
        }
    }
    // ‖n + α dn‖² < 1: a α² + 2 b α + c < 0 with c = ‖n‖² − 1 < 0.
    let a = dn.norm_squared();
    if a > 0.0 {
        let b = n.dot(&dn);
        let c = n.norm_squared() - 1.0;
        let disc = (b * b - a * c).max(0.0);
        // Positive root, written to avoid cancellation.
        let root = if b > 0.0 {
            -c / (b + disc.sqrt())
        } else {
            (-b + disc.sqrt()) / a
        };
        amax = amax.min(root);
    }
    amax
}

/// Solves `H d = −g` for a symmetric positive semi-definite `H`, shifting `H` by a growing
/// multiple of the identity when it is numerically singular.
pub fn newton_direction(h: &Matrix4<f64>, g: &Vector4<f64>) -> Vector4<f64> {
    if let Some(ch) = h.cholesky() {
        let d = ch.solve(&(-g));
        if d.iter().all(|v| v.is_finite()) {
            return d;
        }
    }
    let maxdiag = (0..4)
        .map(|i| h[(i, i)].abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut lambda = 1e-12 * maxdiag;
    for _ in 0..40 {
        let shifted = h + Matrix4::identity() * lambda;
        if let Some(ch) = shifted.cholesky() {
            let d = ch.solve(&(-g));
            if d.iter().all(|v| v.is_finite()) {
                return d;
            }
        }
        lambda *= 10.0;
    }
    -g
}

/// Result of one line search.
#[allow(clippy::large_enum_variant)] // short-lived stack value
enum LineSearch {
    /// New iterate and its full evaluation.
    Accepted(Vector4<f64>, PlaneEval),
    /// No acceptable step size.
    Stalled,
}

/// Feasibility-preserving Armijo backtracking along `dir` from `p`.
fn line_search(
    xa: &[Vector3<f64>],
    xb: &[Vector3<f64>],
    p: &Vector4<f64>,
    ev: &PlaneEval,
    dir: &Vector4<f64>,
    slope: f64,
    s: f64,
) -> LineSearch {
    let gnorm = ev.grad.norm();
    let amax = max_feasible_step(xa, xb, p, dir);
    let mut alpha = if amax > 1.0 { 1.0 } else { 0.99 * amax };
    while alpha > 1e-18 {
        let trial = p + dir * alpha;
        let vt = value(xa, xb, &trial, s);
        if vt.is_finite() {
            if vt <= ev.value + 1e-4 * alpha * slope {
                return LineSearch::Accepted(trial, eval(xa, xb, &trial, s));
            }
            // Predicted decrease below the rounding of U* itself: Armijo cannot decide. Accept a
            // step that does not increase U* beyond rounding if it reduces the gradient.
            if (alpha * slope).abs() <= ev.value_noise && vt <= ev.value + ev.value_noise {
                let et = eval(xa, xb, &trial, s);
                if et.grad.norm() < gnorm {
                    return LineSearch::Accepted(trial, et);
                }
            }
        }
        alpha *= 0.5;
    }
    LineSearch::Stalled
}

/// Newton's method with a feasibility-preserving Armijo backtracking line search from a
/// strictly feasible `p0`.
pub fn solve(
    xa: &[Vector3<f64>],
    xb: &[Vector3<f64>],
    p0: Vector4<f64>,
    set: &PlaneSolveSettings,
) -> Result<PlaneSolution, ContactError> {
    let s = set.s;
    let mut p = p0;
    let mut ev = eval(xa, xb, &p, s);
    let mut iterations = 0;
    loop {
        let gnorm = ev.grad.norm();
        let tol = ev.noise.max(set.tol.min(set.rtol * ev.scale));
        if gnorm <= tol {
            return Ok(PlaneSolution {
                p,
                eval: ev,
                iterations,
            });
        }
        if iterations >= set.max_iters {
            return Err(ContactError::PlaneNotConverged {
                iterations,
                grad_norm: gnorm,
                tolerance: tol,
            });
        }
        iterations += 1;
        let mut dir = newton_direction(&ev.hess, &ev.grad);
        let mut slope = ev.grad.dot(&dir);
        if slope.is_nan() || slope >= 0.0 {
            dir = -ev.grad;
            slope = -gnorm * gnorm;
        }
        match line_search(xa, xb, &p, &ev, &dir, slope, s) {
            LineSearch::Accepted(np, nev) => {
                p = np;
                ev = nev;
            }
            LineSearch::Stalled => {
                return Err(ContactError::PlaneLineSearchStalled {
                    iteration: iterations,
                    grad_norm: gnorm,
                    tolerance: tol,
                });
            }
        }
    }
}
