//! `sdrs plot DIR…`: the convergence of several `sdrs optimize` runs on one
//! plot (best loss per iteration, from each run's `history.csv`), labelled
//! by each run's task and mode (co-design / controller-only, from its
//! `summary.json`), e.g. co-design against controller-only.

use anyhow::{Context, Result, bail};
use sdrs::output::write_atomic;
use sdrs_cli::svg::{Axes, Series, line_plot};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct PlotArgs {
    /// Output directories of `sdrs optimize` (each with history.csv).
    #[arg(required = true, num_args = 1..)]
    pub runs: Vec<PathBuf>,
    /// The SVG to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Plot title (default: the task names).
    #[arg(long)]
    pub title: Option<String>,
    /// Linear loss axis (default: logarithmic when every loss is positive).
    #[arg(long)]
    pub linear: bool,
}

/// One run: its label, task name and best loss per iteration.
struct Run {
    label: String,
    task: String,
    points: Vec<(f64, f64)>,
}

fn load(dir: &Path) -> Result<Run> {
    let file = dir.join("history.csv");
    let mut rd = csv::Reader::from_path(&file).with_context(|| {
        format!(
            "{}: cannot read (is this an `sdrs optimize` output?)",
            file.display()
        )
    })?;
    let h = rd.headers()?.clone();
    let col = |name: &str| {
        h.iter()
            .position(|c| c == name)
            .with_context(|| format!("{}: no `{name}` column", file.display()))
    };
    let (it, best) = (col("iteration")?, col("best_loss")?);
    let mut pts = Vec::new();
    for (k, row) in rd.records().enumerate() {
        let row = row.with_context(|| format!("{}: row {}", file.display(), k + 2))?;
        let num = |i: usize| -> Result<f64> {
            row[i].parse::<f64>().with_context(|| {
                format!(
                    "{}: row {}: `{}` is not a number",
                    file.display(),
                    k + 2,
                    &row[i]
                )
            })
        };
        pts.push((num(it)?, num(best)?));
    }
    if pts.is_empty() {
        bail!("{}: no iterations", file.display());
    }
    let summary: Option<serde_json::Value> = std::fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok());
    let task = summary
        .as_ref()
        .and_then(|s| {
            s["task"].as_str().map(|t| {
                Path::new(t)
                    .parent()
                    .and_then(|p| p.file_name())
                    .map_or(t.to_string(), |n| n.to_string_lossy().into_owned())
            })
        })
        .unwrap_or_else(|| dir.display().to_string());
    let mode = match summary.as_ref().map(|s| s["extra"]["design"].as_str()) {
        Some(Some("off")) => "controller-only",
        Some(Some("on")) => "co-design",
        _ => "run",
    };
    Ok(Run {
        label: format!("{task}: {mode}"),
        task,
        points: pts,
    })
}

pub fn run(a: PlotArgs) -> Result<()> {
    if a.out.extension().and_then(|e| e.to_str()) != Some("svg") {
        bail!(
            "{}: the plot is written as SVG; name it *.svg",
            a.out.display()
        );
    }
    let mut series = Vec::new();
    let mut tasks = Vec::new();
    for d in &a.runs {
        let Run {
            label,
            task,
            points,
        } = load(d)?;
        if !tasks.contains(&task) {
            tasks.push(task);
        }
        series.push(Series {
            label,
            points,
            dashed: false,
        });
    }
    let log = !a.linear && series.iter().all(|s| s.points.iter().all(|p| p.1 > 0.0));
    let title = a
        .title
        .clone()
        .unwrap_or_else(|| format!("{}: best loss per iteration", tasks.join(", ")));
    let svg = line_plot(
        &Axes {
            title: &title,
            x: "iteration",
            y: "best task loss",
            log_x: false,
            log_y: log,
        },
        &series,
    )?;
    write_atomic(&a.out, svg.as_bytes())?;
    eprintln!("{}: {} run(s) plotted", a.out.display(), series.len());
    Ok(())
}
