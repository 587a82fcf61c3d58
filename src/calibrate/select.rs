//! Naming the missing effect: fit every candidate on the training window,
//! then the best pairs, score on the held-out window, rank, decide.
//!
//! Criterion (lower is better), with `n_tr`, `n_ho` residuals and `k`
//! parameters:
//!
//! ```text
//! C = n_tr ln(RSS_tr/n_tr) + k ln(n_tr)      (BIC of the training fit)
//!   + n_ho ln(RSS_ho/n_ho)                   (held-out Gaussian deviance)
//! ```
//!
//! so a flexible effect pays for its parameters (BIC) and must also predict
//! data it was not fitted to. The model without any effect has `k = 0`.
//! The verdict (`effect`, `none`, `unexplained`) is decided by
//! [`super::verdict`] against the model's own error floor
//! ([`super::floor`]); a candidate must still beat that model by
//! `ΔC > min_delta` (default 10: "very strong" evidence on the BIC scale)
//! and lower the held-out RMS by at least `min_gain` (default 5 %). Candidates are fitted in parallel (rayon) and collected
//! in list order, so results do not depend on the thread count.

use super::candidates;
use super::fit::{Fit, FitOptions, confidence, fit};
use super::problem::{Candidate, Problem, Simulated};
use rayon::prelude::*;

/// Options of the selection (defaults in [`SelectOptions::default`]).
#[derive(Clone, Debug)]
pub struct SelectOptions {
    pub fit: FitOptions,
    /// Pairs are formed from this many best single candidates. Default 3.
    pub pair_from: usize,
    /// The best single is also paired with this many further singles (those
    /// beating the baseline, by criterion). Default 8.
    pub pair_with_best: usize,
    /// Minimum criterion improvement for a verdict "effect". Default 10.
    pub min_delta: f64,
    /// Minimum relative held-out RMS reduction. Default 0.05.
    pub min_gain: f64,
}

impl Default for SelectOptions {
    fn default() -> Self {
        SelectOptions {
            fit: FitOptions::default(),
            pair_from: 3,
            pair_with_best: 8,
            min_delta: 10.0,
            min_gain: 0.05,
        }
    }
}

/// One scored model (a candidate, or none).
#[derive(Clone, Debug)]
pub struct Scored {
    pub candidate: Candidate,
    pub fit: Fit,
    /// Held-out residual sum of squares and count.
    pub rss_holdout: f64,
    pub n_holdout: usize,
    pub criterion: f64,
    /// The full-horizon simulation at the fitted values.
    pub sim: Simulated,
}

impl Scored {
    pub fn rms_train(&self) -> f64 {
        (self.fit.rss / self.fit.n.max(1) as f64).sqrt()
    }
    pub fn rms_holdout(&self) -> f64 {
        (self.rss_holdout / self.n_holdout.max(1) as f64).sqrt()
    }
}

fn deviance(rss: f64, n: usize) -> f64 {
    let n = n.max(1) as f64;
    n * (rss.max(1e-300) / n).ln()
}

/// Scores a fitted candidate on the whole horizon.
pub fn score(pb: &Problem, cand: Candidate, fit: Fit) -> Option<Scored> {
    let end = pb.measured.times.len();
    let sim = pb.simulate(&cand.specs(&fit.params), end)?;
    let mut r = Vec::new();
    pb.residuals(&sim, pb.split..end, &mut r);
    let rss_holdout: f64 = r.iter().map(|x| x * x).sum();
    let k = fit.params.len() as f64;
    let criterion =
        deviance(fit.rss, fit.n) + k * (fit.n.max(2) as f64).ln() + deviance(rss_holdout, r.len());
    Some(Scored {
        candidate: cand,
        rss_holdout,
        n_holdout: r.len(),
        criterion,
        sim,
        fit,
    })
}

/// The model as given (no effect).
pub fn baseline(pb: &Problem) -> Option<Scored> {
    let cand = Candidate {
        label: "none".into(),
        templates: Vec::new(),
        lower: Vec::new(),
        upper: Vec::new(),
        typical: Vec::new(),
        starts: vec![Vec::new()],
    };
    let sim = pb.simulate(&[], pb.split)?;
    let mut r = Vec::new();
    pb.residuals(&sim, 0..pb.split, &mut r);
    let fit = Fit {
        params: Vec::new(),
        rss: r.iter().map(|x| x * x).sum(),
        n: r.len(),
        half_width: Vec::new(),
        simulations: 1,
    };
    score(pb, cand, fit)
}

/// Everything the selection found.
pub struct Selection {
    pub baseline: Scored,
    /// Every fitted candidate (singles then pairs), best first.
    pub ranking: Vec<Scored>,
    /// Index into `ranking` of the chosen model, `None` for "no missing
    /// effect found".
    pub chosen: Option<usize>,
    /// Simulations run in total.
    pub simulations: usize,
    /// The model's own error on the data ([`super::floor`]).
    pub floor: super::floor::ErrorFloor,
    /// The verdict and its reason ([`super::verdict`]).
    pub decision: super::verdict::Decision,
}

/// Fits `cands` in parallel (order-preserving).
fn fit_all(
    pb: &Problem,
    cands: Vec<Candidate>,
    opts: &SelectOptions,
    on_done: &(dyn Fn() + Sync),
) -> Vec<Scored> {
    cands
        .into_par_iter()
        .map(|c| {
            let r = fit(pb, &c, &opts.fit).and_then(|f| score(pb, c, f));
            on_done();
            r
        })
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

fn sort(v: &mut [Scored]) {
    v.sort_by(|a, b| {
        a.criterion
            .total_cmp(&b.criterion)
            .then_with(|| a.candidate.label.cmp(&b.candidate.label))
    });
}

/// Runs the selection over `cands`; `on_total(n)` announces the number of
/// fits, `on_done()` is called after each.
pub fn select(
    pb: &Problem,
    cands: Vec<Candidate>,
    opts: &SelectOptions,
    on_total: &dyn Fn(usize),
    on_done: &(dyn Fn() + Sync),
) -> Option<Selection> {
    let base = baseline(pb)?;
    let npairs = opts.pair_from * opts.pair_from.saturating_sub(1) / 2 + opts.pair_with_best;
    on_total(cands.len() + npairs);
    let mut singles = fit_all(pb, cands, opts, on_done);
    sort(&mut singles);
    // Pairs of the best singles that beat the baseline, different kinds.
    let top: Vec<&Scored> = singles
        .iter()
        .filter(|s| s.criterion < base.criterion)
        .take(opts.pair_from)
        .collect();
    let mut pairs = Vec::new();
    let mut push = |a: &Scored, b: &Scored| {
        let shared_kind = a
            .candidate
            .kinds()
            .iter()
            .any(|k| b.candidate.kinds().contains(k));
        if !shared_kind {
            pairs.push(candidates::pair(
                &a.candidate,
                &a.fit.params,
                &b.candidate,
                &b.fit.params,
            ));
        }
    };
    for i in 0..top.len() {
        for j in i + 1..top.len() {
            push(top[i], top[j]);
        }
    }
    // The best single with the next `pair_with_best` singles beyond the top
    // that beat the baseline: a second effect that alone explains little
    // (masked by the first) still gets paired with it.
    if let Some(best) = top.first() {
        for b in singles
            .iter()
            .filter(|s| s.criterion < base.criterion)
            .skip(opts.pair_from)
            .take(opts.pair_with_best)
        {
            push(best, b);
        }
    }
    let npaired = pairs.len();
    let mut ranking = singles;
    ranking.extend(fit_all(pb, pairs, opts, on_done));
    for _ in npaired..npairs {
        on_done();
    }
    sort(&mut ranking);
    let floor = super::floor::estimate(pb, &base.sim)?;
    let inertia = super::verdict::joint_inertia(pb.scene);
    let bad: Vec<(String, String)> = ranking
        .iter()
        .filter_map(|s| {
            super::verdict::implausible(pb, s, &inertia).map(|w| (s.candidate.label.clone(), w))
        })
        .collect();
    let decision = super::verdict::decide(&base, &ranking, &floor, bad, opts);
    let chosen = decision.chosen;
    if let Some(i) = chosen {
        let s = &mut ranking[i];
        confidence(pb, &s.candidate, &mut s.fit, &opts.fit);
    }
    // + 2 refined baseline runs (Δt/2, Δt/4) for the floor.
    let simulations = 3 + ranking.iter().map(|s| s.fit.simulations + 1).sum::<usize>();
    Some(Selection {
        baseline: base,
        ranking,
        chosen,
        simulations,
        floor,
        decision,
    })
}
