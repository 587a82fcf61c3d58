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
    let core = solve_pair(frame, a, b, params, &mut scratch.act)?;
    Ok(assemble_pair(
        frame,
        a,
        b,
        params,
        need,
        &scratch.act,
        &core,
    ))
}

/// The inner solution of one pair kept for its next evaluation ([`friction_pair_memo`]): the
/// active-vertex list and the inner optimum, with the bits of the two step-`t+1` poses and of
/// the parameters they were computed at. Empty (`key: None`) until the first solve, and after
/// [`FrictionMemo::clear`] or a failed solve.
#[derive(Clone, Debug, Default)]
pub struct FrictionMemo {
    key: Option<MemoKey>,
    act: Vec<Active>,
    core: Option<Core>,
}

/// The bits of the inputs a memo's solution was computed at (the frame is not part of it: a
/// memo belongs to one lagged pair and is cleared with it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct MemoKey {
    poses: [[u64; 12]; 2],
    params: [u64; 7],
}

impl MemoKey {
    fn new(a: &HullPose<'_>, b: &HullPose<'_>, p: &FrictionParams) -> MemoKey {
        let bits = |m: &Matrix3x4<f64>| std::array::from_fn(|i| m.as_slice()[i].to_bits());
        let params = [
            p.mu,
            p.dt,
            p.eps_velocity,
            p.eps_force,
            p.inner_tol,
            p.inner_rtol,
            p.inner_max_iters as f64,
        ];
        MemoKey {
            poses: [bits(a.pose), bits(b.pose)],
            params: params.map(f64::to_bits),
        }
    }
}

impl FrictionMemo {
    /// Forgets the kept solution (new lagged data).
    pub fn clear(&mut self) {
        self.key = None;
        self.core = None;
    }
}

/// [`friction_pair`] for the lagged pair whose last solution `memo` keeps: when `a`, `b` and
/// `params` have the bits of that solve's, its active vertices and inner optimum are taken
/// instead of solving again (`prepare` and `solve_inner` are pure functions of the frame, the
/// poses, the local vertices and the parameters, so the solve would return the same bits);
/// the derivatives `need` asks for are assembled from them as in [`friction_pair`]. The
/// caller must pass the same `frame` (and local vertices) for every call with one memo, and
/// [`FrictionMemo::clear`] it when the frame changes. A Newton step evaluates an accepted
/// point again with its Hessian at the same poses (measured in notes/performance.md,
/// 2026-12-07, twenty-first session, helper 4: 10.8 % of the pair evaluations at N = 8).
pub fn friction_pair_memo(
    frame: &FrictionFrame<'_>,
    a: HullPose<'_>,
    b: HullPose<'_>,
    params: &FrictionParams,
    need: FrictionNeed,
    memo: &mut FrictionMemo,
) -> Result<FrictionPair, FrictionError> {
    let key = MemoKey::new(&a, &b, params);
    let core = match memo.core {
        Some(core) if memo.key == Some(key) => core,
        _ => {
            memo.clear();
            let core = solve_pair(frame, a, b, params, &mut memo.act)?;
            memo.key = Some(key);
            memo.core = Some(core);
            core
        }
    };
    Ok(assemble_pair(frame, a, b, params, need, &memo.act, &core))
}

/// The active vertices of the pair into `act` and the inner optimum over `q = (u, ω)`.
fn solve_pair(
    frame: &FrictionFrame<'_>,
    a: HullPose<'_>,
    b: HullPose<'_>,
    params: &FrictionParams,
    act: &mut Vec<Active>,
) -> Result<Core, FrictionError> {
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
        act,
    )?;
    solve_inner(act, spin_free, params)
}

/// `U_f` and the derivatives `need` asks for from the active vertices and the inner optimum:
/// `∂U/∂A_h = (1/Δt) B R_hᵀ`, the Hessian and the mixed block from [`PairSums`].
fn assemble_pair(
    frame: &FrictionFrame<'_>,
    a: HullPose<'_>,
    b: HullPose<'_>,
    params: &FrictionParams,
    need: FrictionNeed,
    act: &[Active],
    core: &Core,
) -> FrictionPair {
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
        return out;
    }
    let dt = params.dt;
    let bm = frame.basis;
    let second = need >= FrictionNeed::Hessian;
    let mut sums = PairSums::zeros();
    sums.accumulate(
        act,
        [a.x_local, b.x_local],
        core,
        params.eps_velocity,
        second,
    );
    // ∂U/∂A_h = (1/Δt) B Rᵀ.
    out.grad_a = bm * sums.r[0].transpose() / dt;
    out.grad_b = bm * sums.r[1].transpose() / dt;
    if !second {
        return out;
    }
    let cmat = sums.c_matrix(&bm, dt);
    out.hessian = Some(sums.hessian(&bm, &cmat, core, dt));
    if need == FrictionNeed::HessianAndMixed {
        let mixed = mixed_block(&frame.normal, core, dt, &bm, &sums, &cmat);
        out.mixed = Some(Box::new(mixed));
    }
    out
}

/// Per-hull sums over the force-carrying vertices (`x̃ = [x_local; 1]`, `w` the vertex's
/// weight, `ρ` and `Φ` the inner solution's per-vertex gradient and Hessian terms, see
/// `vertex_terms`), from which the gradient and both Hessians are contracted.
struct PairSums {
    /// `R_h = Σ x̃ (wρ)ᵀ` (4×2).
    r: [SMatrix<f64, 4, 2>; 2],
    /// `T_h,k = Σ w Φ_ij x̃x̃ᵀ` for `(ij)` = 00, 01, 11 (only for a Hessian).
    t: [[Matrix4<f64>; 3]; 2],
    /// `P_h,c = Σ x̃_c w JᵀΦ` (3×2 each; only for a Hessian).
    p: [[Matrix3x2<f64>; 4]; 2],
}

impl PairSums {
    /// All sums zero.
    fn zeros() -> PairSums {
        PairSums {
            r: [SMatrix::<f64, 4, 2>::zeros(); 2],
            t: [[Matrix4::<f64>::zeros(); 3]; 2],
            p: [[Matrix3x2::<f64>::zeros(); 4]; 2],
        }
    }

    /// Adds one pass over the active vertices; `second` adds `T` and `P`.
    #[inline(always)]
    fn accumulate(
        &mut self,
        act: &[Active],
        locals: [&[Vector3<f64>]; 2],
        core: &Core,
        eps: f64,
        second: bool,
    ) {
        let s = self;
        for act in act {
            let (_, _, rho, bp) = vertex_terms(act, &core.q, eps);
            let xl = locals[act.hull][act.index];
            let xt = Vector4::new(xl.x, xl.y, xl.z, 1.0);
            s.r[act.hull] += xt * (act.w * rho).transpose();
            if second {
                let outer = xt * xt.transpose();
                s.t[act.hull][0] += outer * (act.w * bp[(0, 0)]);
                s.t[act.hull][1] += outer * (act.w * bp[(0, 1)]);
                s.t[act.hull][2] += outer * (act.w * bp[(1, 1)]);
                let g = if core.spin_free {
                    Vector2::zeros()
                } else {
                    act.g
                };
                let pg = bp * g;
                let pm = Matrix3x2::new(bp[(0, 0)], bp[(0, 1)], bp[(1, 0)], bp[(1, 1)], pg.x, pg.y)
                    * act.w;
                for c in 0..4 {
                    s.p[act.hull][c] += pm * xt[c];
                }
            }
        }
    }

    /// The `(c, c2)` 3×3 block of hull `h`'s diagonal block `Hdiag`:
    /// `Σ_ij b_i b_jᵀ T_ij[c, c2] / Δt²` (`bb` = `b_i b_jᵀ` for 00, 01 + 10, 11).
    #[inline(always)]
    fn block(
        &self,
        bb: &[Matrix3<f64>; 3],
        h: usize,
        c: usize,
        c2: usize,
        dt: f64,
    ) -> Matrix3<f64> {
        let t = &self.t[h];
        (bb[0] * t[0][(c, c2)] + bb[1] * t[1][(c, c2)] + bb[2] * t[2][(c, c2)]) / (dt * dt)
    }

    /// `C` (24×3): rows `(h, c, ·) = −(1/Δt) B P_h,cᵀ`.
    fn c_matrix(&self, bm: &Matrix3x2<f64>, dt: f64) -> SMatrix<f64, 24, 3> {
        let mut cmat = SMatrix::<f64, 24, 3>::zeros();
        for h in 0..2 {
            for c in 0..4 {
                let crow = -(bm * self.p[h][c].transpose()) / dt;
                cmat.fixed_view_mut::<3, 3>(12 * h + 3 * c, 0)
                    .copy_from(&crow);
            }
        }
        cmat
    }

    /// `∂²U_f/∂(A^{t+1})² = Hdiag − C H⁻¹ Cᵀ` (symmetrized), written over the product
    /// `C W` (`W = H⁻¹ Cᵀ`) in place: each entry is the difference the zero-initialised
    /// `H = Hdiag; H −= C W` would round to (`0 − p` off the diagonal blocks), bit for bit,
    /// without zero-filling 24×24 first.
    fn hessian(
        &self,
        bm: &Matrix3x2<f64>,
        cmat: &SMatrix<f64, 24, 3>,
        core: &Core,
        dt: f64,
    ) -> Box<SMatrix<f64, 24, 24>> {
        let bb = basis_outer(bm);
        let w = core.hinv * cmat.transpose(); // 3×24
        let mut hess = cmat * w;
        for h in 0..2 {
            let off = 12 * h;
            let h_other = 12 * (1 - h);
            for c in 0..4 {
                for c2 in 0..4 {
                    let blk = self.block(&bb, h, c, c2, dt);
                    let mut view = hess.fixed_view_mut::<3, 3>(off + 3 * c, off + 3 * c2);
                    view.zip_apply(&blk, |e, d| *e = d - *e);
                }
                let mut view = hess.fixed_view_mut::<3, 12>(off + 3 * c, h_other);
                view.apply(|e| *e = 0.0 - *e);
            }
        }
        crate::math::symmetric_part_boxed(&hess)
    }
}

/// `b_i b_jᵀ` of the basis columns for `(ij)` = 00, 01 (+ 10), 11.
fn basis_outer(bm: &Matrix3x2<f64>) -> [Matrix3<f64>; 3] {
    let b0 = bm.column(0).into_owned();
    let b1 = bm.column(1).into_owned();
    [
        b0 * b0.transpose(),
        b0 * b1.transpose() + b1 * b0.transpose(),
        b1 * b1.transpose(),
    ]
}

/// The adjoint's mixed block `∂²U_f/∂A^{t+1}∂A^t` of one pair (paper Eq.
/// `derivativeFriction2`), for fixed lagged normal `n̂`, basis `B` and forces:
///
/// `−Δt Hdiag (I₄ ⊗ Q) − C H⁻¹ U*_{qX}`, with `Q = I/Δt + ω* [n̂]×` and `U*_{qX}` in pose
/// columns `(h, c, r)`: `P_c BᵀQ − e₃ (B R[c])ᵀ [n̂]×` (the second term only when the spin
/// `ω*` is kept). `Hdiag`'s blocks between the two hulls are zero; those blocks of the
/// diagonal part are computed as `0 · Q · (−Δt)`, the bits of a zero-padded product.
fn mixed_block(
    normal: &Vector3<f64>,
    core: &Core,
    dt: f64,
    bm: &Matrix3x2<f64>,
    sums: &PairSums,
    cmat: &SMatrix<f64, 24, 3>,
) -> SMatrix<f64, 24, 24> {
    let bb = basis_outer(bm);
    let nx = cross_matrix(normal);
    let qm = Matrix3::identity() / dt + nx * core.q.z;
    let mut mixed = SMatrix::<f64, 24, 24>::zeros();
    for bi in 0..8 {
        for bj in 0..8 {
            let d = if bi / 4 == bj / 4 {
                sums.block(&bb, bi / 4, bi % 4, bj % 4, dt)
            } else {
                Matrix3::zeros()
            };
            mixed
                .fixed_view_mut::<3, 3>(3 * bi, 3 * bj)
                .copy_from(&(d * qm * (-dt)));
        }
    }
    let btq = bm.transpose() * qm;
    let mut qx = SMatrix::<f64, 3, 24>::zeros();
    for (h, (p_h, r_h)) in sums.p.iter().zip(&sums.r).enumerate() {
        for (c, p_hc) in p_h.iter().enumerate() {
            let mut blk = p_hc * btq;
            if !core.spin_free {
                let brc = bm * r_h.row(c).transpose();
                let row = brc.transpose() * nx;
                for r in 0..3 {
                    blk[(2, r)] -= row[r];
                }
            }
            qx.fixed_view_mut::<3, 3>(0, 12 * h + 3 * c).copy_from(&blk);
        }
    }
    mixed -= cmat * (core.hinv * qx);
    mixed
}
