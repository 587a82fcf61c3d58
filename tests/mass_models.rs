//! Mass models (`crate::model::mass`): the `solid` model's mass, centre of
//! mass and inertia against trimesh (tools/check/check_mass_trimesh.py through the
//! project venv), its vertex derivatives against finite differences
//! (including a vertex moving from inside a hull through a face), and the
//! `given` model against the scene's inertial.

use crate::import_support;

use import_support::{run_tool, temp_dir};
use nalgebra::{Matrix4, Vector3, Vector4};
use rand::{RngExt, SeedableRng};
use sdrs::model::Inertial;
use sdrs::model::mass::{solid_second_moment, solid_second_moment_vjp, solid_triangles};
use sdrs::scene::Scene;
use std::path::Path;

/// Random point clouds: 4–40 points in a random ellipsoid-ish blob, shifted
/// away from the origin (so the shift of the integrals is exercised).
fn random_hulls(n: usize, seed: u64) -> Vec<Vec<Vector3<f64>>> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let k = rng.random_range(4..40);
            let scale = Vector3::new(
                rng.random_range(0.05..1.0),
                rng.random_range(0.05..1.0),
                rng.random_range(0.05..1.0),
            );
            let centre = Vector3::new(
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
            );
            (0..k)
                .map(|_| {
                    let u = Vector3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    );
                    centre + u.component_mul(&scale)
                })
                .collect()
        })
        .collect()
}

fn moment(x: &[Vector3<f64>], density: f64) -> Matrix4<f64> {
    let tris = solid_triangles(x).unwrap();
    solid_second_moment(x, &tris, density)
}

#[test]
fn solid_mass_properties_match_trimesh() {
    if import_support::skip_without_venv() {
        return;
    }
    let hulls = random_hulls(30, 11);
    let densities: Vec<f64> = (0..hulls.len()).map(|i| 500.0 + 97.0 * i as f64).collect();
    let spec = serde_json::json!({
        "hulls": hulls.iter().zip(&densities).map(|(h, d)| serde_json::json!({
            "vertices": h.iter().map(|v| [v.x, v.y, v.z]).collect::<Vec<_>>(),
            "density": d,
        })).collect::<Vec<_>>()
    });
    let dir = temp_dir("mass-trimesh");
    let json = dir.join("hulls.json");
    std::fs::write(&json, spec.to_string()).unwrap();
    let (ok, out, err) = run_tool("check_mass_trimesh.py", &[Path::new(&json)]);
    assert!(ok, "trimesh helper failed: {err}");
    let theirs: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    let mut worst: f64 = 0.0;
    for (i, (h, d)) in hulls.iter().zip(&densities).enumerate() {
        let ours = Inertial::from_second_moment(&moment(h, *d));
        let t = &theirs["hulls"][i];
        let f = |v: &serde_json::Value| v.as_f64().unwrap();
        let mass = f(&t["mass"]);
        let com = Vector3::new(f(&t["com"][0]), f(&t["com"][1]), f(&t["com"][2]));
        let inertia = nalgebra::Matrix3::from_fn(|r, c| f(&t["inertia"][r][c]));
        let size = h
            .iter()
            .flat_map(|a| h.iter().map(move |b| (a - b).norm()))
            .fold(0.0, f64::max);
        // Relative to the quantity's magnitude (COM: to the hull's size, as
        // it may lie near the origin; inertia: to the tensor's norm).
        let e_mass = (ours.mass - mass).abs() / mass;
        let e_com = (ours.com - com).norm() / size;
        let e_inertia = (ours.inertia - inertia).norm() / inertia.norm();
        worst = worst.max(e_mass).max(e_com).max(e_inertia);
        assert!(
            e_mass <= 1e-10 && e_com <= 1e-10 && e_inertia <= 1e-10,
            "hull {i}: mass {e_mass:.2e}, com {e_com:.2e}, inertia {e_inertia:.2e}"
        );
    }
    eprintln!("solid vs trimesh: worst relative error {worst:.2e} over 30 hulls");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `f(x) = ⟨W, M(x)⟩` with the triangulation recomputed (as the design
/// loop's `refresh_moments` does).
fn pairing(w: &Matrix4<f64>, x: &[Vector3<f64>], density: f64) -> f64 {
    w.component_mul(&moment(x, density)).sum()
}

fn analytic(w: &Matrix4<f64>, x: &[Vector3<f64>], density: f64) -> Vec<Vector3<f64>> {
    let tris = solid_triangles(x).unwrap();
    let mut g = vec![Vector3::zeros(); x.len()];
    solid_second_moment_vjp(x, &tris, density, w, &mut g);
    g
}

fn random_cotangent(seed: u64) -> Matrix4<f64> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    Matrix4::from_fn(|_, _| rng.random_range(-1.0..1.0))
}

#[test]
fn solid_vertex_derivatives_match_finite_differences() {
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    for (n, x) in random_hulls(12, 5).into_iter().enumerate() {
        let w = random_cotangent(100 + n as u64);
        let density = 800.0;
        let g = analytic(&w, &x, density);
        let scale = g.iter().map(|v| v.amax()).fold(0.0, f64::max);
        for m in 0..x.len() {
            for e in 0..3 {
                let mut p = x.clone();
                p[m][e] += h;
                let mut q = x.clone();
                q[m][e] -= h;
                let fd = (pairing(&w, &p, density) - pairing(&w, &q, density)) / (2.0 * h);
                let err = (fd - g[m][e]).abs() / scale;
                worst = worst.max(err);
                assert!(
                    err <= 1e-6,
                    "hull {n} vertex {m}.{e}: {} vs FD {fd}",
                    g[m][e]
                );
            }
        }
    }
    eprintln!("solid vertex derivatives vs FD: worst {worst:.2e}");
}

#[test]
fn a_vertex_moving_from_inside_through_a_face_has_the_right_derivative() {
    // Cube [−1, 1]³ and a ninth vertex p(t) = (t, 0.3, 0.2): inside for
    // t < 1, on the face x = 1 at t = 1, outside beyond (a pyramid over the
    // face of height t − 1 joins the solid).
    let cube = sdrs::model::Hull::cuboid(Vector3::repeat(2.0), Vector3::zeros());
    let with = |t: f64| {
        let mut x = cube.clone();
        x.push(Vector3::new(t, 0.3, 0.2));
        x
    };
    let w = random_cotangent(7);
    let rho = 3.0;
    let f = |t: f64| pairing(&w, &with(t), rho);
    let d = |t: f64| analytic(&w, &with(t), rho)[8].x;
    let h = 1e-6;
    // Inside: no influence at all.
    assert_eq!(d(0.5), 0.0);
    assert!((f(0.5 + h) - f(0.5 - h)).abs() < 1e-12);
    // Outside: the derivative matches central differences.
    for t in [1.001, 1.05, 1.3] {
        let fd = (f(t + h) - f(t - h)) / (2.0 * h);
        assert!(
            (d(t) - fd).abs() <= 1e-6 * fd.abs().max(1.0),
            "t = {t}: {} vs {fd}",
            d(t)
        );
    }
    // On the face: continuous; the reported derivative is the inside one
    // (zero) and the outside one-sided difference tends to the outside
    // derivative (the kink of a vertex joining the surface).
    assert_eq!(d(1.0), 0.0);
    assert!((f(1.0) - f(0.999)).abs() < 1e-12);
    let hs = 1e-7;
    let right = (f(1.0 + hs) - f(1.0)) / hs;
    assert!(
        (right - d(1.0 + hs)).abs() <= 1e-6 * right.abs().max(1.0),
        "{right} vs {}",
        d(1.0 + hs)
    );
    let left = (f(1.0) - f(1.0 - hs)) / hs;
    assert!(left.abs() < 1e-6, "{left}");
    // The volume's outward derivative is the face area over 3.
    let vol = |t: f64| moment(&with(t), 1.0)[(3, 3)];
    assert!(((vol(1.0 + hs) - vol(1.0)) / hs - 4.0 / 3.0).abs() < 1e-6);
}

const LINK: &str = r#"
dt: 0.01
robots:
  - name: r
    links:
      - name: body
        joint: {type: free}
        MASS
        hulls: [{box: {size: [0.2, 0.4, 0.6], center: [0.1, 0, 0]}}, {vertices: [[0,0,0],[0.3,0,0],[0,0.3,0],[0,0,0.3]]}]
"#;

fn link_moment(mass: &str) -> Result<Matrix4<f64>, String> {
    Scene::from_str(&LINK.replace("MASS", mass), Path::new("mass.yaml"))
        .map(|s| s.model.second_moment[0])
        .map_err(|e| e.to_string())
}

#[test]
fn scene_mass_models_set_the_links_moments() {
    // Solid by density: the sum of the hulls' solids (superposed).
    let box_m = moment(
        &sdrs::model::Hull::cuboid(Vector3::new(0.2, 0.4, 0.6), Vector3::new(0.1, 0.0, 0.0)),
        1000.0,
    );
    let tet = [
        Vector3::zeros(),
        Vector3::new(0.3, 0.0, 0.0),
        Vector3::new(0.0, 0.3, 0.0),
        Vector3::new(0.0, 0.0, 0.3),
    ];
    let tet_m = moment(&tet, 1000.0);
    let m = link_moment("mass_model: {type: solid, density: 1000}").unwrap();
    assert!((m - box_m - tet_m).norm() < 1e-12 * m.norm());
    // Solid by mass: density = mass / total volume.
    let m = link_moment("mass: 7.0\n        mass_model: {type: solid}").unwrap();
    assert!((m[(3, 3)] - 7.0).abs() < 1e-12);
    // Given: exactly the inertial.
    let m = link_moment(
        "mass_model: {type: given, mass: 2.0, com: [0.1, 0.2, -0.1], inertia: [0.3, 0.01, 0.0, 0.2, -0.02, 0.25]}",
    )
    .unwrap();
    let i = Inertial::from_second_moment(&m);
    assert!((i.mass - 2.0).abs() < 1e-15);
    assert!((i.com - Vector3::new(0.1, 0.2, -0.1)).norm() < 1e-15);
    assert!((i.inertia[(1, 2)] + 0.02).abs() < 1e-15 && (i.inertia[(0, 0)] - 0.3).abs() < 1e-15);
    // Default: vertices, unchanged.
    let m = link_moment("mass: 1.2").unwrap();
    assert!((m.column(3) - Vector4::new(m[(0, 3)], m[(1, 3)], m[(2, 3)], 1.2)).norm() < 1e-15);
    // Bad input names the element.
    for (text, want) in [
        ("mass_model: {type: solid}", "needs `mass`"),
        (
            "mass: 1\n        mass_model: {type: solid, density: 5}",
            "not both",
        ),
        (
            "mass_model: {type: solid, density: -5}",
            "density must be positive",
        ),
        (
            "mass: 1\n        mass_model: {type: given, mass: 1, com: [0,0,0], inertia: [1,0,0,1,0,1]}",
            "remove the link's `mass`",
        ),
        (
            "mass_model: {type: given, mass: 1, com: [0,0,0], inertia: [1,0,0,0.1,0,0.1]}",
            "triangle inequality",
        ),
        (
            "vertex_mass: 0.1\n        mass_model: {type: given, mass: 1, com: [0,0,0], inertia: [1,0,0,1,0,1]}",
            "vertex_mass",
        ),
    ] {
        let e = link_moment(text).unwrap_err();
        assert!(e.contains(want) && e.contains("body"), "{text}: {e}");
    }
}
