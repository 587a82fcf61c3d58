//! Contact and friction between pairs of convex hulls through a separating plane (SDRS paper,
//! §§"Contact Mechanics for Convex Polyhedrons" and "Frictional Contact Mechanics", with the
//! appendices "Well-defined Contact Potential" and "Well-defined Frictional Damping
//! Potential").
//!
//! - [`barrier`]: the locally supported barrier `P_s` and its first three derivatives.
//! - [`potential`]: the contact potential `U_c = min_p U*(p)` of a hull pair, its gradient and
//!   Hessian w.r.t. the two link poses (and w.r.t. world vertices for tests).
//! - [`friction`]: the lagged frictional-damping potential `U_f = min_{u,ω} Σ D_m`, its
//!   gradient, Hessian and mixed derivative w.r.t. the step-`t` positions.
//!
//! Conventions: a link pose is `A = [R | t]` (`Matrix3x4`), a world point is `X = A [x; 1]`,
//! pose parameters are `vec(A)` in column-major order (index `c·3 + r`), so
//! `∂X/∂vec(A) = x̃ᵀ ⊗ I₃`. Pose gradients are returned as `Matrix3x4` (`∂U/∂A`), pose
//! Hessians as `SMatrix<f64, 24, 24>` over `[vec(A_a); vec(A_b)]`. Hull `a` lies on the
//! negative side of the plane, hull `b` on the positive side; the plane normal points from
//! `a` to `b`. Potentials are unscaled: the simulator multiplies them by the stiffness κ
//! (which the paper, Eq. `SDRS`, confusingly also calls μ).

pub mod barrier;
mod error;
pub mod friction;
#[cfg(test)]
mod friction_tests;
mod plane;
pub mod potential;
#[cfg(test)]
mod potential_tests;
mod separation;
#[cfg(test)]
mod test_util;

pub use barrier::{BarrierDerivs, barrier, barrier_d2, barrier_derivs};
pub use error::{ContactError, FrictionError, Hull};
pub use friction::{
    FrictionFrame, FrictionNeed, FrictionPair, FrictionParams, FrictionScratch, FrictionVertices,
    LaggedContact, friction_pair, friction_vertices, tangent_basis,
};
pub use potential::{
    ContactPair, ContactParams, ContactScratch, HullPose, Need, PairOutcome, VertexContact,
    VertexOutcome, contact_pair, contact_vertices,
};
