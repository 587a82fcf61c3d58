//! A real third-party robot (KUKA iiwa, URDF + STL meshes from the
//! `pybullet` package installed by tools/setup/setup_python.sh; not committed)
//! imports with V-HACD into a connected design and simulates.

use crate::import_support;

use import_support::*;
use sdrs::import::{ImportOptions, import};
use sdrs::scene::Scene;

#[test]
fn third_party_kuka_iiwa_imports_and_simulates() {
    if import_support::skip_without_venv() {
        return;
    }
    let urdf = third_party_urdf();
    let opts = ImportOptions::default();
    let t = std::time::Instant::now();
    let imp = import(&urdf, &opts).unwrap_or_else(|e| panic!("{e}"));
    let r = &imp.report;
    eprintln!(
        "kuka_iiwa: {} links, {} hulls, {} vertices in {:.2} s; notes: {:?}",
        r.links.len(),
        r.total_hulls,
        r.total_vertices,
        t.elapsed().as_secs_f64(),
        r.notes
    );
    for l in &r.links {
        eprintln!(
            "  {}: {} hulls, coverage {:.4}, components {}",
            l.name, l.hulls, l.coverage, l.connectivity.components
        );
        assert!(l.coverage >= 0.95, "{}: coverage {}", l.name, l.coverage);
    }
    assert!(
        r.disconnected_links.is_empty(),
        "{:?}",
        r.disconnected_links
    );
    assert_eq!(r.links.len(), 8);
    let scene = Scene::from_spec(imp.scene.clone(), &urdf).unwrap();
    assert_eq!(scene.model.ndof(), 7);
    let mut sim = scene.simulator();
    for _ in 0..3 {
        sim.step().unwrap();
    }
}
