//! The world body's geoms: the first upward plane is the ground, other
//! colliding geoms are obstacles, visual ones are left out.

use super::super::error::ImportError;
use super::super::source::*;
use super::dump::DumpGeom;
use super::frame::*;
use super::geoms::*;
use crate::scene::schema::{GroundSpec, HullSpec, ObstacleSpec};
use nalgebra::Vector3;
use std::path::Path;

/// The environment read from the world body.
pub(super) struct World<'a> {
    pub ground: Option<GroundSpec>,
    pub ground_geom: Option<&'a DumpGeom>,
    pub obstacles: Vec<ObstacleSpec>,
    pub obstacle_geoms: Vec<&'a DumpGeom>,
}

pub(super) fn world<'a>(
    path: &Path,
    world_geoms: &[&'a DumpGeom],
    notes: &mut Vec<String>,
) -> Result<World<'a>, ImportError> {
    let mut ground = None;
    let mut ground_geom = None;
    let mut obstacles = Vec::new();
    let mut obstacle_geoms = Vec::new();
    let mut visual = 0;
    for g in world_geoms {
        if !g.collides() {
            visual += 1;
            continue;
        }
        let r = quat_matrix(&g.quat);
        if g.kind == "plane" {
            let n = r * Vector3::z();
            if ground.is_none() && n.z > 1e-6 {
                let tilt = n.z.clamp(-1.0, 1.0).acos();
                let axis = Vector3::z().cross(&n);
                let slope_axis = if axis.norm() > 1e-12 {
                    axis.normalize().into()
                } else {
                    [0.0, 1.0, 0.0]
                };
                ground = Some(GroundSpec {
                    height: n.dot(&Vector3::from(g.pos)),
                    slope_deg: tilt.to_degrees(),
                    slope_axis,
                    half_size: 50.0,
                    thickness: 1.0,
                });
                ground_geom = Some(*g);
            } else {
                notes.push(format!(
                    "world geom \"{}\": only one upward plane becomes the ground; left out",
                    g.name
                ));
            }
            continue;
        }
        let Some(shape) = geom_shape(path, g, notes)? else {
            continue;
        };
        let hull = shape_points(path, &format!("world geom \"{}\"", g.name), &shape)?;
        obstacles.push(ObstacleSpec {
            name: sanitize(&g.name),
            origin: Frame {
                r,
                t: Vector3::from(g.pos),
            }
            .origin(),
            hulls: vec![HullSpec::from_vertices(
                hull.iter().map(|v| [v.x, v.y, v.z]).collect(),
            )],
            surface_mesh: None,
        });
        obstacle_geoms.push(*g);
    }
    if visual > 0 {
        notes.push(format!("{visual} visual world geom(s) left out"));
    }
    Ok(World {
        ground,
        ground_geom,
        obstacles,
        obstacle_geoms,
    })
}
