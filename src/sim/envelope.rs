//! Which rows of each column of the step Hessian can be non-zero.
//!
//! The assembled `H = ∂²O/∂θ²` of a tree is sparse: entry `(k, l)` is
//! structurally non-zero only when one coordinate's joint is an ancestor of
//! the other's (inertia, gravity, the kinematic second-order terms, a
//! link's own contact block), when a coupled link pair `(i, j)` has `k` and
//! `l` on its two ancestor paths (contact and friction between links), or
//! when a coordinate term couples them (mimic ties). [`ColumnEnvelope`]
//! bounds the non-zeros of each column `l` by a row range
//! `lo_l ≤ k < hi_l`; with coordinates numbered depth-first (every scene
//! and import does) a tree's columns span that tree's coordinates only, so
//! four separate chains of 64 coordinates touch a quarter of the
//! 256 × 256 matrix.
//!
//! Every dense pass over `H` that only needs its non-zeros — clearing it
//! before the next assembly, the finiteness test, the row sums of Newton's
//! round-off floor, the block partition of the linear solve — runs over the
//! envelope. Entries outside it are exactly zero, so each pass gives the
//! bits of the full pass.

use crate::energy::EnergyAccumulator;
use crate::model::Model;
use nalgebra::DMatrix;
use std::ops::Range;

/// Row range of the possible non-zeros of every column (see the module
/// documentation).
#[derive(Clone, Debug, Default)]
pub struct ColumnEnvelope {
    lo: Vec<usize>,
    hi: Vec<usize>,
}

impl ColumnEnvelope {
    /// Number of columns.
    pub fn len(&self) -> usize {
        self.lo.len()
    }

    /// Whether there are no columns.
    pub fn is_empty(&self) -> bool {
        self.lo.is_empty()
    }

    /// Rows of column `l` that may be non-zero.
    pub fn rows(&self, l: usize) -> Range<usize> {
        self.lo[l]..self.hi[l]
    }

    /// One past the last row of each column that may be non-zero.
    pub fn row_ends(&self) -> &[usize] {
        &self.hi
    }

    /// The envelope of the Hessian the assembler builds from `acc`: the
    /// diagonal, every ancestor pair of the tree, both ancestor paths of
    /// every coupled link pair, the coordinate terms' off-diagonal entries.
    pub fn build(&mut self, model: &Model, acc: &EnergyAccumulator) {
        let n = model.ndof();
        self.lo.clear();
        self.lo.extend(0..n);
        self.hi.clear();
        self.hi.extend(1..=n);
        for (b, link) in model.links.iter().enumerate() {
            let (ob, nb) = (link.dof_offset, link.ndof());
            if nb == 0 {
                continue;
            }
            let anc = &model.ancestor_dofs[b];
            let end = ob + nb;
            for l in ob..end {
                self.lo[l] = self.lo[l].min(anc[0]);
                self.hi[l] = self.hi[l].max(end);
            }
            for &k in anc.iter().take_while(|&&k| k < ob) {
                self.hi[k] = self.hi[k].max(end);
            }
        }
        for (i, j, _) in &acc.pair_hess {
            let (ai, aj) = (&model.ancestor_dofs[*i], &model.ancestor_dofs[*j]);
            let (Some(fi), Some(fj)) = (ai.first(), aj.first()) else {
                continue;
            };
            let first = (*fi).min(*fj);
            let end = ai[ai.len() - 1].max(aj[aj.len() - 1]) + 1;
            for &l in ai.iter().chain(aj) {
                self.lo[l] = self.lo[l].min(first);
                self.hi[l] = self.hi[l].max(end);
            }
        }
        for &((k, l), _) in acc.dof_hess.off_diagonal() {
            self.lo[l] = self.lo[l].min(k);
            self.hi[l] = self.hi[l].max(k + 1);
            self.lo[k] = self.lo[k].min(l);
            self.hi[k] = self.hi[k].max(l + 1);
        }
    }

    /// Sets the envelope's entries of `h` to zero.
    pub fn zero(&self, h: &mut DMatrix<f64>) {
        let n = h.nrows();
        for (l, col) in h.as_mut_slice().chunks_exact_mut(n.max(1)).enumerate() {
            col[self.rows(l)].fill(0.0);
        }
    }
}

/// Rows of column `l` that `env` allows (all `n` rows without one).
fn rows(env: Option<&ColumnEnvelope>, l: usize, n: usize) -> Range<usize> {
    env.map_or(0..n, |e| e.rows(l))
}

/// `max_k Σ_l |h_kl|` (`‖h‖∞`), accumulated column by column (contiguous in
/// the column-major `h`; a row-wise walk strides by `n`), so each row still
/// adds its entries in the order `l = 0, 1, …` from the same start. Over
/// the envelope's rows when one is given: the same bits as the full sum,
/// the skipped entries being zeros. `None` when a row sum is not finite:
/// some entry is NaN or infinite (or the sum overflows), so one pass both
/// checks the Hessian and measures it. `sums` is scratch.
pub fn finite_max_row_sum(
    h: &DMatrix<f64>,
    env: Option<&ColumnEnvelope>,
    sums: &mut Vec<f64>,
) -> Option<f64> {
    let n = h.nrows();
    sums.clear();
    // `Sum for f64` folds from −0.0; the same start keeps every bit.
    sums.resize(n, -0.0);
    for (l, col) in h.as_slice().chunks_exact(n.max(1)).enumerate() {
        let r = rows(env, l, n);
        for (s, v) in sums[r.clone()].iter_mut().zip(&col[r]) {
            *s += v.abs();
        }
    }
    sums.iter()
        .try_fold(0.0, |m: f64, s| s.is_finite().then(|| m.max(*s)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::{Need, PoseHessian};
    use crate::kinematics::{KinOrder, Kinematics};
    use crate::scene::Scene;
    use crate::sim::assemble::{AssembleScratch, assemble, assemble_hessian};
    use nalgebra::{DVector, Matrix3x4};
    use rand::{RngExt, SeedableRng};
    type Rng = rand_chacha::ChaCha8Rng;
    use std::path::Path;

    /// Two robots: a branching tree (revolute root, a spherical and a
    /// prismatic branch, a ball joint under the spherical one) and a free
    /// body; plus a fixed link, which has no coordinates of its own.
    const SCENE: &str = r#"
dt: 0.01
robots:
  - name: t
    links:
      - name: a
        joint: {type: revolute, axis: [0, 0, 1]}
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
        mass: 1.0
      - name: b
        parent: a
        joint: {type: spherical, origin: {xyz: [0.2, 0, 0]}}
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
        mass: 1.0
      - name: c
        parent: a
        joint: {type: prismatic, axis: [0, 1, 0], origin: {xyz: [0, 0.2, 0]}}
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
        mass: 1.0
      - name: d
        parent: b
        joint: {type: ball, origin: {xyz: [0.2, 0, 0]}}
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
        mass: 1.0
      - name: e
        parent: d
        joint: {type: fixed, origin: {xyz: [0.2, 0, 0]}}
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
        mass: 1.0
  - name: f
    links:
      - name: g
        joint: {type: free}
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
        mass: 1.0
"#;

    fn random_block(rng: &mut Rng) -> PoseHessian {
        PoseHessian::from_fn(|_, _| rng.random_range(-1.0..1.0))
    }

    /// A random accumulator: gradients, symmetric diagonal blocks on some
    /// links, the inertia moments, coupled pairs (within a tree, across
    /// trees, a link with no coordinates), coordinate terms with an
    /// off-diagonal tie.
    fn random_acc(model: &crate::model::Model, rng: &mut Rng) -> EnergyAccumulator {
        let nl = model.links.len();
        let mut acc = EnergyAccumulator::new(model);
        acc.reset(Need::Hessian);
        for g in acc.link_grad.iter_mut() {
            *g = Matrix3x4::from_fn(|_, _| rng.random_range(-1.0..1.0));
        }
        for i in 0..nl {
            if rng.random_range(0.0..1.0) < 0.5 {
                let b = random_block(rng);
                acc.add_link_hess(i, &(b + b.transpose()));
            }
        }
        acc.link_moment.copy_from_slice(&model.second_moment);
        acc.link_moment_set = true;
        for _ in 0..rng.random_range(0..4usize) {
            let i = rng.random_range(0..nl);
            let j = (i + 1 + rng.random_range(0..nl - 1)) % nl;
            acc.pair_hess.push((i, j, random_block(rng)));
        }
        let n = model.ndof();
        for k in 0..n {
            acc.dof_hess[(k, k)] += rng.random_range(0.0..2.0);
        }
        let (k, l) = (rng.random_range(0..n), rng.random_range(0..n));
        if k != l {
            let v = rng.random_range(-1.0..1.0);
            acc.dof_hess[(k, l)] += v;
            acc.dof_hess[(l, k)] += v;
        }
        acc
    }

    /// The twist-form contraction of general pose blocks (diagonal blocks
    /// through subtree composites; pair blocks within one tree, where the
    /// two ancestor paths overlap, and across trees) equals the explicit
    /// `Σ_i J_iᵀ H_ii J_i + Σ_(i,j) (J_iᵀ H_ij J_j + J_jᵀ H_ijᵀ J_i)` with the
    /// 12-vector columns `vec(S_k Ã_i)` (`crate::math::twist_apply`), to
    /// round-off. No gradients and no moments, so only these blocks enter.
    #[test]
    fn twist_form_blocks_equal_the_explicit_jacobian_contraction() {
        use nalgebra::SMatrix;
        let scene = Scene::from_str(SCENE, Path::new("envelope.yaml")).unwrap();
        let model = &scene.model;
        let (n, nl) = (model.ndof(), model.links.len());
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut kin = Kinematics::new(model);
        let mut worst = 0.0f64;
        for _ in 0..40 {
            let q = DVector::from_fn(n, |_, _| rng.random_range(-0.5..0.5));
            let charts = vec![nalgebra::Matrix3::identity(); model.nchart];
            kin.update(model, &q, &charts, KinOrder::Second);
            let mut acc = EnergyAccumulator::new(model);
            acc.reset(Need::Hessian);
            for i in 0..nl {
                if rng.random_range(0.0..1.0) < 0.6 {
                    let b = random_block(&mut rng);
                    acc.add_link_hess(i, &(b + b.transpose()));
                }
            }
            for i in 0..nl {
                for j in i + 1..nl {
                    if rng.random_range(0.0..1.0) < 0.5 {
                        acc.pair_hess.push((i, j, random_block(&mut rng)));
                    }
                }
            }
            let jac = |i: usize| {
                let mut jm = SMatrix::<f64, 12, 0>::zeros().resize_horizontally(n, 0.0);
                for &k in &model.ancestor_dofs[i] {
                    let d = crate::math::twist_apply(&kin.twist[k], &kin.pose[i]);
                    jm.column_mut(k).copy_from_slice(d.as_slice());
                }
                jm
            };
            let mut expect = DMatrix::<f64>::zeros(n, n);
            for i in 0..nl {
                if acc.link_hess_set[i] {
                    let ji = jac(i);
                    expect += ji.transpose() * acc.link_hess[i] * &ji;
                }
            }
            for (i, j, h) in &acc.pair_hess {
                let c = jac(*i).transpose() * h * jac(*j);
                expect += &c + c.transpose();
            }
            let got = assemble_hessian(model, &kin, &acc);
            let err = (&got - &expect).amax() / expect.amax().max(1e-300);
            worst = worst.max(err);
            assert!(err <= 1e-12, "relative error {err:.2e}");
        }
        eprintln!("twist form vs explicit Jacobians: worst relative error {worst:.2e}");
    }

    /// Assembling into a reused buffer (cleared over the last envelope
    /// only) gives the bits of assembling into a fresh zero matrix; every
    /// non-zero lies in the envelope; the result is exactly symmetric; the
    /// envelope's passes equal the full passes.
    #[test]
    fn reused_buffer_equals_fresh_assembly_and_nonzeros_lie_inside() {
        let scene = Scene::from_str(SCENE, Path::new("envelope.yaml")).unwrap();
        let model = &scene.model;
        let n = model.ndof();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut kin = Kinematics::new(model);
        let mut reused = DMatrix::zeros(n, n);
        let mut reused_scratch = AssembleScratch::default();
        let mut grad = DVector::zeros(n);
        for round in 0..40 {
            let q = DVector::from_fn(n, |_, _| rng.random_range(-0.5..0.5));
            let charts = vec![nalgebra::Matrix3::identity(); model.nchart];
            kin.update(model, &q, &charts, KinOrder::Second);
            let acc = random_acc(model, &mut rng);
            let fresh = assemble_hessian(model, &kin, &acc);
            assemble(
                model,
                &kin,
                &acc,
                Need::Hessian,
                &mut grad,
                &mut reused,
                &mut reused_scratch,
            );
            let env = reused_scratch.envelope();
            for l in 0..n {
                for k in 0..n {
                    let (a, b) = (fresh[(k, l)], reused[(k, l)]);
                    assert_eq!(a.to_bits(), b.to_bits(), "round {round}: ({k}, {l})");
                    assert_eq!(
                        a.to_bits(),
                        fresh[(l, k)].to_bits(),
                        "not symmetric at ({k}, {l})"
                    );
                    if a != 0.0 {
                        assert!(
                            env.rows(l).contains(&k),
                            "round {round}: ({k}, {l}) outside"
                        );
                    }
                }
            }
            let (mut s1, mut s2) = (Vec::new(), Vec::new());
            let norm = finite_max_row_sum(&reused, Some(env), &mut s1).unwrap();
            assert_eq!(
                norm.to_bits(),
                finite_max_row_sum(&reused, None, &mut s2)
                    .unwrap()
                    .to_bits()
            );
            assert!(norm > 0.0);
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                reused[(env.rows(n - 1).start, n - 1)] = bad;
                assert_eq!(finite_max_row_sum(&reused, Some(env), &mut s1), None);
            }
            reused[(env.rows(n - 1).start, n - 1)] = 0.0;
        }
    }
}
