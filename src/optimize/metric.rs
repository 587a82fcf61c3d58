//! The metrics of a co-design run behind one trait: what `summary.json`
//! reports under `extra.metrics` at the start and at the result of a run.
//!
//! - [`GraspMetric`] (`grasp`): the grasp of every trajectory with a
//!   `grasp:` spec ([`super::grasp`]), before and after;
//! - [`TopologyMetric`] (`topology`): the Betti numbers of every designable
//!   link ([`crate::geometry::topology`]), before and after, and whether
//!   they changed;
//! - [`super::metrics::Metrics`] (locomotion, with the task's `metrics:`
//!   section; `initial`, `final`, `definitions`): distance walked, upright
//!   at the horizon, first fall.
//!
//! [`task_metrics`] lists the metrics of a task, [`summarize`] merges their
//! entries.

use super::metrics::Metrics;
use super::{OptimizeError, Outcome, Problem, TaskError, grasp, grasp_metrics};
use nalgebra::DVector;
use serde_json::{Map, Value};

/// A metric of a co-design run.
pub trait Metric: Sync {
    /// The entries this metric adds to `extra.metrics` for a run that
    /// started at design and controller `start` and ended at `outcome`.
    fn summary(
        &self,
        p: &Problem,
        start: (&DVector<f64>, &DVector<f64>),
        outcome: &Outcome,
    ) -> Result<Map<String, Value>, OptimizeError>;
}

/// Serializes a measured value (a failure names `what`).
fn json(what: &str, v: impl serde::Serialize) -> Result<Value, OptimizeError> {
    serde_json::to_value(v).map_err(|e| OptimizeError::serialize(what, e))
}

/// The grasp of every trajectory with a `grasp:` spec, before and after.
pub struct GraspMetric;

impl Metric for GraspMetric {
    fn summary(
        &self,
        p: &Problem,
        (d0, c0): (&DVector<f64>, &DVector<f64>),
        o: &Outcome,
    ) -> Result<Map<String, Value>, OptimizeError> {
        let before = grasp::measure(p, d0, c0)?;
        let after = grasp::measure(p, &o.design, &o.controller)?;
        let count = |v: &[grasp::GraspResult]| v.iter().filter(|g| g.grasped).count();
        let (n, n0, n1) = (before.len(), count(&before), count(&after));
        let (before, after) = (json("grasp", &before)?, json("grasp", &after)?);
        let mut m = Map::new();
        m.insert(
            "grasp".into(),
            serde_json::json!({
                "trajectories": n,
                "grasped_before": n0,
                "grasped_after": n1,
                "before": before,
                "after": after,
            }),
        );
        Ok(m)
    }
}

/// The topology of every designable link, before and after.
pub struct TopologyMetric;

impl Metric for TopologyMetric {
    fn summary(
        &self,
        p: &Problem,
        (d0, _): (&DVector<f64>, &DVector<f64>),
        o: &Outcome,
    ) -> Result<Map<String, Value>, OptimizeError> {
        let t0 = grasp_metrics::topologies(p, d0)?;
        let t1 = grasp_metrics::topologies(p, &o.design)?;
        // A topology change: some link's (components, holes, cavities) differ.
        let betti = |t: &Value| -> Vec<Value> {
            t.as_object()
                .map(|m| {
                    m.values()
                        .map(|v| serde_json::json!([v["components"], v["holes"], v["cavities"]]))
                        .collect()
                })
                .unwrap_or_default()
        };
        let changed = betti(&t0) != betti(&t1);
        let mut m = Map::new();
        m.insert(
            "topology".into(),
            serde_json::json!({
                "resolution": grasp_metrics::TOPOLOGY_RESOLUTION,
                "before": t0,
                "after": t1,
                "changed": changed,
            }),
        );
        Ok(m)
    }
}

/// How the locomotion metric's figures are defined (the `definitions`
/// entry of `summary.json`).
pub const LOCOMOTION_DEFINITIONS: &str = "distance = (COM(H) - COM(0)) . direction (m); tilt = angle (deg) between the reference up n and the torso's initially-up axis; fall = first step with tilt > fall_tilt_deg; upright_at_horizon = tilt(H) <= fall_tilt_deg (see sdrs::optimize::metrics)";

impl Metric for Metrics {
    fn summary(
        &self,
        p: &Problem,
        (d0, c0): (&DVector<f64>, &DVector<f64>),
        o: &Outcome,
    ) -> Result<Map<String, Value>, OptimizeError> {
        let mut m = Map::new();
        m.insert("initial".into(), json("initial", self.measure(p, d0, c0)?)?);
        m.insert(
            "final".into(),
            json("final", self.measure(p, &o.design, &o.controller)?)?,
        );
        m.insert("definitions".into(), LOCOMOTION_DEFINITIONS.into());
        Ok(m)
    }
}

/// The metrics of task `p`: grasp and topology always, locomotion with the
/// task's `metrics:` section (resolved here: an error names the element).
pub fn task_metrics(p: &Problem) -> Result<Vec<Box<dyn Metric>>, TaskError> {
    let mut out: Vec<Box<dyn Metric>> = vec![Box::new(GraspMetric), Box::new(TopologyMetric)];
    if let Some(m) = Metrics::from_problem(p)? {
        out.push(Box::new(m));
    }
    Ok(out)
}

/// Every metric's entries, merged in order (a later entry replaces an
/// earlier one of the same name).
pub fn summarize(
    p: &Problem,
    metrics: &[Box<dyn Metric>],
    start: (&DVector<f64>, &DVector<f64>),
    outcome: &Outcome,
) -> Result<Value, OptimizeError> {
    let mut out = Map::new();
    for m in metrics {
        out.extend(m.summary(p, start, outcome)?);
    }
    Ok(Value::Object(out))
}
