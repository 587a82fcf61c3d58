//! A design block shrinking to a sliver (issue 30, item 1): with the paper's
//! connectivity (one shared vertex per pair of touching blocks, every other
//! vertex free) a block may collapse onto the face it shares with its
//! neighbour. The mass model, the contact potential, Newton and the topology
//! metric must stay well-defined on the way and at the limit.
//!
//! The body: two 2 × 2 × 1 cm blocks side by side (x ∈ [0, 2] and [2, 4] cm),
//! tied through the auxiliary vertex at the centre of their common face
//! (2, 1, 0.5) cm (what `sdrs import --decomposer grid` writes), a free
//! body resting on a static box obstacle (hull–hull contact, not the
//! ground plane). Block B is flattened towards the common face,
//! `x ← 2 cm + λ(x − 2 cm)`: its volume is `λ` times the initial, and at
//! `λ = 0` its vertices are coplanar (the scene loader would refuse that
//! hull; the design update writes it directly, as the optimizer does).

use nalgebra::{Matrix4, Vector3};
use sdrs::geometry::topology;
use sdrs::scene::Scene;
use std::path::Path;

const LAMBDAS: [f64; 8] = [1.0, 0.5, 0.1, 1e-2, 1e-4, 1e-6, 1e-9, 0.0];

fn scene(mass: &str) -> Scene {
    let text = format!(
        r#"
version: 1
dt: 0.01
steps: 60
solver: {{tol: 1.0e-10}}
robots:
  - name: body
    links:
      - name: blocks
        joint: {{type: free, origin: {{xyz: [0, 0, 0.0005]}}}}
        {mass}
        hulls:
          - vertices: [[0,0,0],[0.02,0,0],[0,0.02,0],[0.02,0.02,0],[0,0,0.01],[0.02,0,0.01],[0,0.02,0.01],[0.02,0.02,0.01],[0.02,0.01,0.005]]
          - vertices: [[0.02,0,0],[0.04,0,0],[0.02,0.02,0],[0.04,0.02,0],[0.02,0,0.01],[0.04,0,0.01],[0.02,0.02,0.01],[0.04,0.02,0.01],[0.02,0.01,0.005]]
obstacles:
  - name: table
    hulls:
      - box: {{size: [0.2, 0.2, 0.02], center: [0.02, 0.01, -0.01]}}
contact: {{s: 0.001, mu: 0.3}}
"#
    );
    Scene::from_str(&text, Path::new("degenerate.yaml")).unwrap()
}

/// Block B of the body flattened by `lambda` (see the module docs).
fn flatten(sc: &mut Scene, lambda: f64) {
    let b = &mut sc.model.links[0].hulls[1].x_local;
    for v in b.iter_mut() {
        v.x = 0.02 + lambda * (v.x - 0.02);
    }
    sc.model.links[0].refresh_triangles();
    sc.model.refresh_moments();
}

/// Simulates 60 steps (0.6 s: the body settles on the table); every step
/// must succeed and every pose be finite. Returns the final 3×4 pose and the
/// link's second moment.
fn run(mass: &str, lambda: f64) -> (Vec<f64>, Matrix4<f64>) {
    let mut sc = scene(mass);
    flatten(&mut sc, lambda);
    let m = sc.model.links[0].moments().0;
    assert!(
        m.iter().all(|x| x.is_finite()),
        "{mass} λ={lambda}: moments {m}"
    );
    let mut sim = sc.simulator();
    for k in 0..60 {
        let r = sim.step();
        assert!(r.is_ok(), "{mass} λ={lambda}: step {} failed: {r:?}", k + 1);
        let pose: Vec<f64> = sim
            .state
            .poses
            .iter()
            .flat_map(|p| p.iter().copied())
            .collect();
        assert!(
            pose.iter().all(|x| x.is_finite()),
            "{mass} λ={lambda}: step {}",
            k + 1
        );
    }
    let pose = sim.state.poses[0].iter().copied().collect();
    (pose, m)
}

#[test]
fn a_block_flattened_to_zero_volume_keeps_mass_contact_and_newton_well_defined() {
    for mass in [
        "mass: 0.2",
        "mass_model: {type: solid, density: 500}",
        "mass_model: {type: given, mass: 0.2, com: [0.01, 0.01, 0.005], inertia: [1e-5, 0, 0, 2e-5, 0, 2e-5]}",
    ] {
        let runs: Vec<_> = LAMBDAS.iter().map(|&l| run(mass, l)).collect();
        let (pose0, m0) = &runs[LAMBDAS.len() - 1];
        let scale = runs[0].1.norm();
        for (&l, (pose, m)) in LAMBDAS.iter().zip(&runs) {
            let dm = (m - m0).norm() / scale;
            let dp = pose
                .iter()
                .zip(pose0)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            eprintln!("{mass}: λ = {l:e}: |ΔM|/|M| = {dm:.3e}, max |Δpose| = {dp:.3e}");
            // Mass properties: vertex masses and solid integrals are
            // polynomials of the vertices, linear in λ here (the solid
            // volume is λ·V_B), so |M(λ) − M(0)| ≤ |M(1) − M(0)|·λ to
            // round-off; a given inertial does not depend on the design.
            let d1 = (runs[0].1 - m0).norm() / scale;
            assert!(
                dm <= d1 * l * (1.0 + 1e-9) + 1e-15,
                "{mass}: λ={l}: {dm} vs {d1}·λ"
            );
        }
        // The settled pose converges as the sliver vanishes (the body rests
        // on block A and on B's bottom edge, which stays in contact).
        let dp = |i: usize| {
            runs[i]
                .0
                .iter()
                .zip(pose0)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        };
        assert!(dp(5) <= 1e-4, "{mass}: λ=1e-6 pose {:.3e} from λ=0", dp(5));
        assert!(dp(6) <= 1e-6, "{mass}: λ=1e-9 pose {:.3e} from λ=0", dp(6));
    }
}

#[test]
fn the_topology_metric_counts_a_flat_block_as_empty() {
    let mut sc = scene("mass: 0.2");
    let hulls = |sc: &Scene| -> Vec<Vec<Vector3<f64>>> {
        sc.model.links[0]
            .hulls
            .iter()
            .map(|h| h.x_local.clone())
            .collect()
    };
    let t = topology::measure(&hulls(&sc), 40).unwrap();
    assert_eq!((t.components, t.holes, t.flat_hulls), (1, 0, 0));
    flatten(&mut sc, 0.0);
    let t = topology::measure(&hulls(&sc), 40).unwrap();
    assert_eq!(
        (t.components, t.holes, t.cavities, t.flat_hulls),
        (1, 0, 0, 1)
    );
}
