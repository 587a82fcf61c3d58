//! The lagged data of step `t` that the friction potential of step `t + 1` is built from: the
//! plane normal, tangent basis, vertex positions and normal forces of a contact pair.

use nalgebra::{Matrix2, Matrix3x2, Vector3};

use super::*;
use crate::contact::barrier::barrier_d2;
use crate::contact::error::{FrictionError, Hull};
use crate::contact::potential::{ContactPair, ContactParams, HullPose};

/// Lagged step-`t` data of one hull pair (borrowed view). See the module docs.
#[derive(Clone, Copy, Debug)]
pub struct FrictionFrame<'a> {
    /// Unit plane normal `n̂` from hull `a` to hull `b`.
    pub normal: Vector3<f64>,
    /// Orthonormal tangent basis `B` (3×2, `Bᵀ n̂ = 0`).
    pub basis: Matrix3x2<f64>,
    /// World positions `X^t` of hull `a`'s vertices.
    pub x_prev_a: &'a [Vector3<f64>],
    /// World positions `X^t` of hull `b`'s vertices.
    pub x_prev_b: &'a [Vector3<f64>],
    /// Normal-force magnitudes `κ ‖f_⊥^m‖ ≥ 0` of hull `a`'s vertices.
    pub normal_force_a: &'a [f64],
    /// Normal-force magnitudes `κ ‖f_⊥^m‖ ≥ 0` of hull `b`'s vertices.
    pub normal_force_b: &'a [f64],
}

impl FrictionFrame<'_> {
    pub(super) fn validate(&self) -> Result<(), FrictionError> {
        let n = self.normal;
        if !n.iter().all(|v| v.is_finite()) || (n.norm() - 1.0).abs() > 1e-9 {
            return Err(FrictionError::InvalidFrame {
                reason: "normal is not a finite unit vector",
            });
        }
        let btb = self.basis.transpose() * self.basis;
        if !self.basis.iter().all(|v| v.is_finite())
            || (btb - Matrix2::identity()).norm() > 1e-9
            || (self.basis.transpose() * n).norm() > 1e-9
        {
            return Err(FrictionError::InvalidFrame {
                reason: "tangent basis is not orthonormal and orthogonal to the normal",
            });
        }
        for (hull, x, f) in [
            (Hull::A, self.x_prev_a, self.normal_force_a),
            (Hull::B, self.x_prev_b, self.normal_force_b),
        ] {
            if x.len() != f.len() {
                return Err(FrictionError::LengthMismatch {
                    hull,
                    what: "normal_force",
                    expected: x.len(),
                    got: f.len(),
                });
            }
            if !x.iter().all(|v| v.iter().all(|c| c.is_finite())) {
                return Err(FrictionError::InvalidFrame {
                    reason: "non-finite X^t",
                });
            }
            if !f.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(FrictionError::InvalidFrame {
                    reason: "normal forces must be finite and non-negative",
                });
            }
        }
        Ok(())
    }
}

/// Owned lagged data built from a step-`t` contact solve (allocates; once per step and pair).
#[derive(Clone, Debug, PartialEq)]
pub struct LaggedContact {
    /// Unit normal `n*/‖n*‖`.
    pub normal: Vector3<f64>,
    /// Tangent basis from [`tangent_basis`].
    pub basis: Matrix3x2<f64>,
    /// `X^t` of hull `a`.
    pub x_prev_a: Vec<Vector3<f64>>,
    /// `X^t` of hull `b`.
    pub x_prev_b: Vec<Vector3<f64>>,
    /// `κ ‖f_⊥^m‖` of hull `a`.
    pub normal_force_a: Vec<f64>,
    /// `κ ‖f_⊥^m‖` of hull `b`.
    pub normal_force_b: Vec<f64>,
}

impl LaggedContact {
    /// Lagged data of a separated pair at step `t`: `pair` is the result of
    /// [`contact_pair`](super::contact_pair) at the step-`t` poses `a`, `b`; `kappa` is the
    /// contact stiffness. Normal forces are `κ |P_s'(y_m)| ‖n*‖`.
    pub fn from_contact(
        pair: &ContactPair,
        a: HullPose<'_>,
        b: HullPose<'_>,
        params: &ContactParams,
        kappa: f64,
    ) -> Self {
        let n = pair.normal();
        let nn = n.norm();
        let normal = n / nn;
        let o = pair.plane.w;
        let build = |h: HullPose<'_>, sigma: f64| {
            let mut xs = Vec::with_capacity(h.x_local.len());
            let mut fs = Vec::with_capacity(h.x_local.len());
            for x in h.x_local {
                let xw = h.pose.fixed_columns::<3>(0) * x + h.pose.column(3);
                let (_, d1, _) = barrier_d2(sigma * (n.dot(&xw) + o), params.s);
                xs.push(xw);
                fs.push(kappa * d1.abs() * nn);
            }
            (xs, fs)
        };
        let (x_prev_a, normal_force_a) = build(a, -1.0);
        let (x_prev_b, normal_force_b) = build(b, 1.0);
        Self {
            normal,
            basis: tangent_basis(&normal),
            x_prev_a,
            x_prev_b,
            normal_force_a,
            normal_force_b,
        }
    }

    /// Borrowed view for [`friction_pair`] / [`friction_vertices`].
    pub fn frame(&self) -> FrictionFrame<'_> {
        FrictionFrame {
            normal: self.normal,
            basis: self.basis,
            x_prev_a: &self.x_prev_a,
            x_prev_b: &self.x_prev_b,
            normal_force_a: &self.normal_force_a,
            normal_force_b: &self.normal_force_b,
        }
    }
}
