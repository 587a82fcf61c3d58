//! Synthetic "measured" data for calibration tests: simulate a scene (with
//! a hidden effect switched on), resample at jittered times with a gap, and
//! add seeded Gaussian noise.
#![allow(dead_code)]

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sdrs::scene::Scene;
use std::path::Path;

/// How measured data are made from a simulation.
#[derive(Clone, Debug)]
pub struct Sampling {
    /// Nominal sample period (s).
    pub period: f64,
    /// Uniform jitter of each sample time, ± this fraction of the period.
    pub jitter: f64,
    /// A gap `[a, b)` (s) without samples.
    pub gap: (f64, f64),
    /// Noise standard deviation (rad or m).
    pub noise: f64,
    /// Duration (s).
    pub duration: f64,
    pub seed: u64,
}

impl Default for Sampling {
    fn default() -> Self {
        Sampling {
            period: 0.01,
            jitter: 0.3,
            gap: (0.41, 0.47),
            noise: 1e-4,
            duration: 1.2,
            seed: 1,
        }
    }
}

/// Scene text with `effects` (YAML list entries) appended.
pub fn with_effects(scene: &str, effects: &[&str]) -> String {
    if effects.is_empty() {
        return scene.to_string();
    }
    let mut s = format!("{scene}\neffects:\n");
    for e in effects {
        s.push_str(&format!("  - {e}\n"));
    }
    s
}

/// Measured CSV text (all the scene's joint columns) from `scene_text`.
pub fn measured_csv(scene_text: &str, s: &Sampling) -> String {
    let sc = Scene::from_str(scene_text, Path::new("hidden.yaml")).unwrap();
    let dt = sc.settings.dt;
    let steps = (s.duration / dt).ceil() as usize + 2;
    let mut sim = sc.simulator();
    let traj = sdrs::sim::run::run(&mut sim, steps, |_| {}).unwrap();
    let mut offsets = vec![0.0; sc.model.ndof()];
    for (dofs, b) in sdrs::energy::effects::offsets(&sc.effects) {
        for &k in dofs {
            offsets[k] += b;
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(s.seed);
    let mut out = String::from("t");
    for n in &traj.names {
        out.push(',');
        out.push_str(n);
    }
    out.push('\n');
    let n = (s.duration / s.period) as usize;
    for i in 0..=n {
        let j: f64 = if s.jitter > 0.0 {
            rng.random_range(-s.jitter..s.jitter)
        } else {
            0.0
        };
        let t = ((i as f64 + j) * s.period).clamp(0.0, s.duration);
        if t >= s.gap.0 && t < s.gap.1 {
            continue;
        }
        out.push_str(&format!("{t}"));
        for (k, b) in offsets.iter().enumerate() {
            let v = sdrs::calibrate::data::interpolate(&traj.states, dt, k, t) + b;
            // Box–Muller.
            let (u1, u2): (f64, f64) = (rng.random_range(1e-12..1.0), rng.random_range(0.0..1.0));
            let g = (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos();
            out.push_str(&format!(",{}", v + s.noise * g));
        }
        out.push('\n');
    }
    out
}
