//! `sdrs` command-line interface: parses the command line and dispatches to
//! one file per verb. Errors are reported with their full cause chain and
//! exit code 1; nothing here panics on bad input.

mod bench;
mod calibrate;
mod child;
mod compare;
mod contact_model;
mod export_mjcf;
mod helpers;
mod import;
mod optimize;
mod plot;
mod progress;
mod schema;
mod simulate;
mod util;
mod view;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "sdrs",
    version,
    about = "Shape-differentiable robot simulation (SDRS)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene file and write the trajectory and a summary.
    Simulate(simulate::SimulateArgs),
    /// Benchmarks (release builds): per-step cost of the rotating-chain scene.
    Bench(bench::BenchArgs),
    /// Co-design: optimize shape and controller of a task with adjoint gradients.
    Optimize(optimize::OptimizeArgs),
    /// Import a robot (URDF, MJCF, OBJ, STL or COLLADA) as a convex-hull design space.
    Import(import::ImportArgs),
    /// Write a scene's robots as MJCF for MuJoCo (same kinematics, masses and inertias).
    ExportMjcf(export_mjcf::ExportMjcfArgs),
    /// Calibration: name the physical effect missing from a scene, given measured data.
    Calibrate(calibrate::CalibrateArgs),
    /// Plot optimization runs together (e.g. co-design vs controller-only) from their output directories.
    Plot(plot::PlotArgs),
    /// SDRS vs the mesh-based IPC baseline on the paper's benchmarks: report and regression gate.
    Compare(compare::CompareArgs),
    /// Print the annotated schema of scene or task files (JSON Schema, as YAML or JSON).
    Schema(schema::SchemaArgs),
    /// Self-contained HTML viewer (or glTF binary) of a run, an optimization result or a scene.
    View(view::ViewArgs),
}

fn main() {
    let cli = Cli::parse();
    helpers::install();
    let res = match cli.command {
        Command::Simulate(a) => simulate::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Optimize(a) => optimize::run(a),
        Command::Import(a) => import::run(&a),
        Command::ExportMjcf(a) => export_mjcf::run(a),
        Command::Calibrate(a) => calibrate::run(&a),
        Command::Compare(a) => compare::run(a),
        Command::Plot(a) => plot::run(a),
        Command::Schema(a) => schema::run(a),
        Command::View(a) => view::run(a),
    };
    if let Err(e) = res {
        eprintln!("error: {}", cause_chain(&e));
        std::process::exit(1);
    }
}

/// The error and its causes, `: `-separated, each cause once: a cause whose
/// text the message already contains (errors that embed their source) is
/// not repeated.
fn cause_chain(e: &anyhow::Error) -> String {
    let mut msg = e.to_string();
    for c in e.chain().skip(1) {
        let s = c.to_string();
        if !msg.contains(&s) {
            msg.push_str(": ");
            msg.push_str(&s);
        }
    }
    msg
}
