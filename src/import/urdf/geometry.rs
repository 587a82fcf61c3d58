//! URDF geometry: mesh paths (`package://`, `file://`, relative) and
//! `<collision>`/`<visual>` elements → [`SourceGeometry`].

use super::super::error::ImportError;
use super::super::pybullet_shapes::{
    PLANE_EXTENT, PLANE_THICKNESS, Slot, Special, SpecialShapes, plane_slab,
};
use super::super::source::*;
use super::frames::*;
use std::path::{Path, PathBuf};

/// Resolves a mesh file name from a URDF.
pub fn resolve_mesh_path(urdf: &Path, filename: &str) -> Result<PathBuf, Vec<PathBuf>> {
    let base = urdf
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    if let Some(rest) = filename.strip_prefix("package://") {
        let (pkg, rel) = rest.split_once('/').unwrap_or((rest, ""));
        let mut tried = Vec::new();
        let abs = std::fs::canonicalize(&base).unwrap_or(base.clone());
        for dir in abs.ancestors() {
            let cands = [
                dir.join(pkg),
                if dir.file_name().is_some_and(|n| n == pkg) {
                    dir.to_path_buf()
                } else {
                    PathBuf::new()
                },
            ];
            for c in cands {
                if c.as_os_str().is_empty() {
                    continue;
                }
                let f = c.join(rel);
                if f.is_file() {
                    return Ok(f);
                }
                tried.push(f);
            }
        }
        if let Some(rpp) = std::env::var_os("ROS_PACKAGE_PATH") {
            for entry in std::env::split_paths(&rpp) {
                for c in [entry.join(pkg), entry.clone()] {
                    if c == entry && entry.file_name().is_none_or(|n| n != pkg) {
                        continue;
                    }
                    let f = c.join(rel);
                    if f.is_file() {
                        return Ok(f);
                    }
                    tried.push(f);
                }
            }
        }
        return Err(tried);
    }
    let p = if let Some(rest) = filename.strip_prefix("file://") {
        PathBuf::from(rest)
    } else {
        PathBuf::from(filename)
    };
    let f = if p.is_absolute() { p } else { base.join(p) };
    if f.is_file() { Ok(f) } else { Err(vec![f]) }
}

/// A link's geometry: its `<collision>` elements, or its `<visual>` ones
/// when it has none (a visual whose mesh file is missing is left out with a
/// report line; a missing collision mesh is an error); pybullet's `<plane>`
/// and `<cdf>` substituted as [`super::pybullet_shapes`] says.
pub(super) fn link_geometry(
    path: &Path,
    l: &urdf_rs::Link,
    special: &SpecialShapes,
    notes: &mut Vec<String>,
) -> Result<Vec<SourceGeometry>, ImportError> {
    let invalid = |element: String, msg: String| ImportError::InvalidUrdf {
        path: path.to_path_buf(),
        element,
        msg,
    };
    let one = |slot: Slot, gi: usize, origin: &urdf_rs::Pose, g: &urdf_rs::Geometry| {
        let tag = if slot == Slot::Collision {
            "collision"
        } else {
            "visual"
        };
        let element = format!("link \"{}\" {tag}[{gi}]", l.name);
        match special.get(&(l.name.clone(), slot, gi)) {
            None => geometry_of(path, element, origin, g).map(|g| vec![g]),
            Some(Special::Plane { normal }) => {
                let slab = plane_slab(normal).map_err(|m| invalid(element.clone(), m))?;
                let (r, t) = rt(&origin_of(origin));
                Ok(vec![SourceGeometry {
                    element,
                    rotation: r * slab.rotation,
                    translation: t + r * slab.centre,
                    shape: SourceShape::Box { size: slab.size },
                }])
            }
            Some(Special::Cdf { filename }) => Err(invalid(
                element,
                format!(
                    "pybullet's signed-distance-field geometry <cdf filename=\"{filename}\"> has no visual geometry to stand in for it"
                ),
            )),
        }
    };
    let mut geometry = Vec::new();
    if !l.collision.is_empty() {
        for (gi, c) in l.collision.iter().enumerate() {
            if let Some(Special::Cdf { filename }) =
                special.get(&(l.name.clone(), Slot::Collision, gi))
            {
                if l.visual.is_empty() {
                    return one(Slot::Collision, gi, &c.origin, &c.geometry);
                }
                notes.push(format!(
                    "link \"{}\" collision[{gi}]: pybullet's signed-distance-field geometry <cdf filename=\"{filename}\"> is not supported; the link's visual geometry is used for collision instead",
                    l.name
                ));
                for (vi, v) in l.visual.iter().enumerate() {
                    geometry.extend(one(Slot::Visual, vi, &v.origin, &v.geometry)?);
                }
                continue;
            }
            if let Some(Special::Plane { normal }) =
                special.get(&(l.name.clone(), Slot::Collision, gi))
            {
                notes.push(format!(
                    "link \"{}\" collision[{gi}]: pybullet's infinite <plane normal=\"{normal}\"> is imported as a {PLANE_EXTENT} m × {PLANE_EXTENT} m × {PLANE_THICKNESS} m slab whose top face is the plane (a convex hull cannot be infinite)",
                    l.name
                ));
            }
            geometry.extend(one(Slot::Collision, gi, &c.origin, &c.geometry)?);
        }
    } else {
        for (gi, v) in l.visual.iter().enumerate() {
            match one(Slot::Visual, gi, &v.origin, &v.geometry) {
                Ok(g) => geometry.extend(g),
                // A visual is drawn, not collided: a missing visual mesh
                // (e.g. an absolute path into a vendor SDK) leaves the link
                // without that piece, with a line in the report; a missing
                // collision mesh stays an error.
                Err(ImportError::MissingMesh { element, mesh, .. }) => notes.push(format!(
                    "{element}: mesh file {} not found; a link without <collision> takes its visual geometry for contact, and this piece is left out (the link's <inertial> is kept)",
                    mesh.display()
                )),
                Err(e) => return Err(e),
            }
        }
    }
    Ok(geometry)
}

pub(super) fn geometry_of(
    path: &Path,
    element: String,
    origin: &urdf_rs::Pose,
    g: &urdf_rs::Geometry,
) -> Result<SourceGeometry, ImportError> {
    let o = origin_of(origin);
    let (rotation, translation) = rt(&o);
    let shape = match g {
        urdf_rs::Geometry::Box { size } => SourceShape::Box { size: size.0 },
        urdf_rs::Geometry::Cylinder { radius, length } => SourceShape::Cylinder {
            radius: *radius,
            length: *length,
        },
        urdf_rs::Geometry::Sphere { radius } => SourceShape::Sphere { radius: *radius },
        urdf_rs::Geometry::Capsule { radius, length } => SourceShape::Capsule {
            radius: *radius,
            length: *length,
        },
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let file = resolve_mesh_path(path, filename).map_err(|tried| {
                let hint = if filename.starts_with("package://") {
                    format!(
                        " (looked for the package directory upward from the URDF and in ROS_PACKAGE_PATH; tried {})",
                        tried
                            .iter()
                            .take(4)
                            .map(|p| p.display().to_string())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                } else {
                    String::new()
                };
                ImportError::MissingMesh {
                    path: path.to_path_buf(),
                    element: element.clone(),
                    mesh: tried.first().cloned().unwrap_or_else(|| PathBuf::from(filename)),
                    hint,
                }
            })?;
            SourceShape::Mesh {
                path: file,
                scale: scale.map(|s| s.0).unwrap_or([1.0; 3]),
            }
        }
    };
    Ok(SourceGeometry {
        element,
        rotation,
        translation,
        shape,
    })
}
