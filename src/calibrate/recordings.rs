//! Several recordings, one model (issue 33, item 4): `sdrs calibrate SCENE
//! --measured a.csv --measured b.csv …` fits one parameter set to all of
//! them.
//!
//! - **Initial state.** The first recording is simulated from the scene's
//!   own initial state, as a single recording always is (the scene file
//!   describes the experiment of its first `--measured`). Each further
//!   recording is simulated from the scene's initial state with every
//!   measured coordinate set to the recording's first sample
//!   ([`initial_coordinates`]), the scene's initial velocities (recordings
//!   are expected to start at rest or at the scene's velocities) and the
//!   scene's controller: the excitation differs by where the robot starts.
//!   The first sample must lie within half the median sample spacing of
//!   `t = 0` (it is taken as the state at `t = 0`) and carry a value in
//!   every column; coordinates of free and spherical joints (charted
//!   rotations) are refused.
//! - **Fit and validation.** The training residuals of all recordings are
//!   concatenated (the first 1 − holdout of each by time) and one
//!   parameter set minimizes their sum of squares; the held-out window of
//!   each recording (its last `holdout` fraction) scores the candidates
//!   and the verdict. (Whole held-out recordings are not offered: the
//!   held-out window of each keeps every excitation in both training and
//!   validation.)
//! - **Floor.** The noise and the integrator error ([`super::floor`]) are
//!   pooled over the held-out windows of all recordings. The residual force
//!   regression, the per-regime analysis and the plots use the first
//!   recording; [`gaps`] reports each recording's gap before and after.

use super::CalibrateError;
use super::data::{MIN_SAMPLES, Measured};
use super::mcap_log::LogMapping;
use super::problem::{Problem, Recording};
use crate::energy::effects::EffectSpec;
use crate::scene::Scene;
use nalgebra::DVector;
use serde::Serialize;
use std::path::Path;

/// Index of the first held-out sample of `m` for `holdout`; an error when
/// either window is too short (fewer than `MIN_SAMPLES/2` training or 3
/// held-out sample times).
pub fn split_of(m: &Measured, holdout: f64) -> Result<usize, CalibrateError> {
    let split = m.split(holdout);
    let n = m.times.len();
    if split < MIN_SAMPLES / 2 || n - split < 3 {
        return Err(CalibrateError::TooShort {
            path: m.path.clone(),
            what: format!(
                "{split} training and {} held-out sample time(s) with --holdout {holdout}; at least {} and 3 needed",
                n - split,
                MIN_SAMPLES / 2
            ),
        });
    }
    Ok(split)
}

/// The initial coordinates of a further recording: the scene's `θ^0` with
/// every measured coordinate set to its first sample (see the module doc
/// for the conditions; each violation is an error naming the file and
/// column).
pub fn initial_coordinates(scene: &Scene, m: &Measured) -> Result<DVector<f64>, CalibrateError> {
    let err = |msg: String| CalibrateError::Recording {
        path: m.path.clone(),
        msg,
    };
    let mut gaps: Vec<f64> = m.times.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_by(f64::total_cmp);
    let half = 0.5 * gaps.get(gaps.len() / 2).copied().unwrap_or(0.0);
    let t0 = m.times[0];
    if t0 > half {
        return Err(err(format!(
            "the first sample is at t = {t0} s, not within half a sample spacing ({half:.3e} s) of t = 0: a further recording starts from its first sample, which must be its state at t = 0"
        )));
    }
    let model = &scene.model;
    let mut q0 = scene.q0.clone();
    for ch in &m.channels {
        if model.links[model.dofs[ch.dof].link].joint.has_chart() {
            return Err(err(format!(
                "column \"{}\" is a coordinate of a free or spherical joint: further recordings can only start from measured hinge and slider coordinates",
                ch.name
            )));
        }
        let Some(v) = ch.values[0] else {
            return Err(err(format!(
                "column \"{}\" has no value at the first sample (t = {t0} s): a further recording's initial state is its first sample",
                ch.name
            )));
        };
        q0[ch.dof] = v;
    }
    Ok(q0)
}

/// Loads a further recording for `scene`: its data, split and initial
/// coordinates (an MCAP log is read as `log` says); the scene must simulate from that state over the whole
/// recording.
pub fn load(
    path: &Path,
    scene: &Scene,
    holdout: f64,
    log: &LogMapping,
) -> Result<Recording, CalibrateError> {
    let measured = Measured::load_with(path, &scene.model, log)?;
    let split = split_of(&measured, holdout)?;
    let q0 = initial_coordinates(scene, &measured)?;
    let mut sc = scene.clone();
    sc.q0 = q0.clone();
    let steps = (measured.duration() / sc.settings.dt).ceil() as usize + 1;
    crate::sim::run::run(&mut sc.simulator(), steps, |_| {}).map_err(|e| {
        CalibrateError::Recording {
            path: path.to_path_buf(),
            msg: format!("the scene cannot be simulated from this recording's first sample: {e}"),
        }
    })?;
    Ok(Recording {
        measured,
        split,
        q0,
    })
}

/// One recording's gaps (RMS of simulated − measured over its training
/// and held-out windows, SI units of the channels) before and after
/// calibration.
#[derive(Clone, Debug, Serialize)]
pub struct RecordingGap {
    pub path: String,
    /// `scene` (the scene's initial state) or `first sample`.
    pub initial: String,
    pub samples: usize,
    pub train_before: f64,
    pub train_after: f64,
    pub holdout_before: f64,
    pub holdout_after: f64,
}

/// RMS of `v`.
fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// Training and held-out RMS of one recording's problem with `extra`.
fn windows(q: &Problem, extra: &[EffectSpec]) -> Option<(f64, f64)> {
    let end = q.measured.times.len();
    let sim = q.simulate(extra, end)?;
    let (mut tr, mut ho) = (Vec::new(), Vec::new());
    q.residuals(&sim, 0..q.split, &mut tr);
    q.residuals(&sim, q.split..end, &mut ho);
    Some((rms(&tr), rms(&ho)))
}

/// Each recording's gaps before (the scene as given) and after (with the
/// `chosen` effects); a recording whose simulation fails gets `NaN`
/// (never the case for the chosen model, whose fit simulated it).
pub fn gaps(pb: &Problem, chosen: &[EffectSpec]) -> Vec<RecordingGap> {
    let one = |q: &Problem, initial: &str| {
        let (tb, hb) = windows(q, &[]).unwrap_or((f64::NAN, f64::NAN));
        let (ta, ha) = windows(q, chosen).unwrap_or((f64::NAN, f64::NAN));
        RecordingGap {
            path: q.measured.path.display().to_string(),
            initial: initial.into(),
            samples: q.measured.times.len(),
            train_before: tb,
            train_after: ta,
            holdout_before: hb,
            holdout_after: ha,
        }
    };
    let mut out = vec![one(&pb.first(), "scene")];
    for o in pb.others {
        out.push(pb.with_other(o, |q| one(q, "first sample")));
    }
    out
}

/// The "Recordings" section of `report.md` (nothing for one recording).
pub fn markdown(g: &[RecordingGap]) -> String {
    if g.len() < 2 {
        return String::new();
    }
    let mut s = String::from(
        "## Recordings\n\nOne parameter set fitted to the training windows of all recordings; each is scored on its own held-out window (`calibrate::recordings`). RMS of simulated − measured (SI units of the channels).\n\n| recording | initial state | samples | train before | train after | held-out before | held-out after |\n|---|---|---:|---:|---:|---:|---:|\n",
    );
    for r in g {
        s.push_str(&format!(
            "| `{}` | {} | {} | {:.3e} | {:.3e} | {:.3e} | {:.3e} |\n",
            r.path,
            r.initial,
            r.samples,
            r.train_before,
            r.train_after,
            r.holdout_before,
            r.holdout_after
        ));
    }
    s.push('\n');
    s
}
