//! Whether the solids two closed link surfaces bound meet (the start check
//! for pairs with a source mesh, which may be non-convex): they do iff some
//! triangles of the two meet (closed triangles: touching counts; BVH over
//! one side's triangles) or one surface lies inside the other, tested for
//! one vertex of every component by the generalized winding number
//! `w(x) = Σ_t Ω_t(x) / 4π` (1 inside a closed outward surface, 0 outside;
//! `> 1/2` counts as inside).

use super::self_intersect::{tri_aabb, triangle_bvh};
use super::tri_tri::triangles_intersect;
use crate::cage::validate::solid_angle;
use crate::mesh::LinkMesh;
use nalgebra::Vector3;
use sdrs::math::{Pose, transform_point};

fn world(m: &LinkMesh, p: &Pose) -> (Vec<Vector3<f64>>, Vec<[usize; 3]>) {
    (
        m.x_local.iter().map(|x| transform_point(p, x)).collect(),
        m.tris.iter().map(|t| t.map(|i| i as usize)).collect(),
    )
}

fn winding(v: &[Vector3<f64>], tris: &[[usize; 3]], x: &Vector3<f64>) -> f64 {
    tris.iter()
        .map(|t| solid_angle(x, &v[t[0]], &v[t[1]], &v[t[2]]))
        .sum::<f64>()
        / (4.0 * std::f64::consts::PI)
}

/// One vertex of each component of `m` (by [`LinkMesh::source`]'s
/// component index).
fn component_seeds(m: &LinkMesh) -> Vec<usize> {
    let mut seen = std::collections::BTreeSet::new();
    (0..m.x_local.len())
        .filter(|&i| seen.insert(m.source.get(i).map_or(0, |s| s.0)))
        .collect()
}

/// The solids bounded by `a` at pose `pa` and `b` at pose `pb` meet.
pub fn meshes_intersect(a: &LinkMesh, pa: &Pose, b: &LinkMesh, pb: &Pose) -> bool {
    if a.is_empty() || b.is_empty() {
        return false;
    }
    let (va, ta) = world(a, pa);
    let (vb, tb) = world(b, pb);
    let bvh = triangle_bvh(&vb, &tb);
    for t in &ta {
        let bx = tri_aabb(&va, t);
        let pa3 = t.map(|i| va[i]);
        if bvh
            .intersect_aabb(&bx)
            .any(|j| triangles_intersect(&pa3, &tb[j as usize].map(|i| vb[i])))
        {
            return true;
        }
    }
    component_seeds(a)
        .iter()
        .any(|&i| winding(&vb, &tb, &va[i]) > 0.5)
        || component_seeds(b)
            .iter()
            .any(|&i| winding(&va, &ta, &vb[i]) > 0.5)
}
