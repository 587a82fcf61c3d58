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
//!
//! The structured first-order part and the second-order part are one inner
//! product per entry (`⟨S_k, Z_l⟩`, see `add_tree_blocks`), written only
//! along ancestor paths; with the contact pairs' blocks and the coordinate
//! terms' entries they form the Hessian's envelope
//! ([`crate::energy::HessEnvelope`]): the buffers are cleared and scanned
//! there only, never over the tree's structural zeros.

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::KinOrder;
    use crate::math::twist_mul;
    use crate::scene::Scene;
    use nalgebra::{Matrix3, Vector3};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::path::Path;

    /// A branching robot (ball, revolute, prismatic, fixed joints; two
    /// branches off the base) and a second, free-floating robot.
    const TREE: &str = r#"
dt: 0.01
robots:
  - name: t
    links:
      - name: base
        joint: {name: j0, type: ball, axes: [[1, 0, 0], [0, 1, 0]]}
        mass: 1.0
        hulls: [{box: {size: [0.2, 0.2, 0.2]}}]
      - name: a
        parent: base
        joint: {name: ja, type: revolute, axis: [0, 1, 0], origin: {xyz: [0.2, 0, 0]}}
        mass: 0.5
        hulls: [{box: {size: [0.3, 0.1, 0.1], center: [0.15, 0, 0]}}]
      - name: a2
        parent: a
        joint: {name: ja2, type: prismatic, axis: [1, 0, 0], origin: {xyz: [0.3, 0, 0]}}
        mass: 0.4
        hulls: [{box: {size: [0.2, 0.1, 0.1]}}]
      - name: b
        parent: base
        joint: {name: jb, type: ball, axes: [[1, 0, 0], [0, 0, 1]], origin: {xyz: [-0.2, 0, 0]}}
        mass: 0.5
        hulls: [{box: {size: [0.3, 0.1, 0.1], center: [-0.15, 0, 0]}}]
      - name: b2
        parent: b
        joint: {name: jb2, type: fixed, origin: {xyz: [-0.3, 0, 0]}}
        mass: 0.2
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
      - name: b3
        parent: b2
        joint: {name: jb3, type: revolute, axis: [0, 0, 1], origin: {xyz: [-0.1, 0, 0]}}
        mass: 0.2
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
  - name: f
    links:
      - name: body
        joint: {name: free, type: free}
        mass: 1.0
        hulls: [{box: {size: [0.3, 0.2, 0.1]}}]
"#;

    fn random_sym<const N: usize>(rng: &mut ChaCha8Rng) -> SMatrix<f64, N, N> {
        let a = SMatrix::<f64, N, N>::from_fn(|_, _| rng.random_range(-1.0..1.0));
        a + a.transpose()
    }

    /// Fills `acc` as the terms would: pose gradients, structured and general
    /// diagonal pose blocks, pair blocks `pairs`, coordinate entries.
    fn fill(
        rng: &mut ChaCha8Rng,
        model: &Model,
        acc: &mut EnergyAccumulator,
        pairs: &[(usize, usize)],
    ) {
        let n = model.ndof();
        acc.reset(Need::Hessian);
        for i in 0..model.links.len() {
            acc.link_grad[i] = Matrix3x4::from_fn(|_, _| rng.random_range(-1.0..1.0));
            acc.link_moment[i] = random_sym::<4>(rng);
            if rng.random_range(0.0..1.0) < 0.5 {
                acc.add_link_hess(i, &random_sym::<12>(rng));
            }
        }
        acc.link_moment_set = true;
        for &(i, j) in pairs {
            let h = PoseHessian::from_fn(|_, _| rng.random_range(-1.0..1.0));
            acc.pair_hess.push((i, j, h));
        }
        for k in 0..n {
            acc.add_dof_hess(k, k, rng.random_range(0.0..1.0));
        }
        let (d, m) = (rng.random_range(0..n), rng.random_range(0..n));
        let v = rng.random_range(-1.0..1.0);
        acc.add_dof_hess(d, m, v);
        acc.add_dof_hess(m, d, v);
    }

    /// The fused tree part (`⟨S_k, Z_l⟩`) against the textbook form it
    /// replaces: composites `⟨S_k, S_l C_b⟩` plus second-order
    /// `⟨S_k S_l, Q_b⟩` / `⟨S_kl, Q_b⟩`, entry by entry.
    fn textbook_tree(model: &Model, kin: &Kinematics, acc: &EnergyAccumulator) -> DMatrix<f64> {
        let n = model.ndof();
        let mut h = DMatrix::zeros(n, n);
        let mut q_sub = Vec::new();
        subtree_sums(model, kin, &acc.link_grad, &mut q_sub);
        let mut comp = Vec::new();
        subtree_composites(model, kin, &acc.link_moment, &mut comp);
        for (b, link) in model.links.iter().enumerate() {
            let ob = link.dof_offset;
            for l in ob..ob + link.ndof() {
                for &k in &model.ancestor_dofs[b] {
                    let first = frob(&kin.twist[k], &(kin.twist[l] * comp[b]));
                    let second = if k < ob {
                        frob(&twist_mul(&kin.twist[k], &kin.twist[l]), &q_sub[b])
                    } else {
                        frob(kin.twist2(model, b, k, l), &q_sub[b])
                    };
                    h[(k, l)] += first + second;
                    if k < ob {
                        h[(l, k)] += first + second;
                    }
                }
            }
        }
        h
    }

    /// Swapped assembly with envelope-limited clearing equals a fresh
    /// assembly bit for bit over a sequence of evaluations whose contact
    /// pairs and coordinate entries change (a stale entry left by a
    /// too-small envelope would show); the envelope covers every non-zero;
    /// the fused tree part equals the textbook form to round-off.
    #[test]
    fn swapped_assembly_with_envelope_clearing_equals_fresh_assembly() {
        let scene = Scene::from_str(TREE, Path::new("tree.yaml")).unwrap();
        let model = &scene.model;
        let n = model.ndof();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut kin = Kinematics::new(model);
        let mut acc = EnergyAccumulator::new(model);
        let mut scratch = AssembleScratch::default();
        let (mut g, mut h) = (DVector::zeros(n), DMatrix::zeros(n, n));
        let pair_sets: [&[(usize, usize)]; 6] =
            [&[(2, 6)], &[], &[(5, 6), (2, 5)], &[(0, 6)], &[], &[(2, 3)]];
        for (t, pairs) in pair_sets.iter().enumerate() {
            let q = DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
            let charts: Vec<Matrix3<f64>> = (0..model.nchart)
                .map(|_| {
                    let w = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
                    crate::math::so3::exp(&w)
                })
                .collect();
            kin.update(model, &q, &charts, KinOrder::Second);
            fill(&mut rng, model, &mut acc, pairs);
            // Before the swap hands the accumulator another buffer.
            let want = textbook_tree(model, &kin, &acc) + blocks_alone(model, &kin, &acc);
            let (mut g_ref, mut h_ref) = (DVector::zeros(n), DMatrix::zeros(n, n));
            let mut fresh = AssembleScratch::default();
            assemble(
                model,
                &kin,
                &acc,
                Need::Hessian,
                &mut g_ref,
                &mut h_ref,
                &mut fresh,
            );
            assemble_swapping(
                model,
                &kin,
                &mut acc,
                Need::Hessian,
                &mut g,
                &mut h,
                &mut scratch,
            );
            assert_eq!(g, g_ref, "eval {t}: gradient");
            for j in 0..n {
                for i in 0..n {
                    assert_eq!(
                        h[(i, j)].to_bits(),
                        h_ref[(i, j)].to_bits(),
                        "eval {t}: ({i}, {j})"
                    );
                    if h[(i, j)] != 0.0 {
                        assert!(
                            scratch.hess_env().rows(j).contains(&i),
                            "eval {t}: ({i}, {j}) outside"
                        );
                    }
                }
            }
            let err = (&h - &want).amax() / want.amax();
            assert!(err < 1e-13, "eval {t}: fused vs textbook {err:.2e}");
        }
    }

    /// The coordinate entries, diagonal link blocks and pair blocks alone.
    fn blocks_alone(model: &Model, kin: &Kinematics, acc: &EnergyAccumulator) -> DMatrix<f64> {
        let mut h = acc.dof_hess().clone();
        let mut s = AssembleScratch::default();
        for i in 0..model.links.len() {
            if !acc.link_hess_set[i] {
                continue;
            }
            let anc = &model.ancestor_dofs[i];
            fill_jacobian(kin, i, anc, &mut s.jac);
            for (a, &k) in anc.iter().enumerate() {
                for (b, &l) in anc.iter().enumerate() {
                    h[(k, l)] += s.jac[a].dot(&(acc.link_hess[i] * s.jac[b]));
                }
            }
        }
        for (i, j, ph) in &acc.pair_hess {
            add_pair_block(model, kin, *i, *j, ph, &mut h, &mut s);
        }
        h
    }
}
