//! Newton's method for the per-step objective (paper, `Forward Simulation`):
//! the `|θ|×|θ|` Hessian is eigen-decomposed (block by block: independent
//! bodies give independent blocks), eigenvalues are clamped to at least
//! `eig_clamp`, and a backtracking line search accepts only finite, decreasing
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

use super::counters::StageTimers;
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

/// Statistics of one solve.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct NewtonReport {
    pub iters: usize,
    pub grad_inf: f64,
    pub backtracks: usize,
    /// Iterations accepted by the gradient-norm merit (value below round-off).
    pub gradient_merit_steps: usize,
    pub value: f64,
    /// The solve stalled above `tol` but within the gradient's round-off
    /// floor (`grad_floor`), and its point was accepted (see [`minimize`]).
    pub at_floor: bool,
    /// Of those, accepted because the Newton step itself was below
    /// [`NewtonOptions::step_floor`] (the gradient was noise above
    /// `grad_floor`).
    pub at_step_floor: bool,
    /// Accepted line-search steps that continuous collision detection cut
    /// short (the search then ran again from the cut).
    pub ccd_cuts: usize,
    /// The gradient's round-off floor at the last iterate,
    /// `64 ε ‖H‖∞ (‖θ‖∞ + L)` (J per unit coordinate; `L` the scene's length
    /// scale from [`Objective::length_scale`]).
    pub grad_floor: f64,
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
    comp: Vec<usize>,
}

/// Minimizes `obj` starting from `q` (updated in place).
pub fn minimize(
    obj: &mut dyn Objective,
    q: &mut DVector<f64>,
    opts: &NewtonOptions,
    scratch: &mut NewtonScratch,
    timers: &mut StageTimers,
) -> Result<NewtonReport, NewtonError> {
    let n = q.len();
    scratch.grad = DVector::zeros(n);
    scratch.hess = DMatrix::zeros(n, n);
    scratch.dir = DVector::zeros(n);
    scratch.trial_grad = DVector::zeros(n);
    let mut report = NewtonReport::default();
    let mut value = obj.eval(
        q,
        Need::Hessian,
        &mut scratch.grad,
        &mut scratch.hess,
        timers,
    )?;
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
        if !grad_inf.is_finite() || scratch.hess.iter().any(|v| !v.is_finite()) {
            return Err(NewtonError::NonFinite { iter });
        }
        if grad_inf < opts.tol {
            return Ok(report);
        }
        report.grad_floor =
            64.0 * f64::EPSILON * max_row_sum(&scratch.hess) * (q.amax() + obj.length_scale());
        if iter == opts.max_iters {
            break;
        }
        timers.time("linear_solve", || {
            clamped_newton_direction(
                &scratch.hess,
                &scratch.grad,
                opts.eig_clamp,
                opts.eig_abs,
                &mut scratch.dir,
                &mut scratch.comp,
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
                    if v.is_finite() && v <= value + noise && scratch.trial_grad.amax() < grad_inf {
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

/// `‖H‖∞`, the largest absolute row sum.
fn max_row_sum(h: &DMatrix<f64>) -> f64 {
    h.row_iter()
        .map(|r| r.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// `−Ĥ⁻¹ g` for one symmetric block. If `H − clamp·I` has a Cholesky
/// factorization, every eigenvalue of `H` exceeds `clamp`, clamping changes
/// nothing and `Ĥ = H`: the step is a Cholesky solve (about ten times
/// cheaper than an eigendecomposition). Otherwise eigen-decompose and clamp.
/// With `abs`, eigenvalues become `max(|λ|, clamp)` (see
/// [`NewtonOptions::eig_abs`]); the Cholesky shortcut is exact either way.
fn clamped_block_solve(
    block: DMatrix<f64>,
    g: &DVector<f64>,
    clamp: f64,
    abs: bool,
) -> DVector<f64> {
    let m = block.nrows();
    let shifted = &block - DMatrix::identity(m, m) * clamp;
    if shifted.cholesky().is_some()
        && let Some(ch) = block.clone().cholesky()
    {
        return -ch.solve(g);
    }
    let eig = block.symmetric_eigen();
    let mut coeff = eig.eigenvectors.transpose() * g;
    for (c, &lam) in coeff.iter_mut().zip(eig.eigenvalues.iter()) {
        *c /= if abs { lam.abs() } else { lam }.max(clamp);
    }
    -(eig.eigenvectors * coeff)
}

/// `dir = −Ĥ⁻¹ g`, where `Ĥ` has the eigenvectors of `H` and eigenvalues
/// `max(λ, clamp)` (`max(|λ|, clamp)` with `abs`). `H` is split into the connected components of its
/// sparsity graph and each block is decomposed separately (exact: the
/// eigendecomposition of a block-diagonal matrix is the union of its blocks').
pub fn clamped_newton_direction(
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    clamp: f64,
    abs: bool,
    dir: &mut DVector<f64>,
    comp: &mut Vec<usize>,
) {
    let n = g.len();
    // Union–find over nonzero entries.
    comp.clear();
    comp.extend(0..n);
    fn find(c: &mut [usize], mut i: usize) -> usize {
        while c[i] != i {
            c[i] = c[c[i]];
            i = c[i];
        }
        i
    }
    for j in 0..n {
        for i in 0..j {
            if h[(i, j)] != 0.0 || h[(j, i)] != 0.0 {
                let (a, b) = (find(comp, i), find(comp, j));
                if a != b {
                    comp[a.max(b)] = a.min(b);
                }
            }
        }
    }
    let roots: Vec<usize> = (0..n).map(|i| find(comp, i)).collect();
    dir.fill(0.0);
    let mut done = vec![false; n];
    for start in 0..n {
        if done[start] {
            continue;
        }
        let r = roots[start];
        let idx: Vec<usize> = (start..n).filter(|&i| roots[i] == r).collect();
        for &i in &idx {
            done[i] = true;
        }
        let m = idx.len();
        let block = DMatrix::from_fn(m, m, |a, b| {
            0.5 * (h[(idx[a], idx[b])] + h[(idx[b], idx[a])])
        });
        let gb = DVector::from_fn(m, |a, _| g[idx[a]]);
        let d = clamped_block_solve(block, &gb, clamp, abs);
        for (a, &i) in idx.iter().enumerate() {
            dir[i] = d[a];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    fn eigen_direction(h: &DMatrix<f64>, g: &DVector<f64>, clamp: f64) -> DVector<f64> {
        let eig = h.clone().symmetric_eigen();
        let mut c = eig.eigenvectors.transpose() * g;
        for (x, &l) in c.iter_mut().zip(eig.eigenvalues.iter()) {
            *x /= l.max(clamp);
        }
        -(eig.eigenvectors * c)
    }

    #[test]
    fn cholesky_shortcut_equals_clamped_eigen_step() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for case in 0..40 {
            let n = 2 + case % 9;
            let a = DMatrix::from_fn(n, n, |_, _| rng.random_range(-1.0..1.0));
            // Positive definite, indefinite and nearly singular matrices.
            let shift = [3.0, -0.5, 1e-4][case % 3];
            let h = &a * a.transpose() + DMatrix::identity(n, n) * shift;
            let g = DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
            let clamp = 1e-3;
            let want = eigen_direction(&h, &g, clamp);
            let got = clamped_block_solve(h.clone(), &g, clamp, false);
            assert!((&got - &want).norm() <= 1e-8 * want.norm(), "case {case}");
            // Absolute-value projection: a descent direction whose length
            // along each eigenvector is |g_i| / max(|λ_i|, clamp).
            let eig = h.clone().symmetric_eigen();
            let abs = clamped_block_solve(h.clone(), &g, clamp, true);
            let c = eig.eigenvectors.transpose() * &abs;
            let gc = eig.eigenvectors.transpose() * &g;
            for i in 0..n {
                let want = -gc[i] / eig.eigenvalues[i].abs().max(clamp);
                assert!(
                    (c[i] - want).abs() <= 1e-8 * (1.0 + want.abs()),
                    "case {case}"
                );
            }
            assert!(abs.dot(&g) < 0.0);
        }
    }
}
