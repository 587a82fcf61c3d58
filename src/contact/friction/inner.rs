//! The inner convex problem `U_f = min_{u, ω} Σ_m D_m` (see the module above): the active
//! vertices, the value/gradient/Hessian of `U*` in `q = (u, ω)`, the spin-free reduction and the
//! safeguarded Newton solve.

use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

use super::*;
use crate::contact::error::{FrictionError, Hull};

/// A vertex with non-zero friction weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Active {
    /// 0 for hull `a`, 1 for `b`.
    pub(super) hull: usize,
    /// Index in its hull.
    pub(super) index: usize,
    /// `w = μ Δt A_ε(f)`.
    pub(super) w: f64,
    /// `ẋ = Bᵀ(X' − X^t)/Δt`.
    pub(super) v: Vector2<f64>,
    /// `g = Bᵀ(n̂ × (X^t − c))`.
    pub(super) g: Vector2<f64>,
}

/// Reusable buffers of the friction evaluation.
#[derive(Clone, Debug, Default)]
pub struct FrictionScratch {
    pub(super) act: Vec<Active>,
}

impl FrictionScratch {
    /// Empty scratch.
    pub fn new() -> Self {
        Self::default()
    }
}

/// Inner solution.
#[derive(Clone, Copy, Debug)]
pub(super) struct Core {
    pub(super) q: Vector3<f64>,
    pub(super) spin_free: bool,
    pub(super) value: f64,
    pub(super) hinv: Matrix3<f64>,
    pub(super) iterations: usize,
}

/// Per-vertex quantities at `q`.
#[inline(always)]
pub(super) fn vertex_terms(
    a: &Active,
    q: &Vector3<f64>,
    eps: f64,
) -> (Vector2<f64>, f64, Vector2<f64>, Matrix2<f64>) {
    let r = a.v - Vector2::new(q.x, q.y) - a.g * q.z;
    let phi = (r.norm_squared() + eps).sqrt();
    let rho = r / phi;
    // Φ = (I − ρρᵀ)/φ written without cancellation: its eigenvalue along r is ε/φ³, which
    // `1 − ‖ρ‖²` would lose entirely once ‖r‖ ≳ 10⁸ √ε (and partly long before). With
    // τ = (−ρ_y, ρ_x): Φ = (ε/φ² I + τ τᵀ)/φ.
    let tau = Vector2::new(-rho.y, rho.x);
    let big_phi = (Matrix2::identity() * (eps / (phi * phi)) + tau * tau.transpose()) / phi;
    (r, phi, rho, big_phi)
}

pub(super) struct InnerEval {
    pub(super) value: f64,
    pub(super) grad: Vector3<f64>,
    pub(super) hess: Matrix3<f64>,
    pub(super) scale: f64,
    pub(super) noise: f64,
    pub(super) value_noise: f64,
}

pub(super) fn inner_value(act: &[Active], q: &Vector3<f64>, eps: f64) -> f64 {
    act.iter()
        .map(|a| {
            let r = a.v - Vector2::new(q.x, q.y) - a.g * q.z;
            a.w * (r.norm_squared() + eps).sqrt()
        })
        .sum()
}

pub(super) fn inner_eval(act: &[Active], q: &Vector3<f64>, eps: f64, spin_free: bool) -> InnerEval {
    let mut e = InnerEval {
        value: 0.0,
        grad: Vector3::zeros(),
        hess: Matrix3::zeros(),
        scale: 0.0,
        noise: 0.0,
        value_noise: 0.0,
    };
    for a in act {
        let (r, phi, rho, bp) = vertex_terms(a, q, eps);
        e.value += a.w * phi;
        // ∇_q = −w Jᵀρ, ∇²_q = w Jᵀ Φ J with J = [I | g].
        let gr = a.g.dot(&rho);
        e.grad -= a.w * Vector3::new(rho.x, rho.y, gr);
        let pg = bp * a.g;
        let mut h = Matrix3::zeros();
        h.fixed_view_mut::<2, 2>(0, 0).copy_from(&bp);
        h[(0, 2)] = pg.x;
        h[(1, 2)] = pg.y;
        h[(2, 0)] = pg.x;
        h[(2, 1)] = pg.y;
        h[(2, 2)] = a.g.dot(&pg);
        e.hess += a.w * h;
        let lever = 1.0 + a.g.norm();
        e.scale += a.w * rho.norm() * lever;
        let rerr = a.v.norm() + q.x.abs() + q.y.abs() + q.z.abs() * a.g.norm() + r.norm();
        e.noise += a.w * lever * (1.0 + rerr / phi);
        e.value_noise += a.w * (phi + rerr);
    }
    if spin_free {
        e.grad.z = 0.0;
        for i in 0..3 {
            e.hess[(i, 2)] = 0.0;
            e.hess[(2, i)] = 0.0;
        }
    }
    e.noise *= 64.0 * f64::EPSILON;
    e.value_noise *= 64.0 * f64::EPSILON;
    e
}

/// Solves `H d = −g` (3×3; in spin-free mode only the `u` block).
pub(super) fn inner_direction(h: &Matrix3<f64>, g: &Vector3<f64>, spin_free: bool) -> Vector3<f64> {
    if spin_free {
        let h2 = h.fixed_view::<2, 2>(0, 0).into_owned();
        let g2 = Vector2::new(g.x, g.y);
        let d = h2.cholesky().map(|c| c.solve(&(-g2))).unwrap_or(-g2);
        return Vector3::new(d.x, d.y, 0.0);
    }
    if let Some(c) = h.cholesky() {
        let d = c.solve(&(-g));
        if d.iter().all(|v| v.is_finite()) {
            return d;
        }
    }
    let maxdiag = (0..3)
        .map(|i| h[(i, i)].abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut lambda = 1e-12 * maxdiag;
    for _ in 0..40 {
        if let Some(c) = (h + Matrix3::identity() * lambda).cholesky() {
            let d = c.solve(&(-g));
            if d.iter().all(|v| v.is_finite()) {
                return d;
            }
        }
        lambda *= 10.0;
    }
    -g
}

/// Inverse of `U*_qq` used by the implicit function theorem: the 2×2 `u` block embedded with a
/// zero `ω` row/column in spin-free mode, otherwise the full inverse (eigenvalue pseudo-inverse
/// if numerically singular, which only happens when every weight underflows).
pub(super) fn inner_hessian_inverse(h: &Matrix3<f64>, spin_free: bool) -> Matrix3<f64> {
    let mut out = Matrix3::zeros();
    if spin_free {
        let h2 = h.fixed_view::<2, 2>(0, 0).into_owned();
        if let Some(inv) = h2.try_inverse() {
            out.fixed_view_mut::<2, 2>(0, 0).copy_from(&inv);
        }
        return out;
    }
    if let Some(c) = h.cholesky() {
        let inv = c.inverse();
        if inv.iter().all(|v| v.is_finite()) {
            return inv;
        }
    }
    let eig = h.symmetric_eigen();
    let maxe = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for i in 0..3 {
        let l = eig.eigenvalues[i];
        if l > 1e-13 * maxe && l > 0.0 {
            let v = eig.eigenvectors.column(i);
            out += v * v.transpose() / l;
        }
    }
    out
}

/// Fills the active-vertex list (vertices with a non-zero normal force) and returns whether
/// the problem is spin-free. `next(h, m)` gives the step-`t+1` world position of vertex `m` of
/// hull `h`; it is only called for active vertices, whose positions are checked for finiteness
/// (vertices without normal force do not enter `U_f`).
pub(super) fn prepare(
    frame: &FrictionFrame<'_>,
    next: &dyn Fn(usize, usize) -> Vector3<f64>,
    counts: [usize; 2],
    params: &FrictionParams,
    act: &mut Vec<Active>,
) -> Result<bool, FrictionError> {
    params.validate()?;
    frame.validate()?;
    let prev = [frame.x_prev_a, frame.x_prev_b];
    let forces = [frame.normal_force_a, frame.normal_force_b];
    for (h, hull) in [Hull::A, Hull::B].into_iter().enumerate() {
        if counts[h] != prev[h].len() {
            return Err(FrictionError::LengthMismatch {
                hull,
                what: "vertices at step t+1",
                expected: prev[h].len(),
                got: counts[h],
            });
        }
    }
    // Contact-weighted centroid of X^t (weights A_ε(f)).
    let mut wsum = 0.0;
    let mut c = Vector3::zeros();
    for h in 0..2 {
        for (x, f) in prev[h].iter().zip(forces[h]) {
            if *f > 0.0 {
                let a = params.smoothed_force(*f);
                wsum += a;
                c += a * x;
            }
        }
    }
    act.clear();
    if wsum.is_nan() || wsum <= 0.0 {
        // No normal force anywhere: U_f ≡ 0.
        return Ok(true);
    }
    c /= wsum;
    let bt = frame.basis.transpose();
    let n = frame.normal;
    let (mut lever_in_plane, mut lever_full) = (0.0, 0.0);
    for h in 0..2 {
        for (index, (xp, f)) in prev[h].iter().zip(forces[h]).enumerate() {
            if *f <= 0.0 {
                continue;
            }
            let a = params.smoothed_force(*f);
            if a <= 0.0 {
                continue; // underflow of f²
            }
            let xn = next(h, index);
            if !xn.iter().all(|v| v.is_finite()) {
                return Err(FrictionError::NonFiniteVertex {
                    hull: [Hull::A, Hull::B][h],
                    index,
                });
            }
            let d = xp - c;
            let g = bt * n.cross(&d);
            lever_in_plane += a * g.norm_squared();
            lever_full += a * d.norm_squared();
            act.push(Active {
                hull: h,
                index,
                w: params.mu * params.dt * a,
                v: bt * (xn - xp) / params.dt,
                g,
            });
        }
    }
    Ok(lever_in_plane <= 1e-20 * lever_full)
}

/// Majorize–minimize (Weiszfeld / iteratively reweighted least squares) step from `q`:
/// since `√(t + ε)` is concave in `t = ‖r‖²`, `U* ≤ Σ w (‖r‖² + ε + φ₀²)/(2φ₀)` with `φ₀` taken
/// at `q`, with equality at `q`; minimising this quadratic majorant (a 3×3 weighted least-squares
/// problem) therefore never increases `U*`. Linear convergence, but globally robust.
pub(super) fn mm_step(
    act: &[Active],
    q: &Vector3<f64>,
    eps: f64,
    spin_free: bool,
) -> Option<Vector3<f64>> {
    let mut a = Matrix3::zeros();
    let mut b = Vector3::zeros();
    for t in act {
        let r = t.v - Vector2::new(q.x, q.y) - t.g * q.z;
        let c = t.w / (r.norm_squared() + eps).sqrt();
        let g = if spin_free { Vector2::zeros() } else { t.g };
        let jtj = Matrix3::new(1.0, 0.0, g.x, 0.0, 1.0, g.y, g.x, g.y, g.norm_squared());
        a += jtj * c;
        b += Vector3::new(t.v.x, t.v.y, g.dot(&t.v)) * c;
    }
    if spin_free {
        let a2 = a.fixed_view::<2, 2>(0, 0).into_owned();
        let x = a2.cholesky()?.solve(&Vector2::new(b.x, b.y));
        return Some(Vector3::new(x.x, x.y, 0.0));
    }
    let x = a.cholesky()?.solve(&b);
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Newton's method on `q = (u, ω)` with a safeguarded line minimisation (see
/// [`line_minimize`]) and the majorize–minimize step as a second, monotone candidate.
///
/// Stops when `‖∇U*‖ ≤ max(noise, min(tol, rtol · Σ w‖ρ‖(1 + ‖g‖)))`, or when no decrease of
/// `U*` is detectable any more *and* Newton's predicted decrease `½ gᵀH⁻¹g` is below the
/// rounding of `U*` (the iterate is at the noise floor: no representable step can improve
/// it). Anything else that stops progress is reported as non-convergence.
pub(super) fn solve_inner(
    act: &[Active],
    spin_free: bool,
    params: &FrictionParams,
) -> Result<Core, FrictionError> {
    let eps = params.eps_velocity;
    let wsum: f64 = act.iter().map(|a| a.w).sum();
    if act.is_empty() || wsum.is_nan() || wsum <= 0.0 {
        return Ok(Core {
            q: Vector3::zeros(),
            spin_free: true,
            value: 0.0,
            hinv: Matrix3::zeros(),
            iterations: 0,
        });
    }
    // Start from the weighted mean tangential velocity, no spin.
    let ubar = act.iter().map(|a| a.w * a.v).sum::<Vector2<f64>>() / wsum;
    let mut q = Vector3::new(ubar.x, ubar.y, 0.0);
    let mut ev = inner_eval(act, &q, eps, spin_free);
    let mut iterations = 0;
    let done = |q: Vector3<f64>, ev: &InnerEval, iterations: usize| Core {
        q,
        spin_free,
        value: ev.value,
        hinv: inner_hessian_inverse(&ev.hess, spin_free),
        iterations,
    };
    loop {
        let gnorm = ev.grad.norm();
        let tol = ev
            .noise
            .max(params.inner_tol.min(params.inner_rtol * ev.scale));
        if gnorm <= tol {
            return Ok(done(q, &ev, iterations));
        }
        if iterations >= params.inner_max_iters {
            return Err(FrictionError::NotConverged {
                iterations,
                grad_norm: gnorm,
                tolerance: tol,
            });
        }
        iterations += 1;
        let mut dir = inner_direction(&ev.hess, &ev.grad, spin_free);
        let mut slope = ev.grad.dot(&dir);
        let newton = !(slope.is_nan() || slope >= 0.0);
        if !newton {
            dir = -ev.grad;
            slope = -gnorm * gnorm;
        }
        let p = line_minimize(act, &q, &dir, ev.value, slope, eps, ev.value_noise);
        let mut next = (p.alpha > 0.0 && p.f < ev.value).then(|| (q + dir * p.alpha, p.f));
        if p.alpha != 1.0 {
            // The full step failed: also try the majorize–minimize step (never increases U*)
            // and keep the better point.
            if let Some(qm) = mm_step(act, &q, eps, spin_free) {
                let vm = inner_value(act, &qm, eps);
                if vm < next.map_or(ev.value, |(_, v)| v) {
                    next = Some((qm, vm));
                }
            }
            // And the best point on the kink of a vertex that can hold the plane there.
            if let Some((qk, vk)) = kink_candidate(act, &q, eps, spin_free, ev.value_noise)
                && vk < next.map_or(ev.value, |(_, v)| v)
            {
                next = Some((qk, vk));
            }
        }
        if next.is_none() && (slope.abs() <= ev.value_noise) {
            // Predicted decrease below the rounding of U*: Armijo cannot decide. Accept the
            // full step if it does not increase U* beyond rounding and reduces the gradient.
            let trial = q + dir;
            let et = inner_eval(act, &trial, eps, spin_free);
            if et.value <= ev.value + ev.value_noise && et.grad.norm() < gnorm - ev.noise {
                q = trial;
                ev = et;
                continue;
            }
        }
        match next {
            Some((nq, _)) => {
                q = nq;
                ev = inner_eval(act, &nq, eps, spin_free);
            }
            None if newton && -0.5 * slope <= ev.value_noise => {
                // At the noise floor: Newton predicts a decrease below the rounding of U*.
                return Ok(done(q, &ev, iterations));
            }
            None => {
                return Err(FrictionError::NotConverged {
                    iterations,
                    grad_norm: gnorm,
                    tolerance: tol,
                });
            }
        }
    }
}
