//! Separating-plane friction term `Σ_{pairs} U_f` (paper, `friction.tex`).
//!
//! At the start of each step the contact planes, normal forces and tangent
//! bases are computed at the step-`t` poses and frozen (lagged, as in the
//! paper); every Newton evaluation then solves each active pair's inner
//! problem over the plane's in-plane velocity `u` and spin `ω`.
//! The lagged planes are recomputed here (value-only contact solves, warm
//! started) rather than borrowed from the contact term, which keeps the two
//! terms independent; it costs one contact evaluation per step.
//!
//! Normal forces include the stiffness `κ`, so `U_f` is not multiplied by
//! `κ` again (the paper's eq. `SDRS` scales both sums by one constant; the
//! two conventions agree for forces ≫ `√ε_f`).

use super::pairs::scatter_pair;
use super::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::contact::{
    self, ContactParams, ContactScratch, FrictionNeed, FrictionParams, FrictionScratch, HullPose,
    LaggedContact, PairOutcome,
};
use crate::geometry::{BroadPhase, WorldHulls};
use crate::kinematics::Kinematics;
use crate::model::Model;
use crate::scene::ContactSettings;
use nalgebra::{DVector, Vector4};
use rayon::prelude::*;
use std::collections::{BTreeMap, HashMap};

/// A hull pair (indices into the world hulls) in contact at step `t` and its lagged data.
type LaggedPair = ((usize, usize), LaggedContact);

/// The friction term.
pub struct FrictionEnergy {
    pub settings: ContactSettings,
    pub contact: ContactParams,
    pub friction: FrictionParams,
    hulls: WorldHulls,
    broad: BroadPhase,
    pairs: Vec<(usize, usize)>,
    warm: HashMap<(usize, usize), Vector4<f64>>,
    /// Lagged data of the pairs in contact at step `t`.
    lagged: Vec<((usize, usize), LaggedContact)>,
    results: Vec<Result<contact::FrictionPair, contact::FrictionError>>,
    pair_slots: BTreeMap<(usize, usize), usize>,
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
            hulls: WorldHulls::new(model),
            broad: BroadPhase::default(),
            pairs: Vec::new(),
            warm: HashMap::new(),
            lagged: Vec::new(),
            results: Vec::new(),
            pair_slots: BTreeMap::new(),
        }
    }

    fn hull_pose<'a>(
        &self,
        model: &'a Model,
        poses: &'a [crate::math::Pose],
        h: usize,
    ) -> HullPose<'a> {
        let id = self.hulls.ids[h];
        HullPose {
            pose: &poses[id.link],
            x_local: &model.links[id.link].hulls[id.hull].x_local,
        }
    }
}

impl Energy for FrictionEnergy {
    fn name(&self) -> &'static str {
        "friction"
    }

    fn begin_step(&mut self, ctx: &StepContext, _kin_prev: &Kinematics) -> Result<(), EnergyError> {
        let model = ctx.model;
        let poses = ctx.poses_prev;
        self.hulls.update(model, poses);
        self.broad.candidate_pairs(
            &self.hulls,
            self.contact.support_distance(),
            &self.settings.excluded,
            &mut self.pairs,
        );
        let this = &*self;
        let kappa = self.settings.kappa;
        let lagged: Vec<Result<Option<LaggedPair>, EnergyError>> = self
            .pairs
            .par_iter()
            .map_init(ContactScratch::new, |scratch, &(a, b)| {
                let (pa, pb) = (
                    this.hull_pose(model, poses, a),
                    this.hull_pose(model, poses, b),
                );
                let warm = this.warm.get(&(a, b)).copied();
                match contact::contact_pair(
                    pa,
                    pb,
                    &this.contact,
                    warm,
                    contact::Need::Value,
                    scratch,
                ) {
                    Ok(PairOutcome::Separated(c)) => Ok(Some((
                        (a, b),
                        LaggedContact::from_contact(&c, pa, pb, &this.contact, kappa),
                    ))),
                    Ok(_) => Ok(None),
                    Err(e) => {
                        let case = contact::capture::ContactCase::new(
                            pa,
                            pb,
                            &this.contact,
                            warm,
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
            })
            .collect();
        self.lagged.clear();
        self.warm.clear();
        for item in lagged {
            if let Some((key, lag)) = item? {
                self.lagged.push((key, lag));
            }
        }
        Ok(())
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
        let pose = |h: usize| {
            let id = hulls.ids[h];
            HullPose {
                pose: &kin.pose[id.link],
                x_local: &model.links[id.link].hulls[id.hull].x_local,
            }
        };
        self.lagged
            .par_iter()
            .map_init(FrictionScratch::new, |scratch, ((a, b), lag)| {
                let frame = lag.frame();
                let res =
                    contact::friction_pair(&frame, pose(*a), pose(*b), friction, fneed, scratch);
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
            })
            .collect_into_vec(&mut self.results);
        self.pair_slots.clear();
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
                &mut self.pair_slots,
                need,
                links,
                1.0,
                (&f.grad_a, &f.grad_b),
                f.hessian.as_ref(),
            );
        }
        Ok(())
    }
}
