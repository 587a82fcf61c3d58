//! Separating-plane contact and friction in whole simulations: Coulomb
//! sliding, sticking, resting, momentum conservation, and non-interpenetration
//! confirmed by an independent checker (python-fcl).

use crate::common;

use common::{python, robots, scratch_dir};
use nalgebra::Vector3;
use sdrs::scene::Scene;
use sdrs::sim::run::run;
use std::path::Path;

/// Position along the slope's downhill direction `(cos θ, 0, −sin θ)`.
fn along_slope(x: f64, z: f64, theta: f64) -> f64 {
    x * theta.cos() - z * theta.sin()
}

fn slope_run(file: &str) -> (Vec<f64>, f64, f64, sdrs::output::Trajectory) {
    let scene = Scene::load(robots(file)).unwrap();
    let mut sim = scene.simulator();
    let traj = run(&mut sim, 1000, |_| {}).unwrap();
    let ix = traj.names.iter().position(|n| n == "box/box:x").unwrap();
    let iz = traj.names.iter().position(|n| n == "box/box:z").unwrap();
    let theta = 30f64.to_radians();
    let s: Vec<f64> = traj
        .states
        .iter()
        .map(|q| along_slope(q[ix], q[iz], theta))
        .collect();
    (s, scene.settings.dt, theta, traj)
}

#[test]
fn box_on_30_degree_slope_slides_with_coulomb_acceleration_at_mu_0_2() {
    let (s, dt, theta, traj) = slope_run("box_on_slope_mu02.yaml");
    let v = |i: usize| (s[i + 1] - s[i - 1]) / (2.0 * dt);
    let a = (v(900) - v(400)) / (500.0 * dt);
    let expected = 9.81 * (theta.sin() - 0.2 * theta.cos());
    let rel = (a - expected).abs() / expected;
    eprintln!("slope μ=0.2: a = {a:.5} m/s², expected {expected:.5}, relative error {rel:.2e}");
    assert!(rel < 0.05);
    assert!(
        traj.diagnostics.iter().all(|d| d.contact_pairs > 0),
        "the box left the slope"
    );
}

#[test]
fn box_on_30_degree_slope_sticks_at_mu_0_8_up_to_the_smoothing_creep() {
    // With friction smoothing ε, slip below √ε is viscous: per interface
    // f = μ N v_rel/√(v_rel² + ε). The massless plane sits halfway, so each
    // interface slips at v/2, and the balance m g sin θ = μ m g cos θ ·
    // (v/2)/√((v/2)² + ε) gives the creep speed v = 2√ε r/√(1 − r²),
    // r = tan θ/μ (2.085 mm/s here). Coulomb sticking is the limit ε → 0.
    // During the first ~0.3 s the released box rocks on the barrier (the
    // friction force acts below its centre of mass) and briefly slips
    // faster; that transient stays below 10√ε.
    let (s, dt, theta, _) = slope_run("box_on_slope_mu08.yaml");
    let eps: f64 = 1e-6;
    let r = theta.tan() / 0.8;
    let creep = 2.0 * eps.sqrt() * r / (1.0 - r * r).sqrt();
    let speed = |i: usize| ((s[i + 1] - s[i - 1]) / (2.0 * dt)).abs();
    let settled = (0.4 / dt) as usize;
    let v_settled = (settled..s.len() - 1).map(speed).fold(0.0, f64::max);
    let v_all = (1..s.len() - 1).map(speed).fold(0.0, f64::max);
    let v_end = speed(s.len() - 2);
    eprintln!(
        "slope μ=0.8: creep prediction {creep:.4e} m/s; max speed after 0.4 s {v_settled:.4e}, final {v_end:.4e}, whole run {v_all:.4e} (10√ε = {:.1e})",
        10.0 * eps.sqrt()
    );
    assert!(v_settled < 1.05 * creep);
    assert!((v_end - creep).abs() < 0.01 * creep);
    assert!(v_all < 10.0 * eps.sqrt());
    // Against sliding at μ = 0.2 (metres per second), the box is stuck.
    assert!((s[s.len() - 1] - s[0]).abs() < 0.005);
}

#[test]
fn box_resting_on_ground_for_two_seconds_does_not_sink_or_drift() {
    let scene = Scene::load(robots("box_on_ground.yaml")).unwrap();
    let s = scene.contact.as_ref().unwrap().s;
    let mut sim = scene.simulator();
    let traj = run(&mut sim, 1000, |_| {}).unwrap();
    assert!((traj.times.last().unwrap() - 2.0).abs() < 1e-12);
    let iz = traj.names.iter().position(|n| n == "box/box:z").unwrap();
    let z: Vec<f64> = traj.states.iter().map(|q| q[iz]).collect();
    let drift = z.iter().fold(0.0f64, |m, v| m.max((v - z[0]).abs()));
    let min_gap = traj
        .diagnostics
        .iter()
        .map(|d| d.min_distance)
        .fold(f64::INFINITY, f64::min);
    eprintln!("resting box: max vertical drift {drift:.3e} m (s = {s}), min gap {min_gap:.4e} m");
    assert!(min_gap > 0.0, "interpenetration");
    assert!(drift < s);
    assert!(traj.diagnostics.iter().all(|d| d.contact_pairs == 1));
}

const COLLIDING_BOXES: &str = r#"
dt: 0.002
gravity: [0, 0, 0]
solver: {tol: 1.0e-9}
contact: {s: 0.01, kappa: 1.0, mu: 0.0}
objects:
  - name: a
    mass: 1.0
    hulls: [{box: {size: [0.4, 0.4, 0.4]}}]
    initial: {q: [-0.6, 0.05, 0, 0.1, 0.2, 0.3], qdot: [1.5, 0, 0, 0, 0.5, 1.0]}
  - name: b
    mass: 2.5
    hulls: [{vertices: [[0,0,0.3],[0.3,0,0],[-0.2,0.25,0],[-0.1,-0.3,0.05],[0,0,-0.25]]}]
    initial: {q: [0.5, -0.08, 0.02, 0, 0, 0], qdot: [-0.8, 0.1, 0, 0.3, 0, 0]}
"#;

#[test]
fn two_free_bodies_colliding_in_zero_gravity_conserve_linear_momentum() {
    let scene = Scene::from_str(COLLIDING_BOXES, Path::new("colliding.yaml")).unwrap();
    let mut sim = scene.simulator();
    let traj = run(&mut sim, 600, |_| {}).unwrap();
    let contact_steps = traj
        .diagnostics
        .iter()
        .filter(|d| d.contact_pairs > 0)
        .count();
    let p0 = Vector3::from(traj.diagnostics[0].momentum);
    let worst = traj
        .diagnostics
        .iter()
        .map(|d| (Vector3::from(d.momentum) - p0).norm() / p0.norm())
        .fold(0.0, f64::max);
    // The bodies really bounced: a's x-velocity changed sign.
    let ia = traj.names.iter().position(|n| n == "a/a:x").unwrap();
    let n = traj.states.len();
    let va_end = (traj.states[n - 1][ia] - traj.states[n - 2][ia]) / scene.settings.dt;
    eprintln!(
        "collision: {contact_steps} steps in contact, relative momentum change {worst:.2e}, a's final vx {va_end:.3}"
    );
    assert!(contact_steps > 5);
    assert!(va_end < 1.0, "no collision happened");
    assert!(worst < 1e-8);
}

#[test]
fn separation_checker_reports_overlapping_hulls() {
    if common::skip_without_venv() {
        return;
    }
    // The checker must be able to fail: two unit cubes overlapping by 0.1 m.
    let dir = scratch_dir("fcl-bad");
    let cube: Vec<[f64; 3]> =
        sdrs::model::Hull::cuboid(Vector3::new(1.0, 1.0, 1.0), Vector3::zeros())
            .iter()
            .map(|v| [v.x, v.y, v.z])
            .collect();
    let hulls = serde_json::json!({
        "links": [{"robot": "a", "name": "a", "hulls": [cube]}, {"robot": "b", "name": "b", "hulls": [cube]}],
        "excluded_pairs": []
    });
    std::fs::write(dir.join("hulls.json"), hulls.to_string()).unwrap();
    let mut csv = String::from("step,t,link,a00,a10,a20,a01,a11,a21,a02,a12,a22,t0,t1,t2\n");
    csv.push_str("0,0,0,1,0,0,0,1,0,0,0,1,0,0,0\n0,0,1,1,0,0,0,1,0,0,0,1,0.9,0,0\n");
    std::fs::write(dir.join("poses.csv"), csv).unwrap();
    let check = python()
        .arg(common::root().join("tools/check/check_separation.py"))
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(
        check.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&check.stdout)
    );
}

#[test]
fn intersecting_initial_state_is_a_clear_error() {
    let text = COLLIDING_BOXES.replace("q: [0.5, -0.08, 0.02", "q: [-0.5, 0.05, 0.0");
    let scene = Scene::from_str(&text, Path::new("overlap.yaml")).unwrap();
    let mut sim = scene.simulator();
    let err = sim.step().unwrap_err().to_string();
    assert!(err.contains("step 1") && err.contains("intersect"), "{err}");
}

#[test]
fn stack_of_ten_boxes_stays_stacked_without_interpenetration() {
    let scene = Scene::load(robots("box_stack.yaml")).unwrap();
    let s = scene.contact.as_ref().unwrap().s;
    let mut sim = scene.simulator();
    let traj = run(&mut sim, 1000, |_| {}).unwrap();
    let top = traj.names.iter().position(|n| n == "box9/box9:z").unwrap();
    let tx = traj.names.iter().position(|n| n == "box9/box9:x").unwrap();
    let z0 = traj.states[0][top];
    let sink = traj
        .states
        .iter()
        .map(|q| z0 - q[top])
        .fold(f64::NEG_INFINITY, f64::max);
    let slide = traj.states.iter().map(|q| q[tx].abs()).fold(0.0, f64::max);
    let min_gap = traj
        .diagnostics
        .iter()
        .map(|d| d.min_distance)
        .fold(f64::INFINITY, f64::min);
    let pairs = traj.diagnostics.last().unwrap().contact_pairs;
    eprintln!(
        "stack: top box sank {sink:.3e} m, slid {slide:.1e} m, min gap {min_gap:.4e} m, {pairs} contacts at the end"
    );
    assert!(min_gap > 0.0);
    assert_eq!(
        pairs, 10,
        "every box rests on the one below (and the bottom one on the ground)"
    );
    // Ten barrier layers compress under the growing load, but by less than s each.
    assert!(sink < 10.0 * s);
    assert!(slide < 1e-9, "a symmetric stack must not slide sideways");
}

/// An intersecting start names the pair, the hull indices and the depth, and
/// says how to fix it (shared/repro/ground_a1_intersect_at_start).
#[test]
fn intersecting_start_names_the_pair_and_its_depth() {
    let text = "version: 1\ndt: 0.001\ngravity: [0, 0, 0]\ncontact: {s: 0.01, kappa: 1, mu: 0}\nobjects:\n  - {name: a, mass: 1, hulls: [{box: {size: [1, 1, 1]}}], initial: {q: [0, 0, 0, 0, 0, 0]}}\n  - {name: b, mass: 1, hulls: [{box: {size: [1, 1, 1]}}], initial: {q: [0.9, 0.2, 0, 0, 0, 0]}}\n";
    let scene = Scene::from_str(text, Path::new("overlap.yaml")).unwrap();
    let mut sim = scene.simulator();
    let msg = sim.step().unwrap_err().to_string();
    for part in [
        "step 1",
        "a/a hull 0",
        "b/b hull 0",
        "exclude",
        "initial pose",
    ] {
        assert!(msg.contains(part), "{part:?} missing: {msg}");
    }
    let depth: f64 = msg
        .split("penetration depth ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no depth in {msg}"));
    assert!(
        (depth - 0.1).abs() < 1e-6,
        "depth {depth} (overlap 0.1 m): {msg}"
    );
}
