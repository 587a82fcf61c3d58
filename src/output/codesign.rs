//! What `sdrs view` and the report show of an optimization: the rollouts
//! of the initial and the optimized design over the task horizon (link
//! poses and contact planes), the designed links' hulls at every
//! iteration, a still of the whole robot (initial vs optimized, at `t = 0`
//! and at the horizon) and the designed links' shapes (`shapes.svg`),
//! rendered in Rust. The optimizer (`crate::optimize`) returns data; this
//! module turns it into files and pictures.
//!
//! Files (in the output directory): `playback/initial/` and
//! `playback/optimized/` in the layout of `sdrs simulate --export DIR
//! --planes` (`hulls.json`, `poses.csv`, `contacts.csv`), and
//! `playback/iterations.json` = `{iterations: [{iteration, loss, links:
//! {link index: [hull vertex lists (link frame, m)]}, poses: [[tx, ty, tz,
//! qx, qy, qz, qw] per link]}]}`: the designed links' hulls and every
//! link's pose at `t = 0` (attachment variables move links). The rollouts
//! are extra forward simulations after the run; they do not touch the
//! optimization.

use super::contacts::{ContactsError, active_contacts, contacts_csv};
use super::picture::{Panel, PictureOptions, render_hulls_svg};
use super::playback::Playback;
use crate::files::{OutputError, write_atomic};
use crate::optimize::{OptimizeError, Problem};
use crate::scene::environment::ENVIRONMENT;
use nalgebra::DVector;
use std::path::Path;

/// One recorded iteration: number, loss and design vector.
pub type IterDesign = (usize, f64, DVector<f64>);

/// Why a rollout or a picture of an optimization could not be made.
#[derive(Debug, thiserror::Error)]
pub enum CodesignOutputError {
    /// The rollout's scene or simulator could not be built.
    #[error(transparent)]
    Optimize(#[from] OptimizeError),
    /// A step of the rollout failed.
    #[error(transparent)]
    Step(#[from] crate::sim::StepError),
    /// The contacts of a rollout could not be recorded.
    #[error(transparent)]
    Contacts(#[from] ContactsError),
    /// A file could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Serializing an output (`what`) failed.
    #[error("{what}: {msg}")]
    Serialize { what: String, msg: String },
}

fn serialize(what: &str, e: serde_json::Error) -> CodesignOutputError {
    CodesignOutputError::Serialize {
        what: what.into(),
        msg: e.to_string(),
    }
}

/// Simulates design `d` with controller `c` over the horizon of the (first)
/// trajectory, recording link poses and contact planes.
pub fn rollout(
    p: &Problem,
    d: &DVector<f64>,
    c: &DVector<f64>,
) -> Result<Playback, CodesignOutputError> {
    let t = p.first();
    let scene = p.scene_at(t, d, c);
    let mut sim = t.simulator(&scene)?;
    let traj = crate::sim::run::run_recording(&mut sim, t.horizon, true, |_| {})?;
    let contacts = match &scene.contact {
        Some(cs) => active_contacts(&scene.model, cs.s, &cs.excluded, &traj.poses)?,
        None => Vec::new(),
    };
    Ok(Playback::from_run(&scene.model, &traj, contacts))
}

/// Writes `dir/playback/` (see the module docs).
pub fn write_playback(
    dir: &Path,
    p: &Problem,
    initial: &Playback,
    optimized: &Playback,
    iterations: &[IterDesign],
) -> Result<(), CodesignOutputError> {
    let pb = dir.join("playback");
    for (name, run) in [("initial", initial), ("optimized", optimized)] {
        let d = pb.join(name);
        let hulls = super::HullExport {
            links: run.links.clone(),
            excluded_pairs: Vec::new(),
        };
        write_atomic(
            &d.join("hulls.json"),
            serde_json::to_string(&hulls)
                .map_err(|e| serialize("hulls.json", e))?
                .as_bytes(),
        )?;
        let traj = super::Trajectory {
            times: run.times.clone(),
            poses: run.poses.clone(),
            ..Default::default()
        };
        write_atomic(
            &d.join("poses.csv"),
            super::poses_csv(&traj, &p.first().model).as_bytes(),
        )?;
        write_atomic(
            &d.join("contacts.csv"),
            contacts_csv(&run.contacts).as_bytes(),
        )?;
    }
    let its: Vec<serde_json::Value> = iterations
        .iter()
        .map(|(k, loss, d)| iteration_json(p, *k, *loss, d))
        .collect();
    write_atomic(
        &pb.join("iterations.json"),
        serde_json::to_string(&serde_json::json!({ "iterations": its }))
            .map_err(|e| serialize("iterations.json", e))?
            .as_bytes(),
    )?;
    Ok(())
}

/// One entry of `iterations.json`: iteration `k`, its `loss`, the designed
/// links' hulls at design `d` and every link's pose at `t = 0`.
fn iteration_json(p: &Problem, k: usize, loss: f64, d: &DVector<f64>) -> serde_json::Value {
    let mut m = p.first().model.clone();
    p.design.apply(&mut m, d);
    let hulls: serde_json::Map<String, serde_json::Value> = p
        .design
        .designed_links()
        .iter()
        .map(|&l| {
            let h: Vec<Vec<[f64; 3]>> = m.links[l]
                .hulls
                .iter()
                .map(|h| h.x_local.iter().map(|x| [x.x, x.y, x.z]).collect())
                .collect();
            (l.to_string(), serde_json::json!(h))
        })
        .collect();
    // Link poses at t = 0 of this design (attachments move links).
    let mut scene = p.first().scene.clone();
    scene.model = m;
    let poses: Vec<_> = scene
        .simulator()
        .state
        .poses
        .iter()
        .map(|a| {
            let (t, q) = super::playback::pose_trs(a);
            [t[0], t[1], t[2], q[0], q[1], q[2], q[3]]
        })
        .collect();
    serde_json::json!({"iteration": k, "loss": loss, "links": hulls, "poses": poses})
}

/// World-frame hulls of the robots (not the environment) at recorded state `k`.
fn world_hulls(run: &Playback, k: usize) -> Vec<Vec<nalgebra::Vector3<f64>>> {
    let mut out = Vec::new();
    for (l, a) in run.links.iter().zip(&run.poses[k]) {
        if l.robot == ENVIRONMENT {
            continue;
        }
        for h in &l.hulls {
            out.push(
                h.iter()
                    .map(|x| crate::math::transform_point(a, &nalgebra::Vector3::from(*x)))
                    .collect(),
            );
        }
    }
    out
}

/// `robot.svg`: the whole robot, initial (grey) vs optimized (blue), at
/// `t = 0` (top row) and at the horizon (bottom row), one scale per row
/// ([`render_hulls_svg`]).
pub fn robot_still_svg(initial: &Playback, optimized: &Playback) -> Option<String> {
    if initial.poses.is_empty() || optimized.poses.is_empty() {
        return None;
    }
    let mut panels = Vec::new();
    for (at_end, when) in [(false, "t = 0"), (true, "horizon")] {
        for (run, what, color) in [
            (initial, "initial", [170, 170, 170]),
            (optimized, "optimized", [90, 150, 220]),
        ] {
            let k = if at_end { run.poses.len() - 1 } else { 0 };
            panels.push(Panel {
                title: format!("{what}, {when} ({:.2} s)", run.times[k] - run.times[0]),
                hulls: world_hulls(run, k),
                color,
            });
        }
    }
    Some(render_hulls_svg(&panels, &PictureOptions::default()))
}

/// `shapes.svg`: the designed links' hulls before and after optimization,
/// one row per link (initial left, optimized right, same scale), drawn by
/// [`render_hulls_svg`] in each link's own frame; `None` when nothing is
/// designed.
pub fn initial_vs_optimized_svg(
    p: &Problem,
    initial: &DVector<f64>,
    optimized: &DVector<f64>,
) -> Option<String> {
    let links = p.design.designed_links();
    if links.is_empty() {
        return None;
    }
    let model = &p.first().model;
    let (mut m0, mut m1) = (model.clone(), model.clone());
    p.design.apply(&mut m0, initial);
    p.design.apply(&mut m1, optimized);
    let mut panels = Vec::new();
    for &l in &links {
        let name = format!(
            "{}/{}",
            model.robots[model.links[l].robot].name, model.links[l].name
        );
        for (m, what, color) in [
            (&m0, "initial", [170, 170, 170]),
            (&m1, "optimized", [90, 150, 220]),
        ] {
            panels.push(Panel {
                title: format!("{name} ({what})"),
                hulls: m.links[l].hulls.iter().map(|h| h.x_local.clone()).collect(),
                color,
            });
        }
    }
    Some(render_hulls_svg(&panels, &PictureOptions::default()))
}
