//! The candidate list: every effect of the library on every admissible
//! target (per joint coordinate and shared by all, per link and all links,
//! the contact parameters when the scene has contact), with bounds,
//! typical magnitudes and starting points derived from the scene.
//!
//! Typical magnitudes use each coordinate's effective inertia
//! `I_k = Δt²·∂²(inertia term)/∂θ_k²` at `θ^0` (kg·m² or kg): damping
//! `2 I_k` (a 0.5 s decay), friction and both Stribeck parameters (Coulomb
//! level, excess) `5 I_k` (5 rad/s² of deceleration), armature `0.2 I_k`.
//! Bounds: coefficients in `[0, 10⁴·typical]`, gains and mass scales in
//! `[0.05, 20]`, offsets in `[−0.5, 0.5]`, actuation delays in `[0, 0.1]` s
//! (typical 10 ms, start 5 ms), actuator deadbands in `[0, 0.1]` rad or m
//! (typical 0.01 — a gearbox's backlash is 0.1–1°, a hobby servo's
//! deadband a few degrees — start 0.005), payload masses in
//! `[0, 10 × total mass]` at positions within the link's hull box grown by
//! half its size (at least 5 cm), `μ ∈ [0, 5]`, `κ ∈ [κ₀/100, 100κ₀]`,
//! `s ∈ [s₀/10, min(0.5, 10s₀)]`.
//!
//! Starts: one for single-parameter candidates (their least-squares
//! problems are close to monotone in the parameter: `0.2 ×` typical for
//! coefficients, the nominal value for gains, scales, offsets and contact
//! parameters); two for the Stribeck friction (`(0.2, 0.2) ×` and
//! `(0.2, 1) ×` typical: the excess acts only near velocity reversals, and
//! its cost is not monotone — on `arm2` with an excess of 0.5 hidden, a
//! local minimum at 0.017 from the `0.2 ×` start, a hump between 0.1 and
//! 0.2); two for payloads (at the link's centre of mass and at a
//! corner of its box), whose position makes the problem multi-modal; pairs
//! start from the two single fits.

use super::problem::{Candidate, Template};
use crate::energy::Need;
use crate::energy::effects::{self, EffectKind, EffectSpec, Scope};
use crate::scene::Scene;

/// Upper bound of an actuation delay's fit box (s).
pub const MAX_DELAY: f64 = 0.1;

/// Upper bound of an actuator deadband's half-width (rad or m): 5.7°.
pub const MAX_DEADBAND: f64 = 0.1;

/// Effective inertia of every coordinate at `θ^0` (see the module doc).
pub fn effective_inertia(scene: &Scene) -> Vec<f64> {
    let mut sim = scene.simulator();
    sim.energies
        .retain(|e| e.kind() == crate::energy::TermKind::Inertia);
    let dt = scene.settings.dt;
    let q = sim.state.q.clone();
    match sim.objective(&q, Need::Hessian) {
        Ok((_, _, h)) => (0..h.nrows()).map(|k| h[(k, k)] * dt * dt).collect(),
        Err(_) => vec![1.0; scene.model.ndof()],
    }
}

fn single(
    kind: EffectKind,
    on: String,
    lower: f64,
    upper: f64,
    typical: f64,
    starts: &[f64],
) -> Candidate {
    Candidate {
        label: format!("{}/{on}", kind.name()),
        templates: vec![Template {
            spec: EffectSpec {
                effect: kind,
                on,
                values: vec![0.0],
                eps: None,
            },
        }],
        lower: vec![lower],
        upper: vec![upper],
        typical: vec![typical],
        starts: starts.iter().map(|s| vec![*s]).collect(),
    }
}

fn joint_candidate(kind: EffectKind, on: String, inertia: f64) -> Candidate {
    match kind {
        EffectKind::JointDamping => {
            let t = 2.0 * inertia;
            single(kind, on, 0.0, 1e4 * t, t, &[0.2 * t])
        }
        EffectKind::JointFriction => {
            let t = 5.0 * inertia;
            single(kind, on, 0.0, 1e4 * t, t, &[0.2 * t])
        }
        EffectKind::StribeckFriction => stribeck_candidate(on, 5.0 * inertia),
        EffectKind::Armature => {
            let t = 0.2 * inertia;
            single(kind, on, 0.0, 1e4 * t, t, &[0.2 * t])
        }
        EffectKind::ActuatorGain => single(kind, on, 0.05, 20.0, 1.0, &[1.0]),
        EffectKind::ActuationDelay => single(kind, on, 0.0, MAX_DELAY, 0.01, &[0.005]),
        EffectKind::ActuatorDeadband => single(kind, on, 0.0, MAX_DEADBAND, 0.01, &[0.005]),
        _ => single(kind, on, -0.5, 0.5, 0.05, &[0.0]),
    }
}

/// The Stribeck friction `[f_c, Δf]` on `on` with typical magnitude `t`
/// for both: box `[0, 10⁴ t]²`, starts `(0.2t, 0.2t)` and `(0.2t, t)` (see
/// the module doc).
fn stribeck_candidate(on: String, t: f64) -> Candidate {
    let kind = EffectKind::StribeckFriction;
    Candidate {
        label: format!("{}/{on}", kind.name()),
        templates: vec![Template {
            spec: EffectSpec {
                effect: kind,
                on,
                values: vec![0.0; 2],
                eps: None,
            },
        }],
        lower: vec![0.0; 2],
        upper: vec![1e4 * t; 2],
        typical: vec![t; 2],
        starts: vec![vec![0.2 * t, 0.2 * t], vec![0.2 * t, t]],
    }
}

/// All candidates of `kinds` for `scene`.
pub fn candidates(scene: &Scene, kinds: &[EffectKind]) -> Vec<Candidate> {
    let model = &scene.model;
    let inertia = effective_inertia(scene);
    let dofs = effects::joint_dofs(model);
    let mut out = Vec::new();
    for &kind in kinds {
        match kind.scope() {
            Scope::Joints => {
                if dofs.is_empty() {
                    continue;
                }
                let mean = dofs.iter().map(|&k| inertia[k]).sum::<f64>() / dofs.len() as f64;
                out.push(joint_candidate(kind, "all".into(), mean));
                if dofs.len() > 1 {
                    for &k in &dofs {
                        out.push(joint_candidate(
                            kind,
                            model.dofs[k].name.clone(),
                            inertia[k],
                        ));
                    }
                }
            }
            Scope::Links => {
                let links = effects::massive_links(model);
                if kind == EffectKind::LinkMassScale {
                    out.push(single(kind, "all".into(), 0.05, 20.0, 1.0, &[1.0]));
                    if links.len() > 1 {
                        for &i in &links {
                            let on = effects::link_label(model, i);
                            out.push(single(kind, on, 0.05, 20.0, 1.0, &[1.0]));
                        }
                    }
                    continue;
                }
                let total = model.total_mass().max(1e-6);
                for &i in &links {
                    let link = &model.links[i];
                    // Every massive link, a floating base or a free object
                    // included, can carry a payload (issue 33).
                    let (lo, hi) = link_box(link);
                    let c = model.first_moment[i];
                    let com = [c[0] / c[3], c[1] / c[3], c[2] / c[3]];
                    let size = (0..3).map(|e| hi[e] - lo[e]).fold(0.0, f64::max);
                    let m = 0.2 * link.mass().max(0.1 * total);
                    let mut lower = vec![0.0];
                    let mut upper = vec![10.0 * total];
                    for e in 0..3 {
                        let grow = (0.5 * (hi[e] - lo[e])).max(0.05);
                        lower.push(lo[e] - grow);
                        upper.push(hi[e] + grow);
                    }
                    let on = effects::link_label(model, i);
                    out.push(Candidate {
                        label: format!("{}/{on}", kind.name()),
                        templates: vec![Template {
                            spec: EffectSpec {
                                effect: kind,
                                on,
                                values: vec![0.0; 4],
                                eps: None,
                            },
                        }],
                        lower,
                        upper,
                        typical: vec![m, size.max(0.05), size.max(0.05), size.max(0.05)],
                        starts: vec![
                            vec![0.25 * m, com[0], com[1], com[2]],
                            vec![m, hi[0], hi[1], lo[2]],
                        ],
                    });
                }
            }
            Scope::Contact => {
                let Some(c) = &scene.contact else { continue };
                let cs = crate::scene::contact_settings(&scene.effects, c.clone());
                let v = kind.contact_param().map_or(f64::NAN, |p| p.value(&cs));
                let cand = match kind {
                    EffectKind::ContactMu => {
                        single(kind, "all".into(), 0.0, 5.0, v.max(0.1), &[v.max(0.05)])
                    }
                    EffectKind::ContactKappa => {
                        single(kind, "all".into(), v / 100.0, 100.0 * v, v, &[v])
                    }
                    _ => single(kind, "all".into(), v / 10.0, (10.0 * v).min(0.5), v, &[v]),
                };
                out.push(cand);
            }
        }
    }
    out
}

/// Bounding box of a link's hull vertices (link frame).
fn link_box(link: &crate::model::Link) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for h in &link.hulls {
        for x in &h.x_local {
            for e in 0..3 {
                lo[e] = lo[e].min(x[e]);
                hi[e] = hi[e].max(x[e]);
            }
        }
    }
    if !lo[0].is_finite() {
        return ([0.0; 3], [0.0; 3]);
    }
    (lo, hi)
}

/// A pair of fitted candidates as one candidate (different kinds only),
/// started from both fits' values.
pub fn pair(a: &Candidate, pa: &[f64], b: &Candidate, pb: &[f64]) -> Candidate {
    let cat = |x: &[f64], y: &[f64]| [x, y].concat();
    let starts = vec![cat(pa, pb)];
    Candidate {
        label: format!("{} + {}", a.label, b.label),
        templates: [a.templates.clone(), b.templates.clone()].concat(),
        lower: cat(&a.lower, &b.lower),
        upper: cat(&a.upper, &b.upper),
        typical: cat(&a.typical, &b.typical),
        starts,
    }
}
