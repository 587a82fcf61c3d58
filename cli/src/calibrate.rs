//! `sdrs calibrate`: name the physical effect missing from a scene, given
//! measured data (the logic is `sdrs::calibrate`).

use anyhow::Result;

pub fn run(a: &sdrs::calibrate::CalibrateArgs) -> Result<()> {
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
