//! Running a scene for a number of steps, recording the trajectory.

use super::{Simulator, StepError};
use crate::output::Trajectory;

/// Runs `steps` steps, recording `θ` at every step (including `t = 0`).
/// `on_step` is called after each step (progress bars).
pub fn run(
    sim: &mut Simulator,
    steps: usize,
    mut on_step: impl FnMut(usize),
) -> Result<Trajectory, StepError> {
    let mut traj = Trajectory::new(&sim.model);
    traj.times.push(sim.state.time);
    traj.states.push(sim.state.reported_q(&sim.model));
    for k in 0..steps {
        let d = sim.step()?;
        traj.times.push(sim.state.time);
        traj.states.push(sim.state.reported_q(&sim.model));
        traj.diagnostics.push(d);
        on_step(k + 1);
    }
    Ok(traj)
}
