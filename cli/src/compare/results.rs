//! What a `sdrs compare` run measured (`results.json`), and the flat list of
//! gated metrics derived from it.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The whole run.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Results {
    pub suite: String,
    /// rayon worker threads of the run.
    pub threads: usize,
    pub potential: Option<PotentialPart>,
    pub chains: Option<ChainsPart>,
    #[serde(default)]
    pub codesign: Vec<CodesignPart>,
    /// Benchmarks that were not measured, with the reason (shown in the report).
    #[serde(default)]
    pub not_measured: Vec<String>,
}

/// Contact potential cost (paper Fig. "cost-time").
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PotentialPart {
    pub rows: Vec<PotentialRow>,
    /// The friction potentials on the same pairs, sliding.
    #[serde(default)]
    pub friction: Vec<FrictionRow>,
    /// ipc-toolkit's timing per vertex count, when it ran.
    pub ipctk: Option<BTreeMap<usize, f64>>,
    /// Why ipctk was not timed (missing tool, error).
    pub ipctk_note: Option<String>,
    pub wall_seconds: f64,
}

/// One vertex count: medians over the pairs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PotentialRow {
    pub vertices: usize,
    pub sdrs_us: f64,
    pub ipc_us: f64,
    /// `ipc_us / sdrs_us`, each pair's ratio measured in the same call, median over pairs.
    pub ratio: f64,
    pub candidates: f64,
    pub active: f64,
}

/// Friction potential cost at one vertex count: medians over the pairs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FrictionRow {
    pub vertices: usize,
    pub sdrs_us: f64,
    pub ipc_us: f64,
    pub ratio: f64,
    /// IPC lagged stencils of the pair.
    pub ipc_contacts: f64,
}

/// Four rotating chains (paper Fig. "bench-time", Table "performance").
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ChainsPart {
    pub steps: usize,
    /// Runs per model and size (the fastest is reported).
    #[serde(default)]
    pub repeats: usize,
    pub dt: f64,
    pub rows: Vec<ChainRow>,
    pub wall_seconds: f64,
}

/// One model at one chain length.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ChainRow {
    pub model: String,
    pub links: usize,
    pub dof: usize,
    pub ms_per_step: f64,
    pub newton_iterations: f64,
    /// Forward stages, ms per step.
    pub stages: BTreeMap<String, f64>,
    /// The adjoint over the same horizon, ms per step (SDRS only).
    pub backward_ms_per_step: Option<f64>,
    pub steps_in_contact: usize,
    /// Our minimum hull distance over the run (m).
    pub min_distance: Option<f64>,
    /// python-fcl's, when checked (m).
    pub fcl_min_distance: Option<f64>,
    pub fcl_note: Option<String>,
}

/// One co-design benchmark.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CodesignPart {
    pub name: String,
    pub task: String,
    pub horizon: usize,
    pub iters: usize,
    /// `co-design` and `controller-only`, plus rows for methods not built.
    pub runs: Vec<CodesignRun>,
    pub fd: Option<FdCheck>,
    /// Initial vs optimized designed links (SVG file under the output
    /// directory), when the design has hull vertices.
    #[serde(default)]
    pub shapes_svg: Option<String>,
    /// Methods of the benchmark not finished yet (`--report-only` on an
    /// unfinished run; empty otherwise).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unfinished: Vec<String>,
}

/// One optimization.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CodesignRun {
    pub method: String,
    pub design_variables: usize,
    pub controller_variables: usize,
    pub initial_loss: f64,
    pub final_loss: f64,
    /// Best loss after each iteration (iteration 0 = initial).
    pub history: Vec<f64>,
    pub wall_seconds: f64,
    pub forward_seconds_mean: f64,
    pub backward_seconds_mean: f64,
    /// Minimum hull distance over the final design's trajectory (m).
    pub min_distance: Option<f64>,
    /// Task metrics of the final design (locomotion: distance walked along
    /// the task direction (m), upright at H, first fall (s)), when the task
    /// defines them.
    #[serde(default)]
    pub distance: Option<f64>,
    #[serde(default)]
    pub upright_at_horizon: Option<bool>,
    #[serde(default)]
    pub first_fall_time: Option<f64>,
    /// Grasping tasks: objects grasped by the final design, out of
    /// `grasp_trajectories`.
    #[serde(default)]
    pub grasped: Option<usize>,
    #[serde(default)]
    pub grasp_trajectories: Option<usize>,
    /// Why the run ended before its last iteration (an Adam step that could
    /// not be simulated, `sdrs::optimize::Outcome::stopped`); the row then
    /// holds the iterations that ran.
    #[serde(default)]
    pub stopped: Option<String>,
    /// Mesh-baseline rows: the per-primitive Hessians of the IPC baseline's
    /// Newton (`contact.ipc.hessian`: `exact` or `projected`). Rows
    /// recorded before 2026-12-02 carry none: they used `projected`, the
    /// only choice then. `None` for SDRS rows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ipc_hessian: Option<sdrs_ipc::settings::HessianKind>,
}

/// Central differences of one design-gradient component at the initial design.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FdCheck {
    pub variable: String,
    pub adjoint: f64,
    pub central_difference: f64,
    pub h: f64,
    pub relative_error: f64,
    /// Newton tolerance of the check's solves (absent in results written
    /// before it was recorded: those used the task's own tolerance).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub newton_tol: Option<f64>,
    /// `richardson`: `(4 D(h) − D(2h)) / 3`. Absent in results written
    /// before: a plain central difference `D(h)`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator: Option<String>,
    /// Standard deviation of `central_difference` due to the loss's measured
    /// round-off noise (`sdrs::diff::central`). Absent in older results.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub difference_noise: Option<f64>,
    /// Whether the differences resolve the component to 1e-4 (twice their
    /// noise within 1e-4 of it); when not, `relative_error` measures the
    /// differences' noise as much as the adjoint. Absent in older results.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolved: Option<bool>,
    /// When the check at the first step did not pass resolved and a
    /// smaller step agreed (`sdrs::diff::descending`): the first step and
    /// its relative error, and the halvings taken; `h`, `central_difference`,
    /// `relative_error`, `difference_noise` and `resolved` are then the
    /// agreeing step's. Absent when there was no descent or it found no
    /// agreement (the fields above are the first step's then).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub descended_from: Option<Descended>,
}

/// The first step of a gradient check that descended (see
/// [`FdCheck::descended_from`]).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Descended {
    pub h: f64,
    pub relative_error: f64,
    /// Halvings from `h` to the agreeing step.
    pub halvings: usize,
}

/// Which way a metric improves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Better {
    Lower,
    Higher,
}

/// What a metric measures (selects the default tolerance).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// A task loss (lower is better).
    Loss,
    /// A minimum distance (m): must stay positive.
    Distance,
    /// A relative gradient error.
    GradientError,
    /// A speed ratio measured in one run (baseline time / SDRS time).
    SpeedRatio,
    /// A task metric where higher is better (distance walked, m).
    Task,
}

/// One gated metric.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metric {
    pub value: f64,
    pub better: Better,
    pub kind: Kind,
}

impl Results {
    /// Every gated metric, by name (`codesign.chain_reach.co-design.final_loss`, …).
    pub fn metrics(&self) -> BTreeMap<String, Metric> {
        let mut m = BTreeMap::new();
        let mut put = |k: String, value: f64, better, kind| {
            if value.is_finite() {
                m.insert(
                    k,
                    Metric {
                        value,
                        better,
                        kind,
                    },
                );
            }
        };
        if let Some(p) = &self.potential {
            for r in &p.rows {
                put(
                    format!("potential.{}.ipc_over_sdrs", r.vertices),
                    r.ratio,
                    Better::Higher,
                    Kind::SpeedRatio,
                );
            }
            for r in &p.friction {
                put(
                    format!("friction.{}.ipc_over_sdrs", r.vertices),
                    r.ratio,
                    Better::Higher,
                    Kind::SpeedRatio,
                );
            }
        }
        if let Some(c) = &self.chains {
            for r in &c.rows {
                if let Some(d) = r.min_distance {
                    put(
                        format!("chains.{}.{}.min_distance", r.model, r.links),
                        d,
                        Better::Higher,
                        Kind::Distance,
                    );
                }
                if let Some(d) = r.fcl_min_distance {
                    put(
                        format!("chains.{}.{}.fcl_min_distance", r.model, r.links),
                        d,
                        Better::Higher,
                        Kind::Distance,
                    );
                }
            }
            for s in c.rows.iter().filter(|r| r.model == "sdrs") {
                if let Some(i) = c
                    .rows
                    .iter()
                    .find(|r| r.model == "ipc" && r.links == s.links)
                {
                    put(
                        format!("chains.{}.ipc_over_sdrs", s.links),
                        i.ms_per_step / s.ms_per_step,
                        Better::Higher,
                        Kind::SpeedRatio,
                    );
                }
            }
        }
        for b in &self.codesign {
            for r in &b.runs {
                put(
                    format!("codesign.{}.{}.final_loss", b.name, r.method),
                    r.final_loss,
                    Better::Lower,
                    Kind::Loss,
                );
                if let Some(d) = r.distance {
                    put(
                        format!("codesign.{}.{}.distance_walked", b.name, r.method),
                        d,
                        Better::Higher,
                        Kind::Task,
                    );
                }
                if let Some(g) = r.grasped {
                    put(
                        format!("codesign.{}.{}.grasped", b.name, r.method),
                        g as f64,
                        Better::Higher,
                        Kind::Task,
                    );
                }
                if let Some(d) = r.min_distance {
                    put(
                        format!("codesign.{}.{}.min_distance", b.name, r.method),
                        d,
                        Better::Higher,
                        Kind::Distance,
                    );
                }
            }
            if let Some(fd) = &b.fd {
                put(
                    format!("codesign.{}.gradient_error", b.name),
                    fd.relative_error,
                    Better::Lower,
                    Kind::GradientError,
                );
            }
        }
        m
    }
}
