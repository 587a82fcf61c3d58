//! The phases of [`super::build`] after decomposition: ties inside each
//! link, attachment points, tie groups, then per link its mass model,
//! report and scene spec, and the one-robot design scene.

use super::connectivity::{
    self, DesignHull, LinkConnectivity, attach_point, connect_link, hull_volume,
};
use super::source::SourceRobot;
use super::{
    ImportError, ImportOptions, ImportedLink, LinkGeometry, decompose, grid, mass, report,
};
use crate::energy::effects::{EffectKind, EffectSpec};
use crate::scene::schema::*;
use nalgebra::Vector3;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Settings that contradict each other or name links the input lacks.
pub(super) fn check_options(src: &SourceRobot, opts: &ImportOptions) -> Result<(), ImportError> {
    if opts.ties == connectivity::Ties::Corners && opts.decomposer != decompose::Decomposer::Grid {
        return Err(ImportError::Invalid {
            path: src.file.clone(),
            msg: format!(
                "--ties corners ties the coincident corners of grid blocks and needs --decomposer grid (got {})",
                opts.decomposer.name()
            ),
        });
    }
    if let Some(d) = &opts.designable {
        for name in d {
            if !src.links.iter().any(|l| &l.name == name) {
                let known: Vec<&str> = src.links.iter().map(|l| l.name.as_str()).collect();
                return Err(ImportError::InvalidUrdf {
                    path: src.file.clone(),
                    element: format!("--designable {name}"),
                    msg: format!("no such link (links: {})", known.join(", ")),
                });
            }
        }
    }
    Ok(())
}

/// Shared vertices inside each link (grid blocks: corners or faces); links
/// in parallel (each is independent).
pub(super) fn link_ties(geoms: &mut [LinkGeometry], opts: &ImportOptions) -> Vec<LinkConnectivity> {
    let grid = opts.decomposer == decompose::Decomposer::Grid;
    geoms
        .par_iter_mut()
        .map(|g| match opts.ties {
            connectivity::Ties::Corners if grid => grid::corner_ties(&g.hulls),
            connectivity::Ties::SharedVertex if grid => grid::face_ties(&mut g.hulls),
            _ => connect_link(&mut g.hulls, opts.bridge_gaps),
        })
        .collect()
}

/// The attachment ties and reports of every joint, and notes on joints
/// left untied (MJCF shapes kept as given).
pub(super) struct Attachments {
    pub ties: Vec<AttachmentTie>,
    pub reports: Vec<report::AttachmentReport>,
    pub notes: Vec<String>,
}

/// Attachment points: each joint's origin on its parent's hulls and the
/// child's origin on the child's, hulls extended to them when outside
/// (unless the input's geometry is kept as given).
pub(super) fn attachments(src: &SourceRobot, geoms: &mut [LinkGeometry]) -> Attachments {
    let mut out = Attachments {
        ties: Vec::new(),
        reports: Vec::new(),
        notes: Vec::new(),
    };
    for (li, l) in src.links.iter().enumerate() {
        let Some(p) = l.parent else { continue };
        let xyz = Vector3::from(l.joint.origin.xyz);
        if src.keep_geometry
            && !(connectivity::point_inside(&geoms[p].hulls, &xyz)
                && connectivity::point_inside(&geoms[li].hulls, &Vector3::zeros()))
        {
            if !l.frame_only && !src.links[p].frame_only {
                out.notes.push(format!(
                    "joint \"{}\": the attachment point is outside the hulls; not tied in the design (shapes kept as given)",
                    l.joint.name
                ));
            }
            continue;
        }
        let parent_site = attach_point(&mut geoms[p].hulls, xyz);
        let child_site = attach_point(&mut geoms[li].hulls, Vector3::zeros());
        out.ties.push(AttachmentTie {
            link: l.name.clone(),
            parent_vertex: VertexRef {
                link: src.links[p].name.clone(),
                hull: parent_site.hull,
                vertex: parent_site.vertex,
            },
            child_vertex: VertexRef {
                link: l.name.clone(),
                hull: child_site.hull,
                vertex: child_site.vertex,
            },
        });
        out.reports.push(report::AttachmentReport {
            link: l.name.clone(),
            joint: l.joint.name.clone(),
            parent: src.links[p].name.clone(),
            parent_site,
            child_site,
        });
    }
    out
}

/// Shared vertices as tie groups, merged when they share a vertex, sorted.
pub(super) fn tie_groups(src: &SourceRobot, conn: &[LinkConnectivity]) -> Vec<Vec<VertexRef>> {
    let mut ties: Vec<Vec<VertexRef>> = Vec::new();
    for (li, c) in conn.iter().enumerate() {
        for s in &c.shared {
            let a = VertexRef {
                link: src.links[li].name.clone(),
                hull: s.hulls[0],
                vertex: s.vertices[0],
            };
            let b = VertexRef {
                link: src.links[li].name.clone(),
                hull: s.hulls[1],
                vertex: s.vertices[1],
            };
            let hits: Vec<usize> = (0..ties.len())
                .filter(|&k| ties[k].contains(&a) || ties[k].contains(&b))
                .collect();
            let mut group = vec![a, b];
            for &k in hits.iter().rev() {
                group.extend(ties.swap_remove(k));
            }
            group.sort();
            group.dedup();
            ties.push(group);
        }
    }
    ties.sort();
    ties
}

/// Per link: the scene spec, the report and the imported hulls; plus the
/// joint table of the report.
pub(super) struct LinkOutputs {
    pub specs: Vec<LinkSpec>,
    pub reports: Vec<report::LinkReport>,
    pub imported: Vec<ImportedLink>,
    pub joints: BTreeMap<String, Vec<super::source::InputJoint>>,
}

/// Masses, reports and specs of every link (`notes` gains the mass
/// fallbacks, joint limits left out and mimics).
pub(super) fn link_outputs(
    src: &SourceRobot,
    geoms: &[LinkGeometry],
    conn: &[LinkConnectivity],
    opts: &ImportOptions,
    notes: &mut Vec<String>,
) -> Result<LinkOutputs, ImportError> {
    let n = src.links.len();
    let mut out = LinkOutputs {
        specs: Vec::with_capacity(n),
        reports: Vec::with_capacity(n),
        imported: Vec::with_capacity(n),
        joints: BTreeMap::new(),
    };
    // The report's figures (union volume, coverage) in parallel.
    let figures: Vec<ReportFigures> = geoms.par_iter().map(|g| report_figures(g, opts)).collect();
    for (li, l) in src.links.iter().enumerate() {
        let g = &geoms[li];
        let lm = link_mass(src, li, g, opts, notes)?;
        out.reports
            .push(link_report(l.name.clone(), g, &conn[li], &lm, &figures[li]));
        if !l.joint.input_joints.is_empty() {
            out.joints
                .insert(l.joint.name.clone(), l.joint.input_joints.clone());
        }
        out.specs.push(LinkSpec {
            name: l.name.clone(),
            parent: l.parent.map(|p| src.links[p].name.clone()),
            joint: JointSpec {
                name: (l.joint.name != l.name).then(|| l.joint.name.clone()),
                kind: l.joint.kind,
                axis: l.joint.axis,
                axes: l.joint.axes,
                origin: l.joint.origin.clone(),
                limit: super::effort_velocity_note(
                    l,
                    super::joint_limit(l, src.initial.get(&l.joint.name), notes),
                    notes,
                ),
                mimic: super::mimic(l, src, notes),
            },
            mass: None,
            vertex_mass: None,
            mass_model: Some(lm.spec.clone()),
            hulls: g
                .hulls
                .iter()
                .map(|h| {
                    HullSpec::from_vertices(h.vertices.iter().map(|v| [v.x, v.y, v.z]).collect())
                })
                .collect(),
            collide: l.collides,
            // Filled in by `write::write_outputs` (relative to the design).
            surface_mesh: None,
        });
        out.imported.push(ImportedLink {
            name: l.name.clone(),
            hulls: g.hulls.iter().map(|h| h.vertices.clone()).collect(),
            sources: g.sources.clone(),
        });
    }
    Ok(out)
}

/// The mass model of link `li` (massless for a frame), with a note when
/// it falls back to the density.
fn link_mass(
    src: &SourceRobot,
    li: usize,
    g: &LinkGeometry,
    opts: &ImportOptions,
    notes: &mut Vec<String>,
) -> Result<mass::LinkMass, ImportError> {
    let l = &src.links[li];
    let hull_vertices_now: Vec<&[Vector3<f64>]> =
        g.hulls.iter().map(|h| h.vertices.as_slice()).collect();
    let lm = if l.frame_only {
        mass::massless_frame()
    } else {
        mass::link_mass_model(
            opts.mass,
            l.moment.as_ref(),
            opts.density,
            &hull_vertices_now,
        )
        .map_err(|msg| ImportError::Invalid {
            path: src.file.clone(),
            msg: format!("link \"{}\": {msg}", l.name),
        })?
    };
    if let Some(why) = &lm.fallback {
        notes.push(format!(
            "link \"{}\": {why}: solid hulls at density {} kg/m³ ({:.4} kg)",
            l.name, opts.density, lm.mass
        ));
    }
    Ok(lm)
}

/// A link's report: hulls, union volume, coverage of its sources, mass.
/// A link's union volume (m³), coverage of its sources (fraction) and
/// largest distance from a source sample to the hulls (m).
struct ReportFigures {
    union_volume: f64,
    coverage: f64,
    max_distance: f64,
}

fn report_figures(g: &LinkGeometry, opts: &ImportOptions) -> ReportFigures {
    let polys: Vec<_> = g.hulls.iter().map(|h| h.poly.clone()).collect();
    let union_volume = report::union_volume(&polys, opts.volume_grid);
    let (mut coverage, mut max_distance) = (1.0f64, 0.0f64);
    for (k, s) in g.sources.iter().enumerate() {
        let (c, d) = report::coverage(s, &polys, opts.coverage_samples, opts.seed + k as u64);
        coverage = coverage.min(c);
        max_distance = max_distance.max(d);
    }
    ReportFigures {
        union_volume,
        coverage,
        max_distance,
    }
}

fn link_report(
    name: String,
    g: &LinkGeometry,
    conn: &LinkConnectivity,
    lm: &mass::LinkMass,
    fig: &ReportFigures,
) -> report::LinkReport {
    let (uv, cov, maxd) = (fig.union_volume, fig.coverage, fig.max_distance);
    let max_change = g
        .hulls
        .iter()
        .map(|h: &DesignHull| {
            (hull_volume(&h.vertices) - h.initial_volume).abs() / h.initial_volume
        })
        .fold(0.0, f64::max);
    let hull_vertices: Vec<usize> = g.hulls.iter().map(|h| h.vertices.len()).collect();
    report::LinkReport {
        name,
        hulls: g.hulls.len(),
        vertices: hull_vertices.iter().sum(),
        hull_vertices,
        mass: lm.mass,
        mass_source: lm.source,
        mass_model: lm.model_name(),
        inertial_input: lm.input.clone(),
        inertial_hulls: lm.hulls.clone(),
        union_volume: uv,
        source_volume: g.source_volume,
        coverage: cov,
        coverage_error: 1.0 - cov,
        max_distance: maxd,
        connectivity: conn.clone(),
        max_hull_volume_change: max_change,
        decompose_seconds: g.seconds,
    }
}

/// Notes on attachment points that lay outside a hull (extended to them).
pub(super) fn extension_notes(attachments: &[report::AttachmentReport], notes: &mut Vec<String>) {
    for a in attachments {
        for (side, s) in [("parent", &a.parent_site), ("child", &a.child_site)] {
            if s.extended {
                notes.push(format!(
                    "joint \"{}\": the attachment point was {:.3e} m outside the {side} link's hulls; hull {} was extended to it",
                    a.joint, s.distance, s.hull
                ));
            }
        }
    }
}

/// URDF `<dynamics damping friction>` as `joint_damping`/`joint_friction`
/// effects on the scene joint of the same name (revolute or prismatic);
/// a report line when the input joint was merged into a ball joint.
pub(super) fn dynamics_effects(src: &SourceRobot, notes: &mut Vec<String>) -> Vec<EffectSpec> {
    let mut out = Vec::new();
    for l in &src.links {
        let one = matches!(l.joint.kind, JointType::Revolute | JointType::Prismatic);
        for j in &l.joint.input_joints {
            for (kind, v, what) in [
                (EffectKind::JointDamping, j.damping, "damping"),
                (EffectKind::JointFriction, j.friction, "friction"),
            ] {
                let Some(v) = v else { continue };
                if one && j.name == l.joint.name {
                    out.push(EffectSpec {
                        effect: kind,
                        on: j.name.clone(),
                        values: vec![v],
                        eps: None,
                    });
                } else {
                    notes.push(format!(
                        "joint \"{}\": <dynamics {what}=\"{v}\"> left out (the joint is part of scene joint \"{}\", which takes no per-axis {what})",
                        j.name, l.joint.name
                    ));
                }
            }
        }
    }
    out
}

/// The design scene: one robot at the origin, its initial coordinates and
/// design section, the default gravity, no ground or contact, `effects`.
pub(super) fn design_scene(
    src: &SourceRobot,
    opts: &ImportOptions,
    links: Vec<LinkSpec>,
    ties: Vec<Vec<VertexRef>>,
    attachments: Vec<AttachmentTie>,
    effects: Vec<EffectSpec>,
) -> SceneSpec {
    let robot = RobotSpec {
        name: src.name.clone(),
        base: Origin::default(),
        links,
        chain: None,
        controller: ControllerSpec::default(),
        initial: src
            .initial
            .iter()
            .map(|(j, q)| {
                (
                    j.clone(),
                    InitialSpec {
                        q: q.clone(),
                        qdot: Vec::new(),
                    },
                )
            })
            .collect(),
        design: Some(DesignSpec {
            designable: opts.designable.clone(),
            ties,
            attachments,
            bound: None,
        }),
    };
    SceneSpec {
        version: 1,
        dt: opts.dt,
        steps: opts.steps,
        gravity: [0.0, 0.0, -9.81],
        solver: Default::default(),
        robots: vec![robot],
        objects: Vec::new(),
        ground: None,
        obstacles: Vec::new(),
        contact: None,
        effects,
    }
}
