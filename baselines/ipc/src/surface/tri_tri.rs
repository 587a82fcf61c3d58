//! Exact-sign triangle–triangle intersection of closed triangles (touching
//! counts), for the self-intersection and start checks.
//!
//! With `orient(a, b, c, d) = (b − a) · ((c − a) × (d − a))` (six times the
//! signed volume of the tetrahedron):
//!
//! - two triangles in different planes meet iff an edge of one meets the
//!   other (their intersection is a segment whose ends lie on edges);
//! - segment `pq` meets triangle `abc` (not coplanar) iff `p` and `q` are not
//!   strictly on one side of the plane (`orient(a,b,c,p) · orient(a,b,c,q) ≤ 0`)
//!   and the line `pq` passes inside the triangle: `orient(p,q,a,b)`,
//!   `orient(p,q,b,c)`, `orient(p,q,c,a)` share a sign (zeros allowed);
//! - coplanar cases (all four orientations zero) are decided in the plane:
//!   projected onto the two coordinates the normal's largest component
//!   leaves, by edge crossings and point-in-triangle tests.

use nalgebra::Vector3;

type V = Vector3<f64>;

/// `(b − a) · ((c − a) × (d − a))`.
pub fn orient(a: &V, b: &V, c: &V, d: &V) -> f64 {
    (b - a).dot(&(c - a).cross(&(d - a)))
}

/// The two coordinates kept when projecting along `n`'s largest component.
fn axes(n: &V) -> (usize, usize) {
    let a = n.abs();
    if a.x >= a.y && a.x >= a.z {
        (1, 2)
    } else if a.y >= a.z {
        (2, 0)
    } else {
        (0, 1)
    }
}

fn cross2(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

fn on_segment2(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> bool {
    (0..2).all(|k| p[k] >= a[k].min(b[k]) && p[k] <= a[k].max(b[k]))
}

/// Closed segments `ab`, `cd` in the plane meet.
fn segments2(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (d1, d2) = (cross2(c, d, a), cross2(c, d, b));
    let (d3, d4) = (cross2(a, b, c), cross2(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on_segment2(a, c, d))
        || (d2 == 0.0 && on_segment2(b, c, d))
        || (d3 == 0.0 && on_segment2(c, a, b))
        || (d4 == 0.0 && on_segment2(d, a, b))
}

/// `p` in the closed triangle `t` (plane).
fn inside2(p: [f64; 2], t: &[[f64; 2]; 3]) -> bool {
    let s = [
        cross2(t[0], t[1], p),
        cross2(t[1], t[2], p),
        cross2(t[2], t[0], p),
    ];
    s.iter().all(|&x| x >= 0.0) || s.iter().all(|&x| x <= 0.0)
}

fn project(p: &V, (i, j): (usize, usize)) -> [f64; 2] {
    [p[i], p[j]]
}

/// Segment `pq` and triangle `t` in `t`'s plane meet.
fn segment_triangle_planar(p: &V, q: &V, t: &[V; 3]) -> bool {
    let ax = axes(&(t[1] - t[0]).cross(&(t[2] - t[0])));
    let (p2, q2) = (project(p, ax), project(q, ax));
    let t2 = t.map(|x| project(&x, ax));
    inside2(p2, &t2)
        || inside2(q2, &t2)
        || (0..3).any(|k| segments2(p2, q2, t2[k], t2[(k + 1) % 3]))
}

/// Closed segment `pq` meets closed triangle `t`.
pub fn segment_triangle(p: &V, q: &V, t: &[V; 3]) -> bool {
    let (dp, dq) = (
        orient(&t[0], &t[1], &t[2], p),
        orient(&t[0], &t[1], &t[2], q),
    );
    if dp == 0.0 && dq == 0.0 {
        return segment_triangle_planar(p, q, t);
    }
    if (dp > 0.0 && dq > 0.0) || (dp < 0.0 && dq < 0.0) {
        return false;
    }
    let s = [
        orient(p, q, &t[0], &t[1]),
        orient(p, q, &t[1], &t[2]),
        orient(p, q, &t[2], &t[0]),
    ];
    s.iter().all(|&x| x >= 0.0) || s.iter().all(|&x| x <= 0.0)
}

/// Closed triangles `a` and `b` meet.
pub fn triangles_intersect(a: &[V; 3], b: &[V; 3]) -> bool {
    let o = b.map(|x| orient(&a[0], &a[1], &a[2], &x));
    if o.iter().all(|&x| x > 0.0) || o.iter().all(|&x| x < 0.0) {
        return false;
    }
    if o.iter().all(|&x| x == 0.0) {
        let ax = axes(&(a[1] - a[0]).cross(&(a[2] - a[0])));
        let (a2, b2) = (a.map(|x| project(&x, ax)), b.map(|x| project(&x, ax)));
        return (0..3)
            .any(|i| (0..3).any(|j| segments2(a2[i], a2[(i + 1) % 3], b2[j], b2[(j + 1) % 3])))
            || inside2(a2[0], &b2)
            || inside2(b2[0], &a2);
    }
    (0..3).any(|k| segment_triangle(&a[k], &a[(k + 1) % 3], b))
        || (0..3).any(|k| segment_triangle(&b[k], &b[(k + 1) % 3], a))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> V {
        V::new(x, y, z)
    }

    #[test]
    fn crossing_touching_apart_and_coplanar() {
        let a = [v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.)];
        // Pierces a's interior.
        assert!(triangles_intersect(
            &a,
            &[v(0.2, 0.2, -1.), v(0.3, 0.2, 1.), v(0.2, 0.3, 1.)]
        ));
        // Above a.
        assert!(!triangles_intersect(
            &a,
            &[v(0.2, 0.2, 0.1), v(0.3, 0.2, 1.), v(0.2, 0.3, 1.)]
        ));
        // Touches a's interior with a vertex.
        assert!(triangles_intersect(
            &a,
            &[v(0.2, 0.2, 0.), v(0.3, 0.2, 1.), v(0.2, 0.3, 1.)]
        ));
        // Crosses the plane beside a.
        assert!(!triangles_intersect(
            &a,
            &[v(2., 2., -1.), v(3., 2., 1.), v(2., 3., 1.)]
        ));
        // Coplanar: overlapping, and apart.
        assert!(triangles_intersect(
            &a,
            &[v(0.1, 0.1, 0.), v(2., 0.1, 0.), v(0.1, 2., 0.)]
        ));
        assert!(!triangles_intersect(
            &a,
            &[v(1., 1., 0.), v(2., 1., 0.), v(1., 2., 0.)]
        ));
        // Coplanar, one inside the other (no edge crossings).
        assert!(triangles_intersect(
            &a,
            &[v(0.1, 0.1, 0.), v(0.2, 0.1, 0.), v(0.1, 0.2, 0.)]
        ));
    }
}
