//! One contact-potential evaluation (value + gradient + Hessian, pose space)
//! of SDRS `U_c` vs the IPC baseline on the same pair of random convex hulls
//! (points on spheres of radius 0.5 m) with 8 … 1024 vertices per hull,
//! placed at half the interaction range of each model (SDRS: `2s/(1−s)` with
//! `s = 0.01`; IPC: `d̂` set to that same range), so both see a contact of
//! the same depth into their barrier zone.
//!
//! IPC's cost includes its primitive broad phase (the SDRS figure includes
//! its separation test). Optionally writes the cases to a JSON file for the
//! ipctk timing/cross-check script (`tools/ipctk_crosscheck.py`).
//!
//! Run: `cargo run --release -p sdrs-ipc --example bench_potential [cases.json]`.

use nalgebra::{Matrix3, Matrix3x4, Rotation3, Unit, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sdrs::contact::{ContactParams, ContactScratch, HullPose, Need, PairOutcome, contact_pair};
use sdrs_ipc::broad_phase::{Candidates, PrimitiveBoxes, candidates};
use sdrs_ipc::mesh::LinkMesh;
use sdrs_ipc::pair::{PairGeometry, evaluate_pair};
use std::hint::black_box;
use std::time::Instant;

fn sphere_points(rng: &mut ChaCha8Rng, m: usize, r: f64) -> Vec<Vector3<f64>> {
    (0..m)
        .map(|_| {
            loop {
                let v = Vector3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                let n = v.norm();
                if n > 1e-3 && n <= 1.0 {
                    break v * (r / n);
                }
            }
        })
        .collect()
}

fn rotation(rng: &mut ChaCha8Rng) -> Matrix3<f64> {
    let axis = Unit::new_normalize(Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    ));
    *Rotation3::from_axis_angle(&axis, rng.random_range(-3.1..3.1)).matrix()
}

fn pose(r: &Matrix3<f64>, t: &Vector3<f64>) -> Matrix3x4<f64> {
    let mut a = Matrix3x4::zeros();
    a.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
    a.set_column(3, t);
    a
}

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

fn mesh_of(points: &[Vector3<f64>]) -> LinkMesh {
    let poly = sdrs::import::polytope::convex_hull(points).expect("hull");
    let mut m = LinkMesh::default();
    m.add_closed(0, &poly.vertices, &poly.triangles)
        .expect("closed");
    m.radius = m.x_local.iter().map(|x| x.norm()).fold(0.0, f64::max);
    m
}

fn main() {
    let out = std::env::args().nth(1);
    let params = ContactParams::default();
    let range = params.support_distance();
    let dhat = range;
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    println!(
        "contact potential, value+gradient+Hessian, median µs per evaluation (4 random pairs per size)"
    );
    println!(
        "SDRS s = {}, range {range:.4} m; IPC d̂ = {dhat:.4} m; gap = half the range\n",
        params.s
    );
    println!(
        "{:>8} | {:>10} | {:>10} {:>8} {:>8} | {:>7}",
        "vertices", "SDRS µs", "IPC µs", "cands", "active", "IPC/SDRS"
    );
    let mut cases_json = Vec::new();
    for &m in &[8usize, 16, 32, 64, 128, 256, 512, 1024] {
        let reps = (20_000 / m).clamp(20, 500);
        let (mut ts, mut ti, mut nc, mut na) = (vec![], vec![], vec![], vec![]);
        for _ in 0..4 {
            let la = sphere_points(&mut rng, m, 0.5);
            let lb = sphere_points(&mut rng, m, 0.5);
            let pa = pose(&rotation(&mut rng), &Vector3::zeros());
            let dir = rotation(&mut rng) * Vector3::z();
            let rb = rotation(&mut rng);
            let ma = mesh_of(&la);
            let mb = mesh_of(&lb);
            // Bisection on the translation for an IPC mesh distance of half the range.
            let world = |mesh: &LinkMesh, p: &Matrix3x4<f64>| -> Vec<Vector3<f64>> {
                mesh.x_local
                    .iter()
                    .map(|x| sdrs::math::transform_point(p, x))
                    .collect()
            };
            let wa = world(&ma, &pa);
            let dist = |pb: &Matrix3x4<f64>| -> f64 {
                let wb = world(&mb, pb);
                let (mut ba, mut bb) = (PrimitiveBoxes::default(), PrimitiveBoxes::default());
                ba.build(&ma, &wa, None, 0.5);
                bb.build(&mb, &wb, None, 0.5);
                let mut c = Candidates::default();
                candidates(&ba, &bb, &mut c);
                PairGeometry {
                    mesh: [&ma, &mb],
                    world: [&wa, &wb],
                }
                .min_distance2(&c)
                .sqrt()
            };
            // (Crossing surfaces can have no close primitive pair: SDRS's
            // separation test decides intersection.)
            let mut sc0 = ContactScratch::new();
            let (mut lo, mut hi) = (0.0, 3.0);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                let p = pose(&rb, &(dir * mid));
                let hp = HullPose {
                    pose: &p,
                    x_local: &mb.x_local,
                };
                let ha = HullPose {
                    pose: &pa,
                    x_local: &ma.x_local,
                };
                let inter = matches!(
                    contact_pair(ha, hp, &params, None, Need::Value, &mut sc0),
                    Ok(PairOutcome::Intersecting)
                );
                if inter || dist(&p) < 0.5 * range {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            let pb = pose(&rb, &(dir * hi));
            let wb = world(&mb, &pb);
            // SDRS on the same vertices (hull vertices only, as IPC's mesh).
            let (ha, hb) = (
                HullPose {
                    pose: &pa,
                    x_local: &ma.x_local,
                },
                HullPose {
                    pose: &pb,
                    x_local: &mb.x_local,
                },
            );
            let mut sc = ContactScratch::new();
            ts.push(median_us(reps, || {
                let r =
                    contact_pair(ha, hb, &params, None, Need::Hessian, &mut sc).expect("contact");
                assert!(
                    matches!(r, PairOutcome::Separated(_)),
                    "SDRS pair not in contact: {r:?}"
                );
                black_box(r);
            }));
            // IPC: broad phase + all candidate primitives, pose-space Hessian.
            let (mut ba, mut bb, mut c) = (
                PrimitiveBoxes::default(),
                PrimitiveBoxes::default(),
                Candidates::default(),
            );
            let mut active = 0;
            ti.push(median_us(reps, || {
                ba.build(&ma, &wa, None, 0.5 * dhat);
                bb.build(&mb, &wb, None, 0.5 * dhat);
                candidates(&ba, &bb, &mut c);
                let e = evaluate_pair(
                    &PairGeometry {
                        mesh: [&ma, &mb],
                        world: [&wa, &wb],
                    },
                    &c,
                    dhat * dhat,
                    true,
                    true,
                );
                active = e.active;
                black_box(e);
            }));
            nc.push(c.len() as f64);
            na.push(active as f64);
            if out.is_some() {
                cases_json.push(format!(
                    "{{\"vertices\": {m}, \"dhat\": {dhat:e}, \"va\": {:?}, \"fa\": {:?}, \"vb\": {:?}, \"fb\": {:?}}}",
                    wa.iter().map(|v| [v.x, v.y, v.z]).collect::<Vec<_>>(),
                    ma.tris,
                    wb.iter().map(|v| [v.x, v.y, v.z]).collect::<Vec<_>>(),
                    mb.tris
                ));
            }
        }
        let med = |v: &mut Vec<f64>| {
            v.sort_by(|a, b| a.partial_cmp(b).unwrap());
            0.5 * (v[1] + v[2])
        };
        let (s, i) = (med(&mut ts), med(&mut ti));
        println!(
            "{m:>8} | {s:>10.1} | {i:>10.1} {:>8.0} {:>8.0} | {:>7.2}",
            med(&mut nc),
            med(&mut na),
            i / s
        );
    }
    if let Some(p) = out {
        std::fs::write(&p, format!("[{}]", cases_json.join(",\n"))).expect("write cases");
        println!("\ncases written to {p}");
    }
}
