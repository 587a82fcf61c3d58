//! The URDF's tree: names unique, every joint's links present, one parent
//! joint per link, no cycle, one root; links in parents-first order.

use super::super::error::ImportError;
use super::type_name;
use std::collections::HashMap;
use std::path::Path;

/// The checked tree of a URDF.
pub(super) struct Tree<'a> {
    /// Link index by name.
    pub index: HashMap<&'a str, usize>,
    /// The joint whose child each link is (`None`: the root).
    pub parent_joint: Vec<Option<usize>>,
    /// Link indices, root first, parents before children (breadth first).
    pub order: Vec<usize>,
}

fn invalid(path: &Path, element: String, msg: String) -> ImportError {
    ImportError::InvalidUrdf {
        path: path.to_path_buf(),
        element,
        msg,
    }
}

/// Checks the tree of `robot` (which has at least one link).
pub(super) fn tree<'a>(path: &Path, robot: &'a urdf_rs::Robot) -> Result<Tree<'a>, ImportError> {
    let mut index = HashMap::new();
    for (i, l) in robot.links.iter().enumerate() {
        if index.insert(l.name.as_str(), i).is_some() {
            return Err(invalid(
                path,
                format!("link \"{}\"", l.name),
                "duplicate link name".into(),
            ));
        }
    }
    let parent_joint = parent_joints(path, robot, &index)?;
    check_cycles(path, robot, &index, &parent_joint)?;
    let root = single_root(path, robot, &parent_joint)?;
    let order = parents_first(robot, &index, root);
    Ok(Tree {
        index,
        parent_joint,
        order,
    })
}

/// The parent joint of each link; duplicate joint names, missing links,
/// `planar` joints and links with two parent joints are errors.
fn parent_joints(
    path: &Path,
    robot: &urdf_rs::Robot,
    index: &HashMap<&str, usize>,
) -> Result<Vec<Option<usize>>, ImportError> {
    let mut parent_joint: Vec<Option<usize>> = vec![None; robot.links.len()];
    let mut joint_names = HashMap::new();
    for (ji, j) in robot.joints.iter().enumerate() {
        if joint_names.insert(j.name.as_str(), ji).is_some() {
            return Err(invalid(
                path,
                format!("joint \"{}\"", j.name),
                "duplicate joint name".into(),
            ));
        }
        for (role, l) in [("parent", &j.parent.link), ("child", &j.child.link)] {
            if !index.contains_key(l.as_str()) {
                return Err(invalid(
                    path,
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
    Ok(parent_joint)
}

/// A cycle found by following parents from every link is an error naming
/// its links and the closing joint.
fn check_cycles(
    path: &Path,
    robot: &urdf_rs::Robot,
    index: &HashMap<&str, usize>,
    parent_joint: &[Option<usize>],
) -> Result<(), ImportError> {
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
    Ok(())
}

/// The one link without a parent joint.
fn single_root(
    path: &Path,
    robot: &urdf_rs::Robot,
    parent_joint: &[Option<usize>],
) -> Result<usize, ImportError> {
    let roots: Vec<usize> = (0..robot.links.len())
        .filter(|&i| parent_joint[i].is_none())
        .collect();
    if roots.len() != 1 {
        let names: Vec<&str> = roots
            .iter()
            .map(|&i| robot.links[i].name.as_str())
            .collect();
        return Err(invalid(
            path,
            "robot".into(),
            format!(
                "a URDF needs exactly one root link, found {}: {}",
                roots.len(),
                names.join(", ")
            ),
        ));
    }
    Ok(roots[0])
}

/// Links in breadth-first order of the joint list from `root` (parents
/// first).
fn parents_first(robot: &urdf_rs::Robot, index: &HashMap<&str, usize>, root: usize) -> Vec<usize> {
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
    for (ji, j) in robot.joints.iter().enumerate() {
        children[index[j.parent.link.as_str()]].push(ji);
    }
    let mut order = vec![root];
    let mut k = 0;
    while k < order.len() {
        for &ji in &children[order[k]] {
            order.push(index[robot.joints[ji].child.link.as_str()]);
        }
        k += 1;
    }
    order
}
