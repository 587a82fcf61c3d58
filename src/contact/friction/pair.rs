//! `U_f` of one hull pair with its gradient and Hessians contracted to the two hull poses
//! (paper Eq. `derivativeFriction2` for the mixed block).

use nalgebra::{Matrix3, Matrix3x2, Matrix3x4, Matrix4, SMatrix, Vector2, Vector3, Vector4};

use super::*;
use crate::contact::error::FrictionError;
use crate::contact::potential::HullPose;

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
    pub hessian: Option<Box<SMatrix<f64, 24, 24>>>,
    /// `∂²U_f/∂A^{t+1}∂A^t` (rows `[vec A_a^{t+1}; vec A_b^{t+1}]`, columns
    /// `[vec A_a^t; vec A_b^t]`) for fixed lagged normal, basis and forces, when asked. The
    /// step-`t` vertices are `X^t = A^t [x_local; 1]` with the same local vertices.
    pub mixed: Option<Box<SMatrix<f64, 24, 24>>>,
}

pub(super) fn cross_matrix(n: &Vector3<f64>) -> Matrix3<f64> {
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
    let mut cmat = SMatrix::<f64, 24, 3>::zeros();
    // b_i b_jᵀ for (ij) = 00, 01 (+10), 11.
    let b0 = bm.column(0).into_owned();
    let b1 = bm.column(1).into_owned();
    let bb = [
        b0 * b0.transpose(),
        b0 * b1.transpose() + b1 * b0.transpose(),
        b1 * b1.transpose(),
    ];
    // The (c, c2) 3×3 block of hull h's diagonal block: Σ_ij b_i b_jᵀ T_ij[c, c2] / Δt².
    let block = |h: usize, c: usize, c2: usize| {
        (bb[0] * tacc[h][0][(c, c2)] + bb[1] * tacc[h][1][(c, c2)] + bb[2] * tacc[h][2][(c, c2)])
            / (dt * dt)
    };
    for h in 0..2 {
        for c in 0..4 {
            // C rows (c, ·) = −(1/Δt) B P_cᵀ.
            let crow = -(bm * pacc[h][c].transpose()) / dt;
            cmat.fixed_view_mut::<3, 3>(12 * h + 3 * c, 0)
                .copy_from(&crow);
        }
    }
    let w = core.hinv * cmat.transpose(); // 3×24
    // H = Hdiag − C W, written over the product C W in place: each entry is the difference the
    // zero-initialised `H = Hdiag; H −= C W` would round to (`0 − p` off the diagonal blocks),
    // bit for bit, without zero-filling 24×24 first.
    let mut hess = cmat * w;
    for h in 0..2 {
        let off = 12 * h;
        let h_other = 12 * (1 - h);
        for c in 0..4 {
            for c2 in 0..4 {
                let blk = block(h, c, c2);
                let mut view = hess.fixed_view_mut::<3, 3>(off + 3 * c, off + 3 * c2);
                view.zip_apply(&blk, |e, d| *e = d - *e);
            }
            let mut view = hess.fixed_view_mut::<3, 12>(off + 3 * c, h_other);
            view.apply(|e| *e = 0.0 - *e);
        }
    }
    out.hessian = Some(crate::math::symmetric_part_boxed(&hess));
    if need == FrictionNeed::HessianAndMixed {
        let nx = cross_matrix(&frame.normal);
        let qm = Matrix3::identity() / dt + nx * core.q.z;
        // Diagonal part −Δt Hdiag (I₄ ⊗ Q).
        // Hdiag as a 24×24 with zero off-diagonal blocks (as the Hessian's first term).
        let mut hdiag = SMatrix::<f64, 24, 24>::zeros();
        for h in 0..2 {
            for c in 0..4 {
                for c2 in 0..4 {
                    hdiag
                        .fixed_view_mut::<3, 3>(12 * h + 3 * c, 12 * h + 3 * c2)
                        .copy_from(&block(h, c, c2));
                }
            }
        }
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
        out.mixed = Some(Box::new(mixed));
    }
    Ok(out)
}
