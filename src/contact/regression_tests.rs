//! Regression tests of the inner solves on pair evaluations captured from simulations
//! (`SDRS_DUMP_FAILED_PAIR`, see [`capture`](super::capture)), plus randomised stress tests of
//! the regimes they came from: fast sliding with balanced normal forces (friction) and equal
//! hulls nearly touching with the optimal plane through the pair's shift origin (contact).

use nalgebra::{Matrix3x4, Rotation3, Unit, Vector3};
use rand::RngExt;

use super::capture::{ContactCase, FrictionCase};
use super::friction::*;
use super::test_util::*;
use super::*;

fn friction_case(text: &str) -> FrictionCase {
    serde_json::from_str(text).expect("captured friction case")
}

fn contact_case(text: &str) -> ContactCase {
    serde_json::from_str(text).expect("captured contact case")
}

/// Checks the inner optimality of a friction solve through its physical meaning: the massless
/// plane is in equilibrium, i.e. the friction forces `−∂U_f/∂X'` of all vertices sum to zero
/// and have zero moment about `n̂` (`∂U*/∂u = 0`, `∂U*/∂ω = 0`). Returns the relative force
/// and torque imbalance.
fn plane_equilibrium(frame: &FrictionFrame<'_>, f: &FrictionVertices) -> (f64, f64) {
    let (mut sum, mut tau, mut fs, mut ts) = (Vector3::zeros(), 0.0, 0.0, 0.0);
    for (x, g) in frame
        .x_prev_a
        .iter()
        .zip(&f.grad_a)
        .chain(frame.x_prev_b.iter().zip(&f.grad_b))
    {
        let force = -g;
        sum += force;
        tau += frame.normal.dot(&x.cross(&force));
        fs += force.norm();
        ts += x.norm() * force.norm();
    }
    (sum.norm() / fs, tau.abs() / ts)
}

/// Replays a captured friction failure: it must now converge, well inside the iteration cap,
/// to a plane velocity that is an equilibrium (up to the rounding of the step-`t+1` velocities,
/// ~`ε_mach ‖ẋ‖/√ε_v` relative), with finite derivatives.
fn replay_friction(text: &str, max_iters: usize) -> FrictionPair {
    let case = friction_case(text);
    let params = case.params;
    let out = case.run(None).expect("inner solve converges");
    assert!(out.value.is_finite() && out.value > 0.0);
    assert!(
        out.iterations <= max_iters,
        "{} inner iterations",
        out.iterations
    );
    // Derivatives at the solution are finite.
    let mut hc = case.clone();
    hc.need = "HessianAndMixed".into();
    let full = hc.run(None).expect("converges with derivatives");
    assert_eq!(full.value, out.value);
    assert!(full.hessian.unwrap().iter().all(|v| v.is_finite()));
    assert!(full.mixed.unwrap().iter().all(|v| v.is_finite()));
    // Equilibrium of the plane, checked at vertex level.
    let xa = world(&case.pose_a, &case.local_a);
    let xb = world(&case.pose_b, &case.local_b);
    let frame = case.frame();
    let fv = friction_vertices(&frame, &xa, &xb, &params, &mut FrictionScratch::new())
        .expect("vertex-level solve converges");
    assert_eq!(fv.value, out.value);
    let vmax = xa
        .iter()
        .zip(&case.x_prev_a)
        .chain(xb.iter().zip(&case.x_prev_b))
        .map(|(x1, x0)| (x1 - x0).norm() / params.dt)
        .fold(0.0, f64::max);
    let floor = 1e3 * f64::EPSILON * vmax / params.eps_velocity.sqrt();
    let (ef, et) = plane_equilibrium(&frame, &fv);
    assert!(
        ef <= 1e-9f64.max(floor) && et <= 1e-9f64.max(floor),
        "force {ef:e} torque {et:e} (floor {floor:e})"
    );
    out
}

#[test]
fn friction_solve_converges_for_fast_sliding_edge_contact_a10_step444() {
    // four_chains_a10, step 444: an outer line-search trial moves two crossing links at
    // ~370 m/s relative (3.7e5 √ε_v); one heavy vertex per hull. Used to stop after 100
    // iterations at |∇U*| = 6.7e-7 (4e-3 of the force scale), creeping along a flat valley.
    let out = replay_friction(include_str!("regressions/friction_a10_step444.json"), 40);
    assert!(!out.spin_free);
}

#[test]
fn friction_solve_converges_for_fast_sliding_vertex_edge_contact_a13_step378() {
    // four_chains_a13, step 378: one vertex of a against an edge of b, 200 m/s relative; the
    // total weights of the two sides agree to 2e-4 (force balance of the contact plane), so
    // U* has a slope of 1e-6 over ~100 m/s before the kink where the plane sticks to a.
    replay_friction(include_str!("regressions/friction_a13_step378.json"), 40);
}

#[test]
fn friction_solve_converges_on_four_chains_step1175() {
    // robots/four_chains.yaml (κ = 1e-4), step 1175: the same valley in the paper's scene.
    replay_friction(
        include_str!("regressions/friction_four_chains_step1175.json"),
        40,
    );
}

#[test]
fn friction_solve_follows_spin_valley_to_sticking_kink_quickly_a10() {
    // four_chains_a10, an outer line-search trial: the plane must spin at ~7000 rad/s to
    // follow two heavy vertices on different hulls; the iterate slid along the kink of one of
    // them while creeping towards it (60 iterations). The kink candidate (minimise along the
    // line where the plane sticks to that vertex) jumps there.
    replay_friction(
        include_str!("regressions/friction_a10_spin_valley.json"),
        25,
    );
}

#[test]
fn friction_solve_sticks_to_heavier_side_quickly_a13() {
    // four_chains_a13, an outer line-search trial: vertex–edge contact sliding at ~150 m/s.
    // The iterate first approached the kink of a light vertex that cannot hold the plane
    // (the others pull harder than its weight), then crept to the heavy vertex's kink where
    // the minimiser is (78 iterations). Trying the heaviest vertex's kink as well finds it.
    replay_friction(
        include_str!("regressions/friction_a13_sticks_to_heavier_side.json"),
        25,
    );
}

#[test]
fn plane_solve_stops_at_noise_floor_for_mirror_symmetric_pair() {
    // four_chains_a10: two identical links mirror-symmetric about the contact plane, 6 μm
    // apart, barrier forces ~1e25. The optimal plane passes through the shift origin, so
    // y = n·x + o ≈ 3e-6 comes from products n_i x_i ≈ 0.05 that cancel; the gradient's
    // rounding bound used ε |n·x| instead of ε Σ|n_i x_i| and was 4× below the actual rounding
    // floor, and the solve ran out of iterations there (|∇U*| = 6.7e12 > 1.8e12).
    let case = contact_case(include_str!("regressions/contact_a10_trial.json"));
    assert!(case.error.contains("did not converge"), "{}", case.error);
    let mut full = case.clone();
    full.need = "Hessian".into();
    for c in [&case, &full] {
        let PairOutcome::Separated(out) = c.run().expect("plane solve converges") else {
            panic!("expected a separated pair");
        };
        assert_solved(&out, 20);
        // Force balance of the plane, to the rounding of the barrier arguments amplified by
        // P' ~ y⁻⁶ (see `contact_solver_is_robust_on_random_pairs`).
        let imbalance = plane_force_imbalance(c, &out);
        let bound = 1e3 * f64::EPSILON * 0.4 / out.distance;
        assert!(imbalance <= bound, "{imbalance:e}");
    }
}

/// A replayed separated pair: positive finite potential, finite Hessian (when computed),
/// at most `max_iters` inner iterations.
fn assert_solved(out: &ContactPair, max_iters: usize) {
    assert!(out.iterations <= max_iters, "{} iterations", out.iterations);
    assert!(out.value.is_finite() && out.value > 0.0, "{:e}", out.value);
    if let Some(h) = &out.hessian {
        assert!(h.iter().all(|v| v.is_finite()));
    }
}

/// The net normal force on the massless plane relative to the sum of the forces' magnitudes
/// (0 at the plane's equilibrium).
fn plane_force_imbalance(c: &ContactCase, out: &ContactPair) -> f64 {
    let (ha, hb) = (
        HullPose {
            pose: &c.pose_a,
            x_local: &c.local_a,
        },
        HullPose {
            pose: &c.pose_b,
            x_local: &c.local_b,
        },
    );
    let (mut fa, mut fb) = (vec![], vec![]);
    out.normal_forces_into(ha, hb, c.params.s, &mut fa, &mut fb);
    let net: Vector3<f64> = fa.iter().chain(&fb).sum();
    let scale: f64 = fa.iter().chain(&fb).map(|f| f.norm()).sum();
    net.norm() / scale
}

/// Seven pairs of the single jaw's cross task (issue 30), captured where the optimizer's
/// trials failed: a jaw block against the cross's pointed tip, 0.9985–1.0001 of the support
/// distance `2s/(1−s)` apart (s = 1 mm). From their warm planes the solve crawled (the plane
/// turns by 0.2 rad over 100 iterations while `U*` falls 2.6 → 7e-8) and hit the iteration
/// cap: four line-search trials (rejected as infeasible) and three derivative evaluations at
/// accepted iterates (which failed the optimizer's trial). A failed warm solve is now retried
/// from GJK's cold start (`solve_core`). Each must give a physically consistent outcome: out of
/// range (`U = 0`) exactly when the hulls are at least the support distance apart (four
/// cases), otherwise a positive potential whose plane balances its barrier forces, with a
/// finite Hessian and few iterations (three). Without the retry every case fails.
#[test]
fn plane_solve_at_the_support_edge_recovers_from_a_poor_warm_plane() {
    let cases = [
        include_str!("regressions/contact_cross_support_edge_0.json"),
        include_str!("regressions/contact_cross_support_edge_1.json"),
        include_str!("regressions/contact_cross_support_edge_2.json"),
        include_str!("regressions/contact_cross_support_edge_3.json"),
        include_str!("regressions/contact_cross_support_edge_4.json"),
        include_str!("regressions/contact_cross_support_edge_5.json"),
        include_str!("regressions/contact_cross_support_edge_6.json"),
    ];
    let (mut inside, mut outside) = (0, 0);
    for text in cases {
        let case = contact_case(text);
        assert!(case.error.contains("did not converge"), "{}", case.error);
        assert!(case.warm.is_some(), "captured with a warm plane");
        let support = case.params.support_distance();
        let mut full = case.clone();
        full.need = "Hessian".into();
        for c in [&case, &full] {
            match c.run().expect("the plane solve recovers") {
                PairOutcome::OutOfRange { distance, .. } => {
                    assert!(distance >= support, "{distance:e} < {support:e}");
                    outside += 1;
                }
                PairOutcome::Separated(out) => {
                    assert!(out.distance < support && out.distance > 0.998 * support);
                    assert_solved(&out, 20);
                    let imbalance = plane_force_imbalance(c, &out);
                    assert!(imbalance <= 1e-6, "net force {imbalance:e}");
                    inside += 1;
                }
                PairOutcome::Intersecting => panic!("separated hulls reported intersecting"),
            }
        }
    }
    // Both regimes are covered (each case twice: value and Hessian).
    assert_eq!((inside, outside), (6, 8));
}

/// A random unit vector.
fn unit(r: &mut rand_chacha::ChaCha8Rng) -> Unit<Vector3<f64>> {
    loop {
        let v = Vector3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        );
        if v.norm() > 0.1 && v.norm() <= 1.0 {
            break Unit::new_normalize(v);
        }
    }
}

/// The link hull of the chain scenes: a 0.05 × 0.05 × 0.2 box hanging below its joint.
fn link_box() -> Vec<Vector3<f64>> {
    box_vertices(Vector3::new(0.025, 0.025, 0.1))
        .into_iter()
        .map(|v| v - Vector3::new(0.0, 0.0, 0.1))
        .collect()
}

#[test]
fn plane_solve_is_robust_for_mirror_symmetric_pairs_nearly_touching() {
    // Equal link boxes, mirror images of each other about a random plane (so the optimal plane
    // passes through the midpoint of the centroids, the solver's shift origin), placed ~7 m
    // from the world origin like the chain scenes, gaps log-uniform from 1e-10 to the support
    // distance: value and Hessian solves, cold and warm, never fail.
    let mut r = rng(501);
    let local = link_box();
    let mut max_iters = 0;
    let mut solved = 0;
    for trial in 0..400 {
        let s = [0.005, 0.01, 0.05][trial % 3];
        let p = ContactParams::with_width(s);
        let rot = Rotation3::from_axis_angle(&unit(&mut r), r.random_range(-3.1..3.1));
        let centre = Vector3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            7.0 + r.random_range(-1.0..1.0),
        );
        let n = unit(&mut r).into_inner();
        let pose_a = pose(rot.matrix(), &centre);
        let xa0 = world(&pose_a, &local);
        // Shift a along −n so that its closest vertex is at distance gap/2 from the mirror
        // plane through the origin of the configuration (`centre`).
        let gap = p.support_distance() * 10f64.powf(r.random_range(-8.0..0.0));
        let top = xa0
            .iter()
            .map(|x| (x - centre).dot(&n))
            .fold(f64::NEG_INFINITY, f64::max);
        let shift = -n * (top + 0.5 * gap);
        let xa: Vec<_> = xa0.iter().map(|x| x + shift).collect();
        let xb: Vec<_> = xa
            .iter()
            .map(|x| x - 2.0 * (x - centre).dot(&n) * n)
            .collect();
        let id = Matrix3x4::identity();
        let (ha, hb) = (
            HullPose {
                pose: &id,
                x_local: &xa,
            },
            HullPose {
                pose: &id,
                x_local: &xb,
            },
        );
        let mut sc = ContactScratch::new();
        let mut warm = None;
        for need in [Need::Value, Need::Hessian, Need::Hessian] {
            let out = contact_pair(ha, hb, &p, warm, need, &mut sc)
                .unwrap_or_else(|e| panic!("trial {trial}: s {s}, gap {gap:e}, {need:?}: {e}"));
            if let PairOutcome::Separated(c) = out {
                assert!(c.value.is_finite(), "trial {trial}");
                if let Some(h) = c.hessian {
                    assert!(h.iter().all(|v| v.is_finite()), "trial {trial}");
                }
                max_iters = max_iters.max(c.iterations);
                solved += 1;
                warm = Some(c.plane);
            }
        }
    }
    assert!(solved > 1000, "only {solved} solves");
    report(
        "mirror-pair plane solve max Newton iterations",
        max_iters as f64,
    );
}

#[test]
fn friction_solve_is_robust_for_fast_sliding_with_balanced_forces() {
    // Lagged data from real contact solves (so the normal forces of the two sides balance,
    // which makes U* nearly flat between the two hulls' velocities), then the step-(t+1)
    // poses of the chain scenes' trial points: relative speeds from 1e-3 to 1e7 √ε_v, spins
    // up to 1e4 rad/s, stiffness over eight decades. Every solve converges and the plane is
    // in equilibrium.
    let mut r = rng(502);
    let local = link_box();
    let fp = FrictionParams {
        eps_velocity: 1e-6,
        eps_force: 1e-6,
        ..FrictionParams::new(0.2, 0.005)
    };
    let mut max_iters = 0;
    let mut total_iters = 0;
    let mut solves = 0;
    for trial in 0..300 {
        let cp = ContactParams::with_width(0.005);
        let kappa = 10f64.powf(r.random_range(-4.0..4.0));
        // Two link boxes nearly touching in a random relative orientation.
        let rot_a = Rotation3::from_axis_angle(&unit(&mut r), r.random_range(-3.1..3.1));
        let rot_b = Rotation3::from_axis_angle(&unit(&mut r), r.random_range(-3.1..3.1));
        let ca = Vector3::new(0.3, 0.3, 7.0);
        let pa = pose(rot_a.matrix(), &ca);
        let dir = unit(&mut r).into_inner();
        let target = cp.support_distance() * 10f64.powf(r.random_range(-3.0..-0.1));
        let mut sc = ContactScratch::new();
        let place = |off: f64| pose(rot_b.matrix(), &(ca + dir * off));
        // Bisection on the offset for the target gap.
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            let pb = place(mid);
            let out = contact_pair(
                HullPose {
                    pose: &pa,
                    x_local: &local,
                },
                HullPose {
                    pose: &pb,
                    x_local: &local,
                },
                &cp,
                None,
                Need::Value,
                &mut sc,
            )
            .unwrap();
            match out {
                PairOutcome::Intersecting => lo = mid,
                PairOutcome::Separated(c) if c.distance < target => lo = mid,
                _ => hi = mid,
            }
        }
        let pb = place(hi);
        let (ha, hb) = (
            HullPose {
                pose: &pa,
                x_local: &local,
            },
            HullPose {
                pose: &pb,
                x_local: &local,
            },
        );
        let PairOutcome::Separated(c) =
            contact_pair(ha, hb, &cp, None, Need::Value, &mut sc).unwrap()
        else {
            continue;
        };
        let lag = LaggedContact::from_contact(&c, ha, hb, &cp, kappa);
        for _ in 0..4 {
            // Rigid step of each hull: translation at `speed`, spin about a random axis
            // through a random point of the hull.
            let step = |p: &Matrix3x4<f64>, r: &mut rand_chacha::ChaCha8Rng| {
                let speed = 1e-3 * 10f64.powf(r.random_range(-3.0..7.0));
                let spin = 10f64.powf(r.random_range(-3.0..4.0));
                let rot = Rotation3::from_axis_angle(&unit(r), spin * fp.dt);
                let pivot = p.column(3).into_owned();
                let t = pivot - rot * pivot + unit(r).into_inner() * speed * fp.dt;
                compose(rot.matrix(), &t, p)
            };
            let (pa1, pb1) = (step(&pa, &mut r), step(&pb, &mut r));
            let xa = world(&pa1, &local);
            let xb = world(&pb1, &local);
            let frame = lag.frame();
            let f = friction_vertices(&frame, &xa, &xb, &fp, &mut FrictionScratch::new())
                .unwrap_or_else(|e| panic!("trial {trial}, κ {kappa:e}: {e}"));
            assert!(f.value.is_finite() && f.value >= 0.0);
            assert!(f.dense_hessian().iter().all(|v| v.is_finite()));
            let out = friction_pair(
                &frame,
                HullPose {
                    pose: &pa1,
                    x_local: &local,
                },
                HullPose {
                    pose: &pb1,
                    x_local: &local,
                },
                &fp,
                FrictionNeed::HessianAndMixed,
                &mut FrictionScratch::new(),
            )
            .unwrap_or_else(|e| panic!("trial {trial}, κ {kappa:e}: {e}"));
            assert!(out.hessian.unwrap().iter().all(|v| v.is_finite()));
            let vmax = xa
                .iter()
                .zip(&lag.x_prev_a)
                .chain(xb.iter().zip(&lag.x_prev_b))
                .map(|(x1, x0)| (x1 - x0).norm() / fp.dt)
                .fold(0.0, f64::max);
            let floor = 1e3 * f64::EPSILON * vmax / fp.eps_velocity.sqrt();
            let (ef, et) = plane_equilibrium(&frame, &f);
            if f.value > 0.0 {
                assert!(
                    ef <= 1e-8f64.max(floor) && et <= 1e-8f64.max(floor),
                    "trial {trial}: force {ef:e} torque {et:e} (floor {floor:e})"
                );
            }
            max_iters = max_iters.max(f.iterations);
            total_iters += f.iterations;
            solves += 1;
        }
    }
    assert!(solves > 1000, "only {solves} solves");
    report(
        "fast-sliding friction max inner iterations",
        max_iters as f64,
    );
    report(
        "fast-sliding friction mean inner iterations",
        total_iters as f64 / solves as f64,
    );
}
