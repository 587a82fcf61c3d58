//! `sdrs calibrate` on bad input: every problem with the measured file is a
//! typed error naming the file, the column and the line; nothing is written
//! to the output directory on error; inputs are never overwritten.

use crate::common;

use sdrs::calibrate::{CalibrateError, CalibrateOptions, run};
use sdrs::energy::effects::EffectKind;
use std::path::{Path, PathBuf};

fn scene() -> PathBuf {
    common::robots("calibrate/arm2.yaml")
}

/// A valid measured file: `n` samples of both joints.
fn good(n: usize) -> String {
    let mut s = String::from("t,shoulder,elbow\n");
    for i in 0..n {
        let t = i as f64 * 0.02;
        s.push_str(&format!("{t},{},{}\n", 0.2 + 0.1 * t, -0.3 + 0.2 * t));
    }
    s
}

fn opts(measured: &Path, out: &Path) -> CalibrateOptions {
    CalibrateOptions {
        scene: scene(),
        measured: measured.to_path_buf(),
        more_measured: Vec::new(),
        out: out.to_path_buf(),
        effects: vec![EffectKind::JointDamping],
        holdout: 0.3,
        select: Default::default(),
        log: Default::default(),
        fit_contact_resolution: false,
    }
}

/// Runs with `csv` as the measured file; returns the error message and
/// asserts that the output directory was not created.
fn error_for(name: &str, csv: &str) -> (CalibrateError, String) {
    let dir = common::scratch_dir(&format!("calibrate-bad-{name}"));
    let m = dir.join("measured.csv");
    std::fs::write(&m, csv).unwrap();
    let out = dir.join("out");
    let e = run(&opts(&m, &out)).expect_err(name);
    let msg = e.to_string();
    eprintln!("{name}: {msg}");
    assert!(!out.exists(), "{name}: output directory written on error");
    assert!(
        msg.contains("measured.csv"),
        "{name}: the file is not named: {msg}"
    );
    (e, msg)
}

#[test]
fn unknown_column_is_named_with_its_index() {
    let csv = good(20).replace("t,shoulder,elbow", "t,shoulder,wrist");
    let (e, msg) = error_for("unknown", &csv);
    assert!(
        matches!(e, CalibrateError::UnknownColumn { index: 3, .. }),
        "{e:?}"
    );
    assert!(
        msg.contains("\"wrist\"") && msg.contains("shoulder, elbow"),
        "{msg}"
    );
}

#[test]
fn non_monotonic_time_names_the_line() {
    let mut lines: Vec<String> = good(20).lines().map(String::from).collect();
    lines.swap(6, 7); // data rows 6 and 7 → lines 7 and 8 of the file
    let (e, msg) = error_for("nonmono", &(lines.join("\n") + "\n"));
    assert!(
        matches!(e, CalibrateError::NonMonotonicTime { line: 8, .. }),
        "{e:?}"
    );
    assert!(msg.contains("line 8") && msg.contains("\"t\""), "{msg}");
}

#[test]
fn nan_and_text_name_column_and_line() {
    let mut lines: Vec<String> = good(20).lines().map(String::from).collect();
    lines[4] = "0.06,NaN,0.1".into();
    let (e, msg) = error_for("nan", &(lines.join("\n") + "\n"));
    assert!(
        matches!(e, CalibrateError::BadValue { line: 5, .. }),
        "{e:?}"
    );
    assert!(
        msg.contains("\"shoulder\"") && msg.contains("line 5"),
        "{msg}"
    );
    let mut lines: Vec<String> = good(20).lines().map(String::from).collect();
    lines[9] = "0.16,0.1,abc".into();
    let (_, msg) = error_for("text", &(lines.join("\n") + "\n"));
    assert!(
        msg.contains("\"elbow\"") && msg.contains("line 10") && msg.contains("abc"),
        "{msg}"
    );
    let mut lines: Vec<String> = good(20).lines().map(String::from).collect();
    lines[3] = "inf,0.1,0.2".into();
    let (_, msg) = error_for("inf", &(lines.join("\n") + "\n"));
    assert!(msg.contains("\"t\"") && msg.contains("line 4"), "{msg}");
}

#[test]
fn too_short_data_and_missing_time_are_errors() {
    let (e, msg) = error_for("short", &good(5));
    assert!(matches!(e, CalibrateError::TooShort { .. }), "{e:?}");
    assert!(msg.contains("5 time sample"), "{msg}");
    // Enough rows, but one channel is nearly all gaps.
    let mut s = String::from("t,shoulder,elbow\n");
    for i in 0..20 {
        let e = if i < 3 { "0.1" } else { "" };
        s.push_str(&format!("{},{},{e}\n", i as f64 * 0.02, 0.2));
    }
    let (_, msg) = error_for("gaps", &s);
    assert!(
        msg.contains("\"elbow\"") && msg.contains("3 value"),
        "{msg}"
    );
    let (e, _) = error_for("notime", &good(20).replace("t,shoulder", "time,shoulder"));
    assert!(matches!(
        e,
        CalibrateError::UnknownColumn { .. } | CalibrateError::NoTime { .. }
    ));
    let (e, _) = error_for(
        "dup",
        &good(20).replace("t,shoulder,elbow", "t,shoulder,shoulder"),
    );
    assert!(
        matches!(e, CalibrateError::DuplicateColumn { index: 3, .. }),
        "{e:?}"
    );
    let (e, _) = error_for(
        "only_t",
        "t\n0\n0.1\n0.2\n0.3\n0.4\n0.5\n0.6\n0.7\n0.8\n0.9\n1.0\n",
    );
    assert!(matches!(e, CalibrateError::NoChannels { .. }), "{e:?}");
}

#[test]
fn bad_options_and_missing_files_write_nothing() {
    let dir = common::scratch_dir("calibrate-bad-opts");
    let m = dir.join("measured.csv");
    std::fs::write(&m, good(40)).unwrap();
    let out = dir.join("out");
    let mut o = opts(&m, &out);
    o.holdout = 1.0;
    assert!(matches!(run(&o), Err(CalibrateError::Holdout(_))));
    let mut o = opts(&dir.join("missing.csv"), &out);
    o.holdout = 0.3;
    let e = run(&o).unwrap_err();
    assert!(e.to_string().contains("missing.csv"), "{e}");
    let mut o = opts(&m, &out);
    o.scene = dir.join("nope.yaml");
    assert!(run(&o).unwrap_err().to_string().contains("nope.yaml"));
    assert!(!out.exists());
    // An unknown effect name on the command line.
    let names = ["joint_damping".to_string(), "magic".to_string()];
    let e =
        CalibrateOptions::new(scene(), m.clone(), out.clone(), Some(&names[..]), 0.3).unwrap_err();
    assert!(e.to_string().contains("\"magic\"") && e.to_string().contains("joint_friction"));
}

#[test]
fn inputs_are_never_overwritten() {
    // The scene is named calibrated.yaml and lives in the output directory.
    let dir = common::scratch_dir("calibrate-overwrite");
    let sc = dir.join("calibrated.yaml");
    std::fs::copy(scene(), &sc).unwrap();
    let m = dir.join("measured.csv");
    std::fs::write(&m, good(40)).unwrap();
    let before = std::fs::read(&sc).unwrap();
    let mut o = opts(&m, &dir);
    o.scene = sc.clone();
    let e = run(&o).unwrap_err();
    assert!(
        matches!(e, CalibrateError::WouldOverwriteInput { .. }),
        "{e:?}"
    );
    assert_eq!(std::fs::read(&sc).unwrap(), before);
    assert!(!dir.join("calibration.json").exists());
}
