//! Import: URDF / OBJ / STL / COLLADA robots → convex-hull design spaces with
//! connectivity constraints (paper, `shape.tex`: "users may supply
//! mesh-based link representations, which we convert to our parametric form
//! using approximate convex decomposition; we then insert connectivity
//! constraints").
//!
//! Pipeline ([`import`]): read the input ([`urdf`], or a bare mesh: one free
//! body) → per link, turn every geometry into hulls ([`primitives`], or
//! [`mesh`] + [`decompose`]) → [`connectivity`] (shared vertices inside
//! hull intersections, attachment points) → [`mass`] → [`report`] → a scene
//! (`version: 1`, one robot, `design:` section with the ties). [`write`]
//! puts the scene, an OBJ per link and the report on disk atomically; [`job`]
//! is one whole run (`sdrs import`).

// Comparisons are written `!(x > 0.0)` on purpose: they reject NaN too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod assemble;
pub mod cache;
pub mod collada;
pub mod connectivity;
pub mod decompose;
pub mod error;
pub mod fkcheck;
pub mod grid;
pub mod guard;
pub mod interior;
pub mod job;
pub mod limits;
mod link_geometry;
pub mod mass;
pub mod mesh;
pub mod mjcf;
pub use crate::math::polytope;
pub mod primitives;
pub mod pybullet_shapes;
pub mod python;
pub mod ready;
pub mod report;
pub mod source;
pub mod tolerant;
pub mod urdf;
pub mod write;

pub use decompose::{Decomposer, HullPoints};
pub use error::ImportError;
pub use job::{ImportJob, run_job, run_job_with};
pub use mass::MassMode;
pub use report::ImportReport;

use crate::progress::Progress;
use crate::scene::schema::*;
use link_geometry::{LinkGeometry, link_geometry};
use mesh::TriMesh;
use nalgebra::Vector3;
use rayon::prelude::*;
use source::SourceRobot;
use std::path::Path;
use std::time::Instant;

/// Every import setting, with its default.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportOptions {
    /// Decomposition of mesh geometry. Default `vhacd`. Primitives (box,
    /// cylinder, sphere, capsule) are always one hull each.
    pub decomposer: Decomposer,
    /// Most hulls per link (split evenly over the link's meshes, at least
    /// one each). Default 16.
    pub max_hulls: usize,
    /// V-HACD voxel resolution (voxels along the longest side). Default 64.
    /// CoACD gets `32 × resolution` surface samples (its `resolution`).
    pub resolution: u32,
    /// Concavity threshold (V-HACD `concavity`, CoACD `threshold`).
    /// Default 0.01 for V-HACD; CoACD's own default is 0.05.
    pub threshold: f64,
    /// Points spanning each V-HACD/CoACD part's hull: the decomposer's
    /// (default `voxels`) or the source mesh's vertices (`mesh`; see
    /// [`decompose`]'s module docs).
    pub hull_points: decompose::HullPoints,
    /// Links whose hulls are design variables; `None` = all (default).
    pub designable: Option<Vec<String>>,
    /// Mass assignment. Default `urdf` (with density fallback).
    pub mass: MassMode,
    /// Density (kg/m³) for `density` masses and fallbacks. Default 1000.
    pub density: f64,
    /// Edge (m) of the cube standing in for a link without geometry that
    /// cannot be merged. Default 0.01.
    pub tiny_hull_size: f64,
    /// Connect a link's separate hull groups by growing the closest pair
    /// (reported). Default true.
    pub bridge_gaps: bool,
    /// Which vertices are tied ([`connectivity::Ties`]). Default
    /// `shared_vertex` (the paper's one auxiliary vertex per touching or
    /// overlapping pair); `corners` only with `grid`.
    pub ties: connectivity::Ties,
    /// Time step written to the scene (s). Default 0.001.
    pub dt: f64,
    /// Steps written to the scene. Default 1000.
    pub steps: usize,
    /// Surface samples per source mesh for the coverage figure. Default 2000.
    pub coverage_samples: usize,
    /// Grid cells per side for union volumes. Default 48.
    pub volume_grid: usize,
    /// Seed for sampling and CoACD. Default 0.
    pub seed: u64,
    /// Directory of the decomposition cache ([`cache`]): V-HACD results
    /// are read from it when the mesh and every option they depend on
    /// match, and new ones are stored there. Default `None` (no cache).
    pub cache: Option<std::path::PathBuf>,
}

/// The value of `options` whose `name` is `s` (ASCII case ignored), or a
/// message listing the names: the `FromStr` of the option enums.
fn pick_name<T: Copy>(
    s: &str,
    options: &[T],
    name: impl Fn(T) -> &'static str,
) -> Result<T, String> {
    let names: Vec<&str> = options.iter().map(|&o| name(o)).collect();
    options
        .iter()
        .find(|&&o| name(o).eq_ignore_ascii_case(s))
        .copied()
        .ok_or_else(|| format!("unknown value \"{s}\" (one of: {})", names.join(", ")))
}

impl ImportOptions {
    /// The concavity threshold used when none is given: 0.05 for CoACD
    /// (its own default), else [`ImportOptions::default`]'s 0.01.
    pub fn default_threshold(decomposer: Decomposer) -> f64 {
        match decomposer {
            Decomposer::Coacd => 0.05,
            _ => ImportOptions::default().threshold,
        }
    }
}

impl Default for ImportOptions {
    fn default() -> Self {
        ImportOptions {
            decomposer: Decomposer::Vhacd,
            max_hulls: 16,
            resolution: 64,
            threshold: 0.01,
            hull_points: decompose::HullPoints::Voxels,
            designable: None,
            mass: MassMode::Urdf,
            density: 1000.0,
            tiny_hull_size: 0.01,
            bridge_gaps: true,
            ties: connectivity::Ties::SharedVertex,
            dt: 0.001,
            steps: 1000,
            coverage_samples: 2000,
            volume_grid: 48,
            seed: 0,
            cache: None,
        }
    }
}

/// The hulls of one imported link (link frame).
#[derive(Clone, Debug)]
pub struct ImportedLink {
    pub name: String,
    pub hulls: Vec<Vec<Vector3<f64>>>,
    /// Source surfaces in the link frame (for coverage checks).
    pub sources: Vec<TriMesh>,
}

/// Result of an import.
#[derive(Clone, Debug)]
pub struct Imported {
    /// The scene (one robot) to write as the design YAML.
    pub scene: SceneSpec,
    pub links: Vec<ImportedLink>,
    pub report: ImportReport,
    /// The input marks its root link as static (see [`ready::root_is_static`]).
    pub root_static: bool,
    /// The input's contact friction coefficient (MJCF geoms), if it has one.
    pub friction: Option<f64>,
}

/// Input kinds by extension.
fn is_urdf(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("urdf") || e.eq_ignore_ascii_case("xml"))
}

/// Imports a `.urdf`, `.obj`, `.stl` or `.dae` file.
pub fn import(input: &Path, opts: &ImportOptions) -> Result<Imported, ImportError> {
    import_with(input, opts, &crate::progress::Silent)
}

/// [`import`], reporting the links' decomposition to `progress` (one unit
/// per link, the link's name as the message).
pub fn import_with(
    input: &Path,
    opts: &ImportOptions,
    progress: &dyn Progress,
) -> Result<Imported, ImportError> {
    let t0 = Instant::now();
    if !input.is_file() {
        return Err(ImportError::Io {
            path: input.to_path_buf(),
            err: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        });
    }
    if mjcf::is_mjcf(input) {
        let (src, extra) = mjcf::read_mjcf(input, opts)?;
        let mut imp = build(src, opts, t0, progress)?;
        add_mjcf_scene(&mut imp, extra, input)?;
        return Ok(imp);
    }
    let src = if is_urdf(input) {
        urdf::read_urdf(input, opts)?
    } else {
        SourceRobot::from_mesh(input)
    };
    build(src, opts, t0, progress)
}

/// Puts what an MJCF file adds (gravity, ground, obstacles, MuJoCo's
/// contact filter, joint effects, actuator-driven PD) into the imported
/// scene and validates it.
fn add_mjcf_scene(
    imp: &mut Imported,
    extra: mjcf::MjcfScene,
    input: &Path,
) -> Result<(), ImportError> {
    // MJCF says which bodies are welded to the world: keep it.
    imp.root_static = true;
    imp.friction = extra.friction;
    let scene = &mut imp.scene;
    let robot = scene.robots[0].name.clone();
    let env = crate::scene::environment::ENVIRONMENT;
    scene.gravity = extra.gravity;
    scene.ground = extra.ground;
    scene.obstacles = extra.obstacles;
    // Effects name bare joints (accepted while one robot has the joint).
    scene.effects = extra.effects;
    // Joints driven by the input's actuators: their gains and targets
    // (`ready::make_ready`'s hold leaves these joints alone).
    let controller = &mut scene.robots[0].controller;
    for (joint, d) in extra.drives {
        controller.gains.insert(
            joint.clone(),
            crate::scene::schema::Gains {
                kp: Some(d.kp),
                kd: Some(d.kd),
            },
        );
        controller.targets.insert(
            joint,
            crate::scene::schema::SignalList::One(crate::control::Signal::Constant {
                value: d.target,
            }),
        );
    }

    let mut exclude: Vec<[String; 2]> = extra
        .exclude
        .into_iter()
        .map(|[a, b]| [format!("{robot}/{a}"), format!("{robot}/{b}")])
        .collect();
    if scene.ground.is_some() {
        exclude.extend(
            extra
                .exclude_ground
                .into_iter()
                .map(|l| [format!("{env}/ground"), format!("{robot}/{l}")]),
        );
    }
    exclude.extend(
        extra
            .exclude_obstacle
            .into_iter()
            .map(|[o, l]| [format!("{env}/{o}"), format!("{robot}/{l}")]),
    );
    if !exclude.is_empty() {
        scene.contact = Some(ContactSpec {
            exclude,
            ..ContactSpec::default()
        });
    }
    crate::scene::Scene::from_spec(scene.clone(), input).map_err(|e| ImportError::Invalid {
        path: input.to_path_buf(),
        msg: e.to_string(),
    })?;
    Ok(())
}

/// Bounding-box diagonal (m) above which a placed mesh is reported as
/// probably in millimetres: no robot part spans 10 m, while a 10 mm part
/// written in millimetres reads as 10 m.
pub const MILLIMETRE_HINT_DIAGONAL: f64 = 10.0;

/// A report line when a mesh, as placed (after its `scale`), is too large
/// to be a robot part in metres: the likely unit and the fix. The import
/// goes on with the coordinates as metres (the mass lines say what that
/// gives).
fn units_hint(m: &TriMesh, element: &str, path: &Path) -> Option<String> {
    let d = m.diagonal();
    (d > MILLIMETRE_HINT_DIAGONAL).then(|| {
        format!(
            "units: {element}: mesh {} spans {d:.4} m (bounding-box diagonal, its coordinates read as metres), larger than any robot part: if the file is in millimetres, scale it by 0.001 (URDF <mesh scale=\"0.001 0.001 0.001\">); imported as metres",
            path.display()
        )
    })
}

fn build(
    src: SourceRobot,
    opts: &ImportOptions,
    t0: Instant,
    progress: &dyn Progress,
) -> Result<Imported, ImportError> {
    assemble::check_options(&src, opts)?;
    // 1. Geometry → hulls, link by link.
    let n = src.links.len();
    progress.start(n as u64, "links");
    // Links in parallel (each link's result does not depend on the order;
    // the first error in link order is the one reported).
    let memo = decompose::Memo::new(opts)?;
    let results: Vec<Result<LinkGeometry, ImportError>> = (0..n)
        .into_par_iter()
        .map(|li| {
            progress.message(&src.links[li].name);
            let g = link_geometry(&src, li, opts, &memo);
            progress.inc();
            g
        })
        .collect();
    progress.finish();
    let mut geoms = results.into_iter().collect::<Result<Vec<_>, _>>()?;
    // 2. Shared vertices inside each link; 3. attachment points; 4. tie groups.
    let conn = assemble::link_ties(&mut geoms, opts);
    let attach = assemble::attachments(&src, &mut geoms);
    let ties = assemble::tie_groups(&src, &conn);
    // 5. Masses, report, scene.
    let mut notes = src.notes.clone();
    notes.extend(geoms.iter().flat_map(|g| g.notes.iter().cloned()));
    notes.extend(attach.notes);
    let out = assemble::link_outputs(&src, &geoms, &conn, opts, &mut notes)?;
    let disconnected: Vec<String> = out
        .reports
        .iter()
        .filter(|r| r.connectivity.components > 1)
        .map(|r| r.name.clone())
        .collect();
    assemble::extension_notes(&attach.reports, &mut notes);
    let effects = assemble::dynamics_effects(&src, &mut notes);
    let scene = assemble::design_scene(&src, opts, out.specs, ties, attach.ties, effects);
    // The design must load as a scene.
    crate::scene::Scene::from_spec(scene.clone(), &src.file).map_err(|e| ImportError::Invalid {
        path: src.file.clone(),
        msg: e.to_string(),
    })?;
    let report = ImportReport {
        input: src.file.display().to_string(),
        robot: src.name.clone(),
        decomposer: opts.decomposer.name().into(),
        ties: opts.ties.name(),
        total_hulls: out.reports.iter().map(|r| r.hulls).sum(),
        total_vertices: out.reports.iter().map(|r| r.vertices).sum(),
        links: out.reports,
        attachments: attach.reports,
        joints: out.joints,
        disconnected_links: disconnected,
        notes,
        ready: None,
        seconds: t0.elapsed().as_secs_f64(),
    };
    let root = src.links.iter().find(|l| l.parent.is_none());
    Ok(Imported {
        scene,
        links: out.imported,
        report,
        root_static: root.is_some_and(|r| ready::root_is_static(&r.name, r.mass)),
        friction: None,
    })
}

/// Adds a report line for every input joint of `l` with a URDF `<limit
/// effort velocity>` (N·m or N, rad/s or m/s): the simulation enforces
/// neither; the values stay in the scene's `limit` (for reference) when
/// that limit is kept, and are left out otherwise (continuous joints,
/// limits not containing the initial pose, joints merged into a ball).
/// Returns `limit` unchanged.
fn effort_velocity_note(
    l: &source::SourceLink,
    limit: Option<JointLimitSpec>,
    notes: &mut Vec<String>,
) -> Option<JointLimitSpec> {
    for j in &l.joint.input_joints {
        if j.effort.is_none() && j.velocity.is_none() {
            continue;
        }
        let what: Vec<String> = [("effort", j.effort), ("velocity", j.velocity)]
            .iter()
            .filter_map(|(k, v)| v.map(|v| format!("{k}=\"{v}\"")))
            .collect();
        let kept = limit.is_some() && l.joint.input_joints.len() == 1;
        notes.push(format!(
            "joint \"{}\": <limit {}> not simulated (no effort or velocity limits in the scene); {}",
            j.name,
            what.join(" "),
            if kept {
                "carried in the scene's joint limit for reference"
            } else {
                "left out (the joint has no scene limit)"
            }
        ));
    }
    limit
}

/// The scene limit of an imported 1-DOF joint whose input limits position.
/// Enforced only when the initial coordinate (`initial`, default 0) lies
/// strictly inside; otherwise the limit is noted and left out (the barrier
/// needs a feasible start).
fn joint_limit(
    l: &source::SourceLink,
    initial: Option<&Vec<f64>>,
    notes: &mut Vec<String>,
) -> Option<JointLimitSpec> {
    let [j] = l.joint.input_joints.as_slice() else {
        return None;
    };
    if !j.limited || !matches!(l.joint.kind, JointType::Revolute | JointType::Prismatic) {
        return None;
    }
    let q0 = initial.and_then(|q| q.first().copied()).unwrap_or(0.0);
    if !(j.lower < q0 && q0 < j.upper) {
        notes.push(format!(
            "joint \"{}\": limits [{}, {}] do not contain the initial coordinate {q0} strictly; not enforced",
            j.name, j.lower, j.upper
        ));
        return None;
    }
    Some(JointLimitSpec {
        lower: j.lower,
        upper: j.upper,
        support: None,
        stiffness: None,
        velocity: j.velocity,
        effort: j.effort,
    })
}

/// The scene mimic of an imported joint: kept as a tie when both joints
/// are single revolute/prismatic scene joints, noted and dropped otherwise.
fn mimic(
    l: &source::SourceLink,
    src: &SourceRobot,
    notes: &mut Vec<String>,
) -> Option<crate::scene::schema::MimicSpec> {
    let m = l.joint.mimic.as_ref()?;
    let one_dof = |k: JointType| matches!(k, JointType::Revolute | JointType::Prismatic);
    let followed = src.links.iter().find(|o| o.joint.name == m.joint);
    if one_dof(l.joint.kind) && followed.is_some_and(|o| one_dof(o.joint.kind)) {
        notes.push(format!(
            "joint \"{}\" mimics \"{}\": tied by a stiff coupling term",
            l.joint.name, m.joint
        ));
        Some(m.clone())
    } else {
        notes.push(format!(
            "joint \"{}\" mimics \"{}\", which is not a revolute/prismatic scene joint: left independent",
            l.joint.name, m.joint
        ));
        None
    }
}
