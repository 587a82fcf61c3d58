//! Per-step wall time of one scene: each step's minimum over `ROUNDS` runs
//! of the same deterministic trajectory (the minimum removes the machine's
//! interruptions step by step), with the step's active contact pairs and
//! Newton iterations, as CSV on stdout (`step,seconds,pairs,iters`).
//! `tools/bench/step_classes.sh` pairs it with MuJoCo's steps on the same
//! chains and splits both engines' time into steps with and without
//! contact. (`cli/tests/bench_mujoco.rs` calls [`per_step`] in-process.)
//!
//! `cargo run --release --example step_classes -- SCENE STEPS ROUNDS`
//! (runs on rayon's default thread count: set `RAYON_NUM_THREADS`).

use sdrs::scene::Scene;
use std::process::ExitCode;
use std::time::Instant;

/// One step of [`per_step`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepRow {
    /// The step's smallest wall time over the rounds (s).
    pub seconds: f64,
    /// Hull pairs with non-zero contact potential at the step's end.
    pub pairs: usize,
    /// Newton iterations of the step.
    pub iters: usize,
}

/// `steps` steps of `scene` from its initial state, `rounds` times; per
/// step the minimum wall time and (the same in every round: the run is
/// deterministic) its pairs and iterations. Errors name the failing step.
pub fn per_step(scene: &Scene, steps: usize, rounds: usize) -> Result<Vec<StepRow>, String> {
    let mut rows = vec![
        StepRow {
            seconds: f64::INFINITY,
            pairs: 0,
            iters: 0,
        };
        steps
    ];
    for _ in 0..rounds {
        let mut sim = scene.simulator();
        for (k, row) in rows.iter_mut().enumerate() {
            let t = Instant::now();
            let report = sim.step().map_err(|e| format!("step {k}: {e}"))?;
            row.seconds = row.seconds.min(t.elapsed().as_secs_f64());
            row.pairs = report.contact_pairs;
            row.iters = report.newton.iters;
        }
    }
    Ok(rows)
}

/// The CSV `step,seconds,pairs,iters` of `rows`.
pub fn csv(rows: &[StepRow]) -> String {
    let mut out = String::from("step,seconds,pairs,iters\n");
    for (k, r) in rows.iter().enumerate() {
        out.push_str(&format!("{k},{:.9},{},{}\n", r.seconds, r.pairs, r.iters));
    }
    out
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let usage = || {
        eprintln!("usage: step_classes SCENE STEPS ROUNDS (STEPS, ROUNDS ≥ 1)");
        ExitCode::from(2)
    };
    let [_, path, steps, rounds] = args.as_slice() else {
        return usage();
    };
    let (Ok(steps), Ok(rounds)) = (steps.parse::<usize>(), rounds.parse::<usize>()) else {
        return usage();
    };
    if steps == 0 || rounds == 0 {
        return usage();
    }
    let scene = match Scene::load(path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    match per_step(&scene, steps, rounds) {
        Ok(rows) => {
            print!("{}", csv(&rows));
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("{path}: {e}");
            ExitCode::FAILURE
        }
    }
}
