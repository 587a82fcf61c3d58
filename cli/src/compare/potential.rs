//! Contact potential cost vs hull vertex count: SDRS `U_c` vs the IPC
//! baseline (Rust, same process, interleaved) vs ipc-toolkit (Python) when
//! it is installed in the project's `.venv`.

use super::results::{FrictionRow, PotentialPart, PotentialRow};
use super::suite::PotentialSpec;
use anyhow::{Context, Result};
use indicatif::ProgressBar;
use sdrs::contact::ContactParams;
use sdrs_cli::potential_bench::{
    cases_json, median, potential_cases, time_case, time_friction_case,
};
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

pub fn run(spec: &PotentialSpec, work: &Path, pb: &ProgressBar) -> Result<PotentialPart> {
    let t0 = Instant::now();
    let params = ContactParams::default();
    let cases = potential_cases(&spec.sizes, spec.pairs, spec.seed, &params)?;
    pb.set_length(2 * cases.len() as u64 + u64::from(spec.ipctk));
    let mut rows = Vec::new();
    for &m in &spec.sizes {
        let (mut ts, mut ti, mut r, mut nc, mut na) = (vec![], vec![], vec![], vec![], vec![]);
        for c in cases.iter().filter(|c| c.vertices == m) {
            let t = time_case(c, &params, spec.reps)?;
            ts.push(t.sdrs_us);
            ti.push(t.ipc_us);
            r.push(t.ipc_us / t.sdrs_us);
            nc.push(t.candidates as f64);
            na.push(t.active as f64);
            pb.inc(1);
        }
        rows.push(PotentialRow {
            vertices: m,
            sdrs_us: median(&mut ts),
            ipc_us: median(&mut ti),
            ratio: median(&mut r),
            candidates: median(&mut nc),
            active: median(&mut na),
        });
    }
    let mut friction = Vec::new();
    pb.set_message("friction");
    for &m in &spec.sizes {
        let (mut ts, mut ti, mut r, mut nc) = (vec![], vec![], vec![], vec![]);
        for c in cases.iter().filter(|c| c.vertices == m) {
            let t = time_friction_case(c, &params, spec.reps)?;
            ts.push(t.sdrs_us);
            ti.push(t.ipc_us);
            r.push(t.ipc_us / t.sdrs_us);
            nc.push(t.ipc_contacts as f64);
            pb.inc(1);
        }
        friction.push(FrictionRow {
            vertices: m,
            sdrs_us: median(&mut ts),
            ipc_us: median(&mut ti),
            ratio: median(&mut r),
            ipc_contacts: median(&mut nc),
        });
    }
    let (ipctk, ipctk_note) = if spec.ipctk {
        pb.set_message("ipc-toolkit");
        let r = ipctk(&cases_json(&cases), spec.reps, work);
        pb.inc(1);
        match r {
            Ok(t) => (Some(t), None),
            Err(e) => (None, Some(format!("{e:#}"))),
        }
    } else {
        (None, Some("not requested by the suite".into()))
    };
    Ok(PotentialPart {
        rows,
        friction,
        ipctk,
        ipctk_note,
        wall_seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Runs `tools/bench/bench_ipctk.py` on the cases; µs per vertex count.
fn ipctk(cases: &str, reps: usize, work: &Path) -> Result<BTreeMap<usize, f64>> {
    let py = crate::util::bundled(".venv/bin/python").context(
        "ipc-toolkit not timed: no project Python environment (run tools/setup/setup_python.sh)",
    )?;
    let script = crate::util::bundled("tools/bench/bench_ipctk.py")?;
    let file = work.join("ipctk_cases.json");
    std::fs::write(&file, cases).with_context(|| format!("writing {}", file.display()))?;
    let out = std::process::Command::new(py)
        .arg(script)
        .arg(&file)
        .args(["--reps", &reps.to_string(), "--json"])
        .output()
        .context("running tools/bench/bench_ipctk.py")?;
    if !out.status.success() {
        anyhow::bail!(
            "tools/bench/bench_ipctk.py failed: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    let v: BTreeMap<String, f64> = serde_json::from_slice(&out.stdout)
        .context("tools/bench/bench_ipctk.py printed no JSON table")?;
    v.into_iter()
        .map(|(k, t)| Ok((k.parse::<usize>()?, t)))
        .collect()
}
