//! Inputs that used to fail for numerical or pedantic reasons and must
//! import (reproducers from `shared/repro/`).

mod import_support;

use import_support::*;
use sdrs::import::polytope::convex_hull;
use sdrs::import::{Decomposer, ImportOptions, import};

fn options(decomposer: Decomposer) -> ImportOptions {
    ImportOptions {
        decomposer,
        progress: false,
        ..ImportOptions::default()
    }
}

fn finger_urdf(rpy: &str) -> String {
    format!(
        r#"<robot name="r"><link name="finger"><collision><geometry><mesh filename="l_finger.stl"/></geometry><origin rpy="{rpy}" xyz="0 0 0"/></collision></link></robot>"#
    )
}

/// The hull of a mesh rotated by rpy (−3.1415, 0, 0) failed with "open
/// surface" (a round-off inconsistency in the incremental hull's visible
/// region) while the unrotated mesh imported. A rotation changes no volume.
#[test]
fn a_rotated_mesh_has_the_same_hull_volume_as_the_unrotated_one() {
    let dir = temp_dir("rotated-hull");
    std::fs::copy(
        root().join("tests/data/repro/l_finger.stl"),
        dir.join("l_finger.stl"),
    )
    .unwrap();
    let mut volumes = Vec::new();
    for rpy in ["0 0 0", "-3.1415 0 0", "0.3 -1.2 2.9"] {
        let path = dir.join("r.urdf");
        std::fs::write(&path, finger_urdf(rpy)).unwrap();
        let imported =
            import(&path, &options(Decomposer::Hull)).unwrap_or_else(|e| panic!("rpy {rpy}: {e}"));
        let v: f64 = imported.links[0]
            .hulls
            .iter()
            .map(|h| convex_hull(h).unwrap().volume())
            .sum();
        volumes.push(v);
    }
    eprintln!("hull volumes: {volumes:?}");
    for v in &volumes[1..] {
        assert!((v - volumes[0]).abs() <= 1e-9 * volumes[0], "{volumes:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A fixed joint's axis is irrelevant: a zero axis there (as in the Franka
/// Panda's URDF) must import.
#[test]
fn a_fixed_joint_with_a_zero_axis_imports() {
    let dir = temp_dir("fixed-zero-axis");
    let r = r#"<robot name="r">
  <link name="base"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
  <link name="tool"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="arm"><collision><geometry><box size="0.1 0.1 0.3"/></geometry></collision></link>
  <joint name="weld" type="fixed"><parent link="base"/><child link="tool"/><origin xyz="0 0 0.3"/><axis xyz="0 0 0"/></joint>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0.5 0 0"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"#;
    let path = dir.join("r.urdf");
    std::fs::write(&path, r).unwrap();
    let imported = import(&path, &options(Decomposer::None)).unwrap();
    assert_eq!(imported.links.len(), 3);
    let tool = &imported.scene.robots[0].links[1];
    assert_eq!(tool.name, "tool");
    assert_eq!(tool.joint.kind, sdrs::scene::schema::JointType::Fixed);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A convex decomposition needs no manifold input (laikago, mini_cheetah,
/// the mugs, pr2_gripper and samurai in pybullet_data have non-manifold
/// collision meshes): the import succeeds, says so in the report, and the
/// hulls still cover every vertex of the mesh.
#[test]
fn a_non_manifold_mesh_imports_with_a_note() {
    // A tetrahedron with a fin: edge 1-2 carries three triangles.
    let fin = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0.5 -1 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\nf 1 2 5\n";
    for decomposer in [Decomposer::Hull, Decomposer::Vhacd] {
        let dir = temp_dir("non-manifold");
        std::fs::write(dir.join("fin.obj"), fin).unwrap();
        let r = r#"<robot name="r"><link name="arm"><collision><geometry><mesh filename="fin.obj"/></geometry></collision></link></robot>"#;
        std::fs::write(dir.join("r.urdf"), r).unwrap();
        let imported = import(&dir.join("r.urdf"), &options(decomposer))
            .unwrap_or_else(|e| panic!("{decomposer:?}: {e}"));
        assert!(
            imported
                .report
                .notes
                .iter()
                .any(|n| n.contains("not manifold")),
            "{:?}",
            imported.report.notes
        );
        let hulls: Vec<_> = imported.links[0]
            .hulls
            .iter()
            .map(|h| convex_hull(h).unwrap())
            .collect();
        for v in [[0.5, -1.0, 0.0], [0.0, 0.0, 1.0]] {
            let p = nalgebra::Vector3::from(v);
            let inside = hulls
                .iter()
                .any(|h| h.planes.iter().all(|(n, b)| n.dot(&p) - b <= 0.02));
            assert!(inside, "{decomposer:?}: vertex {v:?} is not covered");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
