//! Scene file schema (YAML, version 1). Every field documents its default;
//! unknown fields are errors (typos must not be silently ignored).
//!
//! ```yaml
//! version: 1                 # schema version (required to be 1 if given)
//! dt: 0.001                  # time step Δt in s (> 0, required)
//! steps: 1000                # number of steps (default 1000; CLI --steps overrides)
//! gravity: [0, 0, -9.81]     # m/s², world frame, z up (default shown)
//! solver:                    # Newton options (defaults: paper values)
//!   tol: 1.0e-4              #   stop when ‖∇O‖∞ < tol
//!   max_iters: 100
//!   eig_clamp: 1.0e-3        #   Hessian eigenvalue floor
//!   max_backtracks: 60
//!   predictor: adaptive      #   start at the cubic or quadratic extrapolation, whichever was closer last step (`cubic`, `quadratic`, `extrapolate`: 2θ^t − θ^{t−1}; `previous`: θ^t)
//!   indefinite: shift        #   Newton model of blocks with λ ≤ eig_clamp (or `clamp`)
//!   settle_blocks: true      #   no re-solve of independent blocks already below tol
//! robots:
//!   - name: arm
//!     base: {xyz: [0, 0, 1], rpy: [0, 0, 0]}   # world pose of the root attachment (default identity)
//!     links:                 # parents before or after children, any order; no cycles
//!       - name: upper
//!         parent: ~          # omitted/null: attached to the base
//!         joint:
//!           name: shoulder   # default: the link name
//!           type: revolute   # fixed | revolute | prismatic | ball | spherical | free
//!           axis: [0, 1, 0]  # revolute/prismatic: unit axis in the joint frame
//!           # axes: [[1,0,0],[0,1,0]]   # ball: two orthogonal hinge axes
//!           origin: {xyz: [0, 0, 0], rpy: [0, 0, 0]}   # attachment in the parent frame;
//!           # limit: {lower: -1.5, upper: 1.5}   # revolute/prismatic: barrier-enforced limits
//!           # mimic: {joint: other, multiplier: 1, offset: 0}   # tied to another joint (stiffness 1e4)
//!                            # xyz is the design-dependent attachment point
//!         mass: 1.0          # kg, divided equally over all hull vertices …
//!         # vertex_mass: 0.125   # … or kg per vertex (the paper's ρ); exactly one of the two
//!         # mass_model: {type: solid}   # vertices (default) | solid {density} | given
//!         #                  {mass, com, inertia: [ixx,ixy,ixz,iyy,iyz,izz]}: see MassModelSpec
//!         hulls:
//!           - vertices: [[0,0,0], [1,0,0], [0,1,0], [0,0,1]]   # ≥ 4, not coplanar
//!           - box: {size: [0.1, 0.1, 1.0], center: [0, 0, -0.5]}
//!         # collide: false   # no contact for this link (default true)
//!         # surface_mesh: arm_meshes/upper.source.obj   # source mesh (IPC `contact.ipc.surface: source`)
//!     # chain: {links: 8, ...}   # generates `links` instead (see ChainSpec)
//!     controller:
//!       kp: 100              # default gains for every target (J/rad²; default 0)
//!       kd: 1                # J s²/rad² (default 0)
//!       gains: {shoulder: {kp: 200, kd: 2}}          # per-joint overrides
//!       targets:             # per joint: one signal per coordinate (list) or one signal
//!         shoulder: {type: sine, offset: 0, terms: [{amplitude: 0.5, frequency: 1, phase: 0}]}
//!     initial:               # per joint (default zeros)
//!       shoulder: {q: [0.1], qdot: [0.0]}
//! effects:                   # optional extra physics (default none; written by `sdrs calibrate`)
//!   - {effect: joint_damping, on: all, values: [0.05]}      # c (N·m·s/rad), every joint coordinate
//!   - {effect: joint_friction, on: shoulder, values: [0.2], eps: 1.0e-4}  # f (N·m); ε ((rad/s)², default 1e-4)
//!   - {effect: stribeck_friction, on: shoulder, values: [0.1, 0.3]}  # f_c, Δf (N·m): Coulomb
//!                            #   level and breakaway excess, v_s = 0.1 rad/s; eps as for joint_friction
//!   - {effect: armature, on: all, values: [0.01]}           # a (kg·m²)
//!   - {effect: actuator_gain, on: all, values: [0.8]}       # g: k_p, k_d → g·k_p, g·k_d
//!   - {effect: actuator_deadband, on: all, values: [0.01]}  # b (rad or m): PD position error
//!                            #   deadband (smoothed over 1e-3)
//!   - {effect: joint_offset, on: shoulder, values: [0.02]}  # encoder bias (rad); measurement only,
//!                            #   `sdrs simulate` writes physical coordinates
//!   - {effect: payload, on: upper, values: [0.5, 0.1, 0, 0]}  # m (kg), x y z (m, link frame)
//!   - {effect: link_mass_scale, on: all, values: [1.1]}     # σ (link name or all)
//!   - {effect: contact_mu, values: [0.6]}                   # μ; also contact_kappa (J·m),
//!                            #   contact_s (m); override `contact:` (needs it)
//! ```
//!
//! `on` is `all` (default: one value shared by every revolute, prismatic
//! and ball coordinate, or every link with mass), a coordinate's column name
//! as in the trajectory CSV, or a link name (`robot/link` when the scene
//! has several robots or objects). Units and formulas: the module docs of
//! `crate::energy::effects::*`.

use crate::control::Signal;
use crate::sim::NewtonOptions;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

fn default_steps() -> usize {
    1000
}
fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}
fn default_version() -> u32 {
    1
}

/// A whole scene.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// Schema version; must be 1. Default 1.
    #[serde(default = "default_version")]
    pub version: u32,
    /// Δt (s).
    pub dt: f64,
    /// Number of steps to simulate (`sdrs simulate --steps` overrides). Default 1000.
    #[serde(default = "default_steps")]
    pub steps: usize,
    /// Gravity (m/s², world frame, z up). Default `[0, 0, -9.81]`.
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    /// Newton solver options of every step (defaults: the paper's values).
    #[serde(default)]
    pub solver: NewtonOptions,
    /// The articulated robots. Default none.
    #[serde(default)]
    pub robots: Vec<RobotSpec>,
    /// Free rigid objects (6-DOF bodies made of hulls).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub objects: Vec<ObjectSpec>,
    /// A static ground half-space (as a large box hull).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<GroundSpec>,
    /// Static convex obstacles.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub obstacles: Vec<ObstacleSpec>,
    /// Contact and friction parameters; contact is off when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactSpec>,
    /// Extra physical effects (written by `sdrs calibrate`; default none).
    /// See [`crate::energy::effects`].
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub effects: Vec<crate::energy::effects::EffectSpec>,
}

/// A free rigid object: one link on a 6-DOF free joint named after the
/// object (coordinates `[x, y, z, rx, ry, rz]`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Object name; also the name of its free joint and of its CSV columns.
    pub name: String,
    /// Total mass (kg), divided equally over the hull vertices; or give `vertex_mass`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    /// Mass per hull vertex (kg, the paper's ρ); exactly one of `mass` and `vertex_mass`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertex_mass: Option<f64>,
    /// Mass model: `vertices` (default: the link's mass lumped at its hull
    /// vertices, the paper's model), `solid` (uniform-density solid hulls)
    /// or `given` (explicit inertial). See [`MassModelSpec`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass_model: Option<MassModelSpec>,
    /// Convex hulls in the object's frame (m).
    pub hulls: Vec<HullSpec>,
    /// Source surface mesh of this body (`.obj`, `.stl` or `.dae`; path
    /// relative to the scene file; coordinates in the body's frame, m): the
    /// mesh its hulls were made from. `sdrs import` writes one per link
    /// (`<stem>_meshes/<link>.source.obj`). Used only by the IPC baseline
    /// with `contact.ipc.surface: source` (a closed, consistently oriented,
    /// non-self-intersecting triangle mesh is required then). Default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface_mesh: Option<String>,
    /// Initial pose `[x, y, z, rx, ry, rz]` (m, rotation vector) and velocity
    /// `[vx, vy, vz, ωx, ωy, ωz]` (world linear, body angular). Default zero.
    #[serde(default)]
    pub initial: InitialSpec,
}

/// Static ground: the half-space below a plane through `height` whose
/// normal is +z tilted by `slope_deg` about `slope_axis`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GroundSpec {
    /// Height of the plane at the origin (m). Default 0.
    #[serde(default)]
    pub height: f64,
    /// Tilt (degrees). Default 0.
    #[serde(default)]
    pub slope_deg: f64,
    /// Tilt axis (world, unit). Default `[0, 1, 0]`: the ground descends
    /// towards +x for a positive slope.
    #[serde(default = "GroundSpec::default_axis")]
    pub slope_axis: [f64; 3],
    /// Half-extent of the ground box (m). Default 50.
    #[serde(default = "GroundSpec::default_size")]
    pub half_size: f64,
    /// Thickness of the ground box (m). Default 1.
    #[serde(default = "GroundSpec::default_thickness")]
    pub thickness: f64,
}

impl GroundSpec {
    fn default_axis() -> [f64; 3] {
        [0.0, 1.0, 0.0]
    }
    fn default_size() -> f64 {
        50.0
    }
    fn default_thickness() -> f64 {
        1.0
    }
}

/// A static obstacle: hulls at a fixed world pose.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ObstacleSpec {
    /// Obstacle name (used in contact statistics and errors).
    pub name: String,
    /// World pose of the obstacle's frame. Default identity.
    #[serde(default)]
    pub origin: Origin,
    /// Convex hulls in the obstacle's frame (m).
    pub hulls: Vec<HullSpec>,
    /// Source surface mesh of this body (`.obj`, `.stl` or `.dae`; path
    /// relative to the scene file; coordinates in the body's frame, m): the
    /// mesh its hulls were made from. `sdrs import` writes one per link
    /// (`<stem>_meshes/<link>.source.obj`). Used only by the IPC baseline
    /// with `contact.ipc.surface: source` (a closed, consistently oriented,
    /// non-self-intersecting triangle mesh is required then). Default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface_mesh: Option<String>,
}

/// Contact and friction parameters (paper, `contact.tex`, `friction.tex`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Which contact model the scene uses: `sdrs` (default: the core's
    /// separating-plane potential) or `ipc` (the mesh-based Incremental
    /// Potential Contact baseline in `baselines/ipc`, provided by the `sdrs`
    /// CLI through [`crate::scene::ContactModelFactory`]). With `sdrs` the
    /// `ipc` section below is ignored and nothing changes.
    #[serde(default, skip_serializing_if = "ContactModelKind::is_sdrs")]
    pub model: ContactModelKind,
    /// The IPC baseline's own settings, read and checked by the baseline
    /// (`baselines/ipc/src/settings.rs`), not by the core:
    /// `{surface: hulls|source, dhat: 1e-3, eps_v: 1e-3}` — each link's
    /// contact surface (its hulls' triangulated boundaries, or its
    /// `surface_mesh`), the barrier activation distance `d̂` (m) and the
    /// friction smoothing speed `ε_v` (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schemars(with = "Option<serde_json::Value>")]
    pub ipc: Option<serde_yaml::Value>,
    /// `surface`, `dhat` and `eps_v` directly under `contact:` — where the
    /// IPC baseline's keys were before they moved into `ipc` (2026-11-26).
    /// Read only to be refused with their new place
    /// ([`super::environment::contact_settings`]), instead of serde's bare
    /// "unknown field".
    #[serde(default, rename = "surface", skip_serializing)]
    #[schemars(skip)]
    pub moved_surface: Option<serde_yaml::Value>,
    #[serde(default, rename = "dhat", skip_serializing)]
    #[schemars(skip)]
    pub moved_dhat: Option<serde_yaml::Value>,
    #[serde(default, rename = "eps_v", skip_serializing)]
    #[schemars(skip)]
    pub moved_eps_v: Option<serde_yaml::Value>,
    /// Barrier support `s` (m, and the bound on `1 − ‖n‖`; `0 < s < 1`).
    /// Hulls interact within `2s/(1−s)`. Default 0.01.
    #[serde(default = "ContactSpec::default_s")]
    pub s: f64,
    /// Barrier stiffness `κ` multiplying every `U_c` (J·m). Default 1.
    /// (The paper writes it as "μ" in eq. `SDRS`; it is not the friction
    /// coefficient.)
    /// With `model: ipc`, `κ` multiplies IPC's barrier on squared distances
    /// (J/m⁴) and, when absent, is chosen adaptively by the baseline.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kappa: Option<f64>,
    /// Friction coefficient `μ`. Default 0 (frictionless).
    #[serde(default)]
    pub mu: f64,
    /// Friction velocity smoothing `ε` ((m/s)²): below relative speeds of
    /// about `√ε` friction acts as viscous damping. Default 1e-6.
    #[serde(default = "ContactSpec::default_eps")]
    pub eps: f64,
    /// Normal-force smoothing of `A_ε(f) = √(f² + ε_f) − √ε_f` (N²). The
    /// paper uses one `ε` for both roles; their units differ. Default 1e-6.
    #[serde(default = "ContactSpec::default_eps")]
    pub eps_force: f64,
    /// Skip pairs of a link and its parent. Default true.
    #[serde(default = "ContactSpec::default_true")]
    pub exclude_adjacent: bool,
    /// Further excluded link pairs, as `robot/link` names.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub exclude: Vec<[String; 2]>,
    /// Continuous collision detection (SDRS model): every Newton step is
    /// capped so that no hull pair can touch anywhere along its curved
    /// path, which makes the whole time step collision-free, not only its
    /// end (see README, "Choices worth knowing"). Default on:
    /// `{enabled: true, keep_fraction: 0.1, max_rounds: 16}`.
    #[serde(
        default,
        skip_serializing_if = "crate::contact::ccd::CcdOptions::is_default"
    )]
    pub ccd: crate::contact::ccd::CcdOptions,
}

pub use crate::contact::settings::ContactModelKind;

impl ContactSpec {
    fn default_s() -> f64 {
        0.01
    }
    /// `κ` when the file gives none (SDRS model).
    pub fn default_kappa() -> f64 {
        1.0
    }
    fn default_eps() -> f64 {
        1e-6
    }
    fn default_true() -> bool {
        true
    }
}

impl Default for ContactSpec {
    fn default() -> Self {
        ContactSpec {
            model: ContactModelKind::Sdrs,
            ipc: None,
            moved_surface: None,
            moved_dhat: None,
            moved_eps_v: None,
            s: Self::default_s(),
            kappa: None,
            mu: 0.0,
            eps: Self::default_eps(),
            eps_force: Self::default_eps(),
            exclude_adjacent: true,
            exclude: Vec::new(),
            ccd: Default::default(),
        }
    }
}

/// A pose given as translation and roll–pitch–yaw (URDF convention).
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Origin {
    /// Translation (m). Default zero.
    #[serde(default)]
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw (rad, fixed axes x, y, z as in URDF). Default zero.
    #[serde(default)]
    pub rpy: [f64; 3],
}

/// One robot or free object.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// Robot name; prefixes its joints' CSV columns (`robot/joint`) when the scene has several robots.
    pub name: String,
    /// World pose of the root attachment. Default identity.
    #[serde(default)]
    pub base: Origin,
    /// The links, in any order (parents before or after children, no cycles); or use `chain`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub links: Vec<LinkSpec>,
    /// Generates `links` as one of the paper's rotating chains instead.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chain: Option<ChainSpec>,
    /// PD targets and gains of the joints. Default: no control (gains 0).
    #[serde(default)]
    pub controller: ControllerSpec,
    /// Initial coordinates and velocities per joint name. Default zeros.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub initial: BTreeMap<String, InitialSpec>,
    /// Design-space description (ties, bounds); read by `sdrs optimize`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub design: Option<DesignSpec>,
}

/// One link.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LinkSpec {
    /// Link name (unique within the robot).
    pub name: String,
    /// Parent link; omitted or null: attached to the robot's base.
    #[serde(default)]
    pub parent: Option<String>,
    /// The joint that connects this link to its parent.
    pub joint: JointSpec,
    /// Link mass (kg), divided equally over all hull vertices; or give `vertex_mass`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    /// Mass per hull vertex (kg, the paper's ρ); exactly one of `mass` and `vertex_mass`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertex_mass: Option<f64>,
    /// Mass model: `vertices` (default: the link's mass lumped at its hull
    /// vertices, the paper's model), `solid` (uniform-density solid hulls)
    /// or `given` (explicit inertial). See [`MassModelSpec`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass_model: Option<MassModelSpec>,
    /// Convex hulls in the link frame (m).
    pub hulls: Vec<HullSpec>,
    /// Whether the link takes part in contact. Default true; `false` for
    /// links that only carry a joint or are visual (MJCF geoms that MuJoCo
    /// never collides).
    #[serde(default = "default_true", skip_serializing_if = "is_true")]
    pub collide: bool,
    /// Source surface mesh of this body (`.obj`, `.stl` or `.dae`; path
    /// relative to the scene file; coordinates in the body's frame, m): the
    /// mesh its hulls were made from. `sdrs import` writes one per link
    /// (`<stem>_meshes/<link>.source.obj`). Used only by the IPC baseline
    /// with `contact.ipc.surface: source` (a closed, consistently oriented,
    /// non-self-intersecting triangle mesh is required then). Default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface_mesh: Option<String>,
}

fn default_true() -> bool {
    true
}
fn is_true(b: &bool) -> bool {
    *b
}

/// How a link's (or object's) mass is distributed; default `vertices`.
/// Formulas: [`crate::model::mass`].
///
/// ```yaml
/// mass_model: {type: vertices}          # link `mass` (or `vertex_mass`) lumped at the hull vertices
/// mass_model: {type: solid, density: 1000}   # kg/m³; or omit density and give the link `mass`
/// mass_model: {type: given, mass: 2.0, com: [0, 0, 0.1], inertia: [0.02, 0, 0, 0.02, 0, 0.01]}
/// ```
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum MassModelSpec {
    /// The paper's lumped vertex masses (needs the link's `mass` or `vertex_mass`).
    Vertices,
    /// Each hull a solid of uniform density; overlapping hulls of a link are
    /// superposed (their overlap counts once per hull). Give `density` or
    /// the link's `mass` (then density = mass / total hull volume at load).
    /// Mass, centre of mass and inertia follow the hull vertices in design
    /// optimization.
    Solid {
        /// Density (kg/m³, > 0). Default: from the link's `mass`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        density: Option<f64>,
    },
    /// An explicit inertial (like URDF `<inertial>`), fixed under design
    /// changes; the link's `mass`/`vertex_mass` must be absent.
    Given {
        /// Mass (kg, > 0).
        mass: f64,
        /// Centre of mass in the link frame (m).
        com: [f64; 3],
        /// Inertia tensor about the centre of mass in link axes (kg m²), in
        /// URDF order `[ixx, ixy, ixz, iyy, iyz, izz]`; principal moments
        /// must be ≥ 0 and obey the triangle inequality.
        inertia: [f64; 6],
    },
}

/// Joint types accepted in scene files.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum JointType {
    Fixed,
    Revolute,
    Prismatic,
    Ball,
    Spherical,
    Free,
}

/// The joint connecting a link to its parent.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct JointSpec {
    /// Joint name (trajectory columns, controller keys). Default: the link's name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Joint type: `fixed`, `revolute`, `prismatic`, `ball` (two hinges), `spherical` (3 rotations) or `free` (6 DOF).
    #[serde(rename = "type")]
    pub kind: JointType,
    /// Revolute and prismatic joints: the unit axis in the joint frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<[f64; 3]>,
    /// Ball joints: two orthogonal unit hinge axes. Default x then y.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axes: Option<[[f64; 3]; 2]>,
    /// The joint frame in the parent link's frame; `xyz` is the design-dependent attachment point (m). Default identity.
    #[serde(default)]
    pub origin: Origin,
    /// Revolute and prismatic joints: position limits, enforced by a barrier
    /// term (see [`JointLimitSpec`]). Default: unlimited.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limit: Option<JointLimitSpec>,
    /// Revolute and prismatic joints: follow another 1-DOF joint of the
    /// same robot, `θ = multiplier·θ_joint + offset` (URDF `<mimic>`), as a
    /// stiff tie (see [`MimicSpec`]). Default: independent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mimic: Option<MimicSpec>,
}

/// A mimic joint, **tied** (not eliminated): the term
/// `½ k (θ − a θ_joint − b)²` (J) couples the two coordinates, so the
/// mimic follows within `torque / k`. When the robot's `initial` does not
/// give the mimic joint, its initial coordinate and velocity follow the
/// relation exactly.
///
/// ```yaml
/// mimic: {joint: finger_left, multiplier: -1}
/// ```
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MimicSpec {
    /// The followed joint (a revolute or prismatic joint of the same robot).
    pub joint: String,
    /// `a` (dimensionless). Default 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub multiplier: Option<f64>,
    /// `b` (rad or m). Default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset: Option<f64>,
    /// Tie stiffness `k` (J/rad² or J/m²), > 0. Default 1.0e4.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
}

/// Position limits of a revolute (rad) or prismatic (m) joint, enforced by
/// the barrier `κ P_s(x)` on the distance `x` to each limit
/// (`crate::energy::joint_limit`): the coordinate never reaches a limit and
/// stops within `support` of it. `velocity` and `effort` are carried for
/// reports (as URDF `<limit>` gives them), not simulated.
///
/// ```yaml
/// limit: {lower: -1.57, upper: 1.57}       # support 0.02, stiffness 1.0e-3
/// ```
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct JointLimitSpec {
    /// Lower limit (rad or m).
    pub lower: f64,
    /// Upper limit (rad or m), > lower.
    pub upper: f64,
    /// Barrier support `s` (rad or m), > 0. Default 0.02, capped at a quarter of the range.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support: Option<f64>,
    /// Barrier stiffness `κ` (J·rad or J·m), > 0. Default 1.0e-3 (about 90 N·m
    /// of push at half the default support).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Velocity limit (rad/s or m/s); reported, not simulated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<f64>,
    /// Effort limit (N·m or N); reported, not simulated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub effort: Option<f64>,
}

/// A hull: explicit `vertices` or a `box` primitive (8 vertices); exactly one.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HullSpec {
    /// Explicit vertices (m, link frame): at least 4, not coplanar; the hull is their convex hull.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertices: Option<Vec<[f64; 3]>>,
    /// Mass of each vertex (kg), overriding the link's `mass`/`vertex_mass`
    /// for this hull (written by `sdrs optimize`; connectivity vertices are
    /// massless).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertex_masses: Option<Vec<f64>>,
    /// A box primitive instead of `vertices` (8 vertices).
    #[serde(default, rename = "box", skip_serializing_if = "Option::is_none")]
    pub cuboid: Option<BoxSpec>,
}

/// Axis-aligned box primitive in the link frame.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Full edge lengths (m).
    pub size: [f64; 3],
    /// Centre in the link frame (m). Default origin.
    #[serde(default)]
    pub center: [f64; 3],
}

impl HullSpec {
    /// A hull from explicit vertices.
    pub fn from_vertices(v: Vec<[f64; 3]>) -> Self {
        HullSpec {
            vertices: Some(v),
            cuboid: None,
            vertex_masses: None,
        }
    }
    /// A box hull.
    pub fn cuboid(size: [f64; 3], center: [f64; 3]) -> Self {
        HullSpec {
            vertices: None,
            cuboid: Some(BoxSpec { size, center }),
            vertex_masses: None,
        }
    }
}

/// Generator for the paper's rotating chains: `links` box links hanging
/// along −z, each attached at the far end of its parent.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ChainSpec {
    /// Number of links (≥ 1).
    pub links: usize,
    /// Link length (m). Default 0.5.
    #[serde(default = "ChainSpec::default_length")]
    pub link_length: f64,
    /// Link cross-section width (m). Default 0.1.
    #[serde(default = "ChainSpec::default_width")]
    pub link_width: f64,
    /// Mass per link (kg). Default 0.1.
    #[serde(default = "ChainSpec::default_mass")]
    pub link_mass: f64,
    /// Joint type of every link: `ball` (default, two hinges about x and y)
    /// or `revolute` (about y).
    #[serde(default = "ChainSpec::default_joint")]
    pub joint: JointType,
}

impl ChainSpec {
    fn default_length() -> f64 {
        0.5
    }
    fn default_width() -> f64 {
        0.1
    }
    fn default_mass() -> f64 {
        0.1
    }
    fn default_joint() -> JointType {
        JointType::Ball
    }
}

/// PD gains.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Gains {
    /// Stiffness `k_p` (J/rad²; restoring torque `2 k_p (θ* − θ)`). Default: the controller's `kp`.
    #[serde(default)]
    pub kp: Option<f64>,
    /// Damping `k_d` (J s²/rad²; damping torque `(2 k_d/Δt) θ̇`). Default: the controller's `kd`.
    #[serde(default)]
    pub kd: Option<f64>,
}

/// One signal, or one per coordinate of a multi-coordinate joint.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(untagged)]
pub enum SignalList {
    One(Signal),
    Many(Vec<Signal>),
}

impl SignalList {
    pub fn as_slice(&self) -> &[Signal] {
        match self {
            SignalList::One(s) => std::slice::from_ref(s),
            SignalList::Many(v) => v,
        }
    }
}

/// Open-loop stable-PD controller.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ControllerSpec {
    /// Default `k_p` (J/rad²). Default 0.
    #[serde(default)]
    pub kp: f64,
    /// Default `k_d` (J s²/rad²). Default 0.
    #[serde(default)]
    pub kd: f64,
    /// Per-joint gain overrides, by joint name.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub gains: BTreeMap<String, Gains>,
    /// Per joint name: its target signal, or a list with one signal per coordinate. Joints without a target are not driven.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub targets: BTreeMap<String, SignalList>,
}

/// Initial coordinates and velocities of one joint (default zeros).
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    /// Initial coordinates (rad or m; one per joint coordinate). Default zeros.
    #[serde(default)]
    pub q: Vec<f64>,
    /// Initial velocities (rad/s or m/s). Default zeros.
    #[serde(default)]
    pub qdot: Vec<f64>,
}

/// A hull vertex of a link.
#[derive(
    Clone, Debug, Serialize, Deserialize, PartialEq, Eq, PartialOrd, Ord, schemars::JsonSchema,
)]
#[serde(deny_unknown_fields)]
pub struct VertexRef {
    /// Link name.
    pub link: String,
    /// Hull index within the link (0-based).
    pub hull: usize,
    /// Vertex index within the hull (0-based).
    pub vertex: usize,
}

/// A joint's attachment point tied to a vertex of a parent hull and a vertex
/// of a child hull (paper, `shape.tex`, Fig. `attachment`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AttachmentTie {
    /// Child link whose joint origin is the attachment point.
    pub link: String,
    /// The parent hull's vertex tied to the attachment point.
    pub parent_vertex: VertexRef,
    /// The child hull's vertex tied to the attachment point.
    pub child_vertex: VertexRef,
}

/// Design space description (paper, `shape.tex`): which links are designable,
/// connectivity ties and box bounds.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DesignSpec {
    /// Designable links (default: all).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub designable: Option<Vec<String>>,
    /// Groups of vertices that are one design variable (shared vertices of
    /// overlapping hulls of one link).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ties: Vec<Vec<VertexRef>>,
    /// Joint attachment points tied to a parent and a child hull vertex (keeps the robot connected while its shape changes).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub attachments: Vec<AttachmentTie>,
    /// Box bound half-width around each initial vertex position (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bound: Option<f64>,
}
