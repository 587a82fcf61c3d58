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

/// Checks a sample of components (`vars`: name and adjoint value of each)
/// with [`check_component`]; `loss_at(k, t)` is the loss with the `k`-th
/// variable moved by `t`, `l0 = L(0)`. Prints one line per component,
/// prefixed by `label`. Returns how many are resolved and agree, and whether
/// every component passes.
pub fn check_sample(
    label: &str,
    vars: &[(String, f64)],
    loss_at: &dyn Fn(usize, f64) -> f64,
    l0: f64,
    h: f64,
    crit: f64,
) -> (usize, bool) {
    let mut agree = 0;
    let mut all = true;
    for (k, (name, g)) in vars.iter().enumerate() {
        let c = check_component(&|t| loss_at(k, t), l0, *g, h, crit);
        eprintln!(
            "{label} {name}: adjoint {:.9e} central {:.9e} rel {:.2e} \
             (loss noise {:.1e}, central noise {:.1e}, {}) {}",
            c.adjoint,
            c.central,
            c.relative_error,
            c.loss_noise,
            c.central_noise,
            if c.resolved {
                "resolved"
            } else {
                "not resolved to the criterion"
            },
            if c.pass { "ok" } else { "FAIL" }
        );
        agree += usize::from(c.resolved && c.pass);
        all &= c.pass;
    }
    (agree, all)
}
