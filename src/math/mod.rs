//! Small math helpers shared by every stage: rigid poses as 3×4 affine
//! matrices, the SO(3) exponential map (generic over dual numbers so that its
//! derivatives are exact), skew matrices.
//!
//! Conventions used across the crate:
//! - A link pose is `Pose = Matrix3x4<f64>`, `A = [R | t]`; a link-local point
//!   `x_local` maps to `x_world = R x_local + t = A [x_local; 1]`.
//! - The 12 pose parameters are `vec(A)` in nalgebra's column-major order
//!   (`A.as_slice()`, index `c*3 + r`), so `∂x_world/∂vec(A) = x̃ᵀ ⊗ I₃` with
//!   `x̃ = [x_local; 1]`. Gradients w.r.t. a pose are `Matrix3x4` (`∂E/∂A`),
//!   pose Hessians are 12×12 (or 24×24 for a pair) over `vec(A)`.
//! - World-frame "twists" `S` are 3×4 matrices (top rows of a 4×4 matrix whose
//!   bottom row is zero): a derivative of a pose is `∂A/∂θ_k = S_k Ã`, with
//!   `Ã` the 4×4 homogeneous form of `A`.

pub mod polytope;
pub mod so3;

use nalgebra::{Matrix3, Matrix3x4, Matrix4, SMatrix, Vector3};

/// A rigid (or, for design derivatives, general affine) transform `[R | t]`.
pub type Pose = Matrix3x4<f64>;

/// The identity pose.
pub fn pose_identity() -> Pose {
    Pose::identity()
}

/// Builds `[R | t]`.
pub fn pose_from(r: &Matrix3<f64>, t: &Vector3<f64>) -> Pose {
    let mut a = Pose::zeros();
    a.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
    a.fixed_view_mut::<3, 1>(0, 3).copy_from(t);
    a
}

/// Rotation block `R` of `[R | t]`.
pub fn rot(a: &Pose) -> Matrix3<f64> {
    a.fixed_view::<3, 3>(0, 0).into_owned()
}

/// Translation column `t` of `[R | t]`.
pub fn trans(a: &Pose) -> Vector3<f64> {
    a.fixed_view::<3, 1>(0, 3).into_owned()
}

/// Homogeneous 4×4 form `Ã = [[R, t], [0, 1]]`.
pub fn homogeneous(a: &Pose) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 4>(0, 0).copy_from(a);
    m
}

/// Composition `A·B` of two poses (`Ã B̃`, top rows).
pub fn compose(a: &Pose, b: &Pose) -> Pose {
    let r = rot(a);
    pose_from(&(r * rot(b)), &(r * trans(b) + trans(a)))
}

/// Inverse of a rigid pose: `[Rᵀ | −Rᵀ t]`. Only valid for orthonormal `R`.
pub fn rigid_inverse(a: &Pose) -> Pose {
    let rt = rot(a).transpose();
    pose_from(&rt, &(-(rt * trans(a))))
}

/// `x_world = A [x_local; 1]`.
#[inline]
pub fn transform_point(a: &Pose, x_local: &Vector3<f64>) -> Vector3<f64> {
    a.fixed_view::<3, 3>(0, 0) * x_local + a.fixed_view::<3, 1>(0, 3)
}

/// Product of two world twists (3×4 top rows of 4×4 matrices with zero
/// bottom row): top rows of `S₁ S₂` = `S₁[:, :3] · S₂`.
#[inline]
pub fn twist_mul(s1: &Matrix3x4<f64>, s2: &Matrix3x4<f64>) -> Matrix3x4<f64> {
    s1.fixed_view::<3, 3>(0, 0) * s2
}

/// Top rows of `S Ã` for a twist `S` and a pose `A`: the derivative of the
/// pose `A` along the twist. `S Ã = S[:, :3] [R | t] + [0 | S[:, 3]]`.
#[inline]
pub fn twist_apply(s: &Matrix3x4<f64>, a: &Pose) -> Pose {
    let mut out = s.fixed_view::<3, 3>(0, 0) * a;
    let col = out.column(3) + s.column(3);
    out.set_column(3, &col);
    out
}

/// Frobenius inner product `⟨X, Y⟩ = Σ X_ij Y_ij`.
#[inline]
pub fn frob(x: &Matrix3x4<f64>, y: &Matrix3x4<f64>) -> f64 {
    x.component_mul(y).sum()
}

/// The symmetric part `(H + Hᵀ)/2` of a square matrix, boxed, formed in
/// place: entry `(i, j)` and `(j, i)` both become `(h_ij + h_ji) · 0.5` (the
/// same bits as `(H + H.transpose()) * 0.5`, addition being commutative),
/// the diagonal `(h_ii + h_ii) · 0.5 = h_ii` exactly. One copy into the box
/// instead of three 24×24 temporaries (the pair Hessians of contact and
/// friction).
pub fn symmetric_part_boxed<const N: usize>(h: &SMatrix<f64, N, N>) -> Box<SMatrix<f64, N, N>> {
    let mut out = Box::new(*h);
    for j in 0..N {
        for i in 0..j {
            let v = (out[(i, j)] + out[(j, i)]) * 0.5;
            out[(i, j)] = v;
            out[(j, i)] = v;
        }
    }
    out
}

/// Skew-symmetric matrix `[v]×` with `[v]× w = v × w`.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Rotation from roll–pitch–yaw (URDF convention: `R = Rz(yaw) Ry(pitch) Rx(roll)`).
pub fn rpy_to_matrix(rpy: &[f64; 3]) -> Matrix3<f64> {
    *nalgebra::Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]).matrix()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symmetric_part_boxed_has_the_bits_of_the_expression() {
        // Entries of mixed magnitudes and signs, so the sums round.
        let h = SMatrix::<f64, 24, 24>::from_fn(|r, c| {
            let x = ((r * 31 + c * 17) % 29) as f64 - 14.0;
            x * 10f64.powi(((r + 2 * c) % 9) as i32 - 4) / 3.0
        });
        let want = (h + h.transpose()) * 0.5;
        let got = symmetric_part_boxed(&h);
        for (a, b) in got.iter().zip(want.iter()) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
        assert_eq!(*got, got.transpose());
    }

    #[test]
    fn twist_apply_matches_homogeneous_product() {
        let s = Matrix3x4::from_fn(|r, c| (r * 4 + c) as f64 * 0.1 - 0.3);
        let a = pose_from(
            &rpy_to_matrix(&[0.3, -0.2, 1.1]),
            &Vector3::new(1.0, 2.0, -0.5),
        );
        let mut s4 = Matrix4::zeros();
        s4.fixed_view_mut::<3, 4>(0, 0).copy_from(&s);
        let full = s4 * homogeneous(&a);
        assert!((twist_apply(&s, &a) - full.fixed_view::<3, 4>(0, 0)).norm() < 1e-14);
    }

    #[test]
    fn rigid_inverse_composes_to_identity() {
        let a = pose_from(
            &rpy_to_matrix(&[0.3, -0.2, 1.1]),
            &Vector3::new(1.0, 2.0, -0.5),
        );
        assert!((compose(&a, &rigid_inverse(&a)) - Pose::identity()).norm() < 1e-14);
    }
}
