//! The model's own error (issue 33, item 1): the noise estimate from the
//! data, the Richardson estimate of the integrator error, and the verdict
//! `none` with the integrator named when the data come from the same
//! physics at a much finer step (a stand-in for the continuous system, or
//! an engine more accurate than ours). Data with a hidden effect on the
//! same fine step must still name the effect.

use crate::calibrate_support;
use crate::common;

use calibrate_support::{Sampling, measured_csv, with_effects};
use nalgebra::DVector;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sdrs::calibrate::data::Channel;
use sdrs::calibrate::floor::noise;
use sdrs::calibrate::problem::Simulated;
use sdrs::calibrate::select::finer_step_channels;
use sdrs::calibrate::{CalibrateOptions, calibrate};
use sdrs::energy::effects::EffectKind;

/// Gaussian noise of known σ on a smooth residual-like signal (0.05 rad at
/// 0.3 Hz plus 0.02 rad at 1.9 Hz) at jittered 100 Hz times with a gap: the
/// estimate is within 10 % of σ, for σ from 1e-4 to 1e-2. (A first version
/// used a raw trajectory, 0.3 rad at 1.9 Hz: its third-difference leak,
/// 1.2e-4, gave +22 % at σ = 1e-4; calibration applies the estimate to the
/// residual, which is smooth and small.)
#[test]
fn noise_estimate_recovers_the_noise_level() {
    for (seed, sigma) in [(1u64, 1e-4), (2, 1e-3), (3, 1e-2)] {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut times = Vec::new();
        let mut rows = vec![Vec::new(), Vec::new()];
        for i in 0..600 {
            let t = (i as f64 + rng.random_range(-0.3..0.3)) * 0.01;
            if (2.0..2.3).contains(&t) {
                continue;
            }
            times.push(t);
            for (c, row) in rows.iter_mut().enumerate() {
                // A residual-like smooth part (model error): its third
                // divided difference leaks `f''' h³/√20` into the estimate,
                // here under 1e-5.
                let s = 0.05 * (2.0 * t + c as f64).sin() + 0.02 * (12.0 * t).cos();
                let (u1, u2): (f64, f64) =
                    (rng.random_range(1e-12..1.0), rng.random_range(0.0..1.0));
                let g = (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos();
                row.push(Some(s + sigma * g));
            }
        }
        let est = noise(&times, &rows);
        eprintln!("σ = {sigma:e}: estimated {est:.4e}");
        assert!(
            (est / sigma - 1.0).abs() < 0.1,
            "σ = {sigma}: estimated {est}"
        );
    }
}

fn arm2() -> String {
    std::fs::read_to_string(common::robots("calibrate/arm2.yaml")).unwrap()
}

/// `arm2.yaml` at Δt/16 (0.125 ms): the "true" system of these tests. The
/// stable-PD damping force is `(2k_d/Δt)(θ̇* − θ̇)`, so `k_d` scales with
/// the step to keep the same controller (0.0004/16).
fn fine(scene: &str) -> String {
    assert!(scene.contains("kd: 0.0004\n"));
    scene
        .replace("dt: 0.002", "dt: 0.000125")
        .replace("kd: 0.0004\n", "kd: 0.000025\n")
}

fn calibrate_on(name: &str, data: String) -> sdrs::calibrate::CalibrationResult {
    calibrate_scene(name, &arm2(), data)
}

/// `sdrs calibrate` of `scene_text` on `data` (every effect kind, 30 %
/// held out).
fn calibrate_scene(
    name: &str,
    scene_text: &str,
    data: String,
) -> sdrs::calibrate::CalibrationResult {
    // One directory per case: the tests run in parallel, and a shared one
    // was emptied by one test while the other read its scene from it.
    let dir = common::scratch_dir(&format!("calibrate-floor-{name}"));
    let scene = dir.join("arm2.yaml");
    std::fs::write(&scene, scene_text).unwrap();
    let measured = dir.join(format!("{name}.csv"));
    std::fs::write(&measured, data).unwrap();
    let opts = CalibrateOptions {
        scene,
        measured,
        more_measured: Vec::new(),
        out: dir.join(format!("out_{name}")),
        effects: EffectKind::ALL.to_vec(),
        holdout: 0.3,
        select: Default::default(),
        log: Default::default(),
        fit_contact_resolution: false,
    };
    calibrate(&opts).unwrap().0
}

const NOISE: f64 = 1e-3;

/// Clean data from the fine step: the gap is the integrator's. The
/// Richardson estimate of the error at Δt = 2 ms matches the measured
/// difference to the fine solution within 25 % (the data's own noise and
/// the fine step's residual error aside), the gap shrinks about 2× at
/// Δt/2 (first order), the noise estimate is within 15 % of the truth, and
/// the verdict is `none` with the integrator as the reason and a suggested
/// Δt below the scene's.
#[test]
fn clean_data_from_a_finer_step_is_the_integrators_gap() {
    let s = Sampling {
        noise: NOISE,
        ..Default::default()
    };
    let r = calibrate_on("clean", measured_csv(&fine(&arm2()), &s));
    let f = &r.error_floor;
    eprintln!("{}\n{}", serde_json::to_string_pretty(f).unwrap(), r.reason);
    assert!((f.noise / NOISE - 1.0).abs() < 0.15, "noise {}", f.noise);
    // The gap without noise is the integrator error itself.
    let true_err = (f.gap.powi(2) - NOISE * NOISE).max(0.0).sqrt();
    assert!(
        (f.integrator / true_err - 1.0).abs() < 0.25,
        "estimated integrator error {} vs {true_err}",
        f.integrator
    );
    assert!(f.order > 0.7 && f.order < 1.5, "order {}", f.order);
    assert!(f.shrink_half_dt > 1.5, "shrink ×{}", f.shrink_half_dt);
    assert!(f.gap_extrapolated < 0.5 * f.gap);
    assert_eq!(r.verdict, "none", "{}", r.reason);
    assert!(r.reason.contains("integrator"), "{}", r.reason);
    assert!(f.suggested_dt.is_some_and(|dt| dt < 0.002));
}

/// Joint damping hidden in the fine-step data: still named alone (the
/// floor does not hide an effect several times its size), within 10 %.
#[test]
fn an_effect_above_the_floor_is_still_named() {
    let s = Sampling {
        noise: NOISE,
        seed: 7,
        ..Default::default()
    };
    let hidden = with_effects(
        &fine(&arm2()),
        &["{effect: joint_damping, on: all, values: [0.3]}"],
    );
    let r = calibrate_on("damping", measured_csv(&hidden, &s));
    damping_alone_within_the_floor(&r);
}

/// The floor of the chosen damping (the same data as
/// [`an_effect_above_the_floor_is_still_named`]) is measured at its
/// Δt → 0 values and holds our integrator's error (issue 33, session 19b).
/// The damping fitted at Δt absorbs the implicit step's numerical
/// dissipation, and the model's `E_gap = clamp(G² − G*², 0, E²)^½`
/// measured there underestimates the integrator error in the data (on the
/// arm2 case: 4.6e-3 of E 8.7e-3, 0.53 E; on [`PENDULUM`]: 0). At the
/// extrapolated value the data lie at the model's Richardson limit, so
/// most of `E` is in the gap: required `E_gap > ½ E` (threshold chosen
/// before the first run; arm2 0.66 E, [`PENDULUM`] 0.70 E).
fn model_floor_holds_the_integrators_error(r: &sdrs::calibrate::CalibrationResult) {
    let f = &r.error_floor;
    eprintln!("{}", serde_json::to_string_pretty(f).unwrap());
    assert!(
        f.integrator_in_gap > 0.5 * f.integrator,
        "E_gap {} of E {}",
        f.integrator_in_gap,
        f.integrator
    );
    assert_eq!(f.floor_of, "joint_damping/all");
    assert!(f.floor_extrapolated);
}

/// Measured data `y_c = a_c + w_c (b_c − a_c) + noise` on three channels of
/// 300 samples, where `a` stands for a model run at Δt and `b` for the same
/// model at Δt/2, `b − a = δ sin(3t + c)`.
fn finer_step_case(
    seed: u64,
    delta: f64,
    weights: [f64; 3],
) -> (sdrs::calibrate::data::Measured, Simulated, Simulated) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = 300;
    let times: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    let mut channels: Vec<Channel> = (0..3)
        .map(|c| Channel {
            name: format!("c{c}"),
            dof: c,
            values: Vec::new(),
        })
        .collect();
    for &t in &times {
        let av = DVector::from_fn(3, |c, _| (t + c as f64).sin());
        let bv = DVector::from_fn(3, |c, _| av[c] + delta * (3.0 * t + c as f64).sin());
        for (c, ch) in channels.iter_mut().enumerate() {
            let (u1, u2): (f64, f64) = (rng.random_range(1e-12..1.0), rng.random_range(0.0..1.0));
            let g = (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos();
            ch.values
                .push(Some(av[c] + weights[c] * (bv[c] - av[c]) + NOISE * g));
        }
        a.push(av);
        b.push(bv);
    }
    let sim = |states| Simulated {
        dt: 0.01,
        states,
        contact: vec![false; n],
        offset: vec![0.0; 3],
    };
    let m = sdrs::calibrate::data::Measured {
        path: "synthetic".into(),
        times,
        channels,
    };
    (m, sim(a), sim(b))
}

/// The per-channel evidence that the data come from a finer step than ours
/// ([`finer_step_channels`], which decides the Δt → 0 extrapolation of the
/// fitted parameters). Settings and thresholds chosen before the first
/// run: σ = 1e-3, 300 samples.
/// - A channel whose data lie at the continuous limit (`w = 2`: first
///   order, `y = a + 2(b − a)`) counts; one made at our own Δt (`w = 0`)
///   and one with a model-form error the finer step makes worse (`w = −3`)
///   do not, in each of 20 noise draws (δ = 5e-4: `‖b − a‖` ≈ 6 σ).
/// - Data made at our own Δt: over 200 draws × 3 channels at δ from 1e-5
///   to 1e-3, at most 3 % of the channels count (the rule's two standard
///   deviations: ≤ 2.3 % expected).
#[test]
fn finer_step_evidence_is_judged_per_channel() {
    for seed in 0..20 {
        let (m, a, b) = finer_step_case(seed, 5e-4, [2.0, 0.0, -3.0]);
        let mask = finer_step_channels(&m, 300, &a, &b, NOISE);
        assert_eq!(mask, [true, false, false], "seed {seed}");
    }
    let mut counted = 0;
    for seed in 0..200u64 {
        let delta = 1e-5 * 100f64.powf(seed as f64 / 199.0);
        let (m, a, b) = finer_step_case(1000 + seed, delta, [0.0; 3]);
        counted += finer_step_channels(&m, 300, &a, &b, NOISE)
            .iter()
            .filter(|&&x| x)
            .count();
    }
    eprintln!("own-step channels counted: {counted} of 600");
    assert!(counted <= 18, "{counted} of 600 own-step channels counted");
}

/// One PD-held link without gravity (arm2's upper link): a damped linear
/// oscillator, whose implicit-step error is mostly numerical dissipation —
/// the direction a joint damping moves the trajectory in. The drive
/// (0.4 and 0.9 Hz) stays well below the PD's natural frequency
/// (√(2k_p/I) ≈ 17 rad/s); a first version driven at arm2's 0.7 and
/// 1.9 Hz sat near resonance (held-out gap 0.199 rad, 5.7e-3 left by the
/// damping: `unexplained`).
const PENDULUM: &str = "version: 1
dt: 0.002
steps: 1000
gravity: [0, 0, 0]
solver: {tol: 1.0e-7}
robots:
  - name: arm
    base: {xyz: [0, 0, 1]}
    links:
      - name: upper
        joint: {name: shoulder, type: revolute, axis: [0, 1, 0]}
        mass: 1.0
        hulls: [{box: {size: [0.05, 0.05, 0.4], center: [0, 0, -0.2]}}]
    controller:
      kp: 8
      kd: 0.0004
      targets:
        shoulder: {type: sine, terms: [{amplitude: 0.8, frequency: 0.4}, {amplitude: 0.3, frequency: 0.9, phase: 0.5}]}
    initial:
      shoulder: {q: [0.2], qdot: [0]}
";

/// Joint damping 0.3 hidden in data of [`PENDULUM`] at Δt/16, σ = 1e-3,
/// 2 s (issue 33 session 19b; written after the arm2 case above turned
/// out to give `E_gap` 0.53 E at the Δt-fitted value too, so that only
/// `floor_extrapolated` told the rules apart there). Here the damping
/// fitted at Δt absorbs most of the integrator's error, and at that value
/// the model's `E_gap = (|e_⊥|² − |e_∥|²)^½` (`e_∥`: the part along the
/// damping's sensitivity) is clamped to 0 — the pusher's case; at the
/// Δt → 0 value `E_gap ≈ |e| = E`. Required: the damping named alone
/// within 10 %, `E_gap > ½ E` (the threshold of the arm2 case, chosen
/// before its first run).
#[test]
fn a_damping_that_absorbs_the_integrators_dissipation_keeps_it_in_the_floor() {
    let s = Sampling {
        noise: NOISE,
        seed: 11,
        duration: 2.0,
        ..Default::default()
    };
    let hidden = with_effects(
        &fine(PENDULUM),
        &["{effect: joint_damping, on: all, values: [0.3]}"],
    );
    let r = calibrate_scene("pendulum-damping", PENDULUM, measured_csv(&hidden, &s));
    eprintln!("{}", serde_json::to_string_pretty(&r.error_floor).unwrap());
    damping_alone_within_the_floor(&r);
}

/// The verdict names the hidden damping 0.3 alone, within 10 %, and its
/// floor holds the integrator's error ([`model_floor_holds_the_integrators_error`]).
fn damping_alone_within_the_floor(r: &sdrs::calibrate::CalibrationResult) {
    eprintln!(
        "{} {:?} {}\n{}",
        r.verdict,
        r.candidate,
        serde_json::to_string(&r.parameters).unwrap(),
        r.reason
    );
    assert_eq!(r.verdict, "effect", "{}", r.reason);
    assert_eq!(r.candidate.as_deref(), Some("joint_damping/all"));
    let c = r.parameters["joint_damping/all"];
    assert!((c / 0.3 - 1.0).abs() < 0.1, "damping {c}");
    model_floor_holds_the_integrators_error(r);
}
