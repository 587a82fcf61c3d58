//! Source meshes as IPC contact surfaces (`contact.ipc.surface: source`): a box
//! dropped over a U-shaped channel falls into the slot when the channel's
//! surface is its (non-convex) source mesh and lands on top when it is its
//! convex hull; the start check follows the surface; bad meshes are errors
//! naming the scene file, the key and the triangle or edge.

use crate::support;

use sdrs::scene::Scene;
use sdrs::sim::run::run;
use sdrs_ipc::IpcFactory;
use sdrs_ipc::surface::{SurfaceError, surface_from_triangles};
use std::path::{Path, PathBuf};
use support::meshes::{Mesh, channel, cube, scratch, sphere, tetra, write_obj};

/// The channel as a static obstacle (hull: its bounding box, what
/// `sdrs import --decomposer hull` makes of it) and a 0.1 m box (mass 1 kg)
/// at `at`.
fn channel_scene(dir: &Path, surface: &str, at: [f64; 3], size: f64, mesh: &str) -> PathBuf {
    let text = format!(
        "version: 1\ndt: 0.005\ncontact: {{model: ipc, mu: 0.3, ipc: {{surface: {surface}}}}}\n\
obstacles:\n  - name: channel\n    hulls: [{{box: {{size: [0.6, 0.6, 0.3], center: [0, 0, 0.15]}}}}]\n    surface_mesh: {mesh}\n\
objects:\n  - name: box\n    mass: 1.0\n    hulls: [{{box: {{size: [{size}, {size}, {size}]}}}}]\n    initial: {{q: [{}, {}, {}, 0, 0, 0]}}\n",
        at[0], at[1], at[2]
    );
    let p = dir.join(format!("channel_{surface}.yaml"));
    std::fs::write(&p, text).unwrap();
    p
}

fn final_z(scene: &Path, steps: usize) -> (f64, f64) {
    let s = Scene::load(scene).unwrap();
    let mut sim = s.simulator_with(&IpcFactory::default()).unwrap();
    let t = run(&mut sim, steps, |_| {}).unwrap();
    let z = t
        .names
        .iter()
        .position(|n| n.ends_with("box:z"))
        .unwrap_or_else(|| panic!("{:?}", t.names));
    let zs: Vec<f64> = t.states.iter().map(|q| q[z]).collect();
    (
        *zs.last().unwrap(),
        zs.iter().copied().fold(f64::INFINITY, f64::min),
    )
}

#[test]
fn box_falls_into_the_channel_slot_under_the_source_mesh_and_rests_on_its_hull() {
    let dir = scratch("channel");
    write_obj(&dir.join("channel.obj"), &channel());
    let start = [0.0, 0.0, 0.37];
    let (src_end, src_min) = final_z(
        &channel_scene(&dir, "source", start, 0.1, "channel.obj"),
        300,
    );
    let (hull_end, hull_min) = final_z(
        &channel_scene(&dir, "hulls", start, 0.1, "channel.obj"),
        300,
    );
    eprintln!(
        "box centre z after 1.5 s: source surface {src_end:.6} (min {src_min:.6}), hull surface {hull_end:.6} (min {hull_min:.6})"
    );
    // Source mesh: on the slot floor (z = 0.1), half a box above it, within d̂.
    assert!(src_end > 0.15 && src_end < 0.15 + 1e-3, "{src_end}");
    assert!(src_min > 0.15, "{src_min}");
    // Hull: on the top (z = 0.3).
    assert!(hull_end > 0.35 && hull_end < 0.35 + 1e-3, "{hull_end}");
    assert!(hull_min > 0.35, "{hull_min}");
}

#[test]
fn start_check_uses_the_surface() {
    let dir = scratch("start");
    write_obj(&dir.join("channel.obj"), &channel());
    // In the slot: inside the hull, outside the source mesh.
    let in_slot = [0.0, 0.0, 0.2];
    let ok = Scene::load(channel_scene(&dir, "source", in_slot, 0.1, "channel.obj")).unwrap();
    assert!(ok.simulator_with(&IpcFactory::default()).is_ok());
    let bad = Scene::load(channel_scene(&dir, "hulls", in_slot, 0.1, "channel.obj")).unwrap();
    let e = bad
        .simulator_with(&IpcFactory::default())
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("channel_hulls.yaml")
            && e.contains("initial state")
            && e.contains("world/channel")
            && e.contains("box/box"),
        "{e}"
    );
    // Crossing the right wall of the source mesh.
    let crossing = channel_scene(&dir, "source", [0.15, 0.0, 0.2], 0.1, "channel.obj");
    let e = Scene::load(&crossing)
        .unwrap()
        .simulator_with(&IpcFactory::default())
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("channel_source.yaml") && e.contains("world/channel") && e.contains("box/box"),
        "{e}"
    );
    // Wholly inside the channel's floor (no triangles cross: the winding test).
    let inside = channel_scene(&dir, "source", [0.0, 0.0, 0.05], 0.05, "channel.obj");
    let e = Scene::load(&inside)
        .unwrap()
        .simulator_with(&IpcFactory::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("initial state") && e.contains("box/box"), "{e}");
}

fn scene_error(dir: &Path, name: &str, mesh: &Mesh) -> String {
    let file = format!("{name}.obj");
    write_obj(&dir.join(&file), mesh);
    let scene = channel_scene(&dir.join(""), "source", [2.0, 0.0, 0.37], 0.1, &file);
    let s = Scene::load(&scene).unwrap();
    s.simulator_with(&IpcFactory::default())
        .err()
        .expect("an error")
        .to_string()
}

#[test]
fn bad_source_meshes_name_the_scene_the_key_the_file_and_the_element() {
    let dir = scratch("bad");
    let key = "obstacles[0] (\"channel\").surface_mesh";
    // Open: a tetrahedron missing its last face.
    let (v, mut t) = tetra();
    t.pop();
    let e = scene_error(&dir, "open", &(v.clone(), t));
    assert!(
        e.contains("channel_source.yaml") && e.contains(key) && e.contains("open.obj"),
        "{e}"
    );
    assert!(
        e.contains("not closed") && e.contains("bounds 1 triangle"),
        "{e}"
    );
    // Inconsistently oriented: one face flipped.
    let (v, mut t) = tetra();
    t[3].swap(1, 2);
    let e = scene_error(&dir, "flipped", &(v, t));
    assert!(
        e.contains("flipped.obj")
            && e.contains("not consistently oriented")
            && e.contains("triangles"),
        "{e}"
    );
    // Degenerate: a cube whose vertex 7 sits on the line of triangle 3's other two.
    let (mut v, t) = cube();
    v[7] = [0.0, 0.5, 1.0];
    let e = scene_error(&dir, "degenerate", &(v, t));
    assert!(
        e.contains("degenerate.obj") && e.contains("triangle 3") && e.contains("degenerate"),
        "{e}"
    );
    // Self-intersecting: the cube's corner 7 pushed through the bottom face.
    let (mut v, t) = cube();
    v[7] = [0.5, 0.5, -0.5];
    let e = scene_error(&dir, "crossing", &(v, t));
    assert!(
        e.contains("crossing.obj") && e.contains("intersects itself") && e.contains("triangles"),
        "{e}"
    );
    // Missing file.
    let scene = channel_scene(&dir, "source", [2.0, 0.0, 0.37], 0.1, "nowhere.obj");
    let e = Scene::load(&scene)
        .unwrap()
        .simulator_with(&IpcFactory::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains(key) && e.contains("nowhere.obj"), "{e}");
}

#[test]
fn typed_errors_carry_the_triangles() {
    let f = Path::new("m.obj");
    let tri = |m: &Mesh| {
        let v: Vec<_> = m.0.iter().map(|p| nalgebra::Vector3::from(*p)).collect();
        surface_from_triangles(f, &v, &m.1)
    };
    let (v, mut t) = tetra();
    t.pop();
    match tri(&(v, t)).unwrap_err() {
        SurfaceError::Open { count, tris, .. } => assert!(count == 1 && tris.len() == 1),
        e => panic!("{e}"),
    }
    let (mut v, t) = cube();
    v[7] = [0.5, 0.5, -0.5];
    match tri(&(v, t.clone())).unwrap_err() {
        SurfaceError::SelfIntersection { t1, t2, v1, v2, .. } => {
            assert!(t1 < t2 && v1 == t[t1] && v2 == t[t2]);
            assert!(!v1.iter().any(|x| v2.contains(x)), "{v1:?} {v2:?}");
        }
        e => panic!("{e}"),
    }
    // A valid closed mesh, and an inside-out one (flipped, accepted).
    assert!(tri(&channel()).is_ok());
    let (v, t) = cube();
    let inv: Vec<[usize; 3]> = t.iter().map(|x| [x[0], x[2], x[1]]).collect();
    let m = tri(&(v, inv)).unwrap();
    assert_eq!(m.tris.len(), 12);
}

#[test]
fn self_intersection_check_is_fast_on_a_large_mesh() {
    // 2 · 200 · 99 = 39 600 triangles: O(n²) would test 7.8e8 pairs.
    let m = sphere(0.5, 100, 200);
    let v: Vec<_> = m.0.iter().map(|p| nalgebra::Vector3::from(*p)).collect();
    let t0 = std::time::Instant::now();
    let s = surface_from_triangles(Path::new("sphere.obj"), &v, &m.1).unwrap();
    let dt = t0.elapsed().as_secs_f64();
    eprintln!("{} triangles checked in {dt:.3} s", s.tris.len());
    assert_eq!(s.tris.len(), 39_600);
    assert!(dt < 5.0, "{dt}");
    // The same sphere with one vertex pushed through the far side.
    let mut bad = v.clone();
    bad[0] = nalgebra::Vector3::new(0.0, 0.0, -0.6);
    let e = surface_from_triangles(Path::new("sphere.obj"), &bad, &m.1).unwrap_err();
    assert!(matches!(e, SurfaceError::SelfIntersection { .. }), "{e}");
}
