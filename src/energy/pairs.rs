//! Scattering of hull-pair derivatives (pose space of two links) into the
//! accumulator, shared by the contact and friction terms.

use super::{EnergyAccumulator, Need, PoseHessian};
use crate::model::Model;
use nalgebra::{Matrix3x4, SMatrix};

/// Adds `scale·E` of a pair of links `(la, lb)` with `∂E/∂A_a`, `∂E/∂A_b`
/// and the 24×24 Hessian over `[vec A_a; vec A_b]`. Links without
/// coordinates (static obstacles) receive nothing. Off-diagonal blocks of
/// the same link pair are merged (within a term and across terms) through
/// the accumulator's slots.
// Arguments kept separate: hot inner loop of every contact pair: the slices and blocks are borrowed from different owners, so a struct would be rebuilt per pair.
#[allow(clippy::too_many_arguments)]
pub fn scatter_pair(
    model: &Model,
    acc: &mut EnergyAccumulator,
    need: Need,
    (la, lb): (usize, usize),
    scale: f64,
    (grad_a, grad_b): (&Matrix3x4<f64>, &Matrix3x4<f64>),
    hess: Option<&SMatrix<f64, 24, 24>>,
) {
    let moves_a = !model.ancestor_dofs[la].is_empty();
    let moves_b = !model.ancestor_dofs[lb].is_empty();
    if need >= Need::Gradient {
        if moves_a {
            acc.link_grad[la] += grad_a * scale;
        }
        if moves_b {
            acc.link_grad[lb] += grad_b * scale;
        }
    }
    if need < Need::Hessian {
        return;
    }
    let Some(h) = hess else { return };
    if moves_a {
        add_scaled_link_hess(acc, la, h, 0, scale);
    }
    if moves_b {
        add_scaled_link_hess(acc, lb, h, 12, scale);
    }
    if moves_a && moves_b {
        // Stored as ∂²E/∂A_i∂A_j with i < j.
        let (i, j, (r0, c0)) = if la < lb {
            (la, lb, (0, 12))
        } else {
            (lb, la, (12, 0))
        };
        match acc.pair_slots.get(&(i, j)) {
            Some(&k) => scaled_into(&mut acc.pair_hess[k].2, h, r0, c0, scale, |e, v| *e += v),
            None => {
                acc.pair_slots.insert((i, j), acc.pair_hess.len());
                let mut block = PoseHessian::zeros();
                scaled_into(&mut block, h, r0, c0, scale, |e, v| *e = v);
                acc.pair_hess.push((i, j, block));
            }
        }
    }
}

/// `write(e, x · scale)` for every entry `e` of `dst` and the matching entry `x` of the 12×12
/// block of `h` at `(r0, c0)`, column by column: a column of the block is a contiguous run of
/// 12 entries of the column-major 24×24 `h`. Each `x · scale` is the entry of
/// `h.fixed_view::<12, 12>(r0, c0) * scale`, bit for bit, without the strided view iterator.
#[inline]
fn scaled_into(
    dst: &mut PoseHessian,
    h: &SMatrix<f64, 24, 24>,
    r0: usize,
    c0: usize,
    scale: f64,
    write: impl Fn(&mut f64, f64),
) {
    let src = h.as_slice();
    for (c, col) in dst.as_mut_slice().chunks_exact_mut(12).enumerate() {
        let run = &src[(c0 + c) * 24 + r0..][..12];
        for (e, &x) in col.iter_mut().zip(run) {
            write(e, x * scale);
        }
    }
}

/// [`EnergyAccumulator::add_link_hess`] of `scale` times the diagonal 12×12 block of `h` at
/// `(off, off)`: `+=` onto a block already written in this evaluation, else `0 + x · scale`
/// (the bits of a cleared block `+=`, signed zeros included).
fn add_scaled_link_hess(
    acc: &mut EnergyAccumulator,
    i: usize,
    h: &SMatrix<f64, 24, 24>,
    off: usize,
    scale: f64,
) {
    if acc.link_hess_set[i] {
        scaled_into(&mut acc.link_hess[i], h, off, off, scale, |e, v| *e += v);
    } else {
        scaled_into(&mut acc.link_hess[i], h, off, off, scale, |e, v| {
            *e = 0.0 + v
        });
        acc.link_hess_set[i] = true;
    }
}

/// `out_i += Σ_j ∂²E/∂A_i∂A_j δA_j` from the pose Hessian blocks written into
/// `acc` (diagonal, structured and pair blocks): a pose-space
/// Hessian–vector product.
pub fn hessian_times(
    acc: &EnergyAccumulator,
    dpose: &[crate::math::Pose],
    out: &mut [Matrix3x4<f64>],
) {
    let vec = |a: &Matrix3x4<f64>| SMatrix::<f64, 12, 1>::from_column_slice(a.as_slice());
    let unvec = |v: SMatrix<f64, 12, 1>| Matrix3x4::from_column_slice(v.as_slice());
    for i in 0..out.len() {
        if acc.link_hess_set[i] {
            out[i] += unvec(acc.link_hess[i] * vec(&dpose[i]));
        }
        if acc.link_moment_set {
            out[i] += dpose[i] * acc.link_moment[i];
        }
    }
    for (i, j, h) in &acc.pair_hess {
        out[*i] += unvec(h * vec(&dpose[*j]));
        out[*j] += unvec(h.transpose() * vec(&dpose[*i]));
    }
}

/// `Σ_i ⟨δA_i, ∂E/∂A_i⟩` from the gradients written into `acc`.
pub fn directional(acc: &EnergyAccumulator, dpose: &[crate::math::Pose]) -> f64 {
    acc.link_grad
        .iter()
        .zip(dpose)
        .map(|(g, d)| g.component_mul(d).sum())
        .sum()
}

/// Scatters world-vertex adjoint products of one hull into pose and local-vertex space.
///
/// The hull's vertices are `X_m = A x̃_m` (`x̃ = [x_local; 1]`), moved along `δX_m = δA x̃_m`.
/// Given `∂Φ/∂X_m` (`d_phi`, at fixed `δX`) and, for a hull on the current state, the
/// gradient `∂E/∂X_m` (`grad`, whose product with `δX` defines `Φ`), this adds
/// `scale·Σ_m (∂Φ/∂X_m) x̃_mᵀ` to `pose_out` (`∂Φ/∂A` at fixed `δA`) and
/// `scale·(Rᵀ ∂Φ/∂X_m + δRᵀ ∂E/∂X_m)` to `vertex_out[m]` (`∂Φ/∂x_local`: through `X_m`
/// and through `δX_m`), with `R`, `δR` the rotation blocks of `A`, `δA`.
// Arguments kept separate: hot inner loop: value, tangent and adjoint inputs of one vertex chain, borrowed from different owners per call.
#[allow(clippy::too_many_arguments)]
pub fn scatter_vertex_products(
    x_local: &[nalgebra::Vector3<f64>],
    pose: &crate::math::Pose,
    dpose: Option<&crate::math::Pose>,
    d_phi: &[nalgebra::Vector3<f64>],
    grad: Option<&[nalgebra::Vector3<f64>]>,
    scale: f64,
    pose_out: &mut Matrix3x4<f64>,
    vertex_out: Option<&mut [nalgebra::Vector3<f64>]>,
) {
    let r = pose.fixed_view::<3, 3>(0, 0);
    let mut acc = Matrix3x4::<f64>::zeros();
    for (x, g) in x_local.iter().zip(d_phi) {
        let xt = nalgebra::Vector4::new(x.x, x.y, x.z, 1.0);
        acc += g * xt.transpose();
    }
    *pose_out += acc * scale;
    if let Some(vo) = vertex_out {
        for (m, (v, g)) in vo.iter_mut().zip(d_phi).enumerate() {
            let mut t = r.transpose() * g;
            if let (Some(da), Some(gr)) = (dpose, grad) {
                t += da.fixed_view::<3, 3>(0, 0).transpose() * gr[m];
            }
            *v += t * scale;
        }
    }
}

/// World positions `A x̃_m` and directions `δA x̃_m` of a hull's vertices.
pub fn vertices_and_directions(
    x_local: &[nalgebra::Vector3<f64>],
    pose: &crate::math::Pose,
    dpose: &crate::math::Pose,
) -> (Vec<nalgebra::Vector3<f64>>, Vec<nalgebra::Vector3<f64>>) {
    x_local
        .iter()
        .map(|x| {
            (
                crate::math::transform_point(pose, x),
                crate::math::transform_point(dpose, x),
            )
        })
        .unzip()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The column-run blocks of `scatter_pair` have the bits of the view expressions
    /// `h.fixed_view::<12, 12>(r, c) * scale` (then `0 + ·` or `+=`), for both link orders.
    #[test]
    fn scaled_blocks_have_the_bits_of_the_view_products() {
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let model = crate::kinematics::motion_bound::tests::every_joint_model(&mut rng);
        let h = SMatrix::<f64, 24, 24>::from_fn(|r, c| {
            let x = ((r * 31 + c * 17) % 29) as f64 - 14.0;
            x * 10f64.powi(((r + 2 * c) % 9) as i32 - 4) / 3.0
        });
        let g = Matrix3x4::zeros();
        let scale = 0.7;
        for (la, lb) in [(1, 2), (2, 1)] {
            let mut acc = EnergyAccumulator::new(&model);
            acc.reset(Need::Hessian);
            for _ in 0..2 {
                scatter_pair(
                    &model,
                    &mut acc,
                    Need::Hessian,
                    (la, lb),
                    scale,
                    (&g, &g),
                    Some(&h),
                );
            }
            let view = |r, c| -> PoseHessian { h.fixed_view::<12, 12>(r, c) * scale };
            let first = |b: PoseHessian| b.map(|x| 0.0 + x);
            let want_a = first(view(0, 0)) + view(0, 0);
            let want_b = first(view(12, 12)) + view(12, 12);
            let off = if la < lb { view(0, 12) } else { view(12, 0) };
            let want_pair = off + off;
            let bits = |m: &PoseHessian| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&acc.link_hess[la]), bits(&want_a));
            assert_eq!(bits(&acc.link_hess[lb]), bits(&want_b));
            assert_eq!(acc.pair_hess.len(), 1);
            assert_eq!(bits(&acc.pair_hess[0].2), bits(&want_pair));
        }
    }
}
