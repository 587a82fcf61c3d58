//! Files written by `sdrs optimize`.

use super::OptimizeError;
use super::{IterRecord, Outcome, Problem};
use crate::control::Controller;
use crate::files::write_atomic;
use crate::math::{compose, rigid_inverse, rot};
use crate::model::{JointKind, MassModel, Model};
use crate::scene::Scene;
use crate::scene::schema::{
    Gains, HullSpec, JointLimitSpec, JointSpec, JointType, LinkSpec, MassModelSpec, MimicSpec,
    Origin, SceneSpec, SignalList,
};
use std::path::Path;

/// `history.csv`.
pub fn history_csv(history: &[IterRecord]) -> String {
    let mut s = String::from(
        "iteration,loss,best_loss,grad_design_norm,grad_controller_norm,radius_design,radius_controller,accepted,forward_seconds,backward_seconds,wall_seconds\n",
    );
    for r in history {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{},{}\n",
            r.iter,
            r.loss,
            r.best_loss,
            r.grad_design_norm,
            r.grad_controller_norm,
            r.radius_design,
            r.radius_controller,
            r.accepted,
            r.forward_seconds,
            r.backward_seconds,
            r.wall_seconds
        ));
    }
    s
}

/// `task-folder: mode` of a run, for titles and legends (`chain_reach:
/// co-design`).
pub fn run_label(p: &Problem, design_on: bool) -> String {
    let task = p
        .task_path
        .parent()
        .and_then(|d| d.file_name())
        .map_or_else(
            || p.task_path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
    format!(
        "{task}: {}",
        if design_on {
            "co-design"
        } else {
            "controller-only"
        }
    )
}

/// Joint type with its `axis` / `axes` fields as written in scene files.
type JointFields = (JointType, Option<[f64; 3]>, Option<[[f64; 3]; 2]>);

fn joint_type(k: &JointKind) -> JointFields {
    match k {
        JointKind::Fixed => (JointType::Fixed, None, None),
        JointKind::Revolute { axis } => (JointType::Revolute, Some((*axis).into()), None),
        JointKind::Prismatic { axis } => (JointType::Prismatic, Some((*axis).into()), None),
        JointKind::Ball { axes } => (
            JointType::Ball,
            None,
            Some([axes[0].into(), axes[1].into()]),
        ),
        JointKind::Spherical => (JointType::Spherical, None, None),
        JointKind::Free => (JointType::Free, None, None),
    }
}

/// The scene as the run simulated it: [`design_scene`] of the loaded
/// specification, with the contact section the run used
/// ([`effective_contact`]). Every scene file an optimization writes
/// (`design.yaml`, `scenes/`, `failed_trials/…/scenes/`) goes through this,
/// so `sdrs simulate` of any of them reproduces the run's trajectory.
pub fn scene_as_run(scene: &Scene, model: &Model, controller: &Controller) -> SceneSpec {
    let mut spec = design_scene(&scene.spec, model, controller);
    effective_contact(&mut spec, scene.contact.as_ref());
    spec
}

/// The contact section as the run used it: `--contact`, `--dhat` and
/// `--kappa` change the loaded settings, not the specification, so without
/// this a scene written by an `--contact ipc` run would simulate with the
/// separating-plane model (and an SDRS stiffness as IPC's `κ`). The model,
/// the IPC section and `κ` are taken from the settings; `κ` is left out
/// when the run chose it (IPC's adaptive stiffness, recomputed the same way
/// from the written scene).
fn effective_contact(spec: &mut SceneSpec, used: Option<&crate::contact::ContactSettings>) {
    let (Some(out), Some(c)) = (spec.contact.as_mut(), used) else {
        return;
    };
    out.model = c.model;
    out.ipc = c.ipc.clone();
    out.kappa = c.kappa_given.then_some(c.kappa);
}

/// The scene specification with the robots' links and controllers replaced
/// by those of `model` and `controller` (explicit links, per-vertex masses):
/// `sdrs simulate` runs it as is.
pub fn design_scene(spec: &SceneSpec, model: &Model, controller: &Controller) -> SceneSpec {
    let mut out = spec.clone();
    for r in &mut out.robots {
        let Some(ri) = model.robots.iter().position(|x| x.name == r.name) else {
            continue;
        };
        let base =
            crate::math::pose_from(&crate::math::rpy_to_matrix(&r.base.rpy), &r.base.xyz.into());
        let range = model.robots[ri].links.clone();
        r.chain = None;
        r.links = range
            .clone()
            .map(|l| {
                let link = &model.links[l];
                let attach = if link.parent.is_some() {
                    link.attach
                } else {
                    compose(&rigid_inverse(&base), &link.attach)
                };
                let (roll, pitch, yaw) =
                    nalgebra::Rotation3::from_matrix_unchecked(rot(&attach)).euler_angles();
                let (kind, axis, axes) = joint_type(&link.joint);
                LinkSpec {
                    name: link.name.clone(),
                    parent: link.parent.map(|p| model.links[p].name.clone()),
                    joint: JointSpec {
                        name: Some(link.joint_name.clone()),
                        kind,
                        axis,
                        axes,
                        origin: Origin {
                            xyz: attach.column(3).into_owned().into(),
                            rpy: [roll, pitch, yaw],
                        },
                        limit: link.limit.as_ref().map(|l| JointLimitSpec {
                            lower: l.lower,
                            upper: l.upper,
                            support: Some(l.support),
                            stiffness: Some(l.stiffness),
                            velocity: l.velocity,
                            effort: l.effort,
                        }),
                        mimic: model
                            .mimics
                            .iter()
                            .find(|m| m.dof == link.dof_offset && link.ndof() == 1)
                            .map(|m| MimicSpec {
                                joint: model.links[model.dofs[m.master].link].joint_name.clone(),
                                multiplier: Some(m.multiplier),
                                offset: Some(m.offset),
                                stiffness: Some(m.stiffness),
                            }),
                    },
                    mass: None,
                    vertex_mass: None,
                    mass_model: mass_model_spec(&link.mass_model),
                    hulls: link
                        .hulls
                        .iter()
                        .map(|h| HullSpec {
                            vertices: Some(h.x_local.iter().map(|x| (*x).into()).collect()),
                            cuboid: None,
                            vertex_masses: matches!(link.mass_model, MassModel::Vertices)
                                .then(|| h.vertex_mass.clone()),
                        })
                        .collect(),
                    collide: link.collides,
                    // The source surface is not re-written (a cage-deformed
                    // one would need its own file): the design is its hulls.
                    surface_mesh: None,
                }
            })
            .collect();
        // Controller: write back every channel of this robot.
        for ch in &controller.channels {
            let l = model.dofs[ch.dof].link;
            if !range.contains(&l) {
                continue;
            }
            let link = &model.links[l];
            let local = ch.dof - link.dof_offset;
            let entry = r
                .controller
                .targets
                .entry(link.joint_name.clone())
                .or_insert_with(|| SignalList::Many(vec![]));
            let mut list = entry.as_slice().to_vec();
            if list.len() < link.ndof() {
                list.resize(link.ndof(), ch.signal.clone());
            }
            list[local] = ch.signal.clone();
            *entry = if list.len() == 1 {
                SignalList::One(list.remove(0))
            } else {
                SignalList::Many(list)
            };
            r.controller.gains.insert(
                link.joint_name.clone(),
                Gains {
                    kp: Some(ch.kp),
                    kd: Some(ch.kd),
                },
            );
        }
    }
    out
}

/// Wavefront OBJ of a link's hulls (one object per hull, triangulated
/// convex hulls), in the link frame.
pub fn link_obj(model: &Model, link: usize) -> String {
    use parry3d_f64::math::Vector;
    let l = &model.links[link];
    let mut s = format!(
        "# sdrs: {}/{} (link frame, m)\n",
        model.robots[l.robot].name, l.name
    );
    let mut offset = 1;
    for (h, hull) in l.hulls.iter().enumerate() {
        let pts: Vec<Vector> = hull
            .x_local
            .iter()
            .map(|x| Vector::new(x.x, x.y, x.z))
            .collect();
        let (v, f) = parry3d_f64::transformation::convex_hull(&pts);
        s.push_str(&format!("o hull{h}\n"));
        for p in &v {
            s.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
        }
        for t in &f {
            s.push_str(&format!(
                "f {} {} {}\n",
                t[0] as usize + offset,
                t[1] as usize + offset,
                t[2] as usize + offset
            ));
        }
        offset += v.len();
    }
    s
}

/// Writes the outputs of an optimization into `dir`: `history.csv`,
/// `design.yaml`, `meshes/`, `summary.json` (the application adds its
/// pictures: `convergence.svg`, `report.html`, …).
pub fn write_all(
    dir: &Path,
    p: &Problem,
    outcome: &Outcome,
    extra: serde_json::Value,
) -> Result<(), OptimizeError> {
    let first = p.first();
    let mut model = first.model.clone();
    p.design.apply(&mut model, &outcome.design);
    let mut controller = first.controller.clone();
    p.controls.apply(&mut controller, &outcome.controller);
    write_atomic(
        &dir.join("history.csv"),
        history_csv(&outcome.history).as_bytes(),
    )?;
    let spec = scene_as_run(&first.scene, &model, &controller);
    let header = format!(
        "# Optimized by `sdrs optimize {}` — a complete scene: `sdrs simulate` runs it.\n",
        p.task_path.display()
    );
    write_atomic(
        &dir.join("design.yaml"),
        (header
            + &serde_yaml::to_string(&spec)
                .map_err(|e| OptimizeError::serialize("design.yaml", e))?)
            .as_bytes(),
    )?;
    for (i, l) in model.links.iter().enumerate() {
        if model.robots[l.robot].name == crate::scene::environment::ENVIRONMENT {
            continue;
        }
        let name = format!("{}_{}.obj", model.robots[l.robot].name, l.name);
        write_atomic(
            &dir.join("meshes").join(name),
            link_obj(&model, i).as_bytes(),
        )?;
    }
    let last = outcome.history.last();
    let n = outcome.history.len().max(1) as f64;
    let fwd: f64 = outcome
        .history
        .iter()
        .map(|r| r.forward_seconds)
        .sum::<f64>()
        / n;
    let bwd: f64 = outcome
        .history
        .iter()
        .map(|r| r.backward_seconds)
        .sum::<f64>()
        / n;
    let summary = serde_json::json!({
        "task": p.task_path.display().to_string(),
        "iterations": outcome.history.len() - 1,
        "design_variables": p.design.len(),
        "controller_variables": p.controls.len(),
        "horizon": first.horizon,
        "initial_loss": outcome.initial_loss,
        "final_loss": outcome.loss,
        "relative_reduction": 1.0 - outcome.loss / outcome.initial_loss,
        "wall_seconds": last.map(|r| r.wall_seconds),
        "mean_forward_seconds": fwd,
        "mean_backward_seconds": bwd,
        "backward_over_forward": bwd / fwd,
        "design": p.design.vars.iter().zip(outcome.design.iter()).map(|(v, x)| (v.name.clone(), *x)).collect::<std::collections::BTreeMap<_, _>>(),
        "controller": p.controls.names(&first.model, &first.controller).into_iter().zip(outcome.controller.iter().copied()).collect::<std::collections::BTreeMap<_, _>>(),
        "extra": extra,
    });
    write_atomic(
        &dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)
            .map_err(|e| OptimizeError::serialize("summary.json", e))?
            .as_bytes(),
    )?;
    Ok(())
}

/// The scene-file form of a link's mass model (`None` for the default
/// `vertices`, whose masses are written per vertex).
pub fn mass_model_spec(m: &MassModel) -> Option<MassModelSpec> {
    match m {
        MassModel::Vertices => None,
        MassModel::Solid { density } => Some(MassModelSpec::Solid {
            density: Some(*density),
        }),
        MassModel::Given(g) => {
            let i = &g.inertia;
            Some(MassModelSpec::Given {
                mass: g.mass,
                com: g.com.into(),
                inertia: [
                    i[(0, 0)],
                    i[(0, 1)],
                    i[(0, 2)],
                    i[(1, 1)],
                    i[(1, 2)],
                    i[(2, 2)],
                ],
            })
        }
    }
}
