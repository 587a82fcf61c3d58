//! `sdrs simulate`: run a scene, write the trajectory CSV, the summary JSON
//! and (with `--export`) hulls and poses for viewers and independent checks.

use crate::util::{progress, same_file};
use anyhow::{Context, Result, bail};
use sdrs::output::{Summary, write_atomic};
use sdrs::scene::Scene;
use std::path::PathBuf;
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
    /// independent checks (`tools/check_separation.py`).
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

pub fn run(a: SimulateArgs) -> Result<()> {
    let mut scene = Scene::load(&a.scene)?;
    a.contact.apply(&mut scene)?;
    for out in [&a.out, &a.json, &a.view].into_iter().flatten() {
        if same_file(out, &a.scene) {
            bail!("{}: refusing to overwrite the input scene", out.display());
        }
    }
    let steps = a.steps.unwrap_or(scene.steps);
    let mut sim = crate::contact_model::simulator(&scene)?;
    let pb = progress(steps, a.quiet);
    let t0 = Instant::now();
    let record_poses = a.export.is_some() || a.view.is_some();
    if let Some(v) = &a.view {
        crate::view::check_overwrite(v, false)?;
    }
    let traj =
        sdrs::sim::run::run_recording(&mut sim, steps, record_poses, |k| pb.set_position(k as u64))
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
        let csv = if a.velocities {
            traj.to_csv_with_velocities(scene.settings.dt, &scene.qdot0)
        } else {
            traj.to_csv()
        };
        write_atomic(out, csv.as_bytes())?;
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
        sdrs::output::export_run(dir, &scene.model, excluded, &traj)?;
        crate::contact_model::export_surfaces(dir, &scene)?;
    }
    // Contact planes are recomputed from the recorded poses: the run above
    // is the same with or without them.
    let playback = if a.planes || a.view.is_some() {
        Some(crate::view::playback_of_run(&scene, &traj)?)
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
