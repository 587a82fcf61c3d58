//! Turns a co-design problem into a cage-based one (`sdrs optimize
//! --contact ipc --cage …`): the cage vertices of the task's
//! `design.vertices` links become the design (bounds `design.bound`), and
//! the IPC surfaces keep the rest triangulation while the cage moves their
//! vertices ([`crate::IpcFactory::topology`]) — the hull surfaces' or, with
//! `contact.ipc.surface: source`, the source mesh's.

use super::{CageDesign, CageError, CageResolution, LinkCage};
use crate::IpcFactory;
use crate::mesh::MeshOrigin;
use nalgebra::Vector3;
use sdrs::optimize::design::Target;
use sdrs::optimize::{Problem, Trajectory};
use std::sync::Arc;

/// Why a problem cannot be caged.
#[derive(Debug, thiserror::Error)]
pub enum CageSetupError {
    #[error(
        "{task}: the task designs no link's hull vertices (its `design.vertices` is empty), so there is nothing to cage"
    )]
    NoVertexDesign { task: String },
    #[error(transparent)]
    Cage(#[from] CageError),
    #[error("{0}")]
    Mesh(String),
    /// The cage design of trajectory `index` differs from the first's (the
    /// caged robot must be the same in every trajectory).
    #[error("trajectories[{index}]: its cage design differs from trajectories[0]'s")]
    Differs { index: usize },
    #[error("a task without trajectories")]
    NoTrajectories,
}

/// The cages (one per designed link) and the number of design variables.
pub struct CageSummary {
    pub cage_vertices: Vec<usize>,
    pub variables: usize,
}

/// Replaces `problem`'s design by the cage vertices and gives each of its
/// trajectories the IPC factory with its frozen surfaces.
pub fn cage_problem(
    problem: &mut Problem,
    res: CageResolution,
) -> Result<CageSummary, CageSetupError> {
    let mut links: Vec<usize> = problem
        .design
        .vars
        .iter()
        .flat_map(|v| &v.targets)
        .filter_map(|t| match t {
            Target::Vertex { link, .. } => Some(*link),
            _ => None,
        })
        .collect();
    links.sort_unstable();
    links.dedup();
    if links.is_empty() {
        return Err(CageSetupError::NoVertexDesign {
            task: problem.task_path.display().to_string(),
        });
    }
    let bound = problem.task.design.as_ref().map_or(0.5, |d| d.bound);
    let mut first: Option<(sdrs::optimize::DesignSpace, CageSummary)> = None;
    for (index, t) in problem.trajectories.iter_mut().enumerate() {
        let (design, summary) = cage_one(t, &links, res, bound)?;
        match &first {
            None => first = Some((design, summary)),
            Some((d0, _)) if *d0 != design => {
                return Err(CageSetupError::Differs { index });
            }
            Some(_) => {}
        }
    }
    let (design, summary) = first.ok_or(CageSetupError::NoTrajectories)?;
    problem.design = design;
    Ok(summary)
}

/// One trajectory's frozen-surface factory (set on it) and cage design
/// (returned: the same for every trajectory of a task, checked). A caged link
/// whose IPC surface is its source mesh (`contact.ipc.surface: source`) gets
/// the mesh's vertices as `Link::surface`, the cage around hulls and mesh,
/// and the mesh's coordinates in the cage ([`LinkCage::with_surface`]), so
/// the cage deforms the contact surface and the hulls (mass) together.
fn cage_one(
    p: &mut Trajectory,
    links: &[usize],
    res: CageResolution,
    bound: f64,
) -> Result<(sdrs::optimize::DesignSpace, CageSummary), CageSetupError> {
    let mut scene = p.scene.clone();
    scene.model = p.model.clone();
    let topology = crate::factory::surface_kind(&scene)
        .and_then(|kind| crate::factory::link_meshes(&scene, kind))
        .map_err(|e| CageSetupError::Mesh(e.at(&scene.source).to_string()))?;
    let mut cages = Vec::with_capacity(links.len());
    for &l in links {
        let surface: Vec<Vector3<f64>> = match topology[l].origin {
            MeshOrigin::Source { .. } => topology[l].x_local.clone(),
            MeshOrigin::Hulls => Vec::new(),
        };
        let cage = LinkCage::automatic_around(&p.model, l, res.segments(), &surface)?;
        let cage = if surface.is_empty() {
            cage
        } else {
            p.model.links[l].surface = surface.clone();
            cage.with_surface(&p.model, &surface)?
        };
        cages.push(cage);
    }
    let design = CageDesign { cages, bound };
    p.contact_factory = Some(Arc::new(IpcFactory {
        topology: Some(Arc::new(topology)),
        ..IpcFactory::default()
    }));
    let space = design.design_space(&p.model);
    let summary = CageSummary {
        cage_vertices: design.cages.iter().map(|c| c.cage.vertices.len()).collect(),
        variables: design.len(),
    };
    Ok((space, summary))
}
