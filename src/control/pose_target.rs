//! PD targets on a free (6-DOF) root joint: a prescribed base path.
//!
//! A free joint's coordinates are `θ = (x, y, z, φ)` with the joint transform
//! `J(θ) = [R_c exp(φ) | (x, y, z)]` in the root's attachment frame `B`
//! (`A = B J`); `R_c` is a rotation chart that the simulator re-centres. Six
//! target signals `(x*, y*, z*, r*_x, r*_y, r*_z)` name the target transform
//! `J* = [exp(r*) | p*]` (`r*` an absolute rotation vector, as `initial.q`
//! and the trajectory CSV columns `body:rx …`), and their time derivatives
//! its rate `J̇* = [Ṙ* | ṗ*]` with `Ṙ* = Σ_k ∂exp(r*)/∂r_k ṙ*_k`.
//!
//! A per-coordinate PD term on `φ` would depend on the chart centre, which
//! the simulator moves (`R_c ← R_c exp(φ)`), so the term is written on the
//! transform instead (chart-free, see [`crate::energy::pd_pose`]).
//!
//! The frame `B` is the root's attachment when the scene was built: the
//! target is a fixed world path `B J*(t)` (a designed root attachment of a
//! free joint is redundant with its translation and does not move it).

use crate::math::{Pose, so3};
use nalgebra::{Matrix3, Vector3};
use num_dual::{Dual64, HyperDual64};

/// The six controller channels of one free root joint.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseTarget {
    /// The root link (index in [`crate::model::Model::links`]).
    pub link: usize,
    /// Index of the `x` channel in [`super::Controller::channels`]; the six
    /// channels `first … first + 5` are `x, y, z, r_x, r_y, r_z`.
    pub first: usize,
    /// `B`: the link's attachment (world frame) when the scene was built.
    pub frame: Pose,
}

/// `exp(r)` and `Ṙ = Σ_k ∂exp(r)/∂r_k ṙ_k` (exact, first-order dual numbers).
pub fn rotation_and_rate(r: &Vector3<f64>, rdot: &Vector3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let d = so3::exp_generic([0, 1, 2].map(|j| Dual64::new(r[j], rdot[j])));
    (
        Matrix3::from_fn(|i, j| d[i * 3 + j].re),
        Matrix3::from_fn(|i, j| d[i * 3 + j].eps),
    )
}

/// `∂exp(r)/∂r_k` and `∂Ṙ/∂r_k = Σ_j ∂²exp(r)/∂r_k∂r_j ṙ_j` for `k = 0, 1, 2`
/// (exact, hyper-dual numbers: `ε₁` along `e_k`, `ε₂` along `ṙ`).
pub fn rotation_partials(
    r: &Vector3<f64>,
    rdot: &Vector3<f64>,
) -> ([Matrix3<f64>; 3], [Matrix3<f64>; 3]) {
    let mut dr = [Matrix3::zeros(); 3];
    let mut drdot = [Matrix3::zeros(); 3];
    for k in 0..3 {
        let phi =
            [0, 1, 2].map(|j| HyperDual64::new(r[j], if j == k { 1.0 } else { 0.0 }, rdot[j], 0.0));
        let e = so3::exp_generic(phi);
        dr[k] = Matrix3::from_fn(|i, j| e[i * 3 + j].eps1);
        drdot[k] = Matrix3::from_fn(|i, j| e[i * 3 + j].eps1eps2);
    }
    (dr, drdot)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partials_match_central_differences() {
        let r = Vector3::new(0.4, -0.7, 1.1);
        let rdot = Vector3::new(0.3, 0.5, -0.2);
        let (dr, drdot) = rotation_partials(&r, &rdot);
        let h = 1e-6;
        for k in 0..3 {
            let mut rp = r;
            rp[k] += h;
            let mut rm = r;
            rm[k] -= h;
            let (ap, bp) = rotation_and_rate(&rp, &rdot);
            let (am, bm) = rotation_and_rate(&rm, &rdot);
            assert!(((ap - am) / (2.0 * h) - dr[k]).amax() < 1e-8);
            assert!(((bp - bm) / (2.0 * h) - drdot[k]).amax() < 1e-8);
        }
        // The rate is the derivative along ṙ.
        let (a, rate) = rotation_and_rate(&r, &rdot);
        let (ap, _) = rotation_and_rate(&(r + rdot * h), &rdot);
        let (am, _) = rotation_and_rate(&(r - rdot * h), &rdot);
        assert!(((ap - am) / (2.0 * h) - rate).amax() < 1e-8);
        assert!((a.transpose() * a - Matrix3::identity()).amax() < 1e-12);
    }
}
