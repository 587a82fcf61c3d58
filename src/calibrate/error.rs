//! Errors of `sdrs calibrate`; each names the file and, for measured data,
//! the column and line (CSV) or the topic and message (MCAP logs).

use std::path::PathBuf;

/// Why calibration could not run. Nothing is written to the output
/// directory when any of these is returned.
#[derive(Debug, thiserror::Error)]
pub enum CalibrateError {
    #[error("{}: cannot read the file: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: malformed CSV at line {line}: {msg}", path.display())]
    Csv {
        path: PathBuf,
        line: u64,
        msg: String,
    },
    #[error("{}: no `t` column (the header must name a time column `t`)", path.display())]
    NoTime { path: PathBuf },
    #[error("{}: column {index} \"{column}\": unknown column (the scene's columns: {known})", path.display())]
    UnknownColumn {
        path: PathBuf,
        column: String,
        index: usize,
        known: String,
    },
    #[error("{}: column {index} \"{column}\" appears twice", path.display())]
    DuplicateColumn {
        path: PathBuf,
        column: String,
        index: usize,
    },
    #[error("{}: no data columns besides `t`", path.display())]
    NoChannels { path: PathBuf },
    #[error("{}: column \"{column}\", line {line}: {msg}", path.display())]
    BadValue {
        path: PathBuf,
        column: String,
        line: u64,
        msg: String,
    },
    #[error("{}: column \"t\", line {line}: time {t} does not increase (previous sample: {prev})", path.display())]
    NonMonotonicTime {
        path: PathBuf,
        line: u64,
        t: f64,
        prev: f64,
    },
    #[error("{}: MCAP: {msg}", path.display())]
    Mcap { path: PathBuf, msg: String },
    #[error("{}: topic \"{topic}\": {msg}", path.display())]
    LogTopic {
        path: PathBuf,
        topic: String,
        msg: String,
    },
    #[error("{}: topic \"{topic}\", message {index} (log time {log_time} ns): {msg}", path.display())]
    LogMessage {
        path: PathBuf,
        topic: String,
        /// 1-based index of the message among the topic's.
        index: usize,
        log_time: u64,
        msg: String,
    },
    #[error("{}: {msg}", path.display())]
    Recording { path: PathBuf, msg: String },
    #[error("{}: too short: {what}", path.display())]
    TooShort { path: PathBuf, what: String },
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    #[error("--effects: {msg}")]
    Effects { msg: String },
    #[error("--holdout must be in (0, 1), got {0}")]
    Holdout(f64),
    #[error("{}: the scene cannot be simulated as given: {source}", path.display())]
    Simulation {
        path: PathBuf,
        #[source]
        source: crate::sim::StepError,
    },
    #[error("{}: {msg}", path.display())]
    Output { path: PathBuf, msg: String },
    #[error("{}: refusing to overwrite an input file", path.display())]
    WouldOverwriteInput { path: PathBuf },
}
