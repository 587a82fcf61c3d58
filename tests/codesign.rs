//! Co-design on the paper's chain-reaching task.

use crate::common;

use common::robots;
use sdrs::optimize::{Problem, optimize};

fn task() -> std::path::PathBuf {
    robots("chain_reach/task.yaml")
}

#[test]
fn ties_and_bounds_hold_after_every_optimizer_iteration() {
    let p = Problem::load(&task(), true).unwrap();
    assert_eq!(p.design.len(), 24, "8 attachment points × 3");
    // Every attachment variable also moves a parent hull vertex (its tie).
    assert!(p.design.vars.iter().all(|v| v.targets.len() == 2));
    let mut checked = 0;
    optimize(&p, 12, |_, d| {
        let mut model = p.first().model.clone();
        p.design.apply(&mut model, d);
        p.design.check(&model).unwrap();
        checked += 1;
    })
    .unwrap();
    assert_eq!(checked, 13);
}

#[test]
fn chain_reaching_codesign_beats_controller_only_by_ninety_percent() {
    let co = Problem::load(&task(), true).unwrap();
    let ctrl = Problem::load(&task(), false).unwrap();
    let iters = co.task.optimizer.iters;
    let a = optimize(&co, iters, |_, _| {}).unwrap();
    let b = optimize(&ctrl, iters, |_, _| {}).unwrap();
    assert_eq!(a.initial_loss, b.initial_loss, "same start");
    let link = 0.25;
    let reach = a.loss.sqrt();
    let improvement = 1.0 - a.loss / b.loss;
    eprintln!(
        "chain reach: initial {:.4e}; controller-only {:.4e} (error {:.3} m = {:.2} links); co-design {:.4e} (error {:.2e} m = {:.4} links); co-design lower by {:.4}%",
        a.initial_loss,
        b.loss,
        b.loss.sqrt(),
        b.loss.sqrt() / link,
        a.loss,
        reach,
        reach / link,
        100.0 * improvement
    );
    assert!(
        b.loss.sqrt() > link,
        "the target must be out of reach without co-design"
    );
    assert!(improvement >= 0.9);
    assert!(reach <= 0.3 * link);
}

/// `optimizer.result`: Adam is not monotone, and the run returns the
/// lowest-loss iterate it passed through (`best`, the default) or its last
/// iterate (`last`). The chain-reaching task with Adam at a learning rate
/// large enough to overshoot; each returned design re-evaluates to the
/// returned loss, bitwise.
///
/// The run must end on an iterate that is not its best. Which iterates
/// overshoot depends on the trajectories' round-off (after
/// `NewtonOptions::derivatives_at_trial`, 2026-11-30, the 10-iteration run
/// happened to end on its best), so the budget is taken from a 10-iteration
/// probe: the last iteration whose loss is above an earlier one's. Adam's
/// history does not depend on the budget, which the test checks too (the
/// shorter run is the probe's prefix, bit for bit).
#[test]
fn adam_returns_its_best_iterate_or_on_request_its_last() {
    use sdrs::optimize::task::ResultIterate;
    let (path, _) = adam_task();
    let mut p = Problem::load(&path, true).unwrap();
    p.task.optimizer.step_design = 0.05;
    p.task.optimizer.step_controller = 0.5;
    let run = |p: &Problem, iters: usize| optimize(p, iters, |_, _| {}).unwrap();
    let losses_of =
        |o: &sdrs::optimize::Outcome| -> Vec<f64> { o.history.iter().map(|r| r.loss).collect() };
    let probe = losses_of(&run(&p, 10));
    eprintln!("Adam losses (10 iterations): {probe:?}");
    let above_earlier =
        |i: usize| probe[i] > probe[..i].iter().copied().fold(f64::INFINITY, f64::min);
    let iters = (1..probe.len())
        .rev()
        .find(|&i| above_earlier(i))
        .expect("the probe never overshoots: the test needs a non-monotone run");
    let best = run(&p, iters);
    let losses = losses_of(&best);
    let same: Vec<u64> = probe[..=iters].iter().map(|l| l.to_bits()).collect();
    assert_eq!(
        losses.iter().map(|l| l.to_bits()).collect::<Vec<_>>(),
        same,
        "a shorter budget must give the probe's prefix"
    );
    let (k, min) =
        losses.iter().enumerate().fold(
            (0, f64::INFINITY),
            |(k, m), (i, &l)| if l < m { (i, l) } else { (k, m) },
        );
    assert!(
        k + 1 < losses.len() && *losses.last().unwrap() > min,
        "the test needs a run whose last iterate is not its best: {losses:?}"
    );
    assert_eq!((best.iter, best.loss.to_bits()), (k, min.to_bits()));
    let again = p.evaluate(&best.design, &best.controller).unwrap().loss;
    assert_eq!(again.to_bits(), min.to_bits());

    p.task.optimizer.result = ResultIterate::Last;
    let last = run(&p, iters);
    let last_losses: Vec<f64> = last.history.iter().map(|r| r.loss).collect();
    assert_eq!(last_losses, losses, "the same run either way");
    assert_eq!(last.iter, losses.len() - 1);
    assert_eq!(last.loss.to_bits(), losses.last().unwrap().to_bits());
    let again = p.evaluate(&last.design, &last.controller).unwrap().loss;
    assert_eq!(again.to_bits(), last.loss.to_bits());
}

/// The Adam variant of chain reaching (`examples/python/chain_reach_adam.yaml`)
/// and its task spec, for the optimizer-option tests below.
fn adam_task() -> (std::path::PathBuf, sdrs::optimize::task::TaskSpec) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/python/chain_reach_adam.yaml");
    let spec = serde_yaml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    (path, spec)
}

/// The loss bits of `iters` iterations of `spec` with `edit` applied to its
/// optimizer settings.
fn loss_bits(
    path: &std::path::Path,
    spec: &sdrs::optimize::task::TaskSpec,
    iters: usize,
    edit: impl Fn(&mut sdrs::optimize::task::OptimizerSpec),
) -> Vec<u64> {
    let mut s = spec.clone();
    edit(&mut s.optimizer);
    let p = Problem::from_spec(path, s, true).unwrap();
    let out = optimize(&p, iters, |_, _| {}).unwrap();
    out.history.iter().map(|r| r.loss.to_bits()).collect()
}

/// `optimizer.clip_design`: a non-positive value is refused naming the
/// field; a bound that never binds leaves Adam's run bitwise unchanged, and
/// one that binds changes it (the clipping itself is unit-tested in
/// `optimize::method`).
#[test]
fn adam_gradient_clip_is_validated_and_wired() {
    let (path, spec) = adam_task();
    let mut nan = spec.clone();
    nan.optimizer.clip_trajectory = Some(f64::NAN);
    let err = Problem::from_spec(&path, nan, true)
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("optimizer.clip_trajectory"), "{err}");
    let mut bad = spec.clone();
    bad.optimizer.clip_design = Some(-1.0);
    let err = Problem::from_spec(&path, bad, true)
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("optimizer.clip_design") && err.contains("-1"),
        "{err}"
    );
    let run = |clip: Option<f64>| loss_bits(&path, &spec, 6, |o| o.clip_design = clip);
    let free = run(None);
    assert_eq!(run(Some(1e300)), free);
    let p0 = Problem::load(&path, true).unwrap();
    let (d0, c0) = (
        p0.design.values(&p0.first().model),
        p0.controls.values(&p0.first().controller),
    );
    let grad0 = p0.evaluate(&d0, &c0).unwrap().grad_design.norm();
    assert!(grad0 > 0.0);
    assert_ne!(run(Some(1e-3 * grad0)), free);
}

/// `optimizer.step_decay`: a fraction outside (0, 1] is refused naming the
/// field; 1 leaves Adam's run bitwise unchanged; 0.01 keeps the first
/// iteration's step (factor 1) and changes the later ones (the schedule
/// itself is unit-tested in `optimize::method`).
#[test]
fn adam_step_decay_is_validated_and_wired() {
    let (path, spec) = adam_task();
    for bad in [0.0, 1.5, f64::NAN] {
        let mut s = spec.clone();
        s.optimizer.step_decay = Some(bad);
        let err = Problem::from_spec(&path, s, true)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("optimizer.step_decay"), "{err}");
    }
    let run = |decay: Option<f64>| loss_bits(&path, &spec, 6, |o| o.step_decay = decay);
    let free = run(None);
    assert_eq!(run(Some(1.0)), free);
    let decayed = run(Some(0.01));
    assert_eq!(decayed[..2], free[..2], "iteration 1 at the full rate");
    assert_ne!(decayed[2..], free[2..]);
}

/// `optimizer.plateau` (Adam's return to its best iterate): refused on the
/// trust region's monotone radius rules and with a zero patience or a factor outside (0, 1], each
/// naming its key; a patience beyond the run leaves it bitwise unchanged. A
/// binding one (rates ×10 so that Adam overshoots, patience 2) returns only
/// after 2 iterations without a new best, the first trial after a return
/// starts from the best iterate (a reset Adam's first step moves each
/// coordinate by at most its halved rate), and a run resumed from the
/// checkpoint of any iteration is bitwise the uninterrupted one.
#[test]
fn adam_plateau_is_validated_and_wired() {
    use sdrs::optimize::task::{Method, Plateau};
    use sdrs::optimize::{RunOptions, optimize_with};
    let (path, spec) = adam_task();
    let refused = |edit: &dyn Fn(&mut sdrs::optimize::task::OptimizerSpec), key: &str| {
        let mut s = spec.clone();
        edit(&mut s.optimizer);
        let err = Problem::from_spec(&path, s, true)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains(key), "{key}: {err}");
    };
    let plateau = |patience, factor| Some(Plateau { patience, factor });
    refused(
        &|o| {
            o.method = Method::TrustRegion;
            o.plateau = plateau(5, 0.5);
        },
        "optimizer.plateau",
    );
    refused(
        &|o| {
            o.method = Method::TrustRegion;
            o.radius = sdrs::optimize::task::RadiusRule::Reset;
            o.plateau = plateau(5, 0.5);
        },
        "optimizer.plateau",
    );
    refused(
        &|o| o.plateau = plateau(0, 0.5),
        "optimizer.plateau.patience",
    );
    for f in [0.0, 1.5, f64::NAN] {
        refused(&|o| o.plateau = plateau(5, f), "optimizer.plateau.factor");
    }
    let free = loss_bits(&path, &spec, 8, |_| {});
    assert_eq!(
        loss_bits(&path, &spec, 8, |o| o.plateau = plateau(100, 0.5)),
        free
    );

    let mut s = spec.clone();
    s.optimizer.step_design *= 10.0;
    s.optimizer.step_controller *= 10.0;
    s.optimizer.plateau = plateau(2, 0.5);
    let p = Problem::from_spec(&path, s, true).unwrap();
    let iters = 16;
    let mut designs = Vec::new();
    let mut states = Vec::new();
    let opts = RunOptions {
        seed: 0,
        resume: None,
    };
    let out = optimize_with(
        &p,
        iters,
        &opts,
        |_, d| designs.push(d.clone()),
        |st| {
            states.push(st.clone());
            Ok::<(), sdrs::optimize::OptimizeError>(())
        },
    )
    .unwrap();
    let returns = out.plateau_returns.clone();
    println!("returns after iterations {returns:?}");
    assert!(!returns.is_empty(), "the overshooting walk never returned");
    let losses: Vec<f64> = out.history.iter().map(|r| r.loss).collect();
    let lr = p.task.optimizer.step_design;
    for (n, &r) in returns.iter().enumerate() {
        // Iterations r−1 and r found no new best: the best of 0..=r is the
        // best of 0..=r−2.
        let best = |k: usize| losses[..=k].iter().cloned().fold(f64::INFINITY, f64::min);
        assert!(
            r >= 2 && best(r) == best(r - 2),
            "return after {r}: {losses:?}"
        );
        let b = (0..=r)
            .min_by(|&i, &j| losses[i].total_cmp(&losses[j]))
            .unwrap();
        if r < iters {
            let step = (&designs[r + 1] - &designs[b]).amax();
            let rate = lr * 0.5f64.powi(n as i32 + 1);
            assert!(
                step <= rate * (1.0 + 1e-9),
                "first step after the return {step} > {rate}"
            );
        }
    }
    for k in [returns[0], returns[0] + 1, iters / 2] {
        assert_resumes_bitwise(&p, iters, &states[k], &out);
    }
}

/// Resuming `p` from `state` (a checkpoint of the run `out`, `iters`
/// iterations) reproduces `out`'s history bit for bit and its plateau returns.
fn assert_resumes_bitwise(
    p: &Problem,
    iters: usize,
    state: &sdrs::optimize::checkpoint::State,
    out: &sdrs::optimize::Outcome,
) {
    use sdrs::optimize::{RunOptions, optimize_with};
    let bits =
        |h: &[sdrs::optimize::IterRecord]| h.iter().map(|r| r.loss.to_bits()).collect::<Vec<_>>();
    let opts = RunOptions {
        seed: 0,
        resume: Some(state.clone()),
    };
    let resumed = optimize_with(
        p,
        iters,
        &opts,
        |_, _| {},
        |_| Ok::<(), sdrs::optimize::OptimizeError>(()),
    )
    .unwrap();
    assert_eq!(
        bits(&resumed.history),
        bits(&out.history),
        "resumed after iteration {}",
        state.iter
    );
    assert_eq!(resumed.plateau_returns, out.plateau_returns);
}

/// `optimizer.design_norm: max` on chain reaching (trust region): the first
/// trial moves every design coordinate whose gradient is non-zero by exactly
/// the radius `step_design` (0.05; the bounds, ±0.3, do not bind), where the
/// Euclidean default moves the trial by 0.05 in norm; the step itself is
/// unit-tested in `optimize::method`.
#[test]
fn trust_region_design_norm_max_is_wired() {
    use sdrs::optimize::task::{DesignNorm, TaskSpec};
    let path = task();
    let spec: TaskSpec = serde_yaml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let first_trial = |norm: DesignNorm| {
        let mut s = spec.clone();
        s.optimizer.design_norm = norm;
        let p = Problem::from_spec(&path, s, true).unwrap();
        let d0 = p.design.values(&p.first().model);
        let g = p
            .evaluate(&d0, &p.controls.values(&p.first().controller))
            .unwrap()
            .grad_design;
        let mut trial = None;
        optimize(&p, 1, |r, d| {
            if r.iter == 1 {
                trial = Some(d - &d0);
            }
        })
        .unwrap();
        (trial.unwrap(), g)
    };
    let (dm, g) = first_trial(DesignNorm::Max);
    let (de, _) = first_trial(DesignNorm::Euclidean);
    assert!((de.norm() - 0.05).abs() < 1e-9, "{}", de.norm());
    let moved = g.iter().filter(|v| **v != 0.0).count();
    assert!(moved >= 2);
    for i in 0..g.len() {
        let want = if g[i] == 0.0 {
            0.0
        } else {
            -0.05 * g[i].signum()
        };
        assert!(
            (dm[i] - want).abs() < 1e-12,
            "coordinate {i}: {} vs {want}",
            dm[i]
        );
    }
}

/// A trust-region run ends early at a converged iterate when a trial rounds
/// to the iterate in a phase where every later trial would too
/// (`optimize::method::no_op_is_final`). With radii of 1e-300 the trials
/// move only the coordinates that are exactly 0 (by subnormal amounts);
/// each rejection halves the radii until even those round away, and the run
/// stops there — long before its 400 iterations — on the start's loss (to
/// the last few bits), with `converged` naming the iteration. With the
/// task's radii a short run ends normally.
#[test]
fn trust_region_run_ends_when_its_trials_round_to_the_iterate() {
    use sdrs::optimize::task::TaskSpec;
    let path = task();
    let spec: TaskSpec = serde_yaml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let mut tiny = spec.clone();
    tiny.optimizer.step_design = 1e-300;
    tiny.optimizer.step_controller = 1e-300;
    let p = Problem::from_spec(&path, tiny, true).unwrap();
    let out = optimize(&p, 400, |_, _| {}).unwrap();
    let why = out.converged.expect("converged");
    let n = out.history.len() - 1;
    assert!((2..400).contains(&n), "{n}");
    assert!(why.contains(&format!("iteration {n} of 400")), "{why}");
    assert!(!out.history[n].accepted);
    assert!((out.loss - out.initial_loss).abs() <= 1e-12 * out.initial_loss);
    let p = Problem::from_spec(&path, spec, true).unwrap();
    let out = optimize(&p, 3, |_, _| {}).unwrap();
    assert!(out.converged.is_none());
    assert_eq!(out.history.len(), 4);
}

/// `optimizer.design_init_noise` (several starts of one task): a negative
/// or non-finite half-width is refused naming its key; 0 leaves the start
/// the task's design; η > 0 moves every variable by at most η, the same
/// seed gives bitwise the same start and another seed another one, the
/// controller's `init_noise` draws are unchanged by it, and an η far
/// beyond the bounds leaves every variable inside `D` (clamped, many at a
/// bound).
#[test]
fn design_init_noise_is_validated_seeded_and_bounded() {
    use sdrs::optimize::start;
    let (path, spec) = adam_task();
    for bad in [-1e-3, f64::NAN, f64::INFINITY] {
        let mut s = spec.clone();
        s.optimizer.design_init_noise = bad;
        let err = Problem::from_spec(&path, s, true)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("optimizer.design_init_noise"), "{err}");
    }
    let problem = |eta: f64, ctrl: f64| {
        let mut s = spec.clone();
        s.optimizer.design_init_noise = eta;
        s.optimizer.init_noise = ctrl;
        Problem::from_spec(&path, s, true).unwrap()
    };
    let p0 = problem(0.0, 0.0);
    let d_task = p0.design.values(&p0.first().model);
    assert!(d_task.len() >= 10, "the test needs design variables");
    assert_eq!(start(&p0, 7).0, d_task);

    let eta = 1e-3;
    let p = problem(eta, 0.0);
    let (d1, _) = start(&p, 1);
    let moved = (&d1 - &d_task).abs();
    assert!(moved.max() <= eta && moved.min() >= 0.0, "{moved}");
    assert!(moved.iter().filter(|&&m| m > 0.0).count() > d_task.len() / 2);
    let bits = |d: &nalgebra::DVector<f64>| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&start(&p, 1).0), bits(&d1), "same seed, same start");
    assert_ne!(
        bits(&start(&p, 2).0),
        bits(&d1),
        "another seed, another start"
    );

    let c_alone = start(&problem(0.0, 0.01), 3).1;
    let (d_both, c_both) = start(&problem(eta, 0.01), 3);
    assert_eq!(bits(&c_both), bits(&c_alone), "controller draws come first");
    assert_ne!(bits(&d_both), bits(&d_task));

    let wide = problem(1e3, 0.0);
    let (dw, _) = start(&wide, 5);
    let (lo, hi) = (wide.design.lower(), wide.design.upper());
    let at_bound = (0..dw.len())
        .filter(|&i| {
            assert!(lo[i] <= dw[i] && dw[i] <= hi[i], "variable {i} outside D");
            dw[i] == lo[i] || dw[i] == hi[i]
        })
        .count();
    assert!(
        at_bound > dw.len() / 2,
        "{at_bound} of {} at a bound",
        dw.len()
    );
}

/// `--design off` of a task with `optimizer.design_init_noise` is the
/// controller-only twin of the co-design run with the same seed on the same
/// robot: [`Problem::load_for_seed`] holds the start's perturbed design
/// fixed, so the twin's loss at its start is bitwise the co-design run's at
/// its start, the twin has no design variables and the same controller
/// start, and another seed gives another robot. Without the noise the twin
/// is [`Problem::load`]`(path, false)` bit for bit.
#[test]
fn design_off_twin_starts_from_the_same_perturbed_robot() {
    let (path, mut spec) = adam_task();
    let dir = common::scratch_dir("design-off-twin");
    spec.scene = path
        .parent()
        .unwrap()
        .join(&spec.scene)
        .display()
        .to_string();
    spec.optimizer.design_init_noise = 0.01;
    spec.optimizer.init_noise = 0.01;
    let noisy = dir.join("task.yaml");
    std::fs::write(&noisy, serde_yaml::to_string(&spec).unwrap()).unwrap();
    let on = Problem::load_for_seed(&noisy, true, 4).unwrap();
    let off = Problem::load_for_seed(&noisy, false, 4).unwrap();
    let (d_on, c_on) = sdrs::optimize::start(&on, 4);
    let (d_off, c_off) = sdrs::optimize::start(&off, 4);
    assert!(d_on.len() >= 8 && d_off.is_empty());
    assert_eq!(c_on, c_off, "the same controller start");
    let l_on = on.loss_value(&d_on, &c_on).unwrap();
    let l_off = off.loss_value(&d_off, &c_off).unwrap();
    assert_eq!(l_on.to_bits(), l_off.to_bits(), "{l_on} vs {l_off}");
    let other = Problem::load_for_seed(&noisy, false, 5).unwrap();
    let l_other = other.loss_value(&d_off, &sdrs::optimize::start(&other, 5).1);
    assert_ne!(
        l_other.unwrap().to_bits(),
        l_off.to_bits(),
        "another seed, another robot"
    );
    let task_robot = on
        .loss_value(&on.design.values(&on.first().model), &c_on)
        .unwrap();
    assert_ne!(
        task_robot.to_bits(),
        l_off.to_bits(),
        "the twin's robot is the perturbed one"
    );

    let plain = Problem::load_for_seed(&path, false, 4).unwrap();
    let reference = Problem::load(&path, false).unwrap();
    let c = sdrs::optimize::start(&reference, 4).1;
    let empty = nalgebra::DVector::zeros(0);
    assert_eq!(
        plain.loss_value(&empty, &c).unwrap().to_bits(),
        reference.loss_value(&empty, &c).unwrap().to_bits()
    );
}
