//! `sdrs view` end to end: the viewer of a four-chain run opens in headless
//! Chromium without a console error, draws every hull, and two screenshots
//! at different slider positions differ; the `.glb` of the same run
//! validates (trimesh + `tools/check/check_glb.py`: node count, animation length
//! = trajectory length, last keyframe = last recorded pose); an optimize
//! result shows both designs; bad input is a clear error.

use crate::support;

use std::path::Path;
use support::browser::{body_attr, chromium, console_messages, file_url, png_pixels};
use support::{python, root, run_ok, scratch_dir, sdrs};

/// Dumps the DOM of `page#fragment` and checks the page finished without
/// any error (page hook and console).
fn open_page(page: &Path, fragment: &str, profile: &Path) -> String {
    let (dom, log) = chromium(&file_url(page, fragment), profile, &["--dump-dom"]);
    assert_eq!(
        body_attr(&dom, "data-ready"),
        Some("1"),
        "the viewer did not finish: {}",
        dom.split("id=\"errors\"").nth(1).unwrap_or("(no DOM)")
    );
    assert_eq!(body_attr(&dom, "data-errors"), Some("0"), "{dom}");
    let console = console_messages(&log);
    assert!(console.is_empty(), "console messages: {console:?}");
    dom
}

/// `label:count` pairs of a body attribute.
fn counts(attr: &str) -> Vec<(String, usize)> {
    attr.split(',')
        .map(|kv| {
            let (k, v) = kv.rsplit_once(':').unwrap();
            (k.to_string(), v.parse().unwrap())
        })
        .collect()
}

#[test]
fn four_chain_viewer_plays_and_glb_validates() {
    if support::skip_without_chromium() {
        return;
    }
    let dir = scratch_dir("view-four-chains");
    let exp = dir.join("run");
    run_ok(
        sdrs()
            .args(["simulate"])
            .arg(root().join("robots/four_chains.yaml"))
            .args(["--steps", "200", "-q", "--planes", "--export"])
            .arg(&exp),
    );
    // Recording planes and writing a viewer leave the trajectory unchanged.
    let (a, b) = (dir.join("a.csv"), dir.join("b.csv"));
    let scene = root().join("robots/four_chains.yaml");
    run_ok(
        sdrs()
            .arg("simulate")
            .arg(&scene)
            .args(["--steps", "200", "-q", "--out"])
            .arg(&a),
    );
    run_ok(
        sdrs()
            .arg("simulate")
            .arg(&scene)
            .args(["--steps", "200", "-q", "--planes", "--export"])
            .arg(dir.join("run2"))
            .arg("--view")
            .arg(dir.join("quick.html"))
            .arg("--out")
            .arg(&b),
    );
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    assert!(
        std::fs::read_to_string(dir.join("quick.html"))
            .unwrap()
            .starts_with("<!doctype html>")
    );
    let page = dir.join("view.html");
    run_ok(sdrs().arg("view").arg(&exp).arg("--out").arg(&page));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        !html.contains("http://") && !html.contains("https://cdn"),
        "the page must not fetch anything"
    );

    // Every hull drawn (4 chains × 8 links, one hull each), pixels covered.
    let dom = open_page(&page, "#frame=0&check=1", &dir.join("c0"));
    assert_eq!(
        counts(body_attr(&dom, "data-meshes").unwrap()),
        [("run".into(), 32)]
    );
    let drawn = counts(body_attr(&dom, "data-drawn").unwrap());
    assert!(drawn[0].1 > 2000, "hulls cover too few pixels: {drawn:?}");
    // The slider moved: the page shows the frame the hash asked for.
    let dom = open_page(&page, "#frame=200", &dir.join("c1"));
    assert_eq!(body_attr(&dom, "data-frame"), Some("200"));
    assert!(
        dom.contains("t = 1.000 s") && dom.contains("(step 200 of 200)"),
        "time label"
    );

    // Two screenshots: rest pose vs after 1 s of driven swinging.
    let shot = |frag: &str, name: &str| {
        let png = dir.join(name);
        chromium(
            &file_url(&page, frag),
            &dir.join(format!("p-{name}")),
            &[
                &format!("--screenshot={}", png.display()),
                "--window-size=900,600",
            ],
        );
        png_pixels(&png)
    };
    let (a, wa, ha) = shot("#frame=0", "t0.png");
    let (b, wb, hb) = shot("#frame=200", "t1.png");
    assert_eq!((wa, ha), (wb, hb));
    let changed = a.chunks(4).zip(b.chunks(4)).filter(|(x, y)| x != y).count();
    assert!(
        changed > 2000,
        "the screenshots differ in only {changed} pixels"
    );

    // glb of the same run, checked independently.
    let glb = dir.join("run.glb");
    run_ok(sdrs().arg("view").arg(&exp).arg("--out").arg(&glb));
    let o = python()
        .arg(root().join("tools/check/check_glb.py"))
        .arg(&glb)
        .arg("--poses")
        .arg(exp.join("poses.csv"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["link_nodes"], 32);
    assert_eq!(v["nodes"], 33);
    assert_eq!(v["trimesh_graph_nodes"], 32);
    assert_eq!(v["keyframes"], 201);
    assert!(
        (v["duration"].as_f64().unwrap() - 200.0 * 0.005).abs() < 1e-6,
        "{v}"
    );
    assert_eq!(v["checked_against_poses"], 32);

    // Overwrites only its own files.
    let user = dir.join("notes.html");
    std::fs::write(&user, "mine").unwrap();
    let o = sdrs()
        .arg("view")
        .arg(&exp)
        .arg("--out")
        .arg(&user)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("was not written by `sdrs view`"));
    assert_eq!(std::fs::read_to_string(&user).unwrap(), "mine");
    run_ok(sdrs().arg("view").arg(&exp).arg("--out").arg(&page));
}

#[test]
fn optimize_result_shows_both_designs() {
    let dir = scratch_dir("view-optimize");
    let out = dir.join("opt");
    run_ok(
        sdrs()
            .arg("optimize")
            .arg(root().join("robots/chain_reach/task.yaml"))
            .args(["--iters", "1", "-q", "--out"])
            .arg(&out),
    );
    // The report embeds the stills next to the convergence plot.
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    let plot = report
        .find("best loss per iteration")
        .expect("convergence plot");
    let still = report.find("optimized, horizon").expect("robot still");
    assert!(plot < still && report.matches("<polygon").count() > 100);

    let page = dir.join("opt.html");
    run_ok(sdrs().arg("view").arg(&out).arg("--out").arg(&page));
    let dom = open_page(&page, "#frame=250&check=1", &dir.join("c0"));
    let meshes = counts(body_attr(&dom, "data-meshes").unwrap());
    let drawn = counts(body_attr(&dom, "data-drawn").unwrap());
    let labels: Vec<&str> = meshes.iter().map(|(k, _)| k.as_str()).collect();
    assert_eq!(labels, ["initial", "optimized", "iteration"]);
    // Same robot (25 hulls) in each, and each covers pixels when drawn alone.
    assert!(meshes.iter().all(|(_, n)| *n == 25), "{meshes:?}");
    assert!(drawn.iter().all(|(_, n)| *n > 1000), "{drawn:?}");
    assert_eq!(body_attr(&dom, "data-iteration"), Some("1"));
}

#[test]
fn bad_inputs_are_clear_errors() {
    let dir = scratch_dir("view-errors");
    let o = sdrs()
        .arg("view")
        .arg(dir.join("missing"))
        .arg("--out")
        .arg(dir.join("v.html"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("missing: no such file or directory"),
        "{err}"
    );
    let o = sdrs()
        .arg("view")
        .arg(&*dir)
        .arg("--out")
        .arg(dir.join("v.html"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("neither a scene file"), "{err}");
    // A corrupted export names the file and line.
    let exp = dir.join("exp");
    run_ok(
        sdrs()
            .arg("simulate")
            .arg(root().join("robots/pendulum.yaml"))
            .args(["--steps", "3", "-q", "--export"])
            .arg(&exp),
    );
    std::fs::write(exp.join("poses.csv"), "step,t\n0,0,7,x\n").unwrap();
    let o = sdrs()
        .arg("view")
        .arg(&exp)
        .arg("--out")
        .arg(dir.join("v.html"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("poses.csv: line 2: 4 fields, expected 16"),
        "{err}"
    );
    assert!(!dir.join("v.html").exists());
}
