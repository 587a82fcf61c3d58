//! Per-step wall time of one scene: each step's minimum over `ROUNDS` runs
//! of the same deterministic trajectory (the minimum removes the machine's
//! interruptions step by step), with the step's active contact pairs and
//! Newton iterations, as CSV on stdout (`step,seconds,pairs,iters`).
//! `tools/bench/step_classes.sh` pairs it with MuJoCo's steps on the same
//! chains and splits both engines' time into steps with and without
//! contact.
//!
//! `cargo run --release --example step_classes -- SCENE STEPS ROUNDS`
//! (runs on rayon's default thread count: set `RAYON_NUM_THREADS`).

use sdrs::scene::Scene;
use std::process::ExitCode;
use std::time::Instant;

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
            eprintln!("{path}: {e}");
            return ExitCode::FAILURE;
        }
    };
    let mut best = vec![f64::INFINITY; steps];
    let (mut pairs, mut iters) = (vec![0usize; steps], vec![0usize; steps]);
    for _ in 0..rounds {
        let mut sim = scene.simulator();
        for k in 0..steps {
            let t = Instant::now();
            let report = match sim.step() {
                Ok(r) => r,
                Err(e) => {
                    eprintln!("{path}: step {k}: {e}");
                    return ExitCode::FAILURE;
                }
            };
            best[k] = best[k].min(t.elapsed().as_secs_f64());
            pairs[k] = report.contact_pairs;
            iters[k] = report.newton.iters;
        }
    }
    println!("step,seconds,pairs,iters");
    for k in 0..steps {
        println!("{k},{:.9},{},{}", best[k], pairs[k], iters[k]);
    }
    ExitCode::SUCCESS
}
