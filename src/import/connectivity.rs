//! Connectivity constraints (paper, `shape.tex`): shared vertices between
//! overlapping hulls of one link, and attachment points shared between a
//! joint's parent and child links.
//!
//! **Shared vertices.** For every pair of hulls of a link whose boxes meet,
//! [`deepest_point`] solves `max r s.t. x is at depth ≥ r in both hulls`.
//! - depth > 1e-9·L (L = the link's extent): the hulls overlap; the point is
//!   strictly inside both (Chebyshev-like centre of the intersection);
//! - otherwise, if some vertices of one hull lie in the other (to 1e-12·L),
//!   the hulls touch (as V-HACD's parts do along their cut planes); their
//!   average, a point of the common face, is used;
//! - otherwise the pair is not connected.
//!
//! The point is appended to both hulls' vertex lists (or an existing vertex
//! at that exact position is reused) and the two become one tie group. The
//! point is inside both hulls, so their shapes and volumes do not change.
//!
//! **Bridging.** If a link's hulls still form several groups, the closest
//! pair between two groups (the point minimising the larger distance to the
//! two hulls) is added to both, which grows them slightly; each bridge and
//! its volume change are reported. Disable with `bridge_gaps = false`; the
//! link is then reported as disconnected.
//!
//! **Attachments.** For a joint, the point at the joint origin (in the parent
//! frame: `origin.xyz`; in the child frame: `0`) is added to the parent hull
//! and the child hull that contain it most deeply. When no hull contains it,
//! the nearest hull is extended to it (reported with its volume change), so
//! that the attachment point always lies in both links as the paper requires.

use super::interior::deepest_point;
use super::polytope::{Polytope, bounds, convex_hull};
use nalgebra::Vector3;
use serde::Serialize;

/// A hull of the design: its vertex list (extreme points plus added shared
/// and attachment points) and its geometry.
#[derive(Clone, Debug)]
pub struct DesignHull {
    pub vertices: Vec<Vector3<f64>>,
    pub poly: Polytope,
    /// Volume when it came out of the decomposition.
    pub initial_volume: f64,
}

impl DesignHull {
    pub fn new(poly: Polytope) -> Self {
        DesignHull {
            vertices: poly.vertices.clone(),
            initial_volume: poly.volume(),
            poly,
        }
    }

    /// Index of the vertex at `p`, appending it when new.
    pub fn add_point(&mut self, p: Vector3<f64>) -> usize {
        if let Some(i) = self.vertices.iter().position(|v| *v == p) {
            return i;
        }
        self.vertices.push(p);
        self.vertices.len() - 1
    }

    /// Adds a point that may lie outside; recomputes the geometry.
    fn extend_to(&mut self, p: Vector3<f64>) -> usize {
        let i = self.add_point(p);
        if let Ok(poly) = convex_hull(&self.vertices) {
            self.poly = poly;
        }
        i
    }
}

/// Which vertices of a link's hulls are tied (one design variable).
///
/// - `shared_vertex` (default; paper, `shape.tex`, "Design Space
///   Parameterization"): each pair of touching or overlapping hulls shares
///   **one** auxiliary vertex `x_ijk`, appended to both vertex lists; every
///   other vertex is free. For `vhacd`/`coacd`/`hull` parts the pairs and
///   points are those of [`connect_link`]; for `grid` blocks they are the
///   face neighbours of [`super::grid::face_ties`] (the centre of the shared
///   face).
/// - `corners` (`grid` only; the design space before issue 30): every two
///   blocks' coincident corners are one variable ([`super::grid::corner_ties`]),
///   so the blocks form a deformable hexahedral lattice in which no block can
///   move away from its neighbours.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ties {
    #[default]
    SharedVertex,
    Corners,
}

impl Ties {
    pub fn name(&self) -> &'static str {
        match self {
            Ties::SharedVertex => "shared_vertex",
            Ties::Corners => "corners",
        }
    }
}

impl std::str::FromStr for Ties {
    type Err = String;
    /// `shared-vertex` or `corners` (any case; the command-line spelling).
    fn from_str(s: &str) -> Result<Self, String> {
        super::pick_name(s, &[Ties::SharedVertex, Ties::Corners], |t| match t {
            Ties::SharedVertex => "shared-vertex",
            Ties::Corners => "corners",
        })
    }
}

/// How a shared vertex was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TieKind {
    Overlap,
    Touch,
    Bridge,
}

/// One shared vertex between two hulls of a link.
#[derive(Clone, Debug, Serialize)]
pub struct SharedVertex {
    pub hulls: [usize; 2],
    pub vertices: [usize; 2],
    pub kind: TieKind,
    /// Depth of the point inside both hulls (negative: a bridge's gap).
    pub depth: f64,
}

/// Connectivity of one link.
#[derive(Clone, Debug, Serialize)]
pub struct LinkConnectivity {
    pub shared: Vec<SharedVertex>,
    /// Groups of hulls connected through shared vertices (1 = connected).
    pub components: usize,
}

fn link_scale(hulls: &[DesignHull]) -> f64 {
    let all: Vec<Vector3<f64>> = hulls
        .iter()
        .flat_map(|h| h.vertices.iter().copied())
        .collect();
    let (lo, hi) = bounds(&all);
    (hi - lo).norm().max(1e-12)
}

struct Dsu(Vec<usize>);
impl Dsu {
    fn find(&mut self, i: usize) -> usize {
        if self.0[i] != i {
            let r = self.find(self.0[i]);
            self.0[i] = r;
        }
        self.0[i]
    }
    fn union(&mut self, a: usize, b: usize) -> bool {
        let (a, b) = (self.find(a), self.find(b));
        self.0[a] = b;
        a != b
    }
}

enum PairResult {
    Shared(Vector3<f64>, TieKind, f64),
    Gap(Vector3<f64>, f64),
}

fn analyse_pair(a: &DesignHull, b: &DesignHull, scale: f64) -> PairResult {
    let mut planes = a.poly.planes.clone();
    planes.extend_from_slice(&b.poly.planes);
    let ca = a.poly.vertices.iter().sum::<Vector3<f64>>() / a.poly.vertices.len() as f64;
    let cb = b.poly.vertices.iter().sum::<Vector3<f64>>() / b.poly.vertices.len() as f64;
    let d = deepest_point(&planes, (ca + cb) / 2.0, scale);
    if d.margin > 1e-9 * scale {
        return PairResult::Shared(d.point, TieKind::Overlap, d.margin);
    }
    let tol = 1e-12 * scale;
    let common: Vec<Vector3<f64>> = a
        .poly
        .vertices
        .iter()
        .filter(|v| b.poly.violation(v) <= tol)
        .chain(
            b.poly
                .vertices
                .iter()
                .filter(|v| a.poly.violation(v) <= tol),
        )
        .copied()
        .collect();
    if !common.is_empty() {
        let p = common.iter().sum::<Vector3<f64>>() / common.len() as f64;
        let depth = (-a.poly.violation(&p)).min(-b.poly.violation(&p));
        return PairResult::Shared(p, TieKind::Touch, depth);
    }
    if d.margin > 0.0 {
        return PairResult::Shared(d.point, TieKind::Overlap, d.margin);
    }
    PairResult::Gap(d.point, d.margin)
}

/// Whether a face plane of one hull has every vertex of the other more than
/// `gap` outside it. Such a pair is neither overlapping nor touching (a
/// vertex within 1e-12·L of the other hull is at least `gap` − 1e-12·L
/// from the plane's far side), so it can only be a gap; gaps are analysed
/// only when a link's groups need bridging (the loop over separate groups
/// in [`connect_link`] takes every pair that has no gap yet).
fn plane_separates(a: &DesignHull, b: &DesignHull, gap: f64) -> bool {
    let beyond = |p: &DesignHull, q: &DesignHull| {
        p.poly
            .planes
            .iter()
            .any(|(n, c)| q.poly.vertices.iter().all(|v| n.dot(v) - c > gap))
    };
    beyond(a, b) || beyond(b, a)
}

fn boxes_meet(a: &DesignHull, b: &DesignHull, tol: f64) -> bool {
    let (la, ha) = bounds(&a.poly.vertices);
    let (lb, hb) = bounds(&b.poly.vertices);
    (0..3).all(|k| la[k] <= hb[k] + tol && lb[k] <= ha[k] + tol)
}

/// Adds shared vertices between the hulls of one link (see the module docs).
pub fn connect_link(hulls: &mut [DesignHull], bridge_gaps: bool) -> LinkConnectivity {
    let n = hulls.len();
    let scale = link_scale(hulls);
    let mut dsu = Dsu((0..n).collect());
    let mut shared = Vec::new();
    let mut gaps: Vec<(f64, usize, usize, Vector3<f64>)> = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            if !boxes_meet(&hulls[i], &hulls[j], 1e-9 * scale)
                || plane_separates(&hulls[i], &hulls[j], 1e-6 * scale)
            {
                continue;
            }
            match analyse_pair(&hulls[i], &hulls[j], scale) {
                PairResult::Shared(p, kind, depth) => {
                    let vi = hulls[i].add_point(p);
                    let vj = hulls[j].add_point(p);
                    shared.push(SharedVertex {
                        hulls: [i, j],
                        vertices: [vi, vj],
                        kind,
                        depth,
                    });
                    dsu.union(i, j);
                }
                PairResult::Gap(p, m) => gaps.push((m, i, j, p)),
            }
        }
    }
    let count = |dsu: &mut Dsu| (0..n).filter(|&i| dsu.find(i) == i).count();
    if bridge_gaps && count(&mut dsu) > 1 {
        // Candidates between every pair of separate groups, closest first.
        for i in 0..n {
            for j in i + 1..n {
                if dsu.find(i) != dsu.find(j)
                    && !gaps.iter().any(|g| g.1 == i && g.2 == j)
                    && let PairResult::Gap(p, m) = analyse_pair(&hulls[i], &hulls[j], scale)
                {
                    gaps.push((m, i, j, p));
                }
            }
        }
        gaps.sort_by(|a, b| b.0.total_cmp(&a.0));
        for (m, i, j, p) in gaps {
            if dsu.union(i, j) {
                let vi = hulls[i].extend_to(p);
                let vj = hulls[j].extend_to(p);
                shared.push(SharedVertex {
                    hulls: [i, j],
                    vertices: [vi, vj],
                    kind: TieKind::Bridge,
                    depth: m,
                });
            }
        }
    }
    LinkConnectivity {
        shared,
        components: count(&mut dsu),
    }
}

/// Where an attachment point went.
#[derive(Clone, Debug, Serialize)]
pub struct AttachmentSite {
    pub hull: usize,
    pub vertex: usize,
    /// Distance from the point to the hull before it was added (0: inside).
    pub distance: f64,
    /// Whether the hull had to grow to include the point.
    pub extended: bool,
}

/// Whether `p` lies in one of `hulls` (to round-off).
pub fn point_inside(hulls: &[DesignHull], p: &Vector3<f64>) -> bool {
    let scale = link_scale(hulls);
    hulls.iter().any(|h| h.poly.violation(p) <= 1e-12 * scale)
}

/// Adds `p` to the hull of `hulls` that contains it most deeply, or extends
/// the nearest hull to it.
pub fn attach_point(hulls: &mut [DesignHull], p: Vector3<f64>) -> AttachmentSite {
    let scale = link_scale(hulls);
    let (best, viol) = hulls
        .iter()
        .enumerate()
        .map(|(i, h)| (i, h.poly.violation(&p)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("a link has hulls");
    if viol <= 1e-12 * scale {
        let vertex = hulls[best].add_point(p);
        return AttachmentSite {
            hull: best,
            vertex,
            distance: 0.0,
            extended: false,
        };
    }
    let (near, dist) = hulls
        .iter()
        .enumerate()
        .map(|(i, h)| (i, h.poly.distance(&p)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    let vertex = hulls[near].extend_to(p);
    AttachmentSite {
        hull: near,
        vertex,
        distance: dist,
        extended: true,
    }
}

/// Hull volume (the convex hull of the current vertex list).
pub fn hull_volume(vertices: &[Vector3<f64>]) -> f64 {
    convex_hull(vertices).map(|p| p.volume()).unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Hull;

    fn boxh(size: [f64; 3], c: [f64; 3]) -> DesignHull {
        DesignHull::new(convex_hull(&Hull::cuboid(Vector3::from(size), Vector3::from(c))).unwrap())
    }

    #[test]
    fn overlapping_touching_and_separate_boxes() {
        // a overlaps b, b touches c, d is apart.
        let mut hs = vec![
            boxh([1.0; 3], [0.0; 3]),
            boxh([1.0; 3], [0.8, 0.0, 0.0]),
            boxh([1.0; 3], [1.8, 0.2, 0.0]),
            boxh([1.0; 3], [4.0, 0.0, 0.0]),
        ];
        let vols: Vec<f64> = hs.iter().map(|h| h.poly.volume()).collect();
        let c = connect_link(&mut hs[..3], false);
        assert_eq!(c.components, 1);
        assert_eq!(c.shared.len(), 2);
        assert_eq!(c.shared[0].kind, TieKind::Overlap);
        assert_eq!(c.shared[1].kind, TieKind::Touch);
        for (h, v) in hs.iter().zip(&vols) {
            assert!((hull_volume(&h.vertices) - v).abs() < 1e-12);
        }
        let c = connect_link(&mut hs, false);
        assert_eq!(c.components, 2);
        let c = connect_link(&mut hs, true);
        assert_eq!(c.components, 1);
        assert!(c.shared.iter().any(|s| s.kind == TieKind::Bridge));
    }

    #[test]
    fn attachment_inside_and_outside() {
        let mut hs = vec![boxh([1.0; 3], [0.0; 3])];
        let a = attach_point(&mut hs, Vector3::new(0.1, 0.0, 0.0));
        assert!(!a.extended && a.vertex == 8);
        let a = attach_point(&mut hs, Vector3::new(0.5, 0.5, 0.5));
        assert!(!a.extended && a.vertex < 8, "corners are reused");
        let a = attach_point(&mut hs, Vector3::new(1.0, 0.0, 0.0));
        assert!(a.extended && (a.distance - 0.5).abs() < 1e-12);
    }
}
