//! `--contact sdrs|ipc [--dhat D] [--kappa K]`: choose the contact model of a
//! run, overriding the scene's `contact.model`, and build the simulator
//! through the core's `Scene::simulator_with` with the IPC baseline's
//! factory (the core never depends on the baseline; the CLI joins them).

use anyhow::{Result, bail};
use sdrs::scene::Scene;
use sdrs::scene::schema::ContactModelKind;
use sdrs::sim::Simulator;

#[derive(clap::Args, Clone, Debug, Default)]
pub struct ContactArgs {
    /// Contact model: `sdrs` (separating planes) or `ipc` (the mesh-based
    /// IPC baseline). Default: the scene's `contact.model`.
    #[arg(long, value_parser = ["sdrs", "ipc"])]
    pub contact: Option<String>,
    /// IPC activation distance d̂ (m), overriding `contact.ipc.dhat`.
    #[arg(long)]
    pub dhat: Option<f64>,
    /// IPC barrier stiffness κ (J/m⁴), overriding `contact.kappa`. When a
    /// scene written for SDRS is switched to IPC with `--contact ipc`, its κ
    /// (an SDRS stiffness) is not used: κ is then adaptive unless given here.
    #[arg(long)]
    pub kappa: Option<f64>,
}

impl ContactArgs {
    /// Applies the overrides to a loaded scene.
    pub fn apply(&self, scene: &mut Scene) -> Result<()> {
        let Some(c) = scene.contact.as_mut() else {
            if self.contact.as_deref() == Some("ipc") || self.dhat.is_some() {
                eprintln!(
                    "note: {} has no `contact` section; --contact/--dhat change nothing",
                    scene.source.display()
                );
            }
            return Ok(());
        };
        if let Some(m) = &self.contact {
            let kind = if m == "ipc" {
                ContactModelKind::Ipc
            } else {
                ContactModelKind::Sdrs
            };
            if kind != c.model && kind == ContactModelKind::Ipc {
                c.kappa_given = false;
            }
            c.model = kind;
        }
        if let Some(d) = self.dhat {
            if !(d > 0.0 && d.is_finite()) {
                bail!(
                    "--dhat: the IPC activation distance must be positive and finite (m), got {d}"
                );
            }
            let mut ipc =
                sdrs_ipc::settings::IpcSettings::of(c).map_err(|e| e.at(&scene.source))?;
            ipc.dhat = d;
            ipc.store(c).map_err(|e| e.at(&scene.source))?;
        }
        if let Some(k) = self.kappa {
            if !(k > 0.0 && k.is_finite()) {
                bail!("--kappa: must be positive and finite, got {k}");
            }
            c.kappa = k;
            c.kappa_given = true;
        }
        Ok(())
    }
}

/// With `--export` under IPC with `contact.ipc.surface: source`: writes
/// `DIR/surfaces.json` (the source-mesh surfaces, link frame), which
/// `tools/check/check_separation.py` uses instead of those links' hulls.
pub fn export_surfaces(dir: &std::path::Path, scene: &Scene) -> Result<()> {
    let Some(c) = scene.contact.as_ref() else {
        return Ok(());
    };
    if c.model != ContactModelKind::Ipc {
        return Ok(());
    }
    let surface = sdrs_ipc::settings::IpcSettings::of(c)
        .map_err(|e| e.at(&scene.source))?
        .surface;
    if surface.is_hulls() {
        return Ok(());
    }
    let meshes = sdrs_ipc::factory::link_meshes(scene, surface).map_err(|e| e.at(&scene.source))?;
    if let Some(json) = sdrs_ipc::surface::export::surfaces_json(&scene.model, &meshes) {
        sdrs::output::write_atomic(
            &dir.join("surfaces.json"),
            serde_json::to_string(&json)?.as_bytes(),
        )?;
    }
    Ok(())
}

/// The scene's simulator with the selected contact model.
pub fn simulator(scene: &Scene) -> Result<Simulator> {
    Ok(scene.simulator_with(&sdrs_ipc::IpcFactory::default())?)
}

/// `sdrs optimize --contact … [--cage coarse|fine|k]`: applies the contact
/// overrides to every trajectory of `problem`, gives it the IPC baseline's
/// factory (SDRS scenes never use it), and with `cage` replaces the design
/// by the cage vertices of the task's `design.vertices` links (automatic
/// box cages, mean value coordinates; see `sdrs_ipc::cage`), bounded by the
/// task's `design.bound`. With IPC contact the cage deforms the meshes (the
/// mesh baseline); with the SDRS contact it deforms the hulls.
pub fn configure_problem(
    problem: &mut sdrs::optimize::Problem,
    args: &ContactArgs,
    cage: Option<&str>,
    design_on: bool,
) -> Result<()> {
    let factory: sdrs::scene::SharedContactFactory =
        std::sync::Arc::new(sdrs_ipc::IpcFactory::default());
    for t in &mut problem.trajectories {
        args.apply(&mut t.scene)?;
    }
    problem.set_contact_factory(factory);
    let Some(cage) = cage else {
        sdrs_ipc::surface::design::check_vertex_design(problem)?;
        return Ok(());
    };
    let res = sdrs_ipc::cage::CageResolution::parse(cage).map_err(anyhow::Error::msg)?;
    let is_ipc = |s: &Scene| {
        s.contact
            .as_ref()
            .is_some_and(|c| c.model == ContactModelKind::Ipc)
    };
    // On the separating-plane contact the cage deforms the hulls alone (the
    // IPC factory is never used): the cage's design space with the SDRS
    // contact, which separates the design space from the contact model in a
    // comparison (notes/paper-step-rule.md, the biped).
    let contact = if is_ipc(&problem.first().scene) {
        "IPC surfaces keep their rest triangulation"
    } else {
        "separating-plane contact: the cage deforms the hulls"
    };
    if !design_on {
        bail!("--cage {cage} with --design off: the cage vertices are the design");
    }
    let summary = sdrs_ipc::cage::cage_problem(problem, res)?;
    eprintln!(
        "--cage {cage}: {} cage(s) of {} vertices replace the design ({} variables); {contact}",
        summary.cage_vertices.len(),
        summary
            .cage_vertices
            .iter()
            .map(|n| n.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        summary.variables
    );
    Ok(())
}
