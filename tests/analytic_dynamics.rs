//! Position-level dynamics against analytic results and conservation laws.

use nalgebra::DVector;
use sdrs::scene::Scene;
use sdrs::sim::run::run;
use std::path::Path;

fn robots(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("robots")
        .join(name)
}

/// Upward zero crossings of `x(t)`, linearly interpolated.
fn zero_crossings(t: &[f64], x: &[f64]) -> Vec<f64> {
    (1..x.len())
        .filter(|&i| x[i - 1] < 0.0 && x[i] >= 0.0)
        .map(|i| t[i - 1] + (t[i] - t[i - 1]) * (-x[i - 1]) / (x[i] - x[i - 1]))
        .collect()
}

#[test]
fn pendulum_small_amplitude_period_matches_two_pi_sqrt_l_over_g() {
    let scene = Scene::load(robots("pendulum.yaml")).unwrap();
    assert_eq!(scene.settings.dt, 1e-3);
    let mut sim = scene.simulator();
    let traj = run(&mut sim, 8000, |_| {}).unwrap();
    let x: Vec<f64> = traj.states.iter().map(|q| q[0]).collect();
    let z = zero_crossings(&traj.times, &x);
    assert!(z.len() >= 3, "too few oscillations: {z:?}");
    let period = (z[z.len() - 1] - z[0]) / (z.len() - 1) as f64;
    let (l, g): (f64, f64) = (1.0, 9.81);
    let expected = 2.0 * std::f64::consts::PI * (l / g).sqrt();
    let rel = (period - expected).abs() / expected;
    eprintln!("pendulum period {period:.5} s, expected {expected:.5} s, relative error {rel:.2e}");
    assert!(rel < 0.01, "period {period} vs {expected}");
}

#[test]
fn free_fall_height_after_one_second_matches_parabola() {
    let scene = Scene::load(robots("free_fall_box.yaml")).unwrap();
    assert_eq!(scene.settings.dt, 1e-3);
    let mut sim = scene.simulator();
    let traj = run(&mut sim, 1000, |_| {}).unwrap();
    let z_col = traj.names.iter().position(|n| n == "body:z").unwrap();
    let t = *traj.times.last().unwrap();
    let z = traj.states.last().unwrap()[z_col];
    let expected = 10.0 - 0.5 * 9.81 * t * t;
    let rel = (z - expected).abs() / expected;
    eprintln!("free fall: z(1 s) = {z:.6}, expected {expected:.6}, relative error {rel:.2e}");
    assert!((t - 1.0).abs() < 1e-12);
    assert!(rel < 0.005);
    // The first-order start lags the parabola by exactly g t Δt / 2.
    assert!((expected - z - 0.5 * 9.81 * t * 1e-3).abs() < 1e-6);
}

const FLOATING: &str = r#"
dt: 0.002
gravity: [0, 0, 0]
solver: {tol: 1.0e-9}
robots:
  - name: floater
    links:
      - name: torso
        joint: {name: root, type: free}
        mass: 3.0
        hulls: [{box: {size: [0.4, 0.3, 0.2]}}]
      - name: arm
        parent: torso
        joint: {name: shoulder, type: ball, origin: {xyz: [0.2, 0, 0]}}
        mass: 1.0
        hulls: [{box: {size: [0.5, 0.05, 0.05], center: [0.25, 0, 0]}}]
      - name: hand
        parent: arm
        joint: {name: elbow, type: revolute, axis: [0, 0, 1], origin: {xyz: [0.5, 0, 0]}}
        mass: 0.5
        hulls: [{box: {size: [0.3, 0.05, 0.05], center: [0.15, 0, 0]}}]
    controller:
      kp: 5
      kd: 0.01
      targets:
        shoulder: [{type: sine, terms: [{amplitude: 0.8, frequency: 1.3}]}, {type: sine, terms: [{amplitude: 0.5, frequency: 0.7, phase: 1}]}]
        elbow: {type: sine, terms: [{amplitude: 1.0, frequency: 2.0}]}
    initial:
      root: {q: [0, 0, 0, 0.4, -0.3, 0.2], qdot: [0.3, -0.2, 0.5, 0.7, 1.1, -0.4]}
      shoulder: {qdot: [1.0, -2.0]}
"#;

#[test]
fn free_floating_articulated_body_conserves_linear_momentum() {
    let scene = Scene::from_str(FLOATING, Path::new("floating.yaml")).unwrap();
    let mut sim = scene.simulator();
    let traj = run(&mut sim, 1500, |_| {}).unwrap();
    let p0 = DVector::from_row_slice(&traj.diagnostics[0].momentum);
    let mut worst: f64 = 0.0;
    for d in &traj.diagnostics {
        let p = DVector::from_row_slice(&d.momentum);
        worst = worst.max((&p - &p0).norm() / p0.norm());
    }
    // The body rotates (charts were re-centred) and the joints move.
    let rot = traj.states.last().unwrap().rows(3, 3).norm();
    eprintln!(
        "momentum |p| = {:.6}, worst relative change {worst:.2e}, final |rotation vector| {rot:.3}",
        p0.norm()
    );
    assert!(worst < 1e-9, "relative momentum change {worst:e}");
}

#[test]
fn pd_held_joint_settles_at_predicted_gravity_offset() {
    // Horizontal 1 m arm (1 kg point-like block) about y, PD target 0:
    // equilibrium 2 k_p θ = m g L cos θ.
    let (kp, m, g, l) = (50.0, 1.0, 9.81, 1.0);
    let text = format!(
        r#"
dt: 0.001
robots:
  - name: arm
    links:
      - name: arm
        joint: {{name: hinge, type: revolute, axis: [0, 1, 0]}}
        mass: {m}
        hulls: [{{box: {{size: [0.01, 0.01, 0.01], center: [{l}, 0, 0]}}}}]
    controller:
      kp: {kp}
      kd: 0.01
      targets: {{hinge: {{type: constant, value: 0}}}}
"#
    );
    let scene = Scene::from_str(&text, Path::new("pd.yaml")).unwrap();
    let mut sim = scene.simulator();
    let traj = run(&mut sim, 4000, |_| {}).unwrap();
    let theta = traj.states.last().unwrap()[0];
    // Solve 2 kp θ = m g L cos θ by Newton.
    let mut th: f64 = 0.1;
    for _ in 0..50 {
        let f = 2.0 * kp * th - m * g * l * th.cos();
        let df = 2.0 * kp + m * g * l * th.sin();
        th -= f / df;
    }
    let rel = (theta - th).abs() / th;
    eprintln!("PD steady state θ = {theta:.6}, predicted {th:.6}, relative error {rel:.2e}");
    assert!(
        th > 0.05,
        "the offset must be significant for the test to mean something"
    );
    assert!(rel < 0.01);
}
