//! Joint kinds and their local transforms `J(q)` with exact first and second
//! derivatives in the joint coordinates `q`.
//!
//! A link's world pose is `A_i = A_parent · C_i · J_i(q_i)` (paper, `pbad.tex`:
//! `T_i = T_λ(i) [R_i^d t_i^d; 0 1] [R_i(θ) t_i(θ); 0 1]`), where `C_i` is the
//! attachment transform (its translation is the design-dependent attachment
//! point in the parent frame) and `J_i` is the joint transform defined here.
//!
//! Rotational joints with three rotational coordinates (spherical, free) use
//! a rotation vector in a *chart*: `R = R_c exp([φ]×)`. The chart centre `R_c`
//! is part of the state, not a degree of freedom; the simulator re-centres it
//! between steps when `‖φ‖` grows (see `sim::state`), so `exp` is never used
//! near its singular set `‖φ‖ = 2π` and there is no gimbal lock.

use crate::math::{Pose, skew, so3};
use nalgebra::{Const, Matrix3, SVector, Vector3};
use num_dual::{Dual2Vec, Dual64, DualNum, hessian};

/// Largest number of coordinates of one joint (free body).
pub const MAX_JOINT_DOF: usize = 6;

/// The kind of a joint and its fixed parameters (axes in the joint frame).
#[derive(Clone, Debug, PartialEq)]
pub enum JointKind {
    /// Rigid attachment, no coordinates.
    Fixed,
    /// Rotation by `q` (rad) about the unit `axis`: `J = [Rot(axis, q) | 0]`.
    Revolute { axis: Vector3<f64> },
    /// Translation by `q` (m) along the unit `axis`: `J = [I | q·axis]`.
    Prismatic { axis: Vector3<f64> },
    /// Two orthogonal hinges (the paper's rotating chains):
    /// `J = [Rot(a₁, q₁) Rot(a₂, q₂) | 0]`.
    Ball { axes: [Vector3<f64>; 2] },
    /// Three rotational coordinates, a rotation vector in a chart:
    /// `J = [R_c exp([φ]×) | 0]`.
    Spherical,
    /// Six coordinates `q = [p; φ]` (m, rad): `J = [R_c exp([φ]×) | p]`.
    /// Used for floating bases and free objects.
    Free,
}

impl JointKind {
    /// Number of coordinates.
    pub fn ndof(&self) -> usize {
        match self {
            JointKind::Fixed => 0,
            JointKind::Revolute { .. } | JointKind::Prismatic { .. } => 1,
            JointKind::Ball { .. } => 2,
            JointKind::Spherical => 3,
            JointKind::Free => 6,
        }
    }

    /// Whether the joint has a rotation-vector chart (`R_c`).
    pub fn has_chart(&self) -> bool {
        matches!(self, JointKind::Spherical | JointKind::Free)
    }

    /// Index of the first rotation-vector coordinate for charted joints.
    pub fn chart_offset(&self) -> usize {
        match self {
            JointKind::Free => 3,
            _ => 0,
        }
    }

    /// Short column suffixes for each coordinate (used in CSV headers).
    pub fn dof_labels(&self) -> &'static [&'static str] {
        match self {
            JointKind::Fixed => &[],
            JointKind::Revolute { .. } | JointKind::Prismatic { .. } => &[""],
            JointKind::Ball { .. } => &["0", "1"],
            JointKind::Spherical => &["rx", "ry", "rz"],
            JointKind::Free => &["x", "y", "z", "rx", "ry", "rz"],
        }
    }

    /// Type name as written in scene files.
    pub fn type_name(&self) -> &'static str {
        match self {
            JointKind::Fixed => "fixed",
            JointKind::Revolute { .. } => "revolute",
            JointKind::Prismatic { .. } => "prismatic",
            JointKind::Ball { .. } => "ball",
            JointKind::Spherical => "spherical",
            JointKind::Free => "free",
        }
    }

    /// `J(q)` as 12 numbers, column-major `[R | t]`, generic over dual numbers.
    fn transform_generic<D: DualNum<Primitive = f64> + Copy>(
        &self,
        chart: &Matrix3<f64>,
        q: &[D],
    ) -> [D; 12] {
        let mut out = [D::zero(); 12];
        let set_rot = |out: &mut [D; 12], r_row_major: &[D; 9]| {
            for r in 0..3 {
                for c in 0..3 {
                    out[c * 3 + r] = r_row_major[r * 3 + c];
                }
            }
        };
        let axis_rot = |axis: &Vector3<f64>, q: D| hinge_rotation(axis, q);
        let chart_rot = |phi: [D; 3]| -> [D; 9] {
            let e = so3::exp_generic(phi);
            let mut r = [D::zero(); 9];
            for i in 0..3 {
                for j in 0..3 {
                    let mut acc = D::zero();
                    for k in 0..3 {
                        acc += e[k * 3 + j] * chart[(i, k)];
                    }
                    r[i * 3 + j] = acc;
                }
            }
            r
        };
        match self {
            JointKind::Fixed => {
                set_rot(&mut out, &identity9());
            }
            JointKind::Revolute { axis } => set_rot(&mut out, &axis_rot(axis, q[0])),
            JointKind::Prismatic { axis } => {
                set_rot(&mut out, &identity9());
                for r in 0..3 {
                    out[9 + r] = q[0] * axis[r];
                }
            }
            JointKind::Ball { axes } => {
                let r1 = axis_rot(&axes[0], q[0]);
                let r2 = axis_rot(&axes[1], q[1]);
                set_rot(&mut out, &mul9(&r1, &r2));
            }
            JointKind::Spherical => set_rot(&mut out, &chart_rot([q[0], q[1], q[2]])),
            JointKind::Free => {
                set_rot(&mut out, &chart_rot([q[3], q[4], q[5]]));
                out[9] = q[0];
                out[10] = q[1];
                out[11] = q[2];
            }
        }
        out
    }

    /// `J(q)` for plain numbers.
    pub fn transform(&self, chart: &Matrix3<f64>, q: &[f64]) -> Pose {
        Pose::from_column_slice(&self.transform_generic(chart, q))
    }

    /// `J(q)` and its rate `dJ/dα` along the straight line `q + α dq` at
    /// `α = 0` (exact, by first-order dual numbers): the rotation's rate in
    /// the first three columns, the translation's in the last.
    pub fn transform_velocity(&self, chart: &Matrix3<f64>, q: &[f64], dq: &[f64]) -> (Pose, Pose) {
        let n = self.ndof();
        let mut qs = [Dual64::from(0.0); 6];
        for k in 0..n {
            qs[k] = Dual64::new(q[k], dq[k]);
        }
        let out = self.transform_generic(chart, &qs[..n.max(1)]);
        (
            Pose::from_fn(|r, c| out[c * 3 + r].re),
            Pose::from_fn(|r, c| out[c * 3 + r].eps),
        )
    }

    /// `J(q)`, `∂J/∂q_k` and `∂²J/∂q_k∂q_l`. `d1[k]` and `d2[k][l]` are
    /// filled for `k, l < ndof`.
    ///
    /// Hinge-type joints in closed form (exact): with `K = [a]×`,
    /// `d/dq exp(qK) = K exp(qK) = exp(qK) K`, so a revolute joint has
    /// `∂R/∂q = K R`, `∂²R/∂q² = K² R`, and the ball joint `R = R₁R₂` has
    /// `∂R/∂q₁ = K₁R`, `∂R/∂q₂ = R K₂`, `∂²R/∂q₁² = K₁²R`,
    /// `∂²R/∂q₁∂q₂ = K₁ R K₂`, `∂²R/∂q₂² = R K₂²`; a prismatic joint has
    /// `∂t/∂q = a` and no curvature. `J(q)` itself is [`JointKind::transform`]
    /// (the same bits as a pose-only evaluation). Charted joints (spherical,
    /// free) use second-order dual numbers ([`JointKind::transform_derivatives_dual`])
    /// for the derivatives, with the value from [`JointKind::transform`];
    /// the dual-number evaluation of the hinges was a third of a step with
    /// two links per chain.
    pub fn transform_derivatives(
        &self,
        chart: &Matrix3<f64>,
        q: &[f64],
        out: &mut JointDerivatives,
    ) {
        let set_rot = |p: &mut Pose, r: &Matrix3<f64>| {
            p.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
            p.set_column(3, &Vector3::zeros());
        };
        match self {
            JointKind::Revolute { axis } => {
                out.value = self.transform(chart, q);
                let r = out.value.fixed_view::<3, 3>(0, 0).into_owned();
                let k = skew(axis);
                let kr = k * r;
                set_rot(&mut out.d1[0], &kr);
                set_rot(&mut out.d2[0][0], &(k * kr));
            }
            JointKind::Ball { axes } => {
                out.value = self.transform(chart, q);
                let r = out.value.fixed_view::<3, 3>(0, 0).into_owned();
                let (k1, k2) = (skew(&axes[0]), skew(&axes[1]));
                let (k1r, rk2) = (k1 * r, r * k2);
                set_rot(&mut out.d1[0], &k1r);
                set_rot(&mut out.d1[1], &rk2);
                set_rot(&mut out.d2[0][0], &(k1 * k1r));
                let mixed = k1r * k2;
                set_rot(&mut out.d2[0][1], &mixed);
                set_rot(&mut out.d2[1][0], &mixed);
                set_rot(&mut out.d2[1][1], &(rk2 * k2));
            }
            JointKind::Prismatic { axis } => {
                out.value = self.transform(chart, q);
                out.d1[0] = Pose::zeros();
                out.d1[0].set_column(3, axis);
                out.d2[0][0] = Pose::zeros();
            }
            _ => {
                self.transform_derivatives_dual(chart, q, out);
                // The dual numbers' real part can differ from `transform`
                // in the last bit (their division and `sin`/`cos` round
                // differently): the value is `transform`'s, so every
                // evaluation order gives one pose for one `q`.
                out.value = self.transform(chart, q);
            }
        }
    }

    /// [`JointKind::transform_derivatives`] by second-order dual numbers
    /// (exact; every kind).
    pub fn transform_derivatives_dual(
        &self,
        chart: &Matrix3<f64>,
        q: &[f64],
        out: &mut JointDerivatives,
    ) {
        match self.ndof() {
            0 => {
                out.value = self.transform(chart, q);
            }
            1 => self.derivs_n::<1>(chart, q, out),
            2 => self.derivs_n::<2>(chart, q, out),
            3 => self.derivs_n::<3>(chart, q, out),
            6 => self.derivs_n::<6>(chart, q, out),
            n => unreachable!("joint with {n} coordinates"),
        }
    }

    fn derivs_n<const N: usize>(
        &self,
        chart: &Matrix3<f64>,
        q: &[f64],
        out: &mut JointDerivatives,
    ) {
        let x = SVector::<f64, N>::from_column_slice(&q[..N]);
        let res = hessian(
            |v: SVector<Dual2Vec<f64, Const<N>>, N>| -> [Dual2Vec<f64, Const<N>>; 12] {
                let qs: [Dual2Vec<f64, Const<N>>; N] = std::array::from_fn(|i| v[i]);
                self.transform_generic(chart, &qs)
            },
            &x,
        );
        for (e, (val, grad, hess)) in res.iter().enumerate() {
            let (c, r) = (e / 3, e % 3);
            out.value[(r, c)] = *val;
            for k in 0..N {
                out.d1[k][(r, c)] = grad[k];
                for l in 0..N {
                    out.d2[k][l][(r, c)] = hess[(k, l)];
                }
            }
        }
    }
}

/// Row-major `Rot(a, q) = I + sin q [a]× + (1 − cos q) [a]×²` for a unit
/// axis `a` (Rodrigues' formula with the angle known: one `sin_cos`, no
/// norm). `[a]×² = a aᵀ − I`.
fn hinge_rotation<D: DualNum<Primitive = f64> + Copy>(a: &Vector3<f64>, q: D) -> [D; 9] {
    let (s, c) = q.sin_cos();
    let v = D::one() - c;
    let k = [0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0];
    let mut r = [D::zero(); 9];
    for i in 0..3 {
        for j in 0..3 {
            let id = if i == j { 1.0 } else { 0.0 };
            let k2 = a[i] * a[j] - id;
            r[i * 3 + j] = s * k[i * 3 + j] + v * k2 + id;
        }
    }
    r
}

fn identity9<D: DualNum<Primitive = f64> + Copy>() -> [D; 9] {
    let mut r = [D::zero(); 9];
    r[0] = D::one();
    r[4] = D::one();
    r[8] = D::one();
    r
}

fn mul9<D: DualNum<Primitive = f64> + Copy>(a: &[D; 9], b: &[D; 9]) -> [D; 9] {
    let mut r = [D::zero(); 9];
    for i in 0..3 {
        for j in 0..3 {
            let mut acc = D::zero();
            for k in 0..3 {
                acc += a[i * 3 + k] * b[k * 3 + j];
            }
            r[i * 3 + j] = acc;
        }
    }
    r
}

/// Local transform of one joint with its coordinate derivatives.
#[derive(Clone, Debug)]
pub struct JointDerivatives {
    /// `J(q)`.
    pub value: Pose,
    /// `∂J/∂q_k`.
    pub d1: [Pose; MAX_JOINT_DOF],
    /// `∂²J/∂q_k∂q_l`.
    pub d2: [[Pose; MAX_JOINT_DOF]; MAX_JOINT_DOF],
}

impl Default for JointDerivatives {
    fn default() -> Self {
        Self {
            value: Pose::identity(),
            d1: [Pose::zeros(); MAX_JOINT_DOF],
            d2: [[Pose::zeros(); MAX_JOINT_DOF]; MAX_JOINT_DOF],
        }
    }
}

/// A mimic tie `θ_dof ≈ multiplier·θ_master + offset`, enforced by the
/// penalty term [`crate::energy::mimic`].
#[derive(Clone, Debug, PartialEq)]
pub struct MimicTie {
    /// The following coordinate.
    pub dof: usize,
    /// The followed coordinate.
    pub master: usize,
    pub multiplier: f64,
    /// rad or m.
    pub offset: f64,
    /// Tie stiffness `k` (J/rad² or J/m²).
    pub stiffness: f64,
}

/// Position limits of a 1-DOF (revolute or prismatic) joint, enforced by
/// the barrier term [`crate::energy::joint_limit`]; velocity and effort
/// limits are carried for reports only (not simulated).
#[derive(Clone, Debug, PartialEq)]
pub struct JointLimit {
    /// Lower and upper position limit (rad or m), `lower < upper`.
    pub lower: f64,
    pub upper: f64,
    /// Barrier support `s` (rad or m).
    pub support: f64,
    /// Barrier stiffness `κ` (J·rad or J·m).
    pub stiffness: f64,
    /// Velocity limit (rad/s or m/s), reported only.
    pub velocity: Option<f64>,
    /// Effort limit (N·m or N), reported only.
    pub effort: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::so3;

    fn kinds() -> Vec<JointKind> {
        vec![
            JointKind::Revolute {
                axis: Vector3::new(0.0, 0.6, 0.8),
            },
            JointKind::Prismatic {
                axis: Vector3::new(1.0, 0.0, 0.0),
            },
            JointKind::Ball {
                axes: [Vector3::x(), Vector3::y()],
            },
            JointKind::Spherical,
            JointKind::Free,
        ]
    }

    #[test]
    fn joint_derivatives_match_finite_differences() {
        let chart = so3::exp(&Vector3::new(0.2, -0.4, 0.9));
        for kind in kinds() {
            let n = kind.ndof();
            for q0 in [
                vec![0.3, -0.7, 1.1, 0.2, -0.5, 0.4],
                vec![0.0; 6],
                // rotation of nearly π for the charted joints
                vec![0.1, 0.2, 0.3, 0.0, 0.0, std::f64::consts::PI - 1e-3],
                vec![0.0, 0.0, std::f64::consts::PI - 1e-3, 0.0, 0.0, 0.0],
            ] {
                let mut d = JointDerivatives::default();
                kind.transform_derivatives(&chart, &q0, &mut d);
                let h = 1e-5;
                for k in 0..n {
                    let mut qp = q0.clone();
                    let mut qm = q0.clone();
                    qp[k] += h;
                    qm[k] -= h;
                    let fd =
                        (kind.transform(&chart, &qp) - kind.transform(&chart, &qm)) / (2.0 * h);
                    assert!((fd - d.d1[k]).norm() < 1e-8, "{kind:?} d1[{k}]");
                    let mut pp = JointDerivatives::default();
                    let mut mm = JointDerivatives::default();
                    kind.transform_derivatives(&chart, &qp, &mut pp);
                    kind.transform_derivatives(&chart, &qm, &mut mm);
                    for l in 0..n {
                        let fd2 = (pp.d1[l] - mm.d1[l]) / (2.0 * h);
                        assert!((fd2 - d.d2[k][l]).norm() < 1e-7, "{kind:?} d2[{k}][{l}]");
                    }
                }
            }
        }
    }

    /// The closed-form hinge derivatives equal the dual-number ones to
    /// round-off (value bit for bit up to the dual path's own rounding).
    #[test]
    fn closed_form_hinge_derivatives_match_dual_numbers() {
        let chart = Matrix3::identity();
        let tilted = Vector3::new(0.3, -0.5, 0.8).normalize();
        let kinds = [
            JointKind::Revolute { axis: tilted },
            JointKind::Prismatic { axis: tilted },
            JointKind::Ball {
                axes: [Vector3::x(), Vector3::y()],
            },
            JointKind::Ball {
                axes: [tilted, tilted.cross(&Vector3::z()).normalize()],
            },
        ];
        for kind in kinds {
            let n = kind.ndof();
            for q in [[0.3, -0.7], [0.0, 0.0], [3.0, -2.9], [1e-9, 2e-12]] {
                let (mut a, mut b) = (JointDerivatives::default(), JointDerivatives::default());
                kind.transform_derivatives(&chart, &q, &mut a);
                kind.transform_derivatives_dual(&chart, &q, &mut b);
                assert!((a.value - b.value).amax() <= 4e-16, "{kind:?} value");
                for k in 0..n {
                    assert!((a.d1[k] - b.d1[k]).amax() <= 1e-14, "{kind:?} d1[{k}]");
                    for l in 0..n {
                        let e = (a.d2[k][l] - b.d2[k][l]).amax();
                        assert!(e <= 1e-14, "{kind:?} d2[{k}][{l}]: {e:e}");
                    }
                }
            }
        }
    }
}
