//! `sdrs view`: one self-contained HTML file that plays back a run (or a
//! `.glb` of it), from
//!
//! - a `simulate --export DIR` directory (`hulls.json`, `poses.csv`, and
//!   `contacts.csv` with `--planes`);
//! - an `optimize` output directory (`playback/`: the initial and the
//!   optimized design's rollouts side by side, and the designed links'
//!   hulls at every iteration);
//! - a scene YAML: simulated first (`--steps`, default the scene's), with
//!   contact planes.
//!
//! The page is built by [`page`]; the glTF binary by
//! [`sdrs::output::gltf`].

mod page;

use crate::util::{progress, same_file};
use anyhow::{Context, Result, bail};
use sdrs::output::contacts::active_contacts;
use sdrs::output::playback::{Playback, pose_trs};
use sdrs::output::write_atomic;
use serde_json::Value;
use std::path::{Path, PathBuf};

pub use page::MARKER;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Self-contained HTML viewer (three.js inlined).
    Html,
    /// glTF 2.0 binary: one node per link, a translation + rotation animation per node.
    Glb,
}

#[derive(clap::Args)]
pub struct ViewArgs {
    /// `simulate --export` directory, `optimize` output directory, or a
    /// scene YAML (simulated first).
    pub input: PathBuf,
    /// Output file (`view.html`, or `robot.glb` with `--format glb`).
    #[arg(long)]
    pub out: PathBuf,
    /// Output format (default: `glb` when `--out` ends in `.glb`, else `html`).
    #[arg(long, value_enum)]
    pub format: Option<Format>,
    /// Steps to simulate when the input is a scene (default: the scene's `steps`).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Overwrite an existing output file that `sdrs view` did not write.
    #[arg(long)]
    pub force: bool,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

/// What the input holds.
enum Input {
    Run(Playback),
    Optimize {
        initial: Playback,
        optimized: Playback,
        iterations: Vec<Value>,
    },
}

pub fn run(a: ViewArgs) -> Result<()> {
    let format = a.format.unwrap_or(
        if a.out
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("glb"))
        {
            Format::Glb
        } else {
            Format::Html
        },
    );
    if same_file(&a.out, &a.input)
        || a.out.starts_with(&a.input) && a.input.is_dir() && {
            let n = a.out.file_name().map(|n| n.to_string_lossy().into_owned());
            matches!(
                n.as_deref(),
                Some("hulls.json" | "poses.csv" | "contacts.csv")
            )
        }
    {
        bail!("{}: refusing to overwrite an input file", a.out.display());
    }
    check_overwrite(&a.out, a.force)?;
    let title = a.input.file_name().map_or_else(
        || a.input.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let input = load(&a.input, a.steps, a.quiet)?;
    let bytes = match (&input, format) {
        (Input::Run(p), Format::Glb) => sdrs::output::gltf::glb(p),
        (Input::Optimize { optimized, .. }, Format::Glb) => sdrs::output::gltf::glb(optimized),
        (Input::Run(p), Format::Html) => run_html(&title, p).into_bytes(),
        (
            Input::Optimize {
                initial,
                optimized,
                iterations,
            },
            Format::Html,
        ) => optimize_html(&title, initial, optimized, iterations.clone()).into_bytes(),
    };
    write_atomic(&a.out, &bytes)?;
    eprintln!(
        "{}: {} ({:.1} MB)",
        a.out.display(),
        match format {
            Format::Html => "viewer, open it in a browser",
            Format::Glb => "glTF binary",
        },
        bytes.len() as f64 / 1e6
    );
    Ok(())
}

/// Refuses to replace a file `sdrs view` did not write (unless `force`).
pub fn check_overwrite(out: &Path, force: bool) -> Result<()> {
    if force || !out.exists() {
        return Ok(());
    }
    let bytes = std::fs::read(out).unwrap_or_default();
    let ours = bytes.starts_with(MARKER.as_bytes())
        || (bytes.starts_with(b"glTF") && bytes.len() >= 20 && {
            let n = u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) as usize;
            let js = &bytes[20..(20 + n).min(bytes.len())];
            String::from_utf8_lossy(js).contains("\"generator\":\"sdrs ")
        });
    if !ours {
        bail!(
            "{}: exists and was not written by `sdrs view` (use --force to overwrite it)",
            out.display()
        );
    }
    Ok(())
}

/// The viewer HTML of one run.
pub fn run_html(title: &str, p: &Playback) -> String {
    page::html(
        title,
        "simulate",
        &[page::SceneData {
            label: title.to_string(),
            playback: p,
            offset: [0.0; 3],
        }],
        Vec::new(),
        0,
    )
}

/// Simulates a scene with link poses recorded, and the contact planes of
/// every recorded state.
pub fn simulate_playback(scene_path: &Path, steps: Option<usize>, quiet: bool) -> Result<Playback> {
    let scene = sdrs::scene::Scene::load(scene_path)?;
    let steps = steps.unwrap_or(scene.steps);
    let mut sim = crate::contact_model::simulator(&scene)?;
    let pb = progress(steps, quiet);
    let traj = sdrs::sim::run::run_recording(&mut sim, steps, true, |k| pb.set_position(k as u64))
        .with_context(|| format!("simulating {}", scene_path.display()))?;
    pb.finish_and_clear();
    playback_of_run(&scene, &traj)
}

/// The playback of a recorded run, with contact planes when the scene has contact.
pub fn playback_of_run(
    scene: &sdrs::scene::Scene,
    traj: &sdrs::output::Trajectory,
) -> Result<Playback> {
    let contacts = match &scene.contact {
        Some(c) => active_contacts(&scene.model, c.s, &c.excluded, &traj.poses)?,
        None => Vec::new(),
    };
    Ok(Playback::from_run(&scene.model, traj, contacts))
}

fn load(input: &Path, steps: Option<usize>, quiet: bool) -> Result<Input> {
    if input.is_file() {
        return Ok(Input::Run(simulate_playback(input, steps, quiet)?));
    }
    if input.join("hulls.json").is_file() {
        return Ok(Input::Run(Playback::load_export(input)?));
    }
    let pb = input.join("playback");
    if pb.is_dir() {
        let initial = Playback::load_export(&pb.join("initial"))?;
        let optimized = Playback::load_export(&pb.join("optimized"))?;
        let it_path = pb.join("iterations.json");
        let text = std::fs::read_to_string(&it_path)
            .with_context(|| format!("{}: cannot read", it_path.display()))?;
        let v: Value = serde_json::from_str(&text)
            .with_context(|| format!("{}: not valid JSON", it_path.display()))?;
        let iterations = iterations_json(&v, initial.links.len())
            .map_err(|m| anyhow::anyhow!("{}: {m}", it_path.display()))?;
        return Ok(Input::Optimize {
            initial,
            optimized,
            iterations,
        });
    }
    if !input.exists() {
        bail!("{}: no such file or directory", input.display());
    }
    bail!(
        "{}: neither a scene file, a `simulate --export` directory (hulls.json, poses.csv) nor an `optimize` output directory (playback/)",
        input.display()
    )
}

/// `playback/iterations.json` (written by `sdrs optimize`: `{iterations:
/// [{iteration, loss, links: {index: [[[x, y, z], …], …]}}]}`) → the page's
/// `iterations`, hulls triangulated.
fn iterations_json(v: &Value, n_links: usize) -> Result<Vec<Value>, String> {
    let its = v["iterations"]
        .as_array()
        .ok_or("`iterations` is not a list")?;
    let mut out = Vec::new();
    for (k, it) in its.iter().enumerate() {
        let mut links = serde_json::Map::new();
        let obj = it["links"]
            .as_object()
            .ok_or(format!("iterations[{k}].links is not a map"))?;
        for (li, hulls) in obj {
            let idx: usize = li
                .parse()
                .ok()
                .filter(|&i| i < n_links)
                .ok_or(format!("iterations[{k}].links: `{li}` is not a link index"))?;
            let hulls: Vec<Vec<[f64; 3]>> = serde_json::from_value(hulls.clone())
                .map_err(|e| format!("iterations[{k}].links.{li}: {e}"))?;
            links.insert(
                idx.to_string(),
                hulls.iter().map(|h| page::hull_json(h)).collect(),
            );
        }
        let poses: Vec<[f64; 7]> = serde_json::from_value(it["poses"].clone())
            .map_err(|e| format!("iterations[{k}].poses: {e}"))?;
        if poses.len() != n_links {
            return Err(format!(
                "iterations[{k}].poses: {} poses for {n_links} links",
                poses.len()
            ));
        }
        out.push(serde_json::json!({
            "iteration": it["iteration"],
            "loss": it["loss"],
            "links": links,
            "poses": poses,
        }));
    }
    Ok(out)
}

/// x extent (m) of the robots' hulls (not the environment) over a run.
fn x_extent(p: &Playback) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for poses in &p.poses {
        for (l, a) in p.links.iter().zip(poses) {
            if l.robot == sdrs::scene::environment::ENVIRONMENT {
                continue;
            }
            let (t, _) = pose_trs(a);
            let r = a.fixed_view::<3, 3>(0, 0);
            for h in &l.hulls {
                for x in h {
                    let y = (r * nalgebra::Vector3::from(*x))[0] + t[0];
                    lo = lo.min(y);
                    hi = hi.max(y);
                }
            }
        }
    }
    if lo.is_finite() { (lo, hi) } else { (0.0, 0.0) }
}

/// Initial and optimized rollouts side by side (along x, 1.3 × the wider
/// one's swept x extent apart), and the design at any iteration (third,
/// at the initial pose).
fn optimize_html(
    title: &str,
    initial: &Playback,
    optimized: &Playback,
    iterations: Vec<Value>,
) -> String {
    let w = [x_extent(initial), x_extent(optimized)]
        .iter()
        .map(|(a, b)| b - a)
        .fold(0.0, f64::max)
        .max(0.2)
        * 1.3;
    let rest = Playback {
        links: initial.links.clone(),
        times: initial.times[..1.min(initial.times.len())].to_vec(),
        poses: initial.poses[..1.min(initial.poses.len())].to_vec(),
        contacts: Vec::new(),
    };
    let mut scenes = vec![
        page::SceneData {
            label: "initial".into(),
            playback: initial,
            offset: [0.0; 3],
        },
        page::SceneData {
            label: "optimized".into(),
            playback: optimized,
            offset: [w, 0.0, 0.0],
        },
    ];
    if !iterations.is_empty() {
        scenes.push(page::SceneData {
            label: "iteration".into(),
            playback: &rest,
            offset: [2.0 * w, 0.0, 0.0],
        });
    }
    page::html(title, "optimize", &scenes, iterations, 2)
}

/// Writes the viewer of a run to `out` (for `simulate --view`).
pub fn write_run_viewer(out: &Path, title: &str, p: &Playback) -> Result<()> {
    check_overwrite(out, false)?;
    write_atomic(out, run_html(title, p).as_bytes())?;
    Ok(())
}
