//! Whole-trajectory gradient checks with the differences' noise measured:
//! a thin wrapper of [`sdrs::diff::central::check_component`] (see its module
//! docs for the estimator and the noise model) for losses that cannot fail.

pub use sdrs::diff::central::{Adaptive, CentralCheck, Stencil};

/// `default` unless the environment says otherwise: `FD_STEPS=m` selects
/// the least-squares fit of `m` differences over `(0, h]`
/// ([`Stencil::Fit`]), otherwise Richardson's table; `FD_LEVELS` sets the
/// even powers removed (default: `default`'s).
pub fn stencil_from_env(default: Stencil) -> Stencil {
    let var = |k: &str| std::env::var(k).ok().and_then(|s| s.parse::<usize>().ok());
    let levels = var("FD_LEVELS").unwrap_or(match default {
        Stencil::Richardson { levels } | Stencil::Fit { levels, .. } => levels,
    });
    match (var("FD_STEPS"), default) {
        (Some(steps), _) | (None, Stencil::Fit { steps, .. }) => Stencil::Fit { steps, levels },
        (None, Stencil::Richardson { .. }) => Stencil::Richardson { levels },
    }
}

/// Checks the adjoint `g` of one component against the central differences
/// combined by `stencil` at step `h` and relative criterion `crit`;
/// `loss_at(t)` is the loss at the design moved by `t` along the component,
/// `l0 = L(0)`.
pub fn check_component(
    loss_at: &dyn Fn(f64) -> f64,
    l0: f64,
    g: f64,
    h: f64,
    stencil: Stencil,
    crit: f64,
) -> CentralCheck {
    let mut at = |t: f64| Ok::<f64, std::convert::Infallible>(loss_at(t));
    match sdrs::diff::central::check_component_with(&mut at, l0, g, h, stencil, crit) {
        Ok(c) => c,
        Err(e) => match e {},
    }
}

/// How each component's differences are taken: at one fixed step, or at a
/// step chosen from its own noise with a smoothness test
/// ([`sdrs::diff::central::check_component_adaptive`]).
#[derive(Clone, Copy, Debug)]
pub enum Steps {
    Fixed(f64),
    Adaptive(Adaptive),
}

/// Checks a sample of components (`vars`: name and adjoint value of each)
/// at fixed or adaptive `steps` (`stencil`, relative criterion `crit`);
/// `loss_at(k, t)` is the loss with the `k`-th variable moved by `t`,
/// `l0 = L(0)`. Prints one line per component, prefixed by `label`.
/// Returns how many are resolved and agree, and whether every component
/// passes.
pub fn check_sample(
    label: &str,
    vars: &[(String, f64)],
    loss_at: &dyn Fn(usize, f64) -> f64,
    l0: f64,
    steps: Steps,
    stencil: Stencil,
    crit: f64,
) -> (usize, bool) {
    let mut agree = 0;
    let mut all = true;
    for (k, (name, g)) in vars.iter().enumerate() {
        let c = match steps {
            Steps::Fixed(h) => check_component(&|t| loss_at(k, t), l0, *g, h, stencil, crit),
            Steps::Adaptive(a) => {
                let mut at = |t: f64| Ok::<f64, std::convert::Infallible>(loss_at(k, t));
                match sdrs::diff::central::check_component_adaptive(
                    &mut at, l0, *g, a, stencil, crit,
                ) {
                    Ok(c) => c,
                    Err(e) => match e {},
                }
            }
        };
        let halved = c
            .halved
            .map_or(String::new(), |v| format!(", at h/2 {v:.9e}"));
        eprintln!(
            "{label} {name}: adjoint {:.9e} central {:.9e} rel {:.2e} at h {:.1e} \
             (loss noise {:.1e}, central noise {:.1e}, {} differences{halved}, {}) {}",
            c.adjoint,
            c.central,
            c.relative_error,
            c.h,
            c.loss_noise,
            c.central_noise,
            c.steps,
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

/// [`check_sample`] of the design components `idx` of problem `p` at
/// (`d`, `c`), whose evaluation there is `ev`: the adjoint values and names
/// come from `ev` and the design space, the losses from the forward-only
/// [`sdrs::optimize::Problem::loss_value`] (bitwise the evaluation's loss).
#[allow(clippy::too_many_arguments)]
pub fn check_problem_sample(
    label: &str,
    p: &sdrs::optimize::Problem,
    d: &nalgebra::DVector<f64>,
    c: &nalgebra::DVector<f64>,
    ev: &sdrs::optimize::Evaluation,
    idx: &[usize],
    steps: Steps,
    stencil: Stencil,
) -> (usize, bool) {
    let vars: Vec<(String, f64)> = idx
        .iter()
        .map(|&i| (p.design.vars[i].name.clone(), ev.grad_design[i]))
        .collect();
    let loss_at = |k: usize, t: f64| {
        let mut dt = d.clone();
        dt[idx[k]] += t;
        p.loss_value(&dt, c).unwrap()
    };
    check_sample(label, &vars, &loss_at, ev.loss, steps, stencil, 1e-4)
}
