//! `sdrs` command-line interface.

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use sdrs::output::{Summary, write_atomic};
use sdrs::scene::Scene;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "sdrs",
    version,
    about = "Shape-differentiable robot simulation (SDRS)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene file and write the trajectory and a summary.
    Simulate(SimulateArgs),
    /// Benchmarks (release builds): per-step cost of the rotating-chain scene.
    Bench(BenchArgs),
    /// Co-design: optimize shape and controller of a task with adjoint gradients.
    Optimize(OptimizeArgs),
    /// Import a robot (URDF, OBJ or STL) as a convex-hull design space.
    Import(sdrs::import::ImportArgs),
    /// Calibration: name the physical effect missing from a scene, given measured data.
    Calibrate(sdrs::calibrate::CalibrateArgs),
}

#[derive(clap::Args)]
struct OptimizeArgs {
    /// Task YAML (see README, "Co-design").
    task: PathBuf,
    /// Output directory: history.csv, convergence.svg, design.yaml,
    /// meshes/<robot>_<link>.obj, summary.json.
    #[arg(long)]
    out: PathBuf,
    /// Iterations (default: the task's `optimizer.iters`).
    #[arg(long)]
    iters: Option<usize>,
    /// `off` optimizes the controller alone (for comparison).
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    design: String,
    /// Write into a non-empty output directory.
    #[arg(long)]
    force: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(clap::Args)]
struct SimulateArgs {
    /// Scene YAML (see README, "Scene files").
    scene: PathBuf,
    /// Number of steps (default: the scene's `steps`).
    #[arg(long)]
    steps: Option<usize>,
    /// Trajectory CSV: a `t` column and one column per coordinate.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Summary JSON (steps, timing, Newton statistics, final state,
    /// energy and momentum diagnostics, stage breakdown).
    #[arg(long)]
    json: Option<PathBuf>,
    /// Also write every hull (link frame, `hulls.json`) and every link pose
    /// per step (`poses.csv`) into this directory, for viewers and
    /// independent checks (`tools/check_separation.py`).
    #[arg(long)]
    export: Option<PathBuf>,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// Scene to benchmark; every robot with a `chain` gets `--links` links.
    #[arg(long, default_value = "robots/four_chains.yaml")]
    scene: PathBuf,
    /// Links per chain, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "2,4,8,16,32")]
    links: Vec<usize>,
    /// Steps per measurement.
    #[arg(long, default_value_t = 200)]
    steps: usize,
    /// Write the table as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
}

fn main() {
    let cli = Cli::parse();
    let res = match cli.command {
        Command::Simulate(a) => simulate(a),
        Command::Bench(a) => bench(a),
        Command::Optimize(a) => optimize(a),
        Command::Import(a) => sdrs::import::run_import(&a),
        Command::Calibrate(a) => calibrate(&a),
    };
    if let Err(e) = res {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn calibrate(a: &sdrs::calibrate::CalibrateArgs) -> Result<()> {
    let opts = sdrs::calibrate::CalibrateOptions::from_args(a)?;
    let r = sdrs::calibrate::run(&opts)?;
    eprintln!(
        "{}: verdict {}{}; held-out RMS {:.4e} -> {:.4e}; {} candidates, {} simulations in {:.2} s; wrote {}",
        a.measured.display(),
        r.verdict,
        r.candidate
            .as_ref()
            .map(|c| format!(" ({c})"))
            .unwrap_or_default(),
        r.gap_before.overall,
        r.gap_after.overall,
        r.ranking.len(),
        r.simulations,
        r.seconds,
        a.out.display()
    );
    Ok(())
}

fn progress(n: usize, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(n as u64);
    pb.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} steps ({eta} left)",
        )
        .expect("static template"),
    );
    pb
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

fn simulate(a: SimulateArgs) -> Result<()> {
    let scene = Scene::load(&a.scene)?;
    for out in [&a.out, &a.json].into_iter().flatten() {
        if same_file(out, &a.scene) {
            bail!("{}: refusing to overwrite the input scene", out.display());
        }
    }
    let steps = a.steps.unwrap_or(scene.steps);
    let mut sim = scene.simulator();
    let pb = progress(steps, a.quiet);
    let t0 = Instant::now();
    let traj = sdrs::sim::run::run_recording(&mut sim, steps, a.export.is_some(), |k| {
        pb.set_position(k as u64)
    })
    .with_context(|| format!("simulating {}", a.scene.display()))?;
    let wall = t0.elapsed().as_secs_f64();
    pb.finish_and_clear();
    let summary = Summary::new(
        &a.scene.display().to_string(),
        scene.settings.dt,
        &traj,
        wall,
        sim.timers.report(),
    );
    if let Some(out) = &a.out {
        write_atomic(out, traj.to_csv().as_bytes())?;
    }
    if let Some(js) = &a.json {
        write_atomic(js, serde_json::to_string_pretty(&summary)?.as_bytes())?;
    }
    if let Some(dir) = &a.export {
        let excluded = scene
            .contact
            .as_ref()
            .map(|c| c.excluded.iter().copied().collect::<Vec<_>>())
            .unwrap_or_default();
        let hulls = sdrs::output::HullExport::new(&scene.model, excluded);
        write_atomic(
            &dir.join("hulls.json"),
            serde_json::to_string(&hulls)?.as_bytes(),
        )?;
        write_atomic(
            &dir.join("poses.csv"),
            sdrs::output::poses_csv(&traj).as_bytes(),
        )?;
    }
    eprintln!(
        "{}: {} steps of {} s in {:.3} s ({:.3} ms/step), Newton iterations mean {:.2} max {}{}",
        a.scene.display(),
        steps,
        scene.settings.dt,
        wall,
        1e3 * summary.seconds_per_step,
        summary.newton.mean_iterations,
        summary.newton.max_iterations,
        match summary.contact.min_distance {
            Some(d) => format!(
                ", contact in {} steps (max {} pairs), min distance {:.3e} m",
                summary.contact.steps_in_contact, summary.contact.max_active_pairs, d
            ),
            None => String::new(),
        }
    );
    Ok(())
}

fn bench(a: BenchArgs) -> Result<()> {
    if cfg!(debug_assertions) {
        eprintln!("warning: debug build; benchmark with `cargo run --release -- bench`");
    }
    let text = std::fs::read_to_string(&a.scene)
        .with_context(|| format!("reading {}", a.scene.display()))?;
    let base: sdrs::scene::SceneSpec =
        serde_yaml::from_str(&text).with_context(|| format!("parsing {}", a.scene.display()))?;
    let mut rows = Vec::new();
    println!("| links/chain | dof | ms/step | Newton it/step | stage breakdown (ms/step) |");
    println!("|---:|---:|---:|---:|---|");
    for &n in &a.links {
        let mut spec = base.clone();
        for r in &mut spec.robots {
            if let Some(c) = &mut r.chain {
                c.links = n;
            }
        }
        let scene = Scene::from_spec(spec, &a.scene)?;
        let mut sim = scene.simulator();
        let t0 = Instant::now();
        let traj = sdrs::sim::run::run(&mut sim, a.steps, |_| {})?;
        let wall = t0.elapsed().as_secs_f64();
        let s = Summary::new("bench", scene.settings.dt, &traj, wall, sim.timers.report());
        let stages: Vec<String> = s
            .stages
            .iter()
            .map(|st| format!("{} {:.3}", st.stage, 1e3 * st.seconds / a.steps as f64))
            .collect();
        println!(
            "| {n} | {} | {:.3} | {:.2} | {} |",
            scene.model.ndof(),
            1e3 * s.seconds_per_step,
            s.newton.mean_iterations,
            stages.join(", ")
        );
        rows.push(serde_json::json!({
            "links_per_chain": n, "dof": scene.model.ndof(), "ms_per_step": 1e3 * s.seconds_per_step,
            "newton_iterations_per_step": s.newton.mean_iterations, "stages": s.stages,
        }));
    }
    if let Some(p) = &a.json {
        write_atomic(p, serde_json::to_string_pretty(&rows)?.as_bytes())?;
    }
    Ok(())
}

fn optimize(a: OptimizeArgs) -> Result<()> {
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
    let iters = a.iters.unwrap_or(problem.task.optimizer.iters);
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
    let outcome = sdrs::optimize::optimize(&problem, iters, |r, _| {
        pb.set_position(r.iter as u64 + 1);
        pb.set_message(format!("loss {:.4e} (best {:.4e})", r.loss, r.best_loss));
    })?;
    pb.finish_and_clear();
    sdrs::optimize::output::write_all(
        &a.out,
        &problem,
        &outcome,
        serde_json::json!({"design": a.design}),
    )?;
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
