//! Tests of the friction potential: finite differences (gradient, Hessian, mixed) at vertex
//! and pose level, the spin-degenerate single-contact case, momentum balance, Coulomb limit,
//! zero force at zero relative velocity, typed errors.

use nalgebra::{DMatrix, DVector, Matrix3x4, Rotation3, Unit, Vector3};
use rand::RngExt;

use super::friction::*;
use super::test_util::*;
use super::*;

const S: f64 = 0.05;
const KAPPA: f64 = 10.0;

fn fparams() -> FrictionParams {
    FrictionParams {
        eps_velocity: 1e-4,
        eps_force: 1e-6,
        ..FrictionParams::new(0.4, 0.01)
    }
}

/// A step-t contact (deliberate near-contact, real contact solve) and its lagged data.
type Lagged = (
    Vec<Vector3<f64>>,
    Matrix3x4<f64>,
    Vec<Vector3<f64>>,
    Matrix3x4<f64>,
    LaggedContact,
);

fn lagged(kind: Features, seed: u64) -> Lagged {
    let cp = ContactParams::with_width(S);
    let mut r = rng(seed);
    let (la, pa, lb, pb) = configuration(kind, 0.3 * cp.support_distance(), &mut r);
    let ha = HullPose {
        pose: &pa,
        x_local: &la,
    };
    let hb = HullPose {
        pose: &pb,
        x_local: &lb,
    };
    let mut sc = ContactScratch::new();
    let PairOutcome::Separated(c) =
        contact_pair(ha, hb, &cp, None, Need::Gradient, &mut sc).unwrap()
    else {
        panic!("expected a separated pair")
    };
    let lag = LaggedContact::from_contact(&c, ha, hb, &cp, KAPPA);
    (la, pa, lb, pb, lag)
}

/// A small random rigid motion applied to a pose (step t → t+1).
fn moved(pose: &Matrix3x4<f64>, r: &mut rand_chacha::ChaCha8Rng, scale: f64) -> Matrix3x4<f64> {
    let axis = Unit::new_normalize(Vector3::new(
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
    ));
    let rot = Rotation3::from_axis_angle(&axis, scale * r.random_range(-1.0..1.0));
    let t = Vector3::new(
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
    ) * scale;
    compose(rot.matrix(), &t, pose)
}

fn vgrad(fr: &FrictionFrame<'_>, xa: &[Vector3<f64>], xb: &[Vector3<f64>]) -> DVector<f64> {
    let mut sc = FrictionScratch::new();
    let f = friction_vertices(fr, xa, xb, &fparams(), &mut sc).unwrap();
    flatten(&[f.grad_a, f.grad_b].concat())
}

fn col(v: &DVector<f64>) -> DMatrix<f64> {
    DMatrix::from_column_slice(v.len(), 1, v.as_slice())
}

/// FD of gradient, Hessian and mixed derivative w.r.t. world vertices at one configuration.
fn fd_vertices(
    fr: &FrictionFrame<'_>,
    xa: &[Vector3<f64>],
    xb: &[Vector3<f64>],
    check_mixed: bool,
) -> (f64, f64, f64) {
    let na = xa.len();
    let x0 = flatten(&[xa.to_vec(), xb.to_vec()].concat());
    let split = |x: &DVector<f64>| {
        let all = unflatten(x);
        (all[..na].to_vec(), all[na..].to_vec())
    };
    let mut sc = FrictionScratch::new();
    let f = friction_vertices(fr, xa, xb, &fparams(), &mut sc).unwrap();
    let h = 1e-8;
    let g = flatten(&[f.grad_a.clone(), f.grad_b.clone()].concat());
    let g_fd = fd_gradient(
        &mut |x| {
            let (a, b) = split(x);
            friction_vertices(fr, &a, &b, &fparams(), &mut sc)
                .unwrap()
                .value
        },
        &x0,
        h,
    );
    let eg = rel_err(&col(&g), &col(&g_fd), 1e-300);
    let hd = f.dense_hessian();
    let h_fd = fd_jacobian(
        &mut |x| {
            let (a, b) = split(x);
            vgrad(fr, &a, &b)
        },
        &x0,
        h,
    );
    let eh = rel_err(&hd, &h_fd, 1e-300);
    assert!((&hd - hd.transpose()).norm() <= 1e-10 * hd.norm());
    let mut em = 0.0;
    if check_mixed {
        let md = f.dense_mixed();
        // Perturb X^t (lagged normal, basis and forces fixed).
        let xp0 = flatten(&[fr.x_prev_a.to_vec(), fr.x_prev_b.to_vec()].concat());
        let m_fd = fd_jacobian(
            &mut |xp| {
                let all = unflatten(xp);
                let frame = FrictionFrame {
                    x_prev_a: &all[..na],
                    x_prev_b: &all[na..],
                    ..*fr
                };
                vgrad(&frame, xa, xb)
            },
            &xp0,
            h,
        );
        em = rel_err(&md, &m_fd, 1e-300);
    }
    (eg, eh, em)
}

#[test]
fn friction_vertex_derivatives_match_fd() {
    let mut worst = (0.0f64, 0.0f64, 0.0f64);
    for (i, kind) in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace]
        .into_iter()
        .enumerate()
    {
        let (la, pa, lb, pb, lag) = lagged(kind, 30 + i as u64);
        let mut r = rng(40 + i as u64);
        for motion in [1e-3, 1e-2] {
            let xa = world(&moved(&pa, &mut r, motion), &la);
            let xb = world(&moved(&pb, &mut r, motion), &lb);
            let (eg, eh, em) = fd_vertices(&lag.frame(), &xa, &xb, true);
            assert!(
                eg <= 1e-5 && eh <= 1e-5 && em <= 1e-5,
                "{kind:?} motion {motion}: grad {eg:e} hess {eh:e} mixed {em:e}"
            );
            worst = (worst.0.max(eg), worst.1.max(eh), worst.2.max(em));
        }
    }
    report("friction vertex grad", worst.0);
    report("friction vertex hess", worst.1);
    report("friction vertex mixed", worst.2);
}

#[test]
fn friction_pose_derivatives_match_fd() {
    let mut worst = (0.0f64, 0.0f64, 0.0f64);
    for (i, kind) in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace]
        .into_iter()
        .enumerate()
    {
        let (la, pa, lb, pb, lag) = lagged(kind, 50 + i as u64);
        let mut r = rng(60 + i as u64);
        let pa1 = moved(&pa, &mut r, 5e-3);
        let pb1 = moved(&pb, &mut r, 5e-3);
        let eval = |a1: &Matrix3x4<f64>, b1: &Matrix3x4<f64>, frame: &FrictionFrame<'_>, need| {
            let mut sc = FrictionScratch::new();
            friction_pair(
                frame,
                HullPose {
                    pose: a1,
                    x_local: &la,
                },
                HullPose {
                    pose: b1,
                    x_local: &lb,
                },
                &fparams(),
                need,
                &mut sc,
            )
            .unwrap()
        };
        let fr = lag.frame();
        let out = eval(&pa1, &pb1, &fr, FrictionNeed::HessianAndMixed);
        let p0 = pose_params(&pa1, &pb1);
        let h = 1e-8;
        let g = pose_params(&out.grad_a, &out.grad_b);
        let g_fd = fd_gradient(
            &mut |p| {
                let (a, b) = poses_from_params(p);
                eval(&a, &b, &fr, FrictionNeed::Value).value
            },
            &p0,
            h,
        );
        let hm = DMatrix::from_iterator(24, 24, out.hessian.unwrap().iter().copied());
        let h_fd = fd_jacobian(
            &mut |p| {
                let (a, b) = poses_from_params(p);
                let o = eval(&a, &b, &fr, FrictionNeed::Gradient);
                pose_params(&o.grad_a, &o.grad_b)
            },
            &p0,
            h,
        );
        // Mixed: perturb A^t, recompute X^t = A^t x̃ with forces, normal and basis fixed.
        let mm = DMatrix::from_iterator(24, 24, out.mixed.unwrap().iter().copied());
        let pt0 = pose_params(&pa, &pb);
        let m_fd = fd_jacobian(
            &mut |p| {
                let (a0, b0) = poses_from_params(p);
                let (xa0, xb0) = (world(&a0, &la), world(&b0, &lb));
                let frame = FrictionFrame {
                    x_prev_a: &xa0,
                    x_prev_b: &xb0,
                    ..fr
                };
                let o = eval(&pa1, &pb1, &frame, FrictionNeed::Gradient);
                pose_params(&o.grad_a, &o.grad_b)
            },
            &pt0,
            h,
        );
        let eg = rel_err(&col(&g), &col(&g_fd), 1e-300);
        let eh = rel_err(&hm, &h_fd, 1e-300);
        let em = rel_err(&mm, &m_fd, 1e-300);
        assert!(
            eg <= 1e-5 && eh <= 1e-5 && em <= 1e-5,
            "{kind:?}: grad {eg:e} hess {eh:e} mixed {em:e}"
        );
        assert!(!out.spin_free);
        worst = (worst.0.max(eg), worst.1.max(eh), worst.2.max(em));
    }
    report("friction pose grad", worst.0);
    report("friction pose hess", worst.1);
    report("friction pose mixed", worst.2);
}

/// Two tetrahedra tip to tip: the only vertices with normal force are the two tips, on one
/// line along the normal, so U* is flat in ω.
type TipToTip = (Vec<Vector3<f64>>, Vec<Vector3<f64>>, Vec<f64>, Vec<f64>);

fn tip_to_tip() -> TipToTip {
    let xa = vec![
        Vector3::new(0.1, 0.2, 0.0),
        Vector3::new(0.5, 0.2, -0.5),
        Vector3::new(-0.2, 0.6, -0.5),
        Vector3::new(-0.2, -0.2, -0.5),
    ];
    let xb = vec![
        Vector3::new(0.1, 0.2, 0.02),
        Vector3::new(0.5, 0.3, 0.5),
        Vector3::new(-0.2, 0.5, 0.5),
        Vector3::new(-0.3, -0.2, 0.5),
    ];
    (xa, xb, vec![3.0, 0.0, 0.0, 0.0], vec![2.5, 0.0, 0.0, 0.0])
}

#[test]
fn friction_single_contact_point_is_spin_free_and_matches_fd() {
    let (xa, xb, fa, fb) = tip_to_tip();
    let n = Vector3::z();
    let frame = FrictionFrame {
        normal: n,
        basis: tangent_basis(&n),
        x_prev_a: &xa,
        x_prev_b: &xb,
        normal_force_a: &fa,
        normal_force_b: &fb,
    };
    let mut r = rng(70);
    let mut worst = (0.0f64, 0.0f64);
    for _ in 0..3 {
        let xa1: Vec<_> = xa
            .iter()
            .map(|x| {
                x + Vector3::new(
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                ) * 2e-3
            })
            .collect();
        let xb1: Vec<_> = xb
            .iter()
            .map(|x| {
                x + Vector3::new(
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                ) * 2e-3
            })
            .collect();
        let mut sc = FrictionScratch::new();
        let f = friction_vertices(&frame, &xa1, &xb1, &fparams(), &mut sc).unwrap();
        assert!(f.spin_free && f.omega == 0.0);
        assert!(
            f.value.is_finite()
                && f.grad_a
                    .iter()
                    .chain(&f.grad_b)
                    .all(|g| g.iter().all(|v| v.is_finite()))
        );
        let (eg, eh, _) = fd_vertices(&frame, &xa1, &xb1, false);
        assert!(
            eg <= 1e-5 && eh <= 1e-5,
            "tip-to-tip: grad {eg:e} hess {eh:e}"
        );
        // The mixed derivative of the ω = 0 branch is finite (U_f is discontinuous in X^t at
        // this configuration, so it is not FD-checkable; see the module docs).
        assert!(f.dense_mixed().iter().all(|v| v.is_finite()));
        worst = (worst.0.max(eg), worst.1.max(eh));
        // Pose level: also finite and spin-free.
        let ident = Matrix3x4::identity();
        let out = friction_pair(
            &frame,
            HullPose {
                pose: &ident,
                x_local: &xa1,
            },
            HullPose {
                pose: &ident,
                x_local: &xb1,
            },
            &fparams(),
            FrictionNeed::HessianAndMixed,
            &mut sc,
        )
        .unwrap();
        assert!(out.spin_free && out.mixed.unwrap().iter().all(|v| v.is_finite()));
    }
    report("friction tip-to-tip grad", worst.0);
    report("friction tip-to-tip hess", worst.1);

    // Only one vertex in total carries force: the plane follows it, U_f = μΔt A_ε(f) √ε_v is
    // constant and every derivative (including the mixed one, FD-checked) vanishes.
    let fb0 = vec![0.0; 4];
    let frame1 = FrictionFrame {
        normal_force_b: &fb0,
        ..frame
    };
    let xa1: Vec<_> = xa
        .iter()
        .map(|x| x + Vector3::new(1e-3, -2e-3, 5e-4))
        .collect();
    let mut sc = FrictionScratch::new();
    let f = friction_vertices(&frame1, &xa1, &xb, &fparams(), &mut sc).unwrap();
    let p = fparams();
    let expect = p.mu * p.dt * p.smoothed_force(3.0) * p.eps_velocity.sqrt();
    assert!(
        (f.value - expect).abs() <= 1e-12 * expect,
        "{} vs {expect}",
        f.value
    );
    let gnorm: f64 = f.grad_a.iter().chain(&f.grad_b).map(|g| g.norm()).sum();
    assert!(gnorm <= 1e-12, "{gnorm}");
    let (_, _, em) = fd_vertices(&frame1, &xa1, &xb, true);
    assert!(f.dense_mixed().norm() <= 1e-9 && em.is_finite());
}

#[test]
fn friction_forces_and_in_plane_torque_balance() {
    let mut worst = 0.0f64;
    for (i, kind) in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace]
        .into_iter()
        .enumerate()
    {
        let (la, pa, lb, pb, lag) = lagged(kind, 80 + i as u64);
        let mut r = rng(90 + i as u64);
        for motion in [1e-4, 1e-3, 2e-2] {
            let xa = world(&moved(&pa, &mut r, motion), &la);
            let xb = world(&moved(&pb, &mut r, motion), &lb);
            let mut sc = FrictionScratch::new();
            let f = friction_vertices(&lag.frame(), &xa, &xb, &fparams(), &mut sc).unwrap();
            let (mut sum, mut tau, mut fs, mut ts) = (Vector3::zeros(), 0.0, 0.0, 0.0);
            for (x, g) in lag
                .x_prev_a
                .iter()
                .zip(&f.grad_a)
                .chain(lag.x_prev_b.iter().zip(&f.grad_b))
            {
                let force = -g;
                sum += force;
                tau += lag.normal.dot(&x.cross(&force));
                fs += force.norm();
                ts += x.norm() * force.norm();
            }
            let ef = sum.norm() / fs;
            let et = tau.abs() / ts;
            assert!(
                ef <= 1e-9 && et <= 1e-9,
                "{kind:?} motion {motion}: force {ef:e} torque {et:e}"
            );
            // Friction forces are tangential.
            assert!(
                f.grad_a
                    .iter()
                    .chain(&f.grad_b)
                    .all(|g| g.dot(&lag.normal).abs() <= 1e-12 * fs)
            );
            worst = worst.max(ef).max(et);
        }
    }
    report("friction momentum balance", worst);
}

#[test]
fn friction_sliding_hull_feels_coulomb_force() {
    // Box b slides over box a at 1 m/s ≫ √ε_v = 1e-2 m/s: the friction force on b is
    // ≈ μ Σ_b ‖f_⊥‖ opposite to the motion (and a feels the reaction).
    let (la, pa, lb, pb, lag) = lagged(Features::FaceFace, 100);
    let p = fparams();
    let speed = 1.0;
    let dir = lag.basis.column(0).into_owned();
    let mut pb1 = pb;
    pb1.set_column(3, &(pb.column(3) + dir * speed * p.dt));
    let mut sc = FrictionScratch::new();
    let out = friction_pair(
        &lag.frame(),
        HullPose {
            pose: &pa,
            x_local: &la,
        },
        HullPose {
            pose: &pb1,
            x_local: &lb,
        },
        &p,
        FrictionNeed::Gradient,
        &mut sc,
    )
    .unwrap();
    // Net force on a rigid hull = −(translation column of ∂U/∂A).
    let force_b = -out.grad_b.column(3).into_owned();
    let force_a = -out.grad_a.column(3).into_owned();
    let normal_b: f64 = lag.normal_force_b.iter().sum();
    let normal_a: f64 = lag.normal_force_a.iter().sum();
    assert!(
        normal_b > 100.0 * p.eps_force.sqrt(),
        "forces too small for the Coulomb limit: {normal_b}"
    );
    assert!(((normal_a - normal_b) / normal_b).abs() < 1e-9);
    let expect = p.mu * normal_b;
    let rel = (force_b.norm() - expect).abs() / expect;
    assert!(
        rel < 1e-3,
        "|f| = {} vs μΣ‖f⊥‖ = {expect} (rel {rel:e})",
        force_b.norm()
    );
    assert!(
        force_b.normalize().dot(&dir) < -0.9999,
        "not opposing the motion: {force_b:?}"
    );
    assert!((force_a + force_b).norm() <= 1e-9 * expect);
    report("friction Coulomb limit rel err", rel);
}

#[test]
fn friction_vanishes_at_zero_relative_velocity() {
    let (la, pa, lb, pb, lag) = lagged(Features::VertexFace, 110);
    let mut sc = FrictionScratch::new();
    let p = fparams();
    // Both at rest.
    let rest = friction_pair(
        &lag.frame(),
        HullPose {
            pose: &pa,
            x_local: &la,
        },
        HullPose {
            pose: &pb,
            x_local: &lb,
        },
        &p,
        FrictionNeed::Hessian,
        &mut sc,
    )
    .unwrap();
    assert_eq!(rest.grad_a, Matrix3x4::zeros());
    assert_eq!(rest.grad_b, Matrix3x4::zeros());
    assert!(rest.hessian.unwrap().iter().all(|v| v.is_finite()));
    // Both translating together in the plane: the plane moves along, no force.
    let v = lag.basis * nalgebra::Vector2::new(0.3, -0.7);
    let (mut pa1, mut pb1) = (pa, pb);
    pa1.set_column(3, &(pa.column(3) + v * p.dt));
    pb1.set_column(3, &(pb.column(3) + v * p.dt));
    let out = friction_pair(
        &lag.frame(),
        HullPose {
            pose: &pa1,
            x_local: &la,
        },
        HullPose {
            pose: &pb1,
            x_local: &lb,
        },
        &p,
        FrictionNeed::Gradient,
        &mut sc,
    )
    .unwrap();
    let scale: f64 =
        p.mu * (lag.normal_force_a.iter().sum::<f64>() + lag.normal_force_b.iter().sum::<f64>());
    assert!(
        out.grad_a.norm() + out.grad_b.norm() <= 1e-9 * scale,
        "{} {}",
        out.grad_a.norm(),
        out.grad_b.norm()
    );
    assert!((out.u - nalgebra::Vector2::new(0.3, -0.7)).norm() <= 1e-9);
}

#[test]
fn friction_rejects_bad_input_with_typed_errors() {
    let (xa, xb, fa, fb) = tip_to_tip();
    let n = Vector3::z();
    let frame = FrictionFrame {
        normal: n,
        basis: tangent_basis(&n),
        x_prev_a: &xa,
        x_prev_b: &xb,
        normal_force_a: &fa,
        normal_force_b: &fb,
    };
    let mut sc = FrictionScratch::new();
    for p in [
        FrictionParams {
            dt: 0.0,
            ..fparams()
        },
        FrictionParams {
            mu: -1.0,
            ..fparams()
        },
        FrictionParams {
            eps_velocity: 0.0,
            ..fparams()
        },
        FrictionParams {
            eps_force: f64::NAN,
            ..fparams()
        },
    ] {
        assert!(matches!(
            friction_vertices(&frame, &xa, &xb, &p, &mut sc),
            Err(FrictionError::InvalidParams { .. })
        ));
    }
    let bad_n = FrictionFrame {
        normal: Vector3::new(0.0, 0.0, 2.0),
        ..frame
    };
    assert!(matches!(
        friction_vertices(&bad_n, &xa, &xb, &fparams(), &mut sc),
        Err(FrictionError::InvalidFrame { .. })
    ));
    assert!(matches!(
        friction_vertices(&frame, &xa[..3], &xb, &fparams(), &mut sc),
        Err(FrictionError::LengthMismatch {
            hull: Hull::A,
            expected: 4,
            got: 3,
            ..
        })
    ));
    let short = [1.0];
    let bad_f = FrictionFrame {
        normal_force_b: &short,
        ..frame
    };
    assert!(matches!(
        friction_vertices(&bad_f, &xa, &xb, &fparams(), &mut sc),
        Err(FrictionError::LengthMismatch { hull: Hull::B, .. })
    ));
    let mut xnan = xb.clone();
    xnan[2].x = f64::NAN;
    assert_eq!(
        friction_vertices(&frame, &xa, &xnan, &fparams(), &mut sc),
        Err(FrictionError::NonFiniteVertex {
            hull: Hull::B,
            index: 2
        })
    );
    let p = FrictionParams {
        inner_max_iters: 1,
        inner_tol: 0.0,
        inner_rtol: 0.0,
        ..fparams()
    };
    let (la, pa, lb, pb, lag) = lagged(Features::FaceFace, 120);
    let mut rr = rng(121);
    let pb1 = moved(&pb, &mut rr, 1e-2);
    match friction_pair(
        &lag.frame(),
        HullPose {
            pose: &pa,
            x_local: &la,
        },
        HullPose {
            pose: &pb1,
            x_local: &lb,
        },
        &p,
        FrictionNeed::Value,
        &mut sc,
    ) {
        Err(FrictionError::NotConverged {
            iterations: 1,
            grad_norm,
            ..
        }) => assert!(grad_norm.is_finite()),
        other => panic!("{other:?}"),
    }
    // No normal force at all: U_f ≡ 0.
    let zeros = [0.0; 4];
    let free = FrictionFrame {
        normal_force_a: &zeros,
        normal_force_b: &zeros,
        ..frame
    };
    let f = friction_vertices(&free, &xa, &xb, &fparams(), &mut sc).unwrap();
    assert_eq!(f.value, 0.0);
    assert!(f.dense_hessian().iter().all(|v| *v == 0.0));
}

#[test]
fn friction_tangent_basis_is_orthonormal() {
    let mut r = rng(130);
    for _ in 0..100 {
        let n = random_rotation(&mut r) * Vector3::z();
        let b = tangent_basis(&n);
        assert!((b.transpose() * b - nalgebra::Matrix2::identity()).norm() < 1e-14);
        assert!((b.transpose() * n).norm() < 1e-14);
        assert!((b.column(0).cross(&b.column(1)) - n).norm() < 1e-14);
    }
    for n in [Vector3::x(), Vector3::y(), Vector3::z(), -Vector3::z()] {
        let b = tangent_basis(&n);
        assert!((b.transpose() * n).norm() < 1e-15);
    }
}

#[test]
fn friction_solver_is_robust_on_random_frames() {
    // Random frames (random normal, positions, forces over six decades, many zero), random
    // step-(t+1) displacements from 1e-7 to 3 with Δt = 1e-3 (relative speeds up to 3e3 m/s
    // against the 1e-3 m/s smoothing): never an error, never NaN, forces balance.
    let mut r = rng(140);
    let mut max_iters = 0;
    for trial in 0..300 {
        let n = random_rotation(&mut r) * Vector3::z();
        let na = r.random_range(1..12);
        let nb = r.random_range(1..12);
        let pts = |r: &mut rand_chacha::ChaCha8Rng, k: usize| -> Vec<Vector3<f64>> {
            (0..k)
                .map(|_| {
                    Vector3::new(
                        r.random_range(-1.0..1.0),
                        r.random_range(-1.0..1.0),
                        r.random_range(-1.0..1.0),
                    )
                })
                .collect()
        };
        let xa = pts(&mut r, na);
        let xb = pts(&mut r, nb);
        let forces = |r: &mut rand_chacha::ChaCha8Rng, k: usize| -> Vec<f64> {
            (0..k)
                .map(|_| {
                    if r.random_range(0.0..1.0) < 0.4 {
                        0.0
                    } else {
                        10f64.powf(r.random_range(-3.0..3.0))
                    }
                })
                .collect()
        };
        let fa = forces(&mut r, na);
        let fb = forces(&mut r, nb);
        let frame = FrictionFrame {
            normal: n,
            basis: tangent_basis(&n),
            x_prev_a: &xa,
            x_prev_b: &xb,
            normal_force_a: &fa,
            normal_force_b: &fb,
        };
        let scale = 10f64.powf(r.random_range(-7.0..0.5));
        let mut step = |x: &Vec<Vector3<f64>>| -> Vec<Vector3<f64>> {
            x.iter()
                .map(|v| {
                    v + Vector3::new(
                        r.random_range(-1.0..1.0),
                        r.random_range(-1.0..1.0),
                        r.random_range(-1.0..1.0),
                    ) * scale
                })
                .collect()
        };
        let xa1 = step(&xa);
        let xb1 = step(&xb);
        let p = FrictionParams::new(0.7, 1e-3);
        let mut sc = FrictionScratch::new();
        let f = friction_vertices(&frame, &xa1, &xb1, &p, &mut sc)
            .unwrap_or_else(|e| panic!("trial {trial}: {e}"));
        assert!(f.value.is_finite() && f.value >= 0.0);
        assert!(
            f.dense_hessian().iter().all(|v| v.is_finite())
                && f.dense_mixed().iter().all(|v| v.is_finite()),
            "trial {trial}"
        );
        let sum: Vector3<f64> = f.grad_a.iter().chain(&f.grad_b).sum();
        let mag: f64 = f.grad_a.iter().chain(&f.grad_b).map(|g| g.norm()).sum();
        // Rounding floor: r = ẋ − u − ωg is formed from velocities up to |ẋ| and divided by
        // φ ≥ √ε_v, so each force carries an error ≈ ε_mach (w/Δt) |ẋ|/√ε_v.
        let floor: f64 = xa
            .iter()
            .zip(&xa1)
            .zip(&fa)
            .chain(xb.iter().zip(&xb1).zip(&fb))
            .map(|((x0, x1), f)| {
                p.mu * p.smoothed_force(*f)
                    * (1.0 + (x1 - x0).norm() / p.dt / p.eps_velocity.sqrt())
            })
            .sum::<f64>()
            * 1e3
            * f64::EPSILON;
        assert!(
            sum.norm() <= 1e-8 * mag + floor,
            "trial {trial}: {:e} (floor {floor:e})",
            sum.norm() / mag
        );
        max_iters = max_iters.max(f.iterations);
    }
    report(
        "friction robustness max Newton iterations",
        max_iters as f64,
    );
}

/// `friction_pair_memo` returns the bits of `friction_pair` for every `need` and every order of
/// calls: after a solve at other poses (a miss), at the same poses (a hit, whatever `need` the
/// first call asked for), after a change of the parameters, and after `clear`.
#[test]
fn friction_memo_has_the_bits_of_a_fresh_solve() {
    let needs = [
        FrictionNeed::Value,
        FrictionNeed::Gradient,
        FrictionNeed::Hessian,
        FrictionNeed::HessianAndMixed,
    ];
    let bits = |p: &FrictionPair| {
        let mut v = vec![p.value, p.u.x, p.u.y, p.omega];
        v.extend(p.grad_a.iter().chain(p.grad_b.iter()));
        v.extend(p.hessian.iter().flat_map(|h| h.iter().copied()));
        v.extend(p.mixed.iter().flat_map(|h| h.iter().copied()));
        let mut b: Vec<u64> = v.iter().map(|x| x.to_bits()).collect();
        b.extend([p.iterations as u64, u64::from(p.spin_free)]);
        b
    };
    for (i, kind) in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace]
        .into_iter()
        .enumerate()
    {
        let (la, pa, lb, pb, lag) = lagged(kind, 70 + i as u64);
        let fr = lag.frame();
        let mut r = rng(80 + i as u64);
        let mut memo = FrictionMemo::default();
        let mut params = fparams();
        for round in 0..6 {
            // Two rounds at each pose pair, the parameters changed once, a clear once.
            let (pa1, pb1) = (moved(&pa, &mut r, 5e-3), moved(&pb, &mut r, 5e-3));
            if round == 3 {
                params.mu *= 1.5;
            }
            if round == 4 {
                memo.clear();
            }
            for (k, need) in needs.iter().chain(needs.iter().rev()).enumerate() {
                let ha = HullPose {
                    pose: &pa1,
                    x_local: &la,
                };
                let hb = HullPose {
                    pose: &pb1,
                    x_local: &lb,
                };
                let mut sc = FrictionScratch::new();
                let want = friction_pair(&fr, ha, hb, &params, *need, &mut sc).unwrap();
                let got = friction_pair_memo(&fr, ha, hb, &params, *need, &mut memo).unwrap();
                assert_eq!(bits(&got), bits(&want), "{kind:?} round {round} call {k}");
            }
        }
    }
}
