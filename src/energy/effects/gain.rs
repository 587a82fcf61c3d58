//! Actuator gain: the motor delivers `g` times the commanded PD torque.
//!
//! The stable-PD term (paper `pbad.tex`, [`crate::energy::pd`]) becomes
//! `g·U_pd`, i.e. `k_p → g k_p` and `k_d → g k_d` on the affected
//! coordinates (`g` dimensionless, 1 = nominal). No new energy term: the
//! gradient comes from the controller channels of the adjoint pass
//! ([`crate::diff::effects::gain_gradient`]),
//! `dL/dg = Σ_ch (k_p,ch dL/dk_p,ch + k_d,ch dL/dk_d,ch)/g` (the scaled
//! gains divided by `g` are the nominal ones).

use crate::control::Controller;

/// Scales the gains of every channel acting on one of `dofs` by `g`.
pub fn apply(controller: &mut Controller, dofs: &[usize], g: f64) {
    for ch in controller.channels.iter_mut() {
        if dofs.contains(&ch.dof) {
            ch.kp *= g;
            ch.kd *= g;
        }
    }
}
