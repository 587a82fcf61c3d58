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

use super::linear_solve::{BlockSolver, Mode};
pub use crate::counters::NewtonReport;
use crate::counters::StageTimers;
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
    /// Starting point of each step's Newton solve. Default `extrapolate`
    /// (`2θ^t − θ^{t−1}`, falling back to `θ^t` where the objective is not
    /// finite): fewer iterations, same solution to within `tol` (see
    /// [`Predictor`]).
    pub predictor: Predictor,
    /// Newton model on Hessian blocks with an eigenvalue `≤ eig_clamp`
    /// (elsewhere the model is the Hessian itself). Default `shift`
    /// (Cholesky only; measured on the four chains: same step solutions to
    /// within the stopping test's bound, fewer iterations than `clamp`, see
    /// `notes/perf.md`). Ignored when [`NewtonOptions::eig_abs`] is set.
    pub indefinite: Indefinite,
    /// Independent Hessian blocks (robots or chains not in contact) whose
    /// gradient already meets the stopping test (`‖g_B‖∞ < tol`) get a zero
    /// step instead of a factorization (see
    /// [`super::linear_solve::BlockSolver::direction`]): a step where one
    /// pair of chains in contact needs ten iterations no longer re-factors
    /// every other chain ten times. Same solution to within `tol`.
    /// Default `true`.
    pub settle_blocks: bool,
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
    #[default]
    Extrapolate,
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
            predictor: Predictor::Extrapolate,
            indefinite: Indefinite::Shift,
            settle_blocks: true,
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
}

/// Scratch buffers of the solver.
#[derive(Clone, Debug, Default)]
pub struct NewtonScratch {
    grad: DVector<f64>,
    hess: DMatrix<f64>,
    dir: DVector<f64>,
    trial: DVector<f64>,
    trial_grad: DVector<f64>,
    /// Row sums of `|H|` ([`max_row_sum`]).
    row_sums: Vec<f64>,
    /// Block-wise Cholesky / clamped-eigen solver and its work space.
    pub(crate) linear: BlockSolver,
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
pub fn minimize_from(
    obj: &mut dyn Objective,
    q: &mut DVector<f64>,
    guess: Option<&DVector<f64>>,
    opts: &NewtonOptions,
    scratch: &mut NewtonScratch,
    timers: &mut StageTimers,
) -> Result<NewtonReport, NewtonError> {
    let n = q.len();
    if scratch.grad.len() != n {
        scratch.grad = DVector::zeros(n);
        scratch.hess = DMatrix::zeros(n, n);
        scratch.dir = DVector::zeros(n);
        scratch.trial_grad = DVector::zeros(n);
    }
    let mut report = NewtonReport::default();
    // The guess replaces `q` when its objective is finite and not larger
    // than at `q` (one extra value evaluation; after an impact the extrapolated
    // point lies deep in the barrier or past it and `q` is the better start).
    // (The guess is evaluated with derivatives right away: it usually wins.)
    let mut value = f64::NAN;
    if let Some(g) = guess {
        let at_q = obj.eval(q, Need::Value, &mut scratch.grad, &mut scratch.hess, timers)?;
        // The jump q → guess must pass the terms' own line-search bounds
        // (IPC's CCD filter, joint-limit approach, chart step): a guess on
        // the far side of an obstacle has a finite objective too.
        scratch.dir.copy_from(g);
        scratch.dir.axpy(-1.0, q, 1.0);
        let reachable = obj.max_step(q, &scratch.dir, timers)? >= 1.0;
        let at_g = if reachable {
            obj.eval(
                g,
                Need::Hessian,
                &mut scratch.grad,
                &mut scratch.hess,
                timers,
            )
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
        value = obj.eval(
            q,
            Need::Hessian,
            &mut scratch.grad,
            &mut scratch.hess,
            timers,
        )?;
    }
    if !value.is_finite() {
        return Err(NewtonError::InfeasibleStart {
            value,
            detail: "hulls intersect in the current state".into(),
        });
    }
    for iter in 0..=opts.max_iters {
        let grad_inf = scratch.grad.amax();
        report.iters = iter;
        report.grad_inf = grad_inf;
        report.value = value;
        if !grad_inf.is_finite() || scratch.hess.as_slice().iter().any(|v| !v.is_finite()) {
            return Err(NewtonError::NonFinite { iter });
        }
        if grad_inf < opts.tol {
            return Ok(report);
        }
        report.grad_floor = 64.0
            * f64::EPSILON
            * max_row_sum(&scratch.hess, &mut scratch.row_sums)
            * (q.amax() + obj.length_scale());
        if iter == opts.max_iters {
            break;
        }
        let mut mode = match (opts.eig_abs, opts.indefinite) {
            (true, _) => Mode::Clamped { abs: true },
            (false, Indefinite::Clamp) => Mode::Clamped { abs: false },
            (false, Indefinite::Shift) => Mode::Shift,
        };
        // With `Indefinite::Shift`, an iteration whose line search fails is
        // repeated once with the paper's clamped eigen step.
        let (accepted, resolvable) = loop {
            timers.time("linear_solve", || {
                scratch.linear.direction(
                    &scratch.hess,
                    &scratch.grad,
                    opts.eig_clamp,
                    mode,
                    if opts.settle_blocks { opts.tol } else { 0.0 },
                    &mut scratch.dir,
                )
            });
            // Predicted decrease of the quadratic model, −gᵀΔ > 0.
            let predicted = -scratch.grad.dot(&scratch.dir);
            // Below ~1e-9 of the objective's magnitude, or near its absolute
            // round-off floor (from the terms' magnitudes), the value cannot
            // rank trial points: the decrease is smaller than the noise.
            let floor = 1e-9 * value.abs() + obj.value_noise();
            let resolvable = predicted > 10.0 * floor;
            // Chart and joint-limit bound on the step.
            let alpha_max = obj.max_step(q, &scratch.dir, timers)?.clamp(0.0, 1.0);
            let t0 = std::time::Instant::now();
            // Time spent in the search's objective evaluations and in continuous
            // collision detection is counted by their own stages;
            // `line_search` gets only the remainder.
            let mut in_evals = std::time::Duration::ZERO;
            // The search runs from `start`; once an accepted segment has been
            // cut by collision detection it runs again from the cut, where every
            // shorter step is certified too (a sub-segment).
            let mut start = alpha_max;
            let mut cut = false;
            let accepted = loop {
                let mut accepted = false;
                let mut alpha = start;
                if resolvable {
                    // Backtracking with Armijo sufficient decrease on a finite value.
                    for _ in 0..=opts.max_backtracks {
                        if alpha * predicted <= 10.0 * floor {
                            // Shorter steps cannot be ranked by value either; an
                            // Armijo test passed on round-off would accept a step
                            // that changes nothing.
                            break;
                        }
                        scratch.trial.clone_from(q);
                        scratch.trial.axpy(alpha, &scratch.dir, 1.0);
                        let te = std::time::Instant::now();
                        let v = obj.eval(
                            &scratch.trial,
                            Need::Value,
                            &mut scratch.trial_grad,
                            &mut scratch.hess,
                            timers,
                        )?;
                        in_evals += te.elapsed();
                        if v.is_finite() && v < value - 1e-4 * alpha * predicted {
                            accepted = true;
                            break;
                        }
                        alpha *= 0.5;
                        report.backtracks += 1;
                    }
                }
                // Otherwise (or if that failed) the gradient norm is the merit
                // function: accept a finite trial point whose value is not larger
                // beyond noise and whose ‖∇O‖∞ is smaller.
                if !accepted {
                    let noise = 1e-10 * value.abs().max(1.0);
                    alpha = start;
                    for _ in 0..8 {
                        scratch.trial.clone_from(q);
                        scratch.trial.axpy(alpha, &scratch.dir, 1.0);
                        let te = std::time::Instant::now();
                        let v = obj.eval(
                            &scratch.trial,
                            Need::Gradient,
                            &mut scratch.trial_grad,
                            &mut scratch.hess,
                            timers,
                        )?;
                        in_evals += te.elapsed();
                        if v.is_finite()
                            && v <= value + noise
                            && scratch.trial_grad.amax() < grad_inf
                        {
                            accepted = true;
                            report.gradient_merit_steps += 1;
                            break;
                        }
                        alpha *= 0.5;
                        report.backtracks += 1;
                    }
                }
                if !accepted || cut {
                    break accepted;
                }
                // Continuous collision detection of the accepted segment
                // `q → q + α Δ` (see `Objective::certify`).
                let tc = std::time::Instant::now();
                let certified = obj.certify(q, &scratch.dir, alpha, timers)?;
                in_evals += tc.elapsed();
                if certified >= alpha {
                    break true;
                }
                report.ccd_cuts += 1;
                cut = true;
                start = certified.max(0.0);
            };
            timers.add("line_search", t0.elapsed().saturating_sub(in_evals));
            if accepted || mode != Mode::Shift {
                break (accepted, resolvable);
            }
            mode = Mode::Clamped { abs: false };
            report.shift_fallbacks += 1;
        };
        if !accepted && grad_inf <= report.grad_floor {
            // No trial point can be ranked and the gradient is within its
            // own round-off: this is the solution to working precision.
            report.at_floor = true;
            return Ok(report);
        }
        let step_len = scratch.dir.amax() * obj.length_scale().max(1.0);
        if !accepted && !resolvable && step_len <= opts.step_floor {
            // Neither value nor gradient can rank points, and Newton's own
            // correction is below the length floor.
            report.at_floor = true;
            report.at_step_floor = true;
            return Ok(report);
        }
        if !accepted {
            return Err(NewtonError::LineSearch {
                iter,
                grad_inf,
                tol: opts.tol,
            });
        }
        std::mem::swap(q, &mut scratch.trial);
        value = obj.eval(
            q,
            Need::Hessian,
            &mut scratch.grad,
            &mut scratch.hess,
            timers,
        )?;
    }
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

/// `‖H‖∞ = max_i Σ_j |h_ij|`, the largest absolute row sum. Accumulated
/// column by column (contiguous in the column-major `h`; a row-wise walk
/// strides by `n` and was 10 % of a step at `n = 256`): each row's sum still
/// adds its entries in the order `j = 0, 1, …` from the same start, so the
/// result is bitwise the row-wise one. `sums` is scratch.
fn max_row_sum(h: &DMatrix<f64>, sums: &mut Vec<f64>) -> f64 {
    let n = h.nrows();
    sums.clear();
    // `Sum for f64` folds from −0.0; the same start keeps every bit.
    sums.resize(n, -0.0);
    if n == 0 {
        return 0.0;
    }
    for col in h.as_slice().chunks_exact(n) {
        for (s, v) in sums.iter_mut().zip(col) {
            *s += v.abs();
        }
    }
    sums.iter().copied().fold(0.0, f64::max)
}
