//! `sdrs import INPUT --out DESIGN.yaml [...]`.

use super::decompose::Decomposer;
use super::mass::MassMode;
use super::write::{OutputPaths, check_outputs, write_outputs};
use super::{ImportOptions, import};
use std::path::PathBuf;

/// Import a robot (URDF + OBJ/STL meshes) or a bare mesh into a convex-hull
/// design space with connectivity constraints.
#[derive(clap::Args, Clone, Debug)]
pub struct ImportArgs {
    /// Input: `.urdf` (robot) or `.obj` / `.stl` (one free body).
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
    /// Designable links, comma-separated [default: all].
    #[arg(long, value_delimiter = ',')]
    pub designable: Option<Vec<String>>,
    /// Mass source: URDF `<mass>` (density fallback) or density × volume.
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
    /// Do not grow hulls to connect a link's separate hull groups.
    #[arg(long)]
    pub no_bridge: bool,
    /// No progress bar or summary.
    #[arg(long, short)]
    pub quiet: bool,
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
            designable: self.designable.clone(),
            mass: self.mass,
            density: self.density,
            bridge_gaps: !self.no_bridge,
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
    let imported = import(&args.input, &opts)?;
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
    }
    Ok(())
}
