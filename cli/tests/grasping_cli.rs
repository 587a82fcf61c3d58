//! Smoke runs of the grasping benchmarks (issue 12): 2 iterations of each
//! task and its `--design off` twin through the binary; the summary holds
//! the grasp and topology metrics, the optimized scenes keep every tie, and
//! every design variable stays within its bounds. Full runs:
//! `tools/bench/bench_grasping.sh`.

use crate::support;

use sdrs::optimize::Problem;
use sdrs::scene::schema::{HullSpec, SceneSpec};
use support::{robots, scratch_dir, sdrs};

fn run(task: &str, design: &str, out: &std::path::Path) -> serde_json::Value {
    let status = sdrs()
        .args([
            "optimize", "-q", "--iters", "2", "--design", design, "--out",
        ])
        .arg(out)
        .arg(robots(task))
        .status()
        .unwrap();
    assert!(status.success(), "{task} --design {design}");
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

fn vertex(spec: &SceneSpec, link: &str, hull: usize, v: usize) -> [f64; 3] {
    let l = spec.robots[0]
        .links
        .iter()
        .find(|l| l.name == link)
        .unwrap();
    let h: &HullSpec = &l.hulls[hull];
    h.vertices.as_ref().expect("a vertex-list hull")[v]
}

#[test]
fn parallel_jaw_smoke_runs_keep_ties_and_bounds_and_report_metrics() {
    let dir = scratch_dir("grasp_pj");
    let on = run("parallel_jaw_gripper/task.yaml", "on", &dir.join("on"));
    let off = run("parallel_jaw_gripper/task.yaml", "off", &dir.join("off"));
    for s in [&on, &off] {
        let m = &s["extra"]["metrics"];
        assert_eq!(m["grasp"]["trajectories"], 4);
        // The benchmark's premise (paper): the initial gripper grasps none.
        assert_eq!(m["grasp"]["grasped_before"], 0, "{m}");
        for jaw in ["gripper/jaw_left", "gripper/jaw_right"] {
            let t = &m["topology"]["before"][jaw];
            if s == &on {
                assert_eq!(
                    (t["components"].as_u64(), t["holes"].as_u64()),
                    (Some(1), Some(0)),
                    "{jaw}: {t}"
                );
            }
        }
    }
    assert_eq!(off["design_variables"], 0);
    assert_eq!(
        off["extra"]["metrics"]["grasp"]["grasped_after"], 0,
        "nothing changed, nothing grasped"
    );
    check_bounds("parallel_jaw_gripper/task.yaml", &on);
    let scenes: Vec<_> = ["scene_cube", "scene_cylinder", "scene_ball", "scene_plus"]
        .iter()
        .map(|n| dir.join("on/scenes").join(format!("{n}.yaml")))
        .collect();
    assert!(check_ties(
        "parallel_jaw_gripper/scene_cube.yaml",
        &scenes,
        100
    ));
}

/// Every design variable of `task` within ±bound of its initial value in
/// the run's summary.
fn check_bounds(task: &str, summary: &serde_json::Value) {
    let p = Problem::load(&robots(task), true).unwrap();
    let (lo, hi) = (p.design.lower(), p.design.upper());
    let vals = summary["design"].as_object().unwrap();
    assert_eq!(vals.len(), p.design.len());
    for (i, v) in p.design.vars.iter().enumerate() {
        let x = vals[&v.name].as_f64().unwrap();
        assert!(
            lo[i] <= x && x <= hi[i],
            "{} = {x} outside [{}, {}]",
            v.name,
            lo[i],
            hi[i]
        );
    }
}

/// In every optimized scene, tied hull vertices (more than `groups` tie
/// groups) are still one point; returns whether the design moved some hull
/// vertex of a tied link away from the initial scene. (Under the paper's
/// connectivity, issue 30, the tied points are face-centre vertices that the
/// first two steps need not move; that tied points move and stay one point
/// is asserted on the topology demonstration, `tests/topology_demo.rs`.)
fn check_ties(initial: &str, scenes: &[std::path::PathBuf], groups: usize) -> bool {
    let initial: SceneSpec =
        serde_yaml::from_str(&std::fs::read_to_string(robots(initial)).unwrap()).unwrap();
    let ties = &initial.robots[0].design.as_ref().unwrap().ties;
    assert!(ties.len() > groups, "{} tie groups", ties.len());
    let mut moved = false;
    for f in scenes {
        let spec: SceneSpec = serde_yaml::from_str(&std::fs::read_to_string(f).unwrap()).unwrap();
        for group in ties {
            let x = vertex(&spec, &group[0].link, group[0].hull, group[0].vertex);
            for t in &group[1..] {
                assert_eq!(
                    x,
                    vertex(&spec, &t.link, t.hull, t.vertex),
                    "{}: tie {group:?}",
                    f.display()
                );
            }
        }
        for (l0, l1) in initial.robots[0].links.iter().zip(&spec.robots[0].links) {
            if ties.iter().flatten().any(|t| t.link == l0.name) {
                moved |= l0.hulls != l1.hulls;
            }
        }
    }
    moved
}

/// The single-jaw task at its full horizon (480 steps take ≈ 0.5 s per
/// evaluation, so the two iterations and the twin run in seconds).
#[test]
fn single_jaw_smoke_runs_keep_ties_and_bounds_and_report_metrics() {
    let dir = scratch_dir("grasp_sj");
    let task = "single_jaw_gripper/task.yaml";
    let on = run(task, "on", &dir.join("on"));
    let off = run(task, "off", &dir.join("off"));
    for s in [&on, &off] {
        let m = &s["extra"]["metrics"];
        assert_eq!(m["grasp"]["trajectories"], 1);
        // The benchmark's premise (paper): the initial jaw cannot lift the X.
        assert_eq!(m["grasp"]["grasped_before"], 0, "{m}");
        assert!(m["topology"]["changed"].is_boolean(), "{m}");
    }
    let t = &on["extra"]["metrics"]["topology"]["before"]["gripper/jaw"];
    assert_eq!(
        (
            t["components"].as_u64(),
            t["holes"].as_u64(),
            t["cavities"].as_u64()
        ),
        (Some(1), Some(0), Some(0)),
        "{t}"
    );
    assert_eq!(off["design_variables"], 0);
    assert_eq!(
        off["controller_variables"], 30,
        "the path is still optimized"
    );
    check_bounds(task, &on);
    assert!(
        check_ties(
            "single_jaw_gripper/scene.yaml",
            &[dir.join("on/scenes/scene.yaml")],
            100
        ),
        "two optimizer steps moved no block vertex"
    );
}

/// The three-fingered hand at its full horizon (3 trajectories of 200
/// steps, ≈ 1 s per evaluation): grasp metrics for 3 objects, topology of
/// all six finger links, bounds, and the few V-HACD ties (3 per link) in
/// all three optimized scenes.
#[test]
fn three_finger_smoke_runs_keep_ties_and_bounds_and_report_metrics() {
    let dir = scratch_dir("grasp_hand");
    let task = "three_finger_hand/task.yaml";
    let on = run(task, "on", &dir.join("on"));
    let off = run(task, "off", &dir.join("off"));
    for s in [&on, &off] {
        let m = &s["extra"]["metrics"];
        assert_eq!(m["grasp"]["trajectories"], 3);
        // Measured (task header): the initial hand lifts the cube only.
        assert_eq!(m["grasp"]["grasped_before"], 1, "{m}");
        assert!(m["topology"]["changed"].is_boolean(), "{m}");
    }
    for f in 0..3 {
        for l in ["proximal", "distal"] {
            let t = &on["extra"]["metrics"]["topology"]["before"][format!("hand/finger{f}_{l}")];
            assert_eq!(
                (t["components"].as_u64(), t["holes"].as_u64()),
                (Some(1), Some(0)),
                "finger{f}_{l}: {t}"
            );
        }
    }
    assert_eq!(on["design_variables"], 6660);
    assert_eq!(off["design_variables"], 0);
    assert_eq!(off["controller_variables"], 0, "a preset controller");
    assert_eq!(
        off["extra"]["metrics"]["grasp"]["grasped_after"], 1,
        "nothing changed"
    );
    check_bounds(task, &on);
    let scenes: Vec<_> = ["scene_cube", "scene_cylinder", "scene_ball"]
        .iter()
        .map(|n| dir.join("on/scenes").join(format!("{n}.yaml")))
        .collect();
    // 18 groups (3 per link); whether a tied point moved depends on its
    // hull touching an object, so it is not asserted.
    check_ties("three_finger_hand/scene_cube.yaml", &scenes, 17);
    let initial = sdrs::optimize::Problem::load(&robots(task), true).unwrap();
    let d0 = initial.design.values(&initial.first().model);
    let vals = on["design"].as_object().unwrap();
    assert!(
        initial
            .design
            .vars
            .iter()
            .enumerate()
            .any(|(i, v)| vals[&v.name].as_f64().unwrap() != d0[i]),
        "two optimizer steps moved no vertex"
    );
}
