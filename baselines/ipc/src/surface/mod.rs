//! Source meshes as IPC contact surfaces (`contact.ipc.surface: source`): each
//! link's `surface_mesh` (the mesh its hulls were made from; `sdrs import`
//! writes one per link) read, checked and turned into a [`LinkMesh`] in the
//! link frame. Links without a `surface_mesh` keep their hull surfaces.
//!
//! What the baseline needs of a source mesh, each checked with a
//! [`SurfaceError`] naming the file and the triangle or edge:
//!
//! - finite coordinates and no degenerate triangle (area
//!   `≤ 10⁻¹² · extent²`): distances to a sliver are ill-conditioned;
//! - **closed** — every edge bounds exactly two triangles — and
//!   **consistently oriented** — the two run it in opposite directions: the
//!   solid a surface bounds (start check, python-fcl check, the cage's
//!   enclosure test) is defined only then. A mesh oriented inwards is flipped;
//! - **not self-intersecting**: no two triangles of one component that
//!   share no vertex meet (closed triangles, touching counts), found with a
//!   BVH over triangle boxes ([`self_intersect`]), so the check is
//!   `O(n log n + k)`, not `O(n²)`.
//!
//! A file may hold several closed components (one per source mesh of the
//! link); like the hulls of a link, components of one link may overlap
//! (pairs within a link never interact), so self-intersection is checked per
//! component.
//!
//! [`LinkMesh`]: crate::mesh::LinkMesh

pub mod design;
pub mod export;
pub mod intersect;
pub mod load;
pub mod paths;
pub mod self_intersect;
pub mod topology;
pub mod tri_tri;

pub use load::{load_surface, surface_from_triangles};
pub use paths::{SurfacePath, surface_paths};

use nalgebra::Vector3;
use std::path::PathBuf;

/// `[x, y, z]` of a vertex, for messages.
pub(crate) fn xyz(p: &Vector3<f64>) -> [f64; 3] {
    [p.x, p.y, p.z]
}

/// Why a source mesh cannot be an IPC contact surface. `file` is the mesh
/// file; triangles are numbered 0-based in file order (faces triangulated,
/// coincident vertices welded, triangles that collapse to a segment or a
/// point by the welding dropped); vertex indices are the reader's (an OBJ
/// reader numbers vertices by first use), so every message also gives the
/// vertices' coordinates (m, mesh frame).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SurfaceError {
    #[error("{}: cannot read the mesh: {msg}", file.display())]
    Read { file: PathBuf, msg: String },
    #[error("{}: the mesh has no triangles", file.display())]
    Empty { file: PathBuf },
    #[error("{}: vertex {vertex} has a non-finite coordinate ({point:?})", file.display())]
    NonFinite {
        file: PathBuf,
        vertex: usize,
        point: [f64; 3],
    },
    #[error(
        "{}: triangle {tri} (vertices {vertices:?} at {points:?}) is degenerate: area {area:.3e} m² for a mesh of extent {extent:.3e} m",
        file.display()
    )]
    Degenerate {
        file: PathBuf,
        tri: usize,
        vertices: [usize; 3],
        points: Box<[[f64; 3]; 3]>,
        area: f64,
        extent: f64,
    },
    #[error(
        "{}: the mesh is not closed: edge {a}–{b} ({pa:?}–{pb:?}) bounds {count} triangle(s) {tris:?}; a closed surface needs exactly 2 per edge",
        file.display()
    )]
    Open {
        file: PathBuf,
        a: usize,
        b: usize,
        pa: [f64; 3],
        pb: [f64; 3],
        count: usize,
        tris: Vec<usize>,
    },
    #[error(
        "{}: the mesh is not consistently oriented: triangles {t1} and {t2} both run edge {a}→{b} ({pa:?}→{pb:?}) in the same direction",
        file.display()
    )]
    Orientation {
        file: PathBuf,
        a: usize,
        b: usize,
        pa: [f64; 3],
        pb: [f64; 3],
        t1: usize,
        t2: usize,
    },
    #[error(
        "{}: the mesh intersects itself: triangles {t1} (vertices {v1:?} at {p1:?}) and {t2} (vertices {v2:?} at {p2:?}) meet but share no vertex",
        file.display()
    )]
    SelfIntersection {
        file: PathBuf,
        t1: usize,
        t2: usize,
        v1: [usize; 3],
        v2: [usize; 3],
        p1: Box<[[f64; 3]; 3]>,
        p2: Box<[[f64; 3]; 3]>,
    },
}
