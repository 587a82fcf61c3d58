//! Controllers: target signals `θ*(t)` with their time derivatives `θ̇*(t)`,
//! turned into stable-PD targets each step (`u^t = (θ*^{t+1}, θ̇*^{t+1})`).

pub mod pose_target;
pub mod signal;

pub use pose_target::PoseTarget;
pub use signal::{Signal, SignalError};

/// Target of one controlled coordinate for the current step: what the
/// controller hands the stable-PD term (`crate::energy::pd`). It lives here,
/// below `energy` and `sim`, so that `control` depends on neither.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PdTarget {
    /// Coordinate index in `θ`.
    pub dof: usize,
    /// Stiffness `k_p` (J/rad² or J/m²).
    pub kp: f64,
    /// Damping `k_d` (J·s²/rad² or J·s²/m²).
    pub kd: f64,
    /// `θ*^{t+1}` (rad or m).
    pub q: f64,
    /// `θ̇*^{t+1}` (rad/s or m/s).
    pub qdot: f64,
}

/// One controlled coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct ControlChannel {
    /// Coordinate index in `θ`.
    pub dof: usize,
    pub kp: f64,
    pub kd: f64,
    pub signal: Signal,
    /// Actuation delay `d` (s, ≥ 0): the channel tracks `θ*(t − d)`,
    /// `θ̇*(t − d)` ([`crate::energy::effects::delay`]). Default 0.
    pub delay: f64,
}

/// Open-loop controller: a set of channels.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Controller {
    pub channels: Vec<ControlChannel>,
    /// Free root joints whose six channels form one pose target (their
    /// channels are driven by [`crate::energy::pd_pose`], not per
    /// coordinate). Default none.
    pub pose_targets: Vec<PoseTarget>,
}

impl Controller {
    /// PD targets at time `t` (s), written into `out` (cleared first); a
    /// channel with a delay `d` reads its signal at `t − d`.
    pub fn targets_at(&self, t: f64, out: &mut Vec<PdTarget>) {
        out.clear();
        out.extend(self.channels.iter().map(|c| {
            let (q, qdot) = c.signal.eval(t - c.delay);
            PdTarget {
                dof: c.dof,
                kp: c.kp,
                kd: c.kd,
                q,
                qdot,
            }
        }));
    }
}
