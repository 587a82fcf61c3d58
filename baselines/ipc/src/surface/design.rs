//! A design that edits hull vertices of a link whose IPC contact surface is
//! its source mesh is refused: the hull edit would change the link's mass
//! but not the surface IPC collides, so the contact gradient w.r.t. those
//! variables would be silently zero. A cage (`--cage`) deforms the source
//! mesh and the hulls together and is the way to design such a link
//! ([`crate::cage::cage_problem`]).

use super::paths::surface_paths;
use crate::settings::{IpcSettings, SurfaceKind};
use sdrs::optimize::Problem;
use sdrs::optimize::design::Target;
use sdrs::scene::schema::ContactModelKind;
use std::path::PathBuf;

/// Why a design cannot run with source-mesh surfaces.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SurfaceDesignError {
    #[error(
        "{task}: the design moves hull vertices of link \"{link}\" (design.vertices), but under contact.ipc.surface: source its IPC contact surface is the source mesh {} (scene key {key}), which a hull edit does not move (the contact gradient would be zero); use --cage coarse|fine|K (the cage deforms the source mesh and the hulls together), contact.ipc.surface: hulls, or leave the link out of design.vertices",
        mesh.display()
    )]
    HullEditOfSourceSurface {
        task: String,
        link: String,
        mesh: PathBuf,
        key: String,
    },
    #[error("{task}: {msg}")]
    Scene { task: String, msg: String },
}

/// Checks every trajectory of `problem` (see the module docs).
pub fn check_vertex_design(problem: &Problem) -> Result<(), SurfaceDesignError> {
    let task = problem.task_path.display().to_string();
    for p in &problem.trajectories {
        let Some(c) = p.scene.contact.as_ref() else {
            continue;
        };
        if c.model != ContactModelKind::Ipc {
            continue;
        }
        let ipc = IpcSettings::of(c).map_err(|e| SurfaceDesignError::Scene {
            task: task.clone(),
            msg: e.at(&p.scene.source).to_string(),
        })?;
        if ipc.surface != SurfaceKind::Source {
            continue;
        }
        let paths = surface_paths(&p.scene).map_err(|e| SurfaceDesignError::Scene {
            task: task.clone(),
            msg: e.at(&p.scene.source).to_string(),
        })?;
        for t in problem.design.vars.iter().flat_map(|v| &v.targets) {
            let link = match *t {
                Target::Vertex { link, .. } | Target::Blend { link, .. } => link,
                _ => continue,
            };
            if let Some(sp) = &paths[link] {
                let l = &p.model.links[link];
                return Err(SurfaceDesignError::HullEditOfSourceSurface {
                    task,
                    link: format!("{}/{}", p.model.robots[l.robot].name, l.name),
                    mesh: sp.file.clone(),
                    key: sp.element.clone(),
                });
            }
        }
    }
    Ok(())
}
