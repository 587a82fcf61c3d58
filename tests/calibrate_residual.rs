//! The residual force regression (issue 33, item 3,
//! `sdrs::calibrate::residual`): on data from `arm2.yaml` integrated at
//! Δt/16 (a stand-in for a finer engine) with 1e-3 rad noise, a hidden
//! effect on one joint is found on that joint as the right basis term, with
//! its coefficient's interval containing the truth; the other joint keeps
//! no term of comparable size. The data from MuJoCo (delay, velocity-squared
//! drag) are the acceptance script's (`tools/check/calib_acceptance.py`).

use crate::calibrate_support;
use crate::common;

use calibrate_support::{Sampling, measured_csv, with_effects};
use sdrs::calibrate::data::Measured;
use sdrs::calibrate::problem::Problem;
use sdrs::calibrate::residual::{ResidualOptions, ResidualRegression, regress};
use sdrs::scene::Scene;
use std::path::Path;

fn arm2() -> String {
    std::fs::read_to_string(common::robots("calibrate/arm2.yaml")).unwrap()
}

/// `arm2.yaml` at Δt/16 with the same continuous controller (`k_d/16`).
fn fine(scene: &str) -> String {
    assert!(scene.contains("kd: 0.0004\n"));
    scene
        .replace("dt: 0.002", "dt: 0.000125")
        .replace("kd: 0.0004\n", "kd: 0.000025\n")
}

fn regression(hidden: &[&str], seed: u64) -> ResidualRegression {
    regression_with(hidden, seed, &ResidualOptions::default())
}

fn regression_with(hidden: &[&str], seed: u64, opts: &ResidualOptions) -> ResidualRegression {
    let s = Sampling {
        noise: 1e-3,
        seed,
        duration: 2.0,
        ..Default::default()
    };
    let csv = measured_csv(&with_effects(&fine(&arm2()), hidden), &s);
    let scene = Scene::from_str(&arm2(), Path::new("arm2.yaml")).unwrap();
    let m = Measured::parse(&csv, Path::new("measured.csv"), &scene.model).unwrap();
    let split = m.split(0.3);
    let pb = Problem {
        scene: &scene,
        measured: &m,
        split,
        others: &[],
    };
    let base = pb.simulate(&[], m.times.len()).unwrap();
    let r = regress(&scene, &m, &base, m.times[split], opts).unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&r).unwrap());
    r
}

fn joint<'a>(
    r: &'a ResidualRegression,
    name: &str,
) -> &'a sdrs::calibrate::residual::JointRegression {
    r.joints.iter().find(|j| j.joint == name).unwrap()
}

/// A viscous damping of 0.3 N·m·s/rad on the elbow: the elbow's first term
/// is `θ̇` with the truth inside its interval (and within 15 %); the
/// shoulder's residual force is much smaller than the elbow's.
#[test]
fn hidden_damping_on_one_joint_is_found_as_theta_dot_there() {
    let r = regression(&["{effect: joint_damping, on: elbow, values: [0.3]}"], 3);
    assert_eq!(r.strongest.as_deref(), Some("elbow: θ̇"));
    let e = joint(&r, "elbow");
    let t = &e.terms[0];
    assert_eq!(t.term, "θ̇");
    assert!(t.low <= 0.3 && 0.3 <= t.high, "{t:?}");
    assert!((t.coefficient / 0.3 - 1.0).abs() < 0.15, "{t:?}");
    assert!(e.explained_holdout > 0.5, "{}", e.explained_holdout);
}

/// An actuation delay of 20 ms on the shoulder: the shoulder's strongest
/// term is the PD command's rate `u̇` with coefficient the delay (within
/// 20 %, truth inside the interval).
#[test]
fn hidden_delay_on_one_joint_is_found_as_the_command_rate_there() {
    let r = regression(
        &["{effect: actuation_delay, on: shoulder, values: [0.02]}"],
        4,
    );
    assert_eq!(r.strongest.as_deref(), Some("shoulder: u̇"));
    let t = &joint(&r, "shoulder").terms[0];
    assert_eq!(t.term, "u̇");
    assert!((t.coefficient / 0.02 - 1.0).abs() < 0.2, "{t:?}");
    assert!(t.low <= 0.02 && 0.02 <= t.high, "{t:?}");
}

/// An actuator deadband of half-width 0.02 rad on the elbow (an effect
/// outside the default candidates, `actuator_deadband`): the elbow's
/// strongest term is the PD error's sign `2k_p sign(e)`, refined to the
/// band's shape (`residual` module doc), its coefficient the band within
/// 20 %. Settings chosen before the first run (2026-11-29): b = 0.02 rad,
/// seed 6, and the delay test's criteria (20 %, truth inside the interval).
///
/// Outcome: the term is found (95 % of the held-out force explained) but
/// the coefficient is 0.0186 (−7 %) with interval [0.0174, 0.0198]: the
/// truth is outside it. Cause, isolated on noise-free data: the
/// Savitzky–Golay smoothing of the measured positions rounds the force's
/// steep change across the band (4k_p b over 2b of error). Coefficient
/// against the window's half-width m (noise-free, 2 s): m = 9, 6, 4 →
/// −7.1, −3.4, −1.5 %; at m = 4 over 6 s, −1.0 %. So the interval holds
/// only with less smoothing: the test asserts it at m = 4 (chosen after
/// that outcome), with the noise of the other tests.
#[test]
fn hidden_deadband_on_one_joint_is_found_as_the_pd_error_sign_there() {
    let hidden = ["{effect: actuator_deadband, on: elbow, values: [0.02]}"];
    let r = regression(&hidden, 6);
    assert_eq!(r.strongest.as_deref(), Some("elbow: 2k_p sign(e)"));
    let t = &joint(&r, "elbow").terms[0];
    assert_eq!(t.term, "2k_p sign(e)");
    assert!((t.coefficient / 0.02 - 1.0).abs() < 0.2, "{t:?}");
    // The interval covers the smoothing bias (it includes the fit at half
    // the window), and stays informative: both criteria set before the
    // run (2026-11-29, fifth session).
    assert!(t.low <= 0.02 && 0.02 <= t.high, "m = 9: {t:?}");
    assert!(
        t.high - t.low <= 0.25 * 0.02,
        "m = 9: interval too wide: {t:?}"
    );
    let narrow = ResidualOptions {
        half_window: 4,
        ..Default::default()
    };
    let r = regression_with(&hidden, 6, &narrow);
    let t = &joint(&r, "elbow").terms[0];
    assert_eq!(t.term, "2k_p sign(e)");
    assert!(t.low <= 0.02 && 0.02 <= t.high, "m = 4: {t:?}");
}

/// Clean data: no joint keeps a term explaining a material share of its
/// (integrator- and noise-sized) residual force... or, if one is kept, its
/// coefficient is small next to the effects above.
#[test]
fn clean_data_keep_no_large_term() {
    let r = regression(&[], 5);
    for j in &r.joints {
        for t in &j.terms {
            if t.term == "θ̇" {
                assert!(t.coefficient.abs() < 0.05, "{} {t:?}", j.joint);
            }
            if t.term == "u̇" {
                assert!(t.coefficient.abs() < 0.004, "{} {t:?}", j.joint);
            }
            if t.term == "2k_p sign(e)" {
                assert!(t.coefficient.abs() < 0.002, "{} {t:?}", j.joint);
            }
        }
    }
}

/// Data made by the scene's own step (Δt = 2 ms, no noise, every 10th
/// step: the Python package's Ray sweep test) with a hidden damping on
/// both joints. The regression against the refined objective sees the
/// implicit step's lag; at c = 0.05 its strongest shoulder term was
/// `θ̇|θ̇|` and vetoed `joint_damping/all`, which reproduces the data to
/// round-off (CI, 2026-11-26). The same term in data simulated by the
/// chosen model itself is now recognised as the step's: the damping is
/// named, within 5 %, for both values.
#[test]
fn own_step_lag_does_not_veto_a_damping_that_reproduces_the_data() {
    let dir = common::scratch_dir("calibrate-own-step");
    let base = arm2();
    let scene = dir.join("arm2.yaml");
    std::fs::write(&scene, &base).unwrap();
    for c in [0.02, 0.05] {
        let hidden = format!("{{effect: joint_damping, on: all, values: [{c}]}}");
        let s = Sampling {
            period: 0.02,
            jitter: 0.0,
            gap: (2.0, 2.0),
            noise: 0.0,
            duration: 1.2,
            seed: 1,
        };
        let measured = dir.join(format!("m_{c}.csv"));
        std::fs::write(
            &measured,
            measured_csv(&with_effects(&base, &[&hidden]), &s),
        )
        .unwrap();
        let opts = sdrs::calibrate::CalibrateOptions {
            scene: scene.clone(),
            measured,
            more_measured: Vec::new(),
            out: dir.join(format!("out_{c}")),
            effects: vec![
                sdrs::energy::effects::EffectKind::JointDamping,
                sdrs::energy::effects::EffectKind::Armature,
            ],
            holdout: 0.3,
            select: Default::default(),
            log: Default::default(),
            fit_contact_resolution: false,
        };
        let r = sdrs::calibrate::calibrate(&opts).unwrap().0;
        assert_eq!(
            r.effect.as_deref(),
            Some("joint_damping"),
            "c = {c}: {}",
            r.reason
        );
        let (_, v) = r.parameters_at_dt.iter().next().unwrap();
        assert!((v / c - 1.0).abs() < 0.05, "c = {c}: {v}");
    }
}
