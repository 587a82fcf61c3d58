//! The topology of every designable link ([`crate::geometry::topology`]),
//! for the topology metric ([`super::metric::TopologyMetric`]), and a
//! runnable optimized scene per trajectory.

use super::{OptimizeError, Outcome, Problem, names, output};
use crate::files::write_atomic;
use crate::geometry::topology;
use nalgebra::DVector;
use std::path::Path;

/// Voxels along a link's longest side for the topology measure.
pub const TOPOLOGY_RESOLUTION: usize = 64;

/// Topology of each designable link (`design.vertices`) of `p` at `d`.
pub fn topologies(p: &Problem, d: &DVector<f64>) -> Result<serde_json::Value, OptimizeError> {
    let mut model = p.first().model.clone();
    p.design.apply(&mut model, d);
    let mut out = serde_json::Map::new();
    let links = p
        .task
        .design
        .as_ref()
        .map(|x| x.vertices.clone())
        .unwrap_or_default();
    for name in links {
        let l = names::link(&model, &name).map_err(|e| OptimizeError::Invalid {
            element: "design.vertices".into(),
            msg: e.to_string(),
        })?;
        let hulls: Vec<_> = model.links[l]
            .hulls
            .iter()
            .map(|h| h.x_local.clone())
            .collect();
        let t = topology::measure(&hulls, TOPOLOGY_RESOLUTION).map_err(|err| {
            OptimizeError::Topology {
                link: name.clone(),
                err,
            }
        })?;
        let t = serde_json::to_value(t).map_err(|e| OptimizeError::serialize(&name, e))?;
        out.insert(name, t);
    }
    Ok(serde_json::Value::Object(out))
}

/// Writes `scenes/<scene file name>` for every trajectory: its scene with
/// the optimized design and controller (`sdrs simulate` runs it).
pub fn write_scenes(dir: &Path, p: &Problem, o: &Outcome) -> Result<(), OptimizeError> {
    write_scenes_at(dir, p, (&o.design, &o.controller), "the design optimized")
}

/// [`write_scenes`] for any design and controller vectors `(d, c)`, e.g. a
/// trial point that could not be simulated; `what` names them in each
/// file's header ("# <scene> with <what> by `sdrs optimize <task>`").
pub fn write_scenes_at(
    dir: &Path,
    p: &Problem,
    (d, c): (&DVector<f64>, &DVector<f64>),
    what: &str,
) -> Result<(), OptimizeError> {
    for q in &p.trajectories {
        let mut model = q.model.clone();
        p.design.apply(&mut model, d);
        let mut controller = q.controller.clone();
        p.controls.apply(&mut controller, c);
        let spec = output::scene_as_run(&q.scene, &model, &controller);
        let name = q
            .scene
            .source
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene.yaml".into());
        let header = format!(
            "# {} with {what} by `sdrs optimize {}`; horizon {} steps.\n",
            q.scene.source.display(),
            p.task_path.display(),
            q.horizon
        );
        let yaml = serde_yaml::to_string(&spec).map_err(|e| OptimizeError::serialize(&name, e))?;
        write_atomic(&dir.join("scenes").join(name), (header + &yaml).as_bytes())?;
    }
    Ok(())
}
