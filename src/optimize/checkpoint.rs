//! Checkpoints of an optimization run (`checkpoint.json` in the output
//! directory), so that `sdrs optimize TASK --resume DIR` continues a long
//! run exactly where it stopped.
//!
//! A checkpoint holds the whole optimizer state after a completed
//! iteration: the iterate `(d, c)`, the trust-region radii, both Adam
//! states and the history. The evaluation at the iterate (loss and
//! gradients) is not stored: it is recomputed on resume, and since a
//! forward + backward pass is deterministic (same inputs and thread count →
//! bitwise the same numbers) the resumed run continues bitwise as the
//! uninterrupted run would (test `optimize_resume` in `cli/tests`). Floats
//! are written with shortest round-trip formatting and read back exactly
//! (serde_json's `float_roundtrip`).
//!
//! A checkpoint is tied to its task: it stores FNV-1a hashes of the task
//! and scene files and the run settings (`--design`, `--seed`); resuming
//! with anything changed is an error naming what differs.

use super::IterRecord;
use super::method::Adam;
use nalgebra::DVector;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Checkpoint file name inside the output directory.
pub const FILE: &str = "checkpoint.json";

/// Checkpoint format version.
const VERSION: u32 = 1;

/// Problems with a checkpoint.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("{}: cannot read the checkpoint: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: malformed checkpoint: {msg}", path.display())]
    Parse { path: PathBuf, msg: String },
    #[error("{}: cannot write the checkpoint: {msg}", path.display())]
    Write { path: PathBuf, msg: String },
    #[error("{}: {what} differs from the run that wrote it (checkpoint: {had}, now: {now})", path.display())]
    Mismatch {
        path: PathBuf,
        what: &'static str,
        had: String,
        now: String,
    },
}

/// The optimizer state after iteration `iter`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct State {
    /// Last completed iteration (0 = the initial evaluation).
    pub iter: usize,
    pub design: DVector<f64>,
    pub controller: DVector<f64>,
    pub radius_design: f64,
    pub radius_controller: f64,
    /// `optimizer.radius: split`: the blocks the next trial moves (absent in
    /// checkpoints written before `split` existed: joint).
    #[serde(default)]
    pub phase: super::method::Phase,
    pub adam_design: Adam,
    pub adam_controller: Adam,
    pub initial_loss: f64,
    pub history: Vec<IterRecord>,
    /// The lowest-loss iterate so far (absent in checkpoints written before
    /// `optimizer.result` existed: then the current iterate).
    #[serde(default)]
    pub best: Option<super::BestIterate>,
    /// `optimizer.plateau`: the iterations after which the run returned to
    /// its best iterate (absent in checkpoints written before the option
    /// existed: none). With `best.iter` it gives the iterations since the
    /// last improvement or return.
    #[serde(default)]
    pub plateau_returns: Vec<usize>,
}

/// What a checkpoint must agree with to be resumed.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct RunKey {
    /// FNV-1a 64 of the task file's bytes (hex).
    pub task_hash: String,
    /// FNV-1a 64 of the scene file's bytes (hex).
    pub scene_hash: String,
    /// `--design on|off`.
    pub design: bool,
    /// `--seed`.
    pub seed: u64,
}

impl RunKey {
    /// Hashes the task and scene files.
    pub fn new(task: &Path, scene: &Path, design: bool, seed: u64) -> std::io::Result<RunKey> {
        Ok(RunKey {
            task_hash: format!("{:016x}", fnv1a(&std::fs::read(task)?)),
            scene_hash: format!("{:016x}", fnv1a(&std::fs::read(scene)?)),
            design,
            seed,
        })
    }
}

/// The file's content.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Checkpoint {
    pub version: u32,
    pub key: RunKey,
    pub state: State,
}

/// FNV-1a, 64 bit.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Writes `dir/checkpoint.json` atomically.
pub fn save(dir: &Path, key: &RunKey, state: &State) -> Result<(), CheckpointError> {
    let c = Checkpoint {
        version: VERSION,
        key: key.clone(),
        state: state.clone(),
    };
    let path = dir.join(FILE);
    let write = |msg: String| CheckpointError::Write {
        path: path.clone(),
        msg,
    };
    let text = serde_json::to_string(&c).map_err(|e| write(e.to_string()))?;
    crate::files::write_atomic(&path, text.as_bytes()).map_err(|e| write(e.to_string()))
}

/// Reads `dir/checkpoint.json` and checks it against `key`.
pub fn load(dir: &Path, key: &RunKey) -> Result<State, CheckpointError> {
    let path = dir.join(FILE);
    let text = std::fs::read_to_string(&path).map_err(|source| CheckpointError::Io {
        path: path.clone(),
        source,
    })?;
    let c: Checkpoint = serde_json::from_str(&text).map_err(|e| CheckpointError::Parse {
        path: path.clone(),
        msg: e.to_string(),
    })?;
    let mismatch = |what, had: String, now: String| CheckpointError::Mismatch {
        path: path.clone(),
        what,
        had,
        now,
    };
    if c.version != VERSION {
        return Err(mismatch(
            "format version",
            c.version.to_string(),
            VERSION.to_string(),
        ));
    }
    let k = &c.key;
    if k.task_hash != key.task_hash {
        return Err(mismatch(
            "the task file",
            k.task_hash.clone(),
            key.task_hash.clone(),
        ));
    }
    if k.scene_hash != key.scene_hash {
        return Err(mismatch(
            "the scene file",
            k.scene_hash.clone(),
            key.scene_hash.clone(),
        ));
    }
    if k.design != key.design {
        return Err(mismatch(
            "--design",
            on_off(k.design).into(),
            on_off(key.design).into(),
        ));
    }
    if k.seed != key.seed {
        return Err(mismatch("--seed", k.seed.to_string(), key.seed.to_string()));
    }
    let s = &c.state;
    if s.history.len() != s.iter + 1 || !s.initial_loss.is_finite() {
        return Err(CheckpointError::Parse {
            path,
            msg: format!(
                "history has {} rows for iteration {}",
                s.history.len(),
                s.iter
            ),
        });
    }
    Ok(c.state)
}

fn on_off(b: bool) -> &'static str {
    if b { "on" } else { "off" }
}
