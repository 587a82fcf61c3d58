//! Tests of [`super`]: cuts at the margin, curved paths, and the shortcuts
//! (start kinematics, lever-bound clearing, partial rounds) giving the same
//! results bit for bit.

use super::*;
use crate::math::{pose_from, transform_point};
use crate::model::{Hull, JointKind, Link, MassModel, RobotInfo};
use nalgebra::{Matrix3, Vector3};

fn link(
    name: &str,
    parent: Option<usize>,
    joint: JointKind,
    at: Vector3<f64>,
    size: Vector3<f64>,
    centre: Vector3<f64>,
) -> Link {
    Link {
        name: name.into(),
        robot: 0,
        parent,
        joint_name: name.into(),
        joint,
        limit: None,
        attach: pose_from(&Matrix3::identity(), &at),
        hulls: vec![Hull::new(Hull::cuboid(size, centre), 0.1).unwrap()],
        mass_model: MassModel::Vertices,
        solid_triangles: Vec::new(),
        surface: Vec::new(),
        dof_offset: 0,
        chart: None,
        collides: true,
    }
}

fn model(links: Vec<Link>) -> Model {
    let n = links.len();
    Model::new(
        links,
        vec![RobotInfo {
            name: "r".into(),
            links: 0..n,
        }],
    )
}

/// Smallest certified gap of every candidate hull pair at `m` points of
/// `[0, alpha]` of `q + α dir`.
fn min_gap_along(model: &Model, q: &DVector<f64>, dir: &DVector<f64>, alpha: f64, m: usize) -> f64 {
    let charts = vec![Matrix3::identity(); model.nchart];
    let mut worst = f64::INFINITY;
    for k in 0..=m {
        let qa = q + dir * (alpha * k as f64 / m as f64);
        let poses = crate::kinematics::link_poses(model, &qa, &charts);
        let world = |l: usize| -> Vec<Vector3<f64>> {
            model.links[l].hulls[0]
                .x_local
                .iter()
                .map(|x| transform_point(&poses[l], x))
                .collect()
        };
        for a in 0..model.links.len() {
            for b in a + 1..model.links.len() {
                if model.links[b].parent == Some(a) {
                    continue;
                }
                let (xa, xb) = (world(a), world(b));
                let g = match separate(&xa, &xb, None, &mut VoronoiSimplex::new()) {
                    Ok(Separation::Separated { max_a, min_b, .. }) => min_b - max_a,
                    _ => -1.0,
                };
                worst = worst.min(g);
            }
        }
    }
    worst
}

#[test]
fn a_box_shot_through_a_thin_wall_is_stopped_at_the_margin_exactly() {
    let m = model(vec![
        link(
            "box",
            None,
            JointKind::Free,
            Vector3::zeros(),
            Vector3::new(0.05, 0.05, 0.05),
            Vector3::zeros(),
        ),
        link(
            "wall",
            None,
            JointKind::Fixed,
            Vector3::zeros(),
            Vector3::new(0.01, 1.0, 1.0),
            Vector3::zeros(),
        ),
    ]);
    let q = DVector::from_vec(vec![-0.5, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let dir = DVector::from_vec(vec![1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let mut ccd = Ccd::new(&m, CcdOptions::default());
    let charts = vec![Matrix3::identity(); m.nchart];
    let excluded = BTreeSet::new();
    let a = ccd.certify(&m, &excluded, &q, None, &dir, 1.0, &charts);
    // Gap 0.47 m, pure translation: the bound is exact, so the cut is
    // at (1 − η) g₀ / ‖Δx‖.
    let g0 = 0.5 - 0.025 - 0.005;
    assert!((a - 0.9 * g0).abs() < 1e-9, "α = {a}");
    assert!(min_gap_along(&m, &q, &dir, a, 400) >= 0.1 * g0 - 1e-9);
    assert_eq!(ccd.stats.alpha_caps, 1);
    // A half step stays clear of the wall: nothing to cut.
    let b = ccd.certify(&m, &excluded, &q, None, &dir, 0.4, &charts);
    assert_eq!(b, 0.4);
    // Tumbling while flying (free joint rotation): still certified.
    let dir = DVector::from_vec(vec![1.0, 0.2, 0.0, 4.0, -3.0, 6.0]);
    let a = ccd.certify(&m, &excluded, &q, None, &dir, 1.0, &charts);
    assert!(a > 0.1 && a < 0.5, "α = {a}");
    assert!(min_gap_along(&m, &q, &dir, a, 2000) > 0.0);
}

#[test]
fn a_whipped_chain_is_certified_along_its_curved_path() {
    // Root revolute (z) → prismatic (x) → spherical: three 0.3 m links
    // swept through a thin post at (0.5, 0.3).
    let z = Vector3::z();
    let rod = Vector3::new(0.3, 0.02, 0.02);
    let mid = Vector3::new(0.15, 0.0, 0.0);
    let m = model(vec![
        link(
            "a",
            None,
            JointKind::Revolute { axis: z },
            Vector3::zeros(),
            rod,
            mid,
        ),
        link(
            "b",
            Some(0),
            JointKind::Prismatic { axis: Vector3::x() },
            Vector3::new(0.3, 0.0, 0.0),
            rod,
            mid,
        ),
        link(
            "c",
            Some(1),
            JointKind::Spherical,
            Vector3::new(0.3, 0.0, 0.0),
            rod,
            mid,
        ),
        link(
            "post",
            None,
            JointKind::Fixed,
            Vector3::new(0.5, 0.3, 0.0),
            Vector3::new(0.01, 0.01, 0.5),
            Vector3::zeros(),
        ),
    ]);
    let q = DVector::from_vec(vec![-0.3, 0.0, 0.0, 0.0, 0.0]);
    let dir = DVector::from_vec(vec![2.0, 0.05, 0.0, 0.0, 0.3]);
    let charts = vec![Matrix3::identity(); m.nchart];
    // Without CCD the segment's end is clear but the path is not.
    assert!(min_gap_along(&m, &q, &dir, 1.0, 2000) < 0.0);
    let end = min_gap_along(&m, &(&q + &dir), &dir, 0.0, 1);
    assert!(end > 0.0, "end {end}");
    let mut ccd = Ccd::new(&m, CcdOptions::default());
    let a = ccd.certify(
        &m,
        &BTreeSet::from([(0, 1), (1, 2)]),
        &q,
        None,
        &dir,
        1.0,
        &charts,
    );
    assert!(a > 0.01 && a < 1.0, "α = {a}");
    assert!(min_gap_along(&m, &q, &dir, a, 4000) > 0.0);
    assert!(ccd.stats.pairs_advanced > 0 && ccd.stats.rounds > 0);
}

/// Two hanging ball-joint chains side by side, a free box and a fixed post;
/// the parent–child pairs excluded.
fn two_chains_box_and_post() -> (Model, BTreeSet<(usize, usize)>) {
    let mut links = Vec::new();
    let mut excluded = BTreeSet::new();
    for x0 in [-0.1, 0.1] {
        let root = links.len();
        for k in 0..5 {
            let parent = (k > 0).then(|| root + k - 1);
            if let Some(p) = parent {
                excluded.insert((p, root + k));
            }
            links.push(link(
                &format!("c{x0}_{k}"),
                parent,
                JointKind::Ball {
                    axes: [Vector3::x(), Vector3::y()],
                },
                if k == 0 {
                    Vector3::new(x0, 0.0, 1.0)
                } else {
                    Vector3::new(0.0, 0.0, -0.2)
                },
                Vector3::new(0.05, 0.05, 0.2),
                Vector3::new(0.0, 0.0, -0.1),
            ));
        }
    }
    links.push(link(
        "box",
        None,
        JointKind::Free,
        Vector3::zeros(),
        Vector3::new(0.1, 0.1, 0.1),
        Vector3::zeros(),
    ));
    links.push(link(
        "post",
        None,
        JointKind::Fixed,
        Vector3::new(0.0, -0.15, 0.5),
        Vector3::new(0.02, 0.02, 1.0),
        Vector3::zeros(),
    ));
    (model(links), excluded)
}

/// The shortcuts change nothing: with the step's start kinematics passed
/// in and the lever-bound clearing on, every result and statistic equals
/// the full computation's bit for bit — on segments from tiny (cleared by
/// the lever bound) to long (cut after advancement rounds), continued from
/// the cut as the line search does.
#[test]
fn shortcuts_give_the_full_computation_bit_for_bit() {
    use rand::{RngExt, SeedableRng};
    let (m, excluded) = two_chains_box_and_post();
    let charts = vec![Matrix3::identity(); m.nchart];
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(19);
    let mut fast = Ccd::new(&m, CcdOptions::default());
    let mut full = Ccd::new(&m, CcdOptions::default());
    full.lever_shortcut = false;
    let mut kin = Kinematics::new(&m);
    let (mut cut, mut whole) = (0, 0);
    for case in 0..400 {
        let scale = [1e-4, 1e-3, 1e-2, 0.1, 0.5][case % 5];
        let mut q = DVector::from_fn(m.ndof(), |_, _| rng.random_range(-0.3..0.3));
        // The box floats between the chains and the post.
        q[20] = rng.random_range(-0.3..0.3);
        q[21] = rng.random_range(0.12..0.4);
        q[22] = rng.random_range(0.3..0.9);
        let dir = DVector::from_fn(m.ndof(), |_, _| scale * rng.random_range(-1.0..1.0));
        kin.update(&m, &q, &charts, KinOrder::Pose);
        let a = fast.certify(&m, &excluded, &q, Some(&kin), &dir, 1.0, &charts);
        let b = full.certify(&m, &excluded, &q, None, &dir, 1.0, &charts);
        assert_eq!(a.to_bits(), b.to_bits(), "case {case}: {a} vs {b}");
        if a < 1.0 {
            cut += 1;
            // Continued from the cut (no start kinematics there).
            let q2 = &q + &dir * a;
            let a2 = fast.certify(&m, &excluded, &q2, None, &dir, 1.0 - a, &charts);
            let b2 = full.certify(&m, &excluded, &q2, None, &dir, 1.0 - a, &charts);
            assert_eq!(a2.to_bits(), b2.to_bits(), "case {case}, continued");
        } else {
            whole += 1;
        }
        assert_eq!(fast.stats, full.stats, "case {case}");
    }
    eprintln!(
        "{whole} whole, {cut} cut, {} cleared by the lever bound, stats {:?}",
        fast.lever_cleared, fast.stats
    );
    assert_eq!(full.lever_cleared, 0);
    assert!(fast.lever_cleared >= 100 && fast.lever_cleared <= 350);
    assert!(cut >= 20 && fast.stats.rounds >= 40);
}
