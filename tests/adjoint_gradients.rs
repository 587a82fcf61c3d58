//! Whole-trajectory gradients by the adjoint method against central finite
//! differences of the loss (re-simulating the whole trajectory).

use crate::common;

use common::adjoint::{Setup, fd};
use nalgebra::Vector3;
use sdrs::diff::{Loss, LossTerm, When};
use sdrs::model::Model;

fn check(name: &str, adjoint: f64, finite: f64, worst: &mut f64) {
    common::adjoint::check(name, adjoint, finite, 1e-4, worst);
}

/// Richardson-extrapolated central difference `(4D(h) − D(2h))/3`.
fn richardson(setup: &Setup, loss: &Loss, h: f64, f: impl Fn(&mut Setup, f64)) -> f64 {
    (4.0 * fd(setup, loss, h, &f) - fd(setup, loss, 2.0 * h, &f)) / 3.0
}

const ARM: &str = r#"
dt: 0.01
gravity: [0.5, -0.3, -9.81]
solver: {tol: 1.0e-10}
robots:
  - name: arm
    links:
      - name: base
        joint: {name: root, type: free}
        mass: 2.0
        hulls: [{box: {size: [0.4, 0.3, 0.2]}}]
      - name: upper
        parent: base
        joint: {name: shoulder, type: ball, origin: {xyz: [0.2, 0.0, 0.1]}}
        mass: 0.6
        hulls: [{box: {size: [0.4, 0.06, 0.06], center: [0.2, 0, 0]}}]
      - name: fore
        parent: upper
        joint: {name: elbow, type: revolute, axis: [0, 0.6, 0.8], origin: {xyz: [0.4, 0, 0]}}
        mass: 0.4
        hulls: [{vertices: [[0,0,0],[0.3,0.02,0],[0.3,-0.02,0.03],[0.15,0,-0.04],[0.1,0.05,0.02]]}]
      - name: slider
        parent: fore
        joint: {name: slide, type: prismatic, axis: [1, 0, 0], origin: {xyz: [0.3, 0, 0]}}
        mass: 0.2
        hulls: [{box: {size: [0.1, 0.05, 0.05], center: [0.05, 0, 0]}}]
    controller:
      kp: 4
      kd: 0.02
      targets:
        shoulder: [{type: sine, offset: 0.1, terms: [{amplitude: 0.4, frequency: 1.5, phase: 0.2}]}, {type: spline, times: [0, 0.2, 0.4, 0.6], values: [0, 0.3, -0.2, 0.1]}]
        elbow: {type: table, times: [0, 0.3, 0.6], values: [0.2, -0.4, 0.3]}
        slide: {type: constant, value: 0.05}
    initial:
      root: {q: [0, 0, 1, 0.3, -0.2, 0.5], qdot: [0.2, 0.1, 0.5, 0.4, -0.3, 0.2]}
      shoulder: {q: [0.2, -0.1], qdot: [0.5, 0.3]}
      elbow: {q: [0.4], qdot: [-0.2]}
"#;

fn arm_loss(model: &Model) -> Loss {
    let link = |n: &str| model.links.iter().position(|l| l.name == n).unwrap();
    Loss {
        terms: vec![
            LossTerm::LinkPoint {
                link: link("slider"),
                point: Vector3::new(0.1, 0.02, 0.0),
                target: Vector3::new(0.8, 0.3, 0.7),
                weight: 1.0,
                when: When::Final,
            },
            LossTerm::Joint {
                dof: model.links[link("fore")].dof_offset,
                target: 0.3,
                weight: 0.5,
                when: When::Running,
            },
            LossTerm::CenterOfMass {
                links: (0..model.links.len()).collect(),
                target: Vector3::new(0.1, 0.0, 0.9),
                axes: Vector3::new(1.0, 1.0, 0.0),
                weight: 2.0,
                when: When::Final,
            },
        ],
    }
}

#[test]
fn trajectory_gradients_match_finite_differences_without_contact() {
    let setup = Setup::new(ARM, 60);
    let loss = arm_loss(&setup.model);
    let g = setup.gradients(&loss);
    assert!(g.unavailable.is_empty(), "{:?}", g.unavailable);
    let mut worst = 0.0;
    // Richardson differences `(4D(h) − D(2h))/3` at h = 1e-4 since 2026-11-29
    // (were central differences at h = 1e-5), changed after this outcome: with
    // the quadratic predictor as the solver's default, `vertex[2][0][1][2]`
    // (a small component, −2.44e-4) failed at 1.86e-4 relative while its
    // adjoint was unchanged to 1e-9. An h-scan of that component (central
    // differences, relative error; quadratic / extrapolate predictor):
    // h = 1e-3: 4.0e-5 / 4.0e-5 (truncation); 1e-4: 9.1e-7 / 1.6e-6;
    // 1e-5: 1.9e-4 / 1.4e-5; 1e-6: 1.9e-3 / 5.2e-5 (the Newton solutions'
    // tol-level error over 2h). At 1e-5 the difference was in the noise.
    // Central differences at 1e-4 then missed `channel[0].kd` by 1.0e-3
    // (truncation: kd = 0.02); Richardson at 1e-4 removes the h² term
    // (the component above: 9.2e-7 / 1.6e-6).
    let h = 1e-4;
    // Initial state.
    for k in [0, 2, 4, 6, 7, 8, 9] {
        let a = richardson(&setup, &loss, h, |s, d| s.q0[k] += d);
        check(&format!("q0[{k}]"), g.q0[k], a, &mut worst);
        let b = richardson(&setup, &loss, h, |s, d| s.qdot0[k] += d);
        check(&format!("qdot0[{k}]"), g.qdot0[k], b, &mut worst);
    }
    // Attachment points and hull vertices.
    for (c, e) in [(1, 0), (1, 2), (2, 0), (2, 1), (3, 0), (0, 2)] {
        let a = richardson(&setup, &loss, h, |s, d| {
            s.model.links[c].attach[(e, 3)] += d
        });
        check(
            &format!("attachment[{c}][{e}]"),
            g.attachments[c][e],
            a,
            &mut worst,
        );
    }
    for (l, hh, v, e) in [
        (0, 0, 3, 1),
        (1, 0, 5, 0),
        (2, 0, 1, 2),
        (2, 0, 4, 0),
        (3, 0, 7, 1),
    ] {
        let a = richardson(&setup, &loss, h, |s, d| {
            s.model.links[l].hulls[hh].x_local[v][e] += d;
            s.model.refresh_moments();
        });
        check(
            &format!("vertex[{l}][{hh}][{v}][{e}]"),
            g.vertices[l][hh][v][e],
            a,
            &mut worst,
        );
    }
    // Controller parameters and gains.
    for ch in 0..setup.controller.channels.len() {
        let np = setup.controller.channels[ch].signal.nparams();
        for k in 0..np {
            let a = richardson(&setup, &loss, h, |s, d| {
                let sig = &mut s.controller.channels[ch].signal;
                let mut p = sig.params();
                p[k] += d;
                sig.set_params(&p);
            });
            check(
                &format!("channel[{ch}].signal[{k}]"),
                g.channels[ch].signal[k],
                a,
                &mut worst,
            );
        }
        let a = richardson(&setup, &loss, h, |s, d| s.controller.channels[ch].kp += d);
        check(
            &format!("channel[{ch}].kp"),
            g.channels[ch].kp,
            a,
            &mut worst,
        );
        let a = richardson(&setup, &loss, h, |s, d| s.controller.channels[ch].kd += d);
        check(
            &format!("channel[{ch}].kd"),
            g.channels[ch].kd,
            a,
            &mut worst,
        );
    }
    // Physics.
    for e in 0..3 {
        let a = richardson(&setup, &loss, h, |s, d| s.settings.gravity[e] += d);
        check(
            &format!("gravity[{e}]"),
            g.physical.gravity[e],
            a,
            &mut worst,
        );
    }
    let a = richardson(&setup, &loss, h, |s, d| {
        for l in &mut s.model.links {
            for hull in &mut l.hulls {
                hull.vertex_mass.iter_mut().for_each(|m| *m *= 1.0 + d);
            }
        }
        s.model.refresh_moments();
    });
    check("mass scale", g.physical.mass_scale, a, &mut worst);
    eprintln!("worst relative error {worst:.2e} (h = {h}, Newton tol 1e-10)");
}

/// The arm with `solid` links (hulls in general position: at a vertex of a
/// planar face with more than three corners, the solid's moments have a
/// kink, see `sdrs::model::mass`) and a `given` slider.
const SOLID_ARM: &str = r#"
dt: 0.01
gravity: [0.5, -0.3, -9.81]
solver: {tol: 1.0e-10}
robots:
  - name: arm
    links:
      - name: base
        joint: {name: root, type: free}
        mass: 2.0
        mass_model: {type: solid}
        hulls: [{vertices: [[-0.21,-0.15,-0.1],[0.2,-0.16,-0.11],[-0.19,0.15,-0.09],[0.22,0.14,-0.093],[-0.2,-0.14,0.1],[0.21,-0.15,0.12],[-0.2,0.16,0.1],[0.19,0.15,0.09]]}]
      - name: upper
        parent: base
        joint: {name: shoulder, type: ball, origin: {xyz: [0.2, 0.0, 0.1]}}
        mass_model: {type: solid, density: 900}
        hulls: [{vertices: [[0,-0.03,-0.03],[0.02,0.03,-0.02],[0.01,0,0.035],[0.4,-0.02,-0.03],[0.38,0.03,0.01],[0.41,0,0.03]]}]
      - name: fore
        parent: upper
        joint: {name: elbow, type: revolute, axis: [0, 0.6, 0.8], origin: {xyz: [0.4, 0, 0]}}
        mass_model: {type: solid, density: 1200}
        hulls: [{vertices: [[0,0,0],[0.3,0.02,0],[0.3,-0.02,0.03],[0.15,0,-0.04],[0.1,0.05,0.02]]}]
      - name: slider
        parent: fore
        joint: {name: slide, type: prismatic, axis: [1, 0, 0], origin: {xyz: [0.3, 0, 0]}}
        mass_model: {type: given, mass: 0.2, com: [0.05, 0.01, 0], inertia: [1.0e-4, 1.0e-5, 0, 2.0e-4, 0, 2.0e-4]}
        hulls: [{box: {size: [0.1, 0.05, 0.05], center: [0.05, 0, 0]}}]
    controller:
      kp: 4
      kd: 0.02
      targets:
        shoulder: [{type: sine, offset: 0.1, terms: [{amplitude: 0.4, frequency: 1.5, phase: 0.2}]}, {type: constant, value: 0.1}]
        elbow: {type: table, times: [0, 0.3, 0.6], values: [0.2, -0.4, 0.3]}
        slide: {type: constant, value: 0.05}
    initial:
      root: {q: [0, 0, 1, 0.3, -0.2, 0.5], qdot: [0.2, 0.1, 0.5, 0.4, -0.3, 0.2]}
      shoulder: {q: [0.2, -0.1], qdot: [0.5, 0.3]}
      elbow: {q: [0.4], qdot: [-0.2]}
"#;

#[test]
fn trajectory_design_gradients_with_solid_and_given_masses_match_finite_differences() {
    let setup = Setup::new(SOLID_ARM, 40);
    assert!(matches!(
        setup.model.links[0].mass_model,
        sdrs::model::MassModel::Solid { .. }
    ));
    let loss = arm_loss(&setup.model);
    let g = setup.gradients(&loss);
    assert!(g.unavailable.is_empty(), "{:?}", g.unavailable);
    let mut worst = 0.0;
    let h = 1e-5;
    for (c, e) in [(1, 0), (2, 1), (3, 0)] {
        let a = fd(&setup, &loss, h, |s, d| {
            s.model.links[c].attach[(e, 3)] += d
        });
        check(
            &format!("attachment[{c}][{e}]"),
            g.attachments[c][e],
            a,
            &mut worst,
        );
    }
    // Solid links: the vertices move mass, COM and inertia.
    for (l, v, e) in [
        (0, 0, 0),
        (0, 5, 2),
        (1, 3, 0),
        (1, 4, 1),
        (2, 1, 2),
        (2, 4, 0),
    ] {
        let a = fd(&setup, &loss, h, |s, d| {
            s.model.links[l].hulls[0].x_local[v][e] += d;
            s.model.refresh_moments();
        });
        check(
            &format!("vertex[{l}][0][{v}][{e}]"),
            g.vertices[l][0][v][e],
            a,
            &mut worst,
        );
    }
    // The given link's inertial does not follow its hull.
    assert_eq!(g.vertices[3][0][2], nalgebra::Vector3::zeros());
    eprintln!("solid/given: worst relative error {worst:.2e} (h = {h})");
}
