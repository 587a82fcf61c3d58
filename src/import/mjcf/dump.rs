//! The compiled MJCF model as `tools/helpers/mjcf_dump.py` prints it (MuJoCo's own
//! compiler resolves defaults, frames, `fromto`, inertias from geoms and
//! mesh re-centring; see the script's docstring for every field).

use super::super::error::ImportError;
use super::super::python;
use serde::Deserialize;
use std::path::Path;

/// The helper script.
pub const DUMP_SCRIPT: &str = "mjcf_dump.py";

#[derive(Clone, Debug, Deserialize)]
pub struct Dump {
    pub model: String,
    pub option: DumpOption,
    pub bodies: Vec<DumpBody>,
    pub geoms: Vec<DumpGeom>,
    /// Every actuator (mapped to the controller or listed in the import
    /// notes: `super::actuators`).
    #[serde(default)]
    pub actuators: Vec<DumpActuator>,
    /// `<contact><exclude>` body pairs (indices into `bodies`, −1 the
    /// world), as MuJoCo compiled them.
    #[serde(default)]
    pub exclude: Vec<[i64; 2]>,
    pub unsupported: std::collections::BTreeMap<String, usize>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct DumpOption {
    /// m/s², world frame.
    pub gravity: [f64; 3],
    /// MuJoCo's time step (s), for the notes.
    pub timestep: f64,
}

/// A body; `parent` −1 is the world. Poses are in the parent body's frame,
/// quaternions `[w, x, y, z]`.
#[derive(Clone, Debug, Deserialize)]
pub struct DumpBody {
    pub name: String,
    pub parent: i64,
    pub pos: [f64; 3],
    pub quat: [f64; 4],
    /// kg.
    pub mass: f64,
    /// Centre of mass and principal axes of inertia in the body frame.
    pub ipos: [f64; 3],
    pub iquat: [f64; 4],
    /// Principal moments (kg m²) about `ipos` along `iquat`'s axes.
    pub inertia: [f64; 3],
    pub mocap: bool,
    pub joints: Vec<DumpJoint>,
}

/// A joint; `pos` (anchor) and `axis` in the body frame.
#[derive(Clone, Debug, Deserialize)]
pub struct DumpJoint {
    pub name: String,
    /// `free`, `ball`, `slide` or `hinge`.
    #[serde(rename = "type")]
    pub kind: String,
    pub pos: [f64; 3],
    pub axis: [f64; 3],
    /// `[lower, upper]` (rad or m) when the joint is limited.
    pub range: Option<[f64; 2]>,
    /// N·m·s/rad or N·s/m.
    pub damping: f64,
    /// kg m² or kg.
    pub armature: f64,
    /// N·m or N.
    pub frictionloss: f64,
    /// N·m/rad or N/m.
    pub stiffness: f64,
    /// The spring's rest configuration (`qpos_spring`; hinge/slide: one
    /// value, rad or m, in `qpos` units).
    #[serde(default)]
    pub springref: Vec<f64>,
    /// Reference configuration (`qpos0`): the value at which the body is
    /// in its XML pose (hinge/slide `ref`; free: position + quaternion).
    pub qpos0: Vec<f64>,
}

/// A geom; `body` −1 is the world. `size` as MuJoCo stores it
/// (half-extents, radius + half-length, …).
#[derive(Clone, Debug, Deserialize)]
pub struct DumpGeom {
    pub name: String,
    pub body: i64,
    #[serde(rename = "type")]
    pub kind: String,
    pub size: [f64; 3],
    pub pos: [f64; 3],
    pub quat: [f64; 4],
    pub contype: u32,
    pub conaffinity: u32,
    pub friction: f64,
    pub mesh: Option<DumpMesh>,
}

impl DumpGeom {
    /// Whether MuJoCo can ever collide this geom (`contype` or
    /// `conaffinity` non-zero); the others are visual.
    pub fn collides(&self) -> bool {
        self.contype != 0 || self.conaffinity != 0
    }

    /// MuJoCo's filter: two geoms may collide when
    /// `(contype₁ & conaffinity₂) | (contype₂ & conaffinity₁) ≠ 0`.
    pub fn may_collide_with(&self, other: &DumpGeom) -> bool {
        (self.contype & other.conaffinity) | (other.contype & self.conaffinity) != 0
    }
}

/// An actuator as MuJoCo compiled it.
#[derive(Clone, Debug, Deserialize)]
pub struct DumpActuator {
    pub name: String,
    /// `motor`, `position`, `velocity` or `general`.
    pub kind: String,
    /// The driven joint (joint transmissions only).
    pub joint: Option<String>,
    /// First gear component (length = gear · q).
    pub gear: f64,
    /// Position gain (N·m per unit control), position actuators.
    pub kp: Option<f64>,
    /// Velocity gain, position (with `kv`) and velocity actuators.
    pub kv: Option<f64>,
    /// `[lower, upper]` when the control is limited.
    pub ctrlrange: Option<[f64; 2]>,
    /// `[lower, upper]` (N·m or N, actuator space) when the force is limited.
    #[serde(default)]
    pub forcerange: Option<[f64; 2]>,
    /// `joint`, `jointinparent`, `slidercrank`, `tendon`, `site` or `body`.
    #[serde(default)]
    pub transmission: String,
    /// Name of the transmission's joint, tendon, site or body.
    #[serde(default)]
    pub target: Option<String>,
    /// Activation dynamics: `none`, `integrator`, `filter`, `filterexact`, …
    #[serde(default)]
    pub dyntype: String,
    /// `fixed`, `affine`, `muscle` or `user`.
    #[serde(default)]
    pub gaintype: String,
    /// `none`, `affine`, `muscle` or `user`.
    #[serde(default)]
    pub biastype: String,
    /// First three gain parameters (`fixed`: force = `gainprm[0]` · ctrl).
    #[serde(default)]
    pub gainprm: Vec<f64>,
    /// First three bias parameters (`affine`: `b₀ + b₁ L + b₂ L̇`, `L` the
    /// actuator length `gear · q`).
    #[serde(default)]
    pub biasprm: Vec<f64>,
}

/// A compiled mesh in its geom's frame.
#[derive(Clone, Debug, Deserialize)]
pub struct DumpMesh {
    pub name: String,
    pub vertices: Vec<[f64; 3]>,
    pub faces: Vec<[usize; 3]>,
}

/// Compiles `path` with MuJoCo (through the project's Python) and reads
/// the result.
pub fn dump(path: &Path) -> Result<Dump, ImportError> {
    let out = python::run_tool(DUMP_SCRIPT, &[path.as_os_str().to_owned()])?;
    match out.code {
        Some(0) => {}
        Some(2) => {
            return Err(ImportError::InvalidMjcf {
                path: path.to_path_buf(),
                element: "model".into(),
                msg: out
                    .stderr
                    .trim()
                    .trim_start_matches(&format!("{}: ", path.display()))
                    .to_string(),
            });
        }
        _ => {
            return Err(ImportError::Python {
                msg: format!(
                    "{}: {DUMP_SCRIPT} failed ({:?}): {}",
                    path.display(),
                    out.code,
                    out.stderr.trim()
                ),
            });
        }
    }
    serde_json::from_str(&out.stdout).map_err(|e| ImportError::Python {
        msg: format!(
            "{}: {DUMP_SCRIPT} printed unreadable output: {e}",
            path.display()
        ),
    })
}
