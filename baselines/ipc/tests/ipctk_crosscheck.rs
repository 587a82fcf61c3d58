//! Cross-check against IPC Toolkit (`ipctk` 1.6.1 from the project's
//! `.venv`, see `tools/setup/setup_python.sh`) through `tools/check/ipctk_crosscheck.py`:
//!
//! - 400 random primitive stencils (200 point–triangle, 200 edge–edge, a
//!   quarter of those near-parallel so the mollifier acts): barrier potential
//!   value, gradient and exact Hessian ≤ 1e-9 relative;
//! - whole mesh pairs (random convex hulls, 16 and 64 vertices, at half of
//!   d̂): potential value and vertex gradient ≤ 1e-9 relative;
//! - 1200 random linear trajectories: whenever ipctk's CCD reports a hit, ours
//!   does too, no later (our ACCD may report extra hits: the conservative
//!   side);
//! - the smoothed friction `f₀`, `f₁` ≤ 1e-12;
//! - the lagged friction potential of whole mesh pairs (ipctk's
//!   `TangentialCollisions` and `FrictionPotential`), sliding and sticking:
//!   value and displacement gradient ≤ 1e-9 relative.

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sdrs_ipc::ccd::{AccdOptions, additive_ccd};
use sdrs_ipc::distance::vec::V3;
use sdrs_ipc::friction_stencil::{f0, f1};
use sdrs_ipc::mesh::LinkMesh;
use sdrs_ipc::mollifier::eps_x;
use sdrs_ipc::primitive::{Primitive, PrimitiveKind, evaluate, exact_hessian};
use serde_json::{Value, json};
use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

use crate::common;

const DHAT: f64 = 1e-3;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn ipctk(job: &Value) -> Value {
    let py = root().join(".venv/bin/python");
    assert!(
        py.exists(),
        "{} missing: run tools/setup/setup_python.sh (installs ipctk)",
        py.display()
    );
    let dir = std::env::temp_dir().join(format!("sdrs_ipctk_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let result = dir.join(format!("out_{}.json", job.to_string().len()));
    let mut child = Command::new(py)
        .arg(root().join("tools/check/ipctk_crosscheck.py"))
        .arg(&result)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(job.to_string().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "ipctk script failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&result).unwrap();
    let _ = std::fs::remove_file(&result);
    serde_json::from_str(&text).unwrap()
}

fn rv(rng: &mut ChaCha8Rng, s: f64) -> Vector3<f64> {
    Vector3::new(
        rng.random_range(-s..s),
        rng.random_range(-s..s),
        rng.random_range(-s..s),
    )
}
fn arr(v: Vector3<f64>) -> V3<f64> {
    [v.x, v.y, v.z]
}
fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}
fn rel(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt();
    let den: f64 = b.iter().map(|y| y * y).sum::<f64>().sqrt();
    num / den.max(1e-300)
}

/// A stencil inside the barrier zone: point–triangle with the point over
/// (or beside) the triangle, or two edges at angle `angle`.
fn stencil(rng: &mut ChaCha8Rng, pt: bool, angle: f64) -> [V3<f64>; 4] {
    loop {
        let x: [V3<f64>; 4] = if pt {
            let t: [Vector3<f64>; 3] = std::array::from_fn(|_| rv(rng, 2e-3));
            let n = (t[1] - t[0]).cross(&(t[2] - t[0])).normalize();
            let (b0, b1): (f64, f64) = (rng.random_range(-0.3..1.1), rng.random_range(-0.3..1.1));
            let p =
                t[0] * b0 + t[1] * b1 + t[2] * (1.0 - b0 - b1) + n * rng.random_range(-DHAT..DHAT);
            [arr(p), arr(t[0]), arr(t[1]), arr(t[2])]
        } else {
            let u = rv(rng, 1.0).normalize();
            let w = u.cross(&rv(rng, 1.0)).normalize();
            let v = u * angle.cos() + w * angle.sin();
            let n = u.cross(&w);
            let c = rv(rng, 2e-3);
            let (la, lb) = (rng.random_range(1e-3..4e-3), rng.random_range(1e-3..4e-3));
            let (s, t): (f64, f64) = (rng.random_range(-0.2..1.2), rng.random_range(-0.2..1.2));
            let a0 = c - u * (s * la);
            let b0 = c + n * rng.random_range(-DHAT..DHAT) - v * (t * lb);
            [arr(a0), arr(a0 + u * la), arr(b0), arr(b0 + v * lb)]
        };
        let kind = kind_of(pt, &x);
        let d = sdrs_ipc::primitive::stencil_distance(kind, &x).0;
        if d > 0.01 * DHAT * DHAT && d < 0.99 * DHAT * DHAT {
            return x;
        }
    }
}

fn kind_of(pt: bool, x: &[V3<f64>; 4]) -> PrimitiveKind {
    if pt {
        return PrimitiveKind::PointTriangle;
    }
    let l2 = |a: &V3<f64>, b: &V3<f64>| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>();
    PrimitiveKind::EdgeEdge {
        eps_x: eps_x(l2(&x[0], &x[1]), l2(&x[2], &x[3])),
    }
}

#[test]
fn primitives_friction_and_ccd_agree_with_ipctk() {
    if common::skip_without_venv() {
        return;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    let mut stencils = Vec::new();
    for k in 0..400 {
        let pt = k < 200;
        let angle = if k % 4 == 0 {
            rng.random_range(1e-3..3e-2)
        } else {
            rng.random_range(0.1..1.5)
        };
        stencils.push((pt, stencil(&mut rng, pt, angle)));
    }
    let mut traj = Vec::new();
    for k in 0..1200 {
        let pt = k % 2 == 0;
        let x0: [V3<f64>; 4] = std::array::from_fn(|_| arr(rv(&mut rng, 1.0)));
        let dx: [V3<f64>; 4] = std::array::from_fn(|_| arr(rv(&mut rng, 1.5)));
        traj.push((pt, x0, dx));
    }
    let ys: Vec<(f64, f64)> = (0..50)
        .map(|_| (rng.random_range(0.0..2e-5), 1e-5))
        .collect();
    let job = json!({
        "primitives": stencils.iter().map(|(pt, x)| json!({"kind": if *pt {"pt"} else {"ee"}, "x": x, "dhat": DHAT})).collect::<Vec<_>>(),
        "ccd": traj.iter().map(|(pt, x0, dx)| {
            let x1: [V3<f64>; 4] = std::array::from_fn(|i| std::array::from_fn(|c| x0[i][c] + dx[i][c]));
            json!({"kind": if *pt {"pt"} else {"ee"}, "x0": x0, "x1": x1})
        }).collect::<Vec<_>>(),
        "friction": ys,
    });
    let out = ipctk(&job);
    let (mut ev, mut eg, mut eh) = (0f64, 0f64, 0f64);
    for (k, (pt, x)) in stencils.iter().enumerate() {
        let r = &out["primitives"][k];
        let (v, g, h) = exact_hessian(kind_of(*pt, x), x, DHAT * DHAT).expect("active");
        ev = ev.max((v - r["value"].as_f64().unwrap()).abs() / r["value"].as_f64().unwrap().abs());
        eg = eg.max(rel(g.as_slice(), &nums(&r["grad"])));
        let theirs: Vec<f64> = r["hess"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(nums)
            .collect();
        // Row-major from Python; ours column-major: the Hessian is symmetric.
        eh = eh.max(rel(h.as_slice(), &theirs));
    }
    eprintln!(
        "ipctk primitives: value {ev:.1e}, gradient {eg:.1e}, Hessian {eh:.1e} (max relative)"
    );
    assert!(ev <= 1e-9 && eg <= 1e-9 && eh <= 1e-9);
    let (mut extra, mut agree) = (0, 0);
    for (k, (pt, x0, dx)) in traj.iter().enumerate() {
        let r = &out["ccd"][k];
        let kind = if *pt {
            PrimitiveKind::PointTriangle
        } else {
            PrimitiveKind::EdgeEdge { eps_x: 0.0 }
        };
        let ours = additive_ccd(
            kind,
            x0,
            dx,
            0.0,
            1.0,
            &AccdOptions {
                s: 0.1,
                max_iters: 1_000_000,
            },
        );
        let theirs = r["hit"].as_bool().unwrap();
        match (ours, theirs) {
            (Some(t), true) => {
                assert!(
                    t <= r["toi"].as_f64().unwrap() / 0.8 + 1e-9,
                    "trajectory {k}: our TOI {t} after ipctk's"
                );
                agree += 1;
            }
            (None, true) => panic!("trajectory {k}: ipctk finds a collision that ours misses"),
            (Some(_), false) => extra += 1,
            (None, false) => agree += 1,
        }
    }
    eprintln!(
        "CCD: {agree} of {} agree, {extra} conservative extra hits",
        traj.len()
    );
    assert!(
        extra * 20 <= traj.len(),
        "too many conservative hits: {extra}"
    );
    for (k, &(y, e)) in ys.iter().enumerate() {
        let r = &out["friction"][k];
        assert!((f0(y, e) - r["f0"].as_f64().unwrap()).abs() <= 1e-12 * e);
        assert!((f1(y, e) - r["f1"].as_f64().unwrap()).abs() <= 1e-12);
    }
}

fn hull_mesh(points: &[Vector3<f64>]) -> LinkMesh {
    let poly = sdrs::import::polytope::convex_hull(points).unwrap();
    let mut m = LinkMesh::default();
    m.add_closed(0, &poly.vertices, &poly.triangles).unwrap();
    m
}

/// Pairs of random convex hull meshes (16 or 64 points on a 0.5 m sphere),
/// the second translated along a random direction until the two are
/// `0.5 d̂` apart (bisection on parry's intersection test and our
/// primitive distances): `(mesh a, mesh b, b's world vertices)`.
fn meshes_half_dhat_apart(seed: u64, dhat: f64) -> Vec<(LinkMesh, LinkMesh, Vec<Vector3<f64>>)> {
    use parry3d_f64::math::{Pose as PPose, Vector as PVec};
    use parry3d_f64::shape::ConvexPolyhedron;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut pairs = Vec::new();
    for &n in &[16usize, 16, 64, 64] {
        let pts = |rng: &mut ChaCha8Rng| -> Vec<Vector3<f64>> {
            (0..n).map(|_| rv(rng, 1.0).normalize() * 0.5).collect()
        };
        let (ma, mb) = (hull_mesh(&pts(&mut rng)), hull_mesh(&pts(&mut rng)));
        let dir = rv(&mut rng, 1.0).normalize();
        let cvx = |v: &[Vector3<f64>]| {
            ConvexPolyhedron::from_convex_hull(
                &v.iter()
                    .map(|p| PVec::new(p.x, p.y, p.z))
                    .collect::<Vec<_>>(),
            )
            .unwrap()
        };
        let (mut lo, mut hi) = (0.0, 2.0);
        let mut wb: Vec<Vector3<f64>>;
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            wb = mb.x_local.iter().map(|x| x + dir * mid).collect::<Vec<_>>();
            let inter = parry3d_f64::query::intersection_test(
                &PPose::IDENTITY,
                &cvx(&ma.x_local),
                &PPose::IDENTITY,
                &cvx(&wb),
            )
            .unwrap()
            .intersecting;
            let (mut ba, mut bb, mut c) = Default::default();
            sdrs_ipc::broad_phase::PrimitiveBoxes::build(&mut ba, &ma, &ma.x_local, None, 1.0);
            sdrs_ipc::broad_phase::PrimitiveBoxes::build(&mut bb, &mb, &wb, None, 1.0);
            sdrs_ipc::broad_phase::candidates(&ba, &bb, &mut c);
            let d = sdrs_ipc::pair::PairGeometry {
                mesh: [&ma, &mb],
                world: [&ma.x_local, &wb],
            }
            .min_distance2(&c)
            .sqrt();
            if inter || d < 0.5 * dhat {
                lo = mid
            } else {
                hi = mid
            }
        }
        wb = mb.x_local.iter().map(|x| x + dir * hi).collect();
        pairs.push((ma, mb, wb));
    }
    pairs
}

/// Adds a stencil's 12-vector `g` (x, y, z per stencil point) into the
/// pair's vertex gradient: mesh a's vertices first, then mesh b's (`na` of
/// a's).
fn scatter(grad: &mut [f64], ids: &[(usize, u32); 4], g: &[f64], na: usize) {
    for (k, (side, i)) in ids.iter().enumerate() {
        let row = 3 * *i as usize + if *side == 1 { 3 * na } else { 0 };
        for c in 0..3 {
            grad[row + c] += g[3 * k + c];
        }
    }
}

#[test]
fn whole_mesh_pair_potential_and_gradient_agree_with_ipctk() {
    if common::skip_without_venv() {
        return;
    }
    let dhat = 0.02;
    let mut jobs = Vec::new();
    let mut ours = Vec::new();
    for (ma, mb, wb) in meshes_half_dhat_apart(78, dhat) {
        // Our potential in vertex space (sum over candidate stencils).
        let (mut ba, mut bb, mut c) = Default::default();
        sdrs_ipc::broad_phase::PrimitiveBoxes::build(&mut ba, &ma, &ma.x_local, None, 0.5 * dhat);
        sdrs_ipc::broad_phase::PrimitiveBoxes::build(&mut bb, &mb, &wb, None, 0.5 * dhat);
        sdrs_ipc::broad_phase::candidates(&ba, &bb, &mut c);
        let geo = sdrs_ipc::pair::PairGeometry {
            mesh: [&ma, &mb],
            world: [&ma.x_local, &wb],
        };
        let na = ma.x_local.len();
        let mut grad = vec![0.0; 3 * (na + wb.len())];
        let mut value = 0.0;
        geo.for_each_stencil(&c, |kind, ids| {
            let x = ids.map(|(s, i)| arr(geo.world[s][i as usize]));
            if let Primitive::Active(e) = evaluate(kind, &x, dhat * dhat, true) {
                value += e.value;
                scatter(&mut grad, &ids, e.grad.as_slice(), na);
            }
        });
        assert!(value > 0.0, "the pair must be in contact");
        ours.push((value, grad));
        let v = |w: &[Vector3<f64>]| w.iter().map(|p| [p.x, p.y, p.z]).collect::<Vec<_>>();
        jobs.push(
            json!({"va": v(&ma.x_local), "fa": ma.tris, "vb": v(&wb), "fb": mb.tris, "dhat": dhat}),
        );
    }
    let out = ipctk(&json!({"meshes": jobs}));
    for (k, (value, grad)) in ours.iter().enumerate() {
        let r = &out["meshes"][k];
        let tv = r["value"].as_f64().unwrap();
        // ipctk returns the gradient with x, y, z interleaved per vertex, as ours.
        let eg = rel(grad, &nums(&r["grad"]));
        let ev = (value - tv).abs() / tv;
        eprintln!(
            "mesh pair {k}: value {value:.6e} vs ipctk {tv:.6e} ({} collisions): value {ev:.1e}, gradient {eg:.1e}",
            r["collisions"]
        );
        assert!(ev <= 1e-9 && eg <= 1e-9);
    }
}

/// IPC's lagged friction on whole mesh pairs against ipctk's
/// `TangentialCollisions` + `FrictionPotential`: lagged at the pair
/// `0.5 d̂` apart (normal forces `λ = κ |b'(d)| 2√d`, closest-point weights
/// and tangent bases there), evaluated on a displacement `u` of mesh b over
/// the step, `D = Σ_c μ λ_c f₀(‖T_cᵀ Σ_k w_ck u_k‖; ε)`. Value and
/// gradient w.r.t. the displacements ≤ 1e-9 relative, with displacements
/// both above `ε` (sliding) and below it (the smoothed sticking branch).
#[test]
fn whole_mesh_pair_friction_agrees_with_ipctk() {
    if common::skip_without_venv() {
        return;
    }
    use sdrs_ipc::friction::{IpcFrictionParams, lag_pair};
    let (dhat, kappa, mu, eps) = (0.02, 1e3, 0.4, 1e-4);
    let params = IpcFrictionParams {
        dhat,
        kappa,
        mu,
        eps_v: eps,
        dt: 1.0,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(79);
    let mut jobs = Vec::new();
    let mut ours = Vec::new();
    for (k, (ma, mb, wb)) in meshes_half_dhat_apart(78, dhat).into_iter().enumerate() {
        let (mut ba, mut bb, mut c) = Default::default();
        sdrs_ipc::broad_phase::PrimitiveBoxes::build(&mut ba, &ma, &ma.x_local, None, 0.5 * dhat);
        sdrs_ipc::broad_phase::PrimitiveBoxes::build(&mut bb, &mb, &wb, None, 0.5 * dhat);
        sdrs_ipc::broad_phase::candidates(&ba, &bb, &mut c);
        let geo = sdrs_ipc::pair::PairGeometry {
            mesh: [&ma, &mb],
            world: [&ma.x_local, &wb],
        };
        let mut lagged = Vec::new();
        lag_pair(&geo, &c, &params, &mut lagged);
        assert!(!lagged.is_empty(), "pair {k} must have friction contacts");
        // Even pairs slide (|u| ≈ 1e-3 ≫ ε), odd ones stick (|u| ≈ 3e-5 < ε).
        let scale = if k % 2 == 0 { 1e-3 } else { 3e-5 };
        let ub: Vec<Vector3<f64>> = wb.iter().map(|_| rv(&mut rng, scale)).collect();
        let na = ma.x_local.len();
        let mut grad = vec![0.0; 3 * (na + wb.len())];
        let mut value = 0.0;
        for (ids, stencil) in &lagged {
            let dx = ids.map(|(s, i)| {
                if s == 1 {
                    ub[i as usize]
                } else {
                    Vector3::zeros()
                }
            });
            let (v, g, _) = stencil.evaluate(&dx, eps, true);
            value += v;
            scatter(&mut grad, ids, g.as_slice(), na);
        }
        ours.push((value, grad, lagged.len()));
        let v = |w: &[Vector3<f64>]| w.iter().map(|p| [p.x, p.y, p.z]).collect::<Vec<_>>();
        jobs.push(json!({
            "va": v(&ma.x_local), "fa": ma.tris, "vb": v(&wb), "fb": mb.tris,
            "ua": vec![[0.0; 3]; na], "ub": v(&ub),
            "dhat": dhat, "kappa": kappa, "mu": mu, "eps": eps,
        }));
    }
    let out = ipctk(&json!({ "friction_meshes": jobs }));
    for (k, (value, grad, n)) in ours.iter().enumerate() {
        let r = &out["friction_meshes"][k];
        let tv = r["value"].as_f64().unwrap();
        let eg = rel(grad, &nums(&r["grad"]));
        let ev = (value - tv).abs() / tv.abs();
        eprintln!(
            "friction pair {k}: D {value:.6e} vs ipctk {tv:.6e} ({n} stencils, ipctk {} contacts): value {ev:.1e}, gradient {eg:.1e}",
            r["collisions"]
        );
        assert!(tv > 0.0);
        assert!(ev <= 1e-9 && eg <= 1e-9);
    }
}
