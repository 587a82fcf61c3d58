//! The stress scenes (four chains driven at 1.0 and 1.3 rad with κ = 1, piles of boxes) run
//! all their steps.
//! They used to stop with inner-solver errors: the friction solve at steps 444 and 378 (fast
//! sliding at outer line-search trial points), and the separating-plane solve on
//! mirror-symmetric link pairs a few nanometres apart (see `src/contact/regression_tests.rs`
//! for the captured pairs). Same as
//! `sdrs simulate robots/stress/four_chains_a10.yaml -q` (and `…_a13.yaml`).

use crate::common;

use common::robots;
use sdrs::scene::Scene;
use sdrs::sim::run::run;

fn run_scene(file: &str) {
    let scene = Scene::load(robots(file)).unwrap();
    let steps = scene.steps;
    let mut sim = scene.simulator();
    let traj = run(&mut sim, steps, |_| {}).unwrap_or_else(|e| panic!("{file}: {e}"));
    assert_eq!(traj.diagnostics.len(), steps);
    assert!(traj.diagnostics.iter().any(|d| d.contact_pairs > 0));
    // Never an interpenetrating state (every accepted step is separated).
    assert!(
        traj.diagnostics.iter().all(|d| d.min_distance > 0.0),
        "{file}: non-positive distance"
    );
}

#[test]
fn stress_scene_four_chains_a10_runs_all_2000_steps() {
    run_scene("stress/four_chains_a10.yaml");
}

#[test]
fn stress_scene_four_chains_a13_runs_all_2000_steps() {
    run_scene("stress/four_chains_a13.yaml");
}

/// Piles of random boxes at Δt = 5 ms (shared/repro/newton_fail_piles) once
/// failed at steps 78, 116 and 126 with ‖∇O‖∞ up to 25: one Newton step
/// along a flat rotational direction threw a box's rotation vector to
/// hundreds of radians, where the chart is singular and Newton crawls.
/// Rotation steps are now limited per iteration (`sim::MAX_ROTATION_STEP`).
#[test]
fn piles_of_boxes_run_all_300_steps() {
    for f in ["pile_s2_dt005", "pile_s7_dt005", "pile_s401_kappa100_mu0"] {
        run_scene(&format!("stress/{f}.yaml"));
    }
}
