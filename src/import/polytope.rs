//! Convex polytopes in both representations: the vertices (V) that the design
//! space uses, and triangles plus outward unit face planes (H) for point
//! queries, volumes and the connectivity solver. Hulls are computed with
//! parry3d's quickhull.

use nalgebra::Vector3;
use parry3d_f64::math::Vector as PVec;

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

/// Convex hull of a point set, or why there is none.
pub fn convex_hull(points: &[Vector3<f64>]) -> Result<Polytope, String> {
    if points.len() < 4 {
        return Err(format!("a hull needs at least 4 points, got {}", points.len()));
    }
    if points.iter().any(|p| !p.iter().all(|v| v.is_finite())) {
        return Err("non-finite coordinates".into());
    }
    let lo = points.iter().fold(Vector3::repeat(f64::INFINITY), |a, p| a.inf(p));
    let hi = points
        .iter()
        .fold(Vector3::repeat(f64::NEG_INFINITY), |a, p| a.sup(p));
    let diag = (hi - lo).norm();
    if !(diag > 0.0) {
        return Err("all points coincide".into());
    }
    let pts: Vec<PVec> = points.iter().map(|p| PVec::new(p.x, p.y, p.z)).collect();
    let (verts, tris) = parry3d_f64::transformation::try_convex_hull(&pts)
        .map_err(|e| format!("convex hull failed: {e:?}"))?;
    // Compact: keep only vertices used by triangles.
    let mut map = vec![usize::MAX; verts.len()];
    let mut vertices = Vec::new();
    let mut triangles = Vec::with_capacity(tris.len());
    for t in &tris {
        let mut out = [0usize; 3];
        for (k, &i) in t.iter().enumerate() {
            let i = i as usize;
            if map[i] == usize::MAX {
                map[i] = vertices.len();
                let v = verts[i];
                vertices.push(Vector3::new(v.x, v.y, v.z));
            }
            out[k] = map[i];
        }
        triangles.push(out);
    }
    let mut poly = Polytope {
        vertices,
        triangles,
        planes: Vec::new(),
    };
    if poly.triangles.len() < 4 || poly.vertices.len() < 4 {
        return Err("the points are coplanar: the hull encloses no volume".into());
    }
    let vol = poly.volume();
    if !(vol > 1e-12 * diag.powi(3)) {
        return Err(format!(
            "the points are (nearly) coplanar: hull volume {vol:.3e} for extent {diag:.3e}"
        ));
    }
    poly.planes = planes_of(&poly.vertices, &poly.triangles, diag);
    Ok(poly)
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
        let b = t.iter().map(|&i| n.dot(&v[i])).fold(f64::NEG_INFINITY, f64::max);
        if planes
            .iter()
            .any(|(m, c)| (m - n).norm() < 1e-12 && (c - b).abs() < 1e-12 * diag)
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
    let lo = v.iter().fold(Vector3::repeat(f64::INFINITY), |a, p| a.inf(p));
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
