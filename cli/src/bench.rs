//! `sdrs bench`: per-step cost of the rotating-chain scene against the
//! number of links per chain, with the stage breakdown.
//!
//! Each size is simulated twice: the ms/step comes from a run with the
//! evaluations untimed (as a user's run; the fastest of `--repeats` such
//! runs), the stage breakdown from a second, identical run with detailed timers (`StageTimers::set_detailed`), whose
//! clock readings add to its own time (`ms_per_step_detailed` in the JSON).

use anyhow::{Context, Result};
use sdrs::output::{Summary, write_atomic};
use sdrs::scene::Scene;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scene to benchmark; every robot with a `chain` gets `--links` links
    /// [default: the bundled robots/four_chains.yaml, found from the current
    /// directory or from the binary's location in a source tree].
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Links per chain, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "2,4,8,16,32")]
    pub links: Vec<usize>,
    /// Steps per measurement.
    #[arg(long, default_value_t = 200)]
    pub steps: usize,
    /// Timed runs per size (each the same trajectory from the scene's
    /// initial state); the fastest gives the ms/step. More than one makes the
    /// figure robust to interruptions by the rest of the machine.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeats: u32,
    /// Write the table as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Newton options overriding the scene's `solver`, as a YAML mapping,
    /// e.g. `--solver '{predictor: previous, indefinite: shift}'`.
    #[arg(long)]
    pub solver: Option<String>,
    #[command(flatten)]
    pub contact: crate::contact_model::ContactArgs,
}

pub fn run(a: BenchArgs) -> Result<()> {
    if cfg!(debug_assertions) {
        eprintln!("warning: debug build; benchmark with `cargo run --release -- bench`");
    }
    let path = match &a.scene {
        Some(s) => s.clone(),
        None => bundled_scene()?,
    };
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let mut base: sdrs::scene::SceneSpec =
        serde_yaml::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    if let Some(over) = &a.solver {
        base.solver = override_solver(&base.solver, over)?;
    }
    let mut rows = Vec::new();
    println!(
        "| links/chain | dof | ms/step | Newton it/step | eigen solves % | stage breakdown (ms/step, detailed run) |"
    );
    println!("|---:|---:|---:|---:|---:|---|");
    for &n in &a.links {
        let mut spec = base.clone();
        for r in &mut spec.robots {
            if let Some(c) = &mut r.chain {
                c.links = n;
            }
        }
        let mut scene = Scene::from_spec(spec, &path)?;
        a.contact.apply(&mut scene)?;
        let mut plain = timed_run(&scene, a.steps, false)?;
        for _ in 1..a.repeats {
            let again = timed_run(&scene, a.steps, false)?;
            if again.2 < plain.2 {
                plain = again;
            }
        }
        let (sim, traj, wall) = timed_run(&scene, a.steps, true)?;
        let s = Summary::new("bench", scene.settings.dt, &traj, wall, sim.timers.report());
        let ms_plain = 1e3 * plain.2 / a.steps as f64;
        let stages: Vec<String> = s
            .stages
            .iter()
            .map(|st| format!("{} {:.3}", st.stage, 1e3 * st.seconds / a.steps as f64))
            .collect();
        // Share of Newton iterations whose step needed an
        // eigendecomposition (a Hessian block with an eigenvalue ≤ clamp).
        let lin = sim.linear_solve_stats();
        let eigen_pct = 100.0 * lin.eigen_solves as f64 / lin.solves.max(1) as f64;
        println!(
            "| {n} | {} | {:.3} | {:.2} | {:.1} | {} |",
            scene.model.ndof(),
            ms_plain,
            s.newton.mean_iterations,
            eigen_pct,
            stages.join(", ")
        );
        rows.push(serde_json::json!({
            "links_per_chain": n, "dof": scene.model.ndof(), "ms_per_step": ms_plain,
            "ms_per_step_detailed": 1e3 * s.seconds_per_step,
            "newton_iterations_per_step": s.newton.mean_iterations, "stages": s.stages,
            "linear_solve": lin, "eigen_solve_percent": eigen_pct, "repeats": a.repeats,
        }));
    }
    if let Some(p) = &a.json {
        write_atomic(p, serde_json::to_string_pretty(&rows)?.as_bytes())?;
    }
    Ok(())
}

/// Simulates `steps` steps of `scene` from its initial state, the
/// evaluations timed by stage when `detailed`; returns the simulator, the
/// trajectory and the wall time (s).
fn timed_run(
    scene: &Scene,
    steps: usize,
    detailed: bool,
) -> Result<(sdrs::sim::Simulator, sdrs::sim::trajectory::Trajectory, f64)> {
    let mut sim = crate::contact_model::simulator(scene)?;
    sim.timers.set_detailed(detailed);
    let t0 = Instant::now();
    let traj = sdrs::sim::run::run(&mut sim, steps, |_| {})?;
    Ok((sim, traj, t0.elapsed().as_secs_f64()))
}

/// `base` with the keys of the YAML mapping `over` replaced.
fn override_solver(
    base: &sdrs::sim::NewtonOptions,
    over: &str,
) -> Result<sdrs::sim::NewtonOptions> {
    let mut v = serde_yaml::to_value(base)?;
    let o: serde_yaml::Value =
        serde_yaml::from_str(over).with_context(|| format!("--solver {over:?}: not YAML"))?;
    let (Some(vm), Some(om)) = (v.as_mapping_mut(), o.as_mapping()) else {
        anyhow::bail!("--solver {over:?}: expected a mapping such as '{{predictor: previous}}'");
    };
    for (k, x) in om {
        vm.insert(k.clone(), x.clone());
    }
    serde_yaml::from_value(v).with_context(|| format!("--solver {over:?}"))
}

/// `robots/four_chains.yaml` in the current directory or above the binary.
fn bundled_scene() -> Result<PathBuf> {
    crate::util::bundled("robots/four_chains.yaml")
        .map_err(|e| anyhow::anyhow!("{e}; pass --scene PATH"))
}
