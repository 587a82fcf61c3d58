//! Validated contact parameters of a scene: the model (SDRS or the IPC
//! baseline), the barrier's support `s` and stiffness `κ`, friction, the
//! excluded link pairs and the CCD options; the IPC baseline's own section
//! (`contact.ipc`) is kept as written for the baseline to read. The scene loader
//! (`crate::scene`) fills them from a file's `contact:` section.

use serde::{Deserialize, Serialize};

/// The contact model of a scene (`contact.model`).
#[derive(
    Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum ContactModelKind {
    /// The core's separating-plane potential (paper, `contact.tex`).
    #[default]
    Sdrs,
    /// Mesh-based Incremental Potential Contact (Li et al. 2020), the
    /// baseline in `baselines/ipc`.
    Ipc,
}

impl ContactModelKind {
    pub fn is_sdrs(&self) -> bool {
        *self == ContactModelKind::Sdrs
    }
    /// Name as written in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            ContactModelKind::Sdrs => "sdrs",
            ContactModelKind::Ipc => "ipc",
        }
    }
}

/// Validated contact parameters (the scene file's `contact:` section, `crate::scene::schema::ContactSpec`).
#[derive(Clone, Debug, PartialEq)]
pub struct ContactSettings {
    /// The contact model (`contact.model`; default SDRS).
    pub model: ContactModelKind,
    /// The IPC baseline's own settings (`contact.ipc`), as written: the
    /// core passes them through uninterpreted; the baseline parses and
    /// checks them (`sdrs_ipc::settings`).
    pub ipc: Option<serde_yaml::Value>,
    /// Barrier support `s`.
    pub s: f64,
    /// Barrier stiffness `κ`.
    pub kappa: f64,
    /// Whether the scene gave `κ` (otherwise the default; the IPC baseline
    /// then chooses it adaptively).
    pub kappa_given: bool,
    /// Friction coefficient `μ`.
    pub mu: f64,
    /// Friction velocity smoothing `ε` ((m/s)²).
    pub eps: f64,
    /// Normal-force smoothing `ε_f` (N²).
    pub eps_force: f64,
    /// Link pairs `(i, j)`, `i < j`, that never interact.
    pub excluded: std::collections::BTreeSet<(usize, usize)>,
    /// Continuous collision detection in the line search (SDRS model).
    pub ccd: super::ccd::CcdOptions,
}
