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
        let block: PoseHessian = h.fixed_view::<12, 12>(0, 0) * scale;
        acc.add_link_hess(la, &block);
    }
    if moves_b {
        let block: PoseHessian = h.fixed_view::<12, 12>(12, 12) * scale;
        acc.add_link_hess(lb, &block);
    }
    if moves_a && moves_b {
        // Stored as ∂²E/∂A_i∂A_j with i < j.
        let (i, j, block): (usize, usize, PoseHessian) = if la < lb {
            (la, lb, h.fixed_view::<12, 12>(0, 12) * scale)
        } else {
            (lb, la, h.fixed_view::<12, 12>(12, 0) * scale)
        };
        match acc.pair_slots.get(&(i, j)) {
            Some(&k) => acc.pair_hess[k].2 += block,
            None => {
                acc.pair_slots.insert((i, j), acc.pair_hess.len());
                acc.pair_hess.push((i, j, block));
            }
        }
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
