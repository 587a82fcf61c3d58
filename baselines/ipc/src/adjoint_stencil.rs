//! Adjoint (vector–Jacobian) products of one IPC stencil, for the backward
//! pass (`sdrs::diff`): the derivatives of
//!
//! ```text
//! Φ(z) = Σ_k ⟨∂E/∂X_k, δX_k⟩          (δX fixed: the adjoint direction)
//! ```
//!
//! with respect to everything the stencil's energy `E` depends on, `z`:
//!
//! - **contact** ([`contact_vjp`]): `E = b(d(X), d̂²) · m(c(X), ε_x)` (the
//!   mollifier only for near-parallel edge–edge stencils), `z = (X, ε_x)`:
//!   `∂Φ/∂X = (∂²E/∂X²) δX` (the *exact*, unprojected Hessian) and
//!   `∂Φ/∂ε_x` (the mollifier threshold depends on the link-frame edge
//!   lengths, i.e. on the design);
//! - **lagged friction** ([`friction_vjp`]): `E = μ λ(Xᵗ) f₀(‖T(Xᵗ)ᵀ Σ_k
//!   w_k(Xᵗ)(X_k − X_kᵗ)‖)`, `z = (X, Xᵗ)`: the step-`t+1` vertices and the
//!   step-`t` ones, through the displacement *and* through the lagged
//!   normal force `λ = κ |b'(d(Xᵗ))| 2√d(Xᵗ)`, closest-point weights `w` and
//!   tangent basis `T` — as the SDRS friction adjoint differentiates its
//!   lagged plane and forces (`sdrs::contact::adjoint_friction`), so a
//!   whole-trajectory gradient sees the same function the forward pass
//!   computes.
//!
//! Both are one mixed second derivative `∂²F/∂t∂z` of
//! `F(t, z) = E(X + t δX, …)` at `t = 0`, computed exactly by forward-mode
//! hyper-dual numbers ([`num_dual::partial_hessian`], one scalar direction
//! `t` against the `N` entries of `z`: `O(N)` per operation, no `N×N`
//! Hessian is formed). The piecewise choices the forward pass makes —
//! distance type, mollifier on/off, tangent-basis axis, the `f₀` branch —
//! are held fixed (the derivative of the active piece, as in IPC).
//!
//! Units: `Φ` has the units of `E` per unit of `δX`'s scale; `κ` is applied
//! by the caller for the contact term (`E` here in m⁴), friction includes
//! `μ κ`.

use crate::barrier::barrier;
use crate::distance::edge_edge::cross_norm2;
use crate::distance::vec::{V3, cross, dot, norm2, sub};
use crate::distance::{DistanceType, squared_distance};
use nalgebra::{Const, SVector};
use num_dual::{DualNum, HyperDualVec, partial_hessian};

/// Result of a stencil's adjoint product.
#[derive(Clone, Debug, PartialEq)]
pub struct StencilVjp {
    /// `Φ = ⟨∇_X E, δX⟩`.
    pub phi: f64,
    /// `∂E/∂X_k` (needed for the `δA`-dependence of `δX = δA x̃`).
    pub grad: [nalgebra::Vector3<f64>; 4],
    /// `∂Φ/∂X_k`.
    pub d_x: [nalgebra::Vector3<f64>; 4],
    /// `∂Φ/∂Xᵗ_k` (friction; zero for contact).
    pub d_prev: [nalgebra::Vector3<f64>; 4],
    /// `∂Φ/∂ε_x` (contact with the mollifier; zero otherwise).
    pub d_eps: f64,
}

/// How a contact stencil is evaluated (fixed pieces of the forward pass).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPiece {
    pub ty: DistanceType,
    /// `Some(ε_x)` when the mollifier is active.
    pub mollifier: Option<f64>,
    /// `d̂²` (m²).
    pub dhat2: f64,
}

/// `m(x, ε) = (2 − x/ε) x/ε` with a differentiable threshold.
fn mollifier_t<T: DualNum<Primitive = f64> + Copy>(x: T, eps: T) -> T {
    let r = x / eps;
    (-r + 2.0) * r
}

/// The contact stencil energy (m⁴) at `x` with threshold `eps` (used only
/// with the mollifier). Generic so dual numbers differentiate it.
pub fn contact_energy<T: DualNum<Primitive = f64> + Copy>(
    x: &[V3<T>; 4],
    eps: T,
    piece: &ContactPiece,
) -> T {
    let mut e = barrier(squared_distance(x, piece.ty), piece.dhat2);
    if piece.mollifier.is_some() {
        e *= mollifier_t(cross_norm2(&x[0], &x[1], &x[2], &x[3]), eps);
    }
    e
}

type Hd<const N: usize> = HyperDualVec<f64, Const<1>, Const<N>>;

fn v3(s: &[f64]) -> nalgebra::Vector3<f64> {
    nalgebra::Vector3::new(s[0], s[1], s[2])
}

/// The contact stencil's adjoint product (see the module docs): `x` the
/// stencil's world points, `dx` the direction `δX`.
pub fn contact_vjp(x: &[V3<f64>; 4], dx: &[V3<f64>; 4], piece: &ContactPiece) -> StencilVjp {
    let t0 = SVector::<f64, 1>::zeros();
    let mut z = SVector::<f64, 13>::zeros();
    for k in 0..4 {
        for e in 0..3 {
            z[3 * k + e] = x[k][e];
        }
    }
    z[12] = piece.mollifier.unwrap_or(1.0);
    let (_, phi, grad, mixed) = partial_hessian(
        |(t, z): (SVector<Hd<13>, 1>, SVector<Hd<13>, 13>)| -> Hd<13> {
            let xs: [V3<Hd<13>>; 4] =
                std::array::from_fn(|k| std::array::from_fn(|e| z[3 * k + e] + t[0] * dx[k][e]));
            contact_energy(&xs, z[12], piece)
        },
        (&t0, &z),
    );
    let mut d_eps = mixed[(0, 12)];
    if piece.mollifier.is_none() {
        d_eps = 0.0;
    }
    StencilVjp {
        phi: phi[0],
        grad: std::array::from_fn(|k| v3(&grad.as_slice()[3 * k..3 * k + 3])),
        d_x: std::array::from_fn(|k| {
            nalgebra::Vector3::new(
                mixed[(0, 3 * k)],
                mixed[(0, 3 * k + 1)],
                mixed[(0, 3 * k + 2)],
            )
        }),
        d_prev: [nalgebra::Vector3::zeros(); 4],
        d_eps,
    }
}

/// Fixed pieces of a lagged friction stencil.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionPiece {
    /// Distance type at the lagged state.
    pub ty: DistanceType,
    /// Coordinate axis the tangent basis was built from
    /// ([`crate::friction_stencil::tangent_axis`]).
    pub axis: usize,
    pub dhat2: f64,
    /// `κ` (J/m⁴).
    pub kappa: f64,
    pub mu: f64,
    /// `ε = ε_v Δt` (m).
    pub eps: f64,
}

/// Closest-point weights of a classified stencil (see
/// [`crate::distance::closest_weights`], the same formulas), generic.
pub fn closest_weights_t<T: DualNum<Primitive = f64> + Copy>(
    x: &[V3<T>; 4],
    ty: DistanceType,
) -> [T; 4] {
    let (z, o) = (T::zero(), T::one());
    let mut w = [z; 4];
    match ty {
        DistanceType::PointPoint(i, j) => {
            w[i as usize] = o;
            w[j as usize] = -o;
        }
        DistanceType::PointLine(p, a, b) => {
            let e = sub(&x[b as usize], &x[a as usize]);
            let t = dot(&sub(&x[p as usize], &x[a as usize]), &e) / norm2(&e);
            w[p as usize] = o;
            w[a as usize] = -(o - t);
            w[b as usize] = -t;
        }
        DistanceType::PointPlane => {
            let (v0, v1, v2) = (sub(&x[2], &x[1]), sub(&x[3], &x[1]), sub(&x[0], &x[1]));
            let (d00, d01, d11) = (dot(&v0, &v0), dot(&v0, &v1), dot(&v1, &v1));
            let (d20, d21) = (dot(&v2, &v0), dot(&v2, &v1));
            let den = d00 * d11 - d01 * d01;
            let b1 = (d11 * d20 - d01 * d21) / den;
            let b2 = (d00 * d21 - d01 * d20) / den;
            w = [o, -(o - b1 - b2), -b1, -b2];
        }
        DistanceType::LineLine => {
            let (d1, d2, r) = (sub(&x[1], &x[0]), sub(&x[3], &x[2]), sub(&x[0], &x[2]));
            let (a, e, b) = (norm2(&d1), norm2(&d2), dot(&d1, &d2));
            let (c, f) = (dot(&d1, &r), dot(&d2, &r));
            let den = a * e - b * b;
            let s = (b * f - c * e) / den;
            let t = (a * f - b * c) / den;
            w = [o - s, s, -(o - t), -t];
        }
    }
    w
}

/// `∂b/∂d` of [`crate::barrier::barrier_derivative`], generic (inside
/// `(0, d̂²)`).
fn barrier_derivative_t<T: DualNum<Primitive = f64> + Copy>(d: T, dhat2: f64) -> T {
    (-d + dhat2) * ((d / dhat2).ln() * 2.0 - d.recip() * dhat2 + 1.0)
}

/// The lagged friction energy (J) of a stencil at current points `x` and
/// lagged points `xp`, everything lagged recomputed from `xp` with the
/// pieces fixed. Generic so dual numbers differentiate it.
pub fn friction_energy<T: DualNum<Primitive = f64> + Copy>(
    x: &[V3<T>; 4],
    xp: &[V3<T>; 4],
    piece: &FrictionPiece,
) -> T {
    let d = squared_distance(xp, piece.ty);
    let lambda = -barrier_derivative_t(d, piece.dhat2) * d.sqrt() * (2.0 * piece.kappa);
    let w = closest_weights_t(xp, piece.ty);
    let mut v = [T::zero(); 3];
    let mut dv = [T::zero(); 3];
    for k in 0..4 {
        for e in 0..3 {
            v[e] += xp[k][e] * w[k];
            dv[e] += (x[k][e] - xp[k][e]) * w[k];
        }
    }
    let inv = norm2(&v).sqrt().recip();
    let n = [v[0] * inv, v[1] * inv, v[2] * inv];
    let mut axis = [T::zero(); 3];
    axis[piece.axis] = T::one();
    let e1 = cross(&n, &axis);
    let inv1 = norm2(&e1).sqrt().recip();
    let e1 = [e1[0] * inv1, e1[1] * inv1, e1[2] * inv1];
    let e2 = cross(&n, &e1);
    let (u1, u2) = (dot(&e1, &dv), dot(&e2, &dv));
    let s = u1 * u1 + u2 * u2;
    let eps = piece.eps;
    let f0 = if s.re() >= eps * eps {
        s.sqrt()
    } else if s.re() > 0.0 {
        -s * s.sqrt() / (3.0 * eps * eps) + s / eps + eps / 3.0
    } else {
        // At u = 0 exactly: the cubic term's first and second derivatives
        // vanish there (its chain through s = ‖u‖² would be 0·∞).
        s / eps + eps / 3.0
    };
    lambda * piece.mu * f0
}

/// The friction stencil's adjoint product (see the module docs): `x`, `xp`
/// the current and lagged world points, `dx` the direction `δX`.
pub fn friction_vjp(
    x: &[V3<f64>; 4],
    xp: &[V3<f64>; 4],
    dx: &[V3<f64>; 4],
    piece: &FrictionPiece,
) -> StencilVjp {
    let t0 = SVector::<f64, 1>::zeros();
    let mut z = SVector::<f64, 24>::zeros();
    for k in 0..4 {
        for e in 0..3 {
            z[3 * k + e] = x[k][e];
            z[12 + 3 * k + e] = xp[k][e];
        }
    }
    let (_, phi, grad, mixed) = partial_hessian(
        |(t, z): (SVector<Hd<24>, 1>, SVector<Hd<24>, 24>)| -> Hd<24> {
            let xs: [V3<Hd<24>>; 4] =
                std::array::from_fn(|k| std::array::from_fn(|e| z[3 * k + e] + t[0] * dx[k][e]));
            let ps: [V3<Hd<24>>; 4] =
                std::array::from_fn(|k| std::array::from_fn(|e| z[12 + 3 * k + e]));
            friction_energy(&xs, &ps, piece)
        },
        (&t0, &z),
    );
    let m = |o: usize| nalgebra::Vector3::new(mixed[(0, o)], mixed[(0, o + 1)], mixed[(0, o + 2)]);
    StencilVjp {
        phi: phi[0],
        grad: std::array::from_fn(|k| v3(&grad.as_slice()[3 * k..3 * k + 3])),
        d_x: std::array::from_fn(|k| m(3 * k)),
        d_prev: std::array::from_fn(|k| m(12 + 3 * k)),
        d_eps: 0.0,
    }
}
