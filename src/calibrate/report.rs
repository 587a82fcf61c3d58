//! `calibration.json` (schema below; also in the README) and `report.md`.
//!
//! ```text
//! verdict        "effect" | "none" | "unexplained"  (rule: calibrate::verdict)
//! reason         why, in words (the floor, the share explained, where the gap sits)
//! error_floor    {dt, noise, integrator, integrator_in_gap, order, gap, gap_half_dt,
//!                 gap_quarter_dt, gap_extrapolated, shrink_half_dt, contact, contact_in_gap,
//!                 contact_s, floor, suggested_dt, floor_of, floor_baseline,
//!                 floor_extrapolated}
//!                the model's own error on the held-out window (calibrate::floor);
//!                floor_of: "none", or the chosen candidate when its own floor is higher;
//!                floor_extrapolated: that floor measured with the candidate's values
//!                extrapolated to Δt → 0 (else as fitted at Δt)
//! residual_regression  {joints: [{joint, rms_force, terms: [{term, meaning, unit,
//!                coefficient, low, high}], explained_holdout, rows}], strongest}
//!                sparse regression of the residual generalized force (calibrate::residual)
//! implausible    [{candidate, reason}] fits outside physically plausible ranges (never chosen)
//! effect         documented name of the chosen effect (pairs: "a+b"), null for none
//! candidate      chosen candidate label ("joint_damping/all"), null for none
//! parameters     {"<effect>/<joint|link|all>[:<param>]": value (SI)}, extrapolated to
//!                Δt → 0 (refit at Δt/2, Richardson order 1, when the data come from a
//!                finer step, judged per channel: calibrate::select), else as fitted at Δt
//! parameters_at_dt  the same keys as fitted at the scene's Δt (in calibrated.yaml)
//! confidence     {key: {value, low, high}}  95 % from the Gauss–Newton Hessian
//!                (low/high null when the parameter is not identifiable)
//! gap_before     {"channels": {name: held-out RMS}, "overall": RMS}  the scene as given
//!                (with --fit-contact-resolution: with the contact resolution fitted)
//! gap_after      same, with the chosen effect (= gap_before for "none")
//! gap_reduction  1 − overall_after/overall_before
//! indistinguishable  single candidates within ΔC < 2 of the chosen one
//! ranking        [{candidate, effects, parameters, rms_train, rms_holdout,
//!                  criterion, delta_criterion (vs none, > 0 is better), explained}]
//! baseline       {rms_train, rms_holdout, criterion}
//! residuals_before / residuals_after   per channel: RMS overall, train, held-out,
//!                free/contact, moving/at rest, accelerating/braking, correlations
//!                with sign θ̇, θ̇, θ̈; the three worst of ten time windows
//! recordings     [{path, initial, samples, train_before, train_after, holdout_before,
//!                  holdout_after}] each recording's RMS gaps (calibrate::recordings);
//!                with several recordings gap_before/gap_after "overall" and the
//!                ranking's RMS values are over all of them, the per-channel
//!                values and residuals_* over the first
//! identifiability [{candidate, condition, min_relative_eigenvalue, unidentifiable,
//!                  suggestion}] each candidate's scaled Gauss–Newton matrix at its start
//!                (calibrate::identifiability); the ranking's entries carry
//!                `unidentifiable` too
//! mass_changes   [{parameter, on, before_kg, after_kg, added_kg}] the mass each chosen
//!                link_mass_scale or payload adds to its links, at `parameters`
//! contact_resolution  {s_given, s_fitted, kappa_given, kappa_fitted, rms_train_given,
//!                rms_train_fitted, simulations} the contact model's resolution fitted
//!                before the selection (calibrate::nuisance, opt-in); null otherwise
//! holdout, split_time, samples, simulations
//! ```

use super::analysis::Analysis;
use super::floor::ErrorFloor;
use super::problem::Problem;
use super::select::{Scored, Selection};
use crate::energy::effects::{self, EffectSpec};
use serde::Serialize;
use std::collections::BTreeMap;

/// Held-out RMS per channel and overall.
#[derive(Clone, Debug, Serialize)]
pub struct Gap {
    pub channels: BTreeMap<String, f64>,
    pub overall: f64,
}

/// A 95 % interval.
#[derive(Clone, Debug, Serialize)]
pub struct Interval {
    pub value: f64,
    pub low: Option<f64>,
    pub high: Option<f64>,
}

/// One entry of the ranking.
#[derive(Clone, Debug, Serialize)]
pub struct Ranked {
    pub candidate: String,
    pub effects: Vec<String>,
    pub parameters: BTreeMap<String, f64>,
    pub rms_train: f64,
    pub rms_holdout: f64,
    pub criterion: f64,
    pub delta_criterion: f64,
    /// `1 − RSS_train(fit)/RSS_train(none)`.
    pub explained: f64,
    /// Parameters not identifiable from the data at the start
    /// ([`super::identifiability`]); empty when all are.
    pub unidentifiable: Vec<String>,
}

/// The mass a chosen `link_mass_scale` or `payload` adds, in kilograms:
/// what a user weighs, and the part of such a fit that stays meaningful when
/// the data cannot place the mass (a payload's position, a mass scale's
/// inertia).
#[derive(Clone, Debug, Serialize)]
pub struct MassChange {
    /// The parameter read: `link_mass_scale/<on>` (`σ`) or `payload/<on>:mass`.
    pub parameter: String,
    /// The effect's target as written (`all`, a link name).
    pub on: String,
    /// `Σ m_i` over the target links in the scene as given (kg).
    pub before_kg: f64,
    /// `σ Σ m_i` for a mass scale, `Σ m_i + m` for a payload (kg).
    pub after_kg: f64,
    /// `after_kg − before_kg` (kg).
    pub added_kg: f64,
}

/// The baseline's scores.
#[derive(Clone, Debug, Serialize)]
pub struct Baseline {
    pub rms_train: f64,
    pub rms_holdout: f64,
    pub criterion: f64,
}

/// A fit outside physically plausible ranges.
#[derive(Clone, Debug, Serialize)]
pub struct Implausible {
    pub candidate: String,
    pub reason: String,
}

/// Sample counts.
#[derive(Clone, Debug, Serialize)]
pub struct Samples {
    pub times: usize,
    pub train: usize,
    pub holdout: usize,
}

/// Everything `calibration.json` holds.
#[derive(Clone, Debug, Serialize)]
pub struct CalibrationResult {
    pub verdict: String,
    pub reason: String,
    /// The residual generalized force of the scene as given regressed on
    /// candidate terms per joint ([`super::residual`]); `null` for robots
    /// with spherical or free joints, or too little data.
    pub residual_regression: Option<super::residual::ResidualRegression>,
    pub error_floor: ErrorFloor,
    pub implausible: Vec<Implausible>,
    pub effect: Option<String>,
    pub candidate: Option<String>,
    /// The chosen model's parameters extrapolated to Δt → 0 (the physical
    /// estimate; [`super::select::extrapolate_to_zero_dt`]), or as fitted at
    /// Δt when the data are fitted worse at Δt/2 (data carrying our own
    /// integrator's error) or the refit failed.
    pub parameters: BTreeMap<String, f64>,
    /// As fitted at the scene's Δt: what `calibrated.yaml` holds and
    /// `gap_after` is measured with.
    pub parameters_at_dt: BTreeMap<String, f64>,
    /// 95 % intervals around `parameters` (half-widths from the fit at Δt).
    pub confidence: BTreeMap<String, Interval>,
    pub gap_before: Gap,
    pub gap_after: Gap,
    pub gap_reduction: f64,
    pub ranking: Vec<Ranked>,
    /// Other single candidates whose criterion is within 2 of the chosen
    /// one's: the data cannot tell them apart (e.g. a gain on every joint of
    /// a contact-free robot is exactly a mass scale of every link by 1/g).
    pub indistinguishable: Vec<String>,
    pub baseline: Baseline,
    pub residuals_before: Analysis,
    pub residuals_after: Analysis,
    pub holdout: f64,
    pub split_time: f64,
    pub samples: Samples,
    pub simulations: usize,
    /// The chosen effects as scene-file entries (also in `calibrated.yaml`).
    pub effects: Vec<EffectSpec>,
    /// Each recording's gaps before and after ([`super::recordings`]).
    pub recordings: Vec<super::recordings::RecordingGap>,
    /// The mass each chosen `link_mass_scale` or `payload` adds, at the
    /// values of `parameters` ([`mass_changes`]); empty otherwise.
    pub mass_changes: Vec<MassChange>,
    /// Each candidate's identifiability at its start, in the ranking's
    /// order ([`super::identifiability`]).
    pub identifiability: Vec<super::identifiability::Identifiability>,
    /// The contact model's resolution fitted before the selection
    /// ([`super::nuisance`]); `null` without contact or when the fit did not
    /// lower the training RSS (or was switched off).
    pub contact_resolution: Option<super::nuisance::ResolutionFit>,
    /// Wall time (s); not written to the JSON (outputs are deterministic).
    #[serde(skip)]
    pub seconds: f64,
}

/// Parameters of a scored candidate by key.
pub fn parameters(pb: &Problem, s: &Scored) -> BTreeMap<String, f64> {
    param_list(pb, s).into_iter().collect()
}

/// Parameters of a scored candidate, in the order of its parameter vector.
pub fn param_list(pb: &Problem, s: &Scored) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    let specs = s.candidate.specs(&s.fit.params);
    if let Some(sc) = pb.scene_with(&specs) {
        let base = sc.effects.len() - specs.len();
        for e in &sc.effects[base..] {
            for (k, key) in effects::param_keys(e).into_iter().enumerate() {
                out.push((key, e.values[k]));
            }
        }
    }
    out
}

fn gap(a: &Analysis, pb: &Problem, s: &Scored) -> Gap {
    Gap {
        channels: a
            .channels
            .iter()
            .map(|c| (c.channel.clone(), c.holdout.rms))
            .collect(),
        overall: s.rms_holdout().max(0.0) * f64::from(pb.split < pb.measured.times.len()),
    }
}

/// The decision's reason; for `unexplained`, with where the gap sits (the
/// channel with the largest held-out error, its regimes, the worst
/// windows).
fn where_it_sits(d: &super::verdict::Decision, before: &Analysis) -> String {
    if d.verdict != super::verdict::Verdict::Unexplained {
        return d.reason.clone();
    }
    let mut s = d.reason.clone();
    if let Some(c) = before
        .channels
        .iter()
        .max_by(|a, b| a.holdout.rms.total_cmp(&b.holdout.rms))
    {
        let regimes = [
            ("free", &c.free),
            ("contact", &c.contact),
            ("moving", &c.moving),
            ("at rest", &c.at_rest),
            ("accelerating", &c.accelerating),
            ("braking", &c.braking),
        ];
        let worst = regimes
            .iter()
            .filter(|(_, r)| r.samples > 0)
            .max_by(|a, b| a.1.rms.total_cmp(&b.1.rms));
        s.push_str(&format!(
            "; it sits on channel `{}` (held-out RMS {:.3e}",
            c.channel, c.holdout.rms
        ));
        if let Some((name, r)) = worst {
            s.push_str(&format!(", largest while {name}: {:.3e}", r.rms));
        }
        s.push_str(&format!(
            "; correlation with sign θ̇ {:+.2}, θ̇ {:+.2}, θ̈ {:+.2})",
            c.corr_velocity_sign, c.corr_velocity, c.corr_acceleration
        ));
    }
    let w: Vec<String> = before
        .worst_windows
        .iter()
        .map(|w| format!("[{:.3}, {:.3}] s", w.t_start, w.t_end))
        .collect();
    if !w.is_empty() {
        s.push_str(&format!(", windows {}", w.join(", ")));
    }
    s
}

/// Assembles the result.
pub fn result(
    pb: &Problem,
    sel: &Selection,
    before: Analysis,
    after: Analysis,
    holdout: f64,
) -> CalibrationResult {
    let base = &sel.baseline;
    let chosen = sel.chosen.map(|i| &sel.ranking[i]);
    let after_scored = chosen.unwrap_or(base);
    let fitted = chosen
        .map(|s| chosen_values(pb, sel, s))
        .unwrap_or_default();
    let gap_before = gap(&before, pb, base);
    let gap_after = gap(&after, pb, after_scored);
    let split_time = pb.split_time();
    let residual_regression = sel.residual.clone();
    let reason = result_reason(sel, &before, residual_regression.as_ref());
    let mass_changes = mass_changes(pb, &fitted.effects, &fitted.parameters);
    CalibrationResult {
        verdict: sel.decision.verdict.name().into(),
        reason,
        residual_regression,
        error_floor: sel.floor.clone(),
        implausible: sel
            .decision
            .implausible
            .iter()
            .map(|(c, r)| Implausible {
                candidate: c.clone(),
                reason: r.clone(),
            })
            .collect(),
        effect: chosen.map(|s| {
            s.candidate
                .kinds()
                .iter()
                .map(|k| k.name())
                .collect::<Vec<_>>()
                .join("+")
        }),
        candidate: chosen.map(|s| s.candidate.label.clone()),
        parameters: fitted.parameters,
        parameters_at_dt: fitted.at_dt,
        confidence: fitted.confidence,
        gap_reduction: 1.0 - gap_after.overall / gap_before.overall.max(1e-300),
        gap_before,
        gap_after,
        indistinguishable: chosen.map_or_else(Vec::new, |c| indistinguishable(sel, c)),
        ranking: ranked(pb, sel),
        baseline: Baseline {
            rms_train: base.rms_train(),
            rms_holdout: base.rms_holdout(),
            criterion: base.criterion,
        },
        residuals_before: before,
        residuals_after: after,
        holdout,
        split_time,
        samples: Samples {
            times: pb.measured.times.len(),
            train: base.fit.n,
            holdout: base.n_holdout,
        },
        simulations: sel.simulations,
        recordings: super::recordings::gaps(pb, &fitted.effects),
        mass_changes,
        identifiability: sel.identifiability.clone(),
        effects: fitted.effects,
        contact_resolution: None,
        seconds: 0.0,
    }
}

/// The mass each `link_mass_scale` or `payload` among `chosen` adds to its
/// target links, at `parameters` (the reported values; the effect's own
/// value when its key is missing): `σ Σ m_i` or `Σ m_i + m` against the
/// scene's `Σ m_i` (the links' masses as modelled, e.g. lumped vertex
/// masses).
pub fn mass_changes(
    pb: &Problem,
    chosen: &[EffectSpec],
    parameters: &BTreeMap<String, f64>,
) -> Vec<MassChange> {
    use crate::energy::effects::{EffectKind, Target};
    let model = &pb.scene.model;
    let Ok(resolved) = effects::resolve(chosen, model, pb.scene.contact.is_some(), "effects")
    else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for e in &resolved {
        let (EffectKind::LinkMassScale | EffectKind::Payload, Target::Links(links)) =
            (e.kind, &e.target)
        else {
            continue;
        };
        let parameter = effects::param_keys(e).swap_remove(0);
        let v = parameters.get(&parameter).copied().unwrap_or(e.values[0]);
        let before_kg: f64 = links.iter().map(|&i| model.links[i].mass()).sum();
        let after_kg = match e.kind {
            EffectKind::Payload => before_kg + v,
            _ => v * before_kg,
        };
        out.push(MassChange {
            parameter,
            on: e.on.clone(),
            before_kg,
            after_kg,
            added_kg: after_kg - before_kg,
        });
    }
    out
}

/// Every scored candidate, best first, with its parameters and scores
/// against the baseline (`delta_criterion`, `explained`).
fn ranked(pb: &Problem, sel: &Selection) -> Vec<Ranked> {
    let base = &sel.baseline;
    sel.ranking
        .iter()
        .zip(&sel.identifiability)
        .map(|(s, id)| Ranked {
            candidate: s.candidate.label.clone(),
            effects: s
                .candidate
                .kinds()
                .iter()
                .map(|k| k.name().into())
                .collect(),
            parameters: parameters(pb, s),
            rms_train: s.rms_train(),
            rms_holdout: s.rms_holdout(),
            criterion: s.criterion,
            delta_criterion: base.criterion - s.criterion,
            explained: 1.0 - s.fit.rss / base.fit.rss.max(1e-300),
            unidentifiable: id.unidentifiable.clone(),
        })
        .collect()
}

/// The chosen candidate's reported values: the Δt → 0 extrapolation when
/// there is one (else the fit at Δt), the values at Δt, their intervals,
/// and the effects they make.
#[derive(Default)]
struct ChosenValues {
    parameters: BTreeMap<String, f64>,
    at_dt: BTreeMap<String, f64>,
    confidence: BTreeMap<String, Interval>,
    effects: Vec<EffectSpec>,
}

fn chosen_values(pb: &Problem, sel: &Selection, s: &Scored) -> ChosenValues {
    let list = param_list(pb, s);
    let values = sel.extrapolated.as_ref().unwrap_or(&s.fit.params);
    let parameters = list
        .iter()
        .zip(values)
        .map(|((k, _), v)| (k.clone(), *v))
        .collect();
    let confidence = list
        .iter()
        .map(|(k, _)| k)
        .zip(values.iter().zip(&s.fit.half_width))
        .map(|(k, (v, hw))| {
            let interval = Interval {
                value: *v,
                low: hw.map(|h| v - h),
                high: hw.map(|h| v + h),
            };
            (k.clone(), interval)
        })
        .collect();
    ChosenValues {
        parameters,
        at_dt: list.iter().cloned().collect(),
        confidence,
        effects: s.candidate.specs(&s.fit.params),
    }
}

/// Single candidates other than the chosen one that fit as well: within 2
/// of its criterion, or within [`super::verdict::INDISTINGUISHABLE_RMS`]
/// of its held-out RMS.
fn indistinguishable(sel: &Selection, c: &Scored) -> Vec<String> {
    sel.ranking
        .iter()
        .filter(|s| {
            s.candidate.label != c.candidate.label
                && s.candidate.templates.len() == 1
                && ((s.criterion - c.criterion).abs() < 2.0
                    || (s.rms_holdout() - c.rms_holdout()).abs()
                        <= super::verdict::INDISTINGUISHABLE_RMS * c.rms_holdout())
        })
        .map(|s| s.candidate.label.clone())
        .collect()
}

/// Where the discrepancy sits, and for `unexplained` the residual force
/// regression's strongest structure.
fn result_reason(
    sel: &Selection,
    before: &Analysis,
    regression: Option<&super::residual::ResidualRegression>,
) -> String {
    let mut reason = where_it_sits(&sel.decision, before);
    if sel.decision.verdict == super::verdict::Verdict::Unexplained
        && let Some(st) = regression.and_then(|r| r.strongest.as_ref())
    {
        reason.push_str(&format!(
            "; the residual force regression's strongest structure is `{st}` (residual_regression)"
        ));
    }
    reason
}

/// The "model's own error" lines of `report.md`.
fn floor_section(s: &mut String, f: &ErrorFloor) {
    s.push_str(&format!(
        "## The model's own error\n\n| quantity (held-out window) | value |\n|---|---:|\n\
         | gap of the scene as given (Δt = {} s) | {:.3e} |\n\
         | gap at Δt/2, Δt/4 | {:.3e}, {:.3e} |\n\
         | gap extrapolated to Δt → 0 (Richardson, order {:.2}) | {:.3e} |\n\
         | noise σ (third differences of the residual) | {:.3e} |\n\
         | integrator error at Δt (estimated / in the gap) | {:.3e} / {:.3e} |\n\
         | contact resolution E_c (estimated / in the gap; s halved{}) | {:.3e} / {:.3e} |\n\
         | error floor F = {}·√(σ² + E_gap² + E_c,gap²) | {:.3e} |\n\n",
        f.dt,
        f.gap,
        f.gap_half_dt,
        f.gap_quarter_dt,
        f.order,
        f.gap_extrapolated,
        f.noise,
        f.integrator,
        f.integrator_in_gap,
        match f.contact_s {
            Some(s) => format!(", from s = {s} m"),
            None => "; no contact".to_string(),
        },
        f.contact,
        f.contact_in_gap,
        super::floor::FLOOR_MARGIN,
        f.floor
    ));
    if f.floor_of != "none" {
        s.push_str(&format!(
            "The floor and the integrator error in the gap are those of the chosen model `{}` (re-estimated at Δt/2, Δt/4 with its effects at their {} values); the scene as given has floor {:.3e}.\n\n",
            f.floor_of,
            if f.floor_extrapolated {
                "Δt → 0"
            } else {
                "fitted"
            },
            f.floor_baseline
        ));
    }
    if let Some(dt) = f.suggested_dt {
        s.push_str(&format!(
            "The integrator error at Δt = {} s is {:.1}× the noise: effects of the size of the noise become resolvable at Δt ≤ {:.2e} s.\n\n",
            f.dt,
            f.integrator / f.noise.max(1e-300),
            dt
        ));
    }
}

/// `report.md`: the verdict, the findings, where the model disagrees and
/// the ranking of the candidates.
pub fn markdown(r: &CalibrationResult, scene: &str, measured: &str) -> String {
    let mut s = String::new();
    md_verdict(&mut s, r, scene, measured);
    md_findings(&mut s, r);
    md_disagreement(&mut s, r);
    md_ranking(&mut s, r);
    s
}

/// Appends `t` and a newline.
fn w(s: &mut String, t: String) {
    s.push_str(&t);
    s.push('\n');
}

/// Title, data, verdict, its reason and the error floor.
fn md_verdict(s: &mut String, r: &CalibrationResult, scene: &str, measured: &str) {
    w(s, "# Calibration report\n".into());
    w(
        s,
        format!(
            "Scene `{scene}`, measured data `{measured}`: {} samples, training window up to t = {:.4} s ({} residuals), held-out window after it ({} residuals, holdout {}).\n",
            r.samples.times, r.split_time, r.samples.train, r.samples.holdout, r.holdout
        ),
    );
    match (&r.candidate, r.verdict.as_str()) {
        (Some(c), _) => w(
            s,
            format!(
                "**Verdict: missing effect `{}`** (candidate `{c}`); the held-out RMS error shrinks from {:.4e} to {:.4e} ({:.1} %).\n",
                r.effect.clone().unwrap_or_default(),
                r.gap_before.overall,
                r.gap_after.overall,
                100.0 * r.gap_reduction
            ),
        ),
        (None, "unexplained") => w(
            s,
            format!(
                "**Verdict: unexplained**: a discrepancy beyond the model's error floor that no candidate explains (held-out RMS {:.4e}).\n",
                r.gap_before.overall
            ),
        ),
        (None, _) => w(
            s,
            format!(
                "**Verdict: no missing effect found** (held-out RMS {:.4e}).\n",
                r.gap_before.overall
            ),
        ),
    }
    w(s, format!("Why: {}.\n", r.reason));
    floor_section(s, &r.error_floor);
}

/// Implausible fits, indistinguishable candidates, fitted parameters.
fn md_findings(s: &mut String, r: &CalibrationResult) {
    if !r.implausible.is_empty() {
        w(
            s,
            "Fits outside physically plausible ranges (never chosen):\n".into(),
        );
        for i in &r.implausible {
            w(s, format!("- `{}`: {}", i.candidate, i.reason));
        }
        w(s, String::new());
    }
    if !r.indistinguishable.is_empty() {
        w(
            s,
            format!(
                "Indistinguishable on these data (criterion within 2): {}.\n",
                r.indistinguishable
                    .iter()
                    .map(|c| format!("`{c}`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        );
    }
    if !r.parameters.is_empty() {
        w(
            s,
            "| parameter | value | 95 % interval |\n|---|---:|---|".into(),
        );
        for (k, v) in &r.parameters {
            let ci = r.confidence.get(k).and_then(|c| Some((c.low?, c.high?)));
            w(
                s,
                format!(
                    "| `{k}` | {v:.6e} | {} |",
                    match ci {
                        Some((a, b)) => format!("[{a:.4e}, {b:.4e}]"),
                        None => "not identifiable".into(),
                    }
                ),
            );
        }
        w(s, String::new());
    }
    for m in &r.mass_changes {
        w(
            s,
            format!(
                "Mass of `{}` (`{}`): {:.4} → {:.4} kg ({:+.4} kg).\n",
                m.on, m.parameter, m.before_kg, m.after_kg, m.added_kg
            ),
        );
    }
}

/// Residual RMS per channel, window and regime, before and after; worst windows.
fn md_disagreement(s: &mut String, r: &CalibrationResult) {
    w(
        s,
        "## Where the model disagrees\n\nRMS of simulated − measured (SI units of each channel) overall, per window and per regime (–: no samples), before and after calibration.\n".into(),
    );
    w(s, "| channel | RMS | train | held-out | free | contact | moving | at rest | accelerating | braking | corr sign θ̇ | corr θ̇ | corr θ̈ |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|".into());
    let cell = |x: &super::analysis::Rms| {
        if x.samples == 0 {
            "–".to_string()
        } else {
            format!("{:.3e}", x.rms)
        }
    };
    for (a, label) in [
        (&r.residuals_before, "before"),
        (&r.residuals_after, "after"),
    ] {
        for c in &a.channels {
            let cells = [
                &c.all,
                &c.train,
                &c.holdout,
                &c.free,
                &c.contact,
                &c.moving,
                &c.at_rest,
                &c.accelerating,
                &c.braking,
            ]
            .map(cell)
            .join(" | ");
            w(
                s,
                format!(
                    "| {} ({label}) | {cells} | {:+.2} | {:+.2} | {:+.2} |",
                    c.channel, c.corr_velocity_sign, c.corr_velocity, c.corr_acceleration
                ),
            );
        }
    }
    w(
        s,
        "\nWindows where the error concentrates (before):\n".into(),
    );
    for win in &r.residuals_before.worst_windows {
        w(
            s,
            format!(
                "- t ∈ [{:.3}, {:.3}] s: RMS {:.3e}, {:.1} % of the squared error",
                win.t_start,
                win.t_end,
                win.rms,
                100.0 * win.share
            ),
        );
    }
}

/// The candidates' ranking and the baseline.
fn md_ranking(s: &mut String, r: &CalibrationResult) {
    w(s, "\n## Ranking\n\nCriterion `C = BIC(train) + n_ho ln(RSS_ho/n_ho)`; ΔC > 0 is better than the model as given.\n".into());
    w(s, "| # | candidate | ΔC | held-out RMS | train RMS | explained | parameters |\n|---:|---|---:|---:|---:|---:|---|".into());
    for (i, c) in r.ranking.iter().enumerate() {
        let mut p: Vec<String> = c
            .parameters
            .iter()
            .map(|(k, v)| format!("{k} = {v:.4e}"))
            .collect();
        if !c.unidentifiable.is_empty() {
            p.push(format!(
                "**not identifiable: {}**",
                c.unidentifiable.join(", ")
            ));
        }
        w(
            s,
            format!(
                "| {} | `{}` | {:.1} | {:.3e} | {:.3e} | {:.3} | {} |",
                i + 1,
                c.candidate,
                c.delta_criterion,
                c.rms_holdout,
                c.rms_train,
                c.explained,
                p.join(", ")
            ),
        );
    }
    w(
        s,
        format!(
            "\nBaseline (no effect): train RMS {:.3e}, held-out RMS {:.3e}. Simulations: {}.\n",
            r.baseline.rms_train, r.baseline.rms_holdout, r.simulations
        ),
    );
    if let Some(c) = &r.contact_resolution {
        w(
            s,
            format!(
                "Contact resolution fitted before the selection (a setting of the simulator's contact model, never named as an effect): {c} ({} simulations).\n",
                c.simulations
            ),
        );
    }
    w(
        s,
        "Plots: `channel_<name>.svg` (measured, simulated, calibrated) and `residuals.svg`.".into(),
    );
}
