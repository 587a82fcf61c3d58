//! pybullet's `<plane>` and `<cdf>` geometry (see
//! `src/import/pybullet_shapes.rs`): a plane becomes a slab whose top face is
//! the plane, in the collision element's frame; a `<cdf>` collision uses the
//! link's visual geometry; both are named in the report.

use crate::import_support;

use import_support::*;
use nalgebra::{Matrix3, Vector3};
use sdrs::import::{Decomposer, ImportOptions, import};
use sdrs::math::rpy_to_matrix;

fn opts() -> ImportOptions {
    ImportOptions {
        decomposer: Decomposer::Hull,
        ..ImportOptions::default()
    }
}

fn hull_points(imp: &sdrs::import::Imported, link: usize) -> Vec<Vector3<f64>> {
    imp.scene.robots[0].links[link]
        .hulls
        .iter()
        .flat_map(|h| h.vertices.iter().flatten())
        .map(|v| Vector3::from(*v))
        .collect()
}

#[test]
fn a_tilted_plane_becomes_a_slab_below_it() {
    let dir = temp_dir("pybullet-plane");
    let (xyz, rpy) = ([0.1, -0.2, 0.3], [0.2, -0.1, 0.4]);
    let normal = Vector3::new(0.0, 0.6, 0.8);
    let urdf = dir.join("plane.urdf");
    std::fs::write(
        &urdf,
        format!(
            r#"<robot name="p"><link name="ground">
  <inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>
  <collision><origin xyz="{} {} {}" rpy="{} {} {}"/><geometry><plane normal="0 0.6 0.8"/></geometry></collision>
</link></robot>"#,
            xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2]
        ),
    )
    .unwrap();
    let imp = import(&urdf, &opts()).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        imp.report
            .notes
            .iter()
            .any(|n| n.contains("slab") && n.contains("collision[0]")),
        "{:?}",
        imp.report.notes
    );
    let r: Matrix3<f64> = rpy_to_matrix(&rpy);
    let n_link = r * normal;
    let p0 = Vector3::from(xyz);
    let pts = hull_points(&imp, 0);
    assert_eq!(pts.len(), 8);
    // Four corners on the plane, four one thickness below it; all 100 m
    // apart in the plane.
    let mut heights: Vec<f64> = pts.iter().map(|p| (p - p0).dot(&n_link)).collect();
    heights.sort_by(f64::total_cmp);
    for (k, h) in heights.iter().enumerate() {
        let want = if k < 4 { -1.0 } else { 0.0 };
        assert!((h - want).abs() < 1e-9, "heights {heights:?}");
    }
    let top: Vec<_> = pts
        .iter()
        .filter(|p| (*p - p0).dot(&n_link).abs() < 1e-9)
        .collect();
    let span = top
        .iter()
        .flat_map(|a| top.iter().map(move |b| (*a - *b).norm()))
        .fold(0.0, f64::max);
    assert!((span - 100.0 * 2f64.sqrt()).abs() < 1e-9, "diagonal {span}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_cdf_collision_uses_the_visual_geometry_or_is_refused_without_one() {
    let dir = temp_dir("pybullet-cdf");
    let with_visual = dir.join("cdf.urdf");
    std::fs::write(
        &with_visual,
        r#"<robot name="c"><link name="box">
  <visual><origin xyz="0 0 0.5"/><geometry><box size="1 2 3"/></geometry></visual>
  <collision><geometry><cdf filename="box.cdf"/></geometry></collision>
</link></robot>"#,
    )
    .unwrap();
    let imp = import(&with_visual, &opts()).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        imp.report
            .notes
            .iter()
            .any(|n| n.contains("<cdf") && n.contains("visual geometry")),
        "{:?}",
        imp.report.notes
    );
    let pts = hull_points(&imp, 0);
    let zmax = pts.iter().map(|p| p.z).fold(f64::MIN, f64::max);
    let ymax = pts.iter().map(|p| p.y).fold(f64::MIN, f64::max);
    assert!(
        (zmax - 2.0).abs() < 1e-12 && (ymax - 1.0).abs() < 1e-12,
        "{pts:?}"
    );

    let without = dir.join("cdf_only.urdf");
    std::fs::write(
        &without,
        r#"<robot name="c"><link name="box">
  <collision><geometry><cdf filename="box.cdf"/></geometry></collision>
</link></robot>"#,
    )
    .unwrap();
    let err = match import(&without, &opts()) {
        Ok(_) => panic!("a <cdf> without visual geometry was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("cdf_only.urdf")
            && err.contains("link \"box\" collision[0]")
            && err.contains("box.cdf"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
