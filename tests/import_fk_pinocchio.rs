//! Forward kinematics of imported URDFs equal Pinocchio's at 20 random
//! configurations to 1e-9 (tools/check/check_fk_pinocchio.py through the project
//! venv: `bash tools/setup/setup_python.sh`).

use crate::import_support;

use import_support::*;
use sdrs::import::fkcheck::fk_samples;
use sdrs::import::{ImportOptions, import};
use sdrs::scene::Scene;
use std::path::Path;

fn check(urdf: &Path, tag: &str, seed: u64) {
    let opts = hull_options();
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
    if import_support::skip_without_venv() {
        return;
    }
    // Floating base, ball joints merged from revolute pairs, rotated hips.
    check(&robot_urdf("spider"), "spider", 1);
}

#[test]
fn fk_of_authored_hand_and_chains_match_pinocchio() {
    if import_support::skip_without_venv() {
        return;
    }
    check(&robot_urdf("three_finger_hand"), "three_finger_hand", 2);
    check(&robot_urdf("chains_8link"), "chains_8link", 3);
}

#[test]
fn fk_of_third_party_kuka_iiwa_matches_pinocchio() {
    if import_support::skip_without_venv() {
        return;
    }
    check(&third_party_urdf(), "kuka_iiwa", 4);
}

#[test]
fn fk_check_detects_a_wrong_pose() {
    if import_support::skip_without_venv() {
        return;
    }
    // The checker must fail when our poses are wrong.
    let urdf = robot_urdf("three_finger_hand");
    let opts = hull_options();
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

#[test]
fn fk_with_merged_fixed_links_primitives_continuous_and_prismatic_matches_pinocchio() {
    if import_support::skip_without_venv() {
        return;
    }
    // A geometry-less flange on a fixed joint is merged into its parent (its
    // child's origin composed through it); continuous joints are (cos, sin)
    // in Pinocchio.
    let text = r#"<?xml version="1.0"?>
<robot name="mixed">
  <link name="base"><collision><geometry><box size="0.3 0.3 0.1"/></geometry></collision></link>
  <link name="upper">
    <inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision><origin xyz="0 0 0.2" rpy="0.1 0 0"/><geometry><cylinder radius="0.04" length="0.4"/></geometry></collision>
  </link>
  <link name="flange"/>
  <link name="slider"><collision><geometry><capsule radius="0.03" length="0.1"/></geometry></collision></link>
  <link name="tip"><visual><geometry><sphere radius="0.05"/></geometry></visual></link>
  <joint name="spin" type="continuous">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0.01 0.02 0.05" rpy="0.3 -0.2 0.7"/><axis xyz="0.2 0.3 1"/>
  </joint>
  <joint name="mount" type="fixed">
    <parent link="upper"/><child link="flange"/>
    <origin xyz="0 0.05 0.4" rpy="0.5 0.1 -0.3"/>
  </joint>
  <joint name="slide" type="prismatic">
    <parent link="flange"/><child link="slider"/>
    <origin xyz="0.02 0 0.01" rpy="0 0.4 0"/><axis xyz="1 0 0"/>
    <limit lower="-0.2" upper="0.3" effort="1" velocity="1"/>
  </joint>
  <joint name="wrist" type="revolute">
    <parent link="slider"/><child link="tip"/>
    <origin xyz="0 0 0.05" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/>
  </joint>
</robot>
"#;
    let dir = temp_dir("fk-mixed-src");
    let urdf = dir.join("mixed.urdf");
    std::fs::write(&urdf, text).unwrap();
    let opts = ImportOptions::default();
    let imp = import(&urdf, &opts).unwrap();
    assert!(
        imp.report
            .notes
            .iter()
            .any(|n| n.contains("\"flange\"") && n.contains("merged"))
    );
    assert_eq!(imp.report.links.len(), 4);
    check(&urdf, "mixed", 6);
    let _ = std::fs::remove_dir_all(&dir);
}
