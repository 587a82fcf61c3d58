//! Broad phase: candidate hull pairs whose bounding boxes, inflated by the
//! contact range, overlap (paper, `contact.tex`: "`U_c` only takes non-zero
//! values when the distance … is less than 2s/(1−s). By bulging each bounding
//! box by this distance, we … prune non-overlapping pairs").
//!
//! Boxes are inflated by half the range on every side, so two boxes overlap
//! whenever the hulls are closer than the range (box distance ≤ hull
//! distance). The tree is parry's BVH, rebuilt per query (hull counts are
//! small next to the narrow phase's cost); the pair list is sorted, so the
//! result is deterministic.

use super::hulls::WorldHulls;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Vector;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};
use std::collections::BTreeSet;

/// Broad-phase state (scratch only; nothing persists between queries but
/// allocations).
#[derive(Clone, Default)]
pub struct BroadPhase {
    aabbs: Vec<Aabb>,
    workspace: BvhWorkspace,
    /// Sweep order of [`BroadPhase::swept_pairs`].
    order: Vec<usize>,
}

/// The box of `x` padded by `half` on every side.
fn padded_box(x: &[nalgebra::Vector3<f64>], half: f64) -> Aabb {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for v in x {
        for e in 0..3 {
            lo[e] = lo[e].min(v[e]);
            hi[e] = hi[e].max(v[e]);
        }
    }
    Aabb::new(
        Vector::new(lo[0] - half, lo[1] - half, lo[2] - half),
        Vector::new(hi[0] + half, hi[1] + half, hi[2] + half),
    )
}

impl BroadPhase {
    /// Candidate pairs `(h₁, h₂)` of hull indices into `hulls` with
    /// `h₁ < h₂`, on different links, whose link pair is not in `excluded`
    /// (pairs `(i, j)` with `i < j`), and whose boxes inflated by `range`
    /// overlap. Written sorted into `out`.
    pub fn candidate_pairs(
        &mut self,
        hulls: &WorldHulls,
        range: f64,
        excluded: &BTreeSet<(usize, usize)>,
        out: &mut Vec<(usize, usize)>,
    ) {
        let half = 0.5 * range;
        self.pairs_padded(hulls, |_| half, excluded, out);
    }

    /// Candidate pairs for continuous collision detection: as
    /// [`BroadPhase::candidate_pairs`], with hull `h`'s box padded by
    /// `pad[h]` on every side — how far any of its points can move on the
    /// segment being checked, so the padded box contains the hull's whole
    /// swept volume and a pair that could meet anywhere on the segment is a
    /// candidate.
    ///
    /// Sweep and prune along x instead of the BVH: the query runs once per
    /// Newton iteration, where a tree rebuild costs more than the sweep
    /// (the pair set is the same, sorted).
    pub fn swept_pairs(
        &mut self,
        hulls: &WorldHulls,
        pad: &[f64],
        excluded: &BTreeSet<(usize, usize)>,
        out: &mut Vec<(usize, usize)>,
    ) {
        out.clear();
        self.aabbs.clear();
        for (h, &p) in pad.iter().enumerate().take(hulls.ids.len()) {
            self.aabbs.push(padded_box(hulls.hull(h), p));
        }
        self.order.clear();
        self.order.extend(0..self.aabbs.len());
        let boxes = &self.aabbs;
        self.order
            .sort_unstable_by(|&a, &b| boxes[a].mins.x.total_cmp(&boxes[b].mins.x).then(a.cmp(&b)));
        for (k, &a) in self.order.iter().enumerate() {
            let ba = &boxes[a];
            for &b in &self.order[k + 1..] {
                let bb = &boxes[b];
                if bb.mins.x > ba.maxs.x {
                    break;
                }
                if bb.mins.y > ba.maxs.y
                    || ba.mins.y > bb.maxs.y
                    || bb.mins.z > ba.maxs.z
                    || ba.mins.z > bb.maxs.z
                {
                    continue;
                }
                let (a, b) = (a.min(b), a.max(b));
                let (la, lb) = (hulls.ids[a].link, hulls.ids[b].link);
                if la != lb && !excluded.contains(&(la.min(lb), la.max(lb))) {
                    out.push((a, b));
                }
            }
        }
        out.sort_unstable();
    }

    /// The padded boxes of the last query, per hull.
    pub fn boxes(&self) -> &[Aabb] {
        &self.aabbs
    }

    fn pairs_padded(
        &mut self,
        hulls: &WorldHulls,
        pad: impl Fn(usize) -> f64,
        excluded: &BTreeSet<(usize, usize)>,
        out: &mut Vec<(usize, usize)>,
    ) {
        out.clear();
        self.aabbs.clear();
        for h in 0..hulls.ids.len() {
            self.aabbs.push(padded_box(hulls.hull(h), pad(h)));
        }
        if self.aabbs.len() < 2 {
            return;
        }
        let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &self.aabbs);
        bvh.traverse_bvtt_single_tree::<false>(&mut self.workspace, &mut |a, b| {
            let (a, b) = (a.min(b) as usize, a.max(b) as usize);
            let (la, lb) = (hulls.ids[a].link, hulls.ids[b].link);
            if la != lb && !excluded.contains(&(la.min(lb), la.max(lb))) {
                out.push((a, b));
            }
        });
        out.sort_unstable();
        out.dedup();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::hulls::HullId;
    use nalgebra::Vector3;

    fn cube(c: Vector3<f64>) -> Vec<Vector3<f64>> {
        crate::model::Hull::cuboid(Vector3::new(1.0, 1.0, 1.0), c)
    }

    #[test]
    fn broad_phase_matches_brute_force_box_overlap() {
        let centers: Vec<Vector3<f64>> = (0..40)
            .map(|i| {
                Vector3::new(
                    (i % 7) as f64 * 1.003,
                    (i / 7) as f64 * 1.01,
                    (i % 3) as f64 * 0.3,
                )
            })
            .collect();
        let mut w = WorldHulls::default();
        for (i, c) in centers.iter().enumerate() {
            let start = w.vertices.len();
            w.vertices.extend(cube(*c));
            w.ranges.push(start..w.vertices.len());
            w.ids.push(HullId { link: i, hull: 0 });
        }
        let excluded: BTreeSet<(usize, usize)> = [(0, 1), (3, 10)].into_iter().collect();
        let range = 0.02;
        let mut bp = BroadPhase::default();
        let mut pairs = Vec::new();
        bp.candidate_pairs(&w, range, &excluded, &mut pairs);
        let mut brute = Vec::new();
        for a in 0..centers.len() {
            for b in a + 1..centers.len() {
                let gap = (centers[a] - centers[b]).abs().map(|d| d - 1.0).max();
                if gap <= range && !excluded.contains(&(a, b)) {
                    brute.push((a, b));
                }
            }
        }
        assert!(!brute.is_empty());
        assert_eq!(pairs, brute);
        // Swept boxes (sweep and prune) with per-hull pads: the same as the
        // BVH query with those pads, and as brute force.
        let pad: Vec<f64> = (0..centers.len()).map(|i| 0.2 * (i % 5) as f64).collect();
        let mut swept = Vec::new();
        bp.swept_pairs(&w, &pad, &excluded, &mut swept);
        let mut brute = Vec::new();
        for a in 0..centers.len() {
            for b in a + 1..centers.len() {
                let gap = (centers[a] - centers[b]).abs().map(|d| d - 1.0).max();
                if gap <= pad[a] + pad[b] && !excluded.contains(&(a, b)) {
                    brute.push((a, b));
                }
            }
        }
        assert!(brute.len() > pairs.len());
        assert_eq!(swept, brute);
    }
}
