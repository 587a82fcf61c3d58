//! Run records: trajectory CSV and summary JSON, written atomically (to a
//! temporary file in the same directory, renamed when complete).

pub mod contacts;
pub mod gltf;
pub mod mjcf;
pub mod picture;
pub mod playback;
pub mod plot;

use crate::model::Model;
use crate::sim::{StageTime, StepDiagnostics};
use nalgebra::DVector;
use serde::{Deserialize, Serialize};
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
    /// Link poses per recorded time, when recording was asked for.
    pub poses: Vec<Vec<crate::math::Pose>>,
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
        self.csv(None)
    }

    /// [`Trajectory::to_csv`] plus one velocity column `<name>:v` per
    /// coordinate: `(q_k − q_{k−1})/Δt`, the velocity the position-level
    /// integrator carries (rad/s or m/s; for rotation vectors, the rate of
    /// the reported vector); the first row holds the initial velocity `qdot0`.
    pub fn to_csv_with_velocities(&self, dt: f64, qdot0: &DVector<f64>) -> String {
        self.csv(Some((dt, qdot0)))
    }

    fn csv(&self, velocities: Option<(f64, &DVector<f64>)>) -> String {
        let mut s = String::from("t");
        for n in &self.names {
            s.push(',');
            s.push_str(n);
        }
        if velocities.is_some() {
            for n in &self.names {
                s.push_str(&format!(",{n}:v"));
            }
        }
        s.push('\n');
        for (k, (t, q)) in self.times.iter().zip(&self.states).enumerate() {
            s.push_str(&format!("{t}"));
            for v in q.iter() {
                s.push_str(&format!(",{v}"));
            }
            if let Some((dt, qdot0)) = velocities {
                for i in 0..q.len() {
                    let v = if k == 0 {
                        qdot0[i]
                    } else {
                        (q[i] - self.states[k - 1][i]) / dt
                    };
                    s.push_str(&format!(",{v}"));
                }
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
    /// Steps whose tolerance lay below the gradient's round-off floor and
    /// that were accepted at that floor (see `sim::newton`), including
    /// `steps_at_step_floor`.
    pub steps_at_roundoff_floor: usize,
    /// Of those, steps whose gradient was noise and whose Newton step was
    /// below `solver.step_floor` (see `sim::newton`).
    pub steps_at_step_floor: usize,
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
    /// Where the energy went (each term's work; absent only when the
    /// simulator's `energy_balance` was switched off).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub balance: Option<EnergyBalance>,
}

/// The energy balance from the first reported step to the last (J):
/// `change = controller + friction + contact + other − numerical_dissipation`
/// (see [`crate::sim::StepWork`]). `numerical_dissipation` is the residual:
/// the implicit scheme's own damping, ≥ 0 and first order in Δt.
#[derive(Clone, Debug, Serialize)]
pub struct EnergyBalance {
    /// `E_final − E_first`, `E` = kinetic + gravity potential.
    pub change: f64,
    pub controller_work: f64,
    pub friction_work: f64,
    pub contact_work: f64,
    pub other_work: f64,
    pub numerical_dissipation: f64,
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
    /// Units of every numeric field (SI; see [`Summary::units`]).
    pub units: BTreeMap<&'static str, &'static str>,
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
    pub contact: ContactStats,
    pub stages: Vec<StageTime>,
}

/// Contact diagnostics over the run.
#[derive(Clone, Debug, Serialize)]
pub struct ContactStats {
    /// Steps with at least one hull pair inside the barrier's range.
    pub steps_in_contact: usize,
    /// Largest number of active hull pairs in one step.
    pub max_active_pairs: usize,
    /// Smallest GJK distance between candidate hull pairs over all accepted
    /// states (m); `null` when no pair was ever a candidate.
    pub min_distance: Option<f64>,
    /// Continuous collision detection over the run (zeros when off): paths
    /// checked (`segments`: each step's straight path, plus the line-search
    /// segments of steps solved again), hull pairs tested and advanced,
    /// advancement rounds, paths capped (`alpha_caps`) and the smallest cap
    /// (`min_alpha`), pairs left to the barrier (`uncertified`), steps
    /// solved again with certified segments (`fallbacks`). See
    /// `sdrs::contact::ccd` and `sdrs::sim::Simulator::step`.
    pub ccd: crate::contact::ccd::CcdStats,
}

impl Summary {
    /// The unit of each field, by its JSON path (`*` for every key).
    pub fn units() -> BTreeMap<&'static str, &'static str> {
        BTreeMap::from([
            ("dt", "s"),
            ("wall_seconds", "s"),
            ("seconds_per_step", "s"),
            (
                "newton.max_final_gradient",
                "J per unit coordinate (J/rad or J/m)",
            ),
            (
                "final_state.*",
                "rad for revolute and rotation coordinates, m for prismatic and translation ones",
            ),
            (
                "energy.*",
                "J (kinetic + gravity potential of the lumped vertex masses; driven, frictional or contact scenes exchange energy with the controller, friction and barrier, so a change is not an error: `energy.balance` says where it went)",
            ),
            ("linear_momentum.*", "kg m/s"),
            ("contact.min_distance", "m"),
            ("stages.*.seconds", "s (whole run)"),
        ])
    }

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
            steps_at_roundoff_floor: d.iter().filter(|x| x.newton.at_floor).count(),
            steps_at_step_floor: d.iter().filter(|x| x.newton.at_step_floor).count(),
        };
        let final_state = traj
            .states
            .last()
            .map(|q| traj.names.iter().cloned().zip(q.iter().copied()).collect())
            .unwrap_or_default();
        let energy = d.first().zip(d.last()).map(|(a, b)| {
            let e0 = a.kinetic + a.potential;
            // Work of steps 2…H: the energy of step 1 is the first reported.
            let works: Option<Vec<crate::sim::StepWork>> = d[1..].iter().map(|x| x.work).collect();
            let balance = works.filter(|_| d.len() > 1).map(|w| {
                let sum = |f: fn(&crate::sim::StepWork) -> f64| w.iter().map(f).sum::<f64>();
                let (c, f, k, o) = (
                    sum(|x| x.controller),
                    sum(|x| x.friction),
                    sum(|x| x.contact),
                    sum(|x| x.other),
                );
                let change = b.kinetic + b.potential - e0;
                EnergyBalance {
                    change,
                    controller_work: c,
                    friction_work: f,
                    contact_work: k,
                    other_work: o,
                    numerical_dissipation: c + f + k + o - change,
                }
            });
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
                balance,
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
        let min_d = d
            .iter()
            .map(|x| x.min_distance)
            .fold(f64::INFINITY, f64::min);
        let contact = ContactStats {
            steps_in_contact: d.iter().filter(|x| x.contact_pairs > 0).count(),
            max_active_pairs: d.iter().map(|x| x.contact_pairs).max().unwrap_or(0),
            min_distance: min_d.is_finite().then_some(min_d),
            ccd: d.iter().fold(
                Default::default(),
                |mut s: crate::contact::ccd::CcdStats, x| {
                    s.merge(&x.ccd);
                    s
                },
            ),
        };
        Summary {
            units: Self::units(),
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
            contact,
            stages,
        }
    }
}

/// Writes `dir/hulls.json` ([`HullExport`]) and `dir/poses.csv`
/// ([`poses_csv`]) of a run recorded with link poses: what viewers and the
/// independent check `tools/check_separation.py` read.
pub fn export_run(
    dir: &Path,
    model: &Model,
    excluded: impl IntoIterator<Item = (usize, usize)>,
    traj: &Trajectory,
) -> Result<(), OutputError> {
    let hulls = HullExport::new(model, excluded);
    let json = serde_json::to_string(&hulls).expect("plain data serializes");
    write_atomic(&dir.join("hulls.json"), json.as_bytes())?;
    write_atomic(&dir.join("poses.csv"), poses_csv(traj, model).as_bytes())
}

/// Hull geometry for external tools: every link's hulls in its frame, and
/// which link pairs interact.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct HullExport {
    pub links: Vec<LinkExport>,
    /// Link index pairs that never interact (parent–child, excluded, static,
    /// a link without contact).
    pub excluded_pairs: Vec<(usize, usize)>,
}

/// One link of a [`HullExport`].
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct LinkExport {
    pub robot: String,
    pub name: String,
    pub hulls: Vec<Vec<[f64; 3]>>,
}

impl HullExport {
    pub fn new(model: &Model, excluded: impl IntoIterator<Item = (usize, usize)>) -> Self {
        HullExport {
            links: model
                .links
                .iter()
                .map(|l| LinkExport {
                    robot: model.robots[l.robot].name.clone(),
                    name: l.name.clone(),
                    hulls: l
                        .hulls
                        .iter()
                        .map(|h| h.x_local.iter().map(|x| [x.x, x.y, x.z]).collect())
                        .collect(),
                })
                .collect(),
            excluded_pairs: {
                // Links without contact (`collide: false`) meet nothing.
                let mut pairs: std::collections::BTreeSet<(usize, usize)> =
                    excluded.into_iter().collect();
                let n = model.links.len();
                for (i, l) in model.links.iter().enumerate() {
                    if !l.collides {
                        for j in (0..n).filter(|&j| j != i) {
                            pairs.insert((i.min(j), i.max(j)));
                        }
                    }
                }
                pairs.into_iter().collect()
            },
        }
    }
}

/// Link poses as CSV: `step,t,link,a00,a10,a20,a01,…,a23` (column-major
/// `[R | t]`, shortest round-trip numbers).
pub fn poses_csv(traj: &Trajectory, model: &Model) -> String {
    let names: Vec<String> = model
        .links
        .iter()
        .map(|l| format!("{}/{}", model.robots[l.robot].name, l.name))
        .collect();
    let mut s =
        String::from("step,t,link,link_name,a00,a10,a20,a01,a11,a21,a02,a12,a22,t0,t1,t2\n");
    for (k, (t, poses)) in traj.times.iter().zip(&traj.poses).enumerate() {
        for (i, a) in poses.iter().enumerate() {
            s.push_str(&format!("{k},{t},{i},{}", names[i]));
            for v in a.as_slice() {
                s.push_str(&format!(",{v}"));
            }
            s.push('\n');
        }
    }
    s
}
