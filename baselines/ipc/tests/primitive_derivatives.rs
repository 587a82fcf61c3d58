//! Value, gradient and Hessian of every IPC primitive against finite
//! differences (Richardson-extrapolated central differences), ≤ 1e-6
//! relative, on random configurations and near-degenerate ones: near-parallel
//! edges (mollifier active), `d → d̂²`, and closest points next to an
//! edge/vertex boundary of the Voronoi regions. Classified distances are
//! also checked against brute-force sampling.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sdrs_ipc::distance::vec::V3;
use sdrs_ipc::distance::{DistanceType, edge_edge_distance, point_triangle_distance};
use sdrs_ipc::mollifier::eps_x;
use sdrs_ipc::primitive::{Mat12, PrimitiveKind, Vec12, evaluate, exact_hessian, stencil_distance};

const DHAT: f64 = 1e-3;

fn unflat(v: &Vec12) -> [V3<f64>; 4] {
    std::array::from_fn(|k| [v[3 * k], v[3 * k + 1], v[3 * k + 2]])
}
fn flat(x: &[V3<f64>; 4]) -> Vec12 {
    Vec12::from_fn(|i, _| x[i / 3][i % 3])
}

fn value(kind: PrimitiveKind, v: &Vec12) -> f64 {
    match evaluate(kind, &unflat(v), DHAT * DHAT, false) {
        sdrs_ipc::primitive::Primitive::Active(e) => e.value,
        sdrs_ipc::primitive::Primitive::Inactive { .. } => 0.0,
        sdrs_ipc::primitive::Primitive::Touching => f64::INFINITY,
    }
}

fn grad(kind: PrimitiveKind, v: &Vec12) -> Vec12 {
    exact_hessian(kind, &unflat(v), DHAT * DHAT)
        .map(|r| r.1)
        .unwrap_or_else(Vec12::zeros)
}

/// Richardson-extrapolated central difference of `f` along coordinate `i`.
fn fd<F: Fn(&Vec12) -> R, R>(
    f: &F,
    v: &Vec12,
    i: usize,
    h: f64,
    sub: impl Fn(R, R) -> R,
    scale: impl Fn(R, f64) -> R,
    comb: impl Fn(R, R) -> R,
) -> R {
    let cd = |h: f64| {
        let (mut a, mut b) = (*v, *v);
        a[i] += h;
        b[i] -= h;
        scale(sub(f(&a), f(&b)), 1.0 / (2.0 * h))
    };
    comb(cd(h / 2.0), cd(h))
}

/// Checks value, gradient and Hessian at `x`; returns false (nothing
/// checked) when the finite-difference stencil straddles a classification
/// boundary, where the Hessian jumps.
fn check(kind: PrimitiveKind, x: &[V3<f64>; 4], label: &str) -> bool {
    let v = flat(x);
    let Some((val, g, h)) = exact_hessian(kind, x, DHAT * DHAT) else {
        panic!("{label}: expected an active primitive");
    };
    // Same formula in dual and plain arithmetic (near d̂² the cancellation
    // in d − d̂² amplifies round-off differences).
    assert!(
        (val - value(kind, &v)).abs() <= 1e-9 * val.abs(),
        "{label}: value mismatch"
    );
    // The step resolves the smallest length scale of the function: the
    // distance, the gap to d̂ ((d̂² − d)/(2√d)) and, for edges, the offset
    // that changes their angle (‖e_a × e_b‖/‖e‖).
    let d = stencil_distance(kind, x).0;
    let mut scale = d.sqrt().min((DHAT * DHAT - d) / (2.0 * d.sqrt()));
    if let PrimitiveKind::EdgeEdge { .. } = kind {
        use sdrs_ipc::distance::vec::{cross, norm2, sub};
        let (ea, eb) = (sub(&x[1], &x[0]), sub(&x[3], &x[2]));
        let l = norm2(&ea).sqrt().max(norm2(&eb).sqrt());
        scale = scale.min(norm2(&cross(&ea, &eb)).sqrt() / l);
        if stencil_distance(kind, x).1 == DistanceType::LineLine {
            // Near-parallel skew lines: the closest points move by
            // ~√d·δ/(l²φ²) per coordinate change δ (φ the angle).
            let (la, lb) = (norm2(&ea).sqrt(), norm2(&eb).sqrt());
            let phi = norm2(&cross(&ea, &eb)).sqrt() / (la * lb);
            scale = scale.min(0.1 * la.min(lb).powi(2) * phi * phi / d.sqrt());
        }
    }
    let step = 1e-2 * scale;
    let ty0 = stencil_distance(kind, x).1;
    for i in 0..12 {
        for h in [step, -step, step / 2.0, -step / 2.0] {
            let mut w = v;
            w[i] += h;
            if stencil_distance(kind, &unflat(&w)).1 != ty0 {
                return false;
            }
        }
    }
    let mut g_fd = Vec12::zeros();
    let mut h_fd = Mat12::zeros();
    for i in 0..12 {
        g_fd[i] = fd(
            &|w: &Vec12| value(kind, w),
            &v,
            i,
            step,
            |a, b| a - b,
            |a, s| a * s,
            |a, b| (4.0 * a - b) / 3.0,
        );
        let col = fd(
            &|w: &Vec12| grad(kind, w),
            &v,
            i,
            step,
            |a, b| a - b,
            |a, s| a * s,
            |a: Vec12, b: Vec12| (a * 4.0 - b) / 3.0,
        );
        h_fd.set_column(i, &col);
    }
    let eg = (g - g_fd).norm() / g.norm().max(1e-300);
    let eh = (h - h_fd).norm() / h.norm().max(1e-300);
    assert!(eg <= 1e-6, "{label}: gradient relative error {eg:.2e}");
    assert!(eh <= 1e-6, "{label}: Hessian relative error {eh:.2e}");
    // The projected Hessian is PSD and equals the exact one where that is PSD.
    let Some(sdrs_ipc::primitive::Primitive::Active(e)) =
        Some(evaluate(kind, x, DHAT * DHAT, true))
    else {
        unreachable!()
    };
    let min_eig = e.hess.symmetric_eigen().eigenvalues.min();
    assert!(
        min_eig >= -1e-12 * e.hess.norm(),
        "{label}: projected Hessian not PSD ({min_eig})"
    );
    true
}

fn rand_v(rng: &mut ChaCha8Rng, s: f64) -> V3<f64> {
    [
        rng.random_range(-s..s),
        rng.random_range(-s..s),
        rng.random_range(-s..s),
    ]
}

/// A triangle of size ~`size` and a point at distance `dist` from the plane,
/// whose projection has barycentric coordinates `bary`.
fn pt_config(rng: &mut ChaCha8Rng, size: f64, bary: [f64; 3], dist: f64) -> [V3<f64>; 4] {
    let t: [V3<f64>; 3] = std::array::from_fn(|_| rand_v(rng, size));
    let n = sdrs_ipc::distance::vec::cross(
        &sdrs_ipc::distance::vec::sub(&t[1], &t[0]),
        &sdrs_ipc::distance::vec::sub(&t[2], &t[0]),
    );
    let nn = sdrs_ipc::distance::vec::norm2(&n).sqrt();
    let p: V3<f64> = std::array::from_fn(|k| {
        bary[0] * t[0][k] + bary[1] * t[1][k] + bary[2] * t[2][k] + dist * n[k] / nn
    });
    [p, t[0], t[1], t[2]]
}

#[test]
fn point_triangle_all_regions_fd() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut seen = std::collections::BTreeSet::new();
    let mut n = 0;
    while n < 300 {
        let b0: f64 = rng.random_range(-0.6..1.2);
        let b1: f64 = rng.random_range(-0.6..1.2);
        let dist = rng.random_range(0.0..DHAT);
        let x = pt_config(&mut rng, 2e-3, [b0, b1, 1.0 - b0 - b1], dist);
        let (d, ty) = stencil_distance(PrimitiveKind::PointTriangle, &x);
        if !(d > 0.05 * DHAT * DHAT && d < 0.95 * DHAT * DHAT) {
            continue;
        }
        seen.insert(format!("{ty:?}").chars().take(9).collect::<String>());
        if check(PrimitiveKind::PointTriangle, &x, &format!("PT #{n} {ty:?}")) {
            n += 1;
        }
    }
    assert_eq!(
        seen.len(),
        3,
        "all of point-point/line/plane exercised: {seen:?}"
    );
}

#[test]
fn point_triangle_near_dhat_and_near_region_boundaries() {
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    for k in 0..40i32 {
        // d → d̂²: the barrier and its derivatives vanish smoothly.
        let frac = 1.0 - 10f64.powi(-(2 + k % 5));
        let x = pt_config(&mut rng, 2e-3, [0.3, 0.3, 0.4], DHAT * frac.sqrt());
        assert!(check(
            PrimitiveKind::PointTriangle,
            &x,
            &format!("near d̂ {frac}")
        ));
        // Projection just inside/outside an edge (face ↔ edge region).
        let eps = [1e-3, -1e-3][k as usize % 2];
        let x = pt_config(
            &mut rng,
            2e-3,
            [0.5 + 20.0 * eps, 0.5, -20.0 * eps],
            0.5 * DHAT,
        );
        let (_, ty) = stencil_distance(PrimitiveKind::PointTriangle, &x);
        assert!(check(
            PrimitiveKind::PointTriangle,
            &x,
            &format!("edge boundary {eps} {ty:?}")
        ));
        // Next to the boundary between the region of edge t₀t₁ and that of
        // vertex t₀: outside the triangle across t₀t₁, with projection
        // parameter ±1e-3 along the edge.
        use nalgebra::Vector3;
        let t: [Vector3<f64>; 3] = std::array::from_fn(|_| Vector3::from(rand_v(&mut rng, 2e-3)));
        let e = t[1] - t[0];
        let n = e.cross(&(t[2] - t[0])).normalize();
        let out = e.cross(&n).normalize()
            * (if e.cross(&n).dot(&(t[2] - t[0])) > 0.0 {
                -1.0
            } else {
                1.0
            });
        let p = t[0] + e * (20.0 * eps) + out * (0.4 * DHAT) + n * (0.3 * DHAT);
        let arr = |p: Vector3<f64>| [p.x, p.y, p.z];
        let x = [arr(p), arr(t[0]), arr(t[1]), arr(t[2])];
        let (_, ty) = stencil_distance(PrimitiveKind::PointTriangle, &x);
        let want = if eps > 0.0 {
            DistanceType::PointLine(0, 1, 2)
        } else {
            DistanceType::PointPoint(0, 1)
        };
        if ty == want {
            assert!(check(
                PrimitiveKind::PointTriangle,
                &x,
                &format!("vertex boundary {eps} {ty:?}")
            ));
        }
    }
}

fn ee_kind(x: &[V3<f64>; 4]) -> PrimitiveKind {
    use sdrs_ipc::distance::vec::{norm2, sub};
    PrimitiveKind::EdgeEdge {
        eps_x: eps_x(norm2(&sub(&x[1], &x[0])), norm2(&sub(&x[3], &x[2]))),
    }
}

/// Edge `a` along a random direction, edge `b` at angle `angle` to it,
/// offset by `dist` along their common normal, with closest-point
/// parameters `s`, `t`.
fn ee_config(rng: &mut ChaCha8Rng, angle: f64, s: f64, t: f64, dist: f64) -> [V3<f64>; 4] {
    use nalgebra::Vector3;
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

#[test]
fn edge_edge_all_cases_fd() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut n = 0;
    let mut seen = std::collections::BTreeSet::new();
    while n < 300 {
        let angle = rng.random_range(0.2..1.5);
        let (s, t, dist) = (
            rng.random_range(-0.5..1.5),
            rng.random_range(-0.5..1.5),
            rng.random_range(0.0..DHAT),
        );
        let x = ee_config(&mut rng, angle, s, t, dist);
        let kind = ee_kind(&x);
        let (d, ty) = stencil_distance(kind, &x);
        if !(d > 0.05 * DHAT * DHAT && d < 0.95 * DHAT * DHAT) {
            continue;
        }
        seen.insert(format!("{ty:?}").chars().take(9).collect::<String>());
        if check(kind, &x, &format!("EE #{n} {ty:?}")) {
            n += 1;
        }
    }
    assert_eq!(seen.len(), 3, "{seen:?}");
}

#[test]
fn edge_edge_near_parallel_mollified_fd() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for k in 0..100 {
        // ε_x = 1e-3 ‖a‖²‖b‖² ⇔ sin²(angle) < 1e-3: angles below ~0.03 rad
        // are mollified. Line–line closest points (s, t interior) down to
        // 1e-3 rad; below that, the line–line case is numerically a
        // point–line one, and overlapping near-parallel segments have
        // nearly tied closest pairs; the segments are put end to end
        // (s = 1.02, t = −0.02: closest pair a₁–b₀) and the mollifier is
        // tested down to 1e-7 rad (below, the finite differences themselves lose the 1e-6 resolution: the step must stay below ‖e_a × e_b‖/‖e‖).
        let angle = [2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 3e-7][k % 10];
        let (s, t) = if angle >= 1e-3 {
            (0.5, 0.4)
        } else {
            (1.02, -0.02)
        };
        let dist = rng.random_range(0.2..0.9) * DHAT;
        let x = ee_config(&mut rng, angle, s, t, dist);
        let kind = ee_kind(&x);
        let (_, ty) = stencil_distance(kind, &x);
        if angle >= 1e-3 {
            assert_eq!(ty, DistanceType::LineLine);
        } else {
            assert_eq!(ty, DistanceType::PointPoint(1, 2));
        }
        assert!(
            check(kind, &x, &format!("near-parallel {angle} {ty:?}")),
            "near-parallel {angle}: FD stencil crosses a case boundary"
        );
    }
}

#[test]
fn classified_distances_equal_brute_force_minima() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let lerp = |a: &V3<f64>, b: &V3<f64>, t: f64| -> V3<f64> {
        std::array::from_fn(|k| a[k] + t * (b[k] - a[k]))
    };
    let d2 = |a: &V3<f64>, b: &V3<f64>| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>();
    for _ in 0..100 {
        let x: [V3<f64>; 4] = std::array::from_fn(|_| rand_v(&mut rng, 1.0));
        let m = 200;
        let mut best_pt = f64::INFINITY;
        let mut best_ee = f64::INFINITY;
        for i in 0..=m {
            for j in 0..=m - i {
                let (u, v) = (i as f64 / m as f64, j as f64 / m as f64);
                let q: V3<f64> = std::array::from_fn(|k| {
                    x[1][k] + u * (x[2][k] - x[1][k]) + v * (x[3][k] - x[1][k])
                });
                best_pt = best_pt.min(d2(&x[0], &q));
            }
            for j in 0..=m {
                let (s, t) = (i as f64 / m as f64, j as f64 / m as f64);
                best_ee = best_ee.min(d2(&lerp(&x[0], &x[1], s), &lerp(&x[2], &x[3], t)));
            }
        }
        let pt = point_triangle_distance(&x);
        let ee = edge_edge_distance(&x);
        // The exact minimum is below the sampled one, by at most the grid error.
        assert!(
            pt <= best_pt + 1e-12 && pt >= best_pt - 2e-2 * best_pt.sqrt() - 1e-4,
            "PT {pt} vs {best_pt}"
        );
        assert!(
            ee <= best_ee + 1e-12 && ee >= best_ee - 2e-2 * best_ee.sqrt() - 1e-4,
            "EE {ee} vs {best_ee}"
        );
    }
}

/// Parallel (or parallel to within round-off) edges, coplanar, far apart:
/// the distance is the true one, never the line–line distance of the
/// coplanar lines (0). Regression: the biped's two foot soles, 0.18 m
/// apart, after a cage reproduced their vertices to 8e-17 m, came out at
/// distance 0 (the parallel test on `a e − b²` drowned in cancellation)
/// and IPC refused the start ("touch or intersect"). Swept over
/// perturbations from 0 to 1e-9 of the edge length, orientations and
/// offsets along the edges, against brute-force sampling.
#[test]
fn parallel_coplanar_edges_far_apart_keep_their_distance() {
    // The stencil as it came out of the biped run (m).
    let x: [V3<f64>; 4] = [
        [
            -0.09000000000000001,
            0.023356119108777648,
            -0.6933115950623014,
        ],
        [-0.09, 0.05149253251477768, -0.6933115950623014],
        [
            0.08999999999999998,
            0.023356119108777634,
            -0.6933115950623014,
        ],
        [0.09, 0.05149253251477767, -0.6933115950623014],
    ];
    let d = edge_edge_distance(&x).sqrt();
    assert!((d - 0.18).abs() < 1e-12, "biped soles: distance {d}");
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let lerp = |a: &V3<f64>, b: &V3<f64>, t: f64| -> V3<f64> {
        std::array::from_fn(|k| a[k] + t * (b[k] - a[k]))
    };
    let d2 = |a: &V3<f64>, b: &V3<f64>| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>();
    for k in 0..400 {
        let len = rng.random_range(0.01..1.0);
        let gap = rng.random_range(1e-4..0.5);
        let shift = rng.random_range(-1.5..1.5) * len;
        let eps = [0.0, 1e-17, 1e-15, 1e-13, 1e-11, 1e-9][k % 6] * len;
        // Edge a along y at x = 0, edge b along y at x = gap (shifted
        // along y), all in the plane z = c; endpoints perturbed in x and y.
        let c = rng.random_range(-1.0..1.0);
        let mut p = || rng.random_range(-1.0..1.0) * eps;
        let a0 = [p(), p(), c];
        let a1 = [p(), len + p(), c];
        let b0 = [gap + p(), shift + p(), c];
        let b1 = [gap + p(), shift + len + p(), c];
        // A random rotation of the whole stencil keeps the distance.
        let axis = rand_v(&mut rng, 1.0);
        let r = nalgebra::Rotation3::new(nalgebra::Vector3::from(axis));
        let rot = |v: V3<f64>| -> V3<f64> {
            let w = r * nalgebra::Vector3::from(v);
            [w.x, w.y, w.z]
        };
        let x = [rot(a0), rot(a1), rot(b0), rot(b1)];
        let m = 400;
        let mut best = f64::INFINITY;
        for i in 0..=m {
            for j in 0..=m {
                let (s, t) = (i as f64 / m as f64, j as f64 / m as f64);
                best = best.min(d2(&lerp(&x[0], &x[1], s), &lerp(&x[2], &x[3], t)));
            }
        }
        let ee = edge_edge_distance(&x);
        assert!(
            // (The sampled minimum exceeds the exact one by at most the
            // grid's along-edge mismatch, (len/m)².)
            ee <= best + 1e-12 && ee >= best - (len / m as f64).powi(2) - 1e-12,
            "case {k} (perturbation {eps:e}, gap {gap}, shift {shift}): {ee} vs sampled {best}"
        );
    }
}
