//! Co-design benchmarks: each task optimized with shape + controller and
//! with the controller alone, from the same start; convergence, final loss,
//! wall time, the final design's minimum hull distance, and a
//! central-difference check of one design-gradient component.

use super::results::{CodesignPart, CodesignRun, Descended, FdCheck};
use super::suite::CodesignSpec;
use anyhow::{Context, Result};
use indicatif::ProgressBar;
use sdrs::diff::descending::{Descent, check_component_descending};
use sdrs::optimize::{Problem, checkpoint};
use sdrs::output::Summary;
use std::path::Path;
use std::time::Instant;

/// One co-design benchmark: the gradient check, then each method of
/// [`variants`] (kept from an earlier run when its part is there, resumed
/// from its checkpoint otherwise), measured on its final design.
pub fn run(
    spec: &CodesignSpec,
    base_dir: &Path,
    out_dir: &Path,
    force: bool,
    pb: &ProgressBar,
) -> Result<CodesignPart> {
    // Each finished method and the gradient check are kept on their own,
    // keyed by the suite entry, so an interrupted run resumes mid-benchmark.
    let parts = out_dir
        .join("parts")
        .join(format!("codesign_{}", spec.name));
    std::fs::create_dir_all(&parts)
        .with_context(|| format!("{}: cannot create the output directory", parts.display()))?;
    let task = base_dir.join(&spec.task);
    let p = load_problem(spec, &task, true)?;
    let iters = spec.iters.unwrap_or(p.task.optimizer.iters);
    let methods = 2 + spec.cages.len() as u64;
    pb.set_length(methods * (iters as u64 + 1) + u64::from(spec.fd_check));
    let fd = gradient_check_part(spec, &p, &parts, force, pb)?;
    let metrics = sdrs::optimize::metrics::Metrics::from_problem(&p)?;
    let row = Row {
        spec,
        task: &task,
        iters,
        force,
        pb,
    };
    let mut runs = Vec::new();
    let mut shapes_svg = None;
    for (method, design, cage) in variants(spec) {
        let file = parts.join(format!("{}.json", slug(&method)));
        let shapes_rel = format!("plots/shapes_{}.svg", spec.name);
        if !force && let Some(run) = super::load_part::<_, CodesignRun>(&file, spec)? {
            if design && cage.is_none() {
                shapes_svg = kept_picture(&spec.name, &method, out_dir, shapes_rel, &file, pb);
            }
            eprintln!("{}: {method} finished earlier, kept", spec.name);
            pb.inc(iters as u64 + 1);
            runs.push(run);
            continue;
        }
        let q = method_problem(spec, &task, &p, design, cage)
            .with_context(|| format!("{}: {method}", spec.name))?;
        pb.set_message(format!("{}: {method}", spec.name));
        let t0 = Instant::now();
        let ckpt = parts.join(format!("{}.checkpoint.json", slug(&method)));
        let (out, resumed) = row
            .optimize(&q, design, &ckpt)
            .with_context(|| format!("{}: {method}", spec.name))?;
        // A resumed run's wall time is the sessions' sum (the history's
        // cumulative clock).
        let wall = match (resumed, out.history.last()) {
            (true, Some(last)) => last.wall_seconds,
            _ => t0.elapsed().as_secs_f64(),
        };
        if let Some(why) = &out.stopped {
            pb.suspend(|| eprintln!("warning: {}: {method}: the run {why}", spec.name));
        }
        if design && cage.is_none() && write_shapes(&q, &out.design, out_dir, &shapes_rel)? {
            shapes_svg = Some(shapes_rel);
        }
        let run = measure_run(&q, &method, &out, wall, metrics.as_ref())?;
        super::store_part(&file, spec, &run)?;
        runs.push(run);
    }
    Ok(CodesignPart {
        name: spec.name.clone(),
        task: spec.task.display().to_string(),
        horizon: p.first().horizon,
        iters,
        runs,
        fd,
        shapes_svg,
        unfinished: Vec::new(),
    })
}

/// The shapes picture of a co-design run kept from an earlier part, if it
/// is still at `out_dir/rel`. A part stores no design, so a missing
/// picture cannot be redrawn from it: the run says so instead of dropping
/// it silently.
fn kept_picture(
    name: &str,
    method: &str,
    out_dir: &Path,
    rel: String,
    part: &Path,
    pb: &ProgressBar,
) -> Option<String> {
    let svg = out_dir.join(&rel);
    if svg.is_file() {
        return Some(rel);
    }
    pb.suspend(|| {
        eprintln!(
            "warning: {name}: {method} kept from an earlier run, but {} is missing: \
             the report has no shapes picture (delete {} to re-run it)",
            svg.display(),
            part.display()
        )
    });
    None
}

/// The task at `task` with the design on or off, every trajectory's horizon
/// replaced by the suite entry's when it has one.
fn load_problem(spec: &CodesignSpec, task: &Path, design: bool) -> Result<Problem> {
    let mut p = Problem::load(task, design)?;
    if let Some(h) = spec.horizon {
        for t in &mut p.trajectories {
            t.horizon = h;
        }
    }
    Ok(p)
}

/// The problem a method optimizes: `p` itself (co-design), the task with
/// the design off (controller-only), or the task under IPC contact with
/// the design replaced by `cage`'s vertices (the mesh baseline).
fn method_problem(
    spec: &CodesignSpec,
    task: &Path,
    p: &Problem,
    design: bool,
    cage: Option<&str>,
) -> Result<Problem> {
    match cage {
        None if design => Ok(p.clone()),
        None => load_problem(spec, task, false),
        Some(c) => {
            let mut q = load_problem(spec, task, true)?;
            let ipc = crate::contact_model::ContactArgs {
                contact: Some("ipc".into()),
                ..Default::default()
            };
            crate::contact_model::configure_problem(&mut q, &ipc, Some(c), true)?;
            Ok(q)
        }
    }
}

/// The gradient check of a benchmark with a design (`spec.fd_check`): kept
/// from an earlier run's part, computed and stored otherwise.
fn gradient_check_part(
    spec: &CodesignSpec,
    p: &Problem,
    parts: &Path,
    force: bool,
    pb: &ProgressBar,
) -> Result<Option<FdCheck>> {
    if !spec.fd_check || p.design.is_empty() {
        return Ok(None);
    }
    pb.set_message(format!("{}: gradient check", spec.name));
    let file = parts.join("fd_check.json");
    let r = match super::load_part(&file, spec)?.filter(|_| !force) {
        Some(r) => r,
        None => {
            let r = fd_check(p).with_context(|| format!("{}: gradient check", spec.name))?;
            super::store_part(&file, spec, &r)?;
            r
        }
    };
    pb.inc(1);
    Ok(Some(r))
}

/// The initial and the optimized shapes side by side at `out_dir/rel`;
/// whether there was a picture to write.
fn write_shapes(
    p: &Problem,
    design: &nalgebra::DVector<f64>,
    out_dir: &Path,
    rel: &str,
) -> Result<bool> {
    let (d0, _) = sdrs::optimize::start(p, 0);
    let Some(svg) = sdrs::output::codesign::initial_vs_optimized_svg(p, &d0, design) else {
        return Ok(false);
    };
    std::fs::create_dir_all(out_dir.join("plots"))?;
    sdrs::output::write_atomic(&out_dir.join(rel), svg.as_bytes())?;
    Ok(true)
}

/// A method's row: its losses and times from the optimizer's history, and
/// the final design measured (minimum hull distance, the task's metrics,
/// grasps).
fn measure_run(
    p: &Problem,
    method: &str,
    out: &sdrs::optimize::Outcome,
    wall: f64,
    metrics: Option<&sdrs::optimize::metrics::Metrics>,
) -> Result<CodesignRun> {
    let n = out.history.len().max(1) as f64;
    let grasps = sdrs::optimize::grasp::measure(p, &out.design, &out.controller)?;
    let m = match metrics {
        Some(m) => Some(m.measure(p, &out.design, &out.controller)?),
        None => None,
    };
    Ok(CodesignRun {
        method: method.to_string(),
        design_variables: p.design.len(),
        controller_variables: p.controls.len(),
        initial_loss: out.initial_loss,
        final_loss: out.loss,
        history: out.history.iter().map(|h| h.best_loss).collect(),
        wall_seconds: wall,
        forward_seconds_mean: out.history.iter().map(|h| h.forward_seconds).sum::<f64>() / n,
        backward_seconds_mean: out.history.iter().map(|h| h.backward_seconds).sum::<f64>() / n,
        min_distance: min_distance(p, &out.design, &out.controller)?,
        distance: m.as_ref().map(|m| m.distance),
        upright_at_horizon: m.as_ref().map(|m| m.upright_at_horizon),
        first_fall_time: m.as_ref().and_then(|m| m.first_fall_time),
        grasped: (!grasps.is_empty()).then(|| grasps.iter().filter(|g| g.grasped).count()),
        grasp_trajectories: (!grasps.is_empty()).then_some(grasps.len()),
        stopped: out.stopped.clone(),
        ipc_hessian: ipc_hessian(p)?,
    })
}

/// `contact.ipc.hessian` of a mesh-baseline problem (its first trajectory's
/// scene; every trajectory of a run gets the same overrides), `None` under
/// SDRS contact.
fn ipc_hessian(p: &Problem) -> Result<Option<sdrs_ipc::settings::HessianKind>> {
    let scene = &p.first().scene;
    let Some(c) = scene.contact.as_ref() else {
        return Ok(None);
    };
    if c.model != sdrs::scene::schema::ContactModelKind::Ipc {
        return Ok(None);
    }
    let ipc = sdrs_ipc::settings::IpcSettings::of(c).map_err(|e| e.at(&scene.source))?;
    Ok(Some(ipc.hessian))
}

/// (method, design on, cage resolution) of a benchmark: SDRS with and
/// without the design, then the mesh baseline with each cage of the suite.
fn variants(spec: &CodesignSpec) -> Vec<(String, bool, Option<&str>)> {
    let mut v: Vec<(String, bool, Option<&str>)> = vec![
        ("co-design".into(), true, None),
        ("controller-only".into(), false, None),
    ];
    for c in &spec.cages {
        v.push((format!("mesh baseline, {c} cage"), true, Some(c.as_str())));
    }
    v
}

/// The finished methods (and gradient check) of a benchmark that has not
/// finished as a whole, for `--report-only`: the part (`None` when nothing
/// has finished) and the methods still missing.
pub fn finished(
    spec: &CodesignSpec,
    base_dir: &Path,
    out_dir: &Path,
) -> Result<(Option<CodesignPart>, Vec<String>)> {
    let parts = out_dir
        .join("parts")
        .join(format!("codesign_{}", spec.name));
    let mut runs = Vec::new();
    let mut missing = Vec::new();
    for (method, _, _) in variants(spec) {
        match super::load_part::<_, CodesignRun>(
            &parts.join(format!("{}.json", slug(&method))),
            spec,
        )? {
            Some(r) => runs.push(r),
            None => missing.push(method),
        }
    }
    let fd: Option<FdCheck> = super::load_part(&parts.join("fd_check.json"), spec)?;
    if runs.is_empty() && fd.is_none() {
        return Ok((None, missing));
    }
    let task = base_dir.join(&spec.task);
    let p = Problem::load(&task, true)?;
    let shapes = format!("plots/shapes_{}.svg", spec.name);
    Ok((
        Some(CodesignPart {
            name: spec.name.clone(),
            task: spec.task.display().to_string(),
            horizon: spec.horizon.unwrap_or(p.first().horizon),
            iters: spec.iters.unwrap_or(p.task.optimizer.iters),
            runs,
            fd,
            shapes_svg: out_dir.join(&shapes).is_file().then_some(shapes),
            unfinished: missing.clone(),
        }),
        missing,
    ))
}

/// What every method of one co-design row shares.
#[derive(Clone, Copy)]
struct Row<'a> {
    spec: &'a CodesignSpec,
    /// The task file (resolved against the suite's directory).
    task: &'a Path,
    iters: usize,
    /// `--force`: start afresh, ignoring checkpoints.
    force: bool,
    pb: &'a ProgressBar,
}

impl Row<'_> {
    /// One method's optimization, checkpointed after every iteration into
    /// `ckpt` (the suite entry without `iters`, the task's
    /// [`checkpoint::RunKey`] and the optimizer state), and resumed from there
    /// when the entry, the task and scene files and the design flag are those
    /// of the checkpoint and it is at most `iters` iterations in (otherwise, or
    /// with `--force`, it starts afresh): a mesh-baseline row that takes longer
    /// than a session continues where it stopped, bitwise as the uninterrupted
    /// run would (see [`sdrs::optimize::checkpoint`]), and a finished row can
    /// be continued to more iterations. The checkpoint is kept after the run.
    /// Returns the outcome and whether it was resumed.
    fn optimize(
        &self,
        p: &Problem,
        design: bool,
        ckpt: &Path,
    ) -> Result<(sdrs::optimize::Outcome, bool)> {
        let Row {
            spec,
            task,
            iters,
            force,
            pb,
        } = *self;
        let key = checkpoint::RunKey::new(task, &p.first().scene.source, design, 0)
            .with_context(|| format!("{}: cannot hash the task and scene", task.display()))?;
        // The entry without its iteration count: a run may be continued to more
        // iterations (as `sdrs optimize --resume`).
        let mut entry = serde_json::to_value(spec)?;
        if let Some(m) = entry.as_object_mut() {
            m.remove("iters");
        }
        let resume = if force {
            None
        } else {
            super::load_part::<_, (checkpoint::RunKey, checkpoint::State)>(ckpt, &entry)?
                .filter(|(k, s)| *k == key && s.iter <= iters)
                .map(|(_, s)| s)
        };
        if let Some(s) = &resume {
            pb.inc(s.iter as u64 + 1);
            pb.suspend(|| {
                eprintln!(
                    "{}: resuming after iteration {} ({})",
                    spec.name,
                    s.iter,
                    ckpt.display()
                )
            });
        }
        let resumed = resume.is_some();
        let opts = sdrs::optimize::RunOptions { seed: 0, resume };
        let out = sdrs::optimize::optimize_with(
            p,
            iters,
            &opts,
            |_, _| pb.inc(1),
            |state| {
                super::store_part(ckpt, &entry, &(&key, state)).map_err(|e| {
                    checkpoint::CheckpointError::Write {
                        path: ckpt.to_path_buf(),
                        msg: format!("{e:#}"),
                    }
                })
            },
        )?;
        Ok((out, resumed))
    }
}

/// A file name for a method ("mesh baseline, fine cage" → `mesh_baseline__fine_cage`).
fn slug(method: &str) -> String {
    method
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

/// The final design's trajectory: minimum hull distance (m).
fn min_distance(
    p: &Problem,
    d: &nalgebra::DVector<f64>,
    c: &nalgebra::DVector<f64>,
) -> Result<Option<f64>> {
    let t = p.first();
    let mut scene = t.scene.clone();
    scene.model = t.model.clone();
    p.design.apply(&mut scene.model, d);
    p.controls.apply(&mut scene.controller, c);
    let mut sim = t.simulator(&scene)?;
    let traj = sdrs::sim::run::run(&mut sim, t.horizon, |_| {})?;
    Ok(
        Summary::new("compare", scene.settings.dt, &traj, 0.0, vec![])
            .contact
            .min_distance,
    )
}

/// Newton tolerance of the gradient check's solves (every trajectory):
/// the check measures the adjoint, so the solver's own stopping error must
/// sit far below what the differences resolve. At a task's tolerance
/// (1e-6 for the biped, 1e-4 by default) the central differences of the
/// single jaw were 4e-2 off the adjoint; at 1e-10 the tests' checks agree
/// to 1e-6 and better (`tests/grasping.rs`, `tests/locomotion.rs`).
pub const FD_NEWTON_TOL: f64 = 1e-10;

/// Richardson-extrapolated central differences (`h = 1e-6 · max(1, |d_k|)`,
/// `(4 D(h) − D(2h)) / 3`) of the loss along the design variable whose
/// adjoint component is largest, at the initial design, every solve at
/// [`FD_NEWTON_TOL`], with the loss's noise measured along it
/// ([`sdrs::diff::central::check_component`], criterion 1e-4): 14 loss
/// evaluations. When that check does not pass resolved, the step halves
/// down to `1e-12 · max(1, |d_k|)` until two consecutive estimates agree
/// ([`sdrs::diff::descending`]: a loss smooth only below the first step,
/// e.g. a walk that falls; at most 62 evaluations), and the agreeing step
/// is reported with the first one.
fn fd_check(p: &Problem) -> Result<FdCheck> {
    let mut tight = p.clone();
    for t in &mut tight.trajectories {
        t.scene.settings.newton.tol = FD_NEWTON_TOL;
    }
    let p = &tight;
    let d0 = p.design.values(&p.first().model);
    let c0 = p.controls.values(&p.first().controller);
    let ev = p.evaluate(&d0, &c0)?;
    let k = ev.grad_design.iamax();
    let h = 1e-6 * d0[k].abs().max(1.0);
    let mut at = |s: f64| -> Result<f64> {
        let mut d = d0.clone();
        d[k] += s;
        Ok(p.evaluate(&d, &c0)?.loss)
    };
    let adj = ev.grad_design[k];
    let steps = Descent {
        h0: h,
        h_floor: 1e-12 * d0[k].abs().max(1.0),
    };
    let check = check_component_descending(&mut at, ev.loss, adj, steps, 1e-4)?;
    // The descended check stands only when it passed resolved.
    let c = check.standing();
    let descended_from = (c != &check.first).then(|| Descended {
        h: check.first.h,
        relative_error: check.first.relative_error,
        halvings: (check.first.h / c.h).log2().round() as usize,
    });
    Ok(FdCheck {
        variable: p.design.vars[k].name.clone(),
        adjoint: adj,
        central_difference: c.central,
        h: c.h,
        relative_error: c.relative_error,
        estimator: Some("richardson".into()),
        difference_noise: Some(c.central_noise),
        resolved: Some(c.resolved),
        newton_tol: Some(FD_NEWTON_TOL),
        descended_from,
    })
}
