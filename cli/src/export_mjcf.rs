//! `sdrs export-mjcf`: a scene's robots as MJCF for MuJoCo
//! (`sdrs::output::mjcf` says what is translated).

use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct ExportMjcfArgs {
    /// Scene file (YAML).
    pub scene: PathBuf,
    /// Output MJCF file.
    #[arg(long)]
    pub out: PathBuf,
    /// Overwrite the output if it exists.
    #[arg(long)]
    pub force: bool,
    /// Model name. Default: the scene file's stem.
    #[arg(long)]
    pub name: Option<String>,
    /// Also write the PD controller's constant-target channels on hinges and
    /// slides as MuJoCo `<position kp="2 k_p" kv="2 k_d/Δt">` actuators with
    /// the target as the keyframe's ctrl (`sdrs::output::mjcf::pd_actuators`).
    #[arg(long)]
    pub actuators: bool,
}

pub fn run(a: ExportMjcfArgs) -> Result<()> {
    let scene = sdrs::scene::Scene::load(&a.scene)?;
    anyhow::ensure!(
        a.force || !a.out.exists(),
        "{} exists; pass --force to overwrite it",
        a.out.display()
    );
    let name = a.name.clone().unwrap_or_else(|| {
        a.scene
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "sdrs".into())
    });
    let text = sdrs::output::mjcf::scene_to_mjcf_with(&scene, &name, a.actuators);
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let tmp = a.out.with_extension("xml.tmp");
    std::fs::write(&tmp, text).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, &a.out).with_context(|| format!("writing {}", a.out.display()))?;
    Ok(())
}
