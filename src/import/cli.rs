//! `sdrs import INPUT --out DESIGN.yaml [...]`.

use super::decompose::{Decomposer, HullPoints};
use super::mass::MassMode;
use super::ready::{BaseMode, ReadyOptions, make_ready};
use super::write::{OutputPaths, check_outputs, write_outputs};
use super::{ImportOptions, import};
use std::path::PathBuf;

/// Import a robot (URDF + OBJ/STL/DAE meshes, or MJCF compiled by MuJoCo) or
/// a bare mesh into a convex-hull design space with connectivity constraints.
#[derive(clap::Args, Clone, Debug)]
pub struct ImportArgs {
    /// Input: `.urdf` (robot), MJCF `.xml` (root element `<mujoco>`; compiled by the
    /// `mujoco` Python package) or `.obj` / `.stl` / `.dae` (one free body).
    pub input: PathBuf,
    /// Output design (scene YAML). Hull OBJs go to `<out stem>_meshes/`.
    #[arg(long)]
    pub out: PathBuf,
    /// Convex decomposition of mesh geometry.
    #[arg(long, value_enum, default_value_t = Decomposer::Vhacd)]
    pub decomposer: Decomposer,
    /// Most hulls per link.
    #[arg(long, default_value_t = 16)]
    pub max_hulls: usize,
    /// V-HACD voxel resolution (CoACD: 32× this many surface samples).
    #[arg(long, default_value_t = 64)]
    pub resolution: u32,
    /// Concavity threshold [default: 0.01 for vhacd, 0.05 for coacd].
    #[arg(long)]
    pub threshold: Option<f64>,
    /// Points spanning each V-HACD/CoACD part's hull: `voxels` (the decomposer's) or `mesh`
    /// (the source mesh's vertices, partitioned by the parts; a convex mesh stays one hull).
    #[arg(long, value_enum, default_value_t = HullPoints::Voxels)]
    pub hull_points: HullPoints,
    /// Designable links, comma-separated [default: all].
    #[arg(long, value_delimiter = ',')]
    pub designable: Option<Vec<String>>,
    /// Masses: `urdf` keeps each link's URDF `<inertial>` (mass, COM, inertia) as a `given`
    /// inertial (solid hulls at --density where there is none); `density` makes every link a
    /// `solid` (its hulls as uniform solids at --density).
    #[arg(long, value_enum, default_value_t = MassMode::Urdf)]
    pub mass: MassMode,
    /// Density (kg/m³) for `--mass density` and fallbacks.
    #[arg(long, default_value_t = 1000.0)]
    pub density: f64,
    /// Write the import report (JSON) here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Replace existing outputs.
    #[arg(long)]
    pub force: bool,
    /// Connectivity: `shared-vertex` ties each pair of touching or overlapping hulls
    /// through one auxiliary vertex (the paper's; grid blocks: face neighbours, at the
    /// centre of the common face); `corners` (grid only) ties every coincident block corner.
    #[arg(long, value_enum, default_value_t = super::connectivity::Ties::SharedVertex)]
    pub ties: super::connectivity::Ties,
    /// Do not grow hulls to connect a link's separate hull groups.
    #[arg(long)]
    pub no_bridge: bool,
    /// No progress bar or summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Base: `auto` floats the robot unless the input's root is static (massless or `world`
    /// URDF root, MJCF body without a free joint) or one chain hangs from it (an arm).
    #[arg(long, value_enum, default_value_t = BaseMode::Auto)]
    pub base: BaseMode,
    /// Add a ground plane and place the robot on it, whatever the base [default: only
    /// when the base floats and the input has no ground].
    #[arg(long)]
    pub ground: bool,
    /// No ground, even under a floating base.
    #[arg(long, conflicts_with = "ground")]
    pub no_ground: bool,
    /// Leave contact off (by default it is on, with exclusions for link
    /// pairs that overlap in the initial pose, listed in the report).
    #[arg(long)]
    pub no_contact: bool,
    /// Write no PD gains (by default every joint holds its initial pose
    /// against gravity).
    #[arg(long)]
    pub no_hold: bool,
    /// Initial pose: `joint=value,…` (rad or m); the PD targets hold it.
    #[arg(long, value_delimiter = ',', value_parser = parse_pose)]
    pub pose: Vec<(String, f64)>,
}

fn parse_pose(s: &str) -> Result<(String, f64), String> {
    let (j, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected joint=value, got \"{s}\""))?;
    let v: f64 = v
        .trim()
        .parse()
        .map_err(|_| format!("\"{v}\" is not a number (in \"{s}\")"))?;
    Ok((j.trim().to_string(), v))
}

impl ImportArgs {
    /// The import options these arguments select.
    pub fn options(&self) -> ImportOptions {
        let d = ImportOptions::default();
        ImportOptions {
            decomposer: self.decomposer,
            max_hulls: self.max_hulls.max(1),
            resolution: self.resolution,
            threshold: self.threshold.unwrap_or(match self.decomposer {
                Decomposer::Coacd => 0.05,
                _ => d.threshold,
            }),
            hull_points: self.hull_points,
            designable: self.designable.clone(),
            mass: self.mass,
            density: self.density,
            bridge_gaps: !self.no_bridge,
            ties: self.ties,
            progress: !self.quiet,
            ..d
        }
    }
}

/// Runs the import command.
pub fn run_import(args: &ImportArgs) -> anyhow::Result<()> {
    let opts = args.options();
    anyhow::ensure!(
        opts.density > 0.0 && opts.density.is_finite(),
        "--density must be positive, got {}",
        opts.density
    );
    anyhow::ensure!(opts.resolution >= 8, "--resolution must be at least 8");
    anyhow::ensure!(
        opts.threshold > 0.0 && opts.threshold <= 1.0,
        "--threshold must be in (0, 1], got {}",
        opts.threshold
    );
    let paths = OutputPaths::new(&args.out, args.report.as_deref());
    check_outputs(&args.input, &paths, args.force)?;
    let mut imported = import(&args.input, &opts)?;
    let ready_opts = ReadyOptions {
        base: args.base,
        ground: (args.ground || args.no_ground).then_some(args.ground),
        contact: !args.no_contact,
        hold: !args.no_hold,
        pose: args.pose.iter().cloned().collect(),
        mu: imported.friction,
    };
    let ready = make_ready(
        &mut imported.scene,
        &args.input,
        imported.root_static,
        &ready_opts,
    )?;
    imported.report.ready = Some(ready);
    write_outputs(&imported, &args.input, &paths, args.force)?;
    if !args.quiet {
        let r = &imported.report;
        eprintln!(
            "imported {} ({} links, {} hulls, {} vertices) in {:.2} s → {}",
            r.robot,
            r.links.len(),
            r.total_hulls,
            r.total_vertices,
            r.seconds,
            args.out.display()
        );
        for l in &r.links {
            eprintln!(
                "  {:<24} {:>3} hulls {:>5} vertices  coverage {:>6.2}%  mass {:.4} kg",
                l.name,
                l.hulls,
                l.vertices,
                100.0 * l.coverage,
                l.mass
            );
        }
        if !r.disconnected_links.is_empty() {
            eprintln!("  not connected: {}", r.disconnected_links.join(", "));
        }
        for n in &r.notes {
            eprintln!("  note: {n}");
        }
        if let Some(ready) = &r.ready {
            eprintln!("  base: {}", ready.base);
            if !ready.excluded_pairs.is_empty() {
                eprintln!(
                    "  contact: {} link pairs overlap in the initial pose and are excluded (see the report)",
                    ready.excluded_pairs.len()
                );
            }
            if let Some(lift) = ready.ground_lift {
                eprintln!("  ground: robot lifted by {lift:.4} m onto the plane z = 0");
            }
        }
    }
    Ok(())
}
