//! Each link's surface as a closed triangle mesh in the link frame: the
//! triangulated boundary of each of its convex hulls (the same shapes SDRS
//! uses, for apples-to-apples comparisons), or the link's source mesh
//! (`contact.ipc.surface: source`, [`crate::surface`]), with unique edges and
//! the per-link bounds the broad phase and the CCD step bound need.

use nalgebra::Vector3;
use sdrs::model::Model;
use std::collections::BTreeMap;

/// Why a link surface is unusable.
#[derive(Debug, Clone, thiserror::Error)]
pub enum MeshError {
    #[error("hull {hull}: cannot triangulate its surface: {msg}")]
    Hull { hull: usize, msg: String },
    #[error(
        "hull {hull}: the surface is not closed (edge {a}–{b} bounds {count} triangles, a closed surface needs 2)"
    )]
    Open {
        hull: usize,
        a: usize,
        b: usize,
        count: usize,
    },
}

/// Where a [`LinkMesh`]'s vertices come from (what design gradients w.r.t.
/// its vertices are gradients of).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum MeshOrigin {
    /// The model's hull vertices ([`LinkMesh::source`] = `(hull, vertex)`).
    #[default]
    Hulls,
    /// The link's source mesh, read from `file` ([`LinkMesh::source`] =
    /// `(component, index)`); vertex `k` is `Link::surface[k]` when a cage
    /// design moves it.
    Source { file: std::path::PathBuf },
}

/// A link's surface mesh (link frame). Hulls of one link are kept as
/// separate closed components (they may overlap: pairs within a link never
/// interact).
#[derive(Clone, Debug, Default)]
pub struct LinkMesh {
    /// Vertices `x̃` in the link frame (m).
    pub x_local: Vec<Vector3<f64>>,
    /// Triangles, counter-clockwise from outside.
    pub tris: Vec<[u32; 3]>,
    /// Unique edges `(i, j)`, `i < j`.
    pub edges: Vec<[u32; 2]>,
    /// Squared rest length of each edge (m², for the mollifier's `ε_x`).
    pub edge_len2: Vec<f64>,
    /// `max ‖x̃‖` over vertices (m): the link-frame radius about its origin.
    pub radius: f64,
    /// Where each vertex comes from: `(component, index)` — for
    /// [`LinkMesh::from_hulls`] the model's hull and vertex (`x̃` is a copy of
    /// `hulls[h].x_local[i]`), so design gradients w.r.t. mesh vertices land
    /// on the model's hull vertices; for [`LinkMesh::add_closed`] the
    /// component and the index in its vertex list.
    pub source: Vec<(u32, u32)>,
    /// Hull surfaces (default) or a source mesh.
    pub origin: MeshOrigin,
}

impl LinkMesh {
    /// The triangulated hull surfaces of link `link` (empty without hulls).
    pub fn from_hulls(model: &Model, link: usize) -> Result<LinkMesh, MeshError> {
        let mut m = LinkMesh::default();
        for (h, hull) in model.links[link].hulls.iter().enumerate() {
            let poly = sdrs::import::polytope::convex_hull(&hull.x_local)
                .map_err(|msg| MeshError::Hull { hull: h, msg })?;
            let tris: Vec<[usize; 3]> = poly.triangles.clone();
            let first = m.x_local.len();
            m.add_closed(h, &poly.vertices, &tris)?;
            // The hull's vertices are copies of input points: find each one.
            for (k, v) in poly.vertices.iter().enumerate() {
                let src =
                    hull.x_local
                        .iter()
                        .position(|x| x == v)
                        .ok_or_else(|| MeshError::Hull {
                            hull: h,
                            msg: format!("surface vertex {k} is not a hull vertex"),
                        })?;
                m.source[first + k] = (h as u32, src as u32);
            }
        }
        m.radius = m.x_local.iter().map(|x| x.norm()).fold(0.0, f64::max);
        Ok(m)
    }

    /// Appends one closed component, checking closedness (every edge in
    /// exactly two triangles).
    pub fn add_closed(
        &mut self,
        component: usize,
        vertices: &[Vector3<f64>],
        tris: &[[usize; 3]],
    ) -> Result<(), MeshError> {
        let mut count: BTreeMap<(usize, usize), usize> = BTreeMap::new();
        for t in tris {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *count.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        if let Some((&(a, b), &c)) = count.iter().find(|&(_, &c)| c != 2) {
            return Err(MeshError::Open {
                hull: component,
                a,
                b,
                count: c,
            });
        }
        let base = self.x_local.len() as u32;
        self.x_local.extend_from_slice(vertices);
        self.source
            .extend((0..vertices.len()).map(|i| (component as u32, i as u32)));
        self.tris.extend(
            tris.iter()
                .map(|t| [t[0] as u32 + base, t[1] as u32 + base, t[2] as u32 + base]),
        );
        for &(a, b) in count.keys() {
            self.edges.push([a as u32 + base, b as u32 + base]);
            self.edge_len2
                .push((vertices[a] - vertices[b]).norm_squared());
        }
        Ok(())
    }

    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }
}
