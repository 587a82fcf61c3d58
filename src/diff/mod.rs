//! Differentiation of whole trajectories by the adjoint method (paper,
//! `differentiable.tex` and appendix "Differentiability of SDRS").
//!
//! Each step solves `g_t = ∇_θ O_t(θ^t; θ^{t−1}, θ^{t−2}, u^t(c), d, φ) = 0`.
//! For a loss `L(θ^{−1} … θ^H, d)`, the backward pass runs `t = H … 1`:
//!
//! ```text
//! ā_t  = ∂L/∂θ^t − (∂g_{t+1}/∂θ^t)ᵀ λ_{t+1} − (∂g_{t+2}/∂θ^t)ᵀ λ_{t+2}
//! λ_t  = H_t⁻¹ ā_t                      (H_t = ∂g_t/∂θ^t, the Newton Hessian)
//! dL/dp = ∂L/∂p − Σ_t (∂g_t/∂p)ᵀ λ_t    (p: design, controller, physics)
//! ```
//!
//! and finally `θ^{−1} = θ^0 − Δt θ̇^0` maps the first two adjoints onto the
//! initial state. Every `(∂g/∂x)ᵀλ` is the gradient of `Φ = λᵀ g_t`, which
//! each energy term provides through [`crate::energy::Energy::vjp`] in pose
//! space; [`backward`] contracts pose-space results with the kinematics at
//! the time level they belong to. Poses are chart-independent, so rotation
//! chart re-centring between steps needs no special treatment: each `θ^t`
//! is differentiated in the chart it was solved in.

pub mod backward;
pub mod central;
pub mod descending;
pub mod effects;
pub mod loss;
pub mod tape;
pub use crate::energy::vjp;

pub use backward::{BackwardError, ChannelGrad, Gradients, backward, loss_of};
pub use loss::{Loss, LossTerm, When};
pub use tape::{Tape, record};
pub use vjp::{AdjointDirection, PhysicalGrad, VjpAccumulator};
