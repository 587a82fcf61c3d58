//! End-to-end checks of the `sdrs` binary.

use crate::support;

use support::{robots, scratch_dir, sdrs};

#[test]
fn determinism_same_scene_twice_gives_byte_identical_csv() {
    let dir = scratch_dir("determinism");
    let mut outputs = Vec::new();
    for run in 0..2 {
        let out = dir.join(format!("run{run}.csv"));
        let status = sdrs()
            .args(["simulate", "--steps", "300", "-q", "--out"])
            .arg(&out)
            .arg(robots("four_chains.yaml"))
            .status()
            .unwrap();
        assert!(status.success());
        outputs.push(std::fs::read(&out).unwrap());
    }
    assert!(outputs[0].len() > 1000);
    assert_eq!(outputs[0], outputs[1], "two runs differ");
}

#[test]
fn determinism_holds_across_rayon_thread_counts() {
    // Pair results are reduced in pair order, so the thread count cannot
    // change a single bit of the trajectory.
    let dir = scratch_dir("threads");
    let mut outputs = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.join(format!("t{threads}.csv"));
        let status = sdrs()
            .env("RAYON_NUM_THREADS", threads)
            .args(["simulate", "--steps", "400", "-q", "--out"])
            .arg(&out)
            .arg(robots("four_chains.yaml"))
            .status()
            .unwrap();
        assert!(status.success());
        outputs.push(std::fs::read(&out).unwrap());
    }
    assert_eq!(outputs[0], outputs[1]);
}

#[test]
fn simulate_writes_csv_with_joint_columns_and_summary_json() {
    let dir = scratch_dir("outputs");
    let (csv, json) = (dir.join("traj.csv"), dir.join("summary.json"));
    let status = sdrs()
        .args(["simulate", "-q", "--steps", "50", "--out"])
        .arg(&csv)
        .arg("--json")
        .arg(&json)
        .arg(robots("triple_pendulum.yaml"))
        .status()
        .unwrap();
    assert!(status.success());
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "t,j1,j2,j3");
    assert_eq!(lines.count(), 51);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(summary["steps"], 50);
    assert_eq!(summary["dt"], 0.001);
    for key in [
        "wall_seconds",
        "newton",
        "final_state",
        "energy",
        "linear_momentum",
        "stages",
    ] {
        assert!(!summary[key].is_null(), "summary lacks {key}");
    }
    assert!(summary["newton"]["max_iterations"].as_u64().unwrap() >= 1);
}

#[test]
fn bad_scene_exits_nonzero_with_a_message_and_no_panic() {
    let dir = scratch_dir("bad");
    let bad = dir.join("bad.yaml");
    std::fs::write(&bad, "dt: -1\nrobots: []\n").unwrap();
    let out = sdrs().arg("simulate").arg(&bad).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.yaml") && err.contains("dt"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn simulate_refuses_to_overwrite_its_input() {
    let dir = scratch_dir("overwrite");
    let scene = dir.join("scene.yaml");
    std::fs::copy(robots("pendulum.yaml"), &scene).unwrap();
    let before = std::fs::read(&scene).unwrap();
    let out = sdrs()
        .args(["simulate", "-q", "--steps", "5", "--out"])
        .arg(&scene)
        .arg(&scene)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert_eq!(std::fs::read(&scene).unwrap(), before);
}

#[test]
fn velocity_columns_units_and_link_names_are_written() {
    let dir = scratch_dir("readable");
    let (csv, json, export) = (dir.join("t.csv"), dir.join("s.json"), dir.join("exp"));
    let status = sdrs()
        .args(["simulate", "-q", "--steps", "20", "--velocities", "--out"])
        .arg(&csv)
        .arg("--json")
        .arg(&json)
        .arg("--export")
        .arg(&export)
        .arg(robots("pendulum.yaml"))
        .status()
        .unwrap();
    assert!(status.success());
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(text.lines().next().unwrap(), "t,hinge,hinge:v");
    let dt = rows[1][0] - rows[0][0];
    for k in 1..rows.len() {
        // The velocity column is the backward difference of the position.
        let v = (rows[k][1] - rows[k - 1][1]) / dt;
        assert!((rows[k][2] - v).abs() <= 1e-9 * v.abs().max(1.0), "row {k}");
    }
    assert_eq!(rows[0][2], 0.0, "initial velocity of the pendulum scene");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(summary["units"]["dt"], "s");
    assert_eq!(summary["units"]["contact.min_distance"], "m");
    let poses = std::fs::read_to_string(export.join("poses.csv")).unwrap();
    assert!(poses.starts_with("step,t,link,link_name,"), "{poses:.80}");
    assert!(
        poses.lines().nth(1).unwrap().contains(",pendulum/bob,"),
        "{poses:.200}"
    );
}
