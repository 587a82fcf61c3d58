//! Tests of [`super`]: sampled paths of every joint kind against the bounds,
//! the chart constants by finite differences, the start rates, and the
//! lever-only upper bound.

use super::*;
use crate::kinematics::{KinOrder, Kinematics};
use crate::math::{pose_from, rpy_to_matrix, transform_point};
use crate::model::{Hull, Link, MassModel};
use nalgebra::Matrix3;
use rand::{RngExt, SeedableRng};

fn link(name: &str, parent: Option<usize>, joint: JointKind, attach: Pose) -> Link {
    Link {
        name: name.into(),
        robot: 0,
        parent,
        joint_name: name.into(),
        joint,
        limit: None,
        attach,
        hulls: vec![
            Hull::new(
                Hull::cuboid(Vector3::new(0.3, 0.1, 0.2), Vector3::new(0.2, 0.05, 0.0)),
                0.1,
            )
            .unwrap(),
        ],
        mass_model: MassModel::Vertices,
        solid_triangles: Vec::new(),
        surface: Vec::new(),
        dof_offset: 0,
        chart: None,
        collides: true,
    }
}

/// The bounds of the segment `q → q + dq` and the link poses at
/// `steps + 1` evenly spaced points of it.
fn bound_and_path(
    model: &Model,
    q: &DVector<f64>,
    dq: &DVector<f64>,
    charts: &[Matrix3<f64>],
    steps: usize,
) -> (SegmentMotion, Vec<f64>, Vec<Vec<Pose>>) {
    let mut kin = Kinematics::new(model);
    kin.update(model, q, charts, KinOrder::Pose);
    let mut radius = Vec::new();
    hull_radii(model, &mut radius);
    let mut m = SegmentMotion::default();
    m.update(model, &kin.pre, &kin.pose, charts, &radius, q, dq);
    let poses = (0..=steps)
        .map(|k| {
            crate::kinematics::link_poses(model, &(q + dq * (k as f64 / steps as f64)), charts)
        })
        .collect();
    (m, radius, poses)
}

/// A tree with every joint kind: free root → revolute → prismatic →
/// spherical → ball, plus a fixed branch off the root and a prismatic
/// root.
pub(crate) fn every_joint_model(rng: &mut impl rand::Rng) -> Model {
    let mut at = |v: f64| {
        pose_from(
            &rpy_to_matrix(&[
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ]),
            &Vector3::new(v, 0.1, -0.2),
        )
    };
    let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
    let links = vec![
        link("base", None, JointKind::Free, at(0.5)),
        link("rev", Some(0), JointKind::Revolute { axis }, at(0.4)),
        link("pri", Some(1), JointKind::Prismatic { axis }, at(0.3)),
        link("sph", Some(2), JointKind::Spherical, at(0.2)),
        link(
            "ball",
            Some(3),
            JointKind::Ball {
                axes: [Vector3::x(), Vector3::y()],
            },
            at(0.3),
        ),
        link("fix", Some(0), JointKind::Fixed, at(0.6)),
        link("slider", None, JointKind::Prismatic { axis }, at(-0.5)),
    ];
    let n = links.len();
    Model::new(
        links,
        vec![crate::model::RobotInfo {
            name: "r".into(),
            links: 0..n,
        }],
    )
}

/// Every hull vertex, sampled densely along random segments, stays within
/// the bound, both in norm and along fixed directions, from every
/// sampled start `α₀` (the bound holds on sub-segments).
#[test]
fn sampled_paths_stay_within_the_lever_bound_for_every_joint_kind() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut worst: f64 = 0.0;
    for case in 0..60 {
        let model = every_joint_model(&mut rng);
        let n = model.ndof();
        let charts: Vec<Matrix3<f64>> =
            (0..model.links.iter().filter(|l| l.chart.is_some()).count())
                .map(|_| {
                    rpy_to_matrix(&[
                        rng.random_range(-3.0..3.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-3.0..3.0),
                    ])
                })
                .collect();
        // Large rotation steps (up to ‖Δφ‖ ≈ 5 rad) probe the chart far
        // from its centre.
        let scale = [0.05, 0.5, 2.0][case % 3];
        let q = DVector::from_fn(n, |_, _| rng.random_range(-1.5..1.5));
        let dq = DVector::from_fn(n, |_, _| scale * rng.random_range(-1.0..1.0));
        let steps = 200;
        let (m, _, poses) = bound_and_path(&model, &q, &dq, &charts, steps);
        let dirs: Vec<Vector3<f64>> = (0..4)
            .map(|_| Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize())
            .collect();
        for (i, l) in model.links.iter().enumerate() {
            for x in &l.hulls[0].x_local {
                let pts: Vec<Vector3<f64>> =
                    poses.iter().map(|p| transform_point(&p[i], x)).collect();
                for k0 in [0, steps / 3] {
                    for k in k0 + 1..=steps {
                        let da = (k - k0) as f64 / steps as f64;
                        let moved = pts[k] - pts[k0];
                        let bound = da * m.reach(i);
                        assert!(
                            moved.norm() <= bound * (1.0 + 1e-9) + 1e-12,
                            "case {case} link {i}: moved {} > bound {bound}",
                            moved.norm()
                        );
                        worst = worst.max(moved.norm() / bound.max(1e-300));
                        // Relative to every ancestor's frame.
                        let mut c = Some(i);
                        while let Some(a) = c {
                            let rel = |k: usize| {
                                let pa = &poses[k][a];
                                rot(pa).transpose() * (pts[k] - pa.column(3))
                            };
                            let moved_rel = (rel(k) - rel(k0)).norm();
                            let b = da * m.relative_spread(i, a);
                            assert!(
                                moved_rel <= b * (1.0 + 1e-9) + 1e-12,
                                "case {case} link {i} relative to {a}: {moved_rel} > {b}"
                            );
                            c = model.links[a].parent;
                        }
                        for d in &dirs {
                            let along = d.dot(&(moved - m.drift[i] * da));
                            assert!(
                                along.abs() <= da * m.spread[i] * (1.0 + 1e-9) + 1e-12,
                                "case {case} link {i}: directional"
                            );
                        }
                    }
                }
            }
        }
    }
    // The bound is not vacuous: some sampled motion uses a good part of it.
    assert!(worst > 0.3, "bound never approached: {worst}");
}

/// `‖J_r(φ) Δφ‖ ≤ ‖Δφ‖` for the chart the code uses
/// (`R = R_c exp([φ]×)`), far beyond `‖φ‖ = π`: the angular speed of
/// `exp` along a straight line, by central differences.
#[test]
fn rotation_vector_angular_speed_never_exceeds_the_coordinate_speed() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut max_ratio: f64 = 0.0;
    for _ in 0..2000 {
        let phi = Vector3::from_fn(|_, _| rng.random_range(-6.0..6.0));
        let d = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
        let h = 1e-6;
        let rp = crate::math::so3::exp(&(phi + d * h));
        let rm = crate::math::so3::exp(&(phi - d * h));
        let r = crate::math::so3::exp(&phi);
        // Body angular velocity: vee(Rᵀ Ṙ).
        let w = r.transpose() * (rp - rm) / (2.0 * h);
        let omega = axial(&w);
        let ratio = omega.norm() / d.norm();
        assert!(ratio <= 1.0 + 1e-6, "ratio {ratio} at φ = {phi:?}");
        max_ratio = max_ratio.max(ratio);
    }
    assert!(max_ratio > 0.999);
}

/// One random chart centre (roll ±3, pitch ±1, yaw ±3 rad), shared by every
/// chart of `model` (the draws in this order: the tests' random streams).
pub(crate) fn random_charts(rng: &mut rand_chacha::ChaCha8Rng, model: &Model) -> Vec<Matrix3<f64>> {
    vec![
        rpy_to_matrix(&[
            rng.random_range(-3.0..3.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-3.0..3.0),
        ]);
        model.links.iter().filter(|l| l.chart.is_some()).count()
    ]
}

/// The exact start rates `ω_i(0)`, `ȯ_i(0)` of the rate bound match
/// central differences of the forward kinematics for every joint kind.
#[test]
fn start_rates_match_finite_differences_for_every_joint_kind() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    for _ in 0..40 {
        let model = every_joint_model(&mut rng);
        let n = model.ndof();
        let charts = random_charts(&mut rng, &model);
        let q = DVector::from_fn(n, |_, _| rng.random_range(-2.0..2.0));
        let dq = DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
        let mut kin = Kinematics::new(&model);
        kin.update(&model, &q, &charts, KinOrder::Pose);
        let mut radius = Vec::new();
        hull_radii(&model, &mut radius);
        let mut m = SegmentMotion::default();
        m.update(&model, &kin.pre, &kin.pose, &charts, &radius, &q, &dq);
        let h = 1e-6;
        let plus = crate::kinematics::link_poses(&model, &(&q + &dq * h), &charts);
        let minus = crate::kinematics::link_poses(&model, &(&q - &dq * h), &charts);
        for i in 0..model.links.len() {
            let dr = (rot(&plus[i]) - rot(&minus[i])) / (2.0 * h);
            let spin = dr * rot(&kin.pose[i]).transpose();
            let w = axial(&spin);
            let v = (plus[i].column(3) - minus[i].column(3)) / (2.0 * h);
            assert!(
                (w - m.omega0[i]).norm() <= 1e-6 * (1.0 + w.norm()),
                "ω link {i}"
            );
            assert!(
                (v - m.origin_rate0[i]).norm() <= 1e-6 * (1.0 + v.norm()),
                "ȯ link {i}"
            );
        }
    }
}

/// `‖d/dα (J_l(φ + αΔφ) Δφ)‖ ≤ C ‖Δφ‖²` with the constant the rate
/// bound uses, by central differences of the space angular velocity of
/// `exp`, far beyond `‖φ‖ = π` and near `φ = 0`.
#[test]
fn the_chart_angular_velocity_turns_no_faster_than_assumed() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let omega = |phi: &Vector3<f64>, d: &Vector3<f64>| {
        let h = 1e-6;
        let r = crate::math::so3::exp(phi);
        let s = (crate::math::so3::exp(&(phi + d * h)) - crate::math::so3::exp(&(phi - d * h)))
            / (2.0 * h)
            * r.transpose();
        axial(&s)
    };
    let mut worst: f64 = 0.0;
    for k in 0..4000 {
        let scale = [1e-3, 0.5, 3.0, 10.0][k % 4];
        let phi = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)) * scale;
        let d = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize();
        let h = 1e-4;
        let turn = (omega(&(phi + d * h), &d) - omega(&(phi - d * h), &d)).norm() / (2.0 * h);
        assert!(turn <= CHART_TURN, "turn {turn} at φ = {phi:?}");
        worst = worst.max(turn);
    }
    // The constant is not vacuous either (sampled maximum ≈ 1/π).
    assert!(worst > 0.25, "{worst}");
}

/// A hanging 32-link ball-joint chain whose joints turn against each
/// other (each link nearly still: the motion of a long chain in its
/// first Newton step): the bound holds along the sampled path and stays
/// within a small factor of the actual motion, where the lever bound
/// alone is far above it.
#[test]
fn alternating_joint_steps_of_a_long_chain_get_a_tight_bound() {
    let n_links = 32;
    let mut links = Vec::new();
    for k in 0..n_links {
        let mut l = link(
            &format!("l{k}"),
            if k == 0 { None } else { Some(k - 1) },
            JointKind::Ball {
                axes: [Vector3::x(), Vector3::y()],
            },
            pose_from(
                &Matrix3::identity(),
                &Vector3::new(0.0, 0.0, if k == 0 { 7.0 } else { -0.2 }),
            ),
        );
        l.hulls = vec![
            Hull::new(
                Hull::cuboid(Vector3::new(0.05, 0.05, 0.2), Vector3::new(0.0, 0.0, -0.1)),
                0.1,
            )
            .unwrap(),
        ];
        links.push(l);
    }
    let model = Model::new(
        links,
        vec![crate::model::RobotInfo {
            name: "chain".into(),
            links: 0..n_links,
        }],
    );
    let n = model.ndof();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
    let q = DVector::from_fn(n, |_, _| rng.random_range(-0.3..0.3));
    // Joint k turns by ±0.03 rad, its neighbour back: links barely move.
    let dq = DVector::from_fn(n, |i, _| {
        let sign = if (i / 2) % 2 == 0 { 1.0 } else { -1.0 };
        sign * 0.03 + rng.random_range(-1e-3..1e-3)
    });
    let charts: Vec<Matrix3<f64>> = Vec::new();
    let steps = 400;
    let (m, radius, poses) = bound_and_path(&model, &q, &dq, &charts, steps);
    let tip = n_links - 1;
    let mut moved_max: f64 = 0.0;
    for i in 0..n_links {
        for x in &model.links[i].hulls[0].x_local {
            let x0 = transform_point(&poses[0][i], x);
            for (k, p) in poses.iter().enumerate().skip(1) {
                let moved = (transform_point(&p[i], x) - x0).norm();
                let bound = m.reach(i) * k as f64 / steps as f64;
                assert!(
                    moved <= bound * (1.0 + 1e-9) + 1e-12,
                    "link {i}: {moved} > {bound}"
                );
                if i == tip {
                    moved_max = moved_max.max(moved);
                }
            }
        }
    }
    let lever = m.origin_full[tip] + m.angular[tip] * radius[tip];
    assert!(
        m.reach(tip) <= 5.0 * moved_max,
        "rate bound {} vs moved {moved_max}",
        m.reach(tip)
    );
    // Measured: moved 0.103 m, rate bound 0.43 m (4.1×), lever 4.5 m (43×).
    assert!(
        lever >= 20.0 * moved_max,
        "lever {lever} vs moved {moved_max}"
    );
}

/// The lever half's upper bound `Ē` is at least the full `E` as computed
/// (bit for bit, no tolerance), and so is the reach, on random segments of
/// every joint kind from tiny to long; and the poses of a subset of links
/// ([`Kinematics::update_poses_where`]) are those of the full evaluation.
#[test]
fn the_lever_half_bounds_the_spread_from_above_exactly() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(23);
    let mut tighter = 0;
    for case in 0..300 {
        let model = every_joint_model(&mut rng);
        let n = model.ndof();
        let charts = random_charts(&mut rng, &model);
        let scale = [1e-6, 1e-3, 0.05, 0.5, 3.0][case % 5];
        let q = DVector::from_fn(n, |_, _| rng.random_range(-1.5..1.5));
        let dq = DVector::from_fn(n, |_, _| scale * rng.random_range(-1.0..1.0));
        let (m, _, _) = bound_and_path(&model, &q, &dq, &charts, 1);
        for i in 0..model.links.len() {
            assert!(m.spread_upper[i] >= m.spread[i], "case {case} link {i}");
            assert!(m.reach_upper(i) >= m.reach(i), "case {case} link {i}");
            if m.spread_upper[i] > m.spread[i] {
                tighter += 1;
            }
        }
        // Poses of a subset closed under ancestors.
        let mut full = Kinematics::new(&model);
        full.update(&model, &q, &charts, KinOrder::Pose);
        let mut part = Kinematics::new(&model);
        let needed: Vec<bool> = (0..model.links.len()).map(|i| i < 3 || i == 6).collect();
        part.update_poses_where(&model, &q, &charts, &needed);
        for (i, &k) in needed.iter().enumerate() {
            if k {
                assert_eq!(part.pose[i], full.pose[i], "pose {i}");
                assert_eq!(part.pre[i], full.pre[i], "pre {i}");
            }
        }
    }
    // The rate bound is the tighter one for most links.
    assert!(tighter > 500, "{tighter}");
}

/// A chain of ball joints with axes at 60° (`a₁·a₂ = ½`) and nearly
/// opposite (`a₁·a₂ ≈ −0.98`), where the exact joint rate
/// `√(Δq₁² + Δq₂² + 2 Δq₁Δq₂ a₁·a₂)` is far below `|Δq₁| + |Δq₂|`, under a
/// free root and a revolute.
fn skew_ball_model(rng: &mut impl rand::Rng) -> Model {
    let mut at = |v: f64| {
        pose_from(
            &rpy_to_matrix(&[
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ]),
            &Vector3::new(v, -0.1, 0.2),
        )
    };
    let a = Vector3::new(0.2, 0.4, -0.9).normalize();
    let sixty = Vector3::new(0.5, 0.75f64.sqrt(), 0.0);
    // a₁·a₂ = −0.98 with a₁ = x.
    let opposite = Vector3::new(-0.98, (1.0f64 - 0.98 * 0.98).sqrt(), 0.0);
    let links = vec![
        link("base", None, JointKind::Free, at(0.4)),
        link(
            "b60",
            Some(0),
            JointKind::Ball {
                axes: [Vector3::x(), sixty],
            },
            at(0.3),
        ),
        link("rev", Some(1), JointKind::Revolute { axis: a }, at(0.3)),
        link(
            "b180",
            Some(2),
            JointKind::Ball {
                axes: [Vector3::x(), opposite],
            },
            at(0.25),
        ),
        link(
            "tip",
            Some(3),
            JointKind::Ball {
                axes: [sixty, Vector3::z()],
            },
            at(0.2),
        ),
    ];
    let n = links.len();
    Model::new(
        links,
        vec![crate::model::RobotInfo {
            name: "r".into(),
            links: 0..n,
        }],
    )
}

/// Ball joints whose axes are not perpendicular (the bound uses their exact
/// rate, not `|Δq₁| + |Δq₂|`): every hull vertex, sampled along random
/// segments, including turns that nearly cancel, stays within the reach
/// from every sampled start.
#[test]
fn sampled_paths_of_skewed_ball_joints_stay_within_the_bound() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41);
    let mut worst: f64 = 0.0;
    for case in 0..60 {
        let model = skew_ball_model(&mut rng);
        let n = model.ndof();
        let charts = random_charts(&mut rng, &model);
        let scale = [0.05, 0.5, 2.0][case % 3];
        let q = DVector::from_fn(n, |_, _| rng.random_range(-1.5..1.5));
        let mut dq = DVector::from_fn(n, |_, _| scale * rng.random_range(-1.0..1.0));
        if case % 2 == 0 {
            // Turns that nearly cancel on the 60° and near-opposite joints.
            let (b60, b180) = (model.links[1].dof_offset, model.links[3].dof_offset);
            dq[b60 + 1] = -dq[b60];
            dq[b180 + 1] = dq[b180];
        }
        let steps = 200;
        let (m, _, poses) = bound_and_path(&model, &q, &dq, &charts, steps);
        for (i, l) in model.links.iter().enumerate() {
            for x in &l.hulls[0].x_local {
                let pts: Vec<Vector3<f64>> =
                    poses.iter().map(|p| transform_point(&p[i], x)).collect();
                for k0 in [0, steps / 3] {
                    for k in k0 + 1..=steps {
                        let da = (k - k0) as f64 / steps as f64;
                        let moved = (pts[k] - pts[k0]).norm();
                        let bound = da * m.reach(i);
                        assert!(
                            moved <= bound * (1.0 + 1e-9) + 1e-12,
                            "case {case} link {i}: moved {moved} > bound {bound}"
                        );
                        worst = worst.max(moved / bound.max(1e-300));
                    }
                }
            }
        }
    }
    assert!(worst > 0.3, "bound never approached: {worst}");
}

/// The chords of the IPC baseline's line search: on random sub-intervals
/// `[α₀, α₀ + h]` of random segments, of every joint kind and of skewed
/// ball joints, every hull vertex stays within
/// [`SegmentMotion::chord_deviation`] of the chord between its exact end
/// positions; both halves of the bound (`E h/2` and `A h²/8`) are the
/// smaller one somewhere, and the bound is approached.
#[test]
fn sampled_paths_stay_within_the_chord_deviation() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(59);
    let (mut worst, mut by_speed, mut by_accel) = (0.0f64, 0, 0);
    for case in 0..80 {
        let model = if case % 2 == 0 {
            every_joint_model(&mut rng)
        } else {
            skew_ball_model(&mut rng)
        };
        let n = model.ndof();
        let charts = random_charts(&mut rng, &model);
        let scale = [0.05, 0.5, 2.0, 4.0][case % 4];
        let q = DVector::from_fn(n, |_, _| rng.random_range(-1.5..1.5));
        let dq = DVector::from_fn(n, |_, _| scale * rng.random_range(-1.0..1.0));
        let mut kin = Kinematics::new(&model);
        kin.update(&model, &q, &charts, KinOrder::Pose);
        let mut radius = Vec::new();
        hull_radii(&model, &mut radius);
        let mut m = SegmentMotion::default();
        m.update(&model, &kin.pre, &kin.pose, &charts, &radius, &q, &dq);
        m.update_chord(&model, &dq);
        for h in [1.0, 0.3, 0.05, 0.004] {
            let a0 = if h < 1.0 {
                rng.random_range(0.0..1.0 - h)
            } else {
                0.0
            };
            let steps = 60;
            let poses: Vec<Vec<Pose>> = (0..=steps)
                .map(|k| {
                    let a = a0 + h * k as f64 / steps as f64;
                    crate::kinematics::link_poses(&model, &(&q + &dq * a), &charts)
                })
                .collect();
            for (i, l) in model.links.iter().enumerate() {
                let bound = m.chord_deviation(i, h);
                if m.spread[i] * h / 2.0 <= m.accel[i] * h * h / 8.0 {
                    by_speed += 1;
                } else {
                    by_accel += 1;
                }
                for x in &l.hulls[0].x_local {
                    let start = transform_point(&poses[0][i], x);
                    let end = transform_point(&poses[steps][i], x);
                    for (k, p) in poses.iter().enumerate() {
                        let s = k as f64 / steps as f64;
                        let off = (transform_point(&p[i], x) - (start + (end - start) * s)).norm();
                        assert!(
                            off <= bound * (1.0 + 1e-9) + 1e-12,
                            "case {case} h {h} link {i}: {off} off the chord > {bound}"
                        );
                        worst = worst.max(off / bound.max(1e-300));
                    }
                }
            }
        }
    }
    assert!(by_speed > 0 && by_accel > 0, "{by_speed} {by_accel}");
    assert!(worst > 0.1, "chord bound never approached: {worst}");
}
