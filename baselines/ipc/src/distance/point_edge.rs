//! Point–line squared distance (the interior case of point–edge):
//! `d = ‖(e₀ − p) × (e₁ − p)‖² / ‖e₁ − e₀‖²` (m²), the squared distance from
//! `p` to the infinite line through `e₀`, `e₁`. Valid where the closest point
//! of the segment is interior; the endpoint cases are point–point.

use super::vec::{V3, cross, norm2, sub};
use num_dual::DualNum;

/// Squared distance from `p` to the line through `e0`, `e1` (`e0 ≠ e1`).
pub fn point_line<T: DualNum<Primitive = f64> + Copy>(p: &V3<T>, e0: &V3<T>, e1: &V3<T>) -> T {
    let c = cross(&sub(e0, p), &sub(e1, p));
    norm2(&c) / norm2(&sub(e1, e0))
}

/// Parameter `t` of the closest point `e₀ + t(e₁ − e₀)` on the line (not
/// clamped); `0` for a degenerate edge.
pub fn line_parameter(p: &V3<f64>, e0: &V3<f64>, e1: &V3<f64>) -> f64 {
    let e = sub(e1, e0);
    let l2 = norm2(&e);
    if l2 <= 0.0 {
        return 0.0;
    }
    super::vec::dot(&sub(p, e0), &e) / l2
}
