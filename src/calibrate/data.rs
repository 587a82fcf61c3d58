//! Measured trajectories: an MCAP robot log ([`super::mcap_log`]) or a CSV with a time column `t` (s) and any subset of
//! the columns `sdrs simulate` writes (joint coordinates named as in the
//! trajectory CSV: `hinge`, `arm/elbow`, `box/box:x`), at its own sampling
//! times. An empty cell is a gap (that channel has no sample at that time);
//! `NaN`, infinities and text are errors naming the column and line.
//! Simulated channels are compared with measured ones by linear
//! interpolation of the simulation (on the scene's Δt) at the measured times
//! ([`Measured::align`]).

use super::CalibrateError;
use super::mcap_log::LogMapping;
use crate::model::Model;
use std::path::{Path, PathBuf};

/// Fewest time samples accepted.
pub const MIN_SAMPLES: usize = 10;

/// One measured channel.
#[derive(Clone, Debug)]
pub struct Channel {
    /// Column name.
    pub name: String,
    /// Coordinate index in `θ`.
    pub dof: usize,
    /// Value per sample time; `None` in gaps.
    pub values: Vec<Option<f64>>,
}

/// A measured data set.
#[derive(Clone, Debug)]
pub struct Measured {
    pub path: PathBuf,
    /// Sample times (s), strictly increasing, ≥ 0.
    pub times: Vec<f64>,
    pub channels: Vec<Channel>,
}

impl Measured {
    /// Reads and validates `path` against the scene's coordinates: an MCAP
    /// robot log when its name ends in `.mcap` (any case; read as
    /// `mapping` says, [`super::mcap_log`]), else CSV.
    pub fn load_with(
        path: &Path,
        model: &Model,
        mapping: &LogMapping,
    ) -> Result<Measured, CalibrateError> {
        let is_mcap = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("mcap"));
        if is_mcap {
            return super::mcap_log::load(path, model, mapping);
        }
        Self::load(path, model)
    }

    /// Reads and validates the CSV file `path` against the scene's coordinates.
    pub fn load(path: &Path, model: &Model) -> Result<Measured, CalibrateError> {
        let text = std::fs::read_to_string(path).map_err(|source| CalibrateError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, path, model)
    }

    /// Parses CSV text; `path` is used in messages.
    pub fn parse(text: &str, path: &Path, model: &Model) -> Result<Measured, CalibrateError> {
        let p = || path.to_path_buf();
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            .from_reader(text.as_bytes());
        let header = rdr.headers().map_err(|e| CalibrateError::Csv {
            path: p(),
            line: 1,
            msg: e.to_string(),
        })?;
        let names: Vec<String> = header.iter().map(str::to_string).collect();
        let mut time_col = None;
        let mut cols: Vec<(usize, Channel)> = Vec::new();
        for (index, name) in names.iter().enumerate() {
            let dup = || CalibrateError::DuplicateColumn {
                path: p(),
                column: name.clone(),
                index: index + 1,
            };
            if name == "t" {
                if time_col.replace(index).is_some() {
                    return Err(dup());
                }
                continue;
            }
            let Some(dof) = model.dofs.iter().position(|d| &d.name == name) else {
                let known: Vec<&str> = model.dofs.iter().map(|d| d.name.as_str()).collect();
                return Err(CalibrateError::UnknownColumn {
                    path: p(),
                    column: name.clone(),
                    index: index + 1,
                    known: known.join(", "),
                });
            };
            if cols.iter().any(|(_, c)| c.dof == dof) {
                return Err(dup());
            }
            cols.push((
                index,
                Channel {
                    name: name.clone(),
                    dof,
                    values: Vec::new(),
                },
            ));
        }
        let time_col = time_col.ok_or_else(|| CalibrateError::NoTime { path: p() })?;
        if cols.is_empty() {
            return Err(CalibrateError::NoChannels { path: p() });
        }
        let mut times: Vec<f64> = Vec::new();
        for rec in rdr.records() {
            let rec = rec.map_err(|e| CalibrateError::Csv {
                path: p(),
                line: e.position().map_or(0, |q| q.line()),
                msg: e.to_string(),
            })?;
            let line = rec.position().map_or(0, |q| q.line());
            if rec.iter().all(str::is_empty) {
                continue; // blank line
            }
            let cell = |col: usize, name: &str| -> Result<Option<f64>, CalibrateError> {
                let s = rec.get(col).unwrap_or("");
                if s.is_empty() {
                    return Ok(None);
                }
                let bad = |msg: String| CalibrateError::BadValue {
                    path: p(),
                    column: name.to_string(),
                    line,
                    msg,
                };
                let v: f64 = s
                    .parse()
                    .map_err(|_| bad(format!("\"{s}\" is not a number")))?;
                if !v.is_finite() {
                    return Err(bad(format!("{s} is not a finite number")));
                }
                Ok(Some(v))
            };
            let t = cell(time_col, "t")?.ok_or_else(|| CalibrateError::BadValue {
                path: p(),
                column: "t".into(),
                line,
                msg: "the time is missing".into(),
            })?;
            if t < 0.0 {
                return Err(CalibrateError::BadValue {
                    path: p(),
                    column: "t".into(),
                    line,
                    msg: format!("time {t} is negative (the scene starts at t = 0)"),
                });
            }
            if let Some(&prev) = times.last().filter(|&&prev| t <= prev) {
                return Err(CalibrateError::NonMonotonicTime {
                    path: p(),
                    line,
                    t,
                    prev,
                });
            }
            times.push(t);
            for (col, ch) in cols.iter_mut() {
                let v = cell(*col, &ch.name)?;
                ch.values.push(v);
            }
        }
        let channels = cols.into_iter().map(|(_, c)| c).collect();
        Self::from_samples(path, times, channels, "column")
    }

    /// A measured data set from samples already read and checked (times
    /// strictly increasing from ≥ 0, finite values), by the CSV reader or
    /// [`super::mcap_log`]: refuses fewer than [`MIN_SAMPLES`] sample
    /// times or values of a channel; `what` names a channel in messages
    /// (`column`, `topic "/joint_states", joint`).
    pub fn from_samples(
        path: &Path,
        times: Vec<f64>,
        channels: Vec<Channel>,
        what: &str,
    ) -> Result<Measured, CalibrateError> {
        let p = || path.to_path_buf();
        if times.len() < MIN_SAMPLES {
            return Err(CalibrateError::TooShort {
                path: p(),
                what: format!(
                    "{} time sample(s), at least {MIN_SAMPLES} needed",
                    times.len()
                ),
            });
        }
        for ch in &channels {
            let n = ch.values.iter().flatten().count();
            if n < MIN_SAMPLES {
                return Err(CalibrateError::TooShort {
                    path: p(),
                    what: format!(
                        "{what} \"{}\" has {n} value(s), at least {MIN_SAMPLES} needed",
                        ch.name
                    ),
                });
            }
        }
        Ok(Measured {
            path: path.to_path_buf(),
            times,
            channels,
        })
    }

    /// Last sample time (s).
    pub fn duration(&self) -> f64 {
        *self.times.last().unwrap_or(&0.0)
    }

    /// Index of the first sample of the held-out window: samples with
    /// `t ≥ (1 − holdout)·t_end`.
    pub fn split(&self, holdout: f64) -> usize {
        let t_split = (1.0 - holdout) * self.duration();
        self.times.partition_point(|&t| t < t_split)
    }
}

/// Linear interpolation of the simulated coordinate `dof` at time `t`, from
/// states recorded at `k·dt`, `k = 0 … states.len() − 1` (clamped at the
/// ends).
pub fn interpolate(states: &[nalgebra::DVector<f64>], dt: f64, dof: usize, t: f64) -> f64 {
    let x = t / dt;
    let last = states.len() - 1;
    let k = (x.floor().max(0.0) as usize).min(last);
    if k >= last {
        return states[last][dof];
    }
    let w = x - k as f64;
    (1.0 - w) * states[k][dof] + w * states[k + 1][dof]
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DVector;

    #[test]
    fn interpolation_is_exact_for_linear_motion_and_clamped_at_the_ends() {
        let dt = 0.01;
        let states: Vec<DVector<f64>> = (0..=10)
            .map(|k| DVector::from_vec(vec![2.0 * k as f64 * dt - 0.3]))
            .collect();
        for t in [0.0, 0.003, 0.05, 0.0999, 0.1] {
            assert!((interpolate(&states, dt, 0, t) - (2.0 * t - 0.3)).abs() < 1e-14);
        }
        assert_eq!(interpolate(&states, dt, 0, 5.0), states[10][0]);
    }

    #[test]
    fn split_holds_out_the_last_fraction_by_time() {
        let m = Measured {
            path: "m.csv".into(),
            times: (0..=100).map(|k| k as f64 * 0.01).collect(),
            channels: Vec::new(),
        };
        let s = m.split(0.3);
        assert!(m.times[s] >= 0.7 - 1e-12 && m.times[s - 1] < 0.7);
    }
}
