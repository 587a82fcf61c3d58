//! Joint limits as a barrier term of the step objective (the SDRS way: the
//! barrier keeps the Newton iterate inside, and the line search's
//! `max_step` keeps every trial point inside):
//!
//! ```text
//! L(θ) = Σ_k κ_k [P_s(θ_k − lo_k) + P_s(hi_k − θ_k)]            (J)
//! ```
//!
//! over the limited coordinates `k` (revolute: rad, prismatic: m), with the
//! SDRS barrier `P_s(x) = (x − s)⁴/x⁵` on `0 < x < s`, zero for `x ≥ s`,
//! `+∞` for `x ≤ 0` ([`crate::contact::barrier`], C³ at `s`). `s` is the
//! barrier's support (rad or m) and `κ` its stiffness (J·rad or J·m):
//! `∂L/∂θ_k = κ[P'(θ−lo) − P'(hi−θ)]`, `∂²L/∂θ_k² = κ[P''(θ−lo) + P''(hi−θ)]`.
//! A coordinate is therefore never at or beyond its limit in an accepted
//! state, and stops inside the support `(lo, lo + s) ∪ (hi − s, hi)` when
//! driven there. The term depends on `θ^{t+1}` and constants only: its
//! adjoint contribution is its Hessian in the step's linear system, and its
//! VJP adds nothing.

use super::{Energy, EnergyAccumulator, EnergyError, Need, StepContext};
use crate::contact::barrier::barrier_d2;
use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::kinematics::Kinematics;
use crate::model::Model;
use nalgebra::{DVector, Matrix3};

/// Fraction of the distance to a limit that one line-search trial may
/// consume: trial points keep at least `1 − MAX_APPROACH` of it.
pub const MAX_APPROACH: f64 = 0.9;

/// One limited coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct LimitedDof {
    pub dof: usize,
    pub lower: f64,
    pub upper: f64,
    /// Barrier support `s` (rad or m).
    pub support: f64,
    /// Barrier stiffness `κ` (J·rad or J·m).
    pub stiffness: f64,
}

/// The joint-limit term.
#[derive(Clone, Debug, Default)]
pub struct JointLimits {
    pub dofs: Vec<LimitedDof>,
    /// The coordinate that made the last evaluation infeasible, if any.
    violated: Option<(usize, f64)>,
}

impl JointLimits {
    /// The term for every limited joint of `model` (see
    /// [`crate::model::JointLimit`]); `None` when no joint is limited.
    pub fn from_model(model: &Model) -> Option<JointLimits> {
        let dofs: Vec<LimitedDof> = model
            .links
            .iter()
            .filter_map(|l| {
                l.limit.as_ref().map(|lim| LimitedDof {
                    dof: l.dof_offset,
                    lower: lim.lower,
                    upper: lim.upper,
                    support: lim.support,
                    stiffness: lim.stiffness,
                })
            })
            .collect();
        (!dofs.is_empty()).then_some(JointLimits {
            dofs,
            violated: None,
        })
    }
}

impl Energy for JointLimits {
    fn name(&self) -> &'static str {
        "joint_limit"
    }

    fn accumulate(
        &mut self,
        _ctx: &StepContext,
        q: &DVector<f64>,
        _kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError> {
        self.violated = None;
        for d in &self.dofs {
            let x = q[d.dof];
            let (lo, hi) = (x - d.lower, d.upper - x);
            if !(lo > 0.0 && hi > 0.0) {
                self.violated = Some((d.dof, x));
                acc.value = f64::INFINITY;
                return Ok(());
            }
            let (va, da, ha) = barrier_d2(lo, d.support);
            let (vb, db, hb) = barrier_d2(hi, d.support);
            acc.value += d.stiffness * (va + vb);
            if need >= Need::Gradient {
                acc.dof_grad[d.dof] += d.stiffness * (da - db);
            }
            if need >= Need::Hessian {
                acc.dof_hess[(d.dof, d.dof)] += d.stiffness * (ha + hb);
            }
        }
        Ok(())
    }

    fn explain_infeasible(&self, model: &Model) -> Option<String> {
        self.violated.map(|(k, x)| {
            let d = self.dofs.iter().find(|d| d.dof == k).unwrap();
            format!(
                "coordinate \"{}\" = {x} is at or beyond its limit [{}, {}]",
                model.dofs[k].name, d.lower, d.upper
            )
        })
    }

    /// The largest `α` with every limited coordinate keeping at least
    /// `1 − MAX_APPROACH` of its distance to each limit.
    fn max_step(
        &mut self,
        _ctx: &StepContext,
        q: &DVector<f64>,
        dq: &DVector<f64>,
        _kin: &Kinematics,
        _charts: &[Matrix3<f64>],
    ) -> Result<f64, EnergyError> {
        let mut alpha: f64 = 1.0;
        for d in &self.dofs {
            let (x, v) = (q[d.dof], dq[d.dof]);
            if v < 0.0 {
                alpha = alpha.min(MAX_APPROACH * (x - d.lower) / -v);
            } else if v > 0.0 {
                alpha = alpha.min(MAX_APPROACH * (d.upper - x) / v);
            }
        }
        Ok(alpha.max(0.0))
    }

    /// No parameters and no dependence on earlier states.
    fn vjp(
        &mut self,
        _ctx: &StepContext,
        _q: &DVector<f64>,
        _kin: &Kinematics,
        _dir: &AdjointDirection,
        _out: &mut VjpAccumulator,
    ) -> Result<(), EnergyError> {
        Ok(())
    }
}
