//! The forward pass with everything the backward pass needs.

use crate::sim::run::run_observed;
use crate::sim::{SimState, Simulator, StepDiagnostics, StepError};
use nalgebra::{DVector, Matrix3};
use std::ops::ControlFlow;

/// One step: the state it started from and the solution `θ^{t}` in the
/// charts of `before` (the chart it was solved in).
#[derive(Clone, Debug)]
pub struct StepRecord {
    pub before: SimState,
    pub q_new: DVector<f64>,
}

/// A recorded trajectory.
#[derive(Clone, Debug)]
pub struct Tape {
    pub steps: Vec<StepRecord>,
    pub dt: f64,
}

impl Tape {
    /// Number of steps `H`.
    pub fn len(&self) -> usize {
        self.steps.len()
    }

    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }

    /// Coordinates and charts of `θ^k`, `k = −1 … H`.
    pub fn coords(&self, k: isize) -> (&DVector<f64>, &[Matrix3<f64>]) {
        match k {
            -1 => (&self.steps[0].before.q_prev, &self.steps[0].before.charts),
            0 => (&self.steps[0].before.q, &self.steps[0].before.charts),
            k => {
                let r = &self.steps[k as usize - 1];
                (&r.q_new, &r.before.charts)
            }
        }
    }
}

/// Runs `steps` steps from the simulator's current state, recording them.
/// The run loop is [`crate::sim::run::run_observed`] (the one every
/// recorder and stream uses); this observer keeps, per step, the state it
/// started from and its solution.
pub fn record(sim: &mut Simulator, steps: usize) -> Result<Tape, StepError> {
    record_observed(sim, steps, |_, _, _| {})
}

/// As [`record`], also calling `also` as [`run_observed`]'s observer would be
/// (after the tape has taken the step): one run serves both, and the
/// trajectory is the one a plain run gives.
pub fn record_observed(
    sim: &mut Simulator,
    steps: usize,
    mut also: impl FnMut(usize, &Simulator, Option<&StepDiagnostics>),
) -> Result<Tape, StepError> {
    let mut tape = Tape {
        steps: Vec::with_capacity(steps),
        dt: sim.settings.dt,
    };
    let mut before = sim.state.clone();
    run_observed(sim, steps, |k, sim, d| {
        if k > 0 {
            // The solution in the chart it was solved in: `sim.state.q` may
            // have been re-centred after acceptance; poses are
            // chart-independent, so recover the pre-re-centring coordinates
            // from `before`'s charts.
            let q_new = solution_in_chart(sim, &before);
            let before = std::mem::replace(&mut before, sim.state.clone());
            tape.steps.push(StepRecord { before, q_new });
        }
        also(k, sim, d);
        ControlFlow::Continue(())
    })?;
    Ok(tape)
}

fn solution_in_chart(sim: &Simulator, before: &SimState) -> DVector<f64> {
    let mut q = sim.state.q.clone();
    for link in &sim.model.links {
        let Some(c) = link.chart else { continue };
        if sim.state.charts[c] == before.charts[c] {
            continue;
        }
        // R = R_c' exp(φ') = R_c exp(φ)  ⇒  φ = log(R_cᵀ R_c' exp(φ')).
        let o = link.dof_offset + link.joint.chart_offset();
        let phi_new = nalgebra::Vector3::new(q[o], q[o + 1], q[o + 2]);
        let r = sim.state.charts[c] * crate::math::so3::exp(&phi_new);
        let phi = crate::math::so3::log(&(before.charts[c].transpose() * r));
        q.rows_mut(o, 3).copy_from(&phi);
    }
    q
}
