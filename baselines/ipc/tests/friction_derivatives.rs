//! IPC's smoothed friction on one stencil: `f₀`/`f₁` consistency, value vs
//! gradient vs Hessian by finite differences (≤ 1e-6 relative) across the
//! static (`‖u‖ < ε`) and sliding regimes and near `‖u‖ → 0` and `‖u‖ → ε`,
//! and the tangent basis.

use nalgebra::{Matrix3x2, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sdrs_ipc::friction_stencil::{FrictionStencil, f0, f1, tangent_basis};
use sdrs_ipc::primitive::{Mat12, Vec12};

fn unflat(v: &Vec12) -> [Vector3<f64>; 4] {
    std::array::from_fn(|k| Vector3::new(v[3 * k], v[3 * k + 1], v[3 * k + 2]))
}

#[test]
fn f1_is_the_derivative_of_f0_and_both_are_c1_at_eps() {
    let eps = 1e-5;
    for k in 1..400 {
        let y = eps * k as f64 / 200.0;
        let h = 1e-6 * eps;
        let fd = (f0(y + h, eps) - f0(y - h, eps)) / (2.0 * h);
        assert!((fd - f1(y, eps)).abs() < 1e-7, "y = {y}");
    }
    assert!((f0(eps * (1.0 - 1e-12), eps) - eps).abs() < 1e-15);
    assert!((f1(eps * (1.0 - 1e-9), eps) - 1.0).abs() < 1e-8);
    assert_eq!(f1(0.0, eps), 0.0);
}

#[test]
fn tangent_basis_is_orthonormal_and_normal_to_n() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    for _ in 0..100 {
        let n = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize();
        let t: Matrix3x2<f64> = tangent_basis(&n);
        assert!((t.transpose() * t - nalgebra::Matrix2::identity()).norm() < 1e-14);
        assert!((t.transpose() * n).norm() < 1e-14);
    }
}

#[test]
fn friction_gradient_and_hessian_match_finite_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    let eps = 1e-5;
    // Sliding, static, small slip and just either side of ε. (At slip
    // ≪ 1e-2 ε, f₀ ≈ ε/3 + y²/ε: differences of the value lose their digits
    // to the constant ε/3, so value-vs-gradient needs y ≳ 1e-2 ε; the
    // gradient-vs-Hessian check is unaffected and runs at 1e-3 ε too.)
    let scales = [10.0, 3.0, 0.5, 0.1, 2e-2, 0.999, 1.001, 1e-3];
    for case in 0..140 {
        let n = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize();
        let b0: f64 = rng.random_range(0.0..1.0);
        let b1: f64 = rng.random_range(0.0..1.0 - b0);
        let st = FrictionStencil {
            w: [1.0, -(1.0 - b0 - b1), -b0, -b1],
            basis: tangent_basis(&n),
            mu_lambda: rng.random_range(0.1..10.0),
        };
        // A displacement whose tangential slip has the wanted size.
        let dir = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let target = scales[case % scales.len()] * eps;
        let mut v = Vec12::from_fn(|_, _| rng.random_range(-1.0..1.0) * 1e-3 * eps);
        v.fixed_rows_mut::<3>(0)
            .copy_from(&(dir * (target / (st.basis.transpose() * dir).norm())));
        let y = st.tangential(&unflat(&v)).norm();
        let (_, g, h) = st.evaluate(&unflat(&v), eps, true);
        let step = 1e-4 * y.min((y - eps).abs()).max(1e-3 * eps);
        let (mut gfd, mut hfd) = (Vec12::zeros(), Mat12::zeros());
        for i in 0..12 {
            let at = |s: f64| {
                let mut w = v;
                w[i] += s;
                st.evaluate(&unflat(&w), eps, true)
            };
            let (p1, p2, m1, m2) = (at(step), at(step / 2.0), at(-step), at(-step / 2.0));
            gfd[i] = (4.0 * (p2.0 - m2.0) / step - (p1.0 - m1.0) / (2.0 * step)) / 3.0;
            hfd.set_column(
                i,
                &((4.0 * (p2.1 - m2.1) / step - (p1.1 - m1.1) / (2.0 * step)) / 3.0),
            );
        }
        let eg = (g - gfd).norm() / g.norm().max(1e-300);
        let eh = (h - hfd).norm() / h.norm();
        assert!(
            eg <= 1e-6 || target < 1e-2 * eps,
            "case {case} (|u|/ε = {}): gradient error {eg:.2e}",
            y / eps
        );
        assert!(
            eh <= 1e-6,
            "case {case} (|u|/ε = {}): Hessian error {eh:.2e}",
            y / eps
        );
        assert!(
            h.symmetric_eigen().eigenvalues.min() >= -1e-9 * h.norm(),
            "not PSD"
        );
    }
}
