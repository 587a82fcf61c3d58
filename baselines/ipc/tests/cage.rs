//! Cage-based deformation: mean value coordinates reproduce affine maps
//! exactly (partition of unity, linear precision — analytic checks) inside
//! box cages of every resolution and inside random convex cages, including
//! points next to the cage surface, on a cage triangle and at a cage vertex;
//! cage sizes match the paper's (26 / 98 / 1538); the chain rule from
//! hull-vertex gradients to cage vertices against finite differences; bad
//! cages rejected with the link and element named.

use nalgebra::{DVector, Matrix3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sdrs::scene::Scene;
use sdrs_ipc::cage::mvc::mean_value_coordinates;
use sdrs_ipc::cage::{Cage, CageDesign, CageError, LinkCage, box_cage};
use std::path::Path;

fn rand_v(rng: &mut ChaCha8Rng, s: f64) -> Vector3<f64> {
    Vector3::new(
        rng.random_range(-s..s),
        rng.random_range(-s..s),
        rng.random_range(-s..s),
    )
}

/// Checks partition of unity and linear precision at `x`, and affine
/// invariance under a random affine map; returns the coordinates.
fn check_affine(cage: &Cage, x: &Vector3<f64>, rng: &mut ChaCha8Rng, label: &str) -> Vec<f64> {
    check_affine_tol(cage, x, rng, label, 1e-11)
}

/// [`check_affine`] with the linear-precision tolerance `tol` (relative to
/// the cage size).
fn check_affine_tol(
    cage: &Cage,
    x: &Vector3<f64>,
    rng: &mut ChaCha8Rng,
    label: &str,
    tol: f64,
) -> Vec<f64> {
    let mut w = vec![0.0; cage.vertices.len()];
    assert!(
        mean_value_coordinates(x, &cage.vertices, &cage.tris, &mut w),
        "{label}: undefined"
    );
    let sum: f64 = w.iter().sum();
    assert!((sum - 1.0).abs() <= 1e-12, "{label}: Σφ = {sum}");
    let rec: Vector3<f64> = w.iter().zip(&cage.vertices).map(|(wj, c)| c * *wj).sum();
    let size = cage.vertices.iter().map(|c| c.norm()).fold(0.0, f64::max);
    if std::env::var("CAGE_DIAG").is_ok() {
        eprintln!(
            "{label}: linear precision {:.3e} (relative {:.3e})",
            (rec - x).norm(),
            (rec - x).norm() / size
        );
    }
    assert!(
        (rec - x).norm() <= tol * size,
        "{label}: Σφc − x = {:.3e}",
        (rec - x).norm()
    );
    // An affine map of the cage maps x the same way (same coordinates).
    let a = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0)) + Matrix3::identity() * 2.0;
    let b = rand_v(rng, 1.0);
    let mapped: Vector3<f64> = w
        .iter()
        .zip(&cage.vertices)
        .map(|(wj, c)| (a * c + b) * *wj)
        .sum();
    assert!(
        (mapped - (a * x + b)).norm() <= 10.0 * tol * (size + 1.0),
        "{label}: affine"
    );
    w
}

#[test]
fn box_cages_have_the_papers_sizes_and_reproduce_affine_maps() {
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let pts: Vec<Vector3<f64>> = (0..50).map(|_| rand_v(&mut rng, 0.1)).collect();
    for (k, n) in [(1, 8), (2, 26), (4, 98), (7, 296), (16, 1538)] {
        let cage = box_cage(&pts, k, 0.01);
        assert_eq!(cage.vertices.len(), n, "k = {k}");
        assert_eq!(cage.tris.len(), 12 * (k * k) as usize);
        // Closed, every surface point enclosed.
        let link_pts: Vec<_> = pts.iter().enumerate().map(|(i, p)| (0, i, *p)).collect();
        sdrs_ipc::cage::validate_cage(&cage, "test", &link_pts).unwrap();
        if k > 7 {
            continue;
        }
        for (i, p) in pts.iter().enumerate().take(20) {
            let w = check_affine(&cage, p, &mut rng, &format!("k = {k} point {i}"));
            // Convex cage: positive coordinates.
            assert!(
                w.iter().all(|&x| x > -1e-14),
                "k = {k}: negative coordinate"
            );
        }
    }
}

#[test]
fn coordinates_reproduce_affine_maps_near_on_and_at_the_cage_surface() {
    let mut rng = ChaCha8Rng::seed_from_u64(32);
    let pts: Vec<Vector3<f64>> = (0..20).map(|_| rand_v(&mut rng, 0.1)).collect();
    let cage = box_cage(&pts, 3, 0.02);
    for t in cage.tris.iter().step_by(5) {
        let p = t.map(|i| cage.vertices[i as usize]);
        let n = (p[1] - p[0]).cross(&(p[2] - p[0])).normalize();
        let centre = (p[0] + p[1] + p[2]) / 3.0;
        // The closed form loses digits next to the surface (cancellation
        // as h → π): measured relative errors 1e-15, 2e-13, 2e-9, 5e-8 at
        // depths 1e-2, 1e-4, 1e-6, 1e-8 m in this 0.15 m cage. Automatic
        // cages keep every mesh vertex ≥ 5 % of the extent inside.
        for (depth, tol) in [(1e-2, 1e-11), (1e-4, 1e-11), (1e-6, 1e-7), (1e-8, 1e-6)] {
            check_affine_tol(
                &cage,
                &(centre - n * depth),
                &mut rng,
                &format!("depth {depth}"),
                tol,
            );
        }
        // On the triangle (2D barycentric case) and at a vertex.
        let w = check_affine(&cage, &centre, &mut rng, "on a triangle");
        for (j, &wj) in w.iter().enumerate() {
            if !t.contains(&(j as u32)) {
                assert!(wj.abs() < 1e-12, "on a triangle: weight on vertex {j}");
            }
        }
        let w = check_affine(&cage, &p[1], &mut rng, "at a vertex");
        assert!((w[t[1] as usize] - 1.0).abs() < 1e-15);
    }
}

#[test]
fn coordinates_reproduce_affine_maps_in_random_convex_cages() {
    let mut rng = ChaCha8Rng::seed_from_u64(33);
    for case in 0..20 {
        let pts: Vec<Vector3<f64>> = (0..30).map(|_| rand_v(&mut rng, 1.0)).collect();
        let poly = sdrs::import::polytope::convex_hull(&pts).unwrap();
        let cage = Cage {
            vertices: poly.vertices.clone(),
            tris: poly.triangles.iter().map(|t| t.map(|i| i as u32)).collect(),
        };
        let centroid: Vector3<f64> =
            cage.vertices.iter().sum::<Vector3<f64>>() / cage.vertices.len() as f64;
        for _ in 0..20 {
            // A random point between the centroid and a random vertex: inside.
            let v = cage.vertices[rng.random_range(0..cage.vertices.len())];
            let x = centroid + (v - centroid) * rng.random_range(0.0..0.999);
            check_affine(&cage, &x, &mut rng, &format!("convex cage {case}"));
        }
    }
}

const SCENE: &str = "
version: 1
dt: 0.01
objects:
  - name: part
    mass: 1.0
    hulls:
      - vertices: [[-0.1, -0.05, -0.02], [0.1, -0.05, -0.02], [-0.1, 0.05, -0.02], [0.1, 0.05, -0.02],
                   [-0.1, -0.05, 0.02], [0.1, -0.05, 0.02], [-0.1, 0.05, 0.02], [0.1, 0.05, 0.03]]
      - vertices: [[0.05, 0.0, 0.02], [0.08, 0.0, 0.02], [0.05, 0.03, 0.02], [0.06, 0.01, 0.07]]
";

#[test]
fn cage_gradient_is_the_chain_rule_of_vertex_gradients_against_finite_differences() {
    let scene = Scene::from_str(SCENE, Path::new("cage.yaml")).unwrap();
    let model = scene.model.clone();
    let link = model.links.iter().position(|l| l.name == "part").unwrap();
    for k in [1, 2, 4] {
        let design = CageDesign {
            cages: vec![LinkCage::automatic(&model, link, k).unwrap()],
            bound: 0.05,
        };
        let c0 = design.initial();
        // The rest cage reproduces the mesh (linear precision).
        let mut m = model.clone();
        design.apply(&mut m, &c0);
        for (h, hull) in model.links[link].hulls.iter().enumerate() {
            for (v, x) in hull.x_local.iter().enumerate() {
                assert!((m.links[link].hulls[h].x_local[v] - x).norm() < 1e-13);
            }
        }
        // A smooth function of the vertices: L = Σ_i (a_i·x_i + ‖x_i‖⁴).
        let loss = |m: &sdrs::model::Model| -> f64 {
            let mut s = 0.0;
            for (h, hull) in m.links[link].hulls.iter().enumerate() {
                for (v, x) in hull.x_local.iter().enumerate() {
                    let a = Vector3::new(1.0 + h as f64, -0.5 * v as f64, 0.3);
                    s += a.dot(x) + x.norm_squared().powi(2);
                }
            }
            s
        };
        let mut g = sdrs::diff::Gradients {
            vertices: model
                .links
                .iter()
                .map(|l| {
                    l.hulls
                        .iter()
                        .map(|hh| vec![Vector3::zeros(); hh.x_local.len()])
                        .collect()
                })
                .collect(),
            ..Default::default()
        };
        for (h, hull) in model.links[link].hulls.iter().enumerate() {
            for (v, x) in hull.x_local.iter().enumerate() {
                let a = Vector3::new(1.0 + h as f64, -0.5 * v as f64, 0.3);
                g.vertices[link][h][v] = a + x * (4.0 * x.norm_squared());
            }
        }
        let gc = design.gradient(&g);
        let (lo, hi) = design.bounds();
        assert!((hi - &lo).iter().all(|&d| (d - 0.1).abs() < 1e-15));
        for i in 0..design.len() {
            let f = |d: f64| {
                let mut c: DVector<f64> = c0.clone();
                c[i] += d;
                let mut m = model.clone();
                design.apply(&mut m, &c);
                loss(&m)
            };
            let h = 1e-6;
            let fd = (f(h) - f(-h)) / (2.0 * h);
            let rel = (fd - gc[i]).abs() / fd.abs().max(gc[i].abs()).max(1e-8);
            assert!(
                rel < 1e-6,
                "k = {k}, cage coordinate {i}: {} vs fd {fd}",
                gc[i]
            );
        }
    }
}

#[test]
fn bad_cages_are_rejected_naming_the_link_and_element() {
    let scene = Scene::from_str(SCENE, Path::new("cage.yaml")).unwrap();
    let model = scene.model.clone();
    let link = model.links.iter().position(|l| l.name == "part").unwrap();
    let pts: Vec<Vector3<f64>> = model.links[link]
        .hulls
        .iter()
        .flat_map(|h| h.x_local.clone())
        .collect();
    let good = box_cage(&pts, 2, 0.01);
    // Open: a triangle removed.
    let mut open = good.clone();
    open.tris.remove(3);
    let e = LinkCage::new(&model, link, open).unwrap_err();
    assert!(matches!(e, CageError::Open { .. }), "{e}");
    assert!(e.to_string().contains("part/part"), "{e}");
    // Degenerate: a triangle with a repeated vertex.
    let mut degen = good.clone();
    degen.tris[0][1] = degen.tris[0][0];
    let e = LinkCage::new(&model, link, degen).unwrap_err();
    assert!(matches!(e, CageError::Degenerate { tri: 0, .. }), "{e}");
    // Not enclosing: a cage around the first hull's lower half only.
    let small = box_cage(&pts[..4], 2, 0.001);
    let e = LinkCage::new(&model, link, small).unwrap_err();
    assert!(matches!(e, CageError::NotEnclosing { .. }), "{e}");
    assert!(e.to_string().contains("vertex"), "{e}");
    // Index out of range.
    let mut bad = good.clone();
    bad.tris[5][2] = 10_000;
    let e = LinkCage::new(&model, link, bad).unwrap_err();
    assert!(
        matches!(
            e,
            CageError::Index {
                tri: 5,
                vertex: 10_000,
                ..
            }
        ),
        "{e}"
    );
    // Inside-out (reversed orientation) is not enclosing either.
    let mut inv = good.clone();
    inv.tris.iter_mut().for_each(|t| t.swap(1, 2));
    let e = LinkCage::new(&model, link, inv).unwrap_err();
    assert!(matches!(e, CageError::NotEnclosing { .. }), "{e}");
}
