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

use super::envelope::ColumnEnvelope;
use crate::energy::{EnergyAccumulator, Need, PoseHessian};
use crate::kinematics::Kinematics;
use crate::math::homogeneous;
use crate::math::{frob, twist_apply, twist_mul};
use crate::model::Model;
use nalgebra::{DMatrix, DVector, Matrix3x4, Matrix4, SMatrix};

/// Scratch buffers of the assembler (allocated once).
#[derive(Clone, Debug, Default)]
pub struct AssembleScratch {
    q_sub: Vec<Matrix3x4<f64>>,
    composite: Vec<Matrix4<f64>>,
    jac: Vec<SMatrix<f64, 12, 1>>,
    jac2: Vec<SMatrix<f64, 12, 1>>,
    hj: Vec<SMatrix<f64, 12, 1>>,
    envelope: ColumnEnvelope,
    /// Address and size of the buffer the last Hessian was written into.
    written: Option<(usize, usize)>,
}

impl AssembleScratch {
    /// The envelope of the last assembled Hessian.
    pub fn envelope(&self) -> &ColumnEnvelope {
        &self.envelope
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
///
/// `hess` is cleared over the envelope of the Hessian this scratch last
/// wrote into the same buffer (entries outside it are zero already), or
/// whole when the buffer or its size changed; `scratch.envelope()` is then
/// the new Hessian's [`ColumnEnvelope`]. (The buffer is recognized by its
/// address and size: a caller must not hand in a different non-zero matrix
/// at the address of the last one.)
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
        let n = hess.nrows();
        let id = (hess.as_ptr() as usize, n);
        if scratch.written == Some(id) && scratch.envelope.len() == n {
            scratch.envelope.zero(hess);
        } else {
            hess.fill(0.0);
        }
        scratch.envelope.build(model, acc);
        scratch.written = Some(id);
        for (k, v) in acc.dof_hess.diagonal().iter().enumerate() {
            hess[(k, k)] = *v;
        }
        for &((k, l), v) in acc.dof_hess.off_diagonal() {
            hess[(k, l)] = v;
        }
    }
    if need < Need::Gradient {
        return;
    }
    grad.copy_from(&acc.dof_grad);
    subtree_sums(model, kin, &acc.link_grad, &mut scratch.q_sub);
    add_coordinate_gradient(model, kin, &scratch.q_sub, grad);
    if need < Need::Hessian {
        return;
    }
    add_link_blocks(model, kin, acc, hess, scratch);
    if acc.link_moment_set {
        fill_composites(model, kin, acc, &mut scratch.composite);
        add_composite_terms(model, kin, hess, scratch);
    }
    for (i, j, h) in &acc.pair_hess {
        add_pair_block(model, kin, *i, *j, h, hess, scratch);
    }
    add_second_order(model, kin, hess, scratch);
}

/// First-order part of the diagonal link blocks, `J_iᵀ H_ii J_i` (both
/// triangles, each entry's two copies with the same additions in the same
/// order: the Hessian stays exactly symmetric).
fn add_link_blocks(
    model: &Model,
    kin: &Kinematics,
    acc: &EnergyAccumulator,
    hess: &mut DMatrix<f64>,
    scratch: &mut AssembleScratch,
) {
    for i in 0..model.links.len() {
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
}

/// Subtree composites `C_b = Σ_{i ∈ subtree(b)} Ã_i W_i Ã_iᵀ` (leaves up).
fn fill_composites(
    model: &Model,
    kin: &Kinematics,
    acc: &EnergyAccumulator,
    composite: &mut Vec<Matrix4<f64>>,
) {
    composite.clear();
    composite.extend((0..model.links.len()).map(|i| {
        let a = homogeneous(&kin.pose[i]);
        a * acc.link_moment[i] * a.transpose()
    }));
    for i in (0..model.links.len()).rev() {
        if let Some(p) = model.links[i].parent {
            let c = composite[i];
            composite[p] += c;
        }
    }
}

/// Structured first-order part `W_i ⊗ I₃` (inertia) through the subtree
/// composites: `⟨S_k, S_l C_b⟩` for each coordinate `l` of joint `b` and
/// each coordinate `k ≤ l` of `b` or of its ancestors.
fn add_composite_terms(
    model: &Model,
    kin: &Kinematics,
    hess: &mut DMatrix<f64>,
    scratch: &AssembleScratch,
) {
    for (b, link) in model.links.iter().enumerate() {
        let ob = link.dof_offset;
        for l in ob..ob + link.ndof() {
            let y = kin.twist[l] * scratch.composite[b];
            for &k in &model.ancestor_dofs[b] {
                if k > l {
                    break; // same-joint pairs once (k ≤ l)
                }
                let v = frob(&kin.twist[k], &y);
                hess[(k, l)] += v;
                if k != l {
                    hess[(l, k)] += v;
                }
            }
        }
    }
}

/// Second-order kinematic part: `⟨Q_b, S_kl⟩` within joint `b`,
/// `⟨Q_b, S_k S_l⟩` for a coordinate `k` of a proper ancestor of `b`.
fn add_second_order(
    model: &Model,
    kin: &Kinematics,
    hess: &mut DMatrix<f64>,
    scratch: &AssembleScratch,
) {
    for (b, link) in model.links.iter().enumerate() {
        let nb = link.ndof();
        if nb == 0 {
            continue;
        }
        let qb = &scratch.q_sub[b];
        let ob = link.dof_offset;
        for l in ob..ob + nb {
            for k in ob..ob + nb {
                hess[(k, l)] += frob(kin.twist2(model, b, k, l), qb);
            }
            for &k in &model.ancestor_dofs[b] {
                if k >= ob {
                    break;
                }
                let v = frob(&twist_mul(&kin.twist[k], &kin.twist[l]), qb);
                hess[(k, l)] += v;
                hess[(l, k)] += v;
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
