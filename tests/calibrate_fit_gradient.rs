//! The exact gradient `Jᵀr` of every candidate's training residuals (one
//! adjoint pass) against central finite differences of `½‖r‖²`
//! (re-simulating), on both calibration robots, away from the optimum.

use crate::calibrate_support;
use crate::common;

use calibrate_support::{Sampling, measured_csv, with_effects};
use rayon::prelude::*;
use sdrs::calibrate::adjoint::residual_gradient;
use sdrs::calibrate::candidates::candidates;
use sdrs::calibrate::data::Measured;
use sdrs::calibrate::problem::Problem;
use sdrs::energy::effects::EffectKind;
use sdrs::scene::Scene;
use std::path::Path;

fn check(robot: &str, hidden: &str) {
    let text = std::fs::read_to_string(common::robots(&format!("calibrate/{robot}.yaml"))).unwrap();
    let scene = Scene::from_str(&text, Path::new("scene.yaml")).unwrap();
    let csv = measured_csv(
        &with_effects(&text, &[hidden]),
        &Sampling {
            duration: 0.5,
            ..Default::default()
        },
    );
    let measured = Measured::parse(&csv, Path::new("m.csv"), &scene.model).unwrap();
    let pb = Problem {
        scene: &scene,
        measured: &measured,
        split: measured.split(0.3),
        others: &[],
    };
    let cands = candidates(&scene, &EffectKind::ALL);
    // Sensitivity scale of the problem: the largest |∂(½‖r‖²)/∂p|·typical
    // over the candidates at their starts. Errors are measured in these
    // cost units (a parameter the data barely see, e.g. damping of the
    // pressed axis, has a gradient 10⁵ times smaller, resolved only to a few
    // digits by either method).
    let scale = cands
        .par_iter()
        .map(|c| {
            let (_, g) = residual_gradient(&pb, c, &c.starts[0]).unwrap();
            g.iter()
                .zip(&c.typical)
                .map(|(g, t)| (g * t).abs())
                .fold(0.0, f64::max)
        })
        .reduce(|| 0.0, f64::max);
    let worst = cands
        .par_iter()
        .map(|c| {
            // A point away from both the start and the optimum.
            let p: Vec<f64> = (0..c.nparams())
                .map(|k| (c.starts[0][k] + 0.37 * c.typical[k]).clamp(c.lower[k], c.upper[k]))
                .collect();
            let (r, g) = residual_gradient(&pb, c, &p)
                .unwrap_or_else(|| panic!("{}: no adjoint gradient at {p:?}", c.label));
            let r0 = pb.train_residuals(c, &p).unwrap();
            let dr = r.iter().zip(&r0).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(dr < 1e-12, "{}: residuals differ by {dr}", c.label);
            let mut worst: f64 = 0.0;
            for k in 0..p.len() {
                let h = 1e-6 * c.typical[k].max(p[k].abs());
                let cost = |d: f64| {
                    let mut q = p.clone();
                    q[k] += d;
                    0.5 * pb.train_residuals(c, &q).unwrap().iter().map(|x| x * x).sum::<f64>()
                };
                let fd = (cost(h) - cost(-h)) / (2.0 * h);
                let own = g[k].abs().max(fd.abs());
                // Relative error, or the mismatch in cost units below 1e-7
                // of the largest sensitivity.
                let rel = ((g[k] - fd).abs() / own.max(1e-300))
                    .min((g[k] - fd).abs() * c.typical[k] / (1e-3 * scale));
                eprintln!("{robot:<15} {:<28} [{k}] adjoint {:+.9e} fd {fd:+.9e} rel {rel:.1e} (of itself {:.1e})", c.label, g[k], (g[k] - fd).abs() / own.max(1e-300));
                assert!(rel < 1e-4, "{} param {k}: adjoint {} vs fd {fd}", c.label, g[k]);
                worst = worst.max(rel);
            }
            worst
        })
        .reduce(|| 0.0, f64::max);
    eprintln!(
        "{robot}: {} candidates, worst relative error {worst:.1e}",
        cands.len()
    );
}

#[test]
fn candidate_gradients_match_finite_differences_on_the_arm() {
    check("arm2", "{effect: joint_friction, on: all, values: [0.4]}");
}

#[test]
fn candidate_gradients_match_finite_differences_with_contact() {
    check("slider_contact", "{effect: contact_mu, values: [0.6]}");
}
