//! COLLADA (`.dae`) meshes, checked against an independent reader and
//! against the same parts' STL twins.
//!
//! - Every `.dae` shipped in `pybullet_data` (racecar parts, a course, a
//!   cone in inches, a duck in centimetres) is read by our reader
//!   (mesh-loader + our unit handling) and by trimesh/pycollada (scene graph
//!   with node transforms; pycollada's `unitmeter` applied by the script).
//!   Bounds must agree to 1e-6 of the mesh's diagonal (positions are f32 in
//!   both readers) and surface area to 1e-5 relative.
//! - A URDF whose collision meshes are the racecar's `.dae` files imports the
//!   same hulls as the same URDF with the `.STL` twins, and the report names
//!   the files' `Y_UP` axis, which is not applied.

use crate::import_support;

use import_support::*;
use sdrs::import::import;
use sdrs::import::mesh::{MeshContext, load_mesh};
use std::path::{Path, PathBuf};

fn pybullet_data() -> PathBuf {
    third_party_urdf()
        .parent()
        .and_then(Path::parent)
        .unwrap()
        .to_path_buf()
}

/// Per-axis minimum and maximum of `points`.
fn extent(points: impl Iterator<Item = [f64; 3]>) -> ([f64; 3], [f64; 3]) {
    points.fold(([f64::MAX; 3], [f64::MIN; 3]), |(mut lo, mut hi), p| {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
        (lo, hi)
    })
}

fn all_dae() -> Vec<PathBuf> {
    let d = pybullet_data();
    let mut v: Vec<PathBuf> = std::fs::read_dir(d.join("racecar/meshes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "dae"))
        .collect();
    v.push(d.join("duck.dae"));
    // Ours: nested nodes, a unit, a polylist, one geometry instanced three
    // times (directly, in a rotated and scaled child, through
    // <instance_node> with a <matrix>).
    v.push(root().join("tests/data/cube_cm.dae"));
    v.push(root().join("tests/data/instanced_mm.dae"));
    v.sort();
    v
}

const TRIMESH_SCRIPT: &str = r#"
import sys, json, trimesh, collada
out = {}
for f in sys.argv[1:]:
    unit = collada.Collada(f).assetInfo.unitmeter or 1.0
    m = trimesh.load(f, force='mesh')
    out[f] = {"lo": (m.bounds[0] * unit).tolist(), "hi": (m.bounds[1] * unit).tolist(),
              "area": float(m.area) * unit * unit}
print(json.dumps(out))
"#;

#[test]
fn dae_meshes_match_trimesh_and_pycollada() {
    if import_support::skip_without_venv() {
        return;
    }
    let files = all_dae();
    assert!(
        files.len() >= 14,
        "expected the racecar .dae files, found {files:?}"
    );
    let out = std::process::Command::new(venv_python())
        .arg("-c")
        .arg(TRIMESH_SCRIPT)
        .args(&files)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "trimesh/pycollada failed (run tools/setup/setup_python.sh): {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let reference: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for f in &files {
        let ctx = MeshContext {
            file: f.clone(),
            element: "test".into(),
        };
        let (m, note) = load_mesh(f, &ctx).unwrap_or_else(|e| panic!("{e}"));
        let r = &reference[f.to_str().unwrap()];
        let (lo, hi) = extent(m.vertices.iter().map(|v| [v.x, v.y, v.z]));
        let diag = m.diagonal();
        let mut worst = 0.0f64;
        for k in 0..3 {
            worst = worst.max((lo[k] - r["lo"][k].as_f64().unwrap()).abs());
            worst = worst.max((hi[k] - r["hi"][k].as_f64().unwrap()).abs());
        }
        let area_ref = r["area"].as_f64().unwrap();
        let area_rel = (m.area() - area_ref).abs() / area_ref;
        eprintln!(
            "{}: {} triangles, diagonal {diag:.4} m, bounds error {:.1e} of diagonal, area rel. error {area_rel:.1e}, note: {note:?}",
            f.file_name().unwrap().to_string_lossy(),
            m.triangles.len(),
            worst / diag
        );
        assert!(
            worst <= 1e-6 * diag,
            "{}: bounds differ by {worst}",
            f.display()
        );
        assert!(
            area_rel <= 1e-5,
            "{}: area {} vs {area_ref}",
            f.display(),
            m.area()
        );
    }
}

fn racecar_urdf(dir: &Path, ext: &str) -> PathBuf {
    let meshes = pybullet_data().join("racecar/meshes");
    let chassis = meshes.join(format!("chassis.{ext}"));
    let wheel = meshes.join(format!("left_front_wheel.{ext}"));
    let text = format!(
        r#"<robot name="car">
  <link name="chassis"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><geometry><mesh filename="{}"/></geometry></collision></link>
  <link name="wheel"><inertial><mass value="0.3"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
    <collision><origin xyz="0 0 0" rpy="1.5708 0 0"/><geometry><mesh filename="{}"/></geometry></collision></link>
  <joint name="axle" type="continuous"><parent link="chassis"/><child link="wheel"/>
    <origin xyz="0.33 0.15 0"/><axis xyz="0 1 0"/></joint>
</robot>"#,
        chassis.display(),
        wheel.display()
    );
    let p = dir.join(format!("car_{ext}.urdf"));
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn urdf_with_dae_collisions_imports_like_its_stl_twins() {
    if import_support::skip_without_venv() {
        return;
    }
    let dir = temp_dir("collada-urdf");
    let opts = hull_options();
    let dae = import(&racecar_urdf(&dir, "dae"), &opts).unwrap_or_else(|e| panic!("{e}"));
    let stl = import(&racecar_urdf(&dir, "STL"), &opts).unwrap_or_else(|e| panic!("{e}"));
    let y_up: Vec<&String> = dae
        .report
        .notes
        .iter()
        .filter(|n| n.contains("Y_UP"))
        .collect();
    assert_eq!(y_up.len(), 2, "notes: {:?}", dae.report.notes);
    assert!(!stl.report.notes.iter().any(|n| n.contains("Y_UP")));
    let (a, b) = (&dae.scene.robots[0], &stl.scene.robots[0]);
    assert_eq!(a.links.len(), 2);
    // The STL twins hold the same parts as binary f32 and the .dae as
    // decimal text, so near-coplanar points of the round wheel may land on
    // either side of a hull face: compare each hull's extent, and its
    // vertex count to 2 %.
    let mut worst = 0.0f64;
    for (la, lb) in a.links.iter().zip(&b.links) {
        assert_eq!(la.hulls.len(), lb.hulls.len(), "link {}", la.name);
        for (ha, hb) in la.hulls.iter().zip(&lb.hulls) {
            let (va, vb) = (ha.vertices.as_ref().unwrap(), hb.vertices.as_ref().unwrap());
            let (na, nb) = (va.len() as f64, vb.len() as f64);
            eprintln!(
                "link {}: {na} hull vertices from .dae, {nb} from .STL",
                la.name
            );
            assert!(
                (na - nb).abs() <= 0.02 * nb,
                "link {}: {na} vs {nb} vertices",
                la.name
            );
            let ((lo_a, hi_a), (lo_b, hi_b)) =
                (extent(va.iter().copied()), extent(vb.iter().copied()));
            for k in 0..3 {
                worst = worst
                    .max((lo_a[k] - lo_b[k]).abs())
                    .max((hi_a[k] - hi_b[k]).abs());
            }
        }
    }
    eprintln!("dae vs STL hull extents: max difference {worst:.2e} m");
    assert!(worst <= 1e-6, "hull extents differ by {worst} m");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bare_dae_file_imports_as_one_free_body() {
    if import_support::skip_without_venv() {
        return;
    }
    let cone = pybullet_data().join("racecar/meshes/cone.dae");
    let opts = hull_options();
    let imp = import(&cone, &opts).unwrap_or_else(|e| panic!("{e}"));
    let l = &imp.scene.robots[0].links[0];
    let zmax = l
        .hulls
        .iter()
        .flat_map(|h| h.vertices.iter().flatten())
        .map(|v| v[2])
        .fold(f64::MIN, f64::max);
    // 6.69 inches tall in the file (<unit meter="0.0254"/>): 0.17 m.
    assert!((zmax - 0.17).abs() < 1e-4, "cone height {zmax} m");
}

/// The fuzzing seed `tests/data/cube_cm.dae`: a unit cube scaled by 2,
/// rotated 90° about z and then translated by 5 along x, in centimetres —
/// the unit applies to the translation as well: x ∈ [0.03, 0.05] m.
#[test]
fn nested_nodes_and_units_compose_in_the_right_order() {
    let p = root().join("tests/data/cube_cm.dae");
    let ctx = MeshContext {
        file: p.clone(),
        element: "test".into(),
    };
    let (m, note) = load_mesh(&p, &ctx).unwrap_or_else(|e| panic!("{e}"));
    assert!(note.is_some_and(|n| n.contains("Y_UP")));
    assert_eq!(m.vertices.len(), 8);
    assert_eq!(m.triangles.len(), 12);
    assert_eq!(m.volume().map(|v| (v * 1e6).round()), Some(8.0)); // 8 cm³
    let want_lo = [0.03, 0.0, 0.0];
    let want_hi = [0.05, 0.02, 0.02];
    for v in &m.vertices {
        for k in 0..3 {
            assert!(
                v[k] > want_lo[k] - 1e-9 && v[k] < want_hi[k] + 1e-9,
                "vertex {v:?}"
            );
        }
    }
}

/// Found by fuzzing: a duplicated `<library_visual_scenes>` line nests one
/// library inside another; the overlapping ranges made the rewrite for
/// mesh-loader slice out of bounds (a panic). Now the outer library is the
/// scene; its visual scene holds no `<node>`, so the mesh is empty: an error.
#[test]
fn nested_libraries_found_by_fuzzing_do_not_panic() {
    let p = root().join("tests/data/repro/collada_nested_scenes.dae");
    let ctx = MeshContext {
        file: p.clone(),
        element: "test".into(),
    };
    let r = std::panic::catch_unwind(|| load_mesh(&p, &ctx).map(|(m, _)| m.triangles.len()));
    let r = r.expect("no panic");
    eprintln!(
        "nested libraries: {:?}",
        r.as_ref().map_err(|e| e.to_string())
    );
}
