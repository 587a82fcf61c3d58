//! The grasping benchmarks (issue 12): design gradients of the block design
//! spaces against central differences, bitwise determinism of the collective
//! (multi-trajectory) evaluation for 1 and 2 threads, and ties/bounds after
//! optimizer iterations. Horizons are shortened here (CI cost); the full
//! horizons are checked by `tools/bench/bench_grasping.sh` and `FULL=1` below.

use crate::common;

use common::robots;
use nalgebra::DVector;
use sdrs::diff::When;
use sdrs::optimize::task::{LossSpec, TaskSpec};
use sdrs::optimize::{Problem, multi, optimize};

/// The task with horizon `h`, every stage window and grasp start scaled
/// into it (the loss keeps its structure), and Newton's tolerance `tol`.
fn shortened(name: &str, h: Option<usize>, tol: f64) -> Problem {
    let path = robots(&format!("{name}/task.yaml"));
    let mut task: TaskSpec =
        serde_yaml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    if let Some(h) = h {
        let full = task.horizon.unwrap();
        let scale = |k: usize| (k * h).div_ceil(full).min(h);
        task.horizon = Some(h);
        let fix = |l: &mut LossSpec| {
            let when = match l {
                LossSpec::LinkPoint { when, .. }
                | LossSpec::Joint { when, .. }
                | LossSpec::Com { when, .. }
                | LossSpec::Relative { when, .. } => when,
            };
            if let When::Window { from, to } = *when {
                let (a, b) = (scale(from), scale(to));
                *when = When::Window {
                    from: a.min(b - 1),
                    to: b,
                };
            }
        };
        task.loss.iter_mut().for_each(fix);
        for t in &mut task.trajectories {
            t.loss.iter_mut().for_each(fix);
            t.horizon = None;
        }
    }
    let mut p = if task.trajectories.is_empty() {
        Problem::from_spec(&path, task, true).unwrap()
    } else {
        multi::load(&path, task, true).unwrap()
    };
    for q in &mut p.trajectories {
        q.scene.settings.newton.tol = tol;
    }
    p
}

/// Design gradient of task `name` (horizon `h`, `None`: full) at the initial
/// design against Richardson-extrapolated central differences with step
/// `eps` (`FD_EPS` overrides; Newton tolerance 1e-11, `FD_TOL` overrides),
/// for the 12 block-vertex variables with the largest |∂L/∂d|. Asserts
/// that at least `need` of them agree to 1e-4 relative and all 12 to 1e-3
/// (every figure is printed).
fn fd_check(name: &str, h: Option<usize>, eps: f64, need: usize) {
    let tol: f64 = std::env::var("FD_TOL")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1e-11);
    fd_check_problem(&shortened(name, h, tol), name, eps, need);
}

/// [`fd_check`] on a loaded problem (a task, or one trajectory of a
/// collective task), `name` labelling the output.
fn fd_check_problem(p: &Problem, name: &str, eps: f64, need: usize) {
    let d = p.design.values(&p.first().model);
    let c = p.controls.values(&p.first().controller);
    let ev = p.evaluate(&d, &c).unwrap();
    let idx = largest_vertex_components(p, &ev, name);
    // Central differences D(h) = (L(d + h e_i) − L(d − h e_i))/2h carry an
    // O(h²) truncation error that is measured here (D(3e-6) is off by ~3e-3,
    // D(1e-6) by ~2.5e-4 relative: the ratio ≈ 9 of an h² error), while
    // below h ≈ 1e-7 the solver's round-off dominates; Richardson's
    // extrapolation (4 D(h) − D(2h))/3 removes the h² term.
    let eps: f64 = std::env::var("FD_EPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(eps);
    let central = |i: usize, h: f64| {
        let mut dp = d.clone();
        dp[i] += h;
        let mut dm = d.clone();
        dm[i] -= h;
        (p.evaluate(&dp, &c).unwrap().loss - p.evaluate(&dm, &c).unwrap().loss) / (2.0 * h)
    };
    if std::env::var("FD_NOISE").is_ok() {
        let stencil = common::fd::stencil_from_env(common::fd::Stencil::Richardson { levels: 1 });
        return fd_check_noise(p, name, &d, &c, &ev, &idx, eps, stencil, need);
    }
    // `need` of the 12 must agree to 1e-4 (the acceptance's figure), all 12
    // to 1e-3.
    let mut errors = Vec::new();
    for &i in &idx {
        let fd = (4.0 * central(i, eps) - central(i, 2.0 * eps)) / 3.0;
        let g = ev.grad_design[i];
        let rel = (fd - g).abs() / g.abs().max(fd.abs());
        eprintln!(
            "{name}: {} analytic {g:.9e} central {fd:.9e} rel {rel:.2e}",
            p.design.vars[i].name
        );
        errors.push(rel);
    }
    let within = errors.iter().filter(|&&e| e <= 1e-4).count();
    let worst = errors.iter().cloned().fold(0.0f64, f64::max);
    eprintln!(
        "{name}: {within} of {} vertices within 1e-4, worst relative error {worst:.2e} (h = {eps:e})",
        idx.len()
    );
    assert!(
        within >= need && worst <= 1e-3,
        "{name}: {within} of {} design-gradient components within 1e-4 (need {need}), worst {worst:.2e}",
        idx.len()
    );
}

/// The 12 block-vertex variables with the largest gradients (the ones in
/// contact; most blocks never touch anything and have zero gradient).
fn largest_vertex_components(
    p: &Problem,
    ev: &sdrs::optimize::Evaluation,
    name: &str,
) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..p.design.len())
        .filter(|&i| p.design.vars[i].name.contains(".hull"))
        .collect();
    idx.sort_by(|&a, &b| ev.grad_design[b].abs().total_cmp(&ev.grad_design[a].abs()));
    idx.truncate(12);
    assert!(
        ev.grad_design[idx[11]].abs() > 0.0,
        "{name}: fewer than 12 vertices with a gradient"
    );
    idx
}

/// [`fd_check_problem`] with `FD_NOISE=1`: each component against
/// Richardson's difference at `eps` with the loss's noise measured along it
/// (`common::fd::check_component`); at least `need` components resolved to
/// 1e-4 and agreeing, every component within its differences' uncertainty.
#[allow(clippy::too_many_arguments)]
fn fd_check_noise(
    p: &Problem,
    name: &str,
    d: &DVector<f64>,
    c: &DVector<f64>,
    ev: &sdrs::optimize::Evaluation,
    idx: &[usize],
    eps: f64,
    stencil: common::fd::Stencil,
    need: usize,
) {
    let (agree, all) = common::fd::check_problem_sample(
        &format!("{name}:"),
        p,
        d,
        c,
        ev,
        idx,
        common::fd::Steps::Fixed(eps),
        stencil,
    );
    eprintln!(
        "{name}: {agree} of {} resolved and within 1e-4 (h = {eps:e}), every component passes: {all}",
        idx.len()
    );
    assert!(
        agree >= need && all,
        "{name}: {agree} resolved components agree (need {need}); all pass: {all}"
    );
}

/// `FULL=1` runs the FD checks at the tasks' full horizons (minutes).
fn horizon(short: usize) -> Option<usize> {
    if std::env::var("FULL").is_ok() {
        None
    } else {
        Some(short)
    }
}

/// h = 1e-7 since the paper's connectivity (issue 30; 2026-11-26): on the
/// shared-vertex design space the 11th and 12th largest components are
/// small (|g| = 4.9e-7, a block corner no longer summed over four blocks)
/// and h = 1e-6 left a truncation error of 1.6e-4 on them (10 of 12 within
/// 1e-4); measured at h = 3e-7 and 1e-7: all 12 within 1.3e-5. All 12 are
/// still asserted.
#[test]
fn parallel_jaw_design_gradient_matches_central_differences() {
    fd_check("parallel_jaw_gripper", horizon(60), 1e-7, 12);
}

/// The parallel jaw at its full horizon 180 (ignored: ≈ 11 min in release;
/// `cargo test --release --test grasping -- --ignored parallel_jaw_full_horizon --nocapture`).
/// Its full-horizon gradients are small (|g| 1.1e-5 … 8.1e-5: the objects
/// leave the jaws at the lift) against a loss noise σ ≈ 1e-16 … 7e-16, and
/// Richardson's differences resolve only the largest four: below h ≈ 1e-6
/// the noise σ/h is ≈ 1e-4 of the small components, above it a truncation
/// error remains that a second Richardson level does not remove (a loss
/// that is C² but not C³ within a micrometre). So the 64 central
/// differences at steps j·6e-7/64 are fitted with `g + a h²`
/// ([`common::fd::Stencil::Fit`], noise 0.38 σ/h against Richardson's
/// 1.90 σ/h over the same span), with the loss's noise measured along each
/// component. All 12 must be resolved and agree to 1e-4 (the acceptance
/// asks ≥ 10). The span (where Richardson at h = 3e-7, i.e. over 6e-7,
/// already agreed within its noise) and the count were set from those
/// earlier measurements before this check was first run; figures in
/// notes/grasping-parallel-jaw.md. `FD_STEPS`, `FD_LEVELS`, `FD_EPS` override.
#[test]
#[ignore]
fn parallel_jaw_full_horizon_design_gradient_matches_fitted_central_differences() {
    let name = "parallel_jaw_gripper";
    let p = shortened(name, None, 1e-11);
    let d = p.design.values(&p.first().model);
    let c = p.controls.values(&p.first().controller);
    let ev = p.evaluate(&d, &c).unwrap();
    let idx = largest_vertex_components(&p, &ev, name);
    let eps: f64 = std::env::var("FD_EPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(6e-7);
    let stencil = common::fd::stencil_from_env(common::fd::Stencil::Fit {
        steps: 64,
        levels: 1,
    });
    fd_check_noise(&p, name, &d, &c, &ev, &idx, eps, stencil, 12);
}

#[test]
fn collective_evaluation_is_bitwise_the_same_for_one_and_two_threads() {
    let p = shortened("parallel_jaw_gripper", Some(40), 1e-6);
    assert_eq!(p.trajectories.len(), 4, "four trajectories");
    let d = p.design.values(&p.first().model);
    let c = p.controls.values(&p.first().controller);
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| p.evaluate(&d, &c).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.loss.to_bits(), b.loss.to_bits());
    assert!(
        a.grad_design
            .iter()
            .zip(b.grad_design.iter())
            .all(|(x, y)| x.to_bits() == y.to_bits())
    );
    // The sum is the sum of the parts, in order; the per-trajectory design
    // gradients (`parts_design`, used by `optimizer.clip_trajectory`) are
    // each trajectory's own, bitwise.
    let ones: Vec<_> = p
        .trajectories
        .iter()
        .map(|q| p.evaluate_trajectory(q, &d, &c).unwrap())
        .collect();
    assert_eq!(a.parts_design.len(), 4);
    for (part, one) in a.parts_design.iter().zip(&ones) {
        assert!(
            part.iter()
                .zip(one.grad_design.iter())
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
    }
    let summed = ones[1..]
        .iter()
        .fold(ones[0].grad_design.clone(), |s, e| s + &e.grad_design);
    assert_eq!(summed, a.grad_design);
    let parts: Vec<f64> = ones.iter().map(|e| e.loss).collect();
    assert_eq!(
        a.loss.to_bits(),
        parts.iter().fold(0.0, |s, x| s + x).to_bits()
    );
    assert!(
        parts.iter().all(|&l| l > 0.0),
        "every trajectory contributes: {parts:?}"
    );
    // The forward-only loss (used by the difference checks) is bitwise the
    // evaluation's, for either thread count.
    for threads in [1, 2] {
        let l = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| p.loss_value(&d, &c).unwrap());
        assert_eq!(l.to_bits(), a.loss.to_bits(), "{threads} thread(s)");
    }
}

/// Ties and bounds after each of 2 optimizer iterations of `name`
/// (horizon `h`): fewer variables than hull-vertex coordinates (shared
/// points are one variable), a point shared by exactly `shared` hull
/// vertices at most (2 for the paper's connectivity: one auxiliary vertex
/// per pair of touching blocks or V-HACD hulls, issue 30; 4 or more for
/// corner-tied blocks), and after every iteration each tie group one point
/// and every variable within its box.
fn ties_and_bounds_hold(name: &str, links: &[&str], h: usize, shared: usize) {
    let p = shortened(name, Some(h), 1e-6);
    let verts: usize = links
        .iter()
        .map(|n| {
            let l = sdrs::optimize::names::link(&p.first().model, n).unwrap();
            p.first().model.links[l]
                .hulls
                .iter()
                .map(|h| h.x_local.len())
                .sum::<usize>()
        })
        .sum();
    // Corner-tied block corners are shared by up to 8 blocks: under half
    // the coordinates remain; shared auxiliary vertices join two hulls each.
    let most = if shared >= 4 {
        verts * 3 / 2
    } else {
        verts * 3
    };
    assert!(
        p.design.len() < most,
        "{name}: {} variables for {verts} vertices",
        p.design.len()
    );
    let largest = p.design.vars.iter().map(|v| v.targets.len()).max();
    assert_eq!(
        largest,
        Some(shared),
        "{name}: the largest tie joins {shared} hull vertices"
    );
    let mut checked = 0;
    let lo = p.design.lower();
    optimize(&p, 2, |_, d: &DVector<f64>| {
        let mut model = p.first().model.clone();
        p.design.apply(&mut model, d);
        p.design.check(&model).unwrap();
        checked += 1;
    })
    .unwrap();
    assert_eq!(checked, 3);
    assert_eq!(lo, p.design.lower());
}

#[test]
fn block_ties_and_bounds_hold_after_optimizer_iterations() {
    ties_and_bounds_hold(
        "parallel_jaw_gripper",
        &["gripper/jaw_left", "gripper/jaw_right"],
        30,
        2,
    );
}

#[test]
fn single_jaw_ties_and_bounds_hold_after_optimizer_iterations() {
    ties_and_bounds_hold("single_jaw_gripper", &["gripper/jaw"], 120, 2);
}

/// The full horizon, 480 steps (all four stages), h = 1e-7, Newton
/// tolerance 1e-11: the 12 vertex coordinates with the largest |∂L/∂d|;
/// at least 10 must agree to 1e-4 (the acceptance: ≥ 10 block
/// vertices), all 12 to 1e-3. Measured 2026-11-25: 11 of 12 within 2.2e-5,
/// the 11th largest (hull7.v0.x, |g| 1.8e-3, a block grazing the X) 6.4e-4;
/// 18 s. The count was set to the acceptance's after that measurement. (The
/// earlier check at horizon 240, stages 1–2 only, had 6 of 12 within 1e-4:
/// fewer blocks touch, and the small components drown in round-off.)
#[test]
fn single_jaw_design_gradient_matches_central_differences() {
    fd_check("single_jaw_gripper", None, 1e-7, 10);
}

#[test]
fn single_jaw_cross_ties_and_bounds_hold_after_optimizer_iterations() {
    ties_and_bounds_hold("single_jaw_cross", &["gripper/jaw"], 120, 2);
}

/// The standing cross (issue 30, `robots/single_jaw_cross`), full horizon,
/// h = 1e-7, Newton tolerance 1e-11, at the drilled design
/// (`scene_hole.yaml`: the arm jams in the hole and the cross is carried):
/// at least 10 of the 12 largest vertex components within 1e-4, all 12
/// within 1e-3, as the first single-jaw task. At the initial design the
/// check is ill-posed: the arm's pointed tip meets the leg exactly where
/// four blocks meet, and the loss has a kink there (measured 2026-11-29:
/// central differences 3.6e-2 where the one-sided analytic value is 2e-6,
/// on a corner vertex's y; notes/grasping-topology-change.md part 2 §8).
#[test]
fn single_jaw_cross_design_gradient_matches_central_differences() {
    let p = cross_problem("scene_hole.yaml", 1e-11);
    fd_check_problem(&p, "single_jaw_cross", 1e-7, 10);
}

/// The cross task's first trust-region trials all simulate (issue 30;
/// notes/grasping-topology-change.md part 2 §9). Until 2026-11-30 the
/// separating-plane solve crawled to its iteration cap from a poorly
/// oriented warm plane at the edge of the support, and 181 of the
/// co-design's 200 trials failed and were silently rejected — from iteration
/// 2 on, so these six iterations had 3 failures (measured with the retry
/// from the cold start disabled).
#[test]
fn single_jaw_cross_trust_region_trials_all_simulate() {
    let path = robots("single_jaw_cross/task.yaml");
    let p = Problem::load(&path, true).unwrap();
    let out = optimize(&p, 6, |_, _: &DVector<f64>| {}).unwrap();
    assert_eq!(
        out.failed_trials.count,
        0,
        "failed trials: {:?}",
        out.failed_trials
            .first
            .iter()
            .map(|t| (t.iteration, &t.error))
            .collect::<Vec<_>>()
    );
    assert!(out.loss < out.initial_loss);
}

/// The cross task with its trajectory's scene replaced by `scene`, Newton
/// tolerance `tol`.
fn cross_problem(scene: &str, tol: f64) -> Problem {
    let path = robots("single_jaw_cross/task.yaml");
    let mut task: TaskSpec =
        serde_yaml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    task.trajectories[0].scene = scene.into();
    let mut p = multi::load(&path, task, true).unwrap();
    p.trajectories[0].scene.settings.newton.tol = tol;
    p
}

/// The design space can carry the cross through a drilled hole (issue 30,
/// the single jaw): `scene_hole.yaml` is the initial jaw with every
/// right-leg vertex near the arm's axis moved ≤ 4.8 mm (inside the task's
/// 14 mm bound). Measured, physics only (the prescribed path, no
/// optimization): the initial jaw pushes the cross along the ground (not
/// grasped, no hole); the drilled jaw has a through-hole (`holes` ≥ 1), the
/// arm passes it and the cross is lifted with the jaw (drift ≤ 2 cm, rise ≥
/// 5 cm), and the task's loss falls more than 100×.
#[test]
fn single_jaw_cross_a_drilled_hole_within_the_bound_lifts_the_cross() {
    let measure = |scene: &str| {
        let p = cross_problem(scene, 1e-6);
        let d = p.design.values(&p.first().model);
        let c = p.controls.values(&p.first().controller);
        let loss = p.evaluate(&d, &c).unwrap().loss;
        let grasp = sdrs::optimize::grasp::measure(&p, &d, &c).unwrap();
        let topo = sdrs::optimize::grasp_metrics::topologies(&p, &d).unwrap();
        let holes = topo["gripper/jaw"]["holes"].as_u64().unwrap();
        let jaw = sdrs::optimize::names::link(&p.first().model, "gripper/jaw").unwrap();
        let verts: Vec<_> = p.first().model.links[jaw]
            .hulls
            .iter()
            .flat_map(|h| h.x_local.clone())
            .collect();
        (loss, grasp[0].clone(), holes, verts)
    };
    let (l0, g0, h0, v0) = measure("scene.yaml");
    let (l1, g1, h1, v1) = measure("scene_hole.yaml");
    println!("initial: loss {l0:.4e}, {g0:?}, holes {h0}");
    println!("drilled: loss {l1:.4e}, {g1:?}, holes {h1}");
    let moved = v0
        .iter()
        .zip(&v1)
        .map(|(a, b)| (a - b).amax())
        .fold(0.0, f64::max);
    println!("largest vertex move {moved:.4e} m");
    assert!(
        moved <= 0.014,
        "the drilled design leaves the bound: {moved}"
    );
    assert!(
        !g0.lifted && g0.max_drift > 0.05,
        "the initial jaw pushes the cross: {g0:?}"
    );
    assert_eq!(h0, 0);
    assert!(h1 >= 1, "a through-hole: holes {h1}");
    assert!(g1.grasped, "the drilled jaw carries the cross: {g1:?}");
    assert!(l1 < 0.01 * l0, "loss {l0} → {l1}");
}

/// The parallel jaw's second task (issue 30; `robots/parallel_jaw_stand`, the
/// objects on a stand; `notes/grasping-parallel-jaw-stand.md`), physics only:
/// the initial jaws grasp none of the four objects (the paper's premise), and
/// the co-designed jaws of the committed run (its best iterate, 312 moved
/// coordinates in `tests/data/parallel_jaw_stand_design.json`) stay inside the
/// 12 mm bound, have a through-hole in each jaw (`holes` 0 → ≥ 1) and hold
/// the cube, the ball and the plus (drift ≤ 2 cm, rise ≥ 5 cm over the
/// lift), while the task's loss falls more than 100×. The cylinder is not
/// asserted: it is carried tilted by 0.7 rad, 2.34 cm off (the run's 3/4).
#[test]
fn parallel_jaw_stand_co_designed_jaws_hold_three_of_four() {
    let p = shortened("parallel_jaw_stand", None, 1e-6);
    let d0 = p.design.values(&p.first().model);
    let c = p.controls.values(&p.first().controller);
    let fixture: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(common::root().join("tests/data/parallel_jaw_stand_design.json"))
            .unwrap(),
    )
    .unwrap();
    assert_eq!(fixture["variables"].as_u64(), Some(d0.len() as u64));
    let mut d1 = d0.clone();
    let (lo, hi) = (p.design.lower(), p.design.upper());
    for m in fixture["moved"].as_array().unwrap() {
        let (i, was, now) = (
            m[0].as_u64().unwrap() as usize,
            m[1].as_f64().unwrap(),
            m[2].as_f64().unwrap(),
        );
        assert_eq!(
            d0[i], was,
            "variable {i} ({}): the design space changed",
            p.design.vars[i].name
        );
        assert!(
            lo[i] <= now && now <= hi[i],
            "variable {i} leaves its bound: {now}"
        );
        d1[i] = now;
    }
    let outcome = |d: &DVector<f64>| {
        let loss = p.evaluate(d, &c).unwrap().loss;
        let grasp = sdrs::optimize::grasp::measure(&p, d, &c).unwrap();
        let topo = sdrs::optimize::grasp_metrics::topologies(&p, d).unwrap();
        let holes: Vec<u64> = ["gripper/jaw_left", "gripper/jaw_right"]
            .iter()
            .map(|j| topo[*j]["holes"].as_u64().unwrap())
            .collect();
        (loss, grasp, holes)
    };
    let (l0, g0, h0) = outcome(&d0);
    let (l1, g1, h1) = outcome(&d1);
    println!("initial: loss {l0:.4e}, holes {h0:?}, {g0:?}");
    println!("co-designed: loss {l1:.4e}, holes {h1:?}, {g1:?}");
    assert!(
        g0.iter().all(|g| !g.grasped),
        "the initial jaws grasp none: {g0:?}"
    );
    assert_eq!(h0, [0, 0]);
    assert!(
        h1.iter().all(|&h| h >= 1),
        "a through-hole in each jaw: {h1:?}"
    );
    for (g, name) in g1.iter().zip(["cube", "cylinder", "ball", "plus"]) {
        if name != "cylinder" {
            assert!(g.grasped, "the co-designed jaws hold the {name}: {g:?}");
        }
    }
    assert!(l1 < 0.01 * l0, "loss {l0} → {l1}");
}

/// The parallel jaw on a stand from several perturbed starts (issue 30;
/// `notes/multistart-design-noise.md`, registered before the runs): the pick
/// of seeds 1–8 with `optimizer.design_init_noise` 2 mm (the lowest best
/// loss, seed 1), physics only. The fixture
/// (`tests/data/parallel_jaw_stand_multistart_design.json`) holds the
/// coordinates the run moved away from its start. Asserted: the start
/// rebuilt by [`sdrs::optimize::start`] is bitwise the run's (the fixture's
/// start values), lies within 2 mm of the task's design and grasps none of
/// the four objects (the paper's premise, as the task's own design); the
/// co-designed jaws stay inside the 12 mm bound with their ties intact
/// (`DesignSpace::check`) and hold all four objects (drift ≤ 2 cm, rise ≥
/// 5 cm over the lift), and the loss falls more than 100× from the start;
/// the same moves applied to the task's own design hold all four as well
/// and open a through-hole (the noise randomizes the path, not the grasp).
#[test]
fn parallel_jaw_stand_multistart_pick_holds_four_of_four() {
    let path = robots("parallel_jaw_stand/task.yaml");
    let fixture: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(
            common::root().join("tests/data/parallel_jaw_stand_multistart_design.json"),
        )
        .unwrap(),
    )
    .unwrap();
    let eta = fixture["design_init_noise"].as_f64().unwrap();
    let seed = fixture["seed"].as_u64().unwrap();
    let mut task: TaskSpec =
        serde_yaml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    task.optimizer.design_init_noise = eta;
    let p = multi::load(&path, task, true).unwrap();
    let d_task = p.design.values(&p.first().model);
    let (d0, c) = sdrs::optimize::start(&p, seed);
    assert_eq!(fixture["variables"].as_u64(), Some(d0.len() as u64));
    assert!(
        (&d0 - &d_task).abs().max() <= eta,
        "the start lies within η of the task's design"
    );
    let mut d1 = d0.clone();
    for m in fixture["moved"].as_array().unwrap() {
        let i = m[0].as_u64().unwrap() as usize;
        let (was, now) = (m[1].as_f64().unwrap(), m[2].as_f64().unwrap());
        assert_eq!(
            d0[i].to_bits(),
            was.to_bits(),
            "variable {i}: the start changed"
        );
        d1[i] = now;
    }
    let (lo, hi) = (p.design.lower(), p.design.upper());
    for i in 0..d1.len() {
        assert!(
            lo[i] <= d1[i] && d1[i] <= hi[i],
            "variable {i} leaves its bound"
        );
    }
    let mut model = p.first().model.clone();
    p.design.apply(&mut model, &d1);
    p.design.check(&model).unwrap();
    let outcome = |d: &DVector<f64>| {
        let loss = p.evaluate(d, &c).unwrap().loss;
        (loss, sdrs::optimize::grasp::measure(&p, d, &c).unwrap())
    };
    let (l0, g0) = outcome(&d0);
    let (l1, g1) = outcome(&d1);
    println!("start: loss {l0:.4e}, {g0:?}\nco-designed: loss {l1:.4e}, {g1:?}");
    assert!(
        g0.iter().all(|g| !g.grasped),
        "the start grasps none: {g0:?}"
    );
    let task_grasps = sdrs::optimize::grasp::measure(&p, &d_task, &c).unwrap();
    assert!(
        task_grasps.iter().all(|g| !g.grasped),
        "the task's design grasps none"
    );
    for (g, name) in g1.iter().zip(["cube", "cylinder", "ball", "plus"]) {
        assert!(g.grasped, "the co-designed jaws hold the {name}: {g:?}");
    }
    assert!(l1 < 0.01 * l0, "loss {l0} → {l1}");

    // The noise is the path's, not the grasp's: the run's moves applied to
    // the task's own design (the start's noise removed) hold all four too,
    // and open a through-hole in a jaw of the otherwise unchanged (1,0,0)
    // jaws (the start's noise itself leaves voxel-scale cracks between the
    // blocks, so the topology is read here, not on the pick).
    let mut moves = d_task.clone();
    for m in fixture["moved"].as_array().unwrap() {
        let i = m[0].as_u64().unwrap() as usize;
        moves[i] += m[2].as_f64().unwrap() - m[1].as_f64().unwrap();
    }
    p.design.project(&mut moves);
    let holes = |d: &DVector<f64>| {
        let topo = sdrs::optimize::grasp_metrics::topologies(&p, d).unwrap();
        ["gripper/jaw_left", "gripper/jaw_right"].map(|j| topo[j]["holes"].as_u64().unwrap())
    };
    let (l2, g2) = outcome(&moves);
    println!(
        "the moves on the task's design: loss {l2:.4e}, holes {:?}, {g2:?}",
        holes(&moves)
    );
    assert!(
        g2.iter().all(|g| g.grasped),
        "the moves alone hold all four: {g2:?}"
    );
    assert_eq!(holes(&d_task), [0, 0]);
    assert!(
        holes(&moves).iter().any(|&h| h >= 1),
        "a through-hole opens"
    );
}

/// How robust a co-designed grasp is to its design (ignored: a probe, run by
/// hand; `notes/adam-plateau-restarts.md`). `PROBE_TASK` (path under
/// `robots/`, default `three_finger_hand/task.yaml`) and `PROBE_CHECKPOINT`
/// (an `sdrs optimize` output's `checkpoint.json`): the checkpoint's best
/// iterate, then that design with every coordinate moved by ±ε (signs from
/// ChaCha8 seeded with 0, 8 draws per ε, projected onto the bounds) for
/// ε in `PROBE_EPS` (default 1e-12,1e-10,1e-8,1e-6,1e-4): the loss and the
/// grasp count of each.
/// `PROBE_CHECKPOINT=… cargo test --release --test integration -- --ignored grasp_robustness_probe --nocapture`
#[test]
#[ignore]
fn grasp_robustness_probe() {
    let task = std::env::var("PROBE_TASK").unwrap_or("three_finger_hand/task.yaml".into());
    let ckpt = std::env::var("PROBE_CHECKPOINT").expect("PROBE_CHECKPOINT");
    let eps: Vec<f64> = std::env::var("PROBE_EPS")
        .unwrap_or("1e-12,1e-10,1e-8,1e-6,1e-4".into())
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    let p = sdrs::optimize::Problem::load(&robots(&task), true).unwrap();
    let ck: sdrs::optimize::checkpoint::Checkpoint =
        serde_json::from_str(&std::fs::read_to_string(&ckpt).unwrap()).unwrap();
    let best = ck.state.best.unwrap();
    let c = best.controller.clone();
    let count = |d: &DVector<f64>| {
        let loss = p.evaluate(d, &c).map(|e| e.loss).unwrap_or(f64::NAN);
        let g = sdrs::optimize::grasp::measure(&p, d, &c).unwrap_or_default();
        (loss, g.iter().filter(|g| g.grasped).count(), g.len())
    };
    let (l, n, m) = count(&best.design);
    println!(
        "best iterate {} (loss {:.6e}): loss {l:.6e}, {n}/{m} grasped",
        best.iter, best.loss
    );
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let mut sign = || if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    for &e in &eps {
        let mut counts = Vec::new();
        let mut losses = Vec::new();
        for _ in 0..8 {
            let mut d = best.design.clone();
            d.iter_mut().for_each(|x| *x += e * sign());
            p.design.project(&mut d);
            let (l, n, _) = count(&d);
            counts.push(n);
            losses.push(format!("{l:.3e}"));
        }
        println!("eps {e:e}: grasped {counts:?} of {m}; losses {losses:?}");
    }
}

/// The hand's six finger links (4 V-HACD hulls each; only a few coincident
/// vertices per link are tied), horizon 60 of 200 (the fingers closing on
/// the object; the loss is final-time, so at step 60).
#[test]
fn three_finger_ties_and_bounds_hold_after_optimizer_iterations() {
    let links: Vec<String> = (0..3)
        .flat_map(|f| ["proximal", "distal"].map(|l| format!("hand/finger{f}_{l}")))
        .collect();
    let links: Vec<&str> = links.iter().map(String::as_str).collect();
    ties_and_bounds_hold("three_finger_hand", &links, 60, 2);
}

/// Horizon 60 of 200 (`FD_H` overrides; the fingers have closed on the
/// object, the loss is final-time): the 12 vertex coordinates with the
/// largest |∂L/∂d| at h = 1e-6, all asserted (cut 0, fixed before
/// measuring); figures in notes/grasping-hand.md. With `FULL=1` (horizon 200) it
/// fails: the ball rolls away from the initial hand, its trajectory's
/// sensitivity grows ≈ 1e4-fold while it rolls (a polyhedron's pivot
/// instability), and the differences converge onto the adjoint only at
/// h ≈ 1e-12, where the loss's round-off noise (≈ 5e-10) leaves them
/// ≈ 1e-3 uncertain (`three_finger_ball_sensitivity_grows_at_the_pivot_rate`,
/// `three_finger_full_horizon_probe`).
#[test]
fn three_finger_design_gradient_matches_central_differences() {
    let h: usize = std::env::var("FD_H")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(60);
    fd_check("three_finger_hand", horizon(h), 1e-6, 12);
}

/// The hand at its full horizon (Newton tolerance 1e-11), its initial
/// design and controller, their evaluation, and the design variable with
/// the largest |∂L/∂d|.
fn hand_full_horizon() -> (
    Problem,
    DVector<f64>,
    DVector<f64>,
    sdrs::optimize::Evaluation,
    usize,
) {
    let p = shortened("three_finger_hand", None, 1e-11);
    let d = p.design.values(&p.first().model);
    let c = p.controls.values(&p.first().controller);
    let ev = p.evaluate(&d, &c).unwrap();
    let i = (0..p.design.len())
        .max_by(|&a, &b| ev.grad_design[a].abs().total_cmp(&ev.grad_design[b].abs()))
        .unwrap();
    (p, d, c, ev, i)
}

/// Probe (ignored; `cargo test --release --test grasping -- --ignored
/// three_finger_full_horizon_probe --nocapture`): at the full horizon 200,
/// for the variable with the largest |∂L/∂d|, each trajectory's analytic
/// derivative and its central differences at h = 1e-5 … 1e-12 (Newton tol
/// 1e-11): the ball's converge onto the adjoint only below h ≈ 3e-12 (see
/// `three_finger_ball_sensitivity_grows_at_the_pivot_rate`). Figures in
/// notes/grasping-hand.md.
#[test]
#[ignore]
fn three_finger_full_horizon_probe() {
    let (p, d, c, _, i) = hand_full_horizon();
    eprintln!("variable {}", p.design.vars[i].name);
    let all = p.trajectories.iter().collect::<Vec<_>>();
    for (k, q) in all.iter().enumerate() {
        let e = p.evaluate_trajectory(q, &d, &c).unwrap();
        eprintln!(
            "trajectory {k}: loss {:.9e} analytic {:.6e}",
            e.loss, e.grad_design[i]
        );
        for h in [
            1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 3e-11, 1e-11, 3e-12, 1e-12,
        ] {
            let mut dp = d.clone();
            dp[i] += h;
            let mut dm = d.clone();
            dm[i] -= h;
            let (lp, lm) = (
                p.trajectory_loss(q, &dp, &c).unwrap(),
                p.trajectory_loss(q, &dm, &c).unwrap(),
            );
            eprintln!(
                "  h {h:e}: L+ {lp:.12e} L- {lm:.12e} central {:.6e}",
                (lp - lm) / (2.0 * h)
            );
        }
    }
    // The cube and cylinder trajectories alone (the ball's loss does not
    // converge under central differences above; this selection was made
    // after seeing that), Richardson at h = 1e-7, all 12 asserted.
    // (A copy of the task with one of its trajectories is that one alone.)
    let alone = |j: usize| {
        let mut one = p.clone();
        one.trajectories = vec![p.trajectories[j].clone()];
        one
    };
    let (cube, cylinder) = (alone(0), alone(1));
    for (q, label) in [(&cube, "cube"), (&cylinder, "cylinder")] {
        fd_check_problem(q, &format!("three_finger_hand/{label} (H = 200)"), 1e-7, 12);
    }
}

/// Why the hand's collective loss cannot be checked against differences to
/// 1e-4 at its full horizon (ignored, ≈ 5 s; `cargo test --release --test
/// grasping -- --ignored three_finger_ball_sensitivity --nocapture`): the
/// ball trajectory at the initial design, re-run with the largest-|∂L/∂d|
/// vertex moved by δ = 1e-7, 1e-8, 1e-9. Every step prints Newton's
/// iterations and max |ΔA|/δ of the link poses A (3×4 each). Asserts:
/// - the response is linear in δ up to step 140 (the three ratios within
///   2 %), i.e. the discrete map is smooth there;
/// - while the ball rolls alone (steps 62–140) the response grows
///   exponentially at a rate within ±30 % of a polyhedral ball's pivot
///   instability `sqrt(g / (1.4 r))` (an inverted pendulum about a contact
///   edge: moment of inertia `(2/5 + 1) m r²`), r the ball's radius.
///
/// Figures in notes/grasping-hand.md.
#[test]
#[ignore]
fn three_finger_ball_sensitivity_grows_at_the_pivot_rate() {
    let (p, d, c, _, i) = hand_full_horizon();
    let ball = &p.trajectories[2];
    // Link poses after every step (chart independent).
    let poses = |d: &DVector<f64>| {
        let mut sim = ball.simulator(&p.scene_at(ball, d, &c)).unwrap();
        (0..ball.horizon)
            .map(|_| {
                let iters = sim.step().unwrap().newton.iters;
                let a: Vec<f64> = sim
                    .state
                    .poses
                    .iter()
                    .flat_map(|p| p.iter().copied())
                    .collect();
                (DVector::from_vec(a), iters)
            })
            .collect::<Vec<_>>()
    };
    let base = poses(&d);
    let deltas = [1e-7, 1e-8, 1e-9];
    let moved: Vec<_> = deltas
        .iter()
        .map(|&dl| {
            let mut dp = d.clone();
            dp[i] += dl;
            poses(&dp)
        })
        .collect();
    let ratio = |j: usize, k: usize| (&moved[j][k].0 - &base[k].0).amax() / deltas[j];
    for (k, (_, newton)) in base.iter().enumerate() {
        eprintln!(
            "step {:3} newton {newton:2} | {:.3e} {:.3e} {:.3e}",
            k + 1,
            ratio(0, k),
            ratio(1, k),
            ratio(2, k)
        );
    }
    for k in 61..140 {
        let r: Vec<f64> = (0..3).map(|j| ratio(j, k)).collect();
        let spread = (r[0] - r[2]).abs().max((r[1] - r[2]).abs()) / r[2];
        assert!(spread < 0.02, "step {}: ratios {r:?} not linear", k + 1);
    }
    let obj = std::fs::read_to_string(robots("three_finger_hand/objects/ball.obj")).unwrap();
    let radius = obj
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
        })
        .fold(0.0, f64::max);
    let g = ball.scene.settings.gravity.norm();
    let dt = ball.scene.settings.dt;
    let predicted = (g / (1.4 * radius)).sqrt();
    let measured = (ratio(2, 139) / ratio(2, 61)).ln() / (78.0 * dt);
    eprintln!(
        "growth over steps 62–140: {measured:.2} /s; pivot instability sqrt(g/(1.4 r)) = \
         {predicted:.2} /s (r = {radius:.4} m); amplification by step 140: {:.2e}",
        ratio(2, 139) / ratio(2, 61)
    );
    assert!(
        (measured / predicted - 1.0).abs() < 0.3,
        "growth {measured} /s against {predicted} /s"
    );
}

/// Probe of the parallel jaw's design-gradient spikes (ignored; issue 30;
/// `PROBE_ITERS=n [SPIKE_ITER=k] cargo test --release --test grasping --
/// --ignored parallel_jaw_gradient_spike_probe --nocapture`): replays the
/// committed task's optimizer for `PROBE_ITERS` iterations (default 12) at
/// the scenes' own Newton tolerance, takes the iterate with the largest
/// ‖∇_d L‖ (or iterate `SPIKE_ITER`), and prints
/// - per trajectory: loss, ‖∇_d L_j‖ and its largest components (names);
/// - for the trajectory with the largest ‖∇_d L_j‖, along its unit gradient
///   `u`: central differences of `L_j` at h = 1e-3 … 1e-10 against the
///   adjoint's `∇L_j·u = ‖∇L_j‖`;
/// - per step, for that trajectory: Newton iterations, contact pairs, the
///   smallest GJK distance, CCD fallbacks/cuts, and max |ΔA|/δ of the link
///   poses for δ = 1e-6, 1e-7, 1e-8 along `u` (where the sensitivity grows).
///
/// Figures in notes/grasping-topology-change.md.
#[test]
#[ignore]
fn parallel_jaw_gradient_spike_probe() {
    let env = |k: &str| std::env::var(k).ok().and_then(|s| s.parse::<usize>().ok());
    let path = robots("parallel_jaw_gripper/task.yaml");
    let p = Problem::load(&path, true).unwrap();
    let iters = env("PROBE_ITERS").unwrap_or(12);
    let mut designs = Vec::new();
    let mut norms = Vec::new();
    optimize(&p, iters, |r, d| {
        eprintln!(
            "iter {:3} loss {:.6e} |g| {:.3e}",
            r.iter, r.loss, r.grad_design_norm
        );
        designs.push(d.clone());
        norms.push(r.grad_design_norm);
    })
    .unwrap();
    let k = env("SPIKE_ITER").unwrap_or_else(|| {
        (0..norms.len())
            .max_by(|&a, &b| norms[a].total_cmp(&norms[b]))
            .unwrap()
    });
    let d = designs[k].clone();
    let c = p.controls.values(&p.first().controller);
    eprintln!("probing iterate {k}: |g| {:.3e}", norms[k]);
    let all = p.trajectories.iter().collect::<Vec<_>>();
    let evs: Vec<_> = all
        .iter()
        .map(|q| p.evaluate_trajectory(q, &d, &c).unwrap())
        .collect();
    for (j, e) in evs.iter().enumerate() {
        let g = &e.grad_design;
        let mut idx: Vec<usize> = (0..g.len()).collect();
        idx.sort_by(|&a, &b| g[b].abs().total_cmp(&g[a].abs()));
        let top: Vec<String> = idx[..6]
            .iter()
            .map(|&i| format!("{} {:.2e}", p.design.vars[i].name, g[i]))
            .collect();
        eprintln!(
            "trajectory {j}: loss {:.6e} |g| {:.3e}; top: {}",
            e.loss,
            g.norm(),
            top.join(", ")
        );
    }
    let j = (0..evs.len())
        .max_by(|&a, &b| {
            evs[a]
                .grad_design
                .norm()
                .total_cmp(&evs[b].grad_design.norm())
        })
        .unwrap();
    let q = all[j];
    let gn = evs[j].grad_design.norm();
    let u = &evs[j].grad_design / gn;
    for h in [
        1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 3e-12, 1e-12,
    ] {
        let (lp, lm) = (
            p.trajectory_loss(q, &(&d + h * &u), &c).unwrap(),
            p.trajectory_loss(q, &(&d - h * &u), &c).unwrap(),
        );
        eprintln!(
            "trajectory {j} along u: h {h:e} L+ {lp:.12e} L- {lm:.12e} central {:.4e} (adjoint {gn:.4e})",
            (lp - lm) / (2.0 * h)
        );
    }
    truncated_check(&path, &d, &c, j);
    let run = |d: &DVector<f64>| {
        let mut sim = q.simulator(&p.scene_at(q, d, &c)).unwrap();
        (0..q.horizon)
            .map(|_| {
                let s = sim.step().unwrap();
                let a: Vec<f64> = sim
                    .state
                    .poses
                    .iter()
                    .flat_map(|p| p.iter().copied())
                    .collect();
                (DVector::from_vec(a), s)
            })
            .collect::<Vec<_>>()
    };
    let base = run(&d);
    let deltas = [1e-6, 1e-7, 1e-8];
    let moved: Vec<_> = deltas.iter().map(|&dl| run(&(&d + dl * &u))).collect();
    for (t, (a, s)) in base.iter().enumerate() {
        let r: Vec<String> = (0..3)
            .map(|m| format!("{:.3e}", (&moved[m][t].0 - a).amax() / deltas[m]))
            .collect();
        eprintln!(
            "step {:3} newton {:2} grad {:.1e} pairs {:2} dmin {:.3e} ccd fallbacks {} caps {} min_alpha {:.3} | {}",
            t + 1,
            s.newton.iters,
            s.newton.grad_inf,
            s.contact_pairs,
            s.min_distance,
            s.ccd.fallbacks,
            s.ccd.alpha_caps,
            s.ccd.min_alpha,
            r.join(" ")
        );
    }
}

/// Part of [`parallel_jaw_gradient_spike_probe`]: the adjoint at the probed
/// design `d` for trajectory `j` with the horizon cut to `PROBE_CUT` steps
/// (default 88: the ball has slipped out and is falling, before it lands)
/// and its loss window to the last 8 of them, against central differences
/// along its unit gradient (plain and Richardson) at h = 1e-5 … 1e-9.
fn truncated_check(path: &std::path::Path, d: &DVector<f64>, c: &DVector<f64>, j: usize) {
    let cut = std::env::var("PROBE_CUT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(88usize);
    let mut task: TaskSpec = serde_yaml::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    task.horizon = Some(cut);
    for t in &mut task.trajectories {
        for l in &mut t.loss {
            if let LossSpec::Relative { when, .. } = l {
                *when = When::Window {
                    from: cut - 8,
                    to: cut,
                };
            }
        }
    }
    let p = multi::load(path, task, true).unwrap();
    let q = &p.trajectories[j];
    let e = p.evaluate_trajectory(q, d, c).unwrap();
    let gn = e.grad_design.norm();
    let u = &e.grad_design / gn;
    let central = |h: f64| {
        (p.trajectory_loss(q, &(d + h * &u), c).unwrap()
            - p.trajectory_loss(q, &(d - h * &u), c).unwrap())
            / (2.0 * h)
    };
    for h in [1e-5, 1e-6, 1e-7, 1e-8, 1e-9] {
        let (d1, d2) = (central(h), central(2.0 * h));
        let rich = (4.0 * d1 - d2) / 3.0;
        eprintln!(
            "horizon {cut}, trajectory {j}: h {h:e} central {d1:.6e} Richardson {rich:.6e} adjoint {gn:.6e} rel {:.2e}",
            (rich - gn).abs() / gn
        );
    }
}
