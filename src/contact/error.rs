//! Typed errors of the contact and friction potentials.

use std::fmt;

/// Which hull of a pair an error refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hull {
    /// Hull `a`, on the negative side of the separating plane.
    A,
    /// Hull `b`, on the positive side of the separating plane.
    B,
}

impl fmt::Display for Hull {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Hull::A => f.write_str("a"),
            Hull::B => f.write_str("b"),
        }
    }
}

/// Errors of [`contact_pair`](super::contact_pair) and
/// [`contact_vertices`](super::contact_vertices).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ContactError {
    /// `s` must lie in `(0, 1)`: it bounds `1 − ‖n‖` as well as being the barrier width.
    #[error("contact barrier width s = {s} must satisfy 0 < s < 1")]
    InvalidWidth {
        /// The offending value.
        s: f64,
    },
    /// Tolerances must be finite and non-negative and the iteration cap positive.
    #[error("invalid inner-solver settings: tol = {tol}, rtol = {rtol}, max_iters = {max_iters}")]
    InvalidSolverSettings {
        /// Absolute gradient tolerance.
        tol: f64,
        /// Relative gradient tolerance.
        rtol: f64,
        /// Iteration cap.
        max_iters: usize,
    },
    /// A hull has no vertex.
    #[error("hull {hull} has no vertex")]
    EmptyHull {
        /// Which hull.
        hull: Hull,
    },
    /// A (world or local) vertex or a pose entry is NaN or infinite.
    #[error("hull {hull}: vertex {index} is not finite in world coordinates: {value:?}")]
    NonFiniteVertex {
        /// Which hull.
        hull: Hull,
        /// Index of the vertex in the hull's vertex list.
        index: usize,
        /// Its world position as computed.
        value: [f64; 3],
    },
    /// GJK neither certified an intersection nor produced a separating direction, and the
    /// fallback direction (between the vertex centroids) does not separate the hulls either.
    #[error(
        "GJK did not converge and no separating direction was found (hulls of {len_a} and {len_b} vertices)"
    )]
    GjkFailed {
        /// Vertex count of hull `a`.
        len_a: usize,
        /// Vertex count of hull `b`.
        len_b: usize,
    },
    /// The inner Newton solve on the separating plane reached its iteration cap.
    #[error(
        "separating-plane Newton did not converge in {iterations} iterations: |grad_p U*| = {grad_norm:e} > tolerance {tolerance:e}"
    )]
    PlaneNotConverged {
        /// Iterations performed.
        iterations: usize,
        /// `‖∇_p U*‖` at the last iterate.
        grad_norm: f64,
        /// The effective tolerance it had to reach.
        tolerance: f64,
    },
    /// The backtracking line search of the inner plane solve could not decrease `U*` along a
    /// descent direction while the gradient was still above tolerance.
    #[error(
        "separating-plane line search stalled at iteration {iteration}: |grad_p U*| = {grad_norm:e} > tolerance {tolerance:e}"
    )]
    PlaneLineSearchStalled {
        /// Iteration at which the line search failed.
        iteration: usize,
        /// `‖∇_p U*‖` at that iterate.
        grad_norm: f64,
        /// The effective tolerance it had to reach.
        tolerance: f64,
    },
}

/// Errors of the friction potential.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FrictionError {
    /// `μ ≥ 0`, `Δt > 0`, `ε_v > 0`, `ε_f > 0` and finite tolerances are required.
    #[error(
        "invalid friction parameters: mu = {mu}, dt = {dt}, eps_velocity = {eps_velocity}, eps_force = {eps_force}"
    )]
    InvalidParams {
        /// Friction coefficient.
        mu: f64,
        /// Time step.
        dt: f64,
        /// Velocity smoothing ε (m²/s²).
        eps_velocity: f64,
        /// Force smoothing ε of `A_ε` (N²).
        eps_force: f64,
    },
    /// The lagged frame is unusable (non-unit normal, non-orthonormal basis, non-finite data).
    #[error("invalid lagged friction frame: {reason}")]
    InvalidFrame {
        /// What is wrong.
        reason: &'static str,
    },
    /// Two per-vertex arrays that must have equal length do not.
    #[error("hull {hull}: {what} has {got} entries, expected {expected}")]
    LengthMismatch {
        /// Which hull.
        hull: Hull,
        /// Which array.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// A vertex position at step t+1 is not finite.
    #[error("hull {hull}: vertex {index} at step t+1 is not finite")]
    NonFiniteVertex {
        /// Which hull.
        hull: Hull,
        /// Index of the vertex.
        index: usize,
    },
    /// The inner Newton solve on the plane velocity `(u, ω)` did not converge.
    #[error(
        "friction inner Newton did not converge in {iterations} iterations: |grad_(u,w) U*| = {grad_norm:e} > tolerance {tolerance:e}"
    )]
    NotConverged {
        /// Iterations performed.
        iterations: usize,
        /// Gradient norm at the last iterate.
        grad_norm: f64,
        /// The effective tolerance it had to reach.
        tolerance: f64,
    },
}
