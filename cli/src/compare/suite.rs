//! Suite files of `sdrs compare` (YAML): which benchmarks run, at which
//! sizes. `--suite quick|paper` loads the bundled `robots/compare/<name>.yaml`;
//! any other value is a path to a suite file. Paths inside a suite are
//! relative to the suite file.
//!
//! ```yaml
//! suite: quick
//! potential: {sizes: [8, 32, 128, 512], pairs: 2, reps: 40, seed: 2024, ipctk: false}
//! chains: {scene: ../four_chains.yaml, links: [2, 4], steps: 150, models: [sdrs, ipc], backward: true, fcl: true}
//! codesign:
//!   - {name: chain_reach, task: ../chain_reach/task.yaml, iters: 3, fd_check: true}
//! ```

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A whole suite.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Suite {
    /// Name written into the results (`quick`, `paper`, …).
    pub suite: String,
    #[serde(default)]
    pub potential: Option<PotentialSpec>,
    #[serde(default)]
    pub chains: Option<ChainsSpec>,
    #[serde(default)]
    pub codesign: Vec<CodesignSpec>,
}

/// Contact-potential cost vs hull vertex count.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PotentialSpec {
    /// Vertices per hull.
    pub sizes: Vec<usize>,
    /// Random hull pairs per size (default 4).
    #[serde(default = "four")]
    pub pairs: usize,
    /// Timed repetitions per pair and model (default 40; the median is kept).
    #[serde(default = "forty")]
    pub reps: usize,
    /// Seed of the random hulls (default 2024).
    #[serde(default = "seed")]
    pub seed: u64,
    /// Also time ipc-toolkit (Python, `.venv`) when installed (default true).
    #[serde(default = "yes")]
    pub ipctk: bool,
}

/// The four rotating chains, ms/step vs links per chain.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChainsSpec {
    /// Scene with `chain` robots (default `../four_chains.yaml`).
    #[serde(default = "chains_scene")]
    pub scene: PathBuf,
    /// Links per chain.
    pub links: Vec<usize>,
    /// Steps per run.
    pub steps: usize,
    /// Runs per model and chain length, models alternating; the fastest is
    /// kept (default 3).
    #[serde(default = "three")]
    pub repeats: usize,
    /// Contact models (default both).
    #[serde(default = "both_models")]
    pub models: Vec<String>,
    /// Also time the SDRS adjoint (backward pass) over the same run (default true).
    #[serde(default = "yes")]
    pub backward: bool,
    /// Check every step's hull distances with python-fcl when installed (default true).
    #[serde(default = "yes")]
    pub fcl: bool,
}

/// One co-design benchmark: the task with shape + controller, and with the
/// controller alone (`--design off`).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CodesignSpec {
    pub name: String,
    pub task: PathBuf,
    /// Optimizer iterations (default: the task's).
    #[serde(default)]
    pub iters: Option<usize>,
    /// Horizon override (default: the task's).
    #[serde(default)]
    pub horizon: Option<usize>,
    /// Central-difference check of the design-gradient component of largest
    /// magnitude at the initial design (default true).
    #[serde(default = "yes")]
    pub fd_check: bool,
    /// Also run the mesh-based co-design (Xu et al. 2021): the same task
    /// under the IPC baseline with the cage vertices of an automatic cage
    /// of each listed resolution as the design (`coarse` = 26 vertices,
    /// `fine` = 98, or `k` segments per box edge; see `sdrs optimize
    /// --cage`). Default none.
    #[serde(default)]
    pub cages: Vec<String>,
}

fn four() -> usize {
    4
}
fn three() -> usize {
    3
}
fn forty() -> usize {
    40
}
fn seed() -> u64 {
    2024
}
fn yes() -> bool {
    true
}
fn chains_scene() -> PathBuf {
    "../four_chains.yaml".into()
}
fn both_models() -> Vec<String> {
    vec!["sdrs".into(), "ipc".into()]
}

impl Suite {
    /// Loads `quick`/`paper` (bundled) or a suite file; returns the suite
    /// and the folder its relative paths start from.
    pub fn load(name: &str) -> Result<(Suite, PathBuf)> {
        let path = match name {
            "quick" | "paper" => crate::util::bundled(&format!("robots/compare/{name}.yaml"))?,
            p => PathBuf::from(p),
        };
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("{}: cannot read the suite file", path.display()))?;
        let suite: Suite = serde_yaml::from_str(&text)
            .with_context(|| format!("{}: malformed suite", path.display()))?;
        suite.validate(&path)?;
        let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        Ok((suite, dir))
    }

    fn validate(&self, path: &Path) -> Result<()> {
        let p = path.display();
        if let Some(s) = &self.potential {
            if s.sizes.is_empty() || s.sizes.iter().any(|&m| m < 4) {
                bail!("{p}: potential.sizes: need at least one size, each ≥ 4 vertices");
            }
            if s.pairs == 0 || s.reps == 0 {
                bail!("{p}: potential.pairs and potential.reps must be ≥ 1");
            }
        }
        if let Some(c) = &self.chains {
            if c.links.is_empty() || c.links.contains(&0) || c.steps == 0 || c.repeats == 0 {
                bail!("{p}: chains: links must be non-empty and ≥ 1, steps and repeats ≥ 1");
            }
            for m in &c.models {
                if m != "sdrs" && m != "ipc" {
                    bail!("{p}: chains.models: unknown contact model `{m}` (sdrs or ipc)");
                }
            }
        }
        let mut names = std::collections::BTreeSet::new();
        for c in &self.codesign {
            if !names.insert(&c.name) {
                bail!("{p}: codesign: the name `{}` appears twice", c.name);
            }
            if c.horizon == Some(0) {
                bail!("{p}: codesign `{}`: horizon must be ≥ 1", c.name);
            }
        }
        Ok(())
    }
}
