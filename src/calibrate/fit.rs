//! Bounded Levenberg–Marquardt fit of a candidate's parameters.
//!
//! Minimizes `½‖r(p)‖²` over the training window within box bounds:
//! `(JᵀJ + λ diag(JᵀJ)) δ = −Jᵀr` over the free parameters (those at a
//! bound whose descent direction points outside are held), `p ← clamp(p + δ)`
//! when the cost
//! decreases (`λ ← λ/3`), otherwise `λ ← 4λ`; converged when the
//! decrease predicted by the Gauss–Newton model, or the achieved one, is
//! below `rel_tol` of the cost. The Jacobian `J = ∂r/∂p` is
//! built from forward finite-difference columns (one extra simulation per
//! parameter; candidates have 1–4 parameters, and the residual count is far
//! larger than the parameter count, so adjoint rows would cost more); the
//! right-hand side `Jᵀr = ∂(½‖r‖²)/∂p` is exact, from one adjoint pass
//! ([`super::adjoint`], FD-tested in `tests/calibrate_fit_gradient.rs`)
//! over the run that evaluated the residuals (recorded as it ran, so the
//! gradient costs a backward pass and no further simulation). Several starts;
//! the best end point wins (ties: the first start, so results are
//! deterministic).
//!
//! Confidence: at the optimum, `σ̂² = ‖r‖²/(n − k)` and
//! `Cov(p) ≈ σ̂² (JᵀJ)⁻¹` (the Gauss–Newton Hessian); the reported interval
//! is `p ± 1.96 √Cov_jj` (95 %, `None` when `JᵀJ` is singular: the
//! parameter is not identifiable from the data).

use super::problem::{Candidate, Problem};
use nalgebra::{DMatrix, DVector};

/// Options of the fit (defaults in [`FitOptions::default`]).
#[derive(Clone, Debug)]
pub struct FitOptions {
    /// Levenberg–Marquardt iterations per start. Default 20.
    pub max_iters: usize,
    /// Stop when an accepted step lowers the cost by less than this
    /// fraction. Default 1e-7.
    pub rel_tol: f64,
    /// Finite-difference step per parameter, relative to
    /// `max(|p|, typical)`. Default 1e-5.
    pub fd_step: f64,
    /// Use the exact gradient `Jᵀr` from the adjoint pass
    /// ([`super::adjoint`]) as the right-hand side of each step (the
    /// finite-difference `J` then only supplies the curvature `JᵀJ`), so the
    /// fit stops at an exact stationary point. Default true.
    pub adjoint_gradient: bool,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            max_iters: 20,
            rel_tol: 1e-7,
            fd_step: 1e-5,
            adjoint_gradient: true,
        }
    }
}

/// Result of fitting one candidate.
#[derive(Clone, Debug)]
pub struct Fit {
    pub params: Vec<f64>,
    /// `‖r‖²` on the training window.
    pub rss: f64,
    /// Number of training residuals.
    pub n: usize,
    /// 95 % half-widths (None: not identifiable).
    pub half_width: Vec<Option<f64>>,
    /// Simulations run.
    pub simulations: usize,
    /// The Gauss–Newton matrix `JᵀJ` at the first start, before any step
    /// (for [`super::identifiability`]; `None` when it could not be built).
    pub gauss_newton_start: Option<DMatrix<f64>>,
}

fn jacobian(
    pb: &Problem,
    cand: &Candidate,
    p: &[f64],
    r: &[f64],
    opts: &FitOptions,
    sims: &mut usize,
) -> Option<DMatrix<f64>> {
    let k = p.len();
    let mut j = DMatrix::zeros(r.len(), k);
    for c in 0..k {
        let mut h = opts.fd_step * p[c].abs().max(cand.typical[c]);
        if p[c] + h > cand.upper[c] {
            h = -h;
        }
        let mut q = p.to_vec();
        q[c] += h;
        *sims += 1;
        let rq = pb.train_residuals(cand, &q)?;
        if rq.len() != r.len() {
            return None;
        }
        for (i, (a, b)) in rq.iter().zip(r).enumerate() {
            j[(i, c)] = (a - b) / h;
        }
    }
    Some(j)
}

fn clamp(cand: &Candidate, p: &mut [f64]) {
    for (k, v) in p.iter_mut().enumerate() {
        *v = v.clamp(cand.lower[k], cand.upper[k]);
    }
}

fn sq(r: &[f64]) -> f64 {
    r.iter().map(|x| x * x).sum()
}

/// The training residuals at `p`; with [`FitOptions::adjoint_gradient`] the
/// runs are recorded as well, so that the exact `Jᵀr` at an accepted point
/// needs only the backward pass (the forward one is this evaluation's).
fn evaluate(
    pb: &Problem,
    cand: &Candidate,
    p: &[f64],
    opts: &FitOptions,
) -> Option<(Vec<f64>, Option<super::adjoint::Recorded>)> {
    if opts.adjoint_gradient {
        super::adjoint::residuals_recorded(pb, cand, p)
    } else {
        Some((pb.train_residuals(cand, p)?, None))
    }
}

/// Fits `cand` from one start; `None` when the start cannot be simulated.
fn fit_from(
    pb: &Problem,
    cand: &Candidate,
    start: &[f64],
    opts: &FitOptions,
    sims: &mut usize,
    gn_start: &mut Option<DMatrix<f64>>,
) -> Option<(Vec<f64>, f64, Vec<f64>)> {
    let mut p = start.to_vec();
    clamp(cand, &mut p);
    *sims += 1;
    let (mut r, mut rec) = evaluate(pb, cand, &p, opts)?;
    let mut cost = sq(&r);
    let mut lambda = 1e-3;
    for _ in 0..opts.max_iters {
        let Some(j) = jacobian(pb, cand, &p, &r, opts, sims) else {
            break;
        };
        let a = j.transpose() * &j;
        if gn_start.is_none() {
            *gn_start = Some(a.clone());
        }
        let exact = rec
            .as_mut()
            .and_then(|t| super::adjoint::gradient(pb, cand, &p, t))
            .map(DVector::from_vec);
        let g = exact.unwrap_or_else(|| j.transpose() * DVector::from_column_slice(&r));
        let mut accepted = false;
        let k = p.len();
        for _ in 0..8 {
            // Active set: a parameter at a bound whose descent direction
            // points outside stays fixed; the step solves for the others.
            let mut m = a.clone();
            let mut rhs = -&g;
            for d in 0..k {
                let at_lower = p[d] <= cand.lower[d] && g[d] > 0.0;
                let at_upper = p[d] >= cand.upper[d] && g[d] < 0.0;
                if at_lower || at_upper {
                    m.row_mut(d).fill(0.0);
                    m.column_mut(d).fill(0.0);
                    m[(d, d)] = 1.0;
                    rhs[d] = 0.0;
                } else {
                    m[(d, d)] += lambda * a[(d, d)].max(1e-300) + 1e-300;
                }
            }
            let Some(delta) = m.cholesky().map(|c| c.solve(&rhs)) else {
                lambda *= 4.0;
                continue;
            };
            let mut q: Vec<f64> = p.iter().zip(delta.iter()).map(|(a, b)| a + b).collect();
            clamp(cand, &mut q);
            // Decrease predicted by the Gauss–Newton model for the
            // projected step; converged when it is negligible.
            let d = DVector::from_iterator(k, q.iter().zip(&p).map(|(a, b)| a - b));
            let predicted = -(g.dot(&d) + 0.5 * d.dot(&(&a * &d)));
            if q == p || predicted <= opts.rel_tol * cost {
                return Some((p, cost, r));
            }
            *sims += 1;
            if let Some((rq, rec_q)) = evaluate(pb, cand, &q, opts) {
                let c = sq(&rq);
                if rq.len() == r.len() && c < cost {
                    let gain = (cost - c) / cost.max(1e-300);
                    p = q;
                    r = rq;
                    rec = rec_q;
                    cost = c;
                    lambda = (lambda / 3.0).max(1e-12);
                    accepted = true;
                    if gain < opts.rel_tol {
                        return Some((p, cost, r));
                    }
                    break;
                }
            }
            lambda *= 4.0;
        }
        if !accepted {
            break;
        }
    }
    Some((p, cost, r))
}

/// Fits `cand` from each of its starts and returns the best.
pub fn fit(pb: &Problem, cand: &Candidate, opts: &FitOptions) -> Option<Fit> {
    let mut sims = 0;
    let mut best: Option<(Vec<f64>, f64, Vec<f64>)> = None;
    let mut gn_start = None;
    for s in &cand.starts {
        // `JᵀJ` is kept at the first start only (a later start's is not
        // overwritten onto it: `gn_start` is filled once).
        if let Some(res) = fit_from(pb, cand, s, opts, &mut sims, &mut gn_start)
            .filter(|res| best.as_ref().is_none_or(|b| res.1 < b.1))
        {
            best = Some(res);
        }
    }
    let (params, rss, r) = best?;
    Some(Fit {
        n: r.len(),
        half_width: vec![None; params.len()],
        params,
        rss,
        simulations: sims,
        gauss_newton_start: gn_start,
    })
}

/// Fills `fit.half_width` (95 % intervals from the Gauss–Newton Hessian at
/// the fitted values; see the module doc). Costs `1 + k` simulations.
pub fn confidence(pb: &Problem, cand: &Candidate, fit: &mut Fit, opts: &FitOptions) {
    let (p, rss, n, k) = (&fit.params, fit.rss, fit.n, fit.params.len());
    let mut sims = 1;
    let Some(r) = pb.train_residuals(cand, p) else {
        return;
    };
    fit.half_width = match jacobian(pb, cand, p, &r, opts, &mut sims) {
        Some(j) => {
            let a = j.transpose() * &j;
            let s2 = rss / (n.saturating_sub(k).max(1)) as f64;
            match a.clone().try_inverse() {
                Some(inv) => (0..k)
                    .map(|d| {
                        let v = inv[(d, d)] * s2;
                        (v.is_finite() && v >= 0.0 && a[(d, d)] > 0.0).then(|| 1.96 * v.sqrt())
                    })
                    .collect(),
                None => vec![None; k],
            }
        }
        None => vec![None; k],
    };
    fit.simulations += sims;
}
