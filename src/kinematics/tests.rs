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
        let chart = link.chart.map(|c| charts[c]).unwrap_or_else(Matrix3::identity);
        let mut d = JointDerivatives::default();
        let qi = q.rows(link.dof_offset, n);
        link.joint.transform_derivatives_dual(&chart, qi.as_slice(), &mut d);
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
                    assert!((fd2 - an2).norm() < 1e-8, "case {case}: ∂²A_{i}/∂θ_{k}∂θ_{l}");
                }
            }
        }
    }
}
