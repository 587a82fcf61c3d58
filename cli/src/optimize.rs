//! `sdrs optimize`: co-design of a task (shape and controller, or the
//! controller alone with `--design off`).

use crate::util::progress;
use anyhow::{Context, Result, bail};
use indicatif::ProgressStyle;
use sdrs::optimize::checkpoint;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct OptimizeArgs {
    /// Task YAML (see README, "Co-design").
    pub task: PathBuf,
    /// Output directory: history.csv, convergence.svg, design.yaml,
    /// meshes/<robot>_<link>.obj, shapes.svg, robot.svg, report.html,
    /// playback/ (for `sdrs view`), summary.json, checkpoint.json, scenes/,
    /// and failed_trials/iteration_<k>/scenes/ when trial points could not be
    /// simulated (the first three; `sdrs simulate` reproduces each).
    #[arg(long, required_unless_present = "resume")]
    pub out: Option<PathBuf>,
    /// Continue the run whose outputs (and checkpoint.json) are in this
    /// directory, up to the total iteration count (`--iters` or the task's);
    /// the outputs are rewritten there. Same task, scene, --design and
    /// --seed as the interrupted run (checked).
    #[arg(long, conflicts_with = "out")]
    pub resume: Option<PathBuf>,
    /// Seed of the run's randomness (`optimizer.init_noise`, `optimizer.design_init_noise`; with `--design off` the latter perturbs the fixed robot as the co-design run with this seed starts).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Iterations in total (default: the task's `optimizer.iters`); a trust-region run ends earlier, at the same result, once its trials round to the iterate (summary.json `converged`).
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
    #[command(flatten)]
    pub contact: crate::contact_model::ContactArgs,
    /// Cage-based design (the mesh baseline with `--contact ipc`; with the
    /// SDRS contact the cage deforms the hulls): the vertices of an
    /// automatic box cage around each `design.vertices` link become the
    /// design, the hull vertices fixed mean-value combinations of them.
    /// `coarse` (26 cage vertices), `fine` (98) or `k` segments per box
    /// edge (6k² + 2 vertices).
    #[arg(long)]
    pub cage: Option<String>,
}

pub fn run(a: OptimizeArgs) -> Result<()> {
    let out = output_dir(&a)?;
    let run = prepare(&a, &out)?;
    std::fs::create_dir_all(&out).with_context(|| format!("{}: cannot create", out.display()))?;
    announce(&a, &run);
    let resumed_from = run.resume.as_ref().map(|s| s.iter);
    let Prepared {
        problem,
        metrics,
        key,
        resume,
        iters,
    } = run;
    let (outcome, designs) = iterate(&a, &out, &problem, &key, resume, iters)?;
    let (d0, c0) = sdrs::optimize::start(&problem, a.seed);
    // The grasp, topology and (with a `metrics:` section) locomotion
    // metrics side by side under `extra.metrics`.
    let metrics_json = sdrs::optimize::metric::summarize(&problem, &metrics, (&d0, &c0), &outcome)?;
    write_summary(&a, &out, &problem, &outcome, resumed_from, &metrics_json)?;
    write_figures(
        &out,
        &problem,
        a.design == "on",
        (&d0, &c0),
        &outcome,
        &designs,
    )?;
    report_end(&out, &outcome, &metrics_json);
    if let Some(why) = &outcome.stopped {
        anyhow::bail!(
            "the run {why}; the outputs in {} are for the iterations that ran (`--resume` continues from there with the next iteration's step)",
            out.display()
        );
    }
    Ok(())
}

/// The output directory (`--resume`'s or `--out`), refused when it is not
/// empty for a new run without `--force`.
fn output_dir(a: &OptimizeArgs) -> Result<PathBuf> {
    let out = a
        .resume
        .clone()
        .or(a.out.clone())
        .expect("clap: --out or --resume");
    if a.resume.is_none()
        && out.exists()
        && std::fs::read_dir(&out)
            .map(|mut d| d.next().is_some())
            .unwrap_or(true)
        && !a.force
    {
        bail!(
            "{}: the output directory is not empty (use --force to write into it, or --resume to continue its run)",
            out.display()
        );
    }
    Ok(out)
}

/// The loaded task and what the run needs before its first iteration.
struct Prepared {
    problem: sdrs::optimize::Problem,
    metrics: Vec<Box<dyn sdrs::optimize::metric::Metric>>,
    key: checkpoint::RunKey,
    /// The checkpoint to continue from (`--resume`).
    resume: Option<checkpoint::State>,
    /// Iterations in total.
    iters: usize,
}

/// Loads the task (contact model and cage applied), its metrics, the run's
/// checkpoint key and, with `--resume`, the checkpoint (checked against the
/// iteration count).
fn prepare(a: &OptimizeArgs, out: &std::path::Path) -> Result<Prepared> {
    let design_on = a.design == "on";
    let mut problem = sdrs::optimize::Problem::load_for_seed(&a.task, design_on, a.seed)?;
    crate::contact_model::configure_problem(
        &mut problem,
        &a.contact,
        a.cage.as_deref(),
        design_on,
    )?;
    let metrics = sdrs::optimize::metric::task_metrics(&problem)?;
    let key = checkpoint::RunKey::new(&a.task, &problem.first().scene.source, design_on, a.seed)
        .with_context(|| format!("{}: cannot hash the task and scene", a.task.display()))?;
    let resume = match &a.resume {
        Some(dir) => Some(checkpoint::load(dir, &key)?),
        None => None,
    };
    // Nothing to optimize (`--design off` with a preset controller): the run
    // is one evaluation of the initial design.
    let iters = if problem.design.is_empty() && problem.controls.is_empty() {
        0
    } else {
        a.iters.unwrap_or(problem.task.optimizer.iters)
    };
    if let Some(s) = &resume
        && s.iter > iters
    {
        bail!(
            "{}: the checkpoint is at iteration {}, beyond the {iters} iterations asked for",
            out.display(),
            s.iter
        );
    }
    Ok(Prepared {
        problem,
        metrics,
        key,
        resume,
        iters,
    })
}

/// The run's first line: variables, horizon, iterations, resume point.
fn announce(a: &OptimizeArgs, run: &Prepared) {
    let problem = &run.problem;
    eprintln!(
        "{}: {} design and {} controller variables, horizon {} steps, {} iterations{}",
        a.task.display(),
        problem.design.len(),
        problem.controls.len(),
        problem.first().horizon,
        run.iters,
        run.resume
            .as_ref()
            .map(|s| format!(" (resuming after iteration {})", s.iter))
            .unwrap_or_default()
    );
}

/// The iterations, with a progress bar and a checkpoint after each; also
/// every iteration's design, for the viewer's design-at-iteration slider
/// (after a resume: the iterations of this session).
fn iterate(
    a: &OptimizeArgs,
    out: &std::path::Path,
    problem: &sdrs::optimize::Problem,
    key: &checkpoint::RunKey,
    resume: Option<checkpoint::State>,
    iters: usize,
) -> Result<(
    sdrs::optimize::Outcome,
    Vec<sdrs::output::codesign::IterDesign>,
)> {
    let pb = progress(iters + 1, a.quiet);
    pb.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} iterations  {msg}",
        )
        .expect("static template"),
    );
    let opts = sdrs::optimize::RunOptions {
        seed: a.seed,
        resume,
    };
    let mut designs: Vec<sdrs::output::codesign::IterDesign> = Vec::new();
    let outcome = sdrs::optimize::optimize_with(
        problem,
        iters,
        &opts,
        |r, d| {
            designs.push((r.iter, r.loss, d.clone()));
            pb.set_position(r.iter as u64 + 1);
            pb.set_message(format!("loss {:.4e} (best {:.4e})", r.loss, r.best_loss));
        },
        |state| checkpoint::save(out, key, state),
    )?;
    pb.finish_and_clear();
    Ok((outcome, designs))
}

/// `summary.json`, `history.csv`, `design.yaml` and the meshes
/// ([`sdrs::optimize::output::write_all`]), with the run's settings and
/// metrics.
fn write_summary(
    a: &OptimizeArgs,
    out: &std::path::Path,
    problem: &sdrs::optimize::Problem,
    outcome: &sdrs::optimize::Outcome,
    resumed_from: Option<usize>,
    metrics_json: &serde_json::Value,
) -> Result<()> {
    sdrs::optimize::output::write_all(
        out,
        problem,
        outcome,
        serde_json::json!({
            "design": a.design,
            "seed": a.seed,
            "resumed_from_iteration": resumed_from,
            // Which iterate `final_loss`, the design and the metrics are.
            "result": {
                "iterate": problem.task.optimizer.result,
                "iteration": outcome.iter,
            },
            "trajectories": problem.trajectories.len(),
            "metrics": metrics_json,
            // Why the run ended before its last iteration, else null.
            "stopped": outcome.stopped,
            // A trust-region run that ended early at a converged iterate
            // (no later trial could move it), else null.
            "converged": outcome.converged,
            // `optimizer.plateau`: the iterations after which the run
            // returned to its best iterate (empty without the option).
            "plateau_returns": outcome.plateau_returns,
            // Trial points that could not be simulated (this session's;
            // each counted as a rejected trust-region step).
            "failed_trials": outcome.failed_trials,
        }),
    )?;
    Ok(())
}

/// `convergence.svg`, the scenes (`scenes/`, and `failed_trials/` for the
/// kept failed trials: `sdrs simulate` reproduces each), `shapes.svg`, and
/// the pictures ([`write_pictures`]; a failure there is a warning).
fn write_figures(
    out: &std::path::Path,
    problem: &sdrs::optimize::Problem,
    design_on: bool,
    (d0, c0): (&nalgebra::DVector<f64>, &nalgebra::DVector<f64>),
    outcome: &sdrs::optimize::Outcome,
    designs: &[sdrs::output::codesign::IterDesign],
) -> Result<()> {
    let label = sdrs::optimize::output::run_label(problem, design_on);
    let convergence = sdrs_cli::svg::convergence_svg(
        &format!("{label}, best loss per iteration"),
        &[(&label, &outcome.history)],
    )?;
    sdrs::output::write_atomic(&out.join("convergence.svg"), convergence.as_bytes())?;
    sdrs::optimize::grasp_metrics::write_scenes(out, problem, outcome)?;
    for t in &outcome.failed_trials.first {
        let dir = out
            .join("failed_trials")
            .join(format!("iteration_{}", t.iteration));
        sdrs::optimize::grasp_metrics::write_scenes_at(
            &dir,
            problem,
            (&t.design, &t.controller),
            &format!(
                "the trial design of iteration {} (it could not be simulated)",
                t.iteration
            ),
        )?;
    }
    let shapes = sdrs::output::codesign::initial_vs_optimized_svg(problem, d0, &outcome.design);
    if let Some(svg) = &shapes {
        sdrs::output::write_atomic(&out.join("shapes.svg"), svg.as_bytes())?;
    }
    // The main outputs are written: a failure here (a rollout) is a warning.
    if let Err(e) = write_pictures(out, problem, (d0, c0), outcome, designs, shapes.as_deref()) {
        eprintln!("warning: report.html, robot.svg and playback/ not written: {e:#}");
    }
    Ok(())
}

/// The closing lines: the loss, the failed trials, the locomotion metrics.
fn report_end(
    out: &std::path::Path,
    outcome: &sdrs::optimize::Outcome,
    metrics_json: &serde_json::Value,
) {
    eprintln!(
        "loss {:.4e} -> {:.4e} ({:.1}% lower) in {} iterations; outputs in {}",
        outcome.initial_loss,
        outcome.loss,
        100.0 * (1.0 - outcome.loss / outcome.initial_loss),
        outcome.history.last().map_or(0, |r| r.iter),
        out.display()
    );
    if let Some(why) = &outcome.converged {
        eprintln!("{why} (summary.json `converged`)");
    }
    let failed = &outcome.failed_trials;
    if let Some(sdrs::optimize::FailedTrial {
        iteration: it,
        error: e,
        ..
    }) = failed.first.first()
    {
        eprintln!(
            "warning: {} trial point(s) could not be simulated and counted as rejected steps \
             (summary.json `failed_trials`; the first {} as scenes in {}); the first, at \
             iteration {it}: {e}",
            failed.count,
            failed.first.len(),
            out.join("failed_trials").display()
        );
    }
    if let Some(m) = metrics_json.get("final") {
        eprintln!(
            "distance {:.3} m (initial {:.3}), upright at H: {}, first fall: {}",
            m["distance"].as_f64().unwrap_or(f64::NAN),
            metrics_json["initial"]["distance"]
                .as_f64()
                .unwrap_or(f64::NAN),
            m["upright_at_horizon"],
            m["first_fall_time"]
        );
    }
}

/// `playback/` (the rollouts of the initial and optimized designs, for
/// `sdrs view`), `robot.svg` and `report.html` (the convergence plot next
/// to the stills).
fn write_pictures(
    out: &std::path::Path,
    problem: &sdrs::optimize::Problem,
    (d0, c0): (&nalgebra::DVector<f64>, &nalgebra::DVector<f64>),
    outcome: &sdrs::optimize::Outcome,
    designs: &[sdrs::output::codesign::IterDesign],
    shapes: Option<&str>,
) -> Result<()> {
    use sdrs::output::codesign as pb;
    let initial = pb::rollout(problem, d0, c0).context("rollout of the initial design")?;
    let optimized = pb::rollout(problem, &outcome.design, &outcome.controller)
        .context("rollout of the optimized design")?;
    pb::write_playback(out, problem, &initial, &optimized, designs)?;
    let robot = pb::robot_still_svg(&initial, &optimized);
    if let Some(svg) = &robot {
        sdrs::output::write_atomic(&out.join("robot.svg"), svg.as_bytes())?;
    }
    let convergence = std::fs::read_to_string(out.join("convergence.svg"))
        .with_context(|| format!("{}: cannot read convergence.svg", out.display()))?;
    let mut figs = Vec::new();
    if let Some(svg) = &robot {
        figs.push(("robot, initial (grey) vs optimized (blue)", svg.as_str()));
    }
    if let Some(svg) = shapes {
        figs.push(("designed links in their frames", svg));
    }
    let html = sdrs::optimize::report::report_html(
        &format!("sdrs optimize {}", problem.task_path.display()),
        outcome.initial_loss,
        outcome.loss,
        outcome.history.len().saturating_sub(1),
        &convergence,
        &figs,
    );
    sdrs::output::write_atomic(&out.join("report.html"), html.as_bytes())?;
    Ok(())
}
