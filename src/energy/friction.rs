//! Separating-plane friction term `Σ_{pairs} U_f` (paper, `friction.tex`).
//!
//! At the start of each step the contact planes, normal forces and tangent
//! bases are computed at the step-`t` poses and frozen (lagged, as in the
//! paper); every Newton evaluation then solves each active pair's inner
//! problem over the plane's in-plane velocity `u` and spin `ω` — once per
//! distinct pair of poses: an evaluation at bit-for-bit the poses of the
//! pair's last one (Newton's Hessian after a gradient-first evaluation of an
//! accepted point) takes that solve's result ([`contact::friction_pair_memo`]),
//! which is the same bits.
//! The lagged planes are recomputed here (value-only contact solves, cold
//! started) rather than borrowed from the contact term, which keeps the two
//! terms independent; it costs one contact evaluation per step (sharing the
//! contact term's planes was tried and reverted, `59bdafb`: the spider's
//! short-horizon FD check failed on it).
//!
//! Normal forces include the stiffness `κ`, so `U_f` is not multiplied by
//! `κ` again (the paper's eq. `SDRS` scales both sums by one constant; the
//! two conventions agree for forces ≫ `√ε_f`).
//!
//! Adjoint ([`Energy::vjp`]): [`contact::friction_vjp`] differentiates `Φ`
//! w.r.t. the current vertices, the lagged vertices — directly and through
//! the lagged plane solve (normal, basis, normal forces) — and `μ`, `κ`, `s`.
//! The lagged plane `p*` is kept with each pair for that purpose; the
//! backward pass re-runs [`Energy::begin_step`] of the step before `vjp`.

use super::pairs::{scatter_pair, scatter_vertex_products, vertices_and_directions};
use super::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::contact::ContactSettings;
use crate::contact::{
    self, ContactParams, ContactScratch, FrictionMemo, FrictionNeed, FrictionParams,
    FrictionScratch, LaggedContact, PairOutcome,
};
use crate::geometry::{BroadPhase, PairWork, WorldHulls};
use crate::kinematics::Kinematics;
use crate::model::Model;
use nalgebra::{DVector, Vector4};
use std::sync::Mutex;

/// A hull pair (indices into the world hulls) in contact at step `t`, its
/// lagged data, the step-`t` plane `p*` it came from (for the adjoint) and
/// its last inner solution (see [`contact::friction_pair_memo`]; a `Mutex`
/// because the pairs are evaluated in parallel, each by one thread).
type LaggedPair = (
    (usize, usize),
    LaggedContact,
    Vector4<f64>,
    Mutex<FrictionMemo>,
);

/// The friction term.
pub struct FrictionEnergy {
    pub settings: ContactSettings,
    pub contact: ContactParams,
    pub friction: FrictionParams,
    /// The collision hulls (ids and ranges; their world vertices are not
    /// kept: the pairs use the link poses).
    hulls: WorldHulls,
    /// Link-frame box of every hull (see [`WorldHulls::enclosing_box`]).
    local_boxes: Vec<(nalgebra::Vector3<f64>, nalgebra::Vector3<f64>)>,
    /// World boxes of the last broad phase.
    boxes: Vec<crate::geometry::Aabb>,
    broad: BroadPhase,
    pairs: Vec<(usize, usize)>,
    /// Lagged data of the pairs in contact at step `t`, with the optimal world plane `p*`
    /// it was built from (needed by the adjoint).
    lagged: Vec<LaggedPair>,
    results: Vec<Result<contact::FrictionPair, contact::FrictionError>>,
    /// Vertex-balanced chunks of the pair evaluations (see [`PairWork`]).
    work: PairWork<Result<contact::FrictionPair, contact::FrictionError>>,
    /// The same for the lagged contact solves of [`Energy::begin_step`].
    begin_work: PairWork<Result<Option<LaggedPair>, EnergyError>>,
    lagged_work: Vec<Result<Option<LaggedPair>, EnergyError>>,
}

impl FrictionEnergy {
    pub fn new(model: &Model, settings: ContactSettings, dt: f64) -> Self {
        let mut friction = FrictionParams::new(settings.mu, dt);
        friction.eps_velocity = settings.eps;
        friction.eps_force = settings.eps_force;
        FrictionEnergy {
            contact: ContactParams::with_width(settings.s),
            friction,
            settings,
            local_boxes: WorldHulls::new(model).local_boxes(model),
            boxes: Vec::new(),
            hulls: WorldHulls::new(model),
            broad: BroadPhase::default(),
            pairs: Vec::new(),
            lagged: Vec::new(),
            results: Vec::new(),
            work: PairWork::default(),
            begin_work: PairWork::default(),
            lagged_work: Vec::new(),
        }
    }
}

impl Energy for FrictionEnergy {
    fn name(&self) -> &'static str {
        "friction"
    }

    fn kind(&self) -> crate::energy::TermKind {
        crate::energy::TermKind::Friction
    }

    fn begin_step(&mut self, ctx: &StepContext, _kin_prev: &Kinematics) -> Result<(), EnergyError> {
        let model = ctx.model;
        let poses = ctx.poses_prev;
        // Boxes from the link-frame boxes (no vertex transformed): the pairs
        // are a superset of the tight boxes' ones, and the extra pairs are out
        // of range, so they add nothing to the lagged contacts.
        self.hulls
            .enclosing_boxes(&self.local_boxes, poses, &mut self.boxes);
        self.broad.candidate_pairs_of_boxes(
            &self.hulls,
            &self.boxes,
            self.contact.support_distance(),
            &self.settings.excluded,
            &mut self.pairs,
        );
        let (hulls, params) = (&self.hulls, &self.contact);
        let kappa = self.settings.kappa;
        let mut lagged = std::mem::take(&mut self.lagged_work);
        self.begin_work.map(
            &self.pairs,
            |&(a, b)| hulls.ranges[a].len() + hulls.ranges[b].len(),
            ContactScratch::new,
            |scratch, &(a, b)| {
                let (pa, pb) = (
                    hulls.hull_pose(model, poses, a),
                    hulls.hull_pose(model, poses, b),
                );
                match contact::contact_pair(pa, pb, params, None, contact::Need::Value, scratch) {
                    Ok(PairOutcome::Separated(c)) => Ok(Some((
                        (a, b),
                        LaggedContact::from_contact(&c, pa, pb, params, kappa),
                        c.plane,
                        Mutex::new(FrictionMemo::default()),
                    ))),
                    Ok(_) => Ok(None),
                    Err(e) => {
                        let case = contact::capture::ContactCase::new(
                            pa,
                            pb,
                            params,
                            None,
                            contact::Need::Value,
                            &e,
                        );
                        contact::capture::dump("contact", &case);
                        Err(EnergyError::Failed {
                            term: "friction",
                            msg: format!("lagged contact: {e}"),
                        })
                    }
                }
            },
            &mut lagged,
        );
        self.lagged.clear();
        let mut out = Ok(());
        for item in lagged.drain(..) {
            match item {
                Ok(Some(lag)) => self.lagged.push(lag),
                Ok(None) => {}
                Err(e) => {
                    out = Err(e);
                    break;
                }
            }
        }
        lagged.clear();
        self.lagged_work = lagged;
        out
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
        let fneed = match need {
            Need::Value => FrictionNeed::Value,
            Need::Gradient => FrictionNeed::Gradient,
            Need::Hessian => FrictionNeed::Hessian,
        };
        let (hulls, friction) = (&self.hulls, &self.friction);
        let pose = |h: usize| hulls.hull_pose(model, &kin.pose, h);
        self.work.map(
            &self.lagged,
            |((a, b), _, _, _)| hulls.ranges[*a].len() + hulls.ranges[*b].len(),
            || (),
            |_, ((a, b), lag, _, memo)| {
                let frame = lag.frame();
                // Each pair is evaluated by one thread: the lock is never contended.
                let mut memo = memo.lock().unwrap_or_else(|e| e.into_inner());
                let res = contact::friction_pair_memo(
                    &frame,
                    pose(*a),
                    pose(*b),
                    friction,
                    fneed,
                    &mut memo,
                );
                if let Err(e) = &res {
                    let case = contact::capture::FrictionCase::new(
                        &frame,
                        pose(*a),
                        pose(*b),
                        friction,
                        fneed,
                        e,
                    );
                    contact::capture::dump("friction", &case);
                }
                res
            },
            &mut self.results,
        );
        // As in the contact term: an unsolvable inner problem at a
        // line-search trial point rejects the point.
        if need == Need::Value && self.results.iter().any(|r| r.is_err()) {
            acc.value = f64::INFINITY;
            return Ok(());
        }
        for (k, res) in self.results.iter().enumerate() {
            let f = res.as_ref().map_err(|e| EnergyError::Failed {
                term: "friction",
                msg: e.to_string(),
            })?;
            let (a, b) = self.lagged[k].0;
            acc.value += f.value;
            let links = (self.hulls.ids[a].link, self.hulls.ids[b].link);
            scatter_pair(
                model,
                acc,
                need,
                links,
                1.0,
                (&f.grad_a, &f.grad_b),
                f.hessian.as_deref(),
            );
        }
        Ok(())
    }

    /// Per lagged pair, with `Φ = Σ_m ⟨∂U_f/∂X'_m, δX'_m⟩`, from
    /// [`contact::friction_vjp`]: `∂Φ/∂A^t` and `∂Φ/∂x_local` through the current vertices
    /// (Hessian–vector product and the `δX' = δA x̃` term), `∂Φ/∂A^{t−1}` and `∂Φ/∂x_local`
    /// through the lagged vertices — directly and through the lagged plane, normal and
    /// normal forces (implicit function theorem on the step-`t−1` plane solve) — and
    /// `∂Φ/∂μ`, `∂Φ/∂κ`, `∂Φ/∂s`. Static links receive pose gradients too (for their
    /// attachment gradient).
    fn vjp(
        &mut self,
        ctx: &StepContext,
        _q: &DVector<f64>,
        kin: &Kinematics,
        dir: &crate::energy::vjp::AdjointDirection,
        out: &mut crate::energy::vjp::VjpAccumulator,
    ) -> Result<(), EnergyError> {
        let model = ctx.model;
        let s = self.contact.s;
        let kappa = self.settings.kappa;
        let want_vertices = out.want_vertices;
        let mut scratch = FrictionScratch::new();
        for ((a, b), lag, plane, _) in &self.lagged {
            let ids = [self.hulls.ids[*a], self.hulls.ids[*b]];
            let local = |h: usize| &model.links[ids[h].link].hulls[ids[h].hull].x_local;
            let (xa, dxa) =
                vertices_and_directions(local(0), &kin.pose[ids[0].link], &dir.dpose[ids[0].link]);
            let (xb, dxb) =
                vertices_and_directions(local(1), &kin.pose[ids[1].link], &dir.dpose[ids[1].link]);
            let v = contact::friction_vjp(
                lag,
                plane,
                s,
                kappa,
                &xa,
                &xb,
                &self.friction,
                &dxa,
                &dxb,
                &mut scratch,
            )
            .map_err(|e| EnergyError::Failed {
                term: "friction",
                msg: format!("backward pass: {e}"),
            })?;
            out.physical.mu += v.mu;
            out.physical.kappa += v.kappa;
            out.physical.s += v.s;
            let sides = [
                (&v.next_a, &v.grad_a, &v.prev_a),
                (&v.next_b, &v.grad_b, &v.prev_b),
            ];
            for (h, (next, grad, prev)) in sides.into_iter().enumerate() {
                let id = ids[h];
                scatter_vertex_products(
                    local(h),
                    &kin.pose[id.link],
                    Some(&dir.dpose[id.link]),
                    next,
                    Some(grad),
                    1.0,
                    &mut out.pose[id.link],
                    want_vertices.then(|| &mut out.vertex[id.link][id.hull][..]),
                );
                scatter_vertex_products(
                    local(h),
                    &ctx.poses_prev[id.link],
                    None,
                    prev,
                    None,
                    1.0,
                    &mut out.pose_prev[id.link],
                    want_vertices.then(|| &mut out.vertex[id.link][id.hull][..]),
                );
            }
        }
        Ok(())
    }
}
