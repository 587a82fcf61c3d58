//! Newton's method for the per-step objective (paper, `Forward Simulation`):
//! the `|θ|×|θ|` Hessian's eigenvalues are clamped to at least `eig_clamp`
//! (block by block, Cholesky where clamping changes nothing: see
//! [`super::linear_solve`]), and a backtracking line search accepts only finite, decreasing
//! objective values (an infeasible, interpenetrating trial point has `+∞`
//! energy and is rejected). Stops when `‖∇O‖∞ < tol`. When the objective's
//! round-off hides the remaining decrease, the gradient norm decides (see
//! [`minimize`]). Round-off is judged from the terms' magnitudes
//! ([`Objective::value_noise`]), not from the value, which is tiny near rest.
//! A solve that cannot reach `tol` because `tol` is below the gradient's own
//! round-off floor (`64 ε ‖H‖∞ (‖θ‖∞ + L)`) accepts its point and says so
//! ([`NewtonReport::at_floor`], counted in the run summary) instead of
//! failing.
//!
//! A second stall is a gradient that is itself noise: when the objective's
//! terms are large and cancel (e.g. barrier forces between nearly touching
//! links of one robot, `O ≈ 1e7` J), `∇O` carries round-off well above the
//! Hessian-based estimate, and successive iterates `1e-10` apart report
//! `‖∇O‖∞` jumping between `2e-4` and `2e-3`. When neither the value nor
//! the gradient can rank a trial point and the full Newton step is below
//! [`NewtonOptions::step_floor`] (a length, measured as
//! `‖Δθ‖∞ · max(1, L)`), the point is the solution to working precision and
//! is accepted the same way ([`NewtonReport::at_step_floor`]).
//!
//! Continuous collision detection: a segment `q → q + αΔ` the search accepts
//! is certified by [`Objective::certify`] before it is taken (every point
//! of it collision-free, not only its end); if only `[0, α']` can be, the
//! search runs again from `α'` ([`NewtonReport::ccd_cuts`]). Starting from
//! `θ^t`, the accepted segments chain into a certified path `θ^t → θ^{t+1}`.
//! The simulator asks for this only when a step's straight path could not be
//! certified after an ordinary solve (see [`crate::sim::Simulator::step`]).

use super::envelope::{self, ColumnEnvelope};
use super::line_model::LineModel;
use super::linear_solve::{BlockSolver, Mode};
use crate::contact::PlaneLine;
pub use crate::counters::NewtonReport;
use crate::counters::{Stage, StageTimers};
use crate::energy::{EnergyError, Need};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Newton settings. Every field has a documented default.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct NewtonOptions {
    /// Stop when `‖∇O‖∞` is below this (J per unit coordinate). Default `1e-4`
    /// (the paper's value).
    pub tol: f64,
    /// Iteration limit; reaching it is an error naming the step. Default 100.
    pub max_iters: usize,
    /// Lower bound for the Hessian eigenvalues. Default `1e-3` (paper).
    pub eig_clamp: f64,
    /// Step halvings before the line search gives up. Default 60.
    pub max_backtracks: usize,
    /// A stalled solve (no trial point ranked by value or gradient) whose
    /// full Newton step is shorter than this (m; rotations count times the
    /// scene's length scale, at least 1 m) is accepted as converged to
    /// working precision. Default `1e-9` m.
    pub step_floor: f64,
    /// Negative eigenvalues become `max(|λ|, eig_clamp)` ("absolute-value
    /// projection") instead of `eig_clamp`. Default `false` (the paper's
    /// clamp; SDRS runs unchanged). The IPC baseline sets it
    /// ([`crate::scene::Scene::simulator_with`]): its barrier forces are
    /// large, and the second-order kinematic part of the joint-space Hessian
    /// (`⟨Q_b, S_k S_l⟩`, force × curvature of the link motion) is then
    /// indefinite with eigenvalues of −1…−400 on the four chains; clamping
    /// them to `1e-3` gives Newton steps `|g|/1e-3` long (10²–10⁴ rad) that
    /// CCD must cut to 1e-2…1e-9, and the solve stalls. With `|λ|` the step
    /// along such a direction has the length its curvature implies. Not a
    /// scene key (set by the contact model).
    #[serde(skip)]
    #[schemars(skip)]
    pub eig_abs: bool,
    /// Starting point of each step's Newton solve. Default `adaptive`
    /// (the cubic extrapolation `4θ^t − 6θ^{t−1} + 4θ^{t−2} − θ^{t−3}` or the
    /// quadratic `3(θ^t − θ^{t−1}) + θ^{t−2}`, whichever predicted the last
    /// step better; falling back to `θ^t` where the objective is not finite
    /// or larger): fewer iterations, same solution to within `tol` (see
    /// [`Predictor`]).
    pub predictor: Predictor,
    /// Newton model on Hessian blocks with an eigenvalue `≤ eig_clamp`
    /// (elsewhere the model is the Hessian itself). Default `shift`
    /// (Cholesky only; measured on the four chains: same step solutions to
    /// within the stopping test's bound, fewer iterations than `clamp`, see
    /// `notes/performance.md`). Ignored when [`NewtonOptions::eig_abs`] is set.
    pub indefinite: Indefinite,
    /// Independent Hessian blocks (robots or chains not in contact) whose
    /// gradient already meets the stopping test (`‖g_B‖∞ < tol`) get a zero
    /// step instead of a factorization (see
    /// [`super::linear_solve::BlockSolver::direction`]): a step where one
    /// pair of chains in contact needs ten iterations no longer re-factors
    /// every other chain ten times. Same solution to within `tol`.
    /// Default `true`.
    pub settle_blocks: bool,
    /// Evaluate an accepted point's gradient before its Hessian when the
    /// point is likely the solution (see [`Solve::eval_accepted`]). With
    /// `derivatives_at_trial` off the iterates and the result are the same
    /// bits either way; only the work differs. With it on (the default) a
    /// miss is the point's second evaluation, whose contact plane solves
    /// start from the first's results, so the bits can differ by round-off
    /// (the solution stays within `tol`). Default `true`. Not a scene key
    /// (an implementation choice; the tests compare both).
    #[serde(skip)]
    #[schemars(skip)]
    pub gradient_first: bool,
    /// Evaluate the first trial point of each line search with the
    /// derivatives the point will need if it is accepted (see
    /// [`Solve::first_trial_need`]) instead of its value alone: a full
    /// Newton step is usually accepted at once, and it is then not
    /// evaluated a second time. Same solution to within `tol` (the
    /// contact planes of the one evaluation start from the previous
    /// point's, so the iterates differ at round-off). Default `true`. Not a
    /// scene key (an implementation choice; the tests compare both).
    #[serde(skip)]
    #[schemars(skip)]
    pub derivatives_at_trial: bool,
    /// The first trial of each line search with a contact pair in range is
    /// the minimizer of a one-dimensional model of the objective along the
    /// Newton direction ([`super::line_model`]: the contact barriers'
    /// own nonlinearity on top of Newton's quadratic model) instead of the
    /// full step, on `(0, LINE_MODEL_CAP]`; if it fails the sufficient
    /// decrease test the search goes on as without it (from the full step
    /// when the model's step was longer). Lines without a pair in range
    /// are unchanged. Same solution to within `tol`. Default `true`.
    pub line_model: bool,
}

/// Positive-definite Newton model of an indefinite (or nearly singular)
/// Hessian block (see [`super::linear_solve`]). Only the path to the
/// solution depends on it: every variant stops at `‖∇O‖∞ < tol`.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Indefinite {
    /// Eigenvalues clamped to at least `eig_clamp` (paper): an
    /// eigendecomposition of the block.
    Clamp,
    /// `H + τI`, the smallest `τ = τ₀ 4^k` that has a Cholesky
    /// factorization (modified Newton; Cholesky only).
    #[default]
    Shift,
}

/// Initial guess of a step's Newton solve. The solution is the same to
/// within the Newton tolerance whichever is used (Newton stops at the first
/// iterate with `‖∇O‖∞ < tol`; a different start reaches a different such
/// iterate), so trajectories differ by at most the solver's own error.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Predictor {
    /// `θ^{t+1}_0 = θ^t` (the paper's choice).
    Previous,
    /// `θ^{t+1}_0 = 2θ^t − θ^{t−1}` (constant generalized velocity: the
    /// explicit, first-order prediction; exact for uniform motion). When the
    /// objective is not finite there (the predicted hulls would
    /// interpenetrate, or a joint would pass its limit), larger than at
    /// `θ^t` (after an impact), or the jump `θ^t → 2θ^t − θ^{t−1}` is not
    /// allowed by the terms' line-search bounds ([`Objective::max_step`]:
    /// IPC's CCD filter — a guess past an obstacle is finite too — and the
    /// joint-limit and chart bounds), the solve starts at the
    /// collision-free `θ^t` instead. With continuous collision detection
    /// the predictor needs no check of its own: the straight path
    /// `θ^t → θ^{t+1}` is certified after the solve (see
    /// [`crate::sim::Simulator::step`]).
    Extrapolate,
    /// `θ^{t+1}_0 = 3(θ^t − θ^{t−1}) + θ^{t−2}` (constant generalized
    /// acceleration: second order, exact for uniformly accelerated
    /// motion), with the same fallback to `θ^t`; `2θ^t − θ^{t−1}` when
    /// `θ^{t−2}` is not known (the first step from an initial state,
    /// [`crate::sim::SimState::q_prev2`]). On the four chains it takes
    /// about a quarter fewer Newton iterations per step than `extrapolate`
    /// (figures: `docs/performance.md`, seventh session).
    Quadratic,
    /// `θ^{t+1}_0 = 4θ^t − 6θ^{t−1} + 4θ^{t−2} − θ^{t−3}` (constant
    /// generalized jerk: the cubic through the last four states, one step
    /// on; third order, exact for motion with a constant third time
    /// derivative), with the same fallback to `θ^t`; the quadratic guess
    /// while `θ^{t−3}` is not known ([`crate::sim::SimState::q_prev3`]).
    /// Its coefficients amplify round-off in the states by
    /// `√(4² + 6² + 4² + 1) ≈ 8.3` (quadratic: `√19 ≈ 4.4`), far below the
    /// Newton tolerance's own spread of the states.
    Cubic,
    /// The cubic or the quadratic guess, whichever was closer (max norm) to
    /// the previous step's solution ([`crate::sim::SimState::cubic_closer`]):
    /// smooth motion gets the cubic, impacts and stick–slip (where the third
    /// difference is noise) the quadratic. The default: on the four chains
    /// it takes 15–32 % fewer Newton iterations than `quadratic` at 8–32
    /// links per chain, and no bundled scene more than 5 % more
    /// (`notes/performance.md`, 2026-11-30, sixth session).
    #[default]
    Adaptive,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            tol: 1e-4,
            max_iters: 100,
            eig_clamp: 1e-3,
            max_backtracks: 60,
            step_floor: 1e-9,
            eig_abs: false,
            predictor: Predictor::default(),
            indefinite: Indefinite::Shift,
            settle_blocks: true,
            gradient_first: true,
            derivatives_at_trial: true,
            line_model: true,
        }
    }
}

/// Why a Newton solve failed.
#[derive(Debug, Clone, thiserror::Error)]
pub enum NewtonError {
    #[error(
        "no convergence after {iters} Newton iterations (‖∇O‖∞ = {grad_inf:.3e}, tolerance {tol:.1e})"
    )]
    NotConverged {
        iters: usize,
        grad_inf: f64,
        tol: f64,
    },
    #[error(
        "line search found no decrease at Newton iteration {iter} (‖∇O‖∞ = {grad_inf:.3e}, tolerance {tol:.1e})"
    )]
    LineSearch {
        iter: usize,
        grad_inf: f64,
        tol: f64,
    },
    #[error("the objective is not finite at the starting point (value {value}): {detail}")]
    InfeasibleStart {
        value: f64,
        /// What makes it infeasible (filled by the simulator from the
        /// terms' [`crate::energy::Energy::explain_infeasible`]).
        detail: String,
    },
    #[error("non-finite gradient or Hessian at Newton iteration {iter}")]
    NonFinite { iter: usize },
    #[error(transparent)]
    Energy(#[from] EnergyError),
}

/// An objective with value, gradient and Hessian.
pub trait Objective {
    /// Evaluates at `q`; writes the gradient/Hessian when `need` asks.
    fn eval(
        &mut self,
        q: &DVector<f64>,
        need: Need,
        grad: &mut DVector<f64>,
        hess: &mut DMatrix<f64>,
        timers: &mut StageTimers,
    ) -> Result<f64, EnergyError>;

    /// Absolute round-off of the value at the point last evaluated (J): two
    /// values closer than this cannot be ranked. It comes from the terms'
    /// magnitudes, not from the value, which is small near rest while its
    /// parts are not (gravity's `ρ g·X` carries `ε|X|` of noise whatever
    /// it is measured from). Default: none beyond the relative test.
    fn value_noise(&self) -> f64 {
        0.0
    }

    /// Largest world coordinate involved (m), plus one: sets the gradient's
    /// round-off floor. Default 1.
    fn length_scale(&self) -> f64 {
        1.0
    }

    /// Largest step fraction `α ≤ 1` along `dir` from `q` that the
    /// parametrization supports and that keeps the objective finite by
    /// construction (rotation charts are good only well inside `‖φ‖ < 2π`;
    /// joint limits, see [`crate::energy::Energy::max_step`]). `q` is the
    /// point of the last evaluation with derivatives. The line search starts
    /// there. Default `1.0`.
    fn max_step(
        &mut self,
        _q: &DVector<f64>,
        _dir: &DVector<f64>,
        _timers: &mut StageTimers,
    ) -> Result<f64, EnergyError> {
        Ok(1.0)
    }

    /// Continuous collision detection of an accepted line-search segment
    /// `q → q + α dir`: the largest `α' ≤ α` such that the whole segment
    /// `[q, q + α' dir]` is certified collision-free (see
    /// [`crate::energy::Energy::certify_step`]). When `α' < α` the search
    /// runs again from `α'`. Called after the search, so only the step
    /// actually taken is checked (a long Newton direction that the search
    /// shortens anyway costs nothing). Default: `α`.
    fn certify(
        &mut self,
        _q: &DVector<f64>,
        _dir: &DVector<f64>,
        alpha: f64,
        _timers: &mut StageTimers,
    ) -> Result<f64, EnergyError> {
        Ok(alpha)
    }

    /// The barrier pairs along the line `q + α dir` for Newton's line model
    /// ([`super::line_model`]), into `out`; `false` when the objective cannot give them
    /// (no model: the search keeps its full step). `q` is the point of the last evaluation
    /// with derivatives. Default: `false`.
    fn line_pairs(
        &mut self,
        _q: &DVector<f64>,
        _dir: &DVector<f64>,
        _out: &mut Vec<PlaneLine>,
    ) -> Result<bool, EnergyError> {
        Ok(false)
    }

    /// Rows of each column of the Hessian of the last evaluation that may
    /// be non-zero (every other entry is exactly zero), when the objective
    /// knows them; the solver's dense passes over `H` then skip the rest.
    /// Default: unknown (every entry is read).
    fn hessian_envelope(&self) -> Option<&ColumnEnvelope> {
        None
    }
}

/// Longest step of the line model's search, in full Newton steps
/// ([`NewtonOptions::line_model`]). The exact line search that sized the idea
/// searched the same range (`notes/performance.md`, twenty-second session).
pub const LINE_MODEL_CAP: f64 = 4.0;

/// Scratch buffers of the solver.
#[derive(Clone, Debug, Default)]
pub struct NewtonScratch {
    grad: DVector<f64>,
    hess: DMatrix<f64>,
    dir: DVector<f64>,
    trial: DVector<f64>,
    trial_grad: DVector<f64>,
    /// Row sums of `|H|` ([`envelope::finite_max_row_sum`]).
    row_sums: Vec<f64>,
    /// Block-wise Cholesky / clamped-eigen solver and its work space.
    pub(crate) linear: BlockSolver,
    /// Iterations of the last solve that met the stopping test (the
    /// gradient-first prediction, see [`Solve::eval_accepted`]).
    last_iters: Option<usize>,
    /// Whether `hess` is the Hessian at the current point (false after a
    /// gradient-first evaluation that met the stopping test, and after a
    /// trial point was evaluated with its Hessian).
    hess_current: bool,
    /// What the last trial point was evaluated with, and its value (see
    /// [`NewtonOptions::derivatives_at_trial`]).
    trial_need: Option<Need>,
    trial_value: f64,
    /// The barrier pairs of the line model ([`NewtonOptions::line_model`]).
    lines: Vec<PlaneLine>,
    /// Whether `dir` solves `H dir = −g` with the Hessian itself (no block
    /// shifted or eigen-clamped): then `dirᵀ H dir = −gᵀ dir`.
    dir_solves_hessian: bool,
}

/// Minimizes `obj` starting from `q` (updated in place).
pub fn minimize(
    obj: &mut dyn Objective,
    q: &mut DVector<f64>,
    opts: &NewtonOptions,
    scratch: &mut NewtonScratch,
    timers: &mut StageTimers,
) -> Result<NewtonReport, NewtonError> {
    minimize_from(obj, q, None, opts, scratch, timers)
}

/// [`minimize`], starting from `guess` when the objective is finite (and
/// evaluates without error) there and not larger than at `q`, else from `q`
/// (which must be feasible).
///
/// Each iteration reads top to bottom as its phases: convergence test
/// ([`Solve::converged`]), direction and line search ([`Solve::search`]:
/// linear solve, Armijo backtracking, gradient-merit fallback, CCD
/// certification of the accepted segment), then the outcome ([`Solve::finish_failed`]
/// when nothing was accepted) and the new point's derivatives.
pub fn minimize_from(
    obj: &mut dyn Objective,
    q: &mut DVector<f64>,
    guess: Option<&DVector<f64>>,
    opts: &NewtonOptions,
    scratch: &mut NewtonScratch,
    timers: &mut StageTimers,
) -> Result<NewtonReport, NewtonError> {
    scratch.resize(q.len());
    let mut run = Solve {
        obj,
        opts,
        scratch,
        timers,
        report: NewtonReport::default(),
        next_iter: 0,
    };
    let mut value = run.start(q, guess)?;
    for iter in 0..=opts.max_iters {
        let grad_inf = run.scratch.grad.amax();
        if let Some(done) = run.converged(q, iter, value, grad_inf)? {
            run.scratch.last_iters = Some(iter);
            return Ok(done);
        }
        if iter == opts.max_iters {
            break;
        }
        run.next_iter = iter + 1;
        let (accepted, resolvable) = run.search(q, value, grad_inf)?;
        if !accepted {
            return run.finish_failed(iter, grad_inf, resolvable);
        }
        std::mem::swap(q, &mut run.scratch.trial);
        value = run.eval_accepted(q, iter + 1)?;
    }
    let mut report = run.report;
    if report.grad_inf <= report.grad_floor {
        report.at_floor = true;
        return Ok(report);
    }
    Err(NewtonError::NotConverged {
        iters: opts.max_iters,
        grad_inf: report.grad_inf,
        tol: opts.tol,
    })
}

impl NewtonScratch {
    /// Sizes the buffers for `n` coordinates (kept when already `n`).
    fn resize(&mut self, n: usize) {
        if self.grad.len() != n {
            self.grad = DVector::zeros(n);
            self.hess = DMatrix::zeros(n, n);
            self.dir = DVector::zeros(n);
            self.trial_grad = DVector::zeros(n);
        }
    }
}

/// One run of [`minimize_from`]: the objective, the options, the buffers and
/// the report being filled.
struct Solve<'a> {
    obj: &'a mut dyn Objective,
    opts: &'a NewtonOptions,
    scratch: &'a mut NewtonScratch,
    timers: &'a mut StageTimers,
    report: NewtonReport,
    /// The index the point accepted by the current line search will have.
    next_iter: usize,
}

/// What the line search of one iteration knows about the current point.
struct SearchPoint {
    /// `O(q)`.
    value: f64,
    /// `‖∇O(q)‖∞`.
    grad_inf: f64,
    /// Predicted decrease of the quadratic model, `−gᵀΔ`.
    predicted: f64,
    /// Round-off floor of the value (below it trial points cannot be ranked).
    floor: f64,
    /// Whether the predicted decrease is above that floor.
    resolvable: bool,
}

impl Solve<'_> {
    /// `O(q)` with gradient and Hessian into the scratch buffers.
    fn eval(&mut self, q: &DVector<f64>, need: Need) -> Result<f64, NewtonError> {
        let s = &mut *self.scratch;
        s.hess_current = need >= Need::Hessian;
        Ok(self
            .obj
            .eval(q, need, &mut s.grad, &mut s.hess, self.timers)?)
    }

    /// The derivatives at the point just accepted, the `iters`-th.
    ///
    /// Gradient first: the Hessian at the solution is never read (the
    /// solve stops on `‖∇O‖∞ < tol`, which needs only the gradient), so
    /// when this point is likely the solution — the last solve met the
    /// stopping test after at most `iters` iterations (a trajectory's
    /// steps are alike) — the gradient is evaluated alone, and the Hessian
    /// only if the test fails (the gradient is then evaluated again with
    /// it: a miss costs one gradient evaluation). The gradient's bits do
    /// not depend on `need`. With `derivatives_at_trial` off the accepted
    /// point was already evaluated by value in the line search, so every
    /// evaluation here is its second or later, which the contact term
    /// repeats bit for bit (`ContactEnergy::start_planes`): the iterates
    /// are the same bits whichever way the point is evaluated; only the
    /// work differs. With it on, a miss is the point's second evaluation
    /// after a first with the gradient, and can differ from a single
    /// evaluation by the plane solves' round-off
    /// ([`NewtonReport::gradient_first`], [`NewtonReport::gradient_first_misses`]).
    /// A Hessian that would be non-finite at the solution is then not
    /// checked here (the next step's first evaluation checks its own).
    fn eval_accepted(&mut self, q: &DVector<f64>, iters: usize) -> Result<f64, NewtonError> {
        if self.opts.derivatives_at_trial {
            let s = &mut *self.scratch;
            match s.trial_need.take() {
                Some(Need::Hessian) => {
                    std::mem::swap(&mut s.grad, &mut s.trial_grad);
                    s.hess_current = true;
                    return Ok(s.trial_value);
                }
                Some(Need::Gradient) => {
                    std::mem::swap(&mut s.grad, &mut s.trial_grad);
                    s.hess_current = false;
                    let (value, grad_inf) = (s.trial_value, s.grad.amax());
                    let likely = self.likely_solution(iters);
                    self.report.gradient_first += usize::from(likely);
                    if value.is_finite() && grad_inf < self.opts.tol {
                        return Ok(value);
                    }
                    self.report.gradient_first_misses += usize::from(likely);
                    return self.eval(q, Need::Hessian);
                }
                _ => {}
            }
        }
        if self.likely_solution(iters) {
            self.report.gradient_first += 1;
            let value = self.eval(q, Need::Gradient)?;
            let grad_inf = self.scratch.grad.amax();
            if value.is_finite() && grad_inf < self.opts.tol {
                return Ok(value);
            }
            self.report.gradient_first_misses += 1;
        }
        self.eval(q, Need::Hessian)
    }

    /// Whether the `iters`-th point is likely the solution: the last solve
    /// met the stopping test after at most `iters` iterations (with
    /// [`NewtonOptions::gradient_first`]).
    fn likely_solution(&self, iters: usize) -> bool {
        self.opts.gradient_first && self.scratch.last_iters.is_some_and(|n| iters >= n)
    }

    /// What the first trial point of a line search is evaluated with
    /// ([`NewtonOptions::derivatives_at_trial`]): the derivatives
    /// [`Solve::eval_accepted`] would ask for if it is accepted (its
    /// gradient alone when it is likely the solution, else gradient and
    /// Hessian). A rejected trial costs the derivatives' share of one
    /// evaluation (and, with a Hessian, the current point's Hessian, which
    /// only the `shift` fallback reads again: see [`Solve::search`]).
    fn first_trial_need(&self) -> Need {
        if !self.opts.derivatives_at_trial {
            Need::Value
        } else if self.likely_solution(self.next_iter) {
            Need::Gradient
        } else {
            Need::Hessian
        }
    }

    /// Phase 0: the start point. The guess replaces `q` when its objective
    /// is finite and not larger than at `q` (one extra value evaluation;
    /// after an impact the extrapolated point lies deep in the barrier or
    /// past it and `q` is the better start). The guess is evaluated with
    /// derivatives right away: it usually wins.
    fn start(
        &mut self,
        q: &mut DVector<f64>,
        guess: Option<&DVector<f64>>,
    ) -> Result<f64, NewtonError> {
        let mut value = f64::NAN;
        if let Some(g) = guess {
            let at_q = self.eval(q, Need::Value)?;
            // The jump q → guess must pass the terms' own line-search bounds
            // (IPC's CCD filter, joint-limit approach, chart step): a guess on
            // the far side of an obstacle has a finite objective too.
            self.scratch.dir.copy_from(g);
            self.scratch.dir.axpy(-1.0, q, 1.0);
            let reachable = self.obj.max_step(q, &self.scratch.dir, self.timers)? >= 1.0;
            let at_g = if reachable {
                let s = &mut *self.scratch;
                s.hess_current = true;
                self.obj
                    .eval(g, Need::Hessian, &mut s.grad, &mut s.hess, self.timers)
            } else {
                Ok(f64::INFINITY)
            };
            if let Ok(v) = at_g
                && v.is_finite()
                && (v <= at_q || at_q.is_nan())
            {
                q.copy_from(g);
                value = v;
            }
        }
        if value.is_nan() {
            value = self.eval(q, Need::Hessian)?;
        }
        if !value.is_finite() {
            return Err(NewtonError::InfeasibleStart {
                value,
                detail: "hulls intersect in the current state".into(),
            });
        }
        Ok(value)
    }

    /// Phase 1 of an iteration: records the point in the report; the
    /// finished report when `‖∇O‖∞ < tol`; an error on non-finite
    /// derivatives. Also sets the gradient's round-off floor
    /// `64 ε ‖H‖∞ (‖q‖∞ + ℓ)` (`ℓ`: the objective's length scale).
    fn converged(
        &mut self,
        q: &DVector<f64>,
        iter: usize,
        value: f64,
        grad_inf: f64,
    ) -> Result<Option<NewtonReport>, NewtonError> {
        self.report.iters = iter;
        self.report.grad_inf = grad_inf;
        self.report.value = value;
        let s = &mut *self.scratch;
        let env = self
            .obj
            .hessian_envelope()
            .filter(|e| e.len() == s.hess.nrows());
        // ‖H‖∞ and the finiteness check in one pass over the Hessian (when
        // it is the current point's: see `eval_accepted`).
        let norm = if s.hess_current {
            match envelope::finite_max_row_sum(&s.hess, env, &mut s.row_sums) {
                Some(v) => v,
                None => return Err(NewtonError::NonFinite { iter }),
            }
        } else {
            f64::NAN
        };
        if !grad_inf.is_finite() {
            return Err(NewtonError::NonFinite { iter });
        }
        if grad_inf < self.opts.tol {
            return Ok(Some(self.report));
        }
        // Not reached without a current Hessian (a gradient-first point is
        // kept only when it meets the test); NaN would leave no floor.
        self.report.grad_floor = 64.0 * f64::EPSILON * norm * (q.amax() + self.obj.length_scale());
        Ok(None)
    }

    /// Phase 2: the Newton direction and the line search along it. With
    /// `Indefinite::Shift`, an iteration whose line search fails is repeated
    /// once with the paper's clamped eigen step. Returns (accepted,
    /// resolvable); the accepted point is in `scratch.trial`.
    fn search(
        &mut self,
        q: &DVector<f64>,
        value: f64,
        grad_inf: f64,
    ) -> Result<(bool, bool), NewtonError> {
        let opts = self.opts;
        let mut mode = match (opts.eig_abs, opts.indefinite) {
            (true, _) => Mode::Clamped { abs: true },
            (false, Indefinite::Clamp) => Mode::Clamped { abs: false },
            (false, Indefinite::Shift) => Mode::Shift,
        };
        loop {
            let s = &mut *self.scratch;
            if let Some(e) = self
                .obj
                .hessian_envelope()
                .filter(|e| e.len() == s.hess.nrows())
            {
                s.linear.bound_rows(e.row_ends());
            }
            let modified = |st: &crate::sim::linear_solve::LinearSolveStats| {
                (st.shifted_blocks, st.eigen_blocks)
            };
            let before = modified(&s.linear.stats);
            self.timers.time(Stage::LinearSolve, || {
                s.linear.direction(
                    &s.hess,
                    &s.grad,
                    opts.eig_clamp,
                    mode,
                    if opts.settle_blocks { opts.tol } else { 0.0 },
                    &mut s.dir,
                )
            });
            s.dir_solves_hessian = modified(&s.linear.stats) == before;
            // Predicted decrease of the quadratic model, −gᵀΔ > 0.
            let predicted = -s.grad.dot(&s.dir);
            // Below ~1e-9 of the objective's magnitude, or near its absolute
            // round-off floor (from the terms' magnitudes), the value cannot
            // rank trial points: the decrease is smaller than the noise.
            let floor = 1e-9 * value.abs() + self.obj.value_noise();
            let at = SearchPoint {
                value,
                grad_inf,
                predicted,
                floor,
                resolvable: predicted > 10.0 * floor,
            };
            let accepted = self.line_search(q, &at)?;
            if accepted || mode != Mode::Shift {
                return Ok((accepted, at.resolvable));
            }
            mode = Mode::Clamped { abs: false };
            self.report.shift_fallbacks += 1;
            if !self.scratch.hess_current {
                // A rejected trial point's Hessian replaced the current one.
                self.eval(q, Need::Hessian)?;
            }
        }
    }

    /// The line search along `scratch.dir`, bounded by the chart and
    /// joint-limit step bound. It runs from `start`; once an accepted segment
    /// has been cut by collision detection it runs again from the cut, where
    /// every shorter step is certified too (a sub-segment). Time spent in
    /// the objective evaluations and in continuous collision detection is
    /// counted by their own stages; `line_search` gets only the remainder.
    fn line_search(&mut self, q: &DVector<f64>, at: &SearchPoint) -> Result<bool, NewtonError> {
        let alpha_max = self
            .obj
            .max_step(q, &self.scratch.dir, self.timers)?
            .clamp(0.0, 1.0);
        // Clock readings only with detailed timers (`StageTimers::set_detailed`).
        let t0 = self.timers.start_laps();
        let mut in_evals = std::time::Duration::ZERO;
        let mut model_alpha = self.model_step(q, at, alpha_max)?;
        let mut start = alpha_max;
        let mut cut = false;
        let accepted = loop {
            let (mut accepted, mut alpha) = (false, start);
            if at.resolvable {
                // The line model's step, then (when it was longer) the full step.
                let (first, fallback) = match model_alpha.take() {
                    Some(a) => (a, (a > start).then_some(start)),
                    None => (start, None),
                };
                (accepted, alpha) = self.armijo(q, at, first, fallback, &mut in_evals)?;
            }
            if !accepted {
                (accepted, alpha) = self.gradient_merit(q, at, start, &mut in_evals)?;
            }
            if !accepted || cut {
                break accepted;
            }
            // Continuous collision detection of the accepted segment
            // `q → q + α Δ` (see `Objective::certify`).
            let tc = self.timers.start_laps();
            let certified = self.obj.certify(q, &self.scratch.dir, alpha, self.timers)?;
            in_evals += tc.map_or(std::time::Duration::ZERO, |t| t.elapsed());
            if certified >= alpha {
                break true;
            }
            self.report.ccd_cuts += 1;
            cut = true;
            start = certified.max(0.0);
        };
        if let Some(t0) = t0 {
            self.timers
                .add(Stage::LineSearch, t0.elapsed().saturating_sub(in_evals));
        }
        Ok(accepted)
    }

    /// The trial point `q + α Δ` into `scratch.trial`, evaluated with `need`
    /// (gradient into `scratch.trial_grad`); its value.
    fn trial(
        &mut self,
        q: &DVector<f64>,
        alpha: f64,
        need: Need,
        in_evals: &mut std::time::Duration,
    ) -> Result<f64, NewtonError> {
        let s = &mut *self.scratch;
        s.trial.clone_from(q);
        s.trial.axpy(alpha, &s.dir, 1.0);
        let te = self.timers.start_laps();
        if need >= Need::Hessian {
            s.hess_current = false;
        }
        let v = self
            .obj
            .eval(&s.trial, need, &mut s.trial_grad, &mut s.hess, self.timers)?;
        s.trial_need = Some(need);
        s.trial_value = v;
        *in_evals += te.map_or(std::time::Duration::ZERO, |t| t.elapsed());
        Ok(v)
    }

    /// Backtracking from `start` with Armijo sufficient decrease on a finite
    /// value, `O(q + αΔ) < O(q) − 10⁻⁴ α (−gᵀΔ)`, halving `α`; it stops
    /// when `α (−gᵀΔ)` falls to the value's noise (shorter steps cannot be
    /// ranked by value either; an Armijo test passed on round-off would
    /// accept a step that changes nothing). Returns (accepted, α).
    fn armijo(
        &mut self,
        q: &DVector<f64>,
        at: &SearchPoint,
        start: f64,
        mut fallback: Option<f64>,
        in_evals: &mut std::time::Duration,
    ) -> Result<(bool, f64), NewtonError> {
        let mut alpha = start;
        let mut need = self.first_trial_need();
        for _ in 0..=self.opts.max_backtracks {
            if alpha * at.predicted <= 10.0 * at.floor {
                break;
            }
            let v = self.trial(q, alpha, need, in_evals)?;
            need = Need::Value;
            if v.is_finite() && v < at.value - 1e-4 * alpha * at.predicted {
                return Ok((true, alpha));
            }
            alpha = fallback.take().unwrap_or(0.5 * alpha);
            self.report.backtracks += 1;
        }
        Ok((false, alpha))
    }

    /// The line model's step length ([`NewtonOptions::line_model`]) for the
    /// search along `scratch.dir` from `q`, whose full step is bounded by
    /// `alpha_max ≤ 1`: the minimizer of [`LineModel`] on
    /// `(0, LINE_MODEL_CAP · b]` (`b` the terms' bound for the longer step)
    /// when the full step is allowed, on `(0, alpha_max]` otherwise. `None`
    /// when off, without a pair in range, or without the current Hessian.
    fn model_step(
        &mut self,
        q: &DVector<f64>,
        at: &SearchPoint,
        alpha_max: f64,
    ) -> Result<Option<f64>, NewtonError> {
        let s = &mut *self.scratch;
        if !self.opts.line_model || !s.hess_current || alpha_max <= 0.0 {
            return Ok(None);
        }
        s.lines.clear();
        if !self.obj.line_pairs(q, &s.dir, &mut s.lines)? || s.lines.is_empty() {
            return Ok(None);
        }
        let hi = if alpha_max >= 1.0 {
            let longer = &s.dir * LINE_MODEL_CAP;
            LINE_MODEL_CAP * self.obj.max_step(q, &longer, self.timers)?.clamp(0.0, 1.0)
        } else {
            alpha_max
        };
        if !(hi > 0.0) {
            return Ok(None);
        }
        s.lines.iter_mut().for_each(|l| l.keep_reachable(hi));
        // φ''(0) = ΔᵀHΔ: −gᵀΔ when Δ solves H Δ = −g block by block (settled
        // blocks have Δ_B = 0 and add nothing to either side), else summed.
        let curvature = if s.dir_solves_hessian {
            at.predicted
        } else {
            s.linear.block_quadratic_form(&s.hess, &s.dir)
        };
        Ok(LineModel::new(-at.predicted, curvature, &s.lines).map(|m| m.minimizer(hi)))
    }

    /// When the value cannot rank points (or Armijo failed), the gradient
    /// norm is the merit function: accept a finite trial point whose value
    /// is not larger beyond noise (`10⁻¹⁰ max(|O|, 1)`) and whose `‖∇O‖∞`
    /// is smaller; at most 8 halvings from `start`. Returns (accepted, α).
    fn gradient_merit(
        &mut self,
        q: &DVector<f64>,
        at: &SearchPoint,
        start: f64,
        in_evals: &mut std::time::Duration,
    ) -> Result<(bool, f64), NewtonError> {
        let noise = 1e-10 * at.value.abs().max(1.0);
        let mut alpha = start;
        for _ in 0..8 {
            let v = self.trial(q, alpha, Need::Gradient, in_evals)?;
            if v.is_finite()
                && v <= at.value + noise
                && self.scratch.trial_grad.amax() < at.grad_inf
            {
                self.report.gradient_merit_steps += 1;
                return Ok((true, alpha));
            }
            alpha *= 0.5;
            self.report.backtracks += 1;
        }
        Ok((false, alpha))
    }

    /// Phase 3 when no trial point was accepted: the solution to working
    /// precision when the gradient is within its own round-off, or when
    /// neither value nor gradient can rank points and Newton's own
    /// correction is below the length floor; otherwise a line-search error.
    fn finish_failed(
        mut self,
        iter: usize,
        grad_inf: f64,
        resolvable: bool,
    ) -> Result<NewtonReport, NewtonError> {
        if grad_inf <= self.report.grad_floor {
            self.report.at_floor = true;
            return Ok(self.report);
        }
        let step_len = self.scratch.dir.amax() * self.obj.length_scale().max(1.0);
        if !resolvable && step_len <= self.opts.step_floor {
            self.report.at_floor = true;
            self.report.at_step_floor = true;
            return Ok(self.report);
        }
        Err(NewtonError::LineSearch {
            iter,
            grad_inf,
            tol: self.opts.tol,
        })
    }
}
