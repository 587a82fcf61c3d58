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
//! # Chords (the IPC baseline's line search)
//!
//! The IPC baseline certifies a line-search step by additive CCD on the
//! *chords* between exactly computed vertex positions, so it needs how far a
//! vertex path strays from its chord over a sub-interval `[α₀, α₀ + h]`. It
//! uses this same bound: the drift `c_i` is constant, so it cancels between
//! the path and its chord, and what is left moves at most at `E_i`; with
//! `s = (α − α₀)/h` the deviation is
//! `‖∫_{α₀}^{α} e − s ∫_{α₀}^{α₀+h} e‖ ≤ 2 s (1 − s) h E_i ≤ E_i h/2`.
//! For short sub-intervals a bound on the acceleration does better: a path
//! whose acceleration is at most `A_i` deviates from its chord by at most
//! `A_i h²/8`, so [`SegmentMotion::chord_deviation`] is
//! `min(E_i h/2, A_i h²/8)`. `A_i` ([`SegmentMotion::update_chord`]) comes
//! from the same joint rates `w_j`, lever arms and travel rates as the lever
//! bound: `Ẍ = Σ_j [ω̇_j × (X − o_j) + ω_j × (Ẋ − ȯ_j)] + …` over the joints
//! `j` on the path to the link, with `‖ω_j‖ ≤ w_j`,
//! `‖ω̇_j‖ ≤ w_j W_λ(j) + κ_j` (the joint's axes turn with its parent; `κ_j`
//! the joint's own turning: 0 for a hinge, `|Δq₁||Δq₂|` for a ball, whose
//! second axis turns about the first, `C ‖Δφ‖²` for a rotation vector,
//! `C = CHART_TURN`), `‖X − o_j‖ ≤ R_j` (the hull radius plus the lever arms
//! below `j`) and `‖Ẋ − ȯ_j‖ ≤ Σ_{k at or below j} (w_k R_k + t_k)`, where
//! `t_k = ‖τ̇_k‖` counts a translation only when the parent turns (else it
//! is drift, exactly linear); a translation in a turning frame adds
//! `t_j W_λ(j)`:
//!
//! ```text
//! A_i = Σ_j [(w_j W_λ(j) + κ_j) R_j + w_j Σ_{k at or below j} (w_k R_k + t_k) + t_j W_λ(j)]
//! ```

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
    /// `A_i`: bound on a hull point's acceleration (m per unit α²), set by
    /// [`SegmentMotion::update_chord`] (the chords of the IPC baseline).
    accel: Vec<f64>,
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

    /// The acceleration bounds `A_i` of the module docs' chord section,
    /// after [`SegmentMotion::update`] on the same segment (`dq` its step).
    /// Only the chords need them; [`SegmentMotion::update`] does not compute
    /// them.
    pub fn update_chord(&mut self, model: &Model, dq: &DVector<f64>) {
        self.accel.clear();
        // Per joint on the path from the link up: (w_j, κ_j, t_j, R_j, W_λ(j)).
        let mut path: Vec<(f64, f64, f64, f64, f64)> = Vec::new();
        for l in 0..model.links.len() {
            path.clear();
            let mut reach = self.radius[l];
            let mut j = l;
            loop {
                let link = &model.links[j];
                let w = self.joint_rate[j];
                let parent_w = link.parent.map_or(0.0, |p| self.angular[p]);
                let t = if parent_w > 0.0 {
                    self.travel_rate[j]
                } else {
                    0.0
                };
                let o = link.dof_offset;
                let turn = match &link.joint {
                    JointKind::Fixed | JointKind::Prismatic { .. } | JointKind::Revolute { .. } => {
                        0.0
                    }
                    JointKind::Ball { .. } => dq[o].abs() * dq[o + 1].abs(),
                    JointKind::Spherical | JointKind::Free => CHART_TURN * w * w,
                };
                path.push((w, turn, t, reach, parent_w));
                let Some(p) = link.parent else { break };
                reach += self.arm[j];
                j = p;
            }
            let (mut acc, mut below) = (0.0, 0.0);
            for &(w, turn, t, r, parent_w) in &path {
                below += w * r + t;
                acc += (w * parent_w + turn) * r + w * below + t * parent_w;
            }
            self.accel.push(acc);
        }
    }

    /// How far a hull point of link `i` can stray from the chord between its
    /// exact positions at the ends of any sub-interval of length `h` of the
    /// segment: `min(E_i h/2, A_i h²/8)` (m; after
    /// [`SegmentMotion::update_chord`]).
    pub fn chord_deviation(&self, link: usize, h: f64) -> f64 {
        (self.spread[link] * h / 2.0).min(self.accel[link] * h * h / 8.0)
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

#[cfg(test)]
#[path = "motion_bound_tests.rs"]
pub(crate) mod tests;
