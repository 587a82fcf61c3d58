//! Tests of [`super::Kinematics`]: the hinge joints' closed-form twists
//! against the generic (dual-number) path and against central differences
//! of the poses, at random and near-degenerate coordinates.

use super::motion_bound::tests::{every_joint_model, random_charts};
use super::*;
use rand::{RngExt, SeedableRng};

/// The twists of the generic path: `right_divide(P ∂J, A)` with `∂J` by
/// second-order dual numbers.
fn generic_twists(
    model: &Model,
    kin: &Kinematics,
    q: &DVector<f64>,
    charts: &[Matrix3<f64>],
) -> (Vec<Matrix3x4<f64>>, Vec<Matrix3x4<f64>>) {
    let mut s1 = vec![Matrix3x4::zeros(); model.ndof()];
    let mut s2 = vec![Matrix3x4::zeros(); kin.twist2.len()];
    for (i, link) in model.links.iter().enumerate() {
        let n = link.ndof();
        let chart = link
            .chart
            .map(|c| charts[c])
            .unwrap_or_else(Matrix3::identity);
        let mut d = JointDerivatives::default();
        let qi = q.rows(link.dof_offset, n);
        link.joint
            .transform_derivatives_dual(&chart, qi.as_slice(), &mut d);
        let (pre, pose) = (&kin.pre[i], &kin.pose[i]);
        for k in 0..n {
            s1[link.dof_offset + k] = right_divide(&apply_linear(pre, &d.d1[k]), pose);
            for l in 0..n {
                s2[kin.twist2_offset[i] + k * n + l] =
                    right_divide(&apply_linear(pre, &d.d2[k][l]), pose);
            }
        }
    }
    (s1, s2)
}

fn coordinates(rng: &mut impl rand::Rng, model: &Model, case: usize) -> DVector<f64> {
    DVector::from_fn(model.ndof(), |_, _| match case {
        0 => rng.random_range(-3.0..3.0),
        // near zero: the Rodrigues series' regime
        1 => rng.random_range(-1e-9..1e-9),
        // near ±π
        _ => std::f64::consts::PI - rng.random_range(0.0..1e-6),
    })
}

/// Closed-form hinge twists equal the generic path's to round-off (every
/// joint kind in the tree; the charted joints take the generic path).
#[test]
fn closed_form_twists_match_the_dual_number_path() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(31);
    for case in 0..3 {
        for _ in 0..10 {
            let model = every_joint_model(&mut rng);
            let charts = random_charts(&mut rng, &model);
            let q = coordinates(&mut rng, &model, case);
            let mut kin = Kinematics::new(&model);
            kin.update(&model, &q, &charts, KinOrder::Second);
            let (s1, s2) = generic_twists(&model, &kin, &q, &charts);
            for (k, (a, b)) in kin.twist.iter().zip(&s1).enumerate() {
                assert!((a - b).norm() < 1e-13, "case {case}: S_{k}: {a} vs {b}");
            }
            for (k, (a, b)) in kin.twist2.iter().zip(&s2).enumerate() {
                assert!((a - b).norm() < 1e-13, "case {case}: S2[{k}]: {a} vs {b}");
            }
        }
    }
}

/// `∂A_i/∂θ_k = S_k Ã_i` and, for two coordinates of one joint,
/// `∂(S_l Ã_i)/∂θ_k = S_kl Ã_i`, against central differences
/// (h = 1e-6; round-off and truncation ≤ 1e-8 here).
#[test]
fn twists_match_central_differences_of_the_poses() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let h = 1e-6;
    for case in 0..3 {
        let model = every_joint_model(&mut rng);
        let charts = random_charts(&mut rng, &model);
        let q = coordinates(&mut rng, &model, case);
        let mut kin = Kinematics::new(&model);
        kin.update(&model, &q, &charts, KinOrder::Second);
        let at = |dq: f64, k: usize| {
            let mut qk = q.clone();
            qk[k] += dq;
            let mut kk = Kinematics::new(&model);
            kk.update(&model, &qk, &charts, KinOrder::First);
            kk
        };
        for k in 0..model.ndof() {
            let (p, m) = (at(h, k), at(-h, k));
            for (i, link) in model.links.iter().enumerate() {
                let fd = (p.pose[i] - m.pose[i]) / (2.0 * h);
                let an = kin.dpose(&model, i, k);
                assert!((fd - an).norm() < 1e-8, "case {case}: ∂A_{i}/∂θ_{k}");
                let own = link.dof_offset..link.dof_offset + link.ndof();
                if !own.contains(&k) {
                    continue;
                }
                for l in own {
                    let fd2 = (twist_apply(&p.twist[l], &p.pose[i])
                        - twist_apply(&m.twist[l], &m.pose[i]))
                        / (2.0 * h);
                    let an2 = twist_apply(kin.twist2(&model, i, k, l), &kin.pose[i]);
                    assert!(
                        (fd2 - an2).norm() < 1e-8,
                        "case {case}: ∂²A_{i}/∂θ_{k}∂θ_{l}"
                    );
                }
            }
        }
    }
}

fn same_bits(a: &[Matrix3x4<f64>], b: &[Matrix3x4<f64>]) -> bool {
    a.iter()
        .flat_map(|m| m.iter())
        .zip(b.iter().flat_map(|m| m.iter()))
        .all(|(x, y)| x.to_bits() == y.to_bits())
}

/// `update_cached` gives the bits of a fresh `update` whatever the order
/// of the requests: the same point asked again with more derivatives, with
/// fewer, a new point, a new chart, and after a partial pose update.
#[test]
fn cached_evaluations_equal_fresh_ones_bit_for_bit() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let model = every_joint_model(&mut rng);
    let charts = random_charts(&mut rng, &model);
    let q = coordinates(&mut rng, &model, 0);
    let q2 = coordinates(&mut rng, &model, 0);
    let charts2 = random_charts(&mut rng, &model);
    let fresh = |q: &DVector<f64>, charts: &[Matrix3<f64>], order| {
        let mut k = Kinematics::new(&model);
        k.update(&model, q, charts, order);
        k
    };
    let mut kin = Kinematics::new(&model);
    let orders = [
        KinOrder::Pose,
        KinOrder::Second,
        KinOrder::First,
        KinOrder::Pose,
    ];
    let points = [
        (&q, &charts),
        (&q, &charts),
        (&q2, &charts),
        (&q2, &charts2),
    ];
    for (at, (qa, ca)) in points.iter().enumerate() {
        for &order in &orders {
            kin.update_cached(&model, qa, ca, order);
            let f = fresh(qa, ca, order);
            assert!(
                same_bits(&kin.pose, &f.pose),
                "point {at}, {order:?}: poses"
            );
            if order >= KinOrder::First {
                assert!(
                    same_bits(&kin.twist, &f.twist),
                    "point {at}, {order:?}: twists"
                );
            }
            if order >= KinOrder::Second {
                assert!(
                    same_bits(&kin.twist2, &f.twist2),
                    "point {at}: second twists"
                );
            }
        }
    }
    // A partial pose update (as collision detection does) invalidates.
    let needed = vec![true; model.links.len()];
    kin.update_poses_where(&model, &q, &charts, &needed);
    kin.update_cached(&model, &q, &charts, KinOrder::Second);
    let f = fresh(&q, &charts, KinOrder::Second);
    assert!(same_bits(&kin.twist2, &f.twist2) && same_bits(&kin.pose, &f.pose));
}

/// `update_or_copy` gives the bits of a fresh pose evaluation, whether it
/// copies (the other object was last evaluated at the point, with any
/// derivative order) or evaluates (a new point, a new chart, or a partial
/// pose update in the other object since); the copy leaves `pre` and the
/// joint values as a fresh evaluation, and a later `update_cached` with
/// derivatives from it still matches a fresh one.
#[test]
fn poses_copied_from_a_matching_evaluation_equal_fresh_ones_bit_for_bit() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let model = every_joint_model(&mut rng);
    let charts = random_charts(&mut rng, &model);
    let charts2 = random_charts(&mut rng, &model);
    let q = coordinates(&mut rng, &model, 0);
    let q2 = coordinates(&mut rng, &model, 0);
    let fresh = |q: &DVector<f64>, charts: &[Matrix3<f64>], order| {
        let mut k = Kinematics::new(&model);
        k.update(&model, q, charts, order);
        k
    };
    let mut other = Kinematics::new(&model);
    other.update(&model, &q, &charts, KinOrder::Second);
    let mut start = Kinematics::new(&model);
    let cases: [(&DVector<f64>, &[Matrix3<f64>]); 3] =
        [(&q, &charts), (&q2, &charts), (&q, &charts2)];
    for (case, (qa, ca)) in cases.into_iter().enumerate() {
        start.update_or_copy(&other, &model, qa, ca);
        let f = fresh(qa, ca, KinOrder::Pose);
        assert!(same_bits(&start.pose, &f.pose), "case {case}: poses");
        assert!(
            same_bits(&start.pre, &f.pre),
            "case {case}: pre-joint frames"
        );
        start.update_cached(&model, qa, ca, KinOrder::Second);
        let f = fresh(qa, ca, KinOrder::Second);
        assert!(
            same_bits(&start.twist2, &f.twist2),
            "case {case}: second twists"
        );
    }
    // A partial pose update in the other object since its evaluation: no copy.
    let mut needed = vec![false; model.links.len()];
    needed[0] = true;
    other.update_poses_where(&model, &q2, &charts, &needed);
    start.update_or_copy(&other, &model, &q, &charts);
    assert!(same_bits(
        &start.pose,
        &fresh(&q, &charts, KinOrder::Pose).pose
    ));
}

/// Every joint kind's value with derivatives is `transform`'s, bit for bit
/// (so a pose does not depend on the derivative order it was asked with).
#[test]
fn joint_values_do_not_depend_on_the_derivative_order() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    for case in 0..3 {
        let model = every_joint_model(&mut rng);
        let charts = random_charts(&mut rng, &model);
        let q = coordinates(&mut rng, &model, case);
        let mut a = Kinematics::new(&model);
        let mut b = Kinematics::new(&model);
        a.update(&model, &q, &charts, KinOrder::Pose);
        b.update(&model, &q, &charts, KinOrder::Second);
        assert!(same_bits(&a.pose, &b.pose), "case {case}");
    }
}
