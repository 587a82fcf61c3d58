//! Bad input → an error naming the file and the element, and no output file
//! left behind (one test each). Runs the command's entry point
//! (`run_job`, what `sdrs import` runs) with the job its flags select.

mod common;
mod import_support;

use import_support::*;
use sdrs::import::{Decomposer, ImportJob, run_job};
use std::path::{Path, PathBuf};

const TET: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

fn urdf(joint_type: &str, mesh: &str, extra: &str) -> String {
    format!(
        r#"<?xml version="1.0"?>
<robot name="bad">
  <link name="base">
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
  <link name="arm">
    <inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision><geometry><mesh filename="{mesh}"/></geometry></collision>
  </link>
  <joint name="shoulder" type="{joint_type}">
    <parent link="base"/><child link="arm"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
{extra}</robot>
"#
    )
}

/// Writes `files` into a fresh directory, imports `input` with a report, and
/// returns the error text; asserts that only the inputs remain.
fn fails(name: &str, files: &[(&str, &str)], input: &str) -> (String, PathBuf) {
    let dir = temp_dir(name);
    for (f, text) in files {
        std::fs::write(dir.join(f), text).unwrap();
    }
    let before = listing(&dir);
    let inp = dir.join(input);
    let out = dir.join("out/design.yaml");
    let report = dir.join("out/report.json");
    let job = ImportJob {
        report: Some(report),
        ..ImportJob::new(inp.clone(), out)
    };
    let err = run_job(&job).expect_err("the import must fail");
    let text = err.to_string();
    eprintln!("{name}: {text}");
    let after: Vec<String> = listing(&dir).into_iter().filter(|f| f != "out").collect();
    assert_eq!(after, before, "{name}: files were left behind ({text})");
    assert!(
        text.contains(&inp.display().to_string()),
        "{name}: the message must name the file: {text}"
    );
    (text, dir)
}

fn cleanup(dir: &Path) {
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn missing_mesh_file_names_the_urdf_link_and_mesh() {
    let (e, dir) = fails(
        "missing",
        &[("r.urdf", &urdf("revolute", "meshes/arm.obj", ""))],
        "r.urdf",
    );
    assert!(
        e.contains("link \"arm\" collision[0]") && e.contains("arm.obj") && e.contains("not found"),
        "{e}"
    );
    cleanup(&dir);
    let (e, dir) = fails(
        "missing-pkg",
        &[(
            "r.urdf",
            &urdf("revolute", "package://nowhere_pkg/arm.stl", ""),
        )],
        "r.urdf",
    );
    assert!(
        e.contains("nowhere_pkg") && e.contains("ROS_PACKAGE_PATH"),
        "{e}"
    );
    cleanup(&dir);
}

#[test]
fn empty_mesh_names_the_mesh() {
    let (e, dir) = fails(
        "empty",
        &[
            ("r.urdf", &urdf("revolute", "arm.obj", "")),
            ("arm.obj", "# nothing\nv 0 0 0\n"),
        ],
        "r.urdf",
    );
    assert!(
        e.contains("arm.obj") && e.contains("empty") && e.contains("link \"arm\""),
        "{e}"
    );
    cleanup(&dir);
}

/// Non-manifold meshes import (see `tests/import_robustness.rs`) except
/// with `--decomposer none`, which needs a closed convex mesh.
#[test]
fn non_manifold_mesh_with_decomposer_none_names_the_mesh() {
    // A tetrahedron with a fin: edge 1-2 carries three triangles.
    let fin = format!("{TET}v 0.5 -1 0\nf 1 2 5\n");
    let dir = temp_dir("nonmanifold-none");
    std::fs::write(dir.join("r.urdf"), urdf("revolute", "arm.obj", "")).unwrap();
    std::fs::write(dir.join("arm.obj"), &fin).unwrap();
    let inp = dir.join("r.urdf");
    let out = dir.join("out/design.yaml");
    let mut job = ImportJob::new(inp.clone(), out.clone());
    job.options.decomposer = Decomposer::None;
    let e = run_job(&job)
        .expect_err("none needs a closed convex mesh")
        .to_string();
    assert!(
        e.contains("link \"arm\"") && e.contains("closed convex"),
        "{e}"
    );
    assert!(!out.exists());
    cleanup(&dir);
}

#[test]
fn unknown_joint_type_names_the_joint() {
    for t in ["planar", "hinge"] {
        let (e, dir) = fails(
            &format!("joint-{t}"),
            &[("r.urdf", &urdf(t, "arm.obj", "")), ("arm.obj", TET)],
            "r.urdf",
        );
        assert!(
            e.contains("joint \"shoulder\"") && e.contains(t) && e.contains("supported"),
            "{e}"
        );
        cleanup(&dir);
    }
}

#[test]
fn kinematic_loop_names_the_links_and_joints() {
    let second_parent = r#"  <link name="hand"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="wrist" type="fixed"><parent link="arm"/><child link="hand"/></joint>
  <joint name="closing" type="fixed"><parent link="base"/><child link="hand"/></joint>
"#;
    let (e, dir) = fails(
        "loop",
        &[
            ("r.urdf", &urdf("revolute", "arm.obj", second_parent)),
            ("arm.obj", TET),
        ],
        "r.urdf",
    );
    assert!(
        e.contains("kinematic loop") && e.contains("\"hand\"") && e.contains("closing"),
        "{e}"
    );
    cleanup(&dir);
    let cycle = r#"  <joint name="back" type="fixed"><parent link="arm"/><child link="base"/></joint>
"#;
    let (e, dir) = fails(
        "cycle",
        &[
            ("r.urdf", &urdf("revolute", "arm.obj", cycle)),
            ("arm.obj", TET),
        ],
        "r.urdf",
    );
    assert!(
        e.contains("kinematic loop") && e.contains("\"base\"") && e.contains("\"arm\""),
        "{e}"
    );
    cleanup(&dir);
}

#[test]
fn malformed_xml_names_the_file_and_line() {
    let text = urdf("revolute", "arm.obj", "")
        .replace("</link>\n  <link name=\"arm\">", "\n  <link name=\"arm\">");
    let (e, dir) = fails("xml", &[("r.urdf", &text), ("arm.obj", TET)], "r.urdf");
    assert!(
        e.contains("malformed URDF XML") && e.contains("line"),
        "{e}"
    );
    cleanup(&dir);
}

#[test]
fn unsupported_mesh_format_says_how_to_convert() {
    let (e, dir) = fails(
        "ply",
        &[
            ("r.urdf", &urdf("revolute", "arm.ply", "")),
            ("arm.ply", "ply\nformat ascii 1.0\nend_header\n"),
        ],
        "r.urdf",
    );
    assert!(
        e.contains(".ply") && e.contains("trimesh") && e.contains("Blender"),
        "{e}"
    );
    cleanup(&dir);
}

/// COLLADA is read (`src/import/collada/`); a document without geometry is
/// an empty mesh, named with the file and element.
#[test]
fn a_collada_file_without_geometry_is_an_empty_mesh() {
    let (e, dir) = fails(
        "dae",
        &[
            ("r.urdf", &urdf("revolute", "arm.dae", "")),
            ("arm.dae", "<COLLADA/>"),
        ],
        "r.urdf",
    );
    assert!(
        e.contains("arm.dae") && e.contains("link \"arm\" collision[0]") && e.contains("empty"),
        "{e}"
    );
    cleanup(&dir);
}

#[test]
fn a_failure_while_writing_leaves_nothing_behind() {
    // The report's directory is a file: writing fails after the design and
    // meshes were staged; everything staged must be removed.
    let dir = temp_dir("write-fail");
    std::fs::write(dir.join("arm.obj"), TET).unwrap();
    std::fs::write(dir.join("blocker"), "not a directory").unwrap();
    let before = listing(&dir);
    let inp = dir.join("arm.obj");
    let out = dir.join("design.yaml");
    let report = dir.join("blocker/report.json");
    let job = ImportJob {
        report: Some(report),
        ..ImportJob::new(inp.clone(), out)
    };
    assert!(run_job(&job).is_err());
    assert_eq!(listing(&dir), before);
    cleanup(&dir);
}

#[test]
fn the_input_is_never_overwritten() {
    let dir = temp_dir("input-safe");
    std::fs::write(dir.join("arm.obj"), TET).unwrap();
    let inp = dir.join("arm.obj");
    let job = ImportJob {
        force: true,
        ..ImportJob::new(inp.clone(), inp.clone())
    };
    let e = run_job(&job).unwrap_err().to_string();
    assert!(e.contains("input"), "{e}");
    assert_eq!(std::fs::read_to_string(&inp).unwrap(), TET);
    cleanup(&dir);
}

#[test]
fn coacd_without_python_or_package_gives_the_install_command() {
    // Only this test touches SDRS_PYTHON (tests in this file run in one
    // process; no other test here runs Python).
    let dir = temp_dir("nopython");
    std::fs::write(dir.join("arm.obj"), TET).unwrap();
    let inp = dir.join("arm.obj");
    let opts = sdrs::import::ImportOptions {
        decomposer: sdrs::import::Decomposer::Coacd,
        ..Default::default()
    };
    unsafe { std::env::set_var("SDRS_PYTHON", dir.join("no-such-python")) };
    let e = sdrs::import::import(&inp, &opts).unwrap_err().to_string();
    assert!(
        e.contains("tools/setup/setup_python.sh") && e.contains("cannot run Python"),
        "{e}"
    );
    // An interpreter without the package: a venv-less python with an empty
    // path for site packages.
    let fake = dir.join("fake-python.sh");
    std::fs::write(&fake, "#!/bin/sh\nexec python3 -S -I \"$@\"\n").unwrap();
    std::process::Command::new("chmod")
        .arg("+x")
        .arg(&fake)
        .status()
        .unwrap();
    unsafe { std::env::set_var("SDRS_PYTHON", &fake) };
    let e = sdrs::import::import(&inp, &opts).unwrap_err().to_string();
    unsafe { std::env::remove_var("SDRS_PYTHON") };
    assert!(
        e.contains("missing Python package") && e.contains("tools/setup/setup_python.sh"),
        "{e}"
    );
    cleanup(&dir);
}

// Reproducers of panics and silent repairs (shared/repro/urdf_*): every
// number entering from a URDF or mesh is checked before geometry code sees it.

#[test]
fn huge_box_is_an_error_not_a_panic() {
    let r = r#"<robot name="r"><link name="a"><collision><geometry><box size="1e308 1 1"/></geometry></collision></link></robot>"#;
    let (e, dir) = fails("huge-box", &[("r.urdf", r)], "r.urdf");
    assert!(
        e.contains("link \"a\" collision[0]")
            && e.contains("box dimensions")
            && e.contains("1e308"),
        "{e}"
    );
    cleanup(&dir);
}

#[test]
fn non_finite_collision_origin_is_an_error_not_a_panic() {
    let r = r#"<robot name="r"><link name="a"><collision><origin xyz="nan 0 0"/><geometry><mesh filename="t.obj"/></geometry></collision></link></robot>"#;
    let (e, dir) = fails("nan-origin", &[("r.urdf", r), ("t.obj", TET)], "r.urdf");
    assert!(
        e.contains("link \"a\" collision[0]") && e.contains("origin") && e.contains("NaN"),
        "{e}"
    );
    cleanup(&dir);
}

#[test]
fn huge_mesh_scale_is_an_error_not_a_panic() {
    let r = r#"<robot name="r"><link name="a"><collision><geometry><mesh filename="t.obj" scale="1e308 1e308 1e308"/></geometry></collision></link></robot>"#;
    let (e, dir) = fails("huge-scale", &[("r.urdf", r), ("t.obj", TET)], "r.urdf");
    assert!(
        e.contains("link \"a\" collision[0]")
            && e.contains("t.obj")
            && e.contains("largest accepted"),
        "{e}"
    );
    cleanup(&dir);
}

#[test]
fn huge_joint_origin_names_the_joint() {
    let r = urdf("revolute", "t.obj", "").replace("xyz=\"0 0 0.1\"", "xyz=\"1e308 0 0.1\"");
    let (e, dir) = fails("huge-joint", &[("r.urdf", &r), ("t.obj", TET)], "r.urdf");
    assert!(
        e.contains("joint \"shoulder\"") && e.contains("largest accepted"),
        "{e}"
    );
    cleanup(&dir);
}

#[test]
fn non_finite_or_negative_mass_names_the_link() {
    for (i, m) in ["nan", "inf", "-1"].iter().enumerate() {
        let r = urdf("revolute", "t.obj", "")
            .replace("mass value=\"1\"", &format!("mass value=\"{m}\""));
        let (e, dir) = fails(
            &format!("mass-{i}"),
            &[("r.urdf", &r), ("t.obj", TET)],
            "r.urdf",
        );
        assert!(
            e.contains("link \"arm\" <inertial>") && e.contains("mass"),
            "{m}: {e}"
        );
        cleanup(&dir);
    }
}

#[test]
fn a_malformed_number_names_the_line_the_element_and_the_attribute() {
    let r = "<robot name=\"r\">\n  <link name=\"a\">\n    <collision><geometry><box size=\"1 x 1\"/></geometry></collision>\n  </link>\n</robot>\n";
    let (e, dir) = fails("bad-number", &[("r.urdf", r)], "r.urdf");
    for part in [
        "line 3",
        "<link name=\"a\">",
        "<box>",
        "size=\"1 x 1\"",
        "\"x\" is not a number",
    ] {
        assert!(e.contains(part), "{part:?} missing: {e}");
    }
    cleanup(&dir);
    let r = "<robot name=\"r\">\n  <link name=\"a\">\n    <visual><origin xyz=\"0 0\"/><geometry><sphere radius=\"1\"/></geometry></visual>\n  </link>\n</robot>\n";
    let (e, dir) = fails("bad-count", &[("r.urdf", r)], "r.urdf");
    assert!(
        e.contains("line 3") && e.contains("must be 3 numbers, got 2"),
        "{e}"
    );
    cleanup(&dir);
}

#[test]
fn an_empty_urdf_says_so() {
    let (e, dir) = fails("empty-urdf", &[("r.urdf", "")], "r.urdf");
    assert!(e.contains("the file is empty"), "{e}");
    cleanup(&dir);
}
