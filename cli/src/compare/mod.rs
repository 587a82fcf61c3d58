//! `sdrs compare`: SDRS and the mesh-based IPC baseline side by side on the
//! paper's benchmarks — one report (`report.html`, `report.md`,
//! `results.json`, a CSV per table) and a regression gate (`--check`).
//!
//! Each benchmark's result is kept in `DIR/parts/<name>.json` together with
//! the suite entry that produced it: re-running into the same directory
//! skips finished benchmarks whose entry is unchanged (`--force` re-runs
//! everything). A co-design benchmark also keeps each finished method
//! (co-design, controller-only, each cage) and its gradient check in
//! `DIR/parts/codesign_<name>/`, so a multi-hour paper run interrupted in
//! its middle loses at most the method it was running.

mod chains;
mod codesign;
mod fcl;
mod gate;
mod potential;
mod report;
mod results;
mod suite;

use crate::util::progress;
use anyhow::{Context, Result, bail};
use indicatif::ProgressStyle;
use results::Results;
use sdrs::output::write_atomic;
use serde::Serialize;
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct CompareArgs {
    /// `quick` (CI-sized, minutes), `paper` (the full reproduction), or a
    /// suite YAML file (see robots/compare/quick.yaml).
    #[arg(long, default_value = "quick")]
    pub suite: String,
    /// Output directory (created; re-running into it resumes).
    #[arg(long)]
    pub out: PathBuf,
    /// Re-run finished benchmarks too.
    #[arg(long)]
    pub force: bool,
    /// Regression gate: compare against this `results.json`; exit non-zero
    /// naming each metric that regressed beyond its tolerance.
    #[arg(long)]
    pub check: Option<PathBuf>,
    /// Tolerance YAML for `--check` (defaults documented in the README).
    #[arg(long, requires = "check")]
    pub tolerance: Option<PathBuf>,
    /// No progress bars.
    #[arg(long, short)]
    pub quiet: bool,
    /// Run nothing: write the report from what an earlier (possibly still
    /// running or interrupted) run into `--out` has finished — whole
    /// benchmarks, and the finished methods of a co-design benchmark; the
    /// rest is listed as not finished.
    #[arg(long, conflicts_with = "force")]
    pub report_only: bool,
    /// Run nothing: write the report (`report.md`, `report.html`, tables,
    /// plots) into `--out` from this `results.json` of an earlier run. The
    /// results page `docs/results/` is made this way
    /// (`tools/gen/render_results.sh`), never edited by hand.
    #[arg(long, value_name = "RESULTS_JSON", conflicts_with_all = ["force", "report_only", "check"])]
    pub render: Option<PathBuf>,
}

/// `--render`: the report of a stored `results.json`, written beside the
/// output files of `report::write` only (nothing else in `out` is touched).
fn render(results: &Path, out: &Path) -> Result<()> {
    let r: Results = serde_json::from_str(
        &std::fs::read_to_string(results)
            .with_context(|| format!("{}: cannot read the results", results.display()))?,
    )
    .with_context(|| {
        format!(
            "{}: not a results.json of `sdrs compare`",
            results.display()
        )
    })?;
    if out.is_file() {
        bail!("{}: the output must be a directory", out.display());
    }
    std::fs::create_dir_all(out)
        .with_context(|| format!("{}: cannot create the output directory", out.display()))?;
    // The optimized-shape pictures are files of the run (`plots/shapes_*.svg`),
    // not results: carried over from beside the results when they are there.
    let from = results.parent().unwrap_or(Path::new("."));
    for f in r.codesign.iter().filter_map(|b| b.shapes_svg.as_ref()) {
        let (src, dst) = (from.join(f), out.join(f));
        if src.is_file() && !dst.exists() {
            if let Some(d) = dst.parent() {
                std::fs::create_dir_all(d)?;
            }
            std::fs::copy(&src, &dst)
                .with_context(|| format!("{}: cannot copy to {}", src.display(), dst.display()))?;
        }
    }
    report::write(out, &r, None)?;
    eprintln!(
        "report: {} (from {})",
        out.join("report.md").display(),
        results.display()
    );
    Ok(())
}

/// A finished benchmark as stored in `parts/`.
#[derive(serde::Serialize, serde::Deserialize)]
struct Part<S, R> {
    spec: S,
    result: R,
}

/// The result stored in `file` if it was produced by the same `spec`.
fn load_part<S, R>(file: &Path, spec: &S) -> Result<Option<R>>
where
    S: Serialize,
    R: DeserializeOwned,
{
    if let Ok(text) = std::fs::read_to_string(file)
        && let Ok(p) = serde_json::from_str::<Part<serde_json::Value, R>>(&text)
        && p.spec == serde_json::to_value(spec)?
    {
        return Ok(Some(p.result));
    }
    Ok(None)
}

/// Stores `result` with the `spec` that produced it (atomically: an
/// interrupted run never leaves a half-written part).
fn store_part<S: Serialize, R: Serialize>(file: &Path, spec: &S, result: &R) -> Result<()> {
    let part = Part { spec, result };
    write_atomic(file, serde_json::to_string_pretty(&part)?.as_bytes())?;
    Ok(())
}

/// Runs `f` unless `parts/<name>.json` holds a result for the same `spec`.
fn resumable<S, R>(
    dir: &Path,
    name: &str,
    spec: &S,
    force: bool,
    quiet: bool,
    f: impl FnOnce(&indicatif::ProgressBar) -> Result<R>,
) -> Result<R>
where
    S: Serialize + DeserializeOwned,
    R: Serialize + DeserializeOwned,
{
    let file = dir.join("parts").join(format!("{name}.json"));
    if !force && let Some(r) = load_part(&file, spec)? {
        eprintln!("{name}: finished earlier, kept (--force re-runs it)");
        return Ok(r);
    }
    let pb = progress(1, quiet);
    pb.set_style(
        ProgressStyle::with_template(&format!(
            "{{spinner}} {name:<28} [{{elapsed_precise}}] {{bar:30}} {{pos}}/{{len}} {{msg}}"
        ))
        .expect("static template"),
    );
    let r = f(&pb)?;
    pb.finish_with_message("done");
    store_part(&file, spec, &r)?;
    Ok(r)
}

/// `--report-only`: the finished parts of the run in `out` (nothing runs).
fn finished_only(suite: &suite::Suite, base: &Path, out: &Path, r: &mut Results) -> Result<()> {
    let parts = out.join("parts");
    let unfinished = |what: &str| format!("{what}: not finished yet (`--report-only`)");
    if let Some(s) = &suite.potential {
        r.potential = load_part(&parts.join("potential.json"), s)?;
        if r.potential.is_none() {
            r.not_measured.push(unfinished("contact potential cost"));
        }
    }
    if let Some(s) = &suite.chains {
        r.chains = load_part(&parts.join("chains.json"), s)?;
        if r.chains.is_none() {
            r.not_measured.push(unfinished("four rotating chains"));
        }
    }
    for s in &suite.codesign {
        let whole = parts.join(format!("codesign_{}.json", s.name));
        if let Some(c) = load_part(&whole, s)? {
            r.codesign.push(c);
            continue;
        }
        let (part, missing) = codesign::finished(s, base, out)?;
        if !missing.is_empty() {
            r.not_measured.push(unfinished(&format!(
                "co-design {}: {}",
                s.name,
                missing.join(", ")
            )));
        }
        r.codesign.extend(part);
    }
    Ok(())
}

/// `sdrs compare`: the suite's benchmarks (each kept from an earlier run
/// when its part is there), `results.json`, the report, and the regression
/// gate against `--check`.
pub fn run(a: CompareArgs) -> Result<()> {
    if let Some(results) = &a.render {
        return render(results, &a.out);
    }
    if cfg!(debug_assertions) {
        eprintln!("warning: debug build; timings are meaningless (use `cargo run --release`)");
    }
    let (suite, base) = suite::Suite::load(&a.suite)?;
    let tol = match &a.tolerance {
        Some(t) => gate::Tolerances::load(t)?,
        None => gate::Tolerances::default(),
    };
    let baseline = a.check.as_deref().map(load_baseline).transpose()?;
    let work = prepare_out(&a)?;
    let r = measure(&a, &suite, &base, &work)?;
    write_atomic(
        &a.out.join("results.json"),
        serde_json::to_string_pretty(&r)?.as_bytes(),
    )?;
    let verdicts = baseline.as_ref().map(|b| gate::check(b, &r, &tol));
    if let Some(v) = &verdicts {
        write_atomic(
            &a.out.join("gate.json"),
            serde_json::to_string_pretty(v)?.as_bytes(),
        )?;
    }
    report::write(&a.out, &r, verdicts.as_deref())?;
    eprintln!(
        "report: {} (report.md and results.json beside it)",
        a.out.join("report.html").display()
    );
    match verdicts {
        Some(v) => gate_outcome(&v),
        None => Ok(()),
    }
}

/// The `--check` baseline: a `results.json` of an earlier run.
fn load_baseline(p: &Path) -> Result<Results> {
    serde_json::from_str(
        &std::fs::read_to_string(p)
            .with_context(|| format!("{}: cannot read the baseline", p.display()))?,
    )
    .with_context(|| format!("{}: not a results.json of `sdrs compare`", p.display()))
}

/// Checks `--out` (a directory, empty or an earlier run's; an earlier run's
/// with `--report-only`) and creates its `parts/` and `work/`; returns
/// `work/`.
fn prepare_out(a: &CompareArgs) -> Result<PathBuf> {
    if a.out.is_file() {
        bail!("{}: the output must be a directory", a.out.display());
    }
    if a.report_only && !a.out.join("parts").is_dir() {
        bail!(
            "{}: --report-only needs the output directory of an earlier `sdrs compare` run",
            a.out.display()
        );
    }
    if a.out.exists()
        && !a.out.join("parts").is_dir()
        && std::fs::read_dir(&a.out)
            .map(|mut d| d.next().is_some())
            .unwrap_or(true)
    {
        bail!(
            "{}: the directory is not empty and holds no earlier `sdrs compare` run; choose another --out",
            a.out.display()
        );
    }
    let work = a.out.join("work");
    // `parts/` marks the folder as a compare run from the start, so a run
    // that fails half-way (e.g. a task that does not load) can be re-run
    // into the same --out once the input is fixed.
    for d in [&work, &a.out.join("parts")] {
        std::fs::create_dir_all(d)
            .with_context(|| format!("{}: cannot create the output directory", a.out.display()))?;
    }
    Ok(work)
}

/// Every benchmark of the suite (with `--report-only`, what an earlier run
/// finished), and what the suite does not measure.
fn measure(a: &CompareArgs, suite: &suite::Suite, base: &Path, work: &Path) -> Result<Results> {
    let mut r = Results {
        suite: suite.suite.clone(),
        threads: rayon::current_num_threads(),
        ..Default::default()
    };
    if a.report_only {
        finished_only(suite, base, &a.out, &mut r)?;
    } else {
        match &suite.potential {
            Some(s) => {
                r.potential = Some(resumable(&a.out, "potential", s, a.force, a.quiet, |pb| {
                    potential::run(s, work, pb)
                })?);
            }
            None => r
                .not_measured
                .push("contact potential cost (not in this suite)".into()),
        }
        match &suite.chains {
            Some(s) => {
                r.chains = Some(resumable(&a.out, "chains", s, a.force, a.quiet, |pb| {
                    chains::run(s, base, work, pb)
                })?);
            }
            None => r
                .not_measured
                .push("four rotating chains (not in this suite)".into()),
        }
        for s in &suite.codesign {
            r.codesign.push(resumable(
                &a.out,
                &format!("codesign_{}", s.name),
                s,
                a.force,
                a.quiet,
                |pb| codesign::run(s, base, &a.out, a.force, pb),
            )?);
        }
    }
    if suite.codesign.iter().all(|s| s.cages.is_empty()) {
        r.not_measured.push(
            "mesh baseline with cage deformation (Xu et al. 2021): not in this suite (`cages:` of a co-design entry)".into(),
        );
    }
    Ok(r)
}

/// The regression gate's outcome: an error listing every regressed metric.
fn gate_outcome(v: &[gate::Verdict]) -> Result<()> {
    let bad: Vec<String> = v
        .iter()
        .filter(|v| v.regressed)
        .map(|v| {
            format!(
                "{}: baseline {}, now {}, limit {} ({})",
                v.metric,
                v.baseline.map_or("—".into(), |x| format!("{x:.4e}")),
                v.now.map_or("missing".into(), |x| format!("{x:.4e}")),
                v.limit.map_or("—".into(), |x| format!("{x:.4e}")),
                v.note
            )
        })
        .collect();
    if !bad.is_empty() {
        bail!(
            "regression gate failed: {} metric(s) regressed:\n  {}",
            bad.len(),
            bad.join("\n  ")
        );
    }
    eprintln!(
        "regression gate passed: {} metrics within tolerance",
        v.len()
    );
    Ok(())
}
