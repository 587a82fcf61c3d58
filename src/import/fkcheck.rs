//! Forward-kinematics samples of an imported robot, for comparison with an
//! independent implementation (`tools/check/check_fk_pinocchio.py`, Pinocchio).
//!
//! Each sample gives the input (URDF) joint values and our world pose of
//! every link. Coordinates are drawn (seeded) within the URDF limits
//! (±π for continuous joints); free joints get a position in `[-1, 1]³` and a
//! rotation vector of norm below π, written for Pinocchio as
//! `[x, y, z, qx, qy, qz, qw]`.

use super::report::ImportReport;
use crate::kinematics::link_poses;
use crate::math::{rot, trans};
use crate::model::JointKind;
use crate::scene::Scene;
use nalgebra::{DVector, Matrix3, UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use serde_json::{Value, json};

/// `n` samples as JSON: `{"configurations": [{"joints": {name: [..]},
/// "links": {name: {"R": [[..]..], "p": [..]}}}]}`.
pub fn fk_samples(scene: &Scene, report: &ImportReport, n: usize, seed: u64) -> Value {
    let model = &scene.model;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut configs = Vec::with_capacity(n);
    for _ in 0..n {
        let mut q = DVector::zeros(model.ndof());
        let mut joints = serde_json::Map::new();
        for link in &model.links {
            let inputs = report.joints.get(&link.joint_name);
            let o = link.dof_offset;
            match (&link.joint, inputs) {
                (JointKind::Free, Some(inp)) => {
                    let p: Vector3<f64> = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
                    let phi = loop {
                        let v: Vector3<f64> = Vector3::from_fn(|_, _| rng.random_range(-3.0..3.0));
                        if v.norm() < 3.0 {
                            break v;
                        }
                    };
                    for k in 0..3 {
                        q[o + k] = p[k];
                        q[o + 3 + k] = phi[k];
                    }
                    let uq = UnitQuaternion::from_scaled_axis(phi);
                    let c = uq.coords; // (i, j, k, w)
                    joints.insert(
                        inp[0].name.clone(),
                        json!([p.x, p.y, p.z, c.x, c.y, c.z, c.w]),
                    );
                }
                (_, Some(inp)) if inp.len() == link.ndof() => {
                    for (k, j) in inp.iter().enumerate() {
                        let v = rng.random_range(j.lower..=j.upper);
                        q[o + k] = v;
                        joints.insert(j.name.clone(), json!([v]));
                    }
                }
                _ => {}
            }
        }
        let charts = vec![Matrix3::identity(); model.nchart];
        let poses = link_poses(model, &q, &charts);
        let mut links = serde_json::Map::new();
        for (link, pose) in model.links.iter().zip(&poses) {
            let r = rot(pose);
            let t = trans(pose);
            links.insert(
                link.name.clone(),
                json!({
                    "R": (0..3).map(|i| (0..3).map(|j| r[(i, j)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
                    "p": [t.x, t.y, t.z],
                }),
            );
        }
        configs.push(json!({"joints": joints, "links": links}));
    }
    json!({ "configurations": configs })
}
