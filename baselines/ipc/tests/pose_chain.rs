//! The stencil → link-pose chain rule (`X_k = A x̃_k`): pose gradient and
//! 24×24 pose Hessian of a quadratic stencil energy against finite
//! differences in `vec A`, and the whole step objective's gradient with IPC
//! contact and friction active against finite differences in the
//! coordinates.

use nalgebra::{DVector, Matrix3x4, SMatrix, Vector3, Vector4};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sdrs::energy::Need;
use sdrs::scene::Scene;
use sdrs_ipc::pair::{PairHessian, chain_to_poses};
use sdrs_ipc::primitive::{Mat12, Vec12};
use std::path::Path;

#[test]
fn pose_gradient_and_hessian_of_a_quadratic_stencil_energy() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    for _ in 0..20 {
        let m = Mat12::from_fn(|_, _| rng.random_range(-1.0..1.0));
        let h: Mat12 = m * m.transpose();
        let g0 = Vec12::from_fn(|_, _| rng.random_range(-1.0..1.0));
        let side = [0usize, 1, 1, 0];
        let loc: [Vector4<f64>; 4] = std::array::from_fn(|_| {
            Vector4::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                1.0,
            )
        });
        let a = SMatrix::<f64, 24, 1>::from_fn(|_, _| rng.random_range(-1.0..1.0));
        let stencil = |a: &SMatrix<f64, 24, 1>| -> Vec12 {
            let pose = |s: usize| Matrix3x4::from_column_slice(&a.as_slice()[12 * s..12 * s + 12]);
            let mut x = Vec12::zeros();
            for k in 0..4 {
                x.fixed_rows_mut::<3>(3 * k)
                    .copy_from(&(pose(side[k]) * loc[k]));
            }
            x
        };
        let energy = |a: &SMatrix<f64, 24, 1>| {
            let x = stencil(a);
            g0.dot(&x) + 0.5 * x.dot(&(h * x))
        };
        let x = stencil(&a);
        let (mut ga, mut gb) = (Matrix3x4::zeros(), Matrix3x4::zeros());
        let mut hp = PairHessian::zeros();
        chain_to_poses(
            &(g0 + h * x),
            &h,
            &side,
            &loc,
            &mut ga,
            &mut gb,
            Some(&mut hp),
        );
        let mut grad = SMatrix::<f64, 24, 1>::zeros();
        grad.fixed_rows_mut::<12>(0).copy_from_slice(ga.as_slice());
        grad.fixed_rows_mut::<12>(12).copy_from_slice(gb.as_slice());
        // The energy is exactly quadratic in vec A: differences are exact up
        // to round-off, so a large step is the accurate one.
        let step = 1e-2;
        for i in 0..24 {
            let (mut p, mut q) = (a, a);
            p[i] += step;
            q[i] -= step;
            let fd = (energy(&p) - energy(&q)) / (2.0 * step);
            assert!((fd - grad[i]).abs() <= 1e-6 * grad.norm(), "gradient {i}");
            for j in 0..24 {
                let (mut pp, mut pm, mut mp, mut mm) = (a, a, a, a);
                pp[i] += step;
                pp[j] += step;
                pm[i] += step;
                pm[j] -= step;
                mp[i] -= step;
                mp[j] += step;
                mm[i] -= step;
                mm[j] -= step;
                let fd =
                    (energy(&pp) - energy(&pm) - energy(&mp) + energy(&mm)) / (4.0 * step * step);
                assert!(
                    (fd - hp[(i, j)]).abs() <= 1e-6 * hp.norm(),
                    "Hessian ({i}, {j}): {fd} vs {}",
                    hp[(i, j)]
                );
            }
        }
    }
}

#[test]
fn step_objective_gradient_with_ipc_contact_and_friction_matches_finite_differences() {
    // A tilted box resting 0.4 mm above a static box, and a second free box
    // touching its corner: point–triangle and edge–edge pairs active.
    let text = "
version: 1
dt: 0.01
contact: {model: ipc, kappa: 1.0e9, mu: 0.5, ipc: {dhat: 1.0e-3, eps_v: 1.0e-2}}
obstacles:
  - name: table
    hulls: [{box: {size: [1, 1, 0.1], center: [0, 0, -0.05]}}]
objects:
  - name: a
    mass: 1.0
    hulls: [{box: {size: [0.2, 0.2, 0.2]}}]
    initial: {q: [0, 0, 0.1004, 0, 0, 0.3]}
  - name: b
    mass: 0.5
    hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
    initial: {q: [0.02, 0.03, 0.2508, 0, 0, 0.7]}
";
    let scene = Scene::from_str(text, Path::new("fd.yaml")).unwrap();
    let mut sim = scene
        .simulator_with(&sdrs_ipc::IpcFactory::default())
        .unwrap();
    let mut q = sim.state.q.clone();
    // Slip of a few ε_v Δt for the friction term, staying inside d̂.
    q[0] += 3e-5;
    q[1] -= 2e-5;
    q[6] += 1e-4;
    let (v, g, _) = sim.objective(&q, Need::Hessian).unwrap();
    assert!(v.is_finite());
    let step = 1e-8;
    let mut worst: f64 = 0.0;
    for i in 0..q.len() {
        let mut f = |s: f64| {
            let mut p: DVector<f64> = q.clone();
            p[i] += s;
            sim.objective(&p, Need::Value).unwrap().0
        };
        let fd = (4.0 * (f(step / 2.0) - f(-step / 2.0)) / step
            - (f(step) - f(-step)) / (2.0 * step))
            / 3.0;
        worst = worst.max((fd - g[i]).abs() / g.amax());
    }
    eprintln!("objective gradient vs FD: worst relative error {worst:.2e}");
    assert!(worst <= 1e-6);
    let _ = Vector3::<f64>::zeros();
}
