//! The four rotating chains: ms/step of each contact model vs links per
//! chain, the stage breakdown, the SDRS adjoint over the same horizon, and
//! the minimum hull distance over every run, checked by python-fcl when it
//! is installed (`tools/check/check_separation.py`).

use super::results::{ChainRow, ChainsPart};
use super::suite::ChainsSpec;
use crate::contact_model::ContactArgs;
use anyhow::{Context, Result};
use indicatif::ProgressBar;
use sdrs::diff::{Loss, LossTerm, When, backward, record};
use sdrs::output::{Summary, export_run};
use sdrs::scene::{Scene, SceneSpec};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub fn run(
    spec: &ChainsSpec,
    base_dir: &Path,
    work: &Path,
    pb: &ProgressBar,
) -> Result<ChainsPart> {
    let t0 = Instant::now();
    let path = base_dir.join(&spec.scene);
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("{}: cannot read the chains scene", path.display()))?;
    let base: SceneSpec = serde_yaml::from_str(&text)
        .with_context(|| format!("{}: malformed scene", path.display()))?;
    pb.set_length((spec.links.len() * spec.models.len() * spec.repeats) as u64);
    let mut rows = Vec::new();
    // (row, export directory) of every run python-fcl is to check.
    let mut exports = Vec::new();
    let mut dt = 0.0;
    for &n in &spec.links {
        let mut s = base.clone();
        for r in &mut s.robots {
            if let Some(c) = &mut r.chain {
                c.links = n;
            }
        }
        let mut scenes = Vec::new();
        for model in &spec.models {
            let mut scene = Scene::from_spec(s.clone(), &path)?;
            ContactArgs {
                contact: Some(model.clone()),
                ..Default::default()
            }
            .apply(&mut scene)?;
            dt = scene.settings.dt;
            scenes.push(scene);
        }
        // The models alternate, `repeats` times; each keeps its fastest run,
        // so that a ratio is measured under the same machine load.
        let mut best: Vec<Option<ChainRow>> = vec![None; scenes.len()];
        for rep in 0..spec.repeats {
            for (k, model) in spec.models.iter().enumerate() {
                pb.set_message(format!("{model}, {n} links per chain, run {}", rep + 1));
                let (r, export) = one(&scenes[k], model, n, spec, work, rep == 0)?;
                if let Some(dir) = export {
                    exports.push((rows.len() + k, dir));
                }
                best[k] = Some(match best[k].take() {
                    None => r,
                    Some(b) if r.ms_per_step < b.ms_per_step => ChainRow {
                        backward_ms_per_step: b.backward_ms_per_step,
                        fcl_min_distance: b.fcl_min_distance,
                        fcl_note: b.fcl_note,
                        ..r
                    },
                    Some(b) => b,
                });
                pb.inc(1);
            }
        }
        rows.extend(best.into_iter().flatten());
    }
    fcl_check(&mut rows, &exports);
    Ok(ChainsPart {
        steps: spec.steps,
        repeats: spec.repeats,
        dt,
        rows,
        wall_seconds: t0.elapsed().as_secs_f64(),
    })
}

/// python-fcl's minimum distances of the exported runs, into their rows
/// (a note instead when a check failed): all in one Python process.
fn fcl_check(rows: &mut [ChainRow], exports: &[(usize, PathBuf)]) {
    if exports.is_empty() {
        return;
    }
    let dirs: Vec<PathBuf> = exports.iter().map(|(_, d)| d.clone()).collect();
    for ((i, _), r) in exports.iter().zip(super::fcl::check_all(&dirs)) {
        match r {
            Ok(d) => rows[*i].fcl_min_distance = d,
            Err(e) => rows[*i].fcl_note = Some(format!("{e:#}")),
        }
    }
}

/// One timed run of `model` with `n` links per chain; on the first
/// repetition with python-fcl requested, its states are exported and the
/// export directory returned (checked by [`fcl_check`] after every run).
fn one(
    scene: &Scene,
    model: &str,
    n: usize,
    spec: &ChainsSpec,
    work: &Path,
    first: bool,
) -> Result<(ChainRow, Option<PathBuf>)> {
    let steps = spec.steps;
    let mut sim = crate::contact_model::simulator(scene)?;
    sim.timers.set_detailed(true);
    let t0 = Instant::now();
    let traj = sdrs::sim::run::run_recording(&mut sim, steps, spec.fcl && first, |_| {})
        .with_context(|| format!("four chains, {model}, {n} links per chain"))?;
    let wall = t0.elapsed().as_secs_f64();
    let summary = Summary::new(
        "compare",
        scene.settings.dt,
        &traj,
        wall,
        sim.timers.report(),
    );
    let per_step = |s: f64| 1e3 * s / steps as f64;
    let stages: BTreeMap<String, f64> = summary
        .stages
        .iter()
        .map(|s| (s.stage.to_string(), per_step(s.seconds)))
        .collect();
    let backward_ms_per_step = if first && spec.backward && model == "sdrs" {
        let mut sim = scene.simulator();
        let tape = record(&mut sim, steps)?;
        let loss = Loss {
            terms: vec![LossTerm::Joint {
                dof: 0,
                target: 0.0,
                weight: 1.0,
                when: When::Final,
            }],
        };
        let g = backward(&mut sim, &tape, &loss)?;
        Some(per_step(g.seconds))
    } else {
        None
    };
    let (export, fcl_note) = if !first {
        (None, None)
    } else if spec.fcl {
        let dir = work.join(format!("chains_{model}_{n}"));
        std::fs::create_dir_all(&dir)?;
        let excluded = scene
            .contact
            .as_ref()
            .map(|c| c.excluded.iter().copied().collect::<Vec<_>>())
            .unwrap_or_default();
        export_run(&dir, &scene.model, excluded, &traj)?;
        (Some(dir), None)
    } else {
        (None, Some("not requested by the suite".into()))
    };
    let row = ChainRow {
        model: model.into(),
        links: n,
        dof: scene.model.ndof(),
        ms_per_step: 1e3 * summary.seconds_per_step,
        newton_iterations: summary.newton.mean_iterations,
        stages,
        backward_ms_per_step,
        steps_in_contact: summary.contact.steps_in_contact,
        min_distance: summary.contact.min_distance,
        fcl_min_distance: None,
        fcl_note,
    };
    Ok((row, export))
}
