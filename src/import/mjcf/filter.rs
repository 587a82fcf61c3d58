//! MuJoCo's contact filter as exclusions: geoms whose `contype`/
//! `conaffinity` masks never match, bodies welded together (`body_weldid`),
//! a weld group and its parent group (`filterparent`, unless the parent is
//! the world), the world's geoms against bodies welded to the world, and
//! the body pairs of `<contact><exclude>` (MuJoCo's `exclude_signature`,
//! bodies as written, world = −1).

use super::super::error::ImportError;
use super::bodies::Bodies;
use super::dump::{Dump, DumpGeom};
use super::invalid;
use super::world::World;
use std::path::Path;

/// Weld groups (MuJoCo's `body_weldid`): a body without joints moves with
/// its parent. `None` is the world.
pub(super) fn weld_groups(path: &Path, d: &Dump) -> Result<Vec<Option<usize>>, ImportError> {
    let mut weld: Vec<Option<usize>> = vec![None; d.bodies.len()];
    for (b, body) in d.bodies.iter().enumerate() {
        let parent = usize::try_from(body.parent).ok();
        if parent.is_some_and(|p| p >= b) {
            return Err(invalid(
                path,
                format!("body \"{}\"", body.name),
                "bodies are not in tree order".into(),
            ));
        }
        weld[b] = if body.joints.is_empty() || body.mocap {
            parent.and_then(|p| weld[p])
        } else {
            Some(b)
        };
    }
    Ok(weld)
}

/// Whether any colliding geom of `a` may touch any colliding geom of `b`.
pub(super) fn masks_meet(a: &[&DumpGeom], b: &[&DumpGeom]) -> bool {
    a.iter().filter(|g| g.collides()).any(|ga| {
        b.iter()
            .filter(|g| g.collides())
            .any(|gb| ga.may_collide_with(gb))
    })
}

/// Whether `<contact><exclude>` names the bodies `a` and `b` (either order;
/// −1 is the world).
pub(super) fn listed(d: &Dump, a: i64, b: i64) -> bool {
    d.exclude
        .iter()
        .any(|&[x, y]| (x, y) == (a, b) || (x, y) == (b, a))
}

/// Excluded pairs of geometry links (names) between bodies.
pub(super) fn body_pairs(
    d: &Dump,
    weld: &[Option<usize>],
    geoms_of: &[Vec<&DumpGeom>],
    bodies: &Bodies,
) -> Vec<[String; 2]> {
    let nb = d.bodies.len();
    let (links, geometry_link, collides) = (&bodies.links, &bodies.geometry_link, &bodies.collides);
    let weld_parent = |w: Option<usize>| -> Option<usize> {
        w.and_then(|b| {
            usize::try_from(d.bodies[b].parent)
                .ok()
                .and_then(|p| weld[p])
        })
    };
    let mut exclude = Vec::new();
    for a in 0..nb {
        for b in a + 1..nb {
            if !(collides[a] && collides[b]) || geometry_link[a] == geometry_link[b] {
                continue;
            }
            let (wa, wb) = (weld[a], weld[b]);
            // MuJoCo's `filterparent`: a weld group and its parent group,
            // unless the parent is the world.
            let parent_child =
                wa.is_some() && wb.is_some() && (weld_parent(wa) == wb || weld_parent(wb) == wa);
            let filtered = wa == wb
                || parent_child
                || listed(d, a as i64, b as i64)
                || !masks_meet(&geoms_of[a], &geoms_of[b]);
            if filtered {
                exclude.push([
                    links[geometry_link[a]].name.clone(),
                    links[geometry_link[b]].name.clone(),
                ]);
            }
        }
    }

    exclude
}

/// Per body that collides: excluded against the ground (link names) and
/// against each obstacle (obstacle, link).
pub(super) fn world_pairs(
    d: &Dump,
    weld: &[Option<usize>],
    geoms_of: &[Vec<&DumpGeom>],
    bodies: &Bodies,
    world: &World,
) -> (Vec<String>, Vec<[String; 2]>) {
    let nb = weld.len();
    let (links, geometry_link, collides) = (&bodies.links, &bodies.geometry_link, &bodies.collides);
    let (ground_geom, obstacles, obstacle_geoms) =
        (world.ground_geom, &world.obstacles, &world.obstacle_geoms);
    let mut exclude_ground = Vec::new();
    let mut exclude_obstacle = Vec::new();
    for b in 0..nb {
        if !collides[b] {
            continue;
        }
        let name = &links[geometry_link[b]].name;
        let off = weld[b].is_none() || listed(d, -1, b as i64);
        if let Some(g) = ground_geom
            && (off || !masks_meet(&geoms_of[b], &[g]))
        {
            exclude_ground.push(name.clone());
        }
        for (o, g) in obstacles.iter().zip(obstacle_geoms.iter()) {
            if off || !masks_meet(&geoms_of[b], &[*g]) {
                exclude_obstacle.push([o.name.clone(), name.clone()]);
            }
        }
    }
    (exclude_ground, exclude_obstacle)
}
