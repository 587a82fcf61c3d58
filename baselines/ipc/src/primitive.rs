//! The barrier potential of one primitive pair (a four-point stencil), with
//! its gradient and PSD-projected Hessian over the 12 stencil coordinates:
//!
//! - point–triangle: `P = b(d(x), d̂²)`;
//! - edge–edge: `P = m(‖e_a × e_b‖², ε_x) · b(d(x), d̂²)` when the edges are
//!   near-parallel (`‖e_a × e_b‖² < ε_x`), else `b(d(x), d̂²)`;
//!
//! with `d` the classified squared distance ([`crate::distance`]), `b` the
//! barrier ([`crate::barrier`]) and `m` the mollifier ([`crate::mollifier`]).
//! Units: m⁴ (the stiffness `κ` is applied by the caller). Derivatives are
//! exact (forward-mode second-order dual numbers through the same formula as
//! the value), and the Hessian is projected to the nearest positive
//! semi-definite matrix by clamping its eigenvalues at 0, as IPC does per
//! primitive.

use crate::barrier::{barrier, barrier_value};
use crate::distance::edge_edge::cross_norm2;
use crate::distance::vec::V3;
use crate::distance::{
    DistanceType, classify_edge_edge, classify_point_triangle, squared_distance,
};
use crate::mollifier::mollifier;
use nalgebra::{Const, SMatrix, SVector};
use num_dual::{Dual2Vec, hessian};

/// 12-vector over a stencil `[x₀; x₁; x₂; x₃]`.
pub type Vec12 = SVector<f64, 12>;
/// 12×12 matrix over a stencil.
pub type Mat12 = SMatrix<f64, 12, 12>;

/// What kind of stencil.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PrimitiveKind {
    /// `[p, t₀, t₁, t₂]`.
    PointTriangle,
    /// `[a₀, a₁, b₀, b₁]` with the mollifier threshold `ε_x` (m⁴).
    EdgeEdge { eps_x: f64 },
}

/// Value and derivatives of one active primitive.
#[derive(Clone, Debug)]
pub struct PrimitiveEval {
    /// Squared distance `d` (m²).
    pub distance2: f64,
    pub ty: DistanceType,
    /// Potential (m⁴).
    pub value: f64,
    /// `∂P/∂x` (m³), when derivatives were requested.
    pub grad: Vec12,
    /// `∂²P/∂x²` (m²), when requested: PSD-projected unless the caller asked
    /// for the exact one ([`evaluate_with`]).
    pub hess: Mat12,
}

/// Outcome of a primitive evaluation.
#[derive(Clone, Debug)]
pub enum Primitive {
    /// `d ≥ d̂²`: no potential. Carries the classified squared distance
    /// `d` (m²), so callers that track the smallest distance need not
    /// classify the stencil again.
    Inactive {
        distance2: f64,
    },
    /// `d ≤ 0`: touching or crossing (the configuration is infeasible).
    Touching,
    Active(Box<PrimitiveEval>),
}

/// Whether the mollifier is active and its `ε_x`.
pub fn mollified(kind: PrimitiveKind, x: &[V3<f64>; 4]) -> Option<f64> {
    match kind {
        PrimitiveKind::PointTriangle => None,
        PrimitiveKind::EdgeEdge { eps_x } => {
            (cross_norm2(&x[0], &x[1], &x[2], &x[3]) < eps_x).then_some(eps_x)
        }
    }
}

/// Classified squared distance of a stencil (m²).
pub fn stencil_distance(kind: PrimitiveKind, x: &[V3<f64>; 4]) -> (f64, DistanceType) {
    let ty = match kind {
        PrimitiveKind::PointTriangle => classify_point_triangle(x),
        PrimitiveKind::EdgeEdge { .. } => classify_edge_edge(x),
    };
    (squared_distance(x, ty), ty)
}

/// Evaluates the barrier potential of a stencil. With `derivatives` false
/// only `value` is meaningful (gradient and Hessian are left zero).
pub fn evaluate(kind: PrimitiveKind, x: &[V3<f64>; 4], dhat2: f64, derivatives: bool) -> Primitive {
    evaluate_with(kind, x, dhat2, derivatives, true)
}

/// [`evaluate`] with the PSD projection of the Hessian optional: `project`
/// false gives the exact Hessian (the backward pass linearizes the step
/// residual exactly; Newton's steps use the projected one).
pub fn evaluate_with(
    kind: PrimitiveKind,
    x: &[V3<f64>; 4],
    dhat2: f64,
    derivatives: bool,
    project: bool,
) -> Primitive {
    let (d, ty) = stencil_distance(kind, x);
    if d <= 0.0 || !d.is_finite() {
        return Primitive::Touching;
    }
    if d >= dhat2 {
        return Primitive::Inactive { distance2: d };
    }
    let moll = mollified(kind, x);
    let mut out = PrimitiveEval {
        distance2: d,
        ty,
        value: barrier_value(d, dhat2),
        grad: Vec12::zeros(),
        hess: Mat12::zeros(),
    };
    if let Some(e) = moll {
        out.value *= mollifier(cross_norm2(&x[0], &x[1], &x[2], &x[3]), e);
    }
    if derivatives {
        let flat = Vec12::from_fn(|i, _| x[i / 3][i % 3]);
        type D = Dual2Vec<f64, Const<12>>;
        let (_, g, h) = hessian(
            |v: SVector<D, 12>| -> D {
                let xs: [V3<D>; 4] =
                    std::array::from_fn(|k| [v[3 * k], v[3 * k + 1], v[3 * k + 2]]);
                let mut e = barrier(squared_distance(&xs, ty), dhat2);
                if let Some(eps) = moll {
                    e *= mollifier(cross_norm2(&xs[0], &xs[1], &xs[2], &xs[3]), eps);
                }
                e
            },
            &flat,
        );
        out.grad = g;
        out.hess = if project { project_psd(&h) } else { h };
    }
    Primitive::Active(Box::new(out))
}

/// The nearest symmetric positive semi-definite matrix (Frobenius norm):
/// eigenvalues clamped at 0.
pub fn project_psd(h: &Mat12) -> Mat12 {
    let sym = (h + h.transpose()) * 0.5;
    let eig = sym.symmetric_eigen();
    if eig.eigenvalues.iter().all(|&l| l >= 0.0) {
        return sym;
    }
    let mut out = Mat12::zeros();
    for (k, &l) in eig.eigenvalues.iter().enumerate() {
        if l > 0.0 {
            let v = eig.eigenvectors.column(k);
            out += v * v.transpose() * l;
        }
    }
    out
}

/// The exact (unprojected) Hessian, for tests.
pub fn exact_hessian(
    kind: PrimitiveKind,
    x: &[V3<f64>; 4],
    dhat2: f64,
) -> Option<(f64, Vec12, Mat12)> {
    let (d, ty) = stencil_distance(kind, x);
    if d <= 0.0 || d >= dhat2 {
        return None;
    }
    let moll = mollified(kind, x);
    let flat = Vec12::from_fn(|i, _| x[i / 3][i % 3]);
    type D = Dual2Vec<f64, Const<12>>;
    Some(hessian(
        |v: SVector<D, 12>| -> D {
            let xs: [V3<D>; 4] = std::array::from_fn(|k| [v[3 * k], v[3 * k + 1], v[3 * k + 2]]);
            let mut e = barrier(squared_distance(&xs, ty), dhat2);
            if let Some(eps) = moll {
                e *= mollifier(cross_norm2(&xs[0], &xs[1], &xs[2], &xs[3]), eps);
            }
            e
        },
        &flat,
    ))
}
