//! The IPC stencils' adjoint products (`sdrs_ipc::adjoint_stencil`) against
//! finite differences: `Φ(z) = ⟨∇_X E, δX⟩` is evaluated exactly (first-order
//! dual numbers) and differenced in every entry of `z` (Richardson-
//! extrapolated central differences), ≤ 1e-6 relative:
//!
//! - contact: `z = (X, ε_x)` over point–triangle (all regions) and edge–edge
//!   stencils, `d → d̂²`, near-parallel (mollified) edges down to 1e-6 rad;
//! - friction: `z = (X, Xᵗ)` (current and lagged points, through the lagged
//!   `λ`, `w`, `T`) in the sliding and smoothed-static regimes, `d → d̂²`,
//!   and near-parallel edges.
//!
//! Also: the generic energies equal the forward pass's (same function), and
//! `∂Φ/∂X` equals the exact Hessian times `δX`.

use nalgebra::{Const, SVector, Vector3};
use num_dual::{DualVec, gradient};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sdrs_ipc::adjoint_stencil::{
    ContactPiece, FrictionPiece, closest_weights_t, contact_energy, contact_vjp, friction_energy,
    friction_vjp,
};
use sdrs_ipc::barrier::barrier_derivative;
use sdrs_ipc::distance::vec::{V3, cross, norm2, sub};
use sdrs_ipc::distance::{DistanceType, closest_weights};
use sdrs_ipc::friction_stencil::{FrictionStencil, tangent_axis, tangent_basis};
use sdrs_ipc::mollifier::eps_x;
use sdrs_ipc::primitive::{
    Primitive, PrimitiveKind, evaluate, exact_hessian, mollified, stencil_distance,
};

const DHAT: f64 = 1e-3;

fn rand_v(rng: &mut ChaCha8Rng, s: f64) -> V3<f64> {
    std::array::from_fn(|_| rng.random_range(-s..s))
}

fn pt_config(rng: &mut ChaCha8Rng, bary: [f64; 3], dist: f64) -> [V3<f64>; 4] {
    let t: [V3<f64>; 3] = std::array::from_fn(|_| rand_v(rng, 2e-3));
    let n = cross(&sub(&t[1], &t[0]), &sub(&t[2], &t[0]));
    let nn = norm2(&n).sqrt();
    let p: V3<f64> = std::array::from_fn(|k| {
        bary[0] * t[0][k] + bary[1] * t[1][k] + bary[2] * t[2][k] + dist * n[k] / nn
    });
    [p, t[0], t[1], t[2]]
}

fn ee_config(rng: &mut ChaCha8Rng, angle: f64, s: f64, t: f64, dist: f64) -> [V3<f64>; 4] {
    let u = Vector3::from(rand_v(rng, 1.0)).normalize();
    let w = u.cross(&Vector3::from(rand_v(rng, 1.0))).normalize();
    let n = u.cross(&w);
    let v = u * angle.cos() + w * angle.sin();
    let (la, lb) = (rng.random_range(1e-3..4e-3), rng.random_range(1e-3..4e-3));
    let c = Vector3::from(rand_v(rng, 2e-3));
    let a0 = c - u * (s * la);
    let b0 = c + n * dist - v * (t * lb);
    let arr = |p: Vector3<f64>| [p.x, p.y, p.z];
    [arr(a0), arr(a0 + u * la), arr(b0), arr(b0 + v * lb)]
}

fn ee_kind(x: &[V3<f64>; 4]) -> PrimitiveKind {
    PrimitiveKind::EdgeEdge {
        eps_x: eps_x(norm2(&sub(&x[1], &x[0])), norm2(&sub(&x[3], &x[2]))),
    }
}

/// Length scale the function varies on near `x` (see
/// `primitive_derivatives.rs`): distance, gap to d̂, edge angle offsets.
fn scale(kind: PrimitiveKind, x: &[V3<f64>; 4]) -> f64 {
    let (d, ty) = stencil_distance(kind, x);
    let mut s = d.sqrt().min((DHAT * DHAT - d) / (2.0 * d.sqrt()));
    if let PrimitiveKind::EdgeEdge { .. } = kind {
        let (ea, eb) = (sub(&x[1], &x[0]), sub(&x[3], &x[2]));
        let (la, lb) = (norm2(&ea).sqrt(), norm2(&eb).sqrt());
        let c = norm2(&cross(&ea, &eb)).sqrt();
        s = s.min(c / la.max(lb));
        if ty == DistanceType::LineLine {
            let phi = c / (la * lb);
            s = s.min(0.1 * la.min(lb).powi(2) * phi * phi / d.sqrt());
        }
    }
    s
}

/// Richardson-extrapolated central difference of `f` in coordinate `i`.
fn fd<const N: usize>(
    f: &impl Fn(&SVector<f64, N>) -> f64,
    z: &SVector<f64, N>,
    i: usize,
    h: f64,
) -> f64 {
    let cd = |h: f64| {
        let (mut a, mut b) = (*z, *z);
        a[i] += h;
        b[i] -= h;
        (f(&a) - f(&b)) / (2.0 * h)
    };
    (4.0 * cd(h / 2.0) - cd(h)) / 3.0
}

fn unflat<T: Copy>(z: &[T], off: usize) -> [V3<T>; 4] {
    std::array::from_fn(|k| std::array::from_fn(|e| z[off + 3 * k + e]))
}

type D13 = DualVec<f64, Const<13>>;
type D24 = DualVec<f64, Const<24>>;

/// Checks the contact adjoint at `x`; false when the FD stencil crosses a
/// distance-type or mollifier boundary (nothing checked).
fn check_contact(kind: PrimitiveKind, x: &[V3<f64>; 4], label: &str, rng: &mut ChaCha8Rng) -> bool {
    let (d, ty) = stencil_distance(kind, x);
    let piece = ContactPiece {
        ty,
        mollifier: mollified(kind, x),
        dhat2: DHAT * DHAT,
    };
    let eps0 = match kind {
        PrimitiveKind::EdgeEdge { eps_x } => eps_x,
        _ => 1.0,
    };
    // Same function as the forward pass.
    let Primitive::Active(e) = evaluate(kind, x, DHAT * DHAT, false) else {
        panic!("{label}: inactive")
    };
    let val = contact_energy(x, eps0, &piece);
    assert!(
        (val - e.value).abs() <= 1e-12 * e.value.abs(),
        "{label}: {val} vs {}",
        e.value
    );
    let dx: [V3<f64>; 4] = std::array::from_fn(|_| rand_v(rng, 1.0));
    let v = contact_vjp(x, &dx, &piece);
    // ∂Φ/∂X = H δX with the exact Hessian.
    let (_, g, h) = exact_hessian(kind, x, DHAT * DHAT).unwrap();
    let dxv = SVector::<f64, 12>::from_fn(|i, _| dx[i / 3][i % 3]);
    let hd = h * dxv;
    let got = SVector::<f64, 12>::from_fn(|i, _| v.d_x[i / 3][i % 3]);
    assert!(
        (got - hd).norm() <= 1e-9 * hd.norm().max(1e-300),
        "{label}: H δX"
    );
    assert!((v.phi - g.dot(&dxv)).abs() <= 1e-9 * v.phi.abs().max(1e-300));
    // Φ(z) exactly (first-order duals), differenced.
    let phi = |z: &SVector<f64, 13>| -> f64 {
        let (_, gz) = gradient(
            |zz: SVector<D13, 13>| contact_energy(&unflat(zz.as_slice(), 0), zz[12], &piece),
            z,
        );
        (0..12).map(|i| gz[i] * dx[i / 3][i % 3]).sum()
    };
    let mut z = SVector::<f64, 13>::zeros();
    for i in 0..12 {
        z[i] = x[i / 3][i % 3];
    }
    z[12] = eps0;
    let step = 1e-2 * scale(kind, x);
    for i in 0..12 {
        for hh in [step, -step, step / 2.0, -step / 2.0] {
            let mut w = z;
            w[i] += hh;
            let xw = unflat(w.as_slice(), 0);
            if stencil_distance(kind, &xw).1 != ty
                || mollified(kind, &xw).is_some() != piece.mollifier.is_some()
            {
                return false;
            }
        }
    }
    let mut want = SVector::<f64, 13>::zeros();
    for i in 0..12 {
        want[i] = fd(&phi, &z, i, step);
    }
    if piece.mollifier.is_some() {
        want[12] = fd(&phi, &z, 12, 1e-3 * eps0);
    }
    let mut have = SVector::<f64, 13>::zeros();
    have.fixed_rows_mut::<12>(0).copy_from(&got);
    have[12] = v.d_eps;
    let err = (have - want).norm() / want.norm().max(1e-300);
    assert!(
        err <= 1e-6,
        "{label}: ∂Φ/∂(X, ε) relative error {err:.2e} (d = {d:.3e})"
    );
    if piece.mollifier.is_some() {
        let e12 = (have[12] - want[12]).abs() / want[12].abs().max(1e-300);
        assert!(e12 <= 1e-6, "{label}: ∂Φ/∂ε relative error {e12:.2e}");
    }
    true
}

#[test]
fn contact_adjoint_point_triangle_matches_finite_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let mut seen = std::collections::BTreeSet::new();
    let mut n = 0;
    while n < 150 {
        let b0: f64 = rng.random_range(-0.6..1.2);
        let b1: f64 = rng.random_range(-0.6..1.2);
        let dist = rng.random_range(0.0..DHAT);
        let x = pt_config(&mut rng, [b0, b1, 1.0 - b0 - b1], dist);
        let (d, ty) = stencil_distance(PrimitiveKind::PointTriangle, &x);
        if !(d > 0.05 * DHAT * DHAT && d < 0.95 * DHAT * DHAT) {
            continue;
        }
        seen.insert(format!("{ty:?}").chars().take(9).collect::<String>());
        if check_contact(
            PrimitiveKind::PointTriangle,
            &x,
            &format!("PT #{n} {ty:?}"),
            &mut rng,
        ) {
            n += 1;
        }
    }
    assert_eq!(seen.len(), 3, "{seen:?}");
    // d → d̂².
    for k in 0..5 {
        let frac = 1.0 - 10f64.powi(-(2 + k));
        let x = pt_config(&mut rng, [0.3, 0.3, 0.4], DHAT * frac.sqrt());
        assert!(check_contact(
            PrimitiveKind::PointTriangle,
            &x,
            &format!("near d̂ {frac}"),
            &mut rng
        ));
    }
}

#[test]
fn contact_adjoint_edge_edge_matches_finite_differences_down_to_near_parallel() {
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    let mut n = 0;
    while n < 150 {
        let angle = rng.random_range(0.2..1.5);
        let (s, t, dist) = (
            rng.random_range(-0.5..1.5),
            rng.random_range(-0.5..1.5),
            rng.random_range(0.0..DHAT),
        );
        let x = ee_config(&mut rng, angle, s, t, dist);
        let (d, ty) = stencil_distance(ee_kind(&x), &x);
        if !(d > 0.05 * DHAT * DHAT && d < 0.95 * DHAT * DHAT) {
            continue;
        }
        if check_contact(ee_kind(&x), &x, &format!("EE #{n} {ty:?}"), &mut rng) {
            n += 1;
        }
    }
    // Near-parallel: the mollifier and its threshold's derivative.
    let mut mollified_checked = 0;
    for k in 0..60 {
        let angle = [2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 1e-4, 1e-5, 1e-6][k % 8];
        let (s, t) = if angle >= 1e-3 {
            (0.5, 0.4)
        } else {
            (1.02, -0.02)
        };
        let dist = rng.random_range(0.2..0.9) * DHAT;
        let x = ee_config(&mut rng, angle, s, t, dist);
        let kind = ee_kind(&x);
        assert!(mollified(kind, &x).is_some(), "angle {angle} not mollified");
        assert!(
            check_contact(kind, &x, &format!("near-parallel {angle}"), &mut rng),
            "near-parallel {angle}: FD stencil crosses a boundary"
        );
        mollified_checked += 1;
    }
    assert_eq!(mollified_checked, 60);
    // d → d̂² for crossing edges.
    for k in 0..5 {
        let frac = 1.0 - 10f64.powi(-(2 + k));
        let x = ee_config(&mut rng, 0.7, 0.4, 0.6, DHAT * frac.sqrt());
        assert!(check_contact(
            ee_kind(&x),
            &x,
            &format!("EE near d̂ {frac}"),
            &mut rng
        ));
    }
}

/// The forward pass's lagged stencil at `xp` (as `friction::lag_pair`).
fn lagged(
    kind: PrimitiveKind,
    xp: &[V3<f64>; 4],
    kappa: f64,
    mu: f64,
) -> (FrictionStencil, DistanceType, usize) {
    let (d, ty) = stencil_distance(kind, xp);
    let w = closest_weights(xp, ty);
    let v: Vector3<f64> = (0..4).map(|j| Vector3::from(xp[j]) * w[j]).sum();
    let lambda = kappa * barrier_derivative(d, DHAT * DHAT).abs() * 2.0 * d.sqrt();
    let n = v / v.norm();
    (
        FrictionStencil {
            w,
            basis: tangent_basis(&n),
            mu_lambda: mu * lambda,
        },
        ty,
        tangent_axis(&n),
    )
}

/// Checks the friction adjoint with lagged points `xp` and current points
/// `xp + slip` (a tangential move of size ~`slip`); false when the FD
/// stencil crosses a piece boundary.
fn check_friction(
    kind: PrimitiveKind,
    xp: &[V3<f64>; 4],
    slip: f64,
    label: &str,
    rng: &mut ChaCha8Rng,
) -> bool {
    let (kappa, mu, eps) = (1e4, 0.4, 1e-5);
    let (st, ty, axis) = lagged(kind, xp, kappa, mu);
    let piece = FrictionPiece {
        ty,
        axis,
        dhat2: DHAT * DHAT,
        kappa,
        mu,
        eps,
    };
    // Rigid-ish motion: every point moves by the same tangential vector plus noise.
    let tdir = st.basis
        * nalgebra::Vector2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
            .normalize();
    let x: [V3<f64>; 4] = std::array::from_fn(|k| {
        let noise = Vector3::from(rand_v(rng, 0.05 * slip));
        let moved = if k == 0 || (ty == DistanceType::LineLine && k == 1) {
            1.0
        } else {
            0.0
        };
        let p = Vector3::from(xp[k]) + tdir * (slip * moved) + noise;
        [p.x, p.y, p.z]
    });
    // Same function as the forward pass.
    let dxs: [Vector3<f64>; 4] =
        std::array::from_fn(|k| Vector3::from(x[k]) - Vector3::from(xp[k]));
    let (fwd, _, _) = st.evaluate(&dxs, eps, false);
    let val = friction_energy(&x, xp, &piece);
    assert!(
        (val - fwd).abs() <= 1e-10 * fwd.abs(),
        "{label}: {val} vs {fwd}"
    );
    let dx: [V3<f64>; 4] = std::array::from_fn(|_| rand_v(rng, 1.0));
    let v = friction_vjp(&x, xp, &dx, &piece);
    // ∂Φ/∂X equals the forward pass's (exact) friction Hessian times δX.
    let (_, g, h) = st.evaluate(&dxs, eps, true);
    let dxv = SVector::<f64, 12>::from_fn(|i, _| dx[i / 3][i % 3]);
    let hd = h * dxv;
    let got = SVector::<f64, 12>::from_fn(|i, _| v.d_x[i / 3][i % 3]);
    assert!(
        (got - hd).norm() <= 1e-8 * hd.norm().max(1e-300),
        "{label}: H δX {got} vs {hd}"
    );
    assert!((v.phi - g.dot(&dxv)).abs() <= 1e-9 * v.phi.abs().max(1e-300));
    let phi = |z: &SVector<f64, 24>| -> f64 {
        let (_, gz) = gradient(
            |zz: SVector<D24, 24>| {
                friction_energy(
                    &unflat(zz.as_slice(), 0),
                    &unflat(zz.as_slice(), 12),
                    &piece,
                )
            },
            z,
        );
        (0..12).map(|i| gz[i] * dx[i / 3][i % 3]).sum()
    };
    let mut z = SVector::<f64, 24>::zeros();
    for i in 0..12 {
        z[i] = x[i / 3][i % 3];
        z[12 + i] = xp[i / 3][i % 3];
    }
    let y = st.tangential(&dxs).norm();
    let step = 1e-2
        * scale(kind, xp)
            .min((y - eps).abs().max(1e-3 * eps))
            .min(y.max(1e-2 * eps));
    for i in 12..24 {
        for hh in [step, -step, step / 2.0, -step / 2.0] {
            let mut w = z;
            w[i] += hh;
            let pw = unflat(w.as_slice(), 12);
            if stencil_distance(kind, &pw).1 != ty || lagged(kind, &pw, kappa, mu).2 != axis {
                return false;
            }
        }
    }
    let want = SVector::<f64, 24>::from_fn(|i, _| fd(&phi, &z, i, step));
    let have = SVector::<f64, 24>::from_fn(|i, _| {
        if i < 12 {
            v.d_x[i / 3][i % 3]
        } else {
            v.d_prev[(i - 12) / 3][i % 3]
        }
    });
    let err = (have - want).norm() / want.norm().max(1e-300);
    assert!(err <= 1e-6, "{label}: ∂Φ/∂(X, Xᵗ) relative error {err:.2e}");
    let ep = (have.rows(12, 12) - want.rows(12, 12)).norm() / want.rows(12, 12).norm().max(1e-300);
    assert!(ep <= 1e-6, "{label}: ∂Φ/∂Xᵗ relative error {ep:.2e}");
    true
}

#[test]
fn friction_adjoint_matches_finite_differences_through_the_lagged_quantities() {
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let eps = 1e-5;
    // Sliding, smoothed-static, either side of ε.
    let slips = [
        10.0 * eps,
        3.0 * eps,
        0.5 * eps,
        0.1 * eps,
        0.999 * eps,
        1.001 * eps,
    ];
    let mut n = 0;
    let mut seen = std::collections::BTreeSet::new();
    while n < 120 {
        let slip = slips[n % slips.len()];
        let (kind, xp) = if n % 2 == 0 {
            let b0: f64 = rng.random_range(-0.6..1.2);
            let b1: f64 = rng.random_range(-0.6..1.2);
            let dist = rng.random_range(0.0..DHAT);
            let x = pt_config(&mut rng, [b0, b1, 1.0 - b0 - b1], dist);
            (PrimitiveKind::PointTriangle, x)
        } else {
            let (angle, s, t, dist) = (
                rng.random_range(0.2..1.5),
                rng.random_range(-0.5..1.5),
                rng.random_range(-0.5..1.5),
                rng.random_range(0.0..DHAT),
            );
            let x = ee_config(&mut rng, angle, s, t, dist);
            (ee_kind(&x), x)
        };
        let (d, ty) = stencil_distance(kind, &xp);
        if !(d > 0.05 * DHAT * DHAT && d < 0.95 * DHAT * DHAT) {
            continue;
        }
        seen.insert(format!("{ty:?}").chars().take(9).collect::<String>());
        if check_friction(
            kind,
            &xp,
            slip,
            &format!("#{n} {ty:?} slip {slip:.1e}"),
            &mut rng,
        ) {
            n += 1;
        }
    }
    assert!(seen.len() >= 4, "{seen:?}");
    // d → d̂² (λ → 0 smoothly) and near-parallel edges.
    for k in 0..5 {
        let frac = 1.0 - 10f64.powi(-(2 + k));
        let xp = pt_config(&mut rng, [0.3, 0.3, 0.4], DHAT * frac.sqrt());
        assert!(check_friction(
            PrimitiveKind::PointTriangle,
            &xp,
            2.0 * eps,
            &format!("near d̂ {frac}"),
            &mut rng
        ));
    }
    for angle in [1e-2, 1e-3] {
        let xp = ee_config(&mut rng, angle, 0.5, 0.4, 0.5 * DHAT);
        assert!(check_friction(
            ee_kind(&xp),
            &xp,
            2.0 * eps,
            &format!("near-parallel {angle}"),
            &mut rng
        ));
    }
}

#[test]
fn generic_closest_weights_equal_the_forward_ones() {
    let mut rng = ChaCha8Rng::seed_from_u64(24);
    for _ in 0..200 {
        let b0 = rng.random_range(-0.5..1.5);
        let x = pt_config(&mut rng, [b0, 0.3, 0.2], 5e-4);
        let (_, ty) = stencil_distance(PrimitiveKind::PointTriangle, &x);
        let a = closest_weights(&x, ty);
        let b = closest_weights_t(&x, ty);
        for k in 0..4 {
            assert!((a[k] - b[k]).abs() <= 1e-12, "{ty:?}: {a:?} vs {b:?}");
        }
    }
}
