//! The verdict: the smallest set of effects that explains the gap down to
//! the model's own error floor (issue 33, item 2).
//!
//! Inputs: the scene as given (baseline), every fitted candidate (singles,
//! then pairs of the best singles), and the floor `F` of [`super::floor`].
//! All RMS values are over the held-out window. The *excess* of a model is
//! the part of its held-out gap beyond the floor,
//! `X = √max(0, RMS_ho² − F²)`.
//!
//! # Rule (thresholds fixed before the acceptance runs of issue 33)
//!
//! 1. **Within the floor**: `G ≤ F` (baseline gap) → `none`, with the reason
//!    (noise, or the integrator: "the gap shrinks ×k at Δt/2").
//! 2. **A single effect** is *eligible* when its fitted values are
//!    plausible (below), its criterion beats the baseline by
//!    `ΔC > min_delta` (10), its held-out RMS is at least `min_gain` (5 %)
//!    below the baseline's, and it explains at least [`SHARE_SINGLE`] (half)
//!    of the baseline's excess: `X_c ≤ (1 − SHARE_SINGLE) X_base`, and it
//!    lowers the held-out gap itself by at least [`MIN_GAP_SHARE`] (a
//!    quarter): `RMS_c ≤ (1 − MIN_GAP_SHARE) G`. The eligible single with
//!    the lowest criterion is chosen. (`MIN_GAP_SHARE` was added in
//!    session 5 after an outcome: on clean MuJoCo data of gymnasium's ant,
//!    a gap 1.11× the floor — the two contact models' difference — was
//!    named `contact_s/all` because it lowered the gap by 14 %, all of the
//!    sliver above the floor; the issue's diagnosis: "≥ 5 % held-out
//!    improvement is passed by any such absorption".)
//! 3. **A second effect** is added (a pair replaces the chosen single) only
//!    when the pair is plausible and, against the chosen single *and* each
//!    of its own members fitted alone, the single leaves a held-out gap
//!    above the floor, the pair explains at least [`SHARE_PAIR`] (half) of
//!    what it leaves beyond the floor (`X_pair ≤ (1 − SHARE_PAIR) X_single`),
//!    and beats the single as the single beat the baseline: held-out RMS at
//!    least `min_gain` (5 %) lower and criterion more than `min_delta` (10)
//!    lower — held-out improvement, not the training fit. When no single is eligible, a pair
//!    satisfying this against both its members and step 2 against the
//!    baseline is chosen (two effects, neither of which explains the gap
//!    alone).
//! 4. **Unexplained**: no eligible candidate and `G > UNEXPLAINED_FACTOR · F`
//!    (2), or the model chosen by steps 2–3 still leaves a held-out gap
//!    above `UNEXPLAINED_FACTOR · F` (a partial absorption, e.g. a damping
//!    for a velocity-squared drag: the effect named must bring the gap down
//!    to the floor): a discrepancy clearly beyond the floor that nothing in
//!    the library explains; the report says where it sits (channels, regimes,
//!    windows). Between `F` and `2F` with no eligible candidate: `none`
//!    ("slightly above the floor; no candidate explains it").
//!
//! 5. **Structure**: a chosen model acting on a joint whose residual force
//!    regression ([`super::residual`]) has, as its strongest term explaining
//!    at least half the held-out residual force, a term no library effect
//!    has (`θ̇|θ̇|`) is not named: `unexplained`
//!    ([`check_structure`]), unless data simulated by the chosen model
//!    show the same term with a coefficient inside the measured 95 %
//!    interval (then it is the scene's own step's).
//!
//! **Plausibility** (relative to the robot's own masses, inertias and
//! gains; `I_k` is the effective inertia of coordinate `k` at `θ^0`, the
//! scene's own armature included, [`joint_inertia`]; the mean over the
//! coordinates for `all`): a payload heavier than
//! [`MAX_PAYLOAD_SHARE`] (½) of the moving mass; a mass scale or actuator
//! gain outside `[1/4, 4]`; a joint damping with a time constant `I/c`
//! under 10 ms (`c > 100 I`); an armature above `10 I`; a contact friction
//! coefficient above 2; an actuation delay shorter than the step Δt (the
//! implicit step's own phase lag is of that order: on MuJoCo reacher data
//! delays of 0.4–0.97 ms at Δt = 1 ms were taken as "second effects"
//! absorbing it); any value at a non-zero bound of its fit box.
//! Implausible candidates are listed with the reason and never chosen.
//!
//! **Indistinguishable**: other single candidates whose held-out RMS is
//! within 2 % of the chosen one's, or whose criterion is within 2, are
//! listed: the data do not tell them apart.

use super::floor::ErrorFloor;
use super::problem::Problem;
use super::select::{Scored, SelectOptions};
use crate::energy::effects::{EffectKind, Target};
use serde::Serialize;

/// Share of the baseline's excess a single effect must explain.
pub const SHARE_SINGLE: f64 = 0.5;
/// Share of the single's remaining excess a second effect must explain.
pub const SHARE_PAIR: f64 = 0.5;
/// Share of the held-out gap itself an effect (or a pair, against the
/// baseline) must remove to be named: materiality, beyond the floor test.
pub const MIN_GAP_SHARE: f64 = 0.25;
/// A gap above this multiple of the floor that no candidate explains is
/// `unexplained`.
pub const UNEXPLAINED_FACTOR: f64 = 2.0;
/// Largest plausible payload, as a share of the moving mass.
pub const MAX_PAYLOAD_SHARE: f64 = 0.5;
/// Range of plausible mass scales and actuator gains.
pub const SCALE_RANGE: (f64, f64) = (0.25, 4.0);
/// Held-out RMS within this relative distance: indistinguishable.
pub const INDISTINGUISHABLE_RMS: f64 = 0.02;

/// The three verdicts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    Effect,
    None,
    Unexplained,
}

impl Verdict {
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Effect => "effect",
            Verdict::None => "none",
            Verdict::Unexplained => "unexplained",
        }
    }
}

/// The decision and why.
#[derive(Clone, Debug)]
pub struct Decision {
    pub verdict: Verdict,
    /// Index into the ranking of the chosen model (`Effect` only).
    pub chosen: Option<usize>,
    /// The model the rule picked, also when it leaves more than
    /// `UNEXPLAINED_FACTOR` × the floor and the verdict is `unexplained`.
    pub best: Option<usize>,
    pub reason: String,
    /// `(candidate label, why)` of every implausible fit.
    pub implausible: Vec<(String, String)>,
}

/// Part of a held-out gap beyond the floor.
pub fn excess(rms: f64, floor: f64) -> f64 {
    (rms * rms - floor * floor).max(0.0).sqrt()
}

/// Effective inertia of every coordinate at `θ^0` (kg·m² or kg): the
/// links' ([`super::candidates::effective_inertia`]) plus the armature the
/// scene already has (an imported MJCF's `armature`, for instance).
pub fn joint_inertia(scene: &crate::scene::Scene) -> Vec<f64> {
    let mut inertia = super::candidates::effective_inertia(scene);
    for e in &scene.effects {
        if let (EffectKind::Armature, Target::Dofs(d)) = (e.kind, &e.target) {
            for &k in d {
                inertia[k] += e.values[0];
            }
        }
    }
    inertia
}

/// Why the fitted values of `s` are implausible (`None`: plausible).
pub fn implausible(pb: &Problem, s: &Scored, inertia: &[f64]) -> Option<String> {
    let c = &s.candidate;
    for (k, p) in s.fit.params.iter().enumerate() {
        let (lo, hi) = (c.lower[k], c.upper[k]);
        let tol = 1e-3 * (hi - lo);
        let at = |b: f64| b != 0.0 && (p - b).abs() <= tol;
        if at(lo) || at(hi) {
            return Some(format!("a value at the bound of its fit box ({p:.4e})"));
        }
    }
    let specs = c.specs(&s.fit.params);
    let sc = pb.scene_with(&specs)?;
    let model = &pb.scene.model;
    let moving: f64 = crate::energy::effects::massive_links(model)
        .iter()
        .map(|&i| model.links[i].mass())
        .sum();
    let first = sc.effects.len() - specs.len();
    for e in &sc.effects[first..] {
        let v = e.values[0];
        let inert = match &e.target {
            Target::Dofs(d) if !d.is_empty() => {
                d.iter().map(|&k| inertia[k]).sum::<f64>() / d.len() as f64
            }
            _ => f64::NAN,
        };
        let why = match e.kind {
            EffectKind::Payload if v > MAX_PAYLOAD_SHARE * moving => Some(format!(
                "payload {v:.3e} kg is more than {MAX_PAYLOAD_SHARE} of the moving mass {moving:.3e} kg"
            )),
            EffectKind::LinkMassScale | EffectKind::ActuatorGain
                if !(SCALE_RANGE.0..=SCALE_RANGE.1).contains(&v) =>
            {
                Some(format!(
                    "{} {v:.3} outside [{}, {}]",
                    e.kind.name(),
                    SCALE_RANGE.0,
                    SCALE_RANGE.1
                ))
            }
            EffectKind::JointDamping if v > 100.0 * inert => Some(format!(
                "damping {v:.3e} N·m·s/rad gives a time constant under 10 ms (inertia {inert:.3e} kg·m²)"
            )),
            EffectKind::Armature if v > 10.0 * inert => Some(format!(
                "armature {v:.3e} kg·m² is more than 10× the joint's inertia {inert:.3e}"
            )),
            EffectKind::ContactMu if v > 2.0 => Some(format!("friction coefficient {v:.3} > 2")),
            EffectKind::ActuationDelay if v < pb.scene.settings.dt => Some(format!(
                "delay {v:.3e} s is shorter than the step Δt = {} s: not resolvable from the integrator's own timing error",
                pb.scene.settings.dt
            )),
            _ => None,
        };
        if let Some(w) = why {
            return Some(format!("{} on {}: {w}", e.kind.name(), e.on));
        }
    }
    None
}

/// Whether the pair `p` explains at least [`SHARE_PAIR`] of what its
/// member `s` alone leaves beyond the floor `f`, and beats `s` as a single
/// must beat the baseline: held-out RMS at least `min_gain` lower and
/// criterion more than `min_delta` lower (and `s` leaves a gap above the
/// floor).
fn second_effect_pays(s: &Scored, p: &Scored, f: f64, opts: &SelectOptions) -> bool {
    let x_s = excess(s.rms_holdout(), f);
    x_s > 0.0
        && excess(p.rms_holdout(), f) <= (1.0 - SHARE_PAIR) * x_s
        && p.rms_holdout() <= (1.0 - opts.min_gain) * s.rms_holdout()
        && s.criterion - p.criterion > opts.min_delta
}

/// Applies the rule of the module doc to a ranking sorted by criterion.
pub fn decide(
    base: &Scored,
    ranking: &[Scored],
    floor: &ErrorFloor,
    bad: Vec<(String, String)>,
    opts: &SelectOptions,
) -> Decision {
    let f = floor.floor;
    let g = base.rms_holdout();
    let is_bad = |s: &Scored| bad.iter().any(|(l, _)| *l == s.candidate.label);
    let mk = |verdict, chosen, reason: String| Decision {
        verdict,
        chosen,
        best: chosen,
        reason,
        implausible: bad.clone(),
    };
    if g <= f {
        return mk(Verdict::None, None, within_floor_reason(floor));
    }
    let x_base = excess(g, f);
    let beats_base = |s: &Scored| {
        !is_bad(s)
            && base.criterion - s.criterion > opts.min_delta
            && s.rms_holdout() <= (1.0 - opts.min_gain.max(MIN_GAP_SHARE)) * g
            && excess(s.rms_holdout(), f) <= (1.0 - SHARE_SINGLE) * x_base
    };
    let single = ranking
        .iter()
        .position(|s| s.candidate.templates.len() == 1 && beats_base(s));
    // A pair must beat each of its members alone by the rule of step 3
    // (and, when no single is eligible, the baseline by that of step 2).
    let pair_ok = |p: &Scored| {
        p.candidate.templates.len() > 1
            && !is_bad(p)
            && p.candidate.label.split(" + ").all(|m| {
                ranking
                    .iter()
                    .find(|s| s.candidate.label == m)
                    .is_some_and(|s| second_effect_pays(s, p, f, opts))
            })
    };
    let pair = match single {
        Some(i) => ranking
            .iter()
            .position(|p| pair_ok(p) && second_effect_pays(&ranking[i], p, f, opts)),
        None => ranking.iter().position(|p| pair_ok(p) && beats_base(p)),
    };
    let Some(i) = single.or(pair) else {
        return if g > UNEXPLAINED_FACTOR * f {
            mk(
                Verdict::Unexplained,
                None,
                format!(
                    "the held-out gap {g:.3e} is {:.1}× the model's error floor {f:.3e} and no candidate (alone or paired) explains half of what lies beyond it",
                    g / f
                ),
            )
        } else {
            mk(
                Verdict::None,
                None,
                format!(
                    "the held-out gap {g:.3e} is slightly above the model's error floor {f:.3e} (less than {UNEXPLAINED_FACTOR}×) and no candidate explains half of the excess while lowering the gap itself by {:.0} %",
                    100.0 * MIN_GAP_SHARE
                ),
            )
        };
    };
    let s = &ranking[i];
    let x_s = excess(s.rms_holdout(), f);
    let k = pair.unwrap_or(i);
    let c = &ranking[k];
    let share = 1.0 - excess(c.rms_holdout(), f) / x_base;
    let reason = format!(
        "`{}` explains {:.0} % of the held-out gap beyond the model's error floor {f:.3e} (gap {g:.3e} → {:.3e}){}",
        c.candidate.label,
        100.0 * share,
        c.rms_holdout(),
        match pair.filter(|&p| p == k && single.is_some()) {
            Some(_) => format!(
                "; the second effect explains {:.0} % of what `{}` alone leaves beyond the floor",
                100.0 * (1.0 - excess(c.rms_holdout(), f) / x_s),
                s.candidate.label
            ),
            None => String::new(),
        }
    );
    let left = c.rms_holdout() / f;
    if left > UNEXPLAINED_FACTOR {
        let mut d = mk(
            Verdict::Unexplained,
            None,
            format!(
                "{reason}, but a held-out gap of {left:.1}× the floor remains: the best candidate set is not the missing effect (or not all of it), so none is named"
            ),
        );
        d.best = Some(k);
        return d;
    }
    mk(Verdict::Effect, Some(k), reason)
}

fn within_floor_reason(fl: &ErrorFloor) -> String {
    let base = format!(
        "the held-out gap {:.3e} is within the model's error floor {:.3e} (noise {:.2e}, integrator error in the gap {:.2e} of {:.2e} estimated at Δt = {} s{})",
        fl.gap,
        fl.floor,
        fl.noise,
        fl.integrator_in_gap,
        fl.integrator,
        fl.dt,
        match fl.contact_s {
            Some(s) => format!(
                ", contact resolution in the gap {:.2e} of {:.2e} estimated at s = {s} m",
                fl.contact_in_gap, fl.contact
            ),
            None => String::new(),
        }
    );
    if fl.contact_in_gap > fl.noise.max(fl.integrator_in_gap) {
        format!(
            "{base}: the remaining gap is the contact model's own resolution (the barrier keeps surfaces up to s apart; the data are closer to its s → 0 limit), not a missing effect"
        )
    } else if fl.integrator_in_gap > fl.noise {
        format!(
            "{base}: the remaining gap is the integrator's: it shrinks ×{:.2} at Δt/2 ({:.3e}) and extrapolates to {:.3e} at Δt → 0",
            fl.shrink_half_dt, fl.gap_half_dt, fl.gap_extrapolated
        )
    } else {
        format!("{base}: the remaining gap is the measurement noise")
    }
}

/// Step 5 of the rule: a chosen model with a joint effect on a joint whose
/// residual force regression's strongest term lies outside the library
/// ([`super::residual::outside_structure`]) is not named: the verdict
/// becomes `unexplained` (the model stays as `best`) — unless the same
/// regression on data simulated by the chosen model itself (`own`, run
/// only when needed) finds that term with a coefficient inside the
/// measured one's 95 % interval ([`super::residual::Structure::reproduced_by`]):
/// then the structure is the scene's integrator's, which the chosen model
/// shares with the data (on `arm2` data made by our own step with a hidden
/// damping 0.05, the implicit step's lag showed as `shoulder: θ̇|θ̇|` and
/// vetoed a damping that reproduced the data to 1e-14).
pub fn check_structure(
    d: &mut Decision,
    chosen: &Scored,
    r: &super::residual::ResidualRegression,
    own: impl FnOnce() -> Option<super::residual::ResidualRegression>,
) {
    let joints: Vec<String> = chosen
        .candidate
        .templates
        .iter()
        .filter(|t| t.spec.effect.scope() == crate::energy::effects::Scope::Joints)
        .map(|t| t.spec.on.clone())
        .collect();
    let Some(st) = super::residual::outside_structure(r, &joints) else {
        return;
    };
    if let Some(c) = own().and_then(|o| st.reproduced_by(&o)) {
        d.reason = format!(
            "{}; the residual force regression's `{st}` ({:.3e} [{:.3e}, {:.3e}]) is also in data simulated by `{}` itself ({c:.3e}): the scene's own step, not a missing structure",
            d.reason, st.term.coefficient, st.term.low, st.term.high, chosen.candidate.label
        );
        return;
    }
    d.reason = format!(
        "{}; but the residual force regression's strongest term on that joint is `{st}`, which no library effect has: `{}` absorbs part of a structure it does not have, so none is named",
        d.reason, chosen.candidate.label
    );
    d.verdict = Verdict::Unexplained;
    d.best = d.chosen.take();
}
