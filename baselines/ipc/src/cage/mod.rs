//! Cage-based shape deformation (Xu et al., RSS 2021: the mesh-based
//! co-design the paper compares against): a closed triangle cage around a
//! link's surface, each surface (hull) vertex a *fixed* combination of the
//! cage vertices by mean value coordinates ([`mvc`]),
//!
//! ```text
//! x_i = Σ_j φ_ij c_j        (link frame, m),      ∂L/∂c_j = Σ_i φ_ij ∂L/∂x_i,
//! ```
//!
//! so the cage vertices `c_j` are the design variables and the backward
//! pass's hull-vertex gradients (which under `--contact ipc` include the IPC
//! contact and friction terms, [`crate::adjoint`]) map to them by `Φᵀ`.
//!
//! - [`generate`]: automatic cages — the mesh's bounding box inflated by a
//!   margin and subdivided into `k × k` quads per face (`6k² + 2` vertices:
//!   `k = 2` gives 26, the paper's coarse biped-foot cage; `k = 4` gives 98,
//!   its coarse gripper cage; `k = 16` gives 1538, its fine gripper cage);
//! - [`validate`]: a user cage must be closed, non-degenerate and enclose
//!   every surface vertex (errors name the link, triangle or vertex);
//! - [`design`]: the cage vertices of chosen links as a bounded design
//!   vector, applied to a model and chained from vertex gradients.

pub mod design;
pub mod generate;
pub mod mvc;
pub mod problem;
pub mod validate;

pub use design::{CageDesign, LinkCage};
pub use generate::{CageResolution, box_cage};
pub use problem::{CageSetupError, CageSummary, cage_problem};
pub use validate::{CageError, validate_cage};

use nalgebra::Vector3;

/// A closed triangle cage in a link frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Cage {
    /// Vertices (m, link frame).
    pub vertices: Vec<Vector3<f64>>,
    /// Triangles, counter-clockwise from outside.
    pub tris: Vec<[u32; 3]>,
}
