//! Contact parameters that calibration can fit: the friction coefficient
//! `μ` (dimensionless), the barrier stiffness `κ` (J·m) and the barrier
//! support `s` (m) of [`ContactSettings`] (paper, `contact.tex`,
//! `friction.tex`). Already differentiable: their gradients are the `mu`,
//! `kappa`, `s` fields of the adjoint pass's physical gradients
//! (`crate::diff::effects::contact_gradient`).

use super::settings::ContactSettings;

/// One of the fitted contact parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactParam {
    Mu,
    Kappa,
    S,
}

impl ContactParam {
    /// Sets the parameter in `c` to `v`.
    pub fn apply(self, c: &mut ContactSettings, v: f64) {
        match self {
            ContactParam::Mu => c.mu = v,
            ContactParam::Kappa => c.kappa = v,
            ContactParam::S => c.s = v,
        }
    }

    /// The parameter's value in `c`.
    pub fn value(self, c: &ContactSettings) -> f64 {
        match self {
            ContactParam::Mu => c.mu,
            ContactParam::Kappa => c.kappa,
            ContactParam::S => c.s,
        }
    }
}
