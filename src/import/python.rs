//! Finding and running the project's Python helpers (`tools/helpers/*.py`).
//!
//! Helper scripts, in this order:
//! 1. a [`HelperSource`] the embedding program registered
//!    ([`set_helper_source`]): the `sdrs` binary registers the scripts it
//!    carries (`include_str!`, written to a per-user temporary folder), so an
//!    installed binary (`cargo install --path cli`) needs no source tree;
//! 2. `$SDRS_ROOT/tools/helpers/<name>` when `SDRS_ROOT` is set;
//! 3. `tools/helpers/<name>` in the current directory or one of its parents, or
//!    above the running program (a source checkout: the library's own
//!    tests, `target/release/sdrs`).
//!
//! Interpreter: `$SDRS_PYTHON` if set, else `<root>/.venv/bin/python` when
//! a source tree `<root>` is known (2 or 3 above) and has one, else
//! `python3` on the `PATH`. `bash tools/setup/setup_python.sh` creates the venv in
//! a checkout; elsewhere `python3 -m pip install <package>` the package an
//! error names.

use super::error::ImportError;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

/// The command that installs the Python helpers' packages in a checkout.
pub const SETUP_COMMAND: &str = "bash tools/setup/setup_python.sh";

/// Exit code the helpers use when a package is missing (they print
/// `missing Python package: NAME` on stderr).
pub const EXIT_MISSING_PACKAGE: i32 = 3;

/// Where the embedding program keeps runnable copies of the helpers.
pub trait HelperSource: Send + Sync {
    /// A path of a runnable copy of `tools/helpers/<name>`, or why there is none.
    fn script(&self, name: &str) -> Result<PathBuf, String>;
}

static SOURCE: OnceLock<Box<dyn HelperSource>> = OnceLock::new();

/// How helper processes run. The core only needs a helper's output; the
/// embedding program decides how the process is tied to its own life (the
/// `sdrs` binary kills its helpers and removes their folders when it is
/// interrupted: `cli/src/child.rs`). Without a registered runner,
/// [`Plain`] runs them.
pub trait HelperRunner: Send + Sync {
    /// Runs `cmd` to completion and collects its status, stdout and stderr,
    /// like [`Command::output`].
    fn output(&self, cmd: Command) -> std::io::Result<Output>;
    /// Creates `path` (and its parents), a temporary folder for a helper,
    /// to be removed if the program is interrupted before
    /// [`Self::forget_folder`]. A runner that removes folders on an
    /// interruption must create and register the folder as one step with
    /// respect to that removal, or a folder made by another thread between
    /// the removal and the exit is left behind. Default: creates it.
    fn create_folder(&self, path: &Path) -> std::io::Result<()> {
        std::fs::create_dir_all(path)
    }
    /// `path` is gone (removed by [`TempDir`]'s drop). Default: nothing.
    fn forget_folder(&self, _path: &Path) {}
}

/// Runs a helper with [`Command::output`] and nothing more (the default
/// runner; the Python package's).
pub struct Plain;

impl HelperRunner for Plain {
    fn output(&self, mut cmd: Command) -> std::io::Result<Output> {
        cmd.output()
    }
}

static RUNNER: OnceLock<Box<dyn HelperRunner>> = OnceLock::new();

/// Registers the program's helper runner (first call wins; returns whether
/// this one was taken).
pub fn set_helper_runner(runner: Box<dyn HelperRunner>) -> bool {
    RUNNER.set(runner).is_ok()
}

/// The registered runner, else [`Plain`].
fn runner() -> &'static dyn HelperRunner {
    match RUNNER.get() {
        Some(r) => r.as_ref(),
        None => &Plain,
    }
}

/// A temporary folder for a helper's files, removed on drop (and by the
/// runner when the program is interrupted, see [`HelperRunner`]).
pub struct TempDir {
    path: PathBuf,
}

impl TempDir {
    /// Creates `path` (and its parents) through the runner
    /// ([`HelperRunner::create_folder`]).
    pub fn create(path: PathBuf) -> std::io::Result<TempDir> {
        runner().create_folder(&path)?;
        Ok(TempDir { path })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.path);
        runner().forget_folder(&self.path);
    }
}

/// Registers the program's helper source (first call wins; returns whether
/// this one was taken).
pub fn set_helper_source(source: Box<dyn HelperSource>) -> bool {
    SOURCE.set(source).is_ok()
}

/// The source tree, if one is known: `$SDRS_ROOT`, else the first of the
/// current directory's and then the running program's ancestors that holds
/// `tools/helpers/mjcf_dump.py` (a checkout, or `target/release/` inside one).
pub fn source_root() -> Option<PathBuf> {
    if let Some(r) = std::env::var_os("SDRS_ROOT") {
        return Some(PathBuf::from(r));
    }
    let starts = [std::env::current_dir().ok(), std::env::current_exe().ok()];
    starts.into_iter().flatten().find_map(|start| {
        start
            .ancestors()
            .find(|d| d.join("tools/helpers/mjcf_dump.py").is_file())
            .map(Path::to_path_buf)
    })
}

/// The Python interpreter to use.
pub fn interpreter() -> PathBuf {
    if let Some(p) = std::env::var_os("SDRS_PYTHON") {
        return PathBuf::from(p);
    }
    match source_root().map(|r| r.join(".venv/bin/python")) {
        Some(venv) if venv.exists() => venv,
        _ => PathBuf::from("python3"),
    }
}

/// Path of a runnable helper script (see the module doc for the order).
pub fn tool(name: &str) -> Result<PathBuf, ImportError> {
    if let Some(s) = SOURCE.get() {
        return s.script(name).map_err(|msg| ImportError::Python { msg });
    }
    let found = source_root().map(|r| r.join("tools/helpers").join(name));
    match found {
        Some(p) if p.is_file() => Ok(p),
        _ => Err(ImportError::Python {
            msg: format!(
                "helper tools/helpers/{name} not found: this program carries no helpers and no sdrs source tree is known (set SDRS_ROOT to one, or use the `sdrs` binary, which carries them)"
            ),
        }),
    }
}

/// Output of a helper run.
pub struct ToolOutput {
    pub stdout: String,
    pub stderr: String,
    pub code: Option<i32>,
}

/// Runs `tools/helpers/<script> args…` with the project interpreter. Fails with the
/// install command when the interpreter or a package is missing.
pub fn run_tool(script: &str, args: &[std::ffi::OsString]) -> Result<ToolOutput, ImportError> {
    let py = interpreter();
    let path = tool(script)?;
    let mut cmd = Command::new(&py);
    cmd.arg(&path).args(args);
    let out = runner().output(cmd).map_err(|e| ImportError::Python {
        msg: format!(
            "cannot run Python ({}): {e}; set SDRS_PYTHON to a Python 3 interpreter (in a source tree: `{SETUP_COMMAND}`)",
            py.display()
        ),
    })?;
    let res = ToolOutput {
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        code: out.status.code(),
    };
    if res.code == Some(EXIT_MISSING_PACKAGE) {
        let package = res
            .stderr
            .lines()
            .find_map(|l| l.strip_prefix("missing Python package: "))
            .and_then(|s| s.split_whitespace().next())
            .unwrap_or("<package>")
            .to_string();
        return Err(ImportError::Python {
            msg: format!(
                "{} (interpreter {}); install it with `{} -m pip install {package}` (in a source tree: `{SETUP_COMMAND}`, which installs the pinned versions of tools/setup/requirements.txt)",
                res.stderr.trim(),
                py.display(),
                py.display()
            ),
        });
    }
    Ok(res)
}
