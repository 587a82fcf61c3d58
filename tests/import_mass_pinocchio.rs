//! The joint-space mass matrix of imported URDFs (default mass setting:
//! the URDF `<inertial>` as a `given` inertial) equals Pinocchio's CRBA on
//! the URDF to 1e-9 relative at 20 random configurations
//! (tools/check/check_mass_matrix_pinocchio.py through the project venv).

use crate::import_support;

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
    let opts = hull_options();
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
    if import_support::skip_without_venv() {
        return;
    }
    let (ok, out, err) = check(&third_party_urdf(), "kuka", 0.0);
    eprintln!("kuka_iiwa: {}", out.trim());
    assert!(ok, "Pinocchio disagrees: {err}{out}");
    let summary: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(summary["configurations"], 20);
    assert_eq!(summary["dofs"], 7);
}

#[test]
fn mass_matrix_check_detects_a_wrong_entry() {
    if import_support::skip_without_venv() {
        return;
    }
    // A relative change of 1e-7 in one entry must fail the 1e-9 check.
    let (ok, _out, err) = check(&third_party_urdf(), "kuka-wrong", 1e-7);
    assert!(!ok && err.contains("mass matrix mismatch"), "{err}");
}

#[test]
fn density_mass_gives_solid_links_and_the_report_compares_inertials() {
    if import_support::skip_without_venv() {
        return;
    }
    let urdf = third_party_urdf();
    let opts = ImportOptions {
        decomposer: Decomposer::Hull,
        mass: sdrs::import::MassMode::Density,
        density: 2000.0,
        ..ImportOptions::default()
    };
    let imp = import(&urdf, &opts).unwrap();
    let scene = Scene::from_spec(imp.scene.clone(), &urdf).unwrap();
    for (link, rep) in scene.model.links.iter().zip(&imp.report.links) {
        assert!(matches!(link.mass_model, MassModel::Solid { density } if density == 2000.0));
        assert_eq!(rep.mass_model, "solid");
        assert!(
            (link.mass() - rep.mass).abs() <= 1e-9 * rep.mass,
            "{}",
            link.name
        );
        // The hulls' COM lies inside their bounding box; the URDF's is listed.
        let (lo, hi) = link.hulls.iter().flat_map(|h| &h.x_local).fold(
            (
                nalgebra::Vector3::repeat(f64::MAX),
                nalgebra::Vector3::repeat(f64::MIN),
            ),
            |(a, b), x| (a.inf(x), b.sup(x)),
        );
        let c = nalgebra::Vector3::from(rep.inertial_hulls.com);
        assert!(
            c.iter()
                .zip(lo.iter().zip(hi.iter()))
                .all(|(v, (l, h))| *l <= *v && *v <= *h)
        );
        // pybullet's iiwa has a massless root (the static base).
        assert!(
            rep.inertial_input.is_some() || link.parent.is_none(),
            "{}: URDF inertial missing",
            link.name
        );
    }
    // Default import: the report's input inertial is the given one.
    let imp = import(&urdf, &hull_options()).unwrap();
    let rep = &imp.report.links[3];
    let inp = rep.inertial_input.as_ref().unwrap();
    assert_eq!(rep.mass_model, "given");
    assert_eq!(inp.mass, rep.mass);
    let p = &inp.principal_moments;
    assert!(p[0] <= p[1] && p[1] <= p[2] && p[0] > 0.0);
}

#[test]
fn urdf_mimic_and_limits_are_imported() {
    let dir = temp_dir("mimic-import");
    let urdf = dir.join("g.urdf");
    let link = |n: &str| {
        format!(
            r#"<link name="{n}"><inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial><collision><geometry><box size="0.02 0.02 0.1"/></geometry></collision></link>"#
        )
    };
    let text = format!(
        r#"<?xml version="1.0"?>
<robot name="g">
  <link name="palm"><collision><geometry><box size="0.2 0.05 0.05"/></geometry></collision></link>
  {}{}
  <joint name="left" type="revolute"><parent link="palm"/><child link="l"/><origin xyz="-0.08 0 -0.1"/><axis xyz="0 1 0"/><limit lower="-0.5" upper="0.6" effort="3" velocity="2"/></joint>
  <joint name="right" type="revolute"><parent link="palm"/><child link="r"/><origin xyz="0.08 0 -0.1"/><axis xyz="0 1 0"/><limit lower="-0.6" upper="0.5" effort="3" velocity="2"/><mimic joint="left" multiplier="-1" offset="0"/></joint>
</robot>
"#,
        link("l"),
        link("r")
    );
    std::fs::write(&urdf, text).unwrap();
    let imp = import(&urdf, &hull_options()).unwrap();
    let scene = Scene::from_spec(imp.scene.clone(), &urdf).unwrap();
    let m = &scene.model;
    assert_eq!(m.mimics.len(), 1);
    assert_eq!(m.mimics[0].multiplier, -1.0);
    let l = m.links.iter().find(|l| l.joint_name == "left").unwrap();
    let lim = l.limit.as_ref().unwrap();
    assert_eq!(
        (lim.lower, lim.upper, lim.velocity, lim.effort),
        (-0.5, 0.6, Some(2.0), Some(3.0))
    );
    assert!(imp.report.notes.iter().any(|n| n.contains("tied")));
    let _ = std::fs::remove_dir_all(&dir);
}
