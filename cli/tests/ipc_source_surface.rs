//! `contact.ipc.surface: source` end to end: non-convex source meshes (a
//! U-shaped channel, an L-shaped bar) as IPC contact surfaces under `sdrs
//! simulate --contact ipc --export`, checked pair by pair with python-fcl on
//! the meshes themselves (`surfaces.json`); `sdrs import` writes the source
//! mesh and names it; `sdrs optimize` refuses hull-vertex designs of a
//! source-surface link (the cage is the way) and cages the source mesh.

use crate::support;

#[path = "../../baselines/ipc/tests/support/meshes.rs"]
mod meshes;

use meshes::{channel, l_shape, write_obj};
use support::{scratch_dir, sdrs};

/// The channel (static; hull: its bounding box), a box that falls into its
/// slot and an L-shaped bar (hulls: two boxes) that lands across the slot's
/// right edge.
const SCENE: &str = "
version: 1
dt: 0.005
contact: {model: ipc, mu: 0.3, ipc: {surface: source}}
obstacles:
  - name: channel
    hulls: [{box: {size: [0.6, 0.6, 0.3], center: [0, 0, 0.15]}}]
    surface_mesh: channel.obj
objects:
  - name: box
    mass: 1.0
    hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
    initial: {q: [-0.05, 0.0, 0.37, 0, 0, 0]}
  - name: ell
    mass: 0.5
    hulls:
      - {box: {size: [0.2, 0.2, 0.05], center: [0.1, 0, 0.025]}}
      - {box: {size: [0.05, 0.2, 0.15], center: [0.025, 0, 0.125]}}
    surface_mesh: ell.obj
    initial: {q: [0.05, 0.02, 0.45, 0, 0, 0.3], qdot: [0, 0, 0, 0.5, -0.5, 0]}
";

#[test]
fn non_convex_source_surfaces_run_and_python_fcl_finds_every_mesh_pair_separated() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("ipc_source");
    write_obj(&dir.join("channel.obj"), &channel());
    write_obj(&dir.join("ell.obj"), &l_shape());
    let scene = dir.join("scene.yaml");
    std::fs::write(&scene, SCENE).unwrap();
    let out = dir.join("run");
    std::fs::create_dir_all(&out).unwrap();
    let summary = support::simulate_export(&out, &["--contact", "ipc", "--steps", "400"], &scene);
    let in_contact = summary["contact"]["steps_in_contact"].as_u64().unwrap();
    assert!(in_contact > 100, "{in_contact} steps in contact");
    assert!(out.join("surfaces.json").is_file());
    let r = support::python_fcl_check(&out);
    eprintln!(
        "source surfaces, python-fcl: {} steps × {} pairs ({} mesh distance calls), min distance {:.6e} m at step {}, surface links {}",
        r["steps_checked"],
        r["hull_pairs"],
        r["mesh_distance_calls"],
        r["min_distance"].as_f64().unwrap(),
        r["min_at_step"],
        r["surface_links"]
    );
    assert_eq!(r["steps_checked"], 401);
    assert_eq!(r["surface_links"].as_array().unwrap().len(), 2);
    assert!(r["mesh_distance_calls"].as_u64().unwrap() > 400);
    let min = r["min_distance"].as_f64().unwrap();
    assert!(min > 0.0 && min < 1e-3, "{min}");
    // The box fell into the slot (below the hull's top at z = 0.3).
    let csv = dir.join("run.csv");
    support::run_ok(
        sdrs()
            .args([
                "simulate",
                "-q",
                "--contact",
                "ipc",
                "--steps",
                "400",
                "--out",
            ])
            .arg(&csv)
            .arg(&scene),
    );
    let z = final_value(&csv, "box/box:z");
    assert!(z < 0.16, "box centre z {z}");
}

#[test]
fn import_writes_the_source_mesh_and_ipc_uses_it() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("ipc_source_import");
    let input = dir.join("channel.obj");
    write_obj(&input, &channel());
    let design = dir.join("design.yaml");
    support::run_ok(
        sdrs()
            .args(["import", "-q", "--decomposer", "hull", "--ground", "--out"])
            .arg(&design)
            .arg(&input),
    );
    let text = std::fs::read_to_string(&design).unwrap();
    let line = text
        .lines()
        .find(|l| l.contains("surface_mesh"))
        .unwrap_or_else(|| panic!("no surface_mesh in\n{text}"));
    assert!(
        line.contains("design_meshes/") && line.contains(".source.obj"),
        "{line}"
    );
    let rel = line.split('"').nth(1).unwrap();
    assert!(dir.join(rel).is_file(), "{rel}");
    // Switch the design to IPC on its source mesh and run it.
    let ipc = text.replacen(
        "contact:\n",
        "contact:\n  model: ipc\n  ipc: {surface: source}\n",
        1,
    );
    assert_ne!(ipc, text, "the design has no contact section");
    let scene = dir.join("design_ipc.yaml");
    std::fs::write(&scene, ipc).unwrap();
    let out = dir.join("run");
    std::fs::create_dir_all(&out).unwrap();
    support::simulate_export(&out, &["--steps", "100"], &scene);
    let r = support::python_fcl_check(&out);
    assert_eq!(r["surface_links"].as_array().unwrap().len(), 1, "{r}");
}

const TASK: &str = "
version: 1
scene: scene.yaml
horizon: 20
loss:
  - {type: link_point, link: box/box, point: [0, 0, 0], target: [0.0, 0, 0.1], weight: 1.0, when: final}
design: {vertices: [ell/ell], bound: 0.01}
optimizer: {method: trust_region, iters: 1, step_design: 0.002}
";

#[test]
fn optimize_refuses_hull_edits_of_a_source_surface_and_cages_the_source_mesh() {
    let dir = scratch_dir("ipc_source_opt");
    write_obj(&dir.join("channel.obj"), &channel());
    write_obj(&dir.join("ell.obj"), &l_shape());
    std::fs::write(dir.join("scene.yaml"), SCENE).unwrap();
    let task = dir.join("task.yaml");
    std::fs::write(&task, TASK).unwrap();
    let o = sdrs()
        .args(["optimize", "-q", "--contact", "ipc", "--out"])
        .arg(dir.join("out"))
        .arg(&task)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("task.yaml")
            && e.contains("ell/ell")
            && e.contains("ell.obj")
            && e.contains("objects[1] (\"ell\").surface_mesh")
            && e.contains("--cage"),
        "{e}"
    );
    // With a cage the source mesh is part of the design.
    let mut p = sdrs::optimize::Problem::load(&task, true).unwrap();
    let s = sdrs_ipc::cage::cage_problem(&mut p, sdrs_ipc::cage::CageResolution::Coarse).unwrap();
    assert_eq!(s.cage_vertices, vec![26]);
    let ell = p
        .first()
        .model
        .links
        .iter()
        .position(|l| l.name == "ell")
        .unwrap();
    assert_eq!(p.first().model.links[ell].surface.len(), 12);
    let blends = p
        .design
        .vars
        .iter()
        .flat_map(|v| &v.targets)
        .filter(|t| matches!(t, sdrs::optimize::design::Target::SurfaceBlend { .. }))
        .count();
    assert!(blends > 0);
    // Moving every cage vertex by +1 cm in x moves the source mesh with it
    // (mean value coordinates reproduce translations).
    let mut x = p.design.values(&p.first().model);
    for (k, v) in p.design.vars.iter().enumerate() {
        if v.name.ends_with(".x") {
            x[k] += 0.01;
        }
    }
    let mut m = p.first().model.clone();
    p.design.apply(&mut m, &x);
    for (a, b) in m.links[ell]
        .surface
        .iter()
        .zip(&p.first().model.links[ell].surface)
    {
        assert!(((a - b) - nalgebra::Vector3::new(0.01, 0.0, 0.0)).norm() < 1e-12);
    }
}

/// pybullet_data's torus (`torus/torus_textured.obj`: major radius 0.5 m,
/// minor 0.25 m, axis y, 1002 triangles, closed) imported as one convex
/// hull (`--decomposer hull`, which fills the hole), fixed upright on the
/// ground, with a 0.1 m box in its hole. With its source mesh the box falls
/// onto the inside of the ring (below the ring's centre, python-fcl clean);
/// with its hull the start is rejected (the box is inside the hull).
#[test]
fn imported_torus_holds_a_box_in_its_hole_only_with_its_source_mesh() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("ipc_source_torus");
    let input = support::pybullet_data().join("torus/torus_textured.obj");
    let design = dir.join("torus.yaml");
    support::run_ok(
        sdrs()
            .args([
                "import",
                "-q",
                "--decomposer",
                "hull",
                "--base",
                "fixed",
                "--ground",
                "--out",
            ])
            .arg(&design)
            .arg(&input),
    );
    let text = std::fs::read_to_string(&design).unwrap();
    assert!(text.contains("torus_meshes/torus_textured.source.obj"));
    let base = text
        .lines()
        .find(|l| l.trim_start().starts_with("base: {xyz: ["))
        .unwrap();
    let zc: f64 = base
        .split(['[', ']'])
        .nth(1)
        .unwrap()
        .split(',')
        .nth(2)
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    assert!(!text.contains("\nobjects:"));
    let with_box = |surface: &str| {
        let s = text.replacen(
            "contact:\n",
            &format!("contact:\n  model: ipc\n  ipc: {{surface: {surface}}}\n"),
            1,
        ) + &format!(
            "objects:\n  - name: peg\n    mass: 0.2\n    hulls: [{{box: {{size: [0.1, 0.1, 0.1]}}}}]\n    initial: {{q: [0, 0, {zc}, 0, 0, 0]}}\n"
        );
        let p = dir.join(format!("torus_{surface}.yaml"));
        std::fs::write(&p, s).unwrap();
        p
    };
    let out = dir.join("run");
    std::fs::create_dir_all(&out).unwrap();
    let summary = support::simulate_export(&out, &["--steps", "400"], &with_box("source"));
    let r = support::python_fcl_check(&out);
    eprintln!(
        "torus: ring centre z {zc:.4}; python-fcl {} steps, min distance {:.3e} m, surface links {}; {} steps in contact",
        r["steps_checked"],
        r["min_distance"].as_f64().unwrap(),
        r["surface_links"],
        summary["contact"]["steps_in_contact"]
    );
    assert_eq!(r["surface_links"].as_array().unwrap().len(), 1);
    assert!(r["min_distance"].as_f64().unwrap() > 0.0);
    let csv = dir.join("run.csv");
    support::run_ok(
        sdrs()
            .args(["simulate", "-q", "--steps", "400", "--out"])
            .arg(&csv)
            .arg(with_box("source")),
    );
    let z = final_value(&csv, "peg/peg:z");
    eprintln!(
        "peg centre z after 0.4 s: {:.5} (ring centre {zc:.5}, hole radius 0.2551)",
        z
    );
    // Resting on the inside of the ring: the box's lower corners (±0.05 m)
    // meet the 0.255 m hole at 0.250 m below the centre.
    assert!(z < zc - 0.15 && z > zc - 0.255, "{} vs {zc}", z);
    // With the hull the box starts inside the torus.
    let o = sdrs()
        .args(["simulate", "-q", "--steps", "1"])
        .arg(with_box("hulls"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("initial state") && e.contains("peg/peg") && e.contains("torus_textured"),
        "{e}"
    );
}

/// The last row's value of column `name` in a trajectory CSV (`--out`).
fn final_value(csv: &std::path::Path, name: &str) -> f64 {
    let text = std::fs::read_to_string(csv).unwrap();
    let head: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let col = head.iter().position(|c| *c == name).unwrap();
    text.lines()
        .last()
        .unwrap()
        .split(',')
        .nth(col)
        .unwrap()
        .parse()
        .unwrap()
}
