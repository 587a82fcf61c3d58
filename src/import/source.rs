//! The robot as read from the input, before decomposition: links in
//! topological order, their joints (already mapped to scene joint types) and
//! their geometry in the link frame.

use crate::scene::schema::{JointType, Origin};
use nalgebra::{Matrix3, Vector3};
use serde::Serialize;
use std::path::PathBuf;

/// A shape attached to a link.
#[derive(Clone, Debug)]
pub enum SourceShape {
    /// A mesh file with per-axis scale.
    Mesh {
        path: PathBuf,
        scale: [f64; 3],
    },
    Box {
        size: [f64; 3],
    },
    Cylinder {
        radius: f64,
        length: f64,
    },
    Sphere {
        radius: f64,
    },
    Capsule {
        radius: f64,
        length: f64,
    },
    /// Ellipsoid of semi-axes (x, y, z) (MJCF `ellipsoid`).
    Ellipsoid {
        radii: [f64; 3],
    },
    /// A mesh given inline (MJCF mesh geoms, compiled by MuJoCo), used as
    /// its convex hull — the shape MuJoCo collides.
    ConvexMesh {
        mesh: super::mesh::TriMesh,
    },
    /// No geometry in the input: a small cube of the given edge at the link
    /// origin keeps the link valid (see [`super::ImportOptions::tiny_hull_size`]).
    Tiny {
        edge: f64,
    },
}

/// One geometry of a link, placed in the link frame.
#[derive(Clone, Debug)]
pub struct SourceGeometry {
    /// For messages: e.g. `link "arm" collision[0]`.
    pub element: String,
    pub rotation: Matrix3<f64>,
    pub translation: Vector3<f64>,
    pub shape: SourceShape,
}

/// A joint, mapped to scene joint types.
#[derive(Clone, Debug)]
pub struct SourceJoint {
    pub name: String,
    pub kind: JointType,
    pub axis: Option<[f64; 3]>,
    pub axes: Option<[[f64; 3]; 2]>,
    /// Attachment in the parent frame (for a root: in the world frame).
    pub origin: Origin,
    /// The input joints behind each coordinate (URDF names; a ball joint
    /// merged from two revolute joints lists both).
    pub input_joints: Vec<InputJoint>,
    /// URDF `<mimic>`: the followed input joint, multiplier, offset.
    pub mimic: Option<crate::scene::schema::MimicSpec>,
}

/// An input (URDF) joint that became coordinates of a scene joint.
#[derive(Clone, Debug, Serialize)]
pub struct InputJoint {
    pub name: String,
    /// URDF type (`revolute`, `continuous`, …).
    #[serde(rename = "type")]
    pub kind: String,
    pub lower: f64,
    pub upper: f64,
    /// Whether the input limits position (URDF `revolute`/`prismatic` with
    /// finite `lower < upper`); `lower`/`upper` are sampling ranges otherwise.
    pub limited: bool,
    /// URDF `<limit velocity>` (rad/s or m/s) when positive; reported only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub velocity: Option<f64>,
    /// URDF `<limit effort>` (N·m or N) when positive; reported only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub effort: Option<f64>,
    /// URDF `<dynamics damping>` (N·m·s/rad or N·s/m) when positive: a
    /// `joint_damping` effect (see `assemble::dynamics_effects`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// URDF `<dynamics friction>` (N·m or N) when positive: a
    /// `joint_friction` effect.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
}

/// One link.
#[derive(Clone, Debug)]
pub struct SourceLink {
    pub name: String,
    /// Index of the parent in [`SourceRobot::links`] (parents come first).
    pub parent: Option<usize>,
    pub joint: SourceJoint,
    pub geometry: Vec<SourceGeometry>,
    /// Mass from the input (URDF `<inertial><mass>`), if positive.
    pub mass: Option<f64>,
    /// The input's inertial (URDF `<inertial>`: origin, mass, inertia) as
    /// the 4×4 second moment `∫ρ x̃ x̃ᵀ` in the link frame (see
    /// [`crate::model::Inertial::second_moment`]), if the mass is positive;
    /// merged links add theirs, moved into this frame (`T M Tᵀ`).
    pub moment: Option<nalgebra::Matrix4<f64>>,
    /// A massless frame between joints of one input body (MJCF bodies with
    /// several joints, massless bodies): mass zero.
    pub frame_only: bool,
    /// Whether the link takes part in contact (MJCF bodies with visual
    /// geoms only do not).
    pub collides: bool,
}

/// A robot read from the input.
#[derive(Clone, Debug)]
pub struct SourceRobot {
    pub name: String,
    /// The input file (for messages).
    pub file: PathBuf,
    pub links: Vec<SourceLink>,
    /// What the reader simplified (merged or dropped links), for the report.
    pub notes: Vec<String>,
    /// Initial coordinates by joint name (default zeros).
    pub initial: std::collections::BTreeMap<String, Vec<f64>>,
    /// Keep the collision geometry as given: a joint whose attachment point
    /// lies outside a link's hulls is left untied in the design instead of
    /// growing the hull to it (MJCF: the shapes are what MuJoCo collides).
    pub keep_geometry: bool,
}

impl SourceRobot {
    /// A single free body made of one mesh file (bare `.obj`/`.stl`/`.dae` input).
    pub fn from_mesh(path: &std::path::Path) -> SourceRobot {
        let name = path
            .file_stem()
            .map(|s| sanitize(&s.to_string_lossy()))
            .unwrap_or_else(|| "body".into());
        SourceRobot {
            name: name.clone(),
            file: path.to_path_buf(),
            links: vec![SourceLink {
                name: name.clone(),
                parent: None,
                joint: SourceJoint {
                    name: name.clone(),
                    kind: JointType::Free,
                    axis: None,
                    axes: None,
                    origin: Origin::default(),
                    input_joints: Vec::new(),
                    mimic: None,
                },
                geometry: vec![SourceGeometry {
                    element: format!("mesh \"{}\"", path.display()),
                    rotation: Matrix3::identity(),
                    translation: Vector3::zeros(),
                    shape: SourceShape::Mesh {
                        path: path.to_path_buf(),
                        scale: [1.0; 3],
                    },
                }],
                mass: None,
                moment: None,
                frame_only: false,
                collides: true,
            }],
            notes: vec!["bare mesh: one free body".into()],
            initial: Default::default(),
            keep_geometry: false,
        }
    }
}

/// A name usable as a file name and a YAML key.
pub fn sanitize(s: &str) -> String {
    let t: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if t.is_empty() { "body".into() } else { t }
}
