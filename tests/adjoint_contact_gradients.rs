//! Whole-trajectory gradients through contact and friction: a prismatic
//! finger pushes a box along the ground (μ > 0 at both interfaces), contact
//! active at every step; adjoint gradients against central finite
//! differences. Also: the loss is C¹ through contact onset.

use crate::common;

use common::adjoint::{Setup, check, fd, push_loss};
use nalgebra::Vector3;
use sdrs::contact::{ContactParams, ContactScratch, VertexOutcome, contact_vertices};
use sdrs::diff::Loss;
use sdrs::math::transform_point;

/// The pushing scene; `{KAPPA}`, `{FINGER_X}` and `{BOX_Z}` are filled in.
const PUSH: &str = r#"
dt: 0.01
gravity: [0, 0, -9.81]
solver: {tol: 1.0e-10}
ground: {height: 0}
contact: {s: 0.01, kappa: {KAPPA}, mu: 0.4}
robots:
  - name: finger
    links:
      - name: pusher
        joint: {name: slide, type: prismatic, axis: [1, 0, 0], origin: {xyz: [{FINGER_X}, 0.015, 0.118]}}
        mass: 0.2
        hulls:
          - vertices: [[-0.08, -0.04, -0.03], [0.0, -0.035, -0.032], [-0.08, 0.04, -0.03], [-0.001, 0.04, -0.028],
                       [-0.08, -0.04, 0.03], [0.0005, -0.036, 0.03], [-0.08, 0.04, 0.03], [0.0, 0.035, 0.029]]
    controller:
      kp: 150
      kd: 0.02
      targets:
        slide: {type: spline, times: [0, 0.4, 0.8, 1.0], values: [0.0, 0.02, 0.045, 0.05]}
objects:
  - name: box
    mass: 0.5
    hulls: [{box: {size: [0.2, 0.2, 0.2]}}]
    initial: {q: [0, 0, {BOX_Z}, 0, 0, 0]}
"#;

const KAPPA: f64 = 1e-5;

fn scene_text(kappa: f64, finger_x: f64, box_z: f64) -> String {
    PUSH.replace("{KAPPA}", &format!("{kappa:e}"))
        .replace("{FINGER_X}", &format!("{finger_x}"))
        .replace("{BOX_Z}", &format!("{box_z}"))
}

/// Height of the box centre at which κ U_c against the ground carries its
/// weight (bisection on the vertical force balance).
fn rest_height(kappa: f64) -> f64 {
    let setup = Setup::new(&scene_text(kappa, -0.2, 0.2), 1);
    let sim = setup.simulator();
    let model = &setup.model;
    let ground = setup.link("ground");
    let bx = setup.link("box");
    let xg: Vec<Vector3<f64>> = model.links[ground].hulls[0]
        .x_local
        .iter()
        .map(|x| transform_point(&sim.state.poses[ground], x))
        .collect();
    let local = &model.links[bx].hulls[0].x_local;
    let s = setup.scene.contact.as_ref().unwrap().s;
    let params = ContactParams::with_width(s);
    let weight = model.links[bx].mass() * 9.81;
    let force = |z: f64| {
        let xb: Vec<Vector3<f64>> = local
            .iter()
            .map(|x| x + Vector3::new(0.0, 0.0, z))
            .collect();
        let mut sc = ContactScratch::new();
        match contact_vertices(&xg, &xb, &params, None, &mut sc).unwrap() {
            VertexOutcome::Separated(c) => kappa * c.grad_b.iter().map(|g| g.z).sum::<f64>(),
            VertexOutcome::OutOfRange { .. } => 0.0,
            VertexOutcome::Intersecting => f64::NEG_INFINITY,
        }
    };
    let (mut lo, mut hi) = (0.1 + 1e-6, 0.1 + 2.0 * s / (1.0 - s));
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if force(mid) + weight < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

fn push_setup(finger_x: f64, steps: usize) -> Setup {
    Setup::new(&scene_text(KAPPA, finger_x, rest_height(KAPPA)), steps)
}

/// Runs the scene and asserts both contacts (box–ground and finger–box) are
/// active at every step.
fn assert_contact_throughout(setup: &Setup) {
    let mut sim = setup.simulator();
    let traj = sdrs::sim::run::run(&mut sim, setup.steps, |_| {}).unwrap();
    for (k, d) in traj.diagnostics.iter().enumerate() {
        assert_eq!(
            d.contact_pairs,
            2,
            "step {}: {} active pairs",
            k + 1,
            d.contact_pairs
        );
    }
    let ix = traj.names.iter().position(|n| n == "box/box:x").unwrap();
    let pushed = traj.states.last().unwrap()[ix] - traj.states[0][ix];
    eprintln!("box pushed {pushed:.4} m in {} steps", setup.steps);
    assert!(
        pushed > 0.02,
        "the finger does not push the box ({pushed} m)"
    );
}

/// 100 steps of Δt = 0.01 s with both contacts active throughout (the box
/// slides on the ground; finger–box slip stays in the smoothed regime).
/// Central differences with h = 1e-6 (1e-4 for θ̇⁰, i.e. 1e-6 in θ^{−1};
/// relative steps for κ and s; 1e-3 for k_p, 1e-7 for k_d), Newton tolerance
/// 1e-10: every gradient within a relative error of 1e-4.
#[test]
fn trajectory_gradients_match_finite_differences_with_contact_and_friction() {
    let t0 = std::time::Instant::now();
    let setup = push_setup(-0.112, 100);
    assert_contact_throughout(&setup);
    let loss = push_loss(&setup);
    let g = setup.gradients(&loss);
    eprintln!("loss {:.9e}, backward pass {:.3} s", g.loss, g.seconds);
    assert!(g.unavailable.is_empty(), "{:?}", g.unavailable);
    let tol = 1e-4;
    let h = 1e-6;
    let mut worst = 0.0;
    let finger = setup.link("pusher");
    let bx = setup.link("box");
    // Initial state (finger slide, box x y z rx ry rz).
    for k in 0..7 {
        let a = fd(&setup, &loss, h, |s, d| s.q0[k] += d);
        check(&format!("q0[{k}]"), g.q0[k], a, tol, &mut worst);
        // θ^{−1} = θ^0 − Δt θ̇^0: a step of 1e-4 in θ̇ moves the state by 1e-6.
        let b = fd(&setup, &loss, 1e-4, |s, d| s.qdot0[k] += d);
        check(&format!("qdot0[{k}]"), g.qdot0[k], b, tol, &mut worst);
    }
    // Attachment points: the finger's slide origin and the box's free-joint origin.
    // The ground is static: its gradients come only from the contact and
    // friction terms' products at static links.
    let ground = setup.link("ground");
    for (c, e) in [
        (finger, 0),
        (finger, 1),
        (finger, 2),
        (bx, 0),
        (bx, 2),
        (ground, 2),
    ] {
        let a = fd(&setup, &loss, h, |s, d| {
            s.model.links[c].attach[(e, 3)] += d
        });
        check(
            &format!("attachment[{c}][{e}]"),
            g.attachments[c][e],
            a,
            tol,
            &mut worst,
        );
    }
    let ground_local = &setup.model.links[ground].hulls[0].x_local;
    let top = ground_local.iter().map(|x| x.z).fold(f64::MIN, f64::max);
    let top_corner = ground_local.iter().position(|x| x.z == top).unwrap();
    // Hull vertices: finger front face (touching the box), finger back, box
    // bottom (on the ground) and box face (touched by the finger).
    for (l, v, e) in [
        (finger, 1, 0),
        (finger, 3, 1),
        (finger, 5, 2),
        (finger, 7, 1),
        (bx, 0, 2),
        (bx, 3, 0),
        (bx, 4, 0),
        (bx, 6, 1),
        (ground, top_corner, 2),
    ] {
        let a = fd(&setup, &loss, h, |s, d| {
            s.model.links[l].hulls[0].x_local[v][e] += d;
            s.model.refresh_moments();
        });
        check(
            &format!("vertex[{l}][0][{v}][{e}]"),
            g.vertices[l][0][v][e],
            a,
            tol,
            &mut worst,
        );
    }
    // Controller: spline values and the PD gains.
    let np = setup.controller.channels[0].signal.nparams();
    for k in 0..np {
        let a = fd(&setup, &loss, h, |s, d| {
            let sig = &mut s.controller.channels[0].signal;
            let mut p = sig.params();
            p[k] += d;
            sig.set_params(&p);
        });
        check(
            &format!("signal[{k}]"),
            g.channels[0].signal[k],
            a,
            tol,
            &mut worst,
        );
    }
    let a = fd(&setup, &loss, 1e-3, |s, d| s.controller.channels[0].kp += d);
    check("kp", g.channels[0].kp, a, tol, &mut worst);
    let a = fd(&setup, &loss, 1e-7, |s, d| s.controller.channels[0].kd += d);
    check("kd", g.channels[0].kd, a, tol, &mut worst);
    // Physics: μ, κ and s (relative steps for κ and s), gravity, mass.
    let a = fd(&setup, &loss, h, |s, d| {
        s.scene.contact.as_mut().unwrap().mu += d
    });
    check("mu", g.physical.mu, a, tol, &mut worst);
    let a = fd(&setup, &loss, h, |s, d| {
        s.scene.contact.as_mut().unwrap().kappa *= 1.0 + d
    });
    check(
        "kappa (relative)",
        g.physical.kappa * KAPPA,
        a,
        tol,
        &mut worst,
    );
    let s0 = setup.scene.contact.as_ref().unwrap().s;
    let a = fd(&setup, &loss, h, |s, d| {
        s.scene.contact.as_mut().unwrap().s *= 1.0 + d
    });
    check("s (relative)", g.physical.s * s0, a, tol, &mut worst);
    let a = fd(&setup, &loss, h, |s, d| s.settings.gravity[2] += d);
    check("gravity[2]", g.physical.gravity[2], a, tol, &mut worst);
    let a = fd(&setup, &loss, h, |s, d| {
        for l in &mut s.model.links {
            for hull in &mut l.hulls {
                hull.vertex_mass.iter_mut().for_each(|m| *m *= 1.0 + d);
            }
        }
        s.model.refresh_moments();
    });
    check("mass scale", g.physical.mass_scale, a, tol, &mut worst);
    eprintln!(
        "worst relative error {worst:.2e} (h = {h}, Newton tol 1e-10), {:.1} s",
        t0.elapsed().as_secs_f64()
    );
}

/// First step (1-based) at which the finger–box pair is within the barrier
/// support, if any; and the loss.
fn onset_and_loss(setup: &Setup, loss: &Loss) -> (Option<usize>, f64) {
    let mut sim = setup.simulator();
    let tape = sdrs::diff::record(&mut sim, setup.steps).unwrap();
    let model = &setup.model;
    let (finger, bx) = (setup.link("pusher"), setup.link("box"));
    let s = setup.scene.contact.as_ref().unwrap().s;
    let params = ContactParams::with_width(s);
    let mut kin = sdrs::kinematics::Kinematics::new(model);
    let mut first = None;
    for k in 1..=tape.len() {
        let (q, charts) = tape.coords(k as isize);
        kin.update(model, q, charts, sdrs::kinematics::KinOrder::Pose);
        let world = |l: usize| -> Vec<Vector3<f64>> {
            model.links[l].hulls[0]
                .x_local
                .iter()
                .map(|x| transform_point(&kin.pose[l], x))
                .collect()
        };
        let mut sc = ContactScratch::new();
        let out = contact_vertices(&world(finger), &world(bx), &params, None, &mut sc).unwrap();
        if matches!(out, VertexOutcome::Separated(_)) {
            first = Some(k);
            break;
        }
    }
    (first, sdrs::diff::loss_of(model, &tape, loss))
}

fn finger_setup(x: f64, steps: usize, z: f64) -> Setup {
    Setup::new(&scene_text(KAPPA, x, z), steps)
}

/// Sweeps the finger's attachment coordinate `x` through the value `x₀` at
/// which finger–box contact first occurs within the horizon. `dL/dx` (central
/// differences, and the adjoint) must vary continuously: on the sweep the
/// change between neighbours across `x₀` is no outlier, and at `x₀` itself
/// `|D(x₀ + δ) − D(x₀ − δ)|` shrinks with `δ` (a jump would not).
#[test]
fn trajectory_loss_is_c1_through_contact_onset() {
    let steps = 100;
    let z = rest_height(KAPPA);
    let base = finger_setup(-0.17, steps, z);
    let loss = push_loss(&base);
    let finger = base.link("pusher");
    let onset = |x: f64| onset_and_loss(&finger_setup(x, steps, z), &loss).0;
    // Bracket and bisect x₀.
    let (mut lo, mut hi) = (-0.2, -0.14);
    assert!(onset(lo).is_none(), "contact already at x = {lo}");
    assert!(onset(hi).is_some(), "no contact at x = {hi}");
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if onset(mid).is_some() {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let x0 = 0.5 * (lo + hi);
    eprintln!(
        "contact onset within {steps} steps at finger x0 = {x0:.12} (bracket {:.1e})",
        hi - lo
    );
    let deriv = |x: f64| {
        let s = finger_setup(x, steps, z);
        let h = 1e-6;
        let d_fd = fd(&s, &loss, h, |p, d| {
            p.model.links[finger].attach[(0, 3)] += d
        });
        let g = s.gradients(&loss);
        (d_fd, g.attachments[finger][0], g.loss)
    };
    // The table.
    let dx = 1e-3;
    let mut rows = Vec::new();
    let mut csv = String::from(
        "x,x_minus_x0,first_contact_step,loss,dL_dx_fd,dL_dx_adjoint,dL_dx_minus_free_line\n",
    );
    eprintln!(
        "{:>10} {:>10} {:>6} {:>16} {:>16} {:>16} {:>11}",
        "x", "x-x0", "onset", "loss", "dL/dx (FD)", "dL/dx (adjoint)", "D - free"
    );
    // Before onset the loss is the contact-free one; its derivative is
    // extrapolated linearly from the two sweep points just below x₀ to show
    // how the contact contribution grows from zero.
    let free_a = x0 - 1.75 * dx;
    let free_b = x0 - 0.75 * dx;
    let (_, da, _) = deriv(free_a);
    let (_, db, _) = deriv(free_b);
    let free_line = |x: f64| da + (x - free_a) * (db - da) / (free_b - free_a);
    for k in -8..=12 {
        // Offset by a quarter step so no sweep point sits exactly on x₀.
        let x = x0 + (k as f64 + 0.25) * dx;
        let (first, l) = onset_and_loss(&finger_setup(x, steps, z), &loss);
        let (dfd, dadj, _) = deriv(x);
        let first_s = first.map_or("-".to_string(), |k| k.to_string());
        let dev = dadj - free_line(x);
        eprintln!(
            "{x:>10.6} {:>10.6} {first_s:>6} {l:>16.9e} {dfd:>16.9e} {dadj:>16.9e} {dev:>11.3e}",
            x - x0
        );
        csv += &format!("{x},{},{first_s},{l:e},{dfd:e},{dadj:e},{dev:e}\n", x - x0);
        assert!(
            (dfd - dadj).abs() <= 1e-4 * dfd.abs().max(dadj.abs()),
            "x = {x}: FD {dfd} vs adjoint {dadj}"
        );
        rows.push((x, first, dfd));
    }
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("contact_onset_sweep.csv");
    std::fs::write(&path, &csv).unwrap();
    eprintln!("sweep written to {}", path.display());
    // Contact starts inside the sweep, at the last step for x just above x₀
    // and earlier further on.
    assert!(rows.iter().any(|r| r.1.is_none()) && rows.iter().any(|r| r.1.is_some()));
    // Neighbouring variation of the FD derivative: the interval containing x₀
    // is no outlier.
    let var: Vec<(bool, f64)> = rows
        .windows(2)
        .map(|w| {
            (
                w[0].1.is_none() && w[1].1.is_some(),
                (w[1].2 - w[0].2).abs(),
            )
        })
        .collect();
    let across = var.iter().find(|v| v.0).unwrap().1;
    let elsewhere = var.iter().filter(|v| !v.0).map(|v| v.1).fold(0.0, f64::max);
    eprintln!("|ΔD| across onset {across:.3e}, largest elsewhere {elsewhere:.3e}");
    assert!(
        across <= 2.0 * elsewhere,
        "derivative jump at onset: {across} vs {elsewhere}"
    );
    // Refinement at x₀: D(x₀ + δ) − D(x₀ − δ) → 0 (adjoint derivatives); the
    // contact part D(x₀ + δ) − (free line) vanishes faster than δ.
    let mut prev: Option<(f64, f64)> = None;
    for delta in [1e-3, 1e-4, 1e-5, 1e-6] {
        let (_, dp, _) = deriv(x0 + delta);
        let (_, dm, _) = deriv(x0 - delta);
        let jump = (dp - dm).abs();
        let dev = (dp - free_line(x0 + delta)).abs();
        eprintln!(
            "δ = {delta:.0e}: |D(x0+δ) − D(x0−δ)| = {jump:.3e}, contact part |D(x0+δ) − free line| = {dev:.3e}"
        );
        if let Some((pj, pd)) = prev {
            assert!(jump <= 0.2 * pj + 1e-9, "no convergence: {jump} after {pj}");
            assert!(dev <= 0.1 * pd + 1e-10, "contact part: {dev} after {pd}");
        }
        prev = Some((jump, dev));
    }
}
