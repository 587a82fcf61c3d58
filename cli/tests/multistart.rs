//! Smoke test of the multi-start script (`tools/bench/multistart.sh`,
//! `tools/bench/multistart_table.py`) on the chain-reaching task: three
//! seeds, co-design and `--design off` twins, three iterations each. Checks
//! what the script promises, not only that it runs: each seed's start is
//! another robot, every twin starts on its co-design seed's robot (the same
//! start loss, bitwise), the pick is the seed with the lowest best loss over
//! the runs' histories, each pick's replay passes python-fcl, and a wrong
//! `KEY` or `--exclude` is refused.

use crate::support;

use support::{root, scratch_dir};

fn script(out: &std::path::Path, key: &str) -> std::process::Command {
    let mut c = std::process::Command::new("bash");
    c.arg(root().join("tools/bench/multistart.sh"))
        .env("TASK", "robots/chain_reach/task.yaml")
        .env("KEY", key)
        .env("ETA", "0.01")
        .env("SEEDS", "1 2 3")
        .env("MODES", "on off")
        .env("ITERS", "3")
        .env("SDRS_BIN", env!("CARGO_BIN_EXE_sdrs"))
        .env("OUT", out);
    c
}

fn summary(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// The lowest loss in a run's history.csv (column `loss`).
fn best_loss(dir: &std::path::Path) -> f64 {
    let text = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse::<f64>().unwrap())
        .fold(summary(dir)["initial_loss"].as_f64().unwrap(), f64::min)
}

#[test]
fn multistart_twins_share_their_start_and_the_pick_is_the_lowest_loss() {
    if support::skip_without_venv() {
        return;
    }
    let out = scratch_dir("multistart");
    let o = script(&out, "design_init_noise").output().unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let start = |mode: &str, s: u64| {
        summary(&out.join(format!("{mode}_{s}")))["initial_loss"]
            .as_f64()
            .unwrap()
    };
    for s in 1..=3 {
        assert_eq!(
            start("on", s).to_bits(),
            start("off", s).to_bits(),
            "seed {s}: the twin starts on the co-design start's robot"
        );
    }
    assert_ne!(start("on", 1), start("on", 2), "seeds give other starts");
    let pick: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("pick.json")).unwrap()).unwrap();
    for mode in ["on", "off"] {
        let best = (1..=3)
            .map(|s| (best_loss(&out.join(format!("{mode}_{s}"))), s))
            .fold((f64::INFINITY, 0), |a, b| if b.0 < a.0 { b } else { a });
        assert_eq!(pick[mode]["seed"].as_u64(), Some(best.1), "{mode}: {pick}");
        assert_eq!(pick[mode]["best_loss"].as_f64(), Some(best.0));
    }
    assert!(stdout.contains("pick (on): seed"), "{stdout}");
    for mode in ["on", "off"] {
        let seed = pick[mode]["seed"].as_u64().unwrap();
        let sep =
            std::fs::read_to_string(out.join(format!("{mode}_{seed}/separation.txt"))).unwrap();
        assert!(
            !sep.is_empty() && sep.lines().all(|l| l.ends_with(": separated")),
            "{mode}: {sep}"
        );
    }
    assert!(stdout.contains("pick (on), python-fcl:"), "{stdout}");

    let bad = script(&out, "seed").output().unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("KEY: design_init_noise or init_noise"));
    let bad_rule = support::python()
        .arg(root().join("tools/bench/multistart_table.py"))
        .arg(&*out)
        .args(["on", "--", "1", "--exclude", "tall"])
        .output()
        .unwrap();
    assert!(!bad_rule.status.success());
    assert!(String::from_utf8_lossy(&bad_rule.stderr).contains("--exclude: grasp or upright"));
}
