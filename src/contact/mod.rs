//! Contact and friction between pairs of convex hulls through a separating plane (SDRS paper,
//! §§"Contact Mechanics for Convex Polyhedrons" and "Frictional Contact Mechanics", with the
//! appendices "Well-defined Contact Potential" and "Well-defined Frictional Damping
//! Potential").
//!
//! - [`barrier`](mod@barrier): the locally supported barrier `P_s` and its first three derivatives.
//! - [`potential`]: the contact potential `U_c = min_p U*(p)` of a hull pair, its gradient and
//!   Hessian w.r.t. the two link poses (and w.r.t. world vertices for tests).
//! - [`friction`]: the lagged frictional-damping potential `U_f = min_{u,ω} Σ D_m`, its
//!   gradient and Hessian w.r.t. the step-`t+1` poses, and the mixed derivative w.r.t. the
//!   step-`t+1` and step-`t` poses.
//!
//! Conventions: a link pose is `A = [R | t]` (`Matrix3x4`), a world point is `X = A [x; 1]`,
//! pose parameters are `vec(A)` in column-major order (index `c·3 + r`), so
//! `∂X/∂vec(A) = x̃ᵀ ⊗ I₃`. Pose gradients are returned as `Matrix3x4` (`∂U/∂A`), pose
//! Hessians as `SMatrix<f64, 24, 24>` over `[vec(A_a); vec(A_b)]`. Hull `a` lies on the
//! negative side of the plane, hull `b` on the positive side; the plane normal points from
//! `a` to `b`.
//!
//! Scaling: `U_c` is unscaled; the simulator multiplies it by the stiffness κ (which the paper,
//! Eq. `SDRS`, confusingly also calls μ). `U_f` takes the normal forces already multiplied by
//! κ, so it is already an energy in physical units and must *not* be multiplied by κ again
//! (the paper's Eq. `SDRS` puts κ in front of `U_c + U_f` with unscaled forces inside `U_f`;
//! the two agree up to the smoothing `A_ε`, and this form keeps the Coulomb limit
//! `μ κ ‖f_⊥‖` exact).
//!
//! # Design notes
//!
//! - Separation is decided by GJK (parry) on the raw vertex slices and then *certified*
//!   exactly along GJK's direction; the certified gap also decides the out-of-range case, so
//!   `U_c = 0` is returned exactly, not approximately. GJK cannot resolve gaps below about
//!   `1e-8 ×` hull size: such pairs are reported as intersecting unless the caller's warm
//!   plane is strictly feasible, which is itself a proof of separation.
//! - Inner solves stop on `max(noise, min(tol, rtol · force scale))`: the absolute tolerance
//!   of the brief where it is attainable, a relative one where the potential is tiny (near
//!   the support edge), and a rounding-noise floor where the barrier is astronomically stiff
//!   (near contact, `P_s' ~ y⁻⁶`). When no step can decrease the inner objective any more,
//!   the solve also ends (successfully) if Newton's predicted decrease is below the rounding
//!   of the objective; only a stall above that floor, or the iteration cap, is an error.
//! - The friction inner solve minimises along the Newton direction instead of only
//!   backtracking: under fast sliding its objective is a nearly flat valley ending in a
//!   `√ε_v`-wide kink (see [`friction`](mod@friction), "Inner solve").
//! - Failing pair evaluations can be captured from a simulation and replayed bit for bit
//!   ([`capture`]); the regression tests of the inner solves are such captures.
//! - Per-vertex normal forces are not stored in the contact outcome (that would allocate per
//!   call); [`ContactPair::normal_forces_into`] and [`LaggedContact::from_contact`] compute
//!   them from `p*` in one pass.

pub mod adjoint_contact;
pub mod adjoint_friction;
pub mod barrier;
pub mod capture;
pub mod ccd;
mod error;
pub mod friction;
#[cfg(test)]
mod friction_tests;
pub mod line_model;
pub mod params;
mod plane;
pub mod potential;
#[cfg(test)]
mod potential_tests;
#[cfg(test)]
mod regression_tests;
pub mod separation;
pub mod settings;
#[cfg(test)]
mod test_util;

pub use adjoint_contact::{ContactVjp, PlaneOptimum, barrier_d1_ds, contact_vjp};
pub use adjoint_friction::{FrictionVjp, friction_vjp};
pub use barrier::{BarrierDerivs, barrier, barrier_d2, barrier_derivs};
pub use error::{ContactError, FrictionError, Hull};
pub use friction::{
    FrictionFrame, FrictionMemo, FrictionNeed, FrictionPair, FrictionParams, FrictionScratch,
    FrictionVertices, LaggedContact, friction_pair, friction_pair_memo, friction_vertices,
    tangent_basis,
};
pub use line_model::PlaneLine;
pub use potential::{
    ContactPair, ContactParams, ContactScratch, HullPose, Need, PairOutcome, PlacedHull,
    VertexContact, VertexOutcome, contact_pair, contact_pair_world, contact_vertices,
};
pub use settings::{ContactModelKind, ContactSettings};
