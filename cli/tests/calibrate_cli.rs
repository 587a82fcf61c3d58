//! `sdrs calibrate` end to end: outputs and their schema, the calibrated
//! scene runs in `sdrs simulate` and reproduces the data, the result is
//! bitwise the same for 1 and 2 threads.

#[path = "../../tests/calibrate_support/mod.rs"]
mod calibrate_support;
use crate::support;
use support as common;

use calibrate_support::{Sampling, measured_csv, with_effects};

fn setup(name: &str) -> (common::Scratch, std::path::PathBuf, std::path::PathBuf) {
    let dir = common::scratch_dir(name);
    let scene = common::robots("calibrate/arm2.yaml");
    let text = std::fs::read_to_string(&scene).unwrap();
    let data = measured_csv(
        &with_effects(&text, &["{effect: joint_friction, on: all, values: [0.4]}"]),
        &Sampling::default(),
    );
    let m = dir.join("measured.csv");
    std::fs::write(&m, data).unwrap();
    (dir, scene, m)
}

fn calibrate(scene: &std::path::Path, m: &std::path::Path, out: &std::path::Path, threads: &str) {
    let o = common::sdrs()
        .env("RAYON_NUM_THREADS", threads)
        .args([
            "calibrate",
            scene.to_str().unwrap(),
            "--measured",
            m.to_str().unwrap(),
        ])
        .args([
            "--out",
            out.to_str().unwrap(),
            "--effects",
            "joint_damping,joint_friction,armature,payload",
            "-q",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn calibrate_writes_a_runnable_scene_and_the_documented_json() {
    let (dir, scene, m) = setup("calibrate-cli");
    let out = dir.join("out");
    calibrate(&scene, &m, &out, "2");
    for f in [
        "calibrated.yaml",
        "calibration.json",
        "report.md",
        "report.html",
        "residuals.svg",
        "channel_shoulder.svg",
        "channel_elbow.svg",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("calibration.json")).unwrap()).unwrap();
    assert_eq!(j["verdict"], "effect");
    assert_eq!(j["effect"], "joint_friction");
    let f = j["parameters"]["joint_friction/all"].as_f64().unwrap();
    assert!((f - 0.4).abs() < 0.02, "fitted {f}");
    let c = &j["confidence"]["joint_friction/all"];
    assert!(c["low"].as_f64().unwrap() < f && f < c["high"].as_f64().unwrap());
    for k in ["gap_before", "gap_after"] {
        assert!(j[k]["overall"].as_f64().unwrap() > 0.0);
        assert!(j[k]["channels"]["shoulder"].is_number() && j[k]["channels"]["elbow"].is_number());
    }
    assert!(
        j["gap_after"]["overall"].as_f64().unwrap()
            < 0.1 * j["gap_before"]["overall"].as_f64().unwrap()
    );
    let ranking = j["ranking"].as_array().unwrap();
    assert!(ranking.len() >= 4);
    assert_eq!(ranking[0]["candidate"], "joint_friction/all");
    // The calibrated scene runs and reproduces the measured data to the noise.
    let traj = dir.join("calibrated.csv");
    let o = common::sdrs()
        .args([
            "simulate",
            out.join("calibrated.yaml").to_str().unwrap(),
            "--steps",
            "610",
            "--out",
            traj.to_str().unwrap(),
            "-q",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let sim: Vec<Vec<f64>> = std::fs::read_to_string(&traj)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let meas: Vec<Vec<f64>> = std::fs::read_to_string(&m)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let dt = 0.002;
    let mut sq = 0.0;
    let mut n = 0;
    for row in &meas {
        let x = row[0] / dt;
        let k = x.floor() as usize;
        let w = x - k as f64;
        for c in 1..3 {
            let v = (1.0 - w) * sim[k][c] + w * sim[k + 1][c];
            sq += (v - row[c]).powi(2);
            n += 1;
        }
    }
    let rms = (sq / n as f64).sqrt();
    assert!(
        rms < 2e-4,
        "calibrated scene vs measured: RMS {rms} (noise 1e-4)"
    );
}

#[test]
fn calibration_is_bitwise_deterministic_across_thread_counts() {
    let (dir, scene, m) = setup("calibrate-det");
    let (a, b) = (dir.join("a"), dir.join("b"));
    calibrate(&scene, &m, &a, "1");
    calibrate(&scene, &m, &b, "2");
    for f in [
        "calibration.json",
        "calibrated.yaml",
        "report.md",
        "report.html",
        "residuals.svg",
    ] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f} differs"
        );
    }
}

/// The bad-input test's scene and a well-formed measured file.
fn bad_input_scene() -> std::path::PathBuf {
    common::robots("calibrate/arm2.yaml")
}

fn good_csv(n: usize) -> String {
    let mut s = String::from("t,shoulder,elbow\n");
    for i in 0..n {
        let t = i as f64 * 0.02;
        s.push_str(&format!("{t},{},{}\n", 0.2 + 0.1 * t, -0.3 + 0.2 * t));
    }
    s
}

#[test]
fn cli_reports_errors_with_exit_code_1() {
    let dir = common::scratch_dir("calibrate-cli-bad");
    let m = dir.join("measured.csv");
    std::fs::write(
        &m,
        good_csv(20).replace("t,shoulder,elbow", "t,shoulder,wrist"),
    )
    .unwrap();
    let out = dir.join("out");
    let o = common::sdrs()
        .args([
            "calibrate",
            bad_input_scene().to_str().unwrap(),
            "--measured",
            m.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-q",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("measured.csv") && err.contains("\"wrist\""),
        "{err}"
    );
    assert!(!out.exists());
}

/// `--measured` repeated: one parameter set fitted across two recordings
/// (arm2 with a hidden damping 0.3 on both joints, the second started from
/// shoulder −0.3, elbow 0.3 rad); `calibration.json` lists both
/// recordings with their gaps before and after, and the fit recovers the
/// damping (data from the scene's own step, noise 1e-4: within 2 %).
#[test]
fn calibrate_fits_one_model_across_repeated_measured_files() {
    let dir = common::scratch_dir("calibrate-cli-two");
    let scene = common::robots("calibrate/arm2.yaml");
    let text = std::fs::read_to_string(&scene).unwrap();
    let hidden = ["{effect: joint_damping, on: all, values: [0.3]}"];
    let from_a = "shoulder: {q: [0.2], qdot: [0]}\n      elbow: {q: [-0.3], qdot: [0]}";
    let from_b = "shoulder: {q: [-0.3], qdot: [0]}\n      elbow: {q: [0.3], qdot: [0]}";
    assert!(text.contains(from_a));
    let (a, b) = (dir.join("a.csv"), dir.join("b.csv"));
    let s = Sampling {
        jitter: 0.0,
        ..Default::default()
    };
    std::fs::write(&a, measured_csv(&with_effects(&text, &hidden), &s)).unwrap();
    let text_b = text.replace(from_a, from_b);
    std::fs::write(&b, measured_csv(&with_effects(&text_b, &hidden), &s)).unwrap();
    let out = dir.join("out");
    let o = common::sdrs()
        .args(["calibrate", scene.to_str().unwrap()])
        .args(["--measured", a.to_str().unwrap()])
        .args(["--measured", b.to_str().unwrap()])
        .args(["--out", out.to_str().unwrap()])
        .args(["--effects", "joint_damping", "-q"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("calibration.json")).unwrap()).unwrap();
    assert_eq!(j["candidate"], "joint_damping/all", "{}", j["reason"]);
    let c = j["parameters"]["joint_damping/all"].as_f64().unwrap();
    assert!((c / 0.3 - 1.0).abs() < 0.02, "fitted {c}");
    let r = j["recordings"].as_array().unwrap();
    assert_eq!(r.len(), 2);
    assert!(r[1]["path"].as_str().unwrap().ends_with("b.csv"));
    assert_eq!(r[1]["initial"], "first sample");
    for g in r {
        assert!(
            g["holdout_after"].as_f64().unwrap() < 0.1 * g["holdout_before"].as_f64().unwrap(),
            "{g}"
        );
    }
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("## Recordings"), "{md}");
}

/// `report.html`: self-contained (no network: no external source, link or
/// URL but the SVG namespace), with the verdict and its reason, the floor
/// against the gap, every candidate of the ranking, the fitted parameter
/// with its interval, the identifiability and residual regression
/// sections and every plot inline; in Chromium (tier 2), every plot
/// draws, the console stays silent, and a screenshot is taken.
#[test]
fn report_html_shows_the_verdict_every_candidate_and_the_plots() {
    let (dir, scene, m) = setup("calibrate-html");
    let out = dir.join("out");
    calibrate(&scene, &m, &out, "2");
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("calibration.json")).unwrap()).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    assert!(
        html.contains("data-verdict=\"effect\"")
            && html.contains("Verdict: Missing effect: joint_friction"),
        "verdict missing"
    );
    let reason = j["reason"].as_str().unwrap();
    let first_words: String = reason.replace('`', "").chars().take(30).collect();
    assert!(
        html.replace("<code>", "")
            .replace("</code>", "")
            .contains(&first_words),
        "reason missing: {first_words}"
    );
    for c in j["ranking"].as_array().unwrap() {
        let c = c["candidate"].as_str().unwrap();
        assert!(
            html.contains(&format!("<td>{c}</td>")),
            "candidate {c} missing"
        );
    }
    for s in [
        "id=\"floor\"",
        "error floor F",
        "gap as given",
        "gap calibrated",
        "id=\"parameters\"",
        "<td>joint_friction/all</td>",
        "id=\"identifiability\"",
        "Residual force regression",
        "<tr class=\"chosen\">",
    ] {
        assert!(html.contains(s), "missing {s}");
    }
    let f = j["parameters"]["joint_friction/all"].as_f64().unwrap();
    assert!(html.contains(&format!("{f:.3e}")), "fitted value missing");
    // The three plots, inline.
    assert_eq!(html.matches("<svg class=\"plot\"").count(), 3);
    for bad in ["src=", "href=", "<link", "@import", "url("] {
        assert!(!html.contains(bad), "external reference {bad}");
    }
    let without_ns = html.replace("http://www.w3.org/2000/svg", "");
    assert!(!without_ns.contains("http"), "a URL in the page");

    if common::skip_without_chromium() {
        return;
    }
    use support::browser::{chromium, console_messages, file_url};
    let page = out.join("report.html");
    let (dom, log) = chromium(&file_url(&page, ""), &dir.join("chrome1"), &["--dump-dom"]);
    assert!(
        dom.contains("plots rendered: 3 of 3"),
        "render check failed: {}",
        dom.split("render-check")
            .nth(1)
            .unwrap_or("(no check element)")
    );
    let console = console_messages(&log);
    assert!(console.is_empty(), "console messages: {console:?}");
    let shot = dir.join("report.png");
    chromium(
        &file_url(&page, ""),
        &dir.join("chrome2"),
        &[
            &format!("--screenshot={}", shot.display()),
            "--window-size=1200,3000",
        ],
    );
    let png = std::fs::read(&shot).expect("no screenshot");
    assert_eq!(&png[1..4], b"PNG");
    assert!(
        png.len() > 100_000,
        "a near-empty screenshot ({} bytes)",
        png.len()
    );
    if let Some(keep) = std::env::var_os("SDRS_KEEP_SCREENSHOT") {
        std::fs::copy(&shot, keep).unwrap();
    }
}

/// `--measured log.mcap` through the command line: a JSON JointState log
/// on another topic with the joints named as a ROS driver names them and
/// a gripper the scene lacks, read with `--topic` and `--rename`; the
/// calibration finds what the CSV of the same samples finds. Without the
/// renames it fails with exit code 1, naming the file, topic, message and
/// joint, and writes nothing.
#[test]
fn calibrate_reads_an_mcap_log_with_topic_and_renames() {
    let (dir, scene, m) = setup("calibrate-cli-mcap");
    let csv = std::fs::read_to_string(&m).unwrap();
    let log = dir.join("run.mcap");
    {
        let f = std::io::BufWriter::new(std::fs::File::create(&log).unwrap());
        let mut w = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .create(f)
            .unwrap();
        let ch = w
            .add_channel(0, "/robot/joint_states", "json", &Default::default())
            .unwrap();
        for (k, line) in csv.lines().skip(1).enumerate() {
            let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            let ns = (v[0] * 1e9).round() as u64 + 1_700_000_000_000_000_000;
            let msg = serde_json::json!({
                "header": {"stamp": {"sec": ns / 1_000_000_000, "nanosec": ns % 1_000_000_000}, "frame_id": ""},
                "name": ["j_elbow", "j_shoulder", "gripper"],
                "position": [v[2], v[1], 0.0],
                "velocity": [],
                "effort": [],
            });
            let h = mcap::records::MessageHeader {
                channel_id: ch,
                sequence: k as u32,
                log_time: ns,
                publish_time: ns,
            };
            w.write_to_known_channel(&h, &serde_json::to_vec(&msg).unwrap())
                .unwrap();
        }
        w.finish().unwrap();
    }
    let run = |out: &std::path::Path, renames: &[&str]| {
        let mut c = common::sdrs();
        c.args(["calibrate", scene.to_str().unwrap()])
            .args(["--measured", log.to_str().unwrap()])
            .args(["--out", out.to_str().unwrap()])
            .args(["--topic", "/robot/joint_states"])
            .args(["--effects", "joint_damping,joint_friction", "-q"]);
        for r in renames {
            c.args(["--rename", r]);
        }
        c.output().unwrap()
    };
    let bad = dir.join("bad");
    let o = run(&bad, &[]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("run.mcap")
            && err.contains("topic \"/robot/joint_states\", message 1 (log time")
            && err.contains("joint \"j_elbow\" is not a coordinate"),
        "{err}"
    );
    assert!(!bad.exists());
    let out = dir.join("out");
    let o = run(&out, &["j_shoulder=shoulder", "j_elbow=elbow", "gripper="]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("calibration.json")).unwrap()).unwrap();
    assert_eq!(j["candidate"], "joint_friction/all", "{}", j["reason"]);
    let f = j["parameters"]["joint_friction/all"].as_f64().unwrap();
    assert!((f - 0.4).abs() < 0.02, "fitted {f}");
    assert!(out.join("report.html").exists());
}
