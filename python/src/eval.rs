//! Forward (record) and backward (adjoint) passes shared by `Scene` and
//! `Task`: the same calls `sdrs optimize` makes ([`sdrs::diff::record`],
//! [`sdrs::diff::backward`]), on a scene with the parameters written in.

use sdrs::diff::{Gradients, Loss, Tape, backward, record};
use sdrs::scene::Scene;
use sdrs::sim::Simulator;

/// A recorded rollout: the simulator after the run and its tape.
pub struct Recorded {
    pub sim: Simulator,
    pub tape: Tape,
}

/// Simulates `steps` steps of `scene` with the SDRS contact model, keeping
/// the tape for a backward pass.
pub fn forward(scene: &Scene, steps: usize) -> Result<Recorded, String> {
    if let Some(c) = scene.contact.as_ref().filter(|c| !c.model.is_sdrs()) {
        return Err(format!(
            "{}: contact.model: {} has no adjoint (gradients need the sdrs model)",
            scene.source.display(),
            c.model.name()
        ));
    }
    let mut sim = scene.simulator();
    let tape = record(&mut sim, steps)
        .map_err(|e| format!("{}: simulating: {e}", scene.source.display()))?;
    Ok(Recorded { sim, tape })
}

/// The adjoint pass of `loss` over a recorded rollout; an error when a
/// term could not be differentiated (as `sdrs optimize`).
pub fn backward_of(rec: &mut Recorded, loss: &Loss) -> Result<Gradients, String> {
    let g = backward(&mut rec.sim, &rec.tape, loss).map_err(|e| e.to_string())?;
    if !g.unavailable.is_empty() {
        return Err(format!(
            "the gradient needs derivatives that are not available yet: {}",
            g.unavailable.join(", ")
        ));
    }
    Ok(g)
}

/// `θ^H` of a tape (the solved coordinates at the last step, in the chart
/// they were solved in; for joints without rotation charts, the reported
/// coordinates).
pub fn final_state(rec: &Recorded) -> Vec<f64> {
    let (q, _) = rec.tape.coords(rec.tape.len() as isize);
    q.iter().copied().collect()
}
