//! Coverage: for every authored robot (and object), ≥ 95 % of points sampled
//! on each source mesh lie inside, or within 2 % of the mesh's bounding-box
//! diagonal of, the link's hulls — checked independently with trimesh
//! (tools/check/check_coverage.py through the project venv) and by our report.

use crate::import_support;

use import_support::*;
use rayon::prelude::*;
use sdrs::import::write::{OutputPaths, write_outputs};
use sdrs::import::{ImportOptions, import};
use std::path::Path;

#[test]
fn authored_robots_cover_their_source_meshes_per_trimesh() {
    if import_support::skip_without_venv() {
        return;
    }
    let dir = temp_dir("coverage");
    let opts = ImportOptions::default();
    let mut inputs: Vec<std::path::PathBuf> = ROBOTS.iter().map(|r| robot_urdf(r)).collect();
    inputs.extend(object_meshes());
    // Inputs are independent: imported two at a time (each import is
    // single-threaded), then checked by trimesh in one Python process (a
    // start per input, mostly trimesh's and scipy's imports, was 28 of the
    // checks' 35 CPU-s).
    let designs: Vec<std::path::PathBuf> = inputs
        .par_iter()
        .enumerate()
        .map(|(k, input)| {
            let imp = import(input, &opts).unwrap_or_else(|e| panic!("{e}"));
            for l in &imp.report.links {
                assert!(
                    l.coverage >= 0.95,
                    "{}: link {} coverage {} (ours)",
                    input.display(),
                    l.name,
                    l.coverage
                );
            }
            let out = dir.join(format!("design{k}.yaml"));
            write_outputs(&imp, input, &OutputPaths::new(&out, None), false).unwrap();
            out
        })
        .collect();
    let mut args: Vec<&Path> = Vec::new();
    for (input, out) in inputs.iter().zip(&designs) {
        args.extend([input.as_path(), out.as_path()]);
    }
    args.extend([Path::new("--min"), Path::new("0.95")]);
    let (ok, stdout, err) = run_tool("check_coverage.py", &args);
    let reports: Vec<serde_json::Value> =
        serde_json::from_str(stdout.trim()).unwrap_or_else(|_| panic!("{stdout}\n{err}"));
    assert_eq!(reports.len(), inputs.len());
    for (input, summary) in inputs.iter().zip(&reports) {
        eprintln!(
            "{}: min coverage {} over {} links (trimesh)",
            input.strip_prefix(root()).unwrap().display(),
            summary["min_coverage"],
            summary["links"].as_object().map(|m| m.len()).unwrap_or(0)
        );
        assert!(
            summary["min_coverage"].as_f64().is_some_and(|c| c >= 0.95),
            "{}: {summary}\n{err}",
            input.display()
        );
    }
    assert!(ok, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn coverage_check_fails_when_a_hull_is_missing() {
    if import_support::skip_without_venv() {
        return;
    }
    // Drop a hull of the single-jaw gripper: trimesh must see the hole.
    let input = robot_urdf("single_jaw_gripper");
    let opts = ImportOptions::default();
    let mut imp = import(&input, &opts).unwrap();
    let link = &mut imp.scene.robots[0].links[0];
    assert!(link.hulls.len() >= 2);
    link.hulls.truncate(1);
    imp.scene.robots[0].design = None;
    let dir = temp_dir("coverage-hole");
    let out = dir.join("design.yaml");
    std::fs::write(&out, sdrs::import::write::to_yaml(&imp.scene)).unwrap();
    let (ok, _stdout, err) = run_tool("check_coverage.py", &[&input, &out]);
    assert!(!ok && err.contains("jaw"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
