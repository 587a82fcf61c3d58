//! The first hour: third-party robots from `pybullet_data` imported with the
//! default options plus `--ground`, simulated for 2 s. The arm must hold its
//! initial pose (≤ 0.05 rad), the quadruped must stay on its feet (base
//! height within 20 % of its initial height), and no state may interpenetrate
//! (our GJK at every step, and python-fcl on the quadruped's export).

mod support;

use std::path::Path;
use support::{pybullet_data, python, scratch_dir, sdrs};

/// Imports `urdf` with `--ground` and simulates 2000 steps of 1 ms; returns
/// the trajectory (header, rows) and the summary.
fn import_and_run(
    dir: &Path,
    urdf: &Path,
    name: &str,
    export: bool,
) -> (Vec<String>, Vec<Vec<f64>>, serde_json::Value) {
    let scene = dir.join(format!("{name}.yaml"));
    let out = sdrs()
        .args(["import", "-q", "--ground", "--out"])
        .arg(&scene)
        .arg("--report")
        .arg(dir.join(format!("{name}_report.json")))
        .arg(urdf)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (csv, json) = (
        dir.join(format!("{name}.csv")),
        dir.join(format!("{name}.json")),
    );
    let mut cmd = sdrs();
    cmd.args(["simulate", "-q", "--steps", "2000", "--out"])
        .arg(&csv)
        .arg("--json")
        .arg(&json)
        .arg(&scene);
    if export {
        cmd.arg("--export").arg(dir.join(format!("{name}_export")));
    }
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 2001);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    if let Some(d) = summary["contact"]["min_distance"].as_f64() {
        assert!(d > 0.0, "{name}: min distance {d}");
    }
    (header, rows, summary)
}

#[test]
fn an_imported_arm_holds_its_pose_on_the_ground() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("first-hour-arm");
    let urdf = pybullet_data().join("kuka_iiwa/model.urdf");
    let (header, rows, _) = import_and_run(&dir, &urdf, "kuka", false);
    let worst = rows
        .iter()
        .flat_map(|r| r[1..].iter().map(|v| v.abs()))
        .fold(0.0, f64::max);
    eprintln!(
        "kuka: {} joints, largest deviation from the initial pose {worst:.3e} rad",
        header.len() - 1
    );
    assert_eq!(header.len(), 8, "7 joints, fixed base: {header:?}");
    assert!(worst <= 0.05, "{worst}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_imported_quadruped_stands_on_the_ground() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("first-hour-quadruped");
    let urdf = pybullet_data().join("a1/a1.urdf");
    let (header, rows, summary) = import_and_run(&dir, &urdf, "a1", true);
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("a1_report.json")).unwrap())
            .unwrap();
    assert!(
        report["ready"]["base"]
            .as_str()
            .unwrap()
            .starts_with("floating")
    );
    let lift = report["ready"]["ground_lift"].as_f64().unwrap();
    let z = header
        .iter()
        .position(|h| h.ends_with("trunk:z"))
        .expect("a floating trunk");
    // The trunk's frame starts `lift` above the ground; q_z is its offset.
    let heights: Vec<f64> = rows.iter().map(|r| lift + r[z]).collect();
    let worst = heights
        .iter()
        .map(|h| (h - lift).abs() / lift)
        .fold(0.0, f64::max);
    eprintln!(
        "a1: initial height {lift:.4} m, final {:.4} m, worst relative change {worst:.3}; contact in {} steps",
        heights.last().unwrap(),
        summary["contact"]["steps_in_contact"]
    );
    assert!(worst <= 0.2, "{worst}");
    assert!(
        summary["contact"]["steps_in_contact"].as_u64().unwrap() > 1000,
        "not on the ground"
    );
    let check = python()
        .arg(support::root().join("tools/check_separation.py"))
        .arg(dir.join("a1_export"))
        .args(["--every", "10"])
        .output()
        .unwrap();
    assert!(
        check.status.success(),
        "python-fcl found interpenetration:\n{}\n{}",
        String::from_utf8_lossy(&check.stdout),
        String::from_utf8_lossy(&check.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_third_imported_robot_runs_on_the_ground_without_error() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("first-hour-r2d2");
    let urdf = pybullet_data().join("r2d2.urdf");
    let (_, rows, summary) = import_and_run(&dir, &urdf, "r2d2", false);
    assert!(rows.iter().all(|r| r.iter().all(|v| v.is_finite())));
    assert!(summary["contact"]["steps_in_contact"].as_u64().unwrap() > 1000);
    let _ = std::fs::remove_dir_all(&dir);
}
