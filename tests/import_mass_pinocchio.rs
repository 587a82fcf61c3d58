//! The joint-space mass matrix of imported URDFs (default mass setting:
//! the URDF `<inertial>` as a `given` inertial) equals Pinocchio's CRBA on
//! the URDF to 1e-9 relative at 20 random configurations
//! (tools/check_mass_matrix_pinocchio.py through the project venv).

mod import_support;

use import_support::*;
use nalgebra::{DMatrix, DVector, Matrix3};
use rand::{RngExt, SeedableRng};
use sdrs::import::{Decomposer, ImportOptions, import};
use sdrs::model::MassModel;
use sdrs::scene::Scene;
use sdrs::sim::mass_matrix::mass_matrix;
use serde_json::json;
use std::path::Path;

/// 20 configurations within the URDF limits: the URDF joint values, the
/// URDF names of our 1-DOF coordinates and our matrix restricted to them.
fn samples(urdf: &Path, seed: u64, perturb: f64) -> serde_json::Value {
    let opts = ImportOptions {
        decomposer: Decomposer::Hull,
        progress: false,
        ..ImportOptions::default()
    };
    let imp = import(urdf, &opts).unwrap_or_else(|e| panic!("{e}"));
    let scene = Scene::from_spec(imp.scene.clone(), urdf).unwrap();
    let model = &scene.model;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut configs = Vec::new();
    for _ in 0..20 {
        let mut q = DVector::zeros(model.ndof());
        let mut joints = serde_json::Map::new();
        let mut dofs = Vec::new();
        let mut names = Vec::new();
        for link in &model.links {
            let Some(inp) = imp.report.joints.get(&link.joint_name) else {
                continue;
            };
            if link.ndof() != 1 || inp.len() != 1 {
                continue;
            }
            let v = rng.random_range(inp[0].lower..=inp[0].upper);
            q[link.dof_offset] = v;
            joints.insert(inp[0].name.clone(), json!(v));
            dofs.push(link.dof_offset);
            names.push(inp[0].name.clone());
        }
        let h = mass_matrix(model, &q, &vec![Matrix3::identity(); model.nchart]);
        let mut sub = DMatrix::from_fn(dofs.len(), dofs.len(), |a, b| h[(dofs[a], dofs[b])]);
        sub[(0, 0)] *= 1.0 + perturb;
        configs.push(json!({
            "joints": joints,
            "dofs": names,
            "M": (0..sub.nrows()).map(|r| sub.row(r).iter().copied().collect::<Vec<_>>()).collect::<Vec<_>>(),
        }));
    }
    // Default import: every link with a URDF inertial is `given`.
    assert!(
        model
            .links
            .iter()
            .filter(|l| !l.name.starts_with("__"))
            .all(|l| matches!(l.mass_model, MassModel::Given(_)) || l.parent.is_none()),
        "default import must keep the URDF inertials"
    );
    json!({ "configurations": configs })
}

fn check(urdf: &Path, tag: &str, perturb: f64) -> (bool, String, String) {
    let s = samples(urdf, 9, perturb);
    let dir = temp_dir(&format!("massmatrix-{tag}"));
    let json = dir.join("samples.json");
    std::fs::write(&json, serde_json::to_string(&s).unwrap()).unwrap();
    let r = run_tool(
        "check_mass_matrix_pinocchio.py",
        &[urdf, &json, Path::new("--tol"), Path::new("1e-9")],
    );
    let _ = std::fs::remove_dir_all(&dir);
    r
}

#[test]
fn mass_matrix_of_imported_kuka_iiwa_matches_pinocchio_crba() {
    let (ok, out, err) = check(&third_party_urdf(), "kuka", 0.0);
    eprintln!("kuka_iiwa: {}", out.trim());
    assert!(ok, "Pinocchio disagrees: {err}{out}");
    let summary: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(summary["configurations"], 20);
    assert_eq!(summary["dofs"], 7);
}

#[test]
fn mass_matrix_check_detects_a_wrong_entry() {
    // A relative change of 1e-7 in one entry must fail the 1e-9 check.
    let (ok, _out, err) = check(&third_party_urdf(), "kuka-wrong", 1e-7);
    assert!(!ok && err.contains("mass matrix mismatch"), "{err}");
}
