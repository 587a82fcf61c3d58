//! The authored benchmark robots (robots/, from `cargo run --example
//! make_robots`) import into connected design spaces whose ties leave every
//! hull unchanged, write their outputs, and simulate.

use crate::import_support;
// The robot generator, called in-process by `make_robots_output_is_reproducible`.
#[path = "../examples/make_robots.rs"]
#[allow(dead_code)]
mod make_robots;

use import_support::*;
use nalgebra::Vector3;
use sdrs::import::polytope::convex_hull;
use sdrs::import::{ImportJob, ImportOptions, import, run_job};
use sdrs::scene::Scene;
use std::collections::BTreeSet;

fn opts() -> ImportOptions {
    ImportOptions::default()
}

/// Removes the tied/attachment vertices from each hull, and checks that the
/// hull with them has the same volume (to 1e-9, relative) and that each of
/// them lies inside the hull of the others.
fn check_ties_keep_hulls(scene: &sdrs::scene::SceneSpec) -> usize {
    let robot = &scene.robots[0];
    let design = robot.design.as_ref().expect("design section");
    let mut added: BTreeSet<(String, usize, usize)> = BTreeSet::new();
    for g in &design.ties {
        assert!(g.len() >= 2, "a tie group needs two vertices");
        let p0 = vertex(robot, &g[0]);
        for r in g {
            assert_eq!(vertex(robot, r), p0, "tied vertices must coincide: {g:?}");
            added.insert((r.link.clone(), r.hull, r.vertex));
        }
    }
    for a in &design.attachments {
        for r in [&a.parent_vertex, &a.child_vertex] {
            added.insert((r.link.clone(), r.hull, r.vertex));
        }
    }
    let mut checked = 0;
    for l in &robot.links {
        for (hi, h) in l.hulls.iter().enumerate() {
            let Some(v) = &h.vertices else { continue };
            let pts: Vec<Vector3<f64>> = v.iter().map(|p| Vector3::from(*p)).collect();
            let keep: Vec<Vector3<f64>> = (0..pts.len())
                .filter(|&k| !added.contains(&(l.name.clone(), hi, k)))
                .map(|k| pts[k])
                .collect();
            if keep.len() == pts.len() {
                continue;
            }
            let with = convex_hull(&pts).unwrap();
            let without = convex_hull(&keep).unwrap();
            let rel = (with.volume() - without.volume()).abs() / without.volume();
            assert!(
                rel <= 1e-9,
                "link {} hull {hi}: adding tie vertices changed the volume by {rel:.3e}",
                l.name
            );
            let scale = without.diagonal();
            for (k, x) in pts.iter().enumerate() {
                if added.contains(&(l.name.clone(), hi, k)) {
                    let viol = without.violation(x);
                    assert!(
                        viol <= 1e-12 * scale,
                        "link {} hull {hi} vertex {k} lies {viol:.3e} m outside the hull",
                        l.name
                    );
                }
            }
            checked += 1;
        }
    }
    checked
}

fn vertex(robot: &sdrs::scene::schema::RobotSpec, r: &sdrs::scene::schema::VertexRef) -> [f64; 3] {
    let l = robot
        .links
        .iter()
        .find(|l| l.name == r.link)
        .expect("tie link exists");
    match &l.hulls[r.hull].vertices {
        Some(v) => v[r.vertex],
        None => panic!("imported hulls are vertex lists"),
    }
}

#[test]
fn authored_robots_are_connected_and_ties_leave_hull_volumes_unchanged() {
    eprintln!(
        "| robot | links | DOF | hulls | vertices | min hulls/link | max hulls/link | ties | import time (s) |"
    );
    eprintln!("|---|---|---|---|---|---|---|---|---|");
    for name in ROBOTS {
        let t = std::time::Instant::now();
        let imp = import(&robot_urdf(name), &opts()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let secs = t.elapsed().as_secs_f64();
        let r = &imp.report;
        assert!(
            r.disconnected_links.is_empty(),
            "{name}: {:?}",
            r.disconnected_links
        );
        for l in &r.links {
            assert_eq!(l.connectivity.components, 1, "{name}/{}", l.name);
            assert!(
                l.connectivity
                    .shared
                    .iter()
                    .all(|s| s.kind != sdrs::import::connectivity::TieKind::Bridge),
                "{name}/{}: hulls had to be bridged",
                l.name
            );
            assert!(l.max_hull_volume_change <= 1e-9, "{name}/{}", l.name);
        }
        for a in &r.attachments {
            assert!(
                !a.parent_site.extended && !a.child_site.extended,
                "{name}: joint {} attachment outside the hulls",
                a.joint
            );
        }
        let checked = check_ties_keep_hulls(&imp.scene);
        let design = imp.scene.robots[0].design.as_ref().unwrap();
        let scene = Scene::from_spec(imp.scene.clone(), &robot_urdf(name)).unwrap();
        let hulls: Vec<usize> = r.links.iter().map(|l| l.hulls).collect();
        eprintln!(
            "| {name} | {} | {} | {} | {} | {} | {} | {} | {secs:.2} |",
            r.links.len(),
            scene.model.ndof(),
            r.total_hulls,
            r.total_vertices,
            hulls.iter().min().unwrap(),
            hulls.iter().max().unwrap(),
            design.ties.len() + design.attachments.len(),
        );
        let _ = checked;
    }
}

#[test]
fn authored_robots_have_the_benchmark_link_and_dof_counts() {
    // (links, joint DOF without a floating base, floating base?)
    let expect = [
        ("rotating_chains", 16, 32, false),
        ("chains_8link", 25, 49, false),
        ("spider", 9, 16, true),
        ("biped", 7, 12, true),
        ("single_jaw_gripper", 1, 0, true),
        ("parallel_jaw_gripper", 3, 5, false),
        ("three_finger_hand", 6, 6, false),
    ];
    for (name, links, dof, floating) in expect {
        let imp = import(&robot_urdf(name), &opts()).unwrap();
        let scene = Scene::from_spec(imp.scene, &robot_urdf(name)).unwrap();
        assert_eq!(scene.model.links.len(), links, "{name}: links");
        let base = if floating { 6 } else { 0 };
        assert_eq!(scene.model.ndof(), dof + base, "{name}: DOF");
    }
}

#[test]
fn authored_robots_and_objects_write_outputs_that_simulate() {
    let dir = temp_dir("robots-sim");
    let mut inputs: Vec<std::path::PathBuf> = ROBOTS.iter().map(|r| robot_urdf(r)).collect();
    inputs.extend(object_meshes());
    assert_eq!(inputs.len(), 7 + 8, "7 robots and 1 + 4 + 3 objects");
    for input in inputs {
        let stem = input.file_stem().unwrap().to_string_lossy().into_owned();
        let robot = input
            .ancestors()
            .find(|a| a.parent().is_some_and(|p| p.ends_with("robots")))
            .and_then(|a| a.file_name())
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let out = dir.join(format!("{robot}_{stem}.yaml"));
        let report = dir.join(format!("{robot}_{stem}.json"));
        let job = ImportJob {
            report: Some(report.clone()),
            ..ImportJob::new(input.clone(), out.clone())
        };
        run_job(&job).unwrap_or_else(|e| panic!("{}: {e}", input.display()));
        assert!(report.is_file());
        let meshes = dir.join(format!("{robot}_{stem}_meshes"));
        let scene = Scene::load(&out).unwrap_or_else(|e| panic!("{e}"));
        // The robot's links have meshes; the environment (the ground a
        // floating import now gets by default) has none.
        let env = sdrs::scene::environment::ENVIRONMENT;
        for l in scene
            .model
            .links
            .iter()
            .filter(|l| scene.model.robots[l.robot].name != env)
        {
            assert!(
                meshes.join(format!("{}.obj", l.name)).is_file(),
                "{}",
                l.name
            );
        }
        let mut sim = scene.simulator();
        for _ in 0..3 {
            sim.step()
                .unwrap_or_else(|e| panic!("{}: {e}", input.display()));
        }
        // A second import without --force must refuse and leave the files.
        let again = run_job(&job);
        assert!(again.is_err(), "overwrote without --force");
        assert!(again.unwrap_err().to_string().contains("--force"));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn make_robots_output_is_reproducible() {
    let dir = temp_dir("make-robots");
    // The generator runs in-process (examples/make_robots.rs as a module):
    // a nested `cargo run --example` resolved the root package's features
    // alone and rebuilt the crate inside the suite (26 s → 180 s in CI).
    make_robots::write_all(&dir);
    for f in listing(&dir) {
        let p = dir.join(&f);
        if p.is_file() {
            let committed = std::fs::read(root().join("robots").join(&f))
                .unwrap_or_else(|_| panic!("robots/{f} is not committed"));
            assert!(
                std::fs::read(&p).unwrap() == committed,
                "robots/{f} differs from the generator's output"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
