//! Run records: trajectory CSV and summary JSON, written atomically (to a
//! temporary file in the same directory, renamed when complete).

use crate::model::Model;
use crate::sim::{StageTime, StepDiagnostics};
use nalgebra::DVector;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A problem writing outputs.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{}: cannot write: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: refusing to overwrite an input file", path.display())]
    WouldOverwriteInput { path: PathBuf },
}

/// Writes `bytes` to `path` atomically.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let io = |source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io)?;
    }
    let file_name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{file_name}.tmp{}", std::process::id()));
    let res = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if res.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    res.map_err(io)
}

/// Trajectory and per-step diagnostics of a run.
#[derive(Clone, Debug, Default)]
pub struct Trajectory {
    pub names: Vec<String>,
    pub times: Vec<f64>,
    /// Reported coordinates per recorded time (charted rotations as absolute
    /// rotation vectors).
    pub states: Vec<DVector<f64>>,
    /// Diagnostics per completed step (one fewer than `states`).
    pub diagnostics: Vec<StepDiagnostics>,
}

impl Trajectory {
    pub fn new(model: &Model) -> Self {
        Trajectory {
            names: model.dofs.iter().map(|d| d.name.clone()).collect(),
            ..Default::default()
        }
    }

    /// CSV text: a `t` column, then one column per coordinate. Numbers use
    /// Rust's shortest round-trip formatting (bit-exact and deterministic).
    pub fn to_csv(&self) -> String {
        let mut s = String::from("t");
        for n in &self.names {
            s.push(',');
            s.push_str(n);
        }
        s.push('\n');
        for (t, q) in self.times.iter().zip(&self.states) {
            s.push_str(&format!("{t}"));
            for v in q.iter() {
                s.push_str(&format!(",{v}"));
            }
            s.push('\n');
        }
        s
    }
}

/// Newton statistics of a run.
#[derive(Clone, Debug, Serialize)]
pub struct NewtonStats {
    pub mean_iterations: f64,
    pub max_iterations: usize,
    pub total_iterations: usize,
    pub max_final_gradient: f64,
}

/// Energy diagnostics (J).
#[derive(Clone, Debug, Serialize)]
pub struct EnergyStats {
    pub kinetic_first: f64,
    pub potential_first: f64,
    pub total_first: f64,
    pub kinetic_final: f64,
    pub potential_final: f64,
    pub total_final: f64,
    /// `max_t |E_t − E_first|`, with `E = kinetic + potential`.
    pub max_abs_drift: f64,
}

/// Linear-momentum diagnostics (kg m/s).
#[derive(Clone, Debug, Serialize)]
pub struct MomentumStats {
    pub first: [f64; 3],
    pub last: [f64; 3],
    /// `max_t ‖p_t − p_first‖`.
    pub max_change: f64,
}

/// The summary JSON of `sdrs simulate`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub scene: String,
    pub steps: usize,
    pub dt: f64,
    pub dof: usize,
    pub wall_seconds: f64,
    pub seconds_per_step: f64,
    pub newton: NewtonStats,
    pub final_state: BTreeMap<String, f64>,
    pub energy: Option<EnergyStats>,
    pub linear_momentum: Option<MomentumStats>,
    pub stages: Vec<StageTime>,
}

impl Summary {
    pub fn new(
        scene: &str,
        dt: f64,
        traj: &Trajectory,
        wall_seconds: f64,
        stages: Vec<StageTime>,
    ) -> Self {
        let d = &traj.diagnostics;
        let steps = d.len();
        let total: usize = d.iter().map(|x| x.newton.iters).sum();
        let newton = NewtonStats {
            mean_iterations: if steps > 0 {
                total as f64 / steps as f64
            } else {
                0.0
            },
            max_iterations: d.iter().map(|x| x.newton.iters).max().unwrap_or(0),
            total_iterations: total,
            max_final_gradient: d.iter().map(|x| x.newton.grad_inf).fold(0.0, f64::max),
        };
        let final_state = traj
            .states
            .last()
            .map(|q| traj.names.iter().cloned().zip(q.iter().copied()).collect())
            .unwrap_or_default();
        let energy = d.first().zip(d.last()).map(|(a, b)| {
            let e0 = a.kinetic + a.potential;
            EnergyStats {
                kinetic_first: a.kinetic,
                potential_first: a.potential,
                total_first: e0,
                kinetic_final: b.kinetic,
                potential_final: b.potential,
                total_final: b.kinetic + b.potential,
                max_abs_drift: d
                    .iter()
                    .map(|x| (x.kinetic + x.potential - e0).abs())
                    .fold(0.0, f64::max),
            }
        });
        let linear_momentum = d.first().zip(d.last()).map(|(a, b)| MomentumStats {
            first: a.momentum,
            last: b.momentum,
            max_change: d
                .iter()
                .map(|x| {
                    (0..3)
                        .map(|k| (x.momentum[k] - a.momentum[k]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(0.0, f64::max),
        });
        Summary {
            scene: scene.to_string(),
            steps,
            dt,
            dof: traj.names.len(),
            wall_seconds,
            seconds_per_step: if steps > 0 {
                wall_seconds / steps as f64
            } else {
                0.0
            },
            newton,
            final_state,
            energy,
            linear_momentum,
            stages,
        }
    }
}
