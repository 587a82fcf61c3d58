//! The time step. Each step is an ordered list of named, timed stages:
//!
//! 1. `begin_step` — PD targets `u^t` at `t^{t+1}`, lagged per-term data
//!    (friction frames);
//! 2. Newton iterations, each timing `kinematics`, one stage per energy term
//!    (`inertia`, `gravity`, `pd`, …), `assembly`, `linear_solve`, and the
//!    `line_search` as a whole;
//! 3. `accept` — rotate the state, re-centre charts, diagnostics.

pub mod assemble;
pub mod effects;
pub mod envelope;
pub mod line_model;
pub mod linear_solve;
pub mod mass_matrix;
pub mod newton;
mod predictor;
pub mod run;
pub mod small_cholesky;
pub mod state;
pub mod substitution;
pub mod trajectory;

pub use crate::counters::{Stage, StageTime, StageTimers, StepDiagnostics, StepWork};

pub use newton::{Indefinite, NewtonError, NewtonOptions, NewtonReport, Predictor};
pub use state::SimState;

use crate::control::Controller;
use crate::energy::{
    Energy, EnergyAccumulator, EnergyError, Need, PdTarget, StepContext, TermKind,
};
use crate::kinematics::{KinOrder, Kinematics};
use crate::math::Pose;
use crate::model::Model;
use assemble::AssembleScratch;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use newton::{NewtonScratch, Objective};
use predictor::{cubic_was_closer, predict_guess};
use std::time::Instant;

/// Largest change of a rotation-vector coordinate in one Newton iteration
/// (rad); see `StepObjective::max_step`.
pub const MAX_ROTATION_STEP: f64 = 1.0;

/// A step that could not be completed.
#[derive(Debug, Clone, thiserror::Error)]
#[error("step {step} (t = {time:.6} s): {cause}")]
pub struct StepError {
    /// Index of the step being solved (1-based: the step producing `θ^{step}`).
    pub step: usize,
    pub time: f64,
    pub cause: NewtonError,
}

/// Global settings of a simulation.
#[derive(Clone, Debug)]
pub struct SimSettings {
    /// Time step Δt (s).
    pub dt: f64,
    /// Gravity (m/s²).
    pub gravity: Vector3<f64>,
    pub newton: NewtonOptions,
}

/// A simulator: model, energy terms, controller and state.
pub struct Simulator {
    pub model: Model,
    pub settings: SimSettings,
    pub controller: Controller,
    pub energies: Vec<Box<dyn Energy>>,
    pub state: SimState,
    pub timers: StageTimers,
    /// Record each term's work per step ([`StepWork`], from Newton's last
    /// gradient evaluation: a few dot products per term; default on). It
    /// does not change the trajectory.
    pub energy_balance: bool,
    scratch: StepScratch,
}

/// Per-step scratch, apart from persistent state.
struct StepScratch {
    kin: Kinematics,
    /// Kinematics at `θ^t` (poses only), from [`Simulator::begin_next_step`]:
    /// the start of the step's path, reused by continuous collision
    /// detection ([`Energy::certify_step`]).
    kin_start: Kinematics,
    /// The step's straight path `θ^{t+1} − θ^t` (certified after the
    /// optimistic solve, see [`Simulator::step`]).
    path: DVector<f64>,
    acc: EnergyAccumulator,
    assemble: AssembleScratch,
    newton: NewtonScratch,
    targets: Vec<PdTarget>,
    /// The step's initial guess ([`Predictor`]).
    guess: DVector<f64>,
    /// Per-term work of the current step (when `energy_balance` is on).
    work: StepWork,
}

/// The step objective `O(θ^{t+1})` as seen by Newton.
struct StepObjective<'a> {
    ctx: StepContext<'a>,
    charts: &'a [Matrix3<f64>],
    energies: &'a mut [Box<dyn Energy>],
    kin: &'a mut Kinematics,
    /// Kinematics at `θ^t = ctx.q_prev` (see [`StepScratch::kin_start`]).
    kin_start: &'a Kinematics,
    acc: &'a mut EnergyAccumulator,
    assemble: &'a mut AssembleScratch,
    /// Per-term work of the step at the last gradient evaluation, when on.
    work: Option<&'a mut StepWork>,
    /// Whether accepted line-search segments are certified by continuous
    /// collision detection ([`Objective::certify`]); off for the first,
    /// optimistic solve of a step (see [`Simulator::step`]).
    certify_segments: bool,
}

/// `Σ_i ⟨∂E/∂A_i, A_i − A_i^t⟩ + ∂E/∂θ·(θ − θ^t)` of what `acc` holds.
///
/// Summed in four interleaved lanes over each link's twelve entries
/// (column-major) and over the coordinates, the lanes added at the end: a
/// fixed order (the same bits for the same inputs), which the compiler
/// vectorizes. It runs once per term whose work is kept, at every
/// evaluation with a gradient.
fn gradient_dot_step(
    acc: &EnergyAccumulator,
    kin: &Kinematics,
    ctx: &StepContext,
    q: &DVector<f64>,
) -> f64 {
    let mut lanes = [0.0f64; 4];
    for (g, (a, a0)) in acc
        .link_grad
        .iter()
        .zip(kin.pose.iter().zip(ctx.poses_prev))
    {
        add_lanes(&mut lanes, g.as_slice(), a.as_slice(), a0.as_slice());
    }
    add_lanes(
        &mut lanes,
        acc.dof_grad.as_slice(),
        q.as_slice(),
        ctx.q_prev.as_slice(),
    );
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
}

/// `lanes[l] += Σ_k g[4k + l] (a[4k + l] − a0[4k + l])`, the remainder into
/// the first lanes (see [`gradient_dot_step`]).
fn add_lanes(lanes: &mut [f64; 4], g: &[f64], a: &[f64], a0: &[f64]) {
    let (g, a, a0) = (g.chunks(4), a.chunks(4), a0.chunks(4));
    for (g, (a, a0)) in g.zip(a.zip(a0)) {
        for (l, ((g, a), a0)) in g.iter().zip(a).zip(a0).enumerate() {
            lanes[l] += g * (a - a0);
        }
    }
}

impl Objective for StepObjective<'_> {
    fn eval(
        &mut self,
        q: &DVector<f64>,
        need: Need,
        grad: &mut DVector<f64>,
        hess: &mut DMatrix<f64>,
        timers: &mut StageTimers,
    ) -> Result<f64, EnergyError> {
        let order = match need {
            Need::Value => KinOrder::Pose,
            Need::Gradient => KinOrder::First,
            Need::Hessian => KinOrder::Second,
        };
        let model = self.ctx.model;
        // Detailed timers only: one clock reading per stage boundary, each
        // ending one stage and starting the next.
        let mut mark = timers.start_laps();
        self.kin.update_cached(model, q, self.charts, order);
        timers.lap(&mut mark, Stage::Kinematics);
        // Clearing the accumulator is counted with the assembly.
        self.acc.reset(need);
        timers.lap(&mut mark, Stage::Assembly);
        let track = need >= Need::Gradient && self.work.is_some();
        let mut work = StepWork::default();
        // `Σ ⟨∂E/∂A, A − A^t⟩ + …` of the accumulator so far: a term's work
        // is the change across it. It is taken only around terms whose work
        // is kept (not inertia and gravity), and the value after one term is
        // the value before the next (computed once; the same bits as
        // computing it again).
        let mut before: Option<f64> = None;
        for (index, e) in self.energies.iter_mut().enumerate() {
            let kind = e.kind();
            let kept = track && !matches!(kind, TermKind::Inertia | TermKind::Gravity);
            if kept && before.is_none() {
                before = Some(gradient_dot_step(self.acc, self.kin, &self.ctx, q));
            }
            e.accumulate(&self.ctx, q, self.kin, need, self.acc)?;
            if kept {
                let after = gradient_dot_step(self.acc, self.kin, &self.ctx, q);
                let w = before.unwrap_or(0.0) - after;
                before = Some(after);
                match kind {
                    TermKind::Controller => work.controller += w,
                    TermKind::Friction => work.friction += w,
                    TermKind::Contact => work.contact += w,
                    TermKind::Inertia | TermKind::Gravity | TermKind::Other => work.other += w,
                }
            } else {
                before = None;
            }
            timers.lap_term(&mut mark, index, e.name());
            if !self.acc.value.is_finite() {
                return Ok(self.acc.value);
            }
        }
        if let Some(w) = self.work.as_deref_mut().filter(|_| track) {
            *w = work;
        }
        if need >= Need::Gradient {
            assemble::assemble(model, self.kin, self.acc, need, grad, hess, self.assemble);
            timers.lap(&mut mark, Stage::Assembly);
        }
        Ok(self.acc.value)
    }

    fn hessian_envelope(&self) -> Option<&envelope::ColumnEnvelope> {
        Some(self.assemble.envelope())
    }

    /// Gravity's `Σ ρ g·X` dominates the round-off of the step objective
    /// near rest: each link contributes `m_i ‖g‖ ε (‖x_i‖ + 1)` (J), with
    /// `x_i` its position at the last evaluation; a safety factor of 64
    /// covers the summation over vertices and the kinematic chain.
    fn value_noise(&self) -> f64 {
        let g = self.ctx.gravity.norm();
        let sum: f64 = self
            .ctx
            .model
            .first_moment
            .iter()
            .zip(&self.kin.pose)
            .map(|(m1, a)| m1[3].abs() * g * (a.column(3).norm() + 1.0))
            .sum();
        64.0 * f64::EPSILON * sum
    }

    /// The largest step the line search may try: a rotation-vector
    /// coordinate moves at most [`MAX_ROTATION_STEP`] per Newton iteration
    /// (far from its chart centre, ‖φ‖ → 2π, the chart is singular and
    /// Newton, started there by one long step along a flat rotational
    /// direction, crawls: piles of boxes once took > 100 iterations; charts
    /// are re-centred between steps), and no term's continuous collision
    /// detection ([`Energy::max_step`]) may be violated.
    fn max_step(
        &mut self,
        q: &DVector<f64>,
        dir: &DVector<f64>,
        _timers: &mut StageTimers,
    ) -> Result<f64, EnergyError> {
        let mut alpha: f64 = 1.0;
        for link in &self.ctx.model.links {
            if link.chart.is_none() {
                continue;
            }
            let o = link.dof_offset + link.joint.chart_offset();
            let d = Vector3::new(dir[o], dir[o + 1], dir[o + 2]).norm();
            if d > MAX_ROTATION_STEP {
                alpha = alpha.min(MAX_ROTATION_STEP / d);
            }
        }
        for e in self.energies.iter_mut() {
            alpha = alpha.min(e.max_step(&self.ctx, q, dir, self.kin, self.charts)?);
        }
        Ok(alpha)
    }

    /// Every term's continuous collision detection of the accepted segment
    /// ([`Energy::certify_step`]); the smallest certified fraction wins.
    /// A segment starting at `θ^t` (the same bits) gets the step's
    /// kinematics there.
    fn certify(
        &mut self,
        q: &DVector<f64>,
        dir: &DVector<f64>,
        alpha: f64,
        _timers: &mut StageTimers,
    ) -> Result<f64, EnergyError> {
        if !self.certify_segments {
            return Ok(alpha);
        }
        let at_start = q.len() == self.ctx.q_prev.len()
            && q.iter()
                .zip(self.ctx.q_prev.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits());
        let start = at_start.then_some(self.kin_start);
        let mut out = alpha;
        for e in self.energies.iter_mut() {
            out = out.min(e.certify_step(&self.ctx, q, start, dir, alpha, self.charts)?);
        }
        Ok(out)
    }

    /// Every term's barrier pairs along `q + α dir` ([`Energy::line_pairs`]), from the
    /// kinematics at `q` (the last evaluation's, first order: no work when cached) and the
    /// links' world twists along `dir` ([`crate::energy::StepTwists`], computed only when a
    /// term has a pair).
    fn line_pairs(
        &mut self,
        q: &DVector<f64>,
        dir: &DVector<f64>,
        out: &mut Vec<crate::contact::PlaneLine>,
    ) -> Result<bool, EnergyError> {
        let model = self.ctx.model;
        self.kin
            .update_cached(model, q, self.charts, KinOrder::First);
        let mut twists = crate::energy::StepTwists::new(model, self.kin, dir);
        for e in self.energies.iter_mut() {
            if !e.line_pairs(&self.ctx, self.kin, &mut twists, out) {
                return Ok(false);
            }
        }
        Ok(true)
    }

    fn length_scale(&self) -> f64 {
        1.0 + self
            .kin
            .pose
            .iter()
            .map(|a| a.column(3).amax())
            .fold(0.0, f64::max)
    }
}

impl Simulator {
    /// A simulator with the standard terms (inertia, gravity, PD, and the
    /// joint-limit barrier when a joint is limited).
    pub fn new(
        model: Model,
        settings: SimSettings,
        controller: Controller,
        state: SimState,
    ) -> Self {
        let mut energies: Vec<Box<dyn Energy>> = vec![
            Box::new(crate::energy::Inertia),
            Box::new(crate::energy::Gravity),
            Box::new(crate::energy::PdController),
        ];
        if let Some(limits) = crate::energy::JointLimits::from_model(&model) {
            energies.push(Box::new(limits));
        }
        if let Some(ties) = crate::energy::MimicTies::from_model(&model) {
            energies.push(Box::new(ties));
        }
        let scratch = StepScratch {
            kin: Kinematics::new(&model),
            kin_start: Kinematics::new(&model),
            path: DVector::zeros(0),
            acc: EnergyAccumulator::new(&model),
            assemble: AssembleScratch::default(),
            newton: NewtonScratch::default(),
            targets: Vec::new(),
            guess: DVector::zeros(0),
            work: StepWork::default(),
        };
        Simulator {
            model,
            settings,
            controller,
            energies,
            state,
            timers: StageTimers::default(),
            energy_balance: true,
            scratch,
        }
    }

    /// Sets the PD targets of the next step and runs every term's
    /// `begin_step` (lagged data); returns `t^{t+1}`.
    fn begin_next_step(&mut self) -> Result<f64, EnergyError> {
        let t_next = (self.state.step + 1) as f64 * self.settings.dt;
        self.controller
            .targets_at(t_next, &mut self.scratch.targets);
        let StepScratch { kin, kin_start, .. } = &mut self.scratch;
        kin_start.update_or_copy(kin, &self.model, &self.state.q, &self.state.charts);
        let ctx = make_context(
            &self.model,
            &self.settings,
            &self.state,
            &self.scratch.targets,
            &self.controller.pose_targets,
            t_next,
            self.timers.detailed(),
        );
        for e in self.energies.iter_mut() {
            e.begin_step(&ctx, &self.scratch.kin_start)?;
        }
        Ok(t_next)
    }

    /// Evaluates the step objective for the *next* step at `q` (no state
    /// change): value, gradient and Hessian. Used by tests and the adjoint.
    pub fn objective(
        &mut self,
        q: &DVector<f64>,
        need: Need,
    ) -> Result<(f64, DVector<f64>, DMatrix<f64>), EnergyError> {
        let t_next = self.begin_next_step()?;
        let n = self.model.ndof();
        let (mut g, mut h) = (DVector::zeros(n), DMatrix::zeros(n, n));
        let (mut obj, _) = step_objective(self, t_next, false);
        let mut timers = StageTimers::default();
        let v = obj.eval(q, need, &mut g, &mut h, &mut timers)?;
        Ok((v, g, h))
    }

    /// Re-creates the context of the step that follows `state` (targets,
    /// lagged data) and returns the objective's gradient and Hessian at
    /// `q`, with the kinematics and pose-space gradients left in
    /// [`Simulator::kinematics`] / [`Simulator::pose_gradients`]. Used by the
    /// backward pass; `state` becomes the simulator's state.
    pub fn linearize(
        &mut self,
        state: &SimState,
        q: &DVector<f64>,
    ) -> Result<(DVector<f64>, DMatrix<f64>), EnergyError> {
        self.state = state.clone();
        let (v, g, h) = self.objective(q, Need::Hessian)?;
        if !v.is_finite() {
            return Err(EnergyError::Failed {
                term: "objective",
                msg: "not finite at the recorded solution".into(),
            });
        }
        Ok((g, h))
    }

    /// Work of the Newton step's linear solver since the simulator was
    /// made (blocks, eigen-decomposed blocks; see [`linear_solve`]).
    pub fn linear_solve_stats(&self) -> linear_solve::LinearSolveStats {
        self.scratch.newton.linear.stats
    }

    /// Kinematics of the last [`Simulator::linearize`] point.
    pub fn kinematics(&self) -> &Kinematics {
        &self.scratch.kin
    }

    /// `∂O/∂A_i` of the last [`Simulator::linearize`] point.
    pub fn pose_gradients(&self) -> &[crate::math::Pose] {
        &self.scratch.acc.link_grad
    }

    /// Runs every term's adjoint product at the last linearization point.
    pub fn vjp(
        &mut self,
        q: &DVector<f64>,
        dir: &crate::energy::vjp::AdjointDirection,
        out: &mut crate::energy::vjp::VjpAccumulator,
    ) -> Result<(), EnergyError> {
        let t_next = (self.state.step + 1) as f64 * self.settings.dt;
        let ctx = make_context(
            &self.model,
            &self.settings,
            &self.state,
            &self.scratch.targets,
            &self.controller.pose_targets,
            t_next,
            self.timers.detailed(),
        );
        for e in self.energies.iter_mut() {
            e.vjp(&ctx, q, &self.scratch.kin, dir, out)?;
        }
        Ok(())
    }

    /// Advances one step: `θ^{t+1} = argmin O(θ; θ^t, θ^{t−1}, u^t)`.
    pub fn step(&mut self) -> Result<StepDiagnostics, StepError> {
        let t_next = (self.state.step + 1) as f64 * self.settings.dt;
        let step_index = self.state.step + 1;
        let fail = |cause: NewtonError| StepError {
            step: step_index,
            time: t_next,
            cause,
        };
        let t0 = Instant::now();
        self.begin_next_step().map_err(|e| fail(e.into()))?;
        self.timers.add(Stage::BeginStep, t0.elapsed());
        let mut q = self.state.q.clone();
        // Continuous collision detection (`contact::ccd`): first an
        // optimistic solve without it, then one check of the straight
        // joint-space path θ^t → θ^{t+1} — the motion the implicit scheme
        // assumes (constant generalized velocity (θ^{t+1} − θ^t)/Δt over the
        // step). Only when that path cannot be certified (or the optimistic
        // solve fails) is the step solved again from θ^t with every accepted
        // line-search segment certified; those chain into a certified
        // polyline θ^t → θ^{t+1}. Either way a collision-free path joins the
        // two states, and when nothing is fast the trajectory is
        // bit-identical to one without collision detection.
        // The predictor (`Predictor`) starts the ordinary solve; a solve
        // that fails from it is repeated from θ^t (with collision detection
        // on, that is the certified fallback below).
        let predictor = self.settings.newton.predictor;
        let predict = predictor != Predictor::Previous;
        let mut guess = std::mem::take(&mut self.scratch.guess);
        if predict {
            predict_guess(&self.state, predictor, &mut guess);
        }
        let guess_ref = predict.then_some(&guess);
        let ccd = self.energies.iter().any(|e| e.certifies());
        if ccd || predict {
            let (mut obj, parts) = step_objective(self, t_next, false);
            let solved = newton::minimize_from(
                &mut obj,
                &mut q,
                guess_ref,
                &parts.settings.newton,
                parts.newton,
                parts.timers,
            );
            if let Ok(report) = solved {
                let certified = if ccd {
                    let q_prev = obj.ctx.q_prev;
                    let path = &mut *parts.path;
                    path.clone_from(&q);
                    *path -= q_prev;
                    obj.certify_segments = true;
                    obj.certify(q_prev, path, 1.0, parts.timers)
                        .map_err(|e| fail(e.into()))?
                        >= 1.0
                } else {
                    true
                };
                if certified {
                    self.scratch.guess = guess;
                    return Ok(self.accept(q, report, false));
                }
            }
            q.clone_from(&self.state.q);
        }
        self.scratch.guess = guess;
        let (mut obj, parts) = step_objective(self, t_next, ccd);
        let report = newton::minimize(
            &mut obj,
            &mut q,
            &parts.settings.newton,
            parts.newton,
            parts.timers,
        )
        .map_err(|e| match e {
            NewtonError::InfeasibleStart { value, detail } => {
                let why: Vec<String> = parts_explain(&self.energies, &self.model);
                NewtonError::InfeasibleStart {
                    value,
                    detail: if why.is_empty() {
                        detail
                    } else {
                        why.join("; ")
                    },
                }
            }
            e => e,
        })
        .map_err(fail)?;
        Ok(self.accept(q, report, ccd))
    }

    /// Takes `q` as `θ^{t+1}`: diagnostics of the step (`fallback`: it was
    /// solved again with certified line-search segments, see
    /// [`Simulator::step`]), then the state advances.
    fn accept(&mut self, q: DVector<f64>, report: NewtonReport, fallback: bool) -> StepDiagnostics {
        let step_index = self.state.step + 1;
        let t0 = Instant::now();
        self.scratch
            .kin
            .update_cached(&self.model, &q, &self.state.charts, KinOrder::Pose);
        let new_poses = self.scratch.kin.pose.clone();
        let mut diag = self.diagnostics(&new_poses, report);
        diag.min_distance = f64::INFINITY;
        if self.energy_balance {
            diag.work = Some(self.scratch.work);
        }
        for (i, e) in self.energies.iter_mut().enumerate() {
            self.timers.set_reporting(Some(i));
            e.report(&mut diag, &mut self.timers);
        }
        self.timers.set_reporting(None);
        if fallback {
            diag.ccd.fallbacks += 1;
        }
        let cubic_closer = cubic_was_closer(&self.state, &q);
        let st = &mut self.state;
        st.cubic_closer = cubic_closer;
        let older = std::mem::replace(&mut st.q_prev, std::mem::replace(&mut st.q, q));
        st.q_prev3 = st.q_prev2.replace(older);
        st.poses_prev = std::mem::replace(&mut st.poses, new_poses);
        st.step = step_index;
        st.time = step_index as f64 * self.settings.dt;
        st.recenter_charts(&self.model);
        self.timers.add(Stage::Accept, t0.elapsed());
        diag
    }

    fn diagnostics(&self, new_poses: &[Pose], newton: NewtonReport) -> StepDiagnostics {
        let dt = self.settings.dt;
        let mut d = StepDiagnostics {
            newton,
            ..Default::default()
        };
        let mut p = Vector3::zeros();
        for (i, (new, old)) in new_poses.iter().zip(&self.state.poses).enumerate() {
            let v = new - old;
            let m2 = &self.model.second_moment[i];
            let m1 = &self.model.first_moment[i];
            d.kinetic += 0.5 * v.component_mul(&(v * m2)).sum() / (dt * dt);
            d.potential -= self.settings.gravity.dot(&(new * m1));
            p += v * m1 / dt;
        }
        d.momentum = [p.x, p.y, p.z];
        d
    }
}

/// Every term's explanation of an infeasible last evaluation.
fn parts_explain(energies: &[Box<dyn Energy>], model: &Model) -> Vec<String> {
    energies
        .iter()
        .filter_map(|e| e.explain_infeasible(model))
        .collect()
}

fn make_context<'a>(
    model: &'a Model,
    settings: &SimSettings,
    state: &'a SimState,
    targets: &'a [PdTarget],
    pose_targets: &'a [crate::control::PoseTarget],
    time: f64,
    timed: bool,
) -> StepContext<'a> {
    StepContext {
        model,
        dt: settings.dt,
        time,
        gravity: settings.gravity,
        poses_prev: &state.poses,
        poses_prev2: &state.poses_prev,
        q_prev: &state.q,
        q_prev2: &state.q_prev,
        targets,
        pose_targets,
        timed,
    }
}

/// Fields of the simulator the Newton solve needs besides the objective.
struct SolverParts<'a> {
    settings: &'a SimSettings,
    newton: &'a mut NewtonScratch,
    timers: &'a mut StageTimers,
    /// [`StepScratch::path`].
    path: &'a mut DVector<f64>,
}

/// The objective of the step following `sim.state` (after
/// [`Simulator::begin_next_step`]), borrowing the simulator field by field.
fn step_objective(
    sim: &mut Simulator,
    t_next: f64,
    certify_segments: bool,
) -> (StepObjective<'_>, SolverParts<'_>) {
    let Simulator {
        model,
        settings,
        controller,
        energies,
        state,
        timers,
        scratch,
        energy_balance,
        ..
    } = sim;
    let StepScratch {
        kin,
        kin_start,
        path,
        acc,
        assemble,
        newton,
        targets,
        work,
        guess: _,
    } = scratch;
    let ctx = make_context(
        model,
        settings,
        state,
        targets,
        &controller.pose_targets,
        t_next,
        timers.detailed(),
    );
    let obj = StepObjective {
        ctx,
        charts: &state.charts,
        energies,
        kin,
        kin_start,
        acc,
        assemble,
        work: energy_balance.then_some(work),
        certify_segments,
    };
    (
        obj,
        SolverParts {
            settings,
            newton,
            timers,
            path,
        },
    )
}
