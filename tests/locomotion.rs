//! The paper's locomotion benchmarks (issue 11): spider on a 15° slope and
//! biped. CI runs smoke versions (2 optimizer iterations, shortened-horizon
//! gradient checks); the full benchmarks are `tools/bench_locomotion.sh`.

mod common;

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
            let mut model = p.model.clone();
            p.design.apply(&mut model, d);
            p.design.check(&model).unwrap();
            checked += 1;
        })
        .unwrap();
        assert_eq!(checked, 3);
        let off = Problem::load(&task(name), false).unwrap();
        assert!(off.design.is_empty());
        let e = off
            .evaluate(&DVector::zeros(0), &off.controls.values(&off.controller))
            .unwrap();
        assert_eq!(e.loss, out.initial_loss, "{name}: same start");
    }
}

/// Central differences of the whole-trajectory loss w.r.t. foot-vertex
/// design variables vs the adjoint gradient, at the initial design.
/// `horizon`: steps (the task's H when None); `tol`: the Newton tolerance
/// (‖∇O‖∞); h = 1e-6 m. Returns the worst relative error.
fn fd_check(name: &str, horizon: Option<usize>, tol: f64, vars: usize) -> f64 {
    let mut p = Problem::load(&task(name), true).unwrap();
    if let Some(h) = horizon {
        p.horizon = h;
    }
    p.scene.settings.newton.tol = env_or("SDRS_FD_TOL", tol);
    let d0 = p.design.values(&p.model);
    let c0 = p.controls.values(&p.controller);
    let ev = p.evaluate(&d0, &c0).unwrap();
    // The foot vertices with the largest gradient components (the ones in
    // or near contact), at most one variable per vertex.
    let mut idx: Vec<usize> = (0..p.design.len())
        .filter(|&i| matches!(p.design.vars[i].targets[0], Target::Vertex { .. }))
        .collect();
    idx.sort_by(|&a, &b| ev.grad_design[b].abs().total_cmp(&ev.grad_design[a].abs()));
    let mut seen = Vec::new();
    let mut picked = Vec::new();
    for i in idx {
        if let Target::Vertex {
            link, hull, vertex, ..
        } = p.design.vars[i].targets[0]
            && !seen.contains(&(link, hull, vertex))
        {
            seen.push((link, hull, vertex));
            picked.push(i);
        }
        if picked.len() == vars {
            break;
        }
    }
    assert_eq!(picked.len(), vars);
    let h = env_or("SDRS_FD_H", 1e-6);
    let gmax = picked
        .iter()
        .map(|&i| ev.grad_design[i].abs())
        .fold(0.0, f64::max);
    let richardson = env_or("SDRS_FD_RICHARDSON", 0.0) != 0.0;
    let central = |i: usize, h: f64| {
        let mut dp = d0.clone();
        dp[i] += h;
        let mut dm = d0.clone();
        dm[i] -= h;
        (p.evaluate(&dp, &c0).unwrap().loss - p.evaluate(&dm, &c0).unwrap().loss) / (2.0 * h)
    };
    let mut worst = 0.0f64;
    // SDRS_FD_SKIP=N: check only the sample's components after the N largest.
    let skip = env_or("SDRS_FD_SKIP", 0.0) as usize;
    for &i in picked.iter().skip(skip) {
        // SDRS_FD_FIT=K: least-squares slope of a cubic through the 2K + 1
        // losses at d + k h (k = −K…K), with its standard error from the
        // residuals: a derivative estimate that averages the loss's noise.
        let fit_k = env_or("SDRS_FD_FIT", 0.0) as i64;
        let fd = if fit_k > 0 {
            let ks: Vec<f64> = (-fit_k..=fit_k).map(|k| k as f64).collect();
            let ls: Vec<f64> = ks
                .iter()
                .map(|&k| {
                    let mut dk = d0.clone();
                    dk[i] += k * h;
                    p.evaluate(&dk, &c0).unwrap().loss
                })
                .collect();
            let a = nalgebra::DMatrix::from_fn(ks.len(), 4, |r, c| ks[r].powi(c as i32));
            let b = nalgebra::DVector::from_iterator(ls.len(), ls.iter().map(|l| l - ls[0]));
            let ata = a.transpose() * &a;
            let coef = ata.clone().cholesky().unwrap().solve(&(a.transpose() * &b));
            let res = &b - &a * &coef;
            let dof = (ks.len() - 4) as f64;
            let s2 = res.norm_squared() / dof;
            let cov11 = ata.try_inverse().unwrap()[(1, 1)];
            let se = (s2 * cov11).sqrt() / h;
            eprintln!(
                "  fit slope {:.9e} ± {se:.2e} (noise σ {:.2e})",
                coef[1] / h,
                s2.sqrt()
            );
            coef[1] / h
        } else if richardson {
            // Richardson's extrapolation (4 D(h) − D(2h)) / 3 removes the
            // h² term of the central difference's error.
            let d1 = central(i, h);
            let d2 = central(i, 2.0 * h);
            eprintln!("  D(h) {d1:.9e} D(2h) {d2:.9e}");
            (4.0 * d1 - d2) / 3.0
        } else {
            central(i, h)
        };
        let g = ev.grad_design[i];
        // Relative to the component, floored at 1e-3 of the sample's largest.
        let rel = (fd - g).abs() / g.abs().max(fd.abs()).max(1e-3 * gmax);
        eprintln!(
            "{name} H={} h={h:.0e} tol={:.0e} {}: adjoint {g:.9e} fd {fd:.9e} rel {rel:.2e}",
            p.horizon, p.scene.settings.newton.tol, p.design.vars[i].name
        );
        worst = worst.max(rel);
    }
    worst
}

/// `SDRS_FD_H` / `SDRS_FD_TOL` override h and the Newton tolerance (for the
/// ignored full-horizon check's study of FD error vs h).
fn env_or(var: &str, default: f64) -> f64 {
    std::env::var(var)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

#[test]
fn spider_design_gradient_matches_central_differences_short_horizon() {
    let worst = fd_check("spider", Some(60), 1e-10, 12);
    assert!(worst <= 1e-4, "worst relative error {worst:.2e}");
}

#[test]
fn biped_design_gradient_matches_central_differences_short_horizon() {
    let worst = fd_check("biped", Some(60), 1e-10, 12);
    assert!(worst <= 1e-4, "worst relative error {worst:.2e}");
}

/// The full-horizon check (H = 550 / 400): `cargo test --release --test
/// locomotion -- --ignored full_horizon --nocapture`.
#[test]
#[ignore = "full horizon: 2-4 min per task in release; FD noise-limited (see notes/loco.md)"]
fn full_horizon_design_gradients_match_central_differences() {
    let tasks = std::env::var("SDRS_FD_TASKS").unwrap_or_else(|_| "spider,biped".into());
    let worst: Vec<f64> = tasks
        .split(',')
        .map(|name| {
            let w = fd_check(name, None, 1e-12, 12);
            eprintln!("{name}: full horizon worst relative error {w:.2e}");
            w
        })
        .collect();
    assert!(
        worst.iter().all(|&w| w <= 1e-4),
        "worst relative errors {worst:?}"
    );
}

/// The exported `design.yaml` (a complete scene with the optimized feet and
/// gait) reproduces the final loss when simulated on its own.
#[test]
fn exported_optimized_scene_reproduces_the_final_loss() {
    let dir = scratch_dir("loco-export");
    let mut p = Problem::load(&task("biped"), true).unwrap();
    p.horizon = 120;
    let out = optimize(&p, 2, |_, _| {}).unwrap();
    assert!(out.loss < out.initial_loss, "2 iterations improve the loss");
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
        .evaluate(&DVector::zeros(0), &q.controls.values(&q.controller))
        .unwrap();
    let rel = (e.loss - out.loss).abs() / out.loss;
    eprintln!(
        "replayed loss {:.12e} vs final {:.12e} (rel {rel:.1e})",
        e.loss, out.loss
    );
    assert!(rel <= 1e-8, "replayed {} vs {}", e.loss, out.loss);
    // The design really changed (else the test would not test the export).
    assert!(out.design != p.design.values(&p.model));
    // The per-link OBJs of the feet exist.
    assert!(dir.join("meshes/biped_left_foot.obj").exists());
}

/// Metrics: the standing spider (zero gait) neither walks nor falls; the
/// initial biped falls (tilt → ~90°) early, as in the paper's setup.
#[test]
fn metrics_distinguish_standing_from_falling() {
    let p = Problem::load(&task("biped"), false).unwrap();
    let m = Metrics::from_problem(&p).unwrap().unwrap();
    let t = m
        .measure(&p, &DVector::zeros(0), &p.controls.values(&p.controller))
        .unwrap();
    assert!(!t.upright_at_horizon && t.tilt_final_deg > 60.0, "{t:?}");
    assert!(t.first_fall_time.unwrap() < 2.0, "{t:?}");
    // Spider with every sine amplitude zero (the gait's offsets are 0: the
    // PD holds the initial pose): stands still on the slope.
    let mut p = Problem::load(&task("spider"), false).unwrap();
    p.horizon = 200;
    let mut c = p.controls.values(&p.controller);
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
