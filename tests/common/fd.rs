//! Whole-trajectory gradient checks with the differences' noise measured:
//! a thin wrapper of [`sdrs::diff::central::check_component`] (see its module
//! docs for the estimator and the noise model) for losses that cannot fail.

pub use sdrs::diff::central::CentralCheck;

/// Checks the adjoint `g` of one component against Richardson's central
/// difference at step `h` and relative criterion `crit`; `loss_at(t)` is the
/// loss at the design moved by `t` along the component, `l0 = L(0)`.
/// `FD_LEVELS` (default 1) sets the extrapolation's depth.
pub fn check_component(
    loss_at: &dyn Fn(f64) -> f64,
    l0: f64,
    g: f64,
    h: f64,
    crit: f64,
) -> CentralCheck {
    let levels: usize = std::env::var("FD_LEVELS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let mut at = |t: f64| Ok::<f64, std::convert::Infallible>(loss_at(t));
    match sdrs::diff::central::check_component(&mut at, l0, g, h, levels, crit) {
        Ok(c) => c,
        Err(e) => match e {},
    }
}
