//! Side-by-side cost of one contact-potential evaluation (value + gradient +
//! Hessian, pose space) of SDRS `U_c` and the IPC baseline on the same pair
//! of random convex hulls (points on spheres of radius 0.5 m), placed so
//! that the IPC mesh distance is half the interaction range of both models
//! (SDRS: `2s/(1−s)`; IPC: `d̂` set to that same range): both see a contact
//! of the same depth into their barrier zone (the paper's Fig. "cost-time").
//!
//! IPC's cost includes its primitive broad phase; the SDRS figure includes
//! its separation test. Used by `cli/examples/bench_potential.rs` and by
//! `sdrs compare` (benchmark code lives with the application, not in the
//! baseline's library).

use nalgebra::{Matrix3x4, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sdrs::contact::{ContactParams, ContactScratch, HullPose, Need, PairOutcome, contact_pair};
use sdrs::geometry::sampling::{pose, random_rotation, sphere_points};
use sdrs_ipc::broad_phase::{Candidates, PrimitiveBoxes, candidates};
use sdrs_ipc::mesh::LinkMesh;
use sdrs_ipc::pair::{PairGeometry, evaluate_pair};
use std::hint::black_box;
use std::time::Instant;

/// Why a benchmark case could not be built or measured.
#[derive(Debug, Clone, thiserror::Error)]
pub enum BenchError {
    #[error("{vertices} vertices: cannot build the hull mesh: {msg}")]
    Mesh { vertices: usize, msg: String },
    #[error("{vertices} vertices: SDRS contact evaluation failed: {msg}")]
    Contact { vertices: usize, msg: String },
    #[error("{vertices} vertices: the SDRS pair is not in its barrier zone ({outcome})")]
    NotInContact { vertices: usize, outcome: String },
}

/// One random hull pair at half the interaction range.
#[derive(Clone, Debug)]
pub struct PotentialCase {
    /// Vertices per hull.
    pub vertices: usize,
    pub mesh: [LinkMesh; 2],
    pub pose: [Matrix3x4<f64>; 2],
    /// World vertices of each mesh at `pose`.
    pub world: [Vec<Vector3<f64>>; 2],
    /// IPC activation distance d̂ (m) = the SDRS support distance.
    pub dhat: f64,
}

impl PotentialCase {
    /// The two hulls at their poses, as SDRS's pair functions take them.
    pub fn hull_poses(&self) -> [HullPose<'_>; 2] {
        [0, 1].map(|k| HullPose {
            pose: &self.pose[k],
            x_local: &self.mesh[k].x_local,
        })
    }
}

/// One measured case.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct PotentialTiming {
    pub vertices: usize,
    /// Median µs of one SDRS `U_c` value + gradient + Hessian.
    pub sdrs_us: f64,
    /// Median µs of one IPC evaluation (broad phase + every candidate).
    pub ipc_us: f64,
    /// IPC primitive candidates after the broad phase.
    pub candidates: usize,
    /// IPC stencils inside `d̂`.
    pub active: usize,
    /// SDRS and IPC potential values (J, with unit stiffness), for the record.
    pub sdrs_value: f64,
    pub ipc_value: f64,
}

fn mesh_of(points: &[Vector3<f64>]) -> Result<LinkMesh, BenchError> {
    let bad = |msg: String| BenchError::Mesh {
        vertices: points.len(),
        msg,
    };
    let poly = sdrs::import::polytope::convex_hull(points).map_err(|e| bad(e.to_string()))?;
    let mut m = LinkMesh::default();
    m.add_closed(0, &poly.vertices, &poly.triangles)
        .map_err(|e| bad(e.to_string()))?;
    m.radius = m.x_local.iter().map(|x| x.norm()).fold(0.0, f64::max);
    Ok(m)
}

fn world(mesh: &LinkMesh, p: &Matrix3x4<f64>) -> Vec<Vector3<f64>> {
    mesh.x_local
        .iter()
        .map(|x| sdrs::math::transform_point(p, x))
        .collect()
}

/// The IPC mesh distance of two hulls (every primitive pair of the 0.5 m
/// test hulls), for the tests.
#[cfg(test)]
fn ipc_distance(mesh: [&LinkMesh; 2], world: [&Vec<Vector3<f64>>; 2]) -> f64 {
    ipc_distance_within(mesh, world, 0.5)
}

/// The IPC mesh distance over the primitive pairs whose boxes, each padded
/// by `pad`, meet: every pair closer than `pad` is among them, so the
/// result is the mesh distance whenever that is below `pad`, and `≥ pad`
/// otherwise. [`potential_cases`]' bisection asks only whether the distance
/// is below half the range: with that padding it gets the same answers as
/// with [`ipc_distance`]'s 0.5 m (every pair of the 0.5 m test hulls), at
/// a fraction of the pairs (the quick suite's eight cases: 12.2 s → under
/// 0.2 s; the same cases, bit for bit).
fn ipc_distance_within(mesh: [&LinkMesh; 2], world: [&Vec<Vector3<f64>>; 2], pad: f64) -> f64 {
    let (mut ba, mut bb) = (PrimitiveBoxes::default(), PrimitiveBoxes::default());
    ba.build(mesh[0], world[0], None, pad);
    bb.build(mesh[1], world[1], None, pad);
    let mut c = Candidates::default();
    candidates(&ba, &bb, &mut c);
    PairGeometry {
        mesh,
        world: [world[0], world[1]],
    }
    .min_distance2(&c)
    .sqrt()
}

/// `per_size` random cases for each vertex count in `sizes` (seeded: the
/// same seed gives the same cases).
pub fn potential_cases(
    sizes: &[usize],
    per_size: usize,
    seed: u64,
    params: &ContactParams,
) -> Result<Vec<PotentialCase>, BenchError> {
    let range = params.support_distance();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    for &m in sizes {
        for _ in 0..per_size {
            let la = sphere_points(&mut rng, m, 0.5);
            let lb = sphere_points(&mut rng, m, 0.5);
            let pa = pose(&random_rotation(&mut rng), &Vector3::zeros());
            let dir = random_rotation(&mut rng) * Vector3::z();
            let rb = random_rotation(&mut rng);
            let ma = mesh_of(&la)?;
            let mb = mesh_of(&lb)?;
            let wa = world(&ma, &pa);
            // Bisection on the translation for an IPC mesh distance of half
            // the range (crossing surfaces can have no close primitive pair:
            // SDRS's separation test decides intersection).
            let mut sc = ContactScratch::new();
            let (mut lo, mut hi) = (0.0, 3.0);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                let p = pose(&rb, &(dir * mid));
                let inter = matches!(
                    contact_pair(
                        HullPose {
                            pose: &pa,
                            x_local: &ma.x_local
                        },
                        HullPose {
                            pose: &p,
                            x_local: &mb.x_local
                        },
                        params,
                        None,
                        Need::Value,
                        &mut sc
                    ),
                    Ok(PairOutcome::Intersecting)
                );
                let wb = world(&mb, &p);
                let half = 0.5 * range;
                if inter || ipc_distance_within([&ma, &mb], [&wa, &wb], half) < half {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            let pb = pose(&rb, &(dir * hi));
            let wb = world(&mb, &pb);
            out.push(PotentialCase {
                vertices: m,
                mesh: [ma, mb],
                pose: [pa, pb],
                world: [wa, wb],
                dhat: range,
            });
        }
    }
    Ok(out)
}

/// Median of `reps` timings (µs) of `f`, after one warm-up call.
pub fn median_us(reps: usize, mut f: impl FnMut()) -> f64 {
    f();
    let mut t: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// Times one case: SDRS and IPC interleaved in the same call, so that both
/// see the same machine load.
pub fn time_case(
    case: &PotentialCase,
    params: &ContactParams,
    reps: usize,
) -> Result<PotentialTiming, BenchError> {
    let m = case.vertices;
    let [ha, hb] = case.hull_poses();
    let mut sc = ContactScratch::new();
    let first = contact_pair(ha, hb, params, None, Need::Hessian, &mut sc).map_err(|e| {
        BenchError::Contact {
            vertices: m,
            msg: e.to_string(),
        }
    })?;
    if !matches!(first, PairOutcome::Separated(_)) {
        return Err(BenchError::NotInContact {
            vertices: m,
            outcome: format!("{first:?}"),
        });
    }
    let sdrs_value = first.value();
    let dhat = case.dhat;
    let (mut ba, mut bb, mut c) = (
        PrimitiveBoxes::default(),
        PrimitiveBoxes::default(),
        Candidates::default(),
    );
    let mut eval_ipc = |c: &mut Candidates| {
        ba.build(&case.mesh[0], &case.world[0], None, 0.5 * dhat);
        bb.build(&case.mesh[1], &case.world[1], None, 0.5 * dhat);
        candidates(&ba, &bb, c);
        evaluate_pair(
            &PairGeometry {
                mesh: [&case.mesh[0], &case.mesh[1]],
                world: [&case.world[0], &case.world[1]],
            },
            c,
            dhat * dhat,
            true,
            true,
            true,
        )
    };
    let e = eval_ipc(&mut c);
    let (ipc_value, active) = (e.value, e.active);
    // Interleave: half the repetitions each, twice.
    let half = reps.div_ceil(2);
    let mut ts = Vec::new();
    let mut ti = Vec::new();
    for _ in 0..2 {
        ts.push(median_us(half, || {
            black_box(contact_pair(ha, hb, params, None, Need::Hessian, &mut sc).ok());
        }));
        ti.push(median_us(half, || {
            black_box(eval_ipc(&mut c));
        }));
    }
    Ok(PotentialTiming {
        vertices: m,
        sdrs_us: ts.iter().copied().fold(f64::INFINITY, f64::min),
        ipc_us: ti.iter().copied().fold(f64::INFINITY, f64::min),
        candidates: c.len(),
        active,
        sdrs_value,
        ipc_value,
    })
}

/// One measured friction case.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct FrictionTiming {
    pub vertices: usize,
    /// Median µs of one SDRS `U_f` value + gradient + Hessian.
    pub sdrs_us: f64,
    /// Median µs of one IPC lagged-friction value + gradient + Hessian over
    /// the pair's lagged stencils.
    pub ipc_us: f64,
    /// IPC lagged contacts (stencils inside `d̂` at step `t`).
    pub ipc_contacts: usize,
    pub sdrs_value: f64,
    pub ipc_value: f64,
}

/// Times the friction potentials of a case: both models lag their contact
/// data at the case's poses (step `t`, not timed: once per time step in a
/// simulation), then hull `b` slides 1 mm along a tangent of the SDRS
/// contact normal and turns 0.01 rad about it (step `t+1`), where the
/// value, gradient and Hessian are timed, interleaved. `μ = 0.5`,
/// `Δt = 0.01 s`, unit stiffness; IPC's `ε_v` is SDRS's `ε_v` (m/s).
pub fn time_friction_case(
    case: &PotentialCase,
    params: &ContactParams,
    reps: usize,
) -> Result<FrictionTiming, BenchError> {
    use sdrs::contact::{
        FrictionNeed, FrictionParams, FrictionScratch, LaggedContact, friction_pair,
    };
    use sdrs_ipc::friction::{IpcFrictionParams, evaluate_pair_friction, lag_pair};
    use sdrs_ipc::pair::PairHessian;
    let m = case.vertices;
    let [ha, hb] = case.hull_poses();
    let mut sc = ContactScratch::new();
    let pair = match contact_pair(ha, hb, params, None, Need::Gradient, &mut sc) {
        Ok(PairOutcome::Separated(p)) => p,
        other => {
            return Err(BenchError::NotInContact {
                vertices: m,
                outcome: format!("{other:?}"),
            });
        }
    };
    let fp = FrictionParams::new(0.5, 0.01);
    let lag = LaggedContact::from_contact(&pair, ha, hb, params, 1.0);
    // Step t+1: slide along the first tangent and turn about the normal.
    let n = lag.normal;
    let t = lag.basis.column(0).into_owned();
    let turn = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(n), 0.01);
    let mut pb_next = case.pose[1];
    let r_next = turn.matrix() * case.pose[1].fixed_view::<3, 3>(0, 0);
    pb_next.fixed_view_mut::<3, 3>(0, 0).copy_from(&r_next);
    let c_next = case.pose[1].column(3) + 1e-3 * t;
    pb_next.set_column(3, &c_next);
    let hb_next = HullPose {
        pose: &pb_next,
        x_local: &case.mesh[1].x_local,
    };
    let mut fs = FrictionScratch::new();
    let sdrs_eval = |fs: &mut FrictionScratch| {
        friction_pair(&lag.frame(), ha, hb_next, &fp, FrictionNeed::Hessian, fs)
    };
    let first = sdrs_eval(&mut fs).map_err(|e| BenchError::Contact {
        vertices: m,
        msg: e.to_string(),
    })?;
    // IPC: lagged stencils at step t, evaluated at t+1.
    let ip = IpcFrictionParams {
        dhat: case.dhat,
        kappa: 1.0,
        mu: fp.mu,
        eps_v: fp.eps_velocity,
        dt: fp.dt,
    };
    let (mut ba, mut bb, mut c) = (
        PrimitiveBoxes::default(),
        PrimitiveBoxes::default(),
        Candidates::default(),
    );
    ba.build(&case.mesh[0], &case.world[0], None, 0.5 * case.dhat);
    bb.build(&case.mesh[1], &case.world[1], None, 0.5 * case.dhat);
    candidates(&ba, &bb, &mut c);
    let mut lagged = Vec::new();
    lag_pair(
        &PairGeometry {
            mesh: [&case.mesh[0], &case.mesh[1]],
            world: [&case.world[0], &case.world[1]],
        },
        &c,
        &ip,
        &mut lagged,
    );
    let world_next_b = world(&case.mesh[1], &pb_next);
    let mut hess = Box::new(PairHessian::zeros());
    let ipc_eval = |hess: &mut PairHessian| {
        let (mut ga, mut gb) = (Matrix3x4::zeros(), Matrix3x4::zeros());
        hess.fill(0.0);
        let v = evaluate_pair_friction(
            lagged.iter().map(|(i, s)| (i, s)),
            [&case.mesh[0], &case.mesh[1]],
            [&case.world[0], &case.world[1]],
            [&case.world[0], &world_next_b],
            ip.eps_v * ip.dt,
            true,
            (&mut ga, &mut gb),
            Some(hess),
        );
        black_box((ga, gb));
        v
    };
    let ipc_value = ipc_eval(&mut hess);
    let half = reps.div_ceil(2);
    let (mut ts, mut ti) = (Vec::new(), Vec::new());
    for _ in 0..2 {
        ts.push(median_us(half, || {
            black_box(sdrs_eval(&mut fs).ok());
        }));
        ti.push(median_us(half, || {
            black_box(ipc_eval(&mut hess));
        }));
    }
    Ok(FrictionTiming {
        vertices: m,
        sdrs_us: ts.iter().copied().fold(f64::INFINITY, f64::min),
        ipc_us: ti.iter().copied().fold(f64::INFINITY, f64::min),
        ipc_contacts: lagged.len(),
        sdrs_value: first.value,
        ipc_value,
    })
}

/// Median over the values of one vertex count.
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The cases as JSON for `tools/bench/bench_ipctk.py`: world vertices and
/// triangles of both hulls and `d̂`.
pub fn cases_json(cases: &[PotentialCase]) -> String {
    let pts = |w: &[Vector3<f64>]| w.iter().map(|v| [v.x, v.y, v.z]).collect::<Vec<_>>();
    let v: Vec<serde_json::Value> = cases
        .iter()
        .map(|c| {
            serde_json::json!({
                "vertices": c.vertices, "dhat": c.dhat,
                "va": pts(&c.world[0]), "fa": c.mesh[0].tris,
                "vb": pts(&c.world[1]), "fb": c.mesh[1].tris,
            })
        })
        .collect();
    serde_json::Value::Array(v).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cases_sit_at_half_the_range_and_both_models_see_contact() {
        let params = ContactParams::default();
        let cases = potential_cases(&[8, 64], 2, 3, &params).unwrap();
        assert_eq!(cases.len(), 4);
        for c in &cases {
            let d = ipc_distance([&c.mesh[0], &c.mesh[1]], [&c.world[0], &c.world[1]]);
            assert!(
                (d - 0.5 * c.dhat).abs() < 1e-6 * c.dhat,
                "distance {d} vs half range {}",
                0.5 * c.dhat
            );
            let t = time_case(c, &params, 3).unwrap();
            assert!(t.sdrs_value > 0.0 && t.ipc_value > 0.0, "{t:?}");
            assert!(t.active >= 1 && t.candidates >= t.active, "{t:?}");
            assert!(t.sdrs_us > 0.0 && t.ipc_us > 0.0);
        }
        // Friction: both models see a sliding contact with positive dissipation.
        for c in &cases {
            let f = time_friction_case(c, &params, 3).unwrap();
            assert!(f.sdrs_value > 0.0 && f.ipc_value > 0.0, "{f:?}");
            assert!(f.ipc_contacts >= 1);
        }
        // Seeded: the same cases again.
        let again = potential_cases(&[8, 64], 2, 3, &params).unwrap();
        assert_eq!(again[3].world[1], cases[3].world[1]);
    }
}
