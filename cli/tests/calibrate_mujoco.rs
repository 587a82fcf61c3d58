//! Calibration against an independent engine: MuJoCo simulates the arm of
//! `robots/calibrate/arm2_fine.yaml` (written by `sdrs export-mjcf`, with the
//! same lumped vertex masses, and given its effects by
//! `tools/check/mujoco_from_export.py --sdrs`; the script's own construction from
//! `sdrs simulate --export` gives the same data to 6e-16 rad) with joint damping, dry friction (`frictionloss`)
//! or armature switched on; `calibrate` must name the matching effect first
//! and shrink the held-out gap by ≥ 80 %. Clean MuJoCo data measure what the
//! integrator difference alone leaves, and must give the verdict "none".

use crate::support;
use support as common;

use rayon::prelude::*;
use sdrs::calibrate::{CalibrateOptions, CalibrationResult, calibrate};
use sdrs::energy::effects::EffectKind;
use std::path::Path;

fn mujoco_data(scene: &Path, export: &Path, out: &Path, effect: &[&str]) {
    let o = common::python()
        .arg(common::root().join("tools/check/mujoco_from_export.py"))
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
        log: Default::default(),
        fit_contact_resolution: false,
    };
    calibrate(&opts).unwrap().0
}

/// `arm2_fine.yaml` and its `sdrs simulate --export` in `dir/export`
/// (what `tools/check/mujoco_from_export.py` builds the MuJoCo robot from).
fn arm2_fine_export(dir: &std::path::Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let scene = common::robots("calibrate/arm2_fine.yaml");
    let export = dir.join("export");
    let o = common::sdrs()
        .args(["simulate", scene.to_str().unwrap(), "--steps", "2", "-q"])
        .arg("--export")
        .arg(&export)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (scene, export)
}

#[test]
fn mujoco_damping_frictionloss_and_armature_are_named_and_close_the_gap() {
    if support::skip_without_venv() {
        return;
    }
    let dir = common::scratch_dir("calibrate-mujoco");
    let (scene, export) = arm2_fine_export(&dir);
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

/// RMS difference of two CSVs written at the same sample times
/// (`t,<joint>…`).
fn csv_rms(a: &Path, b: &Path) -> f64 {
    let read = |p: &Path| -> Vec<Vec<f64>> {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect()
    };
    let (x, y) = (read(a), read(b));
    assert_eq!(x.len(), y.len());
    let (mut s, mut n) = (0.0, 0);
    for (r, q) in x.iter().zip(&y) {
        assert!((r[0] - q[0]).abs() < 1e-9);
        for c in 1..r.len() {
            s += (r[c] - q[c]).powi(2);
            n += 1;
        }
    }
    (s / n as f64).sqrt()
}

/// `calibrated.xml` (issue 33, Deliver 6): MuJoCo data with damping 0.3 on
/// both joints of `arm2_fine`; `sdrs calibrate` writes `calibrated.xml`,
/// MuJoCo loads it with the fitted damping as both joints' `damping`
/// attribute, and MuJoCo's own simulation of it under the scene's
/// controller is closer to the data than its simulation of the original
/// export (threshold fixed before the run: ≤ ¼ of the original's RMS gap).
/// Payload and link-mass-scale effects map to the bodies' inertials: the
/// body mass and centre of mass MuJoCo reads are `σm + m_p` and
/// `(σ m c + m_p p)/(σm + m_p)`.
#[test]
fn calibrated_xml_carries_the_fit_into_mujoco() {
    if support::skip_without_venv() {
        return;
    }
    let dir = common::scratch_dir("calibrate-mujoco-xml");
    let (scene, export) = arm2_fine_export(&dir);
    let data = dir.join("damping.csv");
    mujoco_data(&scene, &export, &data, &["--damping", "0.3"]);
    let out = dir.join("out");
    let o = common::sdrs()
        .args(["calibrate", scene.to_str().unwrap(), "--measured"])
        .arg(&data)
        .arg("--out")
        .arg(&out)
        .args(["--effects", "joint_damping,armature", "-q"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("calibration.json")).unwrap()).unwrap();
    assert_eq!(j["candidate"], "joint_damping/all", "{}", j["reason"]);
    let c = j["parameters"]["joint_damping/all"].as_f64().unwrap();
    let xml = out.join("calibrated.xml");
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("## MuJoCo model"), "{md}");
    // MuJoCo reads the attributes.
    let probe = "import json, sys, mujoco\n\
        m = mujoco.MjModel.from_xml_path(sys.argv[1])\n\
        print(json.dumps({'damping': [float(x) for x in m.dof_damping], \
        'mass': [float(x) for x in m.body_mass], \
        'ipos': [[float(v) for v in p] for p in m.body_ipos]}))";
    let read = |p: &Path| -> serde_json::Value {
        let o = common::python()
            .args(["-c", probe])
            .arg(p)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let m = read(&xml);
    for d in m["damping"].as_array().unwrap() {
        let d = d.as_f64().unwrap();
        assert!(
            (d - c).abs() <= 1e-9 * c,
            "MuJoCo damping {d} vs fitted {c}"
        );
    }
    // MuJoCo simulates calibrated.xml and the original export under the
    // scene's controller, without noise.
    let sim = |model: Option<&Path>, csv: &Path| {
        let mut cmd = common::python();
        cmd.arg(common::root().join("tools/check/mujoco_from_export.py"))
            .arg(&scene)
            .arg(&export)
            .arg("--out")
            .arg(csv)
            .args(["--noise", "0", "--sdrs", env!("CARGO_BIN_EXE_sdrs")]);
        if let Some(x) = model {
            cmd.arg("--model").arg(x);
        }
        let o = cmd.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let (cal, orig) = (dir.join("cal.csv"), dir.join("orig.csv"));
    sim(Some(&xml), &cal);
    sim(None, &orig);
    let (gc, go) = (csv_rms(&cal, &data), csv_rms(&orig, &data));
    eprintln!("MuJoCo vs data: calibrated.xml {gc:.3e}, original {go:.3e} (fitted damping {c})");
    assert!(gc <= 0.25 * go, "calibrated {gc} vs original {go}");
    // Payload and mass scale in the inertial.
    let text = std::fs::read_to_string(&scene).unwrap()
        + "effects:\n  - {effect: link_mass_scale, on: fore, values: [1.5]}\n  \
           - {effect: payload, on: fore, values: [0.2, 0.01, 0.0, -0.3]}\n";
    let with = dir.join("with_mass.yaml");
    std::fs::write(&with, text).unwrap();
    let x2 = dir.join("with_mass.xml");
    let o = common::sdrs()
        .args([
            "export-mjcf",
            with.to_str().unwrap(),
            "--out",
            x2.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (m0, m1) = (read(&xml), read(&x2));
    let b = m0["mass"]
        .as_array()
        .unwrap()
        .iter()
        .rposition(|v| (v.as_f64().unwrap() - 0.5).abs() < 1e-9)
        .expect("the forearm body (0.5 kg)");
    let mass = m1["mass"][b].as_f64().unwrap();
    assert!((mass - (1.5 * 0.5 + 0.2)).abs() < 1e-9, "mass {mass}");
    for (k, p) in [0.01, 0.0, -0.3].iter().enumerate() {
        let c0 = m0["ipos"][b][k].as_f64().unwrap();
        let want = (0.75 * c0 + 0.2 * p) / 0.95;
        let got = m1["ipos"][b][k].as_f64().unwrap();
        assert!((got - want).abs() < 1e-9, "com[{k}] {got} vs {want}");
    }
}
