//! Contraction of pose-space energy derivatives into generalized coordinates.
//!
//! With `G_i = ∂E/∂A_i` and the kinematic rules of [`crate::kinematics`]:
//!
//! - gradient: `∂E/∂θ_k = Σ_{i ∈ subtree(a)} ⟨G_i, S_k Ã_i⟩ = ⟨S_k, Q_a⟩` with
//!   `Q_a = Σ_{i ∈ subtree(a)} G_i Ã_iᵀ` (one pass from the leaves up: O(links));
//! - Hessian, first-order part: `Σ_i J_iᵀ H_ii J_i + Σ_{i≠j} J_iᵀ H_ij J_j`
//!   where column `k` of `J_i` is `vec(S_k Ã_i)`; for structured blocks
//!   `H_ii = W_i ⊗ I₃` (inertia) this is `⟨S_k, S_l C_b⟩` with the subtree
//!   composite `C_b = Σ_{i ∈ subtree(b)} Ã_i W_i Ã_iᵀ` of the deeper joint `b`
//!   (composite-rigid-body style, O(|θ|²));
//! - Hessian, second-order part: `⟨Q_b, S_k S_l⟩` when `k`'s joint is a proper
//!   ancestor of `l`'s joint `b`, and `⟨Q_a, S_kl⟩` within one joint `a`.

use crate::energy::{EnergyAccumulator, HessEnvelope, Need, PoseHessian};
use crate::kinematics::Kinematics;
use crate::math::homogeneous;
use crate::math::{frob, twist_apply};
use crate::model::Model;
use nalgebra::{DMatrix, DVector, Matrix3x4, Matrix4, SMatrix};
use std::ops::AddAssign;

/// Scratch buffers of the assembler (allocated once).
#[derive(Clone, Debug, Default)]
pub struct AssembleScratch {
    q_sub: Vec<Matrix3x4<f64>>,
    composite: Vec<Matrix4<f64>>,
    jac: Vec<SMatrix<f64, 12, 1>>,
    jac2: Vec<SMatrix<f64, 12, 1>>,
    hj: Vec<SMatrix<f64, 12, 1>>,
    /// Envelope of the non-zeros of the `hess` buffer last written by
    /// [`assemble_swapping`] (or [`assemble`]).
    hess_env: HessEnvelope,
    /// Address of that buffer: a buffer not recognized is copied into, not
    /// swapped (its contents are unknown, and would otherwise come back as
    /// the accumulator's coordinate Hessian).
    hess_id: Option<usize>,
    /// Per link, one past its subtree's last coordinate.
    subtree_end: Vec<usize>,
}

impl AssembleScratch {
    /// Envelope of the non-zeros of the Hessian last assembled (valid for
    /// the buffer it was assembled into, until that buffer is changed).
    pub fn hess_env(&self) -> &HessEnvelope {
        &self.hess_env
    }
}

/// `G Ãᵀ = [G_R Rᵀ + g_t tᵀ | g_t]` for `G = [G_R | g_t]`, `A = [R | t]`.
fn g_atr(g: &Matrix3x4<f64>, a: &Matrix3x4<f64>) -> Matrix3x4<f64> {
    let gt = g.column(3).into_owned();
    let t = a.column(3).into_owned();
    let block =
        g.fixed_view::<3, 3>(0, 0) * a.fixed_view::<3, 3>(0, 0).transpose() + gt * t.transpose();
    let mut out = Matrix3x4::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&block);
    out.set_column(3, &gt);
    out
}

/// Adds the pose-space derivatives in `acc` (plus its direct coordinate
/// terms) into `grad` and `hess` (overwritten), as required by `need`.
pub fn assemble(
    model: &Model,
    kin: &Kinematics,
    acc: &EnergyAccumulator,
    need: Need,
    grad: &mut DVector<f64>,
    hess: &mut DMatrix<f64>,
    scratch: &mut AssembleScratch,
) {
    if need >= Need::Hessian {
        hess.copy_from(acc.dof_hess());
        scratch.hess_env.clone_from(acc.dof_env());
        scratch.hess_id = None;
    }
    assemble_onto_dof_hess(model, kin, acc, need, grad, hess, scratch);
}

/// [`assemble`], taking the coordinate Hessian `acc.dof_hess` by swapping
/// buffers instead of copying it: the accumulator then holds the old
/// contents of `hess` with their envelope, and its next
/// [`EnergyAccumulator::reset`] with [`Need::Hessian`] clears only that
/// envelope (the structural zeros of the tree are never written, so never
/// cleared). `hess` must be the buffer of the previous call (or any buffer
/// the first time: an unrecognized buffer is copied into). At 256
/// coordinates the copy and the clearing were each a 512 kB write per
/// Hessian evaluation. The result is bitwise [`assemble`]'s.
pub fn assemble_swapping(
    model: &Model,
    kin: &Kinematics,
    acc: &mut EnergyAccumulator,
    need: Need,
    grad: &mut DVector<f64>,
    hess: &mut DMatrix<f64>,
    scratch: &mut AssembleScratch,
) {
    if need >= Need::Hessian {
        let n = acc.dof_hess().ncols();
        let known = hess.shape() == acc.dof_hess().shape()
            && scratch.hess_id == Some(hess.as_ptr() as usize)
            && scratch.hess_env.len() == n;
        if known {
            acc.swap_dof_hess(hess, &mut scratch.hess_env);
        } else {
            hess.copy_from(acc.dof_hess());
            scratch.hess_env.clone_from(acc.dof_env());
        }
    }
    assemble_onto_dof_hess(model, kin, acc, need, grad, hess, scratch);
    if need >= Need::Hessian {
        scratch.hess_id = Some(hess.as_ptr() as usize);
    }
}

/// [`assemble`] with `hess` already holding `acc.dof_hess` (when `need`
/// asks for the Hessian).
fn assemble_onto_dof_hess(
    model: &Model,
    kin: &Kinematics,
    acc: &EnergyAccumulator,
    need: Need,
    grad: &mut DVector<f64>,
    hess: &mut DMatrix<f64>,
    scratch: &mut AssembleScratch,
) {
    let nlink = model.links.len();
    if need < Need::Gradient {
        return;
    }
    grad.copy_from(&acc.dof_grad);
    subtree_sums(model, kin, &acc.link_grad, &mut scratch.q_sub);
    add_coordinate_gradient(model, kin, &scratch.q_sub, grad);
    if need < Need::Hessian {
        return;
    }
    // First-order part, diagonal link blocks.
    for i in 0..nlink {
        if !acc.link_hess_set[i] {
            continue;
        }
        let anc = &model.ancestor_dofs[i];
        fill_jacobian(kin, i, anc, &mut scratch.jac);
        let h = &acc.link_hess[i];
        scratch.hj.clear();
        scratch.hj.extend(scratch.jac.iter().map(|c| h * c));
        for (a, &k) in anc.iter().enumerate() {
            for (b, &l) in anc.iter().enumerate().skip(a) {
                let v = scratch.jac[a].dot(&scratch.hj[b]);
                hess[(k, l)] += v;
                if k != l {
                    hess[(l, k)] += v;
                }
            }
        }
    }
    cover_tree(model, &mut scratch.subtree_end, &mut scratch.hess_env);
    for (i, j, _) in &acc.pair_hess {
        cover_pair(model, *i, *j, &mut scratch.hess_env);
    }
    // Subtree composites of the structured blocks W_i ⊗ I₃.
    let moments = acc.link_moment_set;
    if moments {
        subtree_composites(model, kin, &acc.link_moment, &mut scratch.composite);
    }
    // First-order part, coupling blocks between links.
    for (i, j, h) in &acc.pair_hess {
        add_pair_block(model, kin, *i, *j, h, hess, scratch);
    }
    // Structured first-order part and second-order kinematic part, fused.
    add_tree_blocks(model, kin, moments, scratch, hess);
}

/// Adds the tree's pattern to `env`: column `j` of link `a`'s joint may be
/// non-zero in the rows of `a`'s ancestor-or-self coordinates and of its
/// subtree's, i.e. (both sets as one interval) from `a`'s first ancestor
/// coordinate to its subtree's last. Every entry the diagonal link blocks,
/// the composites and the second-order part write is inside.
fn cover_tree(model: &Model, subtree_end: &mut Vec<usize>, env: &mut HessEnvelope) {
    subtree_end.clear();
    subtree_end.extend(model.links.iter().map(|l| l.dof_offset + l.ndof()));
    for i in (0..model.links.len()).rev() {
        if let Some(p) = model.links[i].parent {
            subtree_end[p] = subtree_end[p].max(subtree_end[i]);
        }
    }
    for (a, link) in model.links.iter().enumerate() {
        let Some(&lo) = model.ancestor_dofs[a].first() else {
            continue;
        };
        for j in link.dof_offset..link.dof_offset + link.ndof() {
            env.cover_rows(lo..subtree_end[a], j);
        }
    }
}

/// Adds the block `anc(i) × anc(j)` and its transpose to `env`.
fn cover_pair(model: &Model, i: usize, j: usize, env: &mut HessEnvelope) {
    let (ai, aj) = (&model.ancestor_dofs[i], &model.ancestor_dofs[j]);
    let span = |a: &[usize]| a.first().map_or(0..0, |&f| f..a[a.len() - 1] + 1);
    let (ri, rj) = (span(ai), span(aj));
    for &k in ai {
        env.cover_rows(rj.clone(), k);
    }
    for &l in aj {
        env.cover_rows(ri.clone(), l);
    }
}

/// `C_b = Σ_{i ∈ subtree(b)} Ã_i W_i Ã_iᵀ` for every link `b` (leaves up).
fn subtree_composites(
    model: &Model,
    kin: &Kinematics,
    moments: &[Matrix4<f64>],
    composite: &mut Vec<Matrix4<f64>>,
) {
    composite.clear();
    composite.extend(moments.iter().zip(&kin.pose).map(|(w, p)| {
        let a = homogeneous(p);
        a * w * a.transpose()
    }));
    for i in (0..model.links.len()).rev() {
        if let Some(p) = model.links[i].parent {
            let c = composite[i];
            composite[p] += c;
        }
    }
}

/// The tree-structured part of the Hessian, along ancestor paths only
/// (entry `(k, l)` is touched only when `k`'s joint is an ancestor-or-self
/// of `l`'s joint `b`, and mirrored):
///
/// `H_kl += ⟨S_k, S_l C_b⟩ + ⟨S_k S_l, Q_b⟩` for a proper ancestor `k`, and
/// `H_kl += ⟨S_k, S_l C_b⟩ + ⟨S_kl, Q_b⟩` within joint `b`.
///
/// For a proper ancestor, `S_k S_l = S_k[:, :3] S_l` (twists have a zero
/// homogeneous row), so `⟨S_k S_l, Q_b⟩ = ⟨S_k[:, :3], Q_b S_lᵀ⟩` and both
/// parts are one inner product `⟨S_k, Z_l⟩` with
/// `Z_l = S_l C_b + [Q_b S_lᵀ | 0]` (3×4, built once per coordinate `l`):
/// 12 multiply–adds per entry instead of 60 (the kinematic product
/// `S_k S_l` per entry). `C_b` is zero when no term wrote a structured block.
fn add_tree_blocks(
    model: &Model,
    kin: &Kinematics,
    moments: bool,
    scratch: &AssembleScratch,
    hess: &mut DMatrix<f64>,
) {
    for (b, link) in model.links.iter().enumerate() {
        let nb = link.ndof();
        if nb == 0 {
            continue;
        }
        let qb = &scratch.q_sub[b];
        let ob = link.dof_offset;
        for l in ob..ob + nb {
            let sl = &kin.twist[l];
            let first = if moments {
                sl * scratch.composite[b]
            } else {
                Matrix3x4::zeros()
            };
            let mut z = first;
            let q_st = qb * sl.transpose();
            z.fixed_view_mut::<3, 3>(0, 0).add_assign(&q_st);
            // Proper-ancestor coordinates k of joint b (ascending).
            for &k in &model.ancestor_dofs[b] {
                if k >= ob {
                    break;
                }
                let v = frob(&kin.twist[k], &z);
                hess[(k, l)] += v;
                hess[(l, k)] += v;
            }
            // Same joint: the first-order part is symmetric, the second-order
            // `S_kl` need not be bitwise so.
            for k in ob..=l {
                let c = if moments {
                    frob(&kin.twist[k], &first)
                } else {
                    0.0
                };
                hess[(k, l)] += c + frob(kin.twist2(model, b, k, l), qb);
                if k != l {
                    hess[(l, k)] += c + frob(kin.twist2(model, b, l, k), qb);
                }
            }
        }
    }
}

/// `Q_a = Σ_{i ∈ subtree(a)} G_i Ã_iᵀ` for every link `a` (leaves up).
pub fn subtree_sums(
    model: &Model,
    kin: &Kinematics,
    link_grad: &[Matrix3x4<f64>],
    q_sub: &mut Vec<Matrix3x4<f64>>,
) {
    q_sub.clear();
    q_sub.extend(link_grad.iter().zip(&kin.pose).map(|(g, a)| g_atr(g, a)));
    for i in (0..model.links.len()).rev() {
        if let Some(p) = model.links[i].parent {
            let qi = q_sub[i];
            q_sub[p] += qi;
        }
    }
}

/// `grad_k += ⟨S_k, Q_a⟩` for every coordinate `k` of joint `a`.
pub fn add_coordinate_gradient(
    model: &Model,
    kin: &Kinematics,
    q_sub: &[Matrix3x4<f64>],
    grad: &mut DVector<f64>,
) {
    for (i, link) in model.links.iter().enumerate() {
        for k in link.dof_offset..link.dof_offset + link.ndof() {
            grad[k] += frob(&kin.twist[k], &q_sub[i]);
        }
    }
}

/// `Σ_i ⟨G_i, ∂A_i/∂θ⟩`: a pose-space gradient as a coordinate gradient.
pub fn contract_gradient(
    model: &Model,
    kin: &Kinematics,
    link_grad: &[Matrix3x4<f64>],
) -> DVector<f64> {
    let mut q_sub = Vec::new();
    subtree_sums(model, kin, link_grad, &mut q_sub);
    let mut g = DVector::zeros(model.ndof());
    add_coordinate_gradient(model, kin, &q_sub, &mut g);
    g
}

fn fill_jacobian(kin: &Kinematics, link: usize, anc: &[usize], out: &mut Vec<SMatrix<f64, 12, 1>>) {
    out.clear();
    out.extend(anc.iter().map(|&k| {
        let d = twist_apply(&kin.twist[k], &kin.pose[link]);
        SMatrix::<f64, 12, 1>::from_column_slice(d.as_slice())
    }));
}

fn add_pair_block(
    model: &Model,
    kin: &Kinematics,
    i: usize,
    j: usize,
    h: &PoseHessian,
    hess: &mut DMatrix<f64>,
    scratch: &mut AssembleScratch,
) {
    let anc_i = &model.ancestor_dofs[i];
    let anc_j = &model.ancestor_dofs[j];
    fill_jacobian(kin, i, anc_i, &mut scratch.jac);
    fill_jacobian(kin, j, anc_j, &mut scratch.jac2);
    scratch.hj.clear();
    scratch.hj.extend(scratch.jac2.iter().map(|c| h * c));
    for (a, &k) in anc_i.iter().enumerate() {
        for (b, &l) in anc_j.iter().enumerate() {
            let v = scratch.jac[a].dot(&scratch.hj[b]);
            hess[(k, l)] += v;
            hess[(l, k)] += v;
        }
    }
}
