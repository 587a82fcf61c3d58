//! Broad phase: candidate hull pairs whose bounding boxes, inflated by the
//! contact range, overlap (paper, `contact.tex`: "`U_c` only takes non-zero
//! values when the distance … is less than 2s/(1−s). By bulging each bounding
//! box by this distance, we … prune non-overlapping pairs").
//!
//! Boxes are inflated by half the range on every side, so two boxes overlap
//! whenever the hulls are closer than the range (box distance ≤ hull
//! distance).
//!
//! **Incremental sweep and prune.** The query runs once per objective
//! evaluation (several per Newton iteration), and between two queries the
//! hulls move little. The boxes are kept sorted by their lower bound along a
//! sweep axis; the order persists between queries and is repaired by
//! insertion sort, `O(n + k)` for `k` swaps (small: coherent motion), instead
//! of a tree rebuilt from scratch per query (parry's BVH was rebuilt here
//! before, 12 % of a step with two links per chain). The sweep axis is the
//! one along which the box centres spread most (the chains hang along `z`:
//! each box then overlaps few others along it). A pair is reported when its
//! boxes overlap on all three axes (closed intervals, as the BVH's test), so
//! the pair set is the same as before, and it is returned sorted: the result
//! does not depend on the sweep order, and is deterministic.
//!
//! **Links first.** The sweep runs over one box per link (per run of
//! consecutive hulls of one link: the union of their boxes), then tests the
//! hull boxes of each candidate link pair. A link made of many blocks (a
//! designed jaw: tens of touching blocks) no longer puts all pairs of its own
//! blocks through the sweep only to reject them as same-link pairs; that was
//! half of a parallel-jaw co-design iteration. Two hull boxes that overlap
//! lie in link boxes that overlap, so the pair set is unchanged.
//!
//! **Boxes without vertices.** The contact term queries with boxes from each
//! hull's link-frame box ([`BroadPhase::candidate_pairs_of_boxes`],
//! [`WorldHulls::enclosing_box`]: O(1) per hull, at most √3 × looser), so a
//! step never transforms the vertices of hulls far from everything (a
//! designed jaw's blocks: a fifth of a parallel-jaw simulation). The pairs are
//! then a superset; a pair beyond the range is certified out of range by the
//! narrow phase and adds nothing to the energy.

use super::aabb::Aabb;
use super::hulls::WorldHulls;
use std::cmp::Ordering;
use std::collections::BTreeSet;

/// Broad-phase state: the padded boxes of the last query and the persistent
/// sweep order (nothing else persists between queries).
#[derive(Clone, Default)]
pub struct BroadPhase {
    aabbs: Vec<Aabb>,
    /// Runs of consecutive hulls of one link: `(link, hull indices)`.
    groups: Vec<(usize, std::ops::Range<usize>)>,
    /// Each run's box: the union of its hulls' boxes.
    group_boxes: Vec<Aabb>,
    /// Run indices sorted by `(lo[axis], index)`; kept between queries.
    order: Vec<usize>,
    /// Sweep axis (0, 1, 2) of `order`.
    axis: usize,
}

/// The box of `x` (componentwise minimum and maximum).
fn tight_box(x: &[nalgebra::Vector3<f64>]) -> Aabb {
    Aabb::of_points(x)
}

/// `b` padded by `half` on every side.
fn padded(b: &Aabb, half: f64) -> Aabb {
    b.padded(half)
}

/// The box of `x` padded by `half` on every side.
fn padded_box(x: &[nalgebra::Vector3<f64>], half: f64) -> Aabb {
    padded(&tight_box(x), half)
}

/// The (unpadded) box of every hull of `hulls`, written into `out`; for
/// [`BroadPhase::swept_pairs`], which pads them as [`padded_box`] would.
pub fn hull_boxes(hulls: &WorldHulls, out: &mut Vec<Aabb>) {
    out.clear();
    out.extend((0..hulls.ids.len()).map(|h| tight_box(hulls.hull(h))));
}

/// Whether the closed intervals of `a` and `b` overlap along axis `e`
/// (`false` when a bound is NaN).
#[inline]
fn overlap(a: &Aabb, b: &Aabb, e: usize) -> bool {
    a.overlaps_on(b, e)
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
        self.aabbs.clear();
        for h in 0..hulls.ids.len() {
            self.aabbs.push(padded_box(hulls.hull(h), half));
        }
        self.sweep(hulls, excluded, out);
    }

    /// As [`BroadPhase::candidate_pairs`], with the hulls' boxes given
    /// (`boxes[h]`, e.g. [`WorldHulls::enclosing_box`]: any box containing
    /// hull `h`), each padded by `0.5 range`. `hulls` supplies the links
    /// only: its vertices are not read.
    pub fn candidate_pairs_of_boxes(
        &mut self,
        hulls: &WorldHulls,
        boxes: &[Aabb],
        range: f64,
        excluded: &BTreeSet<(usize, usize)>,
        out: &mut Vec<(usize, usize)>,
    ) {
        let half = 0.5 * range;
        self.aabbs.clear();
        self.aabbs
            .extend(boxes.iter().take(hulls.ids.len()).map(|b| padded(b, half)));
        self.sweep(hulls, excluded, out);
    }

    /// Candidate pairs for continuous collision detection: as
    /// [`BroadPhase::candidate_pairs`], with hull `h`'s box padded by
    /// `pad[h]` on every side — how far any of its points can move on the
    /// segment being checked, so the padded box contains the hull's whole
    /// swept volume and a pair that could meet anywhere on the segment is a
    /// candidate. `boxes` are the hulls' unpadded boxes ([`hull_boxes`]):
    /// one computation serves queries with different pads, and the padded
    /// boxes are bit for bit those of [`padded_box`].
    pub fn swept_pairs(
        &mut self,
        hulls: &WorldHulls,
        boxes: &[Aabb],
        pad: &[f64],
        excluded: &BTreeSet<(usize, usize)>,
        out: &mut Vec<(usize, usize)>,
    ) {
        self.aabbs.clear();
        for (b, &p) in boxes.iter().zip(pad).take(hulls.ids.len()) {
            self.aabbs.push(padded(b, p));
        }
        self.sweep(hulls, excluded, out);
    }

    /// The padded boxes of the last query, per hull.
    pub fn boxes(&self) -> &[Aabb] {
        &self.aabbs
    }

    /// As [`BroadPhase::swept_pairs`], but each candidate pair is handed
    /// to `visit` as it is found (in sweep order, not sorted) until `visit`
    /// returns false; returns whether every candidate was visited. For a
    /// test that must hold for every candidate and can stop at the first
    /// failure.
    pub fn swept_pairs_until(
        &mut self,
        hulls: &WorldHulls,
        boxes: &[Aabb],
        pad: &[f64],
        excluded: &BTreeSet<(usize, usize)>,
        visit: impl FnMut(usize, usize) -> bool,
    ) -> bool {
        self.aabbs.clear();
        for (b, &p) in boxes.iter().zip(pad).take(hulls.ids.len()) {
            self.aabbs.push(padded(b, p));
        }
        self.sweep_until(hulls, excluded, visit)
    }

    /// Sweep and prune over `self.aabbs` (see the module documentation).
    fn sweep(
        &mut self,
        hulls: &WorldHulls,
        excluded: &BTreeSet<(usize, usize)>,
        out: &mut Vec<(usize, usize)>,
    ) {
        out.clear();
        self.sweep_until(hulls, excluded, |a, b| {
            out.push((a, b));
            true
        });
        out.sort_unstable();
    }

    /// The sweep itself: every candidate pair `(a, b)`, `a < b`, goes to
    /// `visit` until it returns false (then false is returned).
    fn sweep_until(
        &mut self,
        hulls: &WorldHulls,
        excluded: &BTreeSet<(usize, usize)>,
        mut visit: impl FnMut(usize, usize) -> bool,
    ) -> bool {
        self.group_hulls(hulls);
        let BroadPhase {
            aabbs,
            groups,
            group_boxes,
            order,
            axis,
        } = self;
        sweep_and_prune(group_boxes, order, axis, |ga, gb| {
            let ((la, ra), (lb, rb)) = (&groups[ga], &groups[gb]);
            if la == lb || excluded.contains(&((*la).min(*lb), (*la).max(*lb))) {
                return true;
            }
            for a in ra.clone() {
                let ba = &aabbs[a];
                for b in rb.clone() {
                    if ba.intersects(&aabbs[b]) && !visit(a.min(b), a.max(b)) {
                        return false;
                    }
                }
            }
            true
        })
    }

    /// The runs of consecutive hulls of one link and their boxes (the
    /// componentwise min/max of the hulls' boxes; a NaN bound drops out of
    /// the union, and its hull out of every pair by the hull test).
    fn group_hulls(&mut self, hulls: &WorldHulls) {
        self.groups.clear();
        self.group_boxes.clear();
        for (h, b) in self.aabbs.iter().enumerate() {
            let link = hulls.ids[h].link;
            match self.groups.last_mut() {
                Some((l, r)) if *l == link => {
                    r.end = h + 1;
                    let g = self.group_boxes.last_mut().expect("one box per run");
                    for e in 0..3 {
                        g.lo[e] = g.lo[e].min(b.lo[e]);
                        g.hi[e] = g.hi[e].max(b.hi[e]);
                    }
                }
                _ => {
                    self.groups.push((link, h..h + 1));
                    self.group_boxes.push(*b);
                }
            }
        }
    }
}

/// Incremental sweep and prune over `boxes` (see the module documentation):
/// every pair whose boxes overlap along the sweep axis and the two others
/// goes to `visit` (unordered indices) until it returns false.
fn sweep_and_prune(
    boxes: &[Aabb],
    order: &mut Vec<usize>,
    axis_state: &mut usize,
    mut visit: impl FnMut(usize, usize) -> bool,
) -> bool {
    let n = boxes.len();
    if n < 2 {
        return true;
    }
    // Axis of the largest spread of the box centres (NaN-free spreads
    // only; ties keep the lower axis).
    let mut spread = [0.0f64; 3];
    for (e, s) in spread.iter_mut().enumerate() {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for b in boxes {
            let c = b.lo[e] + b.hi[e];
            lo = lo.min(c);
            hi = hi.max(c);
        }
        *s = hi - lo;
    }
    let mut axis = *axis_state;
    for e in 0..3 {
        if spread[e] > 1.5 * spread[axis] {
            axis = e;
        }
    }
    if order.len() != n {
        order.clear();
        order.extend(0..n);
    }
    *axis_state = axis;
    // Insertion sort by (lo[axis], index): a total order, so the
    // sorted sequence is unique whatever the previous one was.
    let key = |i: usize| (boxes[i].lo[axis], i);
    let less = |a: (f64, usize), b: (f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).is_lt();
    for k in 1..n {
        let cur = order[k];
        let kc = key(cur);
        let mut j = k;
        while j > 0 && less(kc, key(order[j - 1])) {
            order[j] = order[j - 1];
            j -= 1;
        }
        order[j] = cur;
    }
    let (o1, o2) = ((axis + 1) % 3, (axis + 2) % 3);
    for (k, &a) in order.iter().enumerate() {
        let ba = &boxes[a];
        for &b in &order[k + 1..] {
            let bb = &boxes[b];
            // Sorted by lower bound: no later box can overlap `a` along
            // the axis once one starts past its upper bound.
            // (NaN bounds compare as "past" too: no pair, as in the
            // overlap test.)
            if !matches!(
                bb.lo[axis].partial_cmp(&ba.hi[axis]),
                Some(Ordering::Less | Ordering::Equal)
            ) {
                break;
            }
            if !(ba.lo[axis] <= bb.hi[axis] && overlap(ba, bb, o1) && overlap(ba, bb, o2)) {
                continue;
            }
            if !visit(a, b) {
                return false;
            }
        }
    }
    true
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
        let mut boxes = Vec::new();
        hull_boxes(&w, &mut boxes);
        bp.swept_pairs(&w, &boxes, &pad, &excluded, &mut swept);
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

    /// Repeated queries on moving boxes reuse the sweep order (and switch
    /// axes as the spread changes): every query equals brute force.
    #[test]
    fn incremental_sweep_matches_brute_force_while_moving() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let n = 60;
        let mut centers: Vec<Vector3<f64>> = (0..n)
            .map(|_| {
                Vector3::new(
                    rng.random_range(0.0..6.0),
                    rng.random_range(0.0..2.0),
                    rng.random_range(0.0..1.0),
                )
            })
            .collect();
        let excluded: BTreeSet<(usize, usize)> = [(0, 1), (5, 9)].into_iter().collect();
        let mut bp = BroadPhase::default();
        let mut pairs = Vec::new();
        for q in 0..40 {
            // Drift, and after 20 queries stretch the cloud along z.
            for c in &mut centers {
                *c += Vector3::new(
                    rng.random_range(-0.05..0.05),
                    rng.random_range(-0.05..0.05),
                    rng.random_range(-0.05..0.05),
                );
                if q == 20 {
                    c.z *= 12.0;
                }
            }
            let mut w = WorldHulls::default();
            for (i, c) in centers.iter().enumerate() {
                let start = w.vertices.len();
                w.vertices.extend(cube(*c));
                w.ranges.push(start..w.vertices.len());
                w.ids.push(HullId { link: i, hull: 0 });
            }
            let range = 0.05;
            bp.candidate_pairs(&w, range, &excluded, &mut pairs);
            let mut brute = Vec::new();
            for a in 0..n {
                for b in a + 1..n {
                    let gap = (centers[a] - centers[b]).abs().map(|d| d - 1.0).max();
                    if gap <= range && !excluded.contains(&(a, b)) {
                        brute.push((a, b));
                    }
                }
            }
            assert_eq!(pairs, brute, "query {q}");
        }
        assert_eq!(bp.axis, 2, "the sweep follows the largest spread");
    }

    /// Links of several touching blocks (a designed jaw), some links'
    /// hulls not consecutive, an excluded link pair, NaN vertices: the
    /// link-first sweep finds exactly the brute-force hull pairs, on every
    /// one of several moving queries.
    #[test]
    fn many_hulls_per_link_match_brute_force() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
        // (link, centre) per hull: links 0–5 are 3×3 grids of unit blocks
        // 1 mm apart; link 6's hulls are split around link 7's.
        let mut hulls: Vec<(usize, Vector3<f64>)> = Vec::new();
        for link in 0..6 {
            let base = Vector3::new(link as f64 * 2.5, (link % 2) as f64 * 1.5, 0.0);
            for i in 0..9 {
                let o = Vector3::new((i % 3) as f64 * 1.001, (i / 3) as f64 * 1.001, 0.0);
                hulls.push((link, base + o * 0.5));
            }
        }
        hulls.push((6, Vector3::new(1.0, 0.5, 0.4)));
        hulls.push((7, Vector3::new(3.0, 0.5, 0.4)));
        hulls.push((6, Vector3::new(5.0, 0.5, 0.4)));
        let excluded: BTreeSet<(usize, usize)> = [(0, 1), (2, 6)].into_iter().collect();
        let mut bp = BroadPhase::default();
        let mut pairs = Vec::new();
        for q in 0..20 {
            for (_, c) in &mut hulls {
                *c += Vector3::new(
                    rng.random_range(-0.1..0.1),
                    rng.random_range(-0.1..0.1),
                    rng.random_range(-0.1..0.1),
                );
            }
            let mut w = WorldHulls::default();
            for (k, (link, c)) in hulls.iter().enumerate() {
                let start = w.vertices.len();
                let mut v = cube(*c);
                if q % 5 == 4 && k == 7 {
                    v.iter_mut().for_each(|x| x.x = f64::NAN);
                } else if q % 5 == 3 && k == 7 {
                    v[0].x = f64::NAN;
                }
                w.vertices.extend(v);
                w.ranges.push(start..w.vertices.len());
                w.ids.push(HullId {
                    link: *link,
                    hull: k,
                });
            }
            let range = 0.05;
            bp.candidate_pairs(&w, range, &excluded, &mut pairs);
            // The contract, on the padded hull boxes themselves (whatever a
            // NaN vertex does to its box, both sides see the same box).
            let mut boxes = Vec::new();
            hull_boxes(&w, &mut boxes);
            let boxes: Vec<Aabb> = boxes.iter().map(|b| padded(b, 0.5 * range)).collect();
            let mut brute = Vec::new();
            for a in 0..hulls.len() {
                for b in a + 1..hulls.len() {
                    let (la, lb) = (hulls[a].0, hulls[b].0);
                    let apart = !excluded.contains(&(la.min(lb), la.max(lb)));
                    if la != lb && apart && boxes[a].intersects(&boxes[b]) {
                        brute.push((a, b));
                    }
                }
            }
            assert!(!brute.is_empty());
            assert_eq!(pairs, brute, "query {q}");
        }
    }
}
