//! Both decomposers (V-HACD in Rust, CoACD through tools/helpers/coacd_decompose.py)
//! and the `hull` / `none` modes.

use crate::import_support;

use import_support::*;
use sdrs::import::{Decomposer, ImportOptions, import};
use sdrs::scene::Scene;

fn opts(d: Decomposer) -> ImportOptions {
    ImportOptions {
        decomposer: d,
        threshold: if d == Decomposer::Coacd { 0.05 } else { 0.01 },
        ..ImportOptions::default()
    }
}

fn x_object() -> std::path::PathBuf {
    root().join("robots/single_jaw_gripper/objects/x_object.obj")
}

#[test]
fn vhacd_and_coacd_split_the_x_object_into_connected_unchanged_hulls() {
    if import_support::skip_without_venv() {
        return;
    }
    for d in [Decomposer::Vhacd, Decomposer::Coacd] {
        let imp = import(&x_object(), &opts(d)).unwrap_or_else(|e| panic!("{d:?}: {e}"));
        let l = &imp.report.links[0];
        eprintln!(
            "{d:?}: {} hulls, {} vertices, coverage {:.4}, union volume {:.4e} vs source {:.4e}, ties {:?}",
            l.hulls,
            l.vertices,
            l.coverage,
            l.union_volume,
            l.source_volume.unwrap(),
            l.connectivity
                .shared
                .iter()
                .map(|s| s.kind)
                .collect::<Vec<_>>()
        );
        assert!(l.hulls >= 2, "{d:?}: an X is not convex");
        assert_eq!(l.connectivity.components, 1, "{d:?}");
        let bridged = l
            .connectivity
            .shared
            .iter()
            .any(|s| s.kind == sdrs::import::connectivity::TieKind::Bridge);
        if d == Decomposer::Vhacd {
            // V-HACD parts touch exactly: ties never change a hull.
            assert!(!bridged);
            assert!(
                l.max_hull_volume_change <= 1e-9,
                "{d:?}: {}",
                l.max_hull_volume_change
            );
        } else {
            // CoACD can leave ~1e-5 gaps between parts: bridged, reported,
            // and the hulls change only slightly.
            assert!(
                l.max_hull_volume_change <= 1e-3,
                "{d:?}: {}",
                l.max_hull_volume_change
            );
            assert!(!bridged || l.max_hull_volume_change > 0.0);
        }
        assert!(l.coverage >= 0.95, "{d:?}");
        Scene::from_spec(imp.scene, &x_object()).unwrap();
    }
}

#[test]
fn coacd_decomposes_a_robot_link_mesh() {
    if import_support::skip_without_venv() {
        return;
    }
    let urdf = robot_urdf("single_jaw_gripper");
    let imp = import(&urdf, &opts(Decomposer::Coacd)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(imp.report.decomposer, "coacd");
    assert!(imp.report.links[0].hulls >= 2);
    assert!(imp.report.disconnected_links.is_empty());
}

#[test]
fn max_hulls_caps_the_vhacd_parts() {
    let o = ImportOptions {
        max_hulls: 2,
        ..opts(Decomposer::Vhacd)
    };
    let imp = import(&x_object(), &o).unwrap();
    assert!(imp.report.links[0].hulls <= 2);
    assert_eq!(imp.report.links[0].connectivity.components, 1);
}

#[test]
fn hull_mode_gives_one_hull_per_mesh() {
    let imp = import(&robot_urdf("spider"), &opts(Decomposer::Hull)).unwrap();
    for l in &imp.report.links {
        let expect = if l.name.ends_with("_lower") { 2 } else { 1 };
        assert_eq!(l.hulls, expect, "{}", l.name);
        assert_eq!(l.connectivity.components, 1, "{}", l.name);
    }
}

#[test]
fn none_mode_accepts_convex_meshes_and_rejects_others() {
    let cube = root().join("robots/parallel_jaw_gripper/objects/cube.obj");
    let imp = import(&cube, &opts(Decomposer::None)).unwrap();
    assert_eq!(imp.report.links[0].hulls, 1);
    assert_eq!(imp.report.links[0].vertices, 8);
    let err = import(&x_object(), &opts(Decomposer::None))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("x_object.obj") && err.contains("needs a convex mesh"),
        "{err}"
    );
}
