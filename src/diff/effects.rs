//! Gradients of calibration effects ([`crate::energy::effects`]) that are
//! not written by their own energy terms: actuator gains map the controller
//! channels' gradients, contact parameters the physical ones; everything
//! else comes through the generic effect channel of the adjoint pass.

use super::Gradients;
use crate::control::Controller;
use crate::energy::effects::{Effect, EffectKind, Target};

/// `dL/d(values)` of every effect, flattened in slot order, from the
/// adjoint gradients of a trajectory simulated with `effects` installed
/// (`controller`: the simulator's controller, gains already scaled).
pub fn gradient(
    effects: &[Effect],
    controller: &crate::control::Controller,
    grads: &crate::diff::Gradients,
) -> Vec<f64> {
    let n: usize = effects.iter().map(|e| e.values.len()).sum();
    let mut out = vec![0.0; n];
    for e in effects {
        for k in 0..e.values.len() {
            let s = e.slot + k;
            out[s] = match (e.kind, &e.target) {
                (EffectKind::ActuatorGain, Target::Dofs(d)) => {
                    gain_gradient(controller, d, e.values[0], grads)
                }
                (EffectKind::ActuationDelay, Target::Dofs(d)) => {
                    delay_gradient(controller, d, grads)
                }
                (_, Target::Contact) => contact_gradient(e.kind, grads),
                (EffectKind::JointOffset, _) => 0.0,
                _ => grads.effects.get(s).copied().unwrap_or(0.0),
            };
        }
    }
    out
}

/// `dL/d(parameter)` of a contact effect from the adjoint pass (the `mu`,
/// `kappa`, `s` fields of [`super::PhysicalGrad`]).
pub fn contact_gradient(kind: EffectKind, grads: &Gradients) -> f64 {
    match kind {
        EffectKind::ContactMu => grads.physical.mu,
        EffectKind::ContactKappa => grads.physical.kappa,
        EffectKind::ContactS => grads.physical.s,
        _ => 0.0,
    }
}

/// `dL/dg` from the channel gradients of a trajectory simulated with the
/// scaled `controller`.
pub fn gain_gradient(controller: &Controller, dofs: &[usize], g: f64, grads: &Gradients) -> f64 {
    controller
        .channels
        .iter()
        .zip(&grads.channels)
        .filter(|(ch, _)| dofs.contains(&ch.dof))
        .map(|(ch, cg)| (ch.kp * cg.kp + ch.kd * cg.kd) / g)
        .sum()
}

/// `dL/dd` of an actuation delay shared by the channels on `dofs`: the sum
/// of their [`super::ChannelGrad::delay`].
pub fn delay_gradient(controller: &Controller, dofs: &[usize], grads: &Gradients) -> f64 {
    controller
        .channels
        .iter()
        .zip(&grads.channels)
        .filter(|(ch, _)| dofs.contains(&ch.dof))
        .map(|(_, cg)| cg.delay)
        .sum()
}
