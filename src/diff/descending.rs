//! A gradient check that descends in step size when the loss is rough.
//!
//! A trajectory loss can be smooth only at scales far below the usual
//! difference step: on a walk that falls, a foot vertex's `∂L/∂d` can be
//! 5e6 against a loss of 6, and the loss along that vertex swings by more
//! than its slope predicts from `|t| ≈ 1e-8` m on. A central difference at
//! `h = 1e-6` then measures that roughness (and the noise estimate of
//! [`super::central::loss_noise`], a cubic fit over `±h/2`, reads it as
//! noise), while the adjoint is the loss's derivative at the point. Such a
//! component is checkable at steps below the roughness scale, where the
//! differences converge to the derivative with the `h²` truncation of a
//! smooth function (`notes/fd-check-rough-losses.md`).
//!
//! [`check_component_descending`] keeps [`check_component`]'s check at the
//! first step `h₀`; when it does not pass resolved, it halves the step:
//! `D_j = D(h₀ / 2^j)` (`D(h) = (L(h) − L(−h)) / 2h`) down to `h_floor`, with
//! Richardson's level-1 estimate `R_j = (4 D_j − D_{j−1}) / 3` at each step.
//! The first `j` at which **two consecutive** estimates `R_j`, `R_{j+1}` lie
//! within `crit |g|` of the adjoint `g` is taken (a swinging difference can
//! land on `g` at one step by chance, not at two in a row); the loss noise is
//! then measured at `h_j` and the component passes if it is resolved there
//! (`2 σ_c ≤ crit |g|`, `σ_c = 0.950 σ / h_j`, as [`check_component`]).

use super::central::{
    CentralCheck, Stencil, cached_loss, check_component, loss_noise, noise_factor, relative_error,
};

/// Step range of [`check_component_descending`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Descent {
    /// First step `h₀` (the fixed check's).
    pub h0: f64,
    /// Smallest step tried; the descent stops before going below it.
    pub h_floor: f64,
}

/// Outcome of [`check_component_descending`].
#[derive(Clone, Debug, PartialEq)]
pub struct DescendingCheck {
    /// [`check_component`] at `h₀` (Richardson level 1).
    pub first: CentralCheck,
    /// The check at the step where two consecutive estimates agreed with
    /// the adjoint, noise measured there (it may still be unresolved);
    /// `None` when the first check passed resolved (no descent) or no step
    /// in `[h_floor, h₀)` agreed.
    pub descended: Option<CentralCheck>,
    /// `(h_j, R_j)` of every step of the descent (empty without one).
    pub sweep: Vec<(f64, f64)>,
}

impl DescendingCheck {
    /// The check that stands: the descended one if it passed resolved, else
    /// the first (an unresolved descent does not replace it).
    pub fn standing(&self) -> &CentralCheck {
        match &self.descended {
            Some(d) if d.pass && d.resolved => d,
            _ => &self.first,
        }
    }

    /// Whether the component passes: the first check passed resolved, or a
    /// descended check passed resolved.
    pub fn pass(&self) -> bool {
        let c = self.standing();
        c.pass && c.resolved
    }
}

/// Checks `adjoint` against central differences of `loss_at` (the loss
/// with the variable moved by `t`; `l0 = L(0)`), descending in step size
/// when the first check fails (see the module docs). Costs the first
/// check's 14 loss evaluations, plus 2 per halving and 10 for the noise at
/// the agreeing step when it descends (at most `2 log₂(h₀/h_floor) + 24`;
/// `D(h₀)` comes from the first check's evaluations).
pub fn check_component_descending<E>(
    loss_at: &mut dyn FnMut(f64) -> Result<f64, E>,
    l0: f64,
    adjoint: f64,
    steps: Descent,
    crit: f64,
) -> Result<DescendingCheck, E> {
    // Cached: the descent's D(h₀) reuses the first check's L(±h₀).
    let mut cache = Vec::new();
    let mut loss_at = |t: f64| cached_loss(&mut cache, loss_at, t);
    let loss_at: &mut dyn FnMut(f64) -> Result<f64, E> = &mut loss_at;
    let first = check_component(loss_at, l0, adjoint, steps.h0, 1, crit)?;
    let mut out = DescendingCheck {
        first,
        descended: None,
        sweep: Vec::new(),
    };
    if first.pass && first.resolved {
        return Ok(out);
    }
    let mut d = |h: f64| -> Result<f64, E> { Ok((loss_at(h)? - loss_at(-h)?) / (2.0 * h)) };
    let agrees = |r: f64| (r - adjoint).abs() <= crit * adjoint.abs();
    let mut d_prev = d(steps.h0)?;
    let mut h = steps.h0 / 2.0;
    while h >= steps.h_floor {
        let d_h = d(h)?;
        let r = (4.0 * d_h - d_prev) / 3.0;
        out.sweep.push((h, r));
        let n = out.sweep.len();
        if n >= 2 && agrees(r) && agrees(out.sweep[n - 2].1) {
            let (h_agreed, r_agreed) = out.sweep[n - 2];
            out.descended = Some(at_step(loss_at, l0, adjoint, h_agreed, r_agreed, crit)?);
            break;
        }
        d_prev = d_h;
        h /= 2.0;
    }
    Ok(out)
}

/// The check at step `h` with the estimate `central` already known: the
/// loss noise measured at spacing `h/10`, resolution and agreement as in
/// [`check_component`].
fn at_step<E>(
    loss_at: &mut dyn FnMut(f64) -> Result<f64, E>,
    l0: f64,
    adjoint: f64,
    h: f64,
    central: f64,
    crit: f64,
) -> Result<CentralCheck, E> {
    let sigma = loss_noise(loss_at, l0, h / 10.0)?;
    let central_noise = noise_factor(Stencil::Richardson { levels: 1 }) * sigma / h;
    let relative_error = relative_error(central, adjoint);
    let resolved = 2.0 * central_noise <= crit * adjoint.abs();
    Ok(CentralCheck {
        adjoint,
        central,
        h,
        levels: 1,
        steps: 2,
        loss_noise: sigma,
        central_noise,
        relative_error,
        resolved,
        pass: resolved && relative_error <= crit,
        halved: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    /// `L(t) = a t + A sin(ω t + φ)`: smooth at `|t| ≪ 1/ω`, rough beyond;
    /// `L'(0) = a + A ω cos φ`.
    fn rough(t: f64) -> f64 {
        let (a, amp, w, phi) = (2.0, 1e-3, 1e9, 0.3);
        a * t + amp * (w * t + phi).sin()
    }
    const ROUGH_SLOPE: f64 = 2.0 + 1e-3 * 1e9 * 0.955_336_489_125_606; // cos 0.3

    fn run(f: fn(f64) -> f64, adjoint: f64) -> DescendingCheck {
        let mut at = |t: f64| -> Result<f64, Infallible> { Ok(f(t)) };
        let steps = Descent {
            h0: 1e-6,
            h_floor: 1e-12,
        };
        check_component_descending(&mut at, f(0.0), adjoint, steps, 1e-4).unwrap()
    }

    #[test]
    fn a_rough_loss_is_checked_below_its_roughness_scale() {
        let c = run(rough, ROUGH_SLOPE);
        assert!(!c.first.pass, "h0 = 1e-6 sees the roughness: {:?}", c.first);
        let d = c.descended.expect("a step below 1/ω agrees");
        assert!(d.h < 1e-9 && d.h >= 1e-12, "{d:?}");
        assert!(d.pass && d.resolved && d.relative_error <= 1e-4, "{d:?}");
        assert!(c.pass());
        // The steps halve from h0.
        assert_eq!(c.sweep[0].0, 5e-7);
        assert!(c.sweep.windows(2).all(|w| w[1].0 == w[0].0 / 2.0));
    }

    #[test]
    fn a_wrong_adjoint_of_a_rough_loss_fails_at_every_step() {
        for factor in [1.001, 0.999, 1.01, -1.0, 0.0] {
            let c = run(rough, ROUGH_SLOPE * factor);
            assert!(!c.pass(), "factor {factor}: {c:?}");
            assert!(c.descended.is_none(), "factor {factor}");
            // The whole range was swept: 19 halvings from 1e-6 stay ≥ 1e-12.
            assert_eq!(c.sweep.len(), 19, "factor {factor}");
        }
    }

    #[test]
    fn only_a_resolved_passing_descent_replaces_the_first_check() {
        let first = run(rough, ROUGH_SLOPE).first;
        let mut descended = first;
        descended.h = 1e-10;
        let mut c = DescendingCheck {
            first,
            descended: None,
            sweep: Vec::new(),
        };
        for (pass, resolved, replaces) in [
            (true, true, true),
            (true, false, false),
            (false, true, false),
            (false, false, false),
        ] {
            descended.pass = pass;
            descended.resolved = resolved;
            c.descended = Some(descended);
            let want = if replaces { &descended } else { &c.first };
            assert_eq!(c.standing(), want, "pass {pass}, resolved {resolved}");
            assert_eq!(c.pass(), replaces, "pass {pass}, resolved {resolved}");
        }
    }

    #[test]
    fn a_smooth_loss_passing_at_h0_does_not_descend() {
        let smooth = |t: f64| 1.0 + 3.0 * t + 0.5 * t * t + t.powi(3);
        let c = run(smooth, 3.0);
        assert!(c.first.pass && c.first.resolved);
        assert!(c.descended.is_none() && c.sweep.is_empty());
        assert!(c.pass());
        assert_eq!(c.standing(), &c.first);
    }

    #[test]
    fn noise_below_the_roughness_scale_is_reported_unresolved() {
        // Noise of ±1e-7 on the loss (σ ≈ 5.8e-8): the component is resolved
        // (2 · 0.95 σ/h ≤ 1e-4 · 9.6e5) only at h ≳ 1.2e-9, where the sine is
        // rough (ωh ≳ 1.2); where it is smooth the differences are noise. A
        // correct adjoint must not pass, nor a wrong one.
        fn noisy(t: f64) -> f64 {
            let mut x = t.to_bits() ^ 0x9E37_79B9_7F4A_7C15;
            x ^= x >> 33;
            x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
            x ^= x >> 33;
            let u = (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0;
            rough(t) + 1e-7 * u
        }
        for factor in [1.0, 1.01] {
            let c = run(noisy, ROUGH_SLOPE * factor);
            assert!(!c.pass(), "factor {factor}: {c:?}");
            // An unresolved descent never replaces the first check.
            assert_eq!(c.standing(), &c.first, "factor {factor}");
        }
    }
}
