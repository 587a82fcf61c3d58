//! Contact parameters as calibration effects: the friction coefficient `μ`
//! (dimensionless), the barrier stiffness `κ` (J·m) and the barrier support
//! `s` (m) of [`crate::scene::ContactSettings`] (paper, `contact.tex`,
//! `friction.tex`). Already differentiable: their gradients are the
//! `mu`, `kappa`, `s` fields of [`crate::diff::PhysicalGrad`].

use crate::diff::Gradients;
use crate::energy::effects::EffectKind;
use crate::scene::ContactSettings;

/// Sets the parameter of `kind` in `c` to `v`.
pub fn apply(c: &mut ContactSettings, kind: EffectKind, v: f64) {
    match kind {
        EffectKind::ContactMu => c.mu = v,
        EffectKind::ContactKappa => c.kappa = v,
        EffectKind::ContactS => c.s = v,
        _ => {}
    }
}

/// The current value of `kind`'s parameter in `c`.
pub fn value(c: &ContactSettings, kind: EffectKind) -> f64 {
    match kind {
        EffectKind::ContactMu => c.mu,
        EffectKind::ContactKappa => c.kappa,
        EffectKind::ContactS => c.s,
        _ => f64::NAN,
    }
}

/// `dL/d(parameter)` from the adjoint pass.
pub fn gradient(kind: EffectKind, grads: &Gradients) -> f64 {
    match kind {
        EffectKind::ContactMu => grads.physical.mu,
        EffectKind::ContactKappa => grads.physical.kappa,
        EffectKind::ContactS => grads.physical.s,
        _ => 0.0,
    }
}
