//! Tests of the contact potential: finite differences at deliberate near-contacts, support,
//! growth, momentum balance, invariance, warm starts, intersection detection, errors.

use nalgebra::{DMatrix, DVector, Matrix3x4, Vector3, Vector4};

use super::test_util::*;
use super::*;

const S: f64 = 0.05;

fn params() -> ContactParams {
    ContactParams::with_width(S)
}

fn eval_vertices(
    xa: &[Vector3<f64>],
    xb: &[Vector3<f64>],
    sc: &mut ContactScratch,
) -> VertexOutcome {
    contact_vertices(xa, xb, &params(), None, sc).expect("contact solve")
}

fn vertex_value(xa: &[Vector3<f64>], xb: &[Vector3<f64>], sc: &mut ContactScratch) -> f64 {
    eval_vertices(xa, xb, sc).value()
}

fn vertex_grad(xa: &[Vector3<f64>], xb: &[Vector3<f64>], sc: &mut ContactScratch) -> DVector<f64> {
    match eval_vertices(xa, xb, sc) {
        VertexOutcome::Separated(c) => {
            let mut all = c.grad_a.clone();
            all.extend_from_slice(&c.grad_b);
            flatten(&all)
        }
        VertexOutcome::OutOfRange { .. } => DVector::zeros(3 * (xa.len() + xb.len())),
        VertexOutcome::Intersecting => panic!("unexpected intersection"),
    }
}

fn pose_eval(
    la: &[Vector3<f64>],
    pa: &Matrix3x4<f64>,
    lb: &[Vector3<f64>],
    pb: &Matrix3x4<f64>,
    need: Need,
) -> PairOutcome {
    pose_eval_warm(la, pa, lb, pb, need, None)
}

/// [`pose_eval`] from a warm plane.
fn pose_eval_warm(
    la: &[Vector3<f64>],
    pa: &Matrix3x4<f64>,
    lb: &[Vector3<f64>],
    pb: &Matrix3x4<f64>,
    need: Need,
    warm: Option<Vector4<f64>>,
) -> PairOutcome {
    let mut sc = ContactScratch::new();
    contact_pair(
        HullPose {
            pose: pa,
            x_local: la,
        },
        HullPose {
            pose: pb,
            x_local: lb,
        },
        &params(),
        warm,
        need,
        &mut sc,
    )
    .expect("contact solve")
}

/// (value, gradient[24], Hessian 24×24) with zeros out of range.
fn pose_all(
    la: &[Vector3<f64>],
    pa: &Matrix3x4<f64>,
    lb: &[Vector3<f64>],
    pb: &Matrix3x4<f64>,
) -> (f64, DVector<f64>, DMatrix<f64>) {
    match pose_eval(la, pa, lb, pb, Need::Hessian) {
        PairOutcome::Separated(c) => {
            let g = pose_params(&c.grad_a, &c.grad_b);
            let h = c.hessian.unwrap();
            (
                c.value,
                g,
                DMatrix::from_iterator(24, 24, h.iter().copied()),
            )
        }
        PairOutcome::OutOfRange { .. } => (0.0, DVector::zeros(24), DMatrix::zeros(24, 24)),
        PairOutcome::Intersecting => panic!("unexpected intersection"),
    }
}

/// Gap fractions of the support distance used by the FD tests: well inside down to just
/// inside the support edge, and just outside it.
const FRACTIONS: [f64; 5] = [0.05, 0.3, 0.7, 0.99, 1.01];

fn fd_check_vertices(kind: Features, seed: u64) -> (f64, f64) {
    let thr = params().support_distance();
    let mut rng = rng(seed);
    let mut worst = (0.0f64, 0.0f64);
    let mut sc = ContactScratch::new();
    for &frac in &FRACTIONS {
        let (la, pa, lb, pb) = configuration(kind, frac * thr, &mut rng);
        let xa = world(&pa, &la);
        let xb = world(&pb, &lb);
        let na = xa.len();
        let x0 = flatten(&[xa.clone(), xb.clone()].concat());
        let split = |x: &DVector<f64>| {
            let all = unflatten(x);
            (all[..na].to_vec(), all[na..].to_vec())
        };
        let h = 1e-7;
        let out = eval_vertices(&xa, &xb, &mut sc);
        if frac > 1.0 {
            assert!(
                matches!(out, VertexOutcome::OutOfRange { .. }),
                "{kind:?} at {frac}: {out:?}"
            );
            let g_fd = fd_gradient(
                &mut |x| {
                    let (a, b) = split(x);
                    vertex_value(&a, &b, &mut sc)
                },
                &x0,
                h,
            );
            assert_eq!(g_fd.norm(), 0.0);
            continue;
        }
        let VertexOutcome::Separated(c) = out else {
            panic!("{kind:?} at {frac}: {out:?}")
        };
        let g = vertex_grad(&xa, &xb, &mut sc);
        let g_fd = fd_gradient(
            &mut |x| {
                let (a, b) = split(x);
                vertex_value(&a, &b, &mut sc)
            },
            &x0,
            h,
        );
        let eg = rel_err(
            &DMatrix::from_column_slice(g.len(), 1, g.as_slice()),
            &DMatrix::from_column_slice(g.len(), 1, g_fd.as_slice()),
            1e-300,
        );
        let hd = c.dense_hessian(&xa, &xb);
        let h_fd = fd_jacobian(
            &mut |x| {
                let (a, b) = split(x);
                vertex_grad(&a, &b, &mut sc)
            },
            &x0,
            h,
        );
        let eh = rel_err(&hd, &h_fd, 1e-300);
        assert!(eg <= 1e-5, "{kind:?} frac {frac}: gradient rel err {eg:e}");
        assert!(eh <= 1e-5, "{kind:?} frac {frac}: Hessian rel err {eh:e}");
        assert!((&hd - hd.transpose()).norm() <= 1e-12 * hd.norm());
        worst = (worst.0.max(eg), worst.1.max(eh));
    }
    worst
}

fn fd_check_poses(kind: Features, seed: u64) -> (f64, f64) {
    let thr = params().support_distance();
    let mut rng = rng(seed);
    let mut worst = (0.0f64, 0.0f64);
    for &frac in &FRACTIONS {
        let (la, pa, lb, pb) = configuration(kind, frac * thr, &mut rng);
        let p0 = pose_params(&pa, &pb);
        let h = 1e-7;
        let value = |p: &DVector<f64>| {
            let (a, b) = poses_from_params(p);
            pose_eval(&la, &a, &lb, &b, Need::Value).value()
        };
        let grad = |p: &DVector<f64>| {
            let (a, b) = poses_from_params(p);
            pose_all(&la, &a, &lb, &b).1
        };
        let (v, g, hm) = pose_all(&la, &pa, &lb, &pb);
        let g_fd = fd_gradient(&mut |p| value(p), &p0, h);
        let h_fd = fd_jacobian(&mut |p| grad(p), &p0, h);
        if frac > 1.0 {
            assert_eq!(
                (v, g.norm(), hm.norm(), g_fd.norm(), h_fd.norm()),
                (0.0, 0.0, 0.0, 0.0, 0.0)
            );
            continue;
        }
        let eg = (&g - &g_fd).norm() / g.norm();
        let eh = rel_err(&hm, &h_fd, 1e-300);
        assert!(
            eg <= 1e-5,
            "{kind:?} frac {frac}: pose gradient rel err {eg:e}"
        );
        assert!(
            eh <= 1e-5,
            "{kind:?} frac {frac}: pose Hessian rel err {eh:e}"
        );
        worst = (worst.0.max(eg), worst.1.max(eh));
    }
    worst
}

#[test]
fn contact_vertex_derivatives_match_fd_face_face() {
    let (eg, eh) = fd_check_vertices(Features::FaceFace, 1);
    report("contact vertex grad face-face", eg);
    report("contact vertex hess face-face", eh);
}

#[test]
fn contact_vertex_derivatives_match_fd_edge_edge() {
    let (eg, eh) = fd_check_vertices(Features::EdgeEdge, 2);
    report("contact vertex grad edge-edge", eg);
    report("contact vertex hess edge-edge", eh);
}

#[test]
fn contact_vertex_derivatives_match_fd_vertex_face() {
    let (eg, eh) = fd_check_vertices(Features::VertexFace, 3);
    report("contact vertex grad vertex-face", eg);
    report("contact vertex hess vertex-face", eh);
}

#[test]
fn contact_pose_derivatives_match_fd_face_face() {
    let (eg, eh) = fd_check_poses(Features::FaceFace, 11);
    report("contact pose grad face-face", eg);
    report("contact pose hess face-face", eh);
}

#[test]
fn contact_pose_derivatives_match_fd_edge_edge() {
    let (eg, eh) = fd_check_poses(Features::EdgeEdge, 12);
    report("contact pose grad edge-edge", eg);
    report("contact pose hess edge-edge", eh);
}

#[test]
fn contact_pose_derivatives_match_fd_vertex_face() {
    let (eg, eh) = fd_check_poses(Features::VertexFace, 13);
    report("contact pose grad vertex-face", eg);
    report("contact pose hess vertex-face", eh);
}

#[test]
fn contact_pose_derivatives_match_fd_random_sphere_hulls() {
    // Random polytopes (points on spheres) at random gaps, random orientations.
    let mut rng = rng(21);
    let thr = params().support_distance();
    let mut worst = (0.0f64, 0.0f64);
    for _ in 0..4 {
        let la = sphere_points(&mut rng, 12, 0.5);
        let lb = sphere_points(&mut rng, 9, 0.4);
        let ra = random_rotation(&mut rng);
        let rb = random_rotation(&mut rng);
        let pa = test_util::pose(ra.matrix(), &Vector3::zeros());
        let mut pb = test_util::pose(rb.matrix(), &Vector3::new(1.0, 0.2, -0.3));
        // Place b at the requested gap along its offset direction by bisection on the distance.
        let dir = pb.column(3).normalize();
        let target = rand::RngExt::random_range(&mut rng, 0.1..0.9) * thr;
        let (mut lo, mut hi) = (0.0, 3.0);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            pb.set_column(3, &(dir * mid));
            match pose_eval(&la, &pa, &lb, &pb, Need::Value) {
                PairOutcome::Separated(c) if c.distance < target => lo = mid,
                PairOutcome::Intersecting => lo = mid,
                _ => hi = mid,
            }
        }
        pb.set_column(3, &(dir * hi));
        let p0 = pose_params(&pa, &pb);
        let (_, g, hm) = pose_all(&la, &pa, &lb, &pb);
        let g_fd = fd_gradient(
            &mut |p| {
                let (a, b) = poses_from_params(p);
                pose_eval(&la, &a, &lb, &b, Need::Value).value()
            },
            &p0,
            1e-7,
        );
        let h_fd = fd_jacobian(
            &mut |p| {
                let (a, b) = poses_from_params(p);
                pose_all(&la, &a, &lb, &b).1
            },
            &p0,
            1e-7,
        );
        let eg = (&g - &g_fd).norm() / g.norm();
        let eh = rel_err(&hm, &h_fd, 1e-300);
        assert!(eg <= 1e-5 && eh <= 1e-5, "random hulls: {eg:e} {eh:e}");
        worst = (worst.0.max(eg), worst.1.max(eh));
    }
    report("contact pose grad random hulls", worst.0);
    report("contact pose hess random hulls", worst.1);
}

#[test]
fn contact_is_c2_across_support_edge() {
    // Approaching d = 2s/(1−s) from inside, value, gradient and Hessian vanish like δ⁴, δ³, δ²
    // (δ = relative distance to the edge); outside they are exactly zero.
    let thr = params().support_distance();
    for (i, kind) in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace]
        .into_iter()
        .enumerate()
    {
        let mut prev: Option<(f64, f64, f64)> = None;
        for k in 1..=5 {
            let delta = 10f64.powi(-k);
            let mut r = rng(100 + i as u64); // same shapes/orientation for every δ
            let (la, pa, lb, pb) = configuration(kind, (1.0 - delta) * thr, &mut r);
            let (v, g, h) = pose_all(&la, &pa, &lb, &pb);
            let cur = (v, g.norm(), h.norm());
            assert!(v > 0.0 && cur.1 > 0.0 && cur.2 > 0.0, "{kind:?} δ={delta}");
            if let Some(p) = prev {
                // Ratios over one decade: ~1e4, ~1e3, ~1e2 (allow a factor 3 either way).
                let rv = p.0 / cur.0;
                let rg = p.1 / cur.1;
                let rh = p.2 / cur.2;
                assert!(
                    (3e3..3e4).contains(&rv),
                    "{kind:?} value ratio {rv} at δ={delta}"
                );
                assert!(
                    (3e2..3e3).contains(&rg),
                    "{kind:?} gradient ratio {rg} at δ={delta}"
                );
                assert!(
                    (30.0..300.0).contains(&rh),
                    "{kind:?} Hessian ratio {rh} at δ={delta}"
                );
            }
            prev = Some(cur);
        }
        for delta in [1e-9, 1e-3] {
            let mut r = rng(100 + i as u64);
            let (la, pa, lb, pb) = configuration(kind, (1.0 + delta) * thr, &mut r);
            let out = pose_eval(&la, &pa, &lb, &pb, Need::Hessian);
            assert!(
                matches!(out, PairOutcome::OutOfRange { .. }) || out.value() == 0.0,
                "{kind:?}: {out:?}"
            );
        }
    }
}

#[test]
fn contact_is_zero_beyond_support_distance() {
    let thr = params().support_distance();
    let mut rng = rng(5);
    for kind in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace] {
        for frac in [1.0 + 1e-6, 1.01, 1.5, 10.0] {
            let (la, pa, lb, pb) = configuration(kind, frac * thr, &mut rng);
            let out = pose_eval(&la, &pa, &lb, &pb, Need::Hessian);
            match out {
                PairOutcome::OutOfRange { distance, plane } => {
                    assert!(
                        (distance / (frac * thr) - 1.0).abs() < 1e-6,
                        "{distance} vs {}",
                        frac * thr
                    );
                    // The certificate, passed back as the warm start,
                    // re-certifies without GJK: out of range again, with a
                    // lower bound of the distance at or above the threshold.
                    match pose_eval_warm(&la, &pa, &lb, &pb, Need::Hessian, Some(plane)) {
                        PairOutcome::OutOfRange { distance: d2, .. } => {
                            assert!(d2 >= thr && d2 <= distance * (1.0 + 1e-9), "{d2}");
                        }
                        other => panic!("{kind:?} at {frac}: warm: {other:?}"),
                    }
                }
                other => panic!("{kind:?} at {frac}: expected OutOfRange, got {other:?}"),
            }
        }
    }
}

#[test]
fn contact_grows_without_bound_as_distance_shrinks() {
    let thr = params().support_distance();
    for (i, kind) in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace]
        .into_iter()
        .enumerate()
    {
        let mut prev = 0.0;
        let mut last = 0.0;
        for k in 0..=40 {
            // d from 0.99·thr down to 1e-6·thr (1e-7 absolute; GJK resolves gaps down to
            // ~1e-8 × hull size), log-spaced.
            let frac = 0.99 * 10f64.powf(-6.0 * k as f64 / 40.0);
            let mut r = rng(200 + i as u64);
            let (la, pa, lb, pb) = configuration(kind, frac * thr, &mut r);
            let v = pose_eval(&la, &pa, &lb, &pb, Need::Gradient).value();
            assert!(
                v.is_finite() && v > prev,
                "{kind:?}: not increasing at frac {frac}: {v} <= {prev}"
            );
            prev = v;
            last = v;
        }
        assert!(last > 1e25, "{kind:?}: U_c at 1e-6·thr is only {last}");
    }
}

#[test]
fn contact_forces_and_torques_balance() {
    let thr = params().support_distance();
    let mut rng = rng(7);
    let mut worst = 0.0f64;
    for kind in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace] {
        for frac in [1e-4, 0.01, 0.2, 0.6, 0.95] {
            let (la, pa, lb, pb) = configuration(kind, frac * thr, &mut rng);
            let PairOutcome::Separated(c) = pose_eval(&la, &pa, &lb, &pb, Need::Gradient) else {
                panic!()
            };
            let (mut fa, mut fb) = (vec![], vec![]);
            c.normal_forces_into(
                HullPose {
                    pose: &pa,
                    x_local: &la,
                },
                HullPose {
                    pose: &pb,
                    x_local: &lb,
                },
                S,
                &mut fa,
                &mut fb,
            );
            let xa = world(&pa, &la);
            let xb = world(&pb, &lb);
            let mut f = Vector3::zeros();
            let mut tau = Vector3::zeros();
            let (mut fscale, mut tscale) = (0.0, 0.0);
            for (x, fm) in xa.iter().zip(&fa).chain(xb.iter().zip(&fb)) {
                f += fm;
                tau += x.cross(fm);
                fscale += fm.norm();
                tscale += x.norm() * fm.norm();
            }
            let ef = f.norm() / fscale;
            let et = tau.norm() / tscale;
            assert!(
                ef <= 1e-9 && et <= 1e-9,
                "{kind:?} {frac}: force {ef:e}, torque {et:e}"
            );
            // The pose gradient's translation columns carry the same net force.
            let net = c.grad_a.column(3) + c.grad_b.column(3);
            assert!(net.norm() <= 1e-9 * fscale);
            // Forces push a towards −n and b towards +n.
            let n = c.normal();
            assert!(fa.iter().all(|v| v.dot(&n) <= 0.0) && fb.iter().all(|v| v.dot(&n) >= 0.0));
            worst = worst.max(ef).max(et);
        }
    }
    report("contact momentum balance", worst);
}

#[test]
fn contact_is_invariant_under_common_rigid_motion() {
    let thr = params().support_distance();
    let mut rng = rng(8);
    for kind in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace] {
        let (la, pa, lb, pb) = configuration(kind, 0.4 * thr, &mut rng);
        let v0 = pose_eval(&la, &pa, &lb, &pb, Need::Value).value();
        for scale_t in [1.0, 100.0] {
            let g = random_rotation(&mut rng);
            let t = Vector3::new(0.3, -2.0, 1.1) * scale_t;
            let pa2 = compose(g.matrix(), &t, &pa);
            let pb2 = compose(g.matrix(), &t, &pb);
            let v1 = pose_eval(&la, &pa2, &lb, &pb2, Need::Value).value();
            assert!(
                (v1 - v0).abs() <= 1e-9 * v0,
                "{kind:?}: {v0} vs {v1} (translation scale {scale_t})"
            );
        }
    }
}

#[test]
fn contact_warm_start_matches_cold_start() {
    let thr = params().support_distance();
    let mut rng = rng(9);
    for kind in [Features::FaceFace, Features::EdgeEdge, Features::VertexFace] {
        let (la, pa, lb, pb) = configuration(kind, 0.3 * thr, &mut rng);
        let mut sc = ContactScratch::new();
        let ha = HullPose {
            pose: &pa,
            x_local: &la,
        };
        let hb = HullPose {
            pose: &pb,
            x_local: &lb,
        };
        let PairOutcome::Separated(cold) =
            contact_pair(ha, hb, &params(), None, Need::Hessian, &mut sc).unwrap()
        else {
            panic!()
        };
        // Warm plane from a slightly different configuration (the previous "time step").
        let mut pb_prev = pb;
        let shifted = pb.column(3) + cold.normal().normalize() * 0.2 * thr;
        pb_prev.set_column(3, &shifted);
        let PairOutcome::Separated(prev) = contact_pair(
            ha,
            HullPose {
                pose: &pb_prev,
                x_local: &lb,
            },
            &params(),
            None,
            Need::Value,
            &mut sc,
        )
        .unwrap() else {
            panic!()
        };
        for warm in [prev.plane, cold.plane] {
            let PairOutcome::Separated(w) =
                contact_pair(ha, hb, &params(), Some(warm), Need::Hessian, &mut sc).unwrap()
            else {
                panic!()
            };
            assert!((w.value - cold.value).abs() <= 1e-12 * cold.value);
            assert!((w.plane - cold.plane).norm() <= 1e-8 * cold.plane.norm());
            assert!((w.grad_a - cold.grad_a).norm() <= 1e-9 * cold.grad_a.norm());
            let (hw, hc) = (
                **w.hessian.as_ref().unwrap(),
                **cold.hessian.as_ref().unwrap(),
            );
            assert!((hw - hc).norm() <= 1e-8 * hc.norm());
        }
        // An infeasible warm plane (wrong side) is ignored.
        let bad = -cold.plane;
        let PairOutcome::Separated(w) =
            contact_pair(ha, hb, &params(), Some(bad), Need::Value, &mut sc).unwrap()
        else {
            panic!()
        };
        assert!((w.value - cold.value).abs() <= 1e-12 * cold.value);
    }
}

#[test]
fn contact_detects_intersecting_and_touching_hulls() {
    let la = box_vertices(Vector3::new(0.5, 0.5, 0.5));
    let lb = box_vertices(Vector3::new(0.3, 0.3, 0.3));
    let pa = Matrix3x4::identity();
    let mut sc = ContactScratch::new();
    // Overlapping, touching face-to-face, touching edge and vertex, identical hulls.
    for t in [
        Vector3::new(0.0, 0.0, 0.6),
        Vector3::new(0.1, 0.0, 0.8),
        Vector3::new(0.8, 0.0, 0.8),
        Vector3::new(0.8, 0.8, 0.8),
        Vector3::new(0.0, 0.0, 0.0),
    ] {
        let mut pb = Matrix3x4::identity();
        pb.set_column(3, &t);
        let out = contact_pair(
            HullPose {
                pose: &pa,
                x_local: &la,
            },
            HullPose {
                pose: &pb,
                x_local: &lb,
            },
            &params(),
            None,
            Need::Hessian,
            &mut sc,
        )
        .unwrap();
        assert_eq!(out, PairOutcome::Intersecting, "offset {t:?}");
        assert_eq!(out.value(), f64::INFINITY);
        let xb = world(&pb, &lb);
        assert_eq!(
            contact_vertices(&la, &xb, &params(), None, &mut sc).unwrap(),
            VertexOutcome::Intersecting
        );
    }
    // A hair apart (1e-7 for unit-size hulls) is separated.
    let mut pb = Matrix3x4::identity();
    pb.set_column(3, &Vector3::new(0.1, 0.0, 0.8 + 1e-7));
    let out = contact_pair(
        HullPose {
            pose: &pa,
            x_local: &la,
        },
        HullPose {
            pose: &pb,
            x_local: &lb,
        },
        &params(),
        None,
        Need::Hessian,
        &mut sc,
    )
    .unwrap();
    assert!(matches!(out, PairOutcome::Separated(_)), "{out:?}");
    assert!(out.value().is_finite() && out.value() > 1e25);
    // Below GJK's resolution (1e-10 here) a cold start reports Intersecting, but a strictly
    // feasible warm plane certifies the separation and the solve proceeds.
    let gap = 1e-10;
    pb.set_column(3, &Vector3::new(0.1, 0.0, 0.8 + gap));
    let ha = HullPose {
        pose: &pa,
        x_local: &la,
    };
    let hb = HullPose {
        pose: &pb,
        x_local: &lb,
    };
    let cold = contact_pair(ha, hb, &params(), None, Need::Value, &mut sc).unwrap();
    assert_eq!(cold, PairOutcome::Intersecting);
    let nz = 1.0 - S;
    let warm = Vector4::new(0.0, 0.0, nz, -nz * (0.5 + 0.5 * gap));
    let out = contact_pair(ha, hb, &params(), Some(warm), Need::Hessian, &mut sc).unwrap();
    let PairOutcome::Separated(c) = out else {
        panic!("{out:?}")
    };
    assert!(c.value.is_finite() && c.value > 1e40, "{}", c.value);
    assert!((c.distance - gap).abs() < 1e-12);
    assert!(c.hessian.unwrap().iter().all(|v| v.is_finite()));
}

#[test]
fn contact_rejects_bad_input_with_typed_errors() {
    let la = box_vertices(Vector3::new(0.5, 0.5, 0.5));
    let pa = Matrix3x4::identity();
    let mut pb = Matrix3x4::identity();
    pb.set_column(3, &Vector3::new(0.0, 0.0, 1.01));
    let mut sc = ContactScratch::new();
    let ha = HullPose {
        pose: &pa,
        x_local: &la,
    };
    let hb = HullPose {
        pose: &pb,
        x_local: &la,
    };
    for s in [0.0, 1.0, -0.1, f64::NAN] {
        let p = ContactParams::with_width(s);
        assert!(matches!(
            contact_pair(ha, hb, &p, None, Need::Value, &mut sc),
            Err(ContactError::InvalidWidth { .. })
        ));
    }
    let p = ContactParams {
        inner_max_iters: 0,
        ..params()
    };
    assert!(matches!(
        contact_pair(ha, hb, &p, None, Need::Value, &mut sc),
        Err(ContactError::InvalidSolverSettings { .. })
    ));
    let empty: Vec<Vector3<f64>> = vec![];
    let he = HullPose {
        pose: &pb,
        x_local: &empty,
    };
    assert_eq!(
        contact_pair(ha, he, &params(), None, Need::Value, &mut sc),
        Err(ContactError::EmptyHull { hull: Hull::B })
    );
    let mut bad = la.clone();
    bad[3].y = f64::NAN;
    let hbad = HullPose {
        pose: &pa,
        x_local: &bad,
    };
    assert!(matches!(
        contact_pair(hbad, hb, &params(), None, Need::Value, &mut sc),
        Err(ContactError::NonFiniteVertex {
            hull: Hull::A,
            index: 3,
            ..
        })
    ));
    // An iteration cap that is too small is reported, not a panic.
    let p = ContactParams {
        inner_max_iters: 1,
        inner_tol: 0.0,
        inner_rtol: 0.0,
        ..params()
    };
    match contact_pair(ha, hb, &p, None, Need::Value, &mut sc) {
        Err(ContactError::PlaneNotConverged {
            iterations: 1,
            grad_norm,
            ..
        }) => assert!(grad_norm.is_finite()),
        other => panic!("{other:?}"),
    }
}

#[test]
fn contact_single_points_and_degenerate_hulls_work() {
    // Vertex–vertex contact between two single points and a segment: still a valid pair.
    let a = vec![Vector3::new(0.0, 0.0, 0.0)];
    let b = vec![Vector3::new(0.0, 0.0, 0.02), Vector3::new(0.3, 0.1, 0.5)];
    let mut sc = ContactScratch::new();
    let out = contact_vertices(&a, &b, &params(), None, &mut sc).unwrap();
    let VertexOutcome::Separated(c) = out else {
        panic!("{out:?}")
    };
    assert!(c.value > 0.0 && c.value.is_finite());
}

#[test]
fn contact_solver_is_robust_on_random_pairs() {
    // Random polytopes, widths s from 1e-3 to 0.5, gaps log-uniform over eight decades below
    // the support distance, random orientations: the solve never fails, never returns NaN, and
    // the plane's force balance holds.
    let mut rng = rng(31);
    let mut solved = 0;
    let mut max_iters = 0;
    for trial in 0..300 {
        let s = [1e-3, 1e-2, 0.1, 0.5][trial % 4];
        let p = ContactParams::with_width(s);
        let ma = rand::RngExt::random_range(&mut rng, 4..40);
        let mb = rand::RngExt::random_range(&mut rng, 4..40);
        let (ra, rb_) = (
            rand::RngExt::random_range(&mut rng, 0.2..1.0),
            rand::RngExt::random_range(&mut rng, 0.2..1.0),
        );
        let la = sphere_points(&mut rng, ma, ra);
        let lb = sphere_points(&mut rng, mb, rb_);
        let pa = test_util::pose(random_rotation(&mut rng).matrix(), &Vector3::zeros());
        let dir = random_rotation(&mut rng) * Vector3::z();
        let rb = random_rotation(&mut rng);
        let target =
            p.support_distance() * 10f64.powf(rand::RngExt::random_range(&mut rng, -8.0..0.0));
        let mut sc = ContactScratch::new();
        // Bisection on the offset for the target gap.
        let (mut lo, mut hi) = (0.0, 5.0);
        for _ in 0..70 {
            let mid = 0.5 * (lo + hi);
            let pb = test_util::pose(rb.matrix(), &(dir * mid));
            let out = contact_pair(
                HullPose {
                    pose: &pa,
                    x_local: &la,
                },
                HullPose {
                    pose: &pb,
                    x_local: &lb,
                },
                &p,
                None,
                Need::Value,
                &mut sc,
            )
            .unwrap_or_else(|e| panic!("trial {trial}: {e}"));
            match out {
                PairOutcome::Intersecting => lo = mid,
                PairOutcome::Separated(c) if c.distance < target => lo = mid,
                _ => hi = mid,
            }
        }
        let pb = test_util::pose(rb.matrix(), &(dir * hi));
        let ha = HullPose {
            pose: &pa,
            x_local: &la,
        };
        let hb = HullPose {
            pose: &pb,
            x_local: &lb,
        };
        match contact_pair(ha, hb, &p, None, Need::Hessian, &mut sc)
            .unwrap_or_else(|e| panic!("trial {trial}: {e}"))
        {
            PairOutcome::Separated(c) => {
                assert!(c.value.is_finite() && c.value >= 0.0, "trial {trial}");
                let h = c.hessian.as_deref().unwrap();
                assert!(h.iter().all(|v| v.is_finite()), "trial {trial}");
                assert!(
                    c.grad_a
                        .iter()
                        .chain(c.grad_b.iter())
                        .all(|v| v.is_finite())
                );
                let (mut fa, mut fb) = (vec![], vec![]);
                c.normal_forces_into(ha, hb, s, &mut fa, &mut fb);
                let net: Vector3<f64> = fa.iter().chain(&fb).sum();
                let scale: f64 = fa.iter().chain(&fb).map(|f| f.norm()).sum();
                let rel = net.norm() / scale.max(f64::MIN_POSITIVE);
                // Barrier arguments y ≈ ‖n‖ d/2 carry a rounding error ≈ ε_mach · (hull size),
                // which P' ~ y⁻⁶ amplifies: at absolute gaps of 1e-9 the achievable balance is
                // ~1e-5. Elsewhere it is 1e-8 or better.
                let bound = 1e-8f64.max(1e3 * f64::EPSILON * (ra + rb_) / c.distance);
                assert!(
                    rel <= bound,
                    "trial {trial}: s {s}, gap {:e}: balance {rel:e} > {bound:e}",
                    c.distance
                );
                max_iters = max_iters.max(c.iterations);
                solved += 1;
            }
            PairOutcome::OutOfRange { .. } | PairOutcome::Intersecting => {}
        }
    }
    assert!(solved > 250, "only {solved} pairs solved");
    report("contact robustness max Newton iterations", max_iters as f64);
}
