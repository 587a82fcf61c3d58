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
//! - general blocks (contact, friction, pose targets) in twist form: with
//!   `s_k = (ω_k, v_k)` the world twist of coordinate `k` as a 6-vector and
//!   `vec(S_k Ã_i) = L_i s_k` ([`twist_jacobian`]), `J_iᵀ H_ij J_j` has the
//!   entries `s_kᵀ M_ij s_l` with the 6×6 `M_ij = L_iᵀ H_ij L_j`. Diagonal
//!   blocks are summed into subtree composites `Σ_{i ∈ subtree(b)} M_ii`
//!   and enter the tree pass like the inertia's (entry `(k, l)` of the
//!   deeper joint `b`: `s_kᵀ (Σ M_ii) s_l`); pair blocks are contracted pair
//!   by pair, six products per entry.

use super::envelope::ColumnEnvelope;
use crate::energy::{EnergyAccumulator, Need, PoseHessian};
use crate::kinematics::Kinematics;
use crate::math::frob;
use crate::math::homogeneous;
use crate::model::Model;
use nalgebra::{DMatrix, DVector, Matrix3x4, Matrix4, Matrix6, SMatrix, Vector6};

/// Scratch buffers of the assembler (allocated once).
#[derive(Clone, Debug, Default)]
pub struct AssembleScratch {
    q_sub: Vec<Matrix3x4<f64>>,
    composite: Vec<Matrix4<f64>>,
    /// `(ω_k, v_k)` of every coordinate's twist ([`twist_vector`]).
    twist6: Vec<[f64; 6]>,
    /// Subtree sums of the diagonal blocks in twist form,
    /// `Σ_{i ∈ subtree(b)} L_iᵀ H_ii L_i` ([`fill_twist_composites`]).
    twist_composite: Vec<Matrix6<f64>>,
    /// `M s_l` of a pair block for every coordinate `l` of the second link.
    pair_u: Vec<[f64; 6]>,
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

/// [`assemble`] of the Hessian into a fresh zero matrix with a fresh
/// scratch (the gradient is computed and dropped): for one-off assemblies
/// (the mass matrix, reference checks) that reuse no buffer.
pub fn assemble_hessian(model: &Model, kin: &Kinematics, acc: &EnergyAccumulator) -> DMatrix<f64> {
    let n = model.ndof();
    let (mut grad, mut hess) = (DVector::zeros(n), DMatrix::zeros(n, n));
    let mut scratch = AssembleScratch::default();
    assemble(
        model,
        kin,
        acc,
        Need::Hessian,
        &mut grad,
        &mut hess,
        &mut scratch,
    );
    hess
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
    scratch.twist6.clear();
    scratch.twist6.extend(kin.twist.iter().map(twist_vector));
    let blocks = fill_twist_composites(model, kin, acc, &mut scratch.twist_composite);
    if acc.link_moment_set {
        fill_composites(model, kin, acc, &mut scratch.composite);
    }
    add_tree_terms(model, kin, acc.link_moment_set, blocks, hess, scratch);
    for (i, j, h) in &acc.pair_hess {
        add_pair_block(model, kin, *i, *j, h, hess, scratch);
    }
    mirror_upper(&scratch.envelope, hess);
}

/// `L` with `vec(S Ã) = L s` for every twist `S = [[ω]× | v]`, `s = (ω, v)`,
/// at the pose `A = [R | t]` (12×6, `vec` column by column): `S Ã = [[ω]× R |
/// [ω]× t + v]`, and `[ω]× x = −[x]× ω` for each column `x` of `R` and for `t`.
fn twist_jacobian(a: &Matrix3x4<f64>) -> SMatrix<f64, 12, 6> {
    let mut l = SMatrix::<f64, 12, 6>::zeros();
    for c in 0..4 {
        let x = a.column(c);
        let mut block = l.fixed_view_mut::<3, 3>(3 * c, 0);
        block[(0, 1)] = x[2];
        block[(0, 2)] = -x[1];
        block[(1, 0)] = -x[2];
        block[(1, 2)] = x[0];
        block[(2, 0)] = x[1];
        block[(2, 1)] = -x[0];
    }
    l[(9, 3)] = 1.0;
    l[(10, 4)] = 1.0;
    l[(11, 5)] = 1.0;
    l
}

/// `L_aᵀ H L_b` ([`twist_jacobian`]): a pose-space block `∂²E/∂A_a∂A_b` as
/// the 6×6 form on the two links' world twists.
///
/// `L`'s structural zeros are skipped: column `j < 3` of `L` (the `ω_j` part)
/// is non-zero in rows `3c + r` with `r ≠ j` only (eight of twelve), column
/// `j ≥ 3` in row `9 + (j − 3)` only (a 1). `H L` sums `H_{:,k} L_{kj}` over
/// the non-zero `k` in ascending order, as nalgebra's product does over all
/// `k`; `Lᵀ (H L)` is [`l_col_dot`], nalgebra's dot with the zero products
/// left out. A left-out product is `±0`, and `x + (±0) = x` for `x ≠ 0`, so the
/// entries are those of the dense `twist_jacobian(a).tr_mul(&(h * twist_jacobian(b)))`
/// bit for bit but for the sign of an exact zero.
fn twist_block(h: &SMatrix<f64, 12, 12>, a: &Matrix3x4<f64>, b: &Matrix3x4<f64>) -> Matrix6<f64> {
    let lb = twist_jacobian(b);
    let mut hl = SMatrix::<f64, 12, 6>::zeros();
    for j in 0..6 {
        let rows = l_rows(j);
        let (k0, rest) = rows.split_first().expect("every column has a non-zero");
        let mut y = h.column(*k0) * lb[(*k0, j)];
        for &k in rest {
            y += h.column(k) * lb[(k, j)];
        }
        hl.set_column(j, &y);
    }
    let la = twist_jacobian(a);
    Matrix6::from_fn(|i, j| l_col_dot(&la, i, &hl, j))
}

/// Rows of column `j` of [`twist_jacobian`] that can be non-zero, ascending.
fn l_rows(j: usize) -> &'static [usize] {
    match j {
        0 => &[1, 2, 4, 5, 7, 8, 10, 11],
        1 => &[0, 2, 3, 5, 6, 8, 9, 11],
        2 => &[0, 1, 3, 4, 6, 7, 9, 10],
        3 => &[9],
        4 => &[10],
        _ => &[11],
    }
}

/// `L_{:,i} · Y_{:,j}` (length 12) in the order of nalgebra's `dot` — eight
/// lanes `p_0 … p_7`, then `((((0 + (p₀+p₄)) + (p₁+p₅)) + (p₂+p₆)) + (p₃+p₇)) + p₈ + p₉ +
/// p₁₀ + p₁₁` — with the products of `L`'s structural zeros left out.
fn l_col_dot(l: &SMatrix<f64, 12, 6>, i: usize, y: &SMatrix<f64, 12, 6>, j: usize) -> f64 {
    let p = |k: usize| l[(k, i)] * y[(k, j)];
    match i {
        0 => 0.0 + p(4) + (p(1) + p(5)) + p(2) + p(7) + p(8) + p(10) + p(11),
        1 => 0.0 + p(0) + p(5) + (p(2) + p(6)) + p(3) + p(8) + p(9) + p(11),
        2 => 0.0 + (p(0) + p(4)) + p(1) + p(6) + (p(3) + p(7)) + p(9) + p(10),
        _ => 0.0 + p(6 + i),
    }
}

/// Subtree composites of the diagonal blocks in twist form,
/// `Σ_{i ∈ subtree(b)} L_iᵀ H_ii L_i` (leaves up); false (and nothing
/// filled) when no link has a diagonal block.
fn fill_twist_composites(
    model: &Model,
    kin: &Kinematics,
    acc: &EnergyAccumulator,
    composite: &mut Vec<Matrix6<f64>>,
) -> bool {
    if !acc.link_hess_set.iter().any(|&set| set) {
        return false;
    }
    composite.clear();
    composite.resize(model.links.len(), Matrix6::zeros());
    for (i, c) in composite.iter_mut().enumerate() {
        if acc.link_hess_set[i] {
            *c = twist_block(&acc.link_hess[i], &kin.pose[i], &kin.pose[i]);
        }
    }
    for i in (0..model.links.len()).rev() {
        if let Some(p) = model.links[i].parent {
            let c = composite[i];
            composite[p] += c;
        }
    }
    true
}

/// `s_kᵀ u` of two 6-vectors.
#[inline]
fn dot6(s: &[f64; 6], u: &[f64; 6]) -> f64 {
    s[0] * u[0] + s[1] * u[1] + s[2] * u[2] + s[3] * u[3] + s[4] * u[4] + s[5] * u[5]
}

/// `M s` as a 6-array.
#[inline]
fn mul6(m: &Matrix6<f64>, s: &[f64; 6]) -> [f64; 6] {
    let u = m * Vector6::from_column_slice(s);
    [u[0], u[1], u[2], u[3], u[4], u[5]]
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

/// The terms that follow the tree, into the upper triangle: for each
/// coordinate `l` of joint `b` and each coordinate `k ≤ l` of `b` or of its
/// ancestors,
///
/// - the structured first-order part `⟨S_k, S_l C_b⟩` (when `composites`);
/// - the second-order kinematic part: `⟨S_k S_l, Q_b⟩ = ⟨R_k, Q_b S_lᵀ⟩`
///   for a proper ancestor `k` (`R_k` the rotational 3×3 of `S_k`, and
///   `S_k S_l` means `R_k S_l`, see `crate::math::twist_mul`), `⟨S_kl, Q_b⟩`
///   within joint `b`.
///
/// For a proper ancestor both parts are one product `⟨S_k, Z_l⟩` with
/// `Z_l = S_l C_b + [Q_b S_lᵀ | 0]`, formed once per `l`; and since `R_k`
/// is skew-symmetric (`R_k = [ω_k]×`, `S_k = [[ω_k]× | v_k]`),
/// `⟨S_k, Z⟩ = ω_k · ax(Z) + v_k · z₄` with `ax(Z) = (Z₂₁ − Z₁₂, Z₀₂ − Z₂₀,
/// Z₁₀ − Z₀₁)` and `z₄` the last column: six multiplications per entry,
/// like the composite-rigid-body algorithm's `S_kᵀ F_l`.
fn add_tree_terms(
    model: &Model,
    kin: &Kinematics,
    composites: bool,
    blocks: bool,
    hess: &mut DMatrix<f64>,
    scratch: &mut AssembleScratch,
) {
    let n = hess.nrows();
    let h = hess.as_mut_slice();
    for (b, link) in model.links.iter().enumerate() {
        let nb = link.ndof();
        if nb == 0 {
            continue;
        }
        let qb = &scratch.q_sub[b];
        let ob = link.dof_offset;
        let anc = &model.ancestor_dofs[b];
        let proper = &anc[..anc.len() - nb];
        for l in ob..ob + nb {
            let sl = &kin.twist[l];
            let y = composites.then(|| sl * scratch.composite[b]);
            let mut z = y.unwrap_or_else(Matrix3x4::zeros);
            let p = qb * sl.transpose();
            let mut z_rot = z.fixed_view_mut::<3, 3>(0, 0);
            z_rot += p;
            let mut w = axial_and_translation(&z);
            // The diagonal blocks' composite of `b`: `u = (Σ M_ii) s_l`.
            let u = blocks.then(|| mul6(&scratch.twist_composite[b], &scratch.twist6[l]));
            if let Some(u) = &u {
                w.iter_mut().zip(u).for_each(|(w, u)| *w += u);
            }
            let col = &mut h[l * n..(l + 1) * n];
            for &k in proper {
                col[k] += dot6(&scratch.twist6[k], &w);
            }
            for (k, c) in col.iter_mut().enumerate().take(l + 1).skip(ob) {
                let mut v = frob(kin.twist2(model, b, k, l), qb);
                if let Some(y) = &y {
                    v += frob(&kin.twist[k], y);
                }
                if let Some(u) = &u {
                    v += dot6(&scratch.twist6[k], u);
                }
                *c += v;
            }
        }
    }
}

/// `(ω, v)` of a twist matrix `S = [[ω]× | v]` (ω from the skew part of the
/// rotational 3×3, `½(S − Sᵀ)`, which it is up to round-off).
fn twist_vector(s: &Matrix3x4<f64>) -> [f64; 6] {
    [
        0.5 * (s[(2, 1)] - s[(1, 2)]),
        0.5 * (s[(0, 2)] - s[(2, 0)]),
        0.5 * (s[(1, 0)] - s[(0, 1)]),
        s[(0, 3)],
        s[(1, 3)],
        s[(2, 3)],
    ]
}

/// `(ax(Z), z₄)` with `⟨[[ω]× | v], Z⟩ = ω · ax(Z) + v · z₄` (see
/// [`add_tree_terms`]).
fn axial_and_translation(z: &Matrix3x4<f64>) -> [f64; 6] {
    [
        z[(2, 1)] - z[(1, 2)],
        z[(0, 2)] - z[(2, 0)],
        z[(1, 0)] - z[(0, 1)],
        z[(0, 3)],
        z[(1, 3)],
        z[(2, 3)],
    ]
}

/// Copies the upper triangle onto the lower one over the envelope
/// (`h_lk = h_kl` for `k < l` in column `l`'s rows). Every entry the
/// assembly can have written is there; the others are zeros on both sides
/// (the buffer was cleared), so the copy leaves them zero. Columns go in
/// groups of eight: for each row `k`, the eight values of row `k` are
/// written to one contiguous run of column `k` (one cache line) instead of
/// eight strided stores. The result is exactly symmetric.
fn mirror_upper(env: &ColumnEnvelope, hess: &mut DMatrix<f64>) {
    const GROUP: usize = 8;
    let n = hess.nrows();
    let h = hess.as_mut_slice();
    for l0 in (0..n).step_by(GROUP) {
        let l1 = (l0 + GROUP).min(n);
        let k0 = (l0..l1).map(|l| env.rows(l).start).min().unwrap_or(l0);
        for k in k0..l1 {
            for l in l0.max(k + 1)..l1 {
                if env.rows(l).contains(&k) {
                    h[l + k * n] = h[k + l * n];
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

/// `J_iᵀ H_ij J_j` and its transpose into the upper triangle, in twist form
/// (`s_kᵀ M_ij s_l`, see the module docs), column by column.
fn add_pair_block(
    model: &Model,
    kin: &Kinematics,
    i: usize,
    j: usize,
    h: &PoseHessian,
    hess: &mut DMatrix<f64>,
    scratch: &mut AssembleScratch,
) {
    let m = twist_block(h, &kin.pose[i], &kin.pose[j]);
    let anc_i = &model.ancestor_dofs[i];
    let anc_j = &model.ancestor_dofs[j];
    let n = hess.nrows();
    let h = hess.as_mut_slice();
    // Every coordinate of `i`'s path below every one of `j`'s (`i < j` in
    // different branches, the usual contact pair): the block lies in the
    // upper triangle whole, column by column.
    if anc_i.last() < anc_j.first() {
        for &l in anc_j {
            let u = mul6(&m, &scratch.twist6[l]);
            let col = &mut h[l * n..(l + 1) * n];
            for &k in anc_i {
                col[k] += dot6(&scratch.twist6[k], &u);
            }
        }
        return;
    }
    scratch.pair_u.clear();
    scratch
        .pair_u
        .extend(anc_j.iter().map(|&l| mul6(&m, &scratch.twist6[l])));
    for (u, &l) in scratch.pair_u.iter().zip(anc_j) {
        for &k in anc_i {
            let v = dot6(&scratch.twist6[k], u);
            // The block and its transpose: twice on the diagonal.
            match k.cmp(&l) {
                std::cmp::Ordering::Less => h[k + l * n] += v,
                std::cmp::Ordering::Greater => h[l + k * n] += v,
                std::cmp::Ordering::Equal => h[k + k * n] += v + v,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The sparse `L_aᵀ H L_b` has the bits of the dense nalgebra products (entries
    /// of mixed signs and magnitudes, none zero, so no signed zero can differ).
    #[test]
    fn twist_block_has_the_bits_of_the_dense_products() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut r = || {
            let m: f64 = rng.random_range(0.5..2.0);
            let e: i32 = rng.random_range(-6..6);
            let s = if rng.random_range(0..2) == 0 {
                -1.0
            } else {
                1.0
            };
            s * m * 10f64.powi(e)
        };
        for _ in 0..200 {
            let h = SMatrix::<f64, 12, 12>::from_fn(|_, _| r());
            let a = Matrix3x4::from_fn(|_, _| r());
            let b = Matrix3x4::from_fn(|_, _| r());
            let dense = twist_jacobian(&a).tr_mul(&(h * twist_jacobian(&b)));
            let sparse = twist_block(&h, &a, &b);
            for (x, y) in sparse.iter().zip(dense.iter()) {
                assert_eq!(x.to_bits(), y.to_bits());
            }
        }
    }
}
