//! Timing of the contact potential `U_c` and the friction potential `U_f` for random convex hull
//! pairs (points on spheres) with 8 … 1024 vertices per hull, placed at a gap inside the
//! barrier support.
//!
//! Run with `cargo run --release --example bench_contact`.
//!
//! Columns: vertices per hull; median µs of one `U_c` evaluation with value + gradient + 24×24
//! Hessian (separation test included); inner Newton iterations; vertices inside the barrier
//! band; median µs of one `U_f` evaluation (value + gradient + Hessian) and with the mixed
//! derivative as well; friction inner iterations. A second table compares the separation
//! test through our `SupportMap` on the raw vertex slice (what `contact_pair` does) with
//! building a parry `ConvexPolyhedron` and calling `parry3d_f64::query::distance`.

use std::hint::black_box;
use std::time::Instant;

use nalgebra::{Matrix3x4, Rotation3, Unit, Vector3};
use parry3d_f64::math::{Pose as PPose, Vector as PVec};
use parry3d_f64::shape::ConvexPolyhedron;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sdrs::contact::{
    ContactParams, ContactScratch, FrictionNeed, FrictionParams, FrictionScratch, HullPose,
    LaggedContact, Need, PairOutcome, contact_pair, friction_pair,
};
use sdrs::geometry::sampling::{pose, random_rotation, sphere_points};

/// Median of `reps` timings (µs) of `f`, after a warm-up call.
fn median_us(reps: usize, mut f: impl FnMut()) -> f64 {
    f();
    let mut t: Vec<f64> = (0..reps)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    t.sort_by(|a, b| a.partial_cmp(b).unwrap());
    t[t.len() / 2]
}

struct Case {
    la: Vec<Vector3<f64>>,
    lb: Vec<Vector3<f64>>,
    pa: Matrix3x4<f64>,
    pb: Matrix3x4<f64>,
}

/// A random pair at gap `gap` (bisection on the translation of `b` along a random direction).
fn make_case(rng: &mut ChaCha8Rng, m: usize, gap: f64, params: &ContactParams) -> Case {
    let la = sphere_points(rng, m, 0.5);
    let lb = sphere_points(rng, m, 0.5);
    let pa = pose(&random_rotation(rng), &Vector3::zeros());
    let dir = random_rotation(rng) * Vector3::z();
    let rb = random_rotation(rng);
    let mut sc = ContactScratch::new();
    let (mut lo, mut hi) = (0.0, 3.0);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        let pb = pose(&rb, &(dir * mid));
        let out = contact_pair(
            HullPose {
                pose: &pa,
                x_local: &la,
            },
            HullPose {
                pose: &pb,
                x_local: &lb,
            },
            params,
            None,
            Need::Value,
            &mut sc,
        )
        .expect("contact");
        match out {
            PairOutcome::Intersecting => lo = mid,
            PairOutcome::Separated(c) if c.distance < gap => lo = mid,
            _ => hi = mid,
        }
    }
    Case {
        la,
        lb,
        pa,
        pb: pose(&rb, &(dir * hi)),
    }
}

fn main() {
    let params = ContactParams::default();
    let fparams = FrictionParams::new(0.5, 0.01);
    let kappa = 1.0;
    let gap = 0.5 * params.support_distance();
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    println!(
        "SDRS contact benchmark: s = {}, gap = {:.4} (support {:.4}), points on spheres of radius 0.5",
        params.s,
        gap,
        params.support_distance()
    );
    println!("median over repeats of 4 random pairs per size (µs per evaluation)\n");
    println!(
        "{:>9} | {:>12} {:>8} {:>7} | {:>12} {:>14} {:>8}",
        "vertices", "U_c v+g+H", "newton", "active", "U_f v+g+H", "U_f +mixed", "newton"
    );
    println!("{}", "-".repeat(84));
    let sizes = [8usize, 16, 32, 64, 128, 256, 512, 1024];
    let mut gjk_rows = vec![];
    for &m in &sizes {
        let reps = (20_000 / m).clamp(50, 1000);
        let mut tc = vec![];
        let mut tf = vec![];
        let mut tfm = vec![];
        let mut iters_c = vec![];
        let mut iters_f = vec![];
        let mut active = vec![];
        let mut tg_ours = vec![];
        let mut tg_parry = vec![];
        for _ in 0..4 {
            let case = make_case(&mut rng, m, gap, &params);
            let ha = HullPose {
                pose: &case.pa,
                x_local: &case.la,
            };
            let hb = HullPose {
                pose: &case.pb,
                x_local: &case.lb,
            };
            let mut sc = ContactScratch::new();
            let mut last = None;
            tc.push(median_us(reps, || {
                last = Some(black_box(
                    contact_pair(ha, hb, &params, None, Need::Hessian, &mut sc).expect("contact"),
                ));
            }));
            let PairOutcome::Separated(pair) = last.unwrap() else {
                panic!("not separated")
            };
            iters_c.push(pair.iterations as f64);
            // Vertices inside the barrier band (those that carry a force).
            let lag = LaggedContact::from_contact(&pair, ha, hb, &params, kappa);
            active.push(
                lag.normal_force_a
                    .iter()
                    .chain(&lag.normal_force_b)
                    .filter(|f| **f > 0.0)
                    .count() as f64,
            );
            // Step t+1: small rigid motions of both hulls.
            let step = |p: &Matrix3x4<f64>, rng: &mut ChaCha8Rng| {
                let r = Rotation3::from_axis_angle(
                    &Unit::new_normalize(Vector3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    )),
                    1e-3,
                );
                let mut q = r.matrix() * p;
                let t = q.column(3) + Vector3::new(1e-3, -5e-4, 2e-4);
                q.set_column(3, &t);
                q
            };
            let pa1 = step(&case.pa, &mut rng);
            let pb1 = step(&case.pb, &mut rng);
            let fa = HullPose {
                pose: &pa1,
                x_local: &case.la,
            };
            let fb = HullPose {
                pose: &pb1,
                x_local: &case.lb,
            };
            let mut fsc = FrictionScratch::new();
            let frame = lag.frame();
            let mut fit = 0;
            tf.push(median_us(reps, || {
                let o = friction_pair(&frame, fa, fb, &fparams, FrictionNeed::Hessian, &mut fsc)
                    .expect("friction");
                fit = o.iterations;
                black_box(o);
            }));
            tfm.push(median_us(reps, || {
                black_box(
                    friction_pair(
                        &frame,
                        fa,
                        fb,
                        &fparams,
                        FrictionNeed::HessianAndMixed,
                        &mut fsc,
                    )
                    .expect("friction"),
                );
            }));
            iters_f.push(fit as f64);
            // Separation test alone: a far-apart copy of the pair (OutOfRange after GJK).
            let mut pfar = case.pb;
            let tfar = case.pb.column(3) * 1.5;
            pfar.set_column(3, &tfar);
            let hfar = HullPose {
                pose: &pfar,
                x_local: &case.lb,
            };
            tg_ours.push(median_us(reps, || {
                black_box(
                    contact_pair(ha, hfar, &params, None, Need::Value, &mut sc).expect("gjk"),
                );
            }));
            let to_p = |v: &Vector3<f64>| PVec::new(v.x, v.y, v.z);
            let wa: Vec<PVec> = case
                .la
                .iter()
                .map(|x| to_p(&(case.pa.fixed_columns::<3>(0) * x)))
                .collect();
            let wb: Vec<PVec> = case
                .lb
                .iter()
                .map(|x| to_p(&(pfar.fixed_columns::<3>(0) * x + pfar.column(3))))
                .collect();
            tg_parry.push(median_us(reps.min(200), || {
                let ca = ConvexPolyhedron::from_convex_hull(&wa).expect("hull a");
                let cb = ConvexPolyhedron::from_convex_hull(&wb).expect("hull b");
                black_box(
                    parry3d_f64::query::distance(&PPose::IDENTITY, &ca, &PPose::IDENTITY, &cb)
                        .expect("distance"),
                );
            }));
        }
        let med = |v: &mut Vec<f64>| {
            v.sort_by(|a, b| a.partial_cmp(b).unwrap());
            0.5 * (v[(v.len() - 1) / 2] + v[v.len() / 2])
        };
        println!(
            "{:>9} | {:>12.2} {:>8.1} {:>7.1} | {:>12.2} {:>14.2} {:>8.1}",
            m,
            med(&mut tc),
            med(&mut iters_c),
            med(&mut active),
            med(&mut tf),
            med(&mut tfm),
            med(&mut iters_f)
        );
        gjk_rows.push((m, med(&mut tg_ours), med(&mut tg_parry)));
    }
    println!("\nseparation test only (far pair, outcome OutOfRange), µs:");
    println!(
        "{:>9} | {:>22} | {:>34}",
        "vertices", "ours: SupportMap on slice", "parry: ConvexPolyhedron + distance"
    );
    println!("{}", "-".repeat(72));
    for (m, a, b) in gjk_rows {
        println!("{:>9} | {:>22.2} | {:>34.2}", m, a, b);
    }
}
