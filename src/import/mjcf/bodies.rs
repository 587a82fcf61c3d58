//! MJCF bodies → links: a body with joints `j₁ … j_k` becomes a chain of
//! `k` links (the first `k − 1` massless frames), anchors and `ref` folded
//! into the attachments (see the module docs of [`super`]).

use super::super::ImportOptions;
use super::super::error::ImportError;
use super::super::source::*;
use super::dump::{Dump, DumpGeom, DumpJoint};
use super::frame::*;
use super::geoms::*;
use super::invalid;
use crate::energy::effects::{EffectKind, EffectSpec};
use crate::scene::schema::JointType;
use nalgebra::{Matrix3, Rotation3, Unit, Vector3};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The links of every body and what they bring to the scene.
pub(super) struct Bodies {
    pub links: Vec<SourceLink>,
    /// Per body, the link carrying its geoms and inertial.
    pub geometry_link: Vec<usize>,
    /// Per body, whether it has geoms MuJoCo can collide.
    pub collides: Vec<bool>,
    pub initial: BTreeMap<String, Vec<f64>>,
    pub effects: Vec<EffectSpec>,
}

/// Converts every body of `d` (`geoms_of[b]`: the geoms of body `b`).
pub(super) fn body_links(
    path: &Path,
    d: &Dump,
    geoms_of: &[Vec<&DumpGeom>],
    opts: &ImportOptions,
    notes: &mut Vec<String>,
) -> Result<Bodies, ImportError> {
    let nb = d.bodies.len();
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
            if let Some(s) = geom_shape(path, g, notes)? {
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

    Ok(Bodies {
        links,
        geometry_link,
        collides,
        initial,
        effects,
    })
}
