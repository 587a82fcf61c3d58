//! Joint limits (`sdrs::energy::joint_limit`): the barrier's derivatives in
//! the step objective against finite differences near a limit, a joint
//! driven past its limit stopping inside the barrier's support without ever
//! crossing, the adjoint through an active limit, and bad limits.

use crate::common;

use common::adjoint::{Setup, fd};
use nalgebra::DVector;
use sdrs::diff::{Loss, LossTerm, When};
use sdrs::energy::Need;
use sdrs::kinematics::link_poses;
use sdrs::scene::Scene;
use std::path::Path;

/// A two-link arm; the elbow is limited to [−0.5, 0.5] rad (support 0.02),
/// the slider to [−0.1, 0.05] m; PD targets drive both past the upper limit.
const ARM: &str = r#"
dt: 0.01
gravity: [0, 0, -9.81]
solver: {tol: 1.0e-10}
robots:
  - name: arm
    links:
      - name: upper
        joint: {name: shoulder, type: revolute, axis: [0, 1, 0]}
        mass: 1.0
        hulls: [{box: {size: [0.4, 0.05, 0.05], center: [0.2, 0, 0]}}]
      - name: fore
        parent: upper
        joint: {name: elbow, type: revolute, axis: [0, 1, 0], origin: {xyz: [0.4, 0, 0]}, limit: {lower: -0.5, upper: 0.5, support: 0.02, stiffness: 1.0e-3, velocity: 2.0, effort: 30}}
        mass: 0.5
        hulls: [{box: {size: [0.3, 0.05, 0.05], center: [0.15, 0, 0]}}]
      - name: slider
        parent: fore
        joint: {name: slide, type: prismatic, axis: [1, 0, 0], origin: {xyz: [0.3, 0, 0]}, limit: {lower: -0.1, upper: 0.05}}
        mass: 0.2
        hulls: [{box: {size: [0.1, 0.04, 0.04], center: [0.05, 0, 0]}}]
    controller:
      kp: 20
      kd: 0.1
      targets:
        shoulder: {type: constant, value: 0.3}
        elbow: {type: constant, value: 1.5}
        slide: {type: constant, value: 0.4}
    initial:
      elbow: {q: [0.2], qdot: [3.0]}
"#;

fn rel(a: f64, b: f64, floor: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(floor)
}

#[test]
fn limit_barrier_derivatives_match_finite_differences_near_the_limit() {
    let scene = Scene::from_str(ARM, Path::new("limits.yaml")).unwrap();
    let model = &scene.model;
    let mut sim = scene.simulator();
    let q_prev = DVector::from_vec(vec![0.1, 0.45, 0.02]);
    sim.state.poses = link_poses(model, &q_prev, &[]);
    sim.state.poses_prev = sim.state.poses.clone();
    sim.state.q = q_prev.clone();
    sim.state.q_prev = q_prev.clone();
    let mut worst: f64 = 0.0;
    // Distances to the elbow's upper limit across the support (0.02), and
    // to the slider's lower limit.
    for (k, x) in [
        (1, 0.5 - 0.019),
        (1, 0.5 - 0.01),
        (1, 0.5 - 0.002),
        (1, 0.5 - 2e-4),
        (2, -0.1 + 0.003),
    ] {
        let mut q = q_prev.clone();
        q[k] = x;
        let dist = if k == 1 { 0.5 - x } else { x + 0.1 };
        let (_, g, h) = sim.objective(&q, Need::Hessian).unwrap();
        let step = 1e-4 * dist;
        let (mut qp, mut qm) = (q.clone(), q.clone());
        qp[k] += step;
        qm[k] -= step;
        let (vp, gp, _) = sim.objective(&qp, Need::Gradient).unwrap();
        let (vm, gm, _) = sim.objective(&qm, Need::Gradient).unwrap();
        let g_fd = (vp - vm) / (2.0 * step);
        let h_fd: DVector<f64> = (gp - gm) / (2.0 * step);
        let eg = rel(g[k], g_fd, 1e-8);
        let eh = (h.column(k) - &h_fd).amax() / h.column(k).amax();
        worst = worst.max(eg).max(eh);
        assert!(
            eg <= 1e-6 && eh <= 1e-6,
            "dof {k} at {x}: gradient {eg:.2e}, Hessian {eh:.2e}"
        );
    }
    // The barrier dominates the objective's curvature close to the limit.
    let mut q = q_prev.clone();
    q[1] = 0.5 - 2e-4;
    let (_, _, h) = sim.objective(&q, Need::Hessian).unwrap();
    let mut far = q_prev.clone();
    far[1] = 0.3;
    let (_, _, h_far) = sim.objective(&far, Need::Hessian).unwrap();
    assert!(h[(1, 1)] > 1e3 * h_far[(1, 1)]);
    // At or beyond the limit the objective is +∞ (infeasible).
    for x in [0.5, 0.6] {
        q[1] = x;
        let (v, _, _) = sim.objective(&q, Need::Value).unwrap();
        assert_eq!(v, f64::INFINITY);
    }
    eprintln!("joint-limit term vs FD near the limit: worst relative error {worst:.2e}");
}

#[test]
fn joints_driven_past_their_limits_stop_inside_the_support_and_never_cross() {
    let scene = Scene::from_str(ARM, Path::new("limits.yaml")).unwrap();
    let mut sim = scene.simulator();
    let (mut max_elbow, mut max_slide) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    for _ in 0..200 {
        sim.step().unwrap();
        max_elbow = max_elbow.max(sim.state.q[1]);
        max_slide = max_slide.max(sim.state.q[2]);
        assert!(
            sim.state.q[1] < 0.5 && sim.state.q[2] < 0.05,
            "crossed: {}",
            sim.state.q
        );
    }
    // Both rest inside the support, pressed against the limit by the PD
    // targets beyond it.
    let q = &sim.state.q;
    assert!(
        q[1] > 0.5 - 0.02 && q[2] > 0.05 - 0.02,
        "not at the limit: {q}"
    );
    eprintln!(
        "elbow: max {max_elbow:.6} (limit 0.5), final {:.6}; slide: max {max_slide:.6} (limit 0.05), final {:.6}",
        q[1], q[2]
    );
    // Without limits the same targets carry the joints well past them.
    let free = ARM
        .replace(", limit: {lower: -0.5, upper: 0.5, support: 0.02, stiffness: 1.0e-3, velocity: 2.0, effort: 30}", "")
        .replace(", limit: {lower: -0.1, upper: 0.05}", "");
    let mut sim = Scene::from_str(&free, Path::new("free.yaml"))
        .unwrap()
        .simulator();
    for _ in 0..200 {
        sim.step().unwrap();
    }
    assert!(
        sim.state.q[1] > 0.8 && sim.state.q[2] > 0.1,
        "{}",
        sim.state.q
    );
}

#[test]
fn trajectory_gradients_through_an_active_limit_match_finite_differences() {
    let setup = Setup::new(ARM, 40);
    let loss = Loss {
        terms: vec![
            LossTerm::LinkPoint {
                link: 2,
                point: nalgebra::Vector3::new(0.1, 0.0, 0.0),
                target: nalgebra::Vector3::new(0.5, 0.0, -0.5),
                weight: 1.0,
                when: When::Final,
            },
            LossTerm::Joint {
                dof: 1,
                target: 0.0,
                weight: 1.0,
                when: When::Running,
            },
        ],
    };
    let g = setup.gradients(&loss);
    assert!(g.unavailable.is_empty(), "{:?}", g.unavailable);
    let h = 1e-6;
    let mut worst = 0.0;
    for k in 0..3 {
        let a = fd(&setup, &loss, h, |s, d| s.qdot0[k] += d);
        common::adjoint::check(&format!("qdot0[{k}]"), g.qdot0[k], a, 1e-4, &mut worst);
    }
    for (c, e) in [(1, 0), (2, 0)] {
        let a = fd(&setup, &loss, h, |s, d| {
            s.model.links[c].attach[(e, 3)] += d
        });
        common::adjoint::check(
            &format!("attachment[{c}][{e}]"),
            g.attachments[c][e],
            a,
            1e-4,
            &mut worst,
        );
    }
    for ch in 0..3 {
        let a = fd(&setup, &loss, h, |s, d| s.controller.channels[ch].kp += d);
        common::adjoint::check(&format!("kp[{ch}]"), g.channels[ch].kp, a, 1e-4, &mut worst);
    }
    eprintln!("through active limits: worst relative error {worst:.2e}");
}

#[test]
fn bad_limits_are_errors_naming_the_joint() {
    for (from, to, want) in [
        (
            "limit: {lower: -0.5, upper: 0.5, support",
            "limit: {lower: 0.5, upper: -0.5, support",
            "below upper",
        ),
        (
            "limit: {lower: -0.1, upper: 0.05}",
            "limit: {lower: -0.1, upper: 0.05, stiffness: -1}",
            "stiffness",
        ),
        (
            "elbow: {q: [0.2], qdot: [3.0]}",
            "elbow: {q: [0.7], qdot: [3.0]}",
            "strictly inside",
        ),
        (
            "type: revolute, axis: [0, 1, 0]}",
            "type: revolute, axis: [0, 1, 0], limit: {lower: -1, upper: 1, velocity: -2}}",
            "velocity",
        ),
    ] {
        let text = ARM.replacen(from, to, 1);
        assert_ne!(text, ARM, "{from}");
        let e = Scene::from_str(&text, Path::new("bad.yaml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(want)
                && (e.contains("elbow")
                    || e.contains("fore")
                    || e.contains("slider")
                    || e.contains("upper")),
            "{e}"
        );
    }
}

/// Two fingers on a palm; `right` mimics `left` with multiplier −1 and an
/// offset, tied by the coupling term; only `left` is driven.
const GRIPPER: &str = r#"
dt: 0.01
gravity: [0, 0, -9.81]
robots:
  - name: g
    links:
      - name: palm
        joint: {type: fixed}
        mass: 1.0
        hulls: [{box: {size: [0.2, 0.05, 0.05]}}]
      - name: left
        parent: palm
        joint: {name: left, type: revolute, axis: [0, 1, 0], origin: {xyz: [-0.08, 0, -0.03]}}
        mass: 0.1
        hulls: [{box: {size: [0.02, 0.02, 0.1], center: [0, 0, -0.05]}}]
      - name: right
        parent: palm
        joint: {name: right, type: revolute, axis: [0, 1, 0], origin: {xyz: [0.08, 0, -0.03]}, mimic: {joint: left, multiplier: -1, offset: 0.05, stiffness: 100}}
        mass: 0.1
        hulls: [{box: {size: [0.02, 0.02, 0.1], center: [0, 0, -0.05]}}]
    controller:
      gains: {left: {kp: 5, kd: 0.05}}
      targets:
        left: {type: constant, value: 0.4}
    initial:
      left: {q: [0.1], qdot: [0.5]}
"#;

#[test]
fn mimic_tie_derivatives_match_finite_differences() {
    let scene = Scene::from_str(GRIPPER, Path::new("gripper.yaml")).unwrap();
    // The mimic starts on its relation.
    assert!((scene.q0[1] - (-0.1 + 0.05)).abs() < 1e-15 && (scene.qdot0[1] + 0.5).abs() < 1e-15);
    let model = &scene.model;
    let mut sim = scene.simulator();
    let q_prev = DVector::from_vec(vec![0.1, -0.02]);
    sim.state.poses = link_poses(model, &q_prev, &[]);
    sim.state.poses_prev = sim.state.poses.clone();
    sim.state.q = q_prev.clone();
    sim.state.q_prev = q_prev.clone();
    let q = DVector::from_vec(vec![0.13, 0.01]);
    let (_, g, h) = sim.objective(&q, Need::Hessian).unwrap();
    let step = 1e-6;
    for k in 0..2 {
        let (mut qp, mut qm) = (q.clone(), q.clone());
        qp[k] += step;
        qm[k] -= step;
        let (vp, gp, _) = sim.objective(&qp, Need::Gradient).unwrap();
        let (vm, gm, _) = sim.objective(&qm, Need::Gradient).unwrap();
        let g_fd = (vp - vm) / (2.0 * step);
        let h_fd: DVector<f64> = (gp - gm) / (2.0 * step);
        assert!(
            rel(g[k], g_fd, 1e-8) <= 1e-6,
            "gradient {k}: {} vs {g_fd}",
            g[k]
        );
        assert!(
            (h.column(k) - &h_fd).amax() <= 1e-6 * h.column(k).amax(),
            "Hessian column {k}"
        );
    }
    // The coupling block: k [1, −a; −a, a²] with a = −1 adds +k off-diagonal.
    let mut free = scene.clone();
    free.model.mimics.clear();
    let mut sim_free = free.simulator();
    sim_free.state = sim.state.clone();
    let (_, _, h_free) = sim_free.objective(&q, Need::Hessian).unwrap();
    assert!(((&h - &h_free)[(0, 1)] - 100.0).abs() < 1e-9);
}

#[test]
fn a_mimic_joint_follows_its_driven_joint() {
    let scene = Scene::from_str(GRIPPER, Path::new("gripper.yaml")).unwrap();
    let mut sim = scene.simulator();
    let mut worst: f64 = 0.0;
    for _ in 0..150 {
        sim.step().unwrap();
        let q = &sim.state.q;
        worst = worst.max((q[1] - (-q[0] + 0.05)).abs());
    }
    let q = sim.state.q.clone();
    // The driven finger moved well towards its target (from 0.1 to 0.4).
    assert!(q[0] > 0.25, "driven joint at {}", q[0]);
    assert!(worst < 5e-3, "tie violated by {worst}");
    eprintln!(
        "mimic: left {:.4}, right {:.4}, worst tie error {worst:.2e} rad",
        q[0], q[1]
    );
    // Untied, the undriven finger just hangs.
    let mut free = scene.clone();
    free.model.mimics.clear();
    let mut sim = free.simulator();
    for _ in 0..150 {
        sim.step().unwrap();
    }
    assert!(sim.state.q[1].abs() < 0.2 && (sim.state.q[1] - (-q[0] + 0.05)).abs() > 0.1);
}
