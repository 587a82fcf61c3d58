//! Capture of failing pair evaluations for offline reproduction.
//!
//! When the environment variable `SDRS_DUMP_FAILED_PAIR` names a directory, the simulator's
//! contact and friction terms write every pair evaluation that returns an error as a small
//! JSON file there (`contact-<n>.json` / `friction-<n>.json`). Each file holds exactly the
//! inputs of the failing call — parameters, poses, link-local vertices, warm plane or lagged
//! frame — with floats printed shortest-round-trip, so [`ContactCase::run`] and
//! [`FrictionCase::run`] replay the call bit for bit. The regression tests of the inner solvers
//! are such captures (`src/contact/regressions/`).

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use nalgebra::{Matrix3x2, Matrix3x4, Vector3, Vector4};
use serde::{Deserialize, Serialize};

use super::error::{ContactError, FrictionError};
use super::friction::{
    FrictionFrame, FrictionNeed, FrictionPair, FrictionParams, FrictionScratch, friction_pair,
};
use super::potential::{ContactParams, ContactScratch, HullPose, Need, PairOutcome, contact_pair};

/// Environment variable naming the dump directory.
pub const DUMP_ENV: &str = "SDRS_DUMP_FAILED_PAIR";

/// Inputs of one [`contact_pair`] call.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactCase {
    /// What failed (error message), for the reader.
    pub error: String,
    pub params: ContactParams,
    pub pose_a: Matrix3x4<f64>,
    pub pose_b: Matrix3x4<f64>,
    pub local_a: Vec<Vector3<f64>>,
    pub local_b: Vec<Vector3<f64>>,
    pub warm: Option<Vector4<f64>>,
    /// `Value`, `Gradient` or `Hessian`.
    pub need: String,
}

/// Inputs of one [`friction_pair`] call.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrictionCase {
    /// What failed (error message), for the reader.
    pub error: String,
    pub params: FrictionParams,
    pub normal: Vector3<f64>,
    pub basis: Matrix3x2<f64>,
    pub x_prev_a: Vec<Vector3<f64>>,
    pub x_prev_b: Vec<Vector3<f64>>,
    pub normal_force_a: Vec<f64>,
    pub normal_force_b: Vec<f64>,
    pub pose_a: Matrix3x4<f64>,
    pub pose_b: Matrix3x4<f64>,
    pub local_a: Vec<Vector3<f64>>,
    pub local_b: Vec<Vector3<f64>>,
    /// `Value`, `Gradient`, `Hessian` or `HessianAndMixed`.
    pub need: String,
}

fn contact_need(s: &str) -> Need {
    match s {
        "Value" => Need::Value,
        "Gradient" => Need::Gradient,
        _ => Need::Hessian,
    }
}

fn friction_need(s: &str) -> FrictionNeed {
    match s {
        "Value" => FrictionNeed::Value,
        "Gradient" => FrictionNeed::Gradient,
        "Hessian" => FrictionNeed::Hessian,
        _ => FrictionNeed::HessianAndMixed,
    }
}

impl ContactCase {
    /// Records a call.
    pub fn new(
        a: HullPose<'_>,
        b: HullPose<'_>,
        params: &ContactParams,
        warm: Option<Vector4<f64>>,
        need: Need,
        error: &ContactError,
    ) -> Self {
        Self {
            error: error.to_string(),
            params: *params,
            pose_a: *a.pose,
            pose_b: *b.pose,
            local_a: a.x_local.to_vec(),
            local_b: b.x_local.to_vec(),
            warm,
            need: format!("{need:?}"),
        }
    }

    /// Replays the call.
    pub fn run(&self) -> Result<PairOutcome, ContactError> {
        let a = HullPose {
            pose: &self.pose_a,
            x_local: &self.local_a,
        };
        let b = HullPose {
            pose: &self.pose_b,
            x_local: &self.local_b,
        };
        contact_pair(
            a,
            b,
            &self.params,
            self.warm,
            contact_need(&self.need),
            &mut ContactScratch::new(),
        )
    }
}

impl FrictionCase {
    /// Records a call.
    pub fn new(
        frame: &FrictionFrame<'_>,
        a: HullPose<'_>,
        b: HullPose<'_>,
        params: &FrictionParams,
        need: FrictionNeed,
        error: &FrictionError,
    ) -> Self {
        Self {
            error: error.to_string(),
            params: *params,
            normal: frame.normal,
            basis: frame.basis,
            x_prev_a: frame.x_prev_a.to_vec(),
            x_prev_b: frame.x_prev_b.to_vec(),
            normal_force_a: frame.normal_force_a.to_vec(),
            normal_force_b: frame.normal_force_b.to_vec(),
            pose_a: *a.pose,
            pose_b: *b.pose,
            local_a: a.x_local.to_vec(),
            local_b: b.x_local.to_vec(),
            need: format!("{need:?}"),
        }
    }

    /// The lagged frame.
    pub fn frame(&self) -> FrictionFrame<'_> {
        FrictionFrame {
            normal: self.normal,
            basis: self.basis,
            x_prev_a: &self.x_prev_a,
            x_prev_b: &self.x_prev_b,
            normal_force_a: &self.normal_force_a,
            normal_force_b: &self.normal_force_b,
        }
    }

    /// Replays the call (with the recorded parameters unless `params` is given).
    pub fn run(&self, params: Option<&FrictionParams>) -> Result<FrictionPair, FrictionError> {
        let a = HullPose {
            pose: &self.pose_a,
            x_local: &self.local_a,
        };
        let b = HullPose {
            pose: &self.pose_b,
            x_local: &self.local_b,
        };
        friction_pair(
            &self.frame(),
            a,
            b,
            params.unwrap_or(&self.params),
            friction_need(&self.need),
            &mut FrictionScratch::new(),
        )
    }
}

static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// Writes `case` as `<dir>/<kind>-<n>.json` when [`DUMP_ENV`] is set; returns the path
/// written. Best effort: I/O errors are reported on stderr and otherwise ignored (this is a
/// diagnostic aid, it must never change the simulation).
pub fn dump<T: Serialize>(kind: &str, case: &T) -> Option<PathBuf> {
    let dir = std::env::var_os(DUMP_ENV)?;
    let dir = PathBuf::from(dir);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let path = dir.join(format!("{kind}-{n}.json"));
    let res = std::fs::create_dir_all(&dir).and_then(|_| {
        let text = serde_json::to_string_pretty(case).map_err(std::io::Error::other)?;
        std::fs::write(&path, text)
    });
    match res {
        Ok(()) => Some(path),
        Err(e) => {
            eprintln!("{DUMP_ENV}: cannot write {}: {e}", path.display());
            None
        }
    }
}
