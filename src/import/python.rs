//! Finding and running the project's Python helpers (`tools/*.py`).
//!
//! Interpreter: `$SDRS_PYTHON` if set, else the project venv
//! `<root>/.venv/bin/python` if it exists, else `python3` on the `PATH`.
//! `<root>` is `$SDRS_ROOT` if set, else the source tree this binary was
//! built from. `bash tools/setup_python.sh` creates the venv.

use super::error::ImportError;
use std::path::PathBuf;
use std::process::Command;

/// The command that installs the Python helpers' packages.
pub const SETUP_COMMAND: &str = "bash tools/setup_python.sh";

/// Exit code the helpers use when a package is missing.
pub const EXIT_MISSING_PACKAGE: i32 = 3;

/// Project root (holds `tools/` and `.venv/`).
pub fn project_root() -> PathBuf {
    std::env::var_os("SDRS_ROOT")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")))
}

/// The Python interpreter to use.
pub fn interpreter() -> PathBuf {
    if let Some(p) = std::env::var_os("SDRS_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = project_root().join(".venv/bin/python");
    if venv.exists() {
        venv
    } else {
        PathBuf::from("python3")
    }
}

/// Path of a helper script in `tools/`.
pub fn tool(name: &str) -> PathBuf {
    project_root().join("tools").join(name)
}

/// Output of a helper run.
pub struct ToolOutput {
    pub stdout: String,
    pub stderr: String,
    pub code: Option<i32>,
}

/// Runs `tools/<script> args…` with the project interpreter. Fails with the
/// setup command when the interpreter or a package is missing.
pub fn run_tool(script: &str, args: &[std::ffi::OsString]) -> Result<ToolOutput, ImportError> {
    let py = interpreter();
    let path = tool(script);
    if !path.is_file() {
        return Err(ImportError::Python {
            msg: format!(
                "helper {} not found (set SDRS_ROOT to the sdrs source tree)",
                path.display()
            ),
        });
    }
    let mut cmd = Command::new(&py);
    cmd.arg(&path).args(args);
    let out = super::child::spawn_output(cmd).map_err(|e| ImportError::Python {
        msg: format!(
            "cannot run Python ({}): {e}; install the helpers' environment with `{SETUP_COMMAND}` (from the sdrs source tree)",
            py.display()
        ),
    })?;
    let res = ToolOutput {
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        code: out.status.code(),
    };
    if res.code == Some(EXIT_MISSING_PACKAGE) {
        return Err(ImportError::Python {
            msg: format!(
                "{} (interpreter {}); install the packages with `{SETUP_COMMAND}` (or `{} -m pip install -r tools/requirements.txt`)",
                res.stderr.trim(),
                py.display(),
                py.display()
            ),
        });
    }
    Ok(res)
}
