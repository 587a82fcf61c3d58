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

impl Case {
    /// Hull `a` at pose `pose` (its own, or a moved copy's).
    fn a_at<'a>(&'a self, pose: &'a Matrix3x4<f64>) -> HullPose<'a> {
        HullPose {
            pose,
            x_local: &self.la,
        }
    }

    /// Hull `b` at pose `pose` (its own, or a moved copy's).
    fn b_at<'a>(&'a self, pose: &'a Matrix3x4<f64>) -> HullPose<'a> {
        HullPose {
            pose,
            x_local: &self.lb,
        }
    }
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

/// Timings and counts of one hull size, one entry per random pair.
#[derive(Default)]
struct SizeSamples {
    /// µs of `U_c` with value, gradient and Hessian.
    contact_us: Vec<f64>,
    /// µs of `U_f` with value, gradient and Hessian.
    friction_us: Vec<f64>,
    /// µs of `U_f` with the mixed derivative as well.
    friction_mixed_us: Vec<f64>,
    contact_iters: Vec<f64>,
    friction_iters: Vec<f64>,
    /// Vertices inside the barrier band (those that carry a force).
    active: Vec<f64>,
    /// µs of the separation test alone: ours, and parry's hull + distance.
    separation_ours_us: Vec<f64>,
    separation_parry_us: Vec<f64>,
}

/// Pose `p` after a small rigid motion (1 mrad about a random axis, then a
/// fixed ~1 mm translation): step t+1 of the friction evaluation.
fn small_step(p: &Matrix3x4<f64>, rng: &mut ChaCha8Rng) -> Matrix3x4<f64> {
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
}

/// Contact at the case's poses, then friction after a small motion of both
/// hulls (lagged from that contact), into `out`.
fn measure_pair(
    case: &Case,
    reps: usize,
    params: &ContactParams,
    fparams: &FrictionParams,
    rng: &mut ChaCha8Rng,
    out: &mut SizeSamples,
) {
    let kappa = 1.0;
    let (ha, hb) = (case.a_at(&case.pa), case.b_at(&case.pb));
    let mut sc = ContactScratch::new();
    let mut last = None;
    out.contact_us.push(median_us(reps, || {
        last = Some(black_box(
            contact_pair(ha, hb, params, None, Need::Hessian, &mut sc).expect("contact"),
        ));
    }));
    let PairOutcome::Separated(pair) = last.unwrap() else {
        panic!("not separated")
    };
    out.contact_iters.push(pair.iterations as f64);
    let lag = LaggedContact::from_contact(&pair, ha, hb, params, kappa);
    out.active.push(
        lag.normal_force_a
            .iter()
            .chain(&lag.normal_force_b)
            .filter(|f| **f > 0.0)
            .count() as f64,
    );
    let pa1 = small_step(&case.pa, rng);
    let pb1 = small_step(&case.pb, rng);
    let fa = case.a_at(&pa1);
    let fb = case.b_at(&pb1);
    let mut fsc = FrictionScratch::new();
    let frame = lag.frame();
    let mut fit = 0;
    out.friction_us.push(median_us(reps, || {
        let o = friction_pair(&frame, fa, fb, fparams, FrictionNeed::Hessian, &mut fsc)
            .expect("friction");
        fit = o.iterations;
        black_box(o);
    }));
    let mixed = FrictionNeed::HessianAndMixed;
    out.friction_mixed_us.push(median_us(reps, || {
        black_box(friction_pair(&frame, fa, fb, fparams, mixed, &mut fsc).expect("friction"));
    }));
    out.friction_iters.push(fit as f64);
}

/// The separation test alone on a far-apart copy of the pair (OutOfRange
/// after GJK): ours on the raw vertex slices, and parry building both
/// `ConvexPolyhedron`s and calling `query::distance`.
fn measure_separation(case: &Case, reps: usize, params: &ContactParams, out: &mut SizeSamples) {
    let ha = case.a_at(&case.pa);
    let mut pfar = case.pb;
    let tfar = case.pb.column(3) * 1.5;
    pfar.set_column(3, &tfar);
    let hfar = case.b_at(&pfar);
    let mut sc = ContactScratch::new();
    out.separation_ours_us.push(median_us(reps, || {
        black_box(contact_pair(ha, hfar, params, None, Need::Value, &mut sc).expect("gjk"));
    }));
    let to_p = |v: &Vector3<f64>| PVec::new(v.x, v.y, v.z);
    let world = |x: &[Vector3<f64>], p: &Matrix3x4<f64>| -> Vec<PVec> {
        x.iter()
            .map(|x| to_p(&(p.fixed_columns::<3>(0) * x + p.column(3))))
            .collect()
    };
    let (wa, wb) = (world(&case.la, &case.pa), world(&case.lb, &pfar));
    out.separation_parry_us.push(median_us(reps.min(200), || {
        let ca = ConvexPolyhedron::from_convex_hull(&wa).expect("hull a");
        let cb = ConvexPolyhedron::from_convex_hull(&wb).expect("hull b");
        black_box(
            parry3d_f64::query::distance(&PPose::IDENTITY, &ca, &PPose::IDENTITY, &cb)
                .expect("distance"),
        );
    }));
}

/// Median of the samples (mean of the two middle ones for an even count).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    0.5 * (v[(v.len() - 1) / 2] + v[v.len() / 2])
}

fn main() {
    let params = ContactParams::default();
    let fparams = FrictionParams::new(0.5, 0.01);
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
        let mut s = SizeSamples::default();
        for _ in 0..4 {
            let case = make_case(&mut rng, m, gap, &params);
            measure_pair(&case, reps, &params, &fparams, &mut rng, &mut s);
            measure_separation(&case, reps, &params, &mut s);
        }
        println!(
            "{:>9} | {:>12.2} {:>8.1} {:>7.1} | {:>12.2} {:>14.2} {:>8.1}",
            m,
            median(&mut s.contact_us),
            median(&mut s.contact_iters),
            median(&mut s.active),
            median(&mut s.friction_us),
            median(&mut s.friction_mixed_us),
            median(&mut s.friction_iters)
        );
        gjk_rows.push((
            m,
            median(&mut s.separation_ours_us),
            median(&mut s.separation_parry_us),
        ));
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
