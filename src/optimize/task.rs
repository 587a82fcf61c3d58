//! Task files for `sdrs optimize` (YAML, version 1).
//!
//! ```yaml
//! version: 1
//! scene: chain_reach.yaml        # scene file, relative to this file
//! horizon: 250                   # steps H (default: the scene's `steps`)
//! loss:                          # sum of weighted squared errors
//!   - {type: link_point, link: left/link7, point: [0, 0, -0.2], target: [1.5, 0, 4.0], weight: 1, when: final}
//!   - {type: joint, joint: left/cart, index: 0, target: 0, weight: 0.01, when: running}
//!   - {type: com, robot: box, target: [1, 0, 0], axes: [1, 1, 0], weight: 1, when: final}
//!   - {type: relative, link: box/box, point: [0,0,0], to_link: hand/palm, to_point: [0,0,0], offset: [0,0,0.1], weight: 1, when: running}
//! controller:
//!   joints: [left/cart]          # joints whose target-signal parameters are optimized
//!   gains: false                 # also each channel's k_p, k_d (default false)
//! design:                        # omit (or `sdrs optimize --design off`) for controller-only
//!   attachments: [left/link1, left/link2]   # attachment points as design variables
//!   vertices: [left/link3]       # every hull vertex of these links as design variables
//!   bound: 0.5                   # box half-width around each initial value (m; default 0.5)
//! optimizer:
//!   method: trust_region         # trust_region (paper) or adam
//!   iters: 60
//!   step_design: 0.05            # trust-region radius ᾱ_d (m) / Adam learning rate
//!   step_controller: 0.2         # ᾱ_c / Adam learning rate
//!   init_noise: 0.0              # uniform ± perturbation of the initial controller (seeded by --seed)
//!   design_init_noise: 0.0       # uniform ± perturbation (m) of the initial design, clamped to its bounds
//!   step_decay: 0.01             # Adam: cosine decay of the rates to this fraction (default: constant)
//!   plateau: {patience: 20, factor: 0.5}  # Adam: back to the best iterate after 20 iterations without a new best, rates × 0.5 (default: off)
//!   design_norm: euclidean       # trust region: norm of the design step's bound (or max)
//! metrics:                       # optional task metrics in summary.json (see optimize::metrics)
//!   robot: spider                # whose COM is tracked
//!   torso: spider/body           # link whose tilt decides "upright" and "fall"
//!   direction: [1, 0, 0]         # task direction (normalized) for "distance"
//!   up: [0, 0, 1]                # reference up (default: the ground normal, else +z)
//!   fall_tilt_deg: 45            # fallen when the tilt exceeds this (default 45)
//! ```
//! `when` is `final` (at θ^H), `running` (mean over θ^1 … θ^H) or a stage
//! `{window: {from: a, to: b}}` (mean over θ^{a+1} … θ^b).
//!
//! Several scenes optimized collectively (one design, losses summed; see
//! [`super::multi`]) replace `scene`/`loss` by a list:
//! ```yaml
//! trajectories:
//!   - {scene: scene_cube.yaml, loss: [...], grasp: {object: cube/cube, gripper: g/palm, from: 60}}
//!   - {scene: scene_ball.yaml, loss: [...]}
//! ```

use crate::diff::When;
use serde::{Deserialize, Serialize};

fn one() -> f64 {
    1.0
}
fn version() -> u32 {
    1
}
fn final_time() -> When {
    When::Final
}

/// A whole task.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TaskSpec {
    /// Schema version; must be 1. Default 1.
    #[serde(default = "version")]
    pub version: u32,
    /// The scene (empty when `trajectories` is given).
    #[serde(default)]
    pub scene: String,
    /// Steps `H` simulated per evaluation. Default: the scene's `steps`.
    #[serde(default)]
    pub horizon: Option<usize>,
    /// The loss: a sum of weighted terms.
    #[serde(default)]
    pub loss: Vec<LossSpec>,
    /// Several scenes optimized collectively (instead of `scene`/`loss`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub trajectories: Vec<super::multi::TrajectorySpec>,
    /// The grasp metric of a single-scene task (see [`super::grasp`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grasp: Option<super::grasp::GraspSpec>,
    /// Which controller parameters are optimized. Default none.
    #[serde(default)]
    pub controller: ControlSpec,
    /// Which design parameters are optimized; omitted (or `sdrs optimize
    /// --design off`): none, the controller alone.
    #[serde(default)]
    pub design: Option<DesignTaskSpec>,
    /// Optimizer settings.
    #[serde(default)]
    pub optimizer: OptimizerSpec,
    /// Task metrics reported in `summary.json` (see [`super::metrics`]).
    #[serde(default)]
    pub metrics: Option<super::metrics::MetricsSpec>,
}

/// One loss term (see [`crate::diff::LossTerm`]).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum LossSpec {
    /// Squared distance `weight · |A_link p − target|²` (m²) of a point on a link from a world target.
    LinkPoint {
        /// Link (`robot/link`).
        link: String,
        /// Point in the link frame (m). Default origin.
        #[serde(default)]
        point: [f64; 3],
        /// World target point (m).
        target: [f64; 3],
        /// Weight of the term. Default 1.
        #[serde(default = "one")]
        weight: f64,
        /// `final` (default: at the last step), `running` (mean over all steps) or `{window: {from: a, to: b}}` (mean over steps a+1 … b).
        #[serde(default = "final_time")]
        when: When,
    },
    /// Squared error `weight · (θ − target)²` (rad² or m²) of one joint coordinate.
    Joint {
        /// Joint name (`robot/joint`).
        joint: String,
        /// Coordinate of a multi-coordinate joint (0-based). Default 0.
        #[serde(default)]
        index: usize,
        /// Target value (rad or m).
        target: f64,
        /// Weight of the term. Default 1.
        #[serde(default = "one")]
        weight: f64,
        /// `final` (default: at the last step), `running` (mean over all steps) or `{window: {from: a, to: b}}` (mean over steps a+1 … b).
        #[serde(default = "final_time")]
        when: When,
    },
    /// Squared distance `weight · |axes ⊙ (c − target)|²` (m²) of a robot's centre of mass from a world target.
    Com {
        /// Robot name.
        robot: String,
        /// World target of the centre of mass (m).
        target: [f64; 3],
        /// Per-axis weights of the error (e.g. `[1, 1, 0]` ignores height). Default `[1, 1, 1]`.
        #[serde(default = "ones")]
        axes: [f64; 3],
        /// Weight of the term. Default 1.
        #[serde(default = "one")]
        weight: f64,
        /// `final` (default: at the last step), `running` (mean over all steps) or `{window: {from: a, to: b}}` (mean over steps a+1 … b).
        #[serde(default = "final_time")]
        when: When,
    },
    /// Squared distance `weight · |A_link p − (A_to_link p_to + offset)|²` (m²) between points on two links.
    Relative {
        /// Link (`robot/link`).
        link: String,
        /// Point in the link frame (m). Default origin.
        #[serde(default)]
        point: [f64; 3],
        /// The other link (`robot/link`).
        to_link: String,
        /// Point in the other link's frame (m). Default origin.
        #[serde(default)]
        to_point: [f64; 3],
        /// Desired world offset of the first point from the second (m). Default zero.
        #[serde(default)]
        offset: [f64; 3],
        /// Weight of the term. Default 1.
        #[serde(default = "one")]
        weight: f64,
        /// `final` (default: at the last step), `running` (mean over all steps) or `{window: {from: a, to: b}}` (mean over steps a+1 … b).
        #[serde(default = "final_time")]
        when: When,
    },
}

fn ones() -> [f64; 3] {
    [1.0; 3]
}

/// Which controller parameters are optimized.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ControlSpec {
    /// Joints (`robot/joint`) whose target signals' parameters are
    /// optimized.
    #[serde(default)]
    pub joints: Vec<String>,
    /// Also optimize their PD gains. Default false.
    #[serde(default)]
    pub gains: bool,
}

/// Which design parameters are optimized.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DesignTaskSpec {
    /// Links (`robot/link`) whose joint attachment points are design variables (m).
    #[serde(default)]
    pub attachments: Vec<String>,
    /// Links (`robot/link`) whose hull vertices are design variables (m).
    #[serde(default)]
    pub vertices: Vec<String>,
    /// Box bound: each design variable stays within this distance (m) of its initial value. Default 0.5.
    #[serde(default = "DesignTaskSpec::default_bound")]
    pub bound: f64,
    /// Each free-floating robot with designed links starts at the clearance
    /// above the ground its initial design has: the robot is moved along the
    /// ground's normal so that its lowest hull vertex at `θ^0` keeps that
    /// height, whatever the design (the move is part of the gradient;
    /// `src/optimize/rest.rs`). Needs a `ground:`. Default false (the
    /// scene's pose whatever the design).
    #[serde(default)]
    pub rest_on_ground: bool,
}

impl DesignTaskSpec {
    fn default_bound() -> f64 {
        0.5
    }
}

/// Optimizer choice.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// The paper's trust-region projected gradient step.
    TrustRegion,
    /// Adam (Kingma & Ba) with projection onto the bounds.
    Adam,
}

/// Which iterate an optimization run returns as its result.
#[derive(
    Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum ResultIterate {
    /// The iterate with the lowest loss seen (ties: the earliest). The
    /// trust region only accepts decreases, so for it this is always the
    /// last accepted iterate; Adam is not monotone, and its last iterate can
    /// be worse than one it passed through.
    #[default]
    Best,
    /// The last iterate, whatever its loss.
    Last,
}

/// How the trust-region radii change after a trial step (`adaptive`, `reset`:
/// both blocks, design and controller, together, as a trial moves both;
/// `split`: each block on its own outcome).
#[derive(
    Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum RadiusRule {
    /// An accepted step grows each radius ×1.25 (at most 4× its step), a
    /// rejected one halves it: the radius remembers the scale at which the
    /// last steps were accepted.
    #[default]
    Adaptive,
    /// An accepted step resets each radius to its step (the paper's fixed
    /// `ᾱ_d`, `ᾱ_c`); a rejected one halves it. Every iteration therefore
    /// starts at the paper's step and backtracks along the same gradient
    /// (the iterate, hence its gradient, is unchanged by a rejection) until
    /// the loss decreases. On a loss that is smooth only below a small
    /// scale ε but decreases along the gradient at a larger one (a ripple
    /// on a trend: `notes/locomotion-feet-and-radius.md` measures ε ≈ 3e-4 on the spider's gait
    /// parameters), `adaptive` settles at radius ≈ ε and gains ≈ ε‖g‖ per
    /// step, whereas `reset` tries the large scale first every iteration.
    Reset,
    /// `reset`, with the two blocks backtracked separately, each radius
    /// adapted on its own trials, so that a design step that fails cannot
    /// throttle the controller and a controller step that fails cannot
    /// shrink the design radius (`notes/locomotion-feet-and-radius.md`:
    /// under `reset` a rejected trial halves both radii, and the spider's
    /// co-design advanced its controller 4× less per accepted step than its
    /// controller-only twin). Radii `(r_d, r_c)` (initially `(ᾱ_d, ᾱ_c)`)
    /// and a phase (initially *joint*); `TR` is the trust-region step:
    /// - *joint*: `Δd = TR(∇_d L, r_d)`, `Δc = −r_c ∇_c L/‖∇_c L‖`.
    ///   Accepted → both radii reset to `(ᾱ_d, ᾱ_c)`, stay joint;
    ///   rejected → *design* phase, radii unchanged.
    /// - *design*: the design step alone (`Δc = 0`) at `r_d`. Accepted →
    ///   `r_d ← ᾱ_d`; rejected → `r_d ← r_d/2`; either way → *controller*.
    /// - *controller*: the controller step alone (`Δd = 0`) at `r_c`, the
    ///   radius of the rejected joint trial first. Accepted → `r_c ← ᾱ_c`,
    ///   → *joint*; rejected → `r_c ← r_c/2`, stay.
    /// - a joint trial in which one block does not move (`--design off`, a
    ///   zero gradient) follows `reset`, and so does a controller trial with
    ///   `∇_c L = 0` (→ joint).
    ///
    /// Cost: the controller's ladder `ᾱ_c, ᾱ_c/2, …` costs two trials more
    /// per accepted controller step than without a design block (the joint
    /// and the design trial); `--design off` is bitwise the `reset` run.
    Split,
    /// The paper's update as written ("Implementation": each iteration
    /// takes `argmin ∇Lᵀ[Δd; Δc]` subject to the bounds and `‖Δd‖ ≤ ᾱ_d`,
    /// `‖Δc‖ ≤ ᾱ_c`, with no acceptance test): every trial is taken, the
    /// loss rising or falling, and the radii stay at `(ᾱ_d, ᾱ_c)`. The walk
    /// is not monotone, so a run returns its best iterate (`result: best`,
    /// the default) unless told otherwise. A trial that cannot be simulated
    /// is retried at half length from the same iterate, as Adam's (at most
    /// four times; then the run stops there and says so). `adaptive`,
    /// `reset` and `split` accept only a lower loss.
    Fixed,
}

impl RadiusRule {
    /// Radius after a trial of radius `r`, for a block whose task step is
    /// `step` (formulas on the variants; `split`'s per-block bookkeeping is
    /// [`crate::optimize::method::Radii`], which uses this for the trials
    /// that follow `reset`).
    pub fn next(self, r: f64, step: f64, accepted: bool) -> f64 {
        match (self, accepted) {
            (RadiusRule::Fixed, _) => step,
            (_, false) => 0.5 * r,
            (RadiusRule::Adaptive, true) => (r * 1.25).min(4.0 * step),
            (RadiusRule::Reset | RadiusRule::Split, true) => step,
        }
    }
}

/// The norm of the design block's trust region, `‖Δd‖ ≤ r_d` (the paper's
/// `‖Δd‖ ≤ ᾱ_d` leaves it open).
#[derive(
    Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum DesignNorm {
    /// `‖Δd‖₂ ≤ r_d` over all design coordinates: with n coordinates moving
    /// alike, each moves about `r_d/√n`.
    #[default]
    Euclidean,
    /// `max_i |Δd_i| ≤ r_d`: every coordinate may move by up to `r_d`; the
    /// step is `clamp(−r_d sign(g_i), lo_i − d_i, hi_i − d_i)`.
    Max,
}

/// `optimizer.plateau` (Adam, and the trust region under `radius: fixed`,
/// the two walks that leave their best iterate): when the best loss has not
/// improved for `patience` consecutive iterations, the next iteration starts
/// from the best iterate (evaluated there again), with Adam's moments reset
/// and both learning rates (Adam) or both radii ᾱ_d, ᾱ_c (`fixed`: after `n`
/// returns the step is `factorⁿ (ᾱ_d, ᾱ_c)`) multiplied by `factor`
/// (cumulatively, and on top of `step_decay`'s schedule). The count
/// restarts after each return. Why: on a loss that is a staircase of
/// contact regimes (a grasp held or not), Adam's walk passes through a good
/// regime and leaves it without any memory of it, and on a regime where
/// nothing touches the gradient is 0 and the walk stops there
/// (`notes/adam-plateau-restarts.md`). Part of the checkpoint: a resumed
/// run is bitwise the uninterrupted one.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Plateau {
    /// Iterations without a new best loss before a return (≥ 1).
    pub patience: usize,
    /// Factor on both learning rates at each return, in (0, 1].
    pub factor: f64,
}

/// Optimizer settings (defaults documented on each field).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct OptimizerSpec {
    /// Default `trust_region`.
    pub method: Method,
    /// Iterations (forward + backward each). Default 60.
    pub iters: usize,
    /// Trust-region radius for the design (m) / Adam learning rate. Default 0.05.
    pub step_design: f64,
    /// Trust-region radius for the controller / Adam learning rate. Default 0.2.
    pub step_controller: f64,
    /// Half-width of a uniform random perturbation of every initial
    /// controller parameter, drawn from ChaCha8 seeded by `--seed`.
    /// Default 0 (no randomness).
    pub init_noise: f64,
    /// Half-width (m) of a uniform random perturbation of every initial
    /// design variable, each then clamped to its bounds; drawn from the
    /// same ChaCha8 stream as `init_noise`, after the controller's draws.
    /// For several starts of one task on a loss with many contact regimes
    /// (`--seed 1`, `--seed 2`, …; notes/multistart-design-noise.md).
    /// Default 0 (the task's design as imported).
    pub design_init_noise: f64,
    /// The iterate returned, exported and measured (`design.yaml`,
    /// `summary.json`'s final loss and task metrics): `best` (default) or
    /// `last`. `history.csv` lists every iterate either way.
    pub result: ResultIterate,
    /// Adam only: the design gradient is rescaled to at most this Euclidean
    /// norm (the loss's units per metre) before it enters Adam's moments, so
    /// that one spike (a contact switching on or off in a long trajectory)
    /// cannot dominate the second moment and stall every later step for
    /// ~1/(1 − β₂) = 1000 iterations. Default none (no clipping). `history.csv`
    /// keeps the unclipped norm.
    pub clip_design: Option<f64>,
    /// Adam only: the same for the controller gradient. Default none.
    pub clip_controller: Option<f64>,
    /// Adam only, tasks with `trajectories:`: each trajectory's design
    /// gradient `∇_d L_j` is rescaled to at most this Euclidean norm before
    /// the sum, `g = Σ_j ∇_d L_j · min(1, c/‖∇_d L_j‖)` (then `clip_design`
    /// applies to `g`). Why: a trajectory whose object has slipped out and
    /// rolls on the ground has a valid but huge gradient (its sensitivity
    /// grows exponentially, ~1e6 against ~1e-3 for the others; see
    /// notes/grasping-topology-change.md), and clipping only the sum would
    /// scale every other trajectory's gradient down by that factor. Default
    /// none (the plain sum). `history.csv` keeps the unclipped norm.
    pub clip_trajectory: Option<f64>,
    /// Adam only: the learning rates follow a cosine from their value at the
    /// first iteration down to this fraction of it at the run's last,
    /// `α_k = α (f + (1 − f)(1 + cos(π (k − 1)/(K − 1)))/2)` for
    /// iteration k of K, so that the last iterate settles instead of
    /// oscillating at the step's scale around a minimum (a run whose loss
    /// jumps between regimes ends wherever its last step lands). Default
    /// none (constant rates, the paper's Adam).
    pub step_decay: Option<f64>,
    /// Adam and `radius: fixed` only: return to the best iterate on a
    /// plateau (see [`Plateau`]).
    /// Default none (Adam walks on from wherever its last step landed).
    pub plateau: Option<Plateau>,
    /// Trust region only: how the radii change after a trial. Default
    /// `adaptive` (see [`RadiusRule`]).
    pub radius: RadiusRule,
    /// Trust region only: the norm of the design step's bound. Default
    /// `euclidean` (see [`DesignNorm`]).
    pub design_norm: DesignNorm,
    /// Newton tolerance (`‖∇O‖∞`, the scene's `solver.tol`) of every
    /// forward pass of this task, replacing the scene's. The adjoint
    /// gradient is the derivative of the loss at an exact step minimiser; a
    /// loose tolerance leaves each step's minimiser off by up to
    /// `tol / λ_min(∇²O)`, an error that changes discontinuously with the
    /// parameters (the Newton iteration count jumps), so the computed loss
    /// is not the function the gradient describes at small scales.
    /// Default none (the scene's).
    pub newton_tol: Option<f64>,
}

impl Default for OptimizerSpec {
    fn default() -> Self {
        OptimizerSpec {
            method: Method::TrustRegion,
            iters: 60,
            step_design: 0.05,
            step_controller: 0.2,
            init_noise: 0.0,
            design_init_noise: 0.0,
            result: ResultIterate::Best,
            clip_design: None,
            clip_controller: None,
            clip_trajectory: None,
            step_decay: None,
            plateau: None,
            radius: RadiusRule::Adaptive,
            design_norm: DesignNorm::Euclidean,
            newton_tol: None,
        }
    }
}
