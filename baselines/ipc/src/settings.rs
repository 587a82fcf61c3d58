//! The IPC baseline's own scene settings: the `ipc` section of a scene's
//! `contact:` (the core keeps it as written and never reads it).
//!
//! ```yaml
//! contact:
//!   model: ipc
//!   mu: 0.4
//!   ipc: {surface: source, dhat: 3.0e-3, eps_v: 1.0e-2}
//! ```
//!
//! - `surface`: each link's contact surface: `hulls` (default: the
//!   triangulated boundaries of its convex hulls, the shapes SDRS uses) or
//!   `source` (the link's `surface_mesh`, the mesh its hulls were made
//!   from; links without one keep their hulls);
//! - `dhat`: barrier activation distance `d̂` (m, unsquared; the barrier
//!   acts on squared distances below `d̂²`). Default 1e-3;
//! - `eps_v`: friction smoothing speed `ε_v` (m/s): below relative
//!   tangential speeds of `ε_v` friction is smoothed (IPC's `f₁`).
//!   Default 1e-3;
//! - `hessian`: the per-primitive barrier Hessians Newton's steps use:
//!   `exact` (default) or `projected` (each primitive's 12×12 Hessian
//!   projected to the nearest PSD matrix, as IPC's published Newton does).
//!   Both minimize the same objective (the same stationary points, the
//!   same stopping test); only the path of Newton differs. In joint
//!   coordinates the projection discards curvature the rigid maps combine:
//!   on the hand's mesh-baseline trial a step took 102 iterations with it
//!   and 9 without, and no scene of the benchmarks took more iterations
//!   exact (`notes/ipc-baseline-newton-hessian.md`). With `exact`,
//!   indefiniteness is handled by Newton's global `max(|λ|, clamp)`.

use sdrs::contact::ContactSettings;
use sdrs::scene::Invalid;
use serde::{Deserialize, Serialize};

/// Default activation distance `d̂` (m).
pub const DEFAULT_DHAT: f64 = 1e-3;
/// Default friction smoothing speed `ε_v` (m/s).
pub const DEFAULT_EPS_V: f64 = 1e-3;

/// Which triangle mesh is each link's contact surface (`contact.ipc.surface`).
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum SurfaceKind {
    /// The triangulated boundaries of the link's convex hulls.
    #[default]
    Hulls,
    /// The link's `surface_mesh` (its hulls where it has none).
    Source,
}

impl SurfaceKind {
    pub fn is_hulls(&self) -> bool {
        *self == SurfaceKind::Hulls
    }
    /// Name as written in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            SurfaceKind::Hulls => "hulls",
            SurfaceKind::Source => "source",
        }
    }
}

/// Which per-primitive barrier Hessians Newton uses (`contact.ipc.hessian`).
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum HessianKind {
    /// The exact Hessians (the backward pass always uses these).
    #[default]
    Exact,
    /// Each primitive's Hessian projected to PSD (IPC's published Newton).
    Projected,
}

impl HessianKind {
    pub fn is_exact(&self) -> bool {
        *self == HessianKind::Exact
    }
    /// Name as written in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            HessianKind::Exact => "exact",
            HessianKind::Projected => "projected",
        }
    }
}

/// The `contact.ipc` section as written.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct IpcSpec {
    #[serde(default, skip_serializing_if = "SurfaceKind::is_hulls")]
    pub surface: SurfaceKind,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dhat: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eps_v: Option<f64>,
    #[serde(default, skip_serializing_if = "HessianKind::is_exact")]
    pub hessian: HessianKind,
}

/// The checked IPC settings of a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IpcSettings {
    pub surface: SurfaceKind,
    /// `d̂` (m), positive and finite.
    pub dhat: f64,
    /// `ε_v` (m/s), positive and finite.
    pub eps_v: f64,
    /// Newton's per-primitive Hessians.
    pub hessian: HessianKind,
}

impl Default for IpcSettings {
    fn default() -> Self {
        IpcSettings {
            surface: SurfaceKind::Hulls,
            dhat: DEFAULT_DHAT,
            eps_v: DEFAULT_EPS_V,
            hessian: HessianKind::Exact,
        }
    }
}

impl IpcSettings {
    /// The settings of `c.ipc` (defaults for an absent section); an error
    /// names the element (`contact.ipc.dhat`, …).
    pub fn of(c: &ContactSettings) -> Result<IpcSettings, Invalid> {
        let spec: IpcSpec = match &c.ipc {
            None => IpcSpec::default(),
            Some(v) => serde_yaml::from_value(v.clone())
                .map_err(|e| Invalid::new("contact.ipc", e.to_string()))?,
        };
        let dhat = spec.dhat.unwrap_or(DEFAULT_DHAT);
        if !(dhat > 0.0 && dhat.is_finite()) {
            return Err(Invalid::new(
                "contact.ipc.dhat",
                format!("the IPC activation distance must be positive and finite (m), got {dhat}"),
            ));
        }
        let eps_v = spec.eps_v.unwrap_or(DEFAULT_EPS_V);
        if !(eps_v > 0.0 && eps_v.is_finite()) {
            return Err(Invalid::new(
                "contact.ipc.eps_v",
                format!(
                    "the IPC friction smoothing speed must be positive and finite (m/s), got {eps_v}"
                ),
            ));
        }
        Ok(IpcSettings {
            surface: spec.surface,
            dhat,
            eps_v,
            hessian: spec.hessian,
        })
    }

    /// Writes `self` into `c.ipc` (what [`IpcSettings::of`] reads back),
    /// keeping defaults implicit: for command-line overrides (`--dhat`).
    pub fn store(&self, c: &mut ContactSettings) -> Result<(), Invalid> {
        let spec = IpcSpec {
            surface: self.surface,
            dhat: (self.dhat != DEFAULT_DHAT).then_some(self.dhat),
            eps_v: (self.eps_v != DEFAULT_EPS_V).then_some(self.eps_v),
            hessian: self.hessian,
        };
        c.ipc = Some(
            serde_yaml::to_value(spec).map_err(|e| Invalid::new("contact.ipc", e.to_string()))?,
        );
        Ok(())
    }
}
