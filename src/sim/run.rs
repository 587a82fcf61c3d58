//! Running a scene for a number of steps, recording the trajectory or
//! handing each state to an observer (streamed outputs).

use super::trajectory::Trajectory;
use super::{Simulator, StepError};
use crate::counters::StepDiagnostics;
use std::ops::ControlFlow;

/// Runs `steps` steps, recording `θ` at every step (including `t = 0`).
/// `on_step` is called after each step (progress bars).
pub fn run(
    sim: &mut Simulator,
    steps: usize,
    on_step: impl FnMut(usize),
) -> Result<Trajectory, StepError> {
    run_recording(sim, steps, false, on_step)
}

/// As [`run`], also recording every link pose when `poses` is set.
pub fn run_recording(
    sim: &mut Simulator,
    steps: usize,
    poses: bool,
    mut on_step: impl FnMut(usize),
) -> Result<Trajectory, StepError> {
    let mut traj = Trajectory::new(&sim.model);
    run_observed(sim, steps, |k, sim, d| {
        traj.times.push(sim.state.time);
        traj.states.push(sim.state.reported_q(&sim.model));
        if poses {
            traj.poses.push(sim.state.poses.clone());
        }
        if let Some(d) = d {
            traj.diagnostics.push(*d);
            on_step(k);
        }
        ControlFlow::Continue(())
    })?;
    Ok(traj)
}

/// Runs up to `steps` steps, handing every state to `observe(k, sim, d)`:
/// first the initial one (`k = 0`, `d = None`), then the state after step
/// `k` with its diagnostics. Nothing is kept here, so memory does not grow
/// with `steps`. The observer stops the run early with
/// `ControlFlow::Break` (an interrupt, a full disk); the number of
/// completed steps is returned. A failing step returns its error, after
/// the observer has seen every state before it.
pub fn run_observed(
    sim: &mut Simulator,
    steps: usize,
    mut observe: impl FnMut(usize, &Simulator, Option<&StepDiagnostics>) -> ControlFlow<()>,
) -> Result<usize, StepError> {
    if observe(0, sim, None).is_break() {
        return Ok(0);
    }
    for k in 0..steps {
        let d = sim.step()?;
        if observe(k + 1, sim, Some(&d)).is_break() {
            return Ok(k + 1);
        }
    }
    Ok(steps)
}
