//! `sdrs calibrate`: name the physical effect missing from a scene, given
//! measured data (the logic is `sdrs::calibrate`).

use crate::progress::Bar;
use anyhow::Result;
use sdrs::calibrate::CalibrateOptions;
use std::path::PathBuf;

/// Command-line arguments of `sdrs calibrate`.
#[derive(clap::Args, Debug, Clone)]
pub struct CalibrateArgs {
    /// Scene YAML: the model to calibrate (its controller is the commanded one).
    pub scene: PathBuf,
    /// Measured CSV: a `t` column and any subset of the columns `sdrs simulate` writes.
    /// Repeat for several recordings fitted with one parameter set: the first is
    /// simulated from the scene's initial state, each further one from its first
    /// sample (at t = 0) with the scene's controller; each is validated on its own
    /// held-out window (`--holdout`).
    #[arg(long, required = true)]
    pub measured: Vec<PathBuf>,
    /// Output directory: calibrated.yaml, calibrated.xml (MuJoCo), calibration.json, report.md, plots.
    #[arg(long)]
    pub out: PathBuf,
    /// Candidate effects, comma separated (default: all applicable):
    /// joint_damping, joint_friction, armature, actuator_gain, joint_offset,
    /// payload, link_mass_scale, contact_mu, contact_kappa, contact_s,
    /// actuation_delay.
    #[arg(long, value_delimiter = ',')]
    pub effects: Option<Vec<String>>,
    /// Fraction of the data (by time, at the end) held out for scoring.
    #[arg(long, default_value_t = 0.3)]
    pub holdout: f64,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(a: &CalibrateArgs) -> Result<()> {
    let mut opts = CalibrateOptions::new(
        a.scene.clone(),
        a.measured[0].clone(),
        a.out.clone(),
        a.effects.as_deref(),
        a.holdout,
    )?;
    opts.more_measured = a.measured[1..].to_vec();
    let bar = Bar::new(
        "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} candidate fits ({eta} left)",
        0,
        a.quiet,
    );
    let hooks = sdrs::calibrate::Hooks {
        progress: &bar,
        plots: Some(&sdrs_cli::svg::calibration::CalibrationPlots),
        model: Some(&sdrs_cli::calibrated_mjcf::CalibratedMjcf),
    };
    let r = sdrs::calibrate::run_with(&opts, &hooks)?;
    eprintln!(
        "{}: verdict {}{}; held-out RMS {:.4e} -> {:.4e}; {} candidates, {} simulations in {:.2} s; wrote {}",
        a.measured
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
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
