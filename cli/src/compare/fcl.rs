//! The independent non-interpenetration check: `tools/check/check_separation.py`
//! (python-fcl) on an exported run (`hulls.json` + `poses.csv`).

use anyhow::{Context, Result, bail};
use std::path::Path;

/// python-fcl's minimum distance over every interacting hull pair and step
/// (`None` when no pair came near; ≤ 0 when it found touching or
/// overlapping hulls). Fails when the checker cannot run.
pub fn check(dir: &Path) -> Result<Option<f64>> {
    let py = crate::util::bundled(".venv/bin/python").context(
        "python-fcl not run: no project Python environment (run tools/setup/setup_python.sh)",
    )?;
    let script = crate::util::bundled("tools/check/check_separation.py")?;
    let out = std::process::Command::new(py)
        .arg(script)
        .arg(dir)
        .output()
        .context("running tools/check/check_separation.py")?;
    let report = String::from_utf8_lossy(&out.stdout);
    match out.status.code() {
        Some(0 | 1) => {}
        _ => bail!(
            "tools/check/check_separation.py failed on {}: {}",
            dir.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        ),
    }
    let v: serde_json::Value =
        serde_json::from_str(&report).context("tools/check/check_separation.py printed no JSON")?;
    Ok(v["min_distance"].as_f64())
}
