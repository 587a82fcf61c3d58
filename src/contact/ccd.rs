//! Continuous collision detection for articulated motion: the largest
//! fraction `α` of a joint-space segment `θ → θ + Δθ` along which no hull
//! pair can touch, by conservative advancement (Mirtich; Zhang et al. 2006;
//! Rigid-IPC) on the curved world paths that forward kinematics makes of the
//! straight joint-space segment. The simulator certifies each step's
//! straight path `θ^t → θ^{t+1}`, and line-search segments only for steps
//! whose straight path fails (see [`crate::sim::Simulator::step`]).
//!
//! # What is certified
//!
//! For `θ(α) = θ + α Δθ`, [`crate::kinematics::SegmentMotion`] gives per link
//! a constant drift `c` and a spread `E` with `dx/dα = c + e`, `‖e‖ ≤ E`
//! for every hull point, at every `α ∈ [0, 1]` (rigid lever arms from the
//! joints' coordinates steps; see that module). For a hull pair `(a, b)`
//! separated at `α_k` with a certified gap `g_k` along the unit direction
//! `n` (GJK, then the exact support gap `min_B n·y − max_A n·x`, see
//! [`separation`](super::separation)), the gap along the *fixed* `n` is a
//! lower bound of the distance and shrinks at most at the rate
//!
//! ```text
//! ρ = max(0, n·(c_a − c_b) + E_a + E_b)      (m per unit α),
//! ```
//!
//! so `dist(α) ≥ g_k − (α − α_k) ρ` on `[α_k, 1]`. Each pair keeps a
//! margin: its distance never drops below `η g₀` (`g₀` its gap at the start
//! of the segment, `η` = [`CcdOptions::keep_fraction`]), so the barrier never
//! starts from a touching configuration. Conservative advancement takes
//! global rounds: every pair still in doubt allows `(g_k − η g₀)/ρ` more;
//! the smallest is taken, the kinematics and gaps are re-evaluated there,
//! and a pair whose allowance covers the rest of the segment
//! (`ρ (1 − α_k) ≤ g_k − η g₀`) leaves the set. The returned `α` is
//! certified: on `[0, α]` every pair's distance stays `≥ η g₀ > 0`.
//!
//! Candidate pairs come from a broad phase over *swept* boxes: each hull's
//! box at `θ` padded by how far any of its points can move on the whole
//! segment (`‖c‖ + E`), so a pair that could pass through each other within
//! the step is a candidate even if its end poses are far apart. The cheap
//! test that skips CCD for slow pairs is the first round itself: a pair with
//! `ρ ≤ (1 − η) g₀` is cleared with one GJK query and never advanced.
//! Before it, pairs whose direction-free relative-motion bound is 0 or at
//! most `(1 − η)` of a lower bound of their distance (box or bounding-sphere
//! gap) are skipped without GJK.
//!
//! # Cost
//!
//! Three shortcuts make the stage cheap without changing any result (the
//! returned `α` and the statistics are those of the computation above, bit
//! for bit; tested in `ccd_tests.rs`):
//!
//! - the kinematics at the segment's start is taken from the caller when it
//!   has it (the simulator's at `θ^t`, evaluated once per step);
//! - [`Ccd::cleared_by_lever_bound`]: the lever half of the motion bound
//!   (no trigonometry) gives `Ē ≥ E` exactly in floating point; if every
//!   pair of boxes padded by `‖c‖ + Ē` passes the cheap skip with `Ē`, the
//!   full computation would skip them all with `E` too and return 1, so the
//!   exact start rates (dual-number kinematics) are never evaluated. This
//!   decides most segments of slow, separated motion;
//! - each advancement round evaluates poses and world vertices only of the
//!   pairs measured again there (their links and the links' ancestors).
//!
//! What is not certified: a pair that GJK cannot resolve as separated at the
//! start of the segment (gap below its ~1e-8 relative tolerance; the barrier
//! is then astronomically stiff) is counted in [`CcdStats::uncertified`] and
//! left to the barrier. Pairs on the same link, excluded pairs and the
//! ground plane (a half-space cannot be tunnelled through) are not tested.

use super::separation::{Separation, separate};
use crate::geometry::{Aabb, BroadPhase, WorldHulls, hull_boxes};
use crate::kinematics::{KinOrder, Kinematics, SegmentMotion, hull_radii};
use crate::model::Model;
use nalgebra::{DVector, Matrix3, Vector3};
use parry3d_f64::query::gjk::VoronoiSimplex;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;

/// Continuous collision detection settings (scene `contact.ccd`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct CcdOptions {
    /// Cap every Newton line search so that no hull pair can touch along
    /// the step's curved path (articulated continuous collision detection).
    /// Default true. Off, the simulator is collision-free only at the time
    /// steps (the paper's behaviour): fast or thin bodies can tunnel.
    pub enabled: bool,
    /// `η`: each pair keeps at least this fraction of its distance at the
    /// start of a Newton step all along the step (`0 < η < 1`). Default 0.1.
    pub keep_fraction: f64,
    /// Conservative-advancement rounds per Newton iteration; the step is
    /// capped where the last round ended (still certified). Default 16.
    pub max_rounds: usize,
}

impl Default for CcdOptions {
    fn default() -> Self {
        CcdOptions {
            enabled: true,
            keep_fraction: 0.1,
            max_rounds: 16,
        }
    }
}

impl CcdOptions {
    /// Whether these are the defaults (scene files omit them then).
    pub fn is_default(&self) -> bool {
        *self == CcdOptions::default()
    }

    /// A description of the first invalid field, if any.
    pub fn problem(&self) -> Option<String> {
        if !(self.keep_fraction > 0.0 && self.keep_fraction < 1.0) {
            return Some(format!(
                "`ccd.keep_fraction` must lie strictly between 0 and 1, got {}",
                self.keep_fraction
            ));
        }
        if self.max_rounds == 0 {
            return Some("`ccd.max_rounds` must be at least 1".into());
        }
        None
    }
}

pub use crate::counters::CcdStats;

/// A pair in doubt during advancement.
#[derive(Clone, Copy, Debug)]
struct Doubt {
    a: usize,
    b: usize,
    /// For links with a common ancestor: the closing-rate bound relative to
    /// its frame (direction-free), used when below the world-frame
    /// directional one; `None`: only the world-frame one.
    relative: Option<f64>,
    /// `η g₀` (m).
    keep: f64,
    /// Certified gap at the last `α` measured (m) and its direction (a → b).
    gap: f64,
    dir: Vector3<f64>,
    /// Up to here the pair is certified to keep `η g₀`.
    horizon: f64,
}

/// Scratch and statistics of the CCD stage (reused between Newton
/// iterations: no allocation once warm).
#[derive(Clone)]
pub struct Ccd {
    pub options: CcdOptions,
    /// Statistics since the last [`std::mem::take`] by the owner.
    pub stats: CcdStats,
    motion: SegmentMotion,
    radius: Vec<f64>,
    pad: Vec<f64>,
    kin: Kinematics,
    hulls: WorldHulls,
    /// Per hull at the segment's start: its unpadded box.
    boxes: Vec<Aabb>,
    broad: BroadPhase,
    /// The broad phase of [`Ccd::cleared_by_lever_bound`] (its own sweep
    /// order: its pads differ from the exact ones).
    lever_broad: BroadPhase,
    candidates: Vec<(usize, usize)>,
    doubt: Vec<Doubt>,
    /// Per hull at the segment's start: centroid and bounding radius,
    /// computed on first use (`None`: not yet).
    spheres: Vec<Option<(Vector3<f64>, f64)>>,
    /// Depth of every link in its tree (roots 0), for common ancestors.
    depth: Vec<usize>,
    trial: DVector<f64>,
    /// Per advancement round: the links whose poses are needed, and the
    /// hulls whose vertices are (with repeats).
    needed_link: Vec<bool>,
    needed_hull: Vec<usize>,
    /// The segment `α dir` being certified.
    seg: DVector<f64>,
    simplex: VoronoiSimplex,
    /// Tests: whether [`Ccd::cleared_by_lever_bound`] is tried, and how
    /// often it cleared a segment.
    #[cfg(test)]
    lever_shortcut: bool,
    #[cfg(test)]
    lever_cleared: usize,
}

impl Ccd {
    pub fn new(model: &Model, options: CcdOptions) -> Self {
        Ccd {
            options,
            stats: CcdStats::default(),
            motion: SegmentMotion::default(),
            radius: Vec::new(),
            pad: Vec::new(),
            kin: Kinematics::new(model),
            hulls: WorldHulls::new(model),
            boxes: Vec::new(),
            broad: BroadPhase::default(),
            lever_broad: BroadPhase::default(),
            candidates: Vec::new(),
            doubt: Vec::new(),
            spheres: Vec::new(),
            depth: model
                .links
                .iter()
                .scan(Vec::new(), |d: &mut Vec<usize>, l| {
                    let k = l.parent.map_or(0, |p| d[p] + 1);
                    d.push(k);
                    Some(k)
                })
                .collect(),
            trial: DVector::zeros(model.ndof()),
            needed_link: Vec::new(),
            needed_hull: Vec::new(),
            seg: DVector::zeros(model.ndof()),
            simplex: VoronoiSimplex::new(),
            #[cfg(test)]
            lever_shortcut: true,
            #[cfg(test)]
            lever_cleared: 0,
        }
    }

    /// Closing-rate bound `ρ` of a pair along `dir` (m per unit α).
    fn rate(&self, d: &Doubt) -> f64 {
        let (la, lb) = (self.hulls.ids[d.a].link, self.hulls.ids[d.b].link);
        let m = &self.motion;
        let world =
            (d.dir.dot(&(m.drift[la] - m.drift[lb])) + m.spread[la] + m.spread[lb]).max(0.0);
        // Both bound the closing rate: the smaller holds.
        d.relative.map_or(world, |r| r.min(world))
    }

    /// Lower bound of the distance of hulls `a`, `b` from their boxes
    /// (`≤ 0` when the boxes overlap): the largest axis gap.
    fn box_gap(&self, a: usize, b: usize) -> f64 {
        let (ba, bb) = (self.broad.boxes(), self.broad.boxes());
        let (pa, pb) = (self.pad[a], self.pad[b]);
        let (ba, bb) = (&ba[a], &bb[b]);
        (0..3)
            .map(|e| (bb.lo[e] + pb - (ba.hi[e] - pa)).max(ba.lo[e] + pa - (bb.hi[e] - pb)))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Certified gap and direction of hulls `a`, `b` at the current
    /// vertices, `None` when GJK cannot certify separation.
    fn gap(
        &mut self,
        a: usize,
        b: usize,
        hint: Option<Vector3<f64>>,
    ) -> Option<(f64, Vector3<f64>)> {
        match separate(
            self.hulls.hull(a),
            self.hulls.hull(b),
            hint,
            &mut self.simplex,
        ) {
            Ok(Separation::Separated {
                dir, max_a, min_b, ..
            }) => Some((min_b - max_a, dir)),
            _ => None,
        }
    }

    /// Whether the lever bound alone shows that [`Ccd::fraction`]'s full
    /// computation would clear every pair by its cheap skips (and so return
    /// 1 with no pair tested): the candidates of boxes padded by the upper
    /// reach `‖c‖ + Ē ≥ ‖c‖ + E` contain every candidate of the exactly
    /// padded boxes, and for each of them the relative-motion bound with
    /// `Ē` (at least the one with `E`, rounding being monotone) is 0 or at
    /// most `(1 − η)` times a lower bound of the cheap gap: the exact
    /// bounding-sphere gap, or the box gap minus `10⁻¹²` of the operands'
    /// magnitudes (the exactly padded boxes' gap differs from the unpadded
    /// one by a few roundings, `~10⁻¹⁶` of them). Stops at the first pair
    /// it cannot clear (on long chains the lever bound is loose and the
    /// padded boxes overlap a lot). Needs the lever half of the motion
    /// bound and the hulls and boxes at the start.
    fn cleared_by_lever_bound(
        &mut self,
        model: &Model,
        excluded: &BTreeSet<(usize, usize)>,
    ) -> bool {
        self.pad.clear();
        let motion = &self.motion;
        self.pad
            .extend(self.hulls.ids.iter().map(|id| motion.reach_upper(id.link)));
        if !self.pad.iter().all(|p| p.is_finite()) {
            return false;
        }
        let Ccd {
            options,
            motion,
            pad,
            hulls,
            boxes,
            lever_broad,
            spheres,
            depth,
            ..
        } = self;
        let one_minus_eta = 1.0 - options.keep_fraction;
        lever_broad.swept_pairs_until(hulls, boxes, pad, excluded, |a, b| {
            let (bound, _) = pair_bound(model, depth, hulls, motion, a, b, &motion.spread_upper);
            if bound == 0.0 {
                return true;
            }
            let (ba, bb) = (&boxes[a], &boxes[b]);
            let slack = 1e-12 * (pad[a] + pad[b]);
            let box_gap = (0..3)
                .map(|e| {
                    let m = 1e-12 * (ba.lo[e].abs() + ba.hi[e].abs())
                        + 1e-12 * (bb.lo[e].abs() + bb.hi[e].abs())
                        + slack;
                    (bb.lo[e] - ba.hi[e]).max(ba.lo[e] - bb.hi[e]) - m
                })
                .fold(f64::NEG_INFINITY, f64::max);
            let (sa, sb) = (sphere(hulls, spheres, a), sphere(hulls, spheres, b));
            let cheap = box_gap.max((sa.0 - sb.0).norm() - sa.1 - sb.1);
            bound <= one_minus_eta * cheap
        })
    }

    /// The largest certified `α' ≤ α` for the segment `q → q + α dir`
    /// (see the module docs); `excluded` are the link pairs that never
    /// interact, `charts` the step's rotation-vector chart centres. `start`,
    /// when given, is the kinematics at `q` as `Kinematics::update(q,
    /// charts, KinOrder::Pose)` computes it (bit for bit; e.g. the step's
    /// kinematics at `θ^t`), reused instead of evaluated again.
    // Arguments kept separate: the line-search trial's state (q, Δq, α, charts, the reused kinematics), each owned by a different stage of the step.
    #[allow(clippy::too_many_arguments)]
    pub fn certify(
        &mut self,
        model: &Model,
        excluded: &BTreeSet<(usize, usize)>,
        q: &DVector<f64>,
        start: Option<&Kinematics>,
        dir: &DVector<f64>,
        alpha: f64,
        charts: &[Matrix3<f64>],
    ) -> f64 {
        self.seg.clone_from(dir);
        self.seg *= alpha;
        let frac = self.fraction(model, excluded, q, start, charts);
        self.stats.segments += 1;
        if frac < 1.0 {
            self.stats.alpha_caps += 1;
            self.stats.min_alpha = self.stats.min_alpha.min(alpha * frac);
        }
        alpha * frac
    }

    /// The largest certified fraction `β ∈ [0, 1]` of the segment
    /// `q → q + seg`.
    ///
    /// Cost: the lever half of the motion bound (no trigonometry) and one
    /// broad phase decide most segments
    /// ([`Ccd::cleared_by_lever_bound`]); only when they cannot are the
    /// exact start rates computed and the pairs examined as described in
    /// the module docs. Either way the result is the same, bit for bit.
    fn fraction(
        &mut self,
        model: &Model,
        excluded: &BTreeSet<(usize, usize)>,
        q: &DVector<f64>,
        start: Option<&Kinematics>,
        charts: &[Matrix3<f64>],
    ) -> f64 {
        if start.is_none() {
            self.kin.update(model, q, charts, KinOrder::Pose);
        }
        let kin = start.unwrap_or(&self.kin);
        hull_radii(model, &mut self.radius);
        self.motion
            .update_lever(model, &kin.pre, &self.radius, q, &self.seg);
        self.hulls.update(model, &kin.pose);
        hull_boxes(&self.hulls, &mut self.boxes);
        self.spheres.clear();
        self.spheres.resize(self.hulls.ids.len(), None);
        #[cfg(test)]
        let shortcut = self.lever_shortcut;
        #[cfg(not(test))]
        let shortcut = true;
        if shortcut && self.cleared_by_lever_bound(model, excluded) {
            #[cfg(test)]
            {
                self.lever_cleared += 1;
            }
            return 1.0;
        }
        let kin = start.unwrap_or(&self.kin);
        self.motion
            .update_rates(model, &kin.pre, &kin.pose, charts, q, &self.seg);
        self.pad.clear();
        let motion = &self.motion;
        self.pad
            .extend(self.hulls.ids.iter().map(|id| motion.reach(id.link)));
        self.broad.swept_pairs(
            &self.hulls,
            &self.boxes,
            &self.pad,
            excluded,
            &mut self.candidates,
        );
        self.collect_doubts(model);
        self.advance_rounds(model, q, charts)
    }

    /// The candidate pairs whose relative motion may close their gap to
    /// below `η g₀` (`η`: `keep_fraction`): pairs skipped cheaply (no
    /// relative motion, or less than a lower bound of the distance from the
    /// boxes or the bounding spheres) or cleared at once are dropped; the
    /// rest become [`Doubt`]s with their first certified horizon.
    fn collect_doubts(&mut self, model: &Model) {
        let eta = self.options.keep_fraction;
        self.doubt.clear();
        for k in 0..self.candidates.len() {
            let (a, b) = self.candidates[k];
            // Relative motion bound, direction-free (m per unit α).
            let (bound, relative) = pair_bound(
                model,
                &self.depth,
                &self.hulls,
                &self.motion,
                a,
                b,
                &self.motion.spread,
            );
            // Cheap skips: no relative motion, or less than a lower bound of
            // the distance from the boxes or the bounding spheres.
            let (sa, sb) = (
                sphere(&self.hulls, &mut self.spheres, a),
                sphere(&self.hulls, &mut self.spheres, b),
            );
            let cheap = self.box_gap(a, b).max((sa.0 - sb.0).norm() - sa.1 - sb.1);
            if bound == 0.0 || bound <= (1.0 - eta) * cheap {
                continue;
            }
            self.stats.pairs_tested += 1;
            let Some((gap, dir)) = self.gap(a, b, None) else {
                self.stats.uncertified += 1;
                continue;
            };
            let mut d = Doubt {
                a,
                b,
                relative,
                keep: eta * gap,
                gap,
                dir,
                horizon: 0.0,
            };
            if !d.advance(self.rate(&d), 0.0) {
                continue;
            }
            self.stats.pairs_advanced += 1;
            self.doubt.push(d);
        }
    }

    /// Rounds: every pair in doubt is certified up to its horizon; the
    /// segment up to the smallest horizon is certified. Pairs whose
    /// horizon is near it are measured again there (kinematics at the
    /// new α, GJK); the others keep their horizon. Returns the certified
    /// fraction of the segment.
    fn advance_rounds(&mut self, model: &Model, q: &DVector<f64>, charts: &[Matrix3<f64>]) -> f64 {
        let mut alpha = 0.0;
        let mut rounds = 0;
        loop {
            let next = self.doubt.iter().map(|d| d.horizon).fold(1.0, f64::min);
            if next >= 1.0 {
                return 1.0;
            }
            if rounds == self.options.max_rounds || next - alpha <= 1e-12 {
                return next;
            }
            rounds += 1;
            self.stats.rounds += 1;
            self.trial.clone_from(q);
            self.trial.axpy(next, &self.seg, 1.0);
            let soon = (2.0 * next - alpha).min(1.0);
            if !self.measure_again(model, charts, next, soon) {
                // Cannot happen while the bound holds (the gap is at least
                // η g₀ there); stay on the part certified before this round.
                return alpha;
            }
            alpha = next;
        }
    }

    /// Measures again, at `α = next` (the trial point already in
    /// `self.trial`), every pair in doubt whose horizon is below `soon`, and
    /// advances its horizon. Kinematics and world vertices are updated only
    /// for those pairs' links and their ancestors. `false` when a pair's gap
    /// could not be measured (it stays in doubt).
    fn measure_again(
        &mut self,
        model: &Model,
        charts: &[Matrix3<f64>],
        next: f64,
        soon: f64,
    ) -> bool {
        self.needed_link.clear();
        self.needed_link.resize(model.links.len(), false);
        self.needed_hull.clear();
        for d in self.doubt.iter().filter(|d| d.horizon < soon) {
            for h in [d.a, d.b] {
                self.needed_hull.push(h);
                let mut link = Some(self.hulls.ids[h].link);
                while let Some(l) = link.filter(|&l| !self.needed_link[l]) {
                    self.needed_link[l] = true;
                    link = model.links[l].parent;
                }
            }
        }
        self.kin
            .update_poses_where(model, &self.trial, charts, &self.needed_link);
        for &h in &self.needed_hull {
            self.hulls.update_hull(model, &self.kin.pose, h);
        }
        let mut doubt = std::mem::take(&mut self.doubt);
        let mut lost = false;
        doubt.retain_mut(|d| {
            if d.horizon >= soon {
                return true;
            }
            match self.gap(d.a, d.b, Some(d.dir)) {
                Some((gap, dir)) => {
                    d.gap = gap;
                    d.dir = dir;
                    d.advance(self.rate(d), next)
                }
                None => {
                    lost = true;
                    true
                }
            }
        });
        self.doubt = doubt;
        !lost
    }
}

/// Lowest common ancestor of links `a` and `b` (`None`: different trees);
/// `depth` is every link's depth in its tree.
fn common_ancestor(model: &Model, depth: &[usize], mut a: usize, mut b: usize) -> Option<usize> {
    while depth[a] > depth[b] {
        a = model.links[a].parent?;
    }
    while depth[b] > depth[a] {
        b = model.links[b].parent?;
    }
    while a != b {
        a = model.links[a].parent?;
        b = model.links[b].parent?;
    }
    Some(a)
}

/// Bound on the relative motion of hulls `a`, `b` over the segment,
/// direction-free (m per unit α): through their common ancestor's frame
/// when they have one, else the world-frame sum `‖c_a − c_b‖ + E_a + E_b`;
/// `spread` is the per-link `E` to use (`E_i`, or its upper bound `Ē_i`).
/// Also returns the relative bound alone (for [`Doubt::relative`]).
fn pair_bound(
    model: &Model,
    depth: &[usize],
    hulls: &WorldHulls,
    m: &SegmentMotion,
    a: usize,
    b: usize,
    spread: &[f64],
) -> (f64, Option<f64>) {
    let (la, lb) = (hulls.ids[a].link, hulls.ids[b].link);
    let relative = common_ancestor(model, depth, la, lb)
        .map(|c| m.relative_spread(la, c) + m.relative_spread(lb, c));
    let world = (m.drift[la] - m.drift[lb]).norm() + spread[la] + spread[lb];
    (relative.map_or(world, |r| r.min(world)), relative)
}

/// Centroid and bounding radius of hull `h` of `hulls`, cached in
/// `cache[h]` (`√(max ‖v − c‖²)` is bit for bit `max ‖v − c‖`, see
/// [`hull_radii`]).
fn sphere(
    hulls: &WorldHulls,
    cache: &mut [Option<(Vector3<f64>, f64)>],
    h: usize,
) -> (Vector3<f64>, f64) {
    if let Some(s) = cache[h] {
        return s;
    }
    let x = hulls.hull(h);
    let c = x.iter().sum::<Vector3<f64>>() / x.len().max(1) as f64;
    let r = x
        .iter()
        .map(|v| (v - c).norm_squared())
        .fold(0.0, f64::max)
        .sqrt();
    cache[h] = Some((c, r));
    (c, r)
}

impl Doubt {
    /// Sets the horizon from the gap measured at `at` and the closing rate
    /// `rate`: `at + (g − η g₀)/ρ`. Returns false when that covers the
    /// rest of the segment (the pair is cleared).
    fn advance(&mut self, rate: f64, at: f64) -> bool {
        let slack = (self.gap - self.keep).max(0.0);
        if rate * (1.0 - at) <= slack {
            return false;
        }
        self.horizon = at + slack / rate;
        true
    }
}

#[cfg(test)]
#[path = "ccd_tests.rs"]
mod tests;
