//! Unsigned squared distances between mesh primitives, IPC style (Li et al.
//! 2020, §4 and supplement): a point–triangle or edge–edge pair is first
//! *classified* by where its closest points lie ([`classify_point_triangle`],
//! [`classify_edge_edge`]), and the squared distance is then the smooth
//! formula of that case — point–point, point–line, point–plane or line–line.
//! All distances are **squared** (m²), as in IPC, so they are polynomial or
//! rational in the coordinates and the barrier acts on `d = dist²`.
//!
//! A primitive pair is a *stencil* of four points: `[p, t₀, t₁, t₂]` for
//! point–triangle and `[a₀, a₁, b₀, b₁]` for edge–edge. The case is a
//! [`DistanceType`] indexing into the stencil, so value, gradient (12) and
//! Hessian (12×12) are always taken over the same 12 coordinates.

pub mod edge_edge;
pub mod point_edge;
pub mod point_point;
pub mod point_triangle;
pub mod vec;

use num_dual::DualNum;
use vec::{V3, cross, dot, norm2, sub};

/// Which smooth formula gives the squared distance of a stencil, with
/// indices of the stencil points it uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DistanceType {
    /// `‖x_i − x_j‖²`.
    PointPoint(u8, u8),
    /// Point `x_p` to the line through `x_a`, `x_b`.
    PointLine(u8, u8, u8),
    /// Point `x₀` to the plane of `x₁ x₂ x₃` (point–triangle interior).
    PointPlane,
    /// Line `x₀ x₁` to line `x₂ x₃` (edge–edge interior).
    LineLine,
}

/// Relative threshold on `‖a × b‖² / (‖a‖²‖b‖²)` below which two edges are
/// treated as parallel in the classification (the line–line formula is
/// then ill-conditioned; the closest pair is a point–edge one).
pub const PARALLEL_THRESHOLD: f64 = 1e-20;

/// The squared distance of `x` in case `ty` (m²). Generic over the scalar
/// so dual numbers give exact derivatives.
pub fn squared_distance<T: DualNum<Primitive = f64> + Copy>(x: &[V3<T>; 4], ty: DistanceType) -> T {
    match ty {
        DistanceType::PointPoint(i, j) => point_point::point_point(&x[i as usize], &x[j as usize]),
        DistanceType::PointLine(p, a, b) => {
            point_edge::point_line(&x[p as usize], &x[a as usize], &x[b as usize])
        }
        DistanceType::PointPlane => point_triangle::point_plane(&x[0], &x[1], &x[2], &x[3]),
        DistanceType::LineLine => edge_edge::line_line(&x[0], &x[1], &x[2], &x[3]),
    }
}

/// Point `x[p]` against segment `x[a] x[b]`: point–point at an endpoint,
/// point–line inside, point–point for a degenerate segment.
pub fn classify_point_edge(x: &[V3<f64>; 4], p: u8, a: u8, b: u8) -> DistanceType {
    let (pp, pa, pb) = (&x[p as usize], &x[a as usize], &x[b as usize]);
    if norm2(&sub(pb, pa)) <= 0.0 {
        return DistanceType::PointPoint(p, a);
    }
    let t = point_edge::line_parameter(pp, pa, pb);
    if t <= 0.0 {
        DistanceType::PointPoint(p, a)
    } else if t >= 1.0 {
        DistanceType::PointPoint(p, b)
    } else {
        DistanceType::PointLine(p, a, b)
    }
}

/// Classification of `[p, t₀, t₁, t₂]` by the Voronoi region of the
/// triangle that contains `p` (vertex → point–point, edge → point–line,
/// face → point–plane). A degenerate (zero-area) triangle uses its closest
/// edge.
pub fn classify_point_triangle(x: &[V3<f64>; 4]) -> DistanceType {
    let (p, a, b, c) = (&x[0], &x[1], &x[2], &x[3]);
    let ab = sub(b, a);
    let ac = sub(c, a);
    let n2 = norm2(&cross(&ab, &ac));
    if n2 <= 1e-24 * norm2(&ab) * norm2(&ac) || n2 == 0.0 {
        return closest_of(x, &[(0, 1, 2), (0, 2, 3), (0, 3, 1)]);
    }
    let ap = sub(p, a);
    let (d1, d2) = (dot(&ab, &ap), dot(&ac, &ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return DistanceType::PointPoint(0, 1);
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(&ab, &bp), dot(&ac, &bp));
    if d3 >= 0.0 && d4 <= d3 {
        return DistanceType::PointPoint(0, 2);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return DistanceType::PointLine(0, 1, 2);
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(&ab, &cp), dot(&ac, &cp));
    if d6 >= 0.0 && d5 <= d6 {
        return DistanceType::PointPoint(0, 3);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return DistanceType::PointLine(0, 1, 3);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return DistanceType::PointLine(0, 2, 3);
    }
    DistanceType::PointPlane
}

/// Classification of `[a₀, a₁, b₀, b₁]` by the closest points of the two
/// segments (parameters clamped to `[0, 1]`): both interior → line–line, one
/// at an endpoint → point–line, both at endpoints → point–point. Parallel
/// (and degenerate) edges use the closest of the four point–edge pairs.
pub fn classify_edge_edge(x: &[V3<f64>; 4]) -> DistanceType {
    let d1 = sub(&x[1], &x[0]);
    let d2 = sub(&x[3], &x[2]);
    let r = sub(&x[0], &x[2]);
    let (a, e, b) = (norm2(&d1), norm2(&d2), dot(&d1, &d2));
    // `a e − b² = ‖d₁ × d₂‖²` (Lagrange's identity), but the difference
    // loses everything to cancellation for nearly parallel edges: its
    // rounding error, ~ε·a·e, is far above the parallel threshold, so two
    // parallel edges perturbed by 1e-17 m came out "crossing" (s, t
    // interior) and, coplanar, at line–line distance 0 however far apart
    // they were. The cross product has no such cancellation (ipc-toolkit
    // tests the same quantity).
    let denom = norm2(&cross(&d1, &d2));
    if a <= 0.0 || e <= 0.0 || denom <= PARALLEL_THRESHOLD * a * e {
        return closest_of(x, &[(0, 2, 3), (1, 2, 3), (2, 0, 1), (3, 0, 1)]);
    }
    let (c, f) = (dot(&d1, &r), dot(&d2, &r));
    let mut s = ((b * f - c * e) / denom).clamp(0.0, 1.0);
    let mut t = (b * s + f) / e;
    if t <= 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t >= 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    let s_end = (s <= 0.0).then_some(0u8).or((s >= 1.0).then_some(1u8));
    let t_end = (t <= 0.0).then_some(2u8).or((t >= 1.0).then_some(3u8));
    match (s_end, t_end) {
        (Some(i), Some(j)) => DistanceType::PointPoint(i, j),
        (Some(i), None) => DistanceType::PointLine(i, 2, 3),
        (None, Some(j)) => DistanceType::PointLine(j, 0, 1),
        (None, None) => DistanceType::LineLine,
    }
}

/// The point–edge pair `(p, a, b)` of smallest distance, classified.
fn closest_of(x: &[V3<f64>; 4], cands: &[(u8, u8, u8)]) -> DistanceType {
    let mut best = (
        f64::INFINITY,
        DistanceType::PointPoint(cands[0].0, cands[0].1),
    );
    for &(p, a, b) in cands {
        let ty = classify_point_edge(x, p, a, b);
        let d = squared_distance(x, ty);
        if d < best.0 {
            best = (d, ty);
        }
    }
    best.1
}

/// Squared distance of a point–triangle stencil (m²), classified.
pub fn point_triangle_distance(x: &[V3<f64>; 4]) -> f64 {
    squared_distance(x, classify_point_triangle(x))
}

/// Squared distance of an edge–edge stencil (m²), classified.
pub fn edge_edge_distance(x: &[V3<f64>; 4]) -> f64 {
    squared_distance(x, classify_edge_edge(x))
}

/// Closest-point weights `w` of a classified stencil: `Σ_k w_k x_k` is the
/// vector from the closest point of the second primitive to that of the
/// first (for point–triangle, triangle → point; for edge–edge, edge b →
/// edge a), so its norm is the distance. Used for IPC's lagged friction.
pub fn closest_weights(x: &[V3<f64>; 4], ty: DistanceType) -> [f64; 4] {
    let mut w = [0.0; 4];
    match ty {
        DistanceType::PointPoint(i, j) => {
            w[i as usize] = 1.0;
            w[j as usize] = -1.0;
        }
        DistanceType::PointLine(p, a, b) => {
            let t = point_edge::line_parameter(&x[p as usize], &x[a as usize], &x[b as usize]);
            w[p as usize] = 1.0;
            w[a as usize] = -(1.0 - t);
            w[b as usize] = -t;
        }
        DistanceType::PointPlane => {
            let (v0, v1, v2) = (sub(&x[2], &x[1]), sub(&x[3], &x[1]), sub(&x[0], &x[1]));
            let (d00, d01, d11) = (dot(&v0, &v0), dot(&v0, &v1), dot(&v1, &v1));
            let (d20, d21) = (dot(&v2, &v0), dot(&v2, &v1));
            let den = d00 * d11 - d01 * d01;
            let b1 = (d11 * d20 - d01 * d21) / den;
            let b2 = (d00 * d21 - d01 * d20) / den;
            w = [1.0, -(1.0 - b1 - b2), -b1, -b2];
        }
        DistanceType::LineLine => {
            let (d1, d2, r) = (sub(&x[1], &x[0]), sub(&x[3], &x[2]), sub(&x[0], &x[2]));
            let (a, e, b) = (norm2(&d1), norm2(&d2), dot(&d1, &d2));
            let (c, f) = (dot(&d1, &r), dot(&d2, &r));
            let den = a * e - b * b;
            let s = (b * f - c * e) / den;
            let t = (a * f - b * c) / den;
            w = [1.0 - s, s, -(1.0 - t), -t];
        }
    }
    w
}
