//! Triangle meshes: reading OBJ (tobj), STL (stl_io) and COLLADA
//! ([`super::collada`]), welding, checks (empty, non-manifold), transforms,
//! volume and surface sampling.
//!
//! Other formats (`.ply`, `.gltf`, …) are refused with an error that says
//! how to convert them.

use super::error::ImportError;
use super::polytope::{bounds, mesh_volume};
use nalgebra::{Matrix3, Vector3};
use rand::RngExt;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// An indexed triangle mesh (welded: no two vertices share a position).
#[derive(Clone, Debug, Default)]
pub struct TriMesh {
    pub vertices: Vec<Vector3<f64>>,
    pub triangles: Vec<[usize; 3]>,
}

/// Where a mesh is referenced from, for error messages.
#[derive(Clone, Debug)]
pub struct MeshContext {
    /// The file that names the mesh (a URDF), or the mesh itself.
    pub file: PathBuf,
    /// The element, e.g. `link "arm" collision[0]`.
    pub element: String,
}

impl TriMesh {
    /// Welds exactly coincident positions and drops triangles that collapse.
    pub fn welded(vertices: Vec<Vector3<f64>>, triangles: Vec<[usize; 3]>) -> TriMesh {
        let mut index: HashMap<[u64; 3], usize> = HashMap::new();
        let mut out = Vec::new();
        let mut remap = Vec::with_capacity(vertices.len());
        for v in &vertices {
            let key = [v.x, v.y, v.z].map(|c| if c == 0.0 { 0u64 } else { c.to_bits() });
            let i = *index.entry(key).or_insert_with(|| {
                out.push(*v);
                out.len() - 1
            });
            remap.push(i);
        }
        let triangles = triangles
            .into_iter()
            .map(|t| t.map(|i| remap[i]))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        TriMesh {
            vertices: out,
            triangles,
        }
    }

    /// Number of triangles using each undirected edge.
    fn edge_counts(&self) -> HashMap<(usize, usize), usize> {
        let mut edges = HashMap::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        edges
    }

    /// Edges shared by more than two triangles (non-manifold), if any.
    pub fn non_manifold_edges(&self) -> usize {
        self.edge_counts().values().filter(|&&c| c > 2).count()
    }

    /// Whether every edge has exactly two triangles (closed surface).
    pub fn is_closed(&self) -> bool {
        !self.triangles.is_empty() && self.edge_counts().values().all(|&c| c == 2)
    }

    /// Enclosed volume of a closed mesh (absolute value, so either
    /// orientation works), `None` for an open mesh.
    pub fn volume(&self) -> Option<f64> {
        self.is_closed()
            .then(|| mesh_volume(&self.vertices, &self.triangles).abs())
    }

    /// Applies `x ↦ R (s ⊙ x) + t`; a negative scale determinant flips the
    /// triangle orientation so outward stays outward.
    pub fn transformed(&self, scale: [f64; 3], r: &Matrix3<f64>, t: &Vector3<f64>) -> TriMesh {
        let s = Vector3::from(scale);
        let flip = s.x * s.y * s.z < 0.0;
        TriMesh {
            vertices: self
                .vertices
                .iter()
                .map(|v| r * v.component_mul(&s) + t)
                .collect(),
            triangles: self
                .triangles
                .iter()
                .map(|&[a, b, c]| if flip { [a, c, b] } else { [a, b, c] })
                .collect(),
        }
    }

    /// Bounding-box diagonal.
    pub fn diagonal(&self) -> f64 {
        let (lo, hi) = bounds(&self.vertices);
        (hi - lo).norm()
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        self.triangles.iter().map(|t| self.tri_area(t)).sum()
    }

    fn tri_area(&self, t: &[usize; 3]) -> f64 {
        let v = &self.vertices;
        0.5 * (v[t[1]] - v[t[0]]).cross(&(v[t[2]] - v[t[0]])).norm()
    }

    /// `n` points uniformly distributed on the surface (area-weighted).
    pub fn sample_surface(&self, n: usize, rng: &mut impl rand::Rng) -> Vec<Vector3<f64>> {
        let mut cum = Vec::with_capacity(self.triangles.len());
        let mut acc = 0.0;
        for t in &self.triangles {
            acc += self.tri_area(t);
            cum.push(acc);
        }
        if !(acc > 0.0) {
            return Vec::new();
        }
        (0..n)
            .map(|_| {
                let u: f64 = rng.random::<f64>() * acc;
                let k = cum.partition_point(|&c| c < u).min(cum.len() - 1);
                let t = &self.triangles[k];
                let (mut a, mut b): (f64, f64) = (rng.random(), rng.random());
                if a + b > 1.0 {
                    a = 1.0 - a;
                    b = 1.0 - b;
                }
                let v = &self.vertices;
                v[t[0]] + (v[t[1]] - v[t[0]]) * a + (v[t[2]] - v[t[0]]) * b
            })
            .collect()
    }

    /// Writes the mesh as OBJ text.
    pub fn to_obj(&self) -> String {
        let mut s = String::new();
        for v in &self.vertices {
            s.push_str(&format!("v {} {} {}\n", v.x, v.y, v.z));
        }
        for t in &self.triangles {
            s.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
        }
        s
    }
}

/// Reads a mesh file (`.obj`, `.stl` or `.dae`, case-insensitive), welds it
/// and checks that it is non-empty. Open and non-manifold meshes are
/// accepted: a convex decomposition needs only the surface (the caller
/// reports them; their volume is then unknown).
///
/// The second value is a note for the import report, if the file says
/// something the user should know (a COLLADA `<up_axis>` other than `Z_UP`,
/// which is not applied; see [`super::collada`]).
pub fn load_mesh(mesh: &Path, ctx: &MeshContext) -> Result<(TriMesh, Option<String>), ImportError> {
    let ext = mesh
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let bad = |msg: String| ImportError::BadMesh {
        path: ctx.file.clone(),
        element: ctx.element.clone(),
        mesh: mesh.to_path_buf(),
        msg,
    };
    if !matches!(ext.as_str(), "obj" | "stl" | "dae") {
        return Err(ImportError::UnsupportedFormat {
            path: ctx.file.clone(),
            element: ctx.element.clone(),
            mesh: mesh.to_path_buf(),
            ext,
        });
    }
    if !mesh.is_file() {
        return Err(ImportError::MissingMesh {
            path: ctx.file.clone(),
            element: ctx.element.clone(),
            mesh: mesh.to_path_buf(),
            hint: String::new(),
        });
    }
    let mut note = None;
    let (vertices, triangles) = match ext.as_str() {
        "obj" => read_obj(mesh).map_err(bad)?,
        "stl" => read_stl(mesh).map_err(bad)?,
        _ => {
            let c = super::collada::read_collada(mesh).map_err(bad)?;
            note = c.up_axis.map(|axis| {
                format!(
                    "{}: COLLADA mesh {} declares <up_axis>{axis}</up_axis>; read in its raw coordinates (as ROS descriptions expect), not rotated to Z_UP",
                    ctx.element,
                    mesh.display()
                )
            });
            (c.vertices, c.triangles)
        }
    };
    let m = TriMesh::welded(vertices, triangles);
    if m.triangles.is_empty() {
        return Err(ImportError::EmptyMesh {
            path: ctx.file.clone(),
            element: ctx.element.clone(),
            mesh: mesh.to_path_buf(),
        });
    }
    Ok((m, note))
}

type RawMesh = (Vec<Vector3<f64>>, Vec<[usize; 3]>);

fn read_obj(path: &Path) -> Result<RawMesh, String> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj(path, &opts).map_err(|e| e.to_string())?;
    let mut v = Vec::new();
    let mut t = Vec::new();
    for model in models {
        let m = model.mesh;
        let base = v.len();
        for p in m.positions.chunks_exact(3) {
            v.push(Vector3::new(p[0], p[1], p[2]));
        }
        for f in m.indices.chunks_exact(3) {
            let tri = [
                f[0] as usize + base,
                f[1] as usize + base,
                f[2] as usize + base,
            ];
            if tri.iter().any(|&i| i >= v.len()) {
                return Err("face index out of range".into());
            }
            t.push(tri);
        }
    }
    if v.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
        return Err("non-finite vertex coordinates".into());
    }
    Ok((v, t))
}

fn read_stl(path: &Path) -> Result<RawMesh, String> {
    let mut f = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let m = stl_io::read_stl(&mut f).map_err(|e| e.to_string())?;
    let v: Vec<Vector3<f64>> = m
        .vertices
        .iter()
        .map(|p| Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64))
        .collect();
    if v.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
        return Err("non-finite vertex coordinates".into());
    }
    let t = m.faces.iter().map(|f| f.vertices).collect();
    Ok((v, t))
}
