//! Exact separation test between two vertex clouds (their convex hulls) with parry's GJK.
//!
//! parry3d-f64 0.31 speaks glam (`DVec3`) at its API; this module is the only place that
//! converts. The hulls are given as world-space vertex slices and wrapped in [`PointCloud`],
//! which implements parry's [`SupportMap`] by a linear scan (`argmax_m d·X_m`). That avoids
//! building a `ConvexPolyhedron` (a convex-hull computation) on every call; the benchmark
//! `examples/bench_contact.rs` measures both.
//!
//! GJK's closest points are only approximate (parry stops at a relative gap of about
//! `√(10 ε_mach) ≈ 5e-8`). The result is therefore turned into an *exact certificate*: for the
//! unit direction `d = (x_b − x_a)/‖x_b − x_a‖` we compute
//!
//! ```text
//! gap(d) = min_m d·X_b^m − max_m d·X_a^m
//! ```
//!
//! directly from the vertices. `gap(d) > 0` proves the hulls are disjoint (the slab between the
//! two support planes separates them) and `gap(d) ≤ dist(a, b)` always holds, with equality for
//! the exact closest-point direction. Pairs whose gap is not positive are reported as
//! intersecting: this includes touching pairs and pairs closer than GJK's tolerance, where the
//! barrier energy would be astronomically large anyway.

use nalgebra::Vector3;
use parry3d_f64::math::{Pose as PPose, Vector as PVec};
use parry3d_f64::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use parry3d_f64::shape::SupportMap;

use super::error::ContactError;

/// A borrowed vertex cloud whose support map is that of its convex hull.
pub struct PointCloud<'a>(pub &'a [Vector3<f64>]);

#[inline]
fn to_p(v: &Vector3<f64>) -> PVec {
    PVec::new(v.x, v.y, v.z)
}

#[inline]
fn from_p(v: PVec) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

impl SupportMap for PointCloud<'_> {
    fn local_support_point(&self, dir: PVec) -> PVec {
        let d = from_p(dir);
        let mut best = 0usize;
        let mut best_dot = f64::NEG_INFINITY;
        for (i, x) in self.0.iter().enumerate() {
            let v = x.dot(&d);
            if v > best_dot {
                best_dot = v;
                best = i;
            }
        }
        to_p(&self.0[best])
    }
}

/// Outcome of the separation test.
#[derive(Clone, Copy, Debug)]
pub enum Separation {
    /// Overlapping, touching, or closer than GJK can resolve.
    Intersecting,
    /// Certified disjoint.
    Separated {
        /// Unit direction from hull `a` towards hull `b`.
        dir: Vector3<f64>,
        /// `max_m dir·X_a^m` (support of `a` along `dir`).
        max_a: f64,
        /// `min_m dir·X_b^m` (support of `b` along `−dir`).
        min_b: f64,
        /// GJK's distance estimate `‖x_b − x_a‖` (≥ `min_b − max_a`).
        distance: f64,
    },
}

/// `(max_m d·X_a^m, min_m d·X_b^m)`.
#[inline]
pub fn supports_along(xa: &[Vector3<f64>], xb: &[Vector3<f64>], d: &Vector3<f64>) -> (f64, f64) {
    let max_a = xa
        .iter()
        .map(|x| x.dot(d))
        .fold(f64::NEG_INFINITY, f64::max);
    let min_b = xb.iter().map(|x| x.dot(d)).fold(f64::INFINITY, f64::min);
    (max_a, min_b)
}

fn centroid(x: &[Vector3<f64>]) -> Vector3<f64> {
    x.iter().sum::<Vector3<f64>>() / x.len() as f64
}

/// Tests the convex hulls of `xa` and `xb` (world coordinates, both non-empty) for separation.
///
/// `hint` is an optional initial search direction from `a` towards `b` (e.g. the normal of a
/// previous separating plane). `simplex` is reused storage.
pub fn separate(
    xa: &[Vector3<f64>],
    xb: &[Vector3<f64>],
    hint: Option<Vector3<f64>>,
    simplex: &mut VoronoiSimplex,
) -> Result<Separation, ContactError> {
    let ga = PointCloud(xa);
    let gb = PointCloud(xb);
    let ca = centroid(xa);
    let cb = centroid(xb);
    let fallback = cb - ca;
    // GJK projects the origin onto the CSO a − b; a search direction towards it from the CSO is
    // along a − b, i.e. opposite to the a→b direction.
    let ab = hint
        .filter(|h| h.norm_squared() > 0.0 && h.iter().all(|v| v.is_finite()))
        .unwrap_or(fallback);
    let init = if ab.norm_squared() > 0.0 {
        -ab.normalize()
    } else {
        Vector3::x()
    };
    let identity = PPose::IDENTITY;
    simplex.reset(CsoPoint::from_shapes(&identity, &ga, &gb, to_p(&init)));
    let result = gjk::closest_points(&identity, &ga, &gb, f64::MAX, true, simplex);
    let certify = |d: Vector3<f64>, distance: Option<f64>| -> Option<Separation> {
        let (max_a, min_b) = supports_along(xa, xb, &d);
        (min_b - max_a > 0.0).then(|| Separation::Separated {
            dir: d,
            max_a,
            min_b,
            distance: distance.unwrap_or(min_b - max_a),
        })
    };
    match result {
        GJKResult::Intersection => Ok(Separation::Intersecting),
        GJKResult::ClosestPoints(pa, pb, _) => {
            let delta = from_p(pb) - from_p(pa);
            let dist = delta.norm();
            if !dist.is_finite() || dist <= 0.0 {
                return Ok(Separation::Intersecting);
            }
            Ok(certify(delta / dist, Some(dist)).unwrap_or(Separation::Intersecting))
        }
        GJKResult::Proximity(_) | GJKResult::NoIntersection(_) => {
            // Only reachable when GJK hit its iteration cap (max_dist is infinite and exact
            // distances are requested). Try the centroid direction before giving up.
            if fallback.norm_squared() > 0.0
                && let Some(sep) = certify(fallback.normalize(), None)
            {
                return Ok(sep);
            }
            Err(ContactError::GjkFailed {
                len_a: xa.len(),
                len_b: xb.len(),
            })
        }
    }
}

/// Penetration depth of two intersecting hulls (m): the length of the
/// shortest translation that separates them (EPA on the Minkowski
/// difference). `None` when the hulls are disjoint or EPA does not converge.
pub fn penetration_depth(xa: &[Vector3<f64>], xb: &[Vector3<f64>]) -> Option<f64> {
    use parry3d_f64::query::contact::contact_support_map_support_map_with_params;
    let (ga, gb) = (PointCloud(xa), PointCloud(xb));
    let mut simplex = VoronoiSimplex::new();
    match contact_support_map_support_map_with_params(
        &PPose::IDENTITY,
        &ga,
        &gb,
        0.0,
        &mut simplex,
        None,
    ) {
        GJKResult::ClosestPoints(pa, pb, n) => {
            let dist = (pb - pa).dot(n);
            (dist <= 0.0 && dist.is_finite()).then_some(-dist)
        }
        _ => None,
    }
}
