//! Step lengths of the inner solve: the safeguarded minimisation of the convex `α ↦ U*(q + α d)`
//! and the candidates on a vertex's kink (the plane moving exactly with that vertex).

use nalgebra::{Vector2, Vector3};

use super::*;

/// `U*(q + α d)` and its derivative `d/dα`.
pub(super) fn line_eval(
    act: &[Active],
    q: &Vector3<f64>,
    d: &Vector3<f64>,
    alpha: f64,
    eps: f64,
) -> LinePt {
    let qt = q + d * alpha;
    let (mut f, mut df) = (0.0, 0.0);
    for t in act {
        let r = t.v - Vector2::new(qt.x, qt.y) - t.g * qt.z;
        let a = Vector2::new(d.x, d.y) + t.g * d.z;
        let phi = (r.norm_squared() + eps).sqrt();
        f += t.w * phi;
        df -= t.w * a.dot(&r) / phi;
    }
    LinePt { alpha, f, df }
}

/// A point of the search line `q + α d`: step, `φ(α) = U*(q + α d)`, `φ'(α)`.
#[derive(Clone, Copy, Debug)]
pub(super) struct LinePt {
    pub(super) alpha: f64,
    pub(super) f: f64,
    pub(super) df: f64,
}

/// Evaluation budget of one line minimisation (each costs one pass over the active vertices).
pub(super) const LINE_MAX_EVALS: usize = 60;

/// Safeguarded minimisation of the convex `φ(α) = U*(q + α d)` over `α > 0`, given
/// `φ'(0) < 0`; returns the best point found (`α = 0` if none decreased `φ`).
///
/// The full step `α = 1` is taken as soon as it satisfies Armijo (Newton's local quadratic
/// convergence). Otherwise the minimiser is bracketed (`φ'(lo) < 0 ≤ φ'(hi)`, expanding by 4
/// when the step undershoots) and the bracket is shrunk with two candidates per round: the
/// secant root of `φ'` (exact for a quadratic) and the intersection of the tangents at `lo`
/// and `hi` (exact for a V; for a convex `φ` it lies in the bracket and the tangents' value
/// there is a lower bound on `min φ`). This matters because `√(‖r‖² + ε_v)` is a smoothed
/// norm: for relative speeds `≫ √ε_v` the inner objective is piecewise almost linear, and
/// its minimiser sits in a kink of width `√ε_v` (the plane sticking to one hull), which
/// Newton's quadratic model overshoots by orders of magnitude. It stops when the gap between
/// the best value and the lower bound is below 1% of the decrease achievable along the line,
/// or below the rounding of `U*`.
pub(super) fn line_minimize(
    act: &[Active],
    q: &Vector3<f64>,
    d: &Vector3<f64>,
    f0: f64,
    df0: f64,
    eps: f64,
    value_noise: f64,
) -> LinePt {
    let start = LinePt {
        alpha: 0.0,
        f: f0,
        df: df0,
    };
    let mut best = start;
    let mut lo = start;
    let mut evals = 0;
    let mut alpha = 1.0;
    let mut hi = loop {
        let p = line_eval(act, q, d, alpha, eps);
        evals += 1;
        if alpha == 1.0 && p.f < f0 && p.f <= f0 + 1e-4 * df0 {
            return p;
        }
        if p.f < best.f {
            best = p;
        }
        if !p.f.is_finite() || !p.df.is_finite() || p.df >= 0.0 {
            break p;
        }
        lo = p;
        alpha *= 4.0;
        if evals >= LINE_MAX_EVALS || !alpha.is_finite() {
            return best;
        }
    };
    while evals < LINE_MAX_EVALS {
        let tangents = (hi.f - lo.f + lo.df * lo.alpha - hi.df * hi.alpha) / (lo.df - hi.df);
        let lower = lo.f + lo.df * (tangents - lo.alpha);
        if best.f - lower <= value_noise.max(0.01 * (f0 - lower)) {
            break;
        }
        if hi.alpha - lo.alpha <= 4.0 * f64::EPSILON * hi.alpha {
            break;
        }
        let secant = lo.alpha - lo.df * (hi.alpha - lo.alpha) / (hi.df - lo.df);
        for c in [tangents, secant] {
            // Non-finite or outside the (possibly already shrunk) bracket: bisect.
            let c = if c > lo.alpha && c < hi.alpha {
                c
            } else {
                0.5 * (lo.alpha + hi.alpha)
            };
            if c <= lo.alpha || c >= hi.alpha {
                break;
            }
            let p = line_eval(act, q, d, c, eps);
            evals += 1;
            if p.f < best.f {
                best = p;
            }
            if p.df < 0.0 {
                lo = p;
            } else {
                hi = p;
            }
        }
    }
    best
}

/// The best point on the "kink" of vertex `mi`: the set where the plane moves exactly with it
/// (`r_m = 0`, i.e. `u = ẋ_m − ω g_m`, a line in `(u, ω)`; a single point when spin-free),
/// provided the vertex can stick there.
///
/// `U*` restricted to the line is convex; it is minimised from the projection of `q` with
/// [`line_minimize`], started at the 1-D Newton step. Sticking to `m` is consistent only if
/// `m` can hold the plane against all the others: their net pull on `u`, `Σ_{k≠m} w_k ρ_k`,
/// must be weaker than `w_m` (the most `m` can exert, `‖w_m ρ_m‖ < w_m`). Otherwise the
/// minimiser is off this kink, and a point on it is a poor start for Newton (leaving a kink of
/// width `√ε_v` takes many steps), so `None` is returned.
pub(super) fn kink_point(
    act: &[Active],
    mi: usize,
    q: &Vector3<f64>,
    eps: f64,
    spin_free: bool,
    value_noise: f64,
) -> Option<(Vector3<f64>, f64)> {
    let m = &act[mi];
    let sticks = |qk: &Vector3<f64>| {
        let pull: Vector2<f64> = act
            .iter()
            .enumerate()
            .filter(|(k, _)| *k != mi)
            .map(|(_, t)| {
                let r = t.v - Vector2::new(qk.x, qk.y) - t.g * qk.z;
                r * (t.w / (r.norm_squared() + eps).sqrt())
            })
            .sum();
        pull.norm() < m.w
    };
    let omega = if spin_free { 0.0 } else { q.z };
    let q0 = Vector3::new(m.v.x - m.g.x * omega, m.v.y - m.g.y * omega, omega);
    let f0 = line_eval(act, &q0, &Vector3::zeros(), 0.0, eps);
    if spin_free {
        return (f0.f.is_finite() && sticks(&q0)).then_some((q0, f0.f));
    }
    // Along the kink: d = (−g_m, 1). Curvature φ'' = Σ w (ε‖a‖² + (a × r)²)/φ³.
    let d = Vector3::new(-m.g.x, -m.g.y, 1.0);
    let (mut df, mut ddf) = (0.0, 0.0);
    for t in act {
        let r = t.v - Vector2::new(q0.x, q0.y) - t.g * q0.z;
        let a = Vector2::new(d.x, d.y) + t.g * d.z;
        let phi = (r.norm_squared() + eps).sqrt();
        df -= t.w * a.dot(&r) / phi;
        let cross = a.x * r.y - a.y * r.x;
        ddf += t.w * (eps * a.norm_squared() + cross * cross) / (phi * phi * phi);
    }
    let mut best = (q0, f0.f);
    if df != 0.0 && ddf > 0.0 && df.is_finite() && ddf.is_finite() {
        let d = d * (-df / ddf);
        let p = line_minimize(act, &q0, &d, f0.f, -df * df / ddf, eps, value_noise);
        if p.f < best.1 {
            best = (q0 + d * p.alpha, p.f);
        }
    }
    (best.1.is_finite() && sticks(&best.0)).then_some(best)
}

/// Kink candidates of [`kink_point`] for the two vertices most likely to hold the plane: the
/// one closest to sticking relative to its weight (largest `w_m/φ_m`) and the heaviest one
/// (under fast sliding the plane ends up sticking to the heavier side). Returns the better.
///
/// Under fast sliding the minimiser of `U*` typically sits on such a kink, within `√ε_v`.
/// Approaching it, Newton's model of the nearly conical `w √(‖r‖² + ε_v)` is poor across the
/// kink, and the iterate creeps towards it while sliding along it.
pub(super) fn kink_candidate(
    act: &[Active],
    q: &Vector3<f64>,
    eps: f64,
    spin_free: bool,
    value_noise: f64,
) -> Option<(Vector3<f64>, f64)> {
    let argmax = |key: &dyn Fn(&Active) -> f64| {
        act.iter()
            .enumerate()
            .max_by(|x, y| key(x.1).total_cmp(&key(y.1)))
            .map(|(i, _)| i)
    };
    let closest = argmax(&|a: &Active| {
        let r = a.v - Vector2::new(q.x, q.y) - a.g * q.z;
        a.w / (r.norm_squared() + eps).sqrt()
    })?;
    let heaviest = argmax(&|a: &Active| a.w)?;
    let first = kink_point(act, closest, q, eps, spin_free, value_noise);
    if heaviest == closest {
        return first;
    }
    let second = kink_point(act, heaviest, q, eps, spin_free, value_noise);
    match (first, second) {
        (Some(a), Some(b)) => Some(if b.1 < a.1 { b } else { a }),
        (a, b) => a.or(b),
    }
}
