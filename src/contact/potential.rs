//! The contact potential `U_c` of a pair of convex hulls and its derivatives (paper
//! §"Contact Mechanics for Convex Polyhedrons"; proofs in Appendix "Well-defined Contact
//! Potential", `sec:ContactProof`).
//!
//! ```text
//! U_c(X) = min_p U*(X, p),
//! U*(X, p) = P_s(1 − ‖n‖) + Σ_{m∈a} P_s(−(n·X_a^m + o)) + Σ_{m∈b} P_s(n·X_b^m + o)
//! ```
//!
//! # Derivatives (envelope theorem and implicit function theorem, paper Eqs. `derivative`,
//! `derivative2`)
//!
//! With `y_m = σ_m (n·X_m + o)` (`σ = −1` on `a`, `+1` on `b`) and `x̃ = [X; 1]`:
//!
//! ```text
//! ∂U_c/∂X_m        = σ_m P'(y_m) n                                (at p*)
//! U*_{X_m X_m}     = P''(y_m) n nᵀ             (no coupling between different vertices)
//! U*_{X_m p}       = P''(y_m) n x̃_mᵀ + σ_m P'(y_m) [I₃ 0]        (3×4)
//! ∂²U_c/∂X²        = U*_XX − U*_Xp (U*_pp)⁻¹ U*_pX
//! ```
//!
//! The per-vertex normal force is `f_⊥^m = −∂U_c/∂X_m = −σ_m P'(y_m) n*`; its magnitude is
//! `|P'(y_m)| ‖n*‖` (note `‖n*‖ < 1`).
//!
//! # Pose contraction
//!
//! A vertex of a link is `X = A x̃` with `A = [R | t]` (3×4) and `x̃ = [x_local; 1]`, so
//! `∂X/∂vec(A) = x̃ᵀ ⊗ I₃` (column-major `vec`, index `c·3 + r`). Per hull `h`, with the
//! accumulators `k_h = Σ_m σ P'_m x̃_m` and `S_h = Σ_m P''_m x̃_m x̃_mᵀ` (local `x̃`):
//!
//! ```text
//! ∂U_c/∂A_h                  = n k_hᵀ                                  (3×4)
//! Σ_m (x̃x̃ᵀ) ⊗ (P''_m n nᵀ)  = S_h ⊗ (n nᵀ)                            (12×12 block)
//! B_h[(c,r), j]             = n_r (S_h T_hᵀ)[c, j] + δ_rj k_h[c]      (12×4, j < 3)
//! ∂²U_c/∂A²                 = blockdiag(S_a ⊗ nnᵀ, S_b ⊗ nnᵀ) − B (U*_pp)⁻¹ Bᵀ
//! ```
//!
//! where `T_h = [A_h; 0 0 0 1]` maps local to (shifted) world homogeneous coordinates, so that
//! `Σ_m P''_m x̃_local x̃_worldᵀ = S_h T_hᵀ`. The cost is one pass over the vertices with
//! ~30 flops each plus a fixed 24×24 assembly; no (3M)×(3M) matrix is ever formed.
//!
//! # Support (Lemma `contactBasic` iii)
//!
//! If `dist(a, b) ≥ 2s/(1−s)` then `U_c = 0` exactly: take the mid-plane between the closest
//! points `x_a, x_b` with `n = (1−s)(x_b − x_a)/‖x_b − x_a‖` and `o = −n·(x_a + x_b)/2`. Then
//! `P_s(1 − ‖n‖) = P_s(s) = 0`, and every vertex lies at distance ≥ `dist/2 ≥ s/(1−s)` from that
//! plane on its own side (the closest-point bisector of two convex sets separates them), so
//! every barrier argument is `≥ (1−s) · s/(1−s) = s` and contributes 0. Since `U* ≥ 0`, this
//! plane is a minimiser. (The paper's proof has two typos: the denominator must be
//! `‖x_b − x_a‖` and `o` carries no second `(1−s)` factor.) Conversely, if
//! `dist < 2s/(1−s)` then `U_c > 0`: a zero value would need `‖n‖ ≤ 1 − s` and all vertices at
//! distance `≥ s/‖n‖ ≥ s/(1−s)` from the plane on both sides.
//!
//! This module uses the *certified* gap `min_b d·X_b − max_a d·X_a` along GJK's direction `d`
//! (a lower bound on the distance, see the `separation` module): when it is `≥ 2s/(1−s)`
//! the construction above applies verbatim with the two support planes and the outcome is
//! [`PairOutcome::OutOfRange`] with `U_c = 0` exactly.

use nalgebra::{DMatrix, Matrix3x4, Matrix4, SMatrix, Vector3, Vector4};
use parry3d_f64::query::gjk::VoronoiSimplex;

use super::barrier::barrier_d2;
use super::error::{ContactError, Hull};
use super::plane::{self, PlaneSolution, PlaneSolveSettings};
use super::separation::{Separation, separate, supports_along};

/// Parameters of the contact potential.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactParams {
    /// Barrier width `s ∈ (0, 1)`, a length in scene units. It is also the bound on
    /// `1 − ‖n‖`, so scenes must be scaled such that `s < 1` is meaningful (e.g. metres with
    /// `s` of a few millimetres to centimetres). The potential is non-zero only when two hulls
    /// are closer than `2s/(1−s)`. Default `1e-2` (1 cm in metre-scaled scenes).
    pub s: f64,
    /// Absolute tolerance on `‖∇_p U*‖` of the inner plane solve. Default `1e-8`.
    /// It is honoured whenever it is above the rounding-noise floor of the gradient (see
    /// `plane` module docs).
    pub inner_tol: f64,
    /// Relative tolerance on `‖∇_p U*‖`, relative to the total magnitude of the barrier forces
    /// acting on the plane. It takes over when the potential is tiny (near the edge of the
    /// support), where the absolute tolerance would stop too early. Default `1e-10`.
    pub inner_rtol: f64,
    /// Iteration cap of the inner Newton solve. Default `100` (typically 3–15 are used).
    pub inner_max_iters: usize,
}

impl Default for ContactParams {
    fn default() -> Self {
        Self {
            s: 1e-2,
            inner_tol: 1e-8,
            inner_rtol: 1e-10,
            inner_max_iters: 100,
        }
    }
}

impl ContactParams {
    /// Parameters with barrier width `s` and default solver settings.
    pub fn with_width(s: f64) -> Self {
        Self {
            s,
            ..Self::default()
        }
    }

    /// `2s/(1−s)`: pairs at least this far apart have `U_c = 0` exactly. Inflate broad-phase
    /// boxes by this distance.
    pub fn support_distance(&self) -> f64 {
        2.0 * self.s / (1.0 - self.s)
    }

    /// Checks `0 < s < 1` and the solver settings.
    pub fn validate(&self) -> Result<(), ContactError> {
        if !(self.s > 0.0 && self.s < 1.0) {
            return Err(ContactError::InvalidWidth { s: self.s });
        }
        let nonneg = |x: f64| x.is_finite() && x >= 0.0;
        if !nonneg(self.inner_tol) || !nonneg(self.inner_rtol) || self.inner_max_iters == 0 {
            return Err(ContactError::InvalidSolverSettings {
                tol: self.inner_tol,
                rtol: self.inner_rtol,
                max_iters: self.inner_max_iters,
            });
        }
        Ok(())
    }

    fn settings(&self) -> PlaneSolveSettings {
        PlaneSolveSettings {
            s: self.s,
            tol: self.inner_tol,
            rtol: self.inner_rtol,
            max_iters: self.inner_max_iters,
        }
    }
}

pub use crate::geometry::HullPose;

/// Which derivatives to compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Need {
    /// Value only (line searches).
    Value,
    /// Value and gradient.
    Gradient,
    /// Value, gradient and Hessian.
    Hessian,
}

/// Reusable per-pair buffers (world vertices of both hulls and GJK storage). Create one per
/// thread and pass it to every call; it grows to the largest hull seen and never shrinks.
#[derive(Clone, Debug, Default)]
pub struct ContactScratch {
    xa: Vec<Vector3<f64>>,
    xb: Vec<Vector3<f64>>,
    simplex: Option<VoronoiSimplex>,
}

impl ContactScratch {
    /// Empty scratch.
    pub fn new() -> Self {
        Self::default()
    }
}

/// Result of evaluating a separated pair within range.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactPair {
    /// `U_c` (unscaled: the simulator multiplies by the stiffness κ).
    pub value: f64,
    /// Optimal plane `p* = (n*, o*)` in world coordinates: `n*·X + o* < 0` on hull `a`,
    /// `> 0` on hull `b`, `‖n*‖ < 1`. Pass it back as the warm start of the next call.
    pub plane: Vector4<f64>,
    /// A lower bound of the distance between the hulls: GJK's estimate on a
    /// cold start; from a strictly feasible warm plane (no GJK), the gap of
    /// the slab along its normal.
    pub distance: f64,
    /// Inner Newton iterations used.
    pub iterations: usize,
    /// `∂U_c/∂A_a` (zero unless [`Need::Gradient`] or more was asked).
    pub grad_a: Matrix3x4<f64>,
    /// `∂U_c/∂A_b` (zero unless [`Need::Gradient`] or more was asked).
    pub grad_b: Matrix3x4<f64>,
    /// `∂²U_c/∂[vec A_a; vec A_b]²` when [`Need::Hessian`] was asked.
    pub hessian: Option<Box<SMatrix<f64, 24, 24>>>,
}

/// Outcome of [`contact_pair`].
#[derive(Clone, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)] // ≈ 260 bytes: the 24×24 Hessian (4.6 KB) is boxed, as the
// per-pair results are stored and moved in bulk (moving it inline was a fifth of a spider step)
pub enum PairOutcome {
    /// Touching or overlapping (or closer than GJK resolves): the caller treats this as
    /// `U_c = +∞` (e.g. rejects the line-search trial point).
    Intersecting,
    /// Certified gap `≥ 2s/(1−s)`: `U_c = 0` and all derivatives vanish exactly.
    OutOfRange {
        /// A lower bound of the distance (see [`ContactPair::distance`]).
        distance: f64,
        /// A strictly feasible plane certifying the gap (world frame, the
        /// mid-plane of the slab with `‖n‖ = 1 − s`). Pass it back as the warm
        /// start: the next call re-certifies the gap along its normal without
        /// GJK while the pair stays out of range.
        plane: Vector4<f64>,
    },
    /// Separated and within range: value, plane and derivatives.
    Separated(ContactPair),
}

impl PairOutcome {
    /// `U_c` with `+∞` for intersecting pairs.
    pub fn value(&self) -> f64 {
        match self {
            PairOutcome::Intersecting => f64::INFINITY,
            PairOutcome::OutOfRange { .. } => 0.0,
            PairOutcome::Separated(c) => c.value,
        }
    }
}

impl ContactPair {
    /// Unnormalised plane normal `n*` (`‖n*‖ < 1`), pointing from `a` to `b`.
    pub fn normal(&self) -> Vector3<f64> {
        self.plane.fixed_rows::<3>(0).into_owned()
    }

    /// Per-vertex normal forces `f_⊥^m = −∂U_c/∂X^m = −σ_m P_s'(y_m) n*` (unscaled, world
    /// frame) written into the caller's buffers (cleared first; no allocation once they have
    /// grown). Hull `a` is pushed towards `−n*`, hull `b` towards `+n*`.
    pub fn normal_forces_into(
        &self,
        a: HullPose<'_>,
        b: HullPose<'_>,
        s: f64,
        out_a: &mut Vec<Vector3<f64>>,
        out_b: &mut Vec<Vector3<f64>>,
    ) {
        let n = self.normal();
        let o = self.plane.w;
        for (h, sigma, out) in [(a, -1.0, out_a), (b, 1.0, out_b)] {
            out.clear();
            for x in h.x_local {
                let xw = h.pose.fixed_columns::<3>(0) * x + h.pose.column(3);
                let y = sigma * (n.dot(&xw) + o);
                let (_, d1, _) = barrier_d2(y, s);
                out.push(-sigma * d1 * n);
            }
        }
    }
}

/// What the inner solve produced, in the shifted frame.
#[allow(clippy::large_enum_variant)] // short-lived stack value
enum Core {
    Intersecting,
    OutOfRange { distance: f64, plane: Vector4<f64> },
    Separated { sol: PlaneSolution, distance: f64 },
}

/// Outcome of the separation test: the starting plane of the inner solve, in the shifted frame.
enum Start {
    Intersecting,
    OutOfRange { distance: f64, plane: Vector4<f64> },
    Plane { p: Vector4<f64>, distance: f64 },
}

/// Separation test and initial plane choice on shifted vertex buffers.
fn start_plane(
    xa: &[Vector3<f64>],
    xb: &[Vector3<f64>],
    c0: &Vector3<f64>,
    params: &ContactParams,
    warm_plane: Option<Vector4<f64>>,
    simplex: &mut VoronoiSimplex,
) -> Result<Start, ContactError> {
    let s = params.s;
    let hint = warm_plane.map(|p| Vector3::new(p.x, p.y, p.z));
    // A strictly feasible warm plane (shifted into the local frame:
    // n·X + o = n·(X − c0) + (o + n·c0)) is itself a certificate of separation.
    let warm = warm_plane
        .map(|w| Vector4::new(w.x, w.y, w.z, w.w + Vector3::new(w.x, w.y, w.z).dot(c0)))
        .filter(|w| w.iter().all(|v| v.is_finite()))
        .map(|w| (w, plane::value(xa, xb, &w, s)))
        .filter(|(_, v)| v.is_finite());
    // A strictly feasible warm plane separates the hulls: no GJK. The slab
    // along its normal `d` (gap `min_b − max_a`, a lower bound of the
    // distance) certifies the out-of-range case, and the plane is the start.
    if let Some((w, _)) = warm {
        let d = Vector3::new(w.x, w.y, w.z).normalize();
        let (max_a, min_b) = supports_along(xa, xb, &d);
        let gap = min_b - max_a;
        if gap >= params.support_distance() {
            return Ok(Start::OutOfRange {
                distance: gap,
                plane: w,
            });
        }
        return Ok(Start::Plane {
            p: w,
            distance: gap,
        });
    }
    match separate(xa, xb, hint, simplex)? {
        Separation::Separated {
            dir,
            max_a,
            min_b,
            distance,
        } => {
            // Cold start: the mid-plane of the certified slab with ‖n‖ = 1 − s (strictly
            // feasible: every barrier argument is ≥ (1 − s)(min_b − max_a)/2 > 0).
            let n = dir * (1.0 - s);
            let p = Vector4::new(n.x, n.y, n.z, -(1.0 - s) * 0.5 * (max_a + min_b));
            if min_b - max_a >= params.support_distance() {
                return Ok(Start::OutOfRange { distance, plane: p });
            }
            Ok(Start::Plane { p, distance })
        }
        // GJK cannot resolve gaps below ~1e-8 × hull size; without a feasible warm plane
        // to prove separation, the pair counts as intersecting.
        Separation::Intersecting => Ok(Start::Intersecting),
    }
}

/// `P''`-weighted centroid of the vertices at plane `p` (shifted frame): the "centre of
/// stiffness" of the barrier terms. `None` if no vertex is within the support or the weights
/// overflow.
fn stiffness_centre(
    xa: &[Vector3<f64>],
    xb: &[Vector3<f64>],
    p: &Vector4<f64>,
    s: f64,
) -> Option<Vector3<f64>> {
    let n = Vector3::new(p.x, p.y, p.z);
    let (mut w, mut c) = (0.0, Vector3::zeros());
    for (xs, sigma) in [(xa, -1.0), (xb, 1.0)] {
        for x in xs {
            let y = sigma * (n.dot(x) + p.w);
            if y < s {
                let (_, _, d2) = barrier_d2(y, s);
                w += d2;
                c += x * d2;
            }
        }
    }
    let c = c / w;
    (w > 0.0 && c.iter().all(|v| v.is_finite())).then_some(c)
}

/// Separation test, initial plane, re-centring and inner Newton. Fills `scratch` with the
/// world vertices shifted by the returned origin `c0`, the frame of the returned plane.
///
/// Re-centring: the vertices are first shifted by the midpoint of the two vertex centroids
/// (for GJK), then — once the starting plane is known — by its centre of stiffness
/// (`stiffness_centre`). Near contact the barrier curvature `P''(y) x̃ x̃ᵀ` of the few closest
/// vertices exceeds everything else by many decades; with an origin a lever `ℓ` away from
/// them it couples `n` and `o` by `P'' ℓ`, and a plane that must turn about the contact point
/// asks Newton to resolve that coupling to the last bits (it crawled, hitting the feasibility
/// boundary, on mirror-symmetric vertex–vertex contacts 0.1 m from the centroids). About the
/// centre of stiffness the coupling vanishes to first order. `U_c` and its derivatives do not
/// depend on the origin; it only changes rounding.
fn solve_core<IA, IB>(
    scratch: &mut ContactScratch,
    world_a: impl Fn() -> IA,
    world_b: impl Fn() -> IB,
    params: &ContactParams,
    warm_plane: Option<Vector4<f64>>,
) -> Result<(Core, Vector3<f64>), ContactError>
where
    IA: Iterator<Item = Vector3<f64>>,
    IB: Iterator<Item = Vector3<f64>>,
{
    let c0 = fill_shifted(scratch, world_a(), world_b())?;
    let mut simplex = scratch.simplex.take().unwrap_or_default();
    let start = start_plane(
        &scratch.xa,
        &scratch.xb,
        &c0,
        params,
        warm_plane,
        &mut simplex,
    );
    scratch.simplex = Some(simplex);
    let (mut p, distance) = match start? {
        Start::Intersecting => return Ok((Core::Intersecting, c0)),
        Start::OutOfRange { distance, plane } => {
            return Ok((Core::OutOfRange { distance, plane }, c0));
        }
        Start::Plane { p, distance } => (p, distance),
    };
    let s = params.s;
    let mut c0 = c0;
    if let Some(c) = stiffness_centre(&scratch.xa, &scratch.xb, &p, s) {
        let c1 = c0 + c;
        shift(scratch, world_a(), world_b(), &c1);
        // n·(X − c0) + o = n·(X − c1) + (o + n·(c1 − c0)).
        let n = Vector3::new(p.x, p.y, p.z);
        let p1 = Vector4::new(p.x, p.y, p.z, p.w + n.dot(&(c1 - c0)));
        if plane::value(&scratch.xa, &scratch.xb, &p1, s).is_finite() {
            (p, c0) = (p1, c1);
        } else {
            // Rounding of the new shift made a barely feasible start infeasible: keep the
            // original frame (same arithmetic, same bits).
            shift(scratch, world_a(), world_b(), &c0);
        }
    }
    match plane::solve(&scratch.xa, &scratch.xb, p, &params.settings()) {
        Ok(sol) => Ok((Core::Separated { sol, distance }, c0)),
        // A warm plane can be a poor start at the edge of the support: with the pair within a
        // fraction of a percent of `2s/(1−s)`, every barrier argument is close to `s`, `U*` is
        // tiny and nearly flat in the plane's orientation, and Newton turns a badly oriented
        // warm plane so slowly that it reaches the iteration cap (issue 30, the single jaw's
        // cross: seven captures at 0.9985–1.0001 of the support distance, each crawling through
        // 100 iterations from its warm plane; from GJK's closest direction each converged in 6–7
        // iterations or was certified out of range). Such a failure is retried once from the
        // cold start; a solve that converges from its warm plane is unchanged.
        Err(
            ContactError::PlaneNotConverged { .. } | ContactError::PlaneLineSearchStalled { .. },
        ) if warm_plane.is_some() => solve_core(scratch, world_a, world_b, params, None),
        Err(e) => Err(e),
    }
}

/// Inverse of the (symmetric positive semi-definite) plane Hessian `U*_pp`: Cholesky when it
/// is numerically definite, otherwise an eigenvalue pseudo-inverse. The latter only happens
/// when the potential is numerically zero (all `P''` vanish or underflow), where the Schur
/// term it multiplies vanishes as well (paper Lemma `contactHessianVanish`).
pub(crate) fn plane_hessian_inverse(h: &Matrix4<f64>) -> Matrix4<f64> {
    if let Some(ch) = h.cholesky() {
        let inv = ch.inverse();
        if inv.iter().all(|v| v.is_finite()) {
            return inv;
        }
    }
    let eig = h.symmetric_eigen();
    let maxe = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut inv = Matrix4::zeros();
    for i in 0..4 {
        let l = eig.eigenvalues[i];
        if l > 1e-13 * maxe && l > 0.0 {
            let v = eig.eigenvectors.column(i);
            inv += v * v.transpose() / l;
        }
    }
    inv
}

fn check_finite(x: &[Vector3<f64>], hull: Hull) -> Result<(), ContactError> {
    for (index, v) in x.iter().enumerate() {
        if !v.iter().all(|c| c.is_finite()) {
            return Err(ContactError::NonFiniteVertex {
                hull,
                index,
                value: [v.x, v.y, v.z],
            });
        }
    }
    Ok(())
}

/// Fills the scratch with world vertices shifted by the midpoint of the two centroids and
/// returns that origin.
fn fill_shifted(
    scratch: &mut ContactScratch,
    a: impl Iterator<Item = Vector3<f64>>,
    b: impl Iterator<Item = Vector3<f64>>,
) -> Result<Vector3<f64>, ContactError> {
    scratch.xa.clear();
    scratch.xa.extend(a);
    scratch.xb.clear();
    scratch.xb.extend(b);
    if scratch.xa.is_empty() {
        return Err(ContactError::EmptyHull { hull: Hull::A });
    }
    if scratch.xb.is_empty() {
        return Err(ContactError::EmptyHull { hull: Hull::B });
    }
    check_finite(&scratch.xa, Hull::A)?;
    check_finite(&scratch.xb, Hull::B)?;
    let ca = scratch.xa.iter().sum::<Vector3<f64>>() / scratch.xa.len() as f64;
    let cb = scratch.xb.iter().sum::<Vector3<f64>>() / scratch.xb.len() as f64;
    let c0 = 0.5 * (ca + cb);
    for x in scratch.xa.iter_mut().chain(scratch.xb.iter_mut()) {
        *x -= c0;
    }
    Ok(c0)
}

/// Refills the scratch with the (already checked) world vertices shifted by `c0`.
fn shift(
    scratch: &mut ContactScratch,
    a: impl Iterator<Item = Vector3<f64>>,
    b: impl Iterator<Item = Vector3<f64>>,
    c0: &Vector3<f64>,
) {
    scratch.xa.clear();
    scratch.xa.extend(a.map(|x| x - c0));
    scratch.xb.clear();
    scratch.xb.extend(b.map(|x| x - c0));
}

/// World positions `R x + t` of a posed hull.
fn world_iter<'a>(h: HullPose<'a>) -> impl Iterator<Item = Vector3<f64>> + 'a {
    let r = h.pose.fixed_columns::<3>(0).into_owned();
    let t: Vector3<f64> = h.pose.column(3).into_owned();
    h.x_local.iter().map(move |x| r * x + t)
}

/// World plane from the shifted one.
fn world_plane(p: &Vector4<f64>, c0: &Vector3<f64>) -> Vector4<f64> {
    let n = Vector3::new(p.x, p.y, p.z);
    Vector4::new(p.x, p.y, p.z, p.w - n.dot(c0))
}

/// Contact potential `U_c` of hull `a` (negative side) and hull `b` (positive side) with
/// derivatives w.r.t. the two poses.
///
/// Steps: exact separation test (GJK + certified gap), then either [`PairOutcome::Intersecting`],
/// [`PairOutcome::OutOfRange`] (certified gap `≥ 2s/(1−s)`, `U_c = 0`), or an inner Newton
/// solve for `p*` from the mid-plane of the certified slab scaled to `‖n‖ = 1 − s`, or from
/// `warm_plane` (world coordinates) when that plane is strictly feasible and not worse.
/// Derivatives follow from the envelope and implicit-function theorems (module docs).
///
/// "Touching" includes gaps below GJK's resolution (about `1e-8 ×` hull size): those pairs are
/// [`PairOutcome::Intersecting`] unless `warm_plane` is strictly feasible, which proves
/// separation; then the solve proceeds from it.
///
/// Any number of vertices `≥ 1` per hull is accepted (the body is their convex hull; four
/// non-coplanar points are not required by the algorithm). Cost: `O(M)` per GJK iteration and
/// per Newton iteration (typically 5–10), plus a fixed 24×24 assembly for the Hessian.
///
/// Errors: invalid parameters, empty hulls, non-finite vertices, GJK failure, or inner
/// non-convergence — never a panic or NaN.
pub fn contact_pair(
    a: HullPose<'_>,
    b: HullPose<'_>,
    params: &ContactParams,
    warm_plane: Option<Vector4<f64>>,
    need: Need,
    scratch: &mut ContactScratch,
) -> Result<PairOutcome, ContactError> {
    params.validate()?;
    let (core, c0) = solve_core(
        scratch,
        || world_iter(a),
        || world_iter(b),
        params,
        warm_plane,
    )?;
    pair_outcome(a, b, params, need, scratch, core, c0)
}

/// A hull with its world vertices already computed: `world[i] = R x_local[i] + t` in the
/// bits of the internal transform (e.g. by [`crate::math::transform_point`]:
/// `transform_point_has_the_bits_of_world_iter`). `hull` still carries the link pose and the
/// link-frame vertices for the pose-contracted derivatives.
#[derive(Clone, Copy, Debug)]
pub struct PlacedHull<'a> {
    /// The link pose `A = [R | t]` and the link-frame vertices `x_local`.
    pub hull: HullPose<'a>,
    /// The world vertices `X = A x_local`, one per entry of `hull.x_local` (world frame, m).
    pub world: &'a [Vector3<f64>],
}

/// [`contact_pair`] on hulls whose world vertices the caller already has ([`PlacedHull`]), so
/// they are not transformed again. The result is bit for bit [`contact_pair`]'s when the world
/// vertices are the bits of `R x + t`.
pub fn contact_pair_world(
    a: PlacedHull<'_>,
    b: PlacedHull<'_>,
    params: &ContactParams,
    warm_plane: Option<Vector4<f64>>,
    need: Need,
    scratch: &mut ContactScratch,
) -> Result<PairOutcome, ContactError> {
    params.validate()?;
    let (core, c0) = solve_core(
        scratch,
        || a.world.iter().copied(),
        || b.world.iter().copied(),
        params,
        warm_plane,
    )?;
    let (a, b) = (a.hull, b.hull);
    pair_outcome(a, b, params, need, scratch, core, c0)
}

/// The outcome of a solved pair with the derivatives `need` asks for (module docs, "Pose
/// contraction"): `∂U_c/∂A_h = n k_hᵀ` and the 24×24 Hessian
/// `blockdiag(S_h ⊗ nnᵀ) − B (U*_pp)⁻¹ Bᵀ`, from the shifted vertices in `scratch`.
fn pair_outcome(
    a: HullPose<'_>,
    b: HullPose<'_>,
    params: &ContactParams,
    need: Need,
    scratch: &ContactScratch,
    core: Core,
    c0: Vector3<f64>,
) -> Result<PairOutcome, ContactError> {
    let (sol, distance) = match core {
        Core::Intersecting => return Ok(PairOutcome::Intersecting),
        Core::OutOfRange { distance, plane } => {
            let plane = world_plane(&plane, &c0);
            return Ok(PairOutcome::OutOfRange { distance, plane });
        }
        Core::Separated { sol, distance } => (sol, distance),
    };
    let mut out = ContactPair {
        value: sol.eval.value,
        plane: world_plane(&sol.p, &c0),
        distance,
        iterations: sol.iterations,
        grad_a: Matrix3x4::zeros(),
        grad_b: Matrix3x4::zeros(),
        hessian: None,
    };
    if need == Need::Value {
        return Ok(PairOutcome::Separated(out));
    }
    let s = params.s;
    let n = Vector3::new(sol.p.x, sol.p.y, sol.p.z);
    let o = sol.p.w;
    // Per hull: k = Σ σ P' x̃, S = Σ P'' x̃ x̃ᵀ (local homogeneous coordinates).
    let mut k = [Vector4::<f64>::zeros(); 2];
    let mut sm = [Matrix4::<f64>::zeros(); 2];
    for (hi, (h, xs, sigma)) in [(a, &scratch.xa, -1.0), (b, &scratch.xb, 1.0)]
        .into_iter()
        .enumerate()
    {
        let (mut k0, mut k1, mut k2, mut k3) = (0.0, 0.0, 0.0, 0.0);
        let mut su = [0.0f64; 10];
        for (xl, xw) in h.x_local.iter().zip(xs.iter()) {
            let y = sigma * (n.dot(xw) + o);
            if y >= s {
                continue;
            }
            let (_, d1, d2) = barrier_d2(y, s);
            let g = sigma * d1;
            k0 += g * xl.x;
            k1 += g * xl.y;
            k2 += g * xl.z;
            k3 += g;
            if need == Need::Hessian {
                let (wx, wy, wz) = (d2 * xl.x, d2 * xl.y, d2 * xl.z);
                su[0] += wx * xl.x;
                su[1] += wx * xl.y;
                su[2] += wx * xl.z;
                su[3] += wx;
                su[4] += wy * xl.y;
                su[5] += wy * xl.z;
                su[6] += wy;
                su[7] += wz * xl.z;
                su[8] += wz;
                su[9] += d2;
            }
        }
        k[hi] = Vector4::new(k0, k1, k2, k3);
        sm[hi] = Matrix4::new(
            su[0], su[1], su[2], su[3], //
            su[1], su[4], su[5], su[6], //
            su[2], su[5], su[7], su[8], //
            su[3], su[6], su[8], su[9],
        );
    }
    out.grad_a = n * k[0].transpose();
    out.grad_b = n * k[1].transpose();
    if need == Need::Hessian {
        let mut bmat = SMatrix::<f64, 24, 4>::zeros();
        let nnt = n * n.transpose();
        for (hi, h) in [a, b].into_iter().enumerate() {
            let off = 12 * hi;
            // T_h = [A_h with translation shifted by −c0; 0 0 0 1].
            let mut t = Matrix4::<f64>::identity();
            t.fixed_view_mut::<3, 4>(0, 0).copy_from(h.pose);
            for r in 0..3 {
                t[(r, 3)] -= c0[r];
            }
            let kk = sm[hi] * t.transpose(); // Σ P'' x̃_local x̃_worldᵀ
            for c in 0..4 {
                for r in 0..3 {
                    let row = off + 3 * c + r;
                    for j in 0..4 {
                        bmat[(row, j)] = n[r] * kk[(c, j)];
                    }
                    bmat[(row, r)] += k[hi][c];
                }
            }
        }
        let hinv = plane_hessian_inverse(&sol.eval.hess);
        let w = hinv * bmat.transpose(); // 4×24
        // H = blockdiag(S_h ⊗ nnᵀ) − B W, written over the product B W in place: each entry is
        // the difference the zero-initialised `H −= B W` would round to (`0 − p` off the
        // diagonal blocks), bit for bit, without zero-filling 24×24 first.
        let mut hess = bmat * w;
        let entries = hess.as_mut_slice(); // column-major, 24 per column
        for (col, column) in entries.chunks_exact_mut(24).enumerate() {
            let (hc, c2, r2) = (col / 12, (col % 12) / 3, col % 3);
            for (hr, rows) in column.chunks_exact_mut(12).enumerate() {
                if hr != hc {
                    rows.iter_mut().for_each(|e| *e = 0.0 - *e);
                    continue;
                }
                for (c, rows_c) in rows.chunks_exact_mut(3).enumerate() {
                    let s_cc = sm[hr][(c, c2)];
                    for (r, e) in rows_c.iter_mut().enumerate() {
                        *e = s_cc * nnt[(r, r2)] - *e;
                    }
                }
            }
        }
        out.hessian = Some(crate::math::symmetric_part_boxed(&hess));
    }
    Ok(PairOutcome::Separated(out))
}

/// Result of [`contact_vertices`] for a separated pair within range.
#[derive(Clone, Debug, PartialEq)]
pub struct VertexContact {
    /// `U_c`.
    pub value: f64,
    /// Optimal plane in world coordinates.
    pub plane: Vector4<f64>,
    /// GJK distance estimate.
    pub distance: f64,
    /// Inner Newton iterations used.
    pub iterations: usize,
    /// `∂U_c/∂X_a^m` per vertex of `a` (world frame).
    pub grad_a: Vec<Vector3<f64>>,
    /// `∂U_c/∂X_b^m` per vertex of `b` (world frame).
    pub grad_b: Vec<Vector3<f64>>,
    /// Plane in the internal shifted frame and the shift (for [`VertexContact::dense_hessian`]).
    plane_local: Vector4<f64>,
    c0: Vector3<f64>,
    hpp: Matrix4<f64>,
    s: f64,
}

/// Outcome of [`contact_vertices`].
#[derive(Clone, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)] // returned by value, never stored in bulk
pub enum VertexOutcome {
    /// See [`PairOutcome::Intersecting`].
    Intersecting,
    /// See [`PairOutcome::OutOfRange`].
    OutOfRange {
        /// GJK distance estimate.
        distance: f64,
    },
    /// Separated and within range.
    Separated(VertexContact),
}

impl VertexOutcome {
    /// `U_c` with `+∞` for intersecting pairs.
    pub fn value(&self) -> f64 {
        match self {
            VertexOutcome::Intersecting => f64::INFINITY,
            VertexOutcome::OutOfRange { .. } => 0.0,
            VertexOutcome::Separated(c) => c.value,
        }
    }
}

/// [`contact_pair`] for vertices already in world coordinates, with the gradient per vertex.
/// Allocates its result vectors: meant for tests, diagnostics and callers that assemble
/// vertex-level derivatives themselves.
pub fn contact_vertices(
    xa_world: &[Vector3<f64>],
    xb_world: &[Vector3<f64>],
    params: &ContactParams,
    warm_plane: Option<Vector4<f64>>,
    scratch: &mut ContactScratch,
) -> Result<VertexOutcome, ContactError> {
    params.validate()?;
    let (core, c0) = solve_core(
        scratch,
        || xa_world.iter().copied(),
        || xb_world.iter().copied(),
        params,
        warm_plane,
    )?;
    let (sol, distance) = match core {
        Core::Intersecting => return Ok(VertexOutcome::Intersecting),
        Core::OutOfRange { distance, .. } => return Ok(VertexOutcome::OutOfRange { distance }),
        Core::Separated { sol, distance } => (sol, distance),
    };
    let n = Vector3::new(sol.p.x, sol.p.y, sol.p.z);
    let grad = |xs: &[Vector3<f64>], sigma: f64| -> Vec<Vector3<f64>> {
        xs.iter()
            .map(|x| {
                let y = sigma * (n.dot(x) + sol.p.w);
                let (_, d1, _) = barrier_d2(y, params.s);
                sigma * d1 * n
            })
            .collect()
    };
    Ok(VertexOutcome::Separated(VertexContact {
        value: sol.eval.value,
        plane: world_plane(&sol.p, &c0),
        distance,
        iterations: sol.iterations,
        grad_a: grad(&scratch.xa, -1.0),
        grad_b: grad(&scratch.xb, 1.0),
        plane_local: sol.p,
        c0,
        hpp: sol.eval.hess,
        s: params.s,
    }))
}

impl VertexContact {
    /// Dense `∂²U_c/∂X²` over `[X_a^1 … X_a^Ma, X_b^1 … X_b^Mb]` (3 rows per vertex), formed as
    /// `U*_XX − U*_Xp (U*_pp)⁻¹ U*_pX`. `O(M²)` memory: for tests and diagnostics only. The
    /// vertices must be the ones passed to [`contact_vertices`].
    pub fn dense_hessian(
        &self,
        xa_world: &[Vector3<f64>],
        xb_world: &[Vector3<f64>],
    ) -> DMatrix<f64> {
        let nv = xa_world.len() + xb_world.len();
        let n = Vector3::new(self.plane_local.x, self.plane_local.y, self.plane_local.z);
        let o = self.plane_local.w;
        let mut h = DMatrix::zeros(3 * nv, 3 * nv);
        let mut c = DMatrix::zeros(3 * nv, 4);
        let verts = xa_world
            .iter()
            .map(|x| (x, -1.0))
            .chain(xb_world.iter().map(|x| (x, 1.0)));
        for (m, (xw, sigma)) in verts.enumerate() {
            let x = xw - self.c0;
            let y = sigma * (n.dot(&x) + o);
            let (_, d1, d2) = barrier_d2(y, self.s);
            let xt = Vector4::new(x.x, x.y, x.z, 1.0);
            let block = n * n.transpose() * d2;
            h.view_mut((3 * m, 3 * m), (3, 3)).copy_from(&block);
            let mut cm = n * xt.transpose() * d2;
            for r in 0..3 {
                cm[(r, r)] += sigma * d1;
            }
            c.view_mut((3 * m, 0), (3, 4)).copy_from(&cm);
        }
        let hinv = plane_hessian_inverse(&self.hpp);
        let hinv = DMatrix::from_iterator(4, 4, hinv.iter().copied());
        h -= &c * hinv * c.transpose();
        h
    }
}

#[cfg(test)]
mod world_tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// `contact_pair_world` relies on the caller's `transform_point` giving the bits of
    /// `world_iter` (`R x + t` on a view of the pose and on owned copies of its blocks).
    #[test]
    fn transform_point_has_the_bits_of_world_iter() {
        let mut r = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..200 {
            let rot = nalgebra::Rotation3::from_euler_angles(
                r.random_range(-3.0..3.0),
                r.random_range(-1.5..1.5),
                r.random_range(-3.0..3.0),
            );
            let mut pose = Matrix3x4::zeros();
            pose.fixed_view_mut::<3, 3>(0, 0).copy_from(rot.matrix());
            for k in 0..3 {
                pose[(k, 3)] = r.random_range(-2.0..2.0);
            }
            let x: Vec<Vector3<f64>> = (0..16)
                .map(|_| Vector3::from_fn(|_, _| r.random_range(-0.3..0.3)))
                .collect();
            let h = HullPose {
                pose: &pose,
                x_local: &x,
            };
            for (w, xl) in world_iter(h).zip(&x) {
                let t = crate::math::transform_point(&pose, xl);
                for k in 0..3 {
                    assert_eq!(w[k].to_bits(), t[k].to_bits());
                }
            }
        }
    }
}
