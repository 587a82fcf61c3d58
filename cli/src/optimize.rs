//! `sdrs optimize`: co-design of a task (shape and controller, or the
//! controller alone with `--design off`).

use crate::util::progress;
use anyhow::{Result, bail};
use indicatif::ProgressStyle;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct OptimizeArgs {
    /// Task YAML (see README, "Co-design").
    pub task: PathBuf,
    /// Output directory: history.csv, convergence.svg, design.yaml,
    /// meshes/<robot>_<link>.obj, summary.json.
    #[arg(long)]
    pub out: PathBuf,
    /// Iterations (default: the task's `optimizer.iters`).
    #[arg(long)]
    pub iters: Option<usize>,
    /// `off` optimizes the controller alone (for comparison).
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    pub design: String,
    /// Write into a non-empty output directory.
    #[arg(long)]
    pub force: bool,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(a: OptimizeArgs) -> Result<()> {
    if a.out.exists()
        && std::fs::read_dir(&a.out)
            .map(|mut d| d.next().is_some())
            .unwrap_or(true)
        && !a.force
    {
        bail!(
            "{}: the output directory is not empty (use --force to write into it)",
            a.out.display()
        );
    }
    let problem = sdrs::optimize::Problem::load(&a.task, a.design == "on")?;
    // Nothing to optimize (`--design off` with a preset controller): the run
    // is one evaluation of the initial design.
    let iters = if problem.design.is_empty() && problem.controls.is_empty() {
        0
    } else {
        a.iters.unwrap_or(problem.task.optimizer.iters)
    };
    eprintln!(
        "{}: {} design and {} controller variables, horizon {} steps, {} iterations",
        a.task.display(),
        problem.design.len(),
        problem.controls.len(),
        problem.horizon,
        iters
    );
    let pb = progress(iters + 1, a.quiet);
    pb.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} iterations  {msg}",
        )
        .expect("static template"),
    );
    let d0 = problem.design.values(&problem.model);
    let c0 = problem.controls.values(&problem.controller);
    let outcome = sdrs::optimize::optimize(&problem, iters, |r, _| {
        pb.set_position(r.iter as u64 + 1);
        pb.set_message(format!("loss {:.4e} (best {:.4e})", r.loss, r.best_loss));
    })?;
    pb.finish_and_clear();
    sdrs::optimize::output::write_all(
        &a.out,
        &problem,
        &outcome,
        serde_json::json!({
            "design": a.design,
            "trajectories": 1 + problem.others.len(),
            "metrics": sdrs::optimize::metrics::summary(&problem, &d0, &c0, &outcome)?,
        }),
    )?;
    sdrs::optimize::metrics::write_scenes(&a.out, &problem, &outcome)?;
    eprintln!(
        "loss {:.4e} -> {:.4e} ({:.1}% lower) in {} iterations; outputs in {}",
        outcome.initial_loss,
        outcome.loss,
        100.0 * (1.0 - outcome.loss / outcome.initial_loss),
        iters,
        a.out.display()
    );
    Ok(())
}
