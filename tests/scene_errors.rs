//! Bad scene input gets an error naming the file and the element, never a
//! panic. One test per kind of mistake.

use sdrs::scene::{Scene, SceneError};
use std::path::PathBuf;

const GOOD_LINK: &str = r#"
      - name: arm
        joint: {name: hinge, type: revolute, axis: [0, 1, 0]}
        mass: 1.0
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]"#;

/// Writes `text` to a temporary file in a folder of its own and loads it.
///
/// One folder per test: tests run in parallel, and a shared folder could be
/// removed by one test between another's `create_dir_all` and `write`.
fn load(name: &str, text: &str) -> (PathBuf, String) {
    let dir = std::env::temp_dir().join(format!(
        "sdrs-scene-errors-{}-{}",
        std::process::id(),
        name.replace(['/', '.'], "_")
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let err = Scene::load(&path).expect_err("the scene must be rejected");
    let _ = std::fs::remove_file(&path);
    let _ = std::fs::remove_dir(&dir);
    (path, err.to_string())
}

fn assert_names(msg: &str, path: &std::path::Path, parts: &[&str]) {
    assert!(
        msg.contains(&path.display().to_string()),
        "message does not name the file: {msg}"
    );
    for p in parts {
        assert!(msg.contains(p), "message does not mention {p:?}: {msg}");
    }
}

#[test]
fn malformed_yaml_is_reported_with_file_and_line() {
    let text = format!("dt: 0.01\nrobots:\n  - name: r\n    links: [{GOOD_LINK}\n");
    let (path, msg) = load("malformed.yaml", &text);
    assert_names(&msg, &path, &["malformed scene", "line"]);
}

#[test]
fn unknown_joint_type_is_reported_with_the_element() {
    let text = "dt: 0.01\nrobots:\n  - name: r\n    links:\n      - name: arm\n        joint: {type: hinge, axis: [0, 1, 0]}\n        mass: 1\n        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]\n";
    let (path, msg) = load("unknown_joint.yaml", text);
    assert_names(
        &msg,
        &path,
        &["robots[0].links[0].joint", "hinge", "revolute", "line 6"],
    );
}

#[test]
fn hull_with_coplanar_vertices_is_rejected() {
    let text = "dt: 0.01\nrobots:\n  - name: r\n    links:\n      - name: plate\n        joint: {type: fixed}\n        mass: 1\n        hulls:\n          - box: {size: [0.1, 0.1, 0.1]}\n          - vertices: [[0,0,0],[1,0,0],[0,1,0],[1,1,0],[0.5,0.5,0]]\n";
    let (path, msg) = load("coplanar.yaml", text);
    assert_names(
        &msg,
        &path,
        &["robot \"r\"", "link \"plate\"", "hulls[1]", "coplanar"],
    );
}

#[test]
fn hull_with_too_few_vertices_is_rejected() {
    let text = "dt: 0.01\nrobots:\n  - name: r\n    links:\n      - name: tri\n        joint: {type: fixed}\n        mass: 1\n        hulls: [{vertices: [[0,0,0],[1,0,0],[0,1,0]]}]\n";
    let (path, msg) = load("three_vertices.yaml", text);
    assert_names(
        &msg,
        &path,
        &["link \"tri\"", "hulls[0]", "at least 4 vertices"],
    );
}

#[test]
fn kinematic_cycle_is_rejected_naming_the_links() {
    let text = r#"dt: 0.01
robots:
  - name: loop
    links:
      - name: a
        parent: c
        joint: {type: revolute, axis: [0, 0, 1]}
        mass: 1
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
      - name: b
        parent: a
        joint: {type: revolute, axis: [0, 0, 1]}
        mass: 1
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
      - name: c
        parent: b
        joint: {type: revolute, axis: [0, 0, 1]}
        mass: 1
        hulls: [{box: {size: [0.1, 0.1, 0.1]}}]
"#;
    let (path, msg) = load("cycle.yaml", text);
    assert_names(
        &msg,
        &path,
        &["robot \"loop\"", "kinematic cycle", "a", "b", "c"],
    );
}

#[test]
fn non_positive_time_step_is_rejected() {
    for (i, dt) in ["0", "-0.001", ".nan"].iter().enumerate() {
        let text = format!("dt: {dt}\nrobots:\n  - name: r\n    links:{GOOD_LINK}\n");
        let (path, msg) = load(&format!("dt{i}.yaml"), &text);
        assert_names(&msg, &path, &["dt", "positive"]);
    }
}

#[test]
fn unknown_parent_and_bad_target_are_rejected() {
    let text =
        format!("dt: 0.01\nrobots:\n  - name: r\n    links:{GOOD_LINK}\n        parent: nowhere\n");
    let (path, msg) = load("parent.yaml", &text);
    assert_names(&msg, &path, &["link \"arm\".parent", "nowhere"]);
    let text = format!(
        "dt: 0.01\nrobots:\n  - name: r\n    links:{GOOD_LINK}\n    controller:\n      targets: {{elbow: {{type: constant, value: 1}}}}\n"
    );
    let (path, msg) = load("target.yaml", &text);
    assert_names(
        &msg,
        &path,
        &["controller.targets.elbow", "no joint named", "hinge"],
    );
}

#[test]
fn missing_file_is_an_io_error_naming_the_path() {
    let err = Scene::load("/nonexistent/scene.yaml").unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }));
    assert!(err.to_string().contains("/nonexistent/scene.yaml"));
}

// Sizes (shared/repro/sim_chain_links_*): a documented maximum instead of
// an allocation failure, a capacity-overflow panic or a hang.

#[test]
fn absurd_chain_lengths_are_rejected_with_the_maximum() {
    for (i, n) in ["9223372036854775808", "1099511627776", "100000"]
        .iter()
        .enumerate()
    {
        let text = format!(
            "version: 1\ndt: 0.005\nsteps: 5\nrobots:\n- name: c0\n  chain: {{links: {n}, link_length: 0.2, link_width: 0.05, link_mass: 0.1}}\n"
        );
        let t0 = std::time::Instant::now();
        let (path, msg) = load(&format!("chain{i}.yaml"), &text);
        assert!(t0.elapsed().as_secs_f64() < 5.0, "took {:?}", t0.elapsed());
        assert_names(&msg, &path, &["robot \"c0\": chain.links", "maximum"]);
    }
}

#[test]
fn too_many_degrees_of_freedom_are_rejected_before_any_large_allocation() {
    // Two robots of 3000 ball-jointed links: 12000 coordinates.
    let chain = "chain: {links: 3000, link_length: 0.2, link_width: 0.05, link_mass: 0.1}";
    let text = format!(
        "version: 1\ndt: 0.005\nrobots:\n- name: a\n  {chain}\n- name: b\n  base: {{xyz: [5, 0, 0]}}\n  {chain}\n"
    );
    let (path, msg) = load("dof.yaml", &text);
    assert_names(&msg, &path, &["12000 degrees of freedom", "maximum"]);
}

/// Scene building is linear in the number of links: a 5000-link chain
/// (10000 coordinates, the maximum) builds in well under a second per
/// thousand links (the old quadratic-per-link topological sort took
/// minutes at this size).
#[test]
fn building_a_long_chain_is_linear_time() {
    // The fastest of three builds per size: on a shared machine a single
    // timing can be inflated several-fold by other jobs (seen: 0.71 s once
    // for the 5000 links, 0.29–0.37 s in three quiet re-runs).
    let mut times = Vec::new();
    for n in [1250, 5000] {
        let text = format!(
            "version: 1\ndt: 0.005\nrobots:\n- name: c\n  chain: {{links: {n}, link_length: 0.2, link_width: 0.05, link_mass: 0.1}}\n"
        );
        let mut best = f64::INFINITY;
        for _ in 0..3 {
            let t0 = std::time::Instant::now();
            let scene =
                sdrs::scene::Scene::from_str(&text, std::path::Path::new("long.yaml")).unwrap();
            best = best.min(t0.elapsed().as_secs_f64());
            assert_eq!(scene.model.ndof(), 2 * n);
        }
        times.push(best);
    }
    eprintln!("build times for 1250 and 5000 links: {times:?} s");
    assert!(times[1] < 10.0, "{times:?}");
    // Four times the links may cost at most ~8× (linear plus noise), not 64×.
    assert!(times[1] < 8.0 * times[0] + 0.5, "{times:?}");
}

#[test]
fn an_empty_file_says_so() {
    let (path, msg) = load("empty.yaml", "  \n");
    assert_names(&msg, &path, &["the file is empty"]);
    assert!(!msg.contains("missing field"), "{msg}");
}

#[test]
fn a_missing_file_names_its_cause_once() {
    let err = Scene::load("/nonexistent/dir/scene.yaml").unwrap_err();
    // The message and every cause, `: `-separated (as the CLI prints them).
    let mut chain = err.to_string();
    let mut cause = std::error::Error::source(&err);
    while let Some(c) = cause {
        chain = format!("{chain}: {c}");
        cause = c.source();
    }
    assert_eq!(chain.matches("No such file").count(), 1, "{chain}");
}

#[test]
fn bad_ccd_options_name_the_key() {
    for (bad, expect) in [
        ("{keep_fraction: 1.5}", "keep_fraction"),
        ("{keep_fraction: 0}", "keep_fraction"),
        ("{max_rounds: 0}", "max_rounds"),
    ] {
        let text = format!(
            "dt: 0.01\ncontact: {{ccd: {bad}}}\nrobots:\n  - name: r\n    links:{GOOD_LINK}\n"
        );
        let (path, msg) = load("ccd.yaml", &text);
        assert_names(&msg, &path, &["contact.ccd", expect]);
    }
    let text = format!(
        "dt: 0.01\ncontact: {{ccd: {{enable: false}}}}\nrobots:\n  - name: r\n    links:{GOOD_LINK}\n"
    );
    let (path, msg) = load("ccd_typo.yaml", &text);
    assert_names(&msg, &path, &["enable"]);
}

/// The IPC baseline's keys moved from `contact:` into `contact: {ipc: ...}`
/// (2026-11-26): a file written before says where each key now lives,
/// instead of a bare "unknown field".
#[test]
fn ipc_keys_at_their_old_place_are_refused_with_their_new_one() {
    for key in ["surface: source", "dhat: 0.001", "eps_v: 0.001"] {
        let name = key.split(':').next().unwrap();
        let text =
            format!("dt: 0.01\nrobots:\n  - name: r\n    links:{GOOD_LINK}\ncontact: {{{key}}}\n");
        let (path, msg) = load(&format!("moved_{name}.yaml"), &text);
        assert_names(
            &msg,
            &path,
            &[
                &format!("contact.{name}"),
                &format!("contact: {{ipc: {{{name}:"),
            ],
        );
    }
}
