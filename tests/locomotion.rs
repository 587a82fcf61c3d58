//! The paper's locomotion benchmarks (issue 11): spider on a 15° slope and
//! biped. CI runs smoke versions (2 optimizer iterations, shortened-horizon
//! gradient checks); the full benchmarks are `tools/bench/bench_locomotion.sh`.

use crate::common;

use common::{robots, scratch_dir};
use nalgebra::DVector;
use sdrs::optimize::design::Target;
use sdrs::optimize::metrics::Metrics;
use sdrs::optimize::{Problem, optimize};

fn task(name: &str) -> std::path::PathBuf {
    robots(&format!("{name}/task.yaml"))
}

/// 2 iterations of each task at its full horizon: after every iteration the
/// design is inside its bounds and every tie (shared vertices, attachment
/// points) holds exactly; the co-design and controller-only twins start
/// from the same loss; the loss is finite.
#[test]
fn smoke_two_iterations_keep_ties_and_bounds() {
    for name in ["spider", "biped"] {
        let p = Problem::load(&task(name), true).unwrap();
        assert!(p.design.len() >= 10 * 3, "{name}: feet are designable");
        let (lo, hi) = (p.design.lower(), p.design.upper());
        let mut checked = 0;
        let out = optimize(&p, 2, |r, d| {
            assert!(r.loss.is_finite());
            for i in 0..d.len() {
                assert!(
                    lo[i] <= d[i] && d[i] <= hi[i],
                    "{name}: variable {i} out of bounds"
                );
            }
            let mut model = p.first().model.clone();
            p.design.apply(&mut model, d);
            p.design.check(&model).unwrap();
            checked += 1;
        })
        .unwrap();
        assert_eq!(checked, 3);
        let off = Problem::load(&task(name), false).unwrap();
        assert!(off.design.is_empty());
        let e = off
            .evaluate(
                &DVector::zeros(0),
                &off.controls.values(&off.first().controller),
            )
            .unwrap();
        assert_eq!(e.loss, out.initial_loss, "{name}: same start");
    }
}

/// The task `name` (horizon `horizon`, the task's H when None) at Newton
/// tolerance `tol` (`SDRS_FD_TOL` overrides), its evaluation at the initial
/// design and the `vars` foot-vertex variables with the largest gradient
/// components (the ones in or near contact), at most one per vertex.
fn fd_setup(
    name: &str,
    horizon: Option<usize>,
    tol: f64,
    vars: usize,
) -> (
    Problem,
    DVector<f64>,
    DVector<f64>,
    sdrs::optimize::Evaluation,
    Vec<usize>,
) {
    let mut p = Problem::load(&task(name), true).unwrap();
    if let Some(h) = horizon {
        p.first_mut().horizon = h;
    }
    p.first_mut().scene.settings.newton.tol = env_or("SDRS_FD_TOL", tol);
    let d0 = p.design.values(&p.first().model);
    let c0 = p.controls.values(&p.first().controller);
    let ev = p.evaluate(&d0, &c0).unwrap();
    let picked = largest_vertex_components(&p, &ev, Vec::new(), vars);
    assert_eq!(picked.len(), vars);
    (p, d0, c0, ev, picked)
}

/// `picked` extended to `n` vertex variables by those with the largest
/// |∂L/∂d| of `ev`, at most one per vertex (the vertices of `picked`'s
/// first entries count as seen).
fn largest_vertex_components(
    p: &Problem,
    ev: &sdrs::optimize::Evaluation,
    mut picked: Vec<usize>,
    n: usize,
) -> Vec<usize> {
    let vertex_of = |i: usize| match p.design.vars[i].targets[0] {
        Target::Vertex {
            link, hull, vertex, ..
        } => Some((link, hull, vertex)),
        _ => None,
    };
    let mut seen: Vec<_> = picked.iter().filter_map(|&i| vertex_of(i)).collect();
    let mut idx: Vec<usize> = (0..p.design.len())
        .filter(|i| !picked.contains(i) && vertex_of(*i).is_some())
        .collect();
    idx.sort_by(|&a, &b| ev.grad_design[b].abs().total_cmp(&ev.grad_design[a].abs()));
    for i in idx {
        if picked.len() == n {
            break;
        }
        let v = vertex_of(i).expect("a vertex variable");
        if !seen.contains(&v) {
            seen.push(v);
            picked.push(i);
        }
    }
    picked
}

/// The full-horizon check of one task: the 12 foot vertices with the
/// largest |∂L/∂d|, each against Richardson's central difference at h
/// (spider 2e-6 m, biped 1e-6 m; `SDRS_FD_H` overrides) with the loss's noise measured along it
/// (`common::fd::check_component`). A component is *resolved* when the
/// differences' noise is within the 1e-4 criterion (`2 std ≤ 1e-4 |g|`);
/// resolved components must agree to 1e-4, the others within their
/// differences' uncertainty. Returns (resolved vertices that agree,
/// whether every component passed).
fn fd_check_full(name: &str) -> (usize, bool) {
    // `SDRS_FD_HORIZON=H` checks the first H steps instead (where along the
    // walk the differences stop resolving; notes/paper-step-rule.md).
    let horizon = std::env::var("SDRS_FD_HORIZON")
        .ok()
        .map(|v| v.parse().expect("SDRS_FD_HORIZON: a step count"));
    let (p, d0, c0, ev, picked) = fd_setup(name, horizon, 1e-12, 12);
    // The smaller of 1e-6 and 2e-6 at which the measured noise resolves at
    // least 10 components (a larger step buys a smaller noise σ/h, a smaller
    // one less truncation): the biped's noise resolves all 12 at 1e-6, the
    // spider's only 9 there and 10 at 2e-6 (notes/locomotion.md).
    let h = env_or("SDRS_FD_H", if name == "spider" { 2e-6 } else { 1e-6 });
    let label = format!(
        "{name} H={} h={h:.0e} tol={:.0e}",
        p.first().horizon,
        p.first().scene.settings.newton.tol
    );
    let stencil = common::fd::stencil_from_env(common::fd::Stencil::Richardson { levels: 1 });
    let steps = common::fd::Steps::Fixed(h);
    common::fd::check_problem_sample(&label, &p, &d0, &c0, &ev, &picked, steps, stencil)
}

/// `SDRS_FD_H` / `SDRS_FD_TOL` override h and the Newton tolerance (for the
/// ignored full-horizon check's study of FD error vs h).
fn env_or(var: &str, default: f64) -> f64 {
    std::env::var(var)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The short-horizon (H = 60, Newton tolerance 1e-10) check of one task:
/// Richardson's central difference with the loss's noise measured along
/// each of the 12 components, at a step chosen per component from that
/// noise (`sdrs::diff::central::check_component_adaptive`: from h_min, the
/// spider 4e-6 m and the biped 1e-6 m, up to 8 h_min; `SDRS_FD_H` overrides
/// h_min), with a smoothness test (the estimates at h and h/2 agree). A
/// component is resolved when smooth and `4 σ_c ≤ 1e-4 |g|`. At least 10
/// distinct foot vertices must be resolved and agree to 1e-4, and every
/// component must pass (not resolved: within its noise and the measured
/// inconsistency).
///
/// History. Plain central differences at one h, used until the 3-hull
/// feet, failed on the spider's shared tie vertices (|g| ≈ 0.017 against
/// 19.6) at 1.5e-4 while agreeing to 2e-6 at h = 1e-5: noise
/// (notes/locomotion-feet-and-radius.md). The spider's fixed h = 4e-6 was
/// chosen after a run (at 1e-6, 5 of 12 resolved; at 4e-6, 11). That
/// fixed check resolved at `2 σ_c ≤ 1e-4 |g|`, so an error of noise alone
/// failed a resolved component ~5 % of the time: a round-off change of the
/// assembly (notes/performance.md, "Held back") moved `hull1.v51.x` to
/// 1.14e-4 at 2.7 σ_c. The adaptive step and the 4σ margin replace it
/// (settings above chosen before their first run, 2026-11-29).
///
/// Richardson with two levels (was one) since 2026-11-30, after an outcome:
/// the contact plane solve's polish (`sdrs::contact::plane::polish`) removed
/// an adjoint offset of 1.1e-4 |g| on `leg0_lower.hull1.v35.z` (a fit of the
/// loss against the integrated adjoint over ±24 µm: +5.2e-6 → −8e-9
/// absolute; notes/performance.md, 2026-11-30). With the offset gone, that
/// component and its mirror `leg2_lower.hull1.v35.z` (contact onset; the
/// loss's third derivative runs from +1.8e8 to −1.0e8 over ±24 µm) showed
/// the one-level estimate's truncation error: 1.09e-4 at h = 4e-6 against
/// the corrected adjoint (6.4e-5 on the mirror; at h_min 3e-6 the mirror
/// failed). Two levels: 4.9e-6 / 5.2e-5 at h_min 4e-6, and every component
/// passes at h_min 2, 3 and 4e-6 on both tasks (24 of 24 resolved). The
/// criterion is unchanged.
fn fd_check_short(name: &str) -> (usize, bool) {
    let (p, d0, c0, ev, picked) = fd_setup(name, Some(60), 1e-10, 12);
    let h_min = env_or("SDRS_FD_H", if name == "spider" { 4e-6 } else { 1e-6 });
    let label = format!(
        "{name} H={} h_min={h_min:.0e} tol={:.0e}",
        p.first().horizon,
        p.first().scene.settings.newton.tol
    );
    let stencil = common::fd::stencil_from_env(common::fd::Stencil::Richardson { levels: 2 });
    let steps = common::fd::Steps::Adaptive(common::fd::Adaptive {
        h_min,
        h_max: 8.0 * h_min,
        margin: 4.0,
    });
    common::fd::check_problem_sample(&label, &p, &d0, &c0, &ev, &picked, steps, stencil)
}

#[test]
fn spider_design_gradient_matches_central_differences_short_horizon() {
    let (agree, all) = fd_check_short("spider");
    assert!(
        agree >= 10 && all,
        "resolved and agreeing {agree}, all pass {all}"
    );
}

#[test]
fn biped_design_gradient_matches_central_differences_short_horizon() {
    let (agree, all) = fd_check_short("biped");
    assert!(
        agree >= 10 && all,
        "resolved and agreeing {agree}, all pass {all}"
    );
}

/// `design.rest_on_ground` on the biped (H = 60, Newton tolerance 1e-10):
/// one sole vertex, the lowest at the initial design, is lowered along the
/// ground's normal by `drop` (2 mm, and 0.1 mm: close to the tie with the
/// rest of the flat sole), so it alone sets the robot's height; the design
/// gradient, which now carries the placement's term on that vertex
/// (`src/optimize/rest.rs`), matches Richardson's central difference on
/// that vertex's three coordinates and the 9 other foot vertices with the
/// largest |∂L/∂d|, as `fd_check_short` judges them; and the placement's
/// term is not zero (the gradient on that vertex differs from the task's
/// without the option at the same design).
#[test]
fn biped_rest_on_ground_gradient_matches_central_differences() {
    use sdrs::optimize::task::TaskSpec;
    let path = task("biped");
    let load = |rest: bool| {
        let mut spec: TaskSpec =
            serde_yaml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        spec.design.as_mut().unwrap().rest_on_ground = rest;
        let mut p = Problem::from_spec(&path, spec, true).unwrap();
        p.first_mut().horizon = 60;
        p.first_mut().scene.settings.newton.tol = 1e-10;
        p
    };
    let p = load(true);
    let plain = load(false);
    let r = &p.first().rest[0];
    let low = r.lowest(&p.first().model).unwrap();
    let pose = r.poses.iter().find(|(l, _)| *l == low.link).unwrap().1;
    let down = -(pose.fixed_view::<3, 3>(0, 0).transpose() * r.normal);
    let var = |axis: usize| {
        (0..p.design.len())
            .find(|&i| {
                p.design.vars[i].targets.iter().any(|t| {
                    *t == Target::Vertex {
                        link: low.link,
                        hull: low.hull,
                        vertex: low.vertex,
                        axis,
                    }
                })
            })
            .unwrap()
    };
    let own = [var(0), var(1), var(2)];
    let c0 = p.controls.values(&p.first().controller);
    for drop in [2e-3, 1e-4] {
        let mut d = p.design.values(&p.first().model);
        for (k, &i) in own.iter().enumerate() {
            d[i] += drop * down[k];
        }
        let ev = p.evaluate(&d, &c0).unwrap();
        let ev_plain = plain.evaluate(&d, &c0).unwrap();
        let term = own
            .iter()
            .map(|&i| (ev.grad_design[i] - ev_plain.grad_design[i]).abs())
            .fold(0.0, f64::max);
        assert!(
            term > 1e-3 * ev.grad_design.amax(),
            "placement term {term:e}"
        );
        let picked = largest_vertex_components(&p, &ev, own.to_vec(), 12);
        let label = format!("biped rest_on_ground drop={drop:.0e} H=60");
        let stencil = common::fd::Stencil::Richardson { levels: 2 };
        let steps = common::fd::Steps::Adaptive(common::fd::Adaptive {
            h_min: 1e-6,
            h_max: 8e-6,
            margin: 4.0,
        });
        let (agree, all) =
            common::fd::check_problem_sample(&label, &p, &d, &c0, &ev, &picked, steps, stencil);
        assert!(
            agree >= 10 && all,
            "{label}: resolved and agreeing {agree}, all pass {all}"
        );
    }
}

/// `design.rest_on_ground` in a scene without a ground is a load error
/// naming the task file and the key (chain reaching has no ground).
#[test]
fn rest_on_ground_without_a_ground_is_a_clear_error() {
    use sdrs::optimize::task::TaskSpec;
    let path = robots("chain_reach/task.yaml");
    let mut spec: TaskSpec =
        serde_yaml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    spec.design.as_mut().unwrap().rest_on_ground = true;
    let err = Problem::from_spec(&path, spec, true)
        .err()
        .expect("an error");
    let msg = err.to_string();
    assert!(
        msg.contains("chain_reach")
            && msg.contains("design.rest_on_ground")
            && msg.contains("ground:"),
        "{msg}"
    );
}

/// The full-horizon check (H = 550 / 400, Newton tolerance 1e-12):
/// `cargo test --release --test locomotion -- --ignored full_horizon --nocapture`
/// (`SDRS_FD_TASKS=spider`, `SDRS_FD_H=h`, `SDRS_FD_HORIZON=H` for the
/// first H steps). Each task needs at least 10
/// distinct foot vertices resolved by the differences and agreeing to 1e-4,
/// and every one of its 12 components passing (`fd_check_full`).
#[test]
#[ignore = "full horizon: 3-5 min per task in release (see notes/locomotion.md)"]
fn full_horizon_design_gradients_match_central_differences() {
    let tasks = std::env::var("SDRS_FD_TASKS").unwrap_or_else(|_| "spider,biped".into());
    let results: Vec<(String, usize, bool)> = tasks
        .split(',')
        .map(|name| {
            let (agree, all) = fd_check_full(name);
            eprintln!(
                "{name}: full horizon: {agree} resolved vertices agree to 1e-4, every component passes: {all}"
            );
            (name.to_string(), agree, all)
        })
        .collect();
    assert!(
        results.iter().all(|(_, agree, all)| *agree >= 10 && *all),
        "{results:?}"
    );
}

/// The exported `design.yaml` (a complete scene with the optimized feet and
/// gait) reproduces the final loss when simulated on its own. The run is two
/// Adam iterations at the task's steps, returning the last iterate (until
/// 2026-11-30 two trust-region iterations, which had to improve the loss:
/// with the biped's new initial gait the first two trials at H = 120 are
/// rejected and the first accepted one, the third, moves only the
/// controller, and the test needs a moved design; changed after that
/// failure). Adam moves both blocks at every iteration.
#[test]
fn exported_optimized_scene_reproduces_the_final_loss() {
    use sdrs::optimize::task::{Method, ResultIterate};
    let dir = scratch_dir("loco-export");
    let mut p = Problem::load(&task("biped"), true).unwrap();
    p.first_mut().horizon = 120;
    p.task.optimizer.method = Method::Adam;
    p.task.optimizer.result = ResultIterate::Last;
    let out = optimize(&p, 2, |_, _| {}).unwrap();
    assert_eq!(out.iter, 2, "the last iterate");
    sdrs::optimize::output::write_all(&dir, &p, &out, serde_json::Value::Null).unwrap();
    // A controller-only task on the exported scene, same loss and horizon.
    let task_yaml = format!(
        "version: 1\nscene: {}\nhorizon: 120\nloss:\n  - {{type: com, robot: biped, target: [0, 3, 0], weight: 1.0, when: final}}\ncontroller:\n  joints: [biped/left_hip_x+left_hip_y]\n",
        dir.join("design.yaml").display()
    );
    let tp = dir.join("replay_task.yaml");
    std::fs::write(&tp, task_yaml).unwrap();
    let q = Problem::load(&tp, false).unwrap();
    let e = q
        .evaluate(
            &DVector::zeros(0),
            &q.controls.values(&q.first().controller),
        )
        .unwrap();
    let rel = (e.loss - out.loss).abs() / out.loss;
    eprintln!(
        "replayed loss {:.12e} vs final {:.12e} (rel {rel:.1e})",
        e.loss, out.loss
    );
    assert!(rel <= 1e-8, "replayed {} vs {}", e.loss, out.loss);
    // The design really changed (else the test would not test the export).
    assert!(out.design != p.design.values(&p.first().model));
    // The per-link OBJs of the feet exist.
    assert!(dir.join("meshes/biped_left_foot.obj").exists());
}

/// Metrics: the standing spider (zero gait) neither walks nor falls; the
/// initial biped falls (tilt → ~90°) before H, as in the paper's setup (its
/// gait walks on flat soles; on the imported feet it falls at 2.63 s since
/// 2026-11-30, at 0.78 s with the earlier hand-written gait).
#[test]
fn metrics_distinguish_standing_from_falling() {
    let p = Problem::load(&task("biped"), false).unwrap();
    let m = Metrics::from_problem(&p).unwrap().unwrap();
    let t = m
        .measure(
            &p,
            &DVector::zeros(0),
            &p.controls.values(&p.first().controller),
        )
        .unwrap();
    assert!(!t.upright_at_horizon && t.tilt_final_deg > 60.0, "{t:?}");
    assert!(t.first_fall_time.unwrap() < t.horizon_time, "{t:?}");
    // Spider with every sine amplitude zero (the gait's offsets are 0: the
    // PD holds the initial pose): stands still on the slope.
    let mut p = Problem::load(&task("spider"), false).unwrap();
    p.first_mut().horizon = 200;
    let mut c = p.controls.values(&p.first().controller);
    let zero_amp = amplitude_indices(&p);
    for &i in &zero_amp {
        c[i] = 0.0;
    }
    let m = Metrics::from_problem(&p).unwrap().unwrap();
    let t = m.measure(&p, &DVector::zeros(0), &c).unwrap();
    assert!(t.upright_at_horizon && t.first_fall_time.is_none(), "{t:?}");
    assert!(t.distance.abs() < 0.02 && t.max_tilt_deg < 5.0, "{t:?}");
}

/// Indices of the sine amplitudes in the controller vector (parameter
/// layout of a `sine` signal: offset, then (amplitude, frequency, phase)
/// per term).
fn amplitude_indices(p: &Problem) -> Vec<usize> {
    use sdrs::optimize::controls::ControlTarget;
    p.controls
        .entries
        .iter()
        .enumerate()
        .filter_map(|(i, e)| match e {
            ControlTarget::Signal { param, .. } if *param >= 1 && (param - 1) % 3 == 0 => Some(i),
            _ => None,
        })
        .collect()
}

/// Diagnostic of the controller-only run's stall (issue 30, item 2; run by
/// hand, notes/locomotion-feet-and-radius.md): at the iterate of a controller-only checkpoint
/// (`SDRS_PROBE_DIR`, written by `sdrs optimize TASK --design off`; the
/// task's initial gait without it), the loss along the trust-region
/// controller step `Δc = −r g/‖g‖` for r = 3e-1 … 1e-7, against its linear
/// model `L + r gᵀΔc/r = L − r‖g‖`, at the scene's Newton tolerance or
/// `SDRS_FD_TOL`. Prints the gradient's norm per parameter kind
/// (offset / amplitude / frequency / phase). Asserts nothing beyond
/// finiteness: it measures.
#[test]
#[ignore]
fn controller_step_probe() {
    use sdrs::optimize::checkpoint;
    use sdrs::optimize::controls::ControlTarget;
    let name = std::env::var("SDRS_PROBE_TASK").unwrap_or_else(|_| "spider".into());
    let mut p = Problem::load(&task(&name), false).unwrap();
    p.first_mut().scene.settings.newton.tol =
        env_or("SDRS_FD_TOL", p.first().scene.settings.newton.tol);
    let mut c = p.controls.values(&p.first().controller);
    if let Ok(dir) = std::env::var("SDRS_PROBE_DIR") {
        let scene = task(&name).parent().unwrap().join(&p.task.scene);
        let key = checkpoint::RunKey::new(&task(&name), &scene, false, 0).unwrap();
        let st = checkpoint::load(std::path::Path::new(&dir), &key).unwrap();
        eprintln!(
            "checkpoint iter {} radius_controller {:.3e}",
            st.iter, st.radius_controller
        );
        c = st.controller;
    }
    let d = DVector::zeros(0);
    let ev = p.evaluate(&d, &c).unwrap();
    let g = &ev.grad_controller;
    let mut kinds = [0.0f64; 4];
    for (i, e) in p.controls.entries.iter().enumerate() {
        if let ControlTarget::Signal { param, .. } = e {
            let k = if *param == 0 { 0 } else { 1 + (param - 1) % 3 };
            kinds[k] += g[i] * g[i];
        }
    }
    eprintln!(
        "tol {:.0e} loss {:.12e} |g| {:.6e}; |g| by kind offset {:.3e} amplitude {:.3e} frequency {:.3e} phase {:.3e}",
        p.first().scene.settings.newton.tol,
        ev.loss,
        g.norm(),
        kinds[0].sqrt(),
        kinds[1].sqrt(),
        kinds[2].sqrt(),
        kinds[3].sqrt()
    );
    // Directions: the full gradient, the gradient without its frequency
    // components, the frequency components alone.
    let kind_of = |i: usize| match p.controls.entries[i] {
        ControlTarget::Signal { param, .. } if param >= 1 => 1 + (param - 1) % 3,
        _ => 0,
    };
    let only = |keep: &dyn Fn(usize) -> bool| {
        DVector::from_fn(g.len(), |i, _| if keep(kind_of(i)) { g[i] } else { 0.0 })
    };
    for (label, gk) in [
        ("full", g.clone()),
        ("no-frequency", only(&|k| k != 2)),
        ("frequency-only", only(&|k| k == 2)),
    ] {
        let dir = -&gk / gk.norm();
        let slope = g.dot(&dir);
        for r in [3e-1, 1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7] {
            let l = p.loss_value(&d, &(&c + r * &dir)).unwrap();
            let pred = r * slope;
            eprintln!(
                "{label} r {r:.0e}: ΔL {:+.6e} linear {:+.6e} ratio {:+.4}",
                l - ev.loss,
                pred,
                (l - ev.loss) / pred
            );
            assert!(l.is_finite());
        }
    }
}

/// `optimizer.radius: split` on the spider (horizon 60, 10 iterations): a
/// rejected trial that moved both blocks is followed by one trial that
/// moves the design alone at the same design radius (controller radius
/// unchanged; rejected → design radius halved), then by trials that keep the
/// design at the iterate's and halve only the controller radius until one
/// is accepted; with `--design off` the run is bitwise the `reset` run
/// (6 iterations).
#[test]
fn split_radius_backtracks_the_design_and_the_controller_separately() {
    use sdrs::optimize::task::RadiusRule;
    let load = |design: bool, rule: RadiusRule| {
        let mut p = Problem::load(&task("spider"), design).unwrap();
        p.first_mut().horizon = 60;
        p.task.optimizer.radius = rule;
        p
    };
    let p = load(true, RadiusRule::Split);
    let mut rows: Vec<(sdrs::optimize::IterRecord, DVector<f64>)> = Vec::new();
    optimize(&p, 10, |r, d| rows.push((r.clone(), d.clone()))).unwrap();
    // Phases as the rule defines them, checked on what each trial simulated.
    #[derive(PartialEq)]
    enum Ph {
        Joint,
        Design,
        Controller,
    }
    let (mut iterate, mut ph, mut seen) = (rows[0].1.clone(), Ph::Joint, [0; 3]);
    for w in rows.windows(2) {
        let ((prev, _), (r, d)) = (&w[0], &w[1]);
        let moved_design = d != &iterate;
        ph = match ph {
            Ph::Joint => {
                seen[0] += 1;
                if r.accepted || !moved_design {
                    Ph::Joint
                } else {
                    Ph::Design
                }
            }
            Ph::Design => {
                seen[1] += 1;
                assert!(moved_design, "iteration {}: design trial", r.iter);
                assert_eq!(r.radius_controller, prev.radius_controller);
                let want = if r.accepted {
                    p.task.optimizer.step_design
                } else {
                    0.5 * prev.radius_design
                };
                assert_eq!(r.radius_design, want, "iteration {}", r.iter);
                Ph::Controller
            }
            Ph::Controller => {
                seen[2] += 1;
                assert!(!moved_design, "iteration {}: the design is held", r.iter);
                assert_eq!(r.radius_design, prev.radius_design);
                if r.accepted {
                    Ph::Joint
                } else {
                    assert_eq!(r.radius_controller, 0.5 * prev.radius_controller);
                    Ph::Controller
                }
            }
        };
        if r.accepted {
            iterate = d.clone();
        }
    }
    assert!(
        seen[1] > 0 && seen[2] > 0,
        "phases seen {seen:?} in 10 iterations"
    );
    let losses = |rule| {
        let mut l = Vec::new();
        optimize(&load(false, rule), 6, |r, _| {
            l.push((r.loss, r.radius_controller, r.accepted))
        })
        .unwrap();
        l
    };
    assert_eq!(losses(RadiusRule::Split), losses(RadiusRule::Reset));
}

/// `optimizer.radius: fixed` (the paper's update as written) on the spider
/// (horizon 60, 10 iterations): every trial is taken at the radii
/// `(ᾱ_d, ᾱ_c)`, so every design step has length at most ᾱ_d (the bounds'
/// projection can only shorten it) and the loss may rise; the run's result
/// is its best iterate and every row's best loss is the running minimum.
#[test]
fn fixed_radius_takes_every_trial_at_the_paper_step() {
    use sdrs::optimize::task::RadiusRule;
    let mut p = Problem::load(&task("spider"), true).unwrap();
    p.first_mut().horizon = 60;
    p.task.optimizer.radius = RadiusRule::Fixed;
    let o = p.task.optimizer.clone();
    let mut rows: Vec<(sdrs::optimize::IterRecord, DVector<f64>)> = Vec::new();
    let out = optimize(&p, 10, |r, d| rows.push((r.clone(), d.clone()))).unwrap();
    assert_eq!(rows.len(), 11);
    let mut best = f64::INFINITY;
    for w in rows.windows(2) {
        let ((_, d0), (r, d1)) = (&w[0], &w[1]);
        assert!(r.accepted, "iteration {}: every trial is taken", r.iter);
        assert_eq!(
            (r.radius_design, r.radius_controller),
            (o.step_design, o.step_controller),
            "iteration {}",
            r.iter
        );
        let step = (d1 - d0).norm();
        assert!(
            step <= o.step_design * (1.0 + 1e-12) && step > 0.0,
            "iteration {}: design step {step:e}",
            r.iter
        );
    }
    for (r, _) in &rows {
        best = best.min(r.loss);
        assert_eq!(r.best_loss, best, "iteration {}", r.iter);
    }
    assert_eq!(out.loss, best);
    let at = rows.iter().find(|(r, _)| r.loss == best).unwrap();
    assert_eq!(out.design, at.1, "the result is the best iterate's design");
}

/// `radius: fixed` with `optimizer.plateau` (spider, horizon 60, patience
/// 2, factor 0.5; this walk returns after iterations 7 and 11): a return
/// happens only after 2 iterations without a new best; after `n` returns
/// every trial is taken at `0.5ⁿ (ᾱ_d, ᾱ_c)`, and the first trial after a
/// return starts from the best iterate (its design step from the best
/// design is at most the halved radius).
#[test]
fn fixed_radius_plateau_returns_to_the_best_iterate_at_a_shorter_step() {
    use sdrs::optimize::task::{Plateau, RadiusRule};
    let mut p = Problem::load(&task("spider"), true).unwrap();
    p.first_mut().horizon = 60;
    p.task.optimizer.radius = RadiusRule::Fixed;

    p.task.optimizer.plateau = Some(Plateau {
        patience: 2,
        factor: 0.5,
    });
    let o = p.task.optimizer.clone();
    let mut rows: Vec<(sdrs::optimize::IterRecord, DVector<f64>)> = Vec::new();
    let out = optimize(&p, 12, |r, d| rows.push((r.clone(), d.clone()))).unwrap();
    let returns = out.plateau_returns.clone();
    let losses: Vec<f64> = rows.iter().map(|(r, _)| r.loss).collect();
    println!("returns after iterations {returns:?}, losses {losses:?}");
    assert!(!returns.is_empty(), "the walk never returned");
    let best = |k: usize| losses[..=k].iter().cloned().fold(f64::INFINITY, f64::min);
    for &r in &returns {
        assert!(
            r >= 2 && best(r) == best(r - 2),
            "return after {r}: {losses:?}"
        );
    }
    for (r, d) in rows.iter().skip(1) {
        let n = returns.iter().filter(|&&x| x < r.iter).count();
        let scale = 0.5f64.powi(n as i32);
        assert!(r.accepted, "iteration {}: every trial is taken", r.iter);
        assert_eq!(
            (r.radius_design, r.radius_controller),
            (o.step_design * scale, o.step_controller * scale),
            "iteration {} after {n} returns",
            r.iter
        );
        let from = if returns.contains(&(r.iter - 1)) {
            let b = (0..r.iter)
                .min_by(|&i, &j| losses[i].total_cmp(&losses[j]))
                .unwrap();
            &rows[b].1
        } else {
            &rows[r.iter - 1].1
        };
        let step = (d - from).norm();
        assert!(
            step <= o.step_design * scale * (1.0 + 1e-12),
            "iteration {}: design step {step:e} from its start",
            r.iter
        );
    }
}

/// The biped's committed initial gait is the family of
/// `tools/gen/make_locomotion_scenes.py::biped_gait` (the scene is written
/// from it, `--biped-gait-only`; this catches a hand edit or a drift): at
/// every time, each sole stays parallel to the torso (hip + knee + ankle
/// pitch = 0, hip + ankle roll = 0), the knees do not roll, the legs' hip
/// pitches are opposite, and the right knee lags the left by half a period.
#[test]
fn biped_initial_gait_keeps_the_soles_parallel_and_the_legs_in_anti_phase() {
    let text = std::fs::read_to_string(robots("biped/scene.yaml")).unwrap();
    let scene: serde_yaml::Value = serde_yaml::from_str(&text).unwrap();
    let targets = &scene["robots"][0]["controller"]["targets"];
    // (θ*_x, θ*_y) of joint `name` at time t: offset + Σ a sin(2π f t + φ).
    let eval = |name: &str, t: f64| -> [f64; 2] {
        let axes = targets[name].as_sequence().unwrap();
        let mut out = [0.0; 2];
        for (k, s) in axes.iter().enumerate() {
            out[k] = s["offset"].as_f64().unwrap();
            for term in s["terms"].as_sequence().unwrap() {
                let (a, f, p) = (
                    term["amplitude"].as_f64().unwrap(),
                    term["frequency"].as_f64().unwrap(),
                    term["phase"].as_f64().unwrap(),
                );
                out[k] += a * (std::f64::consts::TAU * f * t + p).sin();
            }
        }
        out
    };
    let f = targets["left_hip_x+left_hip_y"][1]["terms"][0]["frequency"]
        .as_f64()
        .unwrap();
    for i in 0..=400 {
        let t = i as f64 * 0.01;
        for side in ["left", "right"] {
            let hip = eval(&format!("{side}_hip_x+{side}_hip_y"), t);
            let knee = eval(&format!("{side}_knee_x+{side}_knee_y"), t);
            let ankle = eval(&format!("{side}_ankle_x+{side}_ankle_y"), t);
            assert!(
                (hip[1] + knee[1] + ankle[1]).abs() < 1e-12,
                "{side} pitch at {t}"
            );
            assert!((hip[0] + ankle[0]).abs() < 1e-12, "{side} roll at {t}");
            assert!(knee[0].abs() < 1e-15, "{side} knee roll at {t}");
        }
        let (l, r) = (
            eval("left_hip_x+left_hip_y", t),
            eval("right_hip_x+right_hip_y", t),
        );
        assert!(
            (l[1] + r[1]).abs() < 1e-12 && (l[0] - r[0]).abs() < 1e-15,
            "hips at {t}"
        );
        let kl = eval("left_knee_x+left_knee_y", t);
        let kr = eval("right_knee_x+right_knee_y", t + 0.5 / f);
        assert!((kl[1] - kr[1]).abs() < 1e-9, "knees at {t}");
    }
    // It moves: the hip pitch swings by more than 0.1 rad.
    let swing = (0..100)
        .map(|i| eval("left_hip_x+left_hip_y", i as f64 * 0.01)[1])
        .fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(swing > 0.1, "{swing}");
}
