//! The step objective's gradient and Hessian w.r.t. θ^{t+1} against central
//! finite differences, for every joint type, at random states (seeded),
//! including a free body rotated by nearly π.

use nalgebra::{DMatrix, DVector, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sdrs::energy::Need;
use sdrs::kinematics::link_poses;
use sdrs::math::so3;
use sdrs::scene::Scene;
use std::path::Path;

const ALL_JOINTS: &str = r#"
dt: 0.01
gravity: [0.3, -0.2, -9.81]
robots:
  - name: all
    links:
      - name: base
        joint: {name: free, type: free}
        mass: 2.0
        hulls: [{box: {size: [0.4, 0.3, 0.2]}}]
      - name: a
        parent: base
        joint: {name: rev, type: revolute, axis: [0.6, 0, 0.8], origin: {xyz: [0.2, 0.1, 0], rpy: [0.1, 0.2, 0.3]}}
        mass: 0.5
        hulls: [{box: {size: [0.1, 0.1, 0.4], center: [0, 0, -0.2]}}]
      - name: b
        parent: a
        joint: {name: pri, type: prismatic, axis: [0, 0, -1], origin: {xyz: [0, 0, -0.4]}}
        mass: 0.4
        hulls: [{vertices: [[0,0,0],[0.1,0,0],[0,0.1,0],[0,0,-0.2],[0.05,0.05,-0.1]]}]
      - name: c
        parent: b
        joint: {name: ball, type: ball, axes: [[1,0,0],[0,1,0]], origin: {xyz: [0, 0, -0.2]}}
        mass: 0.3
        hulls: [{box: {size: [0.05, 0.05, 0.3], center: [0, 0, -0.15]}}]
      - name: d
        parent: c
        joint: {name: sph, type: spherical, origin: {xyz: [0, 0, -0.3]}}
        mass: 0.3
        hulls: [{box: {size: [0.2, 0.05, 0.05], center: [0.1, 0, 0]}}]
      - name: e
        parent: d
        joint: {name: fix, type: fixed, origin: {xyz: [0.2, 0, 0], rpy: [0, 0.5, 0]}}
        mass: 0.2
        hulls: [{box: {size: [0.05, 0.05, 0.05], center: [0.05, 0, 0]}}, {box: {size: [0.03, 0.08, 0.03]}}]
    controller:
      kp: 30
      kd: 0.2
      targets:
        rev: {type: sine, terms: [{amplitude: 0.5, frequency: 1.0}]}
        pri: {type: constant, value: 0.05}
        ball: [{type: constant, value: 0.2}, {type: constant, value: -0.1}]
  - name: body
    links:
      - name: body
        joint: {name: free, type: free}
        mass: 1.0
        hulls: [{box: {size: [0.5, 0.2, 0.1]}}]
"#;

fn rel_err_vec(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / a.amax().max(b.amax()).max(1e-300)
}

fn rel_err_mat(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).amax() / a.amax().max(b.amax()).max(1e-300)
}

#[test]
fn step_objective_gradient_and_hessian_match_finite_differences_for_every_joint_type() {
    let scene = Scene::from_str(ALL_JOINTS, Path::new("all_joints.yaml")).unwrap();
    let model = &scene.model;
    let n = model.ndof();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut worst = (0.0f64, 0.0f64);
    for trial in 0..6 {
        let mut sim = scene.simulator();
        let charts: Vec<_> = (0..model.nchart)
            .map(|_| so3::exp(&Vector3::from_fn(|_, _| rng.random_range(-2.0..2.0))))
            .collect();
        let q_prev2 = DVector::from_fn(n, |_, _| rng.random_range(-0.5..0.5));
        let q_prev = &q_prev2 + DVector::from_fn(n, |_, _| rng.random_range(-0.05..0.05));
        let mut q = &q_prev + DVector::from_fn(n, |_, _| rng.random_range(-0.05..0.05));
        if trial % 2 == 1 {
            // Free bodies' rotation vectors of nearly π (the second robot's
            // free joint and the floating base).
            for link in &model.links {
                if link.chart.is_some() && link.joint.ndof() == 6 {
                    let axis = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize();
                    let phi = axis * (std::f64::consts::PI - 1e-3);
                    q.rows_mut(link.dof_offset + 3, 3).copy_from(&phi);
                }
            }
        }
        sim.state.charts = charts.clone();
        sim.state.poses = link_poses(model, &q_prev, &charts);
        sim.state.poses_prev = link_poses(model, &q_prev2, &charts);
        sim.state.q = q_prev.clone();
        sim.state.q_prev = q_prev2.clone();
        let (_, g, h) = sim.objective(&q, Need::Hessian).unwrap();
        let step = 1e-6;
        let mut g_fd = DVector::zeros(n);
        let mut h_fd = DMatrix::zeros(n, n);
        for k in 0..n {
            let mut qp = q.clone();
            let mut qm = q.clone();
            qp[k] += step;
            qm[k] -= step;
            let (vp, gp, _) = sim.objective(&qp, Need::Gradient).unwrap();
            let (vm, gm, _) = sim.objective(&qm, Need::Gradient).unwrap();
            g_fd[k] = (vp - vm) / (2.0 * step);
            h_fd.set_column(k, &((gp - gm) / (2.0 * step)));
        }
        let (eg, eh) = (rel_err_vec(&g, &g_fd), rel_err_mat(&h, &h_fd));
        assert!(
            (&h - h.transpose()).amax() <= 1e-12 * h.amax(),
            "Hessian not symmetric"
        );
        assert!(
            eg <= 1e-6,
            "trial {trial}: gradient relative error {eg:.3e}"
        );
        assert!(eh <= 1e-6, "trial {trial}: Hessian relative error {eh:.3e}");
        worst = (worst.0.max(eg), worst.1.max(eh));
    }
    eprintln!(
        "worst relative errors: gradient {:.2e}, Hessian {:.2e}",
        worst.0, worst.1
    );
}

#[test]
fn attachment_point_derivative_matches_finite_differences() {
    let scene = Scene::from_str(ALL_JOINTS, Path::new("all_joints.yaml")).unwrap();
    let mut model = scene.model.clone();
    let n = model.ndof();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let q = DVector::from_fn(n, |_, _| rng.random_range(-0.5..0.5));
    let charts = scene.charts.clone();
    let mut kin = sdrs::kinematics::Kinematics::new(&model);
    kin.update(&model, &q, &charts, sdrs::kinematics::KinOrder::First);
    let h = 1e-6;
    for c in 1..model.links.len() {
        for e in 0..3 {
            let orig = model.links[c].attach;
            model.links[c].attach[(e, 3)] = orig[(e, 3)] + h;
            let p = link_poses(&model, &q, &charts);
            model.links[c].attach[(e, 3)] = orig[(e, 3)] - h;
            let m = link_poses(&model, &q, &charts);
            model.links[c].attach = orig;
            for i in 0..model.links.len() {
                let fd = (p[i] - m[i]) / (2.0 * h);
                let an = kin.dpose_attachment(&model, i, c, e);
                assert!((fd - an).amax() < 1e-8, "link {i}, attachment of {c}[{e}]");
            }
        }
    }
}

#[test]
fn step_objective_derivatives_with_active_contact_and_friction_match_finite_differences() {
    // A box resting on the ground (inside the barrier's range) and an arm
    // whose tip lands on it: contact (box–ground, arm–box) and friction.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/stress/arm_on_spinning_box.yaml");
    let scene = Scene::load(path).unwrap();
    let mut sim = scene.simulator();
    // One step (the arm's tip lands on the box): the next step's lagged
    // friction frames come from a moving state with both pairs in range.
    let d = sim.step().unwrap();
    assert_eq!(
        d.contact_pairs, 2,
        "box–ground and arm–box must both be in range"
    );
    let n = scene.model.ndof();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut worst = (0.0f64, 0.0f64);
    for _ in 0..4 {
        let q = &sim.state.q + DVector::from_fn(n, |_, _| rng.random_range(-2e-4..2e-4));
        let (_, g, h) = sim.objective(&q, Need::Hessian).unwrap();
        let step = 1e-7;
        let mut g_fd = DVector::zeros(n);
        let mut h_fd = DMatrix::zeros(n, n);
        for k in 0..n {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[k] += step;
            qm[k] -= step;
            let (vp, gp, _) = sim.objective(&qp, Need::Gradient).unwrap();
            let (vm, gm, _) = sim.objective(&qm, Need::Gradient).unwrap();
            g_fd[k] = (vp - vm) / (2.0 * step);
            h_fd.set_column(k, &((gp - gm) / (2.0 * step)));
        }
        let (eg, eh) = (rel_err_vec(&g, &g_fd), rel_err_mat(&h, &h_fd));
        worst = (worst.0.max(eg), worst.1.max(eh));
        assert!(
            eg <= 1e-5 && eh <= 1e-5,
            "gradient {eg:.2e}, Hessian {eh:.2e}"
        );
    }
    eprintln!(
        "with contact and friction: worst relative errors gradient {:.2e}, Hessian {:.2e}",
        worst.0, worst.1
    );
}
