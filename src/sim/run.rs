//! Running a scene for a number of steps, recording the trajectory.

use super::{Simulator, StepError};
use crate::output::Trajectory;

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
    let record = |traj: &mut Trajectory, sim: &Simulator| {
        traj.times.push(sim.state.time);
        traj.states.push(sim.state.reported_q(&sim.model));
        if poses {
            traj.poses.push(sim.state.poses.clone());
        }
    };
    record(&mut traj, sim);
    for k in 0..steps {
        let d = sim.step()?;
        record(&mut traj, sim);
        traj.diagnostics.push(d);
        on_step(k + 1);
    }
    Ok(traj)
}
