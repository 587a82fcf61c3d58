//! The regression gate: a run's metrics against a stored `results.json`.
//!
//! Each metric has a direction and a kind ([`Kind`]); the allowed change
//! per kind (defaults below, all overridable in a tolerance YAML, per kind
//! and per metric name) is:
//!
//! | kind | regression when | default |
//! |---|---|---|
//! | `loss` | `now > base + max(relative·|base|, absolute)` | relative 0.05, absolute 1e-12 |
//! | `distance` | `now ≤ 0`, or `now < base·(1 − relative) − absolute` | relative 0.5, absolute 0 |
//! | `gradient_error` | `now > max(base·factor, absolute)` | factor 10, absolute 1e-4 |
//! | `speed_ratio` | `now < base·(1 − relative)` | relative 0.5 |
//! | `task` (higher is better, e.g. distance walked) | `now < base − max(relative·|base|, absolute)` | relative 0.05, absolute 1e-3 |
//!
//! Speed enters only as a ratio measured in one run (baseline time / SDRS
//! time on the same machine, interleaved), never as an absolute time. A
//! metric of the baseline that the run lacks is a regression; a new metric
//! is reported but passes.
//!
//! ```yaml
//! # tolerance file
//! loss: {relative: 0.1}
//! speed_ratio: {relative: 0.7}
//! metrics:
//!   codesign.chain_reach.co-design.final_loss: {relative: 0.02}
//! ```

use super::results::{Kind, Metric, Results};
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// One rule; unset fields take the kind's default.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rule {
    pub relative: Option<f64>,
    pub absolute: Option<f64>,
    pub factor: Option<f64>,
}

/// A tolerance file.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tolerances {
    #[serde(default)]
    pub loss: Rule,
    #[serde(default)]
    pub distance: Rule,
    #[serde(default)]
    pub gradient_error: Rule,
    #[serde(default)]
    pub speed_ratio: Rule,
    #[serde(default)]
    pub task: Rule,
    /// Per metric name; overrides the kind's rule field by field.
    #[serde(default)]
    pub metrics: BTreeMap<String, Rule>,
}

impl Tolerances {
    pub fn load(path: &Path) -> Result<Tolerances> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read the tolerance file", path.display()))?;
        let t: Tolerances = serde_yaml::from_str(&text)
            .with_context(|| format!("{}: malformed tolerance file", path.display()))?;
        for (name, r) in std::iter::once(("loss", &t.loss))
            .chain([
                ("distance", &t.distance),
                ("gradient_error", &t.gradient_error),
            ])
            .chain([("speed_ratio", &t.speed_ratio), ("task", &t.task)])
            .chain(t.metrics.iter().map(|(k, v)| (k.as_str(), v)))
        {
            for v in [r.relative, r.absolute, r.factor].into_iter().flatten() {
                if !(v.is_finite() && v >= 0.0) {
                    anyhow::bail!(
                        "{}: {name}: tolerances must be finite and ≥ 0, got {v}",
                        path.display()
                    );
                }
            }
        }
        Ok(t)
    }

    fn rule(&self, name: &str, kind: Kind) -> (f64, f64, f64) {
        let (k, (r0, a0, f0)) = match kind {
            Kind::Loss => (&self.loss, (0.05, 1e-12, 1.0)),
            Kind::Distance => (&self.distance, (0.5, 0.0, 1.0)),
            Kind::GradientError => (&self.gradient_error, (0.0, 1e-4, 10.0)),
            Kind::SpeedRatio => (&self.speed_ratio, (0.5, 0.0, 1.0)),
            Kind::Task => (&self.task, (0.05, 1e-3, 1.0)),
        };
        let m = self.metrics.get(name).copied().unwrap_or_default();
        (
            m.relative.or(k.relative).unwrap_or(r0),
            m.absolute.or(k.absolute).unwrap_or(a0),
            m.factor.or(k.factor).unwrap_or(f0),
        )
    }
}

/// One compared metric.
#[derive(Clone, Debug, Serialize)]
pub struct Verdict {
    pub metric: String,
    pub baseline: Option<f64>,
    pub now: Option<f64>,
    /// The worst value that still passes.
    pub limit: Option<f64>,
    pub regressed: bool,
    pub note: String,
}

/// Compares `now` against `base`; every baseline metric and every new one.
pub fn check(base: &Results, now: &Results, tol: &Tolerances) -> Vec<Verdict> {
    let (mb, mn) = (base.metrics(), now.metrics());
    let mut out = Vec::new();
    for (name, b) in &mb {
        let Some(n) = mn.get(name) else {
            out.push(Verdict {
                metric: name.clone(),
                baseline: Some(b.value),
                now: None,
                limit: None,
                regressed: true,
                note: "missing from this run".into(),
            });
            continue;
        };
        let (regressed, limit, note) = judge(name, b, n, tol);
        out.push(Verdict {
            metric: name.clone(),
            baseline: Some(b.value),
            now: Some(n.value),
            limit: Some(limit),
            regressed,
            note,
        });
    }
    for (name, n) in mn.iter().filter(|(k, _)| !mb.contains_key(*k)) {
        out.push(Verdict {
            metric: name.clone(),
            baseline: None,
            now: Some(n.value),
            limit: None,
            regressed: false,
            note: "new metric (not in the baseline)".into(),
        });
    }
    out
}

fn judge(name: &str, b: &Metric, n: &Metric, tol: &Tolerances) -> (bool, f64, String) {
    let (rel, abs, factor) = tol.rule(name, b.kind);
    match b.kind {
        Kind::Loss => {
            let limit = b.value + (rel * b.value.abs()).max(abs);
            (
                n.value > limit,
                limit,
                format!("loss may rise by {rel}·|base| or {abs}"),
            )
        }
        Kind::Distance => {
            let limit = (b.value * (1.0 - rel) - abs).max(0.0);
            (
                n.value <= 0.0 || n.value < limit,
                limit,
                "must stay positive and not shrink past the limit".into(),
            )
        }
        Kind::GradientError => {
            let limit = (b.value * factor).max(abs);
            (
                n.value > limit,
                limit,
                format!("at most {factor}× the baseline or {abs}"),
            )
        }
        Kind::Task => {
            let limit = b.value - (rel * b.value.abs()).max(abs);
            (
                n.value < limit,
                limit,
                format!("may fall by {rel}·|base| or {abs}"),
            )
        }
        Kind::SpeedRatio => {
            let limit = b.value * (1.0 - rel);
            (
                n.value < limit,
                limit,
                format!("same-run ratio may drop by {}%", 100.0 * rel),
            )
        }
    }
}

/// The verdicts as a markdown table.
pub fn markdown(v: &[Verdict]) -> String {
    let f = |x: Option<f64>| x.map_or("—".to_string(), |x| format!("{x:.4e}"));
    let mut s = String::from(
        "| metric | baseline | this run | limit | verdict |\n|---|---:|---:|---:|---|\n",
    );
    for r in v {
        s.push_str(&format!(
            "| `{}` | {} | {} | {} | {} |\n",
            r.metric,
            f(r.baseline),
            f(r.now),
            f(r.limit),
            if r.regressed {
                format!("**REGRESSED** ({})", r.note)
            } else {
                format!("ok ({})", r.note)
            }
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::results::{CodesignPart, CodesignRun};

    fn run(loss: f64, dist: f64) -> Results {
        Results {
            suite: "t".into(),
            codesign: vec![CodesignPart {
                name: "x".into(),
                task: "x".into(),
                horizon: 1,
                iters: 1,
                runs: vec![CodesignRun {
                    method: "co-design".into(),
                    design_variables: 1,
                    controller_variables: 1,
                    initial_loss: 1.0,
                    final_loss: loss,
                    history: vec![],
                    wall_seconds: 0.0,
                    forward_seconds_mean: 0.0,
                    backward_seconds_mean: 0.0,
                    min_distance: Some(dist),
                    distance: None,
                    upright_at_horizon: None,
                    first_fall_time: None,
                    grasped: None,
                    grasp_trajectories: None,
                    stopped: None,
                    ipc_hessian: None,
                }],
                fd: None,
                shapes_svg: None,
                unfinished: vec![],
            }],
            ..Default::default()
        }
    }

    #[test]
    fn worse_loss_and_vanishing_distance_regress_unchanged_passes() {
        let base = run(1.0, 1e-3);
        let tol = Tolerances::default();
        assert!(check(&base, &base, &tol).iter().all(|v| !v.regressed));
        assert!(
            check(&base, &run(1.04, 1e-3), &tol)
                .iter()
                .all(|v| !v.regressed)
        );
        let v = check(&base, &run(1.2, 1e-3), &tol);
        let bad: Vec<_> = v
            .iter()
            .filter(|v| v.regressed)
            .map(|v| v.metric.as_str())
            .collect();
        assert_eq!(bad, ["codesign.x.co-design.final_loss"]);
        let v = check(&base, &run(1.0, -1e-6), &tol);
        let bad: Vec<_> = v
            .iter()
            .filter(|v| v.regressed)
            .map(|v| v.metric.as_str())
            .collect();
        assert_eq!(bad, ["codesign.x.co-design.min_distance"]);
        // A per-metric rule loosens one metric only.
        let mut loose = Tolerances::default();
        loose.metrics.insert(
            "codesign.x.co-design.final_loss".into(),
            Rule {
                relative: Some(0.5),
                ..Default::default()
            },
        );
        assert!(
            check(&base, &run(1.2, 1e-3), &loose)
                .iter()
                .all(|v| !v.regressed)
        );
        // A metric the run lacks regresses.
        let v = check(&base, &Results::default(), &tol);
        assert!(v.iter().all(|v| v.regressed && v.now.is_none()));
    }
}
