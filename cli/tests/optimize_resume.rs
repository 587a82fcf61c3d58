//! `sdrs optimize --resume`: an interrupted run continued from its
//! checkpoint gives bitwise the same result as an uninterrupted run; the
//! checkpoint refuses a different seed; `--seed` drives `init_noise`; the
//! locomotion task metrics and the shapes picture are written.

use crate::support;

use std::path::Path;
use support::{robots, scratch_dir, sdrs};

/// The biped task shortened to 80 steps, with a seeded perturbation of the
/// initial controller, in `dir`.
fn short_task(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(robots("biped/task.yaml")).unwrap();
    let scene = robots("biped/scene.yaml");
    let text = text
        .replace("scene: scene.yaml", &format!("scene: {}", scene.display()))
        .replace("horizon: 400", "horizon: 80")
        .replace("  iters: 300", "  iters: 5\n  init_noise: 0.01");
    assert!(text.contains("horizon: 80") && text.contains("init_noise"));
    let p = dir.join("task.yaml");
    std::fs::write(&p, text).unwrap();
    p
}

fn run(task: &Path, args: &[&str]) -> std::process::Output {
    sdrs()
        .args(["optimize", "-q"])
        .arg(task)
        .args(args)
        .output()
        .unwrap()
}

/// history.csv without the timing columns (the last three).
fn history_numbers(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("history.csv"))
        .unwrap()
        .lines()
        .map(|l| l.rsplitn(4, ',').last().unwrap().to_string())
        .collect()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn resumed_run_is_bitwise_the_uninterrupted_run() {
    let dir = scratch_dir("optimize-resume");
    let task = short_task(&dir);
    let (full, part) = (dir.join("full"), dir.join("part"));
    let s = |p: &Path| p.to_str().unwrap().to_string();
    assert!(
        run(&task, &["--iters", "5", "--seed", "7", "--out", &s(&full)])
            .status
            .success()
    );
    assert!(
        run(&task, &["--iters", "2", "--seed", "7", "--out", &s(&part)])
            .status
            .success()
    );
    // A different seed cannot continue this run.
    let bad = run(
        &task,
        &["--iters", "5", "--seed", "8", "--resume", &s(&part)],
    );
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && err.contains("--seed"), "{err}");
    let r = run(
        &task,
        &["--iters", "5", "--seed", "7", "--resume", &s(&part)],
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let (a, b) = (history_numbers(&full), history_numbers(&part));
    assert_eq!(a.len(), 1 + 1 + 5);
    assert_eq!(a, b, "history (losses, gradient norms, radii, acceptance)");
    let (sa, sb) = (summary(&full), summary(&part));
    for k in ["final_loss", "initial_loss", "design", "controller"] {
        assert_eq!(sa[k], sb[k], "{k}");
    }
    assert_eq!(sb["extra"]["resumed_from_iteration"], 2);
    assert_eq!(
        std::fs::read(full.join("design.yaml")).unwrap(),
        std::fs::read(part.join("design.yaml")).unwrap()
    );
    // Metrics and the shapes picture are written.
    let m = &sa["extra"]["metrics"]["final"];
    assert!(m["distance"].is_f64() && m["upright_at_horizon"].is_boolean());
    let svg = std::fs::read_to_string(full.join("shapes.svg")).unwrap();
    assert!(svg.contains("biped/left_foot (optimized)") && svg.matches("<polygon").count() > 50);
    // The seed matters: another seed starts elsewhere.
    let other = dir.join("other");
    assert!(
        run(&task, &["--iters", "0", "--seed", "8", "--out", &s(&other)])
            .status
            .success()
    );
    assert_ne!(summary(&other)["initial_loss"], sa["initial_loss"]);
    // --resume on a directory without a checkpoint: a clear error.
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let e = run(&task, &["--resume", &s(&empty)]);
    let err = String::from_utf8_lossy(&e.stderr);
    assert!(
        !e.status.success() && err.contains("checkpoint.json"),
        "{err}"
    );
}
