//! The independent non-interpenetration check: `tools/check/check_separation.py`
//! (python-fcl) on exported runs (`hulls.json` + `poses.csv`).

use anyhow::{Context, Result, anyhow, bail};
use std::path::PathBuf;

/// python-fcl's minimum distance over every interacting hull pair and step
/// of each export in `dirs` (`None` when no pair came near; ≤ 0 when it
/// found touching or overlapping hulls), checked in one Python process (a
/// start, mostly the imports, costs about as much as checking a 400-step
/// four-chain run). Each entry fails on its own when its export could not
/// be read; every entry fails when the checker cannot run.
pub fn check_all(dirs: &[PathBuf]) -> Vec<Result<Option<f64>>> {
    match run(dirs) {
        Ok(reports) => reports
            .iter()
            .zip(dirs)
            .map(|(r, d)| match r.get("error") {
                Some(e) => Err(anyhow!(
                    "tools/check/check_separation.py failed on {}: {}",
                    d.display(),
                    e.as_str().unwrap_or_default()
                )),
                None => Ok(r["min_distance"].as_f64()),
            })
            .collect(),
        Err(e) => dirs.iter().map(|_| Err(anyhow!("{e:#}"))).collect(),
    }
}

/// The checker's report per directory (its JSON object, or list for
/// several directories).
fn run(dirs: &[PathBuf]) -> Result<Vec<serde_json::Value>> {
    let py = crate::util::bundled(".venv/bin/python").context(
        "python-fcl not run: no project Python environment (run tools/setup/setup_python.sh)",
    )?;
    let script = crate::util::bundled("tools/check/check_separation.py")?;
    let out = std::process::Command::new(py)
        .arg(script)
        .args(dirs)
        .output()
        .context("running tools/check/check_separation.py")?;
    let report = String::from_utf8_lossy(&out.stdout);
    let printed: Result<serde_json::Value, _> = serde_json::from_str(&report);
    match (out.status.code(), printed) {
        (Some(0..=2), Ok(serde_json::Value::Array(v))) if v.len() == dirs.len() => Ok(v),
        (Some(0..=2), Ok(v)) if dirs.len() == 1 && v.is_object() => Ok(vec![v]),
        _ => bail!(
            "tools/check/check_separation.py failed: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ),
    }
}
