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

use nalgebra::{
    DMatrix, Matrix2, Matrix3, Matrix3x2, Matrix3x4, Matrix4, SMatrix, Vector2, Vector3, Vector4,
};

use super::barrier::barrier_d2;
use super::error::{FrictionError, Hull};
use super::potential::{ContactPair, ContactParams, HullPose};

/// Parameters of the friction potential.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrictionParams {
    /// Coulomb friction coefficient `μ ≥ 0` (dimensionless). Default `0.5`.
    pub mu: f64,
    /// Time step `Δt > 0` in seconds. Default `0.01`.
    pub dt: f64,
    /// Velocity smoothing `ε_v > 0` in `√(‖ẋ − ṗ‖² + ε_v)`, in (m/s)². Below relative speeds of
    /// about `√ε_v` friction behaves like viscous damping. Default `1e-6` (1 mm/s).
    pub eps_velocity: f64,
    /// Force smoothing `ε_f > 0` of `A_ε(f) = √(f² + ε_f) − √ε_f`, in N². The paper uses one `ε`
    /// for both roles; they are separate here because their units differ. Default `1e-6`.
    pub eps_force: f64,
    /// Absolute tolerance on `‖∇_(u,ω) U*‖`. Default `1e-8`; honoured when above the
    /// rounding-noise floor.
    pub inner_tol: f64,
    /// Relative tolerance on `‖∇_(u,ω) U*‖` w.r.t. the total friction-force magnitude on the
    /// plane. Default `1e-10`.
    pub inner_rtol: f64,
    /// Iteration cap of the inner Newton solve. Default `100`.
    pub inner_max_iters: usize,
}

impl Default for FrictionParams {
    fn default() -> Self {
        Self {
            mu: 0.5,
            dt: 0.01,
            eps_velocity: 1e-6,
            eps_force: 1e-6,
            inner_tol: 1e-8,
            inner_rtol: 1e-10,
            inner_max_iters: 100,
        }
    }
}

impl FrictionParams {
    /// Parameters with the given `μ` and `Δt` and default smoothing and solver settings.
    pub fn new(mu: f64, dt: f64) -> Self {
        Self {
            mu,
            dt,
            ..Self::default()
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), FrictionError> {
        let ok = self.mu >= 0.0
            && self.mu.is_finite()
            && self.dt > 0.0
            && self.dt.is_finite()
            && self.eps_velocity > 0.0
            && self.eps_velocity.is_finite()
            && self.eps_force > 0.0
            && self.eps_force.is_finite()
            && self.inner_tol >= 0.0
            && self.inner_tol.is_finite()
            && self.inner_rtol >= 0.0
            && self.inner_rtol.is_finite()
            && self.inner_max_iters > 0;
        if ok {
            Ok(())
        } else {
            Err(FrictionError::InvalidParams {
                mu: self.mu,
                dt: self.dt,
                eps_velocity: self.eps_velocity,
                eps_force: self.eps_force,
            })
        }
    }

    /// `A_ε(f) = √(f² + ε_f) − √ε_f`, written without cancellation as `f²/(√(f² + ε_f) + √ε_f)`.
    pub fn smoothed_force(&self, f: f64) -> f64 {
        let se = self.eps_force.sqrt();
        f * f / ((f * f + self.eps_force).sqrt() + se)
    }
}

/// A deterministic orthonormal tangent basis `B = [b₁ b₂]` of the plane with unit normal `n`
/// (`b₁ × b₂ = n`).
pub fn tangent_basis(n: &Vector3<f64>) -> Matrix3x2<f64> {
    // Cross with the world axis least aligned with n.
    let a = n
        .iter()
        .map(|v| v.abs())
        .enumerate()
        .fold(
            (0, f64::INFINITY),
            |m, (i, v)| {
                if v < m.1 { (i, v) } else { m }
            },
        );
    let mut e = Vector3::zeros();
    e[a.0] = 1.0;
    let b1 = e.cross(n).normalize();
    let b2 = n.cross(&b1);
    Matrix3x2::from_columns(&[b1, b2])
}

/// Lagged step-`t` data of one hull pair (borrowed view). See the module docs.
#[derive(Clone, Copy, Debug)]
pub struct FrictionFrame<'a> {
    /// Unit plane normal `n̂` from hull `a` to hull `b`.
    pub normal: Vector3<f64>,
    /// Orthonormal tangent basis `B` (3×2, `Bᵀ n̂ = 0`).
    pub basis: Matrix3x2<f64>,
    /// World positions `X^t` of hull `a`'s vertices.
    pub x_prev_a: &'a [Vector3<f64>],
    /// World positions `X^t` of hull `b`'s vertices.
    pub x_prev_b: &'a [Vector3<f64>],
    /// Normal-force magnitudes `κ ‖f_⊥^m‖ ≥ 0` of hull `a`'s vertices.
    pub normal_force_a: &'a [f64],
    /// Normal-force magnitudes `κ ‖f_⊥^m‖ ≥ 0` of hull `b`'s vertices.
    pub normal_force_b: &'a [f64],
}

impl FrictionFrame<'_> {
    fn validate(&self) -> Result<(), FrictionError> {
        let n = self.normal;
        if !n.iter().all(|v| v.is_finite()) || (n.norm() - 1.0).abs() > 1e-9 {
            return Err(FrictionError::InvalidFrame {
                reason: "normal is not a finite unit vector",
            });
        }
        let btb = self.basis.transpose() * self.basis;
        if !self.basis.iter().all(|v| v.is_finite())
            || (btb - Matrix2::identity()).norm() > 1e-9
            || (self.basis.transpose() * n).norm() > 1e-9
        {
            return Err(FrictionError::InvalidFrame {
                reason: "tangent basis is not orthonormal and orthogonal to the normal",
            });
        }
        for (hull, x, f) in [
            (Hull::A, self.x_prev_a, self.normal_force_a),
            (Hull::B, self.x_prev_b, self.normal_force_b),
        ] {
            if x.len() != f.len() {
                return Err(FrictionError::LengthMismatch {
                    hull,
                    what: "normal_force",
                    expected: x.len(),
                    got: f.len(),
                });
            }
            if !x.iter().all(|v| v.iter().all(|c| c.is_finite())) {
                return Err(FrictionError::InvalidFrame {
                    reason: "non-finite X^t",
                });
            }
            if !f.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(FrictionError::InvalidFrame {
                    reason: "normal forces must be finite and non-negative",
                });
            }
        }
        Ok(())
    }
}

/// Owned lagged data built from a step-`t` contact solve (allocates; once per step and pair).
#[derive(Clone, Debug, PartialEq)]
pub struct LaggedContact {
    /// Unit normal `n*/‖n*‖`.
    pub normal: Vector3<f64>,
    /// Tangent basis from [`tangent_basis`].
    pub basis: Matrix3x2<f64>,
    /// `X^t` of hull `a`.
    pub x_prev_a: Vec<Vector3<f64>>,
    /// `X^t` of hull `b`.
    pub x_prev_b: Vec<Vector3<f64>>,
    /// `κ ‖f_⊥^m‖` of hull `a`.
    pub normal_force_a: Vec<f64>,
    /// `κ ‖f_⊥^m‖` of hull `b`.
    pub normal_force_b: Vec<f64>,
}

impl LaggedContact {
    /// Lagged data of a separated pair at step `t`: `pair` is the result of
    /// [`contact_pair`](super::contact_pair) at the step-`t` poses `a`, `b`; `kappa` is the
    /// contact stiffness. Normal forces are `κ |P_s'(y_m)| ‖n*‖`.
    pub fn from_contact(
        pair: &ContactPair,
        a: HullPose<'_>,
        b: HullPose<'_>,
        params: &ContactParams,
        kappa: f64,
    ) -> Self {
        let n = pair.normal();
        let nn = n.norm();
        let normal = n / nn;
        let o = pair.plane.w;
        let build = |h: HullPose<'_>, sigma: f64| {
            let mut xs = Vec::with_capacity(h.x_local.len());
            let mut fs = Vec::with_capacity(h.x_local.len());
            for x in h.x_local {
                let xw = h.pose.fixed_columns::<3>(0) * x + h.pose.column(3);
                let (_, d1, _) = barrier_d2(sigma * (n.dot(&xw) + o), params.s);
                xs.push(xw);
                fs.push(kappa * d1.abs() * nn);
            }
            (xs, fs)
        };
        let (x_prev_a, normal_force_a) = build(a, -1.0);
        let (x_prev_b, normal_force_b) = build(b, 1.0);
        Self {
            normal,
            basis: tangent_basis(&normal),
            x_prev_a,
            x_prev_b,
            normal_force_a,
            normal_force_b,
        }
    }

    /// Borrowed view for [`friction_pair`] / [`friction_vertices`].
    pub fn frame(&self) -> FrictionFrame<'_> {
        FrictionFrame {
            normal: self.normal,
            basis: self.basis,
            x_prev_a: &self.x_prev_a,
            x_prev_b: &self.x_prev_b,
            normal_force_a: &self.normal_force_a,
            normal_force_b: &self.normal_force_b,
        }
    }
}

/// Which derivatives of `U_f` to compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum FrictionNeed {
    /// Value only.
    Value,
    /// Value and `∂U_f/∂A^{t+1}`.
    Gradient,
    /// Plus `∂²U_f/∂(A^{t+1})²`.
    Hessian,
    /// Plus the mixed `∂²U_f/∂A^{t+1}∂A^t` (for fixed lagged normal, basis and forces).
    HessianAndMixed,
}

/// A vertex with non-zero friction weight.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Active {
    /// 0 for hull `a`, 1 for `b`.
    hull: usize,
    /// Index in its hull.
    index: usize,
    /// `w = μ Δt A_ε(f)`.
    w: f64,
    /// `ẋ = Bᵀ(X' − X^t)/Δt`.
    v: Vector2<f64>,
    /// `g = Bᵀ(n̂ × (X^t − c))`.
    g: Vector2<f64>,
}

/// Reusable buffers of the friction evaluation.
#[derive(Clone, Debug, Default)]
pub struct FrictionScratch {
    act: Vec<Active>,
}

impl FrictionScratch {
    /// Empty scratch.
    pub fn new() -> Self {
        Self::default()
    }
}

/// Inner solution.
#[derive(Clone, Copy, Debug)]
struct Core {
    q: Vector3<f64>,
    spin_free: bool,
    value: f64,
    hinv: Matrix3<f64>,
    iterations: usize,
}

/// Per-vertex quantities at `q`.
#[inline(always)]
fn vertex_terms(
    a: &Active,
    q: &Vector3<f64>,
    eps: f64,
) -> (Vector2<f64>, f64, Vector2<f64>, Matrix2<f64>) {
    let r = a.v - Vector2::new(q.x, q.y) - a.g * q.z;
    let phi = (r.norm_squared() + eps).sqrt();
    let rho = r / phi;
    // Φ = (I − ρρᵀ)/φ written without cancellation: its eigenvalue along r is ε/φ³, which
    // `1 − ‖ρ‖²` would lose entirely once ‖r‖ ≳ 10⁸ √ε (and partly long before). With
    // τ = (−ρ_y, ρ_x): Φ = (ε/φ² I + τ τᵀ)/φ.
    let tau = Vector2::new(-rho.y, rho.x);
    let big_phi = (Matrix2::identity() * (eps / (phi * phi)) + tau * tau.transpose()) / phi;
    (r, phi, rho, big_phi)
}

struct InnerEval {
    value: f64,
    grad: Vector3<f64>,
    hess: Matrix3<f64>,
    scale: f64,
    noise: f64,
    value_noise: f64,
}

fn inner_value(act: &[Active], q: &Vector3<f64>, eps: f64) -> f64 {
    act.iter()
        .map(|a| {
            let r = a.v - Vector2::new(q.x, q.y) - a.g * q.z;
            a.w * (r.norm_squared() + eps).sqrt()
        })
        .sum()
}

fn inner_eval(act: &[Active], q: &Vector3<f64>, eps: f64, spin_free: bool) -> InnerEval {
    let mut e = InnerEval {
        value: 0.0,
        grad: Vector3::zeros(),
        hess: Matrix3::zeros(),
        scale: 0.0,
        noise: 0.0,
        value_noise: 0.0,
    };
    for a in act {
        let (r, phi, rho, bp) = vertex_terms(a, q, eps);
        e.value += a.w * phi;
        // ∇_q = −w Jᵀρ, ∇²_q = w Jᵀ Φ J with J = [I | g].
        let gr = a.g.dot(&rho);
        e.grad -= a.w * Vector3::new(rho.x, rho.y, gr);
        let pg = bp * a.g;
        let mut h = Matrix3::zeros();
        h.fixed_view_mut::<2, 2>(0, 0).copy_from(&bp);
        h[(0, 2)] = pg.x;
        h[(1, 2)] = pg.y;
        h[(2, 0)] = pg.x;
        h[(2, 1)] = pg.y;
        h[(2, 2)] = a.g.dot(&pg);
        e.hess += a.w * h;
        let lever = 1.0 + a.g.norm();
        e.scale += a.w * rho.norm() * lever;
        let rerr = a.v.norm() + q.x.abs() + q.y.abs() + q.z.abs() * a.g.norm() + r.norm();
        e.noise += a.w * lever * (1.0 + rerr / phi);
        e.value_noise += a.w * (phi + rerr);
    }
    if spin_free {
        e.grad.z = 0.0;
        for i in 0..3 {
            e.hess[(i, 2)] = 0.0;
            e.hess[(2, i)] = 0.0;
        }
    }
    e.noise *= 64.0 * f64::EPSILON;
    e.value_noise *= 64.0 * f64::EPSILON;
    e
}

/// Solves `H d = −g` (3×3; in spin-free mode only the `u` block).
fn inner_direction(h: &Matrix3<f64>, g: &Vector3<f64>, spin_free: bool) -> Vector3<f64> {
    if spin_free {
        let h2 = h.fixed_view::<2, 2>(0, 0).into_owned();
        let g2 = Vector2::new(g.x, g.y);
        let d = h2.cholesky().map(|c| c.solve(&(-g2))).unwrap_or(-g2);
        return Vector3::new(d.x, d.y, 0.0);
    }
    if let Some(c) = h.cholesky() {
        let d = c.solve(&(-g));
        if d.iter().all(|v| v.is_finite()) {
            return d;
        }
    }
    let maxdiag = (0..3)
        .map(|i| h[(i, i)].abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut lambda = 1e-12 * maxdiag;
    for _ in 0..40 {
        if let Some(c) = (h + Matrix3::identity() * lambda).cholesky() {
            let d = c.solve(&(-g));
            if d.iter().all(|v| v.is_finite()) {
                return d;
            }
        }
        lambda *= 10.0;
    }
    -g
}

/// Inverse of `U*_qq` used by the implicit function theorem: the 2×2 `u` block embedded with a
/// zero `ω` row/column in spin-free mode, otherwise the full inverse (eigenvalue pseudo-inverse
/// if numerically singular, which only happens when every weight underflows).
fn inner_hessian_inverse(h: &Matrix3<f64>, spin_free: bool) -> Matrix3<f64> {
    let mut out = Matrix3::zeros();
    if spin_free {
        let h2 = h.fixed_view::<2, 2>(0, 0).into_owned();
        if let Some(inv) = h2.try_inverse() {
            out.fixed_view_mut::<2, 2>(0, 0).copy_from(&inv);
        }
        return out;
    }
    if let Some(c) = h.cholesky() {
        let inv = c.inverse();
        if inv.iter().all(|v| v.is_finite()) {
            return inv;
        }
    }
    let eig = h.symmetric_eigen();
    let maxe = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for i in 0..3 {
        let l = eig.eigenvalues[i];
        if l > 1e-13 * maxe && l > 0.0 {
            let v = eig.eigenvectors.column(i);
            out += v * v.transpose() / l;
        }
    }
    out
}

/// Fills the active-vertex list (vertices with a non-zero normal force) and returns whether
/// the problem is spin-free. `next(h, m)` gives the step-`t+1` world position of vertex `m` of
/// hull `h`; it is only called for active vertices, whose positions are checked for finiteness
/// (vertices without normal force do not enter `U_f`).
fn prepare(
    frame: &FrictionFrame<'_>,
    next: &dyn Fn(usize, usize) -> Vector3<f64>,
    counts: [usize; 2],
    params: &FrictionParams,
    act: &mut Vec<Active>,
) -> Result<bool, FrictionError> {
    params.validate()?;
    frame.validate()?;
    let prev = [frame.x_prev_a, frame.x_prev_b];
    let forces = [frame.normal_force_a, frame.normal_force_b];
    for (h, hull) in [Hull::A, Hull::B].into_iter().enumerate() {
        if counts[h] != prev[h].len() {
            return Err(FrictionError::LengthMismatch {
                hull,
                what: "vertices at step t+1",
                expected: prev[h].len(),
                got: counts[h],
            });
        }
    }
    // Contact-weighted centroid of X^t (weights A_ε(f)).
    let mut wsum = 0.0;
    let mut c = Vector3::zeros();
    for h in 0..2 {
        for (x, f) in prev[h].iter().zip(forces[h]) {
            if *f > 0.0 {
                let a = params.smoothed_force(*f);
                wsum += a;
                c += a * x;
            }
        }
    }
    act.clear();
    if wsum.is_nan() || wsum <= 0.0 {
        // No normal force anywhere: U_f ≡ 0.
        return Ok(true);
    }
    c /= wsum;
    let bt = frame.basis.transpose();
    let n = frame.normal;
    let (mut lever_in_plane, mut lever_full) = (0.0, 0.0);
    for h in 0..2 {
        for (index, (xp, f)) in prev[h].iter().zip(forces[h]).enumerate() {
            if *f <= 0.0 {
                continue;
            }
            let a = params.smoothed_force(*f);
            if a <= 0.0 {
                continue; // underflow of f²
            }
            let xn = next(h, index);
            if !xn.iter().all(|v| v.is_finite()) {
                return Err(FrictionError::NonFiniteVertex {
                    hull: [Hull::A, Hull::B][h],
                    index,
                });
            }
            let d = xp - c;
            let g = bt * n.cross(&d);
            lever_in_plane += a * g.norm_squared();
            lever_full += a * d.norm_squared();
            act.push(Active {
                hull: h,
                index,
                w: params.mu * params.dt * a,
                v: bt * (xn - xp) / params.dt,
                g,
            });
        }
    }
    Ok(lever_in_plane <= 1e-20 * lever_full)
}

/// Majorize–minimize (Weiszfeld / iteratively reweighted least squares) step from `q`:
/// since `√(t + ε)` is concave in `t = ‖r‖²`, `U* ≤ Σ w (‖r‖² + ε + φ₀²)/(2φ₀)` with `φ₀` taken
/// at `q`, with equality at `q`; minimising this quadratic majorant (a 3×3 weighted least-squares
/// problem) therefore never increases `U*`. Linear convergence, but globally robust.
fn mm_step(act: &[Active], q: &Vector3<f64>, eps: f64, spin_free: bool) -> Option<Vector3<f64>> {
    let mut a = Matrix3::zeros();
    let mut b = Vector3::zeros();
    for t in act {
        let r = t.v - Vector2::new(q.x, q.y) - t.g * q.z;
        let c = t.w / (r.norm_squared() + eps).sqrt();
        let g = if spin_free { Vector2::zeros() } else { t.g };
        let jtj = Matrix3::new(1.0, 0.0, g.x, 0.0, 1.0, g.y, g.x, g.y, g.norm_squared());
        a += jtj * c;
        b += Vector3::new(t.v.x, t.v.y, g.dot(&t.v)) * c;
    }
    if spin_free {
        let a2 = a.fixed_view::<2, 2>(0, 0).into_owned();
        let x = a2.cholesky()?.solve(&Vector2::new(b.x, b.y));
        return Some(Vector3::new(x.x, x.y, 0.0));
    }
    let x = a.cholesky()?.solve(&b);
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// `U*(q + α d)` and its derivative `d/dα`.
fn line_eval(act: &[Active], q: &Vector3<f64>, d: &Vector3<f64>, alpha: f64, eps: f64) -> LinePt {
    let qt = q + d * alpha;
    let (mut f, mut df) = (0.0, 0.0);
    for t in act {
        let r = t.v - Vector2::new(qt.x, qt.y) - t.g * qt.z;
        let a = Vector2::new(d.x, d.y) + t.g * d.z;
        let phi = (r.norm_squared() + eps).sqrt();
        f += t.w * phi;
        df -= t.w * a.dot(&r) / phi;
    }
    LinePt { alpha, f, df }
}

/// A point of the search line `q + α d`: step, `φ(α) = U*(q + α d)`, `φ'(α)`.
#[derive(Clone, Copy, Debug)]
struct LinePt {
    alpha: f64,
    f: f64,
    df: f64,
}

/// Evaluation budget of one line minimisation (each costs one pass over the active vertices).
const LINE_MAX_EVALS: usize = 60;

/// Safeguarded minimisation of the convex `φ(α) = U*(q + α d)` over `α > 0`, given
/// `φ'(0) < 0`; returns the best point found (`α = 0` if none decreased `φ`).
///
/// The full step `α = 1` is taken as soon as it satisfies Armijo (Newton's local quadratic
/// convergence). Otherwise the minimiser is bracketed (`φ'(lo) < 0 ≤ φ'(hi)`, expanding by 4
/// when the step undershoots) and the bracket is shrunk with two candidates per round: the
/// secant root of `φ'` (exact for a quadratic) and the intersection of the tangents at `lo`
/// and `hi` (exact for a V; for a convex `φ` it lies in the bracket and the tangents' value
/// there is a lower bound on `min φ`). This matters because `√(‖r‖² + ε_v)` is a smoothed
/// norm: for relative speeds `≫ √ε_v` the inner objective is piecewise almost linear, and
/// its minimiser sits in a kink of width `√ε_v` (the plane sticking to one hull), which
/// Newton's quadratic model overshoots by orders of magnitude. It stops when the gap between
/// the best value and the lower bound is below 1% of the decrease achievable along the line,
/// or below the rounding of `U*`.
fn line_minimize(
    act: &[Active],
    q: &Vector3<f64>,
    d: &Vector3<f64>,
    f0: f64,
    df0: f64,
    eps: f64,
    value_noise: f64,
) -> LinePt {
    let start = LinePt {
        alpha: 0.0,
        f: f0,
        df: df0,
    };
    let mut best = start;
    let mut lo = start;
    let mut evals = 0;
    let mut alpha = 1.0;
    let mut hi = loop {
        let p = line_eval(act, q, d, alpha, eps);
        evals += 1;
        if alpha == 1.0 && p.f < f0 && p.f <= f0 + 1e-4 * df0 {
            return p;
        }
        if p.f < best.f {
            best = p;
        }
        if !p.f.is_finite() || !p.df.is_finite() || p.df >= 0.0 {
            break p;
        }
        lo = p;
        alpha *= 4.0;
        if evals >= LINE_MAX_EVALS || !alpha.is_finite() {
            return best;
        }
    };
    while evals < LINE_MAX_EVALS {
        let tangents = (hi.f - lo.f + lo.df * lo.alpha - hi.df * hi.alpha) / (lo.df - hi.df);
        let lower = lo.f + lo.df * (tangents - lo.alpha);
        if best.f - lower <= value_noise.max(0.01 * (f0 - lower)) {
            break;
        }
        if hi.alpha - lo.alpha <= 4.0 * f64::EPSILON * hi.alpha {
            break;
        }
        let secant = lo.alpha - lo.df * (hi.alpha - lo.alpha) / (hi.df - lo.df);
        for c in [tangents, secant] {
            // Non-finite or outside the (possibly already shrunk) bracket: bisect.
            let c = if c > lo.alpha && c < hi.alpha {
                c
            } else {
                0.5 * (lo.alpha + hi.alpha)
            };
            if c <= lo.alpha || c >= hi.alpha {
                break;
            }
            let p = line_eval(act, q, d, c, eps);
            evals += 1;
            if p.f < best.f {
                best = p;
            }
            if p.df < 0.0 {
                lo = p;
            } else {
                hi = p;
            }
        }
    }
    best
}

/// The best point on the "kink" of vertex `mi`: the set where the plane moves exactly with it
/// (`r_m = 0`, i.e. `u = ẋ_m − ω g_m`, a line in `(u, ω)`; a single point when spin-free),
/// provided the vertex can stick there.
///
/// `U*` restricted to the line is convex; it is minimised from the projection of `q` with
/// [`line_minimize`], started at the 1-D Newton step. Sticking to `m` is consistent only if
/// `m` can hold the plane against all the others: their net pull on `u`, `Σ_{k≠m} w_k ρ_k`,
/// must be weaker than `w_m` (the most `m` can exert, `‖w_m ρ_m‖ < w_m`). Otherwise the
/// minimiser is off this kink, and a point on it is a poor start for Newton (leaving a kink of
/// width `√ε_v` takes many steps), so `None` is returned.
fn kink_point(
    act: &[Active],
    mi: usize,
    q: &Vector3<f64>,
    eps: f64,
    spin_free: bool,
    value_noise: f64,
) -> Option<(Vector3<f64>, f64)> {
    let m = &act[mi];
    let sticks = |qk: &Vector3<f64>| {
        let pull: Vector2<f64> = act
            .iter()
            .enumerate()
            .filter(|(k, _)| *k != mi)
            .map(|(_, t)| {
                let r = t.v - Vector2::new(qk.x, qk.y) - t.g * qk.z;
                r * (t.w / (r.norm_squared() + eps).sqrt())
            })
            .sum();
        pull.norm() < m.w
    };
    let omega = if spin_free { 0.0 } else { q.z };
    let q0 = Vector3::new(m.v.x - m.g.x * omega, m.v.y - m.g.y * omega, omega);
    let f0 = line_eval(act, &q0, &Vector3::zeros(), 0.0, eps);
    if spin_free {
        return (f0.f.is_finite() && sticks(&q0)).then_some((q0, f0.f));
    }
    // Along the kink: d = (−g_m, 1). Curvature φ'' = Σ w (ε‖a‖² + (a × r)²)/φ³.
    let d = Vector3::new(-m.g.x, -m.g.y, 1.0);
    let (mut df, mut ddf) = (0.0, 0.0);
    for t in act {
        let r = t.v - Vector2::new(q0.x, q0.y) - t.g * q0.z;
        let a = Vector2::new(d.x, d.y) + t.g * d.z;
        let phi = (r.norm_squared() + eps).sqrt();
        df -= t.w * a.dot(&r) / phi;
        let cross = a.x * r.y - a.y * r.x;
        ddf += t.w * (eps * a.norm_squared() + cross * cross) / (phi * phi * phi);
    }
    let mut best = (q0, f0.f);
    if df != 0.0 && ddf > 0.0 && df.is_finite() && ddf.is_finite() {
        let d = d * (-df / ddf);
        let p = line_minimize(act, &q0, &d, f0.f, -df * df / ddf, eps, value_noise);
        if p.f < best.1 {
            best = (q0 + d * p.alpha, p.f);
        }
    }
    (best.1.is_finite() && sticks(&best.0)).then_some(best)
}

/// Kink candidates of [`kink_point`] for the two vertices most likely to hold the plane: the
/// one closest to sticking relative to its weight (largest `w_m/φ_m`) and the heaviest one
/// (under fast sliding the plane ends up sticking to the heavier side). Returns the better.
///
/// Under fast sliding the minimiser of `U*` typically sits on such a kink, within `√ε_v`.
/// Approaching it, Newton's model of the nearly conical `w √(‖r‖² + ε_v)` is poor across the
/// kink, and the iterate creeps towards it while sliding along it.
fn kink_candidate(
    act: &[Active],
    q: &Vector3<f64>,
    eps: f64,
    spin_free: bool,
    value_noise: f64,
) -> Option<(Vector3<f64>, f64)> {
    let argmax = |key: &dyn Fn(&Active) -> f64| {
        act.iter()
            .enumerate()
            .max_by(|x, y| key(x.1).total_cmp(&key(y.1)))
            .map(|(i, _)| i)
    };
    let closest = argmax(&|a: &Active| {
        let r = a.v - Vector2::new(q.x, q.y) - a.g * q.z;
        a.w / (r.norm_squared() + eps).sqrt()
    })?;
    let heaviest = argmax(&|a: &Active| a.w)?;
    let first = kink_point(act, closest, q, eps, spin_free, value_noise);
    if heaviest == closest {
        return first;
    }
    let second = kink_point(act, heaviest, q, eps, spin_free, value_noise);
    match (first, second) {
        (Some(a), Some(b)) => Some(if b.1 < a.1 { b } else { a }),
        (a, b) => a.or(b),
    }
}

/// Newton's method on `q = (u, ω)` with a safeguarded line minimisation (see
/// [`line_minimize`]) and the majorize–minimize step as a second, monotone candidate.
///
/// Stops when `‖∇U*‖ ≤ max(noise, min(tol, rtol · Σ w‖ρ‖(1 + ‖g‖)))`, or when no decrease of
/// `U*` is detectable any more *and* Newton's predicted decrease `½ gᵀH⁻¹g` is below the
/// rounding of `U*` (the iterate is at the noise floor: no representable step can improve
/// it). Anything else that stops progress is reported as non-convergence.
fn solve_inner(
    act: &[Active],
    spin_free: bool,
    params: &FrictionParams,
) -> Result<Core, FrictionError> {
    let eps = params.eps_velocity;
    let wsum: f64 = act.iter().map(|a| a.w).sum();
    if act.is_empty() || wsum.is_nan() || wsum <= 0.0 {
        return Ok(Core {
            q: Vector3::zeros(),
            spin_free: true,
            value: 0.0,
            hinv: Matrix3::zeros(),
            iterations: 0,
        });
    }
    // Start from the weighted mean tangential velocity, no spin.
    let ubar = act.iter().map(|a| a.w * a.v).sum::<Vector2<f64>>() / wsum;
    let mut q = Vector3::new(ubar.x, ubar.y, 0.0);
    let mut ev = inner_eval(act, &q, eps, spin_free);
    let mut iterations = 0;
    let done = |q: Vector3<f64>, ev: &InnerEval, iterations: usize| Core {
        q,
        spin_free,
        value: ev.value,
        hinv: inner_hessian_inverse(&ev.hess, spin_free),
        iterations,
    };
    loop {
        let gnorm = ev.grad.norm();
        let tol = ev
            .noise
            .max(params.inner_tol.min(params.inner_rtol * ev.scale));
        if gnorm <= tol {
            return Ok(done(q, &ev, iterations));
        }
        if iterations >= params.inner_max_iters {
            return Err(FrictionError::NotConverged {
                iterations,
                grad_norm: gnorm,
                tolerance: tol,
            });
        }
        iterations += 1;
        let mut dir = inner_direction(&ev.hess, &ev.grad, spin_free);
        let mut slope = ev.grad.dot(&dir);
        let newton = !(slope.is_nan() || slope >= 0.0);
        if !newton {
            dir = -ev.grad;
            slope = -gnorm * gnorm;
        }
        let p = line_minimize(act, &q, &dir, ev.value, slope, eps, ev.value_noise);
        let mut next = (p.alpha > 0.0 && p.f < ev.value).then(|| (q + dir * p.alpha, p.f));
        if p.alpha != 1.0 {
            // The full step failed: also try the majorize–minimize step (never increases U*)
            // and keep the better point.
            if let Some(qm) = mm_step(act, &q, eps, spin_free) {
                let vm = inner_value(act, &qm, eps);
                if vm < next.map_or(ev.value, |(_, v)| v) {
                    next = Some((qm, vm));
                }
            }
            // And the best point on the kink of a vertex that can hold the plane there.
            if let Some((qk, vk)) = kink_candidate(act, &q, eps, spin_free, ev.value_noise)
                && vk < next.map_or(ev.value, |(_, v)| v)
            {
                next = Some((qk, vk));
            }
        }
        if next.is_none() && (slope.abs() <= ev.value_noise) {
            // Predicted decrease below the rounding of U*: Armijo cannot decide. Accept the
            // full step if it does not increase U* beyond rounding and reduces the gradient.
            let trial = q + dir;
            let et = inner_eval(act, &trial, eps, spin_free);
            if et.value <= ev.value + ev.value_noise && et.grad.norm() < gnorm - ev.noise {
                q = trial;
                ev = et;
                continue;
            }
        }
        match next {
            Some((nq, _)) => {
                q = nq;
                ev = inner_eval(act, &nq, eps, spin_free);
            }
            None if newton && -0.5 * slope <= ev.value_noise => {
                // At the noise floor: Newton predicts a decrease below the rounding of U*.
                return Ok(done(q, &ev, iterations));
            }
            None => {
                return Err(FrictionError::NotConverged {
                    iterations,
                    grad_norm: gnorm,
                    tolerance: tol,
                });
            }
        }
    }
}

/// Result of [`friction_pair`].
#[derive(Clone, Debug, PartialEq)]
pub struct FrictionPair {
    /// `U_f` (energy; see the module docs for units).
    pub value: f64,
    /// Optimal in-plane plane velocity `u*` (coordinates in the basis `B`, m/s).
    pub u: Vector2<f64>,
    /// Optimal spin `ω*` about `n̂` through the contact-weighted centroid (rad/s); `0` when
    /// spin-free.
    pub omega: f64,
    /// `true` when `U*` is flat in `ω` (single contact point or all contact points on one
    /// normal line) and `ω` was dropped; also `true` when no vertex carries a normal force.
    pub spin_free: bool,
    /// Inner Newton iterations.
    pub iterations: usize,
    /// `∂U_f/∂A_a^{t+1}`.
    pub grad_a: Matrix3x4<f64>,
    /// `∂U_f/∂A_b^{t+1}`.
    pub grad_b: Matrix3x4<f64>,
    /// `∂²U_f/∂[vec A_a^{t+1}; vec A_b^{t+1}]²` when asked.
    pub hessian: Option<SMatrix<f64, 24, 24>>,
    /// `∂²U_f/∂A^{t+1}∂A^t` (rows `[vec A_a^{t+1}; vec A_b^{t+1}]`, columns
    /// `[vec A_a^t; vec A_b^t]`) for fixed lagged normal, basis and forces, when asked. The
    /// step-`t` vertices are `X^t = A^t [x_local; 1]` with the same local vertices.
    pub mixed: Option<SMatrix<f64, 24, 24>>,
}

fn cross_matrix(n: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -n.z, n.y, n.z, 0.0, -n.x, -n.y, n.x, 0.0)
}

/// Frictional-damping potential of a hull pair at the step-`t+1` poses `a`, `b` (the local
/// vertices must be the ones whose step-`t` world positions are in `frame`).
///
/// Cost: one pass over the normal forces plus work proportional to the number of vertices
/// with a non-zero normal force (only those are transformed and checked for finiteness; the
/// others do not enter `U_f`). Errors: invalid parameters or frame, length mismatches,
/// non-finite step-`t+1` positions of force-carrying vertices, inner non-convergence.
pub fn friction_pair(
    frame: &FrictionFrame<'_>,
    a: HullPose<'_>,
    b: HullPose<'_>,
    params: &FrictionParams,
    need: FrictionNeed,
    scratch: &mut FrictionScratch,
) -> Result<FrictionPair, FrictionError> {
    let poses = [a.pose, b.pose];
    let locals = [a.x_local, b.x_local];
    let next = |h: usize, m: usize| {
        let p = poses[h];
        p.fixed_columns::<3>(0) * locals[h][m] + p.column(3)
    };
    let spin_free = prepare(
        frame,
        &next,
        [a.x_local.len(), b.x_local.len()],
        params,
        &mut scratch.act,
    )?;
    let core = solve_inner(&scratch.act, spin_free, params)?;
    let mut out = FrictionPair {
        value: core.value,
        u: Vector2::new(core.q.x, core.q.y),
        omega: core.q.z,
        spin_free: core.spin_free,
        iterations: core.iterations,
        grad_a: Matrix3x4::zeros(),
        grad_b: Matrix3x4::zeros(),
        hessian: None,
        mixed: None,
    };
    if need == FrictionNeed::Value {
        return Ok(out);
    }
    let dt = params.dt;
    let eps = params.eps_velocity;
    let bm = frame.basis;
    let locals = [a.x_local, b.x_local];
    // Accumulators per hull: R = Σ x̃ (wρ)ᵀ (4×2); T_k = Σ w Φ_ij x̃x̃ᵀ for (ij) = 00, 01, 11;
    // P_c = Σ x̃_c w JᵀΦ (4 × (3×2)).
    let mut racc = [SMatrix::<f64, 4, 2>::zeros(); 2];
    let mut tacc = [[Matrix4::<f64>::zeros(); 3]; 2];
    let mut pacc = [[Matrix3x2::<f64>::zeros(); 4]; 2];
    let second = need >= FrictionNeed::Hessian;
    for act in &scratch.act {
        let (_, _, rho, bp) = vertex_terms(act, &core.q, eps);
        let xl = locals[act.hull][act.index];
        let xt = Vector4::new(xl.x, xl.y, xl.z, 1.0);
        racc[act.hull] += xt * (act.w * rho).transpose();
        if second {
            let outer = xt * xt.transpose();
            tacc[act.hull][0] += outer * (act.w * bp[(0, 0)]);
            tacc[act.hull][1] += outer * (act.w * bp[(0, 1)]);
            tacc[act.hull][2] += outer * (act.w * bp[(1, 1)]);
            let g = if core.spin_free {
                Vector2::zeros()
            } else {
                act.g
            };
            let pg = bp * g;
            let pm =
                Matrix3x2::new(bp[(0, 0)], bp[(0, 1)], bp[(1, 0)], bp[(1, 1)], pg.x, pg.y) * act.w;
            for c in 0..4 {
                pacc[act.hull][c] += pm * xt[c];
            }
        }
    }
    // ∂U/∂A_h = (1/Δt) B Rᵀ.
    out.grad_a = bm * racc[0].transpose() / dt;
    out.grad_b = bm * racc[1].transpose() / dt;
    if !second {
        return Ok(out);
    }
    let mut hess = SMatrix::<f64, 24, 24>::zeros();
    let mut cmat = SMatrix::<f64, 24, 3>::zeros();
    // b_i b_jᵀ for (ij) = 00, 01 (+10), 11.
    let b0 = bm.column(0).into_owned();
    let b1 = bm.column(1).into_owned();
    let bb = [
        b0 * b0.transpose(),
        b0 * b1.transpose() + b1 * b0.transpose(),
        b1 * b1.transpose(),
    ];
    for h in 0..2 {
        let off = 12 * h;
        for c in 0..4 {
            for c2 in 0..4 {
                let block = (bb[0] * tacc[h][0][(c, c2)]
                    + bb[1] * tacc[h][1][(c, c2)]
                    + bb[2] * tacc[h][2][(c, c2)])
                    / (dt * dt);
                hess.fixed_view_mut::<3, 3>(off + 3 * c, off + 3 * c2)
                    .copy_from(&block);
            }
            // C rows (c, ·) = −(1/Δt) B P_cᵀ.
            let crow = -(bm * pacc[h][c].transpose()) / dt;
            cmat.fixed_view_mut::<3, 3>(off + 3 * c, 0).copy_from(&crow);
        }
    }
    let hdiag = hess;
    let w = core.hinv * cmat.transpose(); // 3×24
    hess -= cmat * w;
    out.hessian = Some((hess + hess.transpose()) * 0.5);
    if need == FrictionNeed::HessianAndMixed {
        let nx = cross_matrix(&frame.normal);
        let qm = Matrix3::identity() / dt + nx * core.q.z;
        // Diagonal part −Δt Hdiag (I₄ ⊗ Q).
        let mut mixed = SMatrix::<f64, 24, 24>::zeros();
        for bi in 0..8 {
            for bj in 0..8 {
                let blk = hdiag.fixed_view::<3, 3>(3 * bi, 3 * bj) * qm * (-dt);
                mixed.fixed_view_mut::<3, 3>(3 * bi, 3 * bj).copy_from(&blk);
            }
        }
        // U*_{qX} in pose columns (h, c, r): P_c BᵀQ − e₃ (B R[c])ᵀ [n̂]×.
        let btq = bm.transpose() * qm;
        let mut qx = SMatrix::<f64, 3, 24>::zeros();
        for (h, (pacc_h, racc_h)) in pacc.iter().zip(&racc).enumerate() {
            for (c, pacc_hc) in pacc_h.iter().enumerate() {
                let mut blk = pacc_hc * btq;
                if !core.spin_free {
                    let brc = bm * racc_h.row(c).transpose();
                    let row = brc.transpose() * nx;
                    for r in 0..3 {
                        blk[(2, r)] -= row[r];
                    }
                }
                qx.fixed_view_mut::<3, 3>(0, 12 * h + 3 * c).copy_from(&blk);
            }
        }
        mixed -= cmat * (core.hinv * qx);
        out.mixed = Some(mixed);
    }
    Ok(out)
}

/// Result of [`friction_vertices`]: value and per-vertex gradient w.r.t. `X^{t+1}`, plus what
/// is needed to form dense second derivatives for tests.
#[derive(Clone, Debug, PartialEq)]
pub struct FrictionVertices {
    /// `U_f`.
    pub value: f64,
    /// `u*`.
    pub u: Vector2<f64>,
    /// `ω*`.
    pub omega: f64,
    /// See [`FrictionPair::spin_free`].
    pub spin_free: bool,
    /// Inner iterations.
    pub iterations: usize,
    /// `∂U_f/∂X_a^{t+1,m}` (the friction force on the vertex is its negative).
    pub grad_a: Vec<Vector3<f64>>,
    /// `∂U_f/∂X_b^{t+1,m}`.
    pub grad_b: Vec<Vector3<f64>>,
    terms: Vec<(usize, Active)>,
    hinv: Matrix3<f64>,
    normal: Vector3<f64>,
    basis: Matrix3x2<f64>,
    dt: f64,
    eps: f64,
    nverts: usize,
}

/// [`friction_pair`] for step-`t+1` vertices given directly in world coordinates.
/// Allocates its result: meant for tests and diagnostics.
pub fn friction_vertices(
    frame: &FrictionFrame<'_>,
    xa_next: &[Vector3<f64>],
    xb_next: &[Vector3<f64>],
    params: &FrictionParams,
    scratch: &mut FrictionScratch,
) -> Result<FrictionVertices, FrictionError> {
    for (hull, xs) in [(Hull::A, xa_next), (Hull::B, xb_next)] {
        if let Some(index) = xs.iter().position(|x| !x.iter().all(|v| v.is_finite())) {
            return Err(FrictionError::NonFiniteVertex { hull, index });
        }
    }
    let sides = [xa_next, xb_next];
    let next = |h: usize, m: usize| sides[h][m];
    let spin_free = prepare(
        frame,
        &next,
        [xa_next.len(), xb_next.len()],
        params,
        &mut scratch.act,
    )?;
    let core = solve_inner(&scratch.act, spin_free, params)?;
    let mut grad_a = vec![Vector3::zeros(); xa_next.len()];
    let mut grad_b = vec![Vector3::zeros(); xb_next.len()];
    let mut terms = Vec::with_capacity(scratch.act.len());
    for act in &scratch.act {
        let (_, _, rho, _) = vertex_terms(act, &core.q, params.eps_velocity);
        let g = frame.basis * rho * (act.w / params.dt);
        if act.hull == 0 {
            grad_a[act.index] = g;
        } else {
            grad_b[act.index] = g;
        }
        let global = if act.hull == 0 {
            act.index
        } else {
            xa_next.len() + act.index
        };
        terms.push((global, *act));
    }
    Ok(FrictionVertices {
        value: core.value,
        u: Vector2::new(core.q.x, core.q.y),
        omega: core.q.z,
        spin_free: core.spin_free,
        iterations: core.iterations,
        grad_a,
        grad_b,
        terms,
        hinv: core.hinv,
        normal: frame.normal,
        basis: frame.basis,
        dt: params.dt,
        eps: params.eps_velocity,
        nverts: xa_next.len() + xb_next.len(),
    })
}

/// Per active vertex: global index, `M_m`, `C_m = U*_{X'_m q}`, `U*_{q X_m}`.
type VertexBlocks = (usize, Matrix3<f64>, Matrix3<f64>, Matrix3<f64>);

impl FrictionVertices {
    fn q(&self) -> Vector3<f64> {
        Vector3::new(self.u.x, self.u.y, self.omega)
    }

    /// Per active vertex: (global index, M_m = (w/Δt²)BΦBᵀ, C_m = −(w/Δt)BΦJ, U*_{qX,m}).
    fn blocks(&self) -> Vec<VertexBlocks> {
        let q = self.q();
        let (b, dt) = (self.basis, self.dt);
        let nx = cross_matrix(&self.normal);
        let qm = Matrix3::identity() / dt + nx * q.z;
        self.terms
            .iter()
            .map(|(gi, act)| {
                let (_, _, rho, bp) = vertex_terms(act, &q, self.eps);
                let g = if self.spin_free {
                    Vector2::zeros()
                } else {
                    act.g
                };
                let mut jm = SMatrix::<f64, 2, 3>::zeros();
                jm[(0, 0)] = 1.0;
                jm[(1, 1)] = 1.0;
                jm[(0, 2)] = g.x;
                jm[(1, 2)] = g.y;
                let m = b * bp * b.transpose() * (act.w / (dt * dt));
                let c = -(b * bp * jm) * (act.w / dt);
                let mut qx = jm.transpose() * bp * b.transpose() * qm * act.w;
                if !self.spin_free {
                    let row = (b * rho * act.w).transpose() * nx;
                    for r in 0..3 {
                        qx[(2, r)] -= row[r];
                    }
                }
                (*gi, m, c, qx)
            })
            .collect()
    }

    /// Dense `∂²U_f/∂(X^{t+1})²` over `[X_a; X_b]` (3 rows per vertex). Tests only.
    pub fn dense_hessian(&self) -> DMatrix<f64> {
        let n = 3 * self.nverts;
        let mut h = DMatrix::zeros(n, n);
        let mut c = DMatrix::zeros(n, 3);
        for (gi, m, cm, _) in self.blocks() {
            h.view_mut((3 * gi, 3 * gi), (3, 3)).copy_from(&m);
            c.view_mut((3 * gi, 0), (3, 3)).copy_from(&cm);
        }
        let hinv = DMatrix::from_iterator(3, 3, self.hinv.iter().copied());
        h - &c * hinv * c.transpose()
    }

    /// Dense mixed `∂²U_f/∂X^{t+1}∂X^t` (rows `X^{t+1}`, columns `X^t`, both `[a; b]`) for fixed
    /// lagged normal, basis and forces. Tests only.
    pub fn dense_mixed(&self) -> DMatrix<f64> {
        let n = 3 * self.nverts;
        let q = self.q();
        let nx = cross_matrix(&self.normal);
        let qm = Matrix3::identity() / self.dt + nx * q.z;
        let mut mx = DMatrix::zeros(n, n);
        let mut c = DMatrix::zeros(n, 3);
        let mut qx = DMatrix::zeros(3, n);
        for (gi, m, cm, qxm) in self.blocks() {
            let d = -(m * qm) * self.dt;
            mx.view_mut((3 * gi, 3 * gi), (3, 3)).copy_from(&d);
            c.view_mut((3 * gi, 0), (3, 3)).copy_from(&cm);
            qx.view_mut((0, 3 * gi), (3, 3)).copy_from(&qxm);
        }
        let hinv = DMatrix::from_iterator(3, 3, self.hinv.iter().copied());
        mx - &c * hinv * qx
    }
}
