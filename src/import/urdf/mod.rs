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
mod simplify;
mod tree;

pub use geometry::resolve_mesh_path;

use super::ImportOptions;
use super::error::ImportError;
use super::limits;
use super::pybullet_shapes::SpecialShapes;
use super::source::*;
use crate::scene::schema::{JointType, Origin};
use frames::*;
use geometry::*;
use nalgebra::Vector3;
use prescan::*;
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
    if robot.links.is_empty() {
        return Err(invalid(
            path,
            "robot".into(),
            "the URDF has no <link>".into(),
        ));
    }
    let tree = tree::tree(path, robot)?;
    let (tmp, massless) = initial_links(path, robot, &tree, special, special_notes)?;
    let mut links: simplify::Slots = tmp.into_iter().map(Some).collect();
    let mut notes = Vec::new();
    if !massless.is_empty() {
        notes.push(format!(
            "links with <mass value=\"0\"> get the mass of their hulls at the default density: {}",
            massless.join(", ")
        ));
    }
    simplify::drop_bare_root(&mut links, &mut notes);
    simplify::merge_fixed_bare_links(&mut links, &mut notes);
    simplify::merge_hinge_pairs(&mut links, &mut notes);
    simplify::fill_bare_links(&mut links, opts, &mut notes);
    Ok(SourceRobot {
        name: sanitize(&robot.name),
        file: path.to_path_buf(),
        links: simplify::compact(links),
        notes,
        initial: Default::default(),
        keep_geometry: false,
    })
}

fn invalid(path: &Path, element: String, msg: String) -> ImportError {
    ImportError::InvalidUrdf {
        path: path.to_path_buf(),
        element,
        msg,
    }
}

/// One link per URDF link in the tree's order, with its geometry, joint
/// and inertial as given; also the names of links with geometry and a
/// zero `<mass>`.
fn initial_links(
    path: &Path,
    robot: &urdf_rs::Robot,
    tree: &tree::Tree,
    special: &SpecialShapes,
    special_notes: &mut Vec<String>,
) -> Result<(Vec<SourceLink>, Vec<String>), ImportError> {
    let mut tmp: Vec<SourceLink> = Vec::new();
    let mut massless = Vec::new();
    let mut pos = vec![usize::MAX; robot.links.len()];
    for &li in &tree.order {
        let l = &robot.links[li];
        let geometry = link_geometry(path, l, special, special_notes)?;
        let (parent, joint) = match tree.parent_joint[li] {
            None => (None, root_joint(&l.name)),
            Some(ji) => {
                let j = &robot.joints[ji];
                let pi = pos[tree.index[j.parent.link.as_str()]];
                (Some(pi), source_joint(path, j)?)
            }
        };
        limits::check_mass(l.inertial.mass.value)
            .map_err(|m| invalid(path, format!("link \"{}\" <inertial>", l.name), m))?;
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
    Ok((tmp, massless))
}

/// The root's joint: fixed at the world origin, named after the link.
fn root_joint(name: &str) -> SourceJoint {
    SourceJoint {
        name: name.to_string(),
        kind: JointType::Fixed,
        axis: None,
        axes: None,
        origin: Origin::default(),
        input_joints: Vec::new(),
        mimic: None,
    }
}

/// The unit axis of a joint that moves along or about it (`z` for fixed
/// and floating joints, which ignore it: URDFs often give them a zero axis).
fn joint_axis(path: &Path, j: &urdf_rs::Joint) -> Result<[f64; 3], ImportError> {
    let moves_on_axis = matches!(
        j.joint_type,
        urdf_rs::JointType::Revolute
            | urdf_rs::JointType::Continuous
            | urdf_rs::JointType::Prismatic
    );
    let a = Vector3::from(j.axis.xyz.0);
    if moves_on_axis && !(a.norm() > 1e-12 && a.iter().all(|c| c.is_finite())) {
        return Err(invalid(
            path,
            format!("joint \"{}\"", j.name),
            format!("axis {:?} must be finite and non-zero", j.axis.xyz.0),
        ));
    }
    let a = if moves_on_axis {
        a.normalize()
    } else {
        Vector3::z()
    };
    Ok([a.x, a.y, a.z])
}

/// A URDF joint as a source joint (origin checked, axis normalised, type
/// mapped, limits and mimic kept).
fn source_joint(path: &Path, j: &urdf_rs::Joint) -> Result<SourceJoint, ImportError> {
    let origin = origin_of(&j.origin);
    limits::check_coordinates(
        "origin",
        &[origin.xyz.as_slice(), origin.rpy.as_slice()].concat(),
    )
    .map_err(|m| invalid(path, format!("joint \"{}\"", j.name), m))?;
    let axis = joint_axis(path, j)?;
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
        urdf_rs::JointType::Planar => unreachable!("rejected by the tree check"),
    };
    let input_joints = if kind == JointType::Fixed {
        Vec::new()
    } else {
        vec![input_joint(j)]
    };
    Ok(SourceJoint {
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
    })
}

/// The input joint behind a moving URDF joint: its sampling range, whether
/// it limits position, `<limit velocity effort>` and `<dynamics damping
/// friction>` when positive.
fn input_joint(j: &urdf_rs::Joint) -> InputJoint {
    let (lower, upper) = limits(j);
    let (lo, hi) = (j.limit.lower, j.limit.upper);
    let positive = |v: f64| Some(v).filter(|v| *v > 0.0 && v.is_finite());
    InputJoint {
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
        damping: j.dynamics.as_ref().and_then(|d| positive(d.damping)),
        friction: j.dynamics.as_ref().and_then(|d| positive(d.friction)),
    }
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
