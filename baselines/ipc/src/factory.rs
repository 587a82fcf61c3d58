//! [`IpcFactory`]: the [`ContactModelFactory`] for `contact.model: ipc`,
//! passed by the CLI to `Scene::simulator_with` (the core never depends on
//! this crate). Builds each link's surface mesh, checks the start is
//! intersection-free, chooses `κ` when the scene gives none, and returns the
//! contact term (and the friction term when `μ > 0`).

use crate::barrier::barrier_derivative;
use crate::contact::{IpcContact, IpcParams};
use crate::friction::{IpcFriction, IpcFrictionParams};
use crate::line_search::CcdOptions;
use crate::mesh::{LinkMesh, MeshOrigin};
use crate::settings::{IpcSettings, SurfaceKind};
use sdrs::energy::Energy;
use sdrs::kinematics::{KinOrder, Kinematics};
use sdrs::scene::schema::ContactModelKind;
use sdrs::scene::{ContactModelFactory, ContactSettings, Invalid, Scene};

/// Provides the IPC baseline's terms.
#[derive(Clone, Debug, Default)]
pub struct IpcFactory {
    /// CCD settings (defaults documented on [`CcdOptions`]).
    pub ccd: CcdOptions,
    /// Exact (unprojected) per-primitive Hessians whatever the scene's
    /// `contact.ipc.hessian` says (default false: the scene's choice,
    /// itself exact by default). The simulator a backward pass linearizes
    /// with needs the exact ones ([`IpcFactory::adjoint`]).
    pub exact_hessian: bool,
    /// Frozen surface triangulation (default `None`: each link's surface is
    /// re-triangulated from its hulls for every simulator). With `Some`,
    /// every link keeps these triangles and edges and only its vertex
    /// positions follow the model's hull vertices ([`LinkMesh::source`]):
    /// what a cage-based design needs, since re-triangulating a planar face
    /// whose vertices a deformation moves off-plane would flip its diagonal
    /// between `d + h` and `d − h` (a jump in the contact energy).
    pub topology: Option<std::sync::Arc<Vec<LinkMesh>>>,
}

impl IpcFactory {
    /// The factory for the simulator of a backward pass
    /// ([`sdrs::diff::backward`]): the same terms with exact Hessians, so the
    /// step residual is linearized exactly. Trajectories are recorded with
    /// `self` (the scene's `contact.ipc.hessian`); the solutions are the
    /// same stationary points either way.
    pub fn adjoint(&self) -> IpcFactory {
        IpcFactory {
            exact_hessian: true,
            ..self.clone()
        }
    }
}

/// Barrier force magnitude per unit `κ` at distance `d` (m) for activation
/// distance `d̂`: `|∂b/∂(d²)| · 2d` (N per J/m⁴).
pub fn force_per_kappa(d: f64, dhat: f64) -> f64 {
    barrier_derivative(d * d, dhat * dhat).abs() * 2.0 * d
}

/// This baseline's adaptive stiffness when the scene gives no `κ`: the
/// barrier force at half the activation distance balances the weight of all
/// moving mass, `κ = M g / (|b'(d̂²/4)| d̂)` (with `g ≥ 9.81 m/s²`), so a
/// resting contact settles well inside `(0, d̂)`. (IPC's own rule balances
/// the elastic and barrier gradients; rigid links have no elastic energy.)
pub fn adaptive_kappa(scene: &Scene, dhat: f64) -> f64 {
    let model = &scene.model;
    let mass: f64 = (0..model.links.len())
        .filter(|&i| !model.ancestor_dofs[i].is_empty())
        .map(|i| model.links[i].mass())
        .sum();
    let g = scene.settings.gravity.norm().max(9.81);
    mass.max(1e-3) * g / force_per_kappa(0.5 * dhat, dhat)
}

/// Surface meshes of every link (empty for links that do not collide):
/// the hull surfaces, or with `surface: source` the link's `surface_mesh`
/// where it has one ([`crate::surface`]; errors name the scene key, the
/// mesh file and the triangle or edge).
pub fn link_meshes(scene: &Scene, surface: SurfaceKind) -> Result<Vec<LinkMesh>, Invalid> {
    let model = &scene.model;
    let paths = match surface {
        SurfaceKind::Hulls => vec![None; model.links.len()],
        SurfaceKind::Source => crate::surface::surface_paths(scene)?,
    };
    (0..model.links.len())
        .map(|i| {
            let l = &model.links[i];
            if !l.collides {
                return Ok(LinkMesh::default());
            }
            if let Some(p) = &paths[i] {
                return crate::surface::load::load_surface_cached(&p.file, &p.element)
                    .map_err(|e| Invalid::new(&p.element, e.to_string()));
            }
            if l.hulls.is_empty() {
                return Ok(LinkMesh::default());
            }
            LinkMesh::from_hulls(model, i).map_err(|e| {
                Invalid::new(
                    format!(
                        "robot \"{}\" link \"{}\"",
                        model.robots[l.robot].name, l.name
                    ),
                    format!("IPC surface mesh: {e}"),
                )
            })
        })
        .collect()
}

/// The IPC surface setting of a scene (hulls without a contact section);
/// an error names a malformed `contact.ipc` section.
pub fn surface_kind(scene: &Scene) -> Result<SurfaceKind, Invalid> {
    match &scene.contact {
        None => Ok(SurfaceKind::Hulls),
        Some(c) => Ok(IpcSettings::of(c)?.surface),
    }
}

/// The frozen `topology` with vertex positions from the scene's hull
/// vertices (each template vertex's [`LinkMesh::source`]); a source-mesh
/// surface takes its positions from `Link::surface` when a design carries
/// it (same length), and keeps the template's otherwise.
pub fn meshes_with_topology(
    scene: &Scene,
    topology: &[LinkMesh],
) -> Result<Vec<LinkMesh>, Invalid> {
    let model = &scene.model;
    if topology.len() != model.links.len() {
        return Err(Invalid::new(
            "contact.model",
            format!(
                "the frozen IPC surfaces are for {} links, the model has {}",
                topology.len(),
                model.links.len()
            ),
        ));
    }
    (0..model.links.len())
        .map(|i| {
            let mut m = topology[i].clone();
            let l = &model.links[i];
            if let MeshOrigin::Source { .. } = m.origin {
                if l.surface.len() == m.x_local.len() {
                    m.x_local.clone_from(&l.surface);
                }
            } else {
            for (k, &(h, v)) in m.source.iter().enumerate() {
                let x = l
                    .hulls
                    .get(h as usize)
                    .and_then(|hh| hh.x_local.get(v as usize))
                    .ok_or_else(|| {
                        Invalid::new(
                            format!("robot \"{}\" link \"{}\"", model.robots[l.robot].name, l.name),
                            format!("frozen IPC surface vertex {k} refers to hull {h} vertex {v}, which does not exist"),
                        )
                    })?;
                m.x_local[k] = *x;
            }
            }
            for (e, len2) in m.edges.iter().zip(m.edge_len2.iter_mut()) {
                *len2 = (m.x_local[e[0] as usize] - m.x_local[e[1] as usize]).norm_squared();
            }
            m.radius = m.x_local.iter().map(|x| x.norm()).fold(0.0, f64::max);
            Ok(m)
        })
        .collect()
}

impl ContactModelFactory for IpcFactory {
    /// The same terms with exact per-primitive Hessians ([`IpcFactory::adjoint`]).
    fn adjoint_energies(
        &self,
        scene: &Scene,
        c: &ContactSettings,
    ) -> Result<Vec<Box<dyn Energy>>, Invalid> {
        self.adjoint().contact_energies(scene, c)
    }

    fn contact_energies(
        &self,
        scene: &Scene,
        c: &ContactSettings,
    ) -> Result<Vec<Box<dyn Energy>>, Invalid> {
        if c.model != ContactModelKind::Ipc {
            return Err(Invalid::new(
                "contact.model",
                format!("\"{}\" is not provided by the IPC baseline", c.model.name()),
            ));
        }
        let ipc = IpcSettings::of(c)?;
        let model = &scene.model;
        let meshes = match &self.topology {
            None => link_meshes(scene, ipc.surface)?,
            Some(t) => meshes_with_topology(scene, t)?,
        };
        let kappa = if c.kappa_given {
            c.kappa
        } else {
            adaptive_kappa(scene, ipc.dhat)
        };
        let params = IpcParams {
            dhat: ipc.dhat,
            kappa,
            ccd: self.ccd.clone(),
        };
        let mut contact = IpcContact::new(model, meshes.clone(), &c.excluded, params.clone());
        contact.exact_hessian = self.exact_hessian || ipc.hessian.is_exact();
        contact.kappa_given = c.kappa_given;
        let mut kin = Kinematics::new(model);
        kin.update(model, &scene.q0, &scene.charts, KinOrder::Pose);
        let (mut d, mut pair) = contact.min_distance(&kin.pose);
        if let Some(p) = crate::start_check::first_intersecting_surfaces(
            model,
            &meshes,
            &kin.pose,
            &contact.link_pairs,
        ) {
            (d, pair) = (0.0, Some(p));
        }
        if let (true, Some((a, b))) = (d <= 0.0, pair) {
            let name = |i: usize| {
                let l = &model.links[i];
                format!("{}/{}", model.robots[l.robot].name, l.name)
            };
            return Err(Invalid::new(
                "initial state",
                format!(
                    "{} and {} touch or intersect at the start; IPC needs a separated start",
                    name(a),
                    name(b)
                ),
            ));
        }
        let mut out: Vec<Box<dyn Energy>> = vec![Box::new(contact)];
        if c.mu > 0.0 {
            let mut friction = IpcFriction::new(
                model,
                meshes,
                &c.excluded,
                IpcFrictionParams {
                    dhat: ipc.dhat,
                    kappa,
                    mu: c.mu,
                    eps_v: ipc.eps_v,
                    dt: scene.settings.dt,
                },
            );
            friction.kappa_given = c.kappa_given;
            out.push(Box::new(friction));
        }
        Ok(out)
    }
}
