//! Rejects an intersecting start: IPC's barrier and CCD keep surfaces apart
//! only if they start apart. Surfaces that cross (or one inside another) need
//! not have any close primitive pair, so the test is on the solids: each
//! link's hulls are convex, and two links intersect iff some hull pair does
//! (parry's GJK-based intersection test), or their surfaces are closer than
//! round-off. A pair where either link's surface is a source mesh (maybe
//! non-convex, its hulls may fill its concavities) is tested on the meshes
//! themselves ([`crate::surface::intersect::meshes_intersect`]).

use nalgebra::Vector3;
use parry3d_f64::math::{Pose as PPose, Vector as PVec};
use parry3d_f64::shape::ConvexPolyhedron;
use sdrs::math::{Pose, transform_point};
use sdrs::model::Model;

use crate::mesh::{LinkMesh, MeshOrigin};

/// The first pair of links (in `pairs` order) whose solids intersect at
/// `pose`: hull pairs by [`first_intersecting`]'s test, pairs with a
/// source-mesh surface by the mesh test.
pub fn first_intersecting_surfaces(
    model: &Model,
    meshes: &[LinkMesh],
    pose: &[Pose],
    pairs: &[(usize, usize)],
) -> Option<(usize, usize)> {
    let is_source = |l: usize| matches!(meshes[l].origin, MeshOrigin::Source { .. });
    let (mesh_pairs, hull_pairs): (Vec<_>, Vec<_>) = pairs
        .iter()
        .copied()
        .partition(|&(a, b)| is_source(a) || is_source(b));
    let hit_hull = first_intersecting(model, pose, &hull_pairs);
    let hit_mesh = mesh_pairs.iter().copied().find(|&(a, b)| {
        crate::surface::intersect::meshes_intersect(&meshes[a], &pose[a], &meshes[b], &pose[b])
    });
    // Report the first in `pairs` order.
    [hit_hull, hit_mesh]
        .into_iter()
        .flatten()
        .min_by_key(|p| pairs.iter().position(|q| q == p))
}

/// The first pair of links (in `pairs` order) whose hulls intersect at
/// `pose`, if any.
pub fn first_intersecting(
    model: &Model,
    pose: &[Pose],
    pairs: &[(usize, usize)],
) -> Option<(usize, usize)> {
    let shapes: Vec<Vec<Option<ConvexPolyhedron>>> = (0..model.links.len())
        .map(|l| {
            model.links[l]
                .hulls
                .iter()
                .map(|h| {
                    let pts: Vec<PVec> = h
                        .x_local
                        .iter()
                        .map(|x| {
                            let w: Vector3<f64> = transform_point(&pose[l], x);
                            PVec::new(w.x, w.y, w.z)
                        })
                        .collect();
                    ConvexPolyhedron::from_convex_hull(&pts)
                })
                .collect()
        })
        .collect();
    let id = PPose::IDENTITY;
    pairs.iter().copied().find(|&(a, b)| {
        shapes[a].iter().flatten().any(|sa| {
            shapes[b].iter().flatten().any(|sb| {
                parry3d_f64::query::intersection_test(&id, sa, &id, sb)
                    .map(|r| r.intersecting)
                    .unwrap_or(true)
            })
        })
    })
}
