//! Convex polytopes in both representations: the vertices (V) that the design
//! space uses, and triangles plus outward unit face planes (H) for point
//! queries, volumes and the connectivity solver. Hulls are computed with
//! parry3d's quickhull.

use nalgebra::Vector3;

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

/// Incremental 3-D convex hull. Points within `eps` of the current hull
/// (coplanar with a face, or inside) are not added, so every returned
/// triangle is a supporting plane to within `eps` and the surface is closed
/// and consistently oriented even for the many coplanar points of voxel
/// hulls (parry's quickhull can return overlapping triangles there).
fn hull3d_indexed(pts: &[Vector3<f64>], eps: f64) -> Result<Vec<[usize; 3]>, String> {
    struct Face {
        v: [usize; 3],
        n: Vector3<f64>,
        b: f64,
        alive: bool,
    }
    let make = |v: [usize; 3]| -> Face {
        let n = (pts[v[1]] - pts[v[0]]).cross(&(pts[v[2]] - pts[v[0]]));
        let n = n / n.norm().max(f64::MIN_POSITIVE);
        Face {
            v,
            n,
            b: n.dot(&pts[v[0]]),
            alive: true,
        }
    };
    // Initial tetrahedron from extreme points.
    let i0 = (0..pts.len())
        .min_by(|&a, &b| pts[a].x.total_cmp(&pts[b].x))
        .unwrap();
    let i1 = (0..pts.len())
        .max_by(|&a, &b| {
            (pts[a] - pts[i0])
                .norm()
                .total_cmp(&(pts[b] - pts[i0]).norm())
        })
        .unwrap();
    let d01 = (pts[i1] - pts[i0]).normalize();
    let line = |k: usize| {
        let w = pts[k] - pts[i0];
        (w - d01 * d01.dot(&w)).norm()
    };
    let i2 = (0..pts.len())
        .max_by(|&a, &b| line(a).total_cmp(&line(b)))
        .unwrap();
    if line(i2) <= eps {
        return Err("the points are collinear".into());
    }
    let nrm = (pts[i1] - pts[i0]).cross(&(pts[i2] - pts[i0])).normalize();
    let off = |k: usize| nrm.dot(&(pts[k] - pts[i0]));
    let i3 = (0..pts.len())
        .max_by(|&a, &b| off(a).abs().total_cmp(&off(b).abs()))
        .unwrap();
    if off(i3).abs() <= eps {
        return Err("the points are coplanar: the hull encloses no volume".into());
    }
    let centre = (pts[i0] + pts[i1] + pts[i2] + pts[i3]) / 4.0;
    let mut faces: Vec<Face> = Vec::new();
    let mut edge: std::collections::HashMap<(usize, usize), usize> =
        std::collections::HashMap::new();
    let add = |faces: &mut Vec<Face>,
               edge: &mut std::collections::HashMap<(usize, usize), usize>,
               mut v: [usize; 3]| {
        let mut f = make(v);
        if f.n.dot(&centre) > f.b {
            v.swap(1, 2);
            f = make(v);
        }
        for k in 0..3 {
            edge.insert((v[k], v[(k + 1) % 3]), faces.len());
        }
        faces.push(f);
    };
    for v in [[i0, i1, i2], [i0, i1, i3], [i0, i2, i3], [i1, i2, i3]] {
        add(&mut faces, &mut edge, v);
    }
    let initial = [i0, i1, i2, i3];
    for (p, &x) in pts.iter().enumerate() {
        if initial.contains(&p) {
            continue;
        }
        // The visible region is grown from the face that sees `x` best,
        // through shared edges only: a connected region has a single
        // horizon loop even when round-off makes a far face's visibility
        // test disagree with its neighbours' (which would otherwise open
        // the surface).
        let Some(seed) = (0..faces.len())
            .filter(|&f| faces[f].alive)
            .map(|f| (f, faces[f].n.dot(&x) - faces[f].b))
            .filter(|&(_, d)| d > eps)
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(f, _)| f)
        else {
            continue;
        };
        let mut in_region = std::collections::HashSet::from([seed]);
        let mut visible = vec![seed];
        let mut k_next = 0;
        while k_next < visible.len() {
            let v = faces[visible[k_next]].v;
            k_next += 1;
            for k in 0..3 {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                let Some(&o) = edge.get(&(b, a)) else {
                    return Err("convex hull failed: open surface".into());
                };
                if faces[o].alive
                    && !in_region.contains(&o)
                    && faces[o].n.dot(&x) - faces[o].b > eps
                {
                    in_region.insert(o);
                    visible.push(o);
                }
            }
        }
        let mut horizon = Vec::new();
        for &f in &visible {
            let v = faces[f].v;
            for k in 0..3 {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                if !in_region.contains(&edge[&(b, a)]) {
                    horizon.push((a, b));
                }
            }
        }
        for &f in &visible {
            faces[f].alive = false;
            let v = faces[f].v;
            for k in 0..3 {
                edge.remove(&(v[k], v[(k + 1) % 3]));
            }
        }
        for (a, b) in horizon {
            let f = make([a, b, p]);
            for (u, w) in [(a, b), (b, p), (p, a)] {
                edge.insert((u, w), faces.len());
            }
            faces.push(f);
        }
    }
    Ok(faces.iter().filter(|f| f.alive).map(|f| f.v).collect())
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

    /// Euclidean distance from `p` to the polytope (0 inside).
    pub fn distance(&self, p: &Vector3<f64>) -> f64 {
        if self.violation(p) <= 0.0 {
            return 0.0;
        }
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

/// Signed volume of a closed, consistently oriented triangle mesh.
pub fn mesh_volume(v: &[Vector3<f64>], tris: &[[usize; 3]]) -> f64 {
    tris.iter()
        .map(|t| v[t[0]].dot(&v[t[1]].cross(&v[t[2]])))
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
