//! Point–plane squared distance (the interior case of point–triangle):
//! `d = ((p − t₀)·n)² / ‖n‖²`, `n = (t₁ − t₀) × (t₂ − t₀)` (m²). Valid where
//! the projection of `p` falls inside the triangle; the other cases are
//! point–edge or point–point (see [`super::classify`]).

use super::vec::{V3, cross, dot, norm2, sub};
use num_dual::DualNum;

/// Squared distance from `p` to the plane of the triangle `t0 t1 t2`
/// (non-degenerate).
pub fn point_plane<T: DualNum<Primitive = f64> + Copy>(
    p: &V3<T>,
    t0: &V3<T>,
    t1: &V3<T>,
    t2: &V3<T>,
) -> T {
    let n = cross(&sub(t1, t0), &sub(t2, t0));
    let h = dot(&sub(p, t0), &n);
    h * h / norm2(&n)
}
