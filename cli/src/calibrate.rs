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
    /// Measured data: a CSV (a `t` column and any subset of the columns `sdrs simulate`
    /// writes) or an MCAP robot log (`.mcap`: sensor_msgs/JointState messages, CDR or
    /// JSON, on `--topic`; joints matched to coordinates by name, see `--rename`). Repeat for several recordings fitted with one parameter set: the first is
    /// simulated from the scene's initial state, each further one from its first
    /// sample (at t = 0) with the scene's controller; each is validated on its own
    /// held-out window (`--holdout`).
    #[arg(long, required = true)]
    pub measured: Vec<PathBuf>,
    /// Output directory: calibrated.yaml, calibrated.xml (MuJoCo), calibration.json, report.md,
    /// report.html (the report with its plots, self-contained), plots (SVG).
    #[arg(long)]
    pub out: PathBuf,
    /// Candidate effects, comma separated (default: all applicable):
    /// joint_damping, joint_friction, armature, actuator_gain, joint_offset,
    /// payload, link_mass_scale, contact_mu, contact_kappa, contact_s,
    /// actuation_delay; and, only when named, stribeck_friction,
    /// actuator_deadband.
    #[arg(long, value_delimiter = ',')]
    pub effects: Option<Vec<String>>,
    /// Fit the contact model's resolution (barrier support s, stiffness κ)
    /// first, as settings of the simulator, and never name them as effects
    /// (experimental: on contact-rich data it also absorbs part of real
    /// effects; notes/calibration.md, session 6).
    #[arg(long)]
    pub fit_contact_resolution: bool,
    /// MCAP logs: the JointState topic to read.
    #[arg(long, default_value = sdrs::calibrate::mcap_log::DEFAULT_TOPIC)]
    pub topic: String,
    /// MCAP logs: LOG_NAME=COORDINATE maps a joint name of the log to a scene
    /// coordinate (as named in `sdrs simulate`'s CSV); LOG_NAME= ignores that joint.
    /// Repeatable; names not renamed must be coordinates of the scene.
    #[arg(long, value_parser = sdrs::calibrate::mcap_log::LogMapping::parse_rename)]
    pub rename: Vec<(String, String)>,
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
    opts.fit_contact_resolution = a.fit_contact_resolution;
    sdrs::calibrate::check_resolution_names(a.effects.as_deref(), opts.fit_contact_resolution)?;
    opts.log = sdrs::calibrate::mcap_log::LogMapping {
        topic: Some(a.topic.clone()),
        rename: a.rename.clone(),
    };
    let bar = Bar::new(
        "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} candidate fits ({eta} left)",
        0,
        a.quiet,
    );
    let hooks = sdrs::calibrate::Hooks {
        progress: &bar,
        plots: Some(&sdrs_cli::svg::calibration::CalibrationPlots),
        model: Some(&sdrs_cli::calibrated_mjcf::CalibratedMjcf),
        report: Some(&sdrs_cli::calibration_report::CalibrationReport),
    };
    let r = sdrs::calibrate::run_with(&opts, &hooks)?;
    if let Some(c) = &r.contact_resolution {
        eprintln!(
            "contact resolution fitted first (a setting of the simulator, not an effect): {c}"
        );
    }
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
