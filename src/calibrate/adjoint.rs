//! The exact gradient of a candidate's training objective by the adjoint
//! method: `g = Jᵀr = ∇_p ½‖r‖²` (paper, `differentiable.tex`; one forward
//! and one backward pass, whatever the number of parameters).
//!
//! With interpolated residuals `r_i = (1 − w_i) θ_c^{k_i} + w_i θ_c^{k_i+1} +
//! b_c − y_i`, `½‖r‖²` has the same parameter gradient as the linear
//! functional `L = Σ_i r_i [(1 − w_i) θ_c^{k_i} + w_i θ_c^{k_i+1}]` with the
//! coefficients frozen at the forward solution, which the backward pass
//! differentiates ([`crate::diff::LossTerm::JointLinear`]); effect
//! parameters map through [`crate::diff::effects::gradient`], and an encoder offset `b_c`
//! (measurement side) gets `Σ_i r_i` over its channels. Charted rotation
//! channels (free and spherical joints) are reported as absolute rotation
//! vectors, not tape coordinates; for them `None` is returned and the fit
//! falls back to `Jᵀr` from its finite-difference Jacobian.

use super::problem::{Candidate, Problem};
use crate::diff::{Loss, LossTerm, Tape, backward};
use crate::energy::effects::{EffectKind, Target};
use crate::scene::Scene;
use crate::sim::Simulator;
use std::collections::BTreeMap;

/// Training residuals and their exact gradient `Jᵀr` at `p`; with several
/// recordings ([`Problem::others`]) the residuals are concatenated in the
/// order of [`Problem::train_residuals`] and the gradients summed (one
/// forward and one backward pass per recording).
pub fn residual_gradient(
    pb: &Problem,
    cand: &Candidate,
    p: &[f64],
) -> Option<(Vec<f64>, Vec<f64>)> {
    let (r, rec) = residuals_recorded(pb, cand, p)?;
    Some((r, gradient(pb, cand, p, &mut rec?)?))
}

/// The forward passes at one parameter vector, kept for [`gradient`]: per
/// recording, the scene with the candidate's effects, the simulator after
/// the run and its tape.
pub struct Recorded(Vec<(Scene, Simulator, Tape)>);

/// [`Problem::train_residuals`] at `p` (the same values: the same runs),
/// with the runs recorded for [`gradient`] when the adjoint applies (`None`
/// beside the residuals when a channel is a charted rotation). `None` when a
/// simulation fails or a residual is not finite.
pub fn residuals_recorded(
    pb: &Problem,
    cand: &Candidate,
    p: &[f64],
) -> Option<(Vec<f64>, Option<Recorded>)> {
    let model = &pb.scene.model;
    if pb
        .measured
        .channels
        .iter()
        .any(|c| model.links[model.dofs[c.dof].link].joint.has_chart())
    {
        return Some((pb.train_residuals(cand, p)?, None));
    }
    let mut runs = Vec::with_capacity(1 + pb.others.len());
    let mut r = own_recorded(pb, cand, p, &mut runs)?;
    for o in pb.others {
        r.extend(pb.with_other(o, |q| own_recorded(q, cand, p, &mut runs))?);
    }
    Some((r, Some(Recorded(runs))))
}

/// One recording's training residuals (as [`Problem::train_residuals`]
/// computes them), its run pushed onto `runs`.
fn own_recorded(
    pb: &Problem,
    cand: &Candidate,
    p: &[f64],
    runs: &mut Vec<(Scene, Simulator, Tape)>,
) -> Option<Vec<f64>> {
    let sc = pb.scene_with(&cand.specs(p))?;
    let (simulated, sim, tape) = pb.simulate_scene_recorded(&sc, pb.steps_to(pb.split))?;
    let mut r = Vec::new();
    pb.residuals(&simulated, 0..pb.split, &mut r);
    runs.push((sc, sim, tape));
    r.iter().all(|x| x.is_finite()).then_some(r)
}

/// The exact `Jᵀr` at `p` from the runs `rec` recorded there by
/// [`residuals_recorded`] (one backward pass per recording, gradients
/// summed); `None` when a term cannot be differentiated.
pub fn gradient(pb: &Problem, cand: &Candidate, p: &[f64], rec: &mut Recorded) -> Option<Vec<f64>> {
    let mut runs = rec.0.iter_mut();
    let (sc, sim, tape) = runs.next()?;
    let mut g = own_gradient(pb, cand, p, sc, sim, tape)?;
    for o in pb.others {
        let (sc, sim, tape) = runs.next()?;
        let go = pb.with_other(o, |q| own_gradient(q, cand, p, sc, sim, tape))?;
        for (a, b) in g.iter_mut().zip(go) {
            *a += b;
        }
    }
    Some(g)
}

/// One recording's `Jᵀr` from its run.
fn own_gradient(
    pb: &Problem,
    cand: &Candidate,
    p: &[f64],
    sc: &Scene,
    sim: &mut Simulator,
    tape: &Tape,
) -> Option<Vec<f64>> {
    let model = &pb.scene.model;
    let specs_len = cand.specs(p).len();
    let offset = super::problem::encoder_offsets(sc);
    let dt = sc.settings.dt;
    let h = tape.len();
    let mut coef: BTreeMap<(usize, usize), f64> = BTreeMap::new();
    let mut sum_r = vec![0.0; model.ndof()];
    for i in 0..pb.split {
        let t = pb.measured.times[i];
        let x = t / dt;
        let k = (x.floor().max(0.0) as usize).min(h);
        let w = if k >= h { 0.0 } else { x - k as f64 };
        for ch in &pb.measured.channels {
            let Some(y) = ch.values[i] else { continue };
            let qa = tape.coords(k as isize).0[ch.dof];
            let v = if w == 0.0 {
                qa
            } else {
                (1.0 - w) * qa + w * tape.coords(k as isize + 1).0[ch.dof]
            };
            let ri = v + offset[ch.dof] - y;
            sum_r[ch.dof] += ri;
            *coef.entry((k, ch.dof)).or_default() += (1.0 - w) * ri;
            if w != 0.0 {
                *coef.entry((k + 1, ch.dof)).or_default() += w * ri;
            }
        }
    }
    let loss = Loss {
        terms: coef
            .into_iter()
            .map(|((level, dof), coef)| LossTerm::JointLinear { dof, level, coef })
            .collect(),
    };
    let grads = backward(sim, tape, &loss).ok()?;
    if !grads.unavailable.is_empty() {
        return None;
    }
    let all = crate::diff::effects::gradient(&sc.effects, &sim.controller, &grads);
    let first = sc.effects.len() - specs_len;
    let mut g = Vec::with_capacity(p.len());
    for e in &sc.effects[first..] {
        match (e.kind, &e.target) {
            (EffectKind::JointOffset, Target::Dofs(d)) => g.push(d.iter().map(|&k| sum_r[k]).sum()),
            _ => g.extend_from_slice(&all[e.slot..e.slot + e.values.len()]),
        }
    }
    Some(g)
}
