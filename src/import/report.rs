//! The import report: per link, hulls and vertices, union volume of the hulls
//! against the source mesh volume, coverage of the source surface, ties,
//! time; plus the simplifications the reader made. Written as JSON.
//!
//! - **Union volume**: the link's hulls are sampled on a regular grid of
//!   `grid³` cell centres over their bounding box (deterministic; relative
//!   error about `6/grid` for blocky shapes).
//! - **Coverage**: `samples` points drawn uniformly (seeded) on each source
//!   surface; a point is covered when it lies inside a hull of the link or
//!   within `2 %` of that source mesh's bounding-box diagonal of one. The
//!   link's coverage is the smallest over its source meshes; the coverage
//!   error is `1 − coverage`. Distances are exact point–polytope distances.

use super::connectivity::{AttachmentSite, LinkConnectivity};
use super::mass::{InertialReport, MassSource};
use super::mesh::TriMesh;
use super::polytope::{Polytope, bounds};
use nalgebra::Vector3;
use rand::SeedableRng;
use serde::Serialize;
use std::collections::BTreeMap;

/// Report of one link.
#[derive(Clone, Debug, Serialize)]
pub struct LinkReport {
    pub name: String,
    pub hulls: usize,
    /// Vertices over all hulls (shared vertices counted once per hull).
    pub vertices: usize,
    /// Vertices per hull.
    pub hull_vertices: Vec<usize>,
    /// The link's mass in the scene (kg).
    pub mass: f64,
    pub mass_source: MassSource,
    /// The scene mass model: `given` (the input inertial) or `solid`.
    pub mass_model: &'static str,
    /// The input's inertial (URDF `<inertial>`, merged links included).
    pub inertial_input: Option<InertialReport>,
    /// The hulls as uniform solids scaled to the link's mass.
    pub inertial_hulls: InertialReport,
    /// Volume of the union of the hulls (m³, grid estimate).
    pub union_volume: f64,
    /// Volume of the source geometry (m³); `None` when a source mesh is open.
    pub source_volume: Option<f64>,
    /// Fraction of source-surface samples within tolerance of the hulls.
    pub coverage: f64,
    pub coverage_error: f64,
    /// Largest distance from a source sample to the hulls (m).
    pub max_distance: f64,
    pub connectivity: LinkConnectivity,
    /// Largest relative change of a hull's volume caused by the added
    /// shared and attachment vertices (0 when every added point was inside).
    pub max_hull_volume_change: f64,
    /// Decomposition time (s).
    pub decompose_seconds: f64,
}

/// Report of one joint's attachment tie.
#[derive(Clone, Debug, Serialize)]
pub struct AttachmentReport {
    pub link: String,
    pub joint: String,
    pub parent: String,
    pub parent_site: AttachmentSite,
    pub child_site: AttachmentSite,
}

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct ImportReport {
    pub input: String,
    pub robot: String,
    pub decomposer: String,
    /// Connectivity of each link's hulls: `shared_vertex` (one auxiliary
    /// vertex per touching or overlapping pair, the paper's) or `corners`
    /// (grid blocks' coincident corners tied); see
    /// [`super::connectivity::Ties`].
    pub ties: &'static str,
    pub links: Vec<LinkReport>,
    pub attachments: Vec<AttachmentReport>,
    /// Scene joint → the input joints behind its coordinates, in order.
    pub joints: BTreeMap<String, Vec<super::source::InputJoint>>,
    pub total_hulls: usize,
    pub total_vertices: usize,
    /// Links whose hulls are not one connected group.
    pub disconnected_links: Vec<String>,
    /// Simplifications and fallbacks, in words.
    pub notes: Vec<String>,
    /// Base, contact exclusions, ground placement and gains written by
    /// `sdrs import` (see [`super::ready`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ready: Option<super::ready::ReadyReport>,
    /// Wall time of the whole import (s).
    pub seconds: f64,
}

/// Volume of the union of `hulls` on a `grid³` lattice.
pub fn union_volume(hulls: &[Polytope], grid: usize) -> f64 {
    let all: Vec<Vector3<f64>> = hulls
        .iter()
        .flat_map(|h| h.vertices.iter().copied())
        .collect();
    let (lo, hi) = bounds(&all);
    let ext = hi - lo;
    let cell = ext / grid as f64;
    let mut inside = 0usize;
    for i in 0..grid {
        for j in 0..grid {
            for k in 0..grid {
                let p = lo
                    + Vector3::new(
                        (i as f64 + 0.5) * cell.x,
                        (j as f64 + 0.5) * cell.y,
                        (k as f64 + 0.5) * cell.z,
                    );
                if hulls.iter().any(|h| h.contains(&p)) {
                    inside += 1;
                }
            }
        }
    }
    inside as f64 * cell.x * cell.y * cell.z
}

/// Coverage of `source` by `hulls`: (fraction covered, largest distance).
pub fn coverage(source: &TriMesh, hulls: &[Polytope], samples: usize, seed: u64) -> (f64, f64) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let pts = source.sample_surface(samples, &mut rng);
    if pts.is_empty() {
        return (1.0, 0.0);
    }
    let tol = 0.02 * source.diagonal();
    let mut covered = 0;
    let mut max_d: f64 = 0.0;
    // A hull's largest plane violation is a lower bound on its distance: a
    // hull whose bound exceeds the nearest distance so far by more than
    // round-off (1e-9 of the mesh's size, against errors of about 1e-15 of
    // it) cannot be nearer and is not measured.
    let slack = 1e-9 * source.diagonal();
    for p in &pts {
        let mut d = f64::INFINITY;
        for h in hulls {
            let v = h.violation(p);
            if v > d + slack {
                continue;
            }
            // `distance`, without evaluating the planes again.
            d = d.min(if v <= 0.0 {
                0.0
            } else {
                h.boundary_distance(p)
            });
        }
        if d <= tol {
            covered += 1;
        }
        max_d = max_d.max(d);
    }
    (covered as f64 / pts.len() as f64, max_d)
}
