//! One whole import, as `sdrs import` and the Python `import_robot` run it:
//! read the input, decompose, make the scene ready to simulate
//! ([`super::ready`]), and write the scene, the hull meshes and the report
//! atomically ([`super::write`]). The command-line arguments that fill an
//! [`ImportJob`] live in the application (`cli/src/import.rs`).

use super::error::ImportError;
use super::ready::{BaseMode, ReadyOptions, make_ready};
use super::report::ImportReport;
use super::write::{OutputPaths, check_outputs, write_outputs};
use super::{ImportOptions, import_with};
use crate::progress::Progress;
use std::path::PathBuf;

/// An import run: input, outputs and every option. [`ImportJob::new`] gives
/// the defaults of `sdrs import INPUT --out OUT`.
#[derive(Clone, Debug)]
pub struct ImportJob {
    /// `.urdf`, MJCF `.xml`, or `.obj` / `.stl` / `.dae` (one free body).
    pub input: PathBuf,
    /// Output design (scene YAML); hull OBJs go to `<out stem>_meshes/`.
    pub out: PathBuf,
    /// Where to write the import report (JSON). Default none.
    pub report: Option<PathBuf>,
    /// Replace existing outputs. Default false.
    pub force: bool,
    /// Decomposition, masses, ties ([`ImportOptions::default`]).
    pub options: ImportOptions,
    /// Base attachment. Default [`BaseMode::Auto`].
    pub base: BaseMode,
    /// Ground plane: `None` adds one (and places the robot on it) when the
    /// base floats and the input has no ground; `Some(true)` always
    /// (`--ground`); `Some(false)` never (`--no-ground`). Default `None`.
    pub ground: Option<bool>,
    /// Turn contact on (with rest-pose exclusions). Default true.
    pub contact: bool,
    /// PD gains holding the initial pose. Default true.
    pub hold: bool,
    /// Initial coordinates `(joint, value)` (rad or m). Default none.
    pub pose: Vec<(String, f64)>,
}

impl ImportJob {
    /// The job `sdrs import input --out out` runs with no other flag.
    pub fn new(input: PathBuf, out: PathBuf) -> ImportJob {
        ImportJob {
            input,
            out,
            report: None,
            force: false,
            options: ImportOptions::default(),
            base: BaseMode::Auto,
            ground: None,
            contact: true,
            hold: true,
            pose: Vec::new(),
        }
    }

    /// Rejects option values no import can use (the message names the flag).
    fn check(&self) -> Result<(), ImportError> {
        let o = &self.options;
        let bad = |msg: String| Err(ImportError::Options { msg });
        if !(o.density > 0.0 && o.density.is_finite()) {
            return bad(format!("--density must be positive, got {}", o.density));
        }
        if o.resolution < 8 {
            return bad("--resolution must be at least 8".into());
        }
        if !(o.threshold > 0.0 && o.threshold <= 1.0) {
            return bad(format!(
                "--threshold must be in (0, 1], got {}",
                o.threshold
            ));
        }
        Ok(())
    }
}

/// Runs `job`: imports, makes the scene ready and writes every output (none
/// when it fails). Returns the report that was written.
pub fn run_job(job: &ImportJob) -> Result<ImportReport, ImportError> {
    run_job_with(job, &crate::progress::Silent)
}

/// [`run_job`], reporting the decomposition's progress ([`import_with`]).
pub fn run_job_with(job: &ImportJob, progress: &dyn Progress) -> Result<ImportReport, ImportError> {
    job.check()?;
    let paths = OutputPaths::new(&job.out, job.report.as_deref());
    check_outputs(&job.input, &paths, job.force)?;
    let mut imported = import_with(&job.input, &job.options, progress)?;
    let ready_opts = ReadyOptions {
        base: job.base,
        ground: job.ground,
        contact: job.contact,
        hold: job.hold,
        pose: job.pose.iter().cloned().collect(),
        mu: imported.friction,
    };
    let ready = make_ready(
        &mut imported.scene,
        &job.input,
        imported.root_static,
        &ready_opts,
    )?;
    imported.report.ready = Some(ready);
    write_outputs(&imported, &job.input, &paths, job.force)?;
    Ok(imported.report)
}
