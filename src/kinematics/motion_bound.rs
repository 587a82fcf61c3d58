//! A conservative bound on how far any hull point of a link moves while the
//! coordinates follow the straight joint-space segment
//! `θ(α) = θ + α Δθ`, `α ∈ [0, 1]`, mapped through forward kinematics (a
//! curved path in the world: continuous collision detection, `contact::ccd`).
//!
//! For a point `x` rigidly attached to link `i`, along the segment
//!
//! ```text
//! dx/dα = c_i + e_i(α, x),   ‖e_i‖ ≤ E_i,
//! ```
//!
//! where `c_i` (m per unit α, world frame) is a *constant* drift — the
//! translation of a free or prismatic root joint under a static attachment,
//! exact — and `E_i` bounds everything else. Hence for `0 ≤ α₀ ≤ α ≤ 1`
//! and any fixed unit vector `n`:
//!
//! ```text
//! |n·(x(α) − x(α₀)) − (α − α₀) n·c_i| ≤ (α − α₀) E_i .
//! ```
//!
//! Derivation (per link, parents first; `o_i` the link frame's origin, the
//! centre of its joint's rotation):
//!
//! - angular speed of joint `i`'s own rotation, `w_i`: revolute `|Δq|`; ball
//!   (two hinges, `R = Rot(a₁, q₁) Rot(a₂, q₂)`) exactly
//!   `√(Δq₁² + Δq₂² + 2 Δq₁Δq₂ a₁·a₂)` (the second axis turns about the
//!   first, so its angle to it is constant); spherical and free, `R = R_c exp([φ]×)`:
//!   the body angular velocity is `J_r(φ) Δφ`, and the right Jacobian of
//!   SO(3) has singular values `1` (along `φ`) and
//!   `|sin(‖φ‖/2)/(‖φ‖/2)| ≤ 1` (across), so `w_i = ‖Δφ‖` for every `φ`
//!   (checked by finite differences in the tests below);
//! - the link's total angular speed `W_i = W_λ(i) + w_i`;
//! - the origin moves as `ȯ_i = ȯ_λ + ω_λ × (R_λ t_i + R_{P_i} τ_i) +
//!   R_{P_i} τ̇_i` (`t_i` the attachment point, `τ_i(α)` the joint's
//!   translation: prismatic `q·axis`, free `p`), so
//!   `‖ȯ_i − c_i‖ ≤ V_i = V_λ + W_λ (‖t_i‖ + τ̄_i) + ‖τ̇_i‖` with
//!   `τ̄_i = max(‖τ_i(0)‖, ‖τ_i(1)‖)` (a norm of an affine function is
//!   convex, so its maximum on the segment is at an end). When the parent
//!   does not rotate (`W_λ = 0`: the pre-joint frame is fixed on the
//!   segment) the joint's translation `R_{P_i} τ̇_i` is constant and joins
//!   the drift instead: `c_i = c_λ + R_{P_i} τ̇_i`;
//! - a hull point `x = o_i + R_i x_local` moves at
//!   `ȯ_i + ω_i × R_i x_local`, so `E_i = V_i + W_i r_i` with
//!   `r_i = max ‖x_local‖` over the link's hull vertices.
//!
//! These are sums of fixed inter-joint distances, prismatic/free travel on
//! the segment and hull radii times angular rates: rigid lever arms, valid at
//! every `α ∈ [0, 1]`, not only at the start.
//!
//! This *lever bound* is tight when the joints turn the same way and loose
//! when they turn against each other; [`SegmentMotion::update`] also
//! computes a *rate bound* from the exact rates at the start and keeps the
//! smaller of the two.
//!
//! # The chord bound (the IPC baseline's line search)
//!
//! The IPC baseline certifies a line-search step by additive CCD on the
//! *chords* between exactly computed vertex positions, so it needs how far
//! a vertex path strays from its chord rather than a drift plus spread.
//! Split `X(α) = X_lin(α) + X_nl(α)`: `X_lin` collects the translations of
//! joints without moving ancestors (exactly linear in `α`) and `X_nl` has
//! speed at most
//!
//! ```text
//! U_L = Σ_{joints j on the path to L} (‖Δθ_j^rot‖ R_{j,L} + [j has a moving ancestor] ‖Δθ_j^trans‖)
//! ```
//!
//! (m per unit `α`; `R_{L,L} = max ‖x̃‖` and, for the child `c` of `j` on
//! the path, `R_{j,L} = ‖t(C_c)‖ + max_α ‖t(J_c)‖ + R_{c,L}`) and acceleration at most
//! `A_L` ([`chord_speed_bounds`]). A path with speed ≤ `U` and acceleration
//! ≤ `A` deviates from its chord over a sub-interval of length `h` by at
//! most `min(U h/2, A h²/8)` ([`chord_deviation`]). Its joint rates differ
//! from the lever bound's above (a ball joint counts `|Δq₁| + |Δq₂|`, not
//! the exact norm), so the two bounds are kept side by side: making the
//! baseline use the lever bound would change its step sizes, and so its
//! trajectories.

use crate::math::{Pose, rot};
use crate::model::{JointKind, Model};
use nalgebra::{DVector, Matrix3, Vector3};

/// Per-link motion bounds of one joint-space segment (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct SegmentMotion {
    /// `c_i`: constant drift of every point of link `i` (m per unit α).
    pub drift: Vec<Vector3<f64>>,
    /// `E_i`: bound on the rest of a hull point's velocity (m per unit α):
    /// the smaller of the lever bound and the rate bound.
    pub spread: Vec<f64>,
    /// `W_i`: lever bound on the link's angular speed (rad per unit α), a
    /// sum of joint rates along the chain.
    angular: Vec<f64>,
    /// `Ŵ_i = min(W_i, ‖ω_i(0)‖ + Ω_i)`: the tighter angular-speed bound.
    angular_tight: Vec<f64>,
    /// `V_i`: bound on the origin's velocity beyond the drift.
    origin: Vec<f64>,
    /// `V'_i`: as `V_i` with the drift folded in (no split).
    origin_full: Vec<f64>,
    /// `U_i ≥ V_i`: `V_i`'s recursion with the lever bound `W (1 + 10⁻¹²)`
    /// in place of `Ŵ` (see [`SegmentMotion::update_lever`]).
    origin_upper: Vec<f64>,
    /// `Ē_i = U_i + W_i r_i ≥ E_i` (m per unit α), known before the rates.
    pub spread_upper: Vec<f64>,
    /// Per link, of its own joint: `w_i` (lever angular rate, rad per unit
    /// α), `ℓ_i = ‖t_i‖ + τ̄_i` (m) and `‖τ̇_i‖` (m per unit α).
    joint_rate: Vec<f64>,
    arm: Vec<f64>,
    travel_rate: Vec<f64>,
    /// `D_i = Σ_{j ≤ i} (‖t_j‖ + τ̄_j)`, summed along the chain from the root.
    lever: Vec<f64>,
    /// `r_i`.
    radius: Vec<f64>,
    /// Exact rates at the segment's start, world frame: `ω_i(0)` and
    /// `ȯ_i(0)` (per unit α).
    omega0: Vec<Vector3<f64>>,
    origin_rate0: Vec<Vector3<f64>>,
    /// `Ω_i ≥ sup_α ‖ω_i(α) − ω_i(0)‖` and `Δ_i ≥ sup_α ‖ȯ_i(α) − ȯ_i(0)‖`.
    omega_change: Vec<f64>,
    origin_change: Vec<f64>,
    /// `dT_i/dα` at the start (rotation rate | origin rate), world frame.
    pose_rate: Vec<Pose>,
}

/// `sup ‖d/dα (J_l(φ + αΔφ) Δφ)‖ / ‖Δφ‖²` for the rotation-vector chart,
/// with margin: the space angular velocity of `exp(φ + αΔφ)` turns at most
/// this fast (sampled maximum `1/π ≈ 0.318`; checked by finite differences
/// in the tests below).
const CHART_TURN: f64 = 0.5;

impl SegmentMotion {
    /// Bounds for the segment `q → q + dq`. `pre` and `pose` are the
    /// pre-joint frames `P_i` and link poses at `q` (`Kinematics::pre`,
    /// `Kinematics::pose`), `charts` the rotation-vector chart centres;
    /// `radius[i]` is `r_i`, the largest distance of a hull vertex of link
    /// `i` from its origin (m).
    ///
    /// Two bounds are computed and the smaller is kept (both hold):
    ///
    /// - the *lever bound* (module docs): sums of joint rates times rigid
    ///   lever arms. Tight when every joint turns the same way; loose by
    ///   orders of magnitude when neighbouring joints turn against each
    ///   other (a hanging chain's links stay nearly still while its relative
    ///   angles alternate: a 32-link chain's lever bound was measured
    ///   100–1000× its actual motion);
    /// - the *rate bound*: the exact rates at the start, `ω_i(0)` and
    ///   `ȯ_i(0)` (forward recursion with first-order dual numbers, so
    ///   cancellations between joints are kept), plus bounds on how much
    ///   they can change along the segment, which are products of small
    ///   rates. With `Ŵ` any bound on a link's angular speed:
    ///
    ///   ```text
    ///   ω_i = ω_λ + ω_rel,i        Ω_i = Ω_λ + ΔΩ_rel,i
    ///   ΔΩ_rel: revolute Ŵ_λ|Δq|; ball Ŵ_λ w_i + |Δq₁||Δq₂|;
    ///           spherical/free Ŵ_λ‖Δφ‖ + min(2, C‖Δφ‖)‖Δφ‖ (C = 1/2)
    ///   Ŵ_i = min(W_i, ‖ω_i(0)‖ + Ω_i)
    ///   ȯ_i = ȯ_λ + ω_λ × d_i + R_{P_i} τ̇_i,   ‖d_i‖ ≤ ℓ_i = ‖t_i‖ + τ̄_i
    ///   Δ_i = Δ_λ + Ω_λ ℓ_i + ‖ω_λ(0)‖ (Ŵ_λ ℓ_i + ‖τ̇_i‖) + Ŵ_λ ‖τ̇_i‖
    ///   E_i = ‖ȯ_i(0) − c_i‖ + Δ_i + Ŵ_i r_i
    ///   ```
    ///
    ///   (an axis fixed in the parent turns at most at the parent's angular
    ///   speed, `‖R(α) − R(0)‖ ≤ α Ŵ`; `d_i` changes at most at
    ///   `Ŵ_λ ℓ_i + ‖τ̇_i‖`).
    // Arguments kept separate: the line-search trial's state (poses before/after, charts, radii, q, Δq), each owned by a different stage of the step.
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        model: &Model,
        pre: &[Pose],
        pose: &[Pose],
        charts: &[Matrix3<f64>],
        radius: &[f64],
        q: &DVector<f64>,
        dq: &DVector<f64>,
    ) {
        self.update_lever(model, pre, radius, q, dq);
        self.update_rates(model, pre, pose, charts, q, dq);
    }

    /// The first half of [`SegmentMotion::update`]: everything that needs
    /// no rates at the start — the drift `c_i`, the lever sums `W_i`,
    /// `V'_i`, `D_i` (so [`SegmentMotion::relative_spread`] is final after
    /// this), and the upper bound `Ē_i ≥ E_i` ([`SegmentMotion::spread_upper`],
    /// [`SegmentMotion::reach_upper`]). No trigonometry: a few norms per link.
    ///
    /// `Ē_i` bounds `E_i` from above *in floating point*, whatever
    /// [`SegmentMotion::update_rates`] later finds: `E_i` is
    /// the minimum of the lever bound `V_i + Ŵ_i r_i` and the rate bound,
    /// and `V_i` is a recursion of sums and products of non-negative terms
    /// in `Ŵ_λ ≤ W_λ (1 + 10⁻¹²)`; the same recursion with `W (1 + 10⁻¹²)`
    /// in place of `Ŵ`,
    ///
    /// ```text
    /// U_i = U_λ [+ W_λ(1 + 10⁻¹²) ℓ_i + ‖τ̇_i‖ when W_λ > 0],   Ē_i = U_i + W_i r_i,
    /// ```
    ///
    /// is at least as large term by term, and rounding is monotone (for
    /// non-negative operands `a ≤ a'`, `b ≤ b'` give `fl(a + b) ≤ fl(a' + b')`
    /// and `fl(a b) ≤ fl(a' b')`), so `Ē_i ≥ E_i` as computed, bit for bit
    /// (and every sum of them with the same other operands, e.g. the reach).
    /// [`crate::contact::ccd`] uses it to clear a segment before any rate is
    /// computed.
    pub fn update_lever(
        &mut self,
        model: &Model,
        pre: &[Pose],
        radius: &[f64],
        q: &DVector<f64>,
        dq: &DVector<f64>,
    ) {
        let n = model.links.len();
        self.drift.resize(n, Vector3::zeros());
        self.angular.resize(n, 0.0);
        self.origin_full.resize(n, 0.0);
        self.lever.resize(n, 0.0);
        self.joint_rate.resize(n, 0.0);
        self.arm.resize(n, 0.0);
        self.travel_rate.resize(n, 0.0);
        self.origin_upper.resize(n, 0.0);
        self.spread_upper.resize(n, 0.0);
        self.radius.clear();
        self.radius.extend_from_slice(radius);
        for (i, link) in model.links.iter().enumerate() {
            let o = link.dof_offset;
            let (w, rate_t, travel) = match &link.joint {
                JointKind::Fixed => (0.0, Vector3::zeros(), 0.0),
                JointKind::Revolute { .. } => (dq[o].abs(), Vector3::zeros(), 0.0),
                JointKind::Prismatic { axis } => {
                    (0.0, axis * dq[o], q[o].abs().max((q[o] + dq[o]).abs()))
                }
                JointKind::Ball { axes } => {
                    // ω = a₁ Δq₁ + Rot(a₁, q₁) a₂ Δq₂ and a₁·Rot(a₁, q₁) a₂ = a₁·a₂:
                    // the norm is exact and constant on the segment.
                    let c = axes[0].dot(&axes[1]);
                    let (x, y) = (dq[o], dq[o + 1]);
                    let w2 = (x * x + y * y + 2.0 * c * x * y).max(0.0);
                    (w2.sqrt() * (1.0 + 1e-15), Vector3::zeros(), 0.0)
                }
                JointKind::Spherical => (
                    Vector3::new(dq[o], dq[o + 1], dq[o + 2]).norm(),
                    Vector3::zeros(),
                    0.0,
                ),
                JointKind::Free => {
                    let p = Vector3::new(q[o], q[o + 1], q[o + 2]);
                    let dp = Vector3::new(dq[o], dq[o + 1], dq[o + 2]);
                    (
                        Vector3::new(dq[o + 3], dq[o + 4], dq[o + 5]).norm(),
                        dp,
                        p.norm().max((p + dp).norm()),
                    )
                }
            };
            let (parent_w, parent_c, parent_full, parent_lever, parent_upper) = match link.parent {
                Some(p) => (
                    self.angular[p],
                    self.drift[p],
                    self.origin_full[p],
                    self.lever[p],
                    self.origin_upper[p],
                ),
                None => (0.0, Vector3::zeros(), 0.0, 0.0, 0.0),
            };
            let attach = link.attach.column(3).norm();
            let ell = attach + travel;
            let tau_rate = rate_t.norm();
            self.joint_rate[i] = w;
            self.arm[i] = ell;
            self.travel_rate[i] = tau_rate;
            self.lever[i] = parent_lever + ell;
            self.origin_full[i] = parent_full + parent_w * ell + tau_rate;
            self.angular[i] = parent_w + w;
            let (drift, upper) = if parent_w == 0.0 {
                // Pre-joint frame fixed on the segment: exact drift.
                (parent_c + rot(&pre[i]) * rate_t, parent_upper)
            } else {
                let parent_wu = parent_w * (1.0 + 1e-12);
                (parent_c, parent_upper + parent_wu * ell + tau_rate)
            };
            self.drift[i] = drift;
            self.origin_upper[i] = upper;
            self.spread_upper[i] = upper + self.angular[i] * radius[i];
        }
    }

    /// The second half of [`SegmentMotion::update`] (after
    /// [`SegmentMotion::update_lever`] on the same segment): the exact rates
    /// at the start and the spread `E_i`.
    pub fn update_rates(
        &mut self,
        model: &Model,
        pre: &[Pose],
        pose: &[Pose],
        charts: &[Matrix3<f64>],
        q: &DVector<f64>,
        dq: &DVector<f64>,
    ) {
        let n = model.links.len();
        self.spread.resize(n, 0.0);
        self.angular_tight.resize(n, 0.0);
        self.origin.resize(n, 0.0);
        self.omega0.resize(n, Vector3::zeros());
        self.origin_rate0.resize(n, Vector3::zeros());
        self.omega_change.resize(n, 0.0);
        self.origin_change.resize(n, 0.0);
        self.pose_rate.resize(n, Pose::zeros());
        for (i, link) in model.links.iter().enumerate() {
            let o = link.dof_offset;
            let nd = link.ndof();
            // Exact rates at the start: dT_i/dα = dP_i/dα · J + P_i · dJ/dα,
            // dP_i/dα = dT_λ/dα · A_i.
            let chart = link
                .chart
                .map(|c| charts[c])
                .unwrap_or_else(Matrix3::identity);
            let (local, local_rate) = link.joint.transform_velocity(
                &chart,
                &q.as_slice()[o..o + nd],
                &dq.as_slice()[o..o + nd],
            );
            let pre_rate = match link.parent {
                Some(p) => rate_compose(&self.pose_rate[p], &link.attach),
                None => Pose::zeros(),
            };
            let rate = rate_compose(&pre_rate, &local) + rotate_rate(&pre[i], &local_rate);
            self.pose_rate[i] = rate;
            let spin = rate.fixed_view::<3, 3>(0, 0) * rot(&pose[i]).transpose();
            self.omega0[i] = axial(&spin);
            self.origin_rate0[i] = rate.column(3).into_owned();

            let (w, ell, tau_rate) = (self.joint_rate[i], self.arm[i], self.travel_rate[i]);
            let (parent_w, parent_wt, parent_v) = match link.parent {
                Some(p) => (self.angular[p], self.angular_tight[p], self.origin[p]),
                None => (0.0, 0.0, 0.0),
            };
            let (parent_omega0, parent_dw, parent_dv) = match link.parent {
                Some(p) => (
                    self.omega0[p].norm(),
                    self.omega_change[p],
                    self.origin_change[p],
                ),
                None => (0.0, 0.0, 0.0),
            };
            // Rate bound on the angular speed.
            let rel_change = match &link.joint {
                JointKind::Fixed | JointKind::Prismatic { .. } => 0.0,
                JointKind::Revolute { .. } => parent_wt * w,
                JointKind::Ball { .. } => parent_wt * w + dq[o].abs() * dq[o + 1].abs(),
                JointKind::Spherical | JointKind::Free => {
                    parent_wt * w + (CHART_TURN * w).min(2.0) * w
                }
            };
            self.omega_change[i] = parent_dw + rel_change;
            let wt = self.angular[i].min(self.omega0[i].norm() + self.omega_change[i]);
            self.angular_tight[i] = wt * (1.0 + 1e-12);
            self.origin_change[i] = parent_dv
                + parent_dw * ell
                + parent_omega0 * (parent_wt * ell + tau_rate)
                + parent_wt * tau_rate;
            let origin = if parent_w == 0.0 {
                parent_v
            } else {
                parent_v + parent_wt * ell + tau_rate
            };
            let drift = self.drift[i];
            self.origin[i] = origin;
            let radius = self.radius[i];
            let lever_bound = origin + wt * radius;
            let rate_bound =
                (self.origin_rate0[i] - drift).norm() + self.origin_change[i] + wt * radius;
            // Round-off guard on the rate bound's exact first-order part.
            let guard = 1e-12 * (self.origin_full[i] + self.angular[i] * radius);
            self.spread[i] = lever_bound.min(rate_bound * (1.0 + 1e-12) + guard);
        }
    }

    /// `E_i^c`: the bound on a hull point's speed of link `i` *relative to
    /// the frame of its ancestor `c`* (`c = i` gives 0). The distance of two
    /// hulls is invariant under a common rigid motion, so for links whose
    /// lowest common ancestor is `c` the joints above `c` do not count:
    /// expressed in `c`'s frame, the recursion above starts at `c` at rest,
    /// which telescopes to `V'_i − V'_c − W_c (D_i − D_c) + (W_i − W_c) r_i`
    /// (`V'`, `D` the undivided origin bound and lever sum). Every term is
    /// a sum of non-negative parts; a relative guard of `1e-12` of the
    /// operands covers the subtraction's round-off.
    pub fn relative_spread(&self, i: usize, c: usize) -> f64 {
        if i == c {
            return 0.0;
        }
        let (wc, wi) = (self.angular[c], self.angular[i]);
        let v = self.origin_full[i] - self.origin_full[c] - wc * (self.lever[i] - self.lever[c]);
        let w = wi - wc;
        let guard = 1e-12 * (self.origin_full[i] + wc * self.lever[i] + wi * self.radius[i]);
        (v + w * self.radius[i]).max(0.0) + guard
    }

    /// `‖c_i‖ + E_i`: how far any hull point of link `i` can move on the
    /// whole segment (m).
    pub fn reach(&self, link: usize) -> f64 {
        self.drift[link].norm() + self.spread[link]
    }

    /// `‖c_i‖ + Ē_i ≥` [`SegmentMotion::reach`] (bit for bit), available
    /// after [`SegmentMotion::update_lever`] alone (m).
    pub fn reach_upper(&self, link: usize) -> f64 {
        self.drift[link].norm() + self.spread_upper[link]
    }
}

/// `ω` from `[ω]× + E`: the axial vector of a matrix's skew part
/// (`Ṙ Rᵀ` of a rotation `R` gives its space angular velocity).
fn axial(m: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    ) * 0.5
}

/// The rate of `T · B` for a constant pose `B`, given `Ṫ` (the
/// translation column of `B` is carried by the rotation rate only).
fn rate_compose(t_rate: &Pose, b: &Pose) -> Pose {
    let r = t_rate.fixed_view::<3, 3>(0, 0);
    let mut out = Pose::zeros();
    out.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(r * b.fixed_view::<3, 3>(0, 0)));
    let t = r * b.column(3) + t_rate.column(3);
    out.set_column(3, &t);
    out
}

/// The rate of `P · J` from a constant `P` and `J̇`: `[R_P Ṙ_J | R_P ṫ_J]`.
fn rotate_rate(p: &Pose, j_rate: &Pose) -> Pose {
    rot(p) * j_rate
}

/// `r_i` per link: the largest distance of a hull vertex from the link
/// frame's origin (m; 0 for a link without hulls), written into `out`.
/// One square root per link: `√` is correctly rounded and monotone, so
/// `√(max ‖x‖²)` is bit for bit `max √(‖x‖²) = max ‖x‖`.
pub fn hull_radii(model: &Model, out: &mut Vec<f64>) {
    out.clear();
    out.extend(model.links.iter().map(|l| {
        l.hulls
            .iter()
            .flat_map(|h| h.x_local.iter())
            .map(|x| x.norm_squared())
            .fold(0.0, f64::max)
            .sqrt()
    }));
}

/// `(U_L, A_L)` for every link: bounds on the speed and the acceleration
/// (per unit `α`) of the non-linear part of its vertex paths (the chord
/// bound of the module docs); `radius[L]` is `max ‖x̃‖` over the link's
/// vertices (m). With `s_j` the rotational speed bound of joint `j`, `t_j` its
/// translation speed (when it has a moving ancestor), `R_j = R_{j,L}`,
/// `W_j = Σ_{ancestors i of j} s_i` and `V_j = Σ_{i on the path at or below
/// j} (s_i R_i + t_i)`: `U_L = Σ_j (s_j R_j + t_j)` and
/// `A_L = Σ_j [s_j (W_j + s_j/2) R_j + s_j V_j + t_j W_j]`, from
/// `Ẍ = Σ_j [ω̇_j × (X − c_j) + ω_j × (Ẋ − ċ_j)]` with `‖ω_j‖ ≤ s_j`,
/// `‖ω̇_j‖ ≤ s_j (W_j + s_j/2)` (the axis turns with the ancestors; the
/// rotation-vector Jacobian changes at rate ≤ ½‖Δφ‖) and
/// `‖Ẋ − ċ_j‖ ≤ V_j`.
pub fn chord_speed_bounds(
    model: &Model,
    radius: &[f64],
    q: &DVector<f64>,
    dq: &DVector<f64>,
    out: &mut Vec<(f64, f64)>,
) {
    out.clear();
    let trans_len = |l: usize, x: &DVector<f64>| -> f64 {
        let link = &model.links[l];
        let o = link.dof_offset;
        match link.joint {
            JointKind::Prismatic { .. } => x[o].abs(),
            JointKind::Free => Vector3::new(x[o], x[o + 1], x[o + 2]).norm(),
            _ => 0.0,
        }
    };
    let rot_speed = |l: usize| -> f64 {
        let link = &model.links[l];
        let o = link.dof_offset;
        match link.joint {
            JointKind::Revolute { .. } => dq[o].abs(),
            JointKind::Ball { .. } => dq[o].abs() + dq[o + 1].abs(),
            JointKind::Spherical => Vector3::new(dq[o], dq[o + 1], dq[o + 2]).norm(),
            JointKind::Free => Vector3::new(dq[o + 3], dq[o + 4], dq[o + 5]).norm(),
            _ => 0.0,
        }
    };
    let trans_speed = |l: usize| -> f64 {
        let link = &model.links[l];
        let o = link.dof_offset;
        match link.joint {
            JointKind::Prismatic { .. } => dq[o].abs(),
            JointKind::Free => Vector3::new(dq[o], dq[o + 1], dq[o + 2]).norm(),
            _ => 0.0,
        }
    };
    let q1 = q + dq;
    for (l, r) in radius.iter().enumerate().take(model.links.len()) {
        // The path L → root: per joint, s (rotational speed), t (translation
        // speed counted as non-linear) and R (centre-to-vertex bound).
        let mut path: Vec<(f64, f64, f64)> = Vec::new();
        let mut reach = *r;
        let mut j = l;
        loop {
            let link = &model.links[j];
            let has_moving_ancestor = link
                .parent
                .is_some_and(|p| !model.ancestor_dofs[p].is_empty());
            let t = if has_moving_ancestor {
                trans_speed(j)
            } else {
                0.0
            };
            path.push((rot_speed(j), t, reach));
            let Some(p) = link.parent else { break };
            reach += link.attach.column(3).norm() + trans_len(j, q).max(trans_len(j, &q1));
            j = p;
        }
        let (mut u, mut acc, mut below) = (0.0, 0.0, 0.0);
        let total_s: f64 = path.iter().map(|p| p.0).sum();
        let mut anc = total_s;
        for &(sp, tp, rp) in &path {
            anc -= sp;
            u += sp * rp + tp;
            below += sp * rp + tp;
            acc += sp * (anc + 0.5 * sp) * rp + sp * below + tp * anc;
        }
        out.push((u, acc));
    }
}

/// Bound on the distance between a link's true vertex path and its chord
/// over a sub-interval of length `h`: `min(U h/2, A h²/8)` (m).
pub fn chord_deviation((u, a): (f64, f64), h: f64) -> f64 {
    (u * h / 2.0).min(a * h * h / 8.0)
}

#[cfg(test)]
#[path = "motion_bound_tests.rs"]
mod tests;
