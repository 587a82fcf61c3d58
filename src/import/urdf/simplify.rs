//! Links without geometry, simplified in four passes (the module docs of
//! [`super`] give the rules): a bare root dropped, bare links on fixed
//! joints merged into their parents, two orthogonal hinges through a bare
//! link merged into a ball joint, the rest given a tiny cube; then the
//! remaining links compacted.

use super::super::ImportOptions;
use super::super::source::*;
use super::frames::*;
use crate::scene::schema::JointType;
use nalgebra::{Matrix3, Matrix4, Vector3};

/// Links by input position, `None` once removed.
pub(super) type Slots = Vec<Option<SourceLink>>;

fn children_of_raw(links: &[Option<SourceLink>], p: usize) -> Vec<usize> {
    (0..links.len())
        .filter(|&c| links[c].as_ref().is_some_and(|l| l.parent == Some(p)))
        .collect()
}

/// Pass 1: a geometry-less root with children is dropped; its children
/// become roots at their own origins.
pub(super) fn drop_bare_root(links: &mut Slots, notes: &mut Vec<String>) {
    if links[0].as_ref().unwrap().geometry.is_empty() && !children_of_raw(links, 0).is_empty() {
        let root = links[0].take().unwrap();
        for c in children_of_raw(links, 0) {
            links[c].as_mut().unwrap().parent = None;
        }
        notes.push(format!(
            "link \"{}\" has no geometry and is the root: dropped, its child joints attach to the base",
            root.name
        ));
    }
}

/// Pass 2: geometry-less links on fixed joints are merged into their
/// parents (mass and second moment `T M Tᵀ` added, children re-attached
/// with the composed origin).
pub(super) fn merge_fixed_bare_links(links: &mut Slots, notes: &mut Vec<String>) {
    for i in 0..links.len() {
        let Some(l) = links[i].as_ref() else { continue };
        if !l.geometry.is_empty() || l.joint.kind != JointType::Fixed {
            continue;
        }
        let Some(p) = l.parent else { continue };
        let l = links[i].take().unwrap();
        if let Some(m) = l.mass {
            let pl = links[p].as_mut().unwrap();
            pl.mass = Some(pl.mass.unwrap_or(0.0) + m);
        }
        if let Some(m) = l.moment {
            let (r, t) = rt(&l.joint.origin);
            let pl = links[p].as_mut().unwrap();
            pl.moment = Some(pl.moment.unwrap_or_else(Matrix4::zeros) + moved_moment(&m, &r, &t));
        }
        for c in children_of_raw(links, i) {
            let cl = links[c].as_mut().unwrap();
            cl.parent = Some(p);
            cl.joint.origin = compose_origin(&l.joint.origin, &cl.joint.origin);
        }
        notes.push(format!(
            "link \"{}\" has no geometry and a fixed joint: merged into \"{}\"",
            l.name,
            links[p].as_ref().unwrap().name
        ));
    }
}

/// The only child of bare revolute link `i` when it is a revolute joint
/// at a zero origin with an axis orthogonal to `i`'s.
fn orthogonal_hinge_child(links: &Slots, i: usize) -> Option<usize> {
    let m = links[i].as_ref()?;
    if !m.geometry.is_empty() || m.joint.kind != JointType::Revolute {
        return None;
    }
    let kids = children_of_raw(links, i);
    if kids.len() != 1 {
        return None;
    }
    let c = kids[0];
    let cl = links[c].as_ref().unwrap();
    let zero = cl
        .joint
        .origin
        .xyz
        .iter()
        .chain(&cl.joint.origin.rpy)
        .all(|v| v.abs() < 1e-12);
    let (a1, a2) = (m.joint.axis.unwrap(), cl.joint.axis.unwrap_or([0.0; 3]));
    let dot: f64 = a1.iter().zip(&a2).map(|(x, y)| x * y).sum();
    if cl.joint.kind != JointType::Revolute || !zero || dot.abs() > 1e-9 {
        return None;
    }
    Some(c)
}

/// Pass 3: revolute pairs through a geometry-less link become one
/// two-hinge ball joint.
pub(super) fn merge_hinge_pairs(links: &mut Slots, notes: &mut Vec<String>) {
    for i in 0..links.len() {
        let Some(c) = orthogonal_hinge_child(links, i) else {
            continue;
        };
        let m = links[i].take().unwrap();
        let cl = links[c].as_mut().unwrap();
        let (a1, a2) = (m.joint.axis.unwrap(), cl.joint.axis.unwrap_or([0.0; 3]));
        let mut inputs = m.joint.input_joints.clone();
        inputs.append(&mut cl.joint.input_joints);
        cl.joint = SourceJoint {
            name: format!("{}+{}", m.joint.name, cl.joint.name),
            kind: JointType::Ball,
            axis: None,
            axes: Some([a1, a2]),
            origin: m.joint.origin.clone(),
            input_joints: inputs,
            mimic: None,
        };
        cl.parent = m.parent;
        if let Some(mm) = m.mass {
            cl.mass = Some(cl.mass.unwrap_or(0.0) + mm);
        }
        // The hinge link's frame is the child's at zero second-hinge angle;
        // its inertial is added there (it then turns with the second hinge
        // too: exact for mass and a COM on that hinge's axis).
        if let Some(mm) = m.moment {
            cl.moment = Some(cl.moment.unwrap_or_else(Matrix4::zeros) + mm);
        }
        notes.push(format!(
            "link \"{}\" has no geometry between two orthogonal hinges: joints merged into ball joint \"{}\"",
            m.name, cl.joint.name
        ));
    }
}

/// Pass 4: every remaining geometry-less link gets a cube of edge
/// `opts.tiny_hull_size` at its origin.
pub(super) fn fill_bare_links(links: &mut Slots, opts: &ImportOptions, notes: &mut Vec<String>) {
    for l in links.iter_mut().flatten() {
        if l.geometry.is_empty() {
            l.geometry.push(SourceGeometry {
                element: format!("link \"{}\" (no geometry)", l.name),
                rotation: Matrix3::identity(),
                translation: Vector3::zeros(),
                shape: SourceShape::Tiny {
                    edge: opts.tiny_hull_size,
                },
            });
            notes.push(format!(
                "link \"{}\" has no geometry: a {} m cube at its origin stands in",
                l.name, opts.tiny_hull_size
            ));
        }
    }
}

/// The remaining links in order, parents re-indexed.
pub(super) fn compact(links: Slots) -> Vec<SourceLink> {
    let mut new_index = vec![usize::MAX; links.len()];
    let mut out = Vec::new();
    for (i, l) in links.into_iter().enumerate() {
        if let Some(mut l) = l {
            l.parent = l.parent.map(|p| new_index[p]);
            debug_assert!(l.parent.is_none_or(|p| p != usize::MAX));
            new_index[i] = out.len();
            out.push(l);
        }
    }
    out
}
