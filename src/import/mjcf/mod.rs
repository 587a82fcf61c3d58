//! MJCF (MuJoCo XML) input.
//!
//! **Reader.** The model is compiled by MuJoCo itself (`tools/helpers/mjcf_dump.py`
//! through the project's Python, the `mujoco` package that
//! `tools/setup/setup_python.sh` installs), not by a second MJCF parser here:
//! MJCF leaves much implicit (default classes and `childclass`, `<compiler
//! angle eulerseq meshdir inertiafromgeom>`, `fromto`, `<include>`,
//! `<frame>`, mesh scaling and re-centring, inertias computed from geoms),
//! and MuJoCo's compiler *is* the definition of those rules. Reading its
//! compiled model gives exactly the kinematics, masses and shapes MuJoCo
//! simulates, and MuJoCo's own error messages (which name the element and
//! line) for bad files.
//!
//! **Mapping** (frames: MuJoCo body frame `F_b`, our link frame `G`):
//! - a body without joints → one link on a `fixed` joint;
//! - a body with joints `j₁ … j_k` (MuJoCo applies them in order, each
//!   rotating about its anchor `p_i` in the body frame as moved by the
//!   previous ones) → a chain of `k` links with `G_i = G_{i−1} T(p_i − p_{i−1})
//!   J_i(θ_i)`, `G_0 = F_parent-link · T(body pos, quat)`, i.e.
//!   `F_b = G_k T(−p_k)`. The first `k − 1` links are massless frames
//!   without contact (a 1 mm cube keeps them valid); the last carries the
//!   body's geoms and inertial, moved by `−p_k`. This reproduces MuJoCo's
//!   kinematics, so the generalized coordinates are MuJoCo's `qpos` for
//!   hinge and slide joints (a `ref` is folded into the attachment so that
//!   `θ = qpos`);
//! - `hinge` → `revolute`, `slide` → `prismatic`, `ball` → `spherical`
//!   (rotation vector in a chart; its velocity is MuJoCo's local angular
//!   velocity at `φ = 0`), `free` → `free` (position of the body origin and
//!   rotation vector; MuJoCo's `qvel` at `φ = 0`);
//! - inertial: MuJoCo's compiled `body_mass`, `body_ipos`, `body_iquat`,
//!   `body_inertia` as a `given` mass model (whatever `inertiafromgeom`
//!   decided), unless `--mass density`;
//! - geoms: those MuJoCo can collide (`contype | conaffinity ≠ 0`) become
//!   hulls — primitives as in URDF import (capsule, cylinder, sphere, box,
//!   ellipsoid), mesh geoms as the convex hull of the compiled mesh (the
//!   shape MuJoCo collides); a body with only visual geoms gets them as hulls
//!   that do not collide; planes in the world body become the ground; other
//!   colliding world geoms become obstacles;
//! - contact filtering as MuJoCo's: pairs whose `contype`/`conaffinity`
//!   masks never match, bodies welded together, and parent–child weld groups
//!   are excluded, and so are the body pairs of `<contact><exclude>`
//!   (with the world body: against the ground and obstacles);
//!   `<contact><pair>` (explicit pairs) is counted in the notes and left out;
//! - joint ranges → limits, `damping`/`armature`/`frictionloss` → the
//!   scene's `joint_damping`/`armature`/`joint_friction` effects,
//!   `stiffness` with `springref` → a `joint_spring` effect (hinge and
//!   slide joints; on ball and free joints a report line), gravity → the
//!   scene's gravity; tendons, equality constraints and height fields are
//!   counted in the notes and left out;
//! - actuators ([`actuators`]): a fixed-gain, affine-bias actuator without
//!   activation dynamics on one hinge or slide (`<position>`, `<velocity>`,
//!   such a `<general>`) → the scene controller's gains and constant target
//!   on that joint, `k_p = K/2`, `k_d = C Δt/2`, `θ* = F/K` (MuJoCo's joint
//!   stiffness `K = g² kp`, damping `C = g² kv` and force at rest
//!   `F = g kp u`, `u` the control at rest: 0 clamped to `ctrlrange`); such a
//!   joint takes its gains from its actuators, not from the import's PD
//!   hold. Motors (no force at rest, no torque-input channel), other
//!   transmissions (tendon, site, body), activation dynamics and
//!   `forcerange` clamping get report lines, one per actuator;
//! - geom sliding friction → the scene's one contact `μ` (MuJoCo's pair
//!   value `max(μ₁, μ₂)`, largest over the pairs with the floor; other pair
//!   values are listed in the notes: [`contact_friction`]).

pub mod actuators;
mod bodies;
pub mod dump;
mod filter;
mod frame;
mod geoms;
mod world;

use super::ImportOptions;
use super::error::ImportError;
use super::source::SourceRobot;
use crate::energy::effects::EffectSpec;
use crate::scene::schema::{GroundSpec, ObstacleSpec};
use dump::DumpGeom;
use std::path::Path;

/// Edge (m) of the cube that keeps a massless joint frame valid.
pub const FRAME_CUBE: f64 = 1e-3;

/// What an MJCF file adds to the imported robot's scene.
#[derive(Clone, Debug, Default)]
pub struct MjcfScene {
    /// m/s², world frame.
    pub gravity: [f64; 3],
    pub ground: Option<GroundSpec>,
    pub obstacles: Vec<ObstacleSpec>,
    /// Excluded pairs of robot link names (MuJoCo's contact filter).
    pub exclude: Vec<[String; 2]>,
    /// Robot links that never collide with the ground.
    pub exclude_ground: Vec<String>,
    /// Links that never collide with each obstacle: (obstacle, link).
    pub exclude_obstacle: Vec<[String; 2]>,
    pub effects: Vec<EffectSpec>,
    /// The one friction coefficient the scene's contact takes (see
    /// [`contact_friction`]); `None` when no two geoms may collide.
    pub friction: Option<f64>,
    /// PD gains and targets of the joints driven by position-like actuators
    /// ([`actuators`]), by joint name.
    pub drives: std::collections::BTreeMap<String, actuators::Drive>,
}

/// The scene has one friction coefficient; MuJoCo gives each contact pair
/// `max(μ₁, μ₂)` of its two geoms' sliding friction (equal priorities, the
/// default). Taken: the largest pair value over the pairs that involve a
/// world geom (the floor) when there are any, else over all pairs; a report
/// line says which, and lists the other pair values when they differ
/// (torsional and rolling friction are not modelled).
pub fn contact_friction(d: &dump::Dump, notes: &mut Vec<String>) -> Option<f64> {
    let g: Vec<&DumpGeom> = d.geoms.iter().filter(|g| g.collides()).collect();
    let mut world_pairs = Vec::new();
    let mut all_pairs = Vec::new();
    for (i, a) in g.iter().enumerate() {
        for b in &g[i + 1..] {
            if a.body == b.body || !a.may_collide_with(b) {
                continue;
            }
            let mu = a.friction.max(b.friction);
            all_pairs.push(mu);
            if a.body < 0 || b.body < 0 {
                world_pairs.push(mu);
            }
        }
    }
    let (pairs, which) = if world_pairs.is_empty() {
        (&all_pairs, "geom pairs")
    } else {
        (&world_pairs, "pairs with a world geom")
    };
    let mu = pairs.iter().copied().fold(f64::NAN, f64::max);
    if mu.is_nan() {
        return None;
    }
    let mut distinct: Vec<f64> = all_pairs.clone();
    distinct.sort_by(f64::total_cmp);
    distinct.dedup();
    let mut line = format!(
        "contact friction μ = {mu} (MuJoCo's pair value max(μ₁, μ₂), largest over the {which})"
    );
    if distinct.len() > 1 {
        line.push_str(&format!(
            "; the scene has one μ, so the other pair values {distinct:?} are not represented"
        ));
    }
    notes.push(line);
    Some(mu)
}

/// Whether `path` is an MJCF file (its root element is `<mujoco>`).
pub fn is_mjcf(path: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(path) else {
        return false;
    };
    roxmltree::Document::parse(&text).is_ok_and(|d| d.root_element().has_tag_name("mujoco"))
}

fn invalid(path: &Path, element: String, msg: String) -> ImportError {
    ImportError::InvalidMjcf {
        path: path.to_path_buf(),
        element,
        msg,
    }
}

/// Reads an MJCF file: the robot (every non-world body) and what it adds
/// to the scene.
pub fn read_mjcf(
    path: &Path,
    opts: &ImportOptions,
) -> Result<(SourceRobot, MjcfScene), ImportError> {
    let d = dump::dump(path)?;
    let mut notes = vec![format!(
        "MJCF compiled by MuJoCo; its time step {} s is not used (the scene's dt is {} s)",
        d.option.timestep, opts.dt
    )];
    for (what, n) in &d.unsupported {
        if *n > 0 {
            notes.push(format!("{n} {what} left out (not simulated)"));
        }
    }
    let drives = actuators::drives(&d, opts.dt, &mut notes);
    let nb = d.bodies.len();
    if nb == 0 {
        return Err(invalid(
            path,
            "worldbody".into(),
            "the model has no bodies".into(),
        ));
    }
    let mut geoms_of: Vec<Vec<&DumpGeom>> = vec![Vec::new(); nb];
    let mut world_geoms = Vec::new();
    for g in &d.geoms {
        match usize::try_from(g.body) {
            Ok(b) if b < nb => geoms_of[b].push(g),
            _ => world_geoms.push(g),
        }
    }
    let friction = contact_friction(&d, &mut notes);
    let weld = filter::weld_groups(path, &d)?;
    let bodies = bodies::body_links(path, &d, &geoms_of, opts, &mut notes)?;
    let exclude = filter::body_pairs(&d, &weld, &geoms_of, &bodies);
    let world = world::world(path, &world_geoms, &mut notes)?;
    let (exclude_ground, exclude_obstacle) =
        filter::world_pairs(&d, &weld, &geoms_of, &bodies, &world);
    let bodies::Bodies {
        links,
        initial,
        effects,
        ..
    } = bodies;
    let world::World {
        ground, obstacles, ..
    } = world;
    let robot = SourceRobot {
        name: super::source::sanitize(if d.model.is_empty() {
            path.file_stem().and_then(|s| s.to_str()).unwrap_or("robot")
        } else {
            &d.model
        }),
        file: path.to_path_buf(),
        links,
        notes,
        initial,
        keep_geometry: true,
    };
    Ok((
        robot,
        MjcfScene {
            gravity: d.option.gravity,
            ground,
            obstacles,
            exclude,
            exclude_ground,
            exclude_obstacle,
            effects,
            friction,
            drives,
        },
    ))
}
