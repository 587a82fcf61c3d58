//! The first hour: third-party robots from `pybullet_data` imported with
//! **no option** and simulated for 2 s (2000 steps of the scene's 1 ms).
//! The import's defaults (`src/import/ready.rs`) must make that sensible:
//! an arm (one chain from its base) gets a fixed base and holds its initial
//! pose (every joint within 0.05 rad), a floating robot (legs, wheels) gets
//! a ground, is placed on it and stays on its feet (base height within 20 %
//! of its initial height, in contact for more than half the run), and no
//! state interpenetrates (our GJK at every step, python-fcl every 10th step
//! of the export). Bounds chosen before the runs, from the issue (32, item 3).

use crate::support;

use std::path::Path;
use support::{pybullet_data, python, scratch_dir, sdrs};

/// A run: trajectory header and rows, summary and import report.
struct Run {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
    summary: serde_json::Value,
    report: serde_json::Value,
}

/// Imports `urdf` with no option, simulates 2000 steps of the scene's Δt
/// (1 ms) with an export, and checks the export with python-fcl.
fn import_and_run(dir: &Path, urdf: &Path, name: &str) -> Run {
    let scene = dir.join(format!("{name}.yaml"));
    let report = dir.join(format!("{name}_report.json"));
    support::run_ok(
        sdrs()
            .args(["import", "-q", "--out"])
            .arg(&scene)
            .arg("--report")
            .arg(&report)
            .arg(urdf),
    );
    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(text.contains("dt: 0.001"), "{name}: Δt is not 1 ms");
    let (csv, json, export) = (
        dir.join(format!("{name}.csv")),
        dir.join(format!("{name}.json")),
        dir.join(format!("{name}_export")),
    );
    support::run_ok(
        sdrs()
            .args(["simulate", "-q", "--steps", "2000", "--out"])
            .arg(&csv)
            .arg("--json")
            .arg(&json)
            .arg("--export")
            .arg(&export)
            .arg(&scene),
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 2001);
    assert!(rows.iter().all(|r| r.iter().all(|v| v.is_finite())));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    if let Some(d) = summary["contact"]["min_distance"].as_f64() {
        assert!(d > 0.0, "{name}: min distance {d}");
    }
    let check = python()
        .arg(support::root().join("tools/check/check_separation.py"))
        .arg(&export)
        .args(["--every", "10"])
        .output()
        .unwrap();
    assert!(
        check.status.success(),
        "{name}: python-fcl found interpenetration:\n{}\n{}",
        String::from_utf8_lossy(&check.stdout),
        String::from_utf8_lossy(&check.stderr)
    );
    let report = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    Run {
        header,
        rows,
        summary,
        report,
    }
}

/// An arm: fixed base (one column per joint), no ground, every joint within
/// 0.05 rad of its initial value for 2 s.
fn arm_holds(rel: &str, name: &str, joints: usize) {
    let dir = scratch_dir(&format!("first-hour-{name}"));
    let r = import_and_run(&dir, &pybullet_data().join(rel), name);
    let base = r.report["ready"]["base"].as_str().unwrap();
    assert!(base.starts_with("fixed"), "{name}: {base}");
    assert!(
        r.report["ready"]["ground_lift"].is_null(),
        "{name}: a ground"
    );
    assert_eq!(r.header.len(), joints + 1, "{name}: {:?}", r.header);
    let worst = r
        .rows
        .iter()
        .flat_map(|row| {
            row[1..]
                .iter()
                .zip(&r.rows[0][1..])
                .map(|(v, v0)| (v - v0).abs())
        })
        .fold(0.0, f64::max);
    eprintln!(
        "{name}: {joints} joints, base {base}; largest deviation from the initial pose {worst:.3e} rad"
    );
    assert!(worst <= 0.05, "{name}: {worst}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A floating robot: placed on a ground, base height within 20 % of its
/// initial height for 2 s, in contact for more than 1000 of 2000 steps.
fn stands(rel: &str, name: &str) {
    let dir = scratch_dir(&format!("first-hour-{name}"));
    let r = import_and_run(&dir, &pybullet_data().join(rel), name);
    let base = r.report["ready"]["base"].as_str().unwrap();
    assert!(base.starts_with("floating"), "{name}: {base}");
    let lift = r.report["ready"]["ground_lift"]
        .as_f64()
        .unwrap_or_else(|| panic!("{name}: no ground"));
    // The root frame starts `lift` above the ground (the import's base is
    // at the origin); the free joint's z is its offset.
    assert!(lift > 0.0, "{name}: lift {lift}");
    let zs: Vec<usize> = (0..r.header.len())
        .filter(|&i| r.header[i].ends_with(":z"))
        .collect();
    let [z] = zs.as_slice() else {
        panic!("{name}: one free joint expected: {:?}", r.header)
    };
    let heights: Vec<f64> = r.rows.iter().map(|row| lift + row[*z]).collect();
    let worst = heights
        .iter()
        .map(|h| (h - heights[0]).abs() / heights[0])
        .fold(0.0, f64::max);
    let in_contact = r.summary["contact"]["steps_in_contact"].as_u64().unwrap();
    eprintln!(
        "{name}: base {base}; initial height {:.4} m, final {:.4} m, worst relative change {worst:.3}; contact in {in_contact} steps",
        heights[0],
        heights.last().unwrap(),
    );
    assert!(worst <= 0.2, "{name}: {worst}");
    assert!(in_contact > 1000, "{name}: not on the ground");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_imported_arm_holds_its_pose() {
    if support::skip_without_venv() {
        return;
    }
    arm_holds("kuka_iiwa/model.urdf", "kuka", 7);
}

#[test]
fn an_arm_whose_root_link_has_a_mass_gets_a_fixed_base() {
    if support::skip_without_venv() {
        return;
    }
    arm_holds("xarm/xarm6_robot.urdf", "xarm6", 6);
}

#[test]
fn an_imported_quadruped_stands_on_the_ground() {
    if support::skip_without_venv() {
        return;
    }
    stands("a1/a1.urdf", "a1");
}

#[test]
fn a_wheeled_robot_rests_on_the_ground() {
    if support::skip_without_venv() {
        return;
    }
    stands("r2d2.urdf", "r2d2");
}

#[test]
#[ignore = "slow: cargo test --release -p sdrs-cli --test integration -- --ignored first_hour::"]
fn laikago_stands_on_the_ground() {
    if support::skip_without_venv() {
        return;
    }
    stands("laikago/laikago_toes_zup.urdf", "laikago");
}

#[test]
#[ignore = "slow: cargo test --release -p sdrs-cli --test integration -- --ignored first_hour::"]
fn minitaur_stands_on_the_ground() {
    if support::skip_without_venv() {
        return;
    }
    stands("quadruped/minitaur.urdf", "minitaur");
}
