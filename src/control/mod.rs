//! Controllers: target signals `θ*(t)` with their time derivatives `θ̇*(t)`,
//! turned into stable-PD targets each step (`u^t = (θ*^{t+1}, θ̇*^{t+1})`).

pub mod pose_target;
pub mod signal;

pub use pose_target::PoseTarget;
pub use signal::{Signal, SignalError};

use crate::energy::PdTarget;

/// One controlled coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct ControlChannel {
    /// Coordinate index in `θ`.
    pub dof: usize,
    pub kp: f64,
    pub kd: f64,
    pub signal: Signal,
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
    /// PD targets at time `t` (s), written into `out` (cleared first).
    pub fn targets_at(&self, t: f64, out: &mut Vec<PdTarget>) {
        out.clear();
        out.extend(self.channels.iter().map(|c| {
            let (q, qdot) = c.signal.eval(t);
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
