//! Central differences of a trajectory loss for checking adjoint gradients,
//! with the differences' own noise measured.
//!
//! Over hundreds of contact-rich steps a loss carries round-off noise: σ ≈
//! 1e-9 on the spider's 550 steps (loss ≈ 100), the same at Newton
//! tolerance 1e-12 and at the solver's round-off floor, i.e. the
//! trajectory's amplification of double-precision round-off, not a stopping
//! error. A central difference at step `h` inherits ≈ σ/h of it, while
//! larger steps add truncation error; so a component much smaller than the
//! loss's scale may not be checkable to a given criterion by *any* `h`.
//! [`check_component`] measures σ along the component and says whether the
//! difference resolves the component before judging it.
//!
//! Estimator: `D(h) = (L(h) − L(−h)) / 2h` has the error series
//! `c₂h² + c₄h⁴ + …`; Richardson's table with ratio 2 removes the first
//! `levels` terms: level 1 is `(4 D(h) − D(2h)) / 3`, level 2
//! `(64 D(h) − 20 D(2h) + D(4h)) / 45`. With independent noise σ on each
//! loss and the estimate `Σ_k c_k D(2^k h)`, its standard deviation is
//! `σ/h · sqrt(Σ_k c_k² / (2 · 4^k))` (level 1: `0.950 σ/h`).
//!
//! [`Stencil::Fit`] trades evaluations for noise: the `m` central
//! differences `D(h_j)`, `h_j = j h/m` (`j = 1…m`), are fitted by weighted
//! least squares with `D(h) = g + a₁h² + … + a_ℓ h^{2ℓ}` (`ℓ = levels`;
//! weights `2 h_j²/σ²`, the inverse variances), and `g` is the estimate. It
//! is exact on the same polynomials as Richardson's level `ℓ`, and its noise
//! is `σ/h · sqrt([(AᵀWA)⁻¹]₀₀)` with `A_jk = (j/m)^{2k}`, `W_jj = 2 (j/m)²`:
//! `ℓ = 1` gives 1.00 / 0.73 / 0.53 / 0.38 `σ/h` for `m` = 8 / 16 / 32 / 64,
//! against `1.90 σ/h` for Richardson's level 1 over the same span (`D(h/2)`
//! and `D(h)`). It is for components whose loss has structure a little
//! beyond the span (e.g. a barrier pair crossing its support, where the loss
//! is C² but not C³) while its round-off needs more than one difference to
//! average out.

/// One component checked against its differences.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CentralCheck {
    /// The adjoint component being checked.
    pub adjoint: f64,
    /// Richardson-extrapolated central difference.
    pub central: f64,
    /// Step `h` (the design variable's units).
    pub h: f64,
    /// Richardson levels used (0: plain central difference), or the even
    /// powers of `h` fitted by [`Stencil::Fit`].
    pub levels: usize,
    /// Central differences combined: `levels + 1` for Richardson's table,
    /// `m` for [`Stencil::Fit`].
    pub steps: usize,
    /// Standard deviation of the loss's noise along this component
    /// ([`loss_noise`] at spacing `h/10`, eleven losses over `±h/2`).
    pub loss_noise: f64,
    /// Standard deviation of `central` due to that noise.
    pub central_noise: f64,
    /// `|central − adjoint| / max(|adjoint|, |central|)`.
    pub relative_error: f64,
    /// The differences resolve the component to the criterion `crit`:
    /// `2 · central_noise ≤ crit · |adjoint|`.
    pub resolved: bool,
    /// Resolved: `relative_error ≤ crit`. Not resolved: `|central − adjoint|
    /// ≤ crit |adjoint| + 3 central_noise` (agreement within the
    /// differences' own uncertainty).
    pub pass: bool,
    /// [`check_component_adaptive`] only: the same stencil's estimate at
    /// `h/2`, whose agreement with `central` is the smoothness test.
    pub halved: Option<f64>,
}

/// Coefficients `c_k` of `D(2^k h)`, `k = 0…levels`, in Richardson's
/// extrapolation with ratio 2 of a series in even powers of `h`
/// (`Σ c_k = 1`; `Σ c_k 4^{jk} = 0` for `j = 1…levels`).
pub fn richardson_coefficients(levels: usize) -> Vec<f64> {
    let mut coef = vec![1.0f64];
    for level in 1..=levels {
        let f = 4f64.powi(level as i32);
        let mut next = vec![0.0; coef.len() + 1];
        for (k, &c) in coef.iter().enumerate() {
            next[k] += f * c / (f - 1.0);
            next[k + 1] -= c / (f - 1.0);
        }
        coef = next;
    }
    coef
}

/// Residual standard deviation of a least-squares cubic through the eleven
/// losses `L(k s)`, `k = −5…5` (`l0 = L(0)` given, ten evaluations): the
/// loss's noise at the scale `s`, where the loss itself is a cubic to far
/// below its noise. Seven degrees of freedom: for Gaussian noise the
/// estimate's ratio to the true σ lies within [0.56, 1.42] in nine of ten
/// draws.
pub fn loss_noise<E>(
    loss_at: &mut dyn FnMut(f64) -> Result<f64, E>,
    l0: f64,
    s: f64,
) -> Result<f64, E> {
    let mut ls = [0.0f64; 11];
    for (j, l) in ls.iter_mut().enumerate() {
        let k = j as f64 - 5.0;
        if k != 0.0 {
            *l = loss_at(k * s)? - l0;
        }
    }
    let a = nalgebra::SMatrix::<f64, 11, 4>::from_fn(|r, c| (r as f64 - 5.0).powi(c as i32));
    let b = nalgebra::SVector::<f64, 11>::from_column_slice(&ls);
    let ata = a.transpose() * a;
    let Some(chol) = ata.cholesky() else {
        return Ok(f64::NAN);
    };
    let coef = chol.solve(&(a.transpose() * b));
    let res = b - a * coef;
    Ok((res.norm_squared() / 7.0).sqrt())
}

/// How the central differences of one component are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stencil {
    /// Richardson's table with ratio 2 over `D(h), D(2h), …, D(2^levels h)`
    /// (`levels` even powers removed; span `2^levels h`).
    Richardson { levels: usize },
    /// Weighted least squares of `D(j h/m)`, `j = 1…steps`, on
    /// `g + Σ_{k=1…levels} a_k h^{2k}` (see the module docs; span `h`).
    Fit { steps: usize, levels: usize },
}

/// Weights `w_j` of the differences `D(h_j)` in `g = Σ w_j D(h_j)` of
/// [`Stencil::Fit`] (`h_j = j h/m`), and the noise factor
/// `sqrt(Σ w_j² / (2 (j/m)²))` (the estimate's standard deviation in units
/// of `σ/h`). `None` when `steps ≤ levels` (too few differences to fit).
pub fn fit_weights(steps: usize, levels: usize) -> Option<(Vec<f64>, f64)> {
    if steps <= levels {
        return None;
    }
    let x = |j: usize| (j + 1) as f64 / steps as f64;
    let a = nalgebra::DMatrix::from_fn(steps, levels + 1, |j, k| x(j).powi(2 * k as i32));
    let w = nalgebra::DVector::from_fn(steps, |j, _| 2.0 * x(j) * x(j));
    let atw = a.transpose() * nalgebra::DMatrix::from_diagonal(&w);
    let normal = (&atw * &a).cholesky()?;
    // Row 0 of (AᵀWA)⁻¹ AᵀW: the weights of the intercept.
    let mut e0 = nalgebra::DVector::zeros(levels + 1);
    e0[0] = 1.0;
    let r = normal.solve(&e0);
    let weights: Vec<f64> = (atw.transpose() * r).iter().copied().collect();
    let var: f64 = weights
        .iter()
        .enumerate()
        .map(|(j, wj)| wj * wj / (2.0 * x(j) * x(j)))
        .sum();
    Some((weights, var.sqrt()))
}

/// `loss_at(t)`, evaluated once per bit pattern of `t`: `cache` holds the
/// `(t.to_bits(), L(t))` already evaluated (a linear search: a check
/// evaluates a few dozen steps).
pub fn cached_loss<E>(
    cache: &mut Vec<(u64, f64)>,
    loss_at: &mut dyn FnMut(f64) -> Result<f64, E>,
    t: f64,
) -> Result<f64, E> {
    if let Some(&(_, v)) = cache.iter().find(|(k, _)| *k == t.to_bits()) {
        return Ok(v);
    }
    let v = loss_at(t)?;
    cache.push((t.to_bits(), v));
    Ok(v)
}

/// `|estimate − adjoint| / max(|adjoint|, |estimate|)` (0 when both are 0):
/// the relative error of [`CentralCheck::relative_error`].
pub fn relative_error(estimate: f64, adjoint: f64) -> f64 {
    let scale = adjoint.abs().max(estimate.abs());
    if scale > 0.0 {
        (estimate - adjoint).abs() / scale
    } else {
        0.0
    }
}

/// Checks the adjoint component `adjoint` against Richardson's central
/// difference (`levels` deep, see the module docs) at step `h` and relative
/// criterion `crit`. `loss_at(t)` is the loss with the design variable
/// moved by `t`; `l0 = L(0)`. Costs `2 (levels + 1) + 10` loss evaluations.
pub fn check_component<E>(
    loss_at: &mut dyn FnMut(f64) -> Result<f64, E>,
    l0: f64,
    adjoint: f64,
    h: f64,
    levels: usize,
    crit: f64,
) -> Result<CentralCheck, E> {
    check_component_with(
        loss_at,
        l0,
        adjoint,
        h,
        Stencil::Richardson { levels },
        crit,
    )
}

/// [`check_component`] with any [`Stencil`]: Richardson's costs
/// `2 (levels + 1) + 10` loss evaluations, the fit `2 steps + 10`. The loss's
/// noise is measured at spacing `h/10` either way. A fit with
/// `steps ≤ levels` is treated as `steps = levels + 1`.
pub fn check_component_with<E>(
    loss_at: &mut dyn FnMut(f64) -> Result<f64, E>,
    l0: f64,
    adjoint: f64,
    h: f64,
    stencil: Stencil,
    crit: f64,
) -> Result<CentralCheck, E> {
    // A fit that cannot be made gives NaN, and the check fails (NaN is
    // neither resolved nor within any band).
    let central = estimate(loss_at, h, stencil)?;
    let factor = noise_factor(stencil);
    let (levels, steps) = shape(stencil);
    let loss_noise = loss_noise(loss_at, l0, h / 10.0)?;
    let central_noise = factor * loss_noise / h;
    let relative_error = relative_error(central, adjoint);
    let resolved = 2.0 * central_noise <= crit * adjoint.abs();
    let pass = if resolved {
        relative_error <= crit
    } else {
        (central - adjoint).abs() <= crit * adjoint.abs() + 3.0 * central_noise
    };
    Ok(CentralCheck {
        adjoint,
        central,
        h,
        levels,
        steps,
        loss_noise,
        central_noise,
        relative_error,
        resolved,
        pass,
        halved: None,
    })
}

/// The stencil's estimate of the derivative at step `h` (NaN for a fit
/// that cannot be made).
fn estimate<E>(
    loss_at: &mut dyn FnMut(f64) -> Result<f64, E>,
    h: f64,
    stencil: Stencil,
) -> Result<f64, E> {
    // `w (L(t) − L(−t)) / 2t`, in this order (the fixed check's bits).
    let mut term =
        |w: f64, t: f64| -> Result<f64, E> { Ok(w * (loss_at(t)? - loss_at(-t)?) / (2.0 * t)) };
    match stencil {
        Stencil::Richardson { levels } => {
            let mut g = 0.0;
            for (k, &c) in richardson_coefficients(levels).iter().enumerate() {
                g += term(c, h * 2f64.powi(k as i32))?;
            }
            Ok(g)
        }
        Stencil::Fit { steps, levels } => {
            let steps = steps.max(levels + 1);
            let Some((w, _)) = fit_weights(steps, levels) else {
                return Ok(f64::NAN);
            };
            let mut g = 0.0;
            for (j, wj) in w.iter().enumerate() {
                g += term(*wj, h * (j + 1) as f64 / steps as f64)?;
            }
            Ok(g)
        }
    }
}

/// The stencil's noise factor: its estimate's standard deviation in units
/// of `σ/h` (Richardson level 1: 0.950; NaN for a fit that cannot be made).
pub fn noise_factor(stencil: Stencil) -> f64 {
    match stencil {
        Stencil::Richardson { levels } => richardson_coefficients(levels)
            .iter()
            .enumerate()
            .map(|(k, c)| c * c / (2.0 * 4f64.powi(k as i32)))
            .sum::<f64>()
            .sqrt(),
        Stencil::Fit { steps, levels } => {
            fit_weights(steps.max(levels + 1), levels).map_or(f64::NAN, |(_, f)| f)
        }
    }
}

/// `(levels, differences)` of a stencil (a fit with `steps ≤ levels` is
/// treated as `steps = levels + 1`).
fn shape(stencil: Stencil) -> (usize, usize) {
    match stencil {
        Stencil::Richardson { levels } => (levels, levels + 1),
        Stencil::Fit { steps, levels } => (levels, steps.max(levels + 1)),
    }
}

/// Step range and resolution margin of [`check_component_adaptive`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// Smallest step; also the loss noise's scale (spacing `h_min/10`).
    pub h_min: f64,
    /// Largest step.
    pub h_max: f64,
    /// A component is resolved when `margin · central_noise ≤ crit |g|`.
    /// With 2 (the fixed check's), an estimate whose error is noise alone
    /// fails a resolved component about 5 % of the time; with 4, 6e-5.
    pub margin: f64,
}

/// A component checked at a step chosen from its own noise, with a test
/// that the loss is smooth over the stencil's span.
///
/// 1. The loss noise `σ` is measured as in [`check_component_with`]
///    (spacing `h_min/10`).
/// 2. `h = clamp(margin · f σ / (crit |g|), h_min, h_max)`, `f` the stencil's
///    noise factor: the smallest step at which the component is resolved
///    with the margin (a large component keeps `h_min`, a small one gets
///    the step its size needs).
/// 3. The estimates `c(h)` and `c(h/2)` are compared: on a loss smooth over
///    `±2h` they differ by noise (and truncation far below it), so
///    `|c(h) − c(h/2)| ≤ 3 √(σ_c(h)² + σ_c(h/2)²) + crit |g|/2` is the
///    smoothness test (a contact kink inside the span fails it).
/// 4. Resolved: smooth and `margin · σ_c(h) ≤ crit |g|`; `c(h)` must then
///    agree to `crit`. Smooth but not resolved (`h = h_max` and still too
///    noisy): `c(h)` must agree within `crit |g| + 3 σ_c(h)`. Not smooth:
///    the fixed check's rule at `h_min` (a kink the larger span reached may
///    lie outside the smaller one): `c(h_min)` within `crit |g| +
///    3 σ_c(h_min)`.
///
/// Costs 10 loss evaluations for the noise plus the stencil's at `h` and
/// `h/2` (Richardson level 1: 6, as `D(h)` is shared), and at `h_min` when
/// not smooth.
pub fn check_component_adaptive<E>(
    loss_at: &mut dyn FnMut(f64) -> Result<f64, E>,
    l0: f64,
    adjoint: f64,
    opts: Adaptive,
    stencil: Stencil,
    crit: f64,
) -> Result<CentralCheck, E> {
    let loss_noise = loss_noise(loss_at, l0, opts.h_min / 10.0)?;
    // Evaluations are cached by step: Richardson's tables at h and h/2 share D(h).
    let mut cache = Vec::new();
    let mut cached = |t: f64| cached_loss(&mut cache, loss_at, t);
    let factor = noise_factor(stencil);
    let want = opts.margin * factor * loss_noise / (crit * adjoint.abs());
    let h = if want.is_finite() {
        want.clamp(opts.h_min, opts.h_max)
    } else {
        opts.h_min
    };
    let central = estimate(&mut cached, h, stencil)?;
    let half = estimate(&mut cached, h / 2.0, stencil)?;
    let (noise_h, noise_half) = (factor * loss_noise / h, 2.0 * factor * loss_noise / h);
    let gap = (central - half).abs();
    let smooth = gap <= 3.0 * noise_h.hypot(noise_half) + 0.5 * crit * adjoint.abs();
    let resolved = smooth && opts.margin * noise_h <= crit * adjoint.abs();
    // Not smooth: the fixed check at h_min (a kink the larger span reached
    // may lie outside the smaller one).
    let (h_used, estimate_used, noise_used) = if smooth {
        (h, central, noise_h)
    } else {
        let noise_min = factor * loss_noise / opts.h_min;
        (
            opts.h_min,
            estimate(&mut cached, opts.h_min, stencil)?,
            noise_min,
        )
    };
    let relative_error = relative_error(estimate_used, adjoint);
    let pass = if resolved {
        relative_error <= crit
    } else {
        (estimate_used - adjoint).abs() <= crit * adjoint.abs() + 3.0 * noise_used
    };
    let (levels, steps) = shape(stencil);
    Ok(CentralCheck {
        adjoint,
        central: estimate_used,
        h: h_used,
        levels,
        steps,
        loss_noise,
        central_noise: noise_used,
        relative_error,
        resolved,
        pass,
        halved: Some(half),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    /// Deterministic pseudo-noise in [−1, 1) (a hash of t's bits).
    fn noise(t: f64) -> f64 {
        let mut x = t.to_bits() ^ 0x9E37_79B9_7F4A_7C15;
        x ^= x >> 33;
        x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
        x ^= x >> 33;
        x = x.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        x ^= x >> 33;
        (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    #[test]
    fn coefficients_sum_to_one_and_cancel_the_even_powers() {
        for levels in 0..4 {
            let c = richardson_coefficients(levels);
            assert_eq!(c.len(), levels + 1);
            assert!((c.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            for j in 1..=levels {
                let s: f64 = c
                    .iter()
                    .enumerate()
                    .map(|(k, &ck)| ck * 4f64.powi((j * k) as i32))
                    .sum();
                assert!(s.abs() < 1e-10, "levels {levels}, power h^{}: {s}", 2 * j);
            }
        }
        let c2 = richardson_coefficients(2);
        for (a, b) in c2.iter().zip([64.0 / 45.0, -20.0 / 45.0, 1.0 / 45.0]) {
            assert!((a - b).abs() < 1e-15);
        }
    }

    /// On a smooth function, each level removes one more even power: the
    /// errors at h = 1e-2 fall as h², h⁴, h⁶ (measured against the exact
    /// derivative; no noise, so every component is resolved and passes).
    #[test]
    fn richardson_levels_remove_truncation_on_a_smooth_function() {
        let f = |t: f64| (3.0 * (t + 0.2)).sin() + (t + 0.2).powi(5);
        let exact = 3.0 * (0.6f64).cos() + 5.0 * 0.2f64.powi(4);
        let mut errs = Vec::new();
        for levels in 0..3 {
            let mut at = |t: f64| Ok::<_, Infallible>(f(t));
            let c = check_component(&mut at, f(0.0), exact, 1e-2, levels, 1e-4).unwrap();
            errs.push((c.central - exact).abs());
        }
        assert!(errs[0] > 1e-5 && errs[0] < 1e-3, "{errs:?}");
        assert!(errs[1] < 3e-7 && errs[1] < 1e-2 * errs[0], "{errs:?}");
        assert!(errs[2] < 1e-2 * errs[1], "{errs:?}");
    }

    /// With noise of known size added, the measured noise is of that size,
    /// small components are reported as not resolved, and a wrong adjoint
    /// fails in both regimes.
    #[test]
    fn noise_decides_what_is_resolved_and_wrong_adjoints_fail() {
        let sigma = 1e-9;
        // Uniform noise on [−1, 1) scaled by √3 σ has standard deviation σ.
        let f = |t: f64, slope: f64| slope * t + 0.5 * t * t + 3f64.sqrt() * sigma * noise(t);
        let h = 1e-6;
        for (slope, want_resolved) in [(100.0, true), (0.5, false)] {
            let mut at = |t: f64| Ok::<_, Infallible>(f(t, slope));
            let l0 = f(0.0, slope);
            let ok = check_component(&mut at, l0, slope, h, 1, 1e-4).unwrap();
            assert!(
                ok.loss_noise > 0.2 * sigma && ok.loss_noise < 3.0 * sigma,
                "measured noise {:e}",
                ok.loss_noise
            );
            assert_eq!(ok.resolved, want_resolved, "slope {slope}: {ok:?}");
            assert!(ok.pass, "slope {slope}: {ok:?}");
            // An adjoint 2 % off is caught whether or not the component is
            // resolved to 1e-4 (the noise band at slope 0.5 is ≈ 3e-3 wide).
            let mut at = |t: f64| Ok::<_, Infallible>(f(t, slope));
            let bad = check_component(&mut at, l0, slope * 1.02, h, 1, 1e-4).unwrap();
            assert!(!bad.pass, "slope {slope}: {bad:?}");
        }
    }

    /// The fit's weights sum to one and cancel `h², …, h^{2ℓ}`; its noise
    /// factors are those quoted in the module docs; on a polynomial loss of
    /// degree `2ℓ + 1` the estimate is exact (to round-off).
    #[test]
    fn fit_is_exact_on_polynomials_and_its_noise_factor_is_as_documented() {
        for levels in 0..3 {
            for steps in [levels + 1, 8, 16] {
                let (w, _) = fit_weights(steps, levels).unwrap();
                let x = |j: usize| (j + 1) as f64 / steps as f64;
                assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-10);
                for p in 1..=levels {
                    let s: f64 = w
                        .iter()
                        .enumerate()
                        .map(|(j, wj)| wj * x(j).powi(2 * p as i32))
                        .sum();
                    assert!(s.abs() < 1e-10, "levels {levels} steps {steps} h^{}", 2 * p);
                }
            }
        }
        assert!(fit_weights(2, 2).is_none());
        for (m, want) in [(8, 1.002), (16, 0.734), (32, 0.529), (64, 0.378)] {
            let (_, f) = fit_weights(m, 1).unwrap();
            assert!((f - want).abs() < 1e-3, "m {m}: {f}");
        }
        // L(t) = 2 t + t² − 7 t³ + 11 t⁵: D(h) = 2 − 7h² + 11h⁴, exact at ℓ = 2.
        let f = |t: f64| 2.0 * t + t * t - 7.0 * t.powi(3) + 11.0 * t.powi(5);
        let mut at = |t: f64| Ok::<_, Infallible>(f(t));
        let stencil = Stencil::Fit {
            steps: 12,
            levels: 2,
        };
        let c = check_component_with(&mut at, 0.0, 2.0, 0.1, stencil, 1e-4).unwrap();
        assert!((c.central - 2.0).abs() < 1e-12, "{c:?}");
        assert_eq!((c.steps, c.levels), (12, 2));
    }

    /// Over many independent noise draws the fit's estimates scatter with
    /// the standard deviation it predicts (within 15 %, 400 draws), as do
    /// Richardson's level-1 estimates.
    #[test]
    fn fit_noise_matches_its_prediction() {
        let sigma = 1e-9;
        let h = 1e-6;
        let draw = |seed: u64, stencil: Stencil| {
            let f = |t: f64| {
                let n = noise(f64::from_bits(t.to_bits() ^ seed.wrapping_mul(0x9E37_79B9)));
                0.3 * t + 3f64.sqrt() * sigma * n
            };
            let mut at = |t: f64| Ok::<_, Infallible>(f(t));
            check_component_with(&mut at, f(0.0), 0.3, h, stencil, 1e-4).unwrap()
        };
        for stencil in [
            Stencil::Fit {
                steps: 32,
                levels: 1,
            },
            Stencil::Richardson { levels: 1 },
        ] {
            let est: Vec<f64> = (1..=400).map(|s| draw(s, stencil).central).collect();
            let mean = est.iter().sum::<f64>() / 400.0;
            let sd = (est.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / 399.0).sqrt();
            let predicted = match stencil {
                Stencil::Fit { steps, levels } => fit_weights(steps, levels).unwrap().1,
                Stencil::Richardson { .. } => 0.950,
            } * sigma
                / h;
            assert!(
                (sd / predicted - 1.0).abs() < 0.15,
                "{stencil:?}: scatter {sd:e}, predicted {predicted:e}"
            );
        }
    }

    /// The adaptive check: a component too small for the fixed step is
    /// resolved at the larger step its size needs (and agrees); an adjoint
    /// 2 % off fails; a large component keeps `h_min`.
    #[test]
    fn adaptive_step_resolves_small_components_and_catches_wrong_adjoints() {
        let sigma = 1e-9;
        let f = |t: f64, slope: f64| slope * t + 0.5 * t * t + 3f64.sqrt() * sigma * noise(t);
        let opts = Adaptive {
            h_min: 1e-6,
            h_max: 1e-3,
            margin: 4.0,
        };
        let stencil = Stencil::Richardson { levels: 1 };
        for slope in [0.5, 100.0] {
            let l0 = f(0.0, slope);
            let mut at = |t: f64| Ok::<_, Infallible>(f(t, slope));
            let fixed = check_component(&mut at, l0, slope, 1e-6, 1, 1e-4).unwrap();
            let mut at = |t: f64| Ok::<_, Infallible>(f(t, slope));
            let c = check_component_adaptive(&mut at, l0, slope, opts, stencil, 1e-4).unwrap();
            assert!(c.resolved && c.pass, "slope {slope}: {c:?}");
            assert_eq!(fixed.resolved, slope > 1.0, "slope {slope}: {fixed:?}");
            assert!(4.0 * c.central_noise <= 1e-4 * slope, "{c:?}");
            if slope > 1.0 {
                assert_eq!(c.h, 1e-6);
            } else {
                assert!(c.h > 1e-5, "{c:?}");
            }
            let mut at = |t: f64| Ok::<_, Infallible>(f(t, slope));
            let bad =
                check_component_adaptive(&mut at, l0, 1.02 * slope, opts, stencil, 1e-4).unwrap();
            assert!(!bad.pass, "slope {slope}: {bad:?}");
        }
    }

    /// A kink inside the stencil's span (a ramp starting at t = 1.5e-5,
    /// inside ±2h for the step the noise asks for) fails the smoothness
    /// test: the component is not resolved and is judged at `h_min`, whose
    /// span (±2e-6) misses the kink, so the true derivative at 0 passes
    /// and a 2 % error is caught there.
    #[test]
    fn adaptive_check_flags_a_kink_inside_its_span() {
        let sigma = 1e-9;
        let f = |t: f64| 0.5 * t + 40.0 * (t - 1.5e-5).max(0.0) + 3f64.sqrt() * sigma * noise(t);
        let opts = Adaptive {
            h_min: 1e-6,
            h_max: 1e-3,
            margin: 4.0,
        };
        let mut at = |t: f64| Ok::<_, Infallible>(f(t));
        let stencil = Stencil::Richardson { levels: 1 };
        let c = check_component_adaptive(&mut at, f(0.0), 0.5, opts, stencil, 1e-4).unwrap();
        assert!(!c.resolved && c.pass && c.h == 1e-6, "{c:?}");
        assert!((c.halved.unwrap() - 0.5).abs() > 1.0, "{c:?}");
        let mut at = |t: f64| Ok::<_, Infallible>(f(t));
        let bad = check_component_adaptive(&mut at, f(0.0), 0.51, opts, stencil, 1e-4).unwrap();
        assert!(!bad.pass, "{bad:?}");
    }

    /// Errors of the loss evaluation are passed through.
    #[test]
    fn evaluation_errors_propagate() {
        let mut at = |t: f64| if t > 0.0 { Err("infeasible") } else { Ok(t) };
        assert_eq!(
            check_component(&mut at, 0.0, 1.0, 1e-3, 1, 1e-4),
            Err("infeasible")
        );
    }
}
