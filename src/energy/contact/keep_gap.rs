//! A start that keeps the gap ([`crate::sim::NewtonOptions::keep_gap`]):
//! the predictor's guess pulled back along `θ^t → guess`, robot group by
//! robot group, until no pair active at `θ^t` has closed its gap by more
//! than the fraction `1 − f` (issue 31; `notes/performance.md`, twenty-first
//! session, helper 3).
//!
//! The polynomial predictors carry a pair's approach velocity into the
//! contact that decelerates it, so on the steps with a long Newton tail the
//! guess lies deeper in a pair's barrier than the step's solution (which
//! keeps about the gap it had at `θ^t`), and from the deep side every full
//! Newton step falls short. With `d_k(α)` the GJK distance of active pair
//! `k` at `θ^t + α (g − θ^t)` restricted to its robot group `G`:
//!
//! ```text
//! α_G = 1                                   if d_k(1) ≥ f d_k(0) for all k ∈ G,
//! α_G = min_{k: d_k(1) < f d_k(0)} (1 − f) d_k(0) / (d_k(0) − d_k(1))   else (secant),
//! ```
//!
//! then checked at the pulled-back point: a group with a pair still below
//! `f d_k(0)` halves `α_G`, at most [`HALVINGS`] times, then takes `α_G = 0`.
//! Groups are the connected components of "robots sharing a pair active at
//! `θ^t`", so a group's pairs depend on its own coordinates only; robots in
//! no group keep the guess. Only the start moves: the solve's acceptance of
//! the start and its stopping test are unchanged.

use super::ContactEnergy;
use crate::contact::PairOutcome;
use crate::contact::separation::{self, Separation};
use crate::energy::{EnergyError, StepContext};
use crate::kinematics::{KinOrder, Kinematics};
use crate::math::{Pose, transform_point};
use crate::model::Model;
use nalgebra::{DVector, Matrix3, Vector3};

/// Halvings of a group's fraction after the secant before it is set to 0.
pub const HALVINGS: usize = 4;

/// Scratch of [`ContactEnergy::keep_gap`] (no allocation once warm).
pub(super) struct GapScratch {
    /// Kinematics at the trial points (the objective's stay at `θ^t`).
    kin: Kinematics,
    /// Pairs active at `θ^t`, their distance there and their group.
    pairs: Vec<(usize, usize)>,
    d0: Vec<f64>,
    group: Vec<usize>,
    /// Per robot: its group's root (union–find), fraction, and whether a
    /// pair of the group is below `f d_k(0)` at the current trial.
    root: Vec<usize>,
    alpha: Vec<f64>,
    short: Vec<bool>,
    xa: Vec<Vector3<f64>>,
    xb: Vec<Vector3<f64>>,
    simplex: parry3d_f64::query::gjk::VoronoiSimplex,
    trial: DVector<f64>,
}

impl GapScratch {
    pub(super) fn new(model: &Model) -> Self {
        GapScratch {
            kin: Kinematics::new(model),
            pairs: Vec::new(),
            d0: Vec::new(),
            group: Vec::new(),
            root: Vec::new(),
            alpha: Vec::new(),
            short: Vec::new(),
            xa: Vec::new(),
            xb: Vec::new(),
            simplex: parry3d_f64::query::gjk::VoronoiSimplex::new(),
            trial: DVector::zeros(0),
        }
    }
}

/// Union–find root of robot `r`.
fn find(root: &mut [usize], mut r: usize) -> usize {
    while root[r] != r {
        root[r] = root[root[r]];
        r = root[r];
    }
    r
}

impl ContactEnergy {
    /// The robot of hull `h`.
    fn robot_of(&self, model: &Model, h: usize) -> usize {
        model.links[self.hulls.ids[h].link].robot
    }

    /// GJK distance of hulls `a`, `b` at `poses` (0 when GJK reports them
    /// intersecting or fails: such a pair counts as closed).
    fn gap_at(&mut self, model: &Model, poses: &[Pose], (a, b): (usize, usize)) -> f64 {
        let g = &mut self.gap;
        for (h, out) in [(a, &mut g.xa), (b, &mut g.xb)] {
            let id = self.hulls.ids[h];
            out.clear();
            out.extend(
                model.links[id.link].hulls[id.hull]
                    .x_local
                    .iter()
                    .map(|x| transform_point(&poses[id.link], x)),
            );
        }
        match separation::separate(&g.xa, &g.xb, None, &mut g.simplex) {
            Ok(Separation::Separated { distance, .. }) => distance,
            _ => 0.0,
        }
    }

    /// Lists the pairs the last evaluation found active (it must have been
    /// at `kin`'s poses, else none), their distances at `kin`, and groups
    /// their robots. Returns whether any pair is active.
    fn gap_pairs(&mut self, model: &Model, kin: &Kinematics) -> bool {
        let mut pairs = std::mem::take(&mut self.gap.pairs);
        pairs.clear();
        if self.last_at(&kin.pose) {
            pairs.extend(
                self.pairs
                    .iter()
                    .zip(&self.results)
                    .filter(|(_, r)| matches!(r, Ok(PairOutcome::Separated(_))))
                    .map(|(p, _)| *p),
            );
        }
        let nr = model.robots.len();
        self.gap.root.clear();
        self.gap.root.extend(0..nr);
        self.gap.d0.clear();
        for &p in &pairs {
            let (ra, rb) = (self.robot_of(model, p.0), self.robot_of(model, p.1));
            let (ra, rb) = (find(&mut self.gap.root, ra), find(&mut self.gap.root, rb));
            self.gap.root[ra.max(rb)] = ra.min(rb);
            let d = self.gap_at(model, &kin.pose, p);
            self.gap.d0.push(d);
        }
        self.gap.group.clear();
        for &p in &pairs {
            let r = self.robot_of(model, p.0);
            let g = find(&mut self.gap.root, r);
            self.gap.group.push(g);
        }
        self.gap.pairs = pairs;
        !self.gap.pairs.is_empty()
    }

    /// Poses at `θ^t + Σ_G α_G (g − θ^t)_G` into the gap kinematics; flags
    /// the groups with a pair below `f d_k(0)` there and, on the first
    /// call (`secant`), sets their `α_G` to the secant fraction. Returns
    /// whether any group was flagged.
    #[allow(clippy::too_many_arguments)]
    fn gap_trial(
        &mut self,
        model: &Model,
        q0: &DVector<f64>,
        guess: &DVector<f64>,
        charts: &[Matrix3<f64>],
        f: f64,
        secant: bool,
    ) -> bool {
        let g = &mut self.gap;
        g.trial.clone_from(q0);
        for (k, t) in g.trial.iter_mut().enumerate() {
            let r = find(&mut g.root, model.links[model.dofs[k].link].robot);
            *t += g.alpha[r] * (guess[k] - q0[k]);
        }
        g.kin.update(model, &g.trial, charts, KinOrder::Pose);
        g.short.iter_mut().for_each(|s| *s = false);
        for i in 0..self.gap.pairs.len() {
            let poses = std::mem::take(&mut self.gap.kin.pose);
            let d = self.gap_at(model, &poses, self.gap.pairs[i]);
            self.gap.kin.pose = poses;
            let (d0, grp) = (self.gap.d0[i], self.gap.group[i]);
            if d < f * d0 {
                self.gap.short[grp] = true;
                if secant {
                    // The trial's coordinates are set: α_G may change now.
                    let a = (1.0 - f) * d0 / (d0 - d);
                    self.gap.alpha[grp] = self.gap.alpha[grp].min(a);
                }
            }
        }
        self.gap.short.iter().any(|&s| s)
    }

    /// [`crate::energy::Energy::keep_gap`] of the contact term (see the
    /// module documentation). `kin` holds the kinematics at `q0 = θ^t`,
    /// whose value the solve has just evaluated.
    pub(super) fn keep_gap_impl(
        &mut self,
        ctx: &StepContext,
        q0: &DVector<f64>,
        kin: &Kinematics,
        guess: &mut DVector<f64>,
        f: f64,
        charts: &[Matrix3<f64>],
    ) -> Result<(), EnergyError> {
        let model = ctx.model;
        if f.is_nan() || f <= 0.0 || guess.len() != q0.len() || !self.gap_pairs(model, kin) {
            return Ok(());
        }
        let nr = model.robots.len();
        self.gap.alpha.clear();
        self.gap.alpha.resize(nr, 1.0);
        self.gap.short.clear();
        self.gap.short.resize(nr, false);
        if !self.gap_trial(model, q0, guess, charts, f, true) {
            return Ok(());
        }
        for round in 0..=HALVINGS {
            if !self.gap_trial(model, q0, guess, charts, f, false) {
                break;
            }
            let g = &mut self.gap;
            for (a, &s) in g.alpha.iter_mut().zip(&g.short) {
                if s {
                    *a = if round < HALVINGS { *a * 0.5 } else { 0.0 };
                }
            }
        }
        // The last fractions (checked, or 0 after the last halving).
        let g = &mut self.gap;
        for k in 0..guess.len() {
            let r = find(&mut g.root, model.links[model.dofs[k].link].robot);
            guess[k] = q0[k] + g.alpha[r] * (guess[k] - q0[k]);
        }
        Ok(())
    }
}
