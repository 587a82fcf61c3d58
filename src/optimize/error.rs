//! Typed errors of co-design runs: evaluating a problem, the optimizer
//! loop, the metrics and the files it writes. Each variant carries the data
//! that names what failed (file, element, iteration, trajectory, step).

use super::TaskError;
use super::checkpoint::CheckpointError;
use std::path::PathBuf;

/// Why an evaluation, an optimization run or one of its outputs failed.
#[derive(Debug, thiserror::Error)]
pub enum OptimizeError {
    #[error(transparent)]
    Task(#[from] TaskError),
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    /// A simulation step failed (forward pass, metrics, rollouts).
    #[error(transparent)]
    Step(#[from] crate::sim::StepError),
    #[error(transparent)]
    Backward(#[from] crate::diff::BackwardError),
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// An output file could not be written.
    #[error(transparent)]
    Output(#[from] crate::files::OutputError),
    /// A scene whose `contact.model` the core does not implement, and no
    /// provider for it ([`super::Problem::contact_factory`]).
    #[error(
        "{}: contact.model: {model} needs the contact model's provider (the `sdrs` CLI passes the IPC baseline's)",
        path.display()
    )]
    NoContactProvider { path: PathBuf, model: String },
    /// The backward pass lacks derivatives of some terms.
    #[error("the gradient needs derivatives that are not available yet: {}", .terms.join(", "))]
    Unavailable { terms: Vec<String> },
    /// A checkpoint's vector sizes differ from the task's.
    #[error(
        "the checkpoint has {design} design and {controller} controller variables, the task {task_design} and {task_controller}"
    )]
    CheckpointSize {
        design: usize,
        controller: usize,
        task_design: usize,
        task_controller: usize,
    },
    /// A task element (`grasp.object`, `design.vertices`, …) that does not
    /// fit the model or the horizon.
    #[error("{element}: {msg}")]
    Invalid { element: String, msg: String },
    /// A simulation step of the named scene failed.
    #[error("{}: step {step}: {err}", path.display())]
    StepOf {
        path: PathBuf,
        step: usize,
        err: crate::sim::StepError,
    },
    /// Serializing an output (`what`) failed.
    #[error("{what}: {msg}")]
    Serialize { what: String, msg: String },
    /// The link's topology could not be measured.
    #[error("{link}: {err}")]
    Topology {
        link: String,
        err: crate::geometry::topology::TopologyError,
    },
    /// In iteration `iter` of the optimizer.
    #[error("iteration {iter}")]
    Iteration {
        iter: usize,
        #[source]
        source: Box<OptimizeError>,
    },
    /// In trajectory `index` of a task with several.
    #[error("trajectory {index}")]
    Trajectory {
        index: usize,
        #[source]
        source: Box<OptimizeError>,
    },
    #[error("a task without trajectories")]
    NoTrajectories,
}

impl OptimizeError {
    /// A serialization failure of `what` (a file name or a value).
    pub fn serialize(what: impl Into<String>, e: impl std::fmt::Display) -> Self {
        OptimizeError::Serialize {
            what: what.into(),
            msg: e.to_string(),
        }
    }
}
