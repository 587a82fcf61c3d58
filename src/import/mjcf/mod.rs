//! MJCF (MuJoCo XML) input.
//!
//! **Reader.** The model is compiled by MuJoCo itself (`tools/mjcf_dump.py`
//! through the project's Python, the `mujoco` package that
//! `tools/setup_python.sh` installs), not by a second MJCF parser here:
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
//!   are excluded;
//! - joint ranges → limits, `damping`/`armature`/`frictionloss` → the
//!   scene's `joint_damping`/`armature`/`joint_friction` effects, gravity →
//!   the scene's gravity. Tendons, equality constraints, actuators, joint
//!   springs and height fields are reported in the notes and left out.

pub mod dump;

use super::ImportOptions;
use super::error::ImportError;
use super::source::{
    InputJoint, SourceGeometry, SourceJoint, SourceLink, SourceRobot, SourceShape,
};
use crate::calibrate::effects::{EffectKind, EffectSpec};
use crate::scene::schema::{GroundSpec, HullSpec, JointType, ObstacleSpec, Origin};
use dump::{DumpBody, DumpGeom, DumpJoint};
use nalgebra::{Matrix3, Rotation3, Unit, UnitQuaternion, Vector3};
use std::collections::{BTreeMap, BTreeSet};
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
}

/// Whether `path` is an MJCF file (its root element is `<mujoco>`).
pub fn is_mjcf(path: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(path) else {
        return false;
    };
    roxmltree::Document::parse(&text).is_ok_and(|d| d.root_element().has_tag_name("mujoco"))
}

/// A rigid transform `x ↦ R x + t`.
#[derive(Clone, Copy, Debug)]
struct Frame {
    r: Matrix3<f64>,
    t: Vector3<f64>,
}

impl Frame {
    fn identity() -> Frame {
        Frame {
            r: Matrix3::identity(),
            t: Vector3::zeros(),
        }
    }
    fn translation(t: Vector3<f64>) -> Frame {
        Frame {
            r: Matrix3::identity(),
            t,
        }
    }
    fn pos_quat(pos: &[f64; 3], q: &[f64; 4]) -> Frame {
        Frame {
            r: quat_matrix(q),
            t: Vector3::from(*pos),
        }
    }
    fn then(&self, o: &Frame) -> Frame {
        Frame {
            r: self.r * o.r,
            t: self.r * o.t + self.t,
        }
    }
    fn origin(&self) -> Origin {
        let (roll, pitch, yaw) = Rotation3::from_matrix_unchecked(self.r).euler_angles();
        Origin {
            xyz: self.t.into(),
            rpy: [roll, pitch, yaw],
        }
    }
}

/// MuJoCo quaternion `[w, x, y, z]` → rotation matrix.
fn quat_matrix(q: &[f64; 4]) -> Matrix3<f64> {
    UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]))
        .to_rotation_matrix()
        .into_inner()
}

/// Rotation vector of a rotation matrix.
fn rotation_vector(r: &Matrix3<f64>) -> [f64; 3] {
    Rotation3::from_matrix_unchecked(*r).scaled_axis().into()
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
    // Weld groups (MuJoCo's `body_weldid`): a body without joints moves with
    // its parent. `None` is the world.
    let mut weld: Vec<Option<usize>> = vec![None; nb];
    for (b, body) in d.bodies.iter().enumerate() {
        let parent = usize::try_from(body.parent).ok();
        if parent.is_some_and(|p| p >= b) {
            return Err(invalid(
                path,
                format!("body \"{}\"", body.name),
                "bodies are not in tree order".into(),
            ));
        }
        weld[b] = if body.joints.is_empty() || body.mocap {
            parent.and_then(|p| weld[p])
        } else {
            Some(b)
        };
    }

    let mut links: Vec<SourceLink> = Vec::new();
    let mut geometry_link = vec![0usize; nb];
    let mut anchor = vec![Vector3::zeros(); nb];
    let mut collides = vec![false; nb];
    let mut initial = BTreeMap::new();
    let mut effects = Vec::new();
    let mut joint_names: BTreeSet<String> = d
        .bodies
        .iter()
        .flat_map(|b| b.joints.iter().map(|j| j.name.clone()))
        .collect();
    for (b, body) in d.bodies.iter().enumerate() {
        let el = format!("body \"{}\"", body.name);
        let parent_body = usize::try_from(body.parent).ok();
        let (parent_link, parent_anchor) = match parent_body {
            Some(p) => (Some(geometry_link[p]), anchor[p]),
            None => (None, Vector3::zeros()),
        };
        // The body frame in the parent link's frame.
        let body_frame =
            Frame::translation(-parent_anchor).then(&Frame::pos_quat(&body.pos, &body.quat));
        let joints: &[DumpJoint] = if body.mocap {
            notes.push(format!("{el}: mocap body imported as fixed"));
            &[]
        } else {
            &body.joints
        };
        let mut prev_anchor = Vector3::zeros();
        let mut pending = body_frame;
        let mut parent = parent_link;
        let nj = joints.len();
        for (k, j) in joints.iter().enumerate() {
            let jel = format!("joint \"{}\" of {el}", j.name);
            let last = k + 1 == nj;
            let p = Vector3::from(j.pos);
            let axis = Vector3::from(j.axis);
            let q0 = |i: usize| j.qpos0.get(i).copied().unwrap_or(0.0);
            let (kind, origin, q) = match j.kind.as_str() {
                "free" => {
                    if nj != 1 || parent_body.is_some() {
                        return Err(invalid(
                            path,
                            jel,
                            "a free joint must be the only joint of a body of the world".into(),
                        ));
                    }
                    // θ = [x, y, z, φ]: the body pose itself.
                    let rv = rotation_vector(&pending.r);
                    let q = vec![pending.t.x, pending.t.y, pending.t.z, rv[0], rv[1], rv[2]];
                    (JointType::Free, Frame::identity(), q)
                }
                "ball" => (
                    JointType::Spherical,
                    pending.then(&Frame::translation(p - prev_anchor)),
                    vec![0.0; 3],
                ),
                "hinge" | "slide" => {
                    let at = pending.then(&Frame::translation(p - prev_anchor));
                    // Fold `ref` (qpos0) into the attachment so that θ = qpos.
                    let r = q0(0);
                    let (kind, undo) = if j.kind == "hinge" {
                        let u = Unit::new_normalize(axis);
                        (
                            JointType::Revolute,
                            Frame {
                                r: Rotation3::from_axis_angle(&u, -r).into_inner(),
                                t: Vector3::zeros(),
                            },
                        )
                    } else {
                        (JointType::Prismatic, Frame::translation(-r * axis))
                    };
                    (kind, at.then(&undo), vec![r])
                }
                other => {
                    return Err(invalid(
                        path,
                        jel,
                        format!("unknown joint type \"{other}\""),
                    ));
                }
            };
            let link_name = if last {
                body.name.clone()
            } else {
                format!("{}__{}", body.name, j.name)
            };
            let one_dof = matches!(kind, JointType::Revolute | JointType::Prismatic);
            let input_joints = if one_dof {
                let (lower, upper, limited) = match j.range {
                    Some([lo, hi]) => (lo, hi, lo < hi),
                    None if kind == JointType::Revolute => {
                        (-std::f64::consts::PI, std::f64::consts::PI, false)
                    }
                    None => (-1.0, 1.0, false),
                };
                vec![InputJoint {
                    name: j.name.clone(),
                    kind: j.kind.clone(),
                    lower,
                    upper,
                    limited,
                    velocity: None,
                    effort: None,
                }]
            } else {
                Vec::new()
            };
            if q.iter().any(|v| *v != 0.0) {
                initial.insert(j.name.clone(), q);
            }
            for (kind_e, v) in [
                (EffectKind::JointDamping, j.damping),
                (EffectKind::Armature, j.armature),
                (EffectKind::JointFriction, j.frictionloss),
            ] {
                if v > 0.0 {
                    if one_dof {
                        effects.push(EffectSpec {
                            effect: kind_e,
                            on: j.name.clone(),
                            values: vec![v],
                            eps: None,
                        });
                    } else {
                        notes.push(format!(
                            "{jel}: {} {v} left out (only hinge and slide joints take it)",
                            kind_e.name()
                        ));
                    }
                }
            }
            if j.stiffness > 0.0 {
                notes.push(format!(
                    "{jel}: joint spring (stiffness {}) left out",
                    j.stiffness
                ));
            }
            links.push(SourceLink {
                name: link_name.clone(),
                parent,
                joint: SourceJoint {
                    name: j.name.clone(),
                    kind,
                    axis: one_dof.then(|| axis.into()),
                    axes: None,
                    origin: origin.origin(),
                    input_joints,
                    mimic: None,
                },
                geometry: if last {
                    Vec::new()
                } else {
                    vec![frame_cube(&link_name)]
                },
                mass: None,
                moment: None,
                frame_only: !last,
                collides: false,
            });
            parent = Some(links.len() - 1);
            prev_anchor = if kind == JointType::Free {
                Vector3::zeros()
            } else {
                p
            };
            pending = Frame::identity();
        }
        if nj == 0 {
            let mut jn = body.name.clone();
            while joint_names.contains(&jn) {
                jn.push_str("_weld");
            }
            joint_names.insert(jn.clone());
            links.push(SourceLink {
                name: body.name.clone(),
                parent: parent_link,
                joint: SourceJoint {
                    name: jn,
                    kind: JointType::Fixed,
                    axis: None,
                    axes: None,
                    origin: body_frame.origin(),
                    input_joints: Vec::new(),
                    mimic: None,
                },
                geometry: Vec::new(),
                mass: None,
                moment: None,
                frame_only: false,
                collides: false,
            });
        }
        let li = links.len() - 1;
        geometry_link[b] = li;
        anchor[b] = prev_anchor;
        // Geometry and inertial of the body, in the link frame x − p_k.
        let colliding: Vec<&DumpGeom> = geoms_of[b]
            .iter()
            .copied()
            .filter(|g| g.collides())
            .collect();
        collides[b] = !colliding.is_empty();
        let shown = if colliding.is_empty() {
            geoms_of[b].clone()
        } else {
            colliding
        };
        let mut geometry = Vec::new();
        for g in shown {
            if let Some(s) = geom_shape(path, g, &mut notes)? {
                geometry.push(SourceGeometry {
                    element: format!("geom \"{}\" of {el}", g.name),
                    rotation: quat_matrix(&g.quat),
                    translation: Vector3::from(g.pos) - prev_anchor,
                    shape: s,
                });
            }
        }
        if geometry.is_empty() {
            geometry.push(SourceGeometry {
                element: format!("{el} (no geometry)"),
                rotation: Matrix3::identity(),
                translation: Vector3::zeros(),
                shape: SourceShape::Tiny {
                    edge: opts.tiny_hull_size,
                },
            });
        }
        let link = &mut links[li];
        link.geometry = geometry;
        link.collides = collides[b];
        link.moment = Some(body_moment(body, &prev_anchor));
        link.mass = Some(body.mass).filter(|m| *m > 0.0);
        if body.mass <= 0.0 {
            link.frame_only = true;
            notes.push(format!("{el}: massless"));
        }
    }

    // MuJoCo's contact filter, per pair of bodies that collide at all.
    let weld_parent = |w: Option<usize>| -> Option<usize> {
        w.and_then(|b| {
            usize::try_from(d.bodies[b].parent)
                .ok()
                .and_then(|p| weld[p])
        })
    };
    let masks_meet = |a: &[&DumpGeom], b: &[&DumpGeom]| {
        a.iter().filter(|g| g.collides()).any(|ga| {
            b.iter()
                .filter(|g| g.collides())
                .any(|gb| ga.may_collide_with(gb))
        })
    };
    let mut exclude = Vec::new();
    for a in 0..nb {
        for b in a + 1..nb {
            if !(collides[a] && collides[b]) || geometry_link[a] == geometry_link[b] {
                continue;
            }
            let (wa, wb) = (weld[a], weld[b]);
            // MuJoCo's `filterparent`: a weld group and its parent group,
            // unless the parent is the world.
            let parent_child =
                wa.is_some() && wb.is_some() && (weld_parent(wa) == wb || weld_parent(wb) == wa);
            let filtered = wa == wb || parent_child || !masks_meet(&geoms_of[a], &geoms_of[b]);
            if filtered {
                exclude.push([
                    links[geometry_link[a]].name.clone(),
                    links[geometry_link[b]].name.clone(),
                ]);
            }
        }
    }

    // World geoms: the first upward plane is the ground, other colliding
    // geoms are obstacles.
    let mut ground = None;
    let mut ground_geom = None;
    let mut obstacles = Vec::new();
    let mut obstacle_geoms = Vec::new();
    let mut visual = 0;
    for g in &world_geoms {
        if !g.collides() {
            visual += 1;
            continue;
        }
        let r = quat_matrix(&g.quat);
        if g.kind == "plane" {
            let n = r * Vector3::z();
            if ground.is_none() && n.z > 1e-6 {
                let tilt = n.z.clamp(-1.0, 1.0).acos();
                let axis = Vector3::z().cross(&n);
                let slope_axis = if axis.norm() > 1e-12 {
                    axis.normalize().into()
                } else {
                    [0.0, 1.0, 0.0]
                };
                ground = Some(GroundSpec {
                    height: n.dot(&Vector3::from(g.pos)),
                    slope_deg: tilt.to_degrees(),
                    slope_axis,
                    half_size: 50.0,
                    thickness: 1.0,
                });
                ground_geom = Some(*g);
            } else {
                notes.push(format!(
                    "world geom \"{}\": only one upward plane becomes the ground; left out",
                    g.name
                ));
            }
            continue;
        }
        let Some(shape) = geom_shape(path, g, &mut notes)? else {
            continue;
        };
        let hull = shape_points(path, &format!("world geom \"{}\"", g.name), &shape)?;
        obstacles.push(ObstacleSpec {
            name: super::source::sanitize(&g.name),
            origin: Frame {
                r,
                t: Vector3::from(g.pos),
            }
            .origin(),
            hulls: vec![HullSpec::from_vertices(
                hull.iter().map(|v| [v.x, v.y, v.z]).collect(),
            )],
        });
        obstacle_geoms.push(*g);
    }
    if visual > 0 {
        notes.push(format!("{visual} visual world geom(s) left out"));
    }
    // The world's geoms meet no body welded to the world, and only bodies
    // whose masks match.
    let mut exclude_ground = Vec::new();
    let mut exclude_obstacle = Vec::new();
    for b in 0..nb {
        if !collides[b] {
            continue;
        }
        let name = &links[geometry_link[b]].name;
        if let Some(g) = ground_geom
            && (weld[b].is_none() || !masks_meet(&geoms_of[b], &[g]))
        {
            exclude_ground.push(name.clone());
        }
        for (o, g) in obstacles.iter().zip(&obstacle_geoms) {
            if weld[b].is_none() || !masks_meet(&geoms_of[b], &[*g]) {
                exclude_obstacle.push([o.name.clone(), name.clone()]);
            }
        }
    }
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
        },
    ))
}

/// The massless frame's cube.
fn frame_cube(link: &str) -> SourceGeometry {
    SourceGeometry {
        element: format!("joint frame \"{link}\""),
        rotation: Matrix3::identity(),
        translation: Vector3::zeros(),
        shape: SourceShape::Tiny { edge: FRAME_CUBE },
    }
}

/// The body's inertial as a 4×4 second moment in the link frame (body
/// frame moved by `−anchor`).
fn body_moment(body: &DumpBody, anchor: &Vector3<f64>) -> nalgebra::Matrix4<f64> {
    let r = quat_matrix(&body.iquat);
    let i = r * Matrix3::from_diagonal(&Vector3::from(body.inertia)) * r.transpose();
    crate::model::Inertial {
        mass: body.mass,
        com: Vector3::from(body.ipos) - anchor,
        inertia: i,
    }
    .second_moment()
}

/// The shape of a geom (`None`, with a note, for what is left out).
fn geom_shape(
    path: &Path,
    g: &DumpGeom,
    notes: &mut Vec<String>,
) -> Result<Option<SourceShape>, ImportError> {
    let s = g.size;
    Ok(Some(match g.kind.as_str() {
        "sphere" => SourceShape::Sphere { radius: s[0] },
        "capsule" => SourceShape::Capsule {
            radius: s[0],
            length: 2.0 * s[1],
        },
        "cylinder" => SourceShape::Cylinder {
            radius: s[0],
            length: 2.0 * s[1],
        },
        "box" => SourceShape::Box {
            size: [2.0 * s[0], 2.0 * s[1], 2.0 * s[2]],
        },
        "ellipsoid" => SourceShape::Ellipsoid { radii: s },
        "mesh" => {
            let Some(m) = &g.mesh else {
                return Err(invalid(
                    path,
                    format!("geom \"{}\"", g.name),
                    "mesh geom without mesh data".into(),
                ));
            };
            SourceShape::ConvexMesh {
                mesh: super::mesh::TriMesh {
                    vertices: m.vertices.iter().map(|v| Vector3::from(*v)).collect(),
                    triangles: m.faces.clone(),
                },
            }
        }
        other => {
            notes.push(format!(
                "geom \"{}\": type {other} is not supported here; left out",
                g.name
            ));
            return Ok(None);
        }
    }))
}

/// The hull points of a shape (for obstacles), in the geom frame.
fn shape_points(
    path: &Path,
    element: &str,
    shape: &SourceShape,
) -> Result<Vec<Vector3<f64>>, ImportError> {
    use super::primitives as p;
    let err = |msg: String| invalid(path, element.to_string(), msg);
    Ok(match shape {
        SourceShape::Sphere { radius } => p::sphere_hull(*radius).map_err(err)?.hull,
        SourceShape::Capsule { radius, length } => {
            p::capsule_hull(*radius, *length).map_err(err)?.hull
        }
        SourceShape::Cylinder { radius, length } => {
            p::cylinder_hull(*radius, *length).map_err(err)?.hull
        }
        SourceShape::Box { size } => p::box_hull(*size).map_err(err)?.hull,
        SourceShape::Ellipsoid { radii } => p::ellipsoid_hull(*radii).map_err(err)?.hull,
        SourceShape::ConvexMesh { mesh } => {
            super::polytope::convex_hull(&mesh.vertices)
                .map_err(err)?
                .vertices
        }
        SourceShape::Mesh { .. } | SourceShape::Tiny { .. } => {
            unreachable!("not produced for MJCF")
        }
    })
}
