//! IPC's edge–edge mollifier (Li et al. 2020, §4.3): near-parallel edges
//! have an ill-defined line–line distance, so an edge–edge barrier is
//! multiplied by
//!
//! `m(x, ε_x) = (2 − x/ε_x)·x/ε_x` for `x < ε_x`, `1` otherwise,
//!
//! with `x = ‖(a₁ − a₀) × (b₁ − b₀)‖²` (m⁴) and
//! `ε_x = 10⁻³ ‖ā₁ − ā₀‖² ‖b̄₁ − b̄₀‖²` from the rest lengths (for rigid links
//! the rest lengths are the link-frame lengths, so `ε_x` is a constant per
//! edge pair). `m` is C¹ at `x = ε_x` and vanishes with the cross product.

use num_dual::DualNum;

/// IPC's factor: `ε_x = 1e-3 · ‖ā‖²‖b̄‖²`.
pub fn eps_x(len2_a: f64, len2_b: f64) -> f64 {
    1e-3 * len2_a * len2_b
}

/// `m(x, ε_x)` for `x < ε_x` (the caller uses 1 otherwise).
pub fn mollifier<T: DualNum<Primitive = f64> + Copy>(x: T, eps_x: f64) -> T {
    let r = x / eps_x;
    (-r + 2.0) * r
}
