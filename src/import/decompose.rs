//! Convex decomposition of one mesh into hulls.
//!
//! - `vhacd` (default): V-HACD from parry3d on a voxelization of the mesh.
//!   Hulls are the convex hulls of each part's surface voxels (every voxel
//!   corner is used: `convex_hull_downsampling = 1`), so neighbouring parts
//!   touch exactly along their cut planes and the hulls cover the mesh to
//!   within half a voxel. parry does not merge parts, so when it returns more
//!   than `max_hulls` parts we merge the pair whose merged hull adds the
//!   least volume until `max_hulls` remain.
//! - `coacd`: CoACD through `tools/helpers/coacd_decompose.py` (Python `coacd`
//!   package), `threshold` is its concavity threshold, `max_hulls` its
//!   `max_convex_hull`, `resolution` its `resolution`.
//! - `hull`: one convex hull of the whole mesh.
//! - With [`HullPoints::Mesh`] (`--hull-points mesh`, V-HACD and CoACD) the
//!   parts only *partition the mesh's vertices*: a closed convex mesh (volume
//!   equal to its hull's to 1e-6) stays one hull; otherwise each vertex `v`
//!   goes to the part `p` minimising `violation_p(v) = max_i (n_i·v − b_i)`
//!   (deepest inside, lowest index on a tie), and part `p`'s hull is the convex
//!   hull of its vertices plus, for every mesh edge `(u, v)` with
//!   `part(u) = p < part(v)`, the vertex `v`. So neighbouring hulls share the
//!   vertices of the edges that cross between them (they touch or overlap,
//!   and the connectivity step ties each such pair through one shared
//!   vertex), every mesh triangle lies in one hull, and a hull has the mesh's
//!   own vertices (a 96-vertex foot in 3 parts gives about 96 + the shared
//!   boundary vertices) instead of one per voxel corner. Deterministic: the
//!   same mesh and parameters give the same hulls.
//! - `grid`: about `max_hulls` equal boxes on a grid over the mesh (the
//!   paper's block design space; see [`super::grid`]); neighbouring blocks'
//!   coincident corners are tied instead of the usual shared vertices.
//! - `none`: the mesh must already be convex (its volume equals its hull's to
//!   1e-6 relative); otherwise an error.

use super::ImportOptions;
use super::cache::DiskCache;
use super::error::ImportError;
use super::mesh::{MeshContext, TriMesh};
use super::polytope::{Polytope, convex_hull};
use super::python;
use nalgebra::Vector3;
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::transformation::vhacd::{VHACD, VHACDParameters};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Which decomposition to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Decomposer {
    Vhacd,
    Coacd,
    Hull,
    None,
    Grid,
}

impl Decomposer {
    pub fn name(&self) -> &'static str {
        match self {
            Decomposer::Vhacd => "vhacd",
            Decomposer::Coacd => "coacd",
            Decomposer::Hull => "hull",
            Decomposer::None => "none",
            Decomposer::Grid => "grid",
        }
    }
}

impl std::str::FromStr for Decomposer {
    type Err = String;
    /// `vhacd`, `coacd`, `hull`, `none` or `grid` (any case).
    fn from_str(s: &str) -> Result<Self, String> {
        let all = [
            Decomposer::Vhacd,
            Decomposer::Coacd,
            Decomposer::Hull,
            Decomposer::None,
            Decomposer::Grid,
        ];
        super::pick_name(s, &all, |d| d.name())
    }
}

/// Which points span a decomposed part's hull.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HullPoints {
    /// The decomposer's own points (V-HACD: every surface voxel corner).
    #[default]
    Voxels,
    /// The source mesh's vertices, partitioned by the parts (module docs).
    Mesh,
}

impl std::str::FromStr for HullPoints {
    type Err = String;
    /// `voxels` or `mesh` (any case).
    fn from_str(s: &str) -> Result<Self, String> {
        super::pick_name(s, &[HullPoints::Voxels, HullPoints::Mesh], |h| match h {
            HullPoints::Voxels => "voxels",
            HullPoints::Mesh => "mesh",
        })
    }
}

/// The decompositions made so far in one import, keyed by the mesh as
/// placed in its link (vertex bits and triangles), the decomposer and the
/// hull budget: a robot's repeated parts (a quadruped's four legs, a
/// gripper's two fingers) are decomposed once, also when links are
/// imported in parallel (the first request of a key computes it, the
/// others wait for it). Every decomposer is deterministic (V-HACD runs
/// sequentially, CoACD with a fixed seed), so a hit returns exactly what a
/// new run would, whichever thread ran it; a failure is not kept (each
/// caller that meets it runs the decomposition itself and gets its own
/// error). With [`ImportOptions::cache`], V-HACD results also come from and
/// go to the disk cache ([`super::cache`]).
#[derive(Default)]
pub struct Memo {
    seen: Mutex<HashMap<MemoKey, Arc<MemoCell>>>,
    disk: Option<DiskCache>,
}

type MemoKey = (Decomposer, usize, Vec<[u64; 3]>, Vec<[usize; 3]>);

/// One key's result: set once by the first request (`None`: it failed).
type MemoCell = OnceLock<Option<Vec<Polytope>>>;

impl Memo {
    /// An empty memo for one import with `opts` (opening its disk cache).
    pub fn new(opts: &ImportOptions) -> Result<Memo, ImportError> {
        let disk = match &opts.cache {
            Some(dir) if DiskCache::caches(opts.decomposer) => Some(DiskCache::open(dir)?),
            _ => None,
        };
        Ok(Memo {
            seen: Default::default(),
            disk,
        })
    }

    /// [`decompose`], or the stored result of the same call.
    pub fn decompose(
        &self,
        mesh: &TriMesh,
        opts: &ImportOptions,
        max_hulls: usize,
        ctx: &MeshContext,
    ) -> Result<Vec<Polytope>, ImportError> {
        let bits = |v: &Vector3<f64>| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
        let key = (
            opts.decomposer,
            max_hulls,
            mesh.vertices.iter().map(bits).collect(),
            mesh.triangles.clone(),
        );
        let cell = {
            let mut seen = self.seen.lock().unwrap_or_else(|e| e.into_inner());
            Arc::clone(seen.entry(key).or_default())
        };
        let mut failure = None;
        let parts = cell.get_or_init(|| match self.compute(mesh, opts, max_hulls, ctx) {
            Ok(parts) => Some(parts),
            Err(e) => {
                failure = Some(e);
                None
            }
        });
        match (parts, failure) {
            (Some(parts), _) => Ok(parts.clone()),
            (None, Some(e)) => Err(e),
            // Another caller's failure: run it for this caller's error.
            (None, None) => self.compute(mesh, opts, max_hulls, ctx),
        }
    }

    /// [`decompose`] through the disk cache.
    fn compute(
        &self,
        mesh: &TriMesh,
        opts: &ImportOptions,
        max_hulls: usize,
        ctx: &MeshContext,
    ) -> Result<Vec<Polytope>, ImportError> {
        let disk = self
            .disk
            .as_ref()
            .filter(|_| DiskCache::caches(opts.decomposer));
        if let Some(parts) = disk.and_then(|d| d.load(mesh, opts, max_hulls)) {
            return Ok(parts);
        }
        let parts = decompose(mesh, opts, max_hulls, ctx)?;
        if let Some(d) = disk {
            d.store(mesh, opts, max_hulls, &parts)?;
        }
        Ok(parts)
    }
}

/// Decomposes `mesh` into at most `opts.max_hulls` convex hulls.
pub fn decompose(
    mesh: &TriMesh,
    opts: &ImportOptions,
    max_hulls: usize,
    ctx: &MeshContext,
) -> Result<Vec<Polytope>, ImportError> {
    let fail = |msg: String| ImportError::Decomposition {
        path: ctx.file.clone(),
        element: ctx.element.clone(),
        msg,
    };
    let whole =
        || convex_hull(&mesh.vertices).map_err(|e| fail(format!("the mesh has no volume: {e}")));
    match opts.decomposer {
        Decomposer::Hull => Ok(vec![whole()?]),
        Decomposer::Grid => super::grid::grid_blocks(mesh, max_hulls).map_err(fail),
        Decomposer::None => {
            let h = whole()?;
            let hv = h.volume();
            let mv = mesh.volume();
            match mv {
                Some(v) if (hv - v).abs() <= 1e-6 * hv => Ok(vec![h]),
                Some(v) => Err(fail(format!(
                    "--decomposer none needs a convex mesh, but the mesh volume {v:.6e} differs from its convex hull's {hv:.6e}; use vhacd, coacd or hull"
                ))),
                None => Err(fail(
                    "--decomposer none needs a closed convex mesh, but the mesh has open edges; use vhacd, coacd or hull".into(),
                )),
            }
        }
        Decomposer::Vhacd | Decomposer::Coacd
            if opts.hull_points == HullPoints::Mesh && is_convex(mesh)? =>
        {
            Ok(vec![whole()?])
        }
        Decomposer::Vhacd => {
            let points: Vec<PVec> = mesh
                .vertices
                .iter()
                .map(|v| PVec::new(v.x, v.y, v.z))
                .collect();
            let indices: Vec<[u32; 3]> =
                mesh.triangles.iter().map(|t| t.map(|i| i as u32)).collect();
            let params = VHACDParameters {
                resolution: opts.resolution,
                concavity: opts.threshold,
                max_convex_hulls: max_hulls as u32,
                convex_hull_downsampling: 1,
                ..VHACDParameters::default()
            };
            let v = VHACD::decompose(&params, &points, &indices, false);
            let mut hulls = Vec::new();
            for (verts, _) in v.compute_convex_hulls(1) {
                let pts: Vec<Vector3<f64>> =
                    verts.iter().map(|p| Vector3::new(p.x, p.y, p.z)).collect();
                if let Ok(h) = convex_hull(&pts) {
                    hulls.push(h);
                }
            }
            if hulls.is_empty() {
                return Err(fail("V-HACD returned no part (is the mesh closed?)".into()));
            }
            let parts = merge_down(hulls, max_hulls).map_err(fail)?;
            finish(mesh, parts, opts.hull_points).map_err(fail)
        }
        Decomposer::Coacd => {
            let hulls = coacd(mesh, opts, max_hulls, ctx)?;
            let parts = merge_down(hulls, max_hulls).map_err(fail)?;
            finish(mesh, parts, opts.hull_points).map_err(fail)
        }
    }
}

/// Whether `mesh` is closed and convex: its volume equals its hull's to
/// 1e-6 relative.
fn is_convex(mesh: &TriMesh) -> Result<bool, ImportError> {
    let Some(v) = mesh.volume() else {
        return Ok(false);
    };
    let h = convex_hull(&mesh.vertices)
        .map(|h| h.volume())
        .unwrap_or(0.0);
    Ok(h > 0.0 && (h - v).abs() <= 1e-6 * h)
}

/// The parts' hulls as `points` selects (module docs).
fn finish(
    mesh: &TriMesh,
    parts: Vec<Polytope>,
    points: HullPoints,
) -> Result<Vec<Polytope>, String> {
    match points {
        HullPoints::Voxels => Ok(parts),
        HullPoints::Mesh => mesh_vertex_hulls(mesh, &parts),
    }
}

/// Partitions the mesh vertices over `parts` and hulls each share with the
/// vertices across its crossing edges (module docs, [`HullPoints::Mesh`]).
/// Parts that receive too few vertices to span a volume are dropped.
pub fn mesh_vertex_hulls(mesh: &TriMesh, parts: &[Polytope]) -> Result<Vec<Polytope>, String> {
    let owner: Vec<usize> = mesh
        .vertices
        .iter()
        .map(|v| {
            let mut best = (f64::INFINITY, 0);
            for (p, part) in parts.iter().enumerate() {
                let d = part.violation(v);
                if d < best.0 {
                    best = (d, p);
                }
            }
            best.1
        })
        .collect();
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); parts.len()];
    for (i, &p) in owner.iter().enumerate() {
        members[p].push(i);
    }
    for t in &mesh.triangles {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            let (pu, pv) = (owner[u], owner[v]);
            if pu < pv {
                members[pu].push(v);
            } else if pv < pu {
                members[pv].push(u);
            }
        }
    }
    let mut hulls = Vec::new();
    for mut m in members {
        m.sort_unstable();
        m.dedup();
        let pts: Vec<Vector3<f64>> = m.iter().map(|&i| mesh.vertices[i]).collect();
        if pts.len() >= 4
            && let Ok(h) = convex_hull(&pts)
        {
            hulls.push(h);
        }
    }
    if hulls.is_empty() {
        return Err("no part kept enough mesh vertices to span a hull".into());
    }
    Ok(hulls)
}

/// Greedily merges hull pairs (smallest added volume first) until at most
/// `max` remain.
fn merge_down(mut hulls: Vec<Polytope>, max: usize) -> Result<Vec<Polytope>, String> {
    let max = max.max(1);
    while hulls.len() > max {
        let mut best: Option<(f64, usize, usize, Polytope)> = None;
        for i in 0..hulls.len() {
            for j in i + 1..hulls.len() {
                let mut pts = hulls[i].vertices.clone();
                pts.extend_from_slice(&hulls[j].vertices);
                let m = convex_hull(&pts)?;
                let cost = m.volume() - hulls[i].volume() - hulls[j].volume();
                if best.as_ref().is_none_or(|b| cost < b.0) {
                    best = Some((cost, i, j, m));
                }
            }
        }
        let (_, i, j, m) = best.expect("at least two hulls");
        hulls.swap_remove(j);
        hulls[i] = m;
    }
    Ok(hulls)
}

/// Runs CoACD through the Python helper: mesh (OBJ) in, hulls (JSON) out.
fn coacd(
    mesh: &TriMesh,
    opts: &ImportOptions,
    max_hulls: usize,
    ctx: &MeshContext,
) -> Result<Vec<Polytope>, ImportError> {
    let fail = |msg: String| ImportError::Decomposition {
        path: ctx.file.clone(),
        element: ctx.element.clone(),
        msg,
    };
    let tmp = python::TempDir::create(std::env::temp_dir().join(format!(
        "sdrs-coacd-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    )))
    .map_err(|e| fail(format!("temporary directory: {e}")))?;
    let input = tmp.path().join("mesh.obj");
    let output = tmp.path().join("hulls.json");
    let result = (|| {
        std::fs::write(&input, mesh.to_obj()).map_err(|e| fail(e.to_string()))?;
        let args: Vec<std::ffi::OsString> = vec![
            input.clone().into(),
            output.clone().into(),
            "--threshold".into(),
            opts.threshold.to_string().into(),
            "--max-hulls".into(),
            max_hulls.to_string().into(),
            "--resolution".into(),
            (opts.resolution.max(20) * 32).to_string().into(),
            "--seed".into(),
            opts.seed.to_string().into(),
        ];
        let out = python::run_tool("coacd_decompose.py", &args)?;
        if out.code != Some(0) {
            return Err(fail(format!(
                "tools/helpers/coacd_decompose.py failed ({:?}): {}",
                out.code,
                out.stderr.trim()
            )));
        }
        let text = std::fs::read_to_string(&output).map_err(|e| fail(e.to_string()))?;
        let parsed: CoacdOutput = serde_json::from_str(&text).map_err(|e| fail(e.to_string()))?;
        let mut hulls = Vec::new();
        for h in parsed.hulls {
            let pts: Vec<Vector3<f64>> = h.vertices.iter().map(|p| Vector3::from(*p)).collect();
            if let Ok(p) = convex_hull(&pts) {
                hulls.push(p);
            }
        }
        if hulls.is_empty() {
            return Err(fail("CoACD returned no part".into()));
        }
        Ok(hulls)
    })();
    drop(tmp);
    result
}

static COUNTER: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

#[derive(Deserialize)]
struct CoacdOutput {
    hulls: Vec<CoacdHull>,
}

#[derive(Deserialize)]
struct CoacdHull {
    vertices: Vec<[f64; 3]>,
}
