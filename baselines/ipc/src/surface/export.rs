//! `surfaces.json` next to an `--export` run's `hulls.json`: the IPC
//! contact surface of every link whose surface is a source mesh (link
//! frame), so the independent checker (`tools/check/check_separation.py`) tests
//! those links' meshes instead of their hulls.
//!
//! ```json
//! {"links": [{"link": 3, "name": "robot/link", "file": "cup.obj",
//!             "vertices": [[x, y, z], …], "triangles": [[i, j, k], …]}]}
//! ```

use crate::mesh::{LinkMesh, MeshOrigin};
use sdrs::model::Model;

/// The JSON document for `meshes` (one per model link; only source-mesh
/// surfaces are listed). `None` when no link has one.
pub fn surfaces_json(model: &Model, meshes: &[LinkMesh]) -> Option<serde_json::Value> {
    let links: Vec<serde_json::Value> = meshes
        .iter()
        .enumerate()
        .filter_map(|(i, m)| match &m.origin {
            MeshOrigin::Source { file } => Some(serde_json::json!({
                "link": i,
                "name": format!("{}/{}", model.robots[model.links[i].robot].name, model.links[i].name),
                "file": file.display().to_string(),
                "vertices": m.x_local.iter().map(|x| [x.x, x.y, x.z]).collect::<Vec<_>>(),
                "triangles": m.tris.clone(),
            })),
            MeshOrigin::Hulls => None,
        })
        .collect();
    (!links.is_empty()).then(|| serde_json::json!({ "links": links }))
}
