//! Forward kinematics of imported URDFs equal Pinocchio's at 20 random
//! configurations to 1e-9 (tools/check_fk_pinocchio.py through the project
//! venv: `bash tools/setup_python.sh`).

mod import_support;

use import_support::*;
use sdrs::import::fkcheck::fk_samples;
use sdrs::import::{Decomposer, ImportOptions, import};
use sdrs::scene::Scene;
use std::path::Path;

fn check(urdf: &Path, tag: &str, seed: u64) {
    let opts = ImportOptions {
        decomposer: Decomposer::Hull,
        progress: false,
        ..ImportOptions::default()
    };
    let imp = import(urdf, &opts).unwrap_or_else(|e| panic!("{e}"));
    let scene = Scene::from_spec(imp.scene.clone(), urdf).unwrap();
    let samples = fk_samples(&scene, &imp.report, 20, seed);
    assert_eq!(samples["configurations"].as_array().unwrap().len(), 20);
    let dir = temp_dir(&format!("fk-{tag}"));
    let json = dir.join("samples.json");
    std::fs::write(&json, serde_json::to_string(&samples).unwrap()).unwrap();
    let (ok, out, err) = run_tool(
        "check_fk_pinocchio.py",
        &[urdf, &json, Path::new("--tol"), Path::new("1e-9")],
    );
    eprintln!("{tag}: {}", out.trim());
    assert!(ok, "{tag}: Pinocchio disagrees: {err}{out}");
    let summary: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(summary["configurations"], 20);
    assert!(summary["poses"].as_u64().unwrap() >= 20);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn fk_of_authored_spider_matches_pinocchio() {
    // Floating base, ball joints merged from revolute pairs, rotated hips.
    check(&robot_urdf("spider"), "spider", 1);
}

#[test]
fn fk_of_authored_hand_and_chains_match_pinocchio() {
    check(&robot_urdf("three_finger_hand"), "three_finger_hand", 2);
    check(&robot_urdf("chains_8link"), "chains_8link", 3);
}

#[test]
fn fk_of_third_party_kuka_iiwa_matches_pinocchio() {
    check(&third_party_urdf(), "kuka_iiwa", 4);
}

#[test]
fn fk_check_detects_a_wrong_pose() {
    // The checker must fail when our poses are wrong.
    let urdf = robot_urdf("three_finger_hand");
    let opts = ImportOptions {
        decomposer: Decomposer::Hull,
        progress: false,
        ..ImportOptions::default()
    };
    let imp = import(&urdf, &opts).unwrap();
    let scene = Scene::from_spec(imp.scene.clone(), &urdf).unwrap();
    let mut samples = fk_samples(&scene, &imp.report, 2, 5);
    let p = &mut samples["configurations"][1]["links"]["finger1_distal"]["p"][2];
    *p = serde_json::json!(p.as_f64().unwrap() + 1e-6);
    let dir = temp_dir("fk-wrong");
    let json = dir.join("samples.json");
    std::fs::write(&json, serde_json::to_string(&samples).unwrap()).unwrap();
    let (ok, _out, err) = run_tool("check_fk_pinocchio.py", &[&urdf, &json]);
    assert!(!ok && err.contains("finger1_distal"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
