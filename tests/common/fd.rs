//! Central differences of a long trajectory's loss, with the differences'
//! own noise measured, for whole-trajectory gradient checks.
//!
//! Over hundreds of contact-rich steps the loss carries round-off noise
//! (σ ≈ 1e-9 on the spider's 550 steps, the same at Newton tolerance 1e-12
//! and at the round-off floor: it is the trajectory's amplification of
//! double-precision round-off, not the solver's tolerance). A central
//! difference at step h inherits ≈ σ/h of it, so a component much smaller
//! than the largest cannot be checked to 1e-4 by *any* h: larger steps
//! trade the noise for truncation error. [`check_component`] therefore
//! measures σ along the component's direction and says whether the
//! difference resolves the component to the criterion before judging it.

/// One component's check: the adjoint `g`, Richardson's central difference
/// `fd`, the difference's noise (standard deviation) and the verdict.
#[derive(Clone, Copy, Debug)]
pub struct FdComponent {
    pub g: f64,
    pub fd: f64,
    /// Standard deviation of the loss's noise along this direction.
    pub loss_noise: f64,
    /// Standard deviation of `fd` due to that noise, `≈ 0.95 σ / h`.
    pub fd_noise: f64,
    /// `|fd − g| / max(|g|, |fd|)`.
    pub rel: f64,
    /// The difference resolves the component to `crit`: `2 fd_noise ≤ crit |g|`.
    pub resolved: bool,
    /// Resolved: `rel ≤ crit`. Not resolved: `|fd − g| ≤ crit |g| + 3 fd_noise`
    /// (agreement within the differences' own uncertainty).
    pub pass: bool,
}

/// Residual standard deviation of a least-squares cubic through the seven
/// losses `L(k s)`, `k = −3…3` (`l0 = L(0)` given): the loss's noise at the
/// scale `s`, where the loss itself is a cubic to far below it.
pub fn loss_noise(loss_at: &dyn Fn(f64) -> f64, l0: f64, s: f64) -> f64 {
    let ks: Vec<f64> = (-3..=3).map(|k| k as f64).collect();
    let ls: Vec<f64> = ks
        .iter()
        .map(|&k| if k == 0.0 { 0.0 } else { loss_at(k * s) - l0 })
        .collect();
    let a = nalgebra::DMatrix::from_fn(ks.len(), 4, |r, c| ks[r].powi(c as i32));
    let b = nalgebra::DVector::from_column_slice(&ls);
    let ata = a.transpose() * &a;
    let coef = ata.cholesky().unwrap().solve(&(a.transpose() * &b));
    let res = &b - &a * &coef;
    (res.norm_squared() / (ks.len() - 4) as f64).sqrt()
}

/// Checks the adjoint `g` of one component against Richardson's central
/// difference at step `h`, at criterion `crit` (relative). `loss_at(t)` is
/// the loss at the design moved by `t` along the component, `l0 = L(0)`.
/// `FD_LEVELS` (default 1) sets the extrapolation's depth:
/// `D(h) = (L(h) − L(−h)) / 2h`; level 1 is `(4 D(h) − D(2h)) / 3` (the h²
/// term removed), level 2 also removes the h⁴ term from level 1 at h and 2h.
/// The noise is measured at spacing `h / 10` ([`loss_noise`]); with
/// independent noise σ on each loss and the estimate `Σ c_k D(2^k h)`,
/// `Var = Σ c_k² σ² / (2 (2^k h)²)` (level 1: `std ≈ 0.950 σ / h`).
pub fn check_component(
    loss_at: &dyn Fn(f64) -> f64,
    l0: f64,
    g: f64,
    h: f64,
    crit: f64,
) -> FdComponent {
    let levels: usize = std::env::var("FD_LEVELS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    // Coefficients c_k of D(2^k h) in the extrapolated estimate: Richardson's
    // table with ratio 2 on a series in h², h⁴, …
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
    let d = |h: f64| (loss_at(h) - loss_at(-h)) / (2.0 * h);
    let fd: f64 = coef
        .iter()
        .enumerate()
        .map(|(k, &c)| c * d(h * 2f64.powi(k as i32)))
        .sum();
    let loss_noise = loss_noise(loss_at, l0, h / 10.0);
    let var: f64 = coef
        .iter()
        .enumerate()
        .map(|(k, &c)| c * c / (2.0 * 4f64.powi(k as i32)))
        .sum();
    let fd_noise = var.sqrt() * loss_noise / h;
    let rel = (fd - g).abs() / g.abs().max(fd.abs());
    let resolved = 2.0 * fd_noise <= crit * g.abs();
    let pass = if resolved {
        rel <= crit
    } else {
        (fd - g).abs() <= crit * g.abs() + 3.0 * fd_noise
    };
    FdComponent {
        g,
        fd,
        loss_noise,
        fd_noise,
        rel,
        resolved,
        pass,
    }
}
