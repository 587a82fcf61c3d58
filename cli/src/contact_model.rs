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
    /// IPC activation distance d̂ (m), overriding `contact.dhat`.
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
            c.dhat = d;
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

/// The scene's simulator with the selected contact model.
pub fn simulator(scene: &Scene) -> Result<Simulator> {
    Ok(scene.simulator_with(&sdrs_ipc::IpcFactory::default())?)
}
