//! URDF → [`SourceRobot`].
//!
//! - The XML is checked first (quick-xml) so malformed files and unknown
//!   joint types get errors naming the line or the joint; urdf-rs then
//!   parses the elements.
//! - Joints: `revolute`, `continuous` (→ revolute), `prismatic`, `fixed`,
//!   `floating` (→ free). `planar`, `spherical` and anything else are errors.
//!   Limits are kept for reports and checks (the scene schema has none).
//! - Geometry: `<collision>` elements, or `<visual>` ones when a link has no
//!   collision element. Mesh `scale` is honoured. Paths: `package://PKG/…`
//!   is resolved by looking for a directory `PKG` in each ancestor of the
//!   URDF's directory (or an ancestor named `PKG`), then in every entry of
//!   `ROS_PACKAGE_PATH`; `file://` and absolute paths are used as given;
//!   relative paths are relative to the URDF.
//! - Links without geometry (documented choice):
//!   * the root, when it has children (a `world` link): dropped; its child
//!     joints attach directly to the robot base (identity pose), so world
//!     poses are unchanged;
//!   * a link attached by a `fixed` joint: merged into its parent (its mass
//!     is added to the parent's, its children re-attached with the composed
//!     origin);
//!   * a link between two revolute/continuous joints whose second joint has a
//!     zero origin and an axis orthogonal to the first: the pair becomes one
//!     two-hinge `ball` joint (exactly the same kinematics);
//!   * any other: a tiny cube at the link origin.
//! - Kinematic loops (a link that is the child of two joints, or a cycle)
//!   are errors naming the links and joints.

mod frames;
mod geometry;
mod prescan;

pub use geometry::resolve_mesh_path;

use super::ImportOptions;
use super::error::ImportError;
use super::limits;
use super::pybullet_shapes::SpecialShapes;
use super::source::*;
use crate::scene::schema::{JointType, Origin};
use frames::*;
use geometry::*;
use nalgebra::{Matrix3, Matrix4, Vector3};
use prescan::*;
use std::collections::HashMap;
use std::path::Path;

/// Reads a URDF file.
pub fn read_urdf(path: &Path, opts: &ImportOptions) -> Result<SourceRobot, ImportError> {
    let text = std::fs::read_to_string(path).map_err(|err| ImportError::Io {
        path: path.to_path_buf(),
        err,
    })?;
    if text.trim().is_empty() {
        return Err(ImportError::MalformedXml {
            path: path.to_path_buf(),
            line: None,
            msg: "the file is empty".into(),
        });
    }
    prescan(path, &text)?;
    let normalized = super::tolerant::normalize(&text);
    let robot = urdf_rs::read_from_string(&normalized.text).map_err(|e| {
        let msg = e.to_string();
        let msg = match msg.split("unknown variant `").nth(1).and_then(|s| s.split('`').next()) {
            Some(shape) if msg.contains("expected one of `box`") => format!(
                "geometry <{shape}> is not supported (supported: box, cylinder, capsule, sphere, mesh){}",
                if shape == "plane" { "; for an infinite ground plane use the scene's `ground:`" } else { "" }
            ),
            _ => msg,
        };
        ImportError::MalformedXml {
            path: path.to_path_buf(),
            line: None,
            msg,
        }
    })?;
    if robot.links.is_empty() && text.contains("<deformable") {
        return Err(ImportError::InvalidUrdf {
            path: path.to_path_buf(),
            element: "robot".into(),
            msg: deformable_message(path, &text),
        });
    }
    let mut special_notes = Vec::new();
    let mut src = convert(path, &robot, &normalized.special, &mut special_notes, opts)?;
    src.notes.extend(normalized.notes);
    src.notes.extend(special_notes);
    Ok(src)
}

fn limits(j: &urdf_rs::Joint) -> (f64, f64) {
    let (lo, hi) = (j.limit.lower, j.limit.upper);
    if lo.is_finite() && hi.is_finite() && lo < hi {
        (lo, hi)
    } else if matches!(j.joint_type, urdf_rs::JointType::Prismatic) {
        (-0.5, 0.5)
    } else {
        (-std::f64::consts::PI, std::f64::consts::PI)
    }
}

fn type_name(t: &urdf_rs::JointType) -> &'static str {
    match t {
        urdf_rs::JointType::Revolute => "revolute",
        urdf_rs::JointType::Continuous => "continuous",
        urdf_rs::JointType::Prismatic => "prismatic",
        urdf_rs::JointType::Fixed => "fixed",
        urdf_rs::JointType::Floating => "floating",
        urdf_rs::JointType::Planar => "planar",
        urdf_rs::JointType::Spherical => "spherical",
    }
}

fn convert(
    path: &Path,
    robot: &urdf_rs::Robot,
    special: &SpecialShapes,
    special_notes: &mut Vec<String>,
    opts: &ImportOptions,
) -> Result<SourceRobot, ImportError> {
    let invalid = |element: String, msg: String| ImportError::InvalidUrdf {
        path: path.to_path_buf(),
        element,
        msg,
    };
    if robot.links.is_empty() {
        return Err(invalid("robot".into(), "the URDF has no <link>".into()));
    }
    let mut index = HashMap::new();
    for (i, l) in robot.links.iter().enumerate() {
        if index.insert(l.name.as_str(), i).is_some() {
            return Err(invalid(
                format!("link \"{}\"", l.name),
                "duplicate link name".into(),
            ));
        }
    }
    // Parent joint of each link.
    let mut parent_joint: Vec<Option<usize>> = vec![None; robot.links.len()];
    let mut joint_names = HashMap::new();
    for (ji, j) in robot.joints.iter().enumerate() {
        if joint_names.insert(j.name.as_str(), ji).is_some() {
            return Err(invalid(
                format!("joint \"{}\"", j.name),
                "duplicate joint name".into(),
            ));
        }
        for (role, l) in [("parent", &j.parent.link), ("child", &j.child.link)] {
            if !index.contains_key(l.as_str()) {
                return Err(invalid(
                    format!("joint \"{}\"", j.name),
                    format!("{role} link \"{l}\" does not exist"),
                ));
            }
        }
        if matches!(j.joint_type, urdf_rs::JointType::Planar) {
            return Err(ImportError::UnsupportedJoint {
                path: path.to_path_buf(),
                joint: j.name.clone(),
                kind: type_name(&j.joint_type).into(),
            });
        }
        let c = index[j.child.link.as_str()];
        if let Some(prev) = parent_joint[c] {
            return Err(ImportError::KinematicLoop {
                path: path.to_path_buf(),
                msg: format!(
                    "link \"{}\" is the child of two joints, \"{}\" and \"{}\" (URDF describes trees only)",
                    robot.links[c].name, robot.joints[prev].name, j.name
                ),
            });
        }
        parent_joint[c] = Some(ji);
    }
    // Cycles: follow parents.
    for start in 0..robot.links.len() {
        let mut seen = vec![start];
        let mut cur = start;
        while let Some(ji) = parent_joint[cur] {
            let p = index[robot.joints[ji].parent.link.as_str()];
            if let Some(pos) = seen.iter().position(|&x| x == p) {
                let names: Vec<String> = seen[pos..]
                    .iter()
                    .rev()
                    .map(|&k| format!("\"{}\"", robot.links[k].name))
                    .collect();
                return Err(ImportError::KinematicLoop {
                    path: path.to_path_buf(),
                    msg: format!(
                        "the links {} form a cycle through joint \"{}\"",
                        names.join(" → "),
                        robot.joints[ji].name
                    ),
                });
            }
            seen.push(p);
            cur = p;
        }
    }
    let roots: Vec<usize> = (0..robot.links.len())
        .filter(|&i| parent_joint[i].is_none())
        .collect();
    if roots.len() != 1 {
        let names: Vec<&str> = roots
            .iter()
            .map(|&i| robot.links[i].name.as_str())
            .collect();
        return Err(invalid(
            "robot".into(),
            format!(
                "a URDF needs exactly one root link, found {}: {}",
                roots.len(),
                names.join(", ")
            ),
        ));
    }
    // Children lists, then a depth-first order from the root.
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
    for (ji, j) in robot.joints.iter().enumerate() {
        children[index[j.parent.link.as_str()]].push(ji);
    }
    let mut order = vec![roots[0]];
    let mut k = 0;
    while k < order.len() {
        for &ji in &children[order[k]] {
            order.push(index[robot.joints[ji].child.link.as_str()]);
        }
        k += 1;
    }

    // Initial links.
    let mut tmp: Vec<SourceLink> = Vec::new();
    let mut massless = Vec::new();
    let mut pos = vec![usize::MAX; robot.links.len()];
    for &li in &order {
        let l = &robot.links[li];
        let geometry = link_geometry(path, l, special, special_notes)?;
        let (parent, joint) = match parent_joint[li] {
            None => (
                None,
                SourceJoint {
                    name: l.name.clone(),
                    kind: JointType::Fixed,
                    axis: None,
                    axes: None,
                    origin: Origin::default(),
                    input_joints: Vec::new(),
                    mimic: None,
                },
            ),
            Some(ji) => {
                let j = &robot.joints[ji];
                let pi = pos[index[j.parent.link.as_str()]];
                let origin = origin_of(&j.origin);
                limits::check_coordinates(
                    "origin",
                    &[origin.xyz.as_slice(), origin.rpy.as_slice()].concat(),
                )
                .map_err(|m| invalid(format!("joint \"{}\"", j.name), m))?;
                // The axis matters only for joints that move along or about
                // it: fixed and floating joints ignore it (URDFs often give
                // them a zero axis).
                let moves_on_axis = matches!(
                    j.joint_type,
                    urdf_rs::JointType::Revolute
                        | urdf_rs::JointType::Continuous
                        | urdf_rs::JointType::Prismatic
                );
                let axis = {
                    let a = Vector3::from(j.axis.xyz.0);
                    if moves_on_axis && !(a.norm() > 1e-12 && a.iter().all(|c| c.is_finite())) {
                        return Err(invalid(
                            format!("joint \"{}\"", j.name),
                            format!("axis {:?} must be finite and non-zero", j.axis.xyz.0),
                        ));
                    }
                    let a = if moves_on_axis {
                        a.normalize()
                    } else {
                        Vector3::z()
                    };
                    [a.x, a.y, a.z]
                };
                let (kind, axis) = match j.joint_type {
                    urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => {
                        (JointType::Revolute, Some(axis))
                    }
                    urdf_rs::JointType::Prismatic => (JointType::Prismatic, Some(axis)),
                    urdf_rs::JointType::Fixed => (JointType::Fixed, None),
                    urdf_rs::JointType::Floating => (JointType::Free, None),
                    // pybullet's extension: a 3-DOF ball joint (rotation
                    // vector in a re-centred chart: no gimbal lock).
                    urdf_rs::JointType::Spherical => (JointType::Spherical, None),
                    urdf_rs::JointType::Planar => unreachable!("rejected above"),
                };
                let (lower, upper) = limits(j);
                let input_joints = if kind == JointType::Fixed {
                    Vec::new()
                } else {
                    let (lo, hi) = (j.limit.lower, j.limit.upper);
                    let positive = |v: f64| Some(v).filter(|v| *v > 0.0 && v.is_finite());
                    vec![InputJoint {
                        name: j.name.clone(),
                        kind: type_name(&j.joint_type).into(),
                        lower,
                        upper,
                        limited: matches!(
                            j.joint_type,
                            urdf_rs::JointType::Revolute | urdf_rs::JointType::Prismatic
                        ) && lo.is_finite()
                            && hi.is_finite()
                            && lo < hi,
                        velocity: positive(j.limit.velocity),
                        effort: positive(j.limit.effort),
                    }]
                };
                (
                    Some(pi),
                    SourceJoint {
                        name: j.name.clone(),
                        kind,
                        axis,
                        axes: None,
                        origin,
                        input_joints,
                        mimic: j.mimic.as_ref().map(|m| crate::scene::schema::MimicSpec {
                            joint: m.joint.clone(),
                            multiplier: m.multiplier,
                            offset: m.offset,
                            stiffness: None,
                        }),
                    },
                )
            }
        };
        limits::check_mass(l.inertial.mass.value)
            .map_err(|m| invalid(format!("link \"{}\" <inertial>", l.name), m))?;
        if l.inertial.mass.value == 0.0 && !geometry.is_empty() {
            massless.push(l.name.clone());
        }
        pos[li] = tmp.len();
        tmp.push(SourceLink {
            name: l.name.clone(),
            parent,
            joint,
            geometry,
            mass: Some(l.inertial.mass.value).filter(|m| *m > 0.0),
            moment: urdf_moment(&l.inertial),
            frame_only: false,
            collides: true,
        });
    }
    let mut links: Vec<Option<SourceLink>> = tmp.into_iter().map(Some).collect();
    let mut notes = Vec::new();
    if !massless.is_empty() {
        notes.push(format!(
            "links with <mass value=\"0\"> get the mass of their hulls at the default density: {}",
            massless.join(", ")
        ));
    }
    let n = links.len();

    // 1. Geometry-less root with children: dropped.
    if links[0].as_ref().unwrap().geometry.is_empty() && !children_of_raw(&links, 0).is_empty() {
        let root = links[0].take().unwrap();
        for c in children_of_raw(&links, 0) {
            links[c].as_mut().unwrap().parent = None;
        }
        notes.push(format!(
            "link \"{}\" has no geometry and is the root: dropped, its child joints attach to the base",
            root.name
        ));
    }
    // 2. Geometry-less links on fixed joints: merged into their parents.
    for i in 0..n {
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
        for c in children_of_raw(&links, i) {
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
    // 3. Revolute pairs through a geometry-less link: one ball joint.
    for i in 0..n {
        let Some(m) = links[i].as_ref() else { continue };
        if !m.geometry.is_empty() || m.joint.kind != JointType::Revolute {
            continue;
        }
        let kids = children_of_raw(&links, i);
        if kids.len() != 1 {
            continue;
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
            continue;
        }
        let m = links[i].take().unwrap();
        let cl = links[c].as_mut().unwrap();
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
    // 4. Remaining geometry-less links: a tiny cube.
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
    // Compact, re-indexing parents.
    let mut new_index = vec![usize::MAX; n];
    let mut out = Vec::new();
    for (i, l) in links.into_iter().enumerate() {
        if let Some(mut l) = l {
            l.parent = l.parent.map(|p| new_index[p]);
            debug_assert!(l.parent.is_none_or(|p| p != usize::MAX));
            new_index[i] = out.len();
            out.push(l);
        }
    }
    Ok(SourceRobot {
        name: sanitize(&robot.name),
        file: path.to_path_buf(),
        links: out,
        notes,
        initial: Default::default(),
        keep_geometry: false,
    })
}

fn children_of_raw(links: &[Option<SourceLink>], p: usize) -> Vec<usize> {
    (0..links.len())
        .filter(|&c| links[c].as_ref().is_some_and(|l| l.parent == Some(p)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn package_paths_resolve_upward_and_through_ros_package_path() {
        let root = std::env::temp_dir().join(format!("sdrs-pkg-{}", std::process::id()));
        let urdf_dir = root.join("ws/my_robot/urdf");
        std::fs::create_dir_all(&urdf_dir).unwrap();
        std::fs::create_dir_all(root.join("ws/my_robot/meshes")).unwrap();
        std::fs::write(root.join("ws/my_robot/meshes/a.stl"), "x").unwrap();
        std::fs::create_dir_all(root.join("elsewhere/other_pkg/m")).unwrap();
        std::fs::write(root.join("elsewhere/other_pkg/m/b.obj"), "x").unwrap();
        let urdf = urdf_dir.join("r.urdf");
        // Upward: an ancestor named like the package.
        let p = resolve_mesh_path(&urdf, "package://my_robot/meshes/a.stl").unwrap();
        assert!(p.ends_with("my_robot/meshes/a.stl"));
        // Relative to the URDF.
        assert!(resolve_mesh_path(&urdf, "../meshes/a.stl").is_ok());
        // Not found without ROS_PACKAGE_PATH; found with it.
        assert!(resolve_mesh_path(&urdf, "package://other_pkg/m/b.obj").is_err());
        // SAFETY: only this test reads or writes ROS_PACKAGE_PATH.
        unsafe { std::env::set_var("ROS_PACKAGE_PATH", root.join("elsewhere")) };
        let found = resolve_mesh_path(&urdf, "package://other_pkg/m/b.obj");
        unsafe { std::env::remove_var("ROS_PACKAGE_PATH") };
        assert!(found.unwrap().ends_with("other_pkg/m/b.obj"));
        let _ = std::fs::remove_dir_all(&root);
    }

    #[test]
    fn composed_origins_match_matrix_products() {
        let a = Origin {
            xyz: [0.1, -0.2, 0.3],
            rpy: [0.3, -0.4, 1.2],
        };
        let b = Origin {
            xyz: [0.5, 0.0, -0.1],
            rpy: [-0.7, 0.2, 0.4],
        };
        let c = compose_origin(&a, &b);
        let (ra, ta) = rt(&a);
        let (rb, tb) = rt(&b);
        let (rc, tc) = rt(&c);
        assert!((rc - ra * rb).norm() < 1e-12);
        assert!((tc - (ta + ra * tb)).norm() < 1e-12);
    }
}
