//! Resolving `robot/link` and `robot/joint` names against a model.

use crate::model::Model;

/// A name that does not resolve.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{what} \"{name}\": {msg}")]
pub struct NameError {
    pub what: &'static str,
    pub name: String,
    pub msg: String,
}

fn split<'a>(what: &'static str, name: &'a str) -> Result<(&'a str, &'a str), NameError> {
    name.split_once('/').ok_or_else(|| NameError {
        what,
        name: name.into(),
        msg: "expected robot/name".into(),
    })
}

/// Index of the link `robot/link`.
pub fn link(model: &Model, name: &str) -> Result<usize, NameError> {
    let (r, l) = split("link", name)?;
    model
        .links
        .iter()
        .position(|x| x.name == l && model.robots[x.robot].name == r)
        .ok_or_else(|| {
            let known: Vec<String> = model
                .links
                .iter()
                .map(|x| format!("{}/{}", model.robots[x.robot].name, x.name))
                .collect();
            NameError {
                what: "link",
                name: name.into(),
                msg: format!("not found (links: {})", known.join(", ")),
            }
        })
}

/// Index of the link whose joint is `robot/joint`.
pub fn joint(model: &Model, name: &str) -> Result<usize, NameError> {
    let (r, j) = split("joint", name)?;
    model
        .links
        .iter()
        .position(|x| x.joint_name == j && model.robots[x.robot].name == r)
        .ok_or_else(|| {
            let known: Vec<String> = model
                .links
                .iter()
                .map(|x| format!("{}/{}", model.robots[x.robot].name, x.joint_name))
                .collect();
            NameError {
                what: "joint",
                name: name.into(),
                msg: format!("not found (joints: {})", known.join(", ")),
            }
        })
}

/// Index of robot `name`.
pub fn robot(model: &Model, name: &str) -> Result<usize, NameError> {
    model
        .robots
        .iter()
        .position(|r| r.name == name)
        .ok_or_else(|| NameError {
            what: "robot",
            name: name.into(),
            msg: "not found".into(),
        })
}
