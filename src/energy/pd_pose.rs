//! Stable-PD term of a free root joint driven along a target pose
//! ([`crate::control::PoseTarget`]), written on the joint transform so that
//! it does not depend on the rotation chart.
//!
//! With `J = B⁻¹A = [R | p]` the joint transform of the root's pose `A`
//! (attachment frame `B = [R_B | t_B]`), `J^t` the same at the previous step,
//! the target `J* = [R* | p*]`, its rate `J̇* = [Ṙ* | ṗ*]`, and
//!
//! ```text
//! E = J − J*,     F = J̇* − (J − J^t)/Δt,
//! U = Σ_r k_p,r E_{r3}² + k_d,r F_{r3}²  +  (k̄_p/2)‖E_rot‖²_F + (k̄_d/2)‖F_rot‖²_F
//! ```
//!
//! (`r = x, y, z` the translation channels' gains; `k̄` the mean of the three
//! rotation channels' gains). The translation part is exactly the
//! per-coordinate PD of [`super::pd`]; for a small rotation error `δ`,
//! `‖R − R*‖²_F = 4(1 − cos‖δ‖) ≈ 2‖δ‖²`, so the rotation part is
//! `≈ k̄_p‖δ‖²`, the same convention. Derivatives (`G = ∂U/∂J`):
//!
//! ```text
//! G_{r3} = 2k_p,r E_{r3} − (2k_d,r/Δt) F_{r3},   G_rot = k̄_p E_rot − (k̄_d/Δt) F_rot,
//! ∂U/∂A = R_B G,   ∂²U/∂vec(A)² = blockdiag(R_B K_c R_Bᵀ),
//! K_rot = (k̄_p + k̄_d/Δt²) I₃,   K_3 = diag(2k_p,r + 2k_d,r/Δt²),
//! ```
//!
//! a constant pose Hessian (the kinematics add the rest).

use super::{EnergyAccumulator, Need, PdTarget, PoseHessian, StepContext};
use crate::control::PoseTarget;
use crate::control::pose_target::{rotation_and_rate, rotation_partials};
use crate::energy::vjp::{AdjointDirection, VjpAccumulator};
use crate::kinematics::Kinematics;
use crate::math::{Pose, rot};
use nalgebra::{Matrix3, Vector3};

/// Everything of one pose target at one step, in the joint frame.
struct Errors {
    /// `R_B`.
    rb: Matrix3<f64>,
    /// `E = J − J*`.
    e: Pose,
    /// `F = J̇* − (J − J^t)/Δt`.
    f: Pose,
    /// Translation gains `k_p,r`, `k_d,r`.
    kp: Vector3<f64>,
    kd: Vector3<f64>,
    /// Mean rotation gains `k̄_p`, `k̄_d`.
    kpr: f64,
    kdr: f64,
    /// Target rotation vector and its rate.
    r: Vector3<f64>,
    rdot: Vector3<f64>,
}

/// `B⁻¹ A` for a rigid `B` (rotation and translation columns).
fn to_joint(b: &Pose, a: &Pose) -> Pose {
    let rbt = rot(b).transpose();
    let mut j = rbt * a;
    let t = rbt * b.column(3);
    j.column_mut(3).zip_apply(&t, |x, y| *x -= y);
    j
}

fn errors(ctx: &StepContext, kin: &Kinematics, p: &PoseTarget) -> Errors {
    let t: &[PdTarget] = &ctx.targets[p.first..p.first + 6];
    let j = to_joint(&p.frame, &kin.pose[p.link]);
    let jt = to_joint(&p.frame, &ctx.poses_prev[p.link]);
    let r = Vector3::new(t[3].q, t[4].q, t[5].q);
    let rdot = Vector3::new(t[3].qdot, t[4].qdot, t[5].qdot);
    let (rs, rsdot) = rotation_and_rate(&r, &rdot);
    let mut target = Pose::zeros();
    let mut rate = Pose::zeros();
    target.fixed_view_mut::<3, 3>(0, 0).copy_from(&rs);
    rate.fixed_view_mut::<3, 3>(0, 0).copy_from(&rsdot);
    for k in 0..3 {
        target[(k, 3)] = t[k].q;
        rate[(k, 3)] = t[k].qdot;
    }
    let inv_dt = 1.0 / ctx.dt;
    Errors {
        rb: rot(&p.frame),
        e: j - target,
        f: rate - (j - jt) * inv_dt,
        kp: Vector3::new(t[0].kp, t[1].kp, t[2].kp),
        kd: Vector3::new(t[0].kd, t[1].kd, t[2].kd),
        kpr: (t[3].kp + t[4].kp + t[5].kp) / 3.0,
        kdr: (t[3].kd + t[4].kd + t[5].kd) / 3.0,
        r,
        rdot,
    }
}

impl Errors {
    /// `M ↦ K M` column-wise with `K_c = a_rot I` (rotation columns) and
    /// `diag(a_t)` (translation column), in the joint frame.
    fn weigh(m: &Pose, a_rot: f64, a_t: &Vector3<f64>) -> Pose {
        let mut out = m * a_rot;
        for k in 0..3 {
            out[(k, 3)] = m[(k, 3)] * a_t[k];
        }
        out
    }
}

/// Adds the value, `∂U/∂A` and the pose Hessian of every pose target.
pub fn accumulate(ctx: &StepContext, kin: &Kinematics, need: Need, acc: &mut EnergyAccumulator) {
    let inv_dt = 1.0 / ctx.dt;
    for p in ctx.pose_targets {
        let s = errors(ctx, kin, p);
        let (e, f) = (&s.e, &s.f);
        let mut v = 0.5 * s.kpr * e.fixed_view::<3, 3>(0, 0).norm_squared()
            + 0.5 * s.kdr * f.fixed_view::<3, 3>(0, 0).norm_squared();
        for k in 0..3 {
            v += s.kp[k] * e[(k, 3)] * e[(k, 3)] + s.kd[k] * f[(k, 3)] * f[(k, 3)];
        }
        acc.value += v;
        if need >= Need::Gradient {
            let g = Errors::weigh(e, s.kpr, &(2.0 * s.kp))
                - Errors::weigh(f, s.kdr * inv_dt, &(2.0 * inv_dt * s.kd));
            acc.link_grad[p.link] += s.rb * g;
        }
        if need >= Need::Hessian {
            let mut h = PoseHessian::zeros();
            let a_rot = s.kpr + s.kdr * inv_dt * inv_dt;
            for c in 0..3 {
                for k in 0..3 {
                    h[(3 * c + k, 3 * c + k)] = a_rot;
                }
            }
            let kt = Matrix3::from_diagonal(&(2.0 * s.kp + 2.0 * inv_dt * inv_dt * s.kd));
            let kt = s.rb * kt * s.rb.transpose();
            h.fixed_view_mut::<3, 3>(9, 9).copy_from(&kt);
            acc.add_link_hess(p.link, &h);
        }
    }
}

/// Adjoint products `∂Φ/∂x` of `Φ = ⟨δA, ∂U/∂A⟩` (`δJ = R_Bᵀ δA`):
/// `∂Φ/∂A = R_B K δJ`, `∂Φ/∂A^t = −R_B K_d δJ/Δt²` (`K_d` the damping part
/// of `K`), and per channel `(∂Φ/∂θ*, ∂Φ/∂θ̇*, ∂Φ/∂k_p, ∂Φ/∂k_d)`:
/// translation `(−2k_p δJ_r, −2k_d δJ_r/Δt, 2E_r δJ_r, −2F_r δJ_r/Δt)`;
/// rotation `k`: `∂Φ/∂r_k = ⟨−k̄_p δJ_rot, ∂R*/∂r_k⟩ + ⟨−(k̄_d/Δt) δJ_rot, ∂Ṙ*/∂r_k⟩`,
/// `∂Φ/∂ṙ_k = ⟨−(k̄_d/Δt) δJ_rot, ∂R*/∂r_k⟩`, `∂Φ/∂k_p,k = ⟨E_rot, δJ_rot⟩/3`,
/// `∂Φ/∂k_d,k = −⟨F_rot, δJ_rot⟩/(3Δt)`.
pub fn vjp(ctx: &StepContext, kin: &Kinematics, dir: &AdjointDirection, out: &mut VjpAccumulator) {
    let inv_dt = 1.0 / ctx.dt;
    let inv_dt2 = inv_dt * inv_dt;
    for p in ctx.pose_targets {
        let s = errors(ctx, kin, p);
        let dj = s.rb.transpose() * dir.dpose[p.link];
        let k_all = Errors::weigh(
            &dj,
            s.kpr + s.kdr * inv_dt2,
            &(2.0 * s.kp + 2.0 * inv_dt2 * s.kd),
        );
        out.pose[p.link] += s.rb * k_all;
        let k_d = Errors::weigh(&dj, s.kdr * inv_dt2, &(2.0 * inv_dt2 * s.kd));
        out.pose_prev[p.link] -= s.rb * k_d;
        for k in 0..3 {
            let c = &mut out.channels[p.first + k];
            let l = dj[(k, 3)];
            c[0] -= 2.0 * s.kp[k] * l;
            c[1] -= 2.0 * s.kd[k] * l * inv_dt;
            c[2] += 2.0 * s.e[(k, 3)] * l;
            c[3] -= 2.0 * s.f[(k, 3)] * l * inv_dt;
        }
        let djr = dj.fixed_view::<3, 3>(0, 0).into_owned();
        let (dr, drdot) = rotation_partials(&s.r, &s.rdot);
        let de = s.e.fixed_view::<3, 3>(0, 0).dot(&djr);
        let df = s.f.fixed_view::<3, 3>(0, 0).dot(&djr);
        for k in 0..3 {
            let c = &mut out.channels[p.first + 3 + k];
            c[0] -= s.kpr * djr.dot(&dr[k]) + s.kdr * inv_dt * djr.dot(&drdot[k]);
            c[1] -= s.kdr * inv_dt * djr.dot(&dr[k]);
            c[2] += de / 3.0;
            c[3] -= df * inv_dt / 3.0;
        }
    }
}
