//! Helpers of the CLI's end-to-end tests: the core's shared test helpers
//! (`tests/common`) plus the `sdrs` binary this package builds.
#![allow(dead_code, unused_imports)]

#[path = "../../../tests/common/mod.rs"]
mod common;

pub use common::*;

pub mod browser;

/// The `sdrs` binary.
pub fn sdrs() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_sdrs"))
}

/// pybullet's robot files (`pybullet_data`, installed in `.venv` by
/// `tools/setup/setup_python.sh`).
pub fn pybullet_data() -> std::path::PathBuf {
    let out = python()
        .args([
            "-c",
            "import pybullet_data; print(pybullet_data.getDataPath())",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "pybullet_data missing: run tools/setup/setup_python.sh"
    );
    std::path::PathBuf::from(String::from_utf8_lossy(&out.stdout).trim())
}

/// Runs `cmd`, asserts it succeeded (the message shows the command and its
/// stderr) and returns its output.
pub fn run_ok(cmd: &mut std::process::Command) -> std::process::Output {
    let o = cmd.output().unwrap();
    assert!(
        o.status.success(),
        "{cmd:?} failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// Runs `sdrs simulate -q [extra…] --json DIR/summary.json --export DIR SCENE`,
/// asserts it succeeded and returns the summary.
pub fn simulate_export(
    dir: &std::path::Path,
    extra: &[&str],
    scene: &std::path::Path,
) -> serde_json::Value {
    run_ok(
        sdrs()
            .args(["simulate", "-q"])
            .args(extra)
            .arg("--json")
            .arg(dir.join("summary.json"))
            .arg("--export")
            .arg(dir)
            .arg(scene),
    );
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// The independent non-interpenetration check (`tools/check/check_separation.py`,
/// python-fcl) of an `sdrs simulate --export DIR` run: asserts that it
/// found every pair separated and returns its JSON report.
pub fn python_fcl_check(dir: &std::path::Path) -> serde_json::Value {
    let check = python()
        .arg(root().join("tools/check/check_separation.py"))
        .arg(dir)
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&check.stdout);
    assert!(
        check.status.success(),
        "checker found interpenetration or failed:\n{report}\n{}",
        String::from_utf8_lossy(&check.stderr)
    );
    serde_json::from_str(&report).unwrap()
}

/// Every file under `dir`, sorted, descending only into the folders for
/// which `descend` holds.
pub fn files_under(
    dir: &std::path::Path,
    descend: impl Fn(&std::path::Path) -> bool,
) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if !p.is_dir() {
                out.push(p);
            } else if descend(&p) {
                stack.push(p);
            }
        }
    }
    out.sort();
    out
}

/// `python tools/check/SCRIPT --sdrs <the CLI under test>`: a check script
/// of `tools/check/`, run by the project's Python with this build's `sdrs`;
/// callers add the script's own arguments.
pub fn check_script(script: &str) -> std::process::Command {
    let mut cmd = python();
    cmd.arg(root().join("tools/check").join(script))
        .arg("--sdrs")
        .arg(env!("CARGO_BIN_EXE_sdrs"));
    cmd
}

/// Runs the calibration check script `tools/check/<script>` with `args`, this
/// package's `sdrs` and `--out dir` in the project's Python; prints its
/// output and returns its exit success and the cases of its
/// `summary.json`.
pub fn calibration_check(
    script: &str,
    args: &[&str],
    dir: &std::path::Path,
) -> (bool, Vec<serde_json::Value>) {
    calibration_check_with(check_script(script).args(args), dir)
}

/// [`calibration_check`] of a [`check_script`] command the caller has
/// given its arguments (and environment): adds `--out dir`, runs it, prints
/// its output and returns its exit success and the cases of its
/// `summary.json`.
pub fn calibration_check_with(
    cmd: &mut std::process::Command,
    dir: &std::path::Path,
) -> (bool, Vec<serde_json::Value>) {
    let o = cmd.arg("--out").arg(dir).output().unwrap();
    eprintln!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    (o.status.success(), summary.as_array().unwrap().clone())
}
