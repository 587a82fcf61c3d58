//! Separating-plane contact term `κ Σ_{pairs} U_c` (paper, eq. `SDRS` and
//! `contact.tex`) over every hull pair on different, non-excluded links.
//!
//! Stages per evaluation: world vertices → broad phase (boxes inflated by
//! `2s/(1−s)`) → narrow phase, one [`contact_pair`](crate::contact::contact_pair) per candidate, in
//! parallel (rayon) in fixed chunks balanced by vertex count when there is
//! enough work ([`PairWork`]), results reduced in pair order (bitwise the
//! same for any thread count) → scatter into pose space. An intersecting pair makes the
//! energy `+∞`, so Newton's line search rejects the trial point and an
//! interpenetrating state is never accepted. Each pair's optimal plane warm
//! starts its next solve (used only when still strictly feasible).
//!
//! Adjoint ([`Energy::vjp`]): per separated pair, the world-vertex
//! Hessian–vector product of `U_c` (implicit-function-theorem Schur
//! complement, `O(M)`) and `∂(∇_X U_c·δX)/∂s` from
//! [`contact::contact_vjp`], scattered to pose and local-vertex space.

use super::pairs::{scatter_pair, scatter_vertex_products, vertices_and_directions};
use super::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::contact::ContactSettings;
use crate::contact::ccd::Ccd;
use crate::contact::separation::{self, Separation};
use crate::contact::{self, ContactParams, ContactScratch, PairOutcome};
use crate::counters::{Stage, StageTimers, StepDiagnostics};
use crate::geometry::{BroadPhase, PairWork, WorldHulls};
use crate::kinematics::Kinematics;
use crate::math::Pose;
use crate::model::Model;
use nalgebra::{DVector, Vector4};
use std::collections::HashMap;
use std::time::{Duration, Instant};

/// A candidate hull pair and the plane its solve starts from.
type PairStart = ((usize, usize), Option<Vector4<f64>>);

/// The contact term.
pub struct ContactEnergy {
    pub settings: ContactSettings,
    pub params: ContactParams,
    hulls: WorldHulls,
    broad: BroadPhase,
    pairs: Vec<(usize, usize)>,
    /// The support range and link poses `hulls` and `pairs` were computed
    /// for (range NaN: never).
    pairs_key: (f64, Vec<Pose>),
    /// Link-frame box of every hull (see [`WorldHulls::enclosing_box`]).
    local_boxes: Vec<(nalgebra::Vector3<f64>, nalgebra::Vector3<f64>)>,
    /// World boxes of the last broad phase.
    boxes: Vec<crate::geometry::Aabb>,
    /// Whether hull `h`'s world vertices in `hulls` are those of the last
    /// broad phase's poses (the candidates' are; the others are stale).
    fresh: Vec<bool>,
    results: Vec<Result<PairOutcome, contact::ContactError>>,
    /// Vertex-balanced chunks of the pair evaluations (see [`PairWork`]).
    work: PairWork<Result<PairOutcome, contact::ContactError>>,
    warm: HashMap<(usize, usize), Vector4<f64>>,
    /// Each candidate pair with the plane its solve starts from at this
    /// evaluation (see [`ContactEnergy::start_planes`]).
    starts: Vec<PairStart>,
    /// Evaluations so far at the poses of `pairs_key`.
    evals_here: usize,
    /// Time spent in the broad phase since the last [`ContactEnergy::take_broad_phase_time`].
    broad_time: Duration,
    /// Statistics of the last evaluation.
    last_active: usize,
    /// The first intersecting pair of the last evaluation.
    last_intersecting: Option<(usize, usize)>,
    /// Continuous collision detection of the line search ([`Energy::max_step`]).
    ccd: Ccd,
    /// Time spent in CCD since the last report.
    ccd_time: Duration,
    /// The vertices' directions of [`Energy::line_pairs`] (scratch).
    line_dx: Vec<nalgebra::Vector3<f64>>,
}

impl ContactEnergy {
    pub fn new(model: &Model, settings: ContactSettings) -> Self {
        ContactEnergy {
            params: ContactParams::with_width(settings.s),
            local_boxes: WorldHulls::new(model).local_boxes(model),
            boxes: Vec::new(),
            fresh: Vec::new(),
            hulls: WorldHulls::new(model),
            broad: BroadPhase::default(),
            pairs: Vec::new(),
            pairs_key: (f64::NAN, Vec::new()),
            results: Vec::new(),
            work: PairWork::default(),
            warm: HashMap::new(),
            starts: Vec::new(),
            evals_here: 0,
            broad_time: Duration::ZERO,
            last_active: 0,
            last_intersecting: None,
            ccd: Ccd::new(model, settings.ccd.clone()),
            ccd_time: Duration::ZERO,
            line_dx: Vec::new(),
            settings,
        }
    }

    /// Candidate pairs at `poses` (boxes from the link-frame boxes, see
    /// [`WorldHulls::enclosing_box`]) and the candidates' world vertices,
    /// recomputed only when the poses or the support range differ bit for
    /// bit from those of the last computation (a Newton iteration
    /// re-evaluates its accepted trial point with derivatives: the same
    /// poses). The pairs are a function of the poses, the range and the
    /// fixed exclusions, so the result is the same bits either way.
    /// Returns whether they were recomputed (the poses are new).
    fn update_pairs(&mut self, model: &Model, poses: &[Pose]) -> bool {
        let range = self.params.support_distance();
        if self.pairs_key.0.to_bits() == range.to_bits() && self.last_at(poses) {
            return false;
        }
        self.hulls
            .enclosing_boxes(&self.local_boxes, poses, &mut self.boxes);
        self.broad.candidate_pairs_of_boxes(
            &self.hulls,
            &self.boxes,
            range,
            &self.settings.excluded,
            &mut self.pairs,
        );
        // World vertices of the candidates only: the pair evaluations take
        // them (`contact_pair_world`), the diagnostics and the infeasibility
        // report read them.
        self.fresh.clear();
        self.fresh.resize(self.hulls.ids.len(), false);
        for &(a, b) in &self.pairs {
            for h in [a, b] {
                if !self.fresh[h] {
                    self.fresh[h] = true;
                    self.hulls.update_hull(model, poses, h);
                }
            }
        }
        self.pairs_key.0 = range;
        self.pairs_key.1.clear();
        self.pairs_key.1.extend_from_slice(poses);
        true
    }

    /// Whether the last computation of `pairs` was at exactly `poses`, bit
    /// for bit (pose by pose: a `flat_map` over all the entries cost ~15
    /// instructions per entry).
    fn last_at(&self, poses: &[Pose]) -> bool {
        let key = &self.pairs_key.1;
        key.len() == poses.len()
            && key.iter().zip(poses).all(|(a, b)| {
                a.as_slice()
                    .iter()
                    .zip(b.as_slice())
                    .all(|(x, y)| x.to_bits() == y.to_bits())
            })
    }

    /// The planes this evaluation's pair solves start from, into `starts`.
    ///
    /// The first evaluation at new poses starts from the warm planes (the
    /// last solves' results); the second from the first one's results
    /// (typically the solution already). Every later evaluation at the same
    /// poses starts where the second did, so it repeats the second's solves
    /// bit for bit: from the second evaluation on, the result does not
    /// depend on how often the point was evaluated (Newton may evaluate an
    /// accepted point with the gradient and then again with the Hessian,
    /// see [`crate::sim::newton`]). The first and the second evaluation can
    /// differ by the plane solves' round-off, so evaluating a point once
    /// instead of twice moves the iterates at round-off (measured in
    /// notes/performance.md, 2026-12-07, twenty-first session).
    fn start_planes(&mut self, new_poses: bool) {
        if new_poses {
            self.evals_here = 0;
        }
        if self.evals_here < 2 {
            let warm = &self.warm;
            self.starts.clear();
            self.starts
                .extend(self.pairs.iter().map(|&p| (p, warm.get(&p).copied())));
        }
        self.evals_here += 1;
    }

    /// The smallest GJK distance estimate over the last evaluation's
    /// candidate pairs (as a cold start reports it). A warm-started pair
    /// carries only a lower bound (the slab gap along its plane), so the
    /// pairs are visited in increasing lower bound and GJK runs until the
    /// next bound is no smaller than the best distance found: usually once.
    fn min_distance(&self) -> f64 {
        let mut order: Vec<(f64, usize)> = self
            .results
            .iter()
            .enumerate()
            .filter_map(|(k, r)| match r {
                Ok(PairOutcome::Separated(c)) => Some((c.distance, k)),
                Ok(PairOutcome::OutOfRange { distance, .. }) => Some((*distance, k)),
                _ => None,
            })
            .collect();
        order.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        let mut best = f64::INFINITY;
        let mut simplex = parry3d_f64::query::gjk::VoronoiSimplex::new();
        for (lower, k) in order {
            if lower >= best {
                break;
            }
            let (a, b) = self.pairs[k];
            let exact = match separation::separate(
                self.hulls.hull(a),
                self.hulls.hull(b),
                None,
                &mut simplex,
            ) {
                Ok(Separation::Separated { distance, .. }) => distance,
                _ => lower,
            };
            best = best.min(exact.max(lower));
        }
        best
    }

    fn describe(&self, model: &Model, h: usize) -> String {
        let id = self.hulls.ids[h];
        let l = &model.links[id.link];
        format!("{}/{} hull {}", model.robots[l.robot].name, l.name, id.hull)
    }
}

impl Energy for ContactEnergy {
    fn name(&self) -> &'static str {
        "contact"
    }

    fn kind(&self) -> crate::energy::TermKind {
        crate::energy::TermKind::Contact
    }

    fn explain_infeasible(&self, model: &Model) -> Option<String> {
        let (a, b) = self.last_intersecting?;
        let depth = contact::separation::penetration_depth(self.hulls.hull(a), self.hulls.hull(b))
            .map(|d| format!("penetration depth {d:.3e} m"))
            .unwrap_or_else(|| "touching".into());
        let name = |h: usize| {
            let l = &model.links[self.hulls.ids[h].link];
            format!("{}/{}", model.robots[l.robot].name, l.name)
        };
        Some(format!(
            "{} and {} intersect ({depth}); if they overlap by design, exclude the pair (`contact: {{exclude: [[\"{}\", \"{}\"]]}}`), otherwise change the initial pose",
            self.describe(model, a),
            self.describe(model, b),
            name(a),
            name(b),
        ))
    }

    fn accumulate(
        &mut self,
        ctx: &StepContext,
        _q: &DVector<f64>,
        kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        let model = ctx.model;
        let t0 = ctx.timed.then(Instant::now);
        let new_poses = self.update_pairs(model, &kin.pose);
        self.broad_time += t0.map_or(Duration::ZERO, |t| t.elapsed());
        self.start_planes(new_poses);

        let cneed = match need {
            Need::Value => contact::Need::Value,
            Need::Gradient => contact::Need::Gradient,
            Need::Hessian => contact::Need::Hessian,
        };
        let (hulls, params) = (&self.hulls, &self.params);
        let pose = |h: usize| hulls.hull_pose(model, &kin.pose, h);
        self.work.map(
            &self.starts,
            |&((a, b), _)| hulls.ranges[a].len() + hulls.ranges[b].len(),
            ContactScratch::new,
            |scratch, &((a, b), w)| {
                // The candidates' world vertices are those of these poses
                // (`update_pairs`), in the bits `contact_pair` would compute.
                let (xa, xb) = (hulls.hull(a), hulls.hull(b));
                let placed = |hull, world| contact::PlacedHull { hull, world };
                let res = contact::contact_pair_world(
                    placed(pose(a), xa),
                    placed(pose(b), xb),
                    params,
                    w,
                    cneed,
                    scratch,
                );
                if let Err(e) = &res {
                    let case =
                        contact::capture::ContactCase::new(pose(a), pose(b), params, w, cneed, e);
                    contact::capture::dump("contact", &case);
                }
                res
            },
            &mut self.results,
        );

        self.last_intersecting = None;
        let mut active = 0;
        // A value-only evaluation is a line-search trial point: if a pair's
        // inner solve fails there, the point is rejected like an infeasible
        // one (+∞) and the search backtracks. Where derivatives are needed
        // (accepted iterates) a failure is an error.
        if need == Need::Value && self.results.iter().any(|r| r.is_err()) {
            acc.value = f64::INFINITY;
            return Ok(());
        }
        for (k, res) in self.results.iter().enumerate() {
            let (a, b) = self.pairs[k];
            let outcome = res.as_ref().map_err(|e| EnergyError::Failed {
                term: "contact",
                msg: format!(
                    "{} vs {}: {e}",
                    self.describe(model, a),
                    self.describe(model, b)
                ),
            })?;
            match outcome {
                PairOutcome::Intersecting => {
                    self.last_intersecting = Some((a, b));
                    acc.value = f64::INFINITY;
                    return Ok(());
                }
                PairOutcome::OutOfRange { plane, .. } => {
                    self.warm.insert((a, b), *plane);
                }
                PairOutcome::Separated(c) => {
                    active += 1;
                    self.warm.insert((a, b), c.plane);
                    let kappa = self.settings.kappa;
                    acc.value += kappa * c.value;
                    let links = (self.hulls.ids[a].link, self.hulls.ids[b].link);
                    scatter_pair(
                        model,
                        acc,
                        need,
                        links,
                        kappa,
                        (&c.grad_a, &c.grad_b),
                        c.hessian.as_deref(),
                    );
                }
            }
        }
        self.last_active = active;
        Ok(())
    }

    /// Per separated pair, with `Φ = κ Σ_m ⟨∂U_c/∂X_m, δX_m⟩` (`δX_m = δA x̃_m`), from
    /// [`contact::contact_vjp`] (world-vertex Hessian–vector product by the IFT Schur
    /// complement, and `∂/∂s`): `∂Φ/∂A^t = κ Σ_m (∂²U_c/∂X² δX)_m x̃_mᵀ` for both links
    /// (static ones included, for their attachment gradient), `∂Φ/∂x_m = κ (Rᵀ(∂²U_c/∂X² δX)_m
    /// + δRᵀ ∂U_c/∂X_m)`, `∂Φ/∂κ = Φ/κ`, `∂Φ/∂s = κ ∂(∇_X U_c·δX)/∂s`.
    fn vjp(
        &mut self,
        ctx: &StepContext,
        q: &DVector<f64>,
        kin: &Kinematics,
        dir: &crate::energy::vjp::AdjointDirection,
        out: &mut crate::energy::vjp::VjpAccumulator,
    ) -> Result<(), EnergyError> {
        let model = ctx.model;
        let mut tmp = EnergyAccumulator::new(model);
        // Re-solves the planes at θ^t (warm started: typically no inner iteration).
        self.accumulate(ctx, q, kin, Need::Value, &mut tmp)?;
        if !tmp.value.is_finite() {
            return Err(EnergyError::Failed {
                term: "contact",
                msg: "intersecting state in the backward pass".into(),
            });
        }
        let kappa = self.settings.kappa;
        let s = self.params.s;
        let want_vertices = out.want_vertices;
        for (k, res) in self.results.iter().enumerate() {
            let Ok(PairOutcome::Separated(c)) = res else {
                continue;
            };
            let (a, b) = self.pairs[k];
            let ids = [self.hulls.ids[a], self.hulls.ids[b]];
            let local = |h: usize| &model.links[ids[h].link].hulls[ids[h].hull].x_local;
            let (xa, dxa) =
                vertices_and_directions(local(0), &kin.pose[ids[0].link], &dir.dpose[ids[0].link]);
            let (xb, dxb) =
                vertices_and_directions(local(1), &kin.pose[ids[1].link], &dir.dpose[ids[1].link]);
            let v = contact::contact_vjp(&xa, &xb, &c.plane, s, &dxa, &dxb);
            out.physical.kappa += v.phi;
            out.physical.s += kappa * v.ds;
            for (h, (hvp, grad)) in [(&v.hvp_a, &v.grad_a), (&v.hvp_b, &v.grad_b)]
                .into_iter()
                .enumerate()
            {
                let id = ids[h];
                scatter_vertex_products(
                    local(h),
                    &kin.pose[id.link],
                    Some(&dir.dpose[id.link]),
                    hvp,
                    Some(grad),
                    kappa,
                    &mut out.pose[id.link],
                    want_vertices.then(|| &mut out.vertex[id.link][id.hull][..]),
                );
            }
        }
        Ok(())
    }

    /// One [`contact::PlaneLine`] per separated pair of the last evaluation, scaled by `κ`,
    /// along the vertices' first-order motion `δX = Ω X + v` (`[Ω | v]` the link's twist; see
    /// [`contact::line_model`]); `false` when that evaluation was not at `kin`'s poses (the
    /// world vertices in `hulls` are those poses' when it was).
    fn line_pairs(
        &mut self,
        _ctx: &StepContext,
        kin: &Kinematics,
        twists: &mut super::StepTwists,
        out: &mut Vec<contact::PlaneLine>,
    ) -> bool {
        if !self.last_at(&kin.pose) || self.results.len() != self.pairs.len() {
            return false;
        }
        for (k, res) in self.results.iter().enumerate() {
            let Ok(PairOutcome::Separated(c)) = res else {
                continue;
            };
            let (a, b) = self.pairs[k];
            let twists = twists.get();
            let moving = |h: usize| {
                let s = &twists[self.hulls.ids[h].link];
                let (w, v) = (s.fixed_view::<3, 3>(0, 0), s.column(3));
                self.hulls.hull(h).iter().map(move |x| w * x + v)
            };
            self.line_dx.clear();
            self.line_dx.extend(moving(a));
            let na = self.line_dx.len();
            self.line_dx.extend(moving(b));
            let (xa, xb) = (self.hulls.hull(a), self.hulls.hull(b));
            let (dxa, dxb) = self.line_dx.split_at(na);
            let scale = self.settings.kappa;
            out.push(contact::PlaneLine::new(
                xa,
                xb,
                dxa,
                dxb,
                &c.plane,
                self.params.s,
                scale,
            ));
        }
        true
    }

    fn certifies(&self) -> bool {
        self.ccd.options.enabled
    }

    /// Continuous collision detection (see [`crate::contact::ccd`]) of the
    /// accepted segment `q → q + α dq`: the largest certified `α' ≤ α`
    /// along which no hull pair can touch; `α` when
    /// [`crate::contact::ccd::CcdOptions::enabled`] is off. Adds no term to
    /// the objective. Timed into the `ccd` stage.
    fn certify_step(
        &mut self,
        ctx: &StepContext,
        q: &DVector<f64>,
        start: Option<&Kinematics>,
        dq: &DVector<f64>,
        alpha: f64,
        charts: &[nalgebra::Matrix3<f64>],
    ) -> Result<f64, EnergyError> {
        if !self.ccd.options.enabled {
            return Ok(alpha);
        }
        let t0 = ctx.timed.then(Instant::now);
        let out = self.ccd.certify(
            ctx.model,
            &self.settings.excluded,
            q,
            start,
            dq,
            alpha,
            charts,
        );
        self.ccd_time += t0.map_or(Duration::ZERO, |t| t.elapsed());
        Ok(out)
    }

    fn report(&mut self, d: &mut StepDiagnostics, timers: &mut StageTimers) {
        if self.ccd.options.enabled {
            d.ccd.merge(&std::mem::take(&mut self.ccd.stats));
            timers.add(Stage::Ccd, std::mem::take(&mut self.ccd_time));
        }
        d.contact_pairs = self.last_active;
        let exact = self.min_distance();
        d.min_distance = d.min_distance.min(exact);
        timers.carve(Stage::BroadPhase, std::mem::take(&mut self.broad_time));
    }
}
