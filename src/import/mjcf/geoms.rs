//! MJCF geoms and inertials → source shapes and second moments.

use super::super::error::ImportError;
use super::super::source::*;
use super::dump::{DumpBody, DumpGeom};
use super::frame::*;

use super::invalid;
use nalgebra::{Matrix3, Vector3};
use std::path::Path;

/// The massless frame's cube.
pub(super) fn frame_cube(link: &str) -> SourceGeometry {
    SourceGeometry {
        element: format!("joint frame \"{link}\""),
        rotation: Matrix3::identity(),
        translation: Vector3::zeros(),
        shape: SourceShape::Tiny {
            edge: super::FRAME_CUBE,
        },
    }
}

/// The body's inertial as a 4×4 second moment in the link frame (body
/// frame moved by `−anchor`).
pub(super) fn body_moment(body: &DumpBody, anchor: &Vector3<f64>) -> nalgebra::Matrix4<f64> {
    let r = quat_matrix(&body.iquat);
    let i = r * Matrix3::from_diagonal(&Vector3::from(body.inertia)) * r.transpose();
    crate::model::Inertial {
        mass: body.mass,
        com: Vector3::from(body.ipos) - anchor,
        inertia: i,
    }
    .second_moment()
}

/// The shape of a geom (`None`, with a note, for what is left out).
pub(super) fn geom_shape(
    path: &Path,
    g: &DumpGeom,
    notes: &mut Vec<String>,
) -> Result<Option<SourceShape>, ImportError> {
    let s = g.size;
    Ok(Some(match g.kind.as_str() {
        "sphere" => SourceShape::Sphere { radius: s[0] },
        "capsule" => SourceShape::Capsule {
            radius: s[0],
            length: 2.0 * s[1],
        },
        "cylinder" => SourceShape::Cylinder {
            radius: s[0],
            length: 2.0 * s[1],
        },
        "box" => SourceShape::Box {
            size: [2.0 * s[0], 2.0 * s[1], 2.0 * s[2]],
        },
        "ellipsoid" => SourceShape::Ellipsoid { radii: s },
        "mesh" => {
            let Some(m) = &g.mesh else {
                return Err(invalid(
                    path,
                    format!("geom \"{}\"", g.name),
                    "mesh geom without mesh data".into(),
                ));
            };
            SourceShape::ConvexMesh {
                mesh: super::super::mesh::TriMesh {
                    vertices: m.vertices.iter().map(|v| Vector3::from(*v)).collect(),
                    triangles: m.faces.clone(),
                },
            }
        }
        other => {
            notes.push(format!(
                "geom \"{}\": type {other} is not supported here; left out",
                g.name
            ));
            return Ok(None);
        }
    }))
}

/// The hull points of a shape (for obstacles), in the geom frame.
pub(super) fn shape_points(
    path: &Path,
    element: &str,
    shape: &SourceShape,
) -> Result<Vec<Vector3<f64>>, ImportError> {
    use super::super::primitives as p;
    let err = |msg: String| invalid(path, element.to_string(), msg);
    Ok(match shape {
        SourceShape::Sphere { radius } => p::sphere_hull(*radius).map_err(err)?.hull,
        SourceShape::Capsule { radius, length } => {
            p::capsule_hull(*radius, *length).map_err(err)?.hull
        }
        SourceShape::Cylinder { radius, length } => {
            p::cylinder_hull(*radius, *length).map_err(err)?.hull
        }
        SourceShape::Box { size } => p::box_hull(*size).map_err(err)?.hull,
        SourceShape::Ellipsoid { radii } => p::ellipsoid_hull(*radii).map_err(err)?.hull,
        SourceShape::ConvexMesh { mesh } => {
            super::super::polytope::convex_hull(&mesh.vertices)
                .map_err(err)?
                .vertices
        }
        SourceShape::Mesh { .. } | SourceShape::Tiny { .. } => {
            unreachable!("not produced for MJCF")
        }
    })
}
