//! Reading a source mesh and building its [`LinkMesh`]: the file is read by
//! the importer's reader (`.obj`, `.stl`, `.dae`; coincident vertices
//! welded), checked ([`super::topology`], [`super::self_intersect`]), split
//! into connected components, each turned outward (positive enclosed
//! volume) and appended as one closed component.

use super::SurfaceError;
use super::self_intersect::first_self_intersection;
use super::topology::{check_closed_oriented, check_metric, components, signed_volume};
use crate::mesh::{LinkMesh, MeshOrigin};
use nalgebra::Vector3;
use sdrs::import::mesh::{MeshContext, load_mesh};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};
use std::time::SystemTime;

/// Checked surfaces already built in this process, by file, keyed by the
/// file's length and modification time (a changed file is read again).
type Cache = Mutex<HashMap<PathBuf, (u64, Option<SystemTime>, LinkMesh)>>;
static CACHE: OnceLock<Cache> = OnceLock::new();

/// [`load_surface`] through a per-process cache: every simulator the IPC
/// factory builds (each optimizer evaluation, finite differences, the
/// backward pass) would otherwise re-read and re-check the file (0.18 s for
/// a 39,600-triangle mesh). Errors are not cached.
pub fn load_surface_cached(file: &Path, element: &str) -> Result<LinkMesh, SurfaceError> {
    let meta = std::fs::metadata(file).ok();
    let key = meta.as_ref().map(|m| (m.len(), m.modified().ok()));
    let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
    if let (Some((len, time)), Ok(c)) = (key, cache.lock())
        && let Some((l, t, m)) = c.get(file)
        && *l == len
        && *t == time
    {
        return Ok(m.clone());
    }
    let m = load_surface(file, element)?;
    if let (Some((len, time)), Ok(mut c)) = (key, cache.lock()) {
        c.insert(file.to_path_buf(), (len, time, m.clone()));
    }
    Ok(m)
}

/// Reads `file` (named in errors; `element` is the scene key that refers to
/// it, for the reader's own messages) and builds its checked surface.
pub fn load_surface(file: &Path, element: &str) -> Result<LinkMesh, SurfaceError> {
    let ctx = MeshContext {
        file: file.to_path_buf(),
        element: element.to_string(),
    };
    let (m, _note) = load_mesh(file, &ctx).map_err(|e| SurfaceError::Read {
        file: file.to_path_buf(),
        msg: e.to_string(),
    })?;
    surface_from_triangles(file, &m.vertices, &m.triangles)
}

/// The checked surface of `vertices`/`tris` (`file` names it in errors).
pub fn surface_from_triangles(
    file: &Path,
    vertices: &[Vector3<f64>],
    tris: &[[usize; 3]],
) -> Result<LinkMesh, SurfaceError> {
    if let Some((i, t)) = tris
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&k| k >= vertices.len()))
    {
        return Err(SurfaceError::Read {
            file: file.to_path_buf(),
            msg: format!(
                "triangle {i} uses vertex {:?}, but the mesh has {} vertices",
                t,
                vertices.len()
            ),
        });
    }
    check_metric(file, vertices, tris)?;
    // Components are vertex-disjoint: the edge analysis of the whole mesh
    // is that of each component.
    check_closed_oriented(file, vertices, tris)?;
    let mut mesh = LinkMesh {
        origin: MeshOrigin::Source {
            file: file.to_path_buf(),
        },
        ..LinkMesh::default()
    };
    for (c, comp) in components(vertices.len(), tris).iter().enumerate() {
        if let Some((t1, t2)) = first_self_intersection(vertices, tris, comp) {
            return Err(SurfaceError::SelfIntersection {
                file: file.to_path_buf(),
                t1,
                t2,
                v1: tris[t1],
                v2: tris[t2],
                p1: Box::new(tris[t1].map(|k| super::xyz(&vertices[k]))),
                p2: Box::new(tris[t2].map(|k| super::xyz(&vertices[k]))),
            });
        }
        let mut local: Vec<usize> = comp.iter().flat_map(|&t| tris[t]).collect();
        local.sort_unstable();
        local.dedup();
        let index = |g: usize| local.binary_search(&g).unwrap_or_default();
        let verts: Vec<Vector3<f64>> = local.iter().map(|&g| vertices[g]).collect();
        let mut ctris: Vec<[usize; 3]> = comp.iter().map(|&t| tris[t].map(index)).collect();
        if signed_volume(&verts, &ctris) < 0.0 {
            for t in &mut ctris {
                t.swap(1, 2);
            }
        }
        mesh.add_closed(c, &verts, &ctris)
            .map_err(|e| SurfaceError::Read {
                file: file.to_path_buf(),
                msg: e.to_string(),
            })?;
    }
    mesh.radius = mesh.x_local.iter().map(|x| x.norm()).fold(0.0, f64::max);
    Ok(mesh)
}
