//! Convex polytopes in both representations: the vertices (V) that the design
//! space uses, and triangles plus outward unit face planes (H) for point
//! queries, volumes and the connectivity solver. Hulls are computed by an
//! incremental construction with exact orientation predicates.

// Comparisons are written `!(x > 0.0)` on purpose: they reject NaN too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::Vector3;
use std::collections::{HashMap, HashSet};

/// A convex polytope.
#[derive(Clone, Debug)]
pub struct Polytope {
    /// Extreme points (the hull's vertices).
    pub vertices: Vec<Vector3<f64>>,
    /// Boundary triangles (indices into `vertices`), counter-clockwise seen
    /// from outside.
    pub triangles: Vec<[usize; 3]>,
    /// Face planes `n·x ≤ b` with unit outward `n`, one per distinct plane.
    pub planes: Vec<(Vector3<f64>, f64)>,
}

/// Boundary triangles of the convex hull of `points` as indices into
/// `points` (counter-clockwise seen from outside); points inside or within
/// `1e-12 ×` the bounding-box diagonal of the hull's surface are in no
/// triangle. Same construction and checks as [`convex_hull`].
pub fn hull_triangles(points: &[Vector3<f64>]) -> Result<Vec<[usize; 3]>, String> {
    let diag = convex_hull(points)?.diagonal();
    hull3d_indexed(points, 1e-12 * diag)
}

/// Convex hull of a point set, or why there is none.
pub fn convex_hull(points: &[Vector3<f64>]) -> Result<Polytope, String> {
    if points.len() < 4 {
        return Err(format!(
            "a hull needs at least 4 points, got {}",
            points.len()
        ));
    }
    if points.iter().any(|p| !p.iter().all(|v| v.is_finite())) {
        return Err("non-finite coordinates".into());
    }
    let lo = points
        .iter()
        .fold(Vector3::repeat(f64::INFINITY), |a, p| a.inf(p));
    let hi = points
        .iter()
        .fold(Vector3::repeat(f64::NEG_INFINITY), |a, p| a.sup(p));
    let diag = (hi - lo).norm();
    if !(diag > 0.0) {
        return Err("all points coincide".into());
    }
    let (vertices, triangles) = hull3d(points, 1e-12 * diag)?;
    let planes = planes_of(&vertices, &triangles, diag);
    let poly = Polytope {
        vertices,
        triangles,
        planes,
    };
    let vol = poly.volume();
    if !(vol > 1e-12 * diag.powi(3)) {
        return Err(format!(
            "the points are (nearly) coplanar: hull volume {vol:.3e} for extent {diag:.3e}"
        ));
    }
    Ok(poly)
}

/// Exact orientation of `x` against the plane of the triangle `a b c`
/// (counter-clockwise seen from outside): `> 0` strictly outside, `0` on the
/// plane, `< 0` inside. The sign is exact for every finite input (Shewchuk's
/// adaptive predicate); the magnitude is `((b − a) × (c − a))·(x − a)` to
/// within round-off, i.e. twice the triangle's area times the signed
/// distance of `x` from its plane.
fn orient(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>, x: &Vector3<f64>) -> f64 {
    let p = |v: &Vector3<f64>| robust::Coord3D {
        x: v.x,
        y: v.y,
        z: v.z,
    };
    // Shewchuk's orient3d is positive when `x` lies below the plane seen
    // with `a b c` counter-clockwise from above: the opposite sign.
    -robust::orient3d(p(a), p(b), p(c), p(x))
}

/// One triangle of the hull under construction.
struct Face {
    v: [usize; 3],
    /// `|(b − a) × (c − a)|`: turns [`orient`] into a distance.
    area2: f64,
    alive: bool,
}

/// Incremental (beneath–beyond) 3-D convex hull with exact predicates.
///
/// A point is added when it lies strictly outside some face by the exact
/// [`orient`] test *and* its distance from that face's plane exceeds `eps`;
/// points within `eps` of the current hull are left out (so the many
/// coplanar points of voxel hulls make no slivers). Because visibility is
/// decided exactly, the triangles always bound the exact convex hull of the
/// points added so far: the faces a new point sees form one connected region
/// with a single horizon loop, and the surface stays closed and consistently
/// oriented whatever the round-off in the coordinates.
///
/// Why exact: the earlier version decided visibility with floating planes
/// `n·x − b > eps` whose unit normals come from nearly degenerate triangles;
/// on dense CAD meshes those tests disagree between neighbouring faces, the
/// hull drifts slightly non-convex, a later point then sees a region whose
/// horizon touches itself, the directed-edge map loses a twin and the
/// construction stopped with "open surface" on watertight meshes.
fn hull3d_indexed(pts: &[Vector3<f64>], eps: f64) -> Result<Vec<[usize; 3]>, String> {
    let init = initial_simplex(pts, eps)?;
    let mut hull = Incremental {
        pts,
        faces: Vec::new(),
        edge: HashMap::new(),
    };
    let [i0, i1, i2, i3] = init;
    // The tetrahedron, each face oriented so that the opposite corner lies
    // strictly inside (the same faces, in the same order, as the earlier
    // floating-point version: inputs it handled get the same triangles).
    for (v, opposite) in [
        ([i0, i1, i2], i3),
        ([i0, i1, i3], i2),
        ([i0, i2, i3], i1),
        ([i1, i2, i3], i0),
    ] {
        let [a, b, c] = v;
        if orient(&pts[a], &pts[b], &pts[c], &pts[opposite]) > 0.0 {
            hull.push([a, c, b]);
        } else {
            hull.push(v);
        }
    }
    // Points in input order: coplanar facets (boxes, voxel hulls) are
    // triangulated as before, which downstream meshes (the IPC baseline's
    // contact surfaces) depend on.
    for p in (0..pts.len()).filter(|k| !init.contains(k)) {
        hull.insert(p, eps)?;
    }
    Ok(hull.faces.iter().filter(|f| f.alive).map(|f| f.v).collect())
}

/// Four points spanning the largest tetrahedron found greedily: the point of
/// least `x`, the point farthest from it, the point farthest from their line
/// and the point farthest from their plane. Fails with a plain reason on
/// (nearly, within `eps`) collinear or coplanar input.
fn initial_simplex(pts: &[Vector3<f64>], eps: f64) -> Result<[usize; 4], String> {
    // Ties: the first point of least `x`, the last of the farthest (the
    // earlier version's choices, kept so that its triangles are kept).
    let argmax = |f: &dyn Fn(usize) -> f64| {
        (0..pts.len())
            .max_by(|&a, &b| f(a).total_cmp(&f(b)))
            .unwrap_or(0)
    };
    let i0 = (0..pts.len())
        .min_by(|&a, &b| pts[a].x.total_cmp(&pts[b].x))
        .unwrap_or(0);
    let i1 = argmax(&|k| (pts[k] - pts[i0]).norm());
    let d01 = (pts[i1] - pts[i0]).normalize();
    let line = |k: usize| {
        let w = pts[k] - pts[i0];
        (w - d01 * d01.dot(&w)).norm()
    };
    let i2 = argmax(&line);
    if !(line(i2) > eps) {
        return Err("the points are collinear".into());
    }
    let nrm = (pts[i1] - pts[i0]).cross(&(pts[i2] - pts[i0])).normalize();
    let off = |k: usize| nrm.dot(&(pts[k] - pts[i0])).abs();
    let i3 = argmax(&off);
    if !(off(i3) > eps) || orient(&pts[i0], &pts[i1], &pts[i2], &pts[i3]) == 0.0 {
        return Err("the points are coplanar: the hull encloses no volume".into());
    }
    Ok([i0, i1, i2, i3])
}

/// The hull under construction: triangles and the directed-edge map
/// `(a, b) → face` (each edge is stored once per direction; the twin
/// `(b, a)` belongs to the neighbouring face).
struct Incremental<'a> {
    pts: &'a [Vector3<f64>],
    faces: Vec<Face>,
    edge: HashMap<(usize, usize), usize>,
}

impl Incremental<'_> {
    fn push(&mut self, v: [usize; 3]) {
        let p = self.pts;
        let area2 = (p[v[1]] - p[v[0]]).cross(&(p[v[2]] - p[v[0]])).norm();
        for k in 0..3 {
            self.edge.insert((v[k], v[(k + 1) % 3]), self.faces.len());
        }
        self.faces.push(Face {
            v,
            area2,
            alive: true,
        });
    }

    /// Exact orientation of point `x` against face `f`.
    fn side(&self, f: usize, x: usize) -> f64 {
        let [a, b, c] = self.faces[f].v;
        let p = self.pts;
        orient(&p[a], &p[b], &p[c], &p[x])
    }

    /// Adds point `x` if it lies farther than `eps` outside the hull.
    fn insert(&mut self, x: usize, eps: f64) -> Result<(), String> {
        // The face that sees `x` farthest (exactly visible ones only).
        let mut seed = None;
        let mut best = eps;
        for f in 0..self.faces.len() {
            if !self.faces[f].alive {
                continue;
            }
            let s = self.side(f, x);
            if s > 0.0 {
                let d = s / self.faces[f].area2.max(f64::MIN_POSITIVE);
                if d > best {
                    best = d;
                    seed = Some(f);
                }
            }
        }
        let Some(seed) = seed else { return Ok(()) };
        // Visible region: exactly visible faces connected to the seed.
        let mut in_region = HashSet::from([seed]);
        let mut visible = vec![seed];
        let mut k_next = 0;
        while k_next < visible.len() {
            let v = self.faces[visible[k_next]].v;
            k_next += 1;
            for k in 0..3 {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                let Some(&o) = self.edge.get(&(b, a)) else {
                    return Err(format!(
                        "convex hull: internal error, edge ({a}, {b}) has no twin"
                    ));
                };
                if !in_region.contains(&o) && self.side(o, x) > 0.0 {
                    in_region.insert(o);
                    visible.push(o);
                }
            }
        }
        let mut horizon = Vec::new();
        for &f in &visible {
            let v = self.faces[f].v;
            for k in 0..3 {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                if !in_region.contains(&self.edge[&(b, a)]) {
                    horizon.push((a, b));
                }
            }
        }
        let mut starts: Vec<usize> = horizon.iter().map(|e| e.0).collect();
        starts.sort_unstable();
        if starts.windows(2).any(|w| w[0] == w[1]) {
            return Err("convex hull: internal error, the horizon is not a simple loop".into());
        }
        for &f in &visible {
            self.faces[f].alive = false;
            let v = self.faces[f].v;
            for k in 0..3 {
                self.edge.remove(&(v[k], v[(k + 1) % 3]));
            }
        }
        for (a, b) in horizon {
            self.push([a, b, x]);
        }
        Ok(())
    }
}

/// [`hull3d_indexed`] with the used points gathered into a vertex list.
#[allow(clippy::type_complexity)]
fn hull3d(pts: &[Vector3<f64>], eps: f64) -> Result<(Vec<Vector3<f64>>, Vec<[usize; 3]>), String> {
    let faces = hull3d_indexed(pts, eps)?;
    let mut map = vec![usize::MAX; pts.len()];
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for f in faces {
        triangles.push(f.map(|i| {
            if map[i] == usize::MAX {
                map[i] = vertices.len();
                vertices.push(pts[i]);
            }
            map[i]
        }));
    }
    Ok((vertices, triangles))
}

/// Unit outward planes of the triangles, merging (nearly) identical planes.
fn planes_of(v: &[Vector3<f64>], tris: &[[usize; 3]], diag: f64) -> Vec<(Vector3<f64>, f64)> {
    let mut planes: Vec<(Vector3<f64>, f64)> = Vec::new();
    for t in tris {
        let n = (v[t[1]] - v[t[0]]).cross(&(v[t[2]] - v[t[0]]));
        let len = n.norm();
        if !(len > 1e-14 * diag * diag) {
            continue; // sliver triangle: its plane is set by its neighbours
        }
        let n = n / len;
        // Offset from the farthest of the three corners: robust for slivers.
        let b = t
            .iter()
            .map(|&i| n.dot(&v[i]))
            .fold(f64::NEG_INFINITY, f64::max);
        if planes
            .iter()
            .any(|(m, c)| (m - n).norm() < 1e-9 && (c - b).abs() < 1e-9 * diag)
        {
            continue;
        }
        planes.push((n, b));
    }
    // Every vertex must satisfy every plane: lift offsets over round-off.
    for (n, b) in planes.iter_mut() {
        let m = v.iter().map(|x| n.dot(x)).fold(f64::NEG_INFINITY, f64::max);
        if m > *b {
            *b = m;
        }
    }
    planes
}

impl Polytope {
    /// Enclosed volume (divergence theorem over the triangles).
    pub fn volume(&self) -> f64 {
        mesh_volume(&self.vertices, &self.triangles)
    }

    /// Bounding-box diagonal.
    pub fn diagonal(&self) -> f64 {
        let (lo, hi) = bounds(&self.vertices);
        (hi - lo).norm()
    }

    /// `max_i (n_i·p − b_i)`: ≤ 0 inside (minus the distance to the
    /// boundary), > 0 outside (a lower bound on the distance).
    pub fn violation(&self, p: &Vector3<f64>) -> f64 {
        self.planes
            .iter()
            .map(|(n, b)| n.dot(p) - b)
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Whether `p` is inside or on the boundary: `violation(p) ≤ 0`
    /// exactly (the same plane values; it stops at the first plane that `p`
    /// is outside of).
    pub fn contains(&self, p: &Vector3<f64>) -> bool {
        !self.planes.iter().any(|(n, b)| n.dot(p) - b > 0.0)
    }

    /// Euclidean distance from `p` to the polytope (0 inside).
    pub fn distance(&self, p: &Vector3<f64>) -> f64 {
        if self.contains(p) {
            return 0.0;
        }
        self.boundary_distance(p)
    }

    /// Distance from `p` to the boundary triangles (the distance to the
    /// polytope for a point outside it, as [`Polytope::distance`] uses it).
    pub fn boundary_distance(&self, p: &Vector3<f64>) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                point_triangle_distance(
                    p,
                    &self.vertices[t[0]],
                    &self.vertices[t[1]],
                    &self.vertices[t[2]],
                )
            })
            .fold(f64::INFINITY, f64::min)
    }
}

/// Signed volume of a closed, consistently oriented triangle mesh:
/// `V = Σ (a − o)·((b − o) × (c − o))/6` over its triangles `abc`, with
/// `o` the first triangle's first corner. Any `o` gives the same volume in
/// exact arithmetic; one on the mesh keeps the terms of the size of the
/// mesh, not of its distance from the origin (about the origin, a unit
/// sphere 1e6 m away summed terms of 1e18 to a volume off by 1e3).
pub fn mesh_volume(v: &[Vector3<f64>], tris: &[[usize; 3]]) -> f64 {
    let Some(o) = tris.first().map(|t| v[t[0]]) else {
        return 0.0;
    };
    tris.iter()
        .map(|t| (v[t[0]] - o).dot(&(v[t[1]] - o).cross(&(v[t[2]] - o))))
        .sum::<f64>()
        / 6.0
}

/// Axis-aligned bounds of a point set.
pub fn bounds(v: &[Vector3<f64>]) -> (Vector3<f64>, Vector3<f64>) {
    let lo = v
        .iter()
        .fold(Vector3::repeat(f64::INFINITY), |a, p| a.inf(p));
    let hi = v
        .iter()
        .fold(Vector3::repeat(f64::NEG_INFINITY), |a, p| a.sup(p));
    (lo, hi)
}

/// Distance from `p` to the triangle `abc` (Ericson, Real-Time Collision
/// Detection, §5.1.5, closest point by Voronoi regions).
pub fn point_triangle_distance(
    p: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
) -> f64 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.norm();
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return bp.norm();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).norm();
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return cp.norm();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).norm();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).norm();
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (p - (a + ab * v + ac * w)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Vec<Vector3<f64>> {
        crate::model::Hull::cuboid(Vector3::new(2.0, 2.0, 2.0), Vector3::zeros())
    }

    #[test]
    fn cube_hull_volume_planes_and_distances() {
        let mut pts = cube();
        pts.push(Vector3::new(0.1, 0.2, 0.3)); // interior point is dropped
        let p = convex_hull(&pts).unwrap();
        assert_eq!(p.vertices.len(), 8);
        assert!((p.volume() - 8.0).abs() < 1e-12);
        assert_eq!(p.planes.len(), 6);
        assert!((p.violation(&Vector3::zeros()) + 1.0).abs() < 1e-12);
        assert!((p.distance(&Vector3::new(3.0, 0.0, 0.0)) - 2.0).abs() < 1e-12);
        assert!((p.distance(&Vector3::new(2.0, 2.0, 1.0)) - 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(p.distance(&Vector3::new(0.5, 0.5, 0.5)), 0.0);
    }

    #[test]
    fn coplanar_points_have_no_hull() {
        let pts = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
        ];
        assert!(convex_hull(&pts).is_err());
    }
}
