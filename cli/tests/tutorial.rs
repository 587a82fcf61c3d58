//! `docs/tutorial.md` runs: every ```` ```sh ```` block (not those marked
//! ```` ```sh no-ci ````) is extracted and its commands are run in order by
//! one bash (`set -euo pipefail`, so variables carry from block to block)
//! in a scratch directory, with the built `sdrs` first on `PATH` and `REPO`
//! set to the repository root, as the tutorial's setup block says. A failing
//! command fails the test naming its block and line. Then the physics the
//! tutorial claims is checked on its outputs: the imported quadruped stays
//! on its feet (trunk height within 20 % of its initial height, contact with
//! the ground throughout), python-fcl finds no interpenetration, and
//! co-design ends with a lower loss than controller-only.

use crate::support;

use std::path::Path;
use std::process::Command;
use support::{root, scratch_dir};

/// One command of the tutorial: block number (1-based, counting the run
/// blocks), line in the markdown file, and the text (continuation lines
/// joined).
struct Cmd {
    block: usize,
    line: usize,
    text: String,
}

/// The commands of every ```` ```sh ```` block except ```` ```sh no-ci ````.
fn commands(md: &str) -> Vec<Cmd> {
    let mut out = Vec::new();
    let (mut inside, mut run, mut block) = (false, false, 0);
    let mut pending: Option<(usize, String)> = None;
    for (i, line) in md.lines().enumerate() {
        let t = line.trim();
        if !inside {
            if let Some(info) = t.strip_prefix("```") {
                inside = true;
                let words: Vec<&str> = info.split_whitespace().collect();
                run = words.first() == Some(&"sh") && !words.contains(&"no-ci");
                if run {
                    block += 1;
                }
            }
            continue;
        }
        if t == "```" {
            inside = false;
            assert!(pending.is_none(), "line {}: a `\\` ends the block", i + 1);
            continue;
        }
        if !run || (pending.is_none() && (t.is_empty() || t.starts_with('#'))) {
            continue;
        }
        let (start, mut text) = pending.take().unwrap_or((i + 1, String::new()));
        if let Some(head) = line.strip_suffix('\\') {
            text.push_str(head);
            pending = Some((start, text));
        } else {
            text.push_str(line);
            out.push(Cmd {
                block,
                line: start,
                text,
            });
        }
    }
    assert!(!inside, "an unclosed ``` block");
    out
}

/// Single-quotes `s` for bash.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

#[test]
fn the_tutorial_runs_and_its_robot_stands() {
    // The tutorial imports pybullet's robot files from `.venv`.
    if support::skip_without_venv() {
        return;
    }
    let md_path = root().join("docs/tutorial.md");
    let md = std::fs::read_to_string(&md_path).unwrap();
    let cmds = commands(&md);
    assert!(cmds.len() >= 8, "only {} commands found", cmds.len());
    let dir = scratch_dir("tutorial");
    // One script: before each command, its place is written to `.where`,
    // so a failure can be named.
    let mut script = String::from("set -euo pipefail\n");
    for c in &cmds {
        let place = format!(
            "block {} (docs/tutorial.md line {}): {}",
            c.block, c.line, c.text
        );
        script.push_str(&format!(
            "printf '%s' {} > .where\n{}\n",
            quote(&place),
            c.text
        ));
    }
    script.push_str("rm -f .where\n");
    let bin = Path::new(env!("CARGO_BIN_EXE_sdrs")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let t0 = std::time::Instant::now();
    let out = Command::new("bash")
        .arg("-c")
        .arg(&script)
        .current_dir(&dir)
        .env("PATH", path)
        .env("REPO", root())
        .output()
        .unwrap();
    eprintln!(
        "tutorial: {} commands in {:.1} s",
        cmds.len(),
        t0.elapsed().as_secs_f64()
    );
    let failed = std::fs::read_to_string(dir.join(".where")).ok();
    assert!(
        out.status.success() && failed.is_none(),
        "the tutorial failed at {}\nstderr:\n{}",
        failed
            .as_deref()
            .unwrap_or("(unknown: the script ended early)"),
        String::from_utf8_lossy(&out.stderr)
    );

    // The quadruped stands: its trunk's world height (poses.csv, `t2`)
    // stays within 20 % of its initial height, and it touches the ground.
    let poses = std::fs::read_to_string(dir.join("a1_export/poses.csv")).unwrap();
    let mut lines = poses.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let (name, z) = (col("link_name"), col("t2"));
    let heights: Vec<f64> = lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|r| r[name] == "a1_description/trunk")
        .map(|r| r[z].parse().unwrap())
        .collect();
    assert_eq!(heights.len(), 1001, "one trunk pose per step");
    let h0 = heights[0];
    let worst = heights
        .iter()
        .map(|h| (h - h0).abs() / h0)
        .fold(0.0, f64::max);
    eprintln!(
        "a1: trunk at {h0:.4} m, finally {:.4} m, worst relative change {worst:.2e}",
        heights.last().unwrap()
    );
    assert!(h0 > 0.2, "lifted onto the ground: {h0}");
    assert!(worst <= 0.2, "the trunk's height changed by {worst}");
    let json = |p: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join(p)).unwrap()).unwrap()
    };
    let sim = json("a1.json");
    assert_eq!(sim["contact"]["steps_in_contact"].as_u64(), Some(1000));
    assert!(sim["contact"]["min_distance"].as_f64().unwrap() > 0.0);
    // The energy balance closes: change = works − numerical dissipation.
    let b = &sim["energy"]["balance"];
    let f = |k: &str| b[k].as_f64().unwrap();
    let works = f("controller_work") + f("friction_work") + f("contact_work") + f("other_work");
    assert!(
        (f("change") - (works - f("numerical_dissipation"))).abs() < 1e-6,
        "{b}"
    );
    assert!(f("numerical_dissipation") >= 0.0);

    // python-fcl (the tutorial's `check_separation.py`) saw no contact.
    let sep = json("a1_separation.json");
    assert_eq!(sep["violation_count"].as_u64(), Some(0), "{sep}");
    assert!(sep["min_distance"].as_f64().unwrap() > 0.0);
    assert!(sep["steps_checked"].as_u64().unwrap() >= 100);

    // Co-design beats the controller alone, and both improved on the start.
    let (on, off) = (
        json("chain_codesign/summary.json"),
        json("chain_control/summary.json"),
    );
    let loss = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap();
    eprintln!(
        "chain_reach: co-design {:.4} m², controller-only {:.4} m² (from {:.4})",
        loss(&on, "final_loss"),
        loss(&off, "final_loss"),
        loss(&on, "initial_loss")
    );
    assert!(loss(&on, "final_loss") < loss(&off, "final_loss"));
    assert!(loss(&off, "final_loss") < loss(&off, "initial_loss"));
    assert!(std::fs::metadata(dir.join("cmp.svg")).unwrap().len() > 1000);

    // The schema the tutorial prints names the scene's top-level keys.
    let schema = std::fs::read_to_string(dir.join("scene-schema.yaml")).unwrap();
    for key in ["robots", "ground", "contact", "dt"] {
        assert!(schema.contains(&format!("  {key}:")), "{key}");
    }
}

#[test]
fn the_extractor_skips_no_ci_blocks_and_joins_continuations() {
    let md = "text\n```sh\n# comment\na \\\n  b\n\nc\n```\n```sh no-ci\nd\n```\n```yaml\ne\n```\n```sh\nf\n```\n";
    let c = commands(md);
    let got: Vec<(usize, usize, &str)> = c
        .iter()
        .map(|c| (c.block, c.line, c.text.as_str()))
        .collect();
    assert_eq!(got, vec![(1, 4, "a   b"), (1, 7, "c"), (2, 16, "f")]);
}
