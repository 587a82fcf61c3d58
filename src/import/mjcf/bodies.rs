//! MJCF bodies → links: a body with joints `j₁ … j_k` becomes a chain of
//! `k` links (the first `k − 1` massless frames), anchors and `ref` folded
//! into the attachments (see the module docs of [`super`]).

use super::super::ImportOptions;
use super::super::error::ImportError;
use super::super::source::*;
use super::dump::{Dump, DumpBody, DumpGeom, DumpJoint};
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
    let mut out = Bodies {
        links: Vec::new(),
        geometry_link: vec![0usize; nb],
        collides: vec![false; nb],
        initial: BTreeMap::new(),
        effects: Vec::new(),
    };
    let mut anchor = vec![Vector3::zeros(); nb];
    let mut joint_names: BTreeSet<String> = d
        .bodies
        .iter()
        .flat_map(|b| b.joints.iter().map(|j| j.name.clone()))
        .collect();
    for (b, body) in d.bodies.iter().enumerate() {
        let el = format!("body \"{}\"", body.name);
        let parent_body = usize::try_from(body.parent).ok();
        let (parent_link, parent_anchor) = match parent_body {
            Some(p) => (Some(out.geometry_link[p]), anchor[p]),
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
        let chain = BodyChain {
            path,
            body,
            el: &el,
            parent_body,
            parent_link,
            body_frame,
        };
        let body_anchor = if joints.is_empty() {
            out.links.push(weld_link(&chain, &mut joint_names));
            Vector3::zeros()
        } else {
            joint_chain(&chain, joints, &mut out, notes)?
        };
        let li = out.links.len() - 1;
        out.geometry_link[b] = li;
        anchor[b] = body_anchor;
        out.collides[b] = body_geometry(
            &chain,
            &geoms_of[b],
            body_anchor,
            opts,
            &mut out.links[li],
            notes,
        )?;
    }
    Ok(out)
}

/// A body being converted: where it hangs and how to name it in messages.
struct BodyChain<'a> {
    path: &'a Path,
    body: &'a DumpBody,
    /// `body "NAME"`.
    el: &'a str,
    parent_body: Option<usize>,
    parent_link: Option<usize>,
    /// The body frame in the parent link's frame.
    body_frame: Frame,
}

/// A body without joints: one link welded at the body frame, its joint
/// named after the body (suffixed `_weld` while that names a joint).
fn weld_link(c: &BodyChain, joint_names: &mut BTreeSet<String>) -> SourceLink {
    let mut jn = c.body.name.clone();
    while joint_names.contains(&jn) {
        jn.push_str("_weld");
    }
    joint_names.insert(jn.clone());
    SourceLink {
        name: c.body.name.clone(),
        parent: c.parent_link,
        joint: SourceJoint {
            name: jn,
            kind: JointType::Fixed,
            axis: None,
            axes: None,
            origin: c.body_frame.origin(),
            input_joints: Vec::new(),
            mimic: None,
        },
        geometry: Vec::new(),
        mass: None,
        moment: None,
        frame_only: false,
        collides: false,
    }
}

/// The links of a body's joints `j₁ … j_k` (the first `k − 1` massless
/// frames), their initial coordinates and effects; returns the last
/// anchor `p_k` (zero for a free joint).
fn joint_chain(
    c: &BodyChain,
    joints: &[DumpJoint],
    out: &mut Bodies,
    notes: &mut Vec<String>,
) -> Result<Vector3<f64>, ImportError> {
    let mut prev_anchor = Vector3::zeros();
    let mut pending = c.body_frame;
    let mut parent = c.parent_link;
    let nj = joints.len();
    for (k, j) in joints.iter().enumerate() {
        let jel = format!("joint \"{}\" of {}", j.name, c.el);
        let last = k + 1 == nj;
        let p = Vector3::from(j.pos);
        let axis = Vector3::from(j.axis);
        let (kind, origin, q) = joint_attachment(c, j, nj, &jel, &pending, &prev_anchor)?;
        let link_name = if last {
            c.body.name.clone()
        } else {
            format!("{}__{}", c.body.name, j.name)
        };
        let one_dof = matches!(kind, JointType::Revolute | JointType::Prismatic);
        let input_joints = if one_dof {
            vec![input_joint(j, kind)]
        } else {
            Vec::new()
        };
        if q.iter().any(|v| *v != 0.0) {
            out.initial.insert(j.name.clone(), q);
        }
        joint_effects(j, one_dof, &jel, &mut out.effects, notes);
        out.links.push(SourceLink {
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
        parent = Some(out.links.len() - 1);
        prev_anchor = if kind == JointType::Free {
            Vector3::zeros()
        } else {
            p
        };
        pending = Frame::identity();
    }
    Ok(prev_anchor)
}

/// A joint's scene type, attachment `G_{i−1} T(p_i − p_{i−1})` (with a
/// hinge/slide `ref` undone so that θ = qpos) and initial coordinates.
fn joint_attachment(
    c: &BodyChain,
    j: &DumpJoint,
    nj: usize,
    jel: &str,
    pending: &Frame,
    prev_anchor: &Vector3<f64>,
) -> Result<(JointType, Frame, Vec<f64>), ImportError> {
    let p = Vector3::from(j.pos);
    let axis = Vector3::from(j.axis);
    let q0 = |i: usize| j.qpos0.get(i).copied().unwrap_or(0.0);
    Ok(match j.kind.as_str() {
        "free" => {
            if nj != 1 || c.parent_body.is_some() {
                return Err(invalid(
                    c.path,
                    jel.to_string(),
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
                c.path,
                jel.to_string(),
                format!("unknown joint type \"{other}\""),
            ));
        }
    })
}

/// The input joint of a hinge or slide: its range (or a sampling range).
fn input_joint(j: &DumpJoint, kind: JointType) -> InputJoint {
    let (lower, upper, limited) = match j.range {
        Some([lo, hi]) => (lo, hi, lo < hi),
        None if kind == JointType::Revolute => (-std::f64::consts::PI, std::f64::consts::PI, false),
        None => (-1.0, 1.0, false),
    };
    InputJoint {
        name: j.name.clone(),
        kind: j.kind.clone(),
        lower,
        upper,
        limited,
        velocity: None,
        effort: None,
        // MJCF joint dynamics become effects here ([`joint_effects`]).
        damping: None,
        friction: None,
    }
}

/// `damping`/`armature`/`frictionloss` → effects on hinge/slide joints,
/// `stiffness` with `springref` → a `joint_spring` effect (a report line
/// on other joints).
fn joint_effects(
    j: &DumpJoint,
    one_dof: bool,
    jel: &str,
    effects: &mut Vec<EffectSpec>,
    notes: &mut Vec<String>,
) {
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
        match j.springref.as_slice() {
            [r] if one_dof => effects.push(EffectSpec {
                effect: EffectKind::JointSpring,
                on: j.name.clone(),
                values: vec![j.stiffness, *r],
                eps: None,
            }),
            _ => notes.push(format!(
                "{jel}: joint spring (stiffness {}) left out (only hinge and slide joints take it)",
                j.stiffness
            )),
        }
    }
}

/// The body's geoms (the colliding ones, else the visual ones, else a
/// tiny cube) and inertial on its last link, in the link frame `x − p_k`;
/// returns whether the body collides.
fn body_geometry(
    c: &BodyChain,
    geoms: &[&DumpGeom],
    anchor: Vector3<f64>,
    opts: &ImportOptions,
    link: &mut SourceLink,
    notes: &mut Vec<String>,
) -> Result<bool, ImportError> {
    let colliding: Vec<&DumpGeom> = geoms.iter().copied().filter(|g| g.collides()).collect();
    let collides = !colliding.is_empty();
    let shown = if colliding.is_empty() {
        geoms.to_vec()
    } else {
        colliding
    };
    let mut geometry = Vec::new();
    for g in shown {
        if let Some(s) = geom_shape(c.path, g, notes)? {
            geometry.push(SourceGeometry {
                element: format!("geom \"{}\" of {}", g.name, c.el),
                rotation: quat_matrix(&g.quat),
                translation: Vector3::from(g.pos) - anchor,
                shape: s,
            });
        }
    }
    if geometry.is_empty() {
        geometry.push(SourceGeometry {
            element: format!("{} (no geometry)", c.el),
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
            shape: SourceShape::Tiny {
                edge: opts.tiny_hull_size,
            },
        });
    }
    link.geometry = geometry;
    link.collides = collides;
    link.moment = Some(body_moment(c.body, &anchor));
    link.mass = Some(c.body.mass).filter(|m| *m > 0.0);
    if c.body.mass <= 0.0 {
        link.frame_only = true;
        notes.push(format!("{}: massless", c.el));
    }
    Ok(collides)
}
