//! One link's geometry → design hulls: each `<collision>` (or MJCF geom)
//! of a link, as a primitive's hull, a convex mesh's hull, or a mesh file
//! decomposed ([`super::decompose`]); with the placed source surfaces (for
//! the coverage check and the mesh baseline), the source volume and the
//! report's notes.

use super::connectivity::DesignHull;
use super::mesh::{self, MeshContext, TriMesh};
use super::polytope::{self, convex_hull};
use super::source::{SourceGeometry, SourceRobot, SourceShape};
use super::{ImportError, ImportOptions, decompose, limits, primitives, units_hint};
use nalgebra::Vector3;
use std::time::Instant;

pub(super) struct LinkGeometry {
    /// What was repaired or worked around, for the report.
    pub notes: Vec<String>,
    pub hulls: Vec<DesignHull>,
    pub sources: Vec<TriMesh>,
    pub source_volume: Option<f64>,
    pub seconds: f64,
}

/// What every geometry element of one link is imported with.
struct LinkContext<'a> {
    src: &'a SourceRobot,
    /// The import's options (with `grid` replaced by `hull` on a link not
    /// designable).
    opts: &'a ImportOptions,
    /// Most hulls per mesh file: the link's `max_hulls` over its meshes.
    per_mesh: usize,
    memo: &'a decompose::Memo,
}

/// What one geometry element adds to its link.
struct GeometryPart {
    hulls: Vec<DesignHull>,
    /// The element's surface, placed in the link frame.
    source: TriMesh,
    /// Its enclosed volume (m³), `None` when the surface encloses none.
    volume: Option<f64>,
    notes: Vec<String>,
}

/// The hulls of link `li` of `src`: one per primitive and convex mesh, and
/// each mesh file decomposed into at most `max_hulls / (meshes on the
/// link)` hulls. With `grid` and a `designable` list, the links not on it
/// keep one hull per mesh (a fixed palm needs no blocks).
pub(super) fn link_geometry(
    src: &SourceRobot,
    li: usize,
    opts: &ImportOptions,
    memo: &decompose::Memo,
) -> Result<LinkGeometry, ImportError> {
    let t0 = Instant::now();
    let link = &src.links[li];
    let grid_opts;
    let opts = match &opts.designable {
        Some(d) if opts.decomposer == decompose::Decomposer::Grid && !d.contains(&link.name) => {
            grid_opts = ImportOptions {
                decomposer: decompose::Decomposer::Hull,
                ..opts.clone()
            };
            &grid_opts
        }
        _ => opts,
    };
    let nmesh = link
        .geometry
        .iter()
        .filter(|g| matches!(g.shape, SourceShape::Mesh { .. }))
        .count()
        .max(1);
    let per_mesh = (opts.max_hulls / nmesh).max(1);
    let mut out = LinkGeometry {
        notes: Vec::new(),
        hulls: Vec::new(),
        sources: Vec::new(),
        source_volume: Some(0.0),
        seconds: 0.0,
    };
    let cx = LinkContext {
        src,
        opts,
        per_mesh,
        memo,
    };
    for g in &link.geometry {
        let part = geometry_part(&cx, g)?;
        out.notes.extend(part.notes);
        out.hulls.extend(part.hulls);
        out.sources.push(part.source);
        out.source_volume = match (out.source_volume, part.volume) {
            (Some(a), Some(b)) => Some(a + b),
            _ => None,
        };
    }
    out.seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}

/// An error in geometry element `g` of `src`'s file.
fn geometry_error(src: &SourceRobot, g: &SourceGeometry) -> impl Fn(String) -> ImportError {
    let (path, element) = (src.file.clone(), g.element.clone());
    move |msg| ImportError::Geometry {
        path: path.clone(),
        element: element.clone(),
        msg,
    }
}

/// One geometry element: its origin checked, then its shape's hulls.
fn geometry_part(cx: &LinkContext, g: &SourceGeometry) -> Result<GeometryPart, ImportError> {
    let geom_err = geometry_error(cx.src, g);
    limits::check_coordinates(
        "origin",
        g.rotation
            .iter()
            .chain(g.translation.iter())
            .copied()
            .collect::<Vec<_>>()
            .as_slice(),
    )
    .map_err(&geom_err)?;
    let place = |v: &Vector3<f64>| g.rotation * v + g.translation;
    let prim = match &g.shape {
        SourceShape::Box { size } => primitives::box_hull(*size),
        SourceShape::Cylinder { radius, length } => primitives::cylinder_hull(*radius, *length),
        SourceShape::Sphere { radius } => primitives::sphere_hull(*radius),
        SourceShape::Capsule { radius, length } => primitives::capsule_hull(*radius, *length),
        SourceShape::Ellipsoid { radii } => primitives::ellipsoid_hull(*radii),
        SourceShape::Tiny { edge } => primitives::box_hull([*edge; 3]),
        SourceShape::ConvexMesh { mesh } => {
            let m = mesh.transformed([1.0; 3], &g.rotation, &g.translation);
            let hull = convex_hull(&m.vertices).map_err(|e| geom_err(e.to_string()))?;
            return Ok(GeometryPart {
                hulls: vec![DesignHull::new(hull)],
                volume: m.volume(),
                source: m,
                notes: Vec::new(),
            });
        }
        SourceShape::Mesh { .. } => return mesh_part(cx, g),
    };
    let prim = prim.map_err(&geom_err)?;
    let pts: Vec<_> = prim.hull.iter().map(place).collect();
    Ok(GeometryPart {
        hulls: vec![DesignHull::new(convex_hull(&pts).map_err(&geom_err)?)],
        source: prim
            .source
            .transformed([1.0; 3], &g.rotation, &g.translation),
        volume: Some(prim.volume),
        notes: Vec::new(),
    })
}

/// A mesh file: loaded, scaled and placed, checked, then decomposed into at
/// most `per_mesh` hulls (a non-manifold mesh as a surface, falling back to
/// the convex hull of its points when that fails).
fn mesh_part(cx: &LinkContext, g: &SourceGeometry) -> Result<GeometryPart, ImportError> {
    let LinkContext {
        src,
        opts,
        per_mesh,
        memo,
    } = *cx;
    let SourceShape::Mesh { path, scale } = &g.shape else {
        unreachable!("mesh_part is called for mesh files only")
    };
    let (path, scale) = (path.as_path(), *scale);
    let geom_err = geometry_error(src, g);
    if scale.iter().any(|s| *s == 0.0 || !s.is_finite()) {
        return Err(geom_err(format!(
            "mesh scale must be finite and non-zero, got {scale:?}"
        )));
    }
    let ctx = MeshContext {
        file: src.file.clone(),
        element: g.element.clone(),
    };
    let (m, note) = mesh::load_mesh(path, &ctx)?;
    let mut notes: Vec<String> = note.into_iter().collect();
    let m = m.transformed(scale, &g.rotation, &g.translation);
    limits::check_coordinates(
        &format!("mesh {} placed with scale {scale:?}", path.display()),
        m.vertices
            .iter()
            .flat_map(|v| v.iter().copied())
            .collect::<Vec<_>>()
            .as_slice(),
    )
    .map_err(&geom_err)?;
    notes.extend(units_hint(&m, &g.element, path));
    let non_manifold = m.non_manifold_edges();
    let parts = if non_manifold > 0 {
        notes.push(format!(
            "{}: mesh {} is not manifold ({non_manifold} edge(s) shared by more than two triangles); decomposed as a surface",
            g.element,
            path.display()
        ));
        match memo.decompose(&m, opts, per_mesh, &ctx) {
            Ok(p) => p,
            Err(e) if opts.decomposer != decompose::Decomposer::None => {
                notes.push(format!(
                    "{}: {e}; used the convex hull of the mesh's points instead",
                    g.element
                ));
                vec![polytope::convex_hull(&m.vertices).map_err(&geom_err)?]
            }
            Err(e) => return Err(e),
        }
    } else {
        memo.decompose(&m, opts, per_mesh, &ctx)?
    };
    Ok(GeometryPart {
        hulls: parts.into_iter().map(DesignHull::new).collect(),
        volume: m.volume(),
        source: m,
        notes,
    })
}
