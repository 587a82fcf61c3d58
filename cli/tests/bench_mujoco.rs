//! Smoke test of the SDRS-vs-MuJoCo benchmark harness
//! (`tools/bench/bench_vs_mujoco.sh`, `tools/bench/bench_mujoco.py`): a few steps at
//! small N. The harness's output is well formed (one row per N and engine,
//! a ratio per N, stage shares), and — a physics check, not only "it runs"
//! — the MuJoCo model integrates the same rigid bodies as SDRS: every
//! body's mass, centre of mass and principal inertia equal those of the
//! SDRS link (lumped vertex masses), and its degrees of freedom are SDRS's.

use crate::support;

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use support::{python, root, scratch_dir};

/// The SDRS four-chain scene with `n` links per chain.
fn sdrs_scene(n: usize) -> sdrs::scene::Scene {
    let path = root().join("robots/four_chains.yaml");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut spec: sdrs::scene::SceneSpec = serde_yaml::from_str(&text).unwrap();
    for r in &mut spec.robots {
        r.chain.as_mut().unwrap().links = n;
    }
    sdrs::scene::Scene::from_spec(spec, &path).unwrap()
}

#[test]
fn harness_is_well_formed_and_mujoco_bodies_match_sdrs_links() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("bench-mujoco");
    let rows_path = dir.join("rows.jsonl");
    let o = std::process::Command::new("bash")
        .arg(root().join("tools/bench/bench_vs_mujoco.sh"))
        .args([
            "--links",
            "2,3",
            "--steps",
            "15",
            "--repeats",
            "2",
            "--sdrs",
        ])
        .arg(env!("CARGO_BIN_EXE_sdrs"))
        .arg("--out")
        .arg(&rows_path)
        .env("PYTHON", python().get_program())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    eprintln!("{stdout}");
    // Printed table: one row per N with a finite, positive ratio.
    for n in [2, 3] {
        let row = stdout
            .lines()
            .find(|l| l.starts_with(&format!("| {n} |")))
            .unwrap_or_else(|| panic!("no table row for N = {n}:\n{stdout}"));
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let ratio: f64 = cells[5].parse().unwrap();
        assert!(ratio.is_finite() && ratio > 0.0, "{row}");
    }
    assert!(stdout.contains("load before:") && stdout.contains("stage shares"));
    // Rows: one per engine and N.
    let rows: Vec<serde_json::Value> = std::fs::read_to_string(&rows_path)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(rows.len(), 4);
    for n in [2usize, 3] {
        let of = |engine: &str| {
            rows.iter()
                .find(|r| r["engine"] == engine && r["links_per_chain"] == n)
                .unwrap_or_else(|| panic!("no {engine} row for N = {n}"))
        };
        let (s, m) = (of("sdrs"), of("mujoco"));
        assert_eq!(s["dof"], m["dof"], "degrees of freedom differ at N = {n}");
        assert_eq!(
            (&s["repeats"], &m["repeats"]),
            (&2.into(), &2.into()),
            "--repeats"
        );
        assert!(s["ms_per_step"].as_f64().unwrap() > 0.0);
        assert!(m["ms_per_step"].as_f64().unwrap() > 0.0);
        assert!(
            m["version"].as_str().unwrap().starts_with('4'),
            "MuJoCo 4 expected"
        );
        // Bodies: mass, centre of mass and principal inertia of each link.
        let scene = sdrs_scene(n);
        let model = &scene.model;
        let bodies = m["bodies"].as_array().unwrap();
        assert_eq!(bodies.len(), model.links.len());
        for (i, b) in bodies.iter().enumerate() {
            let m1 = model.first_moment[i];
            let mass = m1[3];
            let com = Vector3::new(m1[0], m1[1], m1[2]) / mass;
            let w = model.second_moment[i];
            let s2 = w.fixed_view::<3, 3>(0, 0).into_owned() - com * com.transpose() * mass;
            let inertia = Matrix3::identity() * s2.trace() - s2;
            let mut want: Vec<f64> = SymmetricEigen::new(inertia)
                .eigenvalues
                .iter()
                .copied()
                .collect();
            want.sort_by(f64::total_cmp);
            let mut got: Vec<f64> = b["inertia"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            got.sort_by(f64::total_cmp);
            let name = b["name"].as_str().unwrap();
            assert!(
                (b["mass"].as_f64().unwrap() - mass).abs() <= 1e-12,
                "{name}: MuJoCo mass {} vs SDRS {mass}",
                b["mass"]
            );
            for k in 0..3 {
                let c = b["com"][k].as_f64().unwrap();
                assert!((c - com[k]).abs() <= 1e-12, "{name}: centre of mass {k}");
                assert!(
                    (got[k] - want[k]).abs() <= 1e-9 * want[2],
                    "{name}: principal inertia {got:?} vs SDRS {want:?}"
                );
            }
        }
    }
}

// The SDRS side of `tools/bench/step_classes.sh`, called in-process.
#[path = "../../examples/step_classes.rs"]
#[allow(dead_code)]
mod step_classes;

/// Smoke test of `tools/bench/step_classes.{sh,py}` at N = 8, 400 steps:
/// the SDRS side (`examples/step_classes.rs::per_step`, two rounds) gives
/// each step's pairs and Newton iterations of a plain run (the rounds
/// repeat one deterministic trajectory); `step_classes.py chains` writes
/// the scene `sdrs bench` builds (same model); the MuJoCo side runs; and
/// the table's figures are those of the two CSVs. Physics across the two
/// engines: the chains first touch at about the same step in both
/// (observed on 2026-12-07 over 600 steps: SDRS at step 322, MuJoCo at
/// 326; the tolerance, 15 steps = 0.075 s, was set after that
/// observation).
#[test]
fn step_classes_split_matches_its_csvs_and_both_engines_see_the_first_touch() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("step-classes");
    let script = root().join("tools/bench/step_classes.py");
    let run = |args: &[&str]| {
        let o = python().arg(&script).args(args).output().unwrap();
        assert!(
            o.status.success(),
            "step_classes.py {args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let d = |f: &str| dir.join(f).to_str().unwrap().to_owned();
    run(&["chains", "--links", "8", "--out", &d("chains8.yaml")]);
    let scene = sdrs::scene::Scene::load(dir.join("chains8.yaml")).unwrap();
    assert_eq!(scene.model.ndof(), sdrs_scene(8).model.ndof());
    let steps = 400;
    let rows = step_classes::per_step(&scene, steps, 2).unwrap();
    let mut sim = scene.simulator();
    for (k, r) in rows.iter().enumerate() {
        let d = sim.step().unwrap();
        assert_eq!(
            (r.pairs, r.iters),
            (d.contact_pairs, d.newton.iters),
            "step {k}"
        );
        assert!(r.seconds.is_finite() && r.seconds > 0.0);
    }
    std::fs::write(dir.join("sdrs8.csv"), step_classes::csv(&rows)).unwrap();
    let (s, r) = ("400".to_string(), "1".to_string());
    run(&[
        "mujoco",
        "--links",
        "8",
        "--steps",
        &s,
        "--rounds",
        &r,
        "--out",
        &d("mj8.csv"),
    ]);
    let mj: Vec<(f64, usize)> = std::fs::read_to_string(dir.join("mj8.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (c[1].parse().unwrap(), c[2].parse().unwrap())
        })
        .collect();
    assert_eq!(mj.len(), steps);
    let ours = rows.iter().position(|r| r.pairs > 0).unwrap();
    let theirs = mj.iter().position(|m| m.1 > 0).unwrap();
    assert!(
        ours.abs_diff(theirs) <= 15,
        "first contact: SDRS step {ours}, MuJoCo step {theirs}"
    );
    // The table: its row for N = 8 from the two CSVs.
    let table = run(&["summarize", dir.to_str().unwrap(), "8"]);
    let row = table.lines().find(|l| l.starts_with("| 8 |")).unwrap();
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    // (Summed from the CSVs' printed values, in order, as the script does.)
    let printed: Vec<f64> = step_classes::csv(&rows)
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    let ms = |v: &[f64]| v.iter().map(|x| x * 1e3).sum::<f64>() / steps as f64;
    let ours_ms = ms(&printed);
    let theirs_ms = ms(&mj.iter().map(|m| m.0).collect::<Vec<_>>());
    assert_eq!(cells[2], format!("{ours_ms:.4}"), "{row}");
    assert_eq!(cells[3], format!("{theirs_ms:.4}"), "{row}");
    let counts = format!(
        "{} / {}",
        rows.iter().filter(|r| r.pairs > 0).count(),
        mj.iter().filter(|m| m.1 > 0).count()
    );
    assert_eq!(cells[5], counts, "{row}");
}
