//! Run records: trajectory CSV and summary JSON, written atomically (to a
//! temporary file in the same directory, renamed when complete).

pub mod codesign;
pub mod contacts;
pub mod gltf;
pub mod mjcf;
pub mod picture;
pub mod playback;

use crate::model::Model;
use crate::sim::{StageTime, StepDiagnostics};
use nalgebra::DVector;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

pub use crate::files::{OutputError, write_atomic};
pub use crate::sim::trajectory::Trajectory;

/// Writing a trajectory as CSV (the type lives in `sim`, which records it).
impl Trajectory {
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
        let mut fmt = CsvRows::new(velocities);
        let mut s = fmt.header(&self.names);
        for (t, q) in self.times.iter().zip(&self.states) {
            fmt.row(*t, q, &mut s);
        }
        s
    }
}

/// The trajectory CSV's text, row by row: what [`Trajectory::to_csv`]
/// writes and what [`CsvStream`] streams (one formatter, so both are
/// byte-identical).
#[derive(Clone, Debug)]
pub struct CsvRows {
    /// `Δt` and the initial velocity, when velocity columns are written.
    velocities: Option<(f64, DVector<f64>)>,
    /// The previous row's coordinates (velocity differences).
    prev: Option<DVector<f64>>,
}

impl CsvRows {
    /// `velocities`: `Some((Δt, q̇₀))` adds the `<name>:v` columns.
    pub fn new(velocities: Option<(f64, &DVector<f64>)>) -> Self {
        CsvRows {
            velocities: velocities.map(|(dt, v)| (dt, v.clone())),
            prev: None,
        }
    }

    /// The header line (with its newline).
    pub fn header(&self, names: &[String]) -> String {
        let mut s = String::from("t");
        for n in names {
            s.push(',');
            s.push_str(n);
        }
        if self.velocities.is_some() {
            for n in names {
                s.push_str(&format!(",{n}:v"));
            }
        }
        s.push('\n');
        s
    }

    /// Appends the row of time `t` and coordinates `q` (with its newline).
    pub fn row(&mut self, t: f64, q: &DVector<f64>, s: &mut String) {
        s.push_str(&format!("{t}"));
        for v in q.iter() {
            s.push_str(&format!(",{v}"));
        }
        if let Some((dt, qdot0)) = &self.velocities {
            for i in 0..q.len() {
                let v = match &self.prev {
                    None => qdot0[i],
                    Some(p) => (q[i] - p[i]) / dt,
                };
                s.push_str(&format!(",{v}"));
            }
            self.prev = Some(q.clone());
        }
        s.push('\n');
    }
}

/// A trajectory CSV written while the run goes on: memory stays bounded
/// whatever the number of steps, and the file holds whole rows only, so an
/// interrupted (Ctrl-C, SIGTERM) or failed run leaves a valid prefix. Rows are written out
/// at least every [`CsvStream::FLUSH_EVERY`] and whenever
/// [`CsvStream::BUFFER`] bytes wait.
///
/// Under `SIGKILL`, which cannot be handled, whole rows except in a short
/// window: the kernel copies a `write` into the file page by page and stops
/// between two pages when the process is killed, and kills it between two
/// system calls. So every `write` ends at a row's end and crosses no 4 KiB
/// page boundary of the file, except a single row that straddles one
/// (written alone); a kill during the copy of such a row leaves part of it.
/// Measured (`sdrs simulate robots/pendulum.yaml`, killed as soon as the
/// file grows, 1 ms polls, 100 runs each, 2026-11-28): a 1 MiB `BufWriter`
/// left a partial last row 33 times, this layout 2 times. Closing the
/// window needs rows padded to end at page boundaries (not done: every CSV
/// writer would have to pad alike).
pub struct CsvStream {
    path: PathBuf,
    file: std::fs::File,
    /// Bytes in the file.
    offset: u64,
    /// Whole rows not yet in the file.
    buf: Vec<u8>,
    rows: CsvRows,
    line: String,
    written: usize,
    last_flush: std::time::Instant,
}

impl CsvStream {
    /// Longest time rows wait in memory before they reach the file.
    pub const FLUSH_EVERY: std::time::Duration = std::time::Duration::from_secs(1);
    /// Bytes of rows that may wait in memory (64 KiB).
    pub const BUFFER: usize = 1 << 16;
    /// The page size the writes respect (bytes).
    const PAGE: u64 = 4096;

    /// Creates (truncates) `path` and writes the header.
    pub fn create(
        path: &Path,
        names: &[String],
        velocities: Option<(f64, &DVector<f64>)>,
    ) -> Result<Self, OutputError> {
        let io = |source| OutputError::Io {
            path: path.to_path_buf(),
            source,
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(io)?;
        }
        let file = std::fs::File::create(path).map_err(io)?;
        let rows = CsvRows::new(velocities);
        let mut out = CsvStream {
            path: path.to_path_buf(),
            file,
            offset: 0,
            buf: rows.header(names).into_bytes(),
            rows,
            line: String::new(),
            written: 0,
            last_flush: std::time::Instant::now(),
        };
        out.write_out().map_err(io)?;
        Ok(out)
    }

    fn io(&self, source: std::io::Error) -> OutputError {
        OutputError::Io {
            path: self.path.clone(),
            source,
        }
    }

    /// Writes the waiting rows: each `write` ends at a row's end and stays
    /// within one page of the file, or is one row alone (see the type doc).
    fn write_out(&mut self) -> std::io::Result<()> {
        let mut start = 0;
        while start < self.buf.len() {
            let rest = &self.buf[start..];
            let len = next_write(rest, self.offset, Self::PAGE);
            self.file.write_all(&rest[..len])?;
            self.offset += len as u64;
            start += len;
        }
        self.buf.clear();
        self.last_flush = std::time::Instant::now();
        Ok(())
    }

    /// Appends one row.
    pub fn push(&mut self, t: f64, q: &DVector<f64>) -> Result<(), OutputError> {
        self.line.clear();
        self.rows.row(t, q, &mut self.line);
        self.buf.extend_from_slice(self.line.as_bytes());
        self.written += 1;
        if (self.buf.len() >= Self::BUFFER || self.last_flush.elapsed() >= Self::FLUSH_EVERY)
            && let Err(e) = self.write_out()
        {
            return Err(self.io(e));
        }
        Ok(())
    }

    /// Rows written so far (without the header).
    pub fn rows(&self) -> usize {
        self.written
    }

    /// Writes out what is buffered and syncs the file.
    pub fn finish(mut self) -> Result<(), OutputError> {
        if let Err(e) = self.write_out() {
            return Err(self.io(e));
        }
        let r = self.file.sync_all();
        r.map_err(|e| self.io(e))
    }
}

/// Length of the next `write` of `rest` (whole rows, `\n`-terminated) at
/// file offset `offset`: the rows that end within the current page of size
/// `page`, or, when the first row crosses the page's end, that row alone
/// ([`CsvStream`]).
fn next_write(rest: &[u8], offset: u64, page: u64) -> usize {
    let room = (page - offset % page) as usize;
    let within = &rest[..room.min(rest.len())];
    match within.iter().rposition(|&b| b == b'\n') {
        Some(i) => i + 1,
        None => rest
            .iter()
            .position(|&b| b == b'\n')
            .map_or(rest.len(), |i| i + 1),
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

    /// The summary of a recorded run (folded through [`RunStats`]).
    pub fn new(
        scene: &str,
        dt: f64,
        traj: &Trajectory,
        wall_seconds: f64,
        stages: Vec<StageTime>,
    ) -> Self {
        let mut stats = RunStats::new();
        for d in &traj.diagnostics {
            stats.push(d);
        }
        stats.summary(
            scene,
            dt,
            &traj.names,
            traj.states.last(),
            wall_seconds,
            stages,
        )
    }
}

/// The statistics of a [`Summary`], folded one step at a time, so that a
/// streamed run of any length keeps constant memory; every sum and extreme
/// is taken in step order, as over a recorded trajectory.
#[derive(Clone, Debug)]
pub struct RunStats {
    steps: usize,
    total_iterations: usize,
    max_iterations: usize,
    max_final_gradient: f64,
    at_floor: usize,
    at_step_floor: usize,
    first: Option<StepDiagnostics>,
    last: Option<StepDiagnostics>,
    max_abs_drift: f64,
    max_momentum_change: f64,
    /// Work sums (controller, friction, contact, other) of steps 2…H;
    /// `None` once a step has no work record.
    work: Option<[f64; 4]>,
    min_distance: f64,
    steps_in_contact: usize,
    max_active_pairs: usize,
    ccd: crate::contact::ccd::CcdStats,
}

impl Default for RunStats {
    fn default() -> Self {
        Self::new()
    }
}

impl RunStats {
    pub fn new() -> Self {
        let zero: f64 = std::iter::empty::<f64>().sum();
        RunStats {
            steps: 0,
            total_iterations: 0,
            max_iterations: 0,
            max_final_gradient: 0.0,
            at_floor: 0,
            at_step_floor: 0,
            first: None,
            last: None,
            max_abs_drift: 0.0,
            max_momentum_change: 0.0,
            work: Some([zero; 4]),
            min_distance: f64::INFINITY,
            steps_in_contact: 0,
            max_active_pairs: 0,
            ccd: Default::default(),
        }
    }

    /// Steps folded so far.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Folds one completed step.
    pub fn push(&mut self, d: &StepDiagnostics) {
        self.steps += 1;
        self.total_iterations += d.newton.iters;
        self.max_iterations = self.max_iterations.max(d.newton.iters);
        self.max_final_gradient = f64::max(self.max_final_gradient, d.newton.grad_inf);
        self.at_floor += usize::from(d.newton.at_floor);
        self.at_step_floor += usize::from(d.newton.at_step_floor);
        let a = *self.first.get_or_insert(*d);
        if self.steps > 1 {
            self.work = match (self.work, d.work) {
                (Some(s), Some(w)) => Some([
                    s[0] + w.controller,
                    s[1] + w.friction,
                    s[2] + w.contact,
                    s[3] + w.other,
                ]),
                _ => None,
            };
        }
        let e0 = a.kinetic + a.potential;
        self.max_abs_drift = f64::max(self.max_abs_drift, (d.kinetic + d.potential - e0).abs());
        let dp = (0..3)
            .map(|k| (d.momentum[k] - a.momentum[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        self.max_momentum_change = f64::max(self.max_momentum_change, dp);
        self.min_distance = f64::min(self.min_distance, d.min_distance);
        self.steps_in_contact += usize::from(d.contact_pairs > 0);
        self.max_active_pairs = self.max_active_pairs.max(d.contact_pairs);
        self.ccd.merge(&d.ccd);
        self.last = Some(*d);
    }

    /// The summary: `names` and `final_q` give the final state.
    pub fn summary(
        &self,
        scene: &str,
        dt: f64,
        names: &[String],
        final_q: Option<&DVector<f64>>,
        wall_seconds: f64,
        stages: Vec<StageTime>,
    ) -> Summary {
        let steps = self.steps;
        let newton = NewtonStats {
            mean_iterations: if steps > 0 {
                self.total_iterations as f64 / steps as f64
            } else {
                0.0
            },
            max_iterations: self.max_iterations,
            total_iterations: self.total_iterations,
            max_final_gradient: self.max_final_gradient,
            steps_at_roundoff_floor: self.at_floor,
            steps_at_step_floor: self.at_step_floor,
        };
        let final_state = final_q
            .map(|q| names.iter().cloned().zip(q.iter().copied()).collect())
            .unwrap_or_default();
        let energy = self.first.zip(self.last).map(|(a, b)| {
            let e0 = a.kinetic + a.potential;
            let balance = self.work.filter(|_| steps > 1).map(|[c, f, k, o]| {
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
                max_abs_drift: self.max_abs_drift,
                balance,
            }
        });
        let linear_momentum = self.first.zip(self.last).map(|(a, b)| MomentumStats {
            first: a.momentum,
            last: b.momentum,
            max_change: self.max_momentum_change,
        });
        let min_d = self.min_distance;
        let contact = ContactStats {
            steps_in_contact: self.steps_in_contact,
            max_active_pairs: self.max_active_pairs,
            min_distance: min_d.is_finite().then_some(min_d),
            ccd: self.ccd,
        };
        Summary {
            units: Summary::units(),
            scene: scene.to_string(),
            steps,
            dt,
            dof: names.len(),
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
/// independent check `tools/check/check_separation.py` read.
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

#[cfg(test)]
mod tests {
    use super::next_write;

    /// Rows of lengths 1…97 bytes written from every offset in a small
    /// page: each write is whole rows, and it stays within one page unless
    /// it is a single row that crosses the page's end.
    #[test]
    fn writes_end_at_rows_and_cross_no_page_but_one_row() {
        let page = 64u64;
        let mut buf = Vec::new();
        for k in 0..300usize {
            buf.extend(std::iter::repeat_n(b'1', k % 97));
            buf.push(b'\n');
        }
        for offset0 in 0..page {
            let (mut offset, mut start) = (offset0, 0usize);
            while start < buf.len() {
                let len = next_write(&buf[start..], offset, page);
                let w = &buf[start..start + len];
                assert!(len > 0 && w.ends_with(b"\n"), "offset {offset}");
                let rows = w.iter().filter(|&&b| b == b'\n').count();
                let first_page = offset / page;
                let last_page = (offset + len as u64 - 1) / page;
                assert!(
                    first_page == last_page || rows == 1,
                    "a write of {rows} rows crosses a page at offset {offset}"
                );
                offset += len as u64;
                start += len;
            }
            assert_eq!(start, buf.len());
        }
    }
}
