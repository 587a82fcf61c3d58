//! Actuation delay: the motor applies the PD law on a target that lags by
//! `d` seconds (a bus or filter latency between command and torque).
//!
//! The stable-PD term (paper `pbad.tex`, [`crate::energy::pd`]) of every
//! channel on the affected coordinates tracks `θ*(t − d)`, `θ̇*(t − d)`
//! instead of `θ*(t)`, `θ̇*(t)` (`d` in s, ≥ 0; 0 = nominal; the signal is
//! read at negative times for `t < d`, as defined by its formula). No new
//! energy term: the controller channel carries the delay
//! ([`crate::control::ControlChannel::delay`]) and the adjoint pass
//! accumulates its gradient per channel
//! ([`crate::diff::ChannelGrad::delay`]):
//!
//! ```text
//! ∂θ*/∂d = −θ̇*(t − d),   ∂θ̇*/∂d = −θ̈*(t − d)
//! dL/dd = Σ_t (∂Φ_t/∂θ* θ̇*(t − d) + ∂Φ_t/∂θ̇* θ̈*(t − d))
//! ```
//!
//! summed over the channels of the effect ([`crate::diff::effects::gradient`]).

use crate::control::Controller;

/// Adds the delay `d` (s) to every channel acting on one of `dofs` (delays
/// of several effects on one channel add up: `on: all` and `on: elbow`).
pub fn apply(controller: &mut Controller, dofs: &[usize], d: f64) {
    for ch in controller.channels.iter_mut() {
        if dofs.contains(&ch.dof) {
            ch.delay += d;
        }
    }
}
