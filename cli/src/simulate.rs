//! `sdrs simulate`: run a scene, write the trajectory CSV, the summary JSON
//! and (with `--export`) hulls and poses for viewers and independent checks.
//!
//! The CSV is streamed row by row and the summary statistics are folded
//! step by step, so memory does not grow with `--steps` (except with
//! `--export`/`--view`, which need every pose). A failed or interrupted run
//! (Ctrl-C; exit code 130) leaves the rows computed so far, a valid CSV
//! prefix, and its summary JSON.

use crate::util::{progress, same_file};
use anyhow::{Result, bail};
use nalgebra::DVector;
use sdrs::output::{CsvStream, RunStats, Trajectory, write_atomic};
use sdrs::scene::Scene;
use sdrs::scene::build::check_duration;
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

#[derive(clap::Args)]
pub struct SimulateArgs {
    /// Scene YAML (see README, "Scene files").
    pub scene: PathBuf,
    /// Number of steps (default: the scene's `steps`).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Trajectory CSV: a `t` column and one column per coordinate.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Summary JSON (steps, timing, Newton statistics, final state,
    /// energy and momentum diagnostics, stage breakdown).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Also write every hull (link frame, `hulls.json`) and every link pose
    /// per step (`poses.csv`) into this directory, for viewers and
    /// independent checks (`tools/check/check_separation.py`).
    #[arg(long)]
    pub export: Option<PathBuf>,
    /// With `--export`: also write the active contact pairs and their
    /// separating planes at every step (`contacts.csv`, recomputed from the
    /// recorded poses after the run; see `sdrs::output::contacts`).
    #[arg(long, requires = "export")]
    pub planes: bool,
    /// Also write a self-contained HTML viewer of the run (hulls, contact
    /// planes, time slider; open it in a browser). `sdrs view` makes one
    /// from an `--export` directory as well.
    #[arg(long)]
    pub view: Option<PathBuf>,
    /// Also write a velocity column `<name>:v` per coordinate (rad/s, m/s).
    #[arg(long)]
    pub velocities: bool,
    /// Accepted for compatibility: the summary's `energy.balance` (each
    /// term's work and the integrator's numerical dissipation) is always
    /// written now.
    #[arg(long, hide = true)]
    pub energy_balance: bool,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
    #[command(flatten)]
    pub contact: crate::contact_model::ContactArgs,
}

/// What a streamed run produced: the statistics, the final coordinates and,
/// when poses were asked for, the recorded trajectory.
struct Streamed {
    stats: RunStats,
    last_q: Option<DVector<f64>>,
    /// Time of the last state (s).
    last_t: f64,
    traj: Option<Trajectory>,
    rows: usize,
    /// The step error, CSV error or interrupt that ended the run early.
    stop: Option<anyhow::Error>,
    interrupted: bool,
}

/// Set by Ctrl-C (or `SIGTERM`/`SIGHUP`): the run stops after the current
/// step and the outputs are finished; a second signal exits at once (the
/// CSV on disk still holds whole rows only).
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

fn install_interrupt() {
    let _ = ctrlc::set_handler(|| {
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
}

/// Runs the scene, streaming rows to the CSV and folding the summary
/// statistics as it goes (memory independent of `steps` unless poses are
/// recorded for `--export`/`--view`).
fn stream_run(
    a: &SimulateArgs,
    scene: &Scene,
    sim: &mut sdrs::sim::Simulator,
    steps: usize,
    pb: &indicatif::ProgressBar,
) -> Result<Streamed> {
    let names: Vec<String> = sim.model.dofs.iter().map(|d| d.name.clone()).collect();
    let velocities = a.velocities.then_some((scene.settings.dt, &scene.qdot0));
    let mut csv = match &a.out {
        Some(p) => Some(CsvStream::create(p, &names, velocities)?),
        None => None,
    };
    let record_poses = a.export.is_some() || a.view.is_some();
    let mut out = Streamed {
        stats: RunStats::new(),
        last_q: None,
        last_t: 0.0,
        traj: record_poses.then(|| Trajectory::new(&sim.model)),
        rows: 0,
        stop: None,
        interrupted: false,
    };
    install_interrupt();
    let res = sdrs::sim::run::run_observed(sim, steps, |k, sim, d| {
        let q = sim.state.reported_q(&sim.model);
        if let Some(Err(e)) = csv.as_mut().map(|c| c.push(sim.state.time, &q)) {
            out.stop = Some(e.into());
            return ControlFlow::Break(());
        }
        if let Some(d) = d {
            out.stats.push(d);
            pb.set_position(k as u64);
        }
        if let Some(t) = out.traj.as_mut() {
            t.times.push(sim.state.time);
            t.states.push(q.clone());
            t.poses.push(sim.state.poses.clone());
            t.diagnostics.extend(d.copied());
        }
        out.last_q = Some(q);
        out.last_t = sim.state.time;
        if INTERRUPTED.load(Ordering::SeqCst) {
            out.interrupted = true;
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    });
    if let Err(e) = res {
        out.stop = Some(anyhow::Error::new(e).context(format!(
            "simulating {}: step {} failed",
            a.scene.display(),
            out.stats.steps() + 1
        )));
    }
    if let Some(c) = csv {
        out.rows = c.rows();
        c.finish()?;
    }
    Ok(out)
}

/// The outputs that need every recorded pose: `--export` (hulls, poses,
/// surfaces, `--planes` contacts) and `--view`.
fn write_recorded(a: &SimulateArgs, scene: &Scene, traj: &Trajectory) -> Result<()> {
    if let Some(dir) = &a.export {
        let excluded = scene
            .contact
            .as_ref()
            .map(|c| c.excluded.iter().copied().collect::<Vec<_>>())
            .unwrap_or_default();
        sdrs::output::export_run(dir, &scene.model, excluded, traj)?;
        crate::contact_model::export_surfaces(dir, scene)?;
    }
    // Contact planes are recomputed from the recorded poses: the run above
    // is the same with or without them.
    let playback = if a.planes || a.view.is_some() {
        Some(crate::view::playback_of_run(scene, traj)?)
    } else {
        None
    };
    if let (Some(dir), true, Some(p)) = (&a.export, a.planes, &playback) {
        write_atomic(
            &dir.join("contacts.csv"),
            sdrs::output::contacts::contacts_csv(&p.contacts).as_bytes(),
        )?;
    }
    if let (Some(v), Some(p)) = (&a.view, &playback) {
        let title = a
            .scene
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        crate::view::write_run_viewer(v, &title, p)?;
        eprintln!("{}: viewer, open it in a browser", v.display());
    }
    Ok(())
}

pub fn run(a: SimulateArgs) -> Result<()> {
    let mut scene = Scene::load(&a.scene)?;
    a.contact.apply(&mut scene)?;
    for out in [&a.out, &a.json, &a.view].into_iter().flatten() {
        if same_file(out, &a.scene) {
            bail!("{}: refusing to overwrite the input scene", out.display());
        }
    }
    let steps = a.steps.unwrap_or(scene.steps);
    if a.steps.is_some() {
        check_duration(scene.settings.dt, steps, "--steps").map_err(|e| e.at(&a.scene))?;
    }
    let mut sim = crate::contact_model::simulator(&scene)?;
    // The summary's stage breakdown times every evaluation (≈ 7 % of a
    // small robot's step; see `sdrs::counters::timers`).
    sim.timers.set_detailed(true);
    if let Some(v) = &a.view {
        crate::view::check_overwrite(v, false)?;
    }
    let pb = progress(steps, a.quiet);
    let t0 = Instant::now();
    let run = stream_run(&a, &scene, &mut sim, steps, &pb)?;
    let wall = t0.elapsed().as_secs_f64();
    pb.finish_and_clear();
    let names: Vec<String> = sim.model.dofs.iter().map(|d| d.name.clone()).collect();
    let summary = run.stats.summary(
        &a.scene.display().to_string(),
        scene.settings.dt,
        &names,
        run.last_q.as_ref(),
        wall,
        sim.timers.report(),
    );
    if let Some(js) = &a.json {
        write_atomic(js, serde_json::to_string_pretty(&summary)?.as_bytes())?;
    }
    let kept = a.out.as_ref().map_or_else(String::new, |p| {
        format!(
            "; {} holds the {} row(s) up to t = {}",
            p.display(),
            run.rows,
            run.last_t
        )
    });
    if run.interrupted {
        eprintln!(
            "{}: interrupted after {} of {steps} steps{kept}",
            a.scene.display(),
            summary.steps
        );
        std::process::exit(130);
    }
    if let Some(e) = run.stop {
        return Err(e.context(format!(
            "the run stopped after {} steps{kept}",
            summary.steps
        )));
    }
    write_recorded(&a, &scene, &run.traj.unwrap_or_default())?;
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
