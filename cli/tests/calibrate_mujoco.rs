//! Calibration against an independent engine: MuJoCo simulates the arm of
//! `robots/calibrate/arm2_fine.yaml` (written by `sdrs export-mjcf`, with the
//! same lumped vertex masses, and given its effects by
//! `tools/mujoco_from_export.py --sdrs`; the script's own construction from
//! `sdrs simulate --export` gives the same data to 6e-16 rad) with joint damping, dry friction (`frictionloss`)
//! or armature switched on; `calibrate` must name the matching effect first
//! and shrink the held-out gap by ≥ 80 %. Clean MuJoCo data measure what the
//! integrator difference alone leaves, and must give the verdict "none".

mod support;
use support as common;

use rayon::prelude::*;
use sdrs::calibrate::{CalibrateOptions, CalibrationResult, calibrate};
use sdrs::energy::effects::EffectKind;
use std::path::Path;

fn mujoco_data(scene: &Path, export: &Path, out: &Path, effect: &[&str]) {
    let o = common::python()
        .arg(common::root().join("tools/mujoco_from_export.py"))
        .arg(scene)
        .arg(export)
        .arg("--out")
        .arg(out)
        .args(effect)
        .arg("--sdrs")
        .arg(env!("CARGO_BIN_EXE_sdrs"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn run(scene: &Path, measured: &Path, out: &Path) -> CalibrationResult {
    let opts = CalibrateOptions {
        scene: scene.to_path_buf(),
        measured: measured.to_path_buf(),
        more_measured: Vec::new(),
        out: out.to_path_buf(),
        effects: EffectKind::ALL.to_vec(),
        holdout: 0.3,
        select: Default::default(),
    };
    calibrate(&opts).unwrap().0
}

#[test]
fn mujoco_damping_frictionloss_and_armature_are_named_and_close_the_gap() {
    if support::skip_without_venv() {
        return;
    }
    let dir = common::scratch_dir("calibrate-mujoco");
    let scene = common::robots("calibrate/arm2_fine.yaml");
    let export = dir.join("export");
    let o = common::sdrs()
        .args([
            "simulate",
            scene.to_str().unwrap(),
            "--steps",
            "2",
            "-q",
            "--export",
        ])
        .arg(&export)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cases: [(&str, &[&str], &str); 4] = [
        ("clean", &[], ""),
        ("damping", &["--damping", "0.3"], "joint_damping/all"),
        (
            "frictionloss",
            &["--frictionloss", "0.4"],
            "joint_friction/all",
        ),
        ("armature", &["--armature", "0.05"], "armature/all"),
    ];
    for (name, args, _) in &cases {
        mujoco_data(&scene, &export, &dir.join(format!("{name}.csv")), args);
    }
    let results: Vec<CalibrationResult> = cases
        .par_iter()
        .map(|(name, _, _)| run(&scene, &dir.join(format!("{name}.csv")), &dir.join(name)))
        .collect();
    for ((name, _, want), r) in cases.iter().zip(&results) {
        eprintln!(
            "MuJoCo {name:<13} verdict {:<6} {:<22} {:?} held-out RMS {:.3e} -> {:.3e} ({:.1} %), expected {want}",
            r.verdict,
            r.candidate.clone().unwrap_or_default(),
            r.parameters,
            r.gap_before.overall,
            r.gap_after.overall,
            100.0 * r.gap_reduction
        );
    }
    let clean = &results[0];
    assert_eq!(
        clean.verdict, "none",
        "clean MuJoCo data: {:?}",
        clean.candidate
    );
    // What the integrator difference alone leaves (MuJoCo implicitfast at
    // 0.1 ms vs SDRS at 0.5 ms): small next to the effects' gaps.
    for ((name, _, want), r) in cases.iter().zip(&results).skip(1) {
        assert_eq!(r.candidate.as_deref(), Some(*want), "{name}");
        assert!(
            r.gap_reduction >= 0.8,
            "{name}: gap shrinks by {:.1} %",
            100.0 * r.gap_reduction
        );
        assert!(
            r.gap_before.overall > 5.0 * clean.gap_before.overall,
            "{name}"
        );
    }
}
