//! PD targets on a free root joint (a prescribed 6-DOF base path,
//! `sdrs::control::pose_target`): the trajectory follows the path, the
//! rotation chart is re-centred on the way, and whole-trajectory gradients
//! (initial state, every signal parameter, gains, vertices of a child link)
//! match central finite differences.

use crate::common;

use common::adjoint::{Setup, check, fd};
use nalgebra::Vector3;
use sdrs::diff::{Loss, LossTerm, When, record};
use sdrs::math::so3;

/// A free base with a hinged child; the base is driven along a path that
/// turns it by ≈ 2.2 rad (the chart is re-centred past 1 rad), with an
/// attachment frame that is rotated and shifted.
const FLYER: &str = r#"
dt: 0.01
gravity: [0.3, -0.2, -9.81]
solver: {tol: 1.0e-11}
robots:
  - name: flyer
    base: {xyz: [0.1, -0.2, 0.3], rpy: [0.2, -0.1, 0.4]}
    links:
      - name: body
        joint: {name: root, type: free}
        mass: 1.0
        hulls: [{box: {size: [0.3, 0.2, 0.1]}}]
      - name: arm
        parent: body
        joint: {name: hinge, type: revolute, axis: [0, 1, 0], origin: {xyz: [0.15, 0, 0]}}
        mass: 0.3
        hulls: [{vertices: [[0,0,0],[0.2,0.02,0],[0.2,-0.02,0.03],[0.1,0,-0.04],[0.05,0.03,0.02]]}]
    controller:
      kp: 2
      kd: 0.05
      gains: {root: {kp: 40, kd: 0.05}}
      targets:
        root:
          - {type: spline, times: [0, 0.2, 0.4, 0.6], values: [0, 0.1, 0.15, 0.1]}
          - {type: table, times: [0, 0.3, 0.6], values: [0, -0.05, 0.05]}
          - {type: sine, offset: 0.5, terms: [{amplitude: 0.1, frequency: 1.2, phase: 0.3}]}
          - {type: spline, times: [0, 0.2, 0.4, 0.6], values: [0.3, 1.0, 1.8, 2.0]}
          - {type: spline, times: [0, 0.3, 0.6], values: [-0.2, 0.4, 0.6]}
          - {type: constant, value: 0.5}
        hinge: {type: constant, value: 0.3}
    initial:
      root: {q: [0, 0, 0.5, 0.3, -0.2, 0.5], qdot: [0.1, 0, 0.2, 0.3, -0.2, 0.1]}
      hinge: {q: [0.1]}
"#;

fn flyer_loss(s: &Setup) -> Loss {
    Loss {
        terms: vec![
            LossTerm::LinkPoint {
                link: s.link("arm"),
                point: Vector3::new(0.2, 0.0, 0.0),
                target: Vector3::new(0.5, 0.2, 0.9),
                weight: 1.0,
                when: When::Final,
            },
            LossTerm::LinkPoint {
                link: s.link("body"),
                point: Vector3::new(0.1, 0.1, 0.0),
                target: Vector3::new(0.3, -0.1, 0.8),
                weight: 0.5,
                when: When::Running,
            },
        ],
    }
}

#[test]
fn free_root_follows_its_pose_target() {
    let mut s = Setup::new(FLYER, 200);
    s.settings.newton.tol = 1e-9;
    // Without gravity (a PD term alone leaves a static offset under load).
    s.settings.gravity = Vector3::zeros();
    let mut sim = s.simulator();
    record(&mut sim, s.steps).unwrap();
    // After 2 s the targets are constant (held splines, table; the sine is
    // not): compare the rotation, which is held at r* = (2.0, 0.6, 0.5).
    let body = s.link("body");
    let frame = s.controller.pose_targets[0].frame;
    let pose = sdrs::kinematics::link_poses(&s.model, &sim.state.q, &sim.state.charts)[body];
    let rb = frame.fixed_view::<3, 3>(0, 0).into_owned();
    let r_joint = rb.transpose() * pose.fixed_view::<3, 3>(0, 0);
    let target = so3::exp(&Vector3::new(2.0, 0.6, 0.5));
    let err = so3::log(&(target.transpose() * r_joint)).norm();
    eprintln!("rotation error after 2 s: {err:.3e} rad");
    assert!(err < 0.05, "rotation error {err} rad");
    let p = rb.transpose() * (pose.column(3) - frame.column(3));
    eprintln!("position after 2 s: {p:?}");
    assert!(
        (p.x - 0.1).abs() < 0.01 && (p.y - 0.05).abs() < 0.01,
        "{p:?}"
    );
    assert!(
        sim.state.charts[0] != so3::exp(&Vector3::new(0.3, -0.2, 0.5)),
        "the chart was re-centred"
    );
}

#[test]
fn pose_target_gradients_match_finite_differences() {
    let setup = Setup::new(FLYER, 60);
    let loss = flyer_loss(&setup);
    let g = setup.gradients(&loss);
    assert!(g.unavailable.is_empty(), "{:?}", g.unavailable);
    let mut worst = 0.0;
    let h = 1e-5;
    let tol = 1e-4;
    for k in 0..7 {
        let a = fd(&setup, &loss, h, |s, d| s.q0[k] += d);
        check(&format!("q0[{k}]"), g.q0[k], a, tol, &mut worst);
        let b = fd(&setup, &loss, h, |s, d| s.qdot0[k] += d);
        check(&format!("qdot0[{k}]"), g.qdot0[k], b, tol, &mut worst);
    }
    for ch in 0..6 {
        let np = setup.controller.channels[ch].signal.nparams();
        for k in 0..np {
            let a = fd(&setup, &loss, h, |s, d| {
                let sig = &mut s.controller.channels[ch].signal;
                let mut p = sig.params();
                p[k] += d;
                sig.set_params(&p);
            });
            let name = format!("channel[{ch}].signal[{k}]");
            check(&name, g.channels[ch].signal[k], a, tol, &mut worst);
        }
        let a = fd(&setup, &loss, h, |s, d| s.controller.channels[ch].kp += d);
        check(
            &format!("channel[{ch}].kp"),
            g.channels[ch].kp,
            a,
            tol,
            &mut worst,
        );
        let a = fd(&setup, &loss, h, |s, d| s.controller.channels[ch].kd += d);
        check(
            &format!("channel[{ch}].kd"),
            g.channels[ch].kd,
            a,
            tol,
            &mut worst,
        );
    }
    let arm = setup.link("arm");
    for (v, e) in [(1, 0), (2, 2), (4, 1)] {
        let a = fd(&setup, &loss, h, |s, d| {
            s.model.links[arm].hulls[0].x_local[v][e] += d;
            s.model.refresh_moments();
        });
        let name = format!("vertex[arm][{v}][{e}]");
        check(&name, g.vertices[arm][0][v][e], a, tol, &mut worst);
    }
    let a = fd(&setup, &loss, h, |s, d| {
        s.model.links[arm].attach[(2, 3)] += d
    });
    check(
        "attachment[arm][2]",
        g.attachments[arm][2],
        a,
        tol,
        &mut worst,
    );
    eprintln!("worst relative error {worst:.2e} (h = {h}, Newton tol 1e-11)");
}
