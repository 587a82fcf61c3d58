//! The full tunnelling grid of issue 19, with and without continuous
//! collision detection: fast boxes against a 1 cm wall and a 2 mm plate
//! (20–100 m/s), a spinning bar against a post (10–100 rad/s), a whipped
//! chain, tumbling boxes dropped onto a thin plate, a prismatic slider and
//! a spherical arm, at dt 0.005 and 0.01. Every run is checked for
//! crossings (same-side check, `tests/common/tunnel.rs`); with `--fcl DIR`
//! every CCD run is also exported to `DIR/<case>` for
//! `tools/check/check_separation.py` (see `tools/bench/tunnel_grid.sh`).
//!
//! `cargo run --release --example tunnel_grid [-- --fcl DIR]`

#[path = "../tests/common/tunnel.rs"]
mod tunnel;

use sdrs::scene::Scene;
use std::path::{Path, PathBuf};

fn cases(ccd: bool) -> Vec<tunnel::Case> {
    let mut out = Vec::new();
    for dt in [0.005, 0.01] {
        for v in [20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0] {
            out.push(tunnel::shot(v, dt, 0.01, ccd));
            out.push(tunnel::shot(v, dt, 0.002, ccd));
        }
        for w in [10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0] {
            out.push(tunnel::spin(w, dt, ccd));
        }
        for w in [10.0, 20.0, 40.0, 60.0, 80.0] {
            out.push(tunnel::whip(w, dt, ccd));
        }
        for h in [1.0, 5.0, 20.0, 50.0, 100.0] {
            out.push(tunnel::drop(h, dt, ccd));
        }
        for v in [20.0, 50.0, 100.0] {
            out.push(tunnel::slider(v, dt, ccd));
        }
        for w in [20.0, 60.0, 100.0] {
            out.push(tunnel::spherical(w, dt, ccd));
        }
    }
    out
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let fcl: Option<PathBuf> = args
        .iter()
        .position(|a| a == "--fcl")
        .and_then(|i| args.get(i + 1))
        .map(PathBuf::from);
    println!(
        "| case | tunnels without CCD | tunnels with CCD | line-search cuts | CCD pairs advanced |"
    );
    println!("|---|---|---|---:|---:|");
    let (mut off_n, mut on_n, mut total) = (0, 0, 0);
    for (on, off) in cases(true).into_iter().zip(cases(false)) {
        total += 1;
        let mut res = Vec::new();
        for (case, export) in [(&off, None), (&on, fcl.as_ref().map(|d| d.join(&on.name)))] {
            let scene = Scene::from_str(&case.yaml, Path::new(&case.name)).expect("scene");
            let mut sim = scene.simulator();
            let traj = match sdrs::sim::run::run_recording(&mut sim, scene.steps, true, |_| {}) {
                Ok(t) => t,
                Err(e) => {
                    res.push((format!("error: {e}"), 0, 0));
                    continue;
                }
            };
            if let Some(dir) = export {
                std::fs::create_dir_all(&dir).expect("export dir");
                let excluded: Vec<(usize, usize)> = scene
                    .contact
                    .as_ref()
                    .map(|c| c.excluded.iter().copied().collect())
                    .unwrap_or_default();
                sdrs::output::export_run(&dir, &scene.model, excluded, &traj).expect("export");
            }
            let v = tunnel::side_violations(case, &scene.model, &traj.poses);
            let mut ccd = sdrs::contact::ccd::CcdStats::default();
            traj.diagnostics.iter().for_each(|d| ccd.merge(&d.ccd));
            res.push((
                if v.is_empty() {
                    "no".into()
                } else {
                    "**yes**".into()
                },
                ccd.alpha_caps,
                ccd.pairs_advanced,
            ));
        }
        off_n += usize::from(res[0].0 != "no");
        on_n += usize::from(res[1].0 != "no");
        println!(
            "| {} | {} | {} | {} | {} |",
            on.name, res[0].0, res[1].0, res[1].1, res[1].2
        );
    }
    println!();
    println!("{total} cases: {off_n} tunnel (or fail) without CCD, {on_n} with CCD");
    if on_n > 0 {
        std::process::exit(1);
    }
}
