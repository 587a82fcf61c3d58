//! The least-squares problem of one candidate: simulate the scene with the
//! candidate's effects at parameter values `p`, and compare with the
//! measured samples of a time window.
//!
//! Residuals `r_{i,c} = θ̂_c(t_i; p) + b_c − y_{i,c}` (SI units of each
//! channel: rad or m), over samples `i` of the window and channels `c` with a
//! measured value; `θ̂` is the simulation on the scene's Δt interpolated
//! linearly at `t_i`, `b_c` the candidate's encoder offsets (0 otherwise).

use super::data::{Measured, interpolate};
use crate::diff::{Tape, tape::record_observed};
use crate::energy::effects::{self, Effect, EffectKind, EffectSpec};
use crate::scene::Scene;
use crate::sim::Simulator;
use nalgebra::DVector;

/// One effect of a candidate, with the positions of its values in the
/// candidate's parameter vector.
#[derive(Clone, Debug)]
pub struct Template {
    pub spec: EffectSpec,
}

/// A candidate model change: one or more effects whose values are free.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// `joint_damping/all`, or `a + b` for pairs.
    pub label: String,
    pub templates: Vec<Template>,
    /// Box bounds and a typical magnitude per parameter (SI).
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    pub typical: Vec<f64>,
    /// Starting points of the fit.
    pub starts: Vec<Vec<f64>>,
}

impl Candidate {
    pub fn nparams(&self) -> usize {
        self.lower.len()
    }

    /// The effects with values `p`.
    pub fn specs(&self, p: &[f64]) -> Vec<EffectSpec> {
        let mut k = 0;
        self.templates
            .iter()
            .map(|t| {
                let mut s = t.spec.clone();
                for v in s.values.iter_mut() {
                    *v = p[k];
                    k += 1;
                }
                s
            })
            .collect()
    }

    /// Kinds of the effects (for pairing and reports).
    pub fn kinds(&self) -> Vec<EffectKind> {
        self.templates.iter().map(|t| t.spec.effect).collect()
    }
}

/// A simulated trajectory on the scene's time grid.
#[derive(Clone, Debug)]
pub struct Simulated {
    pub dt: f64,
    /// Reported coordinates at `k·dt`.
    pub states: Vec<DVector<f64>>,
    /// Whether any contact pair was active at `k·dt` (false at `k = 0`).
    pub contact: Vec<bool>,
    /// Encoder offsets per coordinate.
    pub offset: Vec<f64>,
}

impl Simulated {
    /// The measured-side value of coordinate `dof` at time `t`.
    pub fn at(&self, dof: usize, t: f64) -> f64 {
        interpolate(&self.states, self.dt, dof, t) + self.offset[dof]
    }

    /// Velocity and acceleration of `dof` at `t` by central differences of
    /// the interpolated trajectory (step `2Δt`).
    pub fn rates(&self, dof: usize, t: f64) -> (f64, f64) {
        let h = 2.0 * self.dt;
        let t = t.max(h);
        let (a, b, c) = (
            interpolate(&self.states, self.dt, dof, t - h),
            interpolate(&self.states, self.dt, dof, t),
            interpolate(&self.states, self.dt, dof, t + h),
        );
        ((c - a) / (2.0 * h), (c - 2.0 * b + a) / (h * h))
    }

    /// This trajectory as data: `m`'s sample times and channels (and its
    /// gaps), each value `θ̂_c(t_i) + b_c` ([`Simulated::at`]). The
    /// calibration runs its analyses on such data to tell what the model
    /// itself produces from what the measurements add.
    pub fn sampled_like(&self, m: &Measured) -> Measured {
        let mut out = m.clone();
        for ch in &mut out.channels {
            for (v, &t) in ch.values.iter_mut().zip(&m.times) {
                *v = v.map(|_| self.at(ch.dof, t));
            }
        }
        out
    }

    /// Whether contact is active at `t` (nearest recorded step).
    pub fn in_contact(&self, t: f64) -> bool {
        let k = ((t / self.dt).round() as usize).min(self.contact.len() - 1);
        self.contact[k]
    }
}

/// A further recording fitted together with the first one (issue 33,
/// item 4; [`Problem::others`]): its data, its first held-out sample, and
/// its initial coordinates `θ^0` (the scene's, with every measured
/// coordinate set to the recording's first sample,
/// [`super::recordings::initial_coordinates`]; the initial velocities are
/// the scene's).
#[derive(Clone, Debug)]
pub struct Recording {
    pub measured: Measured,
    pub split: usize,
    pub q0: DVector<f64>,
}

/// Everything fixed while fitting: the scene (without the candidate), the
/// data and the training window.
///
/// With several recordings, `measured` is the first (simulated from the
/// scene's own initial state, as a single recording always is) and
/// `others` the further ones (each from its own initial state, the
/// scene's controller). One parameter set is fitted to the training
/// windows of all of them ([`Problem::train_residuals`] concatenates) and
/// scored on the held-out window of each ([`Problem::holdout_residuals`]).
/// The floor sums over all recordings; the residual force regression and
/// the per-regime analysis use the first.
#[derive(Clone, Copy)]
pub struct Problem<'a> {
    pub scene: &'a Scene,
    pub measured: &'a Measured,
    /// First held-out sample.
    pub split: usize,
    /// Further recordings (empty for a single one).
    pub others: &'a [Recording],
}

/// A run's reported coordinates and contact flags with `sc`'s encoder
/// offsets.
fn simulated(sc: &Scene, states: Vec<DVector<f64>>, contact: Vec<bool>) -> Simulated {
    Simulated {
        dt: sc.settings.dt,
        states,
        contact,
        offset: encoder_offsets(sc),
    }
}

/// Per coordinate, the sum of `sc`'s encoder offsets on it (the
/// measured-side shift of [`Simulated::at`]).
pub fn encoder_offsets(sc: &Scene) -> Vec<f64> {
    let mut offset = vec![0.0; sc.model.ndof()];
    for (dofs, b) in effects::offsets(&sc.effects) {
        for &k in dofs {
            offset[k] += b;
        }
    }
    offset
}

impl<'a> Problem<'a> {
    /// Time of the first held-out sample (s; the last sample's when the
    /// split lies past the end): training fits `t < split_time`.
    pub fn split_time(&self) -> f64 {
        let times = &self.measured.times;
        times[self.split.min(times.len() - 1)]
    }

    /// Steps needed to reach sample `end − 1`.
    pub fn steps_to(&self, end: usize) -> usize {
        let t = self.measured.times[end - 1];
        (t / self.scene.settings.dt).ceil() as usize + 1
    }

    /// The scene with extra effects (validated against the model).
    pub fn scene_with(&self, extra: &[EffectSpec]) -> Option<Scene> {
        let mut sc = self.scene.clone();
        let mut specs: Vec<EffectSpec> = sc.spec.effects.clone();
        specs.extend_from_slice(extra);
        let resolved: Vec<Effect> =
            effects::resolve(&specs, &sc.model, sc.contact.is_some(), "effects").ok()?;
        sc.effects = resolved;
        sc.spec.effects = specs;
        Some(sc)
    }

    /// Simulates the scene with `extra` effects up to sample `end − 1`;
    /// `None` when a step fails (the parameters are then rejected).
    pub fn simulate(&self, extra: &[EffectSpec], end: usize) -> Option<Simulated> {
        let sc = self.scene_with(extra)?;
        self.simulate_scene(&sc, self.steps_to(end))
    }

    /// Simulates `sc` (this problem's scene, possibly changed) for `steps`
    /// steps; `None` when a step fails.
    pub fn simulate_scene(&self, sc: &Scene, steps: usize) -> Option<Simulated> {
        let mut sim = quiet_simulator(sc);
        let traj = crate::sim::run::run(&mut sim, steps, |_| {}).ok()?;
        let mut contact = vec![false];
        contact.extend(traj.diagnostics.iter().map(|d| d.contact_pairs > 0));
        Some(simulated(sc, traj.states, contact))
    }

    /// As [`Problem::simulate_scene`], also recording the run for the
    /// backward pass: the simulator after the run and its tape (the same
    /// trajectory, from the same single run).
    pub fn simulate_scene_recorded(
        &self,
        sc: &Scene,
        steps: usize,
    ) -> Option<(Simulated, Simulator, Tape)> {
        let mut sim = quiet_simulator(sc);
        let (mut states, mut contact) = (Vec::with_capacity(steps + 1), vec![false]);
        let tape = record_observed(&mut sim, steps, |_, sim, d| {
            states.push(sim.state.reported_q(&sim.model));
            if let Some(d) = d {
                contact.push(d.contact_pairs > 0);
            }
        })
        .ok()?;
        Some((simulated(sc, states, contact), sim, tape))
    }

    /// Residuals over samples `range` (appended to `out`).
    pub fn residuals(&self, sim: &Simulated, range: std::ops::Range<usize>, out: &mut Vec<f64>) {
        for i in range {
            let t = self.measured.times[i];
            for ch in &self.measured.channels {
                if let Some(y) = ch.values[i] {
                    out.push(sim.at(ch.dof, t) - y);
                }
            }
        }
    }

    /// Training residuals of the candidate at `p`, of the first recording
    /// then of each of [`Problem::others`] (`None`: a simulation failed).
    pub fn train_residuals(&self, cand: &Candidate, p: &[f64]) -> Option<Vec<f64>> {
        let mut r = self.own_train_residuals(cand, p)?;
        for o in self.others {
            r.extend(self.with_other(o, |q| q.own_train_residuals(cand, p))?);
        }
        Some(r)
    }

    /// Training residuals of the first recording alone.
    fn own_train_residuals(&self, cand: &Candidate, p: &[f64]) -> Option<Vec<f64>> {
        let sim = self.simulate(&cand.specs(p), self.split)?;
        let mut r = Vec::new();
        self.residuals(&sim, 0..self.split, &mut r);
        r.iter().all(|x| x.is_finite()).then_some(r)
    }

    /// This problem's first recording alone (no [`Problem::others`]).
    pub fn first(&self) -> Problem<'a> {
        Problem {
            others: &[],
            ..*self
        }
    }

    /// `f` applied to the problem of recording `o` alone: this problem's
    /// scene (with whatever Δt and effects it has) started from `o`'s
    /// initial coordinates.
    pub fn with_other<R>(&self, o: &Recording, f: impl FnOnce(&Problem) -> R) -> R {
        let mut sc = self.scene.clone();
        sc.q0 = o.q0.clone();
        f(&Problem {
            scene: &sc,
            measured: &o.measured,
            split: o.split,
            others: &[],
        })
    }

    /// Held-out residuals of every recording with `extra` effects: the first
    /// recording's from `first` (its simulation over the whole data), the
    /// others' simulated here. `None` when a simulation fails.
    pub fn holdout_residuals(&self, extra: &[EffectSpec], first: &Simulated) -> Option<Vec<f64>> {
        let mut r = Vec::new();
        self.residuals(first, self.split..self.measured.times.len(), &mut r);
        for o in self.others {
            self.with_other(o, |q| {
                let end = q.measured.times.len();
                let sim = q.simulate(extra, end)?;
                q.residuals(&sim, q.split..end, &mut r);
                Some(())
            })?;
        }
        Some(r)
    }
}

/// `sc`'s simulator without its energy balance (each term's work per step,
/// [`Simulator::energy_balance`]): no calibration output reads it, and it
/// does not change the trajectory (`tests/energy_balance.rs`).
fn quiet_simulator(sc: &Scene) -> Simulator {
    let mut sim = sc.simulator();
    sim.energy_balance = false;
    sim
}
