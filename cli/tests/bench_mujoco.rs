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
        .args(["--links", "2,3", "--steps", "15", "--sdrs"])
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
