//! `sdrs import INPUT --out DESIGN.yaml [...]`: the arguments, their mapping
//! onto the core's [`sdrs::import::ImportJob`], and the summary printed
//! after the run (the import itself is `sdrs::import`).
//!
//! The option enums are the core's; the `ValueEnum` types here mirror them
//! for clap (same variant names and help texts) and convert with `From`.

use crate::progress::Bar;
use anyhow::Result;
use clap::ValueEnum;
use sdrs::import::connectivity::Ties;
use sdrs::import::ready::BaseMode;
use sdrs::import::{Decomposer, HullPoints, ImportJob, ImportOptions, ImportReport, MassMode};
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
    #[arg(long, value_enum, default_value_t = DecomposerArg::Vhacd)]
    pub decomposer: DecomposerArg,
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
    #[arg(long, value_enum, default_value_t = HullPointsArg::Voxels)]
    pub hull_points: HullPointsArg,
    /// Designable links, comma-separated [default: all].
    #[arg(long, value_delimiter = ',')]
    pub designable: Option<Vec<String>>,
    /// Masses: `urdf` keeps each link's URDF `<inertial>` (mass, COM, inertia) as a `given`
    /// inertial (solid hulls at --density where there is none); `density` makes every link a
    /// `solid` (its hulls as uniform solids at --density).
    #[arg(long, value_enum, default_value_t = MassModeArg::Urdf)]
    pub mass: MassModeArg,
    /// Density (kg/m³) for `--mass density` and fallbacks.
    #[arg(long, default_value_t = 1000.0)]
    pub density: f64,
    /// Write the import report (JSON) here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Decomposition cache: reuse V-HACD results stored in this directory (same mesh, same
    /// decomposition options, same sdrs version) and store new ones there [default: none].
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Replace existing outputs.
    #[arg(long)]
    pub force: bool,
    /// Connectivity: `shared-vertex` ties each pair of touching or overlapping hulls
    /// through one auxiliary vertex (the paper's; grid blocks: face neighbours, at the
    /// centre of the common face); `corners` (grid only) ties every coincident block corner.
    #[arg(long, value_enum, default_value_t = TiesArg::SharedVertex)]
    pub ties: TiesArg,
    /// Do not grow hulls to connect a link's separate hull groups.
    #[arg(long)]
    pub no_bridge: bool,
    /// No progress bar or summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Base: `auto` floats the robot unless the input's root is static (massless or `world`
    /// URDF root, MJCF body without a free joint) or one chain hangs from it (an arm).
    #[arg(long, value_enum, default_value_t = BaseModeArg::Auto)]
    pub base: BaseModeArg,
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
    /// Write no holding PD gains (by default every joint holds its initial
    /// pose against gravity; joints an MJCF position or velocity actuator
    /// drives keep that actuator's gains either way).
    #[arg(long)]
    pub no_hold: bool,
    /// Initial pose: `joint=value,…` (rad or m); the PD targets hold it.
    #[arg(long, value_delimiter = ',', value_parser = parse_pose)]
    pub pose: Vec<(String, f64)>,
}

/// [`Decomposer`] on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DecomposerArg {
    Vhacd,
    Coacd,
    Hull,
    None,
    Grid,
}

impl From<DecomposerArg> for Decomposer {
    fn from(a: DecomposerArg) -> Self {
        match a {
            DecomposerArg::Vhacd => Decomposer::Vhacd,
            DecomposerArg::Coacd => Decomposer::Coacd,
            DecomposerArg::Hull => Decomposer::Hull,
            DecomposerArg::None => Decomposer::None,
            DecomposerArg::Grid => Decomposer::Grid,
        }
    }
}

/// [`HullPoints`] on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum HullPointsArg {
    /// The decomposer's own points (V-HACD: every surface voxel corner).
    Voxels,
    /// The source mesh's vertices, partitioned by the parts (module docs).
    Mesh,
}

impl From<HullPointsArg> for HullPoints {
    fn from(a: HullPointsArg) -> Self {
        match a {
            HullPointsArg::Voxels => HullPoints::Voxels,
            HullPointsArg::Mesh => HullPoints::Mesh,
        }
    }
}

/// [`MassMode`] on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MassModeArg {
    Urdf,
    Density,
}

impl From<MassModeArg> for MassMode {
    fn from(a: MassModeArg) -> Self {
        match a {
            MassModeArg::Urdf => MassMode::Urdf,
            MassModeArg::Density => MassMode::Density,
        }
    }
}

/// [`Ties`] on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum TiesArg {
    SharedVertex,
    Corners,
}

impl From<TiesArg> for Ties {
    fn from(a: TiesArg) -> Self {
        match a {
            TiesArg::SharedVertex => Ties::SharedVertex,
            TiesArg::Corners => Ties::Corners,
        }
    }
}

/// [`BaseMode`] on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BaseModeArg {
    /// Floating unless the input says the base is static (see module doc).
    Auto,
    /// Bolted to the world at the root joint's origin.
    Fixed,
    /// A free 6-DOF body.
    Floating,
}

impl From<BaseModeArg> for BaseMode {
    fn from(a: BaseModeArg) -> Self {
        match a {
            BaseModeArg::Auto => BaseMode::Auto,
            BaseModeArg::Fixed => BaseMode::Fixed,
            BaseModeArg::Floating => BaseMode::Floating,
        }
    }
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
    /// The import job these arguments select.
    pub fn job(&self) -> ImportJob {
        let decomposer = Decomposer::from(self.decomposer);
        let options = ImportOptions {
            decomposer,
            max_hulls: self.max_hulls.max(1),
            resolution: self.resolution,
            threshold: self
                .threshold
                .unwrap_or(ImportOptions::default_threshold(decomposer)),
            hull_points: self.hull_points.into(),
            designable: self.designable.clone(),
            mass: self.mass.into(),
            density: self.density,
            bridge_gaps: !self.no_bridge,
            ties: self.ties.into(),
            cache: self.cache.clone(),
            ..ImportOptions::default()
        };
        ImportJob {
            report: self.report.clone(),
            force: self.force,
            options,
            base: self.base.into(),
            ground: (self.ground || self.no_ground).then_some(self.ground),
            contact: !self.no_contact,
            hold: !self.no_hold,
            pose: self.pose.clone(),
            ..ImportJob::new(self.input.clone(), self.out.clone())
        }
    }
}

/// Runs `sdrs import`.
pub fn run(args: &ImportArgs) -> Result<()> {
    let bar = Bar::new(
        "decomposing {bar:30} {pos}/{len} links {msg}",
        2,
        args.quiet,
    );
    let report = sdrs::import::run_job_with(&args.job(), &bar)?;
    if !args.quiet {
        print_summary(&report, args);
    }
    Ok(())
}

/// The summary on stderr: links, hulls, coverage, masses, notes, base.
fn print_summary(r: &ImportReport, args: &ImportArgs) {
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
        for w in &ready.warnings {
            eprintln!("  warning: {w}");
        }
        if let Some(lift) = ready.ground_lift {
            eprintln!("  ground: robot lifted by {lift:.4} m onto the plane z = 0");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::str::FromStr;

    /// Every command-line value parses, through the core's `FromStr`, to the
    /// value the `From` mapping gives: the mirror enums and the core's
    /// names stay in step (a renamed or added variant fails here).
    #[test]
    fn command_line_names_are_the_core_names() {
        fn check<
            A: ValueEnum + Copy,
            C: FromStr<Err = String> + From<A> + PartialEq + std::fmt::Debug,
        >() {
            for a in A::value_variants() {
                let name = a
                    .to_possible_value()
                    .expect("a value")
                    .get_name()
                    .to_string();
                assert_eq!(C::from_str(&name), Ok(C::from(*a)), "{name}");
                assert_eq!(C::from_str(&name.to_uppercase()), Ok(C::from(*a)), "{name}");
            }
            assert!(C::from_str("no-such-value").is_err());
        }
        check::<DecomposerArg, Decomposer>();
        check::<HullPointsArg, HullPoints>();
        check::<MassModeArg, MassMode>();
        check::<TiesArg, Ties>();
        check::<BaseModeArg, BaseMode>();
    }
}
