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
/// difference `(4 D(h) − D(2h)) / 3`, `D(h) = (L(h) − L(−h)) / 2h` (its h²
/// truncation term removed), at criterion `crit` (relative). `loss_at(t)` is
/// the loss at the design moved by `t` along the component, `l0 = L(0)`.
/// The noise is measured at spacing `h / 10` ([`loss_noise`]); with
/// independent noise σ on each loss, `Var R = (16 σ²/2h² + σ²/8h²) / 9`,
/// i.e. `std R ≈ 0.950 σ / h`.
pub fn check_component(
    loss_at: &dyn Fn(f64) -> f64,
    l0: f64,
    g: f64,
    h: f64,
    crit: f64,
) -> FdComponent {
    let d = |h: f64| (loss_at(h) - loss_at(-h)) / (2.0 * h);
    let fd = (4.0 * d(h) - d(2.0 * h)) / 3.0;
    let loss_noise = loss_noise(loss_at, l0, h / 10.0);
    let fd_noise = (8.125f64 / 9.0).sqrt() * loss_noise / h;
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
