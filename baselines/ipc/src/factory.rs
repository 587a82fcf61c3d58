//! [`IpcFactory`]: the [`ContactModelFactory`] for `contact.model: ipc`,
//! passed by the CLI to `Scene::simulator_with` (the core never depends on
//! this crate). Builds each link's surface mesh, checks the start is
//! intersection-free, chooses `κ` when the scene gives none, and returns the
//! contact term (and the friction term when `μ > 0`).

use crate::barrier::barrier_derivative;
use crate::contact::{IpcContact, IpcParams};
use crate::friction::{IpcFriction, IpcFrictionParams};
use crate::line_search::CcdOptions;
use crate::mesh::LinkMesh;
use sdrs::energy::Energy;
use sdrs::kinematics::{KinOrder, Kinematics};
use sdrs::scene::schema::ContactModelKind;
use sdrs::scene::{ContactModelFactory, ContactSettings, Invalid, Scene};

/// Provides the IPC baseline's terms.
#[derive(Clone, Debug, Default)]
pub struct IpcFactory {
    /// CCD settings (defaults documented on [`CcdOptions`]).
    pub ccd: CcdOptions,
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

/// Surface meshes of every link (empty for links that do not collide).
pub fn link_meshes(scene: &Scene) -> Result<Vec<LinkMesh>, Invalid> {
    let model = &scene.model;
    (0..model.links.len())
        .map(|i| {
            let l = &model.links[i];
            if !l.collides || l.hulls.is_empty() {
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

impl ContactModelFactory for IpcFactory {
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
        let model = &scene.model;
        let meshes = link_meshes(scene)?;
        let kappa = if c.kappa_given {
            c.kappa
        } else {
            adaptive_kappa(scene, c.dhat)
        };
        let params = IpcParams {
            dhat: c.dhat,
            kappa,
            ccd: self.ccd.clone(),
        };
        let mut contact = IpcContact::new(model, meshes.clone(), &c.excluded, params.clone());
        let mut kin = Kinematics::new(model);
        kin.update(model, &scene.q0, &scene.charts, KinOrder::Pose);
        let (mut d, mut pair) = contact.min_distance(&kin.pose);
        if let Some(p) =
            crate::start_check::first_intersecting(model, &kin.pose, &contact.link_pairs)
        {
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
            out.push(Box::new(IpcFriction::new(
                model,
                meshes,
                &c.excluded,
                IpcFrictionParams {
                    dhat: c.dhat,
                    kappa,
                    mu: c.mu,
                    eps_v: c.eps_v,
                    dt: scene.settings.dt,
                },
            )));
        }
        Ok(out)
    }
}
