//! Joint position offset (encoder bias): the sensor reads `θ + b`.
//!
//! A measurement-side parameter: it does not change the dynamics, only the
//! comparison with measured data (`measured ≈ simulated + b`, `b` in rad or
//! m). `sdrs simulate` writes the physical coordinates, without `b`; the
//! residual's derivative is `∂r/∂b = 1` on the affected channels, and the
//! trajectory gradient of any simulated loss w.r.t. `b` is 0.

/// Adds the offset `b` to the simulated channels `dofs` of one sample.
pub fn apply(values: &mut [f64], dofs: &[usize], b: f64) {
    for &k in dofs {
        values[k] += b;
    }
}
