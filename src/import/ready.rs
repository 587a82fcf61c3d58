//! Turns an imported design into a scene that *does something*: the base
//! fixed or floating, the robot on the ground, contact on with exclusions
//! for link pairs that overlap in the rest pose, and PD gains that hold the
//! initial pose under gravity.
//!
//! - **Base** ([`BaseMode::Auto`], the default), in this order:
//!   1. floating when the input's root joint is floating (URDF `floating`,
//!      MJCF `<freejoint/>` / `<joint type="free">`, a bare mesh);
//!   2. fixed when the input says the root is static: a URDF root link
//!      that is massless, lacks an `<inertial>` (pybullet's convention: a
//!      massless base is static) or is named `world`; an MJCF body without
//!      a free joint (MuJoCo welds it to the world);
//!   3. fixed when the robot is a manipulator: exactly one moving joint
//!      hangs from the root link (through fixed joints), i.e. one chain
//!      from the base (xArm, KUKA iiwa, a pendulum): the convention of
//!      MuJoCo's URDF compiler and Pinocchio, where a URDF root is fixed
//!      unless a free joint is added, and of ROS arms bolted to a table;
//!   4. floating otherwise (legs, wheels, several chains from the base:
//!      quadrupeds, humanoids, mobile robots, a single rigid body).
//!
//!   A floating root becomes a `free` joint. The choice and its reason are
//!   in the report (`ready.base`).
//! - **Pose** (`--pose joint=value,…`): initial coordinates of revolute and
//!   prismatic joints (rad or m); the PD targets hold this pose (a joint
//!   driven by an MJCF servo keeps the servo's target, see **Gains**).
//! - **Contact** (on by default): `s = 0.01`, `κ = 1`, `μ = 0.5`; every pair
//!   of the robot's links whose hulls intersect or lie within
//!   `1.5 × 2s/(1−s)` of each other in the initial pose is excluded (listed
//!   in the report): the barrier could never start from such a state, and a
//!   designed overlap is not a collision. A link and the input's environment
//!   (an MJCF ground plane or obstacle) are excluded only when they
//!   intersect, with a warning in the report (the link will pass through):
//!   resting near the ground is the contact the scene is for. A pair whose
//!   separation cannot be computed is excluded with a warning naming it.
//! - **Ground** (by default when the base floats and the input has no
//!   ground of its own; `--ground` adds it whatever the base, `--no-ground`
//!   never): a plane at height 0; the robot is lifted so that its lowest
//!   hull vertex starts at the edge of the barrier's range `2s/(1−s)`
//!   (the clearance, 0.0202 m at `s = 0.01`): no contact force yet, and a
//!   drop of millimetres to where the barrier carries the weight (starting
//!   deeper inside the range launches robots whose feet have many low
//!   vertices). A robot whose input brings a ground (MJCF planes) stays
//!   where the input puts it.
//! - **Gains** per actuated joint `j` (paper convention, restoring force
//!   `2 k_p (θ* − θ)`, damping `(2 k_d/Δt) θ̇`):
//!   `k_p,j = max(k_min, T_j / (2 θ_hold))` with `T_j = m_j g r_j` the
//!   largest gravity torque the joint can see in any pose (`m_j` the mass
//!   and `r_j` the reach of the subtree it moves), plus, for a floating
//!   robot, `m g r_j / 2` (a leg carrying half the body's weight `m g`);
//!   `θ_hold = 0.02 rad` (or m), `k_min = 1`. The joint then deflects by
//!   at most `θ_hold` under gravity, and its stiffness `2 k_p` exceeds
//!   gravity's destabilizing `m_j g r_j` (an upright arm stays up).
//!   `k_d,j = Δt √(2 k_p,j M_jj)` damps the joint's own inertia `M_jj`
//!   (from the step Hessian at rest, `M = Δt² ∂²O/∂θ²`) critically.
//!   A joint whose gains the input already set (an MJCF position or
//!   velocity actuator, `super::mjcf::actuators`) keeps them and its target:
//!   the input's servo is the model's, and MuJoCo simulates it at rest.

use super::error::ImportError;
use crate::contact::ContactParams;
use crate::contact::separation::{Separation, separate};
use crate::control::Signal;
use crate::energy::Need;
use crate::geometry::WorldHulls;
use crate::scene::Scene;
use crate::scene::schema::{
    ContactSpec, Gains, GroundSpec, InitialSpec, JointType, RobotSpec, SceneSpec, SignalList,
};
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// How the robot's base is attached.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BaseMode {
    /// Floating unless the input says the base is static (see module doc).
    Auto,
    /// Bolted to the world at the root joint's origin.
    Fixed,
    /// A free 6-DOF body.
    Floating,
}

impl std::str::FromStr for BaseMode {
    type Err = String;
    /// `auto`, `fixed` or `floating` (any case).
    fn from_str(s: &str) -> Result<Self, String> {
        use BaseMode::*;
        super::pick_name(s, &[Auto, Fixed, Floating], |b| match b {
            Auto => "auto",
            Fixed => "fixed",
            Floating => "floating",
        })
    }
}

/// Options of [`make_ready`]; every default is in the module doc.
#[derive(Clone, Debug)]
pub struct ReadyOptions {
    pub base: BaseMode,
    /// Ground plane, robot placed on it: `None` (default) when the base
    /// floats and the scene has no ground yet; `Some(true)` always
    /// (`--ground`); `Some(false)` never (`--no-ground`).
    pub ground: Option<bool>,
    /// Turn contact on (with rest-pose exclusions). Default true.
    pub contact: bool,
    /// Add PD gains and targets holding the initial pose. Default true.
    pub hold: bool,
    /// Initial coordinates by joint name.
    pub pose: BTreeMap<String, f64>,
    /// Friction coefficient of the contact it turns on. Default `None`:
    /// 0.5; an MJCF import passes its geoms' ([`super::mjcf::contact_friction`]).
    pub mu: Option<f64>,
}

impl Default for ReadyOptions {
    fn default() -> Self {
        ReadyOptions {
            base: BaseMode::Auto,
            ground: None,
            contact: true,
            hold: true,
            pose: BTreeMap::new(),
            mu: None,
        }
    }
}

/// Angle (rad) or displacement (m) by which gravity may deflect a held joint.
pub const HOLD_ERROR: f64 = 0.02;

/// What [`make_ready`] did, for the import report.
#[derive(Clone, Debug, Serialize)]
pub struct ReadyReport {
    /// `fixed` or `floating`, and why.
    pub base: String,
    /// Link pairs excluded from contact because they overlap (or, within
    /// the robot, nearly) in the initial pose, as `robot/link` names.
    pub excluded_pairs: Vec<[String; 2]>,
    /// Exclusions the user must look at, in words: a moving link that
    /// intersects the ground or an obstacle in the initial pose (it will
    /// pass through it), a pair whose separation could not be computed.
    pub warnings: Vec<String>,
    /// Height by which the robot was lifted onto the ground (m), if any.
    pub ground_lift: Option<f64>,
    /// PD gains the hold wrote, per joint: `[k_p, k_d]`. Joints the input
    /// drives itself (MJCF actuators mapped to the controller,
    /// `super::mjcf::actuators`) keep those gains and are not listed.
    pub gains: BTreeMap<String, [f64; 2]>,
}

/// Whether the input marks its root as static (see module doc).
pub fn root_is_static(root_name: &str, root_mass: Option<f64>) -> bool {
    root_name == "world" || !root_mass.is_some_and(|m| m > 0.0)
}

/// Applies the options to the imported scene (one robot); `file` names the
/// input in errors, `root_static` is [`root_is_static`] of the input.
pub fn make_ready(
    scene: &mut SceneSpec,
    file: &Path,
    root_static: bool,
    opts: &ReadyOptions,
) -> Result<ReadyReport, ImportError> {
    let (floating, base) = choose_base(&mut scene.robots[0], root_static, opts.base);
    apply_pose(&mut scene.robots[0], file, &opts.pose)?;
    // The scene as it stands, for geometry and gains.
    let load = |spec: &SceneSpec| {
        Scene::from_spec(spec.clone(), file).map_err(|e| ImportError::Invalid {
            path: file.to_path_buf(),
            msg: e.to_string(),
        })
    };
    let mut report = ReadyReport {
        base,
        excluded_pairs: Vec::new(),
        warnings: Vec::new(),
        ground_lift: None,
        gains: BTreeMap::new(),
    };
    let contact = ContactSpec {
        mu: opts.mu.unwrap_or(0.5),
        ..ContactSpec::default()
    };
    let range = ContactParams::with_width(contact.s).support_distance();
    let plain = load(scene)?;
    let model = &plain.model;
    let mut hulls = WorldHulls::new(model);
    let poses = crate::sim::SimState::new(
        model,
        plain.q0.clone(),
        &plain.qdot0,
        plain.charts.clone(),
        plain.settings.dt,
    )
    .poses;
    hulls.update(model, &poses);
    if opts.contact {
        (report.excluded_pairs, report.warnings) = new_exclusions(scene, model, &hulls, range);
        add_contact(scene, &report.excluded_pairs, contact);
    }
    let ground = opts.ground.unwrap_or(floating && scene.ground.is_none());
    if ground {
        report.ground_lift = place_on_ground(scene, &hulls, range);
        if report.ground_lift.is_none() && opts.ground == Some(true) {
            return Err(ImportError::Invalid {
                path: file.to_path_buf(),
                msg: "--ground: the robot has no colliding hull to place on the ground (e.g. MJCF geoms with contype = conaffinity = 0)".into(),
            });
        }
    }
    if opts.hold {
        // Joints the input drives (MJCF actuators) keep the input's gains.
        let driven: BTreeSet<String> = scene.robots[0].controller.gains.keys().cloned().collect();
        let mut gains = hold_gains(scene, file, floating, &load)?;
        gains.retain(|joint, _| !driven.contains(joint));
        hold_initial_pose(&mut scene.robots[0], &gains);
        report.gains = gains;
    }
    load(scene)?;
    Ok(report)
}

/// Whether the base floats, and why (for the report); a fixed root becomes
/// free or a free root is welded where it stands accordingly. Only a fixed
/// or free root changes: a root on a revolute or prismatic joint (a robot
/// on a rail or a hinge to the world) keeps its joint.
fn choose_base(robot: &mut RobotSpec, root_static: bool, mode: BaseMode) -> (bool, String) {
    let root = robot
        .links
        .iter()
        .position(|l| l.parent.is_none())
        .expect("an imported robot has a root");
    let root_kind = robot.links[root].joint.kind;
    let root_free = root_kind == JointType::Free;
    let own_joint = !matches!(root_kind, JointType::Fixed | JointType::Free);
    let chains = root_chains(robot, root);
    let floating = match mode {
        _ if own_joint => false,
        BaseMode::Fixed => false,
        BaseMode::Floating => true,
        BaseMode::Auto => root_free || (!root_static && chains != 1),
    };
    let base = match (mode, floating) {
        _ if own_joint => "attached to the world by the root link's own joint".to_string(),
        (BaseMode::Auto, true) if root_free => {
            "floating (the input's root joint is floating)".to_string()
        }
        (BaseMode::Auto, true) => format!(
            "floating ({chains} moving joints hang from the root link, which has a mass: legs, wheels or several chains; --base fixed bolts it down)"
        ),
        (BaseMode::Auto, false) if root_static => {
            "fixed (the input's root is static: a massless or `world` URDF root link, or an MJCF body without a free joint; --base floating frees it)".to_string()
        }
        (BaseMode::Auto, false) => "fixed (one chain hangs from the root link: a manipulator; --base floating frees it)".to_string(),
        (_, true) => "floating (--base floating)".to_string(),
        (_, false) => "fixed (--base fixed)".to_string(),
    };
    if floating && root_kind == JointType::Fixed {
        robot.links[root].joint.kind = JointType::Free;
    } else if !floating && root_free {
        fix_free_root(robot, root);
    }
    (floating, base)
}

/// `--pose`: initial coordinates of named revolute/prismatic joints.
fn apply_pose(
    robot: &mut RobotSpec,
    file: &Path,
    pose: &BTreeMap<String, f64>,
) -> Result<(), ImportError> {
    let invalid = |element: String, msg: String| ImportError::InvalidUrdf {
        path: file.to_path_buf(),
        element,
        msg,
    };
    for (joint, value) in pose {
        let Some(link) = robot
            .links
            .iter()
            .find(|l| l.joint.name.as_deref().unwrap_or(&l.name) == joint)
        else {
            let known: Vec<&str> = robot
                .links
                .iter()
                .filter(|l| matches!(l.joint.kind, JointType::Revolute | JointType::Prismatic))
                .map(|l| l.joint.name.as_deref().unwrap_or(&l.name))
                .collect();
            return Err(invalid(
                format!("--pose {joint}"),
                format!(
                    "no revolute or prismatic joint of that name (joints: {})",
                    known.join(", ")
                ),
            ));
        };
        if !matches!(link.joint.kind, JointType::Revolute | JointType::Prismatic)
            || !value.is_finite()
        {
            return Err(invalid(
                format!("--pose {joint}"),
                format!("needs a revolute or prismatic joint and a finite value, got {value}"),
            ));
        }
        robot.initial.insert(
            joint.clone(),
            InitialSpec {
                q: vec![*value],
                qdot: Vec::new(),
            },
        );
    }
    Ok(())
}

/// The rest-pose exclusions ([`rest_pose_exclusions`]) and their warnings,
/// without the pairs the input already excludes (MJCF's contact filter and
/// `<contact><exclude>`), which are not reported again as overlaps.
fn new_exclusions(
    scene: &SceneSpec,
    model: &crate::model::Model,
    hulls: &WorldHulls,
    range: f64,
) -> (Vec<[String; 2]>, Vec<String>) {
    let input_pairs = scene
        .contact
        .as_ref()
        .map(|c| c.exclude.clone())
        .unwrap_or_default();
    let given = |[a, b]: &[String; 2]| {
        input_pairs.contains(&[a.clone(), b.clone()])
            || input_pairs.contains(&[b.clone(), a.clone()])
    };
    let rest = rest_pose_exclusions(model, hulls, range);
    let pairs = rest.excluded.into_iter().filter(|p| !given(p)).collect();
    let warnings = rest
        .warnings
        .into_iter()
        .filter(|(p, _)| !given(p))
        .map(|(_, w)| w)
        .collect();
    (pairs, warnings)
}

/// Link pairs excluded by the rest-pose check, and what the report must say about them.
#[derive(Debug, Default)]
struct RestPose {
    /// `robot/link` name pairs, each once.
    excluded: Vec<[String; 2]>,
    /// Excluded pairs the user must see, with the reason: a moving link
    /// that intersects the environment at rest (it will pass through it), a
    /// pair whose separation failed.
    warnings: BTreeMap<[String; 2], String>,
}

/// How the rest-pose check treats one hull pair.
enum Verdict {
    /// Contact stays on.
    Keep,
    /// Excluded, listed in the report only.
    Exclude,
    /// Excluded, with a warning for the report.
    Warn(String),
}

/// The rest-pose exclusions: pairs of links whose hulls, in the initial pose,
///
/// - within the robot (two links outside the environment): intersect or lie
///   within `1.5 × range` of each other (a designed overlap or near-touch,
///   e.g. links meeting at a joint, which the barrier would otherwise push
///   apart at every step);
/// - against the environment (the ground, an obstacle: links of the
///   [`ENVIRONMENT`](crate::scene::environment::ENVIRONMENT) robot):
///   intersect. A link resting within the barrier's range `range` (m) of the
///   ground is the contact the scene is for, and the barrier starts from any
///   positive distance; excluding it would let the link fall through. (The
///   ground placement of [`place_on_ground`] starts the lowest vertex at
///   `range`, inside the `1.5 × range` margin.) An intersecting moving link
///   is excluded with a warning: it will pass through.
///
/// A pair whose separation fails is excluded with a warning naming it.
fn rest_pose_exclusions(model: &crate::model::Model, hulls: &WorldHulls, range: f64) -> RestPose {
    let name = |l: usize| {
        let link = &model.links[l];
        format!("{}/{}", model.robots[link.robot].name, link.name)
    };
    let mut close = BTreeSet::new();
    let mut warned = BTreeMap::new();
    let mut simplex = parry3d_f64::query::gjk::VoronoiSimplex::new();
    for a in 0..hulls.ids.len() {
        for b in a + 1..hulls.ids.len() {
            let (la, lb) = (hulls.ids[a].link, hulls.ids[b].link);
            let pair = (la.min(lb), la.max(lb));
            if la == lb || close.contains(&pair) {
                continue;
            }
            let names = [name(pair.0), name(pair.1)];
            let separation = separate(hulls.hull(a), hulls.hull(b), None, &mut simplex);
            match pair_verdict(model, pair, &names, separation, range) {
                Verdict::Keep => continue,
                Verdict::Exclude => {}
                Verdict::Warn(w) => {
                    warned.insert(names, w);
                }
            }
            close.insert(pair);
        }
    }
    RestPose {
        excluded: close.iter().map(|&(la, lb)| [name(la), name(lb)]).collect(),
        warnings: warned,
    }
}

/// The rest-pose rule of [`rest_pose_exclusions`] for one hull pair of the
/// links `pair` (named `names`), whose hulls `separate` gave `separation`.
fn pair_verdict(
    model: &crate::model::Model,
    pair: (usize, usize),
    names: &[String; 2],
    separation: Result<Separation, crate::contact::ContactError>,
    range: f64,
) -> Verdict {
    let env = |l: usize| {
        model.robots[model.links[l].robot].name == crate::scene::environment::ENVIRONMENT
    };
    let moves = |l: usize| !model.ancestor_dofs[l].is_empty();
    let [a, b] = names;
    match separation {
        Ok(Separation::Separated { distance, .. }) => {
            if env(pair.0) || env(pair.1) || distance >= 1.5 * range {
                Verdict::Keep
            } else {
                Verdict::Exclude
            }
        }
        Ok(Separation::Intersecting)
            if (env(pair.0) || env(pair.1)) && (moves(pair.0) || moves(pair.1)) =>
        {
            Verdict::Warn(format!(
                "{a} and {b} intersect in the initial pose: contact between them is excluded, so nothing stops one passing through the other (start the link clear of it in the input to keep the contact)"
            ))
        }
        Ok(Separation::Intersecting) => Verdict::Exclude,
        Err(e) => Verdict::Warn(format!(
            "{a} and {b}: their separation in the initial pose could not be computed ({e}); the pair is excluded from contact, check it"
        )),
    }
}

/// Turns contact on with `exclude` added to the exclusions the input gave
/// (MJCF's contact filter).
fn add_contact(scene: &mut SceneSpec, exclude: &[[String; 2]], contact: ContactSpec) {
    let mut all = scene
        .contact
        .as_ref()
        .map(|c| c.exclude.clone())
        .unwrap_or_default();
    for e in exclude {
        if !all.contains(e) {
            all.push(e.clone());
        }
    }
    scene.contact = Some(ContactSpec {
        exclude: all,
        ..contact
    });
}

/// Adds the plane z = 0 and lifts the base so that the lowest hull vertex
/// is at `range` (the barrier's edge); returns the lift (m), or `None`
/// (and no ground) when the robot has no colliding hull.
fn place_on_ground(scene: &mut SceneSpec, hulls: &WorldHulls, range: f64) -> Option<f64> {
    let min_z = (0..hulls.ids.len())
        .flat_map(|h| hulls.hull(h).iter().map(|x| x.z))
        .fold(f64::INFINITY, f64::min);
    if !min_z.is_finite() {
        return None;
    }
    let lift = range - min_z;
    scene.robots[0].base.xyz[2] += lift;
    scene.ground = Some(serde_yaml::from_str::<GroundSpec>("height: 0").expect("static"));
    Some(lift)
}

/// PD gains and constant targets at the initial coordinate (default 0).
fn hold_initial_pose(robot: &mut RobotSpec, gains: &BTreeMap<String, [f64; 2]>) {
    for (joint, [kp, kd]) in gains {
        let q = robot
            .initial
            .get(joint)
            .and_then(|i| i.q.first())
            .copied()
            .unwrap_or(0.0);
        robot.controller.gains.insert(
            joint.clone(),
            Gains {
                kp: Some(*kp),
                kd: Some(*kd),
            },
        );
        robot.controller.targets.insert(
            joint.clone(),
            SignalList::One(Signal::Constant { value: q }),
        );
    }
}

/// The moving joints that hang from the root link `root` through fixed
/// joints only: 1 for a manipulator (one chain from the base), 4 for a
/// quadruped's legs, 0 for a single rigid body.
pub fn root_chains(robot: &RobotSpec, root: usize) -> usize {
    let by_name: BTreeMap<&str, usize> = robot
        .links
        .iter()
        .enumerate()
        .map(|(i, l)| (l.name.as_str(), i))
        .collect();
    // A link is on the base when every joint from it up to the root is fixed.
    let on_base = |mut i: usize| loop {
        if i == root {
            return true;
        }
        let l = &robot.links[i];
        if l.joint.kind != JointType::Fixed {
            return false;
        }
        match l.parent.as_deref().and_then(|p| by_name.get(p)) {
            Some(&p) => i = p,
            None => return false,
        }
    };
    robot
        .links
        .iter()
        .filter(|l| l.joint.kind != JointType::Fixed)
        .filter(|l| {
            l.parent
                .as_deref()
                .and_then(|p| by_name.get(p))
                .is_some_and(|&p| on_base(p))
        })
        .count()
}

/// Welds a free root where it stands: its initial pose `θ = [p, φ]`
/// (position, rotation vector; MJCF free joints carry the body's pose
/// there) moves into the joint origin, `T_origin ← T_origin · (exp(φ̂), p)`,
/// and the now meaningless six-value `initial` entry is removed.
fn fix_free_root(robot: &mut RobotSpec, root: usize) {
    let link = &mut robot.links[root];
    link.joint.kind = JointType::Fixed;
    let name = link.joint.name.clone().unwrap_or_else(|| link.name.clone());
    let Some(init) = robot.initial.remove(&name) else {
        return;
    };
    if init.q.len() != 6 {
        return;
    }
    let o = &mut link.joint.origin;
    let r_o = nalgebra::Rotation3::from_euler_angles(o.rpy[0], o.rpy[1], o.rpy[2]);
    let r_q = nalgebra::Rotation3::new(nalgebra::Vector3::new(init.q[3], init.q[4], init.q[5]));
    let t = nalgebra::Vector3::from(o.xyz)
        + r_o * nalgebra::Vector3::new(init.q[0], init.q[1], init.q[2]);
    let (roll, pitch, yaw) = (r_o * r_q).euler_angles();
    o.xyz = t.into();
    o.rpy = [roll, pitch, yaw];
}

/// Gains of every revolute/prismatic joint (see the module doc).
fn hold_gains(
    scene: &SceneSpec,
    file: &Path,
    floating: bool,
    load: &dyn Fn(&SceneSpec) -> Result<Scene, ImportError>,
) -> Result<BTreeMap<String, [f64; 2]>, ImportError> {
    // Gravity torques and joint inertias with the base fixed, no contact
    // and no controller (an input's actuator gains are not inertia).
    let mut fixed = scene.clone();
    fixed.contact = None;
    fixed.ground = None;
    fixed.robots[0].controller = Default::default();
    let root = fixed.robots[0]
        .links
        .iter()
        .position(|l| l.parent.is_none())
        .expect("root");
    if fixed.robots[0].links[root].joint.kind == JointType::Free {
        fix_free_root(&mut fixed.robots[0], root);
    }
    let s = load(&fixed)?;
    let mut sim = s.simulator();
    let (_, _, hess) = sim
        .objective(&s.q0, Need::Hessian)
        .map_err(|e| ImportError::Invalid {
            path: file.to_path_buf(),
            msg: format!("evaluating the imported robot at its initial pose: {e}"),
        })?;
    let model = &s.model;
    let dt = s.settings.dt;
    let g = s.settings.gravity.norm();
    let total_mass: f64 = model.first_moment.iter().map(|m| m[3]).sum();
    let poses = &sim.state.poses;
    let mut gains = BTreeMap::new();
    for (li, link) in model.links.iter().enumerate() {
        if !matches!(link.joint.type_name(), "revolute" | "prismatic") {
            continue;
        }
        let j = link.dof_offset;
        // Mass and reach of the subtree moved by this joint.
        let origin = poses[li].column(3).into_owned();
        let (mut mass, mut reach) = (0.0, 0.0f64);
        for (lk, other) in model.links.iter().enumerate() {
            if !model.ancestor_dofs[lk].contains(&j) {
                continue;
            }
            mass += model.first_moment[lk][3];
            for h in &other.hulls {
                for x in &h.x_local {
                    let w = poses[lk].fixed_columns::<3>(0) * x + poses[lk].column(3);
                    reach = reach.max((w - origin).norm());
                }
            }
        }
        // The largest gravity torque in any pose, plus (floating) a leg's
        // share of the body's weight.
        let mut torque = mass * g * reach;
        if floating {
            torque += 0.5 * total_mass * g * reach;
        }
        let kp = (torque / (2.0 * HOLD_ERROR)).max(1.0);
        let inertia = (hess[(j, j)] * dt * dt).max(0.0);
        let kd = dt * (2.0 * kp * inertia).sqrt();
        gains.insert(link.joint_name.clone(), [kp, kd]);
    }
    Ok(gains)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::ContactError;
    use nalgebra::Vector3;

    /// [`pair_verdict`] on two free boxes and the ground, with the barrier's
    /// range `2s/(1−s) = 0.0202 m` at `s = 0.01`: between the boxes, a gap
    /// below `1.5 × range` excludes and one above keeps; a box 0.025 m above
    /// the ground (inside the margin, outside the range) keeps its contact,
    /// an intersection with the ground is excluded with a warning, and so is
    /// a failed separation, naming the pair.
    #[test]
    fn rest_pose_rule_keeps_the_ground_and_warns_on_failures() {
        let yaml = "version: 1\ndt: 0.002\nsteps: 1\nground: {height: 0}\nobjects:\n  - {name: a, mass: 1, hulls: [{box: {size: [0.1, 0.1, 0.1]}}], initial: {q: [0, 0, 1, 0, 0, 0]}}\n  - {name: b, mass: 1, hulls: [{box: {size: [0.1, 0.1, 0.1]}}], initial: {q: [1, 0, 1, 0, 0, 0]}}\n";
        let scene = Scene::from_str(yaml, Path::new("rule.yaml")).unwrap();
        let model = &scene.model;
        let link = |n: &str| model.links.iter().position(|l| l.name == n).unwrap();
        let (a, b, ground) = (link("a"), link("b"), link("ground"));
        let range = ContactParams::with_width(0.01).support_distance();
        let apart = |distance: f64| {
            Ok(Separation::Separated {
                dir: Vector3::z(),
                max_a: 0.0,
                min_b: distance,
                distance,
            })
        };
        let verdict = |pair: (usize, usize), sep: Result<Separation, ContactError>| {
            let names = ["x/one".to_string(), "x/two".to_string()];
            pair_verdict(
                model,
                (pair.0.min(pair.1), pair.0.max(pair.1)),
                &names,
                sep,
                range,
            )
        };
        assert!(matches!(
            verdict((a, b), apart(1.4 * range)),
            Verdict::Exclude
        ));
        assert!(matches!(verdict((a, b), apart(1.6 * range)), Verdict::Keep));
        assert!(matches!(verdict((a, ground), apart(0.025)), Verdict::Keep));
        assert!(matches!(verdict((a, ground), apart(1e-9)), Verdict::Keep));
        let warned = |v: Verdict| match v {
            Verdict::Warn(w) => w,
            _ => panic!("no warning"),
        };
        let w = warned(verdict((a, ground), Ok(Separation::Intersecting)));
        assert!(w.contains("x/one and x/two intersect"), "{w}");
        assert!(matches!(
            verdict((a, b), Ok(Separation::Intersecting)),
            Verdict::Exclude
        ));
        let failed = Err(ContactError::GjkFailed { len_a: 8, len_b: 8 });
        let w = warned(verdict((a, b), failed));
        assert!(
            w.contains("x/one and x/two") && w.contains("could not be computed"),
            "{w}"
        );
    }
}
