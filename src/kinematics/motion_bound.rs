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

use crate::math::{Pose, rot};
use crate::model::{JointKind, Model};
use nalgebra::{DVector, Vector3};

/// Per-link motion bounds of one joint-space segment (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct SegmentMotion {
    /// `c_i`: constant drift of every point of link `i` (m per unit α).
    pub drift: Vec<Vector3<f64>>,
    /// `E_i`: bound on the rest of a hull point's velocity (m per unit α).
    pub spread: Vec<f64>,
    /// `W_i`: bound on the link's angular speed (rad per unit α).
    angular: Vec<f64>,
    /// `V_i`: bound on the origin's velocity beyond the drift.
    origin: Vec<f64>,
    /// `V'_i`: as `V_i` with the drift folded in (no split).
    origin_full: Vec<f64>,
    /// `D_i = Σ_{j ≤ i} (‖t_j‖ + τ̄_j)`, summed along the chain from the root.
    lever: Vec<f64>,
    /// `r_i`.
    radius: Vec<f64>,
}

impl SegmentMotion {
    /// Bounds for the segment `q → q + dq`. `pre` are the pre-joint frames
    /// `P_i` at `q` (`Kinematics::pre`); `radius[i]` is `r_i`, the largest
    /// distance of a hull vertex of link `i` from its origin (m).
    pub fn update(
        &mut self,
        model: &Model,
        pre: &[Pose],
        radius: &[f64],
        q: &DVector<f64>,
        dq: &DVector<f64>,
    ) {
        let n = model.links.len();
        self.drift.resize(n, Vector3::zeros());
        self.spread.resize(n, 0.0);
        self.angular.resize(n, 0.0);
        self.origin.resize(n, 0.0);
        self.origin_full.resize(n, 0.0);
        self.lever.resize(n, 0.0);
        self.radius.clear();
        self.radius.extend_from_slice(radius);
        for (i, link) in model.links.iter().enumerate() {
            let o = link.dof_offset;
            let (w, rate, travel) = match &link.joint {
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
            let (parent_w, parent_v, parent_c, parent_full, parent_lever) = match link.parent {
                Some(p) => (
                    self.angular[p],
                    self.origin[p],
                    self.drift[p],
                    self.origin_full[p],
                    self.lever[p],
                ),
                None => (0.0, 0.0, Vector3::zeros(), 0.0, 0.0),
            };
            let attach = link.attach.column(3).norm();
            self.lever[i] = parent_lever + attach + travel;
            self.origin_full[i] = parent_full + parent_w * (attach + travel) + rate.norm();
            let (drift, origin) = if parent_w == 0.0 {
                // Pre-joint frame fixed on the segment: exact drift.
                (parent_c + rot(&pre[i]) * rate, parent_v)
            } else {
                (
                    parent_c,
                    parent_v + parent_w * (attach + travel) + rate.norm(),
                )
            };
            self.drift[i] = drift;
            self.origin[i] = origin;
            self.angular[i] = parent_w + w;
            self.spread[i] = origin + self.angular[i] * radius[i];
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
}

/// `r_i` per link: the largest distance of a hull vertex from the link
/// frame's origin (m; 0 for a link without hulls), written into `out`.
pub fn hull_radii(model: &Model, out: &mut Vec<f64>) {
    out.clear();
    out.extend(model.links.iter().map(|l| {
        l.hulls
            .iter()
            .flat_map(|h| h.x_local.iter())
            .map(|x| x.norm())
            .fold(0.0, f64::max)
    }));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::{KinOrder, Kinematics};
    use crate::math::{pose_from, rpy_to_matrix, transform_point};
    use crate::model::{Hull, Link, MassModel};
    use nalgebra::Matrix3;
    use rand::{RngExt, SeedableRng};

    fn link(name: &str, parent: Option<usize>, joint: JointKind, attach: Pose) -> Link {
        Link {
            name: name.into(),
            robot: 0,
            parent,
            joint_name: name.into(),
            joint,
            limit: None,
            attach,
            hulls: vec![
                Hull::new(
                    Hull::cuboid(Vector3::new(0.3, 0.1, 0.2), Vector3::new(0.2, 0.05, 0.0)),
                    0.1,
                )
                .unwrap(),
            ],
            mass_model: MassModel::Vertices,
            solid_triangles: Vec::new(),
            dof_offset: 0,
            chart: None,
            collides: true,
        }
    }

    /// A tree with every joint kind: free root → revolute → prismatic →
    /// spherical → ball, plus a fixed branch off the root and a prismatic
    /// root.
    fn every_joint_model(rng: &mut impl rand::Rng) -> Model {
        let mut at = |v: f64| {
            pose_from(
                &rpy_to_matrix(&[
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                ]),
                &Vector3::new(v, 0.1, -0.2),
            )
        };
        let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
        let links = vec![
            link("base", None, JointKind::Free, at(0.5)),
            link("rev", Some(0), JointKind::Revolute { axis }, at(0.4)),
            link("pri", Some(1), JointKind::Prismatic { axis }, at(0.3)),
            link("sph", Some(2), JointKind::Spherical, at(0.2)),
            link(
                "ball",
                Some(3),
                JointKind::Ball {
                    axes: [Vector3::x(), Vector3::y()],
                },
                at(0.3),
            ),
            link("fix", Some(0), JointKind::Fixed, at(0.6)),
            link("slider", None, JointKind::Prismatic { axis }, at(-0.5)),
        ];
        let n = links.len();
        Model::new(
            links,
            vec![crate::model::RobotInfo {
                name: "r".into(),
                links: 0..n,
            }],
        )
    }

    /// Every hull vertex, sampled densely along random segments, stays within
    /// the bound, both in norm and along fixed directions, from every
    /// sampled start `α₀` (the bound holds on sub-segments).
    #[test]
    fn sampled_paths_stay_within_the_lever_bound_for_every_joint_kind() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut worst: f64 = 0.0;
        for case in 0..60 {
            let model = every_joint_model(&mut rng);
            let n = model.ndof();
            let charts: Vec<Matrix3<f64>> =
                (0..model.links.iter().filter(|l| l.chart.is_some()).count())
                    .map(|_| {
                        rpy_to_matrix(&[
                            rng.random_range(-3.0..3.0),
                            rng.random_range(-1.0..1.0),
                            rng.random_range(-3.0..3.0),
                        ])
                    })
                    .collect();
            // Large rotation steps (up to ‖Δφ‖ ≈ 5 rad) probe the chart far
            // from its centre.
            let scale = [0.05, 0.5, 2.0][case % 3];
            let q = DVector::from_fn(n, |_, _| rng.random_range(-1.5..1.5));
            let dq = DVector::from_fn(n, |_, _| scale * rng.random_range(-1.0..1.0));
            let mut kin = Kinematics::new(&model);
            kin.update(&model, &q, &charts, KinOrder::Pose);
            let mut radius = Vec::new();
            hull_radii(&model, &mut radius);
            let mut m = SegmentMotion::default();
            m.update(&model, &kin.pre, &radius, &q, &dq);
            let steps = 200;
            let poses: Vec<Vec<Pose>> = (0..=steps)
                .map(|k| {
                    let qa = &q + &dq * (k as f64 / steps as f64);
                    crate::kinematics::link_poses(&model, &qa, &charts)
                })
                .collect();
            let dirs: Vec<Vector3<f64>> = (0..4)
                .map(|_| Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize())
                .collect();
            for (i, l) in model.links.iter().enumerate() {
                for x in &l.hulls[0].x_local {
                    let pts: Vec<Vector3<f64>> =
                        poses.iter().map(|p| transform_point(&p[i], x)).collect();
                    for k0 in [0, steps / 3] {
                        for k in k0 + 1..=steps {
                            let da = (k - k0) as f64 / steps as f64;
                            let moved = pts[k] - pts[k0];
                            let bound = da * m.reach(i);
                            assert!(
                                moved.norm() <= bound * (1.0 + 1e-9) + 1e-12,
                                "case {case} link {i}: moved {} > bound {bound}",
                                moved.norm()
                            );
                            worst = worst.max(moved.norm() / bound.max(1e-300));
                            // Relative to every ancestor's frame.
                            let mut c = Some(i);
                            while let Some(a) = c {
                                let rel = |k: usize| {
                                    let pa = &poses[k][a];
                                    rot(pa).transpose() * (pts[k] - pa.column(3))
                                };
                                let moved_rel = (rel(k) - rel(k0)).norm();
                                let b = da * m.relative_spread(i, a);
                                assert!(
                                    moved_rel <= b * (1.0 + 1e-9) + 1e-12,
                                    "case {case} link {i} relative to {a}: {moved_rel} > {b}"
                                );
                                c = model.links[a].parent;
                            }
                            for d in &dirs {
                                let along = d.dot(&(moved - m.drift[i] * da));
                                assert!(
                                    along.abs() <= da * m.spread[i] * (1.0 + 1e-9) + 1e-12,
                                    "case {case} link {i}: directional"
                                );
                            }
                        }
                    }
                }
            }
        }
        // The bound is not vacuous: some sampled motion uses a good part of it.
        assert!(worst > 0.3, "bound never approached: {worst}");
    }

    /// `‖J_r(φ) Δφ‖ ≤ ‖Δφ‖` for the chart the code uses
    /// (`R = R_c exp([φ]×)`), far beyond `‖φ‖ = π`: the angular speed of
    /// `exp` along a straight line, by central differences.
    #[test]
    fn rotation_vector_angular_speed_never_exceeds_the_coordinate_speed() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut max_ratio: f64 = 0.0;
        for _ in 0..2000 {
            let phi = Vector3::from_fn(|_, _| rng.random_range(-6.0..6.0));
            let d = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let h = 1e-6;
            let rp = crate::math::so3::exp(&(phi + d * h));
            let rm = crate::math::so3::exp(&(phi - d * h));
            let r = crate::math::so3::exp(&phi);
            // Body angular velocity: vee(Rᵀ Ṙ).
            let w = r.transpose() * (rp - rm) / (2.0 * h);
            let omega = Vector3::new(
                w[(2, 1)] - w[(1, 2)],
                w[(0, 2)] - w[(2, 0)],
                w[(1, 0)] - w[(0, 1)],
            ) * 0.5;
            let ratio = omega.norm() / d.norm();
            assert!(ratio <= 1.0 + 1e-6, "ratio {ratio} at φ = {phi:?}");
            max_ratio = max_ratio.max(ratio);
        }
        assert!(max_ratio > 0.999);
    }
}
