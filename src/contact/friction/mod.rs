//! Frictional-damping potential `U_f` between a hull pair through the lagged separating plane
//! (paper §"Frictional Contact Mechanics"; proofs in Appendix "Well-defined Frictional Damping
//! Potential", `sec:FrictionProof`).
//!
//! # Model
//!
//! Lagged data from the contact solve of step `t`: unit plane normal `n̂` (of `p*`, from `a` to
//! `b`), an orthonormal tangent basis `B ∈ R^{3×2}` with `Bᵀn̂ = 0`, the world positions `X^t_m`
//! of the vertices of both hulls and the normal-force magnitudes `f_m = κ‖f_⊥^m‖` (already
//! multiplied by the stiffness κ). With `A_ε(f) = √(f² + ε_f) − √ε_f`, per vertex of both hulls
//!
//! ```text
//! D_m(u, ω) = μ Δt A_ε(f_m) √(‖ẋ_m − ṗ_m‖² + ε_v)
//! ẋ_m = Bᵀ(X^{t+1}_m − X^t_m)/Δt                       (tangential vertex velocity, m/s)
//! ṗ_m = ω Bᵀ(n̂ × (X^t_m − c)) + u                      (plane velocity at the vertex)
//! U_f = min_{u ∈ R², ω ∈ R} Σ_m D_m                     (convex in (u, ω))
//! ```
//!
//! Units: `U_f` has units of force × length (energy) when `f` is a force, `μ` is
//! dimensionless, `Δt` in s, `ε_v` in (m/s)², `ε_f` in N². `−∂U_f/∂X^{t+1}_m` is the friction
//! force `μ A_ε(f_m) B r_m/√(‖r_m‖² + ε_v)` with `r_m = ẋ_m − ṗ_m` (paper's `f_∥`, opposing the
//! relative tangential velocity).
//!
//! # Rotation centre
//!
//! The paper rotates about the world origin (`n̂ × X^t_m`). Here the centre is the
//! contact-weighted centroid `c = Σ A_ε(f_m) X^t_m / Σ A_ε(f_m)`, recomputed from the given
//! `X^t`. `U_f` does not depend on `c` at all: `ω Bᵀ(n̂ × c)` is a constant in-plane vector
//! absorbed by `u` (this is Lemma `bigAlpha` i), whose shift `α B₁` is a special choice of
//! `c`). The centroid choice makes the spin coefficients `g_m = Bᵀ(n̂ × (X^t_m − c))` have zero
//! weighted mean, which decouples `u` from `ω` in the inner Hessian and avoids the near-
//! degeneracy of a far-away centre. Since `U_f` is independent of `c`, all derivatives are
//! computed with `c` held fixed, and they are exactly the derivatives of `U_f`.
//!
//! # Spin degeneracy
//!
//! If every weighted `g_m` vanishes (a single contact vertex, or all contact vertices on one
//! line along `n̂`, e.g. vertex–vertex contact), `U*` is flat in `ω` (paper Lemma in
//! `sec:FrictionProof`, ii). Lemma `bigAlpha` ii) proposes to shift the centre by a large
//! `α B₁`; note that in the fully flat case this only replaces every `g_m` by the same constant
//! vector, which is again redundant with `u`, so the joint `(u, ω)` Hessian stays singular.
//! Instead, by Lemma `bigAlpha` i)-style reasoning `U_f = min_u U*(u, ω = 0)` exactly in that
//! case, so `ω` is dropped ([`FrictionPair::spin_free`]) and the inner problem and the implicit
//! function theorem use the 2×2 `u` block (strictly convex whenever some `f_m > 0`). The test
//! is `Σ w_m ‖g_m‖² ≤ 10⁻²⁰ Σ w_m ‖X^t_m − c‖²` (relative; it catches exact degeneracy up to
//! rounding only). Flatness depends on `X^t` only, so `U_f` is smooth in `X^{t+1}` there. It
//! is not continuous in `X^t` at such configurations (an in-plane perturbation of two
//! coincident contact points creates a tiny lever arm that the plane can exploit with a huge
//! spin); this is a property of the model, not of the solver, and the mixed derivative
//! returned there is the one of the `ω = 0` branch.
//!
//! # Derivatives
//!
//! With `q = (u, ω)`, `J_m = [I₂ | g_m]`, `r_m = ẋ_m − J_m q`, `φ_m = √(‖r_m‖² + ε_v)`,
//! `ρ_m = r_m/φ_m`, `Φ_m = (I − ρ_m ρ_mᵀ)/φ_m`, `w_m = μ Δt A_ε(f_m)`, `Q = I/Δt + ω [n̂]×`:
//!
//! ```text
//! ∂U_f/∂X'_m        = (w_m/Δt) B ρ_m                                   (envelope theorem)
//! U*_{X'_m X'_m}    = (w_m/Δt²) B Φ_m Bᵀ =: M_m
//! U*_{X'_m q}       = −(w_m/Δt) B Φ_m J_m
//! U*_qq             = Σ_m w_m J_mᵀ Φ_m J_m                              (3×3)
//! ∂²U_f/∂X'²        = U*_{X'X'} − U*_{X'q} (U*_qq)⁻¹ U*_{qX'}            (implicit fn. thm.)
//! U*_{X'_m X_m}     = −Δt M_m Q                                         (X = X^t)
//! U*_{q X_m}        = w_m J_mᵀ Φ_m Bᵀ Q − e₃ (w_m B ρ_m)ᵀ [n̂]×
//! ∂²U_f/∂X'∂X       = U*_{X'X} − U*_{X'q} (U*_qq)⁻¹ U*_{qX}              (paper Eq. derivativeFriction2)
//! ```
//!
//! Pose contraction uses, per hull, the accumulators `Σ x̃ w ρᵀ` (4×2), `Σ x̃ x̃ᵀ w Φ_ij`
//! (three 4×4) and `Σ x̃ ⊗ w J_mᵀΦ_m` (4×3×2) over the vertices with a non-zero normal force
//! only; vertices without normal force do not enter `U_f` at all.
//!
//! # Inner solve
//!
//! Newton's method on `q` from `u = Σ w ẋ / Σ w`, `ω = 0`. The full Newton step is taken when
//! it satisfies Armijo (local quadratic convergence); otherwise the step length is found by a
//! safeguarded minimisation of the convex `α ↦ U*(q + α d)` (bracketing, then secant and
//! tangent-intersection candidates; see `line_minimize`), and two more candidates are tried,
//! keeping the best point: the majorize–minimize (Weiszfeld/IRLS) step, which never
//! increases `U*`, and the best point on the "kink" of a vertex (the line of plane motions
//! that move exactly with it; see `kink_candidate`), taken only where that vertex can hold
//! the plane against the pull of all the others.
//!
//! Why a line *minimisation*: when the hulls slide at relative speeds `V ≫ √ε_v`, every
//! `√(‖r‖² + ε_v)` is an almost exact norm, and the contact plane's force balance makes the
//! total weights `Σ_a w` and `Σ_b w` of the two sides nearly equal. `U*` is then nearly flat
//! along the plane velocities between the two hulls' velocities (curvature `~ w ε_v/V³`,
//! slope `~ |Σ_a w − Σ_b w|`), and its minimiser sits in a kink of width `√ε_v` where the
//! plane sticks to the heavier side. Newton's model there proposes steps `~V³/ε_v` (10⁸ m/s
//! for `V` = 100 m/s), a backtracking search with a bounded number of halvings cannot reach
//! the kink, and majorize–minimize crawls along the valley (`~ 10⁻² m/s` per iteration).
//! Minimising along the Newton direction lands in the kink in one or two iterations, after
//! which Newton converges quadratically. When the plane must also spin (two heavy vertices on
//! different hulls near each other), the iterate can instead slide along one vertex's kink
//! while creeping towards it; minimising on the kink itself removes that crawl. `Φ_m` is evaluated as `(ε_v/φ² I + τ τᵀ)/φ`
//! (`τ ⊥ ρ`, `‖τ‖ = ‖ρ‖`), which keeps the valley curvature `ε_v/φ³` accurate where
//! `I − ρρᵀ` would cancel.
//!
//! Stopping rule as for the contact plane: `‖∇_q U*‖ ≤ max(noise, min(tol, rtol · Σ w |ρ|
//! (1 + ‖g‖)))`, or — when no step decreases `U*` any more — Newton's predicted decrease
//! `½ gᵀH⁻¹g` below the rounding of `U*` (noise floor). Anything else that stops progress is
//! an error. Typical iteration counts are 3–12; fast sliding (10⁵–10⁷ `√ε_v`) needs up to
//! ~30 (the stress scenes: mean 6–8, max 29 over 10⁵ solves).
//!
//! # Not covered
//!
//! Derivatives through the lagged data (how `n̂`, `B` and the normal forces depend on the
//! step-`t` state) are not computed here: the mixed derivative is for fixed lagged data, as
//! specified. A full adjoint through `θ^t` also needs `∂f_⊥/∂X^t` (from the contact Hessian
//! machinery) and `∂n*/∂X^t` (from `∂p*/∂X`, paper Eq. `planeDerivative`).
//!
//! # Files
//!
//! `params` (parameters, tangent basis), `lagged` (step-`t` data), `inner` (the inner convex
//! solve), `line` (its step lengths), `pair` (`U_f` of a pair, pose-contracted derivatives),
//! `vertices` (per-vertex derivatives).

mod inner;
mod lagged;
mod line;
mod pair;
mod params;
mod vertices;

pub use inner::FrictionScratch;
use inner::*;
pub use lagged::{FrictionFrame, LaggedContact};
use line::*;
use pair::cross_matrix;
pub use pair::{FrictionMemo, FrictionNeed, FrictionPair, friction_pair, friction_pair_memo};
pub use params::{FrictionParams, tangent_basis};
pub use vertices::{FrictionVertices, friction_vertices};
