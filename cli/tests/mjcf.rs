//! End-to-end MJCF: third-party models from pybullet_data's `mjcf/` folder
//! imported by `sdrs import`, simulated for 1 s on the ground, every
//! exported step checked by an independent checker (python-fcl): no
//! interpenetration, and contact actually happened.

mod support;

use support::{python, scratch_dir};

fn on_ground(model: &str, import_args: &[&str]) {
    let dir = scratch_dir(&format!("mjcf-{model}"));
    let xml = support::pybullet_data()
        .join("mjcf")
        .join(format!("{model}.xml"));
    let scene = dir.join(format!("{model}.yaml"));
    support::run_ok(
        support::sdrs()
            .arg("import")
            .arg(&xml)
            .arg("--out")
            .arg(&scene)
            .args(import_args)
            .arg("-q"),
    );
    let export = dir.join("export");
    std::fs::create_dir_all(&export).unwrap();
    let summary = support::simulate_export(&export, &["--steps", "1000"], &scene);
    let steps = summary["contact"]["steps_in_contact"].as_u64().unwrap();
    assert!(
        steps > 100,
        "{model}: no contact with the ground ({steps} steps)"
    );
    let ours = summary["contact"]["min_distance"].as_f64().unwrap();
    let r = support::python_fcl_check(&export);
    let fcl_min = r["min_distance"].as_f64().unwrap();
    eprintln!(
        "{model}: 1 s, {steps} steps in contact, python-fcl min distance {fcl_min:.4e} m (ours {ours:.4e}) over {} steps",
        r["steps_checked"]
    );
    assert!(fcl_min > 0.0);
    assert!(
        (fcl_min - ours).abs() < 1e-6,
        "{model}: {fcl_min} vs {ours}"
    );
}

#[test]
fn pybullet_mjcf_ant_floating_on_the_ground() {
    on_ground("ant", &["--ground", "--base", "floating"]);
}

#[test]
fn pybullet_mjcf_humanoid_falls_onto_the_ground() {
    on_ground("humanoid", &["--ground", "--base", "floating"]);
}

#[test]
fn pybullet_mjcf_thrower_with_its_own_ground_plane() {
    on_ground("thrower", &[]);
}

/// `sdrs export-mjcf`: the written model compiles in MuJoCo with one body
/// per link and one velocity per coordinate; an existing output is never
/// overwritten without `--force`.
#[test]
fn export_mjcf_writes_a_model_mujoco_loads_and_keeps_existing_files() {
    let dir = scratch_dir("export-mjcf");
    let out = dir.join("four_chains.xml");
    let scene = support::robots("four_chains.yaml");
    support::run_ok(
        support::sdrs()
            .arg("export-mjcf")
            .arg(&scene)
            .arg("--out")
            .arg(&out),
    );
    let o = python()
        .arg("-c")
        .arg("import sys, mujoco; m = mujoco.MjModel.from_xml_path(sys.argv[1]); print(m.nbody, m.nv, m.nkey)")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let counts: Vec<usize> = String::from_utf8_lossy(&o.stdout)
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    // 4 chains × 8 links + the world body; 2 coordinates per ball joint; one keyframe.
    assert_eq!(counts, vec![33, 64, 1]);
    let before = std::fs::read(&out).unwrap();
    let o = support::sdrs()
        .arg("export-mjcf")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--force") && err.contains("four_chains.xml"),
        "{err}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), before);
}
