//! Self-intersection of a triangle mesh: a BVH (parry's `Bvh`, binned
//! build) over the triangles' bounding boxes; each triangle queries its own
//! box, and candidate pairs that share no vertex are tested exactly
//! ([`super::tri_tri::triangles_intersect`]). Cost `O(n log n + k)` for
//! `n` triangles and `k` overlapping box pairs. Triangles that share a
//! vertex or an edge are neighbours in the surface and are not tested.

use super::tri_tri::triangles_intersect;
use nalgebra::Vector3;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};

/// The bounding box of triangle `t` as parry's `Aabb`.
pub fn tri_aabb(v: &[Vector3<f64>], t: &[usize; 3]) -> Aabb {
    let p = t.map(|i| v[i]);
    let lo = p[0].inf(&p[1]).inf(&p[2]);
    let hi = p[0].sup(&p[1]).sup(&p[2]);
    Aabb::new(PVec::new(lo.x, lo.y, lo.z), PVec::new(hi.x, hi.y, hi.z))
}

/// A BVH over the triangles `tris` (leaf `i` = triangle `i`).
pub fn triangle_bvh(v: &[Vector3<f64>], tris: &[[usize; 3]]) -> Bvh {
    let boxes: Vec<Aabb> = tris.iter().map(|t| tri_aabb(v, t)).collect();
    Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes)
}

/// The first pair `(i, j)`, `i < j` (smallest `i`, then smallest `j`), of
/// triangles among `subset` that share no vertex and meet.
pub fn first_self_intersection(
    v: &[Vector3<f64>],
    tris: &[[usize; 3]],
    subset: &[usize],
) -> Option<(usize, usize)> {
    let local: Vec<[usize; 3]> = subset.iter().map(|&i| tris[i]).collect();
    let bvh = triangle_bvh(v, &local);
    for (a, ta) in local.iter().enumerate() {
        let bx = tri_aabb(v, ta);
        let mut hits: Vec<usize> = bvh
            .intersect_aabb(&bx)
            .map(|b| b as usize)
            .filter(|&b| b > a)
            .filter(|&b| !local[b].iter().any(|x| ta.contains(x)))
            .collect();
        hits.sort_unstable();
        let pa = ta.map(|i| v[i]);
        if let Some(&b) = hits
            .iter()
            .find(|&&b| triangles_intersect(&pa, &local[b].map(|i| v[i])))
        {
            return Some((subset[a].min(subset[b]), subset[a].max(subset[b])));
        }
    }
    None
}
