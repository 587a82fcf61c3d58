//! Line–line squared distance (the interior case of edge–edge):
//! `d = ((a₀ − b₀)·n)² / ‖n‖²`, `n = (a₁ − a₀) × (b₁ − b₀)` (m²). Valid where
//! both closest points are interior to their segments and the edges are not
//! parallel; otherwise point–edge or point–point (see [`super::classify`]).

use super::vec::{V3, cross, dot, norm2, sub};
use num_dual::DualNum;

/// Squared distance between the lines through `a0 a1` and `b0 b1`
/// (non-parallel).
pub fn line_line<T: DualNum<Primitive = f64> + Copy>(
    a0: &V3<T>,
    a1: &V3<T>,
    b0: &V3<T>,
    b1: &V3<T>,
) -> T {
    let n = cross(&sub(a1, a0), &sub(b1, b0));
    let h = dot(&sub(a0, b0), &n);
    h * h / norm2(&n)
}

/// `‖(a₁ − a₀) × (b₁ − b₀)‖²` (m⁴): the quantity the parallel-edge mollifier
/// acts on (see [`crate::mollifier`]).
pub fn cross_norm2<T: DualNum<Primitive = f64> + Copy>(
    a0: &V3<T>,
    a1: &V3<T>,
    b0: &V3<T>,
    b1: &V3<T>,
) -> T {
    norm2(&cross(&sub(a1, a0), &sub(b1, b0)))
}
