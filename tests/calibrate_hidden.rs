//! The hidden-effect suite: for each effect of the library on two robots
//! (a two-link arm, and a pad pressed onto and dragged along the ground,
//! with contact and friction), "measured" data are simulated with the
//! effect switched on, resampled at jittered times with a gap and noisy;
//! `calibrate` is given the model without the effect. Asserts the counts:
//! the right candidate named first in ≥ 90 % of cases, its parameter within
//! 10 %, the held-out error shrinking by ≥ 90 %; on clean data (noise and
//! resampling only) the verdict is "none" in every case.

use crate::calibrate_support;
use crate::common;

use calibrate_support::{Sampling, measured_csv, with_effects};
use rayon::prelude::*;
use sdrs::calibrate::{CalibrateOptions, calibrate};
use sdrs::energy::effects::EffectKind;

struct Case {
    robot: &'static str,
    /// Effect entry as in a scene file.
    effect: &'static str,
    /// Expected first candidate.
    label: &'static str,
    /// Parameter key and true value.
    key: &'static str,
    value: f64,
}

const fn case(
    robot: &'static str,
    effect: &'static str,
    label: &'static str,
    key: &'static str,
    value: f64,
) -> Case {
    Case {
        robot,
        effect,
        label,
        key,
        value,
    }
}

const CASES: &[Case] = &[
    case(
        "arm2",
        "{effect: joint_damping, on: all, values: [0.3]}",
        "joint_damping/all",
        "joint_damping/all",
        0.3,
    ),
    case(
        "arm2",
        "{effect: joint_damping, on: elbow, values: [0.2]}",
        "joint_damping/elbow",
        "joint_damping/elbow",
        0.2,
    ),
    case(
        "arm2",
        "{effect: joint_friction, on: all, values: [0.4]}",
        "joint_friction/all",
        "joint_friction/all",
        0.4,
    ),
    case(
        "arm2",
        "{effect: armature, on: all, values: [0.05]}",
        "armature/all",
        "armature/all",
        0.05,
    ),
    // (A gain on every joint of a contact-free robot is exactly a mass scale
    // of every link by 1/g: the step objective is only rescaled. The arm
    // case uses one joint; the slider's contact breaks the equivalence.)
    case(
        "arm2",
        "{effect: actuator_gain, on: shoulder, values: [0.7]}",
        "actuator_gain/shoulder",
        "actuator_gain/shoulder",
        0.7,
    ),
    case(
        "arm2",
        "{effect: joint_offset, on: elbow, values: [0.03]}",
        "joint_offset/elbow",
        "joint_offset/elbow",
        0.03,
    ),
    case(
        "arm2",
        "{effect: payload, on: fore, values: [0.3, 0.0, 0.0, -0.3]}",
        "payload/fore",
        "payload/fore:mass",
        0.3,
    ),
    case(
        "arm2",
        "{effect: link_mass_scale, on: upper, values: [1.5]}",
        "link_mass_scale/upper",
        "link_mass_scale/upper",
        1.5,
    ),
    case(
        "slider_contact",
        "{effect: joint_damping, on: slider/x, values: [3.0]}",
        "joint_damping/slider/x",
        "joint_damping/slider/x",
        3.0,
    ),
    case(
        "slider_contact",
        "{effect: joint_friction, on: slider/x, values: [2.0]}",
        "joint_friction/slider/x",
        "joint_friction/slider/x",
        2.0,
    ),
    case(
        "slider_contact",
        "{effect: armature, on: slider/x, values: [0.5]}",
        "armature/slider/x",
        "armature/slider/x",
        0.5,
    ),
    case(
        "slider_contact",
        "{effect: actuator_gain, on: all, values: [0.7]}",
        "actuator_gain/all",
        "actuator_gain/all",
        0.7,
    ),
    case(
        "slider_contact",
        "{effect: joint_offset, on: slider/x, values: [0.02]}",
        "joint_offset/slider/x",
        "joint_offset/slider/x",
        0.02,
    ),
    case(
        "slider_contact",
        "{effect: link_mass_scale, on: all, values: [1.4]}",
        "link_mass_scale/all",
        "link_mass_scale/all",
        1.4,
    ),
    case(
        "slider_contact",
        "{effect: contact_mu, values: [0.6]}",
        "contact_mu/all",
        "contact_mu/all",
        0.6,
    ),
    case(
        "slider_contact",
        "{effect: actuator_gain, on: slider/x, values: [0.7]}",
        "actuator_gain/slider/x",
        "actuator_gain/slider/x",
        0.7,
    ),
];

fn scene_text(robot: &str) -> String {
    std::fs::read_to_string(common::robots(&format!("calibrate/{robot}.yaml"))).unwrap()
}

struct Outcome {
    named: bool,
    within: bool,
    shrink: bool,
    /// For a named mass scale or payload: whether `mass_changes` reports
    /// the link's scene mass and the mass the fitted value adds.
    mass: Option<bool>,
    line: String,
}

/// `r.mass_changes` against the scene (`dir/<robot>.yaml`) for a chosen
/// `link_mass_scale/<link or all>` (`σ`: adds `(σ − 1) m`, `m` the link's
/// mass or that of every link with mass that moves) or
/// `payload/<link>` (adds its mass): one entry, for `key`, whose mass before
/// is the link's own and whose added mass follows from `r.parameters[key]`
/// (relative 1e-12).
fn mass_change_matches(
    dir: &std::path::Path,
    robot: &str,
    key: &str,
    r: &sdrs::calibrate::CalibrationResult,
) -> bool {
    let scene = sdrs::scene::Scene::load(dir.join(format!("{robot}.yaml"))).unwrap();
    let model = &scene.model;
    let m_link = match key.split(['/', ':']).nth(1).unwrap() {
        "all" => sdrs::energy::effects::massive_links(model)
            .iter()
            .map(|&i| model.links[i].mass())
            .sum(),
        link => model.links.iter().find(|l| l.name == link).unwrap().mass(),
    };
    let v = r.parameters[key];
    let added = if key.starts_with("payload/") {
        v
    } else {
        (v - 1.0) * m_link
    };
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-9);
    matches!(r.mass_changes.as_slice(), [m] if m.parameter == key
        && close(m.before_kg, m_link)
        && close(m.added_kg, added)
        && close(m.after_kg, m_link + added))
}

fn run_case(
    dir: &std::path::Path,
    name: &str,
    robot: &str,
    hidden: &[&str],
    seed: u64,
) -> sdrs::calibrate::CalibrationResult {
    let base = scene_text(robot);
    let data = measured_csv(
        &with_effects(&base, hidden),
        &Sampling {
            seed,
            ..Default::default()
        },
    );
    let scene = dir.join(format!("{robot}.yaml"));
    if !scene.exists() {
        std::fs::write(&scene, &base).unwrap();
    }
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

#[test]
fn hidden_effects_are_named_fitted_and_close_the_gap() {
    let dir = common::scratch_dir("calibrate-hidden");
    for robot in ["arm2", "slider_contact"] {
        std::fs::write(dir.join(format!("{robot}.yaml")), scene_text(robot)).unwrap();
    }
    let t0 = std::time::Instant::now();
    let outcomes: Vec<Outcome> = CASES
        .par_iter()
        .enumerate()
        .map(|(i, c)| {
            let t = std::time::Instant::now();
            let r = run_case(&dir, &format!("case{i}"), c.robot, &[c.effect], 100 + i as u64);
            let secs = t.elapsed().as_secs_f64();
            let named = r.candidate.as_deref() == Some(c.label);
            let fitted = r.ranking.iter().find(|x| x.candidate == c.label).and_then(|x| x.parameters.get(c.key).copied());
            let within = named && fitted.is_some_and(|v| (v - c.value).abs() <= 0.1 * c.value.abs());
            let shrink = r.gap_reduction >= 0.9;
            let mass = (named && (c.label.starts_with("link_mass_scale/") || c.label.starts_with("payload/")))
                .then(|| mass_change_matches(&dir, c.robot, c.key, &r));
            let line = format!(
                "{:<15} {:<26} -> {:<40} {} = {:<12.5e} (true {}) gap {:.3e} -> {:.3e} ({:.1} %) [{}] {secs:.1} s",
                c.robot,
                c.label,
                r.candidate.clone().unwrap_or("none".into()),
                c.key,
                fitted.unwrap_or(f64::NAN),
                c.value,
                r.gap_before.overall,
                r.gap_after.overall,
                100.0 * r.gap_reduction,
                r.ranking.iter().take(3).map(|x| format!("{} ΔC {:.0}", x.candidate, x.delta_criterion)).collect::<Vec<_>>().join("; ")
            );
            Outcome { named, within, shrink, mass, line }
        })
        .collect();
    for o in &outcomes {
        eprintln!("{}", o.line);
    }
    let n = outcomes.len();
    let need = (0.9 * n as f64).ceil() as usize;
    let named = outcomes.iter().filter(|o| o.named).count();
    let within = outcomes.iter().filter(|o| o.within).count();
    let shrink = outcomes.iter().filter(|o| o.shrink).count();
    eprintln!(
        "{n} cases: named first {named}, parameter within 10 % {within}, gap shrinks ≥ 90 % {shrink} ({:.1} s)",
        t0.elapsed().as_secs_f64()
    );
    assert!(n >= 16);
    let masses: Vec<bool> = outcomes.iter().filter_map(|o| o.mass).collect();
    assert!(
        !masses.is_empty() && masses.iter().all(|&ok| ok),
        "mass_changes of the named mass scales and payloads: {masses:?}"
    );
    assert!(
        named >= need,
        "right effect named first in {named}/{n} cases (need {need})"
    );
    assert!(
        within >= need,
        "parameter within 10 % in {within}/{n} cases (need {need})"
    );
    assert!(
        shrink >= need,
        "held-out gap shrinks ≥ 90 % in {shrink}/{n} cases (need {need})"
    );
}

#[test]
fn clean_data_gives_no_missing_effect() {
    let dir = common::scratch_dir("calibrate-clean");
    let seeds = [7u64, 8, 9];
    let jobs: Vec<(&str, u64)> = ["arm2", "slider_contact"]
        .iter()
        .flat_map(|r| seeds.iter().map(move |s| (*r, *s)))
        .collect();
    for robot in ["arm2", "slider_contact"] {
        std::fs::write(dir.join(format!("{robot}.yaml")), scene_text(robot)).unwrap();
    }
    let results: Vec<_> = jobs
        .par_iter()
        .map(|(robot, seed)| {
            (
                robot,
                seed,
                run_case(&dir, &format!("clean_{robot}_{seed}"), robot, &[], *seed),
            )
        })
        .collect();
    for (robot, seed, r) in &results {
        eprintln!(
            "clean {robot} seed {seed}: verdict {} (best {} ΔC {:.1}, held-out RMS {:.3e} vs {:.3e})",
            r.verdict,
            r.ranking[0].candidate,
            r.ranking[0].delta_criterion,
            r.ranking[0].rms_holdout,
            r.gap_before.overall
        );
    }
    for (robot, seed, r) in &results {
        assert_eq!(
            r.verdict, "none",
            "{robot} seed {seed}: clean data gave {:?}",
            r.candidate
        );
        assert!(r.effect.is_none() && r.parameters.is_empty());
    }
}

/// The contact model's resolution is a setting of the simulator, fitted
/// before the selection and never named (`sdrs::calibrate::nuisance`): data
/// made with the barrier's support 1.5× the scene's (0.0075 m against
/// 0.005 m) give `none`, the fit recovers `s` within 15 % and halves the
/// training RMS at least; with the fit switched off, the old behaviour
/// names a contact parameter as the effect. (Settings and bounds chosen
/// before the first run, 2026-11-28. That run offered every effect kind
/// and passed in 162 s of CI time with the rest of this file; the
/// candidates were then cut to the joint and contact kinds for CI's time
/// budget — notes/calibration.md, session 6.)
#[test]
fn contact_resolution_is_fitted_first_and_never_named() {
    let dir = common::scratch_dir("calibrate-resolution");
    let robot = "slider_contact";
    std::fs::write(dir.join(format!("{robot}.yaml")), scene_text(robot)).unwrap();
    let hidden = ["{effect: contact_s, values: [0.0075]}"];
    let results: Vec<_> = [true, false]
        .par_iter()
        .map(|&fit| {
            let base = scene_text(robot);
            let data = measured_csv(
                &with_effects(&base, &hidden),
                &Sampling {
                    seed: 11,
                    ..Default::default()
                },
            );
            let measured = dir.join(format!("resolution_{fit}.csv"));
            std::fs::write(&measured, data).unwrap();
            let opts = CalibrateOptions {
                scene: dir.join(format!("{robot}.yaml")),
                measured,
                more_measured: Vec::new(),
                out: dir.join(format!("out_resolution_{fit}")),
                effects: vec![
                    EffectKind::JointDamping,
                    EffectKind::JointFriction,
                    EffectKind::ActuatorGain,
                    EffectKind::ContactMu,
                    EffectKind::ContactKappa,
                    EffectKind::ContactS,
                ],
                holdout: 0.3,
                select: Default::default(),
                log: Default::default(),
                fit_contact_resolution: fit,
            };
            calibrate(&opts).unwrap().0
        })
        .collect();
    let (on, off) = (&results[0], &results[1]);
    let c = on.contact_resolution.as_ref().expect("resolution fitted");
    eprintln!(
        "fitted: verdict {} ({:?}); {c} (true s 7.5e-3); as given: verdict {} ({:?})",
        on.verdict, on.candidate, off.verdict, off.candidate
    );
    assert_eq!(on.verdict, "none", "{}", on.reason);
    assert!(
        on.ranking
            .iter()
            .all(|r| !r.candidate.contains("contact_s") && !r.candidate.contains("contact_kappa")),
        "a resolution setting was offered as an effect"
    );
    assert!(
        (c.s_fitted - 0.0075).abs() <= 0.15 * 0.0075,
        "s {}",
        c.s_fitted
    );
    assert!(c.rms_train_fitted <= 0.5 * c.rms_train_given);
    assert!(off.contact_resolution.is_none());
    assert_eq!(off.verdict, "effect", "{}", off.reason);
    assert!(
        off.candidate
            .as_deref()
            .is_some_and(|l| l.contains("contact_")),
        "{:?}",
        off.candidate
    );
}
